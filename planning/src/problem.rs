//! Benchmark problem files: the MotionBenchMaker (MBM) JSON format of `bench/mbm/<robot>/`.
//!
//! A [`ProblemSet`] is one file (`<family>.json`): the robot, the planned joint names, and a list
//! of [`Problem`]s, each with box / sphere / cylinder obstacles ([`ObstacleSpec`]), a start
//! configuration and one or more goal configurations. [`JointsInfo`] is the robot's
//! `joints.json` (limits, allowed self-collision pairs, finger opening).
//!
//! Everything is checked on load: malformed JSON, an unknown field (a misspelt `valid` or
//! `obstacles` would otherwise load as its default), an unknown obstacle kind, a field of
//! another kind (a `radius` on a box), a configuration whose length differs from
//! `joint_names`, a non-finite number, a non-unit quaternion or a negative size gives a
//! [`ProblemError`] that names the file, the problem id and the field.
//!
//! ```
//! use hearth_planning::problem::ProblemSet;
//! use hearth_planning::Obstacles;
//! use parry3d::math::Pose;
//! use parry3d::shape::Ball;
//!
//! let json = r#"{"robot": "toy", "family": "demo", "joint_names": ["j1", "j2"],
//!   "problems": [{"id": 1, "valid": true,
//!     "obstacles": [{"kind": "sphere", "center": [1, 0, 0], "radius": 0.2, "name": "ball"}],
//!     "start": [0, 0], "goals": [[1, 1]]}]}"#;
//! let set = ProblemSet::from_json_str(json).unwrap();
//! let scene = set.problems[0].scene();
//! assert!(scene.intersects(&Ball::new(0.1), &Pose::translation(1.25, 0.0, 0.0)));
//!
//! let bad = json.replace("\"sphere\"", "\"cone\"");
//! let err = ProblemSet::from_json_str(&bad).unwrap_err();
//! assert!(err.to_string().contains("problem 1: obstacles[0].kind"), "{err}");
//! ```

use std::fmt;
use std::path::{Path, PathBuf};

use parry3d::math::{Pose, Rotation, Vector};
use serde::{Deserialize, Serialize};

use crate::error::Num;
use crate::obstacles::{Obstacle, ParryScene};

/// How far a quaternion's norm may be from 1 before it is rejected.
///
/// ```
/// use hearth_planning::problem::{Defect, ProblemSet, QUATERNION_NORM_TOLERANCE};
///
/// let set = r#"{"robot": "toy", "family": "f", "joint_names": ["j"], "problems": [{"id": 1, "start": [0],
///   "goals": [[1]], "obstacles": [{"kind": "box", "center": [0, 0, 0], "half_extents": [1, 1, 1],
///   "quat_xyzw": [0, 0, 0, W]}]}]}"#;
/// let with_w = |w: f64| ProblemSet::from_json_str(&set.replace('W', &w.to_string()));
/// assert!(with_w(1.0 + 0.5 * QUATERNION_NORM_TOLERANCE).is_ok());
/// let e = with_w(1.01).unwrap_err();
/// assert_eq!(e.field(), Some("obstacles[0].quat_xyzw"));
/// assert!(matches!(e.defect(), Some(Defect::NotUnitQuaternion(_))));
/// ```
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-4;

/// Largest magnitude of an obstacle's coordinate or size, in metres (1,000 km). Obstacles become
/// parry shapes in f32, whose range ends near 3.4 × 10³⁸: a centre beyond it would give a scene
/// without finite bounds. This limit is far beyond any real scene and far inside f32's range,
/// so a centre plus a size always stays finite.
///
/// ```
/// use hearth_planning::problem::{Defect, ProblemSet, MAX_EXTENT};
/// let set = r#"{"robot": "toy", "family": "f", "joint_names": ["j"], "problems": [{"id": 1,
///   "obstacles": [{"kind": "sphere", "center": [2e6, 0, 0], "radius": 1}], "start": [0], "goals": [[1]]}]}"#;
/// let e = ProblemSet::from_json_str(set).unwrap_err();
/// assert_eq!(e.field(), Some("obstacles[0].center[0]"));
/// assert_eq!(e.defect(), Some(&Defect::TooLarge(2e6)));
/// assert!(2e6 > MAX_EXTENT);
/// ```
pub const MAX_EXTENT: f64 = 1.0e6;

/// The file name in a problem folder that holds [`JointsInfo`], skipped by [`load_dir`].
///
/// ```
/// use hearth_planning::problem::{JointsInfo, JOINTS_FILE};
///
/// let folder = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data"));
/// let joints = JointsInfo::load(folder.join(JOINTS_FILE))?;
/// assert_eq!(joints.robot, "panda");
/// # Ok::<(), hearth_planning::problem::ProblemError>(())
/// ```
pub const JOINTS_FILE: &str = "joints.json";

/// What is wrong with one field of a problem file.
///
/// ```
/// use hearth_planning::problem::{Defect, ProblemSet};
///
/// let set = r#"{"robot": "toy", "family": "f", "joint_names": ["j1", "j2"],
///   "problems": [{"id": 4, "start": [0, 0], "goals": [[1]]}]}"#;
/// let e = ProblemSet::from_json_str(set).unwrap_err();
/// assert_eq!(e.defect(), Some(&Defect::WrongLength { expected: 2, found: 1 }));
/// assert_eq!(e.to_string(), "<string>: problem 4: goals[0] has 1 values, expected 2");
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Defect {
    /// The field is absent.
    #[error("missing")]
    Missing,
    /// An obstacle `kind` other than `box`, `sphere`, `cylinder`.
    #[error("unknown obstacle kind `{0}` (expected box, sphere or cylinder)")]
    UnknownKind(String),
    /// A vector has the wrong number of entries.
    #[error("has {found} values, expected {expected}")]
    WrongLength {
        /// Required length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A NaN or infinite number.
    #[error("is not finite ({})", Num(*.0))]
    NotFinite(f64),
    /// A quaternion whose norm is not 1 (within [`QUATERNION_NORM_TOLERANCE`]); includes zero.
    #[error("is not a unit quaternion (norm {})", Num(*.0))]
    NotUnitQuaternion(f64),
    /// A negative size (radius, half-extent, half-length).
    #[error("is negative ({})", Num(*.0))]
    Negative(f64),
    /// A list that must not be empty is empty.
    #[error("is empty")]
    Empty,
    /// An obstacle coordinate or size beyond ±[`MAX_EXTENT`].
    #[error("is {}, beyond ±{max} m", Num(*.0), max = MAX_EXTENT)]
    TooLarge(f64),
    /// A field that the obstacle's `kind` does not have (a `radius` on a box): a file that
    /// sets it meant another kind or another field.
    #[error("does not belong to a {0}")]
    NotForKind(&'static str),
    /// A lower limit above the upper one.
    #[error("lower limit {} is above upper limit {}", Num(*lower), Num(*upper))]
    InvertedLimits {
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
}

/// Loading a problem or joints file failed.
///
/// ```
/// use hearth_planning::problem::{ProblemError, ProblemSet};
///
/// let e = ProblemSet::from_json_str("{ not json").unwrap_err();
/// assert!(matches!(e, ProblemError::Json { .. }));
/// assert!(e.to_string().starts_with("<string>: malformed JSON"));
/// let e = ProblemSet::load("/no/such/file.json").unwrap_err();
/// assert!(matches!(e, ProblemError::Io { .. }));
/// ```
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// The file or folder could not be read.
    #[error("{}: cannot read: {source}", file.display())]
    Io {
        /// The file or folder.
        file: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not JSON of the expected shape (serde's message has line and column).
    #[error("{}: malformed JSON: {source}", file.display())]
    Json {
        /// The file (`<string>` for [`ProblemSet::from_json_str`]).
        file: PathBuf,
        /// The parser error.
        #[source]
        source: serde_json::Error,
    },
    /// A field has a bad value.
    #[error("{}: {}{field} {defect}", file.display(), ProblemPrefix(*problem))]
    Invalid {
        /// The file (`<string>` for in-memory input).
        file: PathBuf,
        /// The problem's `id`, `None` for a file-level field.
        problem: Option<u32>,
        /// The field path, e.g. `obstacles[3].quat_xyzw` or `goals[0]`.
        field: String,
        /// What is wrong with it.
        defect: Defect,
    },
}

impl ProblemError {
    /// The defect, for [`ProblemError::Invalid`].
    ///
    /// ```
    /// use hearth_planning::problem::{Defect, ProblemSet};
    ///
    /// let set = r#"{"robot": "toy", "family": "f", "joint_names": ["j"], "problems": [{"id": 1,
    ///   "obstacles": [{"kind": "sphere", "center": [0, 0, 1], "radius": -0.1}], "start": [0], "goals": [[1]]}]}"#;
    /// assert_eq!(ProblemSet::from_json_str(set).unwrap_err().defect(), Some(&Defect::Negative(-0.1)));
    /// assert_eq!(ProblemSet::from_json_str("[]").unwrap_err().defect(), None); // not a set at all
    /// ```
    pub fn defect(&self) -> Option<&Defect> {
        match self {
            Self::Invalid { defect, .. } => Some(defect),
            _ => None,
        }
    }

    /// The field path, for [`ProblemError::Invalid`].
    ///
    /// ```
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let set = r#"{"robot": "toy", "family": "f", "joint_names": ["j"], "problems": [{"id": 1,
    ///   "obstacles": [{"kind": "sphere", "center": [0, 0, 1], "radius": -0.1}], "start": [0], "goals": [[1]]}]}"#;
    /// assert_eq!(ProblemSet::from_json_str(set).unwrap_err().field(), Some("obstacles[0].radius"));
    /// ```
    pub fn field(&self) -> Option<&str> {
        match self {
            Self::Invalid { field, .. } => Some(field),
            _ => None,
        }
    }

    /// The problem id, for [`ProblemError::Invalid`] inside a problem.
    ///
    /// ```
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let bad_start = r#"{"robot": "toy", "family": "f", "joint_names": ["j"],
    ///   "problems": [{"id": 9, "start": [0, 0], "goals": [[1]]}]}"#;
    /// assert_eq!(ProblemSet::from_json_str(bad_start).unwrap_err().problem(), Some(9));
    /// let no_joints = r#"{"robot": "toy", "family": "f", "joint_names": [], "problems": []}"#;
    /// assert_eq!(ProblemSet::from_json_str(no_joints).unwrap_err().problem(), None); // a file-level field
    /// ```
    pub fn problem(&self) -> Option<u32> {
        match self {
            Self::Invalid { problem, .. } => *problem,
            _ => None,
        }
    }

    /// The file the error is about: the path given to a `load` function, `<string>` for
    /// parsed strings, `<memory>` for [`ProblemSet::validate`].
    ///
    /// ```
    /// use std::path::Path;
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let e = ProblemSet::load("/no/such/file.json").unwrap_err();
    /// assert_eq!(e.file(), Path::new("/no/such/file.json"));
    /// assert_eq!(ProblemSet::from_json_str("{").unwrap_err().file(), Path::new("<string>"));
    /// ```
    pub fn file(&self) -> &Path {
        match self {
            Self::Io { file, .. } | Self::Json { file, .. } | Self::Invalid { file, .. } => file,
        }
    }
}

struct ProblemPrefix(Option<u32>);

impl fmt::Display for ProblemPrefix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(id) => write!(f, "problem {id}: "),
            None => Ok(()),
        }
    }
}

/// One obstacle primitive, in metres, in the robot base frame (z up).
///
/// `quat_xyzw` rotates the primitive's local frame into the world (order x, y, z, w; normalised
/// on load). Serialises back to the file format (`"kind": "box" | "sphere" | "cylinder"`).
///
/// ```
/// use hearth_planning::problem::ObstacleSpec;
///
/// let shelf = ObstacleSpec::Box {
///     center: [0.8, 0.0, 0.5],
///     half_extents: [0.2, 0.4, 0.01],
///     quat_xyzw: [0.0, 0.0, 0.0, 1.0],
///     name: Some("shelf".into()),
/// };
/// let json = serde_json::to_value(&shelf)?;
/// assert_eq!(json["kind"], "box");
/// assert_eq!(json["half_extents"][1], 0.4);
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ObstacleSpec {
    /// A box.
    Box {
        /// Box centre.
        center: [f64; 3],
        /// Half-extents along the box's local x, y, z.
        half_extents: [f64; 3],
        /// Orientation, x y z w.
        quat_xyzw: [f64; 4],
        /// MBM collision-object id.
        #[serde(skip_serializing_if = "Option::is_none")]
        name: Option<String>,
    },
    /// A sphere.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
        /// MBM collision-object id.
        #[serde(skip_serializing_if = "Option::is_none")]
        name: Option<String>,
    },
    /// A flat-capped cylinder along its local z axis, spanning `center ± half_length · R·ẑ`.
    Cylinder {
        /// Mid-point of the axis.
        center: [f64; 3],
        /// Radius.
        radius: f64,
        /// Half the length along the local z axis.
        half_length: f64,
        /// Orientation, x y z w.
        quat_xyzw: [f64; 4],
        /// MBM collision-object id.
        #[serde(skip_serializing_if = "Option::is_none")]
        name: Option<String>,
    },
}

impl ObstacleSpec {
    /// `"box"`, `"sphere"` or `"cylinder"`: the file's `kind`.
    ///
    /// ```
    /// use hearth_planning::problem::ObstacleSpec;
    ///
    /// let ball = ObstacleSpec::Sphere { center: [0.0; 3], radius: 0.1, name: None };
    /// assert_eq!(ball.kind(), "sphere");
    /// ```
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Box { .. } => "box",
            Self::Sphere { .. } => "sphere",
            Self::Cylinder { .. } => "cylinder",
        }
    }

    /// The obstacle's name from the file, if any.
    ///
    /// ```
    /// use hearth_planning::problem::ObstacleSpec;
    ///
    /// let can = ObstacleSpec::Sphere { center: [0.0; 3], radius: 0.1, name: Some("Can1".into()) };
    /// assert_eq!(can.name(), Some("Can1"));
    /// assert_eq!(ObstacleSpec::Sphere { center: [0.0; 3], radius: 0.1, name: None }.name(), None);
    /// ```
    pub fn name(&self) -> Option<&str> {
        match self {
            Self::Box { name, .. } | Self::Sphere { name, .. } | Self::Cylinder { name, .. } => name.as_deref(),
        }
    }

    /// The primitive's centre (for a cylinder, the mid-point of its axis).
    ///
    /// ```
    /// use hearth_planning::problem::ObstacleSpec;
    ///
    /// let post = ObstacleSpec::Cylinder {
    ///     center: [0.5, 0.0, 0.3],
    ///     radius: 0.05,
    ///     half_length: 0.3,
    ///     quat_xyzw: [0.0, 0.0, 0.0, 1.0],
    ///     name: None,
    /// };
    /// assert_eq!(post.center(), [0.5, 0.0, 0.3]);
    /// ```
    pub fn center(&self) -> [f64; 3] {
        match self {
            Self::Box { center, .. } | Self::Sphere { center, .. } | Self::Cylinder { center, .. } => *center,
        }
    }

    /// The parry obstacle (f32), named after the file's `name` or `"<kind><index>"` without one.
    ///
    /// ```
    /// use hearth_planning::problem::ObstacleSpec;
    /// let spec = ObstacleSpec::Sphere { center: [0.0, 0.0, 1.0], radius: 0.5, name: None };
    /// let o = spec.to_obstacle(3);
    /// assert_eq!(o.name, "sphere3");
    /// assert!((o.aabb().maxs.z - 1.5).abs() < 1e-6);
    /// ```
    pub fn to_obstacle(&self, index: usize) -> Obstacle {
        let name = self
            .name()
            .map_or_else(|| format!("{}{index}", self.kind()), str::to_owned);
        let v = |a: [f64; 3]| Vector::new(a[0] as f32, a[1] as f32, a[2] as f32);
        // A size of -0 (which validation lets through: it is not below 0) becomes +0, the
        // sign parry's shapes require.
        let size = |x: f64| x as f32 + 0.0;
        let sizes = |a: [f64; 3]| Vector::new(size(a[0]), size(a[1]), size(a[2]));
        let pose = |c: [f64; 3], q: [f64; 4]| {
            let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
            let n = if n > 0.0 { n } else { 1.0 };
            let r = Rotation::from_xyzw(
                (q[0] / n) as f32,
                (q[1] / n) as f32,
                (q[2] / n) as f32,
                (q[3] / n) as f32,
            );
            Pose::from_parts(v(c), r.normalize())
        };
        match self {
            Self::Box {
                center,
                half_extents,
                quat_xyzw,
                ..
            } => Obstacle::cuboid(name, pose(*center, *quat_xyzw), sizes(*half_extents)),
            Self::Sphere { center, radius, .. } => Obstacle::ball(name, v(*center), size(*radius)),
            Self::Cylinder {
                center,
                radius,
                half_length,
                quat_xyzw,
                ..
            } => Obstacle::cylinder(name, pose(*center, *quat_xyzw), size(*half_length), size(*radius)),
        }
    }
}

/// One motion-planning query: obstacles, a start and goal configurations (in the set's
/// `joint_names` order).
///
/// ```
/// use hearth_planning::problem::ProblemSet;
///
/// let set = ProblemSet::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/panda_table_pick.json"))?;
/// let p = set.problem(1).unwrap();
/// assert!(p.valid);
/// assert_eq!(p.obstacles.len(), 12);
/// assert_eq!(p.start.len(), set.joint_names.len());
/// assert!(p.goals.iter().all(|g| g.len() == 7));
/// # Ok::<(), hearth_planning::problem::ProblemError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Problem {
    /// The MBM problem index (1–100).
    pub id: u32,
    /// Start collision-free and some goal collision-free in VAMP's model; planners skip `false`.
    pub valid: bool,
    /// The obstacles.
    pub obstacles: Vec<ObstacleSpec>,
    /// Start configuration.
    pub start: Vec<f64>,
    /// Goal configurations; reaching any one solves the problem.
    pub goals: Vec<Vec<f64>>,
}

impl Problem {
    /// A [`ParryScene`] of the obstacles (margin 0), obstacle `i` as `ObstacleId(i)`, named as
    /// [`ObstacleSpec::to_obstacle`] names them.
    ///
    /// ```
    /// use hearth_planning::obstacles::{ObstacleId, Obstacles};
    /// use hearth_planning::problem::ProblemSet;
    /// use parry3d::math::Vector;
    ///
    /// let set = ProblemSet::from_json_str(r#"{"robot": "toy", "family": "f", "joint_names": ["j"],
    ///   "problems": [{"id": 1, "start": [0], "goals": [[1]], "obstacles": [
    ///     {"kind": "sphere", "center": [1, 0, 0], "radius": 0.2, "name": "ball"},
    ///     {"kind": "cylinder", "center": [0, 1, 0.5], "radius": 0.1, "half_length": 0.5,
    ///      "quat_xyzw": [0, 0, 0, 1]}]}]}"#)?;
    /// let scene = set.problems[0].scene();
    /// assert_eq!(scene.find("ball"), Some(ObstacleId(0)));
    /// assert_eq!(scene.name(ObstacleId(1)), Some("cylinder1"));
    /// assert!(scene.ball_hits(Vector::new(0.0, 1.0, 0.95), 0.01)); // the cylinder stands along z
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    pub fn scene(&self) -> ParryScene {
        self.obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| o.to_obstacle(i))
            .collect()
    }
}

/// One problem file: a robot, a family (scene type) and its problems.
///
/// ```
/// use hearth_planning::problem::ProblemSet;
///
/// let set = ProblemSet::from_json_str(r#"{"robot": "toy", "family": "open", "joint_names": ["a", "b"],
///   "problems": [{"id": 1, "start": [0, 0], "goals": [[1, 1]]}, {"id": 2, "start": [1, 1], "goals": [[0, 0]]}]}"#)?;
/// assert_eq!((set.robot.as_str(), set.family.as_str()), ("toy", "open"));
/// assert_eq!(set.joint_names, ["a", "b"]);
/// assert_eq!(set.problems.len(), 2);
/// # Ok::<(), hearth_planning::problem::ProblemError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProblemSet {
    /// Robot name (`panda`, `fetch`).
    pub robot: String,
    /// Problem family (`table_pick`, `bookshelf_small`, …).
    pub family: String,
    /// Planned joints, in the order of every configuration.
    pub joint_names: Vec<String>,
    /// Where the data came from (free-form, informational).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<serde_json::Value>,
    /// The problems, in file order.
    pub problems: Vec<Problem>,
}

impl ProblemSet {
    /// Reads and checks a problem file.
    ///
    /// ```
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let set = ProblemSet::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/fetch_table_pick.json"))?;
    /// assert_eq!((set.robot.as_str(), set.family.as_str()), ("fetch", "table_pick"));
    /// assert_eq!(set.joint_names.len(), 8);
    /// assert!(set.problem(7).is_some());
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    ///
    /// # Errors
    /// [`ProblemError`] naming `path` (and the problem id and field for a bad value).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ProblemError> {
        let path = path.as_ref();
        let text = read(path)?;
        Self::parse(&text, path)
    }

    /// Parses and checks a problem set from a JSON string (errors name the file `<string>`). A
    /// problem's `valid` defaults to `true` and its `obstacles` to none.
    ///
    /// ```
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let set = ProblemSet::from_json_str(r#"{"robot": "toy", "family": "f", "joint_names": ["j"],
    ///   "problems": [{"id": 3, "start": [0], "goals": [[1], [-1]]}]}"#)?;
    /// let p = &set.problems[0];
    /// assert!(p.valid && p.obstacles.is_empty());
    /// assert_eq!(p.goals, [[1.0], [-1.0]]);
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    ///
    /// # Errors
    /// As [`ProblemSet::load`].
    pub fn from_json_str(json: &str) -> Result<Self, ProblemError> {
        Self::parse(json, Path::new("<string>"))
    }

    fn parse(json: &str, file: &Path) -> Result<Self, ProblemError> {
        let raw: RawSet = serde_json::from_str(json).map_err(|source| ProblemError::Json {
            file: file.to_owned(),
            source,
        })?;
        let mut ctx = Ctx { file, problem: None };
        if raw.joint_names.is_empty() {
            return Err(ctx.err("joint_names", Defect::Empty));
        }
        let dof = raw.joint_names.len();
        let problems = raw
            .problems
            .into_iter()
            .map(|p| {
                ctx.problem = Some(p.id);
                p.convert(&ctx, dof)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            robot: raw.robot,
            family: raw.family,
            joint_names: raw.joint_names,
            source: raw.source,
            problems,
        })
    }

    /// Re-checks a set built or edited in code (the same checks as loading; errors name the
    /// file `<memory>`).
    ///
    /// ```
    /// use std::path::Path;
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let mut set = ProblemSet::from_json_str(r#"{"robot": "toy", "family": "f", "joint_names": ["j"],
    ///   "problems": [{"id": 3, "start": [0], "goals": [[1]]}]}"#)?;
    /// assert!(set.validate().is_ok());
    /// set.problems[0].start.push(0.5);
    /// let e = set.validate().unwrap_err();
    /// assert_eq!((e.file(), e.problem(), e.field()), (Path::new("<memory>"), Some(3), Some("start")));
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    ///
    /// # Errors
    /// The first bad field found.
    pub fn validate(&self) -> Result<(), ProblemError> {
        let mut ctx = Ctx {
            file: Path::new("<memory>"),
            problem: None,
        };
        if self.joint_names.is_empty() {
            return Err(ctx.err("joint_names", Defect::Empty));
        }
        for p in &self.problems {
            ctx.problem = Some(p.id);
            let raw = RawProblem {
                id: p.id,
                valid: p.valid,
                obstacles: p.obstacles.iter().map(RawObstacle::from).collect(),
                start: p.start.clone(),
                goals: p.goals.clone(),
            };
            raw.convert(&ctx, self.joint_names.len())?;
        }
        Ok(())
    }

    /// Problems whose `valid` flag is set, in file order.
    ///
    /// ```
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let set = ProblemSet::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/panda_table_pick.json"))?;
    /// let ids: Vec<u32> = set.valid_problems().map(|p| p.id).collect();
    /// assert_eq!(ids, [1]); // problem 41 is flagged invalid
    /// assert_eq!(set.problems.len(), 2);
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    pub fn valid_problems(&self) -> impl Iterator<Item = &Problem> {
        self.problems.iter().filter(|p| p.valid)
    }

    /// The problem with this id (the first, should ids repeat).
    ///
    /// ```
    /// use hearth_planning::problem::ProblemSet;
    ///
    /// let set = ProblemSet::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/panda_table_pick.json"))?;
    /// assert!(set.problem(41).is_some_and(|p| !p.valid));
    /// assert!(set.problem(2).is_none());
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    pub fn problem(&self, id: u32) -> Option<&Problem> {
        self.problems.iter().find(|p| p.id == id)
    }
}

/// Loads every `*.json` problem set in `dir` except [`JOINTS_FILE`], sorted by file name.
///
/// ```
/// use hearth_planning::problem::load_dir;
///
/// let sets = load_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data"))?;
/// let robots: Vec<&str> = sets.iter().map(|s| s.robot.as_str()).collect();
/// assert_eq!(robots, ["fetch", "panda"]); // fetch_table_pick.json, panda_table_pick.json
/// assert!(load_dir("/no/such/folder").is_err());
/// # Ok::<(), hearth_planning::problem::ProblemError>(())
/// ```
///
/// # Errors
/// The first file that fails to load, or the folder cannot be read.
pub fn load_dir(dir: impl AsRef<Path>) -> Result<Vec<ProblemSet>, ProblemError> {
    let dir = dir.as_ref();
    let io = |source| ProblemError::Io {
        file: dir.to_owned(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        let is_json = path.extension().is_some_and(|e| e == "json");
        let is_joints = path.file_name().is_some_and(|n| n == JOINTS_FILE);
        if is_json && !is_joints && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    files.iter().map(ProblemSet::load).collect()
}

/// Position bounds (`lower`, `upper`) of the planned joints.
///
/// ```
/// use hearth_planning::problem::JointsInfo;
///
/// let info = JointsInfo::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/joints.json"))?;
/// let bounds = info.notes.mbm_model_bounds.unwrap();
/// assert_eq!((bounds.lower.len(), bounds.upper.len()), (7, 7));
/// assert!(bounds.upper[3] > info.upper[3]); // MBM lets the Panda's elbow straighten further
/// # Ok::<(), hearth_planning::problem::ProblemError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    /// Lower bounds.
    pub lower: Vec<f64>,
    /// Upper bounds.
    pub upper: Vec<f64>,
}

/// The `notes` of a `joints.json`; every field may be absent.
///
/// ```
/// use hearth_planning::problem::{JointsInfo, JointsNotes};
///
/// let info = JointsInfo::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/joints.json"))?;
/// let pair = ["panda_hand".to_string(), "panda_leftfinger".to_string()];
/// assert!(info.notes.self_collision_allowed_pairs.contains(&pair));
/// assert_eq!(info.notes.mbm_finger_joint_positions, Some(vec![0.065, 0.065]));
/// assert_eq!(serde_json::from_str::<JointsNotes>("{}").unwrap(), JointsNotes::default());
/// # Ok::<(), hearth_planning::problem::ProblemError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointsNotes {
    /// Link pairs allowed to touch (MBM's allowed-collision matrix).
    #[serde(default)]
    pub self_collision_allowed_pairs: Vec<[String; 2]>,
    /// The bounds the MBM/VAMP model samples in (Panda), when given.
    #[serde(default)]
    pub mbm_model_bounds: Option<Bounds>,
    /// Fixed Panda finger positions (m), when given.
    #[serde(default)]
    pub mbm_finger_joint_positions: Option<Vec<f64>>,
    /// Fixed Fetch gripper finger positions (m), when given.
    #[serde(default)]
    pub mbm_gripper_finger_positions: Option<Vec<f64>>,
}

/// A robot's `joints.json`: limits of the planned joints (configuration order) and MBM notes.
///
/// ```
/// use hearth_planning::problem::JointsInfo;
/// let info = JointsInfo::from_json_str(r#"{"robot": "toy", "joint_names": ["a"],
///     "lower": [-1], "upper": [1], "velocity": [2],
///     "notes": {"self_collision_allowed_pairs": [["l0", "l1"]], "mbm_finger_joint_positions": [0.04]}}"#)
///     .unwrap();
/// assert_eq!(info.finger_positions(), Some(&[0.04][..]));
/// assert!(info.acceleration.is_none());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointsInfo {
    /// Robot name.
    pub robot: String,
    /// Planned joints, in configuration order.
    pub joint_names: Vec<String>,
    /// Lower position limits.
    pub lower: Vec<f64>,
    /// Upper position limits.
    pub upper: Vec<f64>,
    /// Velocity limits.
    pub velocity: Vec<f64>,
    /// Acceleration limits, when given.
    #[serde(default)]
    pub acceleration: Option<Vec<f64>>,
    /// Jerk limits, when given.
    #[serde(default)]
    pub jerk: Option<Vec<f64>>,
    /// Which joints are continuous (bounded to ±π in the file), when given.
    #[serde(default)]
    pub continuous: Option<Vec<bool>>,
    /// Notes: allowed self-collision pairs, model bounds, finger opening.
    #[serde(default)]
    pub notes: JointsNotes,
}

impl JointsInfo {
    /// Reads and checks a `joints.json`.
    ///
    /// ```
    /// use hearth_planning::problem::JointsInfo;
    ///
    /// let info = JointsInfo::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/joints.json"))?;
    /// assert_eq!(info.joint_names[0], "panda_joint1");
    /// assert_eq!((info.lower.len(), info.upper.len(), info.velocity.len()), (7, 7, 7));
    /// assert!(info.acceleration.is_some() && info.jerk.is_some());
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    ///
    /// # Errors
    /// [`ProblemError`] naming the file and field (every limit list must match `joint_names`,
    /// be finite, and have `lower ≤ upper`).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ProblemError> {
        let path = path.as_ref();
        let text = read(path)?;
        Self::parse(&text, path)
    }

    /// Parses and checks a `joints.json` from a string (errors name the file `<string>`).
    ///
    /// ```
    /// use hearth_planning::problem::{Defect, JointsInfo};
    ///
    /// let json = r#"{"robot": "toy", "joint_names": ["a", "b"],
    ///   "lower": [-1, 2], "upper": [1, 1], "velocity": [1, 1]}"#;
    /// let e = JointsInfo::from_json_str(json).unwrap_err();
    /// assert_eq!(e.field(), Some("lower[1]"));
    /// assert_eq!(e.defect(), Some(&Defect::InvertedLimits { lower: 2.0, upper: 1.0 }));
    /// assert!(JointsInfo::from_json_str(&json.replace("[-1, 2]", "[-1, 0]")).is_ok());
    /// ```
    ///
    /// # Errors
    /// As [`JointsInfo::load`].
    pub fn from_json_str(json: &str) -> Result<Self, ProblemError> {
        Self::parse(json, Path::new("<string>"))
    }

    fn parse(json: &str, file: &Path) -> Result<Self, ProblemError> {
        let info: Self = serde_json::from_str(json).map_err(|source| ProblemError::Json {
            file: file.to_owned(),
            source,
        })?;
        let ctx = Ctx { file, problem: None };
        let n = info.joint_names.len();
        if n == 0 {
            return Err(ctx.err("joint_names", Defect::Empty));
        }
        ctx.vector("lower", &info.lower, n)?;
        ctx.vector("upper", &info.upper, n)?;
        ctx.vector("velocity", &info.velocity, n)?;
        for (field, v) in [("acceleration", &info.acceleration), ("jerk", &info.jerk)] {
            if let Some(v) = v {
                ctx.vector(field, v, n)?;
            }
        }
        if let Some(c) = &info.continuous
            && c.len() != n
        {
            return Err(ctx.err(
                "continuous",
                Defect::WrongLength {
                    expected: n,
                    found: c.len(),
                },
            ));
        }
        for (i, (&lower, &upper)) in info.lower.iter().zip(&info.upper).enumerate() {
            if lower > upper {
                return Err(ctx.err(format!("lower[{i}]"), Defect::InvertedLimits { lower, upper }));
            }
        }
        if let Some(b) = &info.notes.mbm_model_bounds {
            ctx.vector("notes.mbm_model_bounds.lower", &b.lower, n)?;
            ctx.vector("notes.mbm_model_bounds.upper", &b.upper, n)?;
        }
        Ok(info)
    }

    /// The fixed finger positions MBM plans with (Panda `mbm_finger_joint_positions` or Fetch
    /// `mbm_gripper_finger_positions`), `None` when the notes give neither.
    ///
    /// ```
    /// use hearth_planning::problem::JointsInfo;
    ///
    /// let fetch = JointsInfo::from_json_str(r#"{"robot": "fetch", "joint_names": ["j"], "lower": [-1], "upper": [1],
    ///   "velocity": [1], "notes": {"mbm_gripper_finger_positions": [0.05, 0.05]}}"#)?;
    /// assert_eq!(fetch.finger_positions(), Some(&[0.05, 0.05][..]));
    /// let bare = JointsInfo::from_json_str(r#"{"robot": "toy", "joint_names": ["j"], "lower": [-1], "upper": [1],
    ///   "velocity": [1]}"#)?;
    /// assert_eq!(bare.finger_positions(), None);
    /// # Ok::<(), hearth_planning::problem::ProblemError>(())
    /// ```
    pub fn finger_positions(&self) -> Option<&[f64]> {
        self.notes
            .mbm_finger_joint_positions
            .as_deref()
            .or(self.notes.mbm_gripper_finger_positions.as_deref())
    }
}

fn read(path: &Path) -> Result<String, ProblemError> {
    std::fs::read_to_string(path).map_err(|source| ProblemError::Io {
        file: path.to_owned(),
        source,
    })
}

// ---- raw file layout and checks -------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSet {
    robot: String,
    family: String,
    joint_names: Vec<String>,
    #[serde(default)]
    source: Option<serde_json::Value>,
    problems: Vec<RawProblem>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProblem {
    id: u32,
    #[serde(default = "yes")]
    valid: bool,
    #[serde(default)]
    obstacles: Vec<RawObstacle>,
    start: Vec<f64>,
    goals: Vec<Vec<f64>>,
}

fn yes() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObstacle {
    kind: String,
    center: Option<Vec<f64>>,
    half_extents: Option<Vec<f64>>,
    radius: Option<f64>,
    half_length: Option<f64>,
    quat_xyzw: Option<Vec<f64>>,
    name: Option<String>,
}

impl From<&ObstacleSpec> for RawObstacle {
    fn from(spec: &ObstacleSpec) -> Self {
        let mut raw = RawObstacle {
            kind: spec.kind().to_owned(),
            center: Some(spec.center().to_vec()),
            half_extents: None,
            radius: None,
            half_length: None,
            quat_xyzw: None,
            name: spec.name().map(str::to_owned),
        };
        match spec {
            ObstacleSpec::Box {
                half_extents,
                quat_xyzw,
                ..
            } => {
                raw.half_extents = Some(half_extents.to_vec());
                raw.quat_xyzw = Some(quat_xyzw.to_vec());
            }
            ObstacleSpec::Sphere { radius, .. } => raw.radius = Some(*radius),
            ObstacleSpec::Cylinder {
                radius,
                half_length,
                quat_xyzw,
                ..
            } => {
                raw.radius = Some(*radius);
                raw.half_length = Some(*half_length);
                raw.quat_xyzw = Some(quat_xyzw.to_vec());
            }
        }
        raw
    }
}

struct Ctx<'a> {
    file: &'a Path,
    problem: Option<u32>,
}

impl Ctx<'_> {
    fn err(&self, field: impl Into<String>, defect: Defect) -> ProblemError {
        ProblemError::Invalid {
            file: self.file.to_owned(),
            problem: self.problem,
            field: field.into(),
            defect,
        }
    }

    /// Checks length and finiteness.
    fn vector(&self, field: &str, v: &[f64], expected: usize) -> Result<(), ProblemError> {
        if v.len() != expected {
            return Err(self.err(
                field,
                Defect::WrongLength {
                    expected,
                    found: v.len(),
                },
            ));
        }
        match v.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(self.err(format!("{field}[{i}]"), Defect::NotFinite(v[i]))),
            None => Ok(()),
        }
    }

    fn array<const N: usize>(&self, field: &str, v: Option<&Vec<f64>>) -> Result<[f64; N], ProblemError> {
        let v = v.ok_or_else(|| self.err(field, Defect::Missing))?;
        self.vector(field, v, N)?;
        let mut out = [0.0; N];
        out.copy_from_slice(v);
        Ok(out)
    }

    fn size(&self, field: &str, v: Option<f64>) -> Result<f64, ProblemError> {
        let v = v.ok_or_else(|| self.err(field, Defect::Missing))?;
        if !v.is_finite() {
            return Err(self.err(field, Defect::NotFinite(v)));
        }
        if v < 0.0 {
            return Err(self.err(field, Defect::Negative(v)));
        }
        if v > MAX_EXTENT {
            return Err(self.err(field, Defect::TooLarge(v)));
        }
        Ok(v)
    }

    fn sizes(&self, field: &str, v: Option<&Vec<f64>>) -> Result<[f64; 3], ProblemError> {
        let a = self.point(field, v)?;
        match a.iter().position(|&x| x < 0.0) {
            Some(i) => Err(self.err(format!("{field}[{i}]"), Defect::Negative(a[i]))),
            None => Ok(a),
        }
    }

    /// Three finite values within ±[`MAX_EXTENT`] (a centre or half-extents).
    fn point(&self, field: &str, v: Option<&Vec<f64>>) -> Result<[f64; 3], ProblemError> {
        let a = self.array::<3>(field, v)?;
        match a.iter().position(|x| x.abs() > MAX_EXTENT) {
            Some(i) => Err(self.err(format!("{field}[{i}]"), Defect::TooLarge(a[i]))),
            None => Ok(a),
        }
    }

    fn quaternion(&self, field: &str, v: Option<&Vec<f64>>) -> Result<[f64; 4], ProblemError> {
        let q = self.array::<4>(field, v)?;
        let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            return Err(self.err(field, Defect::NotUnitQuaternion(norm)));
        }
        // A quaternion already normalised stays as it is, so that a set written and read
        // again is the same set (dividing by a norm one ulp off 1 would move its last bits).
        if (norm - 1.0).abs() <= 8.0 * f64::EPSILON {
            return Ok(q);
        }
        Ok(q.map(|x| x / norm))
    }
}

impl RawObstacle {
    fn convert(self, ctx: &Ctx<'_>, i: usize) -> Result<ObstacleSpec, ProblemError> {
        let f = |name: &str| format!("obstacles[{i}].{name}");
        let center = ctx.point(&f("center"), self.center.as_ref())?;
        // Fields of another kind: (field, present, kinds that have it).
        let fields = [
            ("half_extents", self.half_extents.is_some(), &["box"][..]),
            ("radius", self.radius.is_some(), &["sphere", "cylinder"][..]),
            ("half_length", self.half_length.is_some(), &["cylinder"][..]),
            ("quat_xyzw", self.quat_xyzw.is_some(), &["box", "cylinder"][..]),
        ];
        // (An unknown kind is reported below, whatever its fields.)
        let known = ["box", "sphere", "cylinder"].into_iter().find(|k| *k == self.kind);
        if let Some(kind) = known
            && let Some((field, ..)) = fields
                .iter()
                .find(|(_, present, kinds)| *present && !kinds.contains(&kind))
        {
            return Err(ctx.err(f(field), Defect::NotForKind(kind)));
        }
        let name = self.name;
        Ok(match self.kind.as_str() {
            "box" => ObstacleSpec::Box {
                center,
                half_extents: ctx.sizes(&f("half_extents"), self.half_extents.as_ref())?,
                quat_xyzw: ctx.quaternion(&f("quat_xyzw"), self.quat_xyzw.as_ref())?,
                name,
            },
            "sphere" => ObstacleSpec::Sphere {
                center,
                radius: ctx.size(&f("radius"), self.radius)?,
                name,
            },
            "cylinder" => ObstacleSpec::Cylinder {
                center,
                radius: ctx.size(&f("radius"), self.radius)?,
                half_length: ctx.size(&f("half_length"), self.half_length)?,
                quat_xyzw: ctx.quaternion(&f("quat_xyzw"), self.quat_xyzw.as_ref())?,
                name,
            },
            other => return Err(ctx.err(f("kind"), Defect::UnknownKind(other.to_owned()))),
        })
    }
}

impl RawProblem {
    fn convert(self, ctx: &Ctx<'_>, dof: usize) -> Result<Problem, ProblemError> {
        ctx.vector("start", &self.start, dof)?;
        if self.goals.is_empty() {
            return Err(ctx.err("goals", Defect::Empty));
        }
        for (g, goal) in self.goals.iter().enumerate() {
            ctx.vector(&format!("goals[{g}]"), goal, dof)?;
        }
        let obstacles = self
            .obstacles
            .into_iter()
            .enumerate()
            .map(|(i, o)| o.convert(ctx, i))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Problem {
            id: self.id,
            valid: self.valid,
            obstacles,
            start: self.start,
            goals: self.goals,
        })
    }
}
