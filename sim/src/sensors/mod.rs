//! Sensors: cameras (a wgpu rasteriser and a driver-free ray caster with the same modalities,
//! and a CPU depth rasteriser for the geometric ones),
//! 1- and 16-beam LiDAR, and local occupancy grids, all reading the live [`World`](crate::world::World).
//!
//! - [`CameraIntrinsics`], [`Modality`], [`Preset`], [`RenderOptions`], [`Backend`],
//!   [`Mount`] and the output [`Frame`] describe a camera; the [`camera`] module documents
//!   frames and units.
//! - [`VisualScene`] lists every visual shape with its material, semantic class
//!   ([`SemanticClass`]) and instance id.
//! - [`RasterCamera`] is a CPU depth rasteriser for the geometric modalities (depth, point
//!   cloud, normals, ids), the [`Backend::Raster`] backend.
//! - [`RayScene`] is the ray-casting engine (parry shapes in a BVH) that the ray-cast camera
//!   and the LiDARs share.
//! - [`LidarSpec`], [`LidarNoise`], [`Lidar`] and the output [`Scan`] describe a LiDAR; the
//!   [`lidar`] module documents frames, angles and units.
//! - [`OccupancyGrid`] is a robot-centred local map built from a planar scan; the
//!   [`occupancy`] module documents its layout and values.

pub mod camera;
mod cameras;
mod error;
pub mod gpu;
pub mod lidar;
pub mod occupancy;
pub mod raster;
pub mod raycast;
pub mod save;
pub mod shading;
mod visuals;

pub use camera::{Backend, CameraIntrinsics, Frame, Modality, ModalitySet, Mount, Preset, RenderOptions};
pub use cameras::{Camera, CameraConfig};
pub use error::{SensorError, SensorResult};
pub use gpu::{GpuCamera, gpu_adapter};
pub use lidar::{
    CulledRays, IgnoredHits, Lidar, LidarNoise, LidarSpec, MAX_LIDAR_BEAMS, MAX_LIDAR_RAYS, NO_ITEM, Scan, lidar_pose,
    lidar_pose_in_base, model_items,
};
pub use occupancy::{FREE, MAX_GRID_SIDE, OCCUPIED, OccupancyGrid, OccupancyGridSpec, UNKNOWN};
pub use raster::{RASTER_MODALITIES, RasterCamera};
pub use raycast::{RayHit, RayScene, RaycastCamera};
pub use visuals::{
    Instance, PbrMaterial, SceneLight, SemanticClass, VisualItem, VisualScene, VisualShape, default_lights,
    metallic_roughness, pose_f32, scene_lights,
};
