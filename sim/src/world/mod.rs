//! The rapier3d world: stepping, snapshots, robots with controllers, and the live-world
//! collision view for planners.
//!
//! - [`World`] owns rapier's sets and pipeline (z up, gravity −z, 1/120 s physics steps, 4
//!   per control step by default; see [`WorldConfig`]).
//! - [`World::spawn_model`] turns any [`hearth_kinematics::RobotModel`] (robots and objects
//!   alike) into a rapier multibody; [`World::place`], [`World::reset_configuration`] and
//!   [`World::tuck`] pose it.
//! - Controllers: [`World::set_position_targets`], [`World::set_velocity_targets`],
//!   [`World::set_efforts`], [`World::set_joint_command`], [`World::drive`] (differential
//!   drive), [`World::drive_holonomic`], [`World::gripper_open`] / [`World::gripper_close`].
//! - Readout: [`World::joint_positions`], [`World::joint_velocities`],
//!   [`World::joint_efforts`], [`World::base_pose`], [`World::base_twist`],
//!   [`World::link_pose`], [`World::contacts`].
//! - [`World::load_scene`] spawns a [`crate::scene::SceneFile`] (building, objects, robot);
//!   [`World::settle`] steps until it rests.
//! - [`World::snapshot`] / [`World::restore`] and [`World::state_hash`] for exact rollbacks.
//! - [`World::obstacles_view`] implements planning's
//!   [`Obstacles`](hearth_planning::obstacles::Obstacles) over the live colliders.
//!
//! Notes on how rapier is used here:
//! - Each model is one rapier multibody (reduced coordinates); links welded by fixed joints
//!   share a body, and each link contributes one collider (its merged collision shape).
//! - Position and velocity control use rapier's force-based implicit joint motors. rapier does
//!   not report multibody motor impulses, so [`World::joint_efforts`] evaluates the motor's
//!   force law at the current state instead.
//! - A multibody takes its root pose from the root body at the start of every step and
//!   overwrites the body's integrated pose, so a kinematic root would not follow its velocity:
//!   the holonomic base advances its root pose itself before each physics step.
//! - Teleports (spawn, place, reset) refresh the moved colliders and their broad-phase boxes at
//!   once, so collision views are exact before the next step.
//!
//! ```
//! use hearth_sim::kinematics::RobotModel;
//! use hearth_sim::world::{SpawnOptions, World, WorldConfig};
//! use nalgebra::Isometry3;
//!
//! let mut world = World::new(WorldConfig::default())?;
//! let fetch = RobotModel::builtin("fetch").unwrap();
//! let robot = world.spawn_model(&fetch, &Isometry3::identity(), SpawnOptions::free())?;
//! world.tuck(robot)?;
//! world.drive(robot, 0.2, 0.0)?;
//! for _ in 0..15 {
//!     world.step();
//! }
//! assert!(world.base_pose(robot)?.translation.x > 0.02);
//! # Ok::<(), hearth_sim::world::WorldError>(())
//! ```

mod config;
mod contact_filter;
mod control;
mod error;
mod obstacles;
mod physics;
mod properties;
mod readout;
mod scene_load;
mod snapshot;
mod spawn;

pub use config::WorldConfig;
pub use control::{DiffDriveConfig, FINGER_PAD_FRICTION, GripperConfig, JointCommand, JointGains};
pub use error::{WorldError, WorldResult};
pub use obstacles::WorldObstacles;
pub use physics::{BodyId, StaticVisual, World};
pub use readout::{ContactInfo, ContactRef, Twist};
pub use scene_load::{
    BUILDING_PREFIX, LoadSceneError, LoadedScene, REST_ANGULAR_SPEED, REST_LINEAR_SPEED, SettleReport,
};
pub use snapshot::Snapshot;
pub use spawn::{BaseMode, ModelHandle, SpawnOptions, named_configuration};
