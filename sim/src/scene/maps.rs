//! Traversability and room-segmentation grids of a scene, and shortest paths on them.
//!
//! A cell is an obstacle when something between the floor clearance and the robot height
//! stands on it: a solid piece of wall (doorways cut out, windows not) or an object's
//! footprint. Doors are ignored (treated as open) and rugs are flat. Cells outside every room
//! are obstacles too. The free space is then eroded by the robot radius, so a cell is
//! traversable when a disc robot centred there touches nothing.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::footprint::Footprint;
use super::{SceneError, SceneFile};
use crate::assets::{Category, Placement};

/// Largest grid [`SceneMaps::build`] makes (cells).
const MAX_CELLS: f64 = 16e6;

/// Settings of [`SceneMaps::build`].
///
/// ```
/// let o = hearth_sim::scene::MapOptions::default();
/// assert_eq!((o.resolution, o.robot_radius), (0.05, 0.3));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapOptions {
    /// Cell size, metres.
    pub resolution: f64,
    /// Robot radius used to erode the free space, metres.
    pub robot_radius: f64,
    /// Robot height: things entirely above it do not block, metres.
    pub robot_height: f64,
    /// Things entirely below this height (rugs, thresholds) do not block, metres.
    pub floor_clearance: f64,
}

impl Default for MapOptions {
    fn default() -> Self {
        MapOptions {
            resolution: 0.05,
            robot_radius: 0.3,
            robot_height: 1.2,
            floor_clearance: 0.03,
        }
    }
}

/// The grids of a scene: obstacles, traversable cells and the room of each cell.
///
/// ```
/// use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
/// let home = generate(&GenerateOptions { seed: 2, rooms: 3, ..Default::default() }).unwrap();
/// let maps = SceneMaps::build(&home, &MapOptions::default()).unwrap();
/// let a = home.building.rooms[0].center();
/// let b = home.building.rooms[1].center();
/// let path = maps.shortest_path(a, b).unwrap();
/// assert_eq!(path.first(), Some(&a));
/// assert_eq!(path.last(), Some(&b));
/// ```
#[derive(Clone, Debug)]
pub struct SceneMaps {
    /// World coordinates of the lower corner of cell (0, 0).
    pub origin: [f64; 2],
    /// Cell size, metres.
    pub resolution: f64,
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    /// Obstacle cells before erosion, row-major (`iy * width + ix`).
    pub obstacle: Vec<bool>,
    /// Cells where the robot's centre may be, row-major.
    pub traversable: Vec<bool>,
    /// Index into `room_names` of each cell's room, or `None` outside every room.
    pub room_id: Vec<Option<u16>>,
    /// Room names, in the scene's order.
    pub room_names: Vec<String>,
}

impl SceneMaps {
    /// Rasterises a scene (validating it first).
    ///
    /// ```
    /// use hearth_sim::scene::{MapOptions, SceneFile, SceneMaps};
    /// let empty = SceneFile::empty("nothing");
    /// let maps = SceneMaps::build(&empty, &MapOptions::default()).unwrap();
    /// assert!(maps.traversable.iter().all(|t| !t));
    /// ```
    pub fn build(scene: &SceneFile, opts: &MapOptions) -> Result<SceneMaps, SceneError> {
        if !(opts.resolution.is_finite() && opts.resolution >= 0.005) {
            return Err(SceneError::invalid(
                "resolution",
                format!("{} is not a finite size ≥ 0.005 m", opts.resolution),
            ));
        }
        if !(opts.robot_radius.is_finite() && (0.0..=5.0).contains(&opts.robot_radius)) {
            return Err(SceneError::invalid(
                "robot_radius",
                format!("{} is not a size in [0, 5] m", opts.robot_radius),
            ));
        }
        let assets = scene.assets()?;
        let rooms = &scene.building.rooms;
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for r in rooms {
            let (a, b) = r.bounds();
            for k in 0..2 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
        if rooms.is_empty() {
            lo = [0.0; 2];
            hi = [opts.resolution; 2];
        }
        let res = opts.resolution;
        let origin = [lo[0] - res, lo[1] - res];
        let cells = |span: f64| (span / res).ceil() + 2.0;
        let (w, h) = (cells(hi[0] - lo[0]), cells(hi[1] - lo[1]));
        if w * h > MAX_CELLS {
            return Err(SceneError::invalid(
                "resolution",
                format!("a {w} × {h} grid is too large (more than {MAX_CELLS} cells); use coarser cells"),
            ));
        }
        let (width, height) = (w as usize, h as usize);
        let mut maps = SceneMaps {
            origin,
            resolution: res,
            width,
            height,
            obstacle: vec![true; width * height],
            traversable: vec![false; width * height],
            room_id: vec![None; width * height],
            room_names: rooms.iter().map(|r| r.name.clone()).collect(),
        };
        for iy in 0..height {
            for ix in 0..width {
                let p = maps.cell_center(ix, iy);
                if let Some(k) = rooms.iter().position(|r| r.contains(p)) {
                    let i = iy * width + ix;
                    maps.room_id[i] = Some(k.min(u16::MAX as usize) as u16);
                    maps.obstacle[i] = false;
                }
            }
        }
        let band = [opts.floor_clearance, opts.robot_height];
        let blocks = |f: &Footprint| f.z[1] > band[0] && f.z[0] < band[1];
        for wall in &scene.building.walls {
            for piece in wall.pieces() {
                let f = Footprint::of_wall_piece(wall, piece);
                if blocks(&f) {
                    maps.stamp(&f);
                }
            }
        }
        for (o, a) in scene.objects.iter().zip(&assets) {
            if a.category == Category::Door || a.category.placement() == Placement::FloorCovering {
                continue;
            }
            let f = Footprint::of_box(&o.pose(), &a.aabb_min, &a.aabb_max);
            if blocks(&f) {
                maps.stamp(&f);
            }
        }
        maps.erode(opts.robot_radius);
        Ok(maps)
    }

    /// World coordinates of a cell's centre.
    ///
    /// ```
    /// # use hearth_sim::scene::{MapOptions, SceneFile, SceneMaps};
    /// let m = SceneMaps::build(&SceneFile::empty("e"), &MapOptions::default()).unwrap();
    /// let c = m.cell_center(0, 0);
    /// assert!((c[0] - m.origin[0] - 0.025).abs() < 1e-12);
    /// ```
    pub fn cell_center(&self, ix: usize, iy: usize) -> [f64; 2] {
        [
            self.origin[0] + (ix as f64 + 0.5) * self.resolution,
            self.origin[1] + (iy as f64 + 0.5) * self.resolution,
        ]
    }

    /// The cell holding a point, or `None` off the map.
    ///
    /// ```
    /// # use hearth_sim::scene::{MapOptions, SceneFile, SceneMaps};
    /// let m = SceneMaps::build(&SceneFile::empty("e"), &MapOptions::default()).unwrap();
    /// assert!(m.cell_of([1e6, 0.0]).is_none());
    /// ```
    pub fn cell_of(&self, p: [f64; 2]) -> Option<(usize, usize)> {
        let fx = ((p[0] - self.origin[0]) / self.resolution).floor();
        let fy = ((p[1] - self.origin[1]) / self.resolution).floor();
        let inside = fx >= 0.0 && fy >= 0.0 && fx < self.width as f64 && fy < self.height as f64;
        inside.then_some((fx as usize, fy as usize))
    }

    /// Whether the robot may stand at a point.
    ///
    /// ```
    /// # use hearth_sim::scene::{MapOptions, SceneFile, SceneMaps};
    /// let m = SceneMaps::build(&SceneFile::empty("e"), &MapOptions::default()).unwrap();
    /// assert!(!m.is_traversable([0.0, 0.0]));
    /// ```
    pub fn is_traversable(&self, p: [f64; 2]) -> bool {
        self.cell_of(p)
            .is_some_and(|(x, y)| self.traversable[y * self.width + x])
    }

    /// The name of the room a point lies in.
    ///
    /// ```
    /// # use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
    /// let home = generate(&GenerateOptions { seed: 4, rooms: 2, ..Default::default() }).unwrap();
    /// let m = SceneMaps::build(&home, &MapOptions::default()).unwrap();
    /// let r = &home.building.rooms[0];
    /// assert_eq!(m.room_at(r.center()), Some(r.name.as_str()));
    /// ```
    pub fn room_at(&self, p: [f64; 2]) -> Option<&str> {
        let (x, y) = self.cell_of(p)?;
        self.room_id[y * self.width + x].map(|k| self.room_names[k as usize].as_str())
    }

    /// Fraction of the cells inside rooms that are traversable.
    ///
    /// ```
    /// # use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
    /// let home = generate(&GenerateOptions { seed: 4, rooms: 2, ..Default::default() }).unwrap();
    /// let f = SceneMaps::build(&home, &MapOptions::default()).unwrap().free_fraction();
    /// assert!(f > 0.1 && f < 0.9);
    /// ```
    pub fn free_fraction(&self) -> f64 {
        let inside = self.room_id.iter().filter(|r| r.is_some()).count();
        let free = self
            .traversable
            .iter()
            .zip(&self.room_id)
            .filter(|(t, r)| **t && r.is_some())
            .count();
        if inside == 0 { 0.0 } else { free as f64 / inside as f64 }
    }

    fn stamp(&mut self, f: &Footprint) {
        let (a, b) = f.aabb();
        let (Some(c0), Some(c1)) = (self.clamp_cell(a), self.clamp_cell(b)) else {
            return;
        };
        for iy in c0.1..=c1.1 {
            for ix in c0.0..=c1.0 {
                if f.contains(self.cell_center(ix, iy)) {
                    self.obstacle[iy * self.width + ix] = true;
                }
            }
        }
    }

    fn clamp_cell(&self, p: [f64; 2]) -> Option<(usize, usize)> {
        let fx = ((p[0] - self.origin[0]) / self.resolution).floor();
        let fy = ((p[1] - self.origin[1]) / self.resolution).floor();
        if !(fx.is_finite() && fy.is_finite()) {
            return None;
        }
        let cx = fx.clamp(0.0, (self.width - 1) as f64) as usize;
        let cy = fy.clamp(0.0, (self.height - 1) as f64) as usize;
        Some((cx, cy))
    }

    /// Marks as blocked every cell within `radius` of an obstacle cell.
    fn erode(&mut self, radius: f64) {
        let (w, h) = (self.width, self.height);
        let r = (radius / self.resolution).ceil() as i64;
        let lim = (radius / self.resolution).powi(2);
        let offsets: Vec<(i64, i64)> = (-r..=r)
            .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
            .filter(|&(dx, dy)| ((dx * dx + dy * dy) as f64) <= lim + 1e-9)
            .collect();
        let mut blocked = self.obstacle.clone();
        for iy in 0..h {
            for ix in 0..w {
                if !self.obstacle[iy * w + ix] {
                    continue;
                }
                let edge = [(0i64, 1i64), (0, -1), (1, 0), (-1, 0)].iter().any(|&(dx, dy)| {
                    let (x, y) = (ix as i64 + dx, iy as i64 + dy);
                    x >= 0
                        && y >= 0
                        && (x as usize) < w
                        && (y as usize) < h
                        && !self.obstacle[y as usize * w + x as usize]
                });
                if !edge {
                    continue;
                }
                for &(dx, dy) in &offsets {
                    let (x, y) = (ix as i64 + dx, iy as i64 + dy);
                    if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                        blocked[y as usize * w + x as usize] = true;
                    }
                }
            }
        }
        self.traversable = blocked.iter().map(|b| !b).collect();
    }

    fn endpoint(&self, p: [f64; 2], what: &'static str) -> Result<usize, SceneError> {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(SceneError::NonFinite {
                field: what.to_owned(),
                value: if p[0].is_finite() { p[1] } else { p[0] },
            });
        }
        let (x, y) = self.cell_of(p).ok_or(SceneError::OffMap { what, x: p[0], y: p[1] })?;
        let i = y * self.width + x;
        if !self.traversable[i] {
            return Err(SceneError::Blocked { what, x: p[0], y: p[1] });
        }
        Ok(i)
    }

    /// Calls `f(j, step)` for each traversable 8-neighbour `j` of cell `i` (no corner cutting),
    /// `step` in cells (1 or √2).
    fn for_each_neighbour(&self, i: usize, mut f: impl FnMut(usize, f64)) {
        let w = self.width as i64;
        let free = |x: i64, y: i64| {
            x >= 0 && y >= 0 && x < w && y < self.height as i64 && self.traversable[(y * w + x) as usize]
        };
        let (x, y) = (i as i64 % w, i as i64 / w);
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)] {
            let (nx, ny) = (x + dx, y + dy);
            if !free(nx, ny) || (dx != 0 && dy != 0 && !(free(x + dx, y) && free(x, y + dy))) {
                continue;
            }
            let step = if dx != 0 && dy != 0 {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            f((ny * w + nx) as usize, step);
        }
    }

    /// Geodesic distance (metres, along 8-connected traversable cells) from every cell to
    /// `goal`; `f64::INFINITY` where unreachable. One Dijkstra sweep, so per-step distance
    /// lookups afterwards are O(1) ([`SceneMaps::geodesic_at`]).
    ///
    /// # Errors
    /// [`SceneError::OffMap`] / [`SceneError::Blocked`] / [`SceneError::NonFinite`] for a bad goal.
    ///
    /// ```
    /// use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
    /// let home = generate(&GenerateOptions { seed: 2, rooms: 2, ..Default::default() }).unwrap();
    /// let maps = SceneMaps::build(&home, &MapOptions::default()).unwrap();
    /// let goal = home.building.rooms[0].center();
    /// let field = maps.distance_field(goal).unwrap();
    /// assert!(maps.geodesic_at(&field, goal).unwrap() < 0.1);
    /// ```
    pub fn distance_field(&self, goal: [f64; 2]) -> Result<Vec<f64>, SceneError> {
        let g = self.endpoint(goal, "goal")?;
        let mut dist = vec![f64::INFINITY; self.traversable.len()];
        let mut open = BinaryHeap::new();
        dist[g] = 0.0;
        open.push(Reverse((0f64.to_bits(), g)));
        while let Some(Reverse((bits, i))) = open.pop() {
            if f64::from_bits(bits) > dist[i] {
                continue;
            }
            self.for_each_neighbour(i, |j, step| {
                let c = dist[i] + step * self.resolution;
                if c < dist[j] {
                    dist[j] = c;
                    open.push(Reverse((c.to_bits(), j)));
                }
            });
        }
        Ok(dist)
    }

    /// The distance a [`SceneMaps::distance_field`] gives at world point `p` (its cell's),
    /// `None` off the map.
    ///
    /// ```
    /// # use hearth_sim::scene::{MapOptions, SceneFile, SceneMaps};
    /// let studio = SceneFile::from_json_str(r#"{"name": "studio", "building": {"rooms": [
    ///     {"name": "living", "room_type": "living_room", "polygon": [[0, 0], [4, 0], [4, 3], [0, 3]]}]}}"#).unwrap();
    /// let maps = SceneMaps::build(&studio, &MapOptions::default()).unwrap();
    /// let field = maps.distance_field([1.0, 1.5]).unwrap();
    /// let d = maps.geodesic_at(&field, [3.0, 1.5]).unwrap();
    /// assert!((d - 2.0).abs() < 0.1, "{d}");
    /// assert_eq!(maps.geodesic_at(&field, [1e6, 0.0]), None);
    /// ```
    pub fn geodesic_at(&self, field: &[f64], p: [f64; 2]) -> Option<f64> {
        let (x, y) = self.cell_of(p)?;
        field.get(y * self.width + x).copied()
    }

    /// Shortest 8-connected path (no corner cutting) between two points, as world waypoints
    /// from `start` to `goal` with collinear cells merged.
    ///
    /// ```
    /// # use hearth_sim::scene::{MapOptions, SceneError, SceneFile, SceneMaps};
    /// let m = SceneMaps::build(&SceneFile::empty("e"), &MapOptions::default()).unwrap();
    /// assert!(matches!(m.shortest_path([0.0, 0.0], [0.0, 0.0]), Err(SceneError::Blocked { .. })));
    /// ```
    pub fn shortest_path(&self, start: [f64; 2], goal: [f64; 2]) -> Result<Vec<[f64; 2]>, SceneError> {
        let s = self.endpoint(start, "start")?;
        let g = self.endpoint(goal, "goal")?;
        let w = self.width as i64;
        let (gx, gy) = ((g as i64 % w) as f64, (g as i64 / w) as f64);
        let heuristic = |i: usize| {
            let (x, y) = ((i as i64 % w) as f64, (i as i64 / w) as f64);
            let (dx, dy) = ((x - gx).abs(), (y - gy).abs());
            dx.max(dy) + (std::f64::consts::SQRT_2 - 1.0) * dx.min(dy)
        };
        let n = self.traversable.len();
        let mut cost = vec![f64::INFINITY; n];
        let mut parent = vec![usize::MAX; n];
        let mut open = BinaryHeap::new();
        cost[s] = 0.0;
        // Costs are non-negative, so their bit patterns order like the numbers.
        open.push(Reverse((heuristic(s).to_bits(), s)));
        while let Some(Reverse((_, i))) = open.pop() {
            if i == g {
                break;
            }
            self.for_each_neighbour(i, |j, step| {
                let c = cost[i] + step;
                if c < cost[j] {
                    cost[j] = c;
                    parent[j] = i;
                    open.push(Reverse(((c + heuristic(j)).to_bits(), j)));
                }
            });
        }
        if !cost[g].is_finite() {
            return Err(SceneError::NoPath { from: start, to: goal });
        }
        let mut cells = vec![g];
        while let Some(&last) = cells.last() {
            if last == s {
                break;
            }
            cells.push(parent[last]);
        }
        cells.reverse();
        let mut out = vec![start];
        for k in 1..cells.len().saturating_sub(1) {
            let d = |a: usize, b: usize| (b as i64 % w - a as i64 % w, b as i64 / w - a as i64 / w);
            if d(cells[k - 1], cells[k]) != d(cells[k], cells[k + 1]) {
                let (x, y) = (cells[k] % self.width, cells[k] / self.width);
                out.push(self.cell_center(x, y));
            }
        }
        out.push(goal);
        Ok(out)
    }
}
