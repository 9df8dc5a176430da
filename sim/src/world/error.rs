//! [`WorldError`]: everything that can go wrong when building, commanding or reading the world.

use super::ModelHandle;

/// An error from the simulator world. Every variant names the problem; a command that fails
/// leaves the world unchanged.
///
/// ```
/// use hearth_sim::world::{World, WorldConfig, WorldError};
/// let world = World::new(WorldConfig::default()).unwrap();
/// let err = world.joint_positions(hearth_sim::world::ModelHandle::from_index(7)).unwrap_err();
/// assert!(matches!(err, WorldError::UnknownModel { .. }));
/// assert!(err.to_string().contains("#7"));
/// ```
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum WorldError {
    /// A configuration value is invalid (non-finite, non-positive, …).
    #[error("invalid world configuration: `{field}` {reason}")]
    InvalidConfig {
        /// The offending field.
        field: &'static str,
        /// Why it was rejected.
        reason: String,
    },
    /// No model with this handle lives in the world.
    #[error("unknown model {handle}")]
    UnknownModel {
        /// The handle given.
        handle: ModelHandle,
    },
    /// No body with this handle lives in the world.
    #[error("unknown body (index {index}, generation {generation})")]
    UnknownBody {
        /// rapier's arena index.
        index: u32,
        /// rapier's arena generation.
        generation: u32,
    },
    /// The model has no link with this name.
    #[error("model `{model}` has no link `{link}`")]
    UnknownLink {
        /// Model instance name.
        model: String,
        /// The link name given.
        link: String,
    },
    /// The model has no joint with this name.
    #[error("model `{model}` has no joint `{joint}`")]
    UnknownJoint {
        /// Model instance name.
        model: String,
        /// The joint name given.
        joint: String,
    },
    /// The joint exists but cannot be commanded (fixed, or it mimics another joint).
    #[error("joint `{joint}` of `{model}` cannot be commanded: {reason}")]
    JointNotCommandable {
        /// Model instance name.
        model: String,
        /// Joint name.
        joint: String,
        /// Why.
        reason: &'static str,
    },
    /// A vector has the wrong number of entries.
    #[error("{what}: expected {expected} values, got {got}")]
    DimensionMismatch {
        /// What was being set.
        what: &'static str,
        /// Entries expected.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what}: value for `{name}` is not finite ({value})")]
    NonFinite {
        /// What was being set.
        what: &'static str,
        /// The joint or field name.
        name: String,
        /// The value given.
        value: f64,
    },
    /// A value lies outside its allowed range.
    #[error("{what}: value {value} for `{name}` is outside [{lower}, {upper}]")]
    OutOfRange {
        /// What was being set.
        what: &'static str,
        /// The joint or field name.
        name: String,
        /// The value given.
        value: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// The model has no controller of the requested kind (no wheels, no gripper, fixed base…).
    #[error("model `{model}` has no {controller}")]
    NoController {
        /// Model instance name.
        model: String,
        /// The controller asked for (e.g. "differential-drive base").
        controller: &'static str,
    },
    /// No named configuration with this name is known for the model.
    #[error("model `{model}` has no named configuration `{name}`")]
    UnknownConfiguration {
        /// Model instance name.
        model: String,
        /// The configuration name.
        name: String,
    },
    /// The model cannot be turned into a multibody.
    #[error("cannot spawn model `{model}`: {reason}")]
    InvalidModel {
        /// Model name.
        model: String,
        /// Why.
        reason: String,
    },
    /// The snapshot was taken from a world with a different layout.
    #[error("snapshot does not fit this world: {reason}")]
    SnapshotMismatch {
        /// Why.
        reason: &'static str,
    },
}

/// Result alias for world operations.
///
/// ```
/// # use hearth_sim::world::{WorldConfig, WorldResult};
/// fn check(config: &WorldConfig) -> WorldResult<f64> {
///     config.validate()?;
///     Ok(config.control_dt())
/// }
/// assert!(check(&WorldConfig::default()).is_ok());
/// ```
pub type WorldResult<T> = Result<T, WorldError>;

/// Checks that `value` is finite, naming it in the error.
pub(crate) fn check_finite(what: &'static str, name: &str, value: f64) -> WorldResult<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(WorldError::NonFinite {
            what,
            name: name.to_owned(),
            value,
        })
    }
}

/// Checks that `value` is finite and lies in `[lower, upper]`.
pub(crate) fn check_range(what: &'static str, name: &str, value: f64, lower: f64, upper: f64) -> WorldResult<()> {
    check_finite(what, name, value)?;
    if value < lower || value > upper {
        return Err(WorldError::OutOfRange {
            what,
            name: name.to_owned(),
            value,
            lower,
            upper,
        });
    }
    Ok(())
}

/// Checks a vector's length.
pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> WorldResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(WorldError::DimensionMismatch { what, expected, got })
    }
}
