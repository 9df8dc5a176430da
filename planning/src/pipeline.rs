//! [`MotionPlanner`]: a chain's planner, its post-processing and the final check in one value,
//! set up the way `hearth bench plan` plans MotionBenchMaker's problems.
//!
//! Planning a timed motion takes several parts: a [`RobotValidity`], a planning space with the
//! joints' reach as distance weights, a [`MotionValidator`] for the planner's edges, a planner
//! with a step tuned to that metric, an unweighted space in which the path is shortcut and
//! timed within the chain's [`Limits`], and a check of the timed motion at a fine resolution.
//! [`MotionPlanner`] holds them, with the settings the benchmarks chose
//! ([`MotionSettings::default`]), and turns a start and a goal into a [`PlannedMotion`] in one
//! call. Every part stays reachable for what the defaults do not cover (another planner, other
//! limits, objects attached to the gripper).

use std::any::Any;
use std::time::{Duration, Instant};

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::birrt::BiRrt;
use crate::error::PlanError;
use crate::motion::{MotionValidator, checked_resolution};
use crate::planner::{Budget, Goal, Path, PlanRequest, PlanStats, Planner};
use crate::shortcut::{ShortcutSettings, Smoothing, smooth};
use crate::space::JointSpace;
use crate::trajectory::{Limits, Trajectory};
use crate::validity::RobotValidity;

/// Settings of a [`MotionPlanner`]. The defaults are those of `hearth bench plan` on
/// MotionBenchMaker's Panda and Fetch problems (`docs/benchmarks.md`): BiRRT in the joints'
/// reach metric with edges checked every 1/32, parabolic shortcutting, and a check of the timed
/// motion every 0.002 rad.
///
/// ```
/// let s = hearth_planning::pipeline::MotionSettings::default();
/// assert!(s.reach_weights && s.range.is_none());
/// assert_eq!((s.resolution, s.fine_resolution), (1.0 / 32.0, 0.002));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MotionSettings {
    /// Plan in the joints' reach metric ([`RobotValidity::joint_weights`]: a wrist weighs less
    /// than a shoulder, so every step moves the robot about equally far). With it, every
    /// planner solved more of the Fetch's benchmark problems, and faster (fiftieth round of
    /// `docs/planning-log.md`). Smoothing, timing and the final check are unweighted either way.
    pub reach_weights: bool,
    /// The default planner's longest step, in the planning metric. `None`: with the reach
    /// weights [`reach_step`] (the Panda's and the Fetch's benchmark steps), without them
    /// [`BiRrt`]'s own default.
    pub range: Option<f64>,
    /// Spacing of the planner's edge checks, in the planning metric.
    pub resolution: f64,
    /// Spacing (rad, unweighted) at which shortcuts, repairs and the timed motion are
    /// checked: at most `resolution`.
    pub fine_resolution: f64,
    /// Post-processing of the planner's path.
    pub smoothing: Smoothing,
    /// Shortcut attempts per stage of the post-processing.
    pub shortcut_attempts: usize,
    /// Wall-clock budget of the post-processing, after which it returns what it has (still
    /// checked).
    pub smoothing_time: Duration,
}

impl Default for MotionSettings {
    fn default() -> Self {
        Self {
            reach_weights: true,
            range: None,
            resolution: 1.0 / 32.0,
            fine_resolution: 0.002,
            smoothing: Smoothing::Parabolic,
            shortcut_attempts: 100,
            smoothing_time: Duration::from_secs(1),
        }
    }
}

/// BiRRT's step in the joints' reach metric for a chain of `dof` joints: 0.5 up to seven
/// joints, 0.4 for more. Measured on MotionBenchMaker (fiftieth round of
/// `docs/planning-log.md`): the Panda's seven joints planned fastest with 0.5, the Fetch's
/// torso and arm (eight) with 0.4; `hearth bench plan` takes the same.
///
/// ```
/// use hearth_planning::pipeline::reach_step;
/// assert_eq!((reach_step(7), reach_step(8)), (0.5, 0.4));
/// ```
pub fn reach_step(dof: usize) -> f64 {
    if dof <= 7 { 0.5 } else { 0.4 }
}

/// The weight schedule `hearth bench plan` gives the Fetch's BiRRT
/// ([`MotionPlanner::with_weight_schedule`]): the reach weights squared from the start, as
/// they are from iteration 160,000 (about 0.2 s on the 2-vCPU benchmark machine), their square
/// roots from 360,000. The squared weights planned the Fetch's cage and open problems fastest,
/// the square roots its wedged bookshelf goals more often; the schedule took 15 % off the
/// Fetch's median planning times (fifty-first round of `docs/planning-log.md`). The Panda
/// plans its cage more slowly with the squared weights, so it keeps one metric.
///
/// ```
/// let s = hearth_planning::pipeline::FETCH_WEIGHT_SCHEDULE;
/// assert_eq!(s[0], (0, 2.0));
/// assert!(s.windows(2).all(|w| w[0].0 < w[1].0));
/// ```
pub const FETCH_WEIGHT_SCHEDULE: [(u64, f64); 3] = [(0, 2.0), (160_000, 1.0), (360_000, 0.5)];

/// The largest power of the reach weights a weight schedule may take: the Fetch's lightest
/// joint (0.25) weighs 0.004 at the fourth power, its edges checked every 8 rad of it.
///
/// ```
/// assert_eq!(hearth_planning::pipeline::MAX_WEIGHT_POWER, 4.0);
/// ```
pub const MAX_WEIGHT_POWER: f64 = 4.0;

/// A timed, checked motion from [`MotionPlanner::plan`].
///
/// ```
/// # use std::sync::Arc;
/// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
/// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
/// # use hearth_planning::{Budget, Goal, ParryScene, RobotValidity};
/// # use rand::SeedableRng;
/// # let panda = RobotModel::builtin("panda").unwrap();
/// # let arm = Chain::named(&panda, "arm").unwrap();
/// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
/// # let validity = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
/// # let mut planner = MotionPlanner::new(validity, MotionSettings::default())?;
/// # let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let start = [0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.785];
/// let goal = Goal::Config(vec![1.0, 0.3, 0.0, -1.2, 0.0, 1.5, 0.785]);
/// let motion = planner.plan(&start, goal, &Budget::iterations(1_000), &mut rng)?;
/// // The planner's path, then the shortcut and timed motion, sampled at 100 Hz.
/// assert_eq!(motion.planned.states[0], start);
/// let (mut q, mut v) = ([0.0; 7], [0.0; 7]);
/// for k in 0..=(motion.trajectory.duration() * 100.0) as usize {
///     motion.trajectory.sample(k as f64 / 100.0, &mut q, Some(&mut v));
/// }
/// assert!(motion.stats.states_checked > 0); // nothing in the way: no edge to repair
/// assert_eq!(motion.repaired, 0);
/// # Ok::<(), hearth_planning::PlanError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PlannedMotion {
    /// The motion in time, within the planner's [`Limits`]: sample positions, velocities and
    /// accelerations at any time.
    pub trajectory: Trajectory,
    /// The post-processed geometric path (states at most the motion validator's resolution
    /// apart for a parabolic trajectory, the shortcut waypoints otherwise).
    pub path: Path,
    /// The planner's own path, before post-processing.
    pub planned: Path,
    /// The planner's statistics (time, iterations, states and motions checked, tree sizes).
    pub stats: PlanStats,
    /// Wall-clock time of the post-processing.
    pub smoothing_time: Duration,
    /// Edges of the planner's path that failed at the fine resolution and were re-planned.
    pub repaired: usize,
}

/// A chain's planner with its post-processing: states checked by a [`RobotValidity`], a
/// planner ([`BiRrt`] unless [`with_planner`](MotionPlanner::with_planner) sets another) in
/// the joints' reach metric, then shortcutting and timing within the chain's limits, checked at
/// the fine resolution ([`MotionSettings`]).
///
/// The planner value is kept between calls, so a [`LazyPrm`](crate::LazyPrm) given to
/// [`with_planner`](MotionPlanner::with_planner) reuses its roadmap while the obstacles stay
/// the same. Bad input (a start or goal of the wrong length, NaN or outside the limits, in
/// collision) is a typed [`PlanError`] that names the contact, and leaves the planner as it
/// was.
///
/// The self-collision certificates fill as plans check states; for steady times from the
/// first plan on, fill them ahead as the benchmark does:
/// `planner.validity().warm_pair_tables(1_000_000, seed)` (about 0.7 s for the Panda on
/// two cores; the tables belong to the robot model, shared by every validator of it).
///
/// ```
/// use std::sync::Arc;
/// use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
/// use hearth_planning::obstacles::Obstacle;
/// use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
/// use hearth_planning::{Budget, Goal, ParryScene, RobotValidity};
/// use parry3d::math::{Pose, Vector};
/// use rand::SeedableRng;
///
/// let panda = RobotModel::builtin("panda")?;
/// let arm = Chain::named(&panda, "arm")?;
/// let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
/// let post = Obstacle::cuboid("post", Pose::translation(0.5, 0.0, 0.3), Vector::new(0.05, 0.05, 0.3));
/// let validity = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![post])));
/// let mut planner = MotionPlanner::new(validity, MotionSettings::default())?;
///
/// let start = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
/// let goal = vec![0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let motion = planner.plan(&start, Goal::Config(goal.clone()), &Budget::time(1.0), &mut rng)?;
/// let mut end = vec![0.0; 7];
/// motion.trajectory.sample(motion.trajectory.duration(), &mut end, None);
/// assert!(end.iter().zip(&goal).all(|(a, b)| (a - b).abs() < 1e-9));
///
/// // Through the post: the start is refused, naming the contact.
/// let err = planner.plan(&[0.0, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785], Goal::Config(goal), &Budget::time(1.0), &mut rng);
/// assert!(err.unwrap_err().to_string().contains("post"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct MotionPlanner<P = BiRrt> {
    validity: RobotValidity,
    planner: P,
    /// Edges in the planning metric.
    motion: MotionValidator<JointSpace>,
    /// Edges in the unweighted space: post-processing and the final check.
    plain: MotionValidator<JointSpace>,
    limits: Limits,
    settings: MotionSettings,
    /// The joints' reach weights (with [`MotionSettings::reach_weights`]).
    reach: Option<Vec<f64>>,
    /// BiRRT's later metrics: from an iteration on, the planning space with other weights.
    schedule: Vec<(u64, JointSpace)>,
}

impl<P: std::fmt::Debug> std::fmt::Debug for MotionPlanner<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MotionPlanner")
            .field("chain", &self.validity.chain().joint_names())
            .field("planner", &self.planner)
            .field("settings", &self.settings)
            .finish()
    }
}

impl MotionPlanner<BiRrt> {
    /// A planner for `validity`'s chain with [`BiRrt`] and the chain's limits
    /// ([`Limits::for_chain`]).
    ///
    /// # Errors
    /// [`PlanError::BadInput`] for a resolution that is not positive and finite or finer than
    /// the chain's space allows, a fine resolution coarser than the resolution, a step that is
    /// not positive and finite, or a smoothing budget that is zero.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    /// let validity = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
    /// assert!(MotionPlanner::new(validity.clone(), MotionSettings::default()).is_ok());
    /// let coarse = MotionSettings { fine_resolution: 0.1, ..Default::default() };
    /// assert!(MotionPlanner::new(validity, coarse).unwrap_err().to_string().contains("fine resolution"));
    /// ```
    pub fn new(validity: RobotValidity, settings: MotionSettings) -> Result<Self, PlanError> {
        let plain = JointSpace::from_chain(validity.chain()).map_err(|e| PlanError::BadInput(e.to_string()))?;
        let reach = settings.reach_weights.then(|| validity.joint_weights());
        let space = match &reach {
            Some(w) => weighted(&plain, w, 1.0)?,
            None => plain.clone(),
        };
        let motion = MotionValidator::try_new(space, settings.resolution)?;
        let fine = checked_resolution(&plain, "fine resolution", settings.fine_resolution)?;
        if fine > settings.resolution {
            return Err(PlanError::BadInput(format!(
                "the fine resolution ({fine}) must be at most the resolution ({})",
                settings.resolution
            )));
        }
        if let Some(r) = settings.range
            && !(r.is_finite() && r > 0.0)
        {
            return Err(PlanError::BadInput(format!(
                "the step (range) is {r}; it must be positive and finite"
            )));
        }
        if settings.smoothing_time.is_zero() {
            return Err(PlanError::BadInput("the smoothing time is zero".into()));
        }
        let dof = validity.chain().dof();
        let range = settings
            .range
            .or_else(|| settings.reach_weights.then(|| reach_step(dof)));
        Ok(Self {
            limits: Limits::for_chain(validity.chain()),
            planner: BiRrt::with_range(range),
            plain: MotionValidator::try_new(plain, settings.resolution)?,
            motion,
            validity,
            settings,
            reach,
            schedule: Vec::new(),
        })
    }

    /// The same planner changing its metric part-way through each plan
    /// ([`BiRrt::plan_with_metrics`]; the trees are kept): `steps` are (iteration, power)
    /// pairs, each planning in the joints' reach weights raised to `power` from `iteration`
    /// on, the first from iteration 0. [`FETCH_WEIGHT_SCHEDULE`] is the benchmark's for the
    /// Fetch. Iterations rather than seconds keep a seed's plan the same on any machine.
    /// [`with_planner`](MotionPlanner::with_planner) drops the schedule: set it after
    /// choosing the BiRRT.
    ///
    /// # Errors
    /// [`PlanError::BadInput`] without [`MotionSettings::reach_weights`], for no steps, a
    /// first step after iteration 0, iterations that do not increase, or a power outside
    /// 0–4 (0 plans unweighted).
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity, Space};
    /// # let fetch = RobotModel::builtin("fetch").unwrap();
    /// # let arm = Chain::named(&fetch, "arm_with_torso").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&fetch, &SelfCollisionSettings { samples: 300, ..Default::default() });
    /// use hearth_planning::pipeline::{FETCH_WEIGHT_SCHEDULE, MotionPlanner, MotionSettings};
    /// let validity = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
    /// let planner = MotionPlanner::new(validity.clone(), MotionSettings::default())?;
    /// let scheduled = MotionPlanner::new(validity, MotionSettings::default())?
    ///     .with_weight_schedule(&FETCH_WEIGHT_SCHEDULE)?;
    /// // The plans start in the squared weights: a wrist's turn counts for less.
    /// let (a, mut b) = (vec![0.0; 8], vec![0.0; 8]);
    /// b[7] = 1.0; // wrist_roll_joint
    /// assert!(scheduled.space().distance(&a, &b) < planner.space().distance(&a, &b));
    /// assert!(scheduled.with_weight_schedule(&[(5, 1.0)]).is_err()); // not from iteration 0
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn with_weight_schedule(mut self, steps: &[(u64, f64)]) -> Result<Self, PlanError> {
        let Some(reach) = &self.reach else {
            return Err(PlanError::BadInput(
                "a weight schedule needs the reach weights (MotionSettings::reach_weights)".into(),
            ));
        };
        let (mut first, later) = schedule_spaces(self.plain.space(), reach, steps)?;
        self.motion.swap_space(&mut first);
        self.schedule = later;
        Ok(self)
    }
}

/// The spaces of a weight schedule for [`BiRrt::plan_with_metrics`]: `steps` are (iteration,
/// power) pairs, each meaning `plain` with the distance weights `reach` raised to `power` from
/// that iteration on. Returns the first step's space, where a plan starts, and the later
/// steps' spaces with their iterations.
///
/// # Errors
/// [`PlanError::BadInput`] for no steps, a first step after iteration 0, iterations that do
/// not increase, a power outside 0–[`MAX_WEIGHT_POWER`], or weights of another length than
/// the space.
///
/// ```
/// use hearth_planning::pipeline::schedule_spaces;
/// use hearth_planning::space::{JointSpace, Space};
/// let plain = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
/// let (first, later) = schedule_spaces(&plain, &[1.0, 0.25], &[(0, 2.0), (100, 0.5)])?;
/// assert_eq!(first.euclidean_weights(), Some(&[1.0, 0.0625][..]));
/// assert_eq!((later[0].0, later[0].1.euclidean_weights()), (100, Some(&[1.0, 0.5][..])));
/// assert!(schedule_spaces(&plain, &[1.0, 0.25], &[(0, 2.0), (0, 1.0)]).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn schedule_spaces(
    plain: &JointSpace,
    reach: &[f64],
    steps: &[(u64, f64)],
) -> Result<(JointSpace, Vec<(u64, JointSpace)>), PlanError> {
    match steps.first() {
        None => return Err(PlanError::BadInput("a weight schedule needs at least one step".into())),
        Some(&(at, _)) if at != 0 => {
            return Err(PlanError::BadInput(format!(
                "a weight schedule's first step applies from iteration 0, not {at}"
            )));
        }
        Some(_) => {}
    }
    if let Some(w) = steps.windows(2).find(|w| w[1].0 <= w[0].0) {
        return Err(PlanError::BadInput(format!(
            "a weight schedule's iterations must increase ({} after {})",
            w[1].0, w[0].0
        )));
    }
    let mut spaces = steps
        .iter()
        .map(|&(at, power)| weighted(plain, reach, power).map(|s| (at, s)))
        .collect::<Result<Vec<_>, _>>()?;
    let (_, first) = spaces.remove(0);
    Ok((first, spaces))
}

/// `plain` with the distance weights `reach` raised to `power` (0 to 4).
fn weighted(plain: &JointSpace, reach: &[f64], power: f64) -> Result<JointSpace, PlanError> {
    if !(0.0..=MAX_WEIGHT_POWER).contains(&power) {
        return Err(PlanError::BadInput(format!(
            "a power of the reach weights must be between 0 and {MAX_WEIGHT_POWER}, not {power}"
        )));
    }
    let w: Vec<f64> = reach.iter().map(|w| w.powf(power)).collect();
    plain
        .clone()
        .with_weights(&w)
        .map_err(|e| PlanError::BadInput(e.to_string()))
}

impl<P: Planner<JointSpace> + 'static> MotionPlanner<P> {
    /// The same set-up with another planner (its own step: [`MotionSettings::range`] sets
    /// only the default [`BiRrt`]'s).
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// use hearth_planning::LazyPrm;
    /// let planner = MotionPlanner::new(validity, MotionSettings::default())?.with_planner(LazyPrm::default());
    /// assert_eq!(planner.planner().roadmap_size(), 0); // grown by the first query, kept for the next
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn with_planner<Q: Planner<JointSpace> + 'static>(self, planner: Q) -> MotionPlanner<Q> {
        let mut motion = self.motion;
        // A schedule's first metric back out: the new planner plans in the settings' metric.
        if !self.schedule.is_empty()
            && let Some(reach) = &self.reach
            && let Ok(mut space) = weighted(self.plain.space(), reach, 1.0)
        {
            motion.swap_space(&mut space);
        }
        MotionPlanner {
            validity: self.validity,
            planner,
            motion,
            plain: self.plain,
            limits: self.limits,
            settings: self.settings,
            reach: self.reach,
            schedule: Vec::new(),
        }
    }

    /// The same set-up timed within other limits (e.g. [`Limits::scaled`] for slower motions).
    ///
    /// # Errors
    /// [`PlanError::BadInput`] when the limits have another number of joints than the chain.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm.clone(), SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// use hearth_planning::trajectory::Limits;
    /// let slow = Limits::for_chain(&arm).scaled(0.5, 0.5).unwrap();
    /// let planner = MotionPlanner::new(validity, MotionSettings::default())?.with_limits(slow.clone())?;
    /// assert_eq!(planner.limits(), &slow);
    /// let two = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![1.0; 2]).unwrap();
    /// assert!(planner.with_limits(two).is_err());
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn with_limits(mut self, limits: Limits) -> Result<Self, PlanError> {
        let dof = self.validity.chain().dof();
        if limits.velocity().len() != dof {
            return Err(PlanError::BadInput(format!(
                "limits for {} joints, the chain has {dof}",
                limits.velocity().len()
            )));
        }
        self.limits = limits;
        Ok(self)
    }

    /// The state validity: to move the robot's base or fixed joints
    /// ([`RobotValidity::set_reference`]), attach a held object, or explain a contact.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// let mut planner = MotionPlanner::new(validity, MotionSettings::default())?;
    /// let q = [0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.785];
    /// assert!(planner.validity_mut().explain(&q).is_none()); // nothing to touch
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn validity_mut(&mut self) -> &mut RobotValidity {
        &mut self.validity
    }

    /// The state validity.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// let planner = MotionPlanner::new(validity, MotionSettings::default())?;
    /// assert_eq!(planner.validity().chain().dof(), 7);
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn validity(&self) -> &RobotValidity {
        &self.validity
    }

    /// The planner.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// let planner = MotionPlanner::new(validity, MotionSettings::default())?;
    /// assert_eq!(planner.planner().range, Some(0.5)); // the Panda's seven joints, reach weights
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn planner(&self) -> &P {
        &self.planner
    }

    /// The planning space a plan starts in (weighted with [`MotionSettings::reach_weights`],
    /// by a schedule's first power with [`with_weight_schedule`](MotionPlanner::with_weight_schedule)).
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity, Space};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// let planner = MotionPlanner::new(validity, MotionSettings::default())?;
    /// let (a, mut b) = (vec![0.0; 7], vec![0.0; 7]);
    /// b[6] = 1.0; // the last wrist joint weighs less than a shoulder joint
    /// assert!(planner.space().distance(&a, &b) < 0.5);
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn space(&self) -> &JointSpace {
        self.motion.space()
    }

    /// The limits the motions are timed within.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{ParryScene, RobotValidity};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// let planner = MotionPlanner::new(validity, MotionSettings::default())?;
    /// assert_eq!(planner.limits().velocity().len(), 7);
    /// # Ok::<(), hearth_planning::PlanError>(())
    /// ```
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Plans from `start` to `goal` within `budget` (the planner's; the post-processing has
    /// [`MotionSettings::smoothing_time`] on top), then shortcuts, times and checks the motion
    /// at the fine resolution. The same seed gives the same motion, up to the budget's clock
    /// (give an iteration limit for motions that repeat on any machine).
    ///
    /// # Errors
    /// The planner's: [`PlanError::InvalidStart`] and [`PlanError::InvalidGoals`] naming the
    /// contact, [`PlanError::BadInput`] (wrong length, NaN, outside the limits, a budget
    /// without limits), [`PlanError::Timeout`] with statistics; and the post-processing's
    /// [`PlanError::InvalidMotion`] when no checked motion could be made from the path.
    ///
    /// ```
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
    /// # use hearth_planning::{Budget, Goal, ParryScene, PlanError, RobotValidity};
    /// # use rand::SeedableRng;
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let validity = RobotValidity::new(arm, SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() }), Arc::new(ParryScene::new(vec![])));
    /// let mut planner = MotionPlanner::new(validity, MotionSettings::default())?;
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let start = [0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.785];
    /// let goal = Goal::Config(vec![1.0, 0.3, 0.0, -1.2, 0.0, 1.5, 0.785]);
    /// let motion = planner.plan(&start, goal.clone(), &Budget::iterations(1_000), &mut rng)?;
    /// assert!(motion.trajectory.duration() > 0.0);
    /// let nan = [f64::NAN; 7];
    /// assert!(matches!(planner.plan(&nan, goal, &Budget::iterations(1_000), &mut rng), Err(PlanError::BadInput(_))));
    /// # Ok::<(), PlanError>(())
    /// ```
    pub fn plan<R: Rng + ?Sized>(
        &mut self,
        start: &[f64],
        goal: Goal,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<PlannedMotion, PlanError> {
        let request = PlanRequest::new(start.to_vec(), goal);
        let validity = &mut self.validity;
        let planned = match (&mut self.planner as &mut dyn Any).downcast_mut::<BiRrt>() {
            // (Only a BiRRT planner gets a schedule.)
            Some(birrt) if !self.schedule.is_empty() => {
                birrt.plan_with_metrics(&mut self.motion, validity, &request, budget, rng, &mut self.schedule)
            }
            _ => self.planner.plan(&mut self.motion, validity, &request, budget, rng),
        };
        let solution = planned.map_err(|e| e.explain_with(&request, |q| validity.explain(q).map(|c| c.to_string())))?;
        let fine = self.settings.fine_resolution;
        let settings = ShortcutSettings {
            attempts: self.settings.shortcut_attempts,
            time_limit: None,
            // Ramps are checked at the final check's spacing, and the returned motion passes
            // that check.
            fine_resolution: Some(fine),
            verify_resolution: Some(fine),
        };
        let t0 = Instant::now();
        let smoothed = smooth(
            self.settings.smoothing,
            &mut self.plain,
            validity,
            &solution.path,
            &self.limits,
            &settings,
            self.settings.smoothing_time,
            rng,
        )?;
        Ok(PlannedMotion {
            trajectory: smoothed.trajectory,
            path: smoothed.path,
            planned: solution.path,
            stats: solution.stats,
            smoothing_time: t0.elapsed(),
            repaired: smoothed.repaired,
        })
    }
}
