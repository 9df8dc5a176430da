//! LiDARs: planar scanners (Hokuyo URG-04LX, SICK TiM571) and multi-beam spinning sensors
//! (Velodyne VLP-16), cast against the live world through a [`RayScene`].
//!
//! # Frames, angles and units
//! - The **sensor frame** follows the ROS body convention: x forward, y left, z up. A sensor
//!   pose is the pose of this frame in the world (for a robot, the pose of its laser link:
//!   see [`lidar_pose`]).
//! - Horizontal angles (azimuths) are in **radians**, measured counter-clockwise about the
//!   sensor z axis from the x axis, and centred on 0. A scan of field of view `fov` below a
//!   full turn has its first ray at `−fov/2` and its last at `+fov/2` (both ends included);
//!   a full-turn scan starts at `−π` and steps `2π / n`, so no direction is repeated.
//! - Elevations are in **radians**, positive above the sensor's xy plane.
//! - Ray `i` of a scan belongs to beam `i / horizontal_rays` (beams in the order of
//!   [`LidarSpec::elevations`]) and azimuth `i % horizontal_rays`.
//! - Ranges are metres along the ray, as `f32`. A ray with no return (nothing within the
//!   maximum range, a surface closer than the minimum range, or a dropped return) reads the
//!   **maximum range** and has its `hit` flag cleared, as iGibson's scan sensor does.
//!
//! # Speed
//! [`Lidar::scan`] casts every ray against the whole [`RayScene`]. [`Lidar::scan_culled`]
//! casts against a [`CulledRays`] copy that holds only the shapes within reach (and, for a
//! planar scanner, near the scan plane), with the robot's own shapes left out when they are
//! passed through: the same scan, several times faster in a home. Scans of at least 512 rays
//! are cast in parallel with rayon in chunks of 64 rays; smaller ones on the calling thread.
//! No buffer is allocated once a [`Scan`] (and a [`CulledRays`]) has been used.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};
use parry3d::math::Vector;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

use super::camera::Mount;
use super::error::{SensorError, SensorResult, check_param};
use super::raycast::RayScene;
use super::visuals::VisualScene;
use crate::world::{BodyId, ModelHandle, World};

/// Most rays one scan may have (all beams together).
///
/// ```
/// use hearth_sim::sensors::{LidarSpec, MAX_LIDAR_RAYS};
/// assert!(LidarSpec::planar(MAX_LIDAR_RAYS, 1.0, 0.1, 5.0).is_ok());
/// assert!(LidarSpec::planar(MAX_LIDAR_RAYS + 1, 1.0, 0.1, 5.0).is_err());
/// ```
pub const MAX_LIDAR_RAYS: usize = 1_000_000;

/// Most beams (elevation angles) a spec may have.
///
/// ```
/// use hearth_sim::sensors::{LidarSpec, MAX_LIDAR_BEAMS};
/// assert!(LidarSpec::multi_beam(8, 1.0, 0.1, 5.0, vec![0.0; MAX_LIDAR_BEAMS]).is_ok());
/// assert!(LidarSpec::multi_beam(8, 1.0, 0.1, 5.0, vec![0.0; MAX_LIDAR_BEAMS + 1]).is_err());
/// ```
pub const MAX_LIDAR_BEAMS: usize = 1024;

/// Rays per work item: scans are cast in chunks of this many rays (in parallel when the scan
/// is large enough), and each chunk draws its noise from its own stream, so the noise does not
/// depend on how chunks are spread over threads.
const CHUNK: usize = 64;

/// Scans with fewer rays than this are cast on the calling thread alone.
const PARALLEL_MIN_RAYS: usize = 512;

/// Most ignored surfaces one ray steps through before it is given up as no return.
const MAX_PASSES: usize = 256;

/// Item index reported for rays that hit nothing (see [`Scan::items`]).
///
/// ```
/// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
/// # use hearth_sim::world::{World, WorldConfig};
/// # use nalgebra::Isometry3;
/// # let mut world = World::new(WorldConfig::default()).unwrap();
/// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
/// # let visuals = VisualScene::from_world(&world);
/// # let mut rays = RayScene::new(&visuals);
/// # rays.update(&visuals, &world);
/// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
/// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
/// # let mut scan = Scan::default();
/// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
/// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
/// use hearth_sim::sensors::NO_ITEM;
/// assert!(!scan.hit[0]);
/// assert_eq!(scan.items[0], NO_ITEM);
/// assert_ne!(scan.items[2], NO_ITEM); // the wall
/// ```
pub const NO_ITEM: u32 = u32::MAX;

/// What a LiDAR measures: its rays and its range.
///
/// ```
/// use hearth_sim::sensors::LidarSpec;
/// let spec = LidarSpec::hokuyo_urg_04lx();
/// assert_eq!(spec.rays(), 228);
/// assert!((spec.horizontal_fov.to_degrees() - 240.0).abs() < 1e-9);
/// let vlp = LidarSpec::velodyne_vlp16(0.2).unwrap();
/// assert_eq!(vlp.beams(), 16);
/// assert_eq!(vlp.horizontal_rays, 1800);
/// assert!(LidarSpec::planar(0, 1.0, 0.1, 5.0).is_err());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct LidarSpec {
    /// Rays per beam around the z axis.
    pub horizontal_rays: usize,
    /// Horizontal field of view in radians, in `(0, 2π]`, centred on the x axis.
    pub horizontal_fov: f64,
    /// Minimum range (m): closer surfaces give no return.
    pub min_range: f64,
    /// Maximum range (m): farther surfaces give no return.
    pub max_range: f64,
    /// Elevation of each beam in radians (`[0.0]` for a planar scanner), each in
    /// `[−π/2, π/2]`.
    pub elevations: Vec<f64>,
}

impl LidarSpec {
    /// A planar (1-beam) scanner with `rays` rays over `fov_rad` radians.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] as [`LidarSpec::validate`].
    ///
    /// ```
    /// use hearth_sim::sensors::LidarSpec;
    /// let s = LidarSpec::planar(181, std::f64::consts::PI, 0.1, 10.0).unwrap();
    /// assert_eq!((s.beams(), s.rays()), (1, 181));
    /// assert!(LidarSpec::planar(181, std::f64::consts::PI, 10.0, 0.1).is_err()); // min ≥ max
    /// ```
    pub fn planar(rays: usize, fov_rad: f64, min_range: f64, max_range: f64) -> SensorResult<Self> {
        let spec = Self {
            horizontal_rays: rays,
            horizontal_fov: fov_rad,
            min_range,
            max_range,
            elevations: vec![0.0],
        };
        spec.validate()?;
        Ok(spec)
    }

    /// A multi-beam scanner: `rays` azimuths over `fov_rad` radians for each elevation (radians).
    ///
    /// ```
    /// use hearth_sim::sensors::LidarSpec;
    /// let s = LidarSpec::multi_beam(360, std::f64::consts::TAU, 0.1, 30.0, vec![-0.1, 0.0, 0.1]).unwrap();
    /// assert_eq!(s.rays(), 1080);
    /// ```
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] as [`LidarSpec::validate`].
    pub fn multi_beam(
        rays: usize,
        fov_rad: f64,
        min_range: f64,
        max_range: f64,
        elevations: Vec<f64>,
    ) -> SensorResult<Self> {
        let spec = Self {
            horizontal_rays: rays,
            horizontal_fov: fov_rad,
            min_range,
            max_range,
            elevations,
        };
        spec.validate()?;
        Ok(spec)
    }

    /// Hokuyo URG-04LX as iGibson configures it for the Fetch and the TurtleBot: 228 rays over
    /// 240°, 0.02–5.6 m.
    ///
    /// ```
    /// let s = hearth_sim::sensors::LidarSpec::hokuyo_urg_04lx();
    /// assert_eq!((s.horizontal_rays, s.min_range, s.max_range), (228, 0.02, 5.6));
    /// assert!(s.validate().is_ok());
    /// ```
    pub fn hokuyo_urg_04lx() -> Self {
        Self {
            horizontal_rays: 228,
            horizontal_fov: 240f64.to_radians(),
            min_range: 0.02,
            max_range: 5.6,
            elevations: vec![0.0],
        }
    }

    /// SICK TiM571: 220 rays over 220°, 0.05–25 m.
    ///
    /// ```
    /// let s = hearth_sim::sensors::LidarSpec::sick_tim571();
    /// assert_eq!((s.rays(), s.max_range), (220, 25.0));
    /// assert!((s.horizontal_fov.to_degrees() - 220.0).abs() < 1e-9);
    /// ```
    pub fn sick_tim571() -> Self {
        Self {
            horizontal_rays: 220,
            horizontal_fov: 220f64.to_radians(),
            min_range: 0.05,
            max_range: 25.0,
            elevations: vec![0.0],
        }
    }

    /// Velodyne VLP-16: 16 beams evenly from −15° to +15°, a full turn sampled every
    /// `horizontal_resolution_deg` degrees (0.1°–0.4° on the real sensor, by spin rate),
    /// 0.4–100 m.
    ///
    /// ```
    /// let s = hearth_sim::sensors::LidarSpec::velodyne_vlp16(1.0).unwrap();
    /// assert_eq!(s.rays(), 360 * 16);
    /// assert!((s.elevations[0].to_degrees() + 15.0).abs() < 1e-9);
    /// assert!((s.elevations[15].to_degrees() - 15.0).abs() < 1e-9);
    /// ```
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when the resolution is not finite, not positive, or
    /// gives more than [`MAX_LIDAR_RAYS`] rays.
    pub fn velodyne_vlp16(horizontal_resolution_deg: f64) -> SensorResult<Self> {
        check_param(
            "horizontal_resolution_deg",
            horizontal_resolution_deg,
            1e-3,
            360.0,
            "must be in [0.001, 360] degrees",
        )?;
        let rays = (360.0 / horizontal_resolution_deg).round().max(1.0) as usize;
        let elevations = (0..16).map(|i| (-15.0 + 2.0 * i as f64).to_radians()).collect();
        Self::multi_beam(rays, std::f64::consts::TAU, 0.4, 100.0, elevations)
    }

    /// Number of beams (elevations).
    ///
    /// ```
    /// use hearth_sim::sensors::LidarSpec;
    /// assert_eq!(LidarSpec::sick_tim571().beams(), 1);
    /// assert_eq!(LidarSpec::velodyne_vlp16(1.0).unwrap().beams(), 16);
    /// ```
    pub fn beams(&self) -> usize {
        self.elevations.len()
    }

    /// Rays per scan, all beams together.
    ///
    /// ```
    /// let s = hearth_sim::sensors::LidarSpec::velodyne_vlp16(0.5).unwrap();
    /// assert_eq!(s.rays(), s.horizontal_rays * 16);
    /// assert_eq!(s.rays(), 11_520);
    /// ```
    pub fn rays(&self) -> usize {
        self.horizontal_rays.saturating_mul(self.elevations.len())
    }

    /// Whether the azimuths cover a full turn (then `−π` is the first and `+π` is not repeated).
    ///
    /// ```
    /// use hearth_sim::sensors::LidarSpec;
    /// assert!(LidarSpec::velodyne_vlp16(1.0).unwrap().full_turn());
    /// assert!(!LidarSpec::hokuyo_urg_04lx().full_turn());
    /// ```
    pub fn full_turn(&self) -> bool {
        self.horizontal_fov >= std::f64::consts::TAU - 1e-9
    }

    /// Azimuth (radians, counter-clockwise from x) of horizontal ray `h`.
    ///
    /// ```
    /// let s = hearth_sim::sensors::LidarSpec::hokuyo_urg_04lx();
    /// assert!((s.azimuth(0) + 120f64.to_radians()).abs() < 1e-12);
    /// assert!((s.azimuth(227) - 120f64.to_radians()).abs() < 1e-12);
    /// ```
    pub fn azimuth(&self, h: usize) -> f64 {
        let n = self.horizontal_rays;
        if self.full_turn() {
            -std::f64::consts::PI + self.horizontal_fov * h as f64 / n as f64
        } else if n <= 1 {
            0.0
        } else {
            -self.horizontal_fov / 2.0 + self.horizontal_fov * h as f64 / (n - 1) as f64
        }
    }

    /// Checks counts, angles and ranges.
    ///
    /// ```
    /// use hearth_sim::sensors::{LidarSpec, SensorError};
    /// let mut s = LidarSpec::sick_tim571();
    /// s.min_range = 30.0;
    /// assert!(matches!(s.validate(), Err(SensorError::InvalidParameter { name: "min_range", .. })));
    /// ```
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for zero rays or beams, more than [`MAX_LIDAR_RAYS`]
    /// rays or [`MAX_LIDAR_BEAMS`] beams, a field of view outside `(0, 2π]`, a minimum range
    /// below 0 or not below the maximum, a maximum range above 1e6 m, or any value not finite.
    pub fn validate(&self) -> SensorResult<()> {
        let rays = self.horizontal_rays as f64;
        if self.horizontal_rays == 0 || self.horizontal_rays > MAX_LIDAR_RAYS {
            return Err(SensorError::InvalidParameter {
                name: "horizontal_rays",
                value: rays,
                reason: "must be in 1..=1000000",
            });
        }
        let beams = self.elevations.len();
        if beams == 0 || beams > MAX_LIDAR_BEAMS {
            return Err(SensorError::InvalidParameter {
                name: "beams",
                value: beams as f64,
                reason: "must have 1..=1024 elevation angles",
            });
        }
        if self.rays() > MAX_LIDAR_RAYS {
            return Err(SensorError::InvalidParameter {
                name: "rays",
                value: self.rays() as f64,
                reason: "horizontal rays × beams must be at most 1000000",
            });
        }
        check_param(
            "horizontal_fov",
            self.horizontal_fov,
            1e-9,
            std::f64::consts::TAU + 1e-9,
            "must be in (0, 2π] radians",
        )?;
        check_param("max_range", self.max_range, 1e-6, 1e6, "must be in (0, 1e6] m")?;
        check_param("min_range", self.min_range, 0.0, 1e6, "must be finite and at least 0 m")?;
        if self.min_range >= self.max_range {
            return Err(SensorError::InvalidParameter {
                name: "min_range",
                value: self.min_range,
                reason: "must be below max_range",
            });
        }
        for &e in &self.elevations {
            check_param(
                "elevation",
                e,
                -std::f64::consts::FRAC_PI_2,
                std::f64::consts::FRAC_PI_2,
                "must be in [−π/2, π/2] radians",
            )?;
        }
        Ok(())
    }

    /// Unit direction of ray `i` in the sensor frame (x forward, y left, z up).
    ///
    /// ```
    /// let s = hearth_sim::sensors::LidarSpec::sick_tim571();
    /// let d = s.direction(109);
    /// assert!(d.x > 0.999 && d.z == 0.0);
    /// ```
    pub fn direction(&self, i: usize) -> Vector3<f64> {
        let n = self.horizontal_rays.max(1);
        let (b, h) = (i / n, i % n);
        let el = self.elevations.get(b).copied().unwrap_or(0.0);
        let az = self.azimuth(h);
        let (se, ce) = el.sin_cos();
        let (sa, ca) = az.sin_cos();
        Vector3::new(ce * ca, ce * sa, se)
    }
}

/// Noise on a LiDAR's returns.
///
/// ```
/// use hearth_sim::sensors::LidarNoise;
/// let n = LidarNoise { dropout: 0.1, gaussian_std: 0.01 };
/// assert!(n.validate().is_ok());
/// assert!(LidarNoise { dropout: 1.5, ..LidarNoise::NONE }.validate().is_err());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LidarNoise {
    /// Probability in `[0, 1]` that a ray returns nothing (then it reads the maximum range and
    /// is flagged no-hit), as iGibson's dropout noise.
    pub dropout: f64,
    /// Standard deviation (m) of zero-mean Gaussian noise added to each return's range. Noisy
    /// ranges are clamped to `[0, max_range]`.
    pub gaussian_std: f64,
}

impl LidarNoise {
    /// No noise.
    ///
    /// ```
    /// use hearth_sim::sensors::LidarNoise;
    /// assert!(LidarNoise::NONE.is_none());
    /// assert_eq!(LidarNoise::NONE, LidarNoise::default());
    /// ```
    pub const NONE: LidarNoise = LidarNoise {
        dropout: 0.0,
        gaussian_std: 0.0,
    };

    /// Whether any noise is drawn.
    ///
    /// ```
    /// use hearth_sim::sensors::LidarNoise;
    /// assert!(LidarNoise::NONE.is_none());
    /// assert!(!LidarNoise { gaussian_std: 0.01, ..LidarNoise::NONE }.is_none());
    /// ```
    pub fn is_none(&self) -> bool {
        self.dropout == 0.0 && self.gaussian_std == 0.0
    }

    /// Checks both parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a dropout outside `[0, 1]` or a standard deviation
    /// outside `[0, 1e3]` m, or either not finite.
    ///
    /// ```
    /// use hearth_sim::sensors::{LidarNoise, SensorError};
    /// let n = LidarNoise { dropout: 0.0, gaussian_std: -0.1 };
    /// assert!(matches!(n.validate(), Err(SensorError::InvalidParameter { name: "gaussian_std", .. })));
    /// ```
    pub fn validate(&self) -> SensorResult<()> {
        check_param("dropout", self.dropout, 0.0, 1.0, "must be a probability in [0, 1]")?;
        check_param("gaussian_std", self.gaussian_std, 0.0, 1e3, "must be in [0, 1000] m")?;
        Ok(())
    }
}

/// One scan: a range per ray plus whether it returned.
///
/// Ranges are metres (`f32`); a ray with no return reads [`Scan::max_range`] and has
/// `hit[i] == false` (see the [module docs](self)). The buffers are reused from scan to scan.
///
/// ```
/// use hearth_sim::sensors::Scan;
/// let scan = Scan::default();
/// assert!(scan.ranges.is_empty() && scan.hit_count() == 0);
/// ```
#[derive(Clone, Debug)]
pub struct Scan {
    /// Range of each ray (m); the maximum range where there was no return.
    pub ranges: Vec<f32>,
    /// Whether each ray returned.
    pub hit: Vec<bool>,
    /// The [`VisualScene`] item each ray hit ([`NO_ITEM`] where it did not return).
    pub items: Vec<u32>,
    /// Rays per beam.
    pub horizontal_rays: usize,
    /// Number of beams.
    pub beams: usize,
    /// Minimum range of the sensor (m).
    pub min_range: f32,
    /// Maximum range of the sensor (m).
    pub max_range: f32,
    /// World pose of the sensor frame when the scan was taken.
    pub sensor_pose: Isometry3<f64>,
    /// Sensor-frame unit direction of each ray (shared with the [`Lidar`]).
    directions: Arc<[[f32; 3]]>,
}

impl Default for Scan {
    fn default() -> Self {
        Self {
            ranges: Vec::new(),
            hit: Vec::new(),
            items: Vec::new(),
            horizontal_rays: 0,
            beams: 0,
            min_range: 0.0,
            max_range: 0.0,
            sensor_pose: Isometry3::identity(),
            directions: Arc::from(Vec::new()),
        }
    }
}

impl Scan {
    /// Number of rays.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// assert_eq!(scan.len(), 4);
    /// assert_eq!(Scan::default().len(), 0);
    /// ```
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// Whether the scan has no rays (nothing scanned yet).
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// assert!(!scan.is_empty());
    /// assert!(Scan::default().is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Number of rays that returned.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// assert_eq!(scan.hit_count(), 1); // only the ray ahead meets the wall
    /// ```
    pub fn hit_count(&self) -> usize {
        self.hit.iter().filter(|&&h| h).count()
    }

    /// Range of ray `(beam, h)`, if both are in range.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// assert!((scan.range(0, 2).unwrap() - 1.95).abs() < 1e-3);
    /// assert_eq!(scan.range(0, 0), Some(5.0)); // no return: the maximum range
    /// assert_eq!(scan.range(1, 0), None); // there is one beam only
    /// ```
    pub fn range(&self, beam: usize, h: usize) -> Option<f32> {
        if beam >= self.beams || h >= self.horizontal_rays {
            return None;
        }
        self.ranges.get(beam * self.horizontal_rays + h).copied()
    }

    /// Sensor-frame unit direction of ray `i`.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let ahead = scan.direction(2).unwrap();
    /// assert!((ahead.x - 1.0).abs() < 1e-6 && ahead.y.abs() < 1e-6);
    /// assert!(scan.direction(4).is_none());
    /// ```
    pub fn direction(&self, i: usize) -> Option<Vector3<f32>> {
        self.directions.get(i).map(|d| Vector3::new(d[0], d[1], d[2]))
    }

    /// Ranges scaled to `[0, 1]` as iGibson's `scan` observation: `(r − min) / (max − min)`,
    /// clamped, so a ray with no return reads 1.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let mut out = vec![9.0; 10];
    /// scan.normalized_into(&mut out);
    /// assert_eq!(out.len(), 4);
    /// assert!((out[2] - (1.95 - 0.1) / 4.9).abs() < 1e-3);
    /// assert_eq!(out[0], 1.0); // no return
    /// ```
    pub fn normalized_into(&self, out: &mut Vec<f32>) {
        out.clear();
        let span = (self.max_range - self.min_range).max(f32::MIN_POSITIVE);
        out.extend(
            self.ranges
                .iter()
                .map(|&r| ((r - self.min_range) / span).clamp(0.0, 1.0)),
        );
    }

    /// [`Scan::normalized_into`] into a new vector.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let n = scan.normalized();
    /// assert_eq!(n.iter().filter(|&&x| x == 1.0).count(), 3);
    /// ```
    pub fn normalized(&self) -> Vec<f32> {
        let mut v = Vec::with_capacity(self.len());
        self.normalized_into(&mut v);
        v
    }

    /// Sensor-frame points of the rays that returned (in ray order), appended to `out` after
    /// clearing it.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let mut pts = Vec::new();
    /// scan.points_sensor_into(&mut pts);
    /// assert_eq!(pts.len(), 1);
    /// assert!((pts[0].x - 1.95).abs() < 1e-3 && pts[0].z.abs() < 1e-6);
    /// ```
    pub fn points_sensor_into(&self, out: &mut Vec<Point3<f32>>) {
        out.clear();
        for ((d, &r), &h) in self.directions.iter().zip(&self.ranges).zip(&self.hit) {
            if h {
                out.push(Point3::new(d[0] * r, d[1] * r, d[2] * r));
            }
        }
    }

    /// [`Scan::points_sensor_into`] into a new vector.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let p = scan.points_sensor()[0];
    /// assert!((p.coords.norm() - scan.ranges[2]).abs() < 1e-5);
    /// ```
    pub fn points_sensor(&self) -> Vec<Point3<f32>> {
        let mut v = Vec::with_capacity(self.len());
        self.points_sensor_into(&mut v);
        v
    }

    /// World-frame points of the rays that returned (in ray order), through
    /// [`Scan::sensor_pose`], appended to `out` after clearing it.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let mut pts = Vec::new();
    /// scan.points_world_into(&mut pts);
    /// assert_eq!(pts.len(), 1);
    /// assert!((pts[0].x - 1.95).abs() < 1e-3 && (pts[0].z - 0.5).abs() < 1e-6);
    /// ```
    pub fn points_world_into(&self, out: &mut Vec<Point3<f64>>) {
        out.clear();
        for ((d, &r), &h) in self.directions.iter().zip(&self.ranges).zip(&self.hit) {
            if h {
                let p = Point3::new(d[0] as f64, d[1] as f64, d[2] as f64) * r as f64;
                out.push(self.sensor_pose * p);
            }
        }
    }

    /// [`Scan::points_world_into`] into a new vector.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// let p = scan.points_world()[0];
    /// assert!((p - scan.sensor_pose.translation.vector).coords.norm() > 1.9);
    /// ```
    pub fn points_world(&self) -> Vec<Point3<f64>> {
        let mut v = Vec::with_capacity(self.len());
        self.points_world_into(&mut v);
        v
    }
}

/// What a ray does on reaching an item set with [`Lidar::ignore_items`].
///
/// ```
/// assert_eq!(hearth_sim::sensors::IgnoredHits::default(), hearth_sim::sensors::IgnoredHits::PassThrough);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IgnoredHits {
    /// The ray goes on through the item and reports what lies beyond.
    #[default]
    PassThrough,
    /// The ray gives no return (reads the maximum range), as iGibson treats rays that hit the
    /// robot's own body. Cheaper: no ray is cast twice.
    NoReturn,
}

/// A LiDAR: a spec, its noise, and the seeded random stream the noise is drawn from.
///
/// Rays are cast in parallel (rayon) in fixed chunks; the noise of each chunk comes from a
/// stream derived from the LiDAR's seed, the scan's number and the chunk's index, so the same
/// seed gives the same scans bit for bit whatever the number of threads.
///
/// ```
/// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
/// let visuals = VisualScene::from_world(&world);
/// let mut rays = RayScene::new(&visuals);
/// rays.update(&visuals, &world);
/// let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 7).unwrap();
/// let mut scan = Scan::default();
/// lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
/// let centre = scan.ranges[113]; // azimuth −0.5 step: nearly straight ahead
/// assert!((centre - 1.95).abs() < 2e-3, "{centre}");
/// assert!(!scan.hit[0]); // −120°: pointing away from the wall
/// assert_eq!(scan.ranges[0], 5.6);
/// ```
#[derive(Clone, Debug)]
pub struct Lidar {
    spec: LidarSpec,
    noise: LidarNoise,
    seed: u64,
    /// Scans taken since the last (re)seeding.
    scans: u64,
    rng: Pcg64Mcg,
    directions: Arc<[[f32; 3]]>,
    /// Items the rays do not report (e.g. the robot carrying the sensor).
    ignored: Vec<bool>,
    ignored_hits: IgnoredHits,
}

impl Lidar {
    /// A LiDAR with `spec` and `noise`; `seed` fixes the noise.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a bad spec or noise.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec};
    /// let lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// assert_eq!(lidar.directions().len(), 220);
    /// let bad = LidarNoise { dropout: 2.0, gaussian_std: 0.0 };
    /// assert!(Lidar::new(LidarSpec::sick_tim571(), bad, 3).is_err());
    /// ```
    pub fn new(spec: LidarSpec, noise: LidarNoise, seed: u64) -> SensorResult<Self> {
        spec.validate()?;
        noise.validate()?;
        let directions: Vec<[f32; 3]> = (0..spec.rays())
            .map(|i| {
                let d = spec.direction(i);
                [d.x as f32, d.y as f32, d.z as f32]
            })
            .collect();
        Ok(Self {
            spec,
            noise,
            seed,
            scans: 0,
            rng: Pcg64Mcg::seed_from_u64(seed),
            directions: Arc::from(directions),
            ignored: Vec::new(),
            ignored_hits: IgnoredHits::PassThrough,
        })
    }

    /// The spec.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec};
    /// let lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// assert_eq!(lidar.spec(), &LidarSpec::sick_tim571());
    /// ```
    pub fn spec(&self) -> &LidarSpec {
        &self.spec
    }

    /// The noise.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec};
    /// let noise = LidarNoise { dropout: 0.05, gaussian_std: 0.01 };
    /// let lidar = Lidar::new(LidarSpec::sick_tim571(), noise, 3).unwrap();
    /// assert_eq!(lidar.noise(), noise);
    /// ```
    pub fn noise(&self) -> LidarNoise {
        self.noise
    }

    /// The seed the LiDAR was made (or last reset) with.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec};
    /// let mut lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// assert_eq!(lidar.seed(), 3);
    /// lidar.reseed(8);
    /// assert_eq!(lidar.seed(), 8);
    /// ```
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Scans taken since the LiDAR was made or reseeded.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// let mut lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// let mut scan = Scan::default();
    /// lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// assert_eq!(lidar.scans(), 2);
    /// lidar.reseed(3);
    /// assert_eq!(lidar.scans(), 0);
    /// ```
    pub fn scans(&self) -> u64 {
        self.scans
    }

    /// Restarts the noise stream from `seed`: the scans that follow repeat those of a new
    /// LiDAR made with `seed`.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// let noise = LidarNoise { dropout: 0.1, gaussian_std: 0.02 };
    /// let mut lidar = Lidar::new(LidarSpec::sick_tim571(), noise, 5).unwrap();
    /// let pose = Isometry3::translation(0.0, 0.0, 0.5);
    /// let (mut a, mut b) = (Scan::default(), Scan::default());
    /// lidar.scan(&rays, &pose, &mut a);
    /// lidar.reseed(5);
    /// lidar.scan(&rays, &pose, &mut b);
    /// assert_eq!(a.ranges, b.ranges);
    /// ```
    pub fn reseed(&mut self, seed: u64) {
        self.seed = seed;
        self.scans = 0;
        self.rng = Pcg64Mcg::seed_from_u64(seed);
    }

    /// Sets the noise.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] as [`LidarNoise::validate`]; the noise is unchanged.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec};
    /// let mut lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// lidar.set_noise(LidarNoise { dropout: 0.0, gaussian_std: 0.01 }).unwrap();
    /// assert!(!lidar.noise().is_none());
    /// assert!(lidar.set_noise(LidarNoise { dropout: f64::NAN, gaussian_std: 0.0 }).is_err());
    /// assert_eq!(lidar.noise().gaussian_std, 0.01); // unchanged by the refused noise
    /// ```
    pub fn set_noise(&mut self, noise: LidarNoise) -> SensorResult<()> {
        noise.validate()?;
        self.noise = noise;
        Ok(())
    }

    /// Makes the rays ignore the given [`VisualScene`] items (replacing any set before) in the
    /// way `mode` says: typically the robot that carries the sensor, whose own body iGibson's
    /// scans leave out. See [`model_items`]. Ids of 2²⁴ and above are skipped (no scene has
    /// that many shapes).
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// # let spec = LidarSpec::planar(4, std::f64::consts::TAU, 0.1, 5.0).unwrap();
    /// # let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    /// # let mut scan = Scan::default();
    /// # lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// // `scan`: four rays (back, right, ahead, left) from 0.5 m up; a wall 1.95 m ahead.
    /// use hearth_sim::sensors::IgnoredHits;
    /// assert_eq!(scan.hit_count(), 1);
    /// lidar.ignore_items([scan.items[2]], IgnoredHits::NoReturn); // the wall
    /// lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// assert_eq!(scan.hit_count(), 0);
    /// ```
    pub fn ignore_items(&mut self, items: impl IntoIterator<Item = u32>, mode: IgnoredHits) {
        self.ignored_hits = mode;
        self.ignored.clear();
        for i in items {
            if i >= 1 << 24 {
                continue;
            }
            let i = i as usize;
            if i >= self.ignored.len() {
                self.ignored.resize(i + 1, false);
            }
            self.ignored[i] = true;
        }
    }

    /// Number of items set with [`Lidar::ignore_items`].
    ///
    /// ```
    /// use hearth_sim::sensors::{IgnoredHits, Lidar, LidarNoise, LidarSpec};
    /// let mut lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// lidar.ignore_items([4, 7, 7], IgnoredHits::PassThrough);
    /// assert_eq!(lidar.ignored_count(), 2);
    /// lidar.ignore_items([], IgnoredHits::PassThrough);
    /// assert_eq!(lidar.ignored_count(), 0);
    /// ```
    pub fn ignored_count(&self) -> usize {
        self.ignored.iter().filter(|&&b| b).count()
    }

    /// Worker threads a scan may use (rayon's pool of the calling thread; set
    /// `RAYON_NUM_THREADS` to change it).
    ///
    /// ```
    /// assert!(hearth_sim::sensors::Lidar::threads() >= 1);
    /// ```
    pub fn threads() -> usize {
        rayon::current_num_threads()
    }

    /// Sensor-frame unit ray directions (x forward, y left, z up), in ray order.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec};
    /// let spec = LidarSpec::planar(3, std::f64::consts::PI, 0.1, 5.0).unwrap();
    /// let lidar = Lidar::new(spec, LidarNoise::NONE, 3).unwrap();
    /// let d = lidar.directions();
    /// assert!((d[0][1] + 1.0).abs() < 1e-6 && (d[1][0] - 1.0).abs() < 1e-6); // right, then ahead
    /// ```
    pub fn directions(&self) -> &[[f32; 3]] {
        &self.directions
    }

    /// Scans the world as `rays` holds it (call [`RayScene::update`] after each world step)
    /// from `sensor_pose` (world pose of the sensor frame) into `out`, reusing its buffers.
    /// A non-finite pose gives a scan with no returns.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// let mut lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 3).unwrap();
    /// let mut scan = Scan::default();
    /// lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// assert_eq!(scan.len(), 220);
    /// assert!((scan.ranges[110] - 1.95).abs() < 0.01); // straight ahead, at the wall
    /// // A pose that is not finite gives no returns.
    /// lidar.scan(&rays, &Isometry3::translation(f64::NAN, 0.0, 0.5), &mut scan);
    /// assert_eq!(scan.hit_count(), 0);
    /// ```
    pub fn scan(&mut self, rays: &RayScene, sensor_pose: &Isometry3<f64>, out: &mut Scan) {
        self.scan_mapped(rays, &[], sensor_pose, out);
    }

    /// Scans like [`Lidar::scan`], but against a [`CulledRays`] copy of the scene that holds
    /// only the shapes within reach of the sensor (brought up to date from `world` first):
    /// the same ranges, hits and item ids, faster in a large scene. Items set with
    /// [`Lidar::ignore_items`] in [`IgnoredHits::PassThrough`] mode are left out of the copy
    /// altogether.
    ///
    /// ```
    /// use hearth_sim::sensors::{CulledRays, Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("near", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// world.add_box("far", [0.05, 5.0, 1.0], &Isometry3::translation(-50.0, 0.0, 1.0), false).unwrap();
    /// let visuals = VisualScene::from_world(&world);
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 7).unwrap();
    /// let pose = Isometry3::translation(0.0, 0.0, 0.5);
    /// let (mut full, mut culled) = (Scan::default(), Scan::default());
    /// lidar.scan(&rays, &pose, &mut full);
    /// let mut local = CulledRays::default();
    /// lidar.scan_culled(&mut local, &visuals, &world, &pose, &mut culled);
    /// assert_eq!(full.ranges, culled.ranges);
    /// assert_eq!(full.items, culled.items);
    /// assert!(local.len() < visuals.items.len());
    /// ```
    pub fn scan_culled(
        &mut self,
        local: &mut CulledRays,
        visuals: &VisualScene,
        world: &World,
        sensor_pose: &Isometry3<f64>,
        out: &mut Scan,
    ) {
        local.prepare(self, visuals, world, sensor_pose);
        match &local.rays {
            Some(rays) => self.scan_mapped(rays, &local.map, sensor_pose, out),
            None => {
                let empty = RayScene::new(&VisualScene::default());
                self.scan_mapped(&empty, &[], sensor_pose, out);
            }
        }
    }

    fn scan_mapped(&mut self, rays: &RayScene, map: &[u32], sensor_pose: &Isometry3<f64>, out: &mut Scan) {
        let n = self.spec.rays();
        out.ranges.resize(n, 0.0);
        out.hit.resize(n, false);
        out.items.resize(n, NO_ITEM);
        out.horizontal_rays = self.spec.horizontal_rays;
        out.beams = self.spec.beams();
        out.min_range = self.spec.min_range as f32;
        out.max_range = self.spec.max_range as f32;
        out.sensor_pose = *sensor_pose;
        if !Arc::ptr_eq(&out.directions, &self.directions) {
            out.directions = Arc::clone(&self.directions);
        }
        // One draw per scan keys the per-chunk noise streams.
        let scan_key = self.rng.random::<u64>();
        self.scans = self.scans.wrapping_add(1);
        let caster = Caster::new(self, sensor_pose, rays, scan_key, map);
        let dirs = &self.directions[..];
        let chunks = out
            .ranges
            .chunks_mut(CHUNK)
            .zip(out.hit.chunks_mut(CHUNK))
            .zip(out.items.chunks_mut(CHUNK))
            .zip(dirs.chunks(CHUNK));
        if n < PARALLEL_MIN_RAYS || rayon::current_num_threads() < 2 {
            for (k, (((r, h), it), d)) in chunks.enumerate() {
                caster.run(k as u64, d, r, h, it);
            }
        } else {
            out.ranges
                .par_chunks_mut(CHUNK)
                .zip(out.hit.par_chunks_mut(CHUNK))
                .zip(out.items.par_chunks_mut(CHUNK))
                .zip(dirs.par_chunks(CHUNK))
                .enumerate()
                .for_each(|(k, (((r, h), it), d))| caster.run(k as u64, d, r, h, it));
        }
    }
}

/// Everything a chunk of rays needs, shared by the worker threads.
struct Caster<'a> {
    rays: &'a RayScene,
    origin: Vector,
    rot: [[f32; 3]; 3],
    valid: bool,
    min: f32,
    max: f32,
    noise: LidarNoise,
    ignored: &'a [bool],
    ignored_hits: IgnoredHits,
    scan_key: u64,
    /// Item ids of `rays` in the full scene (for a culled scene), or none.
    map: &'a [u32],
}

/// SplitMix64 finaliser: spreads a chunk index over 64 bits.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl<'a> Caster<'a> {
    fn new(lidar: &'a Lidar, pose: &Isometry3<f64>, rays: &'a RayScene, scan_key: u64, map: &'a [u32]) -> Self {
        let t = pose.translation.vector;
        let m = pose.rotation.to_rotation_matrix();
        let m = m.matrix();
        let rot = [0, 1, 2].map(|r| [0, 1, 2].map(|c| m[(r, c)] as f32));
        let valid = t.iter().all(|v| v.is_finite()) && rot.iter().flatten().all(|v| v.is_finite());
        Self {
            rays,
            origin: Vector::new(t.x as f32, t.y as f32, t.z as f32),
            rot,
            valid,
            min: lidar.spec.min_range as f32,
            max: lidar.spec.max_range as f32,
            noise: lidar.noise,
            ignored: &lidar.ignored,
            ignored_hits: lidar.ignored_hits,
            scan_key,
            map,
        }
    }

    /// The full-scene id of item `item` of `rays`.
    fn full_id(&self, item: u32) -> u32 {
        if self.map.is_empty() {
            item
        } else {
            self.map.get(item as usize).copied().unwrap_or(NO_ITEM)
        }
    }

    fn is_ignored(&self, item: u32) -> bool {
        self.ignored.get(item as usize).copied().unwrap_or(false)
    }

    /// First return along world direction `dir`, skipping ignored items.
    fn first_return(&self, dir: Vector) -> Option<(f32, u32)> {
        let mut start = 0.0f32;
        // Each pass steps past one ignored surface (a ray may cross many of a robot's shapes).
        for _ in 0..MAX_PASSES {
            let hit = self.rays.cast(self.origin + dir * start, dir, self.max - start)?;
            let toi = start + hit.toi;
            let item = self.full_id(hit.item);
            if !self.is_ignored(item) {
                return Some((toi, item));
            }
            if self.ignored_hits == IgnoredHits::NoReturn {
                return None;
            }
            start = toi + 1e-4;
            if start >= self.max {
                return None;
            }
        }
        None
    }

    fn run(&self, chunk: u64, dirs: &[[f32; 3]], ranges: &mut [f32], hit: &mut [bool], items: &mut [u32]) {
        let r = &self.rot;
        for (i, d) in dirs.iter().enumerate() {
            let ret = if self.valid {
                let w = Vector::new(
                    r[0][0] * d[0] + r[0][1] * d[1] + r[0][2] * d[2],
                    r[1][0] * d[0] + r[1][1] * d[1] + r[1][2] * d[2],
                    r[2][0] * d[0] + r[2][1] * d[1] + r[2][2] * d[2],
                );
                if self.ignored.is_empty() {
                    self.rays
                        .cast(self.origin, w, self.max)
                        .map(|h| (h.toi, self.full_id(h.item)))
                } else {
                    self.first_return(w)
                }
            } else {
                None
            };
            match ret {
                Some((toi, item)) if toi >= self.min && toi <= self.max => {
                    ranges[i] = toi;
                    hit[i] = true;
                    items[i] = item;
                }
                _ => {
                    ranges[i] = self.max;
                    hit[i] = false;
                    items[i] = NO_ITEM;
                }
            }
        }
        if !self.noise.is_none() {
            self.apply_noise(chunk, ranges, hit, items);
        }
    }

    /// Dropout then Gaussian noise on one chunk, from the chunk's own stream. Every ray draws
    /// the same numbers whether it returned or not, so the noise of a ray depends only on the
    /// seed, the scan and its index.
    fn apply_noise(&self, chunk: u64, ranges: &mut [f32], hit: &mut [bool], items: &mut [u32]) {
        let mut rng = Pcg64Mcg::seed_from_u64(self.scan_key ^ mix(chunk));
        let p = self.noise.dropout;
        let std = self.noise.gaussian_std;
        for i in 0..ranges.len() {
            let dropped = p > 0.0 && rng.random::<f64>() < p;
            let g = if std > 0.0 {
                std * standard_normal(&mut rng)
            } else {
                0.0
            };
            if !hit[i] {
                continue;
            }
            if dropped {
                ranges[i] = self.max;
                hit[i] = false;
                items[i] = NO_ITEM;
            } else if std > 0.0 {
                ranges[i] = (ranges[i] as f64 + g).clamp(0.0, self.max as f64) as f32;
            }
        }
    }
}

/// A copy of the ray scene culled to what a LiDAR can reach: the shapes whose bounding
/// spheres lie within the maximum range (plus a margin) of the sensor and, for a planar
/// scanner, near its scan plane. Used by [`Lidar::scan_culled`], which keeps it up to date:
/// every scan reads the item poses from the world, and the copy is rebuilt when the sensor or
/// any shape has moved by more than half the margin since it was built.
///
/// ```
/// use hearth_sim::sensors::CulledRays;
/// let culled = CulledRays::default();
/// assert!(culled.is_empty() && culled.rebuilds() == 0);
/// ```
#[derive(Debug, Default)]
pub struct CulledRays {
    rays: Option<RayScene>,
    /// Full-scene id of each kept item.
    map: Vec<u32>,
    /// Item-frame bounding box (centre, half extents) of each item of the full scene.
    boxes: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// World poses of every item, read when a body moved.
    poses: Vec<Isometry3<f64>>,
    /// The distinct bodies the items are attached to, and their poses at the last scan.
    bodies: Vec<BodyId>,
    body_poses: Vec<Option<Isometry3<f64>>>,
    /// Whether the items that matter stayed within the margins since the copy was built.
    items_ok: bool,
    /// World poses of the kept items.
    kept_poses: Vec<Isometry3<f64>>,
    /// Item poses when the copy was built.
    built_poses: Vec<Isometry3<f64>>,
    /// Sensor pose when the copy was built.
    built_at: Option<Isometry3<f64>>,
    /// The spec, ignored items and mode the copy was built for.
    built_for: Option<(LidarSpec, Vec<bool>, IgnoredHits)>,
    rebuilds: u64,
}

/// Slack (m) added to the reach of a sensor when culling.
const CULL_MARGIN: f64 = 0.5;

/// Slack (m) added on each side of a planar scanner's scan plane when culling. Wide enough that
/// a wheeled base rocking on its suspension (the plane tilting by a degree at the far end of
/// the range) does not rebuild the copy every step.
const PLANE_MARGIN: f64 = 0.3;

/// Item-frame bounding box of a shape: (centre, half extents).
fn local_box(shape: &super::visuals::VisualShape) -> (Vector3<f64>, Vector3<f64>) {
    use super::visuals::VisualShape;
    let zero = Vector3::zeros();
    match shape {
        VisualShape::Box { half } => (zero, Vector3::new(half[0] as f64, half[1] as f64, half[2] as f64)),
        VisualShape::Sphere { radius } => (zero, Vector3::repeat(*radius as f64)),
        VisualShape::Cylinder { radius, half_length } => {
            let r = *radius as f64;
            (zero, Vector3::new(r, r, *half_length as f64))
        }
        VisualShape::Capsule { radius, half_length } => {
            let r = *radius as f64;
            (zero, Vector3::new(r, r, r + *half_length as f64))
        }
        VisualShape::Mesh(m) => {
            let mut lo = Vector3::repeat(f64::INFINITY);
            let mut hi = Vector3::repeat(f64::NEG_INFINITY);
            for v in &m.vertices {
                let v = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                lo = lo.inf(&v);
                hi = hi.sup(&v);
            }
            if lo.x > hi.x {
                (zero, zero)
            } else {
                ((lo + hi) / 2.0, (hi - lo) / 2.0)
            }
        }
    }
}

impl CulledRays {
    /// Number of shapes kept.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// use hearth_sim::sensors::CulledRays;
    /// let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 3).unwrap();
    /// let (mut local, mut scan) = (CulledRays::default(), Scan::default());
    /// assert_eq!(local.len(), 0);
    /// lidar.scan_culled(&mut local, &visuals, &world, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// assert!(local.len() >= 1 && local.len() <= visuals.items.len());
    /// ```
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// Whether no shape is kept.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// use hearth_sim::sensors::CulledRays;
    /// let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 3).unwrap();
    /// let (mut local, mut scan) = (CulledRays::default(), Scan::default());
    /// assert!(local.is_empty());
    /// lidar.scan_culled(&mut local, &visuals, &world, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    /// assert!(!local.is_empty()); // the wall is within reach
    /// ```
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// How many times the copy has been built.
    ///
    /// ```
    /// # use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(2.0, 0.0, 1.0), false).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// # let mut rays = RayScene::new(&visuals);
    /// # rays.update(&visuals, &world);
    /// use hearth_sim::sensors::CulledRays;
    /// let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 3).unwrap();
    /// let (mut local, mut scan) = (CulledRays::default(), Scan::default());
    /// let pose = Isometry3::translation(0.0, 0.0, 0.5);
    /// lidar.scan_culled(&mut local, &visuals, &world, &pose, &mut scan);
    /// lidar.scan_culled(&mut local, &visuals, &world, &pose, &mut scan);
    /// assert_eq!(local.rebuilds(), 1); // nothing moved: the copy is reused
    /// ```
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    fn prepare(&mut self, lidar: &Lidar, visuals: &VisualScene, world: &World, sensor: &Isometry3<f64>) {
        if self.boxes.len() != visuals.items.len() {
            self.boxes = visuals.items.iter().map(|i| local_box(&i.shape)).collect();
            let mut seen = std::collections::HashSet::new();
            self.bodies = visuals
                .items
                .iter()
                .filter_map(|i| i.body)
                .filter(|h| seen.insert(*h))
                .map(BodyId::from_handle)
                .collect();
            self.body_poses.clear();
            self.built_at = None;
            self.poses.clear();
        }
        // Item poses change only when a body moves: compare the bodies' poses first.
        let mut moved = self.poses.len() != visuals.items.len() || self.body_poses.len() != self.bodies.len();
        self.body_poses.resize(self.bodies.len(), None);
        for (b, last) in self.bodies.iter().zip(self.body_poses.iter_mut()) {
            let now = world.body_pose(*b).ok();
            if now != *last {
                *last = now;
                moved = true;
            }
        }
        let spec = &lidar.spec;
        let planar = spec.elevations.iter().all(|e| e.abs() < 1e-12);
        if moved {
            visuals.world_poses_into(world, &mut self.poses);
            self.items_ok = self.items_stayed(lidar, planar);
        }
        let same_sensor = self
            .built_for
            .as_ref()
            .is_some_and(|(s, ig, mode)| s == spec && *ig == lidar.ignored && *mode == lidar.ignored_hits);
        let still_valid = same_sensor
            && self.items_ok
            && self.built_at.is_some_and(|b| {
                let normal = b.rotation * Vector3::z();
                let moved = sensor.translation.vector - b.translation.vector;
                // How far the scan plane tilts at the far end of the range (a turn about the
                // plane's own normal, a yaw for a level scanner, keeps the plane).
                let tilt = normal.angle(&(sensor.rotation * Vector3::z())) * spec.max_range;
                moved.norm() <= CULL_MARGIN / 2.0 && (!planar || moved.dot(&normal).abs() + tilt <= PLANE_MARGIN / 2.0)
            });
        let rebuilt = !still_valid;
        if rebuilt {
            self.rebuild(lidar, visuals, sensor);
            self.items_ok = true;
        }
        // Nothing moved since the last scan: the copy is up to date.
        if let Some(rays) = &mut self.rays
            && (rebuilt || moved)
        {
            self.kept_poses.clear();
            self.kept_poses.extend(self.map.iter().map(|&i| self.poses[i as usize]));
            rays.update_from_poses(&self.kept_poses);
        }
    }

    /// Whether every item that matters is where it was (within the margins) when the copy was
    /// built.
    fn items_stayed(&self, lidar: &Lidar, planar: bool) -> bool {
        let Some(b) = self.built_at else { return false };
        if self.built_poses.len() != self.poses.len() {
            return false;
        }
        let normal = b.rotation * Vector3::z();
        let pass = lidar.ignored_hits == IgnoredHits::PassThrough;
        self.poses.iter().zip(&self.built_poses).enumerate().all(|(i, (p, q))| {
            if p == q || (pass && lidar.ignored.get(i).copied().unwrap_or(false)) {
                return true;
            }
            let moved = p.translation.vector - q.translation.vector;
            let turn = p.rotation.angle_to(&q.rotation) * (self.boxes[i].0.norm() + self.boxes[i].1.norm());
            moved.norm() + turn <= CULL_MARGIN / 2.0
                && (!planar || moved.dot(&normal).abs() + turn <= PLANE_MARGIN / 2.0)
        })
    }

    fn rebuild(&mut self, lidar: &Lidar, visuals: &VisualScene, sensor: &Isometry3<f64>) {
        let spec = &lidar.spec;
        let origin = sensor.translation.vector;
        let normal = sensor.rotation * Vector3::z();
        let planar = spec.elevations.iter().all(|e| e.abs() < 1e-12);
        let reach = spec.max_range + CULL_MARGIN;
        let pass = lidar.ignored_hits == IgnoredHits::PassThrough;
        self.map.clear();
        for (i, pose) in self.poses.iter().enumerate() {
            if pass && lidar.ignored.get(i).copied().unwrap_or(false) {
                continue;
            }
            let (c, e) = &self.boxes[i];
            if !e.iter().all(|v| v.is_finite()) {
                self.map.push(i as u32);
                continue;
            }
            let d = pose * Point3::from(*c) - Point3::from(origin);
            if d.norm() > reach + e.norm() {
                continue;
            }
            if planar {
                // Half the box's thickness along the scan plane's normal.
                let n_local = pose.rotation.inverse() * normal;
                let half = n_local.x.abs() * e.x + n_local.y.abs() * e.y + n_local.z.abs() * e.z;
                if d.dot(&normal).abs() > half + PLANE_MARGIN {
                    continue;
                }
            }
            self.map.push(i as u32);
        }
        self.built_poses.clone_from(&self.poses);
        self.built_at = Some(*sensor);
        self.built_for = Some((spec.clone(), lidar.ignored.clone(), lidar.ignored_hits));
        self.rebuilds += 1;
        let sub = VisualScene {
            items: self.map.iter().map(|&i| visuals.items[i as usize].clone()).collect(),
            instances: Vec::new(),
            lights: Vec::new(),
        };
        self.rays = Some(RayScene::new(&sub));
    }
}

/// A standard normal sample (Box–Muller, one of the pair).
fn standard_normal(rng: &mut Pcg64Mcg) -> f64 {
    // u1 in (0, 1]: avoids ln(0).
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The [`VisualScene`] items that belong to model `robot` (for [`Lidar::ignore_items`]).
///
/// # Errors
/// [`SensorError::World`] for an unknown model.
///
/// ```
/// use hearth_sim::kinematics::RobotModel;
/// use hearth_sim::sensors::{VisualScene, lidar_pose_in_base, model_items};
/// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// let bot = RobotModel::builtin("turtlebot").unwrap();
/// let bot = world.spawn_model(&bot, &nalgebra::Isometry3::identity(), SpawnOptions::free()).unwrap();
/// let visuals = VisualScene::from_world(&world);
/// let items = model_items(&visuals, &world, bot).unwrap();
/// assert!(!items.is_empty());
/// assert!(!items.contains(&0)); // item 0 is the ground
/// ```
pub fn model_items(visuals: &VisualScene, world: &World, robot: ModelHandle) -> SensorResult<Vec<u32>> {
    let name = world.model_name(robot)?;
    Ok(visuals
        .items
        .iter()
        .enumerate()
        .filter(|(_, it)| {
            visuals
                .instances
                .get((it.instance as usize).wrapping_sub(1))
                .is_some_and(|inst| inst.name == name)
        })
        .map(|(i, _)| i as u32)
        .collect())
}

/// The name of the laser link of `robot`: `link` when given, else the robot's default
/// ([`Mount::default_lidar`]).
fn laser_link(world: &World, robot: ModelHandle, link: Option<&str>) -> SensorResult<String> {
    if let Some(l) = link {
        return Ok(l.to_owned());
    }
    let model = world.model(robot)?.name().to_owned();
    match Mount::default_lidar(&model) {
        Some(Mount::Link { link, .. }) => Ok(link),
        _ => Err(SensorError::NoDefaultMount {
            robot: model,
            sensor: "LiDAR",
        }),
    }
}

/// World pose of the laser link of `robot` in its own body frame (x forward, y left, z up as
/// the link defines it): `link`, or the robot's default laser link when `None`.
///
/// ```
/// use hearth_sim::scene::{GenerateOptions, generate};
/// use hearth_sim::sensors::lidar_pose;
/// use hearth_sim::world::{World, WorldConfig};
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// let loaded = world.load_scene(&generate(&GenerateOptions { seed: 1, rooms: 2, ..Default::default() }).unwrap()).unwrap();
/// let fetch = loaded.robot.unwrap();
/// let pose = lidar_pose(&world, fetch, None).unwrap();
/// let base = world.base_pose(fetch).unwrap();
/// assert!(pose.translation.z > base.translation.z + 0.2);
/// assert!(lidar_pose(&world, fetch, Some("no_such_link")).is_err());
/// ```
///
/// # Errors
/// [`SensorError::NoDefaultMount`] when `link` is `None` and the robot has no default laser
/// link, [`SensorError::NoSuchLink`] when it lacks the link, [`SensorError::World`] for an
/// unknown robot.
pub fn lidar_pose(world: &World, robot: ModelHandle, link: Option<&str>) -> SensorResult<Isometry3<f64>> {
    let link = laser_link(world, robot, link)?;
    let name = world.model_name(robot)?.to_owned();
    world.link_pose(robot, &link).map_err(|_| SensorError::NoSuchLink {
        robot: name,
        link,
        sensor: "LiDAR",
    })
}

/// Pose of the laser link in the robot's base frame (what [`OccupancyGrid`] needs), as
/// [`lidar_pose`].
///
/// [`OccupancyGrid`]: crate::sensors::OccupancyGrid
///
/// # Errors
/// As [`lidar_pose`].
///
/// ```
/// use hearth_sim::kinematics::RobotModel;
/// use hearth_sim::sensors::{VisualScene, lidar_pose_in_base, model_items};
/// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// let bot = RobotModel::builtin("turtlebot").unwrap();
/// let bot = world.spawn_model(&bot, &nalgebra::Isometry3::identity(), SpawnOptions::free()).unwrap();
/// let pose = lidar_pose_in_base(&world, bot, None).unwrap();
/// assert!(pose.translation.z > 0.0); // the laser sits above the base frame
/// assert!(lidar_pose_in_base(&world, bot, Some("no_such_link")).is_err());
/// ```
pub fn lidar_pose_in_base(world: &World, robot: ModelHandle, link: Option<&str>) -> SensorResult<Isometry3<f64>> {
    let sensor = lidar_pose(world, robot, link)?;
    let base = world.base_pose(robot)?;
    Ok(base.inverse() * sensor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_unit_and_ordered_beam_major() {
        let s = LidarSpec::velodyne_vlp16(2.0).unwrap();
        assert_eq!(s.horizontal_rays, 180);
        for i in [0, 179, 180, 2879] {
            assert!((s.direction(i).norm() - 1.0).abs() < 1e-12);
        }
        assert!(s.direction(0).z < 0.0 && s.direction(2879).z > 0.0);
        assert!((s.azimuth(0) + std::f64::consts::PI).abs() < 1e-12);
        assert!((s.azimuth(90)).abs() < 1e-12);
    }

    #[test]
    fn normal_samples_have_unit_variance() {
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let n = 20000;
        let xs: Vec<f64> = (0..n).map(|_| standard_normal(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03 && (var - 1.0).abs() < 0.05, "{mean} {var}");
    }
}
