//! Distance fields of compound links, for self-collision proofs: a grid over the link's
//! bounding box (plus a margin) holding, at each grid point, a lower bound on the distance
//! from that point to the link's collision shape. A ball whose centre `p` lies near grid
//! point `g` is clear of the link when `field(g) - |p - g|` exceeds its radius (distance is
//! 1-Lipschitz), and every ball of another link's sphere cover being clear proves the two
//! links apart, in one lookup per ball instead of tests against each of the link's parts.
//!
//! Only links with at least [`MIN_PARTS`] collision elements get a field: for the others,
//! tests against their parts cost no more.
//!
//! ```
//! use hearth_kinematics::RobotModel;
//! use nalgebra::Point3;
//! let fetch = RobotModel::builtin("fetch").unwrap();
//! let torso = fetch.link_index("torso_lift_link").unwrap();
//! let field = fetch.link_field(torso).expect("the torso lift is a compound of 25 parts");
//! // Far from the torso everything is clear; inside it nothing is.
//! assert!(field.clears_ball(&Point3::new(2.0, 0.0, 0.0), 0.1));
//! let inside = fetch.link_shape(torso).unwrap().shape.compute_local_aabb().center();
//! assert!(!field.clears_ball(&Point3::new(inside.x as f64, inside.y as f64, inside.z as f64), 0.001));
//! ```

use std::sync::{Arc, Mutex};

use nalgebra::{Point3, Vector3};
use parry3d::math::Vector;

use crate::model::{LinkShape, RobotModel};
use crate::per_link::{BuiltinCache, per_link};
use crate::to_pose;

/// Grid spacing (m), for links whose grid holds at most [`MAX_POINTS`] at it. A ball is
/// cleared when its distance bound beats its radius by the distance from its centre to the
/// nearest grid point, at most `step * sqrt(3) / 2` (8.7 mm).
///
/// ```
/// assert!(hearth_kinematics::distance_field::STEP <= 0.01);
/// ```
pub const STEP: f64 = 0.01;
/// Most grid points in one field (2 bytes each): bigger links get a coarser grid.
///
/// ```
/// use hearth_kinematics::{LinkShape, distance_field::{DistanceField, MAX_POINTS}};
/// use parry3d::shape::SharedShape;
/// let hall = LinkShape { shape: SharedShape::cuboid(5.0, 5.0, 1.0), origin: nalgebra::Isometry3::identity() };
/// assert!(DistanceField::build(&hall).len() <= MAX_POINTS);
/// ```
pub const MAX_POINTS: usize = 1 << 21;
/// How far (m) the grid reaches past the link's bounding box; beyond it, the distance to the
/// box is the bound.
///
/// ```
/// use hearth_kinematics::{LinkShape, distance_field::{DistanceField, MARGIN}};
/// use nalgebra::Point3;
/// use parry3d::shape::SharedShape;
/// // A 10 cm cube: on the grid just inside the margin, beyond it by the box alone.
/// let cube = LinkShape { shape: SharedShape::cuboid(0.05, 0.05, 0.05), origin: nalgebra::Isometry3::identity() };
/// let field = DistanceField::build(&cube);
/// for x in [0.05 + MARGIN - 0.01, 0.05 + MARGIN + 0.5] {
///     let bound = field.lower_bound(&Point3::new(x, 0.0, 0.0));
///     assert!(bound <= x - 0.05 && bound > x - 0.05 - 0.01, "{x}: {bound}");
/// }
/// ```
pub const MARGIN: f64 = 0.06;
/// Fewest collision elements a link needs to get a field.
///
/// ```
/// use hearth_kinematics::{RobotModel, distance_field::MIN_PARTS};
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// for link in 0..fetch.links().len() {
///     let parts = fetch.link_shape(link).map_or(0, |s| s.shape.as_compound().map_or(1, |c| c.shapes().len()));
///     assert_eq!(fetch.link_field(link).is_some(), parts >= MIN_PARTS, "{}", fetch.links()[link].name);
/// }
/// ```
pub const MIN_PARTS: usize = 4;
/// Unit of the stored distances (m); they are rounded down to it.
const UNIT: f64 = 1e-4;
/// Subtracted from parry's `f32` distances before storing, for their rounding.
const F32_SLACK: f64 = 1e-5;

/// A grid of distance bounds around one link's collision shape, in the link frame.
///
/// ```
/// use hearth_kinematics::{LinkShape, distance_field::DistanceField};
/// use nalgebra::{Isometry3, Point3};
/// use parry3d::shape::SharedShape;
/// let bar = LinkShape { shape: SharedShape::cuboid(0.2, 0.05, 0.05), origin: Isometry3::identity() };
/// let field = DistanceField::build(&bar);
/// assert!(field.clears_ball(&Point3::new(0.0, 0.0, 0.2), 0.1)); // 5 cm of air below the ball
/// assert!(!field.clears_ball(&Point3::new(0.0, 0.0, 0.2), 0.16));
/// ```
#[derive(Clone, Debug)]
pub struct DistanceField {
    /// Grid point (0, 0, 0) in the link frame.
    origin: Point3<f64>,
    /// Grid spacing (m): [`STEP`], or coarser for a big link.
    step: f64,
    /// `1 / step`.
    inv_step: f64,
    /// Grid points along x, y and z.
    dims: [usize; 3],
    /// Per grid point (x fastest): the distance bound in [`UNIT`]s.
    dist: Vec<u16>,
    /// The shape's bounding box in the link frame: centre and half extents.
    aabb: (Point3<f64>, Vector3<f64>),
}

impl DistanceField {
    /// The field of `link`'s collision shape (in the link frame, where the shape sits at
    /// `link.origin`).
    ///
    /// ```
    /// use hearth_kinematics::{LinkShape, distance_field::DistanceField};
    /// use parry3d::shape::SharedShape;
    /// let ball = LinkShape { shape: SharedShape::ball(0.1), origin: nalgebra::Isometry3::identity() };
    /// let field = DistanceField::build(&ball);
    /// let p = nalgebra::Point3::new(0.15, 0.0, 0.0); // 5 cm from the surface
    /// assert!(field.lower_bound(&p) <= 0.05 && field.lower_bound(&p) > 0.04);
    /// ```
    pub fn build(link: &LinkShape) -> Self {
        let pose = to_pose(&link.origin);
        let aabb = link.shape.compute_aabb(&pose);
        let f = |v: Vector| Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z));
        let (lo, hi) = (f(aabb.mins), f(aabb.maxs));
        let center = Point3::from((lo + hi) * 0.5);
        let half = (hi - lo) * 0.5;
        let origin = Point3::from(lo - Vector3::repeat(MARGIN));
        let span = hi - lo + Vector3::repeat(2.0 * MARGIN);
        // Points along each axis at spacing `step`; the spacing grows until they fit.
        let count = |e: f64, step: f64| (e / step).ceil() as usize + 1;
        let mut step = STEP;
        while span.iter().map(|&e| count(e, step)).product::<usize>() > MAX_POINTS {
            step *= 1.25;
        }
        let dims = [count(span.x, step), count(span.y, step), count(span.z, step)];
        let mut dist = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let g = origin + Vector3::new(i as f64, j as f64, k as f64) * step;
                    let p = Vector::new(g.x as f32, g.y as f32, g.z as f32);
                    // `p` is `g` rounded to f32: the bound at `g` loses that offset too.
                    let off = (g - Point3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z))).norm();
                    let d = f64::from(link.shape.distance_to_point(&pose, p, true)) - F32_SLACK - off;
                    dist.push((d.max(0.0) / UNIT).floor().min(f64::from(u16::MAX)) as u16);
                }
            }
        }
        Self {
            origin,
            step,
            inv_step: 1.0 / step,
            dims,
            dist,
            aabb: (center, half),
        }
    }

    /// A lower bound on the distance from `p` (link frame) to the shape: 0 inside it.
    ///
    /// ```
    /// use hearth_kinematics::{LinkShape, distance_field::DistanceField};
    /// use nalgebra::Point3;
    /// use parry3d::shape::SharedShape;
    /// let cube = LinkShape { shape: SharedShape::cuboid(0.1, 0.1, 0.1), origin: nalgebra::Isometry3::identity() };
    /// let field = DistanceField::build(&cube);
    /// assert_eq!(field.lower_bound(&Point3::origin()), 0.0);
    /// assert!((field.lower_bound(&Point3::new(1.1, 0.0, 0.0)) - 1.0).abs() < 1e-6); // past the grid
    /// ```
    pub fn lower_bound(&self, p: &Point3<f64>) -> f64 {
        match self.nearest(p) {
            Some((stored, gap2)) => (stored - gap2.sqrt()).max(0.0),
            None => self.box_distance2(p).sqrt(),
        }
    }

    /// Whether the ball (`center` in the link frame, `radius`) is certainly clear of the shape.
    ///
    /// ```
    /// use hearth_kinematics::{LinkShape, distance_field::DistanceField};
    /// use nalgebra::Point3;
    /// use parry3d::shape::SharedShape;
    /// let cube = LinkShape { shape: SharedShape::cuboid(0.1, 0.1, 0.1), origin: nalgebra::Isometry3::identity() };
    /// let field = DistanceField::build(&cube);
    /// assert!(field.clears_ball(&Point3::new(0.3, 0.0, 0.0), 0.15));
    /// assert!(!field.clears_ball(&Point3::new(0.3, 0.0, 0.0), 0.21));
    /// ```
    #[inline]
    pub fn clears_ball(&self, center: &Point3<f64>, radius: f64) -> bool {
        match self.nearest(center) {
            // stored - |p - g| > r, without the square root.
            Some((stored, gap2)) => {
                let room = stored - radius;
                room > 0.0 && gap2 < room * room
            }
            None => self.box_distance2(center) > radius * radius,
        }
    }

    /// The stored bound at the grid point nearest `p` and the squared distance to that point;
    /// `None` outside the grid.
    #[inline]
    fn nearest(&self, p: &Point3<f64>) -> Option<(f64, f64)> {
        // Grid coordinates shifted by half a step: truncation then rounds to nearest.
        let g = (p - self.origin) * self.inv_step + Vector3::repeat(0.5);
        let inside = |v: f64, n: usize| v >= 0.0 && v < n as f64;
        if !(inside(g.x, self.dims[0]) && inside(g.y, self.dims[1]) && inside(g.z, self.dims[2])) {
            return None;
        }
        let (i, j, k) = (g.x as usize, g.y as usize, g.z as usize);
        let stored = f64::from(self.dist[(k * self.dims[1] + j) * self.dims[0] + i]) * UNIT;
        let gap = (g - Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5)) * self.step;
        Some((stored, gap.norm_squared()))
    }

    /// Squared distance from `p` to the shape's bounding box (0 inside).
    #[inline]
    fn box_distance2(&self, p: &Point3<f64>) -> f64 {
        let (c, h) = &self.aabb;
        let d = (p - c).abs() - h;
        d.sup(&Vector3::zeros()).norm_squared()
    }

    /// Grid points stored.
    ///
    /// ```
    /// use hearth_kinematics::{LinkShape, distance_field::DistanceField};
    /// use parry3d::shape::SharedShape;
    /// let ball = LinkShape { shape: SharedShape::ball(0.05), origin: nalgebra::Isometry3::identity() };
    /// assert!(DistanceField::build(&ball).len() > 20 * 20 * 20);
    /// ```
    pub fn len(&self) -> usize {
        self.dist.len()
    }

    /// Whether the grid is empty (never, for a built field).
    ///
    /// ```
    /// use hearth_kinematics::{LinkShape, distance_field::DistanceField};
    /// use parry3d::shape::SharedShape;
    /// let ball = LinkShape { shape: SharedShape::ball(0.05), origin: nalgebra::Isometry3::identity() };
    /// assert!(!DistanceField::build(&ball).is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.dist.is_empty()
    }
}

/// Fields of every link of `model` with at least [`MIN_PARTS`] collision elements and finite
/// bounds (see [`crate::per_link`]).
pub(crate) fn fields(model: &RobotModel) -> Arc<Vec<Option<DistanceField>>> {
    static BUILTIN: BuiltinCache<Option<DistanceField>> = Mutex::new(Vec::new());
    per_link(model, &BUILTIN, |link| {
        let parts = link.shape.as_compound().map_or(1, |c| c.shapes().len());
        let aabb = link.shape.compute_local_aabb();
        let finite = (aabb.maxs - aabb.mins).is_finite();
        (parts >= MIN_PARTS && finite).then(|| DistanceField::build(link))
    })
}

#[cfg(test)]
mod tests {
    use super::DistanceField;
    use crate::{LinkShape, RobotModel, to_pose};
    use nalgebra::{Isometry3, Point3};
    use parry3d::math::Vector;
    use rand::{RngExt, SeedableRng};

    /// The bound never exceeds parry's distance, and is within the grid's slack of it, at
    /// random points around every field of the Fetch.
    #[test]
    fn bound_is_below_the_distance_and_close_to_it() {
        let fetch = RobotModel::builtin("fetch").unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let mut fields = 0;
        for l in 0..fetch.links().len() {
            let Some(field) = fetch.link_field(l) else { continue };
            fields += 1;
            let shape: &LinkShape = fetch.link_shape(l).unwrap();
            let pose = to_pose(&shape.origin);
            let aabb = shape.shape.compute_aabb(&pose);
            for _ in 0..3000 {
                let mut r = |lo: f32, hi: f32| f64::from(rng.random_range(lo - 0.15..hi + 0.15));
                let p = Point3::new(
                    r(aabb.mins.x, aabb.maxs.x),
                    r(aabb.mins.y, aabb.maxs.y),
                    r(aabb.mins.z, aabb.maxs.z),
                );
                let exact = f64::from(shape.shape.distance_to_point(
                    &pose,
                    Vector::new(p.x as f32, p.y as f32, p.z as f32),
                    true,
                ));
                let bound = field.lower_bound(&p);
                assert!(
                    bound <= exact + 1e-6,
                    "link {l}: bound {bound} above distance {exact} at {p}"
                );
                let grid_point_reach = field.step * 3f64.sqrt() / 2.0;
                if field.nearest(&p).is_some() {
                    assert!(
                        bound >= exact - 2.0 * grid_point_reach - 1e-3,
                        "link {l}: bound {bound}, distance {exact}"
                    );
                }
            }
        }
        assert!(fields >= 6, "the Fetch's compound links have fields: {fields}");
    }

    /// A ball is cleared only when it misses the shape.
    #[test]
    fn cleared_balls_miss_the_shape() {
        let link = LinkShape {
            shape: parry3d::shape::SharedShape::compound(vec![
                (
                    parry3d::math::Pose::IDENTITY,
                    parry3d::shape::SharedShape::cuboid(0.1, 0.02, 0.3),
                ),
                (
                    parry3d::math::Pose::from_translation(Vector::new(0.0, 0.1, 0.0)),
                    parry3d::shape::SharedShape::cylinder(0.2, 0.04),
                ),
            ]),
            origin: Isometry3::translation(0.0, 0.0, 0.5),
        };
        let field = DistanceField::build(&link);
        let pose = to_pose(&link.origin);
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(4);
        let (mut cleared, mut tested) = (0, 0);
        for _ in 0..20_000 {
            let c = Point3::new(
                rng.random_range(-0.4..0.4),
                rng.random_range(-0.4..0.5),
                rng.random_range(0.0..1.0),
            );
            let r = rng.random_range(0.005..0.1);
            let ball = parry3d::shape::Ball::new(r as f32);
            let at = parry3d::math::Pose::from_translation(Vector::new(c.x as f32, c.y as f32, c.z as f32));
            let d = parry3d::query::distance(&pose, link.shape.as_ref(), &at, &ball)
                .unwrap()
                .distance;
            let clear = field.clears_ball(&c, r);
            assert!(!clear || d > 0.0, "ball at {c} radius {r} cleared at distance {d}");
            tested += usize::from(d > 0.02);
            cleared += usize::from(clear && d > 0.02);
        }
        assert!(
            cleared * 10 > tested * 9,
            "balls 2 cm clear are cleared: {cleared} of {tested}"
        );
    }
}
