//! [`Arm`]: planning and executing arm motions of a robot in the live world.
//!
//! A planned motion goes: collision-aware IK for the goal (several distinct solutions) →
//! BiRRT in the joint space of the arm chain, checked against the live world (what the base
//! stands on ignored, a held object attached) → random, then acceleration-bounded (parabolic)
//! shortcutting → a jerk-limited trajectory (by default the smoothed motion's moving average;
//! see [`JerkPass`]), kept only if it is collision-free at a fine resolution → execution as
//! position targets per control step ([`Execution::Physics`], with unexpected contacts reported
//! as [`SkillError::Collision`]) or by setting the joints along it ([`Execution::Kinematic`]).
//!
//! Straight-line moves of the end effector ([`Arm::move_linear`]) are solved as small IK steps
//! from the current configuration and executed at a fixed Cartesian speed until the distance is
//! covered or the contact force on the arm passes a limit.

use std::sync::Arc;
use std::time::{Duration, Instant};

use hearth_kinematics::parry3d::shape::SharedShape;
use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_planning::goal::PoseGoal;
use hearth_planning::motion::finest_resolution;
use hearth_planning::obstacles::ParryScene;
use hearth_planning::shortcut::{ShortcutSettings, Smoothing, smooth};
use hearth_planning::space::{JointSpace, Space};
use hearth_planning::trajectory::{Limits, Trajectory};
use hearth_planning::validity::Attached;
use hearth_planning::{
    BiRrt, Budget, Goal, MotionValidator, Path, PlanError, PlanRequest, Planner, RobotValidity, StateValidator,
};
use hearth_sim::world::{BodyId, ContactRef, JointCommand, ModelHandle, World};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, RngExt};

use crate::error::{SkillError, SkillResult, require_positive};
use crate::execution::Execution;

/// How [`Arm::plan`] turns the smoothed (acceleration-bounded) motion into the jerk-limited
/// one it executes. Either way the result is kept only if it is collision-free at a tenth of
/// the planning resolution; otherwise the smoothed motion is executed
/// ([`MotionReport::jerk_limited`] tells which).
///
/// On the MotionBenchMaker bookshelf motions (`hearth bench plan --jerk`; `docs/benchmarks.md`,
/// "Jerk-limited motions"), the moving average took 0.07 ms per Fetch motion, lasted 1 %
/// longer than the smoothed motion and passed the check for 134 of 139; Ruckig's waypoint
/// pass took 0.9 s and passed for 92 of 140.
///
/// ```
/// use hearth_skills::arm::{ArmSettings, JerkPass};
/// assert_eq!(ArmSettings::fetch().jerk, JerkPass::Average);
/// let ruckig = ArmSettings { jerk: JerkPass::Waypoints { max: Some(16), sweeps: 1 }, ..ArmSettings::fetch() };
/// assert_ne!(ruckig, ArmSettings::fetch());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JerkPass {
    /// The smoothed motion's moving average ([`Trajectory::with_jerk_limits`]): microseconds,
    /// a window of `w = 2 a / j` longer (0.06 s for the Fetch at the default velocity scale),
    /// within `a w² / 24` of the checked motion (2 × 10⁻⁴ rad).
    Average,
    /// Ruckig's waypoint solver through states of the smoothed motion every
    /// [`WAYPOINT_SPACING`] ([`Trajectory::jerk_limited_with`]): at most `max` of them, evenly spread (`None`: all),
    /// refined by `sweeps` sweeps of its local search. Each sweep costs about as much as the
    /// last (about 0.3 s for a Fetch motion of 69 waypoints); 0 takes milliseconds but gives a
    /// motion several times slower. It may cut corners between the waypoints.
    Waypoints {
        /// Most waypoints.
        max: Option<usize>,
        /// Sweeps of the local search ([`Trajectory::DEFAULT_REFINEMENT_SWEEPS`] by default).
        sweeps: usize,
    },
    /// None: the smoothed motion as it is.
    Off,
}

/// Joint-space spacing (rad) of the states of a smoothed motion that Ruckig's waypoint pass
/// ([`JerkPass::Waypoints`]) goes through, before any thinning to `max`.
///
/// ```
/// assert_eq!(hearth_skills::arm::WAYPOINT_SPACING, 0.2);
/// ```
pub const WAYPOINT_SPACING: f64 = 0.2;

/// Settings of an [`Arm`].
///
/// ```
/// let s = hearth_skills::arm::ArmSettings::fetch();
/// assert_eq!(s.chain, "arm_with_torso");
/// assert_eq!(s.tip, "gripper_link");
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ArmSettings {
    /// Name of the planned chain of the robot model.
    pub chain: String,
    /// The end-effector link (IK tip; what grasps and pushes).
    pub tip: String,
    /// Links whose contacts with what the robot stands on are expected (base, wheels).
    pub support_links: Vec<String>,
    /// Clearance kept from obstacles by planned motions, metres.
    pub margin: f32,
    /// Resolution of edge checks, radians (joint-space distance).
    pub resolution: f64,
    /// BiRRT iterations at most (the budget that keeps a seed's result reproducible).
    pub plan_iterations: u64,
    /// Wall-clock safety limit of one BiRRT run, seconds.
    pub plan_time: f64,
    /// Random shortcut attempts after planning.
    pub shortcut_attempts: usize,
    /// Fraction of the joint velocity and acceleration limits used by planned motions.
    pub velocity_scale: f64,
    /// Contact force (N) on a link that counts as a collision during a planned motion.
    pub contact_force: f64,
    /// Control steps to hold the goal after a motion.
    pub settle_steps: usize,
    /// IK restarts per call when sampling goal configurations.
    pub ik_attempts: usize,
    /// Largest final joint error (rad or m) accepted after a physics execution.
    pub tolerance: f64,
    /// Distance from the tip link's origin to the fingertips along its approach axis (+x),
    /// metres: where pushes touch.
    pub tool_reach: f64,
    /// How a smoothed motion is made jerk-limited before execution.
    pub jerk: JerkPass,
}

impl ArmSettings {
    /// Settings for the Fetch: `arm_with_torso` to `gripper_link`, base and wheels as support.
    ///
    /// ```
    /// use hearth_skills::kinematics::{Chain, RobotModel};
    /// let s = hearth_skills::ArmSettings::fetch();
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// assert_eq!(Chain::named(&fetch, &s.chain).unwrap().dof(), 8);
    /// assert!(s.support_links.iter().all(|l| fetch.link_index(l).is_ok()));
    /// ```
    pub fn fetch() -> Self {
        Self {
            chain: "arm_with_torso".into(),
            tip: "gripper_link".into(),
            support_links: vec!["base_link".into(), "l_wheel_link".into(), "r_wheel_link".into()],
            margin: 0.02,
            resolution: 0.02,
            plan_iterations: 20_000,
            plan_time: 5.0,
            shortcut_attempts: 100,
            velocity_scale: 0.6,
            contact_force: 5.0,
            settle_steps: 20,
            ik_attempts: 40,
            tolerance: 0.05,
            tool_reach: 0.036,
            jerk: JerkPass::Average,
        }
    }
}

/// Where a planned motion should take the end effector, in the world frame.
///
/// ```
/// use hearth_skills::arm::ArmTarget;
/// let t = ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0));
/// assert!(matches!(t, ArmTarget::Position(_)));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum ArmTarget {
    /// A full pose of the tip link.
    Pose(Isometry3<f64>),
    /// A position of the tip link's origin, any orientation.
    Position(Point3<f64>),
    /// A configuration of the chain.
    Joints(Vec<f64>),
}

/// An object held in the gripper: it moves with the tip and is checked like a link.
///
/// ```no_run
/// # fn f(arm: &hearth_skills::Arm) {
/// if let Some(held) = arm.held() {
///     println!("holding {} at {:?} in the gripper frame", held.name, held.offset);
/// }
/// # }
/// ```
#[derive(Clone)]
pub struct Held {
    /// The object's model.
    pub object: ModelHandle,
    /// Its name (for messages).
    pub name: String,
    /// Its bodies (ignored as obstacles while held).
    pub bodies: Vec<BodyId>,
    /// The object's root pose in the tip frame at the grasp.
    pub offset: Isometry3<f64>,
    /// Its collision shape.
    pub shape: SharedShape,
    /// The shape's pose in the tip frame.
    pub shape_offset: Isometry3<f64>,
    /// The object's orientation where it rests, taken once the fingers have closed on it and
    /// before the lift (the squeeze may tip it by a few degrees): "upright" for placing it.
    pub rest: UnitQuaternion<f64>,
}

impl Held {
    /// The held object's shape pose in the object's root frame (fixed, whatever the hold).
    ///
    /// ```no_run
    /// # fn f(h: &hearth_skills::arm::Held) {
    /// let shape_in_object = h.shape_in_object();
    /// assert!(shape_in_object.translation.vector.norm() < 1.0);
    /// # }
    /// ```
    pub fn shape_in_object(&self) -> Isometry3<f64> {
        self.offset.inverse() * self.shape_offset
    }
}

impl std::fmt::Debug for Held {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Held")
            .field("name", &self.name)
            .field("offset", &self.offset)
            .finish()
    }
}

/// What a planned motion took and gave.
///
/// ```
/// let r = hearth_skills::arm::MotionReport::default();
/// assert!(!r.executed);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MotionReport {
    /// IK, planning and smoothing time.
    pub planning_time: Duration,
    /// Joint-space length of the executed path (rad, metres for the torso).
    pub path_length: f64,
    /// Duration of the trajectory, seconds.
    pub duration: f64,
    /// Waypoints of the planner's path.
    pub waypoints: usize,
    /// Whether the jerk-limited trajectory ([`ArmSettings::jerk`]) was used (else the
    /// acceleration-bounded one: with [`JerkPass::Off`], or when the jerk-limited one was not
    /// collision-free).
    pub jerk_limited: bool,
    /// Whether the motion was executed (false for a dry run).
    pub executed: bool,
    /// Largest joint error at the end of execution (0 for kinematic execution).
    pub tracking_error: f64,
}

/// A planned motion, ready to execute.
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
/// use hearth_skills::arm::ArmTarget;
/// use rand::SeedableRng;
/// let target = ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0));
/// let plan = arm.plan(world, &target, &[], &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert!(plan.trajectory.duration() > 0.0 && !plan.report.executed);
/// arm.execute(world, &plan, hearth_skills::Execution::Physics).unwrap();
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct ArmPlan {
    /// The trajectory of the chain.
    pub trajectory: Trajectory,
    /// Its final configuration.
    pub goal: Vec<f64>,
    /// The tip pose it was planned to reach, for a [`ArmTarget::Pose`] target: physics
    /// execution ends with a short correcting move onto it.
    pub target: Option<Isometry3<f64>>,
    /// Timing and size.
    pub report: MotionReport,
}

/// A straight-line move of the end effector.
///
/// ```
/// use hearth_skills::arm::LinearMove;
/// let m = LinearMove::new(nalgebra::Vector3::new(0.0, 0.0, 1.0), 0.1);
/// assert_eq!(m.force_limit, 60.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct LinearMove {
    /// Direction in the world frame (normalised on use).
    pub direction: Vector3<f64>,
    /// Distance, metres.
    pub distance: f64,
    /// Cartesian speed, m/s.
    pub speed: f64,
    /// The move stops when the contact force on the arm (sum over its links, N) stays above
    /// this for two control steps.
    pub force_limit: f64,
    /// Length of one IK step, metres.
    pub step: f64,
    /// Bodies the move may go into (the pushed or grasped object); everything else is an
    /// obstacle for the straight-line path, which is cut short before the first collision.
    pub ignore: Vec<BodyId>,
    /// Whether the obstacles of the world are checked at all (else only self-collision).
    pub check_world: bool,
}

impl LinearMove {
    /// A move at 0.1 m/s with a 60 N force limit, 1 cm IK steps, checked against the world.
    ///
    /// ```
    /// use hearth_skills::arm::LinearMove;
    /// let lift = LinearMove::new(nalgebra::Vector3::z(), 0.15);
    /// assert_eq!((lift.distance, lift.speed, lift.step), (0.15, 0.1, 0.01));
    /// assert!(lift.check_world && lift.ignore.is_empty());
    /// ```
    pub fn new(direction: Vector3<f64>, distance: f64) -> Self {
        Self {
            direction,
            distance,
            speed: 0.1,
            force_limit: 60.0,
            step: 0.01,
            ignore: Vec::new(),
            check_world: true,
        }
    }
}

/// A move of the tip through world poses (e.g. along a door handle's arc).
///
/// ```
/// use hearth_skills::arm::PoseMove;
/// let m = PoseMove::new(vec![nalgebra::Isometry3::translation(0.6, 0.0, 0.9)]);
/// assert_eq!(m.force_limit, 60.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PoseMove {
    /// The tip poses, world frame, each a small step from the one before (the first a small
    /// step from where the tip is).
    pub poses: Vec<Isometry3<f64>>,
    /// Time spent on each step, seconds.
    pub step_time: f64,
    /// Force limit on the arm, N (as for [`LinearMove`]).
    pub force_limit: f64,
    /// Bodies the move may touch.
    pub ignore: Vec<BodyId>,
    /// Whether the world's obstacles are checked (else only self-collision).
    pub check_world: bool,
    /// A line in the tip frame (point, direction) the tip may turn about to stay reachable:
    /// the long axis of a pinched handle bar.
    pub free_axis: Option<(Point3<f64>, Vector3<f64>)>,
}

impl PoseMove {
    /// 0.1 s per step, 60 N, checked against the world.
    ///
    /// ```
    /// use hearth_skills::arm::PoseMove;
    /// use nalgebra::Isometry3;
    /// let arc: Vec<_> = (0..5).map(|i| Isometry3::translation(0.6, 0.01 * i as f64, 0.9)).collect();
    /// let m = PoseMove::new(arc);
    /// assert_eq!((m.poses.len(), m.step_time), (5, 0.1));
    /// assert!(m.check_world && m.free_axis.is_none());
    /// ```
    pub fn new(poses: Vec<Isometry3<f64>>) -> Self {
        Self {
            poses,
            step_time: 0.1,
            force_limit: 60.0,
            ignore: Vec::new(),
            check_world: true,
            free_axis: None,
        }
    }
}

/// How a [`PoseMove`] ended.
///
/// ```
/// assert_eq!(hearth_skills::arm::PoseReport::default().planned, 0);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseReport {
    /// Poses the IK path reaches (a prefix of the requested ones).
    pub planned: usize,
    /// Poses requested.
    pub requested: usize,
    /// Largest contact force on the arm seen (N).
    pub peak_force: f64,
    /// Whether the force limit stopped the move.
    pub stopped_by_force: bool,
    /// Simulated time taken, seconds.
    pub duration: f64,
}

/// How a straight-line move ended.
///
/// ```
/// let r = hearth_skills::arm::LinearReport::default();
/// assert_eq!(r.travelled, 0.0);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinearReport {
    /// Distance the IK path covers (less than asked where it was cut short), metres.
    pub planned: f64,
    /// Distance the tip travelled along the direction, metres.
    pub travelled: f64,
    /// Largest contact force on the arm seen (N).
    pub peak_force: f64,
    /// Whether the force limit stopped the move.
    pub stopped_by_force: bool,
    /// Simulated time taken, seconds.
    pub duration: f64,
}

/// Plans and executes motions of one robot's arm in a [`World`].
///
/// ```no_run
/// use hearth_skills::arm::{Arm, ArmSettings, ArmTarget};
/// use hearth_skills::Execution;
/// use hearth_sim::kinematics::RobotModel;
/// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
/// use rand::SeedableRng;
///
/// let mut world = World::new(WorldConfig::default())?;
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// let robot = world.spawn_model(&fetch, &nalgebra::Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())?;
/// world.tuck(robot)?;
/// let mut arm = Arm::new(&world, robot, ArmSettings::fetch())?;
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let report = arm.move_to(&mut world, &ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0)), Execution::Physics, &mut rng)?;
/// assert!(report.executed && report.duration > 0.0);
/// # Ok::<(), hearth_skills::SkillError>(())
/// ```
pub struct Arm {
    robot: ModelHandle,
    chain: Chain,
    tip: usize,
    matrix: SelfCollisionMatrix,
    space: JointSpace,
    limits: Limits,
    settings: ArmSettings,
    held: Option<Held>,
    /// Joint values (model variable, value) planning assumes instead of the measured ones.
    assume: Vec<(usize, f64)>,
}

impl std::fmt::Debug for Arm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Arm")
            .field("chain", &self.chain.joint_names())
            .field("settings", &self.settings)
            .field("held", &self.held)
            .finish()
    }
}

impl Arm {
    /// An arm helper for `robot`: resolves the chain and tip, computes the self-collision
    /// matrix (once; a few hundred milliseconds for the Fetch).
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for an unknown chain or tip or unusable settings;
    /// [`SkillError::World`] for an unknown robot.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// use hearth_skills::arm::{Arm, ArmSettings};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let locobot = RobotModel::builtin("locobot").unwrap();
    /// let robot = world.spawn_model(&locobot, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let settings = ArmSettings { chain: "arm".into(), support_links: vec![], ..ArmSettings::fetch() };
    /// let arm = Arm::new(&world, robot, settings.clone())?;
    /// assert_eq!(arm.chain().dof(), 5);
    /// let fine = ArmSettings { resolution: 1e-300, ..settings.clone() };
    /// assert!(Arm::new(&world, robot, fine).unwrap_err().to_string().contains("finer than"));
    /// let bad = ArmSettings { chain: "leg".into(), ..settings };
    /// assert_eq!(Arm::new(&world, robot, bad).unwrap_err().reason(), "bad_input");
    /// # Ok::<(), hearth_skills::SkillError>(())
    /// ```
    pub fn new(world: &World, robot: ModelHandle, settings: ArmSettings) -> SkillResult<Self> {
        let model = world.model(robot)?.clone();
        let chain = Chain::named(&model, &settings.chain)
            .map_err(|e| SkillError::BadInput(format!("chain `{}`: {e}", settings.chain)))?;
        let tip = model
            .link_index(&settings.tip)
            .map_err(|e| SkillError::BadInput(format!("tip `{}`: {e}", settings.tip)))?;
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(settings.resolution)
            || !positive(settings.plan_time)
            || !positive(settings.contact_force)
            || !positive(settings.tolerance)
            || !(0.0..=1.0).contains(&settings.velocity_scale)
            || settings.velocity_scale == 0.0
            || !(settings.margin.is_finite() && settings.margin >= 0.0)
            || settings.plan_iterations == 0
            || settings.ik_attempts == 0
        {
            return Err(SkillError::BadInput(format!("arm settings out of range: {settings:?}")));
        }
        let matrix = SelfCollisionMatrix::compute(
            &model,
            &SelfCollisionSettings {
                samples: 500,
                ..Default::default()
            },
        );
        let space = JointSpace::from_chain(&chain).map_err(|e| SkillError::BadInput(e.to_string()))?;
        // Motions are re-checked at a tenth of the resolution.
        let finest = finest_resolution(&space);
        if settings.resolution / 10.0 < finest {
            return Err(SkillError::BadInput(format!(
                "resolution {:e} is finer than chain `{}` allows: a tenth of it, the fine re-check, must be at least {finest:.3e}",
                settings.resolution, settings.chain
            )));
        }
        let limits = Limits::for_chain(&chain)
            .scaled(settings.velocity_scale, settings.velocity_scale)
            .map_err(|e| SkillError::BadInput(e.to_string()))?;
        Ok(Self {
            robot,
            chain,
            tip,
            matrix,
            space,
            limits,
            settings,
            held: None,
            assume: Vec::new(),
        })
    }

    /// The robot.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// let robot = arm.robot();
    /// assert!(world.model(robot).is_ok());
    /// # }
    /// ```
    pub fn robot(&self) -> ModelHandle {
        self.robot
    }

    /// The planned chain.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// assert_eq!(arm.chain().dof(), 8); // torso + 7 arm joints on the Fetch
    /// # }
    /// ```
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The settings.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// assert_eq!(arm.settings().tip, "gripper_link");
    /// # }
    /// ```
    pub fn settings(&self) -> &ArmSettings {
        &self.settings
    }

    /// The held object, if any.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// assert!(arm.held().is_none());
    /// # }
    /// ```
    pub fn held(&self) -> Option<&Held> {
        self.held.as_ref()
    }

    /// Sets (or clears) the held object; it is attached to the tip for planning.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// arm.set_held(None);
    /// assert!(arm.held().is_none());
    /// # }
    /// ```
    pub fn set_held(&mut self, held: Option<Held>) {
        self.held = held;
    }

    /// Joints outside the chain (e.g. fingers about to open) that planning should assume at
    /// the given values instead of where they are now; an empty list measures them all.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for an unknown joint or a value outside its limits.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// arm.assume_joints(&[("r_gripper_finger_joint", 0.05)]).unwrap();
    /// arm.assume_joints(&[]).unwrap();
    /// # }
    /// ```
    pub fn assume_joints(&mut self, joints: &[(&str, f64)]) -> SkillResult<()> {
        let model = self.chain.model();
        let mut assume = Vec::with_capacity(joints.len());
        for &(name, x) in joints {
            let v = model
                .variable_names()
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| SkillError::BadInput(format!("unknown joint `{name}`")))?;
            if !(model.lower()[v]..=model.upper()[v]).contains(&x) || self.chain.variables().contains(&v) {
                return Err(SkillError::BadInput(format!(
                    "cannot assume `{name}` at {x}: outside its limits or part of the chain"
                )));
            }
            assume.push((v, x));
        }
        self.assume = assume;
        Ok(())
    }

    /// The reference configuration planning uses: measured, with assumed joints replaced.
    fn reference(&self, world: &World) -> SkillResult<Vec<f64>> {
        let (mut q, _) = self.configuration(world)?;
        for &(v, x) in &self.assume {
            q[v] = x;
        }
        Ok(q)
    }

    /// The tip link's world pose now.
    ///
    /// # Errors
    /// [`SkillError::World`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// let tip = arm.tip_pose(world).unwrap();
    /// assert!(tip.translation.z > 0.0);
    /// # }
    /// ```
    pub fn tip_pose(&self, world: &World) -> SkillResult<Isometry3<f64>> {
        Ok(world.link_pose(self.robot, &self.settings.tip)?)
    }

    /// The full configuration now, clamped to the limits (gravity can press a joint a hair
    /// beyond its limit), and the chain's part of it with continuous joints wrapped into
    /// `(-π, π]`.
    ///
    /// # Errors
    /// [`SkillError::World`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// let (full, chain) = arm.configuration(world).unwrap();
    /// assert_eq!(chain.len(), arm.chain().dof());
    /// assert!(full.len() > chain.len());
    /// # }
    /// ```
    pub fn configuration(&self, world: &World) -> SkillResult<(Vec<f64>, Vec<f64>)> {
        let model = self.chain.model();
        let mut q = world.joint_positions(self.robot)?;
        for (v, x) in q.iter_mut().enumerate() {
            *x = x.clamp(model.lower()[v], model.upper()[v]);
        }
        let mut c = vec![0.0; self.chain.dof()];
        self.chain.gather(&q, &mut c);
        for (x, &continuous) in c.iter_mut().zip(self.chain.continuous()) {
            if continuous {
                *x = hearth_kinematics::wrap_angle(*x);
            }
        }
        Ok((q, c))
    }

    /// What the robot's support links stand on (and the ground): never obstacles.
    ///
    /// # Errors
    /// [`SkillError::World`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// let under = arm.support_bodies(world).unwrap();
    /// assert!(under.contains(&world.ground().unwrap()));
    /// # }
    /// ```
    pub fn support_bodies(&self, world: &World) -> SkillResult<Vec<BodyId>> {
        let mut under: Vec<BodyId> = world
            .contacts(self.robot)?
            .into_iter()
            .filter(|c| self.settings.support_links.contains(&c.link))
            .map(|c| c.other)
            .collect();
        under.extend(world.ground());
        under.sort_by_key(|b| b.handle().into_raw_parts());
        under.dedup();
        Ok(under)
    }

    /// A validity checker of the chain against the live world now: the robot's own bodies,
    /// what it stands on, the held object and `ignore` excluded, `margin` of clearance, the
    /// held object attached.
    ///
    /// # Errors
    /// [`SkillError::World`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::planning::StateValidator;
    /// let mut v = arm.validity(world, &[], 0.01).unwrap();
    /// let (_, q) = arm.configuration(world).unwrap();
    /// assert!(v.is_valid(&q));
    /// # }
    /// ```
    pub fn validity(&self, world: &World, ignore: &[BodyId], margin: f32) -> SkillResult<RobotValidity> {
        let mut skip = self.support_bodies(world)?;
        skip.extend_from_slice(ignore);
        if let Some(h) = &self.held {
            skip.extend_from_slice(&h.bodies);
        }
        let view = world
            .obstacles_view(&[self.robot])?
            .excluding_bodies(&skip)
            .with_margin(margin);
        // A static copy of the view answers the same, faster (see `WorldObstacles::to_scene`).
        self.checker(world, Arc::new(view.to_scene()))
    }

    fn checker(
        &self,
        world: &World,
        obstacles: Arc<dyn hearth_planning::obstacles::Obstacles>,
    ) -> SkillResult<RobotValidity> {
        let q = self.reference(world)?;
        let mut v = RobotValidity::new(self.chain.clone(), self.matrix.clone(), obstacles);
        v.set_reference(&q)?;
        v.set_base(world.base_pose(self.robot)?);
        if let Some(h) = &self.held {
            v.attach(Attached {
                name: h.name.clone(),
                link: self.tip,
                offset: h.shape_offset,
                shape: h.shape.clone(),
            })?;
        }
        Ok(v)
    }

    /// An IK solver for the tip with reproducible settings (no wall-clock limit).
    fn ik(&self, world: &World, attempts: usize) -> SkillResult<IkSolver> {
        let q = self.reference(world)?;
        let settings = IkSettings {
            time_limit: None,
            max_attempts: attempts.max(1),
            ..IkSettings::default()
        };
        let tip = &self.chain.model().links()[self.tip].name;
        let mut ik = IkSolver::new(self.chain.clone(), tip, settings)?;
        ik.set_reference(&q)?;
        Ok(ik)
    }

    /// Goal configurations for `target`: distinct collision-free IK solutions (or the given
    /// joints, checked).
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a malformed target; [`SkillError::IkFailed`] when no
    /// collision-free solution is found; [`SkillError::Unreachable`] for joints in collision.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::ArmTarget;
    /// use rand::SeedableRng;
    /// let mut v = arm.validity(world, &[], 0.01).unwrap();
    /// let target = ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0));
    /// let goals = arm.goal_configurations(world, &target, &mut v, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
    /// assert!(!goals.is_empty());
    /// # }
    /// ```
    pub fn goal_configurations<R: Rng + ?Sized>(
        &self,
        world: &World,
        target: &ArmTarget,
        validity: &mut RobotValidity,
        rng: &mut R,
    ) -> SkillResult<Vec<Vec<f64>>> {
        let (_, start) = self.configuration(world)?;
        let base = world.base_pose(self.robot)?;
        let ik_target = match target {
            ArmTarget::Joints(q) => {
                self.chain
                    .check(q)
                    .map_err(|e| SkillError::BadInput(format!("goal joints: {e}")))?;
                if !validity.is_valid(q) {
                    let why = validity.explain(q).map(|c| c.to_string()).unwrap_or_default();
                    return Err(SkillError::Unreachable(format!("goal joints in collision: {why}")));
                }
                return Ok(vec![q.clone()]);
            }
            ArmTarget::Pose(p) => {
                check_finite_pose(p)?;
                IkTarget::Pose(base.inverse() * p)
            }
            ArmTarget::Position(p) => {
                if !p.coords.iter().all(|x| x.is_finite()) {
                    return Err(SkillError::BadInput(format!("goal position {p:?} is not finite")));
                }
                IkTarget::Position(base.inverse() * p)
            }
        };
        let mut ik = self.ik(world, self.settings.ik_attempts)?;
        let goal = PoseGoal {
            target: ik_target,
            solutions: 4,
            max_calls: 8,
            min_separation: 0.1,
        };
        match goal.sample(&mut ik, validity, &start, rng) {
            Ok(g) => Ok(g.states().to_vec()),
            Err(PlanError::BadInput(m)) => Err(SkillError::BadInput(m)),
            Err(e @ PlanError::NoGoalConfiguration { .. }) => Err(SkillError::IkFailed(e.to_string())),
            Err(e) => Err(e.into()),
        }
    }

    /// Plans a motion to `target` without executing it (a dry run): IK goals, BiRRT, parabolic
    /// shortcutting, jerk-limited timing. `ignore` lists bodies the motion may touch. Motions
    /// keep `margin` from obstacles, unless the arm starts closer than that (then none).
    ///
    /// # Errors
    /// [`SkillError::IkFailed`], [`SkillError::PlanningFailed`] (e.g. the start in collision,
    /// naming the contact), [`SkillError::PlanningTimeout`], [`SkillError::BadInput`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::ArmTarget;
    /// use rand::SeedableRng;
    /// let target = ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0));
    /// let plan = arm.plan(world, &target, &[], &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
    /// assert!(plan.report.path_length > 0.0);
    /// # }
    /// ```
    pub fn plan<R: Rng + ?Sized>(
        &self,
        world: &World,
        target: &ArmTarget,
        ignore: &[BodyId],
        rng: &mut R,
    ) -> SkillResult<ArmPlan> {
        let t0 = Instant::now();
        let mut validity = self.validity(world, ignore, self.settings.margin)?;
        let (_, start) = self.configuration(world)?;
        if !validity.is_valid(&start) {
            // Closer than the margin to something (after a contact-rich move): plan without
            // the margin rather than not at all.
            validity = self.validity(world, ignore, 0.0)?;
        }
        // Touching something (pressed against a wall by a pull, say): back off to the nearest
        // free configuration close by first, and plan from there. None close by: the planner
        // refuses the start, naming the contact.
        let escape = if validity.is_valid(&start) {
            None
        } else {
            escape_from(&self.space, &mut validity, &start, rng)
        };
        let from = escape.clone().unwrap_or_else(|| start.clone());
        let goals = self.goal_configurations(world, target, &mut validity, rng)?;
        let mut motion = MotionValidator::new(self.space.clone(), self.settings.resolution);
        let request = PlanRequest::new(from.clone(), Goal::AnyOf(goals));
        let budget = Budget::iterations(self.settings.plan_iterations).with_time(self.settings.plan_time);
        let solution = BiRrt::default()
            .plan(&mut motion, &mut validity, &request, &budget, rng)
            .map_err(|e| SkillError::from(e.explain_with(&request, |q| validity.explain(q).map(|c| c.to_string()))))?;
        let smoothed = smooth(
            Smoothing::Parabolic,
            &mut motion,
            &mut validity,
            &solution.path,
            &self.limits,
            &ShortcutSettings {
                attempts: self.settings.shortcut_attempts,
                time_limit: None,
                fine_resolution: Some(self.settings.resolution / 10.0),
                verify_resolution: Some(self.settings.resolution / 10.0),
            },
            Duration::from_secs(1),
            rng,
        )?;
        let goal = smoothed.path.states.last().cloned().unwrap_or_else(|| from.clone());
        // The jerk-limited motion, kept only if it stays collision-free.
        let jerk = match self.settings.jerk {
            JerkPass::Average => Some(smoothed.trajectory.with_jerk_limits(&self.limits)),
            JerkPass::Waypoints { max, sweeps } => Some(
                smoothed
                    .trajectory
                    .to_path(&self.space, WAYPOINT_SPACING)
                    .and_then(|mut waypoints| {
                        if let Some(max) = max {
                            thin_waypoints(&mut waypoints.states, max);
                        }
                        Trajectory::jerk_limited_with(&self.space, &waypoints, &self.limits, sweeps)
                    }),
            ),
            JerkPass::Off => None,
        };
        let (trajectory, jerk_limited) = match jerk {
            Some(Ok(j))
                if j.check(&self.space, &mut validity, self.settings.resolution / 10.0)
                    .is_ok() =>
            {
                (j, true)
            }
            _ => (smoothed.trajectory, false),
        };
        let trajectory = match escape {
            Some(free) => {
                let leg = Path {
                    states: vec![start, free],
                };
                Trajectory::rest_to_rest(&self.space, &leg, &self.limits)
                    .and_then(|lead| lead.then(trajectory))
                    .map_err(|e| SkillError::PlanningFailed(format!("backing off the contact: {e}")))?
            }
            None => trajectory,
        };
        let path_length = trajectory
            .length(&self.space, self.settings.resolution)
            .map_err(|e| SkillError::BadInput(format!("arm settings: {e}")))?;
        Ok(ArmPlan {
            report: MotionReport {
                planning_time: t0.elapsed(),
                path_length,
                duration: trajectory.duration(),
                waypoints: solution.path.states.len(),
                jerk_limited,
                executed: false,
                tracking_error: 0.0,
            },
            trajectory,
            goal,
            target: match target {
                ArmTarget::Pose(p) => Some(*p),
                _ => None,
            },
        })
    }

    /// Plans and executes a motion to `target`.
    ///
    /// # Errors
    /// As [`Arm::plan`] and [`Arm::execute`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::ArmTarget;
    /// use rand::SeedableRng;
    /// let target = ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0));
    /// let r = arm.move_to(world, &target, hearth_skills::Execution::Kinematic, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
    /// assert!(r.executed);
    /// # }
    /// ```
    pub fn move_to<R: Rng + ?Sized>(
        &mut self,
        world: &mut World,
        target: &ArmTarget,
        execution: Execution,
        rng: &mut R,
    ) -> SkillResult<MotionReport> {
        let plan = self.plan(world, target, &[], rng)?;
        self.execute(world, &plan, execution)
    }

    /// Executes a planned motion. In physics, the trajectory is sampled at the control rate as
    /// position targets of the chain's joints (other joints keep their commands), then the goal
    /// is held for `settle_steps`; kinematically, the joints are set along it.
    ///
    /// # Errors
    /// [`SkillError::Collision`] naming the link and body when a contact pushes harder than
    /// `contact_force` (the arm stops where it is); [`SkillError::Slipped`] when a held object
    /// leaves the gripper; [`SkillError::NotFinished`] when the final joint error exceeds the
    /// tolerance.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::ArmTarget;
    /// use rand::SeedableRng;
    /// let target = ArmTarget::Position(nalgebra::Point3::new(0.6, 0.0, 1.0));
    /// let plan = arm.plan(world, &target, &[], &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
    /// let r = arm.execute(world, &plan, hearth_skills::Execution::Physics).unwrap();
    /// assert!(r.tracking_error < 0.05);
    /// # }
    /// ```
    pub fn execute(&mut self, world: &mut World, plan: &ArmPlan, execution: Execution) -> SkillResult<MotionReport> {
        let mut report = plan.report.clone();
        let dt = world.config().control_dt();
        let duration = plan.trajectory.duration();
        let motion_steps = (duration / dt).ceil() as usize;
        let mut q = vec![0.0; self.chain.dof()];
        plan.trajectory.sample(0.0, &mut q, None);
        let turns = self.turns(world, &q)?;
        match execution {
            Execution::Kinematic => {
                let (mut full, _) = self.configuration(world)?;
                let commands = world.joint_commands(self.robot)?.to_vec();
                for k in 1..=motion_steps {
                    plan.trajectory.sample((k as f64 * dt).min(duration), &mut q, None);
                    self.unwrap_to(&mut q, &turns);
                    self.chain.scatter(&q, &mut full);
                    world.reset_configuration(self.robot, &full)?;
                    self.carry_held(world)?;
                }
                self.restore_commands(world, &commands)?;
                for _ in 0..self.settings.settle_steps {
                    world.step();
                }
                self.check_held(world)?;
            }
            Execution::Physics => {
                let support = self.support_bodies(world)?;
                // What the arm already presses on (a pull can leave the elbow against a wall,
                // and the plan then starts by backing off) is no collision of this motion:
                // allowed until the arm has left it, unless it pushes much harder.
                let mut pressed = self.pressing(world, &support)?;
                for k in 1..=motion_steps + self.settings.settle_steps {
                    plan.trajectory.sample((k as f64 * dt).min(duration), &mut q, None);
                    self.unwrap_to(&mut q, &turns);
                    self.command(world, &q)?;
                    world.step();
                    if !pressed.is_empty() {
                        let still = self.pressing(world, &support)?;
                        pressed.retain(|(b, _)| still.iter().any(|(s, _)| s == b));
                    }
                    if let Some(hit) = self.unexpected_contact(world, &support, &pressed)? {
                        self.hold_here(world)?;
                        return Err(SkillError::Collision(format!("{hit} at t = {:.2} s", world.time())));
                    }
                    self.check_held(world)?;
                }
                let reached = self.measured(world)?;
                let mut goal = vec![0.0; self.chain.dof()];
                plan.trajectory.sample(duration, &mut goal, None);
                self.unwrap_to(&mut goal, &turns);
                report.tracking_error = reached
                    .iter()
                    .zip(&goal)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                if report.tracking_error > self.settings.tolerance {
                    return Err(SkillError::NotFinished(format!(
                        "largest joint error {:.3} after the motion (tolerance {:.3})",
                        report.tracking_error, self.settings.tolerance
                    )));
                }
                if let Some(target) = &plan.target {
                    self.correct_onto(world, target)?;
                }
            }
        }
        report.executed = true;
        Ok(report)
    }

    /// Closes the gap physics leaves between the tip and a planned pose: the base tilts a
    /// little on its wheels and casters as the arm's weight moves out, and loaded joints sag,
    /// so a plan that ends exactly on the pose in the model ends millimetres to centimetres off
    /// it in the world. Straight IK steps of at most 5 mm from the measured tip to `target`,
    /// solved against the measured base pose (tilt included), run twice at most. A gap that
    /// cannot be closed without a collision is left as it is.
    fn correct_onto(&mut self, world: &mut World, target: &Isometry3<f64>) -> SkillResult<()> {
        const STEP: f64 = 0.005;
        for _ in 0..2 {
            let tip = world.base_pose(self.robot)? * self.start_tool_pose(world)?;
            let gap = (target.translation.vector - tip.translation.vector).norm();
            if gap < 0.002 && tip.rotation.angle_to(&target.rotation) < 0.01 {
                break;
            }
            let steps = (gap / STEP).ceil().max(1.0) as usize;
            let targets: Vec<Isometry3<f64>> = (1..=steps)
                .map(|i| {
                    let s = i as f64 / steps as f64;
                    Isometry3::from_parts(
                        Translation3::from(tip.translation.vector.lerp(&target.translation.vector, s)),
                        tip.rotation.slerp(&target.rotation, s),
                    )
                })
                .collect();
            match self.ik_path(world, &targets, &[], true, None) {
                Ok(states) if states.len() >= 2 => {
                    self.run_states(world, &states, 0.1, 30.0, Execution::Physics)?;
                }
                _ => break,
            }
        }
        Ok(())
    }

    /// Clamps bounded joints into their limits and shifts continuous joints by whole turns so
    /// that the trajectory's start lands on the measured start `from` (a wrapped angle sent as
    /// a target would spin the joint the long way round).
    fn unwrap_to(&self, q: &mut [f64], turns: &[f64]) {
        let (lo, hi) = (self.chain.lower(), self.chain.upper());
        for (i, x) in q.iter_mut().enumerate() {
            if self.chain.continuous()[i] {
                *x += turns[i];
            } else {
                *x = x.clamp(lo[i], hi[i]);
            }
        }
    }

    /// The chain's joint positions as measured (continuous joints not wrapped).
    fn measured(&self, world: &World) -> SkillResult<Vec<f64>> {
        let mut c = vec![0.0; self.chain.dof()];
        self.chain.gather(&world.joint_positions(self.robot)?, &mut c);
        Ok(c)
    }

    /// Whole turns between a trajectory start and the measured chain configuration.
    fn turns(&self, world: &World, start: &[f64]) -> SkillResult<Vec<f64>> {
        let measured = self.measured(world)?;
        Ok(measured
            .iter()
            .zip(start)
            .zip(self.chain.continuous())
            .map(|((m, s), &c)| {
                if c {
                    ((m - s) / std::f64::consts::TAU).round() * std::f64::consts::TAU
                } else {
                    0.0
                }
            })
            .collect())
    }

    /// Position targets for the chain's joints.
    fn command(&self, world: &mut World, q: &[f64]) -> SkillResult<()> {
        let model = self.chain.model();
        for (&v, &x) in self.chain.variables().iter().zip(q) {
            world.set_joint_command(
                self.robot,
                &model.variable_names()[v],
                JointCommand::Position { target: x },
            )?;
        }
        Ok(())
    }

    /// Holds the chain where it is now.
    fn hold_here(&self, world: &mut World) -> SkillResult<()> {
        let mut q = self.measured(world)?;
        let zero = vec![0.0; q.len()];
        self.unwrap_to(&mut q, &zero);
        self.command(world, &q)
    }

    /// Re-installs the commands of joints outside the chain (a kinematic reset overwrote them).
    fn restore_commands(&self, world: &mut World, commands: &[JointCommand]) -> SkillResult<()> {
        let model = self.chain.model();
        for (v, &c) in commands.iter().enumerate() {
            if self.chain.variables().contains(&v) {
                continue;
            }
            world.set_joint_command(self.robot, &model.variable_names()[v], c)?;
        }
        Ok(())
    }

    /// Moves a held object with the tip (kinematic execution).
    fn carry_held(&self, world: &mut World) -> SkillResult<()> {
        if let Some(h) = &self.held {
            let pose = self.tip_pose(world)? * h.offset;
            world.place(h.object, &pose)?;
        }
        Ok(())
    }

    /// Fails with `Slipped` when the held object has left the fingers: more than 3 cm from
    /// where the grasp put it with fewer than two finger links touching it, or more than 8 cm
    /// away at all (a pinched object may swing about the finger axis and stay held).
    fn check_held(&self, world: &World) -> SkillResult<()> {
        if let Some(h) = &self.held {
            let expected = self.tip_pose(world)? * h.offset;
            let actual = world.base_pose(h.object)?;
            let off = (expected.translation.vector - actual.translation.vector).norm();
            if off <= 0.03 {
                return Ok(());
            }
            let mut links: Vec<String> = world
                .contacts(self.robot)?
                .into_iter()
                .filter(|c| h.bodies.contains(&c.other) && c.link.contains("finger"))
                .map(|c| c.link)
                .collect();
            links.sort_unstable();
            links.dedup();
            let fingers = links.len();
            if fingers < 2 || off > 0.08 {
                return Err(SkillError::Slipped(format!(
                    "`{}` is {off:.3} m from where the gripper holds it, {fingers} finger(s) on it",
                    h.name
                )));
            }
        }
        Ok(())
    }

    /// The first contact that pushes harder than `contact_force` on a link, other than the
    /// support links on what they stand on and the held object; a body in `allowed` may push
    /// up to the force given with it.
    fn unexpected_contact(
        &self,
        world: &World,
        support: &[BodyId],
        allowed: &[(BodyId, f64)],
    ) -> SkillResult<Option<String>> {
        let mut hit = None;
        world.for_each_contact(self.robot, |c| {
            if hit.is_some() || !self.counts(c, support) {
                return;
            }
            let limit = allowed
                .iter()
                .find(|(b, _)| *b == c.other)
                .map_or(self.settings.contact_force, |&(_, f)| f);
            if c.force.norm() > limit {
                hit = Some(format!(
                    "link `{}` touched `{}` ({:.1} N)",
                    c.link,
                    c.other_name,
                    c.force.norm()
                ));
            }
        })?;
        Ok(hit)
    }

    /// Bodies pushing on the robot harder than `contact_force` now (support contacts and the
    /// held object excluded), each with the force it may reach before it counts as a
    /// collision: twice its largest contact force now plus `contact_force`.
    fn pressing(&self, world: &World, support: &[BodyId]) -> SkillResult<Vec<(BodyId, f64)>> {
        let mut out: Vec<(BodyId, f64)> = Vec::new();
        world.for_each_contact(self.robot, |c| {
            let f = c.force.norm();
            if !self.counts(c, support) || f <= self.settings.contact_force {
                return;
            }
            let limit = 2.0 * f + self.settings.contact_force;
            match out.iter_mut().find(|(b, _)| *b == c.other) {
                Some((_, l)) => *l = l.max(limit),
                None => out.push((c.other, limit)),
            }
        })?;
        Ok(out)
    }

    /// The sum of contact forces on the arm's links (support contacts excluded), N.
    fn arm_force(&self, world: &World, support: &[BodyId]) -> SkillResult<f64> {
        let mut sum = 0.0;
        world.for_each_contact(self.robot, |c| {
            if self.counts(c, support) {
                sum += c.force.norm();
            }
        })?;
        Ok(sum)
    }

    /// Whether a contact of the robot counts as touching something: not a support link on
    /// one of the `support` bodies, not the held object.
    fn counts(&self, c: &ContactRef<'_>, support: &[BodyId]) -> bool {
        let on_support = support.contains(&c.other) && self.settings.support_links.iter().any(|l| *l == c.link);
        let held = self.held.as_ref().is_some_and(|h| h.bodies.contains(&c.other));
        !on_support && !held
    }

    /// The chain configurations of a straight-line move of the tip from where it is now, one
    /// per IK step (the first is the current configuration), cut short before the first step
    /// whose solution jumps, fails or collides; and the distance covered.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a zero or non-finite direction or distance.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::LinearMove;
    /// let (states, covered) = arm.linear_path(world, &LinearMove::new(nalgebra::Vector3::z(), 0.1)).unwrap();
    /// assert!(states.len() >= 1 && covered <= 0.1);
    /// # }
    /// ```
    pub fn linear_path(&self, world: &World, m: &LinearMove) -> SkillResult<(Vec<Vec<f64>>, f64)> {
        let n = m.direction.norm();
        if !n.is_finite() || n < 1e-9 {
            return Err(SkillError::BadInput(format!(
                "linear move direction {:?} has no length",
                m.direction
            )));
        }
        require_positive(
            "linear move ",
            &[
                ("distance", m.distance),
                ("speed", m.speed),
                ("step", m.step),
                ("force limit", m.force_limit),
            ],
        )?;
        let base = world.base_pose(self.robot)?;
        let start_pose = base * self.start_tool_pose(world)?;
        let dir = m.direction / n;
        let steps = (m.distance / m.step).ceil().max(1.0) as usize;
        let targets: Vec<Isometry3<f64>> = (1..=steps)
            .map(|i| {
                let s = m.distance * i as f64 / steps as f64;
                Isometry3::from_parts(
                    Translation3::from(start_pose.translation.vector + dir * s),
                    start_pose.rotation,
                )
            })
            .collect();
        let states = self.ik_path(world, &targets, &m.ignore, m.check_world, None)?;
        let covered = m.distance * (states.len() - 1) as f64 / steps as f64;
        Ok((states, covered))
    }

    /// The tool pose of the current configuration in the robot's root frame.
    fn start_tool_pose(&self, world: &World) -> SkillResult<Isometry3<f64>> {
        let mut ik = self.ik(world, 1)?;
        let (_, start) = self.configuration(world)?;
        Ok(ik.tool_pose(&start)?)
    }

    /// Chain configurations through world tip poses by IK steps from the current
    /// configuration (the first state), cut short before the first step whose solution fails,
    /// jumps (> 0.2 rad in a joint) or collides. With a free axis (a point and direction in the
    /// tip frame), each step may also turn the tip about it.
    fn ik_path(
        &self,
        world: &World,
        targets: &[Isometry3<f64>],
        ignore: &[BodyId],
        check_world: bool,
        free_axis: Option<&(Point3<f64>, Vector3<f64>)>,
    ) -> SkillResult<Vec<Vec<f64>>> {
        let base = world.base_pose(self.robot)?;
        let mut validity = if check_world {
            self.validity(world, ignore, 0.0)?
        } else {
            self.checker(world, Arc::new(ParryScene::new(Vec::new())))?
        };
        // One attempt from the previous step (a restart would jump), patient enough to creep
        // along a joint limit.
        let mut ik = self.ik(world, 1)?;
        ik.set_settings(IkSettings {
            max_iterations: 150,
            stall_iterations: 150,
            position_tolerance: 0.002,
            orientation_tolerance: 0.02,
            ..ik.settings().clone()
        });
        let (_, start) = self.configuration(world)?;
        let mut states = vec![start];
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0);
        // Turns about the free axis tried at each step, relative to the last one taken.
        const WIGGLE: [f64; 7] = [0.0, 0.1, -0.1, 0.25, -0.25, 0.5, -0.5];
        let tries: &[f64] = if free_axis.is_some() { &WIGGLE } else { &WIGGLE[..1] };
        let mut turned = 0.0;
        'steps: for target in targets {
            check_finite_pose(target)?;
            let prev = states.last().cloned().unwrap_or_default();
            for &d in tries {
                let turn = match free_axis {
                    Some((p, axis)) => {
                        let r = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(*axis), turned + d);
                        Isometry3::from_parts(Translation3::from(p.coords), r)
                            * Isometry3::from_parts(Translation3::from(-p.coords), UnitQuaternion::identity())
                    }
                    None => Isometry3::identity(),
                };
                let goal = IkTarget::Pose(base.inverse() * target * turn);
                let solved = ik.solve_with(&goal, &prev, &mut rng, |q| {
                    q.iter().zip(&prev).all(|(a, b)| (a - b).abs() < 0.2) && validity.is_valid(q)
                });
                if let Ok(sol) = solved {
                    states.push(sol.q);
                    turned += d;
                    continue 'steps;
                }
            }
            break;
        }
        Ok(states)
    }

    /// Moves the tip through world poses (small steps apart; a door handle's arc, a drawer's
    /// pull) spending `m.step_time` on each, stopping early where the IK path ends or the
    /// contact force on the arm passes `m.force_limit`.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a malformed move; [`SkillError::Unreachable`] when not even
    /// the first step is possible.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::PoseMove;
    /// let tip = arm.tip_pose(world).unwrap();
    /// let poses = (1..=10).map(|k| nalgebra::Isometry3::translation(0.0, 0.0, 0.01 * k as f64) * tip).collect();
    /// let r = arm.move_through(world, &PoseMove::new(poses), hearth_skills::Execution::Physics).unwrap();
    /// assert!(r.planned <= r.requested);
    /// # }
    /// ```
    pub fn move_through(&mut self, world: &mut World, m: &PoseMove, execution: Execution) -> SkillResult<PoseReport> {
        if m.poses.is_empty()
            || !m.step_time.is_finite()
            || m.step_time <= 0.0
            || !m.force_limit.is_finite()
            || m.force_limit <= 0.0
        {
            return Err(SkillError::BadInput(format!(
                "pose move of {} poses, {} s per step, force limit {} is unusable",
                m.poses.len(),
                m.step_time,
                m.force_limit
            )));
        }
        let states = self.ik_path(world, &m.poses, &m.ignore, m.check_world, m.free_axis.as_ref())?;
        if states.len() < 2 {
            return Err(SkillError::Unreachable(
                "not even the first pose of the move is reachable".into(),
            ));
        }
        let (peak_force, stopped_by_force, duration) =
            self.run_states(world, &states, m.step_time, m.force_limit, execution)?;
        Ok(PoseReport {
            planned: states.len() - 1,
            requested: m.poses.len(),
            peak_force,
            stopped_by_force,
            duration,
        })
    }

    /// Executes chain states `segment` seconds apart (linear in between); returns the peak
    /// arm force, whether the force limit stopped it, and the simulated time taken.
    fn run_states(
        &mut self,
        world: &mut World,
        states: &[Vec<f64>],
        segment: f64,
        force_limit: f64,
        execution: Execution,
    ) -> SkillResult<(f64, bool, f64)> {
        let dt = world.config().control_dt();
        let duration = segment * (states.len() - 1) as f64;
        let steps = (duration / dt).ceil() as usize;
        let support = self.support_bodies(world)?;
        let commands = world.joint_commands(self.robot)?.to_vec();
        let (mut full, _) = self.configuration(world)?;
        let mut q = vec![0.0; self.chain.dof()];
        let turns = self.turns(world, &states[0])?;
        let t0 = world.time();
        let (mut over, mut peak, mut stopped) = (0, 0.0_f64, false);
        for k in 1..=steps + self.settings.settle_steps / 2 {
            let t = (k as f64 * dt).min(duration) / segment;
            let i = (t.floor() as usize).min(states.len() - 2);
            let f = (t - i as f64).clamp(0.0, 1.0);
            for (j, x) in q.iter_mut().enumerate() {
                *x = states[i][j] + f * (states[i + 1][j] - states[i][j]);
            }
            self.unwrap_to(&mut q, &turns);
            match execution {
                Execution::Physics => self.command(world, &q)?,
                Execution::Kinematic => {
                    self.chain.scatter(&q, &mut full);
                    world.reset_configuration(self.robot, &full)?;
                    self.restore_commands(world, &commands)?;
                    self.carry_held(world)?;
                }
            }
            world.step();
            let force = self.arm_force(world, &support)?;
            peak = peak.max(force);
            over = if force > force_limit { over + 1 } else { 0 };
            if over >= 2 {
                stopped = true;
                self.hold_here(world)?;
                break;
            }
        }
        Ok((peak, stopped, world.time() - t0))
    }

    /// Moves the tip along a straight line (orientation kept) at `m.speed`, stopping at the
    /// end of the IK path or when the contact force on the arm passes `m.force_limit`.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a malformed move; [`SkillError::Unreachable`] when not even
    /// the first IK step is possible.
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
    /// use hearth_skills::arm::LinearMove;
    /// let up = LinearMove::new(nalgebra::Vector3::z(), 0.1);
    /// let r = arm.move_linear(world, &up, hearth_skills::Execution::Physics).unwrap();
    /// assert!(r.travelled <= 0.11);
    /// # }
    /// ```
    pub fn move_linear(
        &mut self,
        world: &mut World,
        m: &LinearMove,
        execution: Execution,
    ) -> SkillResult<LinearReport> {
        let (states, planned) = self.linear_path(world, m)?;
        if states.len() < 2 {
            return Err(SkillError::Unreachable(format!(
                "no straight-line step of {:.3} m is possible along {:?}",
                m.step, m.direction
            )));
        }
        let start_tip = self.tip_pose(world)?.translation.vector;
        let dir = m.direction.normalize();
        let segment = planned / (states.len() - 1) as f64 / m.speed;
        let (peak_force, stopped_by_force, duration) =
            self.run_states(world, &states, segment, m.force_limit, execution)?;
        Ok(LinearReport {
            planned,
            travelled: (self.tip_pose(world)?.translation.vector - start_tip).dot(&dir),
            peak_force,
            stopped_by_force,
            duration,
        })
    }
}

/// Keeps at most `max` (at least 2) of `states`, evenly spread, always the first and the last.
fn thin_waypoints(states: &mut Vec<Vec<f64>>, max: usize) {
    let max = max.max(2);
    let n = states.len();
    if n <= max {
        return;
    }
    // Index of the k-th kept state, rounded: 0 first, n - 1 last, strictly increasing.
    let kept = |k: usize| (k * (n - 1) + (max - 1) / 2) / (max - 1);
    let mut k = 0;
    let mut i = 0;
    states.retain(|_| {
        let keep = k < max && kept(k) == i;
        k += usize::from(keep);
        i += 1;
        keep
    });
}

/// A tip orientation whose approach axis (+x) points along `approach` and whose +z is as close
/// to world up as possible (world +x when `approach` is vertical), turned by `roll` about the
/// approach axis.
///
/// ```
/// use nalgebra::Vector3;
/// let r = hearth_skills::arm::approach_rotation(&Vector3::new(0.0, 0.0, -2.0), 0.0).unwrap();
/// assert!((r * Vector3::x() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
/// assert!(hearth_skills::arm::approach_rotation(&Vector3::zeros(), 0.0).is_err());
/// ```
///
/// # Errors
/// [`SkillError::BadInput`] for a zero or non-finite direction.
pub fn approach_rotation(approach: &Vector3<f64>, roll: f64) -> SkillResult<UnitQuaternion<f64>> {
    let n = approach.norm();
    if !n.is_finite() || n < 1e-9 || !roll.is_finite() {
        return Err(SkillError::BadInput(format!(
            "approach direction {approach:?} (roll {roll}) is unusable"
        )));
    }
    let x = approach / n;
    let up = if x.z.abs() > 0.95 { Vector3::x() } else { Vector3::z() };
    let z = (up - x * up.dot(&x)).normalize();
    let y = z.cross(&x);
    let r = nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_columns(&[x, y, z]));
    Ok(UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_unchecked(x), roll)
        * UnitQuaternion::from_rotation_matrix(&r))
}

/// Largest joint-space step (rad) [`escape_from`] takes to get free of a contact.
const ESCAPE_RADII: [f64; 4] = [0.03, 0.06, 0.1, 0.15];
/// Samples per radius.
const ESCAPE_SAMPLES: usize = 40;

/// The free configuration nearest to `start` (which touches something) among random ones at
/// most 0.03, 0.06, 0.1 and 0.15 rad away per joint, whose straight way out is free from
/// halfway on (the first half may still graze what `start` touches); `None` if there is none.
fn escape_from<R: Rng + ?Sized>(
    space: &JointSpace,
    validity: &mut RobotValidity,
    start: &[f64],
    rng: &mut R,
) -> Option<Vec<f64>> {
    let mut q = vec![0.0; start.len()];
    let mut mid = vec![0.0; start.len()];
    for r in ESCAPE_RADII {
        let mut best: Option<(f64, Vec<f64>)> = None;
        for _ in 0..ESCAPE_SAMPLES {
            for (x, s) in q.iter_mut().zip(start) {
                *x = s + rng.random_range(-r..=r);
            }
            space.enforce_bounds(&mut q);
            let d = space.distance(start, &q);
            if best.as_ref().is_some_and(|(b, _)| *b <= d) || !validity.is_valid(&q) {
                continue;
            }
            let free_on = [0.5, 0.75].iter().all(|&t| {
                space.interpolate(start, &q, t, &mut mid);
                validity.is_valid(&mid)
            });
            if free_on {
                best = Some((d, q.clone()));
            }
        }
        if let Some((_, q)) = best {
            return Some(q);
        }
    }
    None
}

fn check_finite_pose(p: &Isometry3<f64>) -> SkillResult<()> {
    let finite = p.translation.vector.iter().all(|x| x.is_finite()) && p.rotation.coords.iter().all(|x| x.is_finite());
    if finite {
        Ok(())
    } else {
        Err(SkillError::BadInput(format!("goal pose {p:?} is not finite")))
    }
}

/// The path a plan's trajectory follows, sampled at `resolution` (for inspection);
/// [`SkillError::BadInput`] for a resolution that is not positive and finite.
///
/// ```no_run
/// # fn f(arm: &hearth_skills::arm::Arm, plan: &hearth_skills::arm::ArmPlan) -> Result<(), hearth_skills::SkillError> {
/// let path = hearth_skills::arm::plan_path(arm, plan, 0.05)?;
/// assert!(path.states.len() >= 2);
/// assert!(hearth_skills::arm::plan_path(arm, plan, 0.0).is_err());
/// # Ok(())
/// # }
/// ```
pub fn plan_path(arm: &Arm, plan: &ArmPlan, resolution: f64) -> Result<Path, SkillError> {
    plan.trajectory
        .to_path(&arm.space, resolution)
        .map_err(|e| SkillError::BadInput(format!("plan path: {e}")))
}

#[cfg(test)]
mod tests {
    use super::thin_waypoints;

    #[test]
    fn thinning_keeps_the_ends_and_spreads_the_rest() {
        let states: Vec<Vec<f64>> = (0..50).map(|i| vec![f64::from(i)]).collect();
        let mut thin = states.clone();
        thin_waypoints(&mut thin, 16);
        assert_eq!(thin.len(), 16);
        assert_eq!(thin[0], states[0]);
        assert_eq!(thin[15], states[49]);
        assert!(thin.windows(2).all(|w| w[1][0] > w[0][0] && w[1][0] - w[0][0] <= 4.0));
        let mut short = states[..10].to_vec();
        thin_waypoints(&mut short, 16);
        assert_eq!(short.len(), 10, "fewer than the cap are kept as they are");
        let mut two = states.clone();
        thin_waypoints(&mut two, 0);
        assert_eq!(two, vec![states[0].clone(), states[49].clone()]);
    }
}
