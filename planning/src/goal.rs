//! End-effector pose goals: goal configurations sampled by IK, collision-aware.

use hearth_kinematics::{IkError, IkSolver, IkTarget};
use rand::Rng;

use crate::error::PlanError;
use crate::planner::Goal;
use crate::validity::StateValidator;

/// A goal given as a pose (or position) of the IK solver's tool frame. [`PoseGoal::sample`]
/// turns it into a [`Goal::AnyOf`] of distinct collision-free IK solutions, which every planner
/// handles (BiRRT grows its goal tree from all of them).
///
/// ```
/// use std::sync::Arc;
/// use hearth_planning::goal::PoseGoal;
/// use hearth_planning::kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
/// use hearth_planning::kinematics::{SelfCollisionMatrix, SelfCollisionSettings};
/// use hearth_planning::kinematics::nalgebra::{Isometry3, Translation3, UnitQuaternion};
/// use hearth_planning::{ParryScene, RobotValidity};
/// use rand::SeedableRng;
///
/// let panda = RobotModel::builtin("panda").unwrap();
/// let arm = Chain::named(&panda, "arm").unwrap();
/// let mut ik = IkSolver::new(arm.clone(), "panda_hand_tcp", IkSettings::default()).unwrap();
/// let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
/// let mut validity = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
/// let down = UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0);
/// let target = IkTarget::Pose(Isometry3::from_parts(Translation3::new(0.5, 0.1, 0.4), down));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let goal = PoseGoal::new(target).sample(&mut ik, &mut validity, &[0.0, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8], &mut rng).unwrap();
/// assert!(goal.states().len() >= 2);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PoseGoal {
    /// Where the tool frame must be.
    pub target: IkTarget,
    /// Distinct solutions wanted.
    pub solutions: usize,
    /// IK calls at most (each restarts from a random configuration after the first, which
    /// starts from the seed).
    pub max_calls: usize,
    /// Two solutions closer than this (joint-space L2) count as one.
    pub min_separation: f64,
}

impl PoseGoal {
    /// A goal with 8 solutions from at most 32 IK calls, 0.1 rad apart.
    ///
    /// ```
    /// use hearth_planning::goal::PoseGoal;
    /// use hearth_planning::kinematics::IkTarget;
    /// use hearth_planning::kinematics::nalgebra::Point3;
    ///
    /// let goal = PoseGoal::new(IkTarget::Position(Point3::new(0.4, 0.0, 0.5)));
    /// assert_eq!((goal.solutions, goal.max_calls, goal.min_separation), (8, 32, 0.1));
    /// let first_only = PoseGoal { solutions: 1, ..goal };
    /// assert_eq!(first_only.max_calls, 32);
    /// ```
    pub fn new(target: IkTarget) -> Self {
        Self {
            target,
            solutions: 8,
            max_calls: 32,
            min_separation: 0.1,
        }
    }

    /// Samples goal configurations: IK from `seed` first, then from random configurations,
    /// keeping solutions that `validator` accepts and that differ from those already found.
    /// Fails with [`PlanError::BadInput`] for an unusable target or seed and
    /// [`PlanError::NoGoalConfiguration`] when no collision-free solution is found.
    ///
    /// ```
    /// use hearth_planning::goal::PoseGoal;
    /// use hearth_planning::kinematics::nalgebra::Point3;
    /// use hearth_planning::kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
    /// use hearth_planning::{PlanError, StateValidator};
    /// use rand::SeedableRng;
    ///
    /// // Accepts states whose first joint is positive (or none at all).
    /// struct Left(bool);
    /// impl StateValidator for Left {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 && q[0] > 0.0 }
    ///     fn checks(&self) -> u64 { 0 }
    /// }
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// let mut ik = IkSolver::new(arm, "panda_hand_tcp", IkSettings::default()).unwrap();
    /// let point = Point3::new(0.3, 0.3, 0.5);
    /// let goal = PoseGoal { solutions: 3, ..PoseGoal::new(IkTarget::Position(point)) };
    /// let seed = [0.0, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8];
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
    /// let found = goal.sample(&mut ik, &mut Left(true), &seed, &mut rng).unwrap();
    /// assert_eq!(found.states().len(), 3);
    /// for q in found.states() {
    ///     assert!(q[0] > 0.0 && (ik.tool_pose(q).unwrap().translation.vector - point.coords).norm() < 1e-3);
    /// }
    /// // Every solution that 4 calls find, however many are asked for.
    /// let all = PoseGoal { solutions: usize::MAX, max_calls: 4, ..goal.clone() };
    /// assert!(all.sample(&mut ik, &mut Left(true), &seed, &mut rng).unwrap().states().len() <= 4);
    /// let none = PoseGoal { max_calls: 2, ..goal };
    /// let e = none.sample(&mut ik, &mut Left(false), &seed, &mut rng).unwrap_err();
    /// assert!(matches!(e, PlanError::NoGoalConfiguration { .. }));
    /// ```
    pub fn sample<V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &self,
        ik: &mut IkSolver,
        validator: &mut V,
        seed: &[f64],
        rng: &mut R,
    ) -> Result<Goal, PlanError> {
        // (Room for what the calls can find, not for a huge `solutions`.)
        let mut found: Vec<Vec<f64>> = Vec::with_capacity(self.solutions.min(self.max_calls).min(64));
        let mut last_error = None;
        let mut start = seed.to_vec();
        for call in 0..self.max_calls.max(1) {
            if found.len() >= self.solutions.max(1) {
                break;
            }
            if call > 0 {
                ik.chain().random_configuration(rng, &mut start);
            }
            match ik.solve_with(&self.target, &start, rng, |q| validator.is_valid(q)) {
                Ok(s) => {
                    let distinct = found.iter().all(|f| {
                        f.iter().zip(&s.q).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt() >= self.min_separation
                    });
                    if distinct {
                        found.push(s.q);
                    }
                }
                Err(IkError::Input(msg)) => return Err(PlanError::BadInput(msg)),
                Err(e) => last_error = Some(e.to_string()),
            }
        }
        if found.is_empty() {
            return Err(PlanError::NoGoalConfiguration {
                reason: last_error.unwrap_or_else(|| "no IK call was made".to_owned()),
            });
        }
        Ok(Goal::AnyOf(found))
    }
}
