//! [`SensorError`]: what can go wrong when configuring or reading a sensor.

use hearth_kinematics::Num;

use crate::world::WorldError;

/// An error from a camera, LiDAR or occupancy map. Every variant names the problem; a failed
/// call leaves the sensor and the world as they were.
///
/// ```
/// use hearth_sim::sensors::{Modality, SensorError};
/// let err = "colour".parse::<Modality>().unwrap_err();
/// assert!(matches!(err, SensorError::UnknownModality { .. }));
/// assert!(err.to_string().contains("colour"));
/// ```
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SensorError {
    /// Width or height is zero or above the limit.
    #[error("invalid image size {width}×{height}: each side must be in 1..={max}")]
    InvalidResolution {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Largest side allowed.
        max: u32,
    },
    /// A numeric sensor parameter is out of range or not finite.
    #[error("invalid sensor parameter `{name}` = {}: {reason}", Num(*value))]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What it must satisfy.
        reason: &'static str,
    },
    /// A modality name that does not exist.
    #[error("unknown modality `{name}` (known: {known})")]
    UnknownModality {
        /// Name given.
        name: String,
        /// The known names, comma separated.
        known: &'static str,
    },
    /// A preset name that does not exist.
    #[error("unknown render preset `{name}` (known: visual-rl, high-fidelity)")]
    UnknownPreset {
        /// Name given.
        name: String,
    },
    /// A backend name that does not exist.
    #[error("unknown camera backend `{name}` (known: auto, wgpu, raycast, raster)")]
    UnknownBackend {
        /// Name given.
        name: String,
    },
    /// The robot has no link to mount the sensor on.
    #[error("robot `{robot}` has no link `{link}` to mount the {sensor} on")]
    NoSuchLink {
        /// Robot (model instance) name.
        robot: String,
        /// Link asked for.
        link: String,
        /// `camera` or `LiDAR`.
        sensor: &'static str,
    },
    /// The robot has no default mount for this sensor, and none was named.
    #[error("robot `{robot}` has no default {sensor} link; name one")]
    NoDefaultMount {
        /// Robot (model) name.
        robot: String,
        /// `camera` or `LiDAR`.
        sensor: &'static str,
    },
    /// `--backend wgpu` (or [`crate::sensors::Backend::Wgpu`]) was asked for but no graphics
    /// adapter exists.
    #[error("no graphics adapter for the wgpu camera backend ({reason}); use the raycast backend")]
    NoAdapter {
        /// What wgpu reported.
        reason: String,
    },
    /// The GPU device failed while rendering or reading back.
    #[error("GPU error: {0}")]
    Gpu(String),
    /// The camera backend cannot render this modality.
    #[error("the {backend} camera backend does not render `{modality}` (use wgpu or raycast)")]
    Unsupported {
        /// The backend's name.
        backend: &'static str,
        /// The modality asked for.
        modality: &'static str,
    },
    /// A modality was read that the last frame did not produce.
    #[error("modality `{0}` was not rendered in this frame")]
    NotRendered(&'static str),
    /// Writing an image or array failed.
    #[error("cannot write {path}: {reason}")]
    Io {
        /// File path.
        path: String,
        /// The OS error.
        reason: String,
    },
    /// The world refused a query (unknown model or link).
    #[error(transparent)]
    World(#[from] WorldError),
}

/// Shorthand for results of sensor calls.
///
/// ```
/// use hearth_sim::sensors::{CameraIntrinsics, SensorError, SensorResult};
/// let r: SensorResult<CameraIntrinsics> = CameraIntrinsics::new(0, 24, 60.0);
/// assert!(matches!(r, Err(SensorError::InvalidResolution { width: 0, .. })));
/// ```
pub type SensorResult<T> = Result<T, SensorError>;

/// Checks that `value` is finite and in `[lo, hi]`.
pub(crate) fn check_param(name: &'static str, value: f64, lo: f64, hi: f64, reason: &'static str) -> SensorResult<()> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(SensorError::InvalidParameter { name, value, reason })
    }
}
