//! `interactive_nav`: point navigation with movable obstacles (chairs, … from the asset
//! library) placed on the shortest start–goal path every episode. Pushing them is allowed:
//! contacts with them are counted in `object_contacts`, not as collisions.
//!
//! The obstacles are spawned once, when the env is built, and parked outside the home; each
//! reset moves them onto the path.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand::RngExt;

use super::point_nav::{PointNav, sample};
use super::{BuildContext, Ending, ResetContext, StepContext};
use crate::assets::Asset;
use crate::env::config::{TaskConfig, parse_asset};
use crate::env::error::{EnvError, EnvResult};
use crate::world::{BaseMode, ModelHandle, SpawnOptions};

/// Obstacles keep at least this far (m, along the path) from the start and the goal.
const CLEARANCE: f64 = 0.9;

/// The interactive-navigation task state.
#[derive(Clone, Debug)]
pub(crate) struct InteractiveNav {
    pub(crate) nav: PointNav,
    obstacles: Vec<ModelHandle>,
    names: Vec<String>,
}

impl InteractiveNav {
    pub(crate) fn new(config: TaskConfig, ctx: BuildContext<'_>) -> EnvResult<Self> {
        let mut obstacles = Vec::new();
        let mut names = Vec::new();
        for (k, spec) in config.obstacles.iter().enumerate() {
            let (category, variant) = parse_asset(spec).map_err(|reason| EnvError::Config {
                key: "task.obstacles".into(),
                reason,
            })?;
            let asset = Asset::build(category, variant, 1.0).map_err(|e| EnvError::Config {
                key: "task.obstacles".into(),
                reason: e.to_string(),
            })?;
            let name = format!("obstacle_{k}_{}", category.name());
            let handle = ctx.world.spawn_model(
                &asset.model,
                &parking(ctx.maps.origin, k),
                SpawnOptions {
                    name: Some(name.clone()),
                    base: BaseMode::Free,
                    friction: Some(asset.material.props().friction),
                    ..SpawnOptions::default()
                },
            )?;
            obstacles.push(handle);
            names.push(name);
        }
        Ok(Self {
            nav: PointNav::new(config),
            obstacles,
            names,
        })
    }

    /// Names of the obstacles' models.
    pub(crate) fn obstacle_names(&self) -> &[String] {
        &self.names
    }

    /// Samples start and goal as `point_nav_random` and puts the obstacles on the path between.
    pub(crate) fn reset(&mut self, ctx: ResetContext<'_>) -> EnvResult<[f64; 3]> {
        let (start, goal) = sample(ctx.maps, ctx.rng, self.nav.config.geodesic_range)?;
        self.nav.set(ctx.maps, start, goal)?;
        let path = ctx
            .maps
            .shortest_path([start[0], start[1]], goal)
            .map_err(|e| EnvError::Task(format!("start {start:?} to goal {goal:?}: {e}")))?;
        let length: f64 = path
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum();
        let n = self.obstacles.len();
        for (k, &h) in self.obstacles.iter().enumerate() {
            let s = length * (k + 1) as f64 / (n + 1) as f64;
            let yaw = ctx.rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            if s < CLEARANCE || length - s < CLEARANCE {
                // The path is too short for this one: it stays parked.
                continue;
            }
            let p = point_along(&path, s);
            let pose = Isometry3::from_parts(
                Translation3::new(p[0], p[1], 0.0),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            );
            ctx.world.place(h, &pose)?;
        }
        Ok(start)
    }

    /// Reward and ending of one step.
    pub(crate) fn step(&mut self, ctx: &StepContext<'_>) -> (f64, Option<Ending>) {
        self.nav.step(ctx)
    }
}

/// Where obstacle `k` waits outside the home.
fn parking(origin: [f64; 2], k: usize) -> Isometry3<f64> {
    Isometry3::translation(origin[0] - 5.0 - 2.0 * k as f64, origin[1] - 5.0, 0.0)
}

/// The point `s` m along a polyline.
fn point_along(path: &[[f64; 2]], mut s: f64) -> [f64; 2] {
    for w in path.windows(2) {
        let l = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        if s <= l && l > 0.0 {
            let t = s / l;
            return [w[0][0] + t * (w[1][0] - w[0][0]), w[0][1] + t * (w[1][1] - w[0][1])];
        }
        s -= l;
    }
    path.last().copied().unwrap_or([0.0; 2])
}
