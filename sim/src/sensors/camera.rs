//! Camera description shared by both backends: intrinsics, modalities, presets, the output
//! [`Frame`], and where a camera sits on a robot.
//!
//! # Frames and units
//! - The **camera frame** is the optical frame: x right, y down, z forward (along the optical
//!   axis), in metres. A camera pose is the pose of this frame in the world.
//! - Pixel (u, v) has its centre at (u + ½, v + ½); u grows to the right, v downwards; images
//!   are stored row-major, top row first.
//! - `depth` is the z coordinate in the camera frame (metres along the optical axis, not the
//!   ray length). Pixels that see nothing, or whose depth is outside `[near, far]`, are 0.
//! - `normal` is the unit surface normal in the camera frame, facing the camera; 0 where
//!   nothing is seen.
//! - `pc` is the camera-frame XYZ of the surface point of each pixel (0 where nothing).
//! - `seg` is the [semantic class](crate::sensors::SemanticClass) id, `ins_seg` the instance id
//!   (both 0 for background).
//! - `optical_flow` is (Δu, Δv) in pixels: where the surface point seen now was projected in
//!   the previous frame, subtracted from where it is projected now.
//! - `scene_flow` is the point's camera-frame position now minus the same material point's
//!   camera-frame position in the previous frame (each in its own frame's camera), metres.
//!   Both flows are 0 on a camera's first frame.

use std::str::FromStr;

use nalgebra::{Isometry3, Point3, Rotation3, UnitQuaternion, Vector3};

use super::error::{SensorError, SensorResult, check_param};
use crate::world::{ModelHandle, World};

/// Largest image side accepted.
///
/// ```
/// use hearth_sim::sensors::{CameraIntrinsics, camera::MAX_IMAGE_SIDE};
/// assert!(CameraIntrinsics::new(MAX_IMAGE_SIDE, 16, 60.0).is_ok());
/// assert!(CameraIntrinsics::new(MAX_IMAGE_SIDE + 1, 16, 60.0).is_err());
/// ```
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// Pinhole intrinsics from width, height and vertical field of view, with clipping planes.
///
/// ```
/// use hearth_sim::sensors::CameraIntrinsics;
/// let k = CameraIntrinsics::new(128, 128, 90.0).unwrap();
/// assert!((k.fy() - 64.0).abs() < 1e-9);
/// assert!(CameraIntrinsics::new(0, 128, 90.0).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraIntrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Vertical field of view in degrees.
    pub vfov_deg: f64,
    /// Near clipping distance (m): closer depths read 0.
    pub near: f64,
    /// Far clipping distance (m): farther depths read 0.
    pub far: f64,
}

impl CameraIntrinsics {
    /// Intrinsics with iGibson's default clipping (near 0.05 m, far 100 m... set `far` lower for
    /// a real sensor range).
    ///
    /// # Errors
    /// [`SensorError::InvalidResolution`] or [`SensorError::InvalidParameter`].
    ///
    /// ```
    /// use hearth_sim::sensors::CameraIntrinsics;
    /// let k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// assert_eq!((k.near, k.far), (0.05, 100.0));
    /// assert!(CameraIntrinsics::new(32, 24, 180.0).is_err());
    /// ```
    pub fn new(width: u32, height: u32, vfov_deg: f64) -> SensorResult<Self> {
        let k = Self {
            width,
            height,
            vfov_deg,
            near: 0.05,
            far: 100.0,
        };
        k.validate()?;
        Ok(k)
    }

    /// Checks sizes, field of view and clipping planes.
    ///
    /// # Errors
    /// As [`CameraIntrinsics::new`].
    ///
    /// ```
    /// use hearth_sim::sensors::{CameraIntrinsics, SensorError};
    /// let mut k = CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// k.far = 0.01; // below `near`
    /// assert!(matches!(k.validate(), Err(SensorError::InvalidParameter { name: "far", .. })));
    /// ```
    pub fn validate(&self) -> SensorResult<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Err(SensorError::InvalidResolution {
                width: self.width,
                height: self.height,
                max: MAX_IMAGE_SIDE,
            });
        }
        check_param("vfov_deg", self.vfov_deg, 1.0, 170.0, "must be in [1, 170] degrees")?;
        check_param("near", self.near, 1e-4, 1e4, "must be in [1e-4, 1e4] m")?;
        check_param(
            "far",
            self.far,
            self.near * 1.0001,
            1e6,
            "must exceed near and be at most 1e6 m",
        )?;
        Ok(())
    }

    /// Focal length in pixels along y (square pixels: also along x).
    ///
    /// ```
    /// let k = hearth_sim::sensors::CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// assert!((k.fy() - 12.0).abs() < 1e-9); // half the height at 90°
    /// ```
    pub fn fy(&self) -> f64 {
        self.height as f64 / 2.0 / (self.vfov_deg.to_radians() / 2.0).tan()
    }

    /// Focal length in pixels along x.
    ///
    /// ```
    /// let k = hearth_sim::sensors::CameraIntrinsics::new(32, 24, 90.0).unwrap();
    /// assert_eq!(k.fx(), k.fy());
    /// ```
    pub fn fx(&self) -> f64 {
        self.fy()
    }

    /// Principal point (cx, cy) in pixels: the image centre.
    ///
    /// ```
    /// let k = hearth_sim::sensors::CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// assert_eq!(k.principal_point(), (16.0, 12.0));
    /// ```
    pub fn principal_point(&self) -> (f64, f64) {
        (self.width as f64 / 2.0, self.height as f64 / 2.0)
    }

    /// Number of pixels.
    ///
    /// ```
    /// let k = hearth_sim::sensors::CameraIntrinsics::new(32, 24, 60.0).unwrap();
    /// assert_eq!(k.pixels(), 768);
    /// ```
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Camera-frame direction (z = 1) through the centre of pixel (u, v).
    ///
    /// ```
    /// let k = hearth_sim::sensors::CameraIntrinsics::new(4, 4, 90.0).unwrap();
    /// let d = k.pixel_ray(1.5, 1.5);
    /// assert!(d.x.abs() < 1e-12 && d.y.abs() < 1e-12 && d.z == 1.0);
    /// ```
    pub fn pixel_ray(&self, u: f64, v: f64) -> Vector3<f64> {
        let (cx, cy) = self.principal_point();
        Vector3::new((u + 0.5 - cx) / self.fx(), (v + 0.5 - cy) / self.fy(), 1.0)
    }

    /// Projects a camera-frame point to continuous pixel coordinates (pixel centres at +½);
    /// `None` behind the camera.
    ///
    /// ```
    /// use nalgebra::Point3;
    /// let k = hearth_sim::sensors::CameraIntrinsics::new(4, 4, 90.0).unwrap();
    /// let (u, v) = k.project(&Point3::new(0.0, 0.0, 2.0)).unwrap();
    /// assert!((u - 2.0).abs() < 1e-12 && (v - 2.0).abs() < 1e-12);
    /// ```
    pub fn project(&self, p: &Point3<f64>) -> Option<(f64, f64)> {
        if p.z <= 1e-9 {
            return None;
        }
        let (cx, cy) = self.principal_point();
        Some((self.fx() * p.x / p.z + cx, self.fy() * p.y / p.z + cy))
    }
}

/// One output of a camera.
///
/// ```
/// use hearth_sim::sensors::Modality;
/// assert_eq!("ins_seg".parse::<Modality>().unwrap(), Modality::InsSeg);
/// assert_eq!(Modality::OpticalFlow.name(), "optical_flow");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Modality {
    /// Shaded colour, RGB8.
    Rgb,
    /// Depth along the optical axis, metres.
    Depth,
    /// Camera-frame unit normals.
    Normal,
    /// Semantic class ids.
    Seg,
    /// Instance ids.
    InsSeg,
    /// Pixel displacement since the previous frame.
    OpticalFlow,
    /// Camera-frame 3-D displacement since the previous frame.
    SceneFlow,
    /// Camera-frame XYZ per pixel.
    Pc,
}

const MODALITY_NAMES: &str = "rgb, depth, normal, seg, ins_seg, optical_flow, scene_flow, pc";

impl Modality {
    /// Every modality.
    ///
    /// ```
    /// use hearth_sim::sensors::{Modality, ModalitySet};
    /// assert_eq!(Modality::ALL.len(), 8);
    /// assert_eq!(Modality::ALL.into_iter().collect::<ModalitySet>(), ModalitySet::ALL);
    /// ```
    pub const ALL: [Modality; 8] = [
        Modality::Rgb,
        Modality::Depth,
        Modality::Normal,
        Modality::Seg,
        Modality::InsSeg,
        Modality::OpticalFlow,
        Modality::SceneFlow,
        Modality::Pc,
    ];

    /// The name used in configs and on the command line.
    ///
    /// ```
    /// use hearth_sim::sensors::Modality;
    /// assert_eq!(Modality::SceneFlow.name(), "scene_flow");
    /// assert_eq!(Modality::SceneFlow.name().parse::<Modality>().unwrap(), Modality::SceneFlow);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Modality::Rgb => "rgb",
            Modality::Depth => "depth",
            Modality::Normal => "normal",
            Modality::Seg => "seg",
            Modality::InsSeg => "ins_seg",
            Modality::OpticalFlow => "optical_flow",
            Modality::SceneFlow => "scene_flow",
            Modality::Pc => "pc",
        }
    }

    const fn bit(self) -> u8 {
        1 << (self as u8)
    }

    /// Parses a comma-separated list (`rgb,depth`) into a set.
    ///
    /// ```
    /// use hearth_sim::sensors::Modality;
    /// let set = Modality::parse_list("rgb, depth").unwrap();
    /// assert!(set.contains(Modality::Depth) && !set.contains(Modality::Seg));
    /// assert!(Modality::parse_list("rgb,sonar").is_err());
    /// ```
    ///
    /// # Errors
    /// [`SensorError::UnknownModality`] for a name not in the list.
    pub fn parse_list(list: &str) -> SensorResult<ModalitySet> {
        let mut set = ModalitySet::EMPTY;
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            set = set.with(name.parse()?);
        }
        Ok(set)
    }
}

impl FromStr for Modality {
    type Err = SensorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Modality::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| SensorError::UnknownModality {
                name: s.to_owned(),
                known: MODALITY_NAMES,
            })
    }
}

impl std::fmt::Display for Modality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of [`Modality`]s (a bit set).
///
/// ```
/// use hearth_sim::sensors::{Modality, ModalitySet};
/// let s = ModalitySet::EMPTY.with(Modality::Rgb).with(Modality::Pc);
/// assert_eq!(s.iter().collect::<Vec<_>>(), vec![Modality::Rgb, Modality::Pc]);
/// assert!(ModalitySet::ALL.contains(Modality::SceneFlow));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ModalitySet(u8);

impl ModalitySet {
    /// No modality.
    ///
    /// ```
    /// use hearth_sim::sensors::ModalitySet;
    /// assert!(ModalitySet::EMPTY.is_empty());
    /// assert_eq!(ModalitySet::EMPTY.iter().count(), 0);
    /// ```
    pub const EMPTY: ModalitySet = ModalitySet(0);
    /// Every modality.
    ///
    /// ```
    /// use hearth_sim::sensors::{Modality, ModalitySet};
    /// assert_eq!(ModalitySet::ALL.iter().collect::<Vec<_>>(), Modality::ALL.to_vec());
    /// ```
    pub const ALL: ModalitySet = ModalitySet(0xff);

    /// This set plus `m`.
    ///
    /// ```
    /// use hearth_sim::sensors::{Modality, ModalitySet};
    /// let s = ModalitySet::EMPTY.with(Modality::Seg).with(Modality::Seg);
    /// assert_eq!(s.iter().count(), 1);
    /// ```
    pub const fn with(self, m: Modality) -> Self {
        Self(self.0 | m.bit())
    }

    /// Whether `m` is in the set.
    ///
    /// ```
    /// use hearth_sim::sensors::{Modality, ModalitySet};
    /// let s = ModalitySet::EMPTY.with(Modality::Normal);
    /// assert!(s.contains(Modality::Normal) && !s.contains(Modality::Depth));
    /// ```
    pub const fn contains(self, m: Modality) -> bool {
        self.0 & m.bit() != 0
    }

    /// Whether the set is empty.
    ///
    /// ```
    /// use hearth_sim::sensors::{Modality, ModalitySet};
    /// assert!(ModalitySet::default().is_empty());
    /// assert!(!ModalitySet::EMPTY.with(Modality::Rgb).is_empty());
    /// ```
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The modalities, in [`Modality::ALL`] order.
    ///
    /// ```
    /// use hearth_sim::sensors::{Modality, ModalitySet};
    /// let s = ModalitySet::EMPTY.with(Modality::Pc).with(Modality::Rgb);
    /// assert_eq!(s.iter().collect::<Vec<_>>(), vec![Modality::Rgb, Modality::Pc]);
    /// ```
    pub fn iter(self) -> impl Iterator<Item = Modality> {
        Modality::ALL.into_iter().filter(move |m| self.contains(*m))
    }
}

impl FromIterator<Modality> for ModalitySet {
    fn from_iter<I: IntoIterator<Item = Modality>>(iter: I) -> Self {
        iter.into_iter().fold(ModalitySet::EMPTY, ModalitySet::with)
    }
}

/// Renderer quality switches.
///
/// ```
/// use hearth_sim::sensors::{Preset, RenderOptions};
/// let o = RenderOptions::from(Preset::HighFidelity);
/// assert!(o.pbr && o.shadows && o.msaa > 1);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    /// Physically based (metallic-roughness) shading with image-based ambient light; off
    /// gives Lambert shading.
    pub pbr: bool,
    /// Shadow mapping for the directional light (wgpu backend; the ray-cast backend casts
    /// shadow rays when on).
    pub shadows: bool,
    /// MSAA sample count for RGB (1 = off; the wgpu backend supports 1 or 4).
    pub msaa: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Preset::VisualRl.into()
    }
}

/// iGibson's render presets.
///
/// ```
/// use hearth_sim::sensors::Preset;
/// let p: Preset = "visual-rl".parse().unwrap();
/// assert_eq!(p.resolution(), 128);
/// assert!("cinematic".parse::<Preset>().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// 128×128, PBR on, no MSAA, no shadows.
    VisualRl,
    /// 512×512, PBR, MSAA, shadows.
    HighFidelity,
}

impl Preset {
    /// Image side in pixels.
    ///
    /// ```
    /// use hearth_sim::sensors::Preset;
    /// assert_eq!(Preset::VisualRl.resolution(), 128);
    /// assert_eq!(Preset::HighFidelity.resolution(), 512);
    /// ```
    pub fn resolution(self) -> u32 {
        match self {
            Preset::VisualRl => 128,
            Preset::HighFidelity => 512,
        }
    }

    /// The preset's name (`visual-rl`, `high-fidelity`).
    ///
    /// ```
    /// use hearth_sim::sensors::Preset;
    /// assert_eq!(Preset::HighFidelity.name(), "high-fidelity");
    /// assert_eq!("high-fidelity".parse::<Preset>().unwrap(), Preset::HighFidelity);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Preset::VisualRl => "visual-rl",
            Preset::HighFidelity => "high-fidelity",
        }
    }

    /// Square intrinsics at the preset's resolution with vertical field of view `vfov_deg`.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a bad field of view.
    ///
    /// ```
    /// use hearth_sim::sensors::Preset;
    /// let k = Preset::VisualRl.intrinsics(90.0).unwrap();
    /// assert_eq!((k.width, k.height), (128, 128));
    /// assert!(Preset::VisualRl.intrinsics(0.0).is_err());
    /// ```
    pub fn intrinsics(self, vfov_deg: f64) -> SensorResult<CameraIntrinsics> {
        CameraIntrinsics::new(self.resolution(), self.resolution(), vfov_deg)
    }
}

impl From<Preset> for RenderOptions {
    fn from(p: Preset) -> Self {
        match p {
            Preset::VisualRl => RenderOptions {
                pbr: true,
                shadows: false,
                msaa: 1,
            },
            Preset::HighFidelity => RenderOptions {
                pbr: true,
                shadows: true,
                msaa: 4,
            },
        }
    }
}

impl FromStr for Preset {
    type Err = SensorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "visual-rl" | "visual_rl" => Ok(Preset::VisualRl),
            "high-fidelity" | "high_fidelity" => Ok(Preset::HighFidelity),
            _ => Err(SensorError::UnknownPreset { name: s.to_owned() }),
        }
    }
}

/// Which camera implementation renders.
///
/// ```
/// use hearth_sim::sensors::Backend;
/// assert_eq!("raycast".parse::<Backend>().unwrap(), Backend::Raycast);
/// assert_eq!("raster".parse::<Backend>().unwrap(), Backend::Raster);
/// assert!("opengl".parse::<Backend>().is_err());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// wgpu when an adapter exists, otherwise ray casting (with a one-line notice on stderr).
    #[default]
    Auto,
    /// The wgpu rasteriser (a GPU, or Mesa's lavapipe on a CPU).
    Wgpu,
    /// CPU ray casting with parry; needs no graphics driver.
    Raycast,
    /// CPU depth rasteriser ([`crate::sensors::RasterCamera`]): depth, point cloud, normals and
    /// ids only, fastest for RL observations without colour; needs no graphics driver.
    Raster,
}

impl Backend {
    /// The backend's name.
    ///
    /// ```
    /// use hearth_sim::sensors::Backend;
    /// assert_eq!(Backend::default().name(), "auto");
    /// assert_eq!(Backend::Raster.name().parse::<Backend>().unwrap(), Backend::Raster);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Wgpu => "wgpu",
            Backend::Raycast => "raycast",
            Backend::Raster => "raster",
        }
    }
}

impl FromStr for Backend {
    type Err = SensorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Backend::Auto),
            "wgpu" => Ok(Backend::Wgpu),
            "raycast" => Ok(Backend::Raycast),
            "raster" => Ok(Backend::Raster),
            _ => Err(SensorError::UnknownBackend { name: s.to_owned() }),
        }
    }
}

/// One rendered frame: every requested modality as a row-major array (see the module docs for
/// frames and units). Buffers are kept between frames, so rendering does not allocate once
/// warm.
///
/// ```
/// let f = hearth_sim::sensors::Frame::default();
/// assert!(f.depth.is_empty() && f.rgb.is_empty());
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Modalities this frame holds (others are stale or empty).
    pub modalities: ModalitySet,
    /// RGB8, 3 bytes per pixel.
    pub rgb: Vec<u8>,
    /// Depth along the optical axis, m (0 = nothing within `[near, far]`).
    pub depth: Vec<f32>,
    /// Camera-frame unit normal per pixel.
    pub normal: Vec<[f32; 3]>,
    /// Semantic class id per pixel.
    pub seg: Vec<u32>,
    /// Instance id per pixel.
    pub ins_seg: Vec<u32>,
    /// (Δu, Δv) pixels since the previous frame.
    pub optical_flow: Vec<[f32; 2]>,
    /// Camera-frame displacement since the previous frame, m.
    pub scene_flow: Vec<[f32; 3]>,
    /// Camera-frame XYZ per pixel, m.
    pub pc: Vec<[f32; 3]>,
}

impl Frame {
    /// Resizes every requested buffer to `w × h` (contents unspecified) and records the set.
    ///
    /// ```
    /// use hearth_sim::sensors::{Frame, Modality, ModalitySet};
    /// let mut f = Frame::default();
    /// f.prepare(4, 3, ModalitySet::EMPTY.with(Modality::Rgb).with(Modality::Depth));
    /// assert_eq!((f.rgb.len(), f.depth.len(), f.seg.len()), (36, 12, 0));
    /// ```
    pub fn prepare(&mut self, w: u32, h: u32, modalities: ModalitySet) {
        let n = w as usize * h as usize;
        self.width = w;
        self.height = h;
        self.modalities = modalities;
        let fit = |on: bool, len: usize| if on { len } else { 0 };
        self.rgb.resize(fit(modalities.contains(Modality::Rgb), 3 * n), 0);
        self.depth.resize(fit(modalities.contains(Modality::Depth), n), 0.0);
        self.normal
            .resize(fit(modalities.contains(Modality::Normal), n), [0.0; 3]);
        self.seg.resize(fit(modalities.contains(Modality::Seg), n), 0);
        self.ins_seg.resize(fit(modalities.contains(Modality::InsSeg), n), 0);
        self.optical_flow
            .resize(fit(modalities.contains(Modality::OpticalFlow), n), [0.0; 2]);
        self.scene_flow
            .resize(fit(modalities.contains(Modality::SceneFlow), n), [0.0; 3]);
        self.pc.resize(fit(modalities.contains(Modality::Pc), n), [0.0; 3]);
    }

    /// Row-major index of pixel (u, v).
    ///
    /// ```
    /// use hearth_sim::sensors::{Frame, Modality, ModalitySet};
    /// let mut f = Frame::default();
    /// f.prepare(4, 3, ModalitySet::EMPTY.with(Modality::Depth));
    /// assert_eq!(f.index(1, 2), 9);
    /// ```
    pub fn index(&self, u: u32, v: u32) -> usize {
        v as usize * self.width as usize + u as usize
    }

    /// RGB as f32 in [0, 1], 3 per pixel.
    ///
    /// # Errors
    /// [`SensorError::NotRendered`] when the frame has no RGB.
    ///
    /// ```
    /// use hearth_sim::sensors::{Frame, Modality, ModalitySet};
    /// let mut f = Frame::default();
    /// assert!(f.rgb_f32().is_err()); // no RGB rendered
    /// f.prepare(1, 1, ModalitySet::EMPTY.with(Modality::Rgb));
    /// f.rgb.copy_from_slice(&[0, 255, 51]);
    /// assert_eq!(f.rgb_f32().unwrap(), vec![0.0, 1.0, 0.2]);
    /// ```
    pub fn rgb_f32(&self) -> SensorResult<Vec<f32>> {
        if !self.modalities.contains(Modality::Rgb) {
            return Err(SensorError::NotRendered("rgb"));
        }
        Ok(self.rgb.iter().map(|&c| c as f32 / 255.0).collect())
    }
}

/// Checks a backend's render inputs: one pose per scene item, a finite camera pose.
pub(crate) fn check_render_inputs(
    item_poses: &[Isometry3<f64>],
    items: usize,
    camera: &Isometry3<f64>,
) -> SensorResult<()> {
    if item_poses.len() != items {
        return Err(SensorError::InvalidParameter {
            name: "item_poses",
            value: item_poses.len() as f64,
            reason: "must hold one pose per scene item",
        });
    }
    if camera.to_homogeneous().iter().any(|x| !x.is_finite()) {
        return Err(SensorError::InvalidParameter {
            name: "camera",
            value: f64::NAN,
            reason: "camera pose must be finite",
        });
    }
    Ok(())
}

/// Where a camera or LiDAR sits.
///
/// ```
/// use hearth_sim::sensors::Mount;
/// let m = Mount::default_camera("fetch").unwrap();
/// assert!(matches!(m, Mount::Link { ref link, .. } if link == "eyes"));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Mount {
    /// A fixed world pose of the camera (optical) frame.
    Free(Isometry3<f64>),
    /// A robot link. When `optical` is false the link follows the ROS body convention (x
    /// forward, y left, z up) and the camera looks along its x axis; when true the link is
    /// already an optical frame (z forward, y down).
    Link {
        /// Link name.
        link: String,
        /// Whether the link is an optical frame.
        optical: bool,
    },
}

/// Rotation from the optical frame (z forward, y down) to the body frame (x forward, z up).
pub(crate) fn body_from_optical() -> Rotation3<f64> {
    // Columns: optical x (right) = body −y, optical y (down) = body −z, optical z = body x.
    Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        0.0, 0.0, 1.0, //
        -1.0, 0.0, 0.0, //
        0.0, -1.0, 0.0,
    ))
}

impl Mount {
    /// The camera link a built-in robot carries (`eyes` on the Fetch, as iGibson; the
    /// LoCoBot's and TurtleBot's camera links).
    ///
    /// ```
    /// use hearth_sim::sensors::Mount;
    /// assert_eq!(Mount::default_camera("turtlebot"), Some(Mount::link("camera_rgb_frame")));
    /// assert!(Mount::default_camera("drone").is_none());
    /// ```
    pub fn default_camera(robot: &str) -> Option<Mount> {
        let link = match robot {
            "fetch" => "eyes",
            "locobot" => "camera_link",
            "turtlebot" => "camera_rgb_frame",
            _ => return None,
        };
        Some(Mount::Link {
            link: link.to_owned(),
            optical: false,
        })
    }

    /// The laser link of a built-in wheeled robot.
    ///
    /// ```
    /// use hearth_sim::sensors::Mount;
    /// assert_eq!(Mount::default_lidar("locobot"), Some(Mount::link("laser_link")));
    /// assert!(Mount::default_lidar("panda").is_none());
    /// ```
    pub fn default_lidar(robot: &str) -> Option<Mount> {
        matches!(robot, "fetch" | "locobot" | "turtlebot").then(|| Mount::Link {
            link: "laser_link".to_owned(),
            optical: false,
        })
    }

    /// A link mount, optical if the link's name contains `optical`.
    ///
    /// ```
    /// use hearth_sim::sensors::Mount;
    /// assert_eq!(Mount::link("head_camera_rgb_optical_frame"), Mount::Link { link: "head_camera_rgb_optical_frame".into(), optical: true });
    /// assert!(matches!(Mount::link("eyes"), Mount::Link { optical: false, .. }));
    /// ```
    pub fn link(link: &str) -> Mount {
        Mount::Link {
            link: link.to_owned(),
            optical: link.contains("optical"),
        }
    }

    /// A free camera at `eye` looking at `target`, with world z up in the image.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `eye` and `target` coincide or are not finite.
    ///
    /// ```
    /// use hearth_sim::sensors::Mount;
    /// use nalgebra::{Point3, Vector3};
    /// let m = Mount::look_at(Point3::new(0.0, 0.0, 1.0), Point3::new(2.0, 0.0, 1.0)).unwrap();
    /// let Mount::Free(pose) = m else { unreachable!() };
    /// let forward = pose.rotation * Vector3::z();
    /// assert!((forward - Vector3::x()).norm() < 1e-12);
    /// ```
    pub fn look_at(eye: Point3<f64>, target: Point3<f64>) -> SensorResult<Mount> {
        let d = target - eye;
        let n = d.norm();
        if !n.is_finite() || n < 1e-9 {
            return Err(SensorError::InvalidParameter {
                name: "look_at target",
                value: n,
                reason: "must be finite and differ from the eye position",
            });
        }
        let z = d / n;
        let up = if z.z.abs() > 0.999 { Vector3::x() } else { Vector3::z() };
        let x = z.cross(&up).normalize(); // right
        let y = z.cross(&x); // down
        let r = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_columns(&[x, y, z]));
        Ok(Mount::Free(Isometry3::from_parts(
            eye.coords.into(),
            UnitQuaternion::from_rotation_matrix(&r),
        )))
    }

    /// The world pose of the optical frame now.
    ///
    /// # Errors
    /// [`SensorError::NoSuchLink`] when the robot lacks the link, [`SensorError::World`] for an
    /// unknown robot.
    ///
    /// ```
    /// use hearth_sim::sensors::Mount;
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Point3;
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// let m = Mount::look_at(Point3::new(0.0, 0.0, 1.0), Point3::new(1.0, 0.0, 1.0)).unwrap();
    /// assert_eq!(m.pose(&world, None).unwrap().translation.z, 1.0);
    /// assert!(Mount::link("eyes").pose(&world, None).is_err()); // a link mount needs a robot
    /// ```
    pub fn pose(&self, world: &World, robot: Option<ModelHandle>) -> SensorResult<Isometry3<f64>> {
        match self {
            Mount::Free(p) => Ok(*p),
            Mount::Link { link, optical } => {
                let Some(robot) = robot else {
                    return Err(SensorError::NoSuchLink {
                        robot: "(none)".into(),
                        link: link.clone(),
                        sensor: "camera",
                    });
                };
                let name = world.model_name(robot)?.to_owned();
                let pose = world.link_pose(robot, link).map_err(|_| SensorError::NoSuchLink {
                    robot: name,
                    link: link.clone(),
                    sensor: "camera",
                })?;
                if *optical {
                    Ok(pose)
                } else {
                    Ok(pose * UnitQuaternion::from_rotation_matrix(&body_from_optical()))
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn body_from_optical_maps_axes() {
        let r = body_from_optical();
        assert!((r * Vector3::z() - Vector3::x()).norm() < 1e-12);
        assert!((r * Vector3::x() + Vector3::y()).norm() < 1e-12);
        assert!((r * Vector3::y() + Vector3::z()).norm() < 1e-12);
        assert!((r.matrix().determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn projection_inverts_pixel_rays() {
        let k = CameraIntrinsics::new(64, 48, 60.0).unwrap();
        for (u, v) in [(0, 0), (63, 47), (10, 30)] {
            let p = Point3::from(k.pixel_ray(u as f64, v as f64) * 3.0);
            let (pu, pv) = k.project(&p).unwrap();
            assert!((pu - (u as f64 + 0.5)).abs() < 1e-9 && (pv - (v as f64 + 0.5)).abs() < 1e-9);
        }
    }
}
