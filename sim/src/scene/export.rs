//! URDF export: the building, one URDF per object, the robot, and a `scene.json` manifest that
//! other simulators (PyBullet, iGibson) can load body by body.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{SceneError, SceneFile};
use crate::assets::writer::{Part, UrdfWriter};

/// One body of a [`Manifest`].
///
/// ```
/// let b = hearth_sim::scene::ManifestBody {
///     name: "building".into(), urdf: "building.urdf".into(), position: [0.0; 3],
///     quat_xyzw: [0.0, 0.0, 0.0, 1.0], fixed: true, robot: false, joints: Default::default(),
/// };
/// assert!(serde_json::to_string(&b).unwrap().contains("quat_xyzw"));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestBody {
    /// Body name (the object's name, `building`, or the robot's name).
    pub name: String,
    /// URDF path relative to the export directory.
    pub urdf: String,
    /// Base position.
    pub position: [f64; 3],
    /// Base orientation, quaternion x, y, z, w.
    pub quat_xyzw: [f64; 4],
    /// Whether the base is fixed.
    pub fixed: bool,
    /// Whether this is the robot.
    pub robot: bool,
    /// Initial joint positions by joint name (omitted when empty).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joints: BTreeMap<String, f64>,
}

/// The `scene.json` written by [`export_urdf`].
///
/// ```
/// let m = hearth_sim::scene::Manifest { bodies: Vec::new() };
/// assert_eq!(serde_json::to_string(&m).unwrap(), r#"{"bodies":[]}"#);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Every body, the building first.
    pub bodies: Vec<ManifestBody>,
}

fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn write(path: &Path, text: &str) -> Result<(), SceneError> {
    std::fs::write(path, text).map_err(|e| SceneError::io(path, e))
}

/// One solid box of the building: a floor or ceiling slab (its polygon's bounding box), or a
/// wall piece left between openings. Export writes them into one URDF body; the physics world
/// spawns each as a fixed body.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BuildingBox {
    /// `floor/NAME`, `ceiling/NAME` or `wall/NAME/PIECE`.
    pub(crate) name: String,
    /// Full size along the box's own x, y, z.
    pub(crate) size: [f64; 3],
    /// Centre in the world.
    pub(crate) center: [f64; 3],
    /// Rotation about z.
    pub(crate) yaw: f64,
    /// Surface material.
    pub(crate) material: crate::assets::Material,
}

impl SceneFile {
    /// The building's floors, ceilings and walls (openings cut out) as boxes, in that order.
    pub(crate) fn building_boxes(&self) -> Vec<BuildingBox> {
        building_boxes(self)
    }
}

fn building_boxes(scene: &SceneFile) -> Vec<BuildingBox> {
    let b = &scene.building;
    let mut out = Vec::new();
    for (slabs, kind, up) in [(&b.floors, "floor", false), (&b.ceilings, "ceiling", true)] {
        for s in slabs {
            let room = super::Room {
                name: String::new(),
                room_type: crate::assets::RoomType::Corridor,
                polygon: s.polygon.clone(),
            };
            let (lo, hi) = room.bounds();
            let zc = if up {
                s.z + s.thickness / 2.0
            } else {
                s.z - s.thickness / 2.0
            };
            out.push(BuildingBox {
                name: format!("{kind}/{}", s.name),
                size: [hi[0] - lo[0], hi[1] - lo[1], s.thickness],
                center: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, zc],
                yaw: 0.0,
                material: s.material,
            });
        }
    }
    for wall in &b.walls {
        for (k, [s0, s1, zb, zt]) in wall.pieces().into_iter().enumerate() {
            let mid = wall.point_at((s0 + s1) / 2.0);
            out.push(BuildingBox {
                name: format!("wall/{}/{k}", wall.name),
                size: [s1 - s0, wall.thickness, zt - zb],
                center: [mid[0], mid[1], (zb + zt) / 2.0],
                yaw: wall.yaw(),
                material: wall.material,
            });
        }
    }
    out
}

/// The building's boxes as one fixed URDF body.
fn building_urdf(scene: &SceneFile) -> String {
    let mut w = UrdfWriter::new("building", 1.0);
    let base = w.base();
    for b in building_boxes(scene) {
        w.add(base, Part::cuboid(b.size, b.center, b.material).yawed(b.yaw));
    }
    w.finish().urdf
}

/// Writes `dir/building.urdf`, `dir/objects/NAME.urdf` for every object, the built-in robot's
/// URDF when `robot` names one (placed at the scene's robot pose, else at the origin), and
/// `dir/scene.json`. The scene is validated first.
///
/// ```
/// use hearth_sim::scene::{GenerateOptions, export_urdf, generate};
/// let home = generate(&GenerateOptions { seed: 0, rooms: 2, ..Default::default() }).unwrap();
/// let dir = std::env::temp_dir().join("hearth_doc_export");
/// let manifest = export_urdf(&home, &dir, Some("fetch")).unwrap();
/// assert_eq!(manifest.bodies.len(), home.objects.len() + 2);
/// assert!(dir.join("scene.json").exists());
/// ```
pub fn export_urdf(scene: &SceneFile, dir: impl AsRef<Path>, robot: Option<&str>) -> Result<Manifest, SceneError> {
    let dir = dir.as_ref();
    let assets = scene.assets()?;
    let robot_urdf = match robot {
        Some(name) => Some(
            hearth_kinematics::BUILTIN_ROBOTS
                .iter()
                .find(|r| r.name == name)
                .ok_or_else(|| SceneError::UnknownRobot {
                    name: name.to_owned(),
                    known: hearth_kinematics::builtin_names().join(", "),
                })?,
        ),
        None => None,
    };
    let objects_dir = dir.join("objects");
    std::fs::create_dir_all(&objects_dir).map_err(|e| SceneError::io(&objects_dir, e))?;
    let mut manifest = Manifest::default();
    write(&dir.join("building.urdf"), &building_urdf(scene))?;
    manifest.bodies.push(ManifestBody {
        name: "building".into(),
        urdf: "building.urdf".into(),
        position: [0.0; 3],
        quat_xyzw: [0.0, 0.0, 0.0, 1.0],
        fixed: true,
        robot: false,
        joints: BTreeMap::new(),
    });
    let mut used = std::collections::HashSet::new();
    for (i, (o, a)) in scene.objects.iter().zip(&assets).enumerate() {
        // Names that sanitise alike get the object's index appended.
        let mut stem = file_name(&o.name);
        if stem.is_empty() || !used.insert(stem.clone()) {
            stem = format!("{stem}_{i}");
            used.insert(stem.clone());
        }
        let rel = format!("objects/{stem}.urdf");
        write(&dir.join(&rel), &a.urdf)?;
        let q = o.orientation.rotation();
        manifest.bodies.push(ManifestBody {
            name: o.name.clone(),
            urdf: rel,
            position: o.position,
            quat_xyzw: [q.i, q.j, q.k, q.w],
            fixed: o.fixed,
            robot: false,
            joints: o.joints.clone(),
        });
    }
    if let Some(r) = robot_urdf {
        let rel = format!("robot_{}.urdf", file_name(r.name));
        write(&dir.join(&rel), r.urdf)?;
        let (position, yaw) = scene.robot.as_ref().map_or(([0.0; 3], 0.0), |p| (p.position, p.yaw));
        let (s, c) = (yaw / 2.0).sin_cos();
        manifest.bodies.push(ManifestBody {
            name: r.name.to_owned(),
            urdf: rel,
            position,
            quat_xyzw: [0.0, 0.0, s, c],
            fixed: false,
            robot: true,
            joints: BTreeMap::new(),
        });
    }
    let text = serde_json::to_string_pretty(&manifest).map_err(|e| SceneError::invalid("manifest", e.to_string()))?;
    write(&dir.join("scene.json"), &text)?;
    Ok(manifest)
}
