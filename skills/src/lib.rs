//! # hearth-skills
//!
//! Skill primitives (navigate, push at pixel, grasp, place, open/close) that chain IK, the
//! planners and execution in the simulator. Each skill returns a report on success and a
//! [`SkillError`] with a [`SkillError::reason`] on failure; [`Execution`] chooses between
//! controllers in physics (the default) and kinematic teleporting.
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

pub mod arm;
pub mod articulated;
pub mod error;
pub mod execution;
pub mod grasp;
pub mod place;
pub mod push;

pub use arm::{Arm, ArmSettings, ArmTarget};
pub use error::{SkillError, SkillResult};
pub use execution::Execution;
