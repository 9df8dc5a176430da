//! # hearth-sim
//!
//! The physics backend, built on [`hearth_planning`] and [`hearth_kinematics`]:
//!
//! - [`world`]: the rapier3d world (deterministic stepping, snapshots, state hash), robots and
//!   articulated objects as multibodies with controllers, readout, and the live-world
//!   [`Obstacles`](hearth_planning::obstacles::Obstacles) view planners check against.
//! - [`assets`]: household object categories generated as URDF (cabinets with drawers and
//!   doors, fridges, tables, chairs, …, bowls and mugs), with a material table.
//! - [`scene`]: the scene file format, procedural homes, traversability and room maps, URDF
//!   export and scene statistics.
//! - [`sensors`]: cameras (wgpu rasteriser and CPU ray caster, eight modalities), LiDAR and
//!   occupancy grids.
//! - [`env`](mod@env): Gymnasium-shaped environments and tasks built from a TOML file, vectorised.
//! - [`randomize`]: seeded domain randomisation of object models, visual and physical
//!   materials, poses and sensor noise.
//!
//! ```
//! use hearth_sim::scene::{generate, GenerateOptions, SceneInfo};
//!
//! let home = generate(&GenerateOptions { seed: 1, rooms: 3, ..Default::default() }).unwrap();
//! let info = SceneInfo::of(&home);
//! assert!(info.rooms.len() >= 3);
//! ```
#![warn(missing_docs)]

pub mod assets;
pub mod env;
pub mod randomize;
pub mod scene;
pub mod sensors;
pub mod world;

/// The kinematics crate this one builds on.
pub use hearth_kinematics as kinematics;
/// The planning crate this one builds on.
pub use hearth_planning as planning;
