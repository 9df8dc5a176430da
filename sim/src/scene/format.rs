//! The scene file format (JSON): building, objects, lights and an optional robot.
//!
//! Units are metres and radians, z is up, the floor is at z = 0. Unknown fields are errors (a
//! typo never passes silently). A minimal file:
//!
//! ```
//! use hearth_sim::scene::SceneFile;
//! let text = r#"{
//!   "name": "studio",
//!   "building": {
//!     "walls": [
//!       {"name": "south", "start": [0, 0], "end": [4, 0], "height": 2.7, "thickness": 0.2,
//!        "openings": [{"kind": "window", "center": 2.0, "width": 1.2, "bottom": 0.9, "height": 1.2}]}
//!     ],
//!     "rooms": [{"name": "living", "room_type": "living_room",
//!                "polygon": [[0, 0], [4, 0], [4, 3], [0, 3]]}]
//!   },
//!   "objects": [
//!     {"name": "table", "category": "table", "variant": 3, "position": [2, 1.5, 0]},
//!     {"name": "laptop", "category": "laptop", "position": [2, 1.5, 0.75],
//!      "orientation": {"yaw": 1.57}, "on": "table", "joints": {"lid_hinge": 1.9}}
//!   ],
//!   "lights": [{"name": "sun", "kind": "directional", "position": [0, 0, 10],
//!               "direction": [0.3, 0.2, -1], "intensity": 3.0}],
//!   "robot": {"name": "fetch", "position": [1, 1, 0], "yaw": 0}
//! }"#;
//! let scene = SceneFile::from_json_str(text).unwrap();
//! assert_eq!(scene.objects.len(), 2);
//! let again = SceneFile::from_json_str(&scene.to_json_string()).unwrap();
//! assert_eq!(scene, again);
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use super::SceneError;
use crate::assets::{Material, RoomType};

/// The current format version.
///
/// ```
/// assert_eq!(hearth_sim::scene::SceneFile::empty("e").version, hearth_sim::scene::SCENE_VERSION);
/// ```
pub const SCENE_VERSION: u32 = 1;

fn version() -> u32 {
    SCENE_VERSION
}
fn one() -> f64 {
    1.0
}
fn white() -> [f64; 3] {
    [1.0, 1.0, 1.0]
}
fn plaster() -> Material {
    Material::Plaster
}

/// A whole scene: the building, the objects in it, lights and an optional robot.
///
/// ```
/// let scene = hearth_sim::scene::generate(&hearth_sim::scene::GenerateOptions::default()).unwrap();
/// assert!(!scene.building.rooms.is_empty());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Format version ([`SCENE_VERSION`]).
    #[serde(default = "version")]
    pub version: u32,
    /// Scene name.
    pub name: String,
    /// Floors, walls, ceilings and rooms.
    pub building: Building,
    /// Furniture and small objects.
    #[serde(default)]
    pub objects: Vec<SceneObject>,
    /// Light sources.
    #[serde(default)]
    pub lights: Vec<Light>,
    /// Where a robot starts, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<RobotPlacement>,
}

/// The building shell.
///
/// ```
/// let b = hearth_sim::scene::Building::default();
/// assert!(b.walls.is_empty());
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Building {
    /// Floor slabs (top face at `z`).
    #[serde(default)]
    pub floors: Vec<Slab>,
    /// Walls as segments with openings.
    #[serde(default)]
    pub walls: Vec<Wall>,
    /// Ceiling slabs (bottom face at `z`).
    #[serde(default)]
    pub ceilings: Vec<Slab>,
    /// Named, typed rooms.
    #[serde(default)]
    pub rooms: Vec<Room>,
}

/// A horizontal slab over a polygon (floors and ceilings).
///
/// ```
/// use hearth_sim::{assets::Material, scene::Slab};
/// let s = Slab { name: "f".into(), polygon: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], z: 0.0, thickness: 0.1, material: Material::Wood };
/// assert_eq!(s.polygon.len(), 3);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slab {
    /// Name.
    pub name: String,
    /// Outline, counter-clockwise, metres.
    pub polygon: Vec<[f64; 2]>,
    /// Height of the walking (floor) or visible (ceiling) face.
    pub z: f64,
    /// Thickness.
    pub thickness: f64,
    /// Surface material.
    pub material: Material,
}

/// A straight wall from `start` to `end` (its centre line) with openings.
///
/// ```
/// use hearth_sim::scene::Wall;
/// let w = Wall::new("w", [0.0, 0.0], [3.0, 4.0], 2.7, 0.12);
/// assert_eq!(w.length(), 5.0);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wall {
    /// Name.
    pub name: String,
    /// Start of the centre line.
    pub start: [f64; 2],
    /// End of the centre line.
    pub end: [f64; 2],
    /// Height.
    pub height: f64,
    /// Thickness.
    pub thickness: f64,
    /// Surface material.
    #[serde(default = "plaster")]
    pub material: Material,
    /// Door and window openings.
    #[serde(default)]
    pub openings: Vec<Opening>,
}

impl Wall {
    /// A plaster wall without openings.
    ///
    /// ```
    /// let w = hearth_sim::scene::Wall::new("w", [0.0, 0.0], [2.0, 0.0], 2.5, 0.1);
    /// assert!(w.openings.is_empty());
    /// ```
    pub fn new(name: &str, start: [f64; 2], end: [f64; 2], height: f64, thickness: f64) -> Wall {
        Wall {
            name: name.to_owned(),
            start,
            end,
            height,
            thickness,
            material: Material::Plaster,
            openings: Vec::new(),
        }
    }

    /// Length of the centre line.
    ///
    /// ```
    /// assert_eq!(hearth_sim::scene::Wall::new("w", [1.0, 1.0], [1.0, 3.0], 2.5, 0.1).length(), 2.0);
    /// ```
    pub fn length(&self) -> f64 {
        (self.end[0] - self.start[0]).hypot(self.end[1] - self.start[1])
    }

    /// Direction angle of the centre line (radians from +x).
    ///
    /// ```
    /// let w = hearth_sim::scene::Wall::new("w", [0.0, 0.0], [0.0, 2.0], 2.5, 0.1);
    /// assert!((w.yaw() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    /// ```
    pub fn yaw(&self) -> f64 {
        (self.end[1] - self.start[1]).atan2(self.end[0] - self.start[0])
    }

    /// The point at distance `s` along the centre line.
    ///
    /// ```
    /// let w = hearth_sim::scene::Wall::new("w", [0.0, 0.0], [4.0, 0.0], 2.5, 0.1);
    /// assert_eq!(w.point_at(1.0), [1.0, 0.0]);
    /// ```
    pub fn point_at(&self, s: f64) -> [f64; 2] {
        let (sin, cos) = self.yaw().sin_cos();
        [self.start[0] + cos * s, self.start[1] + sin * s]
    }

    /// The solid pieces of the wall as (from, to, bottom, top) intervals along its length,
    /// after cutting out the openings.
    ///
    /// ```
    /// use hearth_sim::scene::{Opening, OpeningKind, Wall};
    /// let mut w = Wall::new("w", [0.0, 0.0], [4.0, 0.0], 2.5, 0.1);
    /// w.openings.push(Opening { kind: OpeningKind::Door, center: 2.0, width: 1.0, bottom: 0.0, height: 2.1 });
    /// assert_eq!(w.pieces().len(), 3); // left, right, above the door
    /// ```
    pub fn pieces(&self) -> Vec<[f64; 4]> {
        let len = self.length();
        let mut cuts: Vec<&Opening> = self.openings.iter().collect();
        cuts.sort_by(|a, b| a.center.total_cmp(&b.center));
        let mut out = Vec::new();
        let mut s = 0.0;
        for o in cuts {
            let (a, b) = ((o.center - o.width / 2.0).max(0.0), (o.center + o.width / 2.0).min(len));
            if a > s {
                out.push([s, a, 0.0, self.height]);
            }
            if b > a {
                if o.bottom > 0.0 {
                    out.push([a, b, 0.0, o.bottom]);
                }
                if o.bottom + o.height < self.height {
                    out.push([a, b, o.bottom + o.height, self.height]);
                }
            }
            s = s.max(b);
        }
        if s < len {
            out.push([s, len, 0.0, self.height]);
        }
        out
    }
}

/// What fills an opening.
///
/// ```
/// assert_eq!(serde_json::to_string(&hearth_sim::scene::OpeningKind::Door).unwrap(), "\"door\"");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpeningKind {
    /// A doorway (floor to `height`).
    Door,
    /// A window (from `bottom` to `bottom + height`).
    Window,
}

/// An opening in a wall.
///
/// ```
/// use hearth_sim::scene::{Opening, OpeningKind};
/// let o = Opening { kind: OpeningKind::Window, center: 1.0, width: 1.2, bottom: 0.9, height: 1.2 };
/// assert!(o.bottom > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Opening {
    /// Door or window.
    pub kind: OpeningKind,
    /// Distance from the wall's start to the opening's centre, along the wall.
    pub center: f64,
    /// Width along the wall.
    pub width: f64,
    /// Height of the opening's bottom above the floor.
    #[serde(default)]
    pub bottom: f64,
    /// Height of the opening.
    pub height: f64,
}

/// A named room of a type, outlined by a polygon.
///
/// ```
/// use hearth_sim::{assets::RoomType, scene::Room};
/// let r = Room { name: "k".into(), room_type: RoomType::Kitchen, polygon: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]] };
/// assert_eq!(r.area(), 6.0);
/// assert_eq!(r.center(), [1.0, 1.5]);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Room {
    /// Name.
    pub name: String,
    /// Type.
    pub room_type: RoomType,
    /// Outline (wall centre lines), metres.
    pub polygon: Vec<[f64; 2]>,
}

impl Room {
    /// Area of the polygon, m².
    ///
    /// ```
    /// # use hearth_sim::{assets::RoomType, scene::Room};
    /// let r = Room { name: "r".into(), room_type: RoomType::Office, polygon: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] };
    /// assert_eq!(r.area(), 0.5);
    /// ```
    pub fn area(&self) -> f64 {
        let p = &self.polygon;
        let n = p.len();
        let twice: f64 = (0..n)
            .map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1])
            .sum();
        twice.abs() / 2.0
    }

    /// Centre of the polygon's bounding box.
    ///
    /// ```
    /// # use hearth_sim::{assets::RoomType, scene::Room};
    /// let r = Room { name: "r".into(), room_type: RoomType::Office, polygon: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]] };
    /// assert_eq!(r.center(), [2.0, 1.0]);
    /// ```
    pub fn center(&self) -> [f64; 2] {
        let (lo, hi) = self.bounds();
        [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0]
    }

    /// Lower and upper corners of the polygon's bounding box.
    ///
    /// ```
    /// # use hearth_sim::{assets::RoomType, scene::Room};
    /// let r = Room { name: "r".into(), room_type: RoomType::Office, polygon: vec![[1.0, 0.0], [4.0, 0.0], [4.0, 2.0]] };
    /// assert_eq!(r.bounds(), ([1.0, 0.0], [4.0, 2.0]));
    /// ```
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &self.polygon {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Whether a point lies inside the polygon (even-odd rule).
    ///
    /// ```
    /// # use hearth_sim::{assets::RoomType, scene::Room};
    /// let r = Room { name: "r".into(), room_type: RoomType::Office, polygon: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]] };
    /// assert!(r.contains([1.0, 1.0]) && !r.contains([5.0, 1.0]));
    /// ```
    pub fn contains(&self, q: [f64; 2]) -> bool {
        let p = &self.polygon;
        let n = p.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (p[i], p[(i + n - 1) % n]);
            if (a[1] > q[1]) != (b[1] > q[1]) && q[0] < (b[0] - a[0]) * (q[1] - a[1]) / (b[1] - a[1]) + a[0] {
                inside = !inside;
            }
        }
        inside
    }
}

/// Orientation of an object: a yaw about z, or a full quaternion.
///
/// ```
/// use hearth_sim::scene::Orientation;
/// let o: Orientation = serde_json::from_str(r#"{"yaw": 0.5}"#).unwrap();
/// assert!((o.yaw() - 0.5).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Orientation {
    /// Rotation about +z, radians.
    Yaw(f64),
    /// Quaternion x, y, z, w (normalised on use).
    QuatXyzw([f64; 4]),
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation::Yaw(0.0)
    }
}

impl Orientation {
    /// The rotation (a zero quaternion gives the identity).
    ///
    /// ```
    /// use hearth_sim::scene::Orientation;
    /// let q = Orientation::QuatXyzw([0.0, 0.0, 0.0, 2.0]).rotation();
    /// assert!(q.angle() < 1e-12);
    /// ```
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        match *self {
            Orientation::Yaw(y) => UnitQuaternion::from_euler_angles(0.0, 0.0, y),
            Orientation::QuatXyzw([x, y, z, w]) => {
                let q = Quaternion::new(w, x, y, z);
                if q.norm() > 1e-12 {
                    UnitQuaternion::from_quaternion(q)
                } else {
                    UnitQuaternion::identity()
                }
            }
        }
    }

    /// The heading: rotation about z of the rotated x axis.
    ///
    /// ```
    /// assert_eq!(hearth_sim::scene::Orientation::Yaw(1.0).yaw(), 1.0);
    /// ```
    pub fn yaw(&self) -> f64 {
        match *self {
            Orientation::Yaw(y) => y,
            Orientation::QuatXyzw(_) => self.rotation().euler_angles().2,
        }
    }
}

/// An object placed in the scene.
///
/// ```
/// use hearth_sim::scene::SceneObject;
/// let o = SceneObject::new("chair_1", "chair", 0, [1.0, 2.0, 0.0]);
/// assert_eq!(o.scale, 1.0);
/// assert!(!o.fixed);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneObject {
    /// Unique name.
    pub name: String,
    /// Category name (see [`crate::assets::Category`]).
    pub category: String,
    /// Shape variant.
    #[serde(default)]
    pub variant: usize,
    /// Position of the asset origin (footprint centre at its bottom).
    pub position: [f64; 3],
    /// Orientation.
    #[serde(default)]
    pub orientation: Orientation,
    /// Uniform scale.
    #[serde(default = "one")]
    pub scale: f64,
    /// Replaces the category's main material.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<Material>,
    /// Whether the base is fixed to the world (joints still move).
    #[serde(default)]
    pub fixed: bool,
    /// Initial joint positions by joint name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joints: BTreeMap<String, f64>,
    /// The object this one rests on (it may overlap its support).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on: Option<String>,
    /// The room it belongs to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub room: Option<String>,
    /// Bounding box in the object frame, as written by the generator (informational).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bbox: Option<BoundingBox>,
}

impl SceneObject {
    /// An object with defaults: yaw 0, scale 1, free, no joint positions.
    ///
    /// ```
    /// let o = hearth_sim::scene::SceneObject::new("m", "mug", 1, [0.0, 0.0, 0.9]);
    /// assert_eq!(o.variant, 1);
    /// ```
    pub fn new(name: &str, category: &str, variant: usize, position: [f64; 3]) -> Self {
        SceneObject {
            name: name.to_owned(),
            category: category.to_owned(),
            variant,
            position,
            orientation: Orientation::default(),
            scale: 1.0,
            material: None,
            fixed: false,
            joints: BTreeMap::new(),
            on: None,
            room: None,
            bbox: None,
        }
    }

    /// Pose of the object frame in the world.
    ///
    /// ```
    /// let o = hearth_sim::scene::SceneObject::new("m", "mug", 1, [1.0, 2.0, 0.9]);
    /// assert_eq!(o.pose().translation.vector.x, 1.0);
    /// ```
    pub fn pose(&self) -> Isometry3<f64> {
        let [x, y, z] = self.position;
        Isometry3::from_parts(Translation3::new(x, y, z), self.orientation.rotation())
    }
}

/// An axis-aligned box in an object's frame.
///
/// ```
/// let b = hearth_sim::scene::BoundingBox { min: [-1.0, -1.0, 0.0], max: [1.0, 1.0, 1.0] };
/// assert_eq!(b.max[2], 1.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundingBox {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// Kind of light source.
///
/// ```
/// assert_eq!(serde_json::to_string(&hearth_sim::scene::LightKind::Point).unwrap(), "\"point\"");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LightKind {
    /// Omnidirectional point light.
    Point,
    /// Cone light along `direction`.
    Spot,
    /// Parallel light along `direction` (sun).
    Directional,
}

/// A light source.
///
/// ```
/// use hearth_sim::scene::{Light, LightKind};
/// let l = Light { name: "lamp".into(), kind: LightKind::Point, position: [1.0, 1.0, 2.5], direction: None, color: [1.0; 3], intensity: 40.0 };
/// assert!(l.direction.is_none());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: LightKind,
    /// Position, metres.
    pub position: [f64; 3],
    /// Direction for spot and directional lights.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
    /// Linear RGB colour.
    #[serde(default = "white")]
    pub color: [f64; 3],
    /// Intensity (candela for point and spot lights, lux for directional).
    pub intensity: f64,
}

/// Where a robot starts.
///
/// ```
/// let r = hearth_sim::scene::RobotPlacement { name: "fetch".into(), position: [0.0, 0.0, 0.0], yaw: 0.0 };
/// assert_eq!(r.name, "fetch");
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotPlacement {
    /// Built-in robot name.
    pub name: String,
    /// Base position.
    pub position: [f64; 3],
    /// Heading, radians.
    #[serde(default)]
    pub yaw: f64,
}

impl SceneFile {
    /// An empty scene with a name.
    ///
    /// ```
    /// let s = hearth_sim::scene::SceneFile::empty("void");
    /// assert!(s.validate().is_ok());
    /// ```
    pub fn empty(name: &str) -> Self {
        SceneFile {
            version: SCENE_VERSION,
            name: name.to_owned(),
            building: Building::default(),
            objects: Vec::new(),
            lights: Vec::new(),
            robot: None,
        }
    }

    /// Parses JSON text and validates it.
    ///
    /// ```
    /// let err = hearth_sim::scene::SceneFile::from_json_str("{\"name\": 3}").unwrap_err();
    /// assert!(err.to_string().contains("line 1"));
    /// ```
    pub fn from_json_str(text: &str) -> Result<SceneFile, SceneError> {
        let scene: SceneFile = serde_json::from_str(text).map_err(|e| SceneError::Json {
            line: e.line(),
            column: e.column(),
            message: {
                // The position is reported in its own fields.
                let m = e.to_string();
                m.rfind(" at line ").map_or(m.clone(), |i| m[..i].to_owned())
            },
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads and validates a scene file.
    ///
    /// ```
    /// let err = hearth_sim::scene::SceneFile::load("/nonexistent/scene.json").unwrap_err();
    /// assert!(err.to_string().contains("/nonexistent/scene.json"));
    /// ```
    pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::io(path, e))?;
        SceneFile::from_json_str(&text)
    }

    /// Pretty JSON text of the scene.
    ///
    /// ```
    /// let s = hearth_sim::scene::SceneFile::empty("void");
    /// assert!(s.to_json_string().contains("\"void\""));
    /// ```
    pub fn to_json_string(&self) -> String {
        // Serialising plain data with string keys cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Writes the scene as pretty JSON.
    ///
    /// ```
    /// let path = std::env::temp_dir().join("hearth_doc_void_scene.json");
    /// hearth_sim::scene::SceneFile::empty("void").save(&path).unwrap();
    /// assert_eq!(hearth_sim::scene::SceneFile::load(&path).unwrap().name, "void");
    /// ```
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), SceneError> {
        let path = path.as_ref();
        std::fs::write(path, self.to_json_string()).map_err(|e| SceneError::io(path, e))
    }
}
