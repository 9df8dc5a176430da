//! [`EnvError`]: configuration, scene, sensor and action errors of an environment.

use crate::randomize::RandomizeError;
use crate::scene::SceneError;
use crate::sensors::SensorError;
use crate::world::{LoadSceneError, WorldError};

/// An environment error. A failed `step` or `reset` changes nothing.
///
/// ```
/// use hearth_sim::env::{EnvConfig, EnvError};
/// let err = EnvConfig::from_toml("[task]\nname = \"fly\"\n").unwrap_err();
/// assert!(matches!(err, EnvError::Config { ref key, .. } if key == "task.name"));
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EnvError {
    /// The TOML does not parse or has an unknown key (the message names it and its line).
    #[error("config: {0}")]
    Parse(String),
    /// A value is out of range.
    #[error("config: `{key}` {reason}")]
    Config {
        /// Dotted key, e.g. `task.goal_tolerance`.
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// A file could not be read.
    #[error("cannot read {path}: {reason}")]
    Io {
        /// Path.
        path: String,
        /// OS error.
        reason: String,
    },
    /// An action of the wrong length or with a non-finite entry.
    #[error("bad action: {0}")]
    BadAction(String),
    /// `step` before the first `reset`.
    #[error("call reset before step")]
    NotReset,
    /// The task could not place a start and goal.
    #[error("task: {0}")]
    Task(String),
    /// The scene failed.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Loading the scene failed.
    #[error(transparent)]
    Load(#[from] LoadSceneError),
    /// The world refused a command.
    #[error(transparent)]
    World(#[from] WorldError),
    /// A sensor failed.
    #[error(transparent)]
    Sensor(#[from] SensorError),
    /// Domain randomisation could not be applied.
    #[error(transparent)]
    Randomize(#[from] RandomizeError),
}

/// Shorthand.
///
/// ```
/// use hearth_sim::env::{EnvConfig, EnvResult};
/// fn robot_of(toml: &str) -> EnvResult<String> {
///     Ok(EnvConfig::from_toml(toml)?.robot.name)
/// }
/// assert_eq!(robot_of("[task]\nname = \"object_nav\"\n").unwrap(), "turtlebot");
/// assert!(robot_of("[task]\nname = \"fly\"\n").is_err());
/// ```
pub type EnvResult<T> = Result<T, EnvError>;
