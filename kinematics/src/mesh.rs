//! Mesh files (STL, OBJ, COLLADA) and their collision shapes.

use std::path::Path;

use nalgebra::Vector3;
use parry3d::math::Vector;
use parry3d::shape::SharedShape;

use crate::error::{KinematicsError, Result};
use crate::model::TriangleMesh;
use crate::urdf::MAX_LENGTH;

/// How a mesh becomes a collision shape.
///
/// ```
/// use hearth_kinematics::{LoadOptions, MeshCollision};
/// assert_eq!(MeshCollision::default(), MeshCollision::ConvexHull);
/// let tight = LoadOptions { mesh_collision: MeshCollision::ConvexDecomposition, ..Default::default() };
/// assert_ne!(tight.mesh_collision, LoadOptions::default().mesh_collision);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MeshCollision {
    /// One convex hull per mesh: fast, conservative (the default).
    #[default]
    ConvexHull,
    /// An approximate convex decomposition (V-HACD): tighter around concave parts, slower to
    /// build and to check.
    ConvexDecomposition,
    /// The exact triangle mesh (a surface, not a volume: misses objects fully inside it).
    TriMesh,
}

/// Loads a mesh file (format from the extension: `.stl`, `.obj`, `.dae`), merges its parts and
/// applies `scale`.
///
/// ```
/// use hearth_kinematics::load_mesh;
/// let path = std::env::temp_dir().join("hearth_doc_load_mesh.obj");
/// std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
/// let mesh = load_mesh(&path, &nalgebra::Vector3::repeat(2.0)).unwrap();
/// assert_eq!(mesh.triangles.len(), 1);
/// assert!(mesh.vertices.contains(&[2.0, 0.0, 0.0])); // scaled
/// assert!(load_mesh(std::path::Path::new("part.ply"), &nalgebra::Vector3::repeat(1.0)).is_err());
/// ```
pub fn load_mesh(path: &Path, scale: &Vector3<f64>) -> Result<TriangleMesh> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if !matches!(ext.as_str(), "stl" | "obj" | "dae") {
        return Err(KinematicsError::MeshLoad {
            path: path.to_path_buf(),
            message: format!("unsupported mesh format `.{ext}` (supported: .stl, .obj, .dae)"),
        });
    }
    let bytes = std::fs::read(path).map_err(|error| KinematicsError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    // The loaders are third-party parsers of untrusted files: contain any panic.
    let parsed = std::panic::catch_unwind(|| {
        mesh_loader::Loader::default()
            .merge_meshes(true)
            .load_from_slice(&bytes, path)
    });
    let scene = match parsed {
        Ok(Ok(scene)) => scene,
        Ok(Err(e)) => {
            return Err(KinematicsError::MeshLoad {
                path: path.to_path_buf(),
                message: e.to_string(),
            });
        }
        Err(_) => {
            return Err(KinematicsError::MeshLoad {
                path: path.to_path_buf(),
                message: "the mesh parser failed on this file".into(),
            });
        }
    };
    let mut out = TriangleMesh::default();
    let s = [scale.x as f32, scale.y as f32, scale.z as f32];
    for mesh in scene.meshes {
        let base = out.vertices.len() as u32;
        let n = mesh.vertices.len() as u32;
        out.vertices
            .extend(mesh.vertices.iter().map(|v| [v[0] * s[0], v[1] * s[1], v[2] * s[2]]));
        for f in &mesh.faces {
            if f.iter().all(|&i| i < n) {
                out.triangles.push([base + f[0], base + f[1], base + f[2]]);
            }
        }
    }
    if out.triangles.is_empty() || out.vertices.iter().flatten().any(|c| !c.is_finite()) {
        return Err(KinematicsError::MeshLoad {
            path: path.to_path_buf(),
            message: "no usable triangles (empty, or non-finite vertices)".into(),
        });
    }
    if let Some(c) = out.vertices.iter().flatten().find(|c| f64::from(c.abs()) > MAX_LENGTH) {
        return Err(KinematicsError::MeshLoad {
            path: path.to_path_buf(),
            message: format!("a vertex coordinate is {c:e} m (scaled), beyond ±{MAX_LENGTH} m"),
        });
    }
    Ok(out)
}

/// Builds the parry shape of a mesh.
pub(crate) fn mesh_shape(mesh: &TriangleMesh, mode: MeshCollision, uri: &str) -> Result<SharedShape> {
    let points: Vec<Vector> = mesh.vertices.iter().map(|v| Vector::new(v[0], v[1], v[2])).collect();
    let fail = |message: String| KinematicsError::MeshLoad {
        path: uri.into(),
        message,
    };
    match mode {
        MeshCollision::ConvexHull => SharedShape::convex_hull(&points)
            .ok_or_else(|| fail("degenerate mesh: its convex hull has no volume".into())),
        MeshCollision::ConvexDecomposition => {
            // The decomposition panics on a mesh without volume (it builds an empty compound):
            // refuse those as the hull does, and contain any other panic of it.
            if SharedShape::convex_hull(&points).is_none() {
                return Err(fail("degenerate mesh: its convex hull has no volume".into()));
            }
            std::panic::catch_unwind(|| SharedShape::convex_decomposition(&points, &mesh.triangles))
                .map_err(|_| fail("the convex decomposition failed on this mesh".into()))
        }
        MeshCollision::TriMesh => SharedShape::trimesh(points, mesh.triangles.clone())
            .map_err(|e| fail(format!("invalid triangle mesh: {e:?}"))),
    }
}
