//! `reaching`: bring the Fetch's gripper (`gripper_link`) to a random 3-D goal sampled in front
//! of the robot's start, within `reach_tolerance` (iGibson: 0.1 m).

use rand::RngExt;

use super::field::{cell_center, free_cells};
use super::{BuildContext, Ending, Metrics, Progress, ResetContext, StepContext, failure, in_base_frame};
use crate::env::config::TaskConfig;
use crate::env::error::{EnvError, EnvResult};

/// The link that has to reach the goal.
pub(crate) const END_EFFECTOR: &str = "gripper_link";

/// `task_obs` entries: goal x, y, z and end-effector x, y, z in the base frame, their distance,
/// forward speed, yaw rate.
pub(crate) const OBS_LEN: usize = 9;

/// The reaching task state of one episode.
#[derive(Clone, Debug)]
pub(crate) struct Reaching {
    config: TaskConfig,
    pub(crate) start: [f64; 3],
    /// The goal, world frame.
    pub(crate) goal: [f64; 3],
    /// The goal in the start's base frame, drawn at reset.
    local_goal: [f64; 3],
    progress: Progress,
    pub(crate) metrics: Metrics,
}

impl Reaching {
    pub(crate) fn new(config: TaskConfig, ctx: &BuildContext<'_>) -> EnvResult<Self> {
        ctx.world
            .link_pose(ctx.robot, END_EFFECTOR)
            .map_err(|e| EnvError::Task(format!("reaching needs the Fetch's `{END_EFFECTOR}`: {e}")))?;
        Ok(Self {
            config,
            start: [0.0; 3],
            goal: [0.0; 3],
            local_goal: [0.0; 3],
            progress: Progress::default(),
            metrics: Metrics::default(),
        })
    }

    /// A random start on the traversable map; the goal in front of it.
    pub(crate) fn reset(&mut self, ctx: ResetContext<'_>) -> EnvResult<[f64; 3]> {
        let free = free_cells(ctx.maps);
        if free.is_empty() {
            return Err(EnvError::Task("the home has no traversable cell".into()));
        }
        let s = cell_center(ctx.maps, free[ctx.rng.random_range(0..free.len())]);
        let yaw = ctx.rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let c = &self.config;
        let ahead = ctx.rng.random_range(c.goal_ahead[0]..=c.goal_ahead[1]);
        let side = ctx.rng.random_range(-c.goal_lateral..=c.goal_lateral);
        let height = ctx.rng.random_range(c.goal_height[0]..=c.goal_height[1]);
        self.local_goal = [ahead, side, height];
        self.start = [s[0], s[1], yaw];
        Ok(self.start)
    }

    /// Places the goal in front of the placed robot and starts the potential.
    pub(crate) fn begin(&mut self, ctx: &StepContext<'_>) -> EnvResult<()> {
        // The goal height is above the floor, not above the base frame.
        let [ax, ay, h] = self.local_goal;
        let p = ctx.base * nalgebra::Point3::new(ax, ay, 0.0);
        self.goal = [p.x, p.y, h];
        let d = self.distance(ctx)?;
        self.metrics = Metrics {
            remaining: d,
            ..Metrics::default()
        };
        self.progress = Progress::start(super::xy_of(&ctx.base), d);
        Ok(())
    }

    fn end_effector(&self, ctx: &StepContext<'_>) -> Option<[f64; 3]> {
        let t = ctx.world.link_pose(ctx.robot, END_EFFECTOR).ok()?.translation;
        Some([t.x, t.y, t.z])
    }

    fn distance(&self, ctx: &StepContext<'_>) -> EnvResult<f64> {
        let ee = self
            .end_effector(ctx)
            .ok_or_else(|| EnvError::Task(format!("the robot has no `{END_EFFECTOR}`")))?;
        Ok(dist3(ee, self.goal))
    }

    /// Goal and end effector in the base frame, their distance, speed and yaw rate.
    pub(crate) fn task_obs(&self, ctx: &StepContext<'_>, v: f64, omega: f64, out: &mut Vec<f32>) {
        let ee = self.end_effector(ctx).unwrap_or(self.goal);
        let g = in_base_frame(&ctx.base, self.goal);
        let e = in_base_frame(&ctx.base, ee);
        out.extend(g.iter().chain(&e).map(|&x| x as f32));
        out.extend_from_slice(&[dist3(ee, self.goal) as f32, v as f32, omega as f32]);
    }

    /// Reward and ending of one step.
    pub(crate) fn step(&mut self, ctx: &StepContext<'_>) -> (f64, Option<Ending>) {
        let d = self
            .end_effector(ctx)
            .map_or(self.metrics.remaining, |ee| dist3(ee, self.goal));
        let mut reward = self.progress.step(&self.config, &mut self.metrics, ctx, d);
        let ending = if d < self.config.reach_tolerance {
            reward += self.config.success_reward;
            self.metrics.success = true;
            Some(Ending::Success)
        } else {
            failure(&self.config, &self.metrics, ctx.on_map)
        };
        (reward, ending)
    }
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
