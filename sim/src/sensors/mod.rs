//! Sensors: cameras (a wgpu rasteriser and a driver-free ray caster with the same modalities),
//! 1- and 16-beam LiDAR, and local occupancy grids, all reading the live [`World`](crate::world::World).
//!
//! - [`CameraIntrinsics`], [`Modality`], [`Preset`], [`RenderOptions`], [`Backend`],
//!   [`Mount`] and the output [`Frame`] describe a camera; the [`camera`] module documents
//!   frames and units.
//! - [`VisualScene`] lists every visual shape with its material, semantic class
//!   ([`SemanticClass`]) and instance id.
//! - [`RayScene`] is the ray-casting engine (parry shapes in a BVH) that the ray-cast camera
//!   and the LiDARs share.

pub mod camera;
mod cameras;
mod error;
pub mod gpu;
pub mod raycast;
pub mod save;
pub mod shading;
mod visuals;

pub use camera::{Backend, CameraIntrinsics, Frame, Modality, ModalitySet, Mount, Preset, RenderOptions};
pub use cameras::{Camera, CameraConfig};
pub use error::{SensorError, SensorResult};
pub use gpu::{GpuCamera, gpu_adapter};
pub use raycast::{RayHit, RayScene, RaycastCamera};
pub use visuals::{
    Instance, PbrMaterial, SceneLight, SemanticClass, VisualItem, VisualScene, VisualShape, default_lights,
    metallic_roughness, pose_f32, scene_lights,
};
