//! [`DistanceField`]: geodesic distances over the traversability map to a goal point or to a
//! set of goal cells (multi-source Dijkstra), looked up in O(1) per step.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::scene::SceneMaps;

/// Geodesic distance (m) from every map cell to the nearest goal cell; infinite where
/// unreachable.
#[derive(Clone, Debug, Default)]
pub(crate) struct DistanceField {
    field: Vec<f64>,
    origin: [f64; 2],
    resolution: f64,
    width: usize,
    height: usize,
}

impl DistanceField {
    /// Dijkstra from every cell in `sources` at once (8-connected traversable cells, no corner
    /// cutting, as `SceneMaps::distance_field`).
    pub(crate) fn from_cells(maps: &SceneMaps, sources: &[usize]) -> Self {
        let (w, h) = (maps.width as i64, maps.height as i64);
        let free = |x: i64, y: i64| x >= 0 && y >= 0 && x < w && y < h && maps.traversable[(y * w + x) as usize];
        let mut dist = vec![f64::INFINITY; maps.traversable.len()];
        let mut open = BinaryHeap::new();
        for &s in sources {
            if s < dist.len() {
                dist[s] = 0.0;
                open.push(Reverse((0f64.to_bits(), s)));
            }
        }
        while let Some(Reverse((bits, i))) = open.pop() {
            if f64::from_bits(bits) > dist[i] {
                continue;
            }
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
                let j = (ny * w + nx) as usize;
                let c = dist[i] + step * maps.resolution;
                if c < dist[j] {
                    dist[j] = c;
                    open.push(Reverse((c.to_bits(), j)));
                }
            }
        }
        Self::wrap(maps, dist)
    }

    /// Wraps a field computed by `SceneMaps::distance_field`.
    pub(crate) fn wrap(maps: &SceneMaps, field: Vec<f64>) -> Self {
        Self {
            field,
            origin: maps.origin,
            resolution: maps.resolution,
            width: maps.width,
            height: maps.height,
        }
    }

    /// The distance at world point `xy` (its cell's), `None` off the map.
    pub(crate) fn at(&self, xy: [f64; 2]) -> Option<f64> {
        let x = ((xy[0] - self.origin[0]) / self.resolution).floor();
        let y = ((xy[1] - self.origin[1]) / self.resolution).floor();
        if x < 0.0 || y < 0.0 || x >= self.width as f64 || y >= self.height as f64 {
            return None;
        }
        self.field.get(y as usize * self.width + x as usize).copied()
    }

    /// The distance of cell `i`.
    pub(crate) fn cell(&self, i: usize) -> f64 {
        self.field.get(i).copied().unwrap_or(f64::INFINITY)
    }
}

/// Indices of the traversable cells.
pub(crate) fn free_cells(maps: &SceneMaps) -> Vec<usize> {
    (0..maps.traversable.len()).filter(|&i| maps.traversable[i]).collect()
}

/// The centre of cell `i`.
pub(crate) fn cell_center(maps: &SceneMaps, i: usize) -> [f64; 2] {
    maps.cell_center(i % maps.width, i / maps.width)
}

/// The traversable cell nearest to `p` within `radius` m, if any.
pub(crate) fn nearest_free(maps: &SceneMaps, p: [f64; 2], radius: f64) -> Option<usize> {
    let r = (radius / maps.resolution).ceil() as i64;
    let cx = ((p[0] - maps.origin[0]) / maps.resolution).floor() as i64;
    let cy = ((p[1] - maps.origin[1]) / maps.resolution).floor() as i64;
    let mut best: Option<(f64, usize)> = None;
    for y in (cy - r)..=(cy + r) {
        for x in (cx - r)..=(cx + r) {
            if x < 0 || y < 0 || x >= maps.width as i64 || y >= maps.height as i64 {
                continue;
            }
            let i = y as usize * maps.width + x as usize;
            if !maps.traversable[i] {
                continue;
            }
            let c = cell_center(maps, i);
            let d = (c[0] - p[0]).hypot(c[1] - p[1]);
            if d <= radius && best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, i));
            }
        }
    }
    best.map(|(_, i)| i)
}
