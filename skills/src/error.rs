//! [`SkillError`]: why a skill failed, with a short machine-readable [`SkillError::reason`].

use hearth_kinematics::{KinematicsError, Num};
use hearth_planning::PlanError;
use hearth_sim::scene::SceneError;
use hearth_sim::sensors::SensorError;
use hearth_sim::world::WorldError;

/// Why a skill failed. Failures found before execution (bad input, unreachable target, IK or
/// planning failure) leave the world untouched; failures during execution leave it where the
/// robot stopped (take a [`hearth_sim::world::Snapshot`] first to roll back).
///
/// ```
/// let e = hearth_skills::SkillError::Unreachable("goal inside a wall".into());
/// assert_eq!(e.reason(), "unreachable");
/// assert!(e.to_string().contains("inside a wall"));
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SkillError {
    /// An argument is malformed: NaN, out of range, a pixel outside the image, an unknown
    /// object or link.
    #[error("bad input: {0}")]
    BadInput(String),
    /// The target cannot be reached: no free path on the map, a goal in collision, a point
    /// outside the arm's workspace.
    #[error("unreachable: {0}")]
    Unreachable(String),
    /// No collision-free inverse-kinematics solution for the wanted pose.
    #[error("IK failed: {0}")]
    IkFailed(String),
    /// The planner ran out of its budget.
    #[error("planning timed out: {0}")]
    PlanningTimeout(String),
    /// The planner failed for another reason (invalid start, invalid goal).
    #[error("planning failed: {0}")]
    PlanningFailed(String),
    /// Execution touched something it should not have (names the contact).
    #[error("collision during execution: {0}")]
    Collision(String),
    /// The robot was blocked and replanning did not get it through.
    #[error("blocked: {0}")]
    Blocked(String),
    /// A grasped object left the gripper.
    #[error("object slipped: {0}")]
    Slipped(String),
    /// The grasp closed on nothing, or a skill that needs a held object has none.
    #[error("not held: {0}")]
    NotHeld(String),
    /// Execution ended without reaching its goal within tolerance or time.
    #[error("execution did not finish: {0}")]
    NotFinished(String),
    /// The push, open or close moved the target less than required.
    #[error("no effect: {0}")]
    NoEffect(String),
    /// An error of the physics world.
    #[error(transparent)]
    World(#[from] WorldError),
    /// An error of a sensor.
    #[error(transparent)]
    Sensor(#[from] SensorError),
    /// An error of the kinematics layer.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// An error of a scene or its maps.
    #[error(transparent)]
    Scene(#[from] SceneError),
}

impl SkillError {
    /// A short snake_case code for reports and RL `info`: `bad_input`, `unreachable`,
    /// `ik_failed`, `planning_timeout`, `planning_failed`, `collision`, `blocked`, `slipped`,
    /// `not_held`, `not_finished`, `no_effect`, `world`, `sensor`, `kinematics`, `scene`.
    ///
    /// ```
    /// use hearth_skills::SkillError;
    /// assert_eq!(SkillError::BadInput("pixel outside the image".into()).reason(), "bad_input");
    /// let e = SkillError::NotHeld("the gripper closed on nothing".into());
    /// assert_eq!(e.reason(), "not_held");
    /// assert!(e.to_string().contains("closed on nothing"));
    /// ```
    pub fn reason(&self) -> &'static str {
        match self {
            Self::BadInput(_) => "bad_input",
            Self::Unreachable(_) => "unreachable",
            Self::IkFailed(_) => "ik_failed",
            Self::PlanningTimeout(_) => "planning_timeout",
            Self::PlanningFailed(_) => "planning_failed",
            Self::Collision(_) => "collision",
            Self::Blocked(_) => "blocked",
            Self::Slipped(_) => "slipped",
            Self::NotHeld(_) => "not_held",
            Self::NotFinished(_) => "not_finished",
            Self::NoEffect(_) => "no_effect",
            Self::World(_) => "world",
            Self::Sensor(_) => "sensor",
            Self::Kinematics(_) => "kinematics",
            Self::Scene(_) => "scene",
        }
    }
}

impl From<PlanError> for SkillError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::Timeout { .. } => Self::PlanningTimeout(e.to_string()),
            other => Self::PlanningFailed(other.to_string()),
        }
    }
}

/// `Ok` when every setting `(name, value)` is finite and above 0, else
/// [`SkillError::BadInput`] naming the first that is not: "`{prefix}{name} {value} must be
/// positive`", the value printed short ([`Num`]). The skills' settings checks share it.
pub(crate) fn require_positive(prefix: &str, settings: &[(&str, f64)]) -> SkillResult<()> {
    require(prefix, settings, true)
}

/// As [`require_positive`], for settings that may also be 0 ("… must be non-negative").
pub(crate) fn require_non_negative(prefix: &str, settings: &[(&str, f64)]) -> SkillResult<()> {
    require(prefix, settings, false)
}

fn require(prefix: &str, settings: &[(&str, f64)], strict: bool) -> SkillResult<()> {
    let bad = |x: f64| !x.is_finite() || if strict { x <= 0.0 } else { x < 0.0 };
    match settings.iter().find(|&&(_, x)| bad(x)) {
        None => Ok(()),
        Some(&(name, x)) => Err(SkillError::BadInput(format!(
            "{prefix}{name} {} must be {}",
            Num(x),
            if strict { "positive" } else { "non-negative" }
        ))),
    }
}

/// Result of a skill.
///
/// ```
/// use hearth_skills::{SkillError, SkillResult};
/// fn checked_speed(v: f64) -> SkillResult<f64> {
///     if v.is_finite() && v > 0.0 { Ok(v) } else { Err(SkillError::BadInput(format!("speed {v}"))) }
/// }
/// assert_eq!(checked_speed(0.5).unwrap(), 0.5);
/// assert_eq!(checked_speed(-1.0).unwrap_err().reason(), "bad_input");
/// ```
pub type SkillResult<T> = Result<T, SkillError>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_checks_name_the_first_bad_setting_and_print_it_short() {
        assert!(require_positive("push ", &[("speed", 0.1), ("distance", 0.3)]).is_ok());
        let e = require_positive("push ", &[("speed", 0.1), ("distance", 0.0), ("force", -1.0)]).unwrap_err();
        assert_eq!(e.to_string(), "bad input: push distance 0 must be positive");
        let e = require_positive("", &[("amount", f64::NAN)]).unwrap_err();
        assert_eq!(e.to_string(), "bad input: amount NaN must be positive");
        assert!(require_non_negative("grasp ", &[("palm offset", 0.0)]).is_ok());
        let e = require_non_negative("grasp ", &[("palm offset", -1e30)]).unwrap_err();
        assert_eq!(e.to_string(), "bad input: grasp palm offset -1e30 must be non-negative");
        assert_eq!(e.reason(), "bad_input");
    }
}
