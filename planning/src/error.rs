//! [`PlanError`]: why a planner returned no path.

use crate::planner::{PlanRequest, PlanStats};

/// Why a planner returned no path, OMPL's `INVALID_START`, `INVALID_GOAL` and `TIMEOUT`
/// statuses as a typed error.
///
/// Planners only see a [`StateValidator`](crate::validity::StateValidator), which says *whether*
/// a state is valid, not *why*; fill in the colliding pair with [`PlanError::explain_with`] and,
/// for a robot, [`RobotValidity::explain`](crate::validity::RobotValidity::explain).
///
/// ```
/// use hearth_planning::error::PlanError;
/// use hearth_planning::planner::{Goal, PlanRequest};
///
/// let request = PlanRequest::new(vec![0.5, 0.5], Goal::Config(vec![0.9, 0.9]));
/// let e = PlanError::InvalidStart { contact: None }
///     .explain_with(&request, |q| (q[0] == 0.5).then(|| "link `hand` touches obstacle `wall`".to_owned()));
/// assert!(e.to_string().contains("wall"));
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The start state is in collision.
    #[error("the start state is invalid{}", describe(contact))]
    InvalidStart {
        /// What it touches, when known.
        contact: Option<String>,
    },
    /// Every goal state is in collision.
    #[error("all {count} goal state(s) are invalid{}", describe(first_contact))]
    InvalidGoals {
        /// Number of goal states given.
        count: usize,
        /// What the first goal touches, when known.
        first_contact: Option<String>,
    },
    /// The budget ran out before a path was found.
    #[error(
        "no path within the budget ({} iterations, {} states and {} motions checked, trees of {:?} states, {:.3} s)",
        stats.iterations, stats.states_checked, stats.motions_checked, stats.tree_sizes, stats.time.as_secs_f64()
    )]
    Timeout {
        /// What the planner did meanwhile.
        stats: PlanStats,
    },
    /// A pose goal for which no collision-free configuration was found (IK failed or every
    /// solution collides).
    #[error("no collision-free configuration reaches the goal pose: {reason}")]
    NoGoalConfiguration {
        /// The last IK failure.
        reason: String,
    },
    /// The request, budget or planner settings are unusable (wrong dimension, NaN, out of
    /// bounds, no goal, no budget, a negative time limit, a non-positive range, …); the message
    /// names the culprit, such as `goal 2: coordinate 3 (panda_joint4) is 4.1, outside [-3.07, -0.07]` from
    /// [`Space::check`](crate::space::Space::check).
    #[error("bad input: {0}")]
    BadInput(String),
    /// Post-processing produced no motion that passes the final check at the verification
    /// resolution (see `ShortcutSettings::verify_resolution`): the state at `time` s collides.
    #[error("the smoothed motion collides at {time:.4} s when re-checked at the verification resolution")]
    InvalidMotion {
        /// Time along the motion of the colliding state found (s).
        time: f64,
    },
}

fn describe(contact: &Option<String>) -> String {
    contact.as_ref().map(|c| format!(": {c}")).unwrap_or_default()
}

impl PlanError {
    /// The same error with the contact of an invalid start, or of the first goal, filled in
    /// by `explain` (which returns `None` for a valid state). Other errors pass through.
    ///
    /// ```
    /// use hearth_planning::error::PlanError;
    /// use hearth_planning::planner::{Goal, PlanRequest};
    ///
    /// let request = PlanRequest::new(vec![0.0], Goal::AnyOf(vec![vec![2.0], vec![3.0]]));
    /// let why = |q: &[f64]| (q[0] > 1.0).then(|| format!("x = {} is inside the wall", q[0]));
    /// let e = PlanError::InvalidGoals { count: 2, first_contact: None }.explain_with(&request, why);
    /// assert_eq!(e, PlanError::InvalidGoals { count: 2, first_contact: Some("x = 2 is inside the wall".into()) });
    /// let other = PlanError::BadInput("no goal state given".into());
    /// assert_eq!(other.clone().explain_with(&request, why), other);
    /// ```
    pub fn explain_with(mut self, request: &PlanRequest, mut explain: impl FnMut(&[f64]) -> Option<String>) -> Self {
        match &mut self {
            PlanError::InvalidStart { contact } => *contact = explain(&request.start),
            PlanError::InvalidGoals { first_contact, .. } => {
                *first_contact = request.goal.states().first().and_then(|g| explain(g))
            }
            _ => {}
        }
        self
    }
}

/// A [`Space::check`](crate::space::Space::check) failure of the state called `what`.
pub(crate) fn bad_state(what: &str, e: crate::space::SpaceError) -> PlanError {
    PlanError::BadInput(format!("{what}: {e}"))
}

/// A number in an error message, short (the kinematics crate's formatter).
pub(crate) use hearth_kinematics::Num;

#[cfg(test)]
mod tests {
    use super::Num;

    #[test]
    fn numbers_in_messages_stay_short() {
        for (v, s) in [
            (1e308, "1e308"),
            (-2.5e-9, "-2.5e-9"),
            (0.0, "0"),
            (1.5, "1.5"),
            (-3.0, "-3"),
            (123456.0, "123456"),
            (f64::INFINITY, "inf"),
            (f64::NAN, "NaN"),
        ] {
            assert_eq!(Num(v).to_string(), s);
        }
    }
}
