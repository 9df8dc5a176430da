//! [`Execution`]: how a skill carries out its plan.

/// How a skill carries out a planned motion.
///
/// - [`Execution::Physics`] (the default) sends the trajectory to the robot's controllers and
///   steps the physics world: contacts, slips and pushes happen as they would on a robot. Use it
///   for anything whose outcome depends on contact (pushing, grasping, opening, data for
///   learning interaction).
/// - [`Execution::Kinematic`] teleports the joints along the plan (as iGibson 1.0 executed
///   its plans) and lets physics settle only where the skill needs it. It is several times
///   faster and suits navigation-only studies and planner benchmarks, but it can pass through
///   contacts physics would have resolved, so its success rates for contact-rich skills are
///   optimistic.
///
/// ```
/// use hearth_skills::Execution;
/// assert_eq!(Execution::default(), Execution::Physics);
/// assert_eq!("kinematic".parse::<Execution>().unwrap(), Execution::Kinematic);
/// assert!("teleport".parse::<Execution>().is_err());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Execution {
    /// Controllers and physics steps.
    #[default]
    Physics,
    /// Joints set along the plan.
    Kinematic,
}

impl std::str::FromStr for Execution {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "physics" => Ok(Self::Physics),
            "kinematic" => Ok(Self::Kinematic),
            other => Err(format!(
                "unknown execution mode `{other}` (expected physics or kinematic)"
            )),
        }
    }
}

impl std::fmt::Display for Execution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Physics => "physics",
            Self::Kinematic => "kinematic",
        })
    }
}
