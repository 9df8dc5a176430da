//! # hearth-skills
//!
//! Skill primitives (navigate, push at pixel, grasp, place, open/close) that chain IK, the
//! planners and execution in the simulator. They build on [`hearth_sim`]; the skills
//! themselves are being written (see the project's issues).
//!
//! ```
//! let locobot = hearth_skills::kinematics::RobotModel::builtin("locobot").unwrap();
//! assert!(locobot.dof() > 0);
//! ```
#![warn(missing_docs)]

/// The kinematics crate.
pub use hearth_kinematics as kinematics;
/// The planning crate.
pub use hearth_planning as planning;
/// The simulator crate this one builds on.
pub use hearth_sim as sim;
