//! [`RandomizeError`]: what can go wrong when configuring or applying randomisation.

use crate::scene::SceneError;
use crate::sensors::SensorError;
use crate::world::WorldError;

/// Why a randomisation configuration was refused or could not be applied. Configuration errors
/// name the offending key (dotted path inside the `[randomization]` section).
///
/// ```
/// use hearth_sim::randomize::{RandomizationConfig, RandomizeError};
/// let err = RandomizationConfig::from_toml_str("[physics]\nfrition = true").unwrap_err();
/// assert!(matches!(err, RandomizeError::UnknownKey { ref key, .. } if key == "frition"));
/// let err = RandomizationConfig::from_toml_str("every_k_episodes = 0").unwrap_err();
/// assert!(matches!(err, RandomizeError::InvalidValue { ref key, .. } if key == "every_k_episodes"));
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RandomizeError {
    /// The section names a key that does not exist (a typo never passes silently).
    #[error("randomization: unknown key `{key}`: {message}")]
    UnknownKey {
        /// The unknown key.
        key: String,
        /// The parser's message (it lists the expected keys).
        message: String,
    },
    /// The TOML text does not parse or a value has the wrong type.
    #[error("randomization: {message}")]
    Parse {
        /// The parser's message (it names the key and the line).
        message: String,
    },
    /// A value is out of its range.
    #[error("randomization.{key} = {value}: {reason}")]
    InvalidValue {
        /// Dotted key inside `[randomization]`, e.g. `physics.joint_damping`.
        key: String,
        /// The value given, as text.
        value: String,
        /// What it must satisfy.
        reason: String,
    },
    /// The scene does not validate (before randomisation: randomisation itself only produces
    /// scenes that validate).
    #[error("randomization: the scene is invalid: {0}")]
    Scene(#[from] SceneError),
    /// The world refused a property change.
    #[error("randomization: {0}")]
    World(#[from] WorldError),
    /// A camera refused a material.
    #[error("randomization: {0}")]
    Sensor(#[from] SensorError),
}

impl RandomizeError {
    pub(crate) fn invalid(key: &str, value: impl std::fmt::Display, reason: &str) -> Self {
        RandomizeError::InvalidValue {
            key: key.to_owned(),
            value: value.to_string(),
            reason: reason.to_owned(),
        }
    }

    /// Wraps a TOML/serde message, recognising unknown keys.
    pub(crate) fn from_parser(message: String) -> Self {
        const MARK: &str = "unknown field `";
        if let Some(start) = message.find(MARK) {
            let rest = &message[start + MARK.len()..];
            if let Some(end) = rest.find('`') {
                return RandomizeError::UnknownKey {
                    key: rest[..end].to_owned(),
                    message,
                };
            }
        }
        RandomizeError::Parse { message }
    }
}
