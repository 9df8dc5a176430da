//! Point-goal navigation (`point_nav_fixed`, `point_nav_random`): start and goal, shaping
//! reward, terminations and metrics as iGibson defines them.

use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use super::config::TaskConfig;
use super::error::{EnvError, EnvResult};
use crate::scene::SceneMaps;

/// Per-episode metrics, reported in `info`.
///
/// ```
/// let m = hearth_sim::env::Metrics::default();
/// assert!(!m.success && m.spl == 0.0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// Whether the goal was reached.
    pub success: bool,
    /// Success weighted by (shortest path length / max(path length, shortest)).
    pub spl: f64,
    /// Distance the base travelled, m.
    pub path_length: f64,
    /// Steps with a collision.
    pub collisions: u32,
    /// Steps taken.
    pub episode_length: u32,
    /// Geodesic start–goal distance, m.
    pub geodesic_distance: f64,
}

/// Why an episode ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// The goal was reached.
    Success,
    /// Too many collisions.
    MaxCollisions,
    /// The robot left the map (or fell).
    OutOfBounds,
    /// The step limit.
    Timeout,
}

/// Placement of a map grid.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: [f64; 2],
    resolution: f64,
    width: usize,
    height: usize,
}

/// The point-navigation task state of one episode.
#[derive(Clone, Debug)]
pub(crate) struct PointNav {
    pub(crate) config: TaskConfig,
    pub(crate) start: [f64; 3],
    pub(crate) goal: [f64; 2],
    /// Geodesic distance to the goal from every map cell.
    field: Vec<f64>,
    /// The grid the field is laid on.
    grid: Option<Grid>,
    potential: f64,
    last_xy: [f64; 2],
    pub(crate) metrics: Metrics,
}

impl PointNav {
    pub(crate) fn new(config: TaskConfig) -> Self {
        Self {
            config,
            start: [0.0; 3],
            goal: [0.0; 2],
            field: Vec::new(),
            grid: None,
            potential: 0.0,
            last_xy: [0.0; 2],
            metrics: Metrics::default(),
        }
    }

    /// Picks start and goal for a new episode and precomputes the distance field.
    pub(crate) fn reset(&mut self, maps: &SceneMaps, rng: &mut Pcg64Mcg) -> EnvResult<()> {
        let (start, goal) = match (self.config.name.as_str(), self.config.start, self.config.goal) {
            ("point_nav_fixed", Some(s), Some(g)) => (s, g),
            _ => self.sample(maps, rng)?,
        };
        self.field = maps
            .distance_field(goal)
            .map_err(|e| EnvError::Task(format!("goal {goal:?}: {e}")))?;
        let d0 = maps
            .geodesic_at(&self.field, [start[0], start[1]])
            .unwrap_or(f64::INFINITY);
        if !d0.is_finite() {
            return Err(EnvError::Task(format!("no path from start {start:?} to goal {goal:?}")));
        }
        self.start = start;
        self.goal = goal;
        self.grid = Some(Grid {
            origin: maps.origin,
            resolution: maps.resolution,
            width: maps.width,
            height: maps.height,
        });
        self.last_xy = [start[0], start[1]];
        self.metrics = Metrics {
            geodesic_distance: d0,
            ..Metrics::default()
        };
        self.potential = self.potential_at([start[0], start[1]]);
        Ok(())
    }

    /// A random start on the traversable map and a goal whose geodesic distance is in range.
    fn sample(&self, maps: &SceneMaps, rng: &mut Pcg64Mcg) -> EnvResult<([f64; 3], [f64; 2])> {
        let free: Vec<usize> = (0..maps.traversable.len()).filter(|&i| maps.traversable[i]).collect();
        if free.is_empty() {
            return Err(EnvError::Task("the home has no traversable cell".into()));
        }
        let cell = |i: usize| maps.cell_center(i % maps.width, i / maps.width);
        let [lo, hi] = self.config.geodesic_range;
        for _ in 0..20 {
            let s = cell(free[rng.random_range(0..free.len())]);
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
            let g = cell(goals[rng.random_range(0..goals.len())]);
            let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            return Ok(([s[0], s[1], yaw], g));
        }
        Err(EnvError::Task(format!(
            "no start–goal pair with geodesic distance in [{lo}, {hi}] m after 20 starts"
        )))
    }

    fn potential_at(&self, xy: [f64; 2]) -> f64 {
        if self.config.potential == "l2" {
            (xy[0] - self.goal[0]).hypot(xy[1] - self.goal[1])
        } else {
            self.field_at(xy)
        }
    }

    fn field_at(&self, xy: [f64; 2]) -> f64 {
        // Off the traversable map (against a wall) fall back to the straight-line distance.
        self.maps_lookup(xy)
            .filter(|d| d.is_finite())
            .unwrap_or_else(|| (xy[0] - self.goal[0]).hypot(xy[1] - self.goal[1]))
    }

    fn maps_lookup(&self, xy: [f64; 2]) -> Option<f64> {
        let g = self.grid.as_ref()?;
        let x = ((xy[0] - g.origin[0]) / g.resolution).floor();
        let y = ((xy[1] - g.origin[1]) / g.resolution).floor();
        if x < 0.0 || y < 0.0 || x >= g.width as f64 || y >= g.height as f64 {
            return None;
        }
        self.field.get(y as usize * g.width + x as usize).copied()
    }

    /// Goal in the robot frame, distance to it: the `task_obs` entries.
    pub(crate) fn task_obs(&self, xy: [f64; 2], yaw: f64, v: f64, omega: f64) -> [f32; 5] {
        let (dx, dy) = (self.goal[0] - xy[0], self.goal[1] - xy[1]);
        let (s, c) = yaw.sin_cos();
        let local = [c * dx + s * dy, -s * dx + c * dy];
        [
            local[0] as f32,
            local[1] as f32,
            dx.hypot(dy) as f32,
            v as f32,
            omega as f32,
        ]
    }

    /// Reward and ending of one step that ended at `xy`.
    pub(crate) fn step(&mut self, xy: [f64; 2], collided: bool, on_map: bool) -> (f64, Option<Ending>) {
        let c = &self.config;
        self.metrics.episode_length += 1;
        self.metrics.path_length += (xy[0] - self.last_xy[0]).hypot(xy[1] - self.last_xy[1]);
        self.last_xy = xy;
        if collided {
            self.metrics.collisions += 1;
        }
        let potential = self.potential_at(xy);
        let mut reward = c.potential_weight * (self.potential - potential);
        self.potential = potential;
        if collided {
            reward -= c.collision_penalty;
        }
        let distance = (xy[0] - self.goal[0]).hypot(xy[1] - self.goal[1]);
        let ending = if distance < c.goal_tolerance {
            reward += c.success_reward;
            self.metrics.success = true;
            let shortest = self.metrics.geodesic_distance;
            self.metrics.spl = shortest / self.metrics.path_length.max(shortest).max(1e-9);
            Some(Ending::Success)
        } else if c.max_collisions > 0 && self.metrics.collisions >= c.max_collisions {
            Some(Ending::MaxCollisions)
        } else if !on_map {
            Some(Ending::OutOfBounds)
        } else {
            None
        };
        (reward, ending)
    }
}
