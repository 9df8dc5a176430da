//! Scene files, procedurally generated homes, traversability maps and URDF export.
//!
//! - [`SceneFile`]: the documented JSON format (building, objects, lights, robot), loaded with
//!   validation ([`SceneError`] names every problem) and saved back;
//! - [`generate`]: multi-room homes, deterministic per seed;
//! - [`SceneMaps`]: traversability and room-segmentation grids with A* shortest paths;
//! - [`export_urdf`]: the building and every object as URDF files plus a `scene.json` manifest;
//! - [`SceneInfo`]: rooms, objects per room, categories, articulated objects.
//!
//! ```
//! use hearth_sim::scene::{GenerateOptions, SceneInfo, generate};
//! let home = generate(&GenerateOptions { seed: 1, rooms: 3, ..Default::default() }).unwrap();
//! let info = SceneInfo::of(&home);
//! assert_eq!(info.rooms.len(), 4);
//! ```

mod error;
mod export;
mod footprint;
mod format;
mod generate;
mod info;
mod maps;
mod validate;

pub use error::SceneError;
pub use export::{Manifest, ManifestBody, export_urdf};
pub use format::{
    BoundingBox, Building, Light, LightKind, Opening, OpeningKind, Orientation, RobotPlacement, Room, SCENE_VERSION,
    SceneFile, SceneObject, Slab, Wall,
};
pub use generate::{GenerateOptions, generate};
pub use info::{RoomInfo, SceneInfo};
pub use maps::{MapOptions, SceneMaps};
pub use validate::OVERLAP_TOLERANCE;
