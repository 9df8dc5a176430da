//! [`ReLMoGenConfig`]: the TOML file of a [`super::ReLMoGenEnv`], and [`ReLMoGenError`].

use std::path::{Path, PathBuf};

use hearth_kinematics::Num;
use hearth_sim::env::{CameraSection, EnvConfig, EnvError};
use serde::{Deserialize, Serialize};

use crate::error::SkillError;
use crate::execution::Execution;
use crate::push::PushSettings;

/// An error of the ReLMoGen env or its dataset writer.
///
/// ```
/// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenError};
/// let toml = "failure_penalty = -1.0\n[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"push_drawer\"\n";
/// let e = ReLMoGenConfig::from_toml(toml).unwrap_err();
/// assert!(matches!(e, ReLMoGenError::Config { ref key, .. } if key == "failure_penalty"));
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReLMoGenError {
    /// The TOML does not parse or has an unknown key (the message names it and its line).
    #[error("config: {0}")]
    Parse(String),
    /// A value is out of range.
    #[error("config: `{key}` {reason}")]
    Config {
        /// Dotted key.
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {reason}")]
    Io {
        /// Path.
        path: String,
        /// OS error.
        reason: String,
    },
    /// An action of the wrong length, non-finite, out of range or not an index.
    #[error("bad action: {0}")]
    BadAction(String),
    /// `step` before `reset`.
    #[error("call reset before step")]
    NotReset,
    /// The wrapped env failed.
    #[error(transparent)]
    Env(#[from] EnvError),
    /// A skill failed in a way that is not a subgoal failure (set-up, sensors).
    #[error(transparent)]
    Skill(#[from] SkillError),
}

/// Result of the ReLMoGen env.
///
/// ```
/// let r: hearth_skills::relmogen::ReLMoGenResult<u8> = Ok(1);
/// assert!(r.is_ok());
/// ```
pub type ReLMoGenResult<T> = Result<T, ReLMoGenError>;

pub(crate) fn bad(key: &str, reason: impl Into<String>) -> ReLMoGenError {
    ReLMoGenError::Config {
        key: key.to_owned(),
        reason: reason.into(),
    }
}

pub(crate) fn io_error(path: &Path, e: impl std::fmt::Display) -> ReLMoGenError {
    ReLMoGenError::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
}

/// The form of the action.
///
/// ```
/// use hearth_skills::relmogen::ActionForm;
/// assert_eq!(ActionForm::default(), ActionForm::Continuous);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActionForm {
    /// A box of 8 entries in [−1, 1] (ReLMoGen-R).
    #[default]
    Continuous,
    /// One index into the base and arm score maps (ReLMoGen-D).
    Discrete,
}

/// Push settings of the arm subgoal (the keys of [`PushSettings`] that a config may set).
///
/// ```
/// let s = hearth_skills::relmogen::PushSection::default();
/// assert_eq!(s.settings().distance, 0.30);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PushSection {
    /// Length of the push, m.
    pub distance: f64,
    /// Force limit, N.
    pub force_limit: f64,
    /// Gap between fingertips and surface before the push, m.
    pub standoff: f64,
    /// Push speed, m/s.
    pub speed: f64,
    /// The touched point must move more than this for success, m.
    pub min_motion: f64,
}

impl Default for PushSection {
    fn default() -> Self {
        let p = PushSettings::default();
        Self {
            distance: p.distance,
            force_limit: p.force_limit,
            standoff: p.standoff,
            speed: p.speed,
            min_motion: p.min_motion,
        }
    }
}

impl PushSection {
    /// The push skill's settings.
    ///
    /// ```
    /// let p = hearth_skills::relmogen::PushSection { distance: 0.2, ..Default::default() };
    /// assert_eq!(p.settings().distance, 0.2);
    /// ```
    pub fn settings(&self) -> PushSettings {
        PushSettings {
            distance: self.distance,
            force_limit: self.force_limit,
            standoff: self.standoff,
            speed: self.speed,
            min_motion: self.min_motion,
            ..PushSettings::default()
        }
    }
}

fn default_penalty() -> f64 {
    0.1
}
fn default_base_distance() -> f64 {
    2.0
}
fn default_bins() -> usize {
    8
}

/// The configuration of a [`super::ReLMoGenEnv`] (TOML; unknown keys are errors naming them).
///
/// | key | default | meaning |
/// |---|---|---|
/// | `env_file` | — | path of an env TOML (relative to this file when loaded with [`ReLMoGenConfig::load`]) |
/// | `[env]` | — | the env config inline (exactly one of `env_file`, `[env]`) |
/// | `action` | `continuous` | `continuous` or `discrete` |
/// | `failure_penalty` | 0.1 | subtracted from the reward when the subgoal fails |
/// | `execution` | `kinematic` | `kinematic` or `physics` |
/// | `max_base_distance` | 2.0 | metres the continuous base subgoal may go |
/// | `direction_bins` | 8 | D: yaw bins of the base map, push-direction bins of the arm map |
/// | `[camera]` | the env's `[sensors.camera]` | the planner's head camera (pixel → point) |
/// | `[push]` | [`PushSettings`] defaults | `distance`, `force_limit`, `standoff`, `speed`, `min_motion` |
///
/// ```
/// use hearth_skills::relmogen::{ActionForm, ReLMoGenConfig};
/// let c = ReLMoGenConfig::from_toml(
///     "action = \"discrete\"\n[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"push_drawer\"\n",
/// ).unwrap();
/// assert_eq!(c.action, ActionForm::Discrete);
/// let e = ReLMoGenConfig::from_toml("penalty = 1\n").unwrap_err();
/// assert!(e.to_string().contains("penalty"));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReLMoGenConfig {
    /// Path of an env TOML.
    #[serde(default)]
    pub env_file: Option<PathBuf>,
    /// The env config inline.
    #[serde(default)]
    pub env: Option<EnvConfig>,
    /// The action form.
    #[serde(default)]
    pub action: ActionForm,
    /// Penalty subtracted from the reward of a step whose subgoal failed.
    #[serde(default = "default_penalty")]
    pub failure_penalty: f64,
    /// How the skills execute.
    #[serde(default = "kinematic")]
    pub execution: Execution,
    /// Longest base subgoal of the continuous form, m.
    #[serde(default = "default_base_distance")]
    pub max_base_distance: f64,
    /// D: yaw bins of the base map and push-direction bins of the arm map.
    #[serde(default = "default_bins")]
    pub direction_bins: usize,
    /// The planner's head camera (pixel → point); absent: the env's `[sensors.camera]`, so
    /// action pixels refer to the observed images.
    #[serde(default)]
    pub camera: Option<CameraSection>,
    /// Push settings.
    #[serde(default)]
    pub push: PushSection,
}

fn kinematic() -> Execution {
    Execution::Kinematic
}

impl ReLMoGenConfig {
    /// A config around an env config, every other key at its default.
    ///
    /// ```
    /// use hearth_sim::env::EnvConfig;
    /// let env = EnvConfig::from_toml("[robot]\nname = \"fetch\"\n[task]\nname = \"push_drawer\"\n").unwrap();
    /// let c = hearth_skills::relmogen::ReLMoGenConfig::new(env);
    /// assert!(c.validate().is_ok());
    /// ```
    pub fn new(env: EnvConfig) -> Self {
        Self {
            env_file: None,
            env: Some(env),
            action: ActionForm::default(),
            failure_penalty: default_penalty(),
            execution: kinematic(),
            max_base_distance: default_base_distance(),
            direction_bins: default_bins(),
            camera: None,
            push: PushSection::default(),
        }
    }

    /// Parses and validates TOML text (an `env_file` is read relative to the working
    /// directory).
    ///
    /// # Errors
    /// [`ReLMoGenError::Parse`] naming an unknown key and its line; [`ReLMoGenError::Config`]
    /// for values out of range; errors of the env config.
    ///
    /// ```
    /// let c = hearth_skills::relmogen::ReLMoGenConfig::from_toml(
    ///     "[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"interactive_nav\"\n",
    /// ).unwrap();
    /// assert_eq!(c.failure_penalty, 0.1);
    /// ```
    pub fn from_toml(text: &str) -> ReLMoGenResult<Self> {
        Self::parse(text, None)
    }

    /// Reads a TOML file; `env_file` is relative to its folder.
    ///
    /// # Errors
    /// [`ReLMoGenError::Io`], then as [`ReLMoGenConfig::from_toml`].
    ///
    /// ```no_run
    /// let c = hearth_skills::relmogen::ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// assert_eq!(c.env_config()?.task.name, "push_drawer");
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn load(path: &Path) -> ReLMoGenResult<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| io_error(path, e))?;
        Self::parse(&text, path.parent())
    }

    fn parse(text: &str, dir: Option<&Path>) -> ReLMoGenResult<Self> {
        let mut config: Self = toml::from_str(text).map_err(|e| ReLMoGenError::Parse(e.to_string()))?;
        if let Some(file) = config.env_file.take() {
            if config.env.is_some() {
                return Err(bad("env_file", "and an [env] table are both given; keep one"));
            }
            let path = match dir {
                Some(d) if file.is_relative() => d.join(&file),
                _ => file.clone(),
            };
            config.env = Some(EnvConfig::load(&path)?);
            config.env_file = Some(path);
        }
        config.validate()?;
        Ok(config)
    }

    /// The env config.
    ///
    /// # Errors
    /// [`ReLMoGenError::Config`] when neither `env_file` nor `[env]` gave one.
    ///
    /// ```
    /// use hearth_skills::relmogen::ReLMoGenConfig;
    /// let mut c = ReLMoGenConfig::from_toml("[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"push_cabinet\"\n").unwrap();
    /// assert_eq!(c.env_config().unwrap().task.name, "push_cabinet");
    /// c.env = None;
    /// assert!(c.env_config().is_err());
    /// ```
    pub fn env_config(&self) -> ReLMoGenResult<&EnvConfig> {
        self.env
            .as_ref()
            .ok_or_else(|| bad("env", "missing: give `env_file` or an [env] table"))
    }

    /// The planner camera's settings: `[camera]`, or the env's `[sensors.camera]`.
    ///
    /// # Errors
    /// As [`ReLMoGenConfig::env_config`].
    ///
    /// ```
    /// use hearth_skills::relmogen::ReLMoGenConfig;
    /// let c = ReLMoGenConfig::from_toml("[camera]\nwidth = 64\nheight = 64\n[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"push_drawer\"\n").unwrap();
    /// assert_eq!(c.camera_section().unwrap().width, 64);
    /// ```
    pub fn camera_section(&self) -> ReLMoGenResult<&CameraSection> {
        match &self.camera {
            Some(c) => Ok(c),
            None => Ok(&self.env_config()?.sensors.camera),
        }
    }

    /// Checks every value.
    ///
    /// # Errors
    /// [`ReLMoGenError::Config`] naming the key.
    ///
    /// ```
    /// use hearth_skills::relmogen::ReLMoGenConfig;
    /// let mut c = ReLMoGenConfig::from_toml("[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"push_drawer\"\n").unwrap();
    /// c.direction_bins = 0;
    /// assert!(c.validate().unwrap_err().to_string().contains("direction_bins"));
    /// ```
    pub fn validate(&self) -> ReLMoGenResult<()> {
        let env = self.env_config()?;
        env.validate()?;
        if !matches!(
            env.task.name.as_str(),
            "push_drawer" | "push_cabinet" | "interactive_nav"
        ) {
            return Err(bad(
                "env.task.name",
                format!(
                    "`{}` is not a ReLMoGen task (push_drawer, push_cabinet, interactive_nav)",
                    env.task.name
                ),
            ));
        }
        if env.robot.name != "fetch" {
            return Err(bad(
                "env.robot.name",
                format!("`{}`: ReLMoGen needs the Fetch (base and arm)", env.robot.name),
            ));
        }
        if !(self.failure_penalty.is_finite() && self.failure_penalty >= 0.0) {
            return Err(bad("failure_penalty", format!("{} must be ≥ 0", self.failure_penalty)));
        }
        if !(self.max_base_distance.is_finite() && self.max_base_distance > 0.0 && self.max_base_distance <= 2.0) {
            return Err(bad(
                "max_base_distance",
                format!("{} must be in (0, 2] m", self.max_base_distance),
            ));
        }
        if !(1..=64).contains(&self.direction_bins) {
            return Err(bad(
                "direction_bins",
                format!("{} must be in [1, 64]", self.direction_bins),
            ));
        }
        let c = self.camera_section()?;
        if c.width < 4 || c.height < 4 || c.width % 4 != 0 || c.height % 4 != 0 {
            return Err(bad(
                "camera",
                format!("{}×{} must be at least 4×4 and multiples of 4", c.width, c.height),
            ));
        }
        let p = &self.push;
        for (key, x, strict) in [
            ("push.distance", p.distance, true),
            ("push.force_limit", p.force_limit, true),
            ("push.speed", p.speed, true),
            ("push.standoff", p.standoff, false),
            ("push.min_motion", p.min_motion, false),
        ] {
            let ok = x.is_finite() && if strict { x > 0.0 } else { x >= 0.0 };
            if !ok {
                return Err(bad(
                    key,
                    format!("{} must be {}", Num(x), if strict { "> 0" } else { "≥ 0" }),
                ));
            }
        }
        Ok(())
    }
}
