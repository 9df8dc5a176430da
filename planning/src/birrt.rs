//! [`BiRrt`]: RRT-Connect (Kuffner & LaValle 2000), OMPL's `RRTConnect`.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::motion::MotionValidator;
use crate::planner::{Budget, Path, PlanRequest, Planner, Run, Solution, Tree, resolve_range, valid_goals};
use crate::space::Space;
use crate::validity::StateValidator;

/// RRT-Connect: a tree from the start and a tree from the goals (seeded with every valid goal),
/// grown in turns. Each iteration extends one tree a step of at most `range` towards a random
/// sample, then greedily connects the other tree to the new state (repeated steps until it
/// reaches it or is blocked); the trees swap roles every iteration.
///
/// One iteration is one sample. Settings are serde-derivable.
///
/// ```
/// use hearth_planning::birrt::BiRrt;
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// // A wall at x = 0.5 with a gap above y = 0.8.
/// struct Wall(u64);
/// impl StateValidator for Wall {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; (q[0] - 0.5).abs() > 0.05 || q[1] > 0.8 }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
/// let mut motion = MotionValidator::new(space, 0.01);
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let solution = BiRrt::default()
///     .plan(&mut motion, &mut Wall(0), &request, &Budget::iterations(10_000), &mut rng)
///     .unwrap();
/// assert!(solution.path.states.iter().any(|q| q[1] > 0.8));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BiRrt {
    /// Longest step; `None` is a tenth of [`default_range`](crate::planner::default_range)
    /// (0.02 × the space's extent, ≈ 0.26 rad for the Panda and the Fetch). OMPL's default,
    /// 0.2 × the extent, made each extension check up to ~120 states on MotionBenchMaker
    /// problems; the short step was 3–8× faster there with higher success (`docs/benchmarks.md`).
    pub range: Option<f64>,
}

/// [`BiRrt`]'s default step as a fraction of [`default_range`](crate::planner::default_range).
const BIRRT_RANGE_SCALE: f64 = 0.1;

/// Result of one extension step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Extend {
    /// Blocked: nothing added.
    Trapped,
    /// A state a step short of the target was added.
    Advanced(usize),
    /// The target itself was added.
    Reached(usize),
}

/// Scratch buffers and settings shared by the extension steps.
struct Stepper {
    range: f64,
    step: Vec<f64>,
}

impl Stepper {
    /// Extends `tree` one step towards `target`.
    fn extend<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        tree: &mut Tree,
        target: &[f64],
    ) -> Extend {
        let space = motion.space();
        let near = tree.nn.nearest(space, target).expect("trees are never empty");
        let d = space.distance(tree.state(near), target);
        let reached = d <= self.range;
        if reached {
            self.step.copy_from_slice(target);
        } else {
            space.interpolate(tree.state(near), target, self.range / d, &mut self.step);
        }
        if !validator.is_valid(&self.step) || !motion.check_motion(validator, tree.state(near), &self.step) {
            return Extend::Trapped;
        }
        let i = tree.add(&self.step, Some(near));
        if reached {
            Extend::Reached(i)
        } else {
            Extend::Advanced(i)
        }
    }
}

impl<S: Space> Planner<S> for BiRrt {
    fn plan<V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<Solution, PlanError> {
        let mut run = Run::start(budget, motion, validator);
        let space = motion.space();
        let range = resolve_range(space, self.range, BIRRT_RANGE_SCALE)?;
        let goals = valid_goals(space, validator, request, budget)?;
        let dim = space.dim();
        let mut start_tree = Tree::new(dim);
        start_tree.add(&request.start, None);
        let mut goal_tree = Tree::new(dim);
        for g in &goals {
            goal_tree.add(g, None);
        }
        let mut stepper = Stepper {
            range,
            step: vec![0.0; dim],
        };
        // `target` is first the state to connect to (the start, then each new state), then
        // the next sample.
        let mut target = request.start.clone();
        // Which tree grew last; the other one is connected to `target`.
        let mut from_start = true;
        // Try connecting the goal tree straight to the start first.
        let mut connect = true;
        loop {
            if connect {
                connect = false;
                let other = if from_start { &mut goal_tree } else { &mut start_tree };
                let reached = loop {
                    match stepper.extend(motion, validator, other, &target) {
                        Extend::Advanced(_) => {}
                        Extend::Reached(i) => break Some(i),
                        Extend::Trapped => break None,
                    }
                };
                if let Some(i) = reached {
                    // `target` is now the newest state of both trees; join the branches at it.
                    let (si, gi) = if from_start {
                        (start_tree.len() - 1, i)
                    } else {
                        (i, goal_tree.len() - 1)
                    };
                    let mut states = start_tree.branch(si);
                    let mut back = goal_tree.branch(gi);
                    back.reverse();
                    states.extend(back.into_iter().skip(1));
                    let stats = run.stats(motion, validator, vec![start_tree.len(), goal_tree.len()]);
                    return Ok(Solution {
                        path: Path { states },
                        stats,
                    });
                }
                from_start = !from_start;
            }
            if !run.next() {
                break;
            }
            motion.space().sample(rng, &mut target);
            let tree = if from_start { &mut start_tree } else { &mut goal_tree };
            match stepper.extend(motion, validator, tree, &target) {
                Extend::Trapped => from_start = !from_start,
                Extend::Advanced(i) | Extend::Reached(i) => {
                    target.copy_from_slice(tree.state(i));
                    connect = true;
                }
            }
        }
        Err(PlanError::Timeout {
            stats: run.stats(motion, validator, vec![start_tree.len(), goal_tree.len()]),
        })
    }
}
