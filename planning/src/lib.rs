//! # hearth-planning
//!
//! Configuration spaces, collision checking and sampling-based planners (RRT, BiRRT,
//! LazyPRM) with shortcutting, on top of [`hearth_kinematics`].
//!
//! - [`space`]: the [`Space`] trait (sample, distance, interpolate, bounds) for joint spaces
//!   with bounded and continuous joints, SE(2) bases, and compound base + arm spaces.
//! - [`obstacles`]: the [`Obstacles`] seam ("does this shape at this pose touch anything?",
//!   distance, ray cast) and [`ParryScene`], its static implementation over a parry BVH.
//! - [`validity`]: [`StateValidator`] and the exact [`RobotValidity`] (FK + links vs obstacles
//!   + self-collision + attached objects); [`motion`]: edges checked midpoint-first.
//! - [`planner`]: the [`Planner`] trait, [`PlanRequest`], [`Budget`], [`Solution`]; planners
//!   [`Rrt`], [`BiRrt`] (RRT-Connect) and [`LazyPrm`], failing with a typed [`PlanError`];
//!   [`nn`]: exact nearest-neighbour search under any space's metric.
//! - [`goal`]: end-effector pose goals, sampled by collision-aware IK.
//! - [`shortcut`]: repair at a fine resolution, random and acceleration-bounded (parabolic)
//!   shortcutting; [`trajectory`]: timed motions (trapezoids, Ruckig ramps, jerk-limited
//!   motions through waypoints) within per-joint [`trajectory::Limits`].
//! - [`problem`]: benchmark problem files (MotionBenchMaker JSON).
//!
//! ```
//! let panda = hearth_planning::kinematics::RobotModel::builtin("panda").unwrap();
//! assert_eq!(panda.dof(), 8);
//! ```
#![warn(missing_docs)]

/// The kinematics crate this one builds on.
pub use hearth_kinematics as kinematics;

pub mod birrt;
pub mod error;
pub mod goal;
pub mod lazy_prm;
pub mod motion;
pub mod nn;
pub mod obstacles;
pub mod planner;
pub mod problem;
pub mod rrt;
pub mod shortcut;
pub mod space;
pub mod trajectory;
pub mod validity;

pub use birrt::{BiRrt, Connect, DynamicDomain, Escape};
pub use error::PlanError;
pub use lazy_prm::{LazyPrm, LazyPrmSettings};
pub use motion::MotionValidator;
pub use nn::NearestNeighbors;
pub use obstacles::{Obstacles, ParryScene};
pub use planner::{Budget, Goal, Path, PlanRequest, PlanStats, Planner, Solution};
pub use rrt::Rrt;
pub use space::Space;
pub use validity::{RobotValidity, StateValidator};
