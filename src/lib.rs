//! # Hearth
//!
//! Motion planning and mobile manipulation in Rust, with a physics-simulator backend.
//!
//! This facade re-exports the workspace crates under short names:
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`kinematics`] | `hearth-kinematics` | robot models (URDF, built-in robots), FK, Jacobians, IK, self-collision |
//! | [`planning`] | `hearth-planning` | configuration spaces, collision checking, RRT / BiRRT / LazyPRM, shortcutting |
//! | [`sim`] | `hearth-sim` | the rapier world, robots with controllers, scenes, sensors |
//! | [`skills`] | `hearth-skills` | navigate, push, grasp, place, open/close |
//!
//! ```
//! use hearth::kinematics::RobotModel;
//! let panda = RobotModel::builtin("panda").unwrap();
//! assert_eq!(panda.variable_names()[0], "panda_joint1");
//! ```
#![warn(missing_docs)]

pub use hearth_kinematics as kinematics;
pub use hearth_planning as planning;
pub use hearth_sim as sim;
pub use hearth_skills as skills;

/// The most used types in one import.
///
/// ```
/// use hearth::prelude::*;
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// let arm = Chain::named(&fetch, "arm").unwrap();
/// assert_eq!(arm.dof(), 7);
/// ```
pub mod prelude {
    pub use hearth_kinematics::{
        Chain, IkMethod, IkSettings, IkSolution, IkSolver, IkTarget, KinematicsError, RobotModel, SelfCollisionMatrix,
    };
}
