//! Conservative sphere covers of link collision shapes: a few balls whose union contains the
//! whole link, so that "no ball touches anything" proves "the link touches nothing". Planners
//! use them as a broad phase before exact parry tests.
//!
//! How a cover is built (once per model, on first use):
//! 1. Every convex part of the link's shape is sampled on a grid in its own frame, spacing at
//!    most [`GRID_STEP`] (coarser for big parts). Every point of the part lies in a grid cell,
//!    within half the cell diagonal `h` of one of the cell's corners, so keeping the grid
//!    points that lie within `h` of the part (parry's solid point distance) loses nothing.
//!    Non-convex parts keep every grid point of their bounding box.
//! 2. The points are clustered (farthest-point seeds, then Lloyd iterations, deterministic).
//! 3. Each cluster becomes a ball around its centre with radius = the largest distance to one
//!    of its points + that point's `h`. Every point of the part is within `h` of a kept grid
//!    point, and that grid point lies in some ball shrunk by `h`, so the balls cover the part.

use std::sync::{Arc, Mutex};

use nalgebra::Point3;
use parry3d::math::{Pose, Vector};
use parry3d::shape::Shape;

use crate::model::{LinkShape, RobotModel};
use crate::per_link::{BuiltinCache, per_link};

/// Covers of every link of `model` (see [`crate::per_link`]).
pub(crate) fn covers(model: &RobotModel) -> Arc<Vec<Vec<Sphere>>> {
    static BUILTIN: BuiltinCache<Vec<Sphere>> = Mutex::new(Vec::new());
    per_link(model, &BUILTIN, cover)
}

/// Finest grid spacing (m) used to sample a part.
///
/// ```
/// use hearth_kinematics::spheres::{GRID_STEP, TARGET};
/// assert!(GRID_STEP > 0.0 && GRID_STEP < 0.01); // millimetre scale
/// assert!(TARGET > 1.0);
/// ```
pub const GRID_STEP: f64 = 0.004;
/// Most grid points one part is sampled with (coarser spacing for big parts).
const MAX_POINTS_PER_PART: f64 = 4_000.0;
/// Most balls in one link's cover.
///
/// ```
/// use hearth_kinematics::LinkShape;
/// use hearth_kinematics::spheres::{MAX_SPHERES, cover};
/// use parry3d::shape::SharedShape;
/// // A thin 2 m pole would need far more balls to be covered tightly.
/// let pole = LinkShape { shape: SharedShape::cylinder(1.0, 0.01), origin: nalgebra::Isometry3::identity() };
/// assert_eq!(cover(&pole).len(), MAX_SPHERES);
/// ```
pub const MAX_SPHERES: usize = 16;
/// Ball spacing along a link as a fraction of its second extent.
const SPACING: f64 = 0.35;
/// A cover is tight enough when its biggest ball is at most this many times half the link's
/// smallest extent (plus the sampling slack).
///
/// ```
/// use hearth_kinematics::LinkShape;
/// use hearth_kinematics::spheres::{GRID_STEP, TARGET, cover};
/// use parry3d::shape::SharedShape;
/// // A rod of radius 3 cm and length 30 cm: the biggest ball stays near the rod's radius.
/// let rod = LinkShape { shape: SharedShape::cylinder(0.15, 0.03), origin: nalgebra::Isometry3::identity() };
/// let biggest = cover(&rod).iter().map(|s| s.radius).fold(0.0, f64::max);
/// assert!(biggest <= TARGET * 0.03 + 2.0 * GRID_STEP);
/// ```
pub const TARGET: f64 = 1.3;
/// Lloyd iterations.
const ITERATIONS: usize = 12;

/// A ball in a link's frame.
///
/// ```
/// use hearth_kinematics::spheres::Sphere;
/// use nalgebra::Point3;
/// let s = Sphere { center: Point3::new(0.0, 0.0, 0.1), radius: 0.05 };
/// assert!((Point3::new(0.0, 0.03, 0.1) - s.center).norm() <= s.radius);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre in the link frame.
    pub center: Point3<f64>,
    /// Radius (m).
    pub radius: f64,
}

/// Sample points of a link shape in the link frame, each with the distance within which it
/// stands for every point of the shape near it.
fn samples(link: &LinkShape) -> Vec<(Point3<f64>, f64)> {
    let mut out = Vec::new();
    let mut add = |pose: &Pose, part: &dyn Shape| {
        let aabb = part.compute_local_aabb();
        let (lo, hi) = (aabb.mins, aabb.maxs);
        let ext = hi - lo;
        if !(ext.is_finite() && ext.min_element() >= 0.0) {
            return;
        }
        let volume = (f64::from(ext.x) + GRID_STEP) * (f64::from(ext.y) + GRID_STEP) * (f64::from(ext.z) + GRID_STEP);
        let step = GRID_STEP.max((volume / MAX_POINTS_PER_PART).cbrt());
        let n = |e: f32| ((f64::from(e) / step).ceil() as usize).max(1);
        let (nx, ny, nz) = (n(ext.x), n(ext.y), n(ext.z));
        let (sx, sy, sz) = (
            f64::from(ext.x) / nx as f64,
            f64::from(ext.y) / ny as f64,
            f64::from(ext.z) / nz as f64,
        );
        let h = 0.5 * (sx * sx + sy * sy + sz * sz).sqrt();
        let convex = part.is_convex();
        for i in 0..=nx {
            for j in 0..=ny {
                for k in 0..=nz {
                    let p = Vector::new(
                        (f64::from(lo.x) + i as f64 * sx) as f32,
                        (f64::from(lo.y) + j as f64 * sy) as f32,
                        (f64::from(lo.z) + k as f64 * sz) as f32,
                    );
                    if convex && f64::from(part.distance_to_local_point(p, true)) > h {
                        continue;
                    }
                    let w = pose.transform_point(p);
                    let w = link.origin * Point3::new(f64::from(w.x), f64::from(w.y), f64::from(w.z));
                    out.push((w, h));
                }
            }
        }
    };
    if let Some(compound) = link.shape.as_compound() {
        for (pose, part) in compound.shapes() {
            add(pose, part.as_ref());
        }
    } else {
        add(&Pose::IDENTITY, link.shape.as_ref());
    }
    out
}

/// How many balls to use for points whose bounding box has sorted extents `e` (largest
/// first): about one per half of the second extent along the first, so a rod of radius r and
/// length L gets about L / r balls.
fn ball_count(e: [f64; 3]) -> usize {
    let across = e[1].max(1e-3);
    ((e[0] / (SPACING * across)).round() as usize).clamp(1, MAX_SPHERES)
}

/// A cover of `link` by at most [`MAX_SPHERES`] balls (empty if the shape has no finite
/// extent, in which case callers must fall back to exact tests). More balls are used until
/// the biggest is within [`TARGET`] of half the link's smallest extent (a rod's radius).
///
/// ```
/// use hearth_kinematics::{LinkShape, spheres::cover};
/// use nalgebra::{Isometry3, Point3};
/// use parry3d::shape::SharedShape;
/// let bar = LinkShape { shape: SharedShape::cuboid(0.3, 0.04, 0.04), origin: Isometry3::translation(0.0, 0.0, 1.0) };
/// let balls = cover(&bar);
/// assert!(balls.len() > 1); // a long bar needs several balls
/// // Every corner of the bar lies in some ball.
/// for corner in [Point3::new(0.3, 0.04, 1.04), Point3::new(-0.3, -0.04, 0.96)] {
///     assert!(balls.iter().any(|b| (corner - b.center).norm() <= b.radius));
/// }
/// ```
pub fn cover(link: &LinkShape) -> Vec<Sphere> {
    let pts = samples(link);
    if pts.is_empty() {
        return Vec::new();
    }
    let mut lo = pts[0].0;
    let mut hi = pts[0].0;
    for (p, _) in &pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let mut e = [hi.x - lo.x, hi.y - lo.y, hi.z - lo.z];
    e.sort_by(|a, b| b.total_cmp(a));
    let h = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let target = TARGET * 0.5 * e[2] + h;
    let mut k = ball_count(e).min(pts.len());
    loop {
        let balls = cluster(&pts, k);
        if k >= MAX_SPHERES.min(pts.len()) || balls.iter().all(|b| b.radius <= target) {
            return balls;
        }
        k += 1;
    }
}

/// `k` balls around clusters of `pts` (farthest-point seeds, Lloyd iterations).
fn cluster(pts: &[(Point3<f64>, f64)], k: usize) -> Vec<Sphere> {
    let centroid =
        Point3::from(pts.iter().fold(nalgebra::Vector3::zeros(), |s, (p, _)| s + p.coords) / pts.len() as f64);
    let mut centers = Vec::with_capacity(k);
    let mut dist = vec![f64::INFINITY; pts.len()];
    let mut next = far_from(pts, &centroid);
    for _ in 0..k {
        let c = pts[next].0;
        centers.push(c);
        for (d, (p, _)) in dist.iter_mut().zip(pts) {
            *d = d.min((p - c).norm_squared());
        }
        next = dist
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
    }
    let cols = Columns::new(pts);
    let mut owner = vec![0usize; pts.len()];
    let mut best = vec![0.0; pts.len()];
    for _ in 0..ITERATIONS {
        assign(&cols, &centers, &mut owner, &mut best);
        let mut sum = vec![(nalgebra::Vector3::zeros(), 0usize); centers.len()];
        // The running sum of the current owner stays in registers while the owner repeats
        // (neighbouring grid points mostly share one): the same additions in the same order.
        let mut at = owner.first().copied().unwrap_or(0);
        let mut run = (nalgebra::Vector3::zeros(), 0usize);
        for ((p, _), &o) in pts.iter().zip(&owner) {
            if o != at {
                sum[at] = run;
                at = o;
                run = sum[o];
            }
            run.0 += p.coords;
            run.1 += 1;
        }
        if !owner.is_empty() {
            sum[at] = run;
        }
        for (c, (s, n)) in centers.iter_mut().zip(sum) {
            if n > 0 {
                *c = Point3::from(s / n as f64);
            }
        }
    }
    assign(&cols, &centers, &mut owner, &mut best);
    let mut radius = vec![f64::NEG_INFINITY; centers.len()];
    for ((p, h), &o) in pts.iter().zip(&owner) {
        radius[o] = radius[o].max((p - centers[o]).norm() + h);
    }
    centers
        .into_iter()
        .zip(radius)
        .filter(|(_, r)| r.is_finite())
        .map(|(center, radius)| Sphere { center, radius })
        .collect()
}

fn far_from(pts: &[(Point3<f64>, f64)], c: &Point3<f64>) -> usize {
    pts.iter()
        .enumerate()
        .max_by(|a, b| (a.1.0 - c).norm_squared().total_cmp(&(b.1.0 - c).norm_squared()))
        .map_or(0, |(i, _)| i)
}

/// Points as separate coordinate arrays, so that [`assign`] runs several points per
/// instruction.
struct Columns {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
}

impl Columns {
    fn new(pts: &[(Point3<f64>, f64)]) -> Self {
        Self {
            x: pts.iter().map(|p| p.0.x).collect(),
            y: pts.iter().map(|p| p.0.y).collect(),
            z: pts.iter().map(|p| p.0.z).collect(),
        }
    }
}

/// Each point to the centre that needs the smallest ball to hold it (the first such centre
/// on ties). `best` is scratch space of one value per point.
fn assign(cols: &Columns, centers: &[Point3<f64>], owner: &mut [usize], best: &mut [f64]) {
    best.fill(f64::INFINITY);
    for (i, c) in centers.iter().enumerate() {
        let rows = cols.x.iter().zip(&cols.y).zip(&cols.z);
        for (((&x, &y), &z), (b, o)) in rows.zip(best.iter_mut().zip(owner.iter_mut())) {
            let (dx, dy, dz) = (x - c.x, y - c.y, z - c.z);
            let d = dx * dx + dy * dy + dz * dz;
            let nearer = d < *b;
            *b = if nearer { d } else { *b };
            *o = if nearer { i } else { *o };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RobotModel;

    /// Every point of every part (sampled far finer than the cover's grid, surfaces and
    /// interiors) lies in some ball.
    #[test]
    fn covers_contain_every_point_of_the_links() {
        for robot in ["panda", "fetch"] {
            let m = RobotModel::builtin(robot).unwrap();
            for l in 0..m.links().len() {
                let Some(shape) = m.link_shape(l) else { continue };
                let balls = m.link_spheres(l);
                assert!(!balls.is_empty() && balls.len() <= MAX_SPHERES, "{robot} link {l}");
                let parts: Vec<(Pose, &dyn Shape)> = match shape.shape.as_compound() {
                    Some(c) => c.shapes().iter().map(|(p, s)| (*p, s.as_ref())).collect(),
                    None => vec![(Pose::IDENTITY, shape.shape.as_ref())],
                };
                for (pose, part) in parts {
                    let aabb = part.compute_local_aabb();
                    let n = 9;
                    for i in 0..=n {
                        for j in 0..=n {
                            for k in 0..=n {
                                let t = |lo: f32, hi: f32, s: usize| lo + (hi - lo) * s as f32 / n as f32;
                                let p = Vector::new(
                                    t(aabb.mins.x, aabb.maxs.x, i),
                                    t(aabb.mins.y, aabb.maxs.y, j),
                                    t(aabb.mins.z, aabb.maxs.z, k),
                                );
                                if !part.contains_local_point(p) {
                                    continue;
                                }
                                let w = pose.transform_point(p);
                                let w = shape.origin * Point3::new(f64::from(w.x), f64::from(w.y), f64::from(w.z));
                                assert!(
                                    balls.iter().any(|b| (w - b.center).norm() <= b.radius + 1e-9),
                                    "{robot} link {} point {w} outside its cover",
                                    m.links()[l].name
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// The cover is tight: its balls hold little more volume than the link's bounding ball.
    #[test]
    fn covers_are_tighter_than_one_bounding_ball() {
        let m = RobotModel::builtin("panda").unwrap();
        let l = m.link_index("panda_link3").unwrap();
        let one = m.link_shape(l).unwrap().shape.compute_local_bounding_sphere().radius();
        let balls = m.link_spheres(l);
        assert!(balls.len() > 1);
        let biggest = balls.iter().map(|b| b.radius).fold(0.0, f64::max);
        assert!(biggest < 0.8 * f64::from(one), "{biggest} vs {one}");
    }
}
