//! [`OccupancyGrid`]: a robot-centred local occupancy grid from a planar LiDAR scan, as iGibson's
//! `occupancy_grid` observation.
//!
//! # Layout and values
//! - The grid is `size × size` cells of `resolution` metres, stored row-major (`row * size +
//!   col`), aligned with the robot's **base frame** and centred on its origin: the base origin
//!   sits at the continuous cell coordinate `(size / 2, size / 2)`.
//! - It reads as an image with the robot looking **up**: row 0 is the farthest ahead (base +x
//!   decreases with the row), and column 0 is the farthest to the left (base +y decreases
//!   with the column). For a point `(x, y)` in the base frame,
//!   `row = floor(size/2 − x/resolution)`, `col = floor(size/2 − y/resolution)`
//!   ([`OccupancyGrid::cell_of`]).
//! - Cells hold [`OCCUPIED`] (0), [`UNKNOWN`] (1) or [`FREE`] (2); halved, these are iGibson's
//!   float convention (0.0 occupied, 0.5 unknown, 1.0 free): see
//!   [`OccupancyGrid::to_f32_into`].
//!
//! # How a scan fills it
//! Every cell starts unknown. Each ray is traced (Bresenham) in the grid's xy plane from the
//! sensor's cell to its end point's cell; the cells before the end are free. A ray that
//! returned marks its end cell occupied; a ray with no return (it reads the maximum range)
//! marks its whole length free when [`OccupancyGridSpec::no_return_is_free`] is set (as
//! iGibson does), and nothing otherwise. Then the robot footprint, a disc of
//! [`OccupancyGridSpec::footprint_radius`] around the base origin, is marked free, and the
//! occupied cells are marked last so that no other ray clears them.

use nalgebra::{Isometry3, Point3};

use super::error::{SensorError, SensorResult, check_param};
use super::lidar::Scan;

/// A cell seen occupied.
///
/// ```
/// use hearth_sim::sensors::{FREE, OCCUPIED, UNKNOWN};
/// assert!(OCCUPIED < UNKNOWN && UNKNOWN < FREE);
/// assert_eq!(OCCUPIED as f32 * 0.5, 0.0); // iGibson's float value
/// ```
pub const OCCUPIED: u8 = 0;
/// A cell not seen.
///
/// ```
/// use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, UNKNOWN};
/// let grid = OccupancyGrid::new(OccupancyGridSpec::default()).unwrap();
/// assert_eq!(grid.count(UNKNOWN), 128 * 128); // a new grid has seen nothing
/// ```
pub const UNKNOWN: u8 = 1;
/// A cell seen free.
///
/// ```
/// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
/// # use nalgebra::Isometry3;
/// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
/// let mut grid = OccupancyGrid::new(spec).unwrap();
/// grid.update(&Scan::default(), &Isometry3::identity()).unwrap();
/// assert_eq!(grid.at(0.0, 0.0), Some(FREE)); // the robot's footprint
/// ```
pub const FREE: u8 = 2;

/// Largest grid side in cells.
///
/// ```
/// use hearth_sim::sensors::{MAX_GRID_SIDE, OccupancyGridSpec};
/// let spec = OccupancyGridSpec { size: MAX_GRID_SIDE + 1, ..Default::default() };
/// assert!(spec.validate().is_err());
/// ```
pub const MAX_GRID_SIDE: usize = 8192;

/// Size, resolution and footprint of an [`OccupancyGrid`].
///
/// ```
/// use hearth_sim::sensors::OccupancyGridSpec;
/// let s = OccupancyGridSpec::default();
/// assert_eq!(s.size, 128);
/// assert!((s.extent() - 5.0).abs() < 1e-12);
/// assert!(OccupancyGridSpec { size: 0, ..s }.validate().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OccupancyGridSpec {
    /// Cells per side.
    pub size: usize,
    /// Cell side in metres.
    pub resolution: f64,
    /// Radius (m) of the disc around the base origin marked free.
    pub footprint_radius: f64,
    /// Whether rays with no return mark their whole length (to the maximum range) free.
    pub no_return_is_free: bool,
}

impl Default for OccupancyGridSpec {
    /// iGibson's defaults: 128 cells over 5 m (0.0390625 m per cell), footprint radius 0.32 m
    /// (the Fetch's).
    fn default() -> Self {
        Self {
            size: 128,
            resolution: 5.0 / 128.0,
            footprint_radius: 0.32,
            no_return_is_free: true,
        }
    }
}

impl OccupancyGridSpec {
    /// Side length of the grid in metres.
    ///
    /// ```
    /// use hearth_sim::sensors::OccupancyGridSpec;
    /// let spec = OccupancyGridSpec { size: 40, resolution: 0.05, ..Default::default() };
    /// assert!((spec.extent() - 2.0).abs() < 1e-12);
    /// ```
    pub fn extent(&self) -> f64 {
        self.size as f64 * self.resolution
    }

    /// Checks the size, resolution and radius.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a size outside `1..=`[`MAX_GRID_SIDE`], a
    /// resolution outside `[1e-4, 1e3]` m or a footprint radius outside `[0, 1e3]` m.
    ///
    /// ```
    /// use hearth_sim::sensors::{OccupancyGridSpec, SensorError};
    /// let spec = OccupancyGridSpec { resolution: 0.0, ..Default::default() };
    /// assert!(matches!(spec.validate(), Err(SensorError::InvalidParameter { name: "resolution", .. })));
    /// assert!(OccupancyGridSpec::default().validate().is_ok());
    /// ```
    pub fn validate(&self) -> SensorResult<()> {
        if self.size == 0 || self.size > MAX_GRID_SIDE {
            return Err(SensorError::InvalidParameter {
                name: "size",
                value: self.size as f64,
                reason: "must be in 1..=8192 cells",
            });
        }
        check_param(
            "resolution",
            self.resolution,
            1e-4,
            1e3,
            "must be in [1e-4, 1e3] m per cell",
        )?;
        check_param(
            "footprint_radius",
            self.footprint_radius,
            0.0,
            1e3,
            "must be in [0, 1e3] m",
        )?;
        Ok(())
    }
}

/// A local occupancy grid around a robot (see the [module docs](self) for the layout).
///
/// ```
/// use hearth_sim::sensors::{
///     FREE, Lidar, LidarNoise, LidarSpec, OCCUPIED, OccupancyGrid, OccupancyGridSpec, RayScene, Scan, UNKNOWN,
///     VisualScene,
/// };
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(1.5, 0.0, 1.0), false).unwrap();
/// let visuals = VisualScene::from_world(&world);
/// let mut rays = RayScene::new(&visuals);
/// rays.update(&visuals, &world);
/// let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 0).unwrap();
/// let mut scan = Scan::default();
/// let sensor_in_base = Isometry3::translation(0.0, 0.0, 0.3);
/// lidar.scan(&rays, &sensor_in_base, &mut scan); // base at the world origin
/// let mut grid = OccupancyGrid::new(OccupancyGridSpec::default()).unwrap();
/// grid.update(&scan, &sensor_in_base).unwrap();
/// assert_eq!(grid.at(1.46, 0.0), Some(OCCUPIED));
/// assert_eq!(grid.at(0.8, 0.0), Some(FREE));
/// assert_eq!(grid.at(2.2, 0.0), Some(UNKNOWN));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyGrid {
    spec: OccupancyGridSpec,
    cells: Vec<u8>,
    /// Reused buffer of occupied end cells.
    ends: Vec<(usize, usize)>,
}

impl OccupancyGrid {
    /// An all-unknown grid.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] as [`OccupancyGridSpec::validate`].
    ///
    /// ```
    /// use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, UNKNOWN};
    /// let grid = OccupancyGrid::new(OccupancyGridSpec { size: 8, ..Default::default() }).unwrap();
    /// assert!(grid.cells().iter().all(|&c| c == UNKNOWN));
    /// assert!(OccupancyGrid::new(OccupancyGridSpec { footprint_radius: -1.0, ..Default::default() }).is_err());
    /// ```
    pub fn new(spec: OccupancyGridSpec) -> SensorResult<Self> {
        spec.validate()?;
        Ok(Self {
            spec,
            cells: vec![UNKNOWN; spec.size * spec.size],
            ends: Vec::new(),
        })
    }

    /// The spec.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// assert_eq!(grid.spec(), &spec);
    /// ```
    pub fn spec(&self) -> &OccupancyGridSpec {
        &self.spec
    }

    /// Cells per side.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// assert_eq!(grid.size(), 10);
    /// ```
    pub fn size(&self) -> usize {
        self.spec.size
    }

    /// The cells, row-major.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// assert_eq!(grid.cells().len(), 10 * 10);
    /// ```
    pub fn cells(&self) -> &[u8] {
        &self.cells
    }

    /// The value of cell `(row, col)`, if inside.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// assert_eq!(grid.get(9, 9), Some(UNKNOWN));
    /// assert_eq!(grid.get(10, 0), None);
    /// ```
    pub fn get(&self, row: usize, col: usize) -> Option<u8> {
        (row < self.spec.size && col < self.spec.size).then(|| self.cells[row * self.spec.size + col])
    }

    /// The cell holding the base-frame point `(x, y)`, if inside the grid.
    ///
    /// ```
    /// use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec};
    /// let g = OccupancyGrid::new(OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() }).unwrap();
    /// assert_eq!(g.cell_of(0.01, 0.01), Some((4, 4))); // just ahead and to the left of the centre
    /// assert_eq!(g.cell_of(0.45, -0.45), Some((0, 9)));
    /// assert_eq!(g.cell_of(0.6, 0.0), None);
    /// ```
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let (r, c) = self.continuous(x, y);
        let n = self.spec.size as f64;
        (r >= 0.0 && r < n && c >= 0.0 && c < n).then_some((r as usize, c as usize))
    }

    /// The base-frame `(x, y)` of the centre of cell `(row, col)`.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// let (x, y) = grid.cell_center(0, 9); // ahead and to the right
    /// assert!((x - 0.45).abs() < 1e-12 && (y + 0.45).abs() < 1e-12);
    /// assert_eq!(grid.cell_of(x, y), Some((0, 9)));
    /// ```
    pub fn cell_center(&self, row: usize, col: usize) -> (f64, f64) {
        let h = self.spec.size as f64 / 2.0;
        let res = self.spec.resolution;
        ((h - row as f64 - 0.5) * res, (h - col as f64 - 0.5) * res)
    }

    /// The value at the base-frame point `(x, y)`, if inside the grid.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// grid.update(&Scan::default(), &Isometry3::identity()).unwrap();
    /// assert_eq!(grid.at(0.05, 0.05), Some(FREE)); // within the footprint
    /// assert_eq!(grid.at(0.45, 0.45), Some(UNKNOWN));
    /// assert_eq!(grid.at(1.0, 0.0), None); // outside the 1 m grid
    /// ```
    pub fn at(&self, x: f64, y: f64) -> Option<u8> {
        self.cell_of(x, y).and_then(|(r, c)| self.get(r, c))
    }

    /// Number of cells holding `value`.
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// grid.update(&Scan::default(), &Isometry3::identity()).unwrap();
    /// let free = grid.count(FREE);
    /// assert!(free > 0 && free + grid.count(UNKNOWN) == 100);
    /// ```
    pub fn count(&self, value: u8) -> usize {
        self.cells.iter().filter(|&&v| v == value).count()
    }

    /// The cells in iGibson's float convention (0.0 occupied, 0.5 unknown, 1.0 free),
    /// row-major, into `out` (cleared first).
    ///
    /// ```
    /// # use hearth_sim::sensors::{OccupancyGrid, OccupancyGridSpec, Scan, FREE, UNKNOWN};
    /// # use nalgebra::Isometry3;
    /// let spec = OccupancyGridSpec { size: 10, resolution: 0.1, ..Default::default() };
    /// let mut grid = OccupancyGrid::new(spec).unwrap();
    /// let mut out = Vec::new();
    /// grid.to_f32_into(&mut out);
    /// assert_eq!(out.len(), 100);
    /// assert!(out.iter().all(|&v| v == 0.5)); // all unknown
    /// ```
    pub fn to_f32_into(&self, out: &mut Vec<f32>) {
        out.clear();
        out.extend(self.cells.iter().map(|&v| v as f32 * 0.5));
    }

    /// Continuous (row, col) of a base-frame point.
    fn continuous(&self, x: f64, y: f64) -> (f64, f64) {
        let h = self.spec.size as f64 / 2.0;
        (h - x / self.spec.resolution, h - y / self.spec.resolution)
    }

    /// Rebuilds the grid from a 1-beam `scan` taken by a sensor at `sensor_in_base` (the
    /// sensor frame's pose in the robot's base frame, e.g. from
    /// [`lidar_pose_in_base`](crate::sensors::lidar_pose_in_base)). Ray end points are
    /// projected onto the base xy plane.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when the scan has more than one beam or the pose is
    /// not finite; the grid is unchanged.
    ///
    /// ```
    /// use hearth_sim::sensors::{Lidar, LidarNoise, LidarSpec, OccupancyGrid, OccupancyGridSpec, RayScene, Scan};
    /// use hearth_sim::sensors::{FREE, OCCUPIED, VisualScene};
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(1.0, 0.0, 1.0), false).unwrap();
    /// let visuals = VisualScene::from_world(&world);
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// let spec = LidarSpec::planar(31, std::f64::consts::FRAC_PI_2, 0.05, 5.0).unwrap();
    /// let mut lidar = Lidar::new(spec, LidarNoise::NONE, 0).unwrap();
    /// let (mut scan, sensor_in_base) = (Scan::default(), Isometry3::translation(0.0, 0.0, 0.3));
    /// lidar.scan(&rays, &sensor_in_base, &mut scan); // base at the world origin
    /// let mut grid = OccupancyGrid::new(OccupancyGridSpec { size: 32, resolution: 0.1, ..Default::default() }).unwrap();
    /// grid.update(&scan, &sensor_in_base).unwrap();
    /// assert_eq!(grid.at(0.96, 0.0), Some(OCCUPIED));
    /// assert_eq!(grid.at(0.5, 0.0), Some(FREE));
    /// scan.beams = 2; // the grid takes planar scans only
    /// assert!(grid.update(&scan, &sensor_in_base).is_err());
    /// ```
    pub fn update(&mut self, scan: &Scan, sensor_in_base: &Isometry3<f64>) -> SensorResult<()> {
        if scan.beams > 1 {
            return Err(SensorError::InvalidParameter {
                name: "beams",
                value: scan.beams as f64,
                reason: "the occupancy grid needs a 1-beam (planar) scan",
            });
        }
        let t = sensor_in_base.translation.vector;
        let q = sensor_in_base.rotation.coords;
        if !(t.iter().all(|v| v.is_finite()) && q.iter().all(|v| v.is_finite())) {
            return Err(SensorError::InvalidParameter {
                name: "sensor_in_base",
                value: f64::NAN,
                reason: "the sensor pose must be finite",
            });
        }
        self.cells.fill(UNKNOWN);
        self.ends.clear();
        let n = self.spec.size;
        let (r0, c0) = self.continuous(t.x, t.y);
        for i in 0..scan.len() {
            let (Some(d), Some(&range)) = (scan.direction(i), scan.ranges.get(i)) else {
                continue;
            };
            let hit = scan.hit.get(i).copied().unwrap_or(false);
            if !hit && !self.spec.no_return_is_free {
                continue;
            }
            if !range.is_finite() {
                continue;
            }
            let local = Point3::new(d.x as f64, d.y as f64, d.z as f64) * range as f64;
            let p = sensor_in_base * local;
            let (r1, c1) = self.continuous(p.x, p.y);
            trace_free(&mut self.cells, n, (r0, c0), (r1, c1));
            if hit && let Some(cell) = self.cell_of(p.x, p.y) {
                self.ends.push(cell);
            }
        }
        // The footprint disc around the base origin.
        let rad = self.spec.footprint_radius / self.spec.resolution;
        let h = n as f64 / 2.0;
        let lo = (h - rad).floor().max(0.0) as usize;
        let hi = ((h + rad).ceil().max(0.0) as usize).min(n);
        for row in lo..hi {
            for col in lo..hi {
                let dr = row as f64 + 0.5 - h;
                let dc = col as f64 + 0.5 - h;
                if dr * dr + dc * dc <= rad * rad {
                    self.cells[row * n + col] = FREE;
                }
            }
        }
        for &(r, c) in &self.ends {
            self.cells[r * n + c] = OCCUPIED;
        }
        Ok(())
    }
}

/// Marks free the cells from `a` up to (not including) `b`, continuous (row, col) coordinates,
/// clipped to the grid.
fn trace_free(cells: &mut [u8], n: usize, a: (f64, f64), b: (f64, f64)) {
    let Some((ca, cb)) = clip(n as f64, a, b) else {
        return;
    };
    let cell = |p: (f64, f64)| -> (i64, i64) {
        let m = n as i64 - 1;
        ((p.0.floor() as i64).clamp(0, m), (p.1.floor() as i64).clamp(0, m))
    };
    let (mut r, mut c) = cell(ca);
    let (r1, c1) = cell(cb);
    // Whether the segment was cut short by the grid edge: then its last cell is free too.
    let end_inside = cb == b;
    let dr = (r1 - r).abs();
    let dc = -(c1 - c).abs();
    let sr = if r < r1 { 1 } else { -1 };
    let sc = if c < c1 { 1 } else { -1 };
    let mut err = dr + dc;
    loop {
        let last = r == r1 && c == c1;
        if last && end_inside {
            break;
        }
        cells[r as usize * n + c as usize] = FREE;
        if last {
            break;
        }
        let e2 = 2 * err;
        if e2 >= dc {
            err += dc;
            r += sr;
        }
        if e2 <= dr {
            err += dr;
            c += sc;
        }
    }
}

/// Clips the segment `a`–`b` to the square `[0, n]²` (Liang–Barsky); `None` when it misses.
fn clip(n: f64, a: (f64, f64), b: (f64, f64)) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, a.0), (dx, n - a.0), (-dy, a.1), (dy, n - a.1)] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
    Some((if t0 == 0.0 { a } else { at(t0) }, if t1 == 1.0 { b } else { at(t1) }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_inside_segments_and_cuts_outside_ones() {
        assert_eq!(clip(10.0, (1.0, 1.0), (2.0, 3.0)), Some(((1.0, 1.0), (2.0, 3.0))));
        let (_, b) = clip(10.0, (5.0, 5.0), (5.0, 25.0)).unwrap();
        assert!((b.1 - 10.0).abs() < 1e-12);
        assert!(clip(10.0, (-5.0, -5.0), (-1.0, 20.0)).is_none());
    }

    #[test]
    fn traces_stop_before_the_end_cell() {
        let mut cells = vec![UNKNOWN; 100];
        trace_free(&mut cells, 10, (5.5, 5.5), (5.5, 9.5));
        assert_eq!(&cells[50..60], &[1, 1, 1, 1, 1, 2, 2, 2, 2, 1]);
        let mut cells = vec![UNKNOWN; 100];
        trace_free(&mut cells, 10, (5.5, 5.5), (5.5, 19.5));
        assert_eq!(&cells[50..60], &[1, 1, 1, 1, 1, 2, 2, 2, 2, 2]);
    }
}
