//! Fixtures shared by the kinematics integration tests: the cube mesh.

/// Corners of the cube [-0.5, 0.5]³.
pub const CUBE_V: [[f32; 3]; 8] = [
    [-0.5, -0.5, -0.5],
    [0.5, -0.5, -0.5],
    [0.5, 0.5, -0.5],
    [-0.5, 0.5, -0.5],
    [-0.5, -0.5, 0.5],
    [0.5, -0.5, 0.5],
    [0.5, 0.5, 0.5],
    [-0.5, 0.5, 0.5],
];

/// Its 12 triangles, counter-clockwise seen from outside.
pub const CUBE_F: [[usize; 3]; 12] = [
    [0, 2, 1],
    [0, 3, 2],
    [4, 5, 6],
    [4, 6, 7],
    [0, 1, 5],
    [0, 5, 4],
    [1, 2, 6],
    [1, 6, 5],
    [2, 3, 7],
    [2, 7, 6],
    [3, 0, 4],
    [3, 4, 7],
];

/// The cube as an OBJ file.
pub fn cube_obj() -> String {
    let mut s = String::from("# cube\no cube\n");
    for v in &CUBE_V {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for f in &CUBE_F {
        s += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    s
}
