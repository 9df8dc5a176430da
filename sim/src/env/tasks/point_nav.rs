//! Point-goal navigation (`point_nav_fixed`, `point_nav_random`): start and goal, shaping
//! reward, terminations and metrics as iGibson defines them.

use nalgebra::Isometry3;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use super::field::{DistanceField, cell_center, free_cells};
use super::{Ending, Metrics, Progress, StepContext, failure, in_planar_frame, xy_of};
use crate::env::config::TaskConfig;
use crate::env::error::{EnvError, EnvResult};
use crate::scene::SceneMaps;

/// `task_obs` entries: goal x, y in the robot frame, distance, forward speed, yaw rate.
pub(crate) const OBS_LEN: usize = 5;

/// The point-navigation task state of one episode.
#[derive(Clone, Debug)]
pub(crate) struct PointNav {
    pub(crate) config: TaskConfig,
    pub(crate) start: [f64; 3],
    pub(crate) goal: [f64; 2],
    /// Geodesic distance to the goal from every map cell.
    field: DistanceField,
    progress: Progress,
    pub(crate) metrics: Metrics,
}

impl PointNav {
    pub(crate) fn new(config: TaskConfig) -> Self {
        Self {
            config,
            start: [0.0; 3],
            goal: [0.0; 2],
            field: DistanceField::default(),
            progress: Progress::default(),
            metrics: Metrics::default(),
        }
    }

    /// Picks start and goal for a new episode and precomputes the distance field.
    pub(crate) fn reset(&mut self, maps: &SceneMaps, rng: &mut Pcg64Mcg) -> EnvResult<[f64; 3]> {
        let (start, goal) = match (self.config.name.as_str(), self.config.start, self.config.goal) {
            ("point_nav_fixed", Some(s), Some(g)) => (s, g),
            _ => sample(maps, rng, self.config.geodesic_range)?,
        };
        self.set(maps, start, goal)?;
        Ok(start)
    }

    /// Sets start and goal and the field; the potential starts at the start.
    pub(crate) fn set(&mut self, maps: &SceneMaps, start: [f64; 3], goal: [f64; 2]) -> EnvResult<()> {
        let field = maps
            .distance_field(goal)
            .map_err(|e| EnvError::Task(format!("goal {goal:?}: {e}")))?;
        self.field = DistanceField::wrap(maps, field);
        let d0 = self.field.at([start[0], start[1]]).unwrap_or(f64::INFINITY);
        if !d0.is_finite() {
            return Err(EnvError::Task(format!("no path from start {start:?} to goal {goal:?}")));
        }
        self.start = start;
        self.goal = goal;
        let potential = self.potential_at([start[0], start[1]]);
        self.metrics = Metrics {
            geodesic_distance: d0,
            remaining: potential,
            ..Metrics::default()
        };
        self.progress = Progress::start([start[0], start[1]], potential);
        Ok(())
    }

    fn potential_at(&self, xy: [f64; 2]) -> f64 {
        let straight = (xy[0] - self.goal[0]).hypot(xy[1] - self.goal[1]);
        if self.config.potential == "l2" {
            straight
        } else {
            // Off the traversable map (against a wall) fall back to the straight-line distance.
            self.field.interpolated(xy).unwrap_or(straight)
        }
    }

    /// Goal in the robot frame, distance to it, speed and yaw rate: the `task_obs` entries.
    pub(crate) fn task_obs(&self, base: &Isometry3<f64>, v: f64, omega: f64, out: &mut Vec<f32>) {
        let xy = xy_of(base);
        let local = in_planar_frame(base, self.goal);
        let d = (self.goal[0] - xy[0]).hypot(self.goal[1] - xy[1]);
        out.extend_from_slice(&[local[0] as f32, local[1] as f32, d as f32, v as f32, omega as f32]);
    }

    /// Reward and ending of one step.
    pub(crate) fn step(&mut self, ctx: &StepContext<'_>) -> (f64, Option<Ending>) {
        let xy = xy_of(&ctx.base);
        let potential = self.potential_at(xy);
        let mut reward = self.progress.step(&self.config, &mut self.metrics, ctx, potential);
        let distance = (xy[0] - self.goal[0]).hypot(xy[1] - self.goal[1]);
        let ending = if distance < self.config.goal_tolerance {
            reward += self.config.success_reward;
            self.metrics.success = true;
            self.metrics.spl = spl(&self.metrics);
            Some(Ending::Success)
        } else {
            failure(&self.config, &self.metrics, ctx.on_map)
        };
        (reward, ending)
    }
}

/// SPL of a successful episode: shortest / max(path length, shortest).
pub(crate) fn spl(m: &Metrics) -> f64 {
    let shortest = m.geodesic_distance;
    shortest / m.path_length.max(shortest).max(1e-9)
}

/// A random start on the traversable map and a goal whose geodesic distance is in `range`.
pub(crate) fn sample(maps: &SceneMaps, rng: &mut Pcg64Mcg, range: [f64; 2]) -> EnvResult<([f64; 3], [f64; 2])> {
    let free = free_cells(maps);
    if free.is_empty() {
        return Err(EnvError::Task("the home has no traversable cell".into()));
    }
    let [lo, hi] = range;
    for _ in 0..20 {
        let s = cell_center(maps, free[rng.random_range(0..free.len())]);
        let field = maps
            .distance_field(s)
            .map_err(|e| EnvError::Task(format!("start {s:?}: {e}")))?;
        let goals: Vec<usize> = free
            .iter()
            .copied()
            .filter(|&i| (lo..=hi).contains(&field[i]))
            .collect();
        if goals.is_empty() {
            continue;
        }
        let g = cell_center(maps, goals[rng.random_range(0..goals.len())]);
        let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        return Ok(([s[0], s[1], yaw], g));
    }
    Err(EnvError::Task(format!(
        "no start–goal pair with geodesic distance in [{lo}, {hi}] m after 20 starts"
    )))
}
