//! # hearth-skills
//!
//! Skill primitives (navigate, push at pixel, grasp, place, open/close) that chain IK, the
//! planners and execution in the simulator. Each skill returns a report on success and a
//! [`SkillError`] with a [`SkillError::reason`] on failure; [`Execution`] chooses between
//! controllers in physics (the default) and kinematic teleporting.
//!
//! [`navigate()`] drives a wheeled base to an SE(2) goal: a path on the home's traversability
//! map, refined by SE(2) BiRRT with the base footprint against the live world, followed by
//! pure pursuit with replanning when blocked.
//!
//! Arm skills build on [`Arm`] ([`arm`]): collision-aware IK goals, BiRRT against the live
//! world, parabolic shortcutting, jerk-limited execution, straight-line and
//! pose-following moves with a force limit. On top of it: [`push::push_at_pixel`] (ReLMoGen's
//! push primitive), [`grasp::grasp`] and [`grasp::release`], [`place::place`], and
//! [`articulated::open`] / [`articulated::close`] for drawers and doors.
//!
//! [`story::run_story`] chains them into the scripted mobile-manipulation story of `hearth
//! demo`: drive to the kitchen, open a drawer, take a cup from the worktop to the sink.
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
pub mod navigate;
pub mod place;
pub mod push;
pub mod relmogen;
pub mod story;

pub use arm::{Arm, ArmSettings, ArmTarget, JerkPass};
pub use articulated::{ArticulatedSettings, close, open};
pub use error::{SkillError, SkillResult};
pub use execution::Execution;
pub use grasp::{GraspSettings, grasp, release};
pub use navigate::{NavigateReport, NavigateSettings, Navigator, navigate};
pub use place::{PlaceSettings, PlaceTarget, place};
pub use push::{PushSettings, push_at_pixel};
pub use relmogen::{ReLMoGenConfig, ReLMoGenEnv, ReLMoGenVecEnv};
pub use story::{StoryOptions, StoryReport, run_story};
