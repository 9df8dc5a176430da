//! Turns [`VisualShape`]s into triangles: one merged vertex and index buffer for the whole
//! scene, each vertex tagged with the index of the item it belongs to.
//!
//! Winding is counter-clockwise seen from outside (outward normals by the right-hand rule).

use std::collections::HashMap;

use crate::sensors::visuals::{VisualScene, VisualShape};

/// Segments around round shapes (cylinders, spheres, capsules).
pub(crate) const SEGMENTS: usize = 16;
/// Latitude bands of a sphere (each capsule cap gets half).
const RINGS: usize = 8;
/// Largest angle (radians) between faces of a mesh whose shared vertex normals are smoothed.
const SMOOTH_ANGLE: f32 = 0.6;

/// One vertex as the shaders read it: position, normal (snorm16, w unused) and item index.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Vertex {
    pub pos: [f32; 3],
    pub normal: [i16; 4],
    pub item: u32,
}

/// Index range of one item in the merged index buffer, and its bounding sphere in item frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ItemRange {
    pub first_index: u32,
    pub index_count: u32,
    /// Centre of the bounding sphere in the item frame.
    pub center: [f32; 3],
    /// Radius of the bounding sphere.
    pub radius: f32,
    /// Whether the shape is closed with consistent winding (back faces may be culled).
    pub closed: bool,
}

/// The merged geometry of a scene.
#[derive(Clone, Debug, Default)]
pub(crate) struct SceneMesh {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub ranges: Vec<ItemRange>,
}

fn snorm(n: [f32; 3]) -> [i16; 4] {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let s = if len > 1e-12 { 1.0 / len } else { 0.0 };
    let q = |c: f32| (c * s * 32767.0).round().clamp(-32767.0, 32767.0) as i16;
    [q(n[0]), q(n[1]), q(n[2]), 0]
}

pub(crate) fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = dot(a, a).sqrt();
    if l > 1e-20 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Builder of one item's triangles.
struct Emit<'a> {
    mesh: &'a mut SceneMesh,
    item: u32,
    base: u32,
}

impl Emit<'_> {
    fn vertex(&mut self, pos: [f32; 3], normal: [f32; 3]) -> u32 {
        let i = self.mesh.vertices.len() as u32 - self.base;
        self.mesh.vertices.push(Vertex {
            pos,
            normal: snorm(normal),
            item: self.item,
        });
        i
    }

    fn tri(&mut self, a: u32, b: u32, c: u32) {
        let base = self.base;
        self.mesh.indices.extend_from_slice(&[a + base, b + base, c + base]);
    }
}

fn emit_box(e: &mut Emit<'_>, half: [f32; 3]) {
    // Each face: outward normal and two in-face axes u, v with u × v = normal.
    let faces: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
        ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
    ];
    for (n, u, v) in faces {
        let corner = |su: f32, sv: f32| -> [f32; 3] {
            let mut p = [0.0f32; 3];
            for k in 0..3 {
                p[k] = (n[k] + su * u[k] + sv * v[k]) * half[k];
            }
            p
        };
        let a = e.vertex(corner(-1.0, -1.0), n);
        let b = e.vertex(corner(1.0, -1.0), n);
        let c = e.vertex(corner(1.0, 1.0), n);
        let d = e.vertex(corner(-1.0, 1.0), n);
        e.tri(a, b, c);
        e.tri(a, c, d);
    }
}

fn emit_cylinder(e: &mut Emit<'_>, radius: f32, half_length: f32) {
    let n = SEGMENTS;
    let ring = |i: usize| {
        let t = i as f32 / n as f32 * std::f32::consts::TAU;
        (t.cos(), t.sin())
    };
    // Side: two vertices per segment boundary, smooth radial normals.
    let side0 = e.vertex([radius, 0.0, -half_length], [1.0, 0.0, 0.0]);
    e.vertex([radius, 0.0, half_length], [1.0, 0.0, 0.0]);
    for i in 1..n {
        let (c, s) = ring(i);
        e.vertex([radius * c, radius * s, -half_length], [c, s, 0.0]);
        e.vertex([radius * c, radius * s, half_length], [c, s, 0.0]);
    }
    for i in 0..n as u32 {
        let j = (i + 1) % n as u32;
        let (a, b) = (side0 + 2 * i, side0 + 2 * i + 1);
        let (c, d) = (side0 + 2 * j, side0 + 2 * j + 1);
        e.tri(a, c, d);
        e.tri(a, d, b);
    }
    // Caps: fans with flat normals.
    for (z, nz) in [(half_length, 1.0f32), (-half_length, -1.0)] {
        let centre = e.vertex([0.0, 0.0, z], [0.0, 0.0, nz]);
        let first = centre + 1;
        for i in 0..n {
            let (c, s) = ring(i);
            e.vertex([radius * c, radius * s, z], [0.0, 0.0, nz]);
        }
        for i in 0..n as u32 {
            let j = (i + 1) % n as u32;
            if nz > 0.0 {
                e.tri(centre, first + i, first + j);
            } else {
                e.tri(centre, first + j, first + i);
            }
        }
    }
}

/// A sphere (`half_length` 0) or capsule along z: latitude rings, the upper hemisphere shifted
/// up by `half_length` and the lower one down.
fn emit_capsule(e: &mut Emit<'_>, radius: f32, half_length: f32) {
    let n = SEGMENTS;
    // Rings from the south pole (k = 0) to the north pole (k = RINGS); a capsule repeats the
    // equator so each hemisphere keeps its own offset.
    let mut lats: Vec<(f32, f32)> = Vec::new(); // (polar angle from -z, z offset)
    for k in 0..=RINGS {
        let theta = k as f32 / RINGS as f32 * std::f32::consts::PI;
        let north = k * 2 > RINGS;
        let offset = if north { half_length } else { -half_length };
        lats.push((theta, offset));
        if half_length > 0.0 && k * 2 == RINGS {
            lats.push((theta, half_length));
        }
    }
    let first = e.mesh.vertices.len() as u32 - e.base;
    for &(theta, offset) in &lats {
        let (sin_t, cos_t) = theta.sin_cos();
        let z = -cos_t;
        for i in 0..=n {
            let phi = i as f32 / n as f32 * std::f32::consts::TAU;
            let (s, c) = phi.sin_cos();
            let nrm = [sin_t * c, sin_t * s, z];
            e.vertex([radius * nrm[0], radius * nrm[1], radius * z + offset], nrm);
        }
    }
    let row = (n + 1) as u32;
    for k in 0..lats.len() as u32 - 1 {
        for i in 0..n as u32 {
            let a = first + k * row + i;
            let b = a + 1;
            let c = a + row;
            let d = c + 1;
            // Southernmost / northernmost bands are triangles (the pole row is degenerate).
            if k > 0 {
                e.tri(a, b, d);
            }
            if k + 2 < lats.len() as u32 {
                e.tri(a, d, c);
            }
        }
    }
}

/// Mesh triangles with normals smoothed across edges whose faces differ by less than
/// [`SMOOTH_ANGLE`], split (flat) elsewhere.
fn emit_mesh(e: &mut Emit<'_>, vertices: &[[f32; 3]], triangles: &[[u32; 3]]) {
    let nv = vertices.len() as u32;
    let valid: Vec<[u32; 3]> = triangles
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&i| i < nv))
        .collect();
    let face_n: Vec<[f32; 3]> = valid
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            cross(sub(b, a), sub(c, a)) // area weighted
        })
        .collect();
    let mut incident: Vec<Vec<u32>> = vec![Vec::new(); vertices.len()];
    for (f, t) in valid.iter().enumerate() {
        for &i in t {
            incident[i as usize].push(f as u32);
        }
    }
    let cos_limit = SMOOTH_ANGLE.cos();
    let mut seen: HashMap<(u32, [i16; 4]), u32> = HashMap::new();
    for (f, t) in valid.iter().enumerate() {
        let fnrm = normalize(face_n[f]);
        let mut out = [0u32; 3];
        for (k, &vi) in t.iter().enumerate() {
            let mut acc = [0.0f32; 3];
            for &g in &incident[vi as usize] {
                let gn = face_n[g as usize];
                if dot(normalize(gn), fnrm) >= cos_limit {
                    acc = [acc[0] + gn[0], acc[1] + gn[1], acc[2] + gn[2]];
                }
            }
            let nrm = if dot(acc, acc) > 0.0 { normalize(acc) } else { fnrm };
            let key = (vi, snorm(nrm));
            out[k] = match seen.get(&key) {
                Some(&idx) => idx,
                None => {
                    let idx = e.vertex(vertices[vi as usize], nrm);
                    seen.insert(key, idx);
                    idx
                }
            };
        }
        e.tri(out[0], out[1], out[2]);
    }
}

fn bounds(points: impl Iterator<Item = [f32; 3]>) -> ([f32; 3], f32) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut any = false;
    let pts: Vec<[f32; 3]> = points.collect();
    for p in &pts {
        any = true;
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if !any {
        return ([0.0; 3], 0.0);
    }
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let r = pts
        .iter()
        .map(|p| dot(sub(*p, c), sub(*p, c)))
        .fold(0.0f32, f32::max)
        .sqrt();
    (c, r)
}

/// Tessellates every item of `scene` into one merged mesh.
pub(crate) fn tessellate(scene: &VisualScene) -> SceneMesh {
    let mut mesh = SceneMesh::default();
    for (i, item) in scene.items.iter().enumerate() {
        let base = mesh.vertices.len() as u32;
        let first_index = mesh.indices.len() as u32;
        let mut closed = true;
        {
            let mut e = Emit {
                mesh: &mut mesh,
                item: i as u32,
                base,
            };
            match &item.shape {
                VisualShape::Box { half } => emit_box(&mut e, half.map(|h| h.abs())),
                VisualShape::Cylinder { radius, half_length } => emit_cylinder(&mut e, radius.abs(), half_length.abs()),
                VisualShape::Sphere { radius } => emit_capsule(&mut e, radius.abs(), 0.0),
                VisualShape::Capsule { radius, half_length } => emit_capsule(&mut e, radius.abs(), half_length.abs()),
                VisualShape::Mesh(m) => {
                    closed = false;
                    emit_mesh(&mut e, &m.vertices, &m.triangles);
                }
            }
        }
        let (center, radius) = bounds(mesh.vertices[base as usize..].iter().map(|v| v.pos));
        mesh.ranges.push(ItemRange {
            first_index,
            index_count: mesh.indices.len() as u32 - first_index,
            center,
            radius,
            closed,
        });
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_outward(mesh: &SceneMesh) {
        // Every triangle's geometric normal agrees with its vertex normals and points away
        // from the centre.
        for t in mesh.indices.chunks(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.vertices[i as usize]);
            let g = cross(sub(b.pos, a.pos), sub(c.pos, a.pos));
            if dot(g, g) < 1e-12 {
                continue;
            }
            let centroid = [
                (a.pos[0] + b.pos[0] + c.pos[0]) / 3.0,
                (a.pos[1] + b.pos[1] + c.pos[1]) / 3.0,
                (a.pos[2] + b.pos[2] + c.pos[2]) / 3.0,
            ];
            assert!(dot(g, centroid) > 0.0, "inward triangle {t:?}");
            let n = a.normal.map(|x| x as f32);
            assert!(dot(g, [n[0], n[1], n[2]]) > 0.0);
        }
    }

    fn item(shape: VisualShape) -> VisualScene {
        use crate::sensors::{PbrMaterial, VisualItem};
        VisualScene {
            items: vec![VisualItem {
                body: None,
                local: nalgebra::Isometry3::identity(),
                shape,
                material: PbrMaterial::from_urdf(None, None),
                semantic: 1,
                instance: 1,
            }],
            ..Default::default()
        }
    }

    #[test]
    fn primitives_wind_outwards() {
        for shape in [
            VisualShape::Box { half: [0.5, 1.0, 2.0] },
            VisualShape::Cylinder {
                radius: 0.3,
                half_length: 0.5,
            },
            VisualShape::Sphere { radius: 0.4 },
            VisualShape::Capsule {
                radius: 0.2,
                half_length: 0.3,
            },
        ] {
            let m = tessellate(&item(shape));
            assert_eq!(m.ranges[0].index_count as usize, m.indices.len());
            check_outward(&m);
        }
        let b = tessellate(&item(VisualShape::Box { half: [0.5, 1.0, 2.0] }));
        assert_eq!(b.vertices.len(), 24);
        assert!((b.ranges[0].radius - (0.25f32 + 1.0 + 4.0).sqrt()).abs() < 1e-5);
    }
}
