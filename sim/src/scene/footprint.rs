//! Oriented rectangles in the plane with a vertical extent: the space an object or a piece of
//! wall takes, used by validation, the home generator and the maps.

use nalgebra::{Isometry3, Point3, Vector3};

use super::Wall;

/// An oriented rectangle in the plane, extruded over `z`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Footprint {
    /// Centre.
    pub(crate) c: [f64; 2],
    /// Half extents along the rectangle's own axes.
    pub(crate) half: [f64; 2],
    /// Angle of the rectangle's first axis from +x.
    pub(crate) yaw: f64,
    /// Bottom and top heights.
    pub(crate) z: [f64; 2],
}

impl Footprint {
    /// The footprint of a box `[lo, hi]` (object frame) placed at `pose`; a tilted object gets the
    /// axis-aligned box of its corners.
    pub(crate) fn of_box(pose: &Isometry3<f64>, lo: &Vector3<f64>, hi: &Vector3<f64>) -> Footprint {
        let r = pose.rotation.to_rotation_matrix();
        let m = r.matrix();
        if m[(2, 2)] > 0.9999 {
            let centre = pose * Point3::from((lo + hi) / 2.0);
            let half = (hi - lo) / 2.0;
            return Footprint {
                c: [centre.x, centre.y],
                half: [half.x, half.y],
                yaw: m[(1, 0)].atan2(m[(0, 0)]),
                z: [centre.z - half.z, centre.z + half.z],
            };
        }
        let mut a = Vector3::repeat(f64::INFINITY);
        let mut b = Vector3::repeat(f64::NEG_INFINITY);
        for k in 0..8 {
            let corner = Vector3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let p = pose * Point3::from(corner);
            a = a.inf(&p.coords);
            b = b.sup(&p.coords);
        }
        Footprint {
            c: [(a.x + b.x) / 2.0, (a.y + b.y) / 2.0],
            half: [(b.x - a.x) / 2.0, (b.y - a.y) / 2.0],
            yaw: 0.0,
            z: [a.z, b.z],
        }
    }

    /// One solid piece `[from, to, bottom, top]` of a wall (see [`Wall::pieces`]).
    pub(crate) fn of_wall_piece(wall: &Wall, piece: [f64; 4]) -> Footprint {
        let mid = wall.point_at((piece[0] + piece[1]) / 2.0);
        Footprint {
            c: mid,
            half: [(piece[1] - piece[0]) / 2.0, wall.thickness / 2.0],
            yaw: wall.yaw(),
            z: [piece[2], piece[3]],
        }
    }

    /// An axis-aligned rectangle.
    pub(crate) fn rect(lo: [f64; 2], hi: [f64; 2], z: [f64; 2]) -> Footprint {
        Footprint {
            c: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0],
            half: [(hi[0] - lo[0]) / 2.0, (hi[1] - lo[1]) / 2.0],
            yaw: 0.0,
            z,
        }
    }

    fn axes(&self) -> [[f64; 2]; 2] {
        let (s, c) = self.yaw.sin_cos();
        [[c, s], [-s, c]]
    }

    fn radius_along(&self, a: [f64; 2]) -> f64 {
        let [u, v] = self.axes();
        self.half[0] * (u[0] * a[0] + u[1] * a[1]).abs() + self.half[1] * (v[0] * a[0] + v[1] * a[1]).abs()
    }

    /// Penetration depth of two footprints (negative or zero when apart): the smaller of the
    /// planar overlap along the separating-axis candidates and the vertical overlap.
    pub(crate) fn overlap(&self, other: &Footprint) -> f64 {
        let d = [other.c[0] - self.c[0], other.c[1] - self.c[1]];
        let mut depth = self.z[1].min(other.z[1]) - self.z[0].max(other.z[0]);
        for a in self.axes().into_iter().chain(other.axes()) {
            let gap = (d[0] * a[0] + d[1] * a[1]).abs();
            depth = depth.min(self.radius_along(a) + other.radius_along(a) - gap);
        }
        depth
    }

    /// Whether a point of the plane lies inside the rectangle.
    pub(crate) fn contains(&self, p: [f64; 2]) -> bool {
        let d = [p[0] - self.c[0], p[1] - self.c[1]];
        let [u, v] = self.axes();
        (d[0] * u[0] + d[1] * u[1]).abs() <= self.half[0] && (d[0] * v[0] + d[1] * v[1]).abs() <= self.half[1]
    }

    /// Lower and upper corners of the planar bounding box.
    pub(crate) fn aabb(&self) -> ([f64; 2], [f64; 2]) {
        let rx = self.radius_along([1.0, 0.0]);
        let ry = self.radius_along([0.0, 1.0]);
        ([self.c[0] - rx, self.c[1] - ry], [self.c[0] + rx, self.c[1] + ry])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotated_squares_overlap_like_geometry_says() {
        let a = Footprint::rect([0.0, 0.0], [1.0, 1.0], [0.0, 1.0]);
        let mut b = a;
        b.c = [1.6, 0.5];
        b.yaw = std::f64::consts::FRAC_PI_4;
        // The diamond reaches 0.5·√2 ≈ 0.707 to the left of its centre: 1.6 − 0.707 < 1.
        assert!(b.overlap(&a) > 0.08 && b.overlap(&a) < 0.12);
        b.c = [1.8, 0.5];
        assert!(a.overlap(&b) < 0.0);
        let mut high = a;
        high.z = [2.0, 3.0];
        assert!(a.overlap(&high) < 0.0);
    }
}
