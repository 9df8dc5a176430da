//! The tasks an [`Env`](super::Env) can run, one file per family, behind the [`Task`] enum:
//!
//! - [`point_nav`]: `point_nav_fixed`, `point_nav_random`;
//! - [`object_nav`]: `object_nav` (find a view of a category, from the `seg` image);
//! - [`interactive_nav`]: `interactive_nav` (point navigation through movable obstacles);
//! - [`reaching`]: `reaching` (the Fetch's gripper to a 3-D goal);
//! - [`articulated`]: `push_drawer`, `push_cabinet`, `room_rearrangement` (close what is open).
//!
//! A task picks the robot's start at reset (and may move objects), and turns each step into a
//! reward, an optional [`Ending`] and [`Metrics`].

pub(crate) mod articulated;
pub(crate) mod clearance;
pub(crate) mod field;
pub(crate) mod interactive_nav;
pub(crate) mod object_nav;
pub(crate) mod point_nav;
pub(crate) mod reaching;
pub(crate) mod viewpoints;

use nalgebra::Isometry3;
use rand_pcg::Pcg64Mcg;

use super::config::TaskConfig;
use super::error::EnvResult;
use crate::scene::{SceneFile, SceneMaps};
use crate::world::{LoadedScene, ModelHandle, World};

/// Per-episode metrics, reported in `info`.
///
/// ```
/// let m = hearth_sim::env::Metrics::default();
/// assert!(!m.success && m.spl == 0.0 && m.object_contacts == 0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// Whether the task was accomplished.
    pub success: bool,
    /// Success weighted by (shortest path length / max(path length, shortest)); navigation
    /// tasks only (0 elsewhere).
    pub spl: f64,
    /// Distance the base travelled, m.
    pub path_length: f64,
    /// Steps with a collision (a contact with anything but the floor, rugs and the task's own
    /// objects).
    pub collisions: u32,
    /// Steps with a contact with the task's objects (the obstacles of `interactive_nav`, the
    /// furniture of the articulated tasks): pushing them is allowed.
    pub object_contacts: u32,
    /// Steps taken.
    pub episode_length: u32,
    /// Geodesic start–goal distance (navigation tasks; for `object_nav` to the nearest view
    /// cell of the category), m.
    pub geodesic_distance: f64,
    /// What is left of the task: distance to the goal (m; geodesic for navigation, straight
    /// for reaching) or the total opening (sum over the joints of position / range) for the
    /// articulated tasks.
    pub remaining: f64,
}

/// Why an episode ended.
///
/// ```
/// use hearth_sim::env::{Ending, Info};
/// let info = Info { ending: Some(Ending::Timeout), ..Info::default() };
/// assert_ne!(info.ending, Some(Ending::Success));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// The task was accomplished.
    Success,
    /// Too many collisions.
    MaxCollisions,
    /// The robot left the map (or fell).
    OutOfBounds,
    /// The step limit.
    Timeout,
}

/// What a task sees when an episode starts.
pub(crate) struct ResetContext<'a> {
    pub(crate) world: &'a mut World,
    pub(crate) maps: &'a SceneMaps,
    pub(crate) rng: &'a mut Pcg64Mcg,
}

/// What a task sees after each step (and after reset, for its first observation).
pub(crate) struct StepContext<'a> {
    pub(crate) world: &'a World,
    pub(crate) robot: ModelHandle,
    /// Base pose after the step.
    pub(crate) base: Isometry3<f64>,
    /// A contact with something that counts as a collision.
    pub(crate) collided: bool,
    /// A contact with one of the task's objects.
    pub(crate) touched: bool,
    /// The base is on the map and above the floor.
    pub(crate) on_map: bool,
    /// The camera's semantic image, when the camera renders one.
    pub(crate) seg: Option<&'a [u32]>,
}

/// What a task needs at construction: the home as a file, what the world spawned of it, and
/// the world (tasks may spawn their own objects before the home snapshot is taken).
pub(crate) struct BuildContext<'a> {
    pub(crate) home: &'a SceneFile,
    pub(crate) loaded: &'a LoadedScene,
    pub(crate) world: &'a mut World,
    pub(crate) maps: &'a SceneMaps,
    pub(crate) robot: ModelHandle,
    /// The configured camera (`object_nav` estimates its views with it).
    pub(crate) camera: viewpoints::CameraView,
}

/// One task's state.
#[derive(Clone, Debug)]
pub(crate) enum Task {
    PointNav(point_nav::PointNav),
    ObjectNav(object_nav::ObjectNav),
    InteractiveNav(interactive_nav::InteractiveNav),
    Reaching(reaching::Reaching),
    Articulated(articulated::Articulated),
}

impl Task {
    /// The task named in `config` (the name was validated).
    pub(crate) fn new(config: &TaskConfig, ctx: BuildContext<'_>) -> EnvResult<Self> {
        Ok(match config.name.as_str() {
            "object_nav" => Task::ObjectNav(object_nav::ObjectNav::new(config.clone(), &ctx)?),
            "interactive_nav" => Task::InteractiveNav(interactive_nav::InteractiveNav::new(config.clone(), ctx)?),
            "reaching" => Task::Reaching(reaching::Reaching::new(config.clone(), &ctx)?),
            "push_drawer" | "push_cabinet" | "room_rearrangement" => {
                Task::Articulated(articulated::Articulated::new(config.clone(), &ctx)?)
            }
            _ => Task::PointNav(point_nav::PointNav::new(config.clone())),
        })
    }

    /// Whether the action carries arm joint velocity commands after (v, ω).
    pub(crate) fn uses_arm(&self) -> bool {
        matches!(self, Task::Reaching(_) | Task::Articulated(_))
    }

    /// Whether the task reads the camera's semantic image.
    pub(crate) fn needs_seg(&self) -> bool {
        matches!(self, Task::ObjectNav(_))
    }

    /// Starts an episode: returns the robot's start (x, y, yaw).
    pub(crate) fn reset(&mut self, ctx: ResetContext<'_>) -> EnvResult<[f64; 3]> {
        match self {
            Task::PointNav(t) => t.reset(ctx.maps, ctx.rng),
            Task::ObjectNav(t) => t.reset(ctx.maps, ctx.world, ctx.rng),
            Task::InteractiveNav(t) => t.reset(ctx),
            Task::Reaching(t) => t.reset(ctx),
            Task::Articulated(t) => t.reset(ctx),
        }
    }

    /// Called once the robot stands at its start and the sensors have rendered, before the first
    /// observation (tasks whose goal depends on the placed robot finish their set-up here).
    pub(crate) fn begin(&mut self, ctx: &StepContext<'_>) -> EnvResult<()> {
        match self {
            Task::Reaching(t) => t.begin(ctx),
            Task::Articulated(t) => t.begin(ctx),
            Task::ObjectNav(t) => {
                t.begin(ctx);
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Reward and ending of one step.
    pub(crate) fn step(&mut self, ctx: &StepContext<'_>) -> (f64, Option<Ending>) {
        match self {
            Task::PointNav(t) => t.step(ctx),
            Task::ObjectNav(t) => t.step(ctx),
            Task::InteractiveNav(t) => t.step(ctx),
            Task::Reaching(t) => t.step(ctx),
            Task::Articulated(t) => t.step(ctx),
        }
    }

    /// Number of `task_obs` entries.
    pub(crate) fn obs_len(&self) -> usize {
        match self {
            Task::PointNav(_) | Task::InteractiveNav(_) => point_nav::OBS_LEN,
            Task::ObjectNav(_) => object_nav::OBS_LEN,
            Task::Reaching(_) => reaching::OBS_LEN,
            Task::Articulated(_) => articulated::OBS_LEN,
        }
    }

    /// Writes the `task_obs` entries (`v`, `omega`: forward speed and yaw rate).
    pub(crate) fn task_obs(&self, ctx: &StepContext<'_>, v: f64, omega: f64, out: &mut Vec<f32>) {
        out.clear();
        match self {
            Task::PointNav(t) => t.task_obs(&ctx.base, v, omega, out),
            Task::InteractiveNav(t) => t.nav.task_obs(&ctx.base, v, omega, out),
            Task::ObjectNav(t) => t.task_obs(ctx, v, omega, out),
            Task::Reaching(t) => t.task_obs(ctx, v, omega, out),
            Task::Articulated(t) => t.task_obs(ctx, v, omega, out),
        }
    }

    /// Metrics so far.
    pub(crate) fn metrics(&self) -> Metrics {
        match self {
            Task::PointNav(t) => t.metrics,
            Task::ObjectNav(t) => t.metrics,
            Task::InteractiveNav(t) => t.nav.metrics,
            Task::Reaching(t) => t.metrics,
            Task::Articulated(t) => t.metrics,
        }
    }

    /// Names of models whose contacts are not collisions (the task's own objects).
    pub(crate) fn own_objects(&self) -> &[String] {
        match self {
            Task::InteractiveNav(t) => t.obstacle_names(),
            Task::Articulated(t) => t.target_names(),
            _ => &[],
        }
    }

    /// The episode's start (x, y, yaw).
    pub(crate) fn start(&self) -> [f64; 3] {
        match self {
            Task::PointNav(t) => t.start,
            Task::ObjectNav(t) => t.start,
            Task::InteractiveNav(t) => t.nav.start,
            Task::Reaching(t) => t.start,
            Task::Articulated(t) => t.start,
        }
    }

    /// The episode's goal as a world point: the point-navigation goal (z = 0), the reaching
    /// goal, the nearest instance of the target category, or the first target object's front.
    pub(crate) fn goal(&self) -> [f64; 3] {
        match self {
            Task::PointNav(t) => [t.goal[0], t.goal[1], 0.0],
            Task::InteractiveNav(t) => [t.nav.goal[0], t.nav.goal[1], 0.0],
            Task::ObjectNav(t) => t.goal(),
            Task::Reaching(t) => t.goal,
            Task::Articulated(t) => t.goal(),
        }
    }
}

/// Shared shaping and bookkeeping of one step: path length, collisions, potential difference.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Progress {
    last_xy: [f64; 2],
    potential: f64,
}

impl Progress {
    /// Starts from `xy` at `potential`.
    pub(crate) fn start(xy: [f64; 2], potential: f64) -> Self {
        Self { last_xy: xy, potential }
    }

    /// Counts one step into `metrics` and returns `weight × (previous − current potential)`,
    /// minus `collision_penalty` on a collision.
    pub(crate) fn step(
        &mut self,
        config: &TaskConfig,
        metrics: &mut Metrics,
        ctx: &StepContext<'_>,
        potential: f64,
    ) -> f64 {
        let xy = xy_of(&ctx.base);
        metrics.episode_length += 1;
        metrics.path_length += (xy[0] - self.last_xy[0]).hypot(xy[1] - self.last_xy[1]);
        self.last_xy = xy;
        if ctx.collided {
            metrics.collisions += 1;
        }
        if ctx.touched {
            metrics.object_contacts += 1;
        }
        let mut reward = config.potential_weight * (self.potential - potential);
        self.potential = potential;
        metrics.remaining = potential;
        if ctx.collided {
            reward -= config.collision_penalty;
        }
        reward
    }
}

/// The ending of a step that did not succeed: too many collisions, off the map, or none.
pub(crate) fn failure(config: &TaskConfig, metrics: &Metrics, on_map: bool) -> Option<Ending> {
    if config.max_collisions > 0 && metrics.collisions >= config.max_collisions {
        Some(Ending::MaxCollisions)
    } else if !on_map {
        Some(Ending::OutOfBounds)
    } else {
        None
    }
}

/// (x, y) of a pose.
pub(crate) fn xy_of(pose: &Isometry3<f64>) -> [f64; 2] {
    [pose.translation.x, pose.translation.y]
}

/// Yaw of a pose.
pub(crate) fn yaw_of(pose: &Isometry3<f64>) -> f64 {
    pose.rotation.euler_angles().2
}

/// `p` (world) in the base frame of `base`, full 3-D.
pub(crate) fn in_base_frame(base: &Isometry3<f64>, p: [f64; 3]) -> [f64; 3] {
    let local = base.inverse_transform_point(&nalgebra::Point3::new(p[0], p[1], p[2]));
    [local.x, local.y, local.z]
}

/// (x, y) of `p` in the planar frame of `base` (its yaw only).
pub(crate) fn in_planar_frame(base: &Isometry3<f64>, p: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (p[0] - base.translation.x, p[1] - base.translation.y);
    let (s, c) = yaw_of(base).sin_cos();
    [c * dx + s * dy, -s * dx + c * dy]
}
