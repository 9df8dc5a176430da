//! Mesh loading end to end: STL (ASCII and binary), OBJ and COLLADA files written to a fresh
//! temporary folder, referenced from URDFs by relative path, `package://`, PyBullet-style
//! `package://meshes/…`, `file://` and `HEARTH_PACKAGE_PATH`; scale, collision modes,
//! bad files and visual-only meshes.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use hearth_kinematics::{
    Geometry, KinematicsError, LoadOptions, MeshCollision, PACKAGE_PATH_ENV, PackageResolver, RobotModel, load_mesh,
};
use nalgebra::Vector3;

mod common;
use common::{CUBE_F, CUBE_V, cube_obj};

// ---------------------------------------------------------------------------------------------
// Fixtures
// ---------------------------------------------------------------------------------------------

/// A fresh, empty folder unique to this process and call.
fn fresh_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("hearth_meshes_{}_{n}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn normal(f: &[usize; 3]) -> [f32; 3] {
    let [a, b, c] = f.map(|i| Vector3::from(CUBE_V[i]));
    let n = (b - a).cross(&(c - a)).normalize();
    [n.x, n.y, n.z]
}

fn ascii_stl() -> String {
    let mut s = String::from("solid cube\n");
    for f in &CUBE_F {
        let n = normal(f);
        s += &format!("  facet normal {} {} {}\n    outer loop\n", n[0], n[1], n[2]);
        for &i in f {
            let v = CUBE_V[i];
            s += &format!("      vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid cube\n"
}

fn binary_stl() -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b[..11].copy_from_slice(b"binary cube");
    b.extend_from_slice(&(CUBE_F.len() as u32).to_le_bytes());
    for f in &CUBE_F {
        for c in normal(f) {
            b.extend_from_slice(&c.to_le_bytes());
        }
        for &i in f {
            for c in CUBE_V[i] {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&0u16.to_le_bytes());
    }
    b
}

fn collada() -> String {
    let positions: Vec<String> = CUBE_V.iter().flatten().map(|c| c.to_string()).collect();
    let indices: Vec<String> = CUBE_F.iter().flatten().map(|i| i.to_string()).collect();
    format!(
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>
    <created>2024-01-01T00:00:00</created>
    <modified>2024-01-01T00:00:00</modified>
    <unit name="meter" meter="1"/>
    <up_axis>Z_UP</up_axis>
  </asset>
  <library_geometries>
    <geometry id="cube-mesh" name="cube">
      <mesh>
        <source id="cube-positions">
          <float_array id="cube-positions-array" count="24">{}</float_array>
          <technique_common>
            <accessor source="#cube-positions-array" count="8" stride="3">
              <param name="X" type="float"/>
              <param name="Y" type="float"/>
              <param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>
        <vertices id="cube-vertices">
          <input semantic="POSITION" source="#cube-positions"/>
        </vertices>
        <triangles count="12">
          <input semantic="VERTEX" source="#cube-vertices" offset="0"/>
          <p>{}</p>
        </triangles>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="Scene" name="Scene">
      <node id="cube" name="cube" type="NODE">
        <instance_geometry url="#cube-mesh" name="cube"/>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene>
    <instance_visual_scene url="#Scene"/>
  </scene>
</COLLADA>
"##,
        positions.join(" "),
        indices.join(" ")
    )
}

/// Writes all four cube files into `dir` (created if needed).
fn write_cubes(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("cube.stl"), ascii_stl()).unwrap();
    std::fs::write(dir.join("cube_bin.stl"), binary_stl()).unwrap();
    std::fs::write(dir.join("cube.obj"), cube_obj()).unwrap();
    std::fs::write(dir.join("cube.dae"), collada()).unwrap();
}

/// A URDF whose link `body` has one collision mesh with this `filename` (and `extra` attributes).
fn mesh_urdf(filename: &str, extra: &str) -> String {
    format!(
        r#"<robot name="meshy">
  <link name="body">
    <collision><geometry><mesh filename="{filename}" {extra}/></geometry></collision>
  </link>
</robot>"#
    )
}

/// Half extents of the AABB of link `link`'s collision shape.
fn half_extents(m: &RobotModel, link: usize) -> [f32; 3] {
    let aabb = m
        .link_shape(link)
        .expect("the link has a collision shape")
        .shape
        .compute_local_aabb();
    [
        (aabb.maxs.x - aabb.mins.x) / 2.0,
        (aabb.maxs.y - aabb.mins.y) / 2.0,
        (aabb.maxs.z - aabb.mins.z) / 2.0,
    ]
}

#[track_caller]
fn assert_cube(m: &RobotModel, half: f32) {
    let h = half_extents(m, 0);
    for c in h {
        assert!((c - half).abs() < 1e-4, "expected half extents {half}, got {h:?}");
    }
    match &m.links()[0].collisions[0].geometry {
        Geometry::Mesh { mesh, .. } => {
            assert_eq!(mesh.triangles.len(), 12, "a cube has 12 triangles");
            assert!(mesh.vertices.len() >= 8);
        }
        other => panic!("expected a mesh geometry, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Formats
// ---------------------------------------------------------------------------------------------

#[test]
fn every_format_loads_as_a_unit_cube() {
    let dir = fresh_dir("formats");
    write_cubes(&dir);
    for file in ["cube.stl", "cube_bin.stl", "cube.obj", "cube.dae"] {
        let mesh = load_mesh(&dir.join(file), &Vector3::repeat(1.0)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(mesh.triangles.len(), 12, "{file}");
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for v in &mesh.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        for k in 0..3 {
            assert!(
                (lo[k] + 0.5).abs() < 1e-5 && (hi[k] - 0.5).abs() < 1e-5,
                "{file}: {lo:?} {hi:?}"
            );
        }
        // Every triangle indexes real vertices.
        assert!(
            mesh.triangles
                .iter()
                .flatten()
                .all(|&i| (i as usize) < mesh.vertices.len()),
            "{file}"
        );

        // And through a URDF with a relative path.
        let m = RobotModel::from_urdf_str(&mesh_urdf(file, ""), Some(&dir)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_cube(&m, 0.5);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn load_mesh_applies_a_non_uniform_scale() {
    let dir = fresh_dir("load_scale");
    write_cubes(&dir);
    let mesh = load_mesh(&dir.join("cube.obj"), &Vector3::new(1.0, 2.0, 3.0)).unwrap();
    let max = |k: usize| mesh.vertices.iter().map(|v| v[k]).fold(f32::MIN, f32::max);
    assert!((max(0) - 0.5).abs() < 1e-6 && (max(1) - 1.0).abs() < 1e-6 && (max(2) - 1.5).abs() < 1e-6);
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// Resolution
// ---------------------------------------------------------------------------------------------

#[test]
fn relative_path_from_a_urdf_file() {
    let dir = fresh_dir("relative");
    write_cubes(&dir.join("meshes"));
    let urdf = dir.join("robot.urdf");
    std::fs::write(&urdf, mesh_urdf("meshes/cube_bin.stl", "")).unwrap();
    let m = RobotModel::from_urdf_file(&urdf).unwrap();
    assert_cube(&m, 0.5);

    // Without a base folder the relative path is taken against the working directory, and
    // the error says where it looked.
    let e = RobotModel::from_urdf_str(&mesh_urdf("meshes/cube_bin.stl", ""), None).unwrap_err();
    assert!(matches!(e, KinematicsError::MeshNotFound { .. }), "{e:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn package_uri_with_the_urdf_in_pkg_urdf() {
    let root = fresh_dir("pkg_layout");
    let pkg = root.join("my_bot");
    write_cubes(&pkg.join("meshes"));
    std::fs::create_dir_all(pkg.join("urdf")).unwrap();
    let urdf = pkg.join("urdf/my_bot.urdf");
    std::fs::write(&urdf, mesh_urdf("package://my_bot/meshes/cube.stl", "")).unwrap();
    let m = RobotModel::from_urdf_file(&urdf).unwrap();
    assert_cube(&m, 0.5);

    // The same URDF text loaded from somewhere unrelated needs the package root…
    let elsewhere = fresh_dir("pkg_elsewhere");
    let text = mesh_urdf("package://my_bot/meshes/cube.stl", "");
    let e = RobotModel::from_urdf_str(&text, Some(&elsewhere)).unwrap_err();
    assert!(matches!(e, KinematicsError::MeshNotFound { .. }), "{e:?}");

    // …given as an explicit root (the folder holding the package, or the package itself).
    for explicit in [root.clone(), pkg.clone()] {
        let opts = LoadOptions {
            package_paths: vec![explicit.clone()],
            ..Default::default()
        };
        let m = RobotModel::from_urdf_str_with(&text, "robot.urdf", Some(&elsewhere), &opts)
            .unwrap_or_else(|e| panic!("root {}: {e}", explicit.display()));
        assert_cube(&m, 0.5);

        let found = PackageResolver::new(vec![explicit.clone()])
            .resolve("package://my_bot/meshes/cube.stl", None)
            .unwrap_or_else(|tried| panic!("root {}: tried {tried:?}", explicit.display()));
        assert_eq!(
            std::fs::canonicalize(found).unwrap(),
            std::fs::canonicalize(pkg.join("meshes/cube.stl")).unwrap()
        );
    }
    let _ = std::fs::remove_dir_all(&root);
    let _ = std::fs::remove_dir_all(&elsewhere);
}

#[test]
fn pybullet_style_package_uri_next_to_the_urdf() {
    let dir = fresh_dir("pybullet");
    write_cubes(&dir.join("meshes"));
    let urdf = dir.join("robot.urdf");
    std::fs::write(&urdf, mesh_urdf("package://meshes/cube.obj", "")).unwrap();
    let m = RobotModel::from_urdf_file(&urdf).unwrap();
    assert_cube(&m, 0.5);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn file_uri_with_an_absolute_path() {
    let dir = fresh_dir("file_uri");
    write_cubes(&dir);
    let abs = std::fs::canonicalize(dir.join("cube.dae")).unwrap();
    assert!(abs.is_absolute());
    let uri = format!("file://{}", abs.display());
    // The URDF's own folder is unrelated: the URI alone locates the file.
    let elsewhere = fresh_dir("file_uri_elsewhere");
    let m = RobotModel::from_urdf_str(&mesh_urdf(&uri, ""), Some(&elsewhere)).unwrap();
    assert_cube(&m, 0.5);
    // A plain absolute path works too.
    let m = RobotModel::from_urdf_str(&mesh_urdf(&abs.display().to_string(), ""), Some(&elsewhere)).unwrap();
    assert_cube(&m, 0.5);
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&elsewhere);
}

/// The only test in this file that touches the process environment (tests run in parallel
/// threads of one process). Other tests only ever *gain* a search root from it, which none of
/// their assertions depends on.
#[test]
fn hearth_package_path_environment_variable() {
    let root = fresh_dir("env_root");
    let pkg_name = format!("hearth_env_pkg_{}", std::process::id());
    write_cubes(&root.join(&pkg_name).join("meshes"));
    let text = mesh_urdf(&format!("package://{pkg_name}/meshes/cube.stl"), "");
    let elsewhere = fresh_dir("env_elsewhere");

    let previous = std::env::var_os(PACKAGE_PATH_ENV);
    let before = RobotModel::from_urdf_str(&text, Some(&elsewhere));
    // SAFETY: no other test in this binary writes the environment, and std serialises its own
    // environment reads and writes.
    unsafe {
        std::env::set_var(
            PACKAGE_PATH_ENV,
            std::env::join_paths([Path::new("/nonexistent/hearth"), &root]).unwrap(),
        )
    };
    let resolver = PackageResolver::new(vec![]);
    let with_env = RobotModel::from_urdf_str(&text, Some(&elsewhere));
    unsafe {
        match &previous {
            Some(v) => std::env::set_var(PACKAGE_PATH_ENV, v),
            None => std::env::remove_var(PACKAGE_PATH_ENV),
        }
    }

    let e = before.expect_err("without the variable the package cannot be found");
    assert!(matches!(e, KinematicsError::MeshNotFound { .. }), "{e:?}");
    assert!(
        resolver.roots().iter().any(|r| r == &root),
        "roots: {:?}",
        resolver.roots()
    );
    let m = with_env.unwrap();
    assert_cube(&m, 0.5);
    let _ = std::fs::remove_dir_all(&root);
    let _ = std::fs::remove_dir_all(&elsewhere);
}

// ---------------------------------------------------------------------------------------------
// Scale and collision modes
// ---------------------------------------------------------------------------------------------

#[test]
fn scale_scales_the_collision_shape() {
    let dir = fresh_dir("scale");
    write_cubes(&dir);
    for file in ["cube.stl", "cube.obj", "cube.dae"] {
        let m = RobotModel::from_urdf_str(&mesh_urdf(file, r#"scale="2 2 2""#), Some(&dir)).unwrap();
        assert_cube(&m, 1.0);
        match &m.links()[0].collisions[0].geometry {
            Geometry::Mesh { scale, .. } => assert_eq!(*scale, Vector3::repeat(2.0)),
            other => panic!("{other:?}"),
        }
    }
    let m = RobotModel::from_urdf_str(&mesh_urdf("cube.stl", r#"scale="1 2 3""#), Some(&dir)).unwrap();
    let h = half_extents(&m, 0);
    assert!(
        (h[0] - 0.5).abs() < 1e-4 && (h[1] - 1.0).abs() < 1e-4 && (h[2] - 1.5).abs() < 1e-4,
        "{h:?}"
    );

    // A zero scale is rejected.
    let e = RobotModel::from_urdf_str(&mesh_urdf("cube.stl", r#"scale="1 0 1""#), Some(&dir)).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::InvalidValue {
                what: "mesh scale y",
                ..
            }
        ),
        "{e:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn collision_modes() {
    let dir = fresh_dir("modes");
    write_cubes(&dir);
    let text = mesh_urdf("cube.stl", "");

    let m = RobotModel::from_urdf_str(&text, Some(&dir)).unwrap();
    let shape = &m.link_shape(0).unwrap().shape;
    assert!(
        shape.as_convex_polyhedron().is_some(),
        "default: a convex hull, got {:?}",
        shape.shape_type()
    );

    let load = |mode| {
        let opts = LoadOptions {
            mesh_collision: mode,
            ..Default::default()
        };
        RobotModel::from_urdf_str_with(&text, "cube.urdf", Some(&dir), &opts).unwrap()
    };
    let m = load(MeshCollision::ConvexHull);
    assert!(m.link_shape(0).unwrap().shape.as_convex_polyhedron().is_some());

    let m = load(MeshCollision::ConvexDecomposition);
    let shape = &m.link_shape(0).unwrap().shape;
    let compound = shape
        .as_compound()
        .unwrap_or_else(|| panic!("a compound, got {:?}", shape.shape_type()));
    assert!(!compound.shapes().is_empty());
    assert_cube(&m, 0.5);

    let m = load(MeshCollision::TriMesh);
    let shape = &m.link_shape(0).unwrap().shape;
    let tri = shape
        .as_trimesh()
        .unwrap_or_else(|| panic!("a trimesh, got {:?}", shape.shape_type()));
    assert_eq!(tri.indices().len(), 12);
    assert_cube(&m, 0.5);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A link with a mesh and a second collision element gets one compound in every mode: a
/// compound cannot hold a convex decomposition or a triangle mesh (parry panicked on the
/// nesting when the URDF was loaded), so their convex parts or triangles become its parts,
/// placed where the element puts them.
#[test]
fn a_mesh_beside_another_element_joins_one_compound_in_every_mode() {
    let dir = fresh_dir("mesh_and_box");
    write_cubes(&dir);
    let text = r#"<robot name="meshy">
  <link name="body">
    <collision><origin xyz="0 0 -1"/><geometry><mesh filename="cube.obj"/></geometry></collision>
    <collision><origin xyz="0 0 1"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
</robot>"#;
    for (mode, least) in [
        (MeshCollision::ConvexHull, 2),
        (MeshCollision::ConvexDecomposition, 2),
        (MeshCollision::TriMesh, 13),
    ] {
        let opts = LoadOptions {
            mesh_collision: mode,
            ..Default::default()
        };
        let m = RobotModel::from_urdf_str_with(text, "two.urdf", Some(&dir), &opts)
            .unwrap_or_else(|e| panic!("{mode:?}: {e}"));
        let shape = &m.link_shape(0).unwrap().shape;
        let compound = shape.as_compound().expect("a compound");
        assert!(
            compound.shapes().len() >= least,
            "{mode:?}: {} parts",
            compound.shapes().len()
        );
        assert!(
            compound.shapes().iter().all(|(_, s)| s.as_composite_shape().is_none()),
            "{mode:?}"
        );
        // The cube below (moved down by 1) and the small box above.
        let aabb = shape.compute_local_aabb();
        assert!(
            (aabb.mins.z + 1.5).abs() < 1e-4 && (aabb.maxs.z - 1.05).abs() < 1e-4,
            "{mode:?}: {aabb:?}"
        );
        assert!(
            (aabb.mins.x + 0.5).abs() < 1e-4 && (aabb.maxs.x - 0.5).abs() < 1e-4,
            "{mode:?}: {aabb:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// Bad files
// ---------------------------------------------------------------------------------------------

/// Meshes that load as triangles but make no usable collision shape are refused with the
/// file named, in every mode where they would break it: all vertices on a line (the convex
/// decomposition panicked on an empty compound), and a vertex 10³⁰ m out (within the f32
/// range, beyond the ±10⁴ m the loader allows for any length).
#[test]
fn degenerate_and_far_meshes_are_mesh_load_errors() {
    let dir = fresh_dir("degenerate");
    std::fs::write(dir.join("line.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        dir.join("far.obj"),
        "v 1e30 0 0\nv 1 0 0\nv 1 1 1\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    for (file, modes) in [
        (
            "line.obj",
            &[MeshCollision::ConvexHull, MeshCollision::ConvexDecomposition][..],
        ),
        (
            "far.obj",
            &[
                MeshCollision::ConvexHull,
                MeshCollision::ConvexDecomposition,
                MeshCollision::TriMesh,
            ][..],
        ),
    ] {
        for &mode in modes {
            let opts = LoadOptions {
                mesh_collision: mode,
                ..Default::default()
            };
            let e = RobotModel::from_urdf_str_with(&mesh_urdf(file, ""), "m.urdf", Some(&dir), &opts)
                .err()
                .unwrap_or_else(|| panic!("{file} {mode:?} should not load"));
            assert!(
                matches!(&e, KinematicsError::MeshLoad { path, .. } if path.ends_with(file)),
                "{file} {mode:?}: {e:?}"
            );
        }
    }
    // Out-of-range numbers in the URDF itself are named short.
    let e = RobotModel::from_urdf_str(&mesh_urdf("line.obj", r#"scale="1e30 1 1""#), Some(&dir)).unwrap_err();
    assert!(e.to_string().contains("scale x is 1e30,"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn empty_or_garbage_stl_is_a_mesh_load_error() {
    let dir = fresh_dir("garbage");
    std::fs::write(dir.join("empty.stl"), b"").unwrap();
    std::fs::write(
        dir.join("garbage.stl"),
        b"\x00\x01 this is not a mesh \xff\xfe at all".repeat(3),
    )
    .unwrap();
    std::fs::write(dir.join("no_facets.stl"), b"solid x\nendsolid x\n").unwrap();
    // A binary STL cut in the middle of a triangle. (A file that merely holds fewer triangles
    // than its header's count loads: mesh-loader ignores the count, as many exporters write a
    // bogus one.)
    let mut short = binary_stl();
    short.truncate(84 + 50 * 3 + 17);
    std::fs::write(dir.join("truncated.stl"), short).unwrap();
    std::fs::write(dir.join("garbage.obj"), "v 1 2\nf 1 2 9\nnonsense\n").unwrap();
    std::fs::write(dir.join("garbage.dae"), "<COLLADA><broken").unwrap();

    for file in [
        "empty.stl",
        "garbage.stl",
        "no_facets.stl",
        "truncated.stl",
        "garbage.obj",
        "garbage.dae",
    ] {
        let e = RobotModel::from_urdf_str(&mesh_urdf(file, ""), Some(&dir))
            .err()
            .unwrap_or_else(|| panic!("{file} should not load"));
        match &e {
            KinematicsError::MeshLoad { path, .. } => {
                assert!(path.ends_with(file), "{file}: {e:?}");
                assert!(e.to_string().contains(file), "{e}");
            }
            other => panic!("{file}: expected MeshLoad, got {other:?}"),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unsupported_extension_is_a_mesh_load_error_naming_it() {
    let dir = fresh_dir("ply");
    std::fs::write(
        dir.join("cube.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    let e = RobotModel::from_urdf_str(&mesh_urdf("cube.ply", ""), Some(&dir)).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, KinematicsError::MeshLoad { ref path, ref message } if path.ends_with("cube.ply") && message.contains(".ply")),
        "{e:?}"
    );
    assert!(msg.contains("cube.ply") && msg.contains(".ply"), "{msg}");

    let e = load_mesh(&dir.join("cube.ply"), &Vector3::repeat(1.0)).unwrap_err();
    assert!(matches!(e, KinematicsError::MeshLoad { .. }), "{e:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// Visuals
// ---------------------------------------------------------------------------------------------

#[test]
fn visual_only_mesh_with_material() {
    let dir = fresh_dir("visual");
    write_cubes(&dir.join("meshes"));
    let text = r#"<robot name="painted">
  <material name="shared_blue"><color rgba="0 0 1 1"/></material>
  <link name="body">
    <visual name="shell">
      <origin xyz="0 0 0.25"/>
      <geometry><mesh filename="meshes/cube.dae" scale="0.5 0.5 0.5"/></geometry>
      <material name="steel"><color rgba="0.1 0.2 0.3 0.4"/></material>
    </visual>
    <visual>
      <geometry><mesh filename="meshes/cube.obj"/></geometry>
      <material name="shared_blue"/>
    </visual>
  </link>
</robot>"#;
    let m = RobotModel::from_urdf_str(text, Some(&dir)).unwrap();
    let link = &m.links()[0];
    assert!(link.collisions.is_empty());
    assert!(m.link_shape(0).is_none(), "visual meshes are not collision shapes");
    assert_eq!(link.visuals.len(), 2);

    let v = &link.visuals[0];
    assert_eq!(v.name.as_deref(), Some("shell"));
    assert_eq!(v.material.as_deref(), Some("steel"));
    assert_eq!(v.rgba, Some([0.1, 0.2, 0.3, 0.4]));
    assert!((v.origin.translation.z - 0.25).abs() < 1e-12);
    match &v.geometry {
        Geometry::Mesh { uri, scale, mesh } => {
            assert_eq!(uri, "meshes/cube.dae");
            assert_eq!(*scale, Vector3::repeat(0.5));
            assert_eq!(mesh.triangles.len(), 12);
            let max = mesh.vertices.iter().flatten().fold(f32::MIN, |a, &b| a.max(b));
            assert!((max - 0.25).abs() < 1e-6, "scaled by 0.5: {max}");
        }
        other => panic!("expected a mesh, got {other:?}"),
    }
    let v = &link.visuals[1];
    assert_eq!(v.material.as_deref(), Some("shared_blue"));
    assert_eq!(v.rgba, Some([0.0, 0.0, 1.0, 1.0]), "colour of the robot-level material");
    assert!(matches!(v.geometry, Geometry::Mesh { .. }));

    // A missing visual mesh is an error too (not silently skipped).
    let e = RobotModel::from_urdf_str(&text.replace("cube.obj", "gone.obj"), Some(&dir)).unwrap_err();
    assert!(
        matches!(e, KinematicsError::MeshNotFound { ref uri, .. } if uri == "meshes/gone.obj"),
        "{e:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
