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

    /// The distance at world point `xy`, interpolated bilinearly between the centres of the four
    /// cells around it (cells off the map or unreachable left out, the others' weights scaled
    /// up); `None` when none of the four has a finite distance. A robot that creeps sideways
    /// across a cell border sees its potential change by as much as it moved, not by a cell's
    /// diagonal step.
    pub(crate) fn interpolated(&self, xy: [f64; 2]) -> Option<f64> {
        let u = (xy[0] - self.origin[0]) / self.resolution - 0.5;
        let v = (xy[1] - self.origin[1]) / self.resolution - 0.5;
        if !(u.is_finite() && v.is_finite()) {
            return None;
        }
        let (i, j) = (u.floor(), v.floor());
        let (fx, fy) = (u - i, v - j);
        let (mut sum, mut weight) = (0.0, 0.0);
        for (di, dj, w) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let (x, y) = (i + di, j + dj);
            if w <= 0.0 || x < 0.0 || y < 0.0 || x >= self.width as f64 || y >= self.height as f64 {
                continue;
            }
            let d = self.field[y as usize * self.width + x as usize];
            if d.is_finite() {
                sum += w * d;
                weight += w;
            }
        }
        (weight > 1e-9).then(|| sum / weight)
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

#[cfg(test)]
mod tests {
    use super::DistanceField;

    /// A 3 × 2 field of 1 m cells from the origin; the middle of the top row is unreachable.
    fn field() -> DistanceField {
        DistanceField {
            field: vec![0.0, 1.0, 2.0, 1.0, f64::INFINITY, 3.0],
            origin: [0.0, 0.0],
            resolution: 1.0,
            width: 3,
            height: 2,
        }
    }

    #[test]
    fn interpolation_meets_the_cells_at_their_centres_and_blends_between() {
        let f = field();
        assert_eq!(f.interpolated([0.5, 0.5]), Some(0.0));
        assert_eq!(f.interpolated([2.5, 1.5]), Some(3.0));
        assert_eq!(f.interpolated([1.0, 0.5]), Some(0.5)); // half-way along the bottom row
        assert_eq!(f.interpolated([0.75, 0.5]), Some(0.25));
        // Between four centres, one unreachable: the three others, their weights scaled up.
        let d = f.interpolated([1.0, 1.0]).unwrap();
        assert!((d - (0.0 + 1.0 + 1.0) / 3.0).abs() < 1e-12, "{d}");
        // At the unreachable cell's centre nothing finite has weight.
        assert_eq!(f.interpolated([1.5, 1.5]), None);
        // Beyond the outer centres the border cells hold; off the map entirely, nothing.
        assert_eq!(f.interpolated([0.1, 0.1]), Some(0.0));
        assert_eq!(f.interpolated([-3.0, 0.5]), None);
        assert_eq!(f.interpolated([f64::NAN, 0.5]), None);
        // The cell lookup, for comparison, jumps at the border.
        assert_eq!((f.at([0.99, 0.5]), f.at([1.01, 0.5])), (Some(0.0), Some(1.0)));
    }
}
