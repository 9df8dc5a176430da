//! Gymnasium-shaped environments: [`Env`] (`reset(seed) -> (obs, info)`,
//! `step(action) -> Step`), configured by a TOML file ([`EnvConfig`]), with declared
//! observation and action [`Space`]s, and [`VecEnv`] for many envs in one process.
//!
//! Tasks (iGibson's definitions of rewards, terminations and metrics; `docs/env.md` has the
//! details):
//! - `point_nav_fixed`, `point_nav_random`: reach a point; potential reward on the geodesic or
//!   straight-line distance, collision penalty, success reward; SPL, path length, collisions.
//! - `object_nav`: reach a view where a category covers 5 % of the semantic image.
//! - `interactive_nav`: point navigation with movable obstacles on the path.
//! - `reaching`: the Fetch's gripper to a 3-D goal (arm velocities in the action).
//! - `push_drawer`, `push_cabinet`, `room_rearrangement`: close drawers and doors opened at
//!   reset.

mod arm;
mod config;
mod environment;
mod error;
mod spaces;
mod tasks;
mod vector;

pub use config::{
    CameraSection, EnvConfig, EpisodeConfig, LidarSection, OBSERVATION_NAMES, PhysicsConfig, RobotConfig, SceneConfig,
    SensorsConfig, TASK_NAMES, TaskConfig,
};
pub use environment::{Env, Info, Step};
pub use error::{EnvError, EnvResult};
pub use spaces::{DType, Obs, ObsData, Space};
pub use tasks::{Ending, Metrics};
pub use vector::{BatchedObs, VecEnv, VecStep};
