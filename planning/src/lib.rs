//! # hearth-planning
//!
//! Configuration spaces, collision checking and sampling-based planners (RRT, BiRRT,
//! LazyPRM) with shortcutting. This crate builds on [`hearth_kinematics`]; its planners are
//! being written (see the project's issues), and for now it exposes the kinematics it
//! stands on.
//!
//! ```
//! let panda = hearth_planning::kinematics::RobotModel::builtin("panda").unwrap();
//! assert_eq!(panda.dof(), 8);
//! ```
#![warn(missing_docs)]

/// The kinematics crate this one builds on.
pub use hearth_kinematics as kinematics;
