//! The one error type of scenes: loading, validation, generation, maps and export.

use std::path::PathBuf;

use hearth_kinematics::Num;

use crate::assets::AssetError;

/// What went wrong with a scene; every variant names the culprit.
///
/// ```
/// use hearth_sim::scene::{SceneError, SceneFile};
/// let err = SceneFile::from_json_str("{\"name\": \"x\", \"bilding\": {}}").unwrap_err();
/// assert!(matches!(err, SceneError::Json { .. }));
/// assert!(err.to_string().contains("bilding"));
/// ```
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The text is not valid scene JSON (syntax, unknown field, wrong type, missing field).
    #[error("scene JSON, line {line} column {column}: {message}")]
    Json {
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// The parser's message (it names unknown fields and the expected ones).
        message: String,
    },
    /// A file could not be read or written.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        error: std::io::Error,
    },
    /// An object names a category the library does not have.
    #[error("object `{object}`: unknown category `{category}`")]
    UnknownCategory {
        /// The object.
        object: String,
        /// The category as written.
        category: String,
    },
    /// An object's asset could not be built (variant out of range, bad scale).
    #[error("object `{object}`: {reason}")]
    Asset {
        /// The object.
        object: String,
        /// Why.
        reason: Box<AssetError>,
    },
    /// A number is NaN or infinite.
    #[error("{field} is not a finite number ({value})")]
    NonFinite {
        /// Where, e.g. `objects[3].position[0]`.
        field: String,
        /// The value.
        value: f64,
    },
    /// A value is out of its allowed range or inconsistent.
    #[error("{field}: {message}")]
    Invalid {
        /// Where.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Two items of the same kind share a name.
    #[error("duplicate {kind} name `{name}`")]
    DuplicateName {
        /// `object`, `room`, `wall`, …
        kind: &'static str,
        /// The name.
        name: String,
    },
    /// Two objects occupy the same space.
    #[error("objects `{a}` and `{b}` overlap by {depth:.3} m")]
    Overlap {
        /// First object.
        a: String,
        /// Second object.
        b: String,
        /// Penetration depth along the axis of least overlap.
        depth: f64,
    },
    /// An object reaches into a wall.
    #[error("object `{object}` overlaps wall `{wall}` by {depth:.3} m")]
    WallOverlap {
        /// The object.
        object: String,
        /// The wall.
        wall: String,
        /// Penetration depth.
        depth: f64,
    },
    /// An initial joint position names a joint the object does not have.
    #[error("object `{object}`: unknown joint `{joint}` (its joints: {known})")]
    UnknownJoint {
        /// The object.
        object: String,
        /// The joint as written.
        joint: String,
        /// The joints it has, comma separated.
        known: String,
    },
    /// An initial joint position is outside the joint's limits.
    #[error("object `{object}`: joint `{joint}` = {} is outside [{}, {}]", Num(*value), Num(*lower), Num(*upper))]
    JointOutOfRange {
        /// The object.
        object: String,
        /// The joint.
        joint: String,
        /// The value.
        value: f64,
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
    /// An object rests on a support that is not in the scene.
    #[error("object `{object}` rests on `{support}`, which is not another object of the scene")]
    UnknownSupport {
        /// The object.
        object: String,
        /// The support as written.
        support: String,
    },
    /// A point given to a map query lies outside the map.
    #[error("{what} ({:.2}, {:.2}) is outside the map", Num(*x), Num(*y))]
    OffMap {
        /// `start` or `goal`.
        what: &'static str,
        /// x, metres.
        x: f64,
        /// y, metres.
        y: f64,
    },
    /// A point given to a map query is not traversable.
    #[error("{what} ({x:.2}, {y:.2}) is not traversable for the robot")]
    Blocked {
        /// `start` or `goal`.
        what: &'static str,
        /// x, metres.
        x: f64,
        /// y, metres.
        y: f64,
    },
    /// No traversable path joins two points.
    #[error("no traversable path from ({:.2}, {:.2}) to ({:.2}, {:.2})", from[0], from[1], to[0], to[1])]
    NoPath {
        /// Start.
        from: [f64; 2],
        /// Goal.
        to: [f64; 2],
    },
    /// A robot name that is not built in.
    #[error("unknown robot `{name}` (built-in: {known})")]
    UnknownRobot {
        /// The name.
        name: String,
        /// The built-in names, comma separated.
        known: String,
    },
}

impl SceneError {
    pub(crate) fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError::Invalid {
            field: field.into(),
            message: message.into(),
        }
    }

    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        SceneError::Io {
            path: path.to_owned(),
            error: source,
        }
    }
}
