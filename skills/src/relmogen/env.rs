//! [`ReLMoGenEnv`]: an [`Env`] whose actions are subgoals for the base (navigate) or the arm
//! (push), executed by the skills.

use std::time::Instant;

use hearth_sim::env::{Env, Info, Obs, Space};
use hearth_sim::scene::SceneMaps;
use hearth_sim::sensors::{Backend, Camera, CameraConfig, CameraIntrinsics, RenderOptions};
use hearth_sim::world::ModelHandle;
use nalgebra::{Point3, Vector3};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

use super::action::{ActionSpec, PushDirection, Subgoal};
use super::config::{ReLMoGenConfig, ReLMoGenError, ReLMoGenResult, bad};
use crate::arm::{Arm, ArmSettings};
use crate::error::{SkillError, SkillResult};
use crate::navigate::{NavigateSettings, Navigator};
use crate::push::{PushSettings, push_at_point, surface_at_pixel};

/// Largest height of a point that counts as floor for a base subgoal at a pixel, m.
const FLOOR_HEIGHT: f64 = 0.05;

/// What a ReLMoGen step reports: the env's [`Info`] and what the planner did.
///
/// ```
/// let i = hearth_skills::relmogen::ReLMoGenInfo::default();
/// assert!(!i.planner_success && i.failure_reason.is_none());
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ReLMoGenInfo {
    /// The env's info of the scoring step.
    pub env: Info,
    /// `base`, `arm`, or empty after a reset.
    pub subgoal: &'static str,
    /// Whether the skill reached its subgoal (for a push: the point moved more than
    /// `push.min_motion`).
    pub planner_success: bool,
    /// [`SkillError::reason`] of a failed subgoal.
    pub failure_reason: Option<&'static str>,
    /// The failure's message.
    pub failure_message: Option<String>,
    /// Planning time, s: the arm's IK, planning and smoothing time of the approach; for the
    /// base (and for failed pushes) the wall-clock time of the whole skill call.
    pub planning_time: f64,
    /// Base: metres driven. Arm: joint-space length of the approach (rad; m for the torso).
    pub path_length: f64,
    /// How far the pushed point moved, m (0 for the base).
    pub moved: f64,
    /// The subgoal in the world: the base goal (x, y, yaw) or the pushed point (x, y, z);
    /// `None` when it could not be resolved (the pixel saw nothing usable).
    pub target: Option<[f64; 3]>,
    /// Wall-clock time of the skill call, s.
    pub skill_time: f64,
}

/// The result of [`ReLMoGenEnv::step`].
///
/// ```no_run
/// # fn f(step: hearth_skills::relmogen::ReLMoGenStep) {
/// if step.terminated || step.truncated {
///     println!("episode over: {:?}", step.info.env.ending);
/// }
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ReLMoGenStep {
    /// Observations after the subgoal.
    pub obs: Obs,
    /// The env's reward of the state, minus `failure_penalty` for a failed subgoal.
    pub reward: f64,
    /// Ended by the task.
    pub terminated: bool,
    /// Hit the step limit (one step per subgoal).
    pub truncated: bool,
    /// What the planner did.
    pub info: ReLMoGenInfo,
}

/// An [`Env`] (Fetch; `push_drawer`, `push_cabinet` or `interactive_nav`) driven by subgoals,
/// as in ReLMoGen (Xia et al., 2021): each action picks the base or the arm and a subgoal
/// ([`ActionSpec`] documents both action forms); the subgoal runs through
/// [`Navigator::navigate`] or [`push_at_point`], then [`Env::step`] with a zero action scores
/// the state it left (the potential reward is the change the subgoal made). A failed subgoal
/// costs `failure_penalty` and its [`SkillError::reason`] goes into the info.
///
/// ```no_run
/// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
/// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
/// let mut env = ReLMoGenEnv::new(config)?;
/// let (_obs, _info) = env.reset(3)?;
/// // Arm, push the pixel at the image centre straight ahead.
/// let step = env.step(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])?;
/// println!("{} {:?} {:.3}", step.reward, step.info.failure_reason, step.info.planning_time);
/// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
/// ```
pub struct ReLMoGenEnv {
    config: ReLMoGenConfig,
    env: Env,
    maps: SceneMaps,
    camera: Camera,
    arm: Arm,
    spec: ActionSpec,
    space: Space,
    navigator: Navigator,
    push: PushSettings,
    rng: Pcg64Mcg,
    zero: Vec<f32>,
    started: bool,
}

impl std::fmt::Debug for ReLMoGenEnv {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReLMoGenEnv")
            .field("env", &self.env)
            .field("spec", &self.spec)
            .finish_non_exhaustive()
    }
}

impl ReLMoGenEnv {
    /// Builds the env, the planner's camera and the arm.
    ///
    /// # Errors
    /// Config errors naming the key; errors of [`Env::new`], the camera or the arm.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// assert_eq!(env.robot(), env.env().robot());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(config: ReLMoGenConfig) -> ReLMoGenResult<Self> {
        config.validate()?;
        let env = Env::new(config.env_config()?.clone())?;
        let c = config.camera_section()?;
        let intrinsics = CameraIntrinsics {
            width: c.width,
            height: c.height,
            vfov_deg: c.vfov,
            near: c.near,
            far: c.far,
        };
        intrinsics.validate().map_err(|e| bad("camera", e.to_string()))?;
        let backend: Backend = c
            .backend
            .parse()
            .map_err(|e: hearth_sim::sensors::SensorError| bad("camera.backend", e.to_string()))?;
        let robot = env.robot();
        let camera = Camera::new(
            env.world(),
            Some(robot),
            CameraConfig {
                intrinsics,
                options: RenderOptions::default(),
                backend,
                mount: None,
            },
        )
        .map_err(SkillError::from)?;
        let arm = Arm::new(env.world(), robot, ArmSettings::fetch())?;
        let spec = ActionSpec {
            form: config.action,
            width: c.width,
            height: c.height,
            bins: config.direction_bins,
            max_base_distance: config.max_base_distance,
        };
        let navigator = Navigator::new(NavigateSettings {
            execution: config.execution,
            ..NavigateSettings::default()
        })?;
        let zero = vec![0.0; env.action_space().size()];
        Ok(Self {
            maps: env.maps().clone(),
            push: config.push.settings(),
            space: spec.space(),
            rng: Pcg64Mcg::seed_from_u64(0),
            config,
            env,
            camera,
            arm,
            spec,
            navigator,
            zero,
            started: false,
        })
    }

    /// The configuration.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// assert!(env.config().failure_penalty >= 0.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn config(&self) -> &ReLMoGenConfig {
        &self.config
    }

    /// The action space (see [`ActionSpec`]).
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// assert_eq!(env.action_space().name, "action");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn action_space(&self) -> &Space {
        &self.space
    }

    /// How actions decode.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// let i = env.action_spec().arm_index(16, 16, 0).unwrap();
    /// assert!(env.action_spec().decode(&[i as f32])?.is_arm());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn action_spec(&self) -> &ActionSpec {
        &self.spec
    }

    /// The observation spaces: the wrapped env's.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// assert_eq!(env.observation_spaces(), env.env().observation_spaces());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn observation_spaces(&self) -> &[Space] {
        self.env.observation_spaces()
    }

    /// The wrapped env.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// println!("{}", env.env().task_name());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn env(&self) -> &Env {
        &self.env
    }

    /// The wrapped env, writable (scripted set-ups and tests; see [`Env::world_mut`]).
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// env.reset(0)?;
    /// let robot = env.robot();
    /// env.env_mut().world_mut().tuck(robot)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn env_mut(&mut self) -> &mut Env {
        &mut self.env
    }

    /// The planner's head camera.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// assert_eq!(env.camera().config().intrinsics.width, 128);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The robot.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// let pose = env.env().world().base_pose(env.robot())?;
    /// println!("{pose:?}");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn robot(&self) -> ModelHandle {
        self.env.robot()
    }

    /// Starts an episode ([`Env::reset`]) and seeds the planners from `seed`.
    ///
    /// # Errors
    /// As [`Env::reset`].
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// let (obs, info) = env.reset(5)?;
    /// assert_eq!(info.env.episode_seed, 5);
    /// assert!(obs.get("rgb").is_some());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn reset(&mut self, seed: u64) -> ReLMoGenResult<(Obs, ReLMoGenInfo)> {
        let (obs, info) = self.env.reset(seed)?;
        self.rng = Pcg64Mcg::seed_from_u64(seed ^ 0x7265_6c6d_6f67_656e);
        self.camera.reset_flow();
        self.started = true;
        Ok((
            obs,
            ReLMoGenInfo {
                env: info,
                ..ReLMoGenInfo::default()
            },
        ))
    }

    /// Decodes `action`, runs its subgoal, and scores the state with a zero-action env step.
    ///
    /// # Errors
    /// [`ReLMoGenError::NotReset`] before a reset; [`ReLMoGenError::BadAction`] for an action
    /// [`ActionSpec::decode`] refuses (the world is not touched); env errors. A subgoal that
    /// fails is not an error: it is reported in the info and penalised.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut env = ReLMoGenEnv::new(config)?;
    /// env.reset(0)?;
    /// assert!(env.step(&[f32::NAN]).is_err());
    /// let step = env.step(&[0.0])?;
    /// println!("{:?}", step.info.failure_reason);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn step(&mut self, action: &[f32]) -> ReLMoGenResult<ReLMoGenStep> {
        if !self.started {
            return Err(ReLMoGenError::NotReset);
        }
        let subgoal = self.spec.decode(action)?;
        let mut info = ReLMoGenInfo {
            subgoal: if subgoal.is_arm() { "arm" } else { "base" },
            ..ReLMoGenInfo::default()
        };
        let clock = Instant::now();
        let outcome = self.run(subgoal, &mut info);
        info.skill_time = clock.elapsed().as_secs_f64();
        match outcome {
            Ok(()) => info.planner_success = true,
            Err(e) => {
                info.failure_reason = Some(e.reason());
                info.failure_message = Some(e.to_string());
            }
        }
        if !(subgoal.is_arm() && info.planner_success) {
            info.planning_time = info.skill_time;
        }
        let step = self.env.step(&self.zero)?;
        let penalty = if info.planner_success {
            0.0
        } else {
            self.config.failure_penalty
        };
        info.env = step.info;
        Ok(ReLMoGenStep {
            obs: step.obs,
            reward: step.reward - penalty,
            terminated: step.terminated,
            truncated: step.truncated,
            info,
        })
    }

    /// Resolves and executes a subgoal.
    fn run(&mut self, subgoal: Subgoal, info: &mut ReLMoGenInfo) -> SkillResult<()> {
        let robot = self.env.robot();
        let base = self.env.world().base_pose(robot)?;
        let (x, y, heading) = (base.translation.x, base.translation.y, base.rotation.euler_angles().2);
        let goal = match subgoal {
            Subgoal::Base { bearing, distance, yaw } => {
                let (s, c) = (heading + bearing).sin_cos();
                [x + distance * c, y + distance * s, heading + yaw]
            }
            Subgoal::BaseAtPixel { u, v, yaw } => {
                let (p, n, body) =
                    surface_at_pixel(self.env.world(), &mut self.camera, Some(robot), u.into(), v.into())?;
                if n.z < 0.9 || p.z > FLOOR_HEIGHT {
                    let name = self.env.world().body_name(body).unwrap_or("?");
                    return Err(SkillError::BadInput(format!(
                        "pixel ({u}, {v}) sees `{name}` at height {:.2} m, not the floor",
                        p.z
                    )));
                }
                [p.x, p.y, heading + yaw]
            }
            Subgoal::Arm { u, v, direction } => {
                let (p, n, body) =
                    surface_at_pixel(self.env.world(), &mut self.camera, Some(robot), u.into(), v.into())?;
                info.target = Some([p.x, p.y, p.z]);
                let along = match direction {
                    PushDirection::AgainstNormal => -n,
                    PushDirection::Horizontal(angle) => {
                        let (s, c) = (heading + angle).sin_cos();
                        Vector3::new(c, s, 0.0)
                    }
                };
                let report = push_at_point(
                    self.env.world_mut(),
                    &mut self.arm,
                    Point3::from(p.coords),
                    -along,
                    body,
                    &self.push,
                    self.config.execution,
                    &mut self.rng,
                );
                return match report {
                    Ok(r) => {
                        info.planning_time = r.approach.planning_time.as_secs_f64();
                        info.path_length = r.approach.path_length;
                        info.moved = r.moved;
                        Ok(())
                    }
                    Err(e) => Err(e),
                };
            }
        };
        info.target = Some(goal);
        let report = self
            .navigator
            .navigate(self.env.world_mut(), robot, &self.maps, goal, &mut self.rng)?;
        info.path_length = report.distance;
        Ok(())
    }
}
