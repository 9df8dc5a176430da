//! [`Rrt`]: the rapidly-exploring random tree (LaValle 1998), OMPL's `RRT`.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::birrt::Retraction;
use crate::error::PlanError;
use crate::motion::MotionValidator;
use crate::planner::{
    Budget, Path, PlanRequest, Planner, Run, Solution, Tree, positive_finite, resolve_range, valid_goals,
};
use crate::space::{Space, pull_towards, steer};
use crate::validity::StateValidator;

/// RRT: one tree grown from the start towards random samples (towards a random goal with
/// probability `goal_bias`, towards a point near a random goal with probability `goal_zone`),
/// steps of at most `range`. After each new state it tries a straight motion to the nearest
/// goal when that goal is within `range`. [`Rrt::ompl`] is OMPL's `RRT` (no goal zone).
///
/// One iteration is one sample. Settings are serde-derivable, so a TOML file can set them.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
/// use hearth_planning::rrt::Rrt;
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// struct Free(u64);
/// impl StateValidator for Free {
///     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
/// let mut motion = MotionValidator::new(space, 0.01);
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let solution = Rrt::default()
///     .plan(&mut motion, &mut Free(0), &request, &Budget::iterations(10_000), &mut rng)
///     .unwrap();
/// assert_eq!(solution.path.states.last().unwrap(), &vec![0.9, 0.9]);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Rrt {
    /// Longest step; `None` is [`default_range`](crate::planner::default_range)
    /// (0.2 × the space's extent, as in OMPL). A step that is not positive and finite, or
    /// shorter than [`finest_resolution`](crate::motion::finest_resolution), is
    /// [`PlanError::BadInput`].
    pub range: Option<f64>,
    /// Probability of steering towards a goal instead of a uniform sample (OMPL: 0.05).
    pub goal_bias: f64,
    /// Probability of steering towards a point near a goal: a uniform sample pulled to within
    /// `goal_zone_radius` × `range` of a random goal (a uniform fraction of that distance).
    /// The tree then grows into the goal's neighbourhood, so a goal wedged between obstacles
    /// (a grasp on a shelf) gets states that can see it from close by. 0 turns it off (OMPL);
    /// with the default, 0.1, the median planning time on the MotionBenchMaker Panda bookshelf
    /// problems fell 2.3–2.9× (table_pick 1.9×; box and table_under_pick unchanged), with as
    /// many successes (`docs/planning-log.md`). `goal_bias + goal_zone` must not exceed 1.
    pub goal_zone: f64,
    /// Radius of the goal zone as a fraction of `range`.
    pub goal_zone_radius: f64,
    /// Retraction of goal-zone samples that land in obstacles: one in
    /// [`every`](Retraction::every) zone samples that are within a step of the tree (so
    /// checked themselves) and collide is pushed out of the obstacles along the contact
    /// normals ([`StateValidator::retract`]); when the pushed state is valid, the tree steers
    /// towards it instead of drawing again. Near a goal wedged between obstacles most zone
    /// samples collide, and the pushed ones lie beside the walls around the goal, where the
    /// tree has to pass. Validators that know no geometry retract nothing, so their plans are
    /// the same with or without it. `None` turns it off ([`Rrt::ompl`]). Measured on the
    /// MotionBenchMaker Panda problems with the benchmark's 6 rad step
    /// (`docs/planning-log.md`, fifty-seventh round): 1,656 of 1,677 plans within 1 s over
    /// seeds 0–2 against 1,643, bookshelf_small 94.9 % against 91.9 %, at medians 13–21 %
    /// higher.
    pub zone_retraction: Option<Retraction>,
}

/// [`Rrt::zone_retraction`]'s default: one colliding goal-zone sample in four, three joint
/// steps, 1 cm beyond the surfaces.
const ZONE_RETRACTION: Retraction = Retraction {
    every: 4,
    rounds: 3,
    clearance: 0.01,
};

impl Default for Rrt {
    fn default() -> Self {
        Self {
            range: None,
            goal_bias: 0.05,
            goal_zone: 0.1,
            goal_zone_radius: 0.3,
            zone_retraction: Some(ZONE_RETRACTION),
        }
    }
}

impl Rrt {
    /// OMPL's `RRT`: goal bias 0.05, no goal zone (so no zone retraction), step `range`.
    ///
    /// ```
    /// let rrt = hearth_planning::Rrt::ompl(None);
    /// assert_eq!((rrt.goal_bias, rrt.goal_zone, rrt.zone_retraction), (0.05, 0.0, None));
    /// ```
    pub fn ompl(range: Option<f64>) -> Self {
        Self {
            range,
            goal_zone: 0.0,
            zone_retraction: None,
            ..Self::default()
        }
    }
}

impl<S: Space> Planner<S> for Rrt {
    fn plan<V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<Solution, PlanError> {
        if !(0.0..=1.0).contains(&self.goal_bias) {
            return Err(PlanError::BadInput(format!(
                "goal_bias is {}; it must be in [0, 1]",
                self.goal_bias
            )));
        }
        if !(0.0..=1.0).contains(&self.goal_zone) || self.goal_bias + self.goal_zone > 1.0 {
            return Err(PlanError::BadInput(format!(
                "goal_zone is {}; it must be in [0, 1 - goal_bias]",
                self.goal_zone
            )));
        }
        positive_finite("goal_zone_radius", self.goal_zone_radius)?;
        if let Some(r) = &self.zone_retraction {
            r.validate()?;
        }
        let mut run = Run::start(budget, motion, validator)?;
        let space = motion.space();
        let range = resolve_range(space, self.range, 1.0)?;
        let goals = valid_goals(space, validator, request)?;
        let dim = space.dim();
        let mut tree = Tree::new(dim);
        tree.add(&request.start, None);
        let (mut target, mut step) = (vec![0.0; dim], vec![0.0; dim]);
        let zone_radius = self.goal_zone_radius * range;
        // Direct connection first, when a goal is within range.
        let mut newest = Some(0);
        let mut last = 0;
        // Colliding goal-zone samples, counted for [`Retraction::every`].
        let mut colliding = 0u64;
        loop {
            if let Some(i) = newest.take()
                && let Some(g) = nearest_goal(motion.space(), &goals, tree.state(i), range)
                && motion.check_motion(validator, tree.state(i), &goals[g])
            {
                let last = tree.add(&goals[g], Some(i));
                let stats = run.stats(motion, validator, vec![tree.len()]);
                return Ok(Solution {
                    path: Path {
                        states: tree.branch(last),
                    },
                    stats,
                });
            }
            if !run.next() {
                break;
            }
            let space = motion.space();
            // One draw picks uniform, goal or goal zone (each probability as documented).
            let pick = if self.goal_bias > 0.0 || self.goal_zone > 0.0 {
                rng.random::<f64>()
            } else {
                1.0
            };
            if pick < self.goal_bias {
                target.copy_from_slice(&goals[rng.random_range(0..goals.len())]);
            } else if pick < self.goal_bias + self.goal_zone {
                space.sample(rng, &mut step);
                let g = &goals[rng.random_range(0..goals.len())];
                pull_towards(space, g, &step, zone_radius, rng, &mut target);
            } else {
                space.sample(rng, &mut target);
            }
            // When some tree state is within `range` of the target, so is the nearest, and the
            // step is the target itself: check it before the nearest-neighbour query, which an
            // invalid target makes unnecessary. The same states are checked in the same order.
            let reaches =
                space.distance(tree.state(0), &target) <= range || space.distance(tree.state(last), &target) <= range;
            if reaches && !validator.is_valid(&target) {
                // A goal-zone sample in an obstacle: pushed out, it may still serve.
                let zone = pick >= self.goal_bias && pick < self.goal_bias + self.goal_zone;
                let Some(r) = self.zone_retraction.as_ref().filter(|_| zone) else {
                    continue;
                };
                colliding += 1;
                if !colliding.is_multiple_of(r.every) || !validator.retract(&target, r.clearance, r.rounds, &mut step) {
                    continue;
                }
                target.copy_from_slice(&step);
            }
            let near = tree.nn.nearest(space, &target).expect("the tree holds the start");
            let d = steer(space, tree.state(near), &target, range, &mut step);
            if d == 0.0 {
                continue;
            }
            // A reached target was checked (or retracted to a valid state); a step short of a
            // retracted one was not.
            if (!reaches || d > range) && !validator.is_valid(&step) {
                continue;
            }
            if !motion.check_motion(validator, tree.state(near), &step) {
                continue;
            }
            last = tree.add(&step, Some(near));
            newest = Some(last);
        }
        Err(PlanError::Timeout {
            stats: run.stats(motion, validator, vec![tree.len()]),
        })
    }
}

/// Index of the goal nearest to `q` if it is within `range`.
fn nearest_goal<S: Space>(space: &S, goals: &[Vec<f64>], q: &[f64], range: f64) -> Option<usize> {
    goals
        .iter()
        .map(|g| space.distance(q, g))
        .enumerate()
        .filter(|&(_, d)| d <= range)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}
