//! Gymnasium-shaped environments: [`Env`] (`reset(seed) -> (obs, info)`,
//! `step(action) -> Step`), configured by a TOML file ([`EnvConfig`]), with declared
//! observation and action [`Space`]s, and [`VecEnv`] for many envs in one process.
//!
//! Tasks: `point_nav_fixed` and `point_nav_random` (iGibson's point-goal navigation: potential
//! reward on the geodesic or straight-line distance, collision penalty, success reward; SPL,
//! path length and collisions in `info`).

mod config;
mod environment;
mod error;
mod spaces;
mod task;
mod vector;

pub use config::{
    CameraSection, EnvConfig, EpisodeConfig, LidarSection, OBSERVATION_NAMES, PhysicsConfig, RobotConfig, SceneConfig,
    SensorsConfig, TASK_NAMES, TaskConfig,
};
pub use environment::{Env, Info, Step};
pub use error::{EnvError, EnvResult};
pub use spaces::{DType, Obs, ObsData, Space};
pub use task::{Ending, Metrics};
pub use vector::{BatchedObs, VecEnv, VecStep};
