//! # hearth-kinematics
//!
//! Robot models and their kinematics, the foundation of Hearth's planners, simulator and
//! skills:
//!
//! - [`RobotModel`]: an immutable, cheaply cloned robot loaded from URDF (links, joints,
//!   limits, mimic joints, inertials, visual and collision geometry; meshes in STL, OBJ and
//!   COLLADA; `package://` resolution via [`PackageResolver`]), or one of the
//!   [built-in robots](BUILTIN_ROBOTS) (Panda, Fetch, LoCoBot, TurtleBot).
//! - [`RobotModel::fk`]: every link pose into a caller-provided buffer, without allocating.
//! - [`RobotModel::jacobian`]: the geometric Jacobian of any link point.
//! - [`IkSolver`]: full-pose or position IK with damped least squares or a clarabel QP step,
//!   random restarts, seed-closest selection and an optional validity callback.
//! - [`Chain`]: an ordered subset of joints (e.g. Fetch torso + arm).
//! - [`SelfCollisionMatrix`]: which link pairs need self-collision checks.
//! - [`to_pose`] / [`from_pose`]: the one seam between nalgebra `f64` and parry's glam `f32`.
//!
//! ```
//! use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
//! use rand::SeedableRng;
//!
//! let fetch = RobotModel::builtin("fetch")?;
//! let arm = Chain::named(&fetch, "arm_with_torso")?;
//! let mut ik = IkSolver::new(arm, "gripper_link", IkSettings::default())?;
//! let target = ik.tool_pose(&[0.2, 0.5, -0.3, 0.4, 1.2, 0.0, 0.8, 0.0])?;
//! let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
//! let seed = vec![0.1; 8];
//! let solution = ik.solve(&IkTarget::Pose(target), &seed, &mut rng).expect("reachable");
//! assert!(solution.position_error < 1e-3);
//! # Ok::<(), hearth_kinematics::KinematicsError>(())
//! ```
#![warn(missing_docs)]

mod builtin;
mod chain;
mod convert;
pub mod distance_field;
mod error;
mod fk;
mod ik;
mod jacobian;
mod mesh;
mod model;
mod pair_table;
mod per_link;
mod resolve;
mod self_collision;
pub mod spheres;
mod urdf;

pub use builtin::{BUILTIN_ROBOTS, BuiltinRobot, builtin_names};
pub use chain::{Chain, wrap_angle};
pub use convert::{from_pose, to_pose, to_vector};
pub use error::{KinematicsError, Num, Result};
pub use fk::FkSubset;
pub use ik::dls::damped_least_squares_step;
pub use ik::{IkError, IkMethod, IkSettings, IkSolution, IkSolver, IkTarget};
pub use mesh::{MeshCollision, load_mesh};
pub use model::{
    ChainSpec, Collision, Dynamics, Geometry, Inertial, Joint, JointKind, JointLimits, Link, LinkShape, Mimic,
    RobotModel, TriangleMesh, Visual,
};
pub use pair_table::PairTable;
pub use resolve::{PACKAGE_PATH_ENV, PackageResolver};
pub use self_collision::{DisabledReason, SelfCollisionMatrix, SelfCollisionSettings, links_touch};
pub use urdf::LoadOptions;

/// Re-exported so users name the same versions.
pub use nalgebra;
pub use parry3d;
