//! The crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong while loading a robot model or evaluating its kinematics.
///
/// Every variant names the file, element or value at fault, so that a user can fix the input
/// without a debugger. Errors never leave a partially built model behind.
///
/// ```
/// use hearth_kinematics::{KinematicsError, RobotModel};
/// let err = RobotModel::from_urdf_str("<robot name='r'><link name='a'/>", None).unwrap_err();
/// assert!(matches!(err, KinematicsError::Xml { .. }));
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum KinematicsError {
    /// The text is not well-formed URDF XML.
    #[error("{source_name}: malformed URDF: {message}")]
    Xml {
        /// File name (or `<string>`) of the URDF.
        source_name: String,
        /// What the XML parser reported.
        message: String,
    },
    /// The file could not be read.
    #[error("{}: {error}", path.display())]
    Io {
        /// The path that failed.
        path: PathBuf,
        /// The underlying error.
        error: std::io::Error,
    },
    /// A URDF has no links.
    #[error("{source_name}: the robot has no <link>")]
    NoLinks {
        /// File name of the URDF.
        source_name: String,
    },
    /// Two links or two joints share a name.
    #[error("{source_name}: duplicate {element} name `{name}`")]
    DuplicateName {
        /// File name of the URDF.
        source_name: String,
        /// `link` or `joint`.
        element: &'static str,
        /// The repeated name.
        name: String,
    },
    /// A joint refers to a link that does not exist.
    #[error("{source_name}: joint `{joint}` names {role} link `{link}`, which does not exist")]
    MissingLink {
        /// File name of the URDF.
        source_name: String,
        /// The joint.
        joint: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The missing link.
        link: String,
    },
    /// A link is the child of more than one joint.
    #[error("{source_name}: link `{link}` is the child of two joints, `{first}` and `{second}`")]
    MultipleParents {
        /// File name of the URDF.
        source_name: String,
        /// The link.
        link: String,
        /// First parent joint.
        first: String,
        /// Second parent joint.
        second: String,
    },
    /// The joints form a cycle, so there is no root link.
    #[error("{source_name}: the joints form a cycle through link `{link}`")]
    JointCycle {
        /// File name of the URDF.
        source_name: String,
        /// A link on the cycle.
        link: String,
    },
    /// More than one link has no parent joint.
    #[error("{source_name}: the robot has several root links ({roots}); a URDF must be one tree")]
    MultipleRoots {
        /// File name of the URDF.
        source_name: String,
        /// The root links, comma separated.
        roots: String,
    },
    /// A joint type that this crate does not model.
    #[error(
        "{source_name}: joint `{joint}` has type `{kind}`, which is not supported \
         (supported: revolute, continuous, prismatic, fixed; model a mobile base as a separate pose)"
    )]
    UnsupportedJoint {
        /// File name of the URDF.
        source_name: String,
        /// The joint.
        joint: String,
        /// The joint type as written.
        kind: String,
    },
    /// A revolute or prismatic joint without a `<limit>` element.
    #[error("{source_name}: {kind} joint `{joint}` has no <limit lower=.. upper=.. velocity=..>")]
    MissingLimit {
        /// File name of the URDF.
        source_name: String,
        /// The joint.
        joint: String,
        /// Its type.
        kind: &'static str,
    },
    /// Lower limit above upper limit.
    #[error("{source_name}: joint `{joint}` has inverted limits: lower {lower} > upper {upper}")]
    InvertedLimits {
        /// File name of the URDF.
        source_name: String,
        /// The joint.
        joint: String,
        /// Lower position limit.
        lower: f64,
        /// Upper position limit.
        upper: f64,
    },
    /// A number in the model is NaN, infinite where it must be finite, or out of its range.
    #[error("{source_name}: {element}: {what} is {v}, {expected}", v = Num(*.value))]
    InvalidValue {
        /// File name of the URDF.
        source_name: String,
        /// Which element (e.g. `joint \`panda_joint1\``).
        element: String,
        /// Which attribute.
        what: &'static str,
        /// The offending value.
        value: f64,
        /// What was expected instead.
        expected: &'static str,
    },
    /// A joint axis of zero length.
    #[error("{source_name}: joint `{joint}` has a zero-length axis")]
    ZeroAxis {
        /// File name of the URDF.
        source_name: String,
        /// The joint.
        joint: String,
    },
    /// A mimic joint refers to a joint that is missing, fixed, or itself loops back.
    #[error("{source_name}: joint `{joint}` mimics `{target}`: {reason}")]
    BadMimic {
        /// File name of the URDF.
        source_name: String,
        /// The mimicking joint.
        joint: String,
        /// The joint it names.
        target: String,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// A mesh file referenced by the URDF could not be found.
    #[error("{source_name}: link `{link}`: mesh `{uri}` not found (looked in: {searched})")]
    MeshNotFound {
        /// File name of the URDF.
        source_name: String,
        /// The link.
        link: String,
        /// The `filename` attribute as written.
        uri: String,
        /// The candidate paths tried, comma separated.
        searched: String,
    },
    /// A mesh file exists but could not be loaded or has no triangles.
    #[error("{}: cannot load mesh: {message}", path.display())]
    MeshLoad {
        /// The mesh file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// No built-in robot has this name.
    #[error("unknown robot `{name}`: not a built-in robot ({known}) and not a .urdf path")]
    UnknownRobot {
        /// The requested name.
        name: String,
        /// The built-in names, comma separated.
        known: String,
    },
    /// No link with this name.
    #[error("robot `{robot}` has no link `{name}`")]
    UnknownLink {
        /// Robot name.
        robot: String,
        /// The requested link.
        name: String,
    },
    /// No joint with this name.
    #[error("robot `{robot}` has no joint `{name}`")]
    UnknownJoint {
        /// Robot name.
        robot: String,
        /// The requested joint.
        name: String,
    },
    /// No chain with this name.
    #[error("robot `{robot}` has no chain `{name}` (it has: {known})")]
    UnknownChain {
        /// Robot name.
        robot: String,
        /// The requested chain.
        name: String,
        /// The chains it has, comma separated.
        known: String,
    },
    /// A joint that cannot be part of a chain (fixed or mimic).
    #[error("joint `{name}` cannot be a chain variable: it is {why}")]
    NotAVariable {
        /// The joint.
        name: String,
        /// `fixed` or `a mimic joint`.
        why: &'static str,
    },
    /// A configuration or buffer of the wrong length.
    #[error("{what}: expected {expected} values, got {got}")]
    DimensionMismatch {
        /// What was passed (e.g. `configuration`).
        what: &'static str,
        /// Required length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// A configuration value that is NaN or infinite.
    #[error("{what}: value {index} ({name}) is {value}, not a finite number")]
    NonFinite {
        /// What was passed.
        what: &'static str,
        /// Index of the value.
        index: usize,
        /// Joint name (or `x`, `qw`, …).
        name: String,
        /// The value.
        value: f64,
    },
    /// A target pose that is not usable (NaN, zero quaternion).
    #[error("invalid target: {0}")]
    InvalidTarget(String),
    /// A self-collision cache that belongs to another model.
    #[error(
        "self-collision matrix {source_name} was computed for another model (fingerprint {found}, this model {expected})"
    )]
    StaleCache {
        /// Where it came from.
        source_name: String,
        /// The fingerprint in the file.
        found: String,
        /// The fingerprint of the model.
        expected: String,
    },
    /// A self-collision cache file that is not valid JSON of the expected shape.
    #[error("self-collision matrix {source_name}: {message}")]
    BadCache {
        /// Where it came from.
        source_name: String,
        /// What the parser said.
        message: String,
    },
}

/// Shorthand for results of this crate.
///
/// ```
/// use hearth_kinematics::{KinematicsError, Result, RobotModel};
/// fn hand_index(model: &RobotModel) -> Result<usize> {
///     model.link_index("panda_hand")
/// }
/// let panda = RobotModel::builtin("panda")?;
/// assert!(hand_index(&panda)? > 0);
/// assert!(matches!(hand_index(&RobotModel::builtin("fetch")?), Err(KinematicsError::UnknownLink { .. })));
/// # Ok::<(), KinematicsError>(())
/// ```
pub type Result<T, E = KinematicsError> = std::result::Result<T, E>;

/// A number as error messages show it: as Rust prints it when that is short, in scientific
/// notation when it is huge or tiny (a value of 10³⁰ would otherwise print 31 digits); with a
/// precision (`{:.2}`), that many decimals, and scientific notation only when huge. It
/// holds an `f64` or an `f32` (the precision parry's shapes use), each printed with its own
/// shortest digits.
///
/// ```
/// use hearth_kinematics::Num;
/// assert_eq!(Num(1e30).to_string(), "1e30");
/// assert_eq!(Num(0.25).to_string(), "0.25");
/// assert_eq!(Num(-2e-7).to_string(), "-2e-7");
/// assert_eq!(Num(f64::NAN).to_string(), "NaN");
/// assert_eq!(Num(1e30_f32).to_string(), "1e30");
/// assert_eq!(Num(-0.1_f32).to_string(), "-0.1");
/// // A precision keeps that many decimals, and scientific notation for huge values:
/// assert_eq!(format!("{:.2}", Num(3.14159)), "3.14");
/// assert_eq!(format!("{:.2}", Num(-1e30)), "-1.00e30");
/// assert_eq!(format!("{:.2}", Num(1e-9)), "0.00");
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Num<T = f64>(pub T);

macro_rules! short_display {
    ($($t:ty),*) => {$(
        impl std::fmt::Display for Num<$t> {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                let a = self.0.abs();
                let huge = a.is_finite() && a >= 1e7;
                match f.precision() {
                    // A fixed number of decimals rounds tiny values to zero, as asked.
                    Some(p) if huge => write!(f, "{:.p$e}", self.0),
                    Some(p) => write!(f, "{:.p$}", self.0),
                    None if huge || (a != 0.0 && a < 1e-4) => write!(f, "{:e}", self.0),
                    None => write!(f, "{}", self.0),
                }
            }
        }
    )*};
}
short_display!(f64, f32);
