//! The [`Planner`] trait and what it takes and returns: [`PlanRequest`], [`Goal`], [`Budget`],
//! [`Solution`] ([`Path`] + [`PlanStats`]).
//!
//! Planners own only their settings (and, for [`LazyPrm`](crate::lazy_prm::LazyPrm), a
//! roadmap); the space, the [`MotionValidator`] and the [`StateValidator`] belong to the
//! caller and are lent to each [`Planner::plan`] call, so one planner answers many queries.

use std::cell::RefCell;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Num, PlanError, bad_state};
use crate::motion::MotionValidator;
use crate::space::Space;
use crate::validity::StateValidator;

/// When a planner gives up: after a wall-clock time, a number of iterations, or whichever
/// comes first. At least one must be set, and a time limit must be zero or more seconds:
/// planners refuse other budgets with [`PlanError::BadInput`].
///
/// ```
/// use hearth_planning::planner::Budget;
///
/// let b = Budget::time(0.5).with_iterations(10_000);
/// assert_eq!(b.iterations, Some(10_000));
/// assert_eq!(b.time, Some(0.5));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Budget {
    /// Wall-clock limit in seconds, as given. Planners refuse a NaN or negative one with
    /// [`PlanError::BadInput`] and read more than 10⁹ s (`+∞` included) as 10⁹ s.
    pub time: Option<f64>,
    /// Iteration limit (what an iteration is depends on the planner; see each planner).
    /// Iteration limits make a run reproducible regardless of machine speed.
    pub iterations: Option<u64>,
}

/// The longest time limit, in seconds (about 32 years); longer ones, `+∞` included, read as
/// this.
const MAX_TIME: f64 = 1e9;

impl Budget {
    /// A time limit of `secs` seconds and no iteration limit. `secs` is kept as given: planners
    /// refuse a NaN or negative time limit with [`PlanError::BadInput`] (naming it) and read
    /// more than 10⁹ s, `+∞` included, as 10⁹ s. A zero time limit is valid: it runs out at once,
    /// so the planner returns [`PlanError::Timeout`] unless it finds a path before its first
    /// iteration.
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::{PlanError, Rrt};
    /// use rand::SeedableRng;
    /// # use hearth_planning::validity::StateValidator;
    /// # struct Free(u64);
    /// # impl StateValidator for Free {
    /// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
    /// #     fn checks(&self) -> u64 { self.0 }
    /// # }
    /// assert_eq!(Budget::time(0.25), Budget { time: Some(0.25), iterations: None });
    /// // `Free` is a validator that accepts every state.
    /// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
    /// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
    /// let mut plan = |budget: Budget| {
    ///     let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
    ///     Rrt::default().plan(&mut motion, &mut Free(0), &request, &budget, &mut rng)
    /// };
    /// assert!(plan(Budget::time(10.0)).is_ok());
    /// assert!(matches!(plan(Budget::time(0.0)), Err(PlanError::Timeout { .. })));
    /// let Err(PlanError::BadInput(why)) = plan(Budget::time(f64::NAN)) else { panic!("NaN s is refused") };
    /// assert!(why.contains("time limit is NaN"));
    /// assert!(matches!(plan(Budget::time(-1.0)), Err(PlanError::BadInput(_))));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn time(secs: f64) -> Self {
        Self {
            time: Some(secs),
            iterations: None,
        }
    }

    /// An iteration limit and no time limit: the budget for reproducible runs.
    ///
    /// ```
    /// use hearth_planning::planner::Budget;
    ///
    /// assert_eq!(Budget::iterations(500), Budget { time: None, iterations: Some(500) });
    /// ```
    pub fn iterations(n: u64) -> Self {
        Self {
            time: None,
            iterations: Some(n),
        }
    }

    /// The same budget with an iteration limit too (replacing any it had).
    ///
    /// ```
    /// use hearth_planning::planner::Budget;
    ///
    /// let b = Budget::time(2.0).with_iterations(100);
    /// assert_eq!((b.time, b.iterations), (Some(2.0), Some(100)));
    /// assert_eq!(Budget::iterations(5).with_iterations(7).iterations, Some(7));
    /// ```
    pub fn with_iterations(mut self, n: u64) -> Self {
        self.iterations = Some(n);
        self
    }

    /// The same budget with a time limit of `secs` seconds too (replacing any it had), kept as
    /// given like [`Budget::time`]'s: planners refuse a NaN or negative one with
    /// [`PlanError::BadInput`] and read more than 10⁹ s as 10⁹ s.
    ///
    /// ```
    /// use hearth_planning::planner::Budget;
    ///
    /// let b = Budget::iterations(100).with_time(0.5);
    /// assert_eq!((b.time, b.iterations), (Some(0.5), Some(100)));
    /// // Kept as given, for the planner to refuse.
    /// assert!(Budget::time(1.0).with_time(f64::NAN).time.is_some_and(f64::is_nan));
    /// assert_eq!(Budget::time(1.0).with_time(-2.0).time, Some(-2.0));
    /// ```
    pub fn with_time(mut self, secs: f64) -> Self {
        self.time = Some(secs);
        self
    }

    /// Checks that the budget sets a limit and that its time limit is zero or more seconds,
    /// and returns that time limit (at most [`MAX_TIME`]).
    fn check(&self) -> Result<Option<Duration>, PlanError> {
        if self.time.is_none() && self.iterations.is_none() {
            return Err(PlanError::BadInput(
                "the budget sets neither a time nor an iteration limit".to_owned(),
            ));
        }
        match self.time {
            None => Ok(None),
            // False for NaN; -0 is a zero duration.
            Some(secs) if secs >= 0.0 => Ok(Some(Duration::from_secs_f64(secs.min(MAX_TIME)))),
            Some(secs) => Err(PlanError::BadInput(format!(
                "the budget's time limit is {secs} s; it must be zero or more seconds"
            ))),
        }
    }
}

/// Where to go.
///
/// End-effector pose goals become [`Goal::AnyOf`] through
/// [`PoseGoal::sample`](crate::goal::PoseGoal::sample) (collision-aware IK), which every planner
/// handles natively (BiRRT seeds its goal tree with all of them, LazyPRM searches to the nearest
/// reachable one).
///
/// ```
/// use hearth_planning::planner::Goal;
///
/// let one = Goal::Config(vec![0.0, 1.0]);
/// let either = Goal::AnyOf(vec![vec![0.0, 1.0], vec![1.0, 0.0]]);
/// assert_eq!(one.states(), &either.states()[..1]);
/// assert_eq!(either.states().len(), 2);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Goal {
    /// One goal configuration.
    Config(Vec<f64>),
    /// Any of these configurations.
    AnyOf(Vec<Vec<f64>>),
}

impl Goal {
    /// The goal configurations: one for [`Goal::Config`], all of them for [`Goal::AnyOf`] (planners
    /// reject an empty list with [`PlanError::BadInput`]).
    ///
    /// ```
    /// use hearth_planning::planner::Goal;
    ///
    /// assert_eq!(Goal::Config(vec![0.5]).states(), &[vec![0.5]]);
    /// assert!(Goal::AnyOf(vec![]).states().is_empty());
    /// ```
    pub fn states(&self) -> &[Vec<f64>] {
        match self {
            Goal::Config(q) => std::slice::from_ref(q),
            Goal::AnyOf(qs) => qs,
        }
    }
}

/// A planning query: from `start` to `goal`.
///
/// ```
/// use hearth_planning::planner::{Goal, PlanRequest};
///
/// let r = PlanRequest::new(vec![0.0, 0.0], Goal::AnyOf(vec![vec![1.0, 0.0], vec![0.0, 1.0]]));
/// assert_eq!(r.goal.states().len(), 2);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanRequest {
    /// Start configuration.
    pub start: Vec<f64>,
    /// Goal configuration(s).
    pub goal: Goal,
}

impl PlanRequest {
    /// A request from `start` to `goal`.
    ///
    /// ```
    /// use hearth_planning::planner::{Goal, PlanRequest};
    ///
    /// let r = PlanRequest::new(vec![0.0], Goal::Config(vec![1.0]));
    /// assert_eq!(r, PlanRequest { start: vec![0.0], goal: Goal::Config(vec![1.0]) });
    /// ```
    pub fn new(start: Vec<f64>, goal: Goal) -> Self {
        Self { start, goal }
    }
}

/// A path: states whose consecutive pairs are valid motions, from the start to a goal. It
/// serialises as `{"states": [[...], ...]}`.
///
/// ```
/// use hearth_planning::planner::Path;
///
/// let path = Path { states: vec![vec![0.0, 0.0], vec![1.0, 0.5]] };
/// let json = serde_json::to_string(&path)?;
/// assert_eq!(json, r#"{"states":[[0.0,0.0],[1.0,0.5]]}"#);
/// assert_eq!(serde_json::from_str::<Path>(&json)?, path);
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Path {
    /// The states, start first.
    pub states: Vec<Vec<f64>>,
}

impl Path {
    /// Sum of the distances between consecutive states.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0, 0.0], &[5.0, 5.0], &[false, false])?;
    /// let path = Path { states: vec![vec![0.0, 0.0], vec![3.0, 4.0], vec![3.0, 5.0]] };
    /// assert_eq!(path.length(&space), 6.0);
    /// // A path of one state has length +0 (not the -0 of an empty float sum).
    /// let still = Path { states: vec![vec![1.0, 1.0]] };
    /// assert!(still.length(&space) == 0.0 && still.length(&space).is_sign_positive());
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn length<S: Space>(&self, space: &S) -> f64 {
        self.states
            .windows(2)
            .fold(0.0, |sum, w| sum + space.distance(&w[0], &w[1]))
    }
}

/// What a planner did.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::BiRrt;
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // `Free` is a validator that accepts every state.
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let mut free = Free(0);
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let solution = BiRrt::default().plan(&mut motion, &mut free, &request, &Budget::iterations(100), &mut rng)?;
/// let stats = solution.stats;
/// assert_eq!(stats.tree_sizes.len(), 2); // the start tree and the goal tree
/// assert!(stats.iterations <= 100);
/// assert_eq!((stats.states_checked, stats.motions_checked), (free.checks(), motion.motions()));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanStats {
    /// Iterations run (see each planner for what one is).
    pub iterations: u64,
    /// States checked by the validator during the call (its
    /// [`checks`](StateValidator::checks) delta, start and goal checks included).
    pub states_checked: u64,
    /// Motions checked by the motion validator during the call.
    pub motions_checked: u64,
    /// Size of each tree (RRT: one, BiRRT: start tree then goal tree) or of the roadmap.
    pub tree_sizes: Vec<usize>,
    /// Wall-clock time of the call.
    pub time: Duration,
}

/// A found path and what finding it took.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::Rrt;
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // `Free` is a validator that accepts every state.
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let solution = Rrt::default().plan(&mut motion, &mut Free(0), &request, &Budget::iterations(1_000), &mut rng)?;
/// assert_eq!(solution.path.states.first(), Some(&request.start));
/// assert_eq!(solution.path.states.last(), Some(&vec![0.9, 0.9]));
/// assert!(solution.stats.iterations >= 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Solution {
    /// The path, from the request's start to one of its goals.
    pub path: Path,
    /// Statistics of the call.
    pub stats: PlanStats,
}

/// A sampling-based planner, generic over the space so the hot loop is monomorphised (no
/// virtual calls per state).
///
/// Every implementation validates its input first: a budget with no limit or with a NaN or
/// negative time limit, states of the wrong dimension, non-finite or out of bounds give
/// [`PlanError::BadInput`]; an invalid start
/// [`PlanError::InvalidStart`]; all goals invalid [`PlanError::InvalidGoals`]. Invalid goals
/// among valid ones are skipped. A run is deterministic for a given generator state and an
/// iteration-only budget.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, Path, PlanRequest, Planner};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::{BiRrt, LazyPrm, Rrt};
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // Any planner of a joint space, across an empty square; `Free` accepts every state.
/// fn cross<P: Planner<JointSpace>>(mut planner: P) -> Path {
///     let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2]).unwrap(), 0.01);
///     let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
///     let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
///     planner.plan(&mut motion, &mut Free(0), &request, &Budget::iterations(1_000), &mut rng).unwrap().path
/// }
/// assert_eq!(cross(Rrt::default()).states.last(), Some(&vec![0.9, 0.9]));
/// assert_eq!(cross(BiRrt::default()).states.last(), Some(&vec![0.9, 0.9]));
/// assert_eq!(cross(LazyPrm::default()).states.last(), Some(&vec![0.9, 0.9]));
/// ```
pub trait Planner<S: Space> {
    /// Plans from `request.start` to one of its goals, checking states with `validator` and
    /// edges with `motion` (which also provides the space), until `budget` runs out
    /// ([`PlanError::Timeout`]).
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::validity::StateValidator;
    /// use hearth_planning::{PlanError, Rrt};
    /// use rand::SeedableRng;
    ///
    /// // A disc of obstacle in the middle of the unit square.
    /// struct Disc(u64);
    /// impl StateValidator for Disc {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; (q[0] - 0.5).hypot(q[1] - 0.5) > 0.2 }
    ///     fn checks(&self) -> u64 { self.0 }
    /// }
    /// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    /// let mut plan = |start: Vec<f64>, budget: Budget| {
    ///     let request = PlanRequest::new(start, Goal::Config(vec![0.9, 0.9]));
    ///     Rrt::default().plan(&mut motion, &mut Disc(0), &request, &budget, &mut rng)
    /// };
    /// assert_eq!(plan(vec![0.1, 0.1], Budget::iterations(5_000))?.path.states.last(), Some(&vec![0.9, 0.9]));
    /// assert!(matches!(plan(vec![0.5, 0.5], Budget::iterations(10)), Err(PlanError::InvalidStart { .. })));
    /// assert!(matches!(plan(vec![2.0, 0.1], Budget::iterations(10)), Err(PlanError::BadInput(_))));
    /// assert!(matches!(plan(vec![0.1, 0.1], Budget::default()), Err(PlanError::BadInput(_))));
    /// assert!(matches!(plan(vec![0.1, 0.1], Budget::time(-1.0)), Err(PlanError::BadInput(_))));
    /// assert!(matches!(plan(vec![0.1, 0.1], Budget::iterations(0)), Err(PlanError::Timeout { .. })));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    fn plan<V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<Solution, PlanError>;
}

thread_local! {
    /// The stop count of the [`Race`](crate::race::Race) that this thread plans for, if any.
    static STOP_AT: RefCell<Option<Arc<AtomicU64>>> = const { RefCell::new(None) };
}

/// Runs `f` with `stop` as this thread's stop count: every planning run started inside `f`
/// ends (as a timeout) once it has made as many iterations as `stop` holds.
pub(crate) fn with_stop_at<T>(stop: &Arc<AtomicU64>, f: impl FnOnce() -> T) -> T {
    /// Puts the thread's previous stop count back, even when `f` panics.
    struct Restore(Option<Arc<AtomicU64>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let before = self.0.take();
            STOP_AT.with(|s| *s.borrow_mut() = before);
        }
    }
    let _restore = Restore(STOP_AT.with(|s| s.replace(Some(Arc::clone(stop)))));
    f()
}

/// The budget and counters of one planning call.
pub(crate) struct Run {
    started: Instant,
    deadline: Option<Instant>,
    max_iterations: u64,
    /// An iteration count shared by the planners of one [`Race`](crate::race::Race) (set
    /// on this thread by [`with_stop_at`]): once this run has made that many iterations,
    /// another copy has already found a path in as few, so this one stops.
    stop_at: Option<Arc<AtomicU64>>,
    checks0: u64,
    motions0: u64,
    pub(crate) iterations: u64,
}

impl Run {
    /// Checks the budget ([`PlanError::BadInput`] for one without a limit or with a NaN or
    /// negative time limit), then starts the clock and the counters.
    pub(crate) fn start<S: Space, V: StateValidator + ?Sized>(
        budget: &Budget,
        motion: &MotionValidator<S>,
        validator: &V,
    ) -> Result<Self, PlanError> {
        let time = budget.check()?;
        let started = Instant::now();
        Ok(Self {
            started,
            deadline: time.and_then(|t| started.checked_add(t)),
            max_iterations: budget.iterations.unwrap_or(u64::MAX),
            stop_at: STOP_AT.with(|s| s.borrow().clone()),
            checks0: validator.checks(),
            motions0: motion.motions(),
            iterations: 0,
        })
    }

    /// Counts an iteration; false once the budget is spent.
    #[inline]
    pub(crate) fn next(&mut self) -> bool {
        if self.iterations >= self.max_iterations || self.deadline.is_some_and(|d| Instant::now() >= d) {
            return false;
        }
        if let Some(stop) = &self.stop_at
            && self.iterations >= stop.load(Ordering::Relaxed)
        {
            return false;
        }
        self.iterations += 1;
        true
    }

    /// Statistics so far.
    pub(crate) fn stats<S: Space, V: StateValidator + ?Sized>(
        &self,
        motion: &MotionValidator<S>,
        validator: &V,
        tree_sizes: Vec<usize>,
    ) -> PlanStats {
        PlanStats {
            iterations: self.iterations,
            states_checked: validator.checks() - self.checks0,
            motions_checked: motion.motions() - self.motions0,
            tree_sizes,
            time: self.started.elapsed(),
        }
    }
}

/// Checks the request and returns the valid goals (in request order); [`Run::start`] checks
/// the budget.
pub(crate) fn valid_goals<S: Space, V: StateValidator + ?Sized>(
    space: &S,
    validator: &mut V,
    request: &PlanRequest,
) -> Result<Vec<Vec<f64>>, PlanError> {
    space.check(&request.start).map_err(|e| bad_state("start", e))?;
    let goals = request.goal.states();
    if goals.is_empty() {
        return Err(PlanError::BadInput("no goal state given".to_owned()));
    }
    for (i, g) in goals.iter().enumerate() {
        space.check(g).map_err(|e| bad_state(&format!("goal {i}"), e))?;
    }
    if !validator.is_valid(&request.start) {
        return Err(PlanError::InvalidStart { contact: None });
    }
    let valid: Vec<Vec<f64>> = goals.iter().filter(|g| validator.is_valid(g)).cloned().collect();
    if valid.is_empty() {
        return Err(PlanError::InvalidGoals {
            count: goals.len(),
            first_contact: None,
        });
    }
    Ok(valid)
}

/// The default step size of tree planners: 0.2 × the space's extent, OMPL's
/// `maxDistance` default. The extent is twice the distance from the lower corner of the bounds
/// to their centre: the diagonal of the bounds for bounded coordinates, 2π per continuous one
/// (twice its true extent; the difference only matters for a mostly-continuous space).
///
/// ```
/// use hearth_planning::planner::default_range;
/// use hearth_planning::space::JointSpace;
///
/// let square = JointSpace::new(&[0.0, 0.0], &[3.0, 4.0], &[false, false])?;
/// assert!((default_range(&square) - 1.0).abs() < 1e-12);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
pub fn default_range<S: Space>(space: &S) -> f64 {
    0.2 * diameter(space)
}

/// Twice the distance from `space`'s lower bounds to its centre: the longest edge between
/// states within the bounds of a space without continuous coordinates, and an upper bound on
/// it otherwise.
pub(crate) fn diameter<S: Space>(space: &S) -> f64 {
    let centre: Vec<f64> = space
        .lower()
        .iter()
        .zip(space.upper())
        .map(|(l, u)| 0.5 * (l + u))
        .collect();
    2.0 * space.distance(space.lower(), &centre)
}

/// `value` if it is positive and finite.
pub(crate) fn positive(value: f64) -> Option<f64> {
    (value.is_finite() && value > 0.0).then_some(value)
}

/// `value` if it is positive and finite, else [`PlanError::BadInput`] naming the setting `what`.
pub(crate) fn positive_finite(what: &str, value: f64) -> Result<f64, PlanError> {
    positive(value)
        .ok_or_else(|| PlanError::BadInput(format!("{what} is {}; it must be positive and finite", Num(value))))
}

/// The spacing that [`MotionValidator::new`](crate::motion::MotionValidator::new), which has
/// no `Result`, uses for a resolution that is not positive and finite.
pub(crate) fn resolution_or_default(resolution: f64) -> f64 {
    positive(resolution).unwrap_or(0.01)
}

/// The step size from a setting: `Some(r)` must be positive, finite and no shorter than
/// [`finest_resolution`](crate::motion::finest_resolution) (a straight connection of steps of
/// 10⁻⁹ rad adds states by the billion before the budget is next looked at), `None` is
/// [`default_range`] times `scale` (or 1 for a zero-extent space).
pub(crate) fn resolve_range<S: Space>(space: &S, range: Option<f64>, scale: f64) -> Result<f64, PlanError> {
    match range {
        Some(r) => crate::motion::checked_resolution(space, "range", r),
        None => {
            let r = default_range(space) * scale;
            Ok(if r.is_finite() && r > 0.0 { r } else { 1.0 })
        }
    }
}

/// A tree of states: flat arena, parent links and a nearest-neighbour index.
pub(crate) struct Tree {
    pub(crate) nn: crate::nn::NearestNeighbors,
    parents: Vec<u32>,
}

/// Parent of a root.
const ROOT: u32 = u32::MAX;

impl Tree {
    pub(crate) fn new(dim: usize) -> Self {
        Self {
            nn: crate::nn::NearestNeighbors::new(dim),
            parents: Vec::new(),
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.parents.len()
    }

    pub(crate) fn add(&mut self, q: &[f64], parent: Option<usize>) -> usize {
        self.parents.push(parent.map_or(ROOT, |p| p as u32));
        self.nn.insert(q)
    }

    #[inline]
    pub(crate) fn state(&self, i: usize) -> &[f64] {
        self.nn.state(i)
    }

    /// The parent of state `i` (`None` for a root).
    #[inline]
    pub(crate) fn parent(&self, i: usize) -> Option<usize> {
        let p = self.parents[i];
        (p != ROOT).then_some(p as usize)
    }

    /// States from the root to `i`.
    pub(crate) fn branch(&self, mut i: usize) -> Vec<Vec<f64>> {
        let mut out = vec![self.state(i).to_vec()];
        while self.parents[i] != ROOT {
            i = self.parents[i] as usize;
            out.push(self.state(i).to_vec());
        }
        out.reverse();
        out
    }
}
