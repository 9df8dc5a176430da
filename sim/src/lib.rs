//! # hearth-sim
//!
//! The physics backend (rapier3d world, robots with controllers, articulated furniture,
//! scenes, sensors). It builds on [`hearth_planning`] and [`hearth_kinematics`]; the world
//! itself is being written (see the project's issues).
//!
//! ```
//! let fetch = hearth_sim::kinematics::RobotModel::builtin("fetch").unwrap();
//! assert!(fetch.link_index("base_link").is_ok());
//! ```
#![warn(missing_docs)]

pub mod assets;
pub mod scene;
pub mod world;

/// The kinematics crate this one builds on.
pub use hearth_kinematics as kinematics;
/// The planning crate this one builds on.
pub use hearth_planning as planning;
