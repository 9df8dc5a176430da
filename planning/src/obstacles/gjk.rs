//! An exact yes/no intersection test for pairs of boxes and cylinders: the
//! Gilbert–Johnson–Keerthi search for the origin in their Minkowski difference (Gilbert,
//! Johnson & Keerthi 1988), in `f64` with closed-form support points.
//!
//! [`ParryScene`](super::ParryScene)'s closed forms settle most part-versus-obstacle tests;
//! the rest (a cylinder against a box where no candidate axis separates them and no point is
//! found inside both, and anything against a cylindrical obstacle) used to go through parry's
//! generic GJK behind its shape dispatcher. This search asks no more than the two shapes'
//! support points and answers only when it is sure: `Some(false)` once a plane separates the
//! shapes by at least [`SEPARATION`], `Some(true)` once a tetrahedron of points of the
//! difference holds the origin, `None` (the caller asks parry) when the shapes are within
//! [`SEPARATION`] of touching or the search does not settle in [`MAX_ITERATIONS`] steps.

use nalgebra::Vector3;
use parry3d::math::{Real, Vector};

type V = Vector3<f64>;

/// Gap (m) that a separating plane must prove before the search answers `Some(false)`: far
/// above `f64` rounding at the size of robots and furniture, and about the `f32` rounding of
/// the poses the shapes come from.
const SEPARATION: f64 = 1e-7;
/// Distance (m) of the simplex from the origin within which a direction that fails to
/// separate the shapes by [`SEPARATION`] ends the search (`None`): they are that close to
/// touching.
const NEAR_CONTACT: f64 = 1e-5;
/// Steps after which the search gives up (`None`). Boxes and cylinders settle in a handful.
const MAX_ITERATIONS: usize = 48;
/// Steps reduced by the quick region tests of [`evolve`]; the rest by [`nearest_feature`].
/// The quick tests can drop a point the nearest feature needs, and then cycle through the
/// same few simplices (a pair of boxes 9.8 mm apart did, every four steps); the exact
/// reduction makes each step's simplex the one nearest the origin, which cannot cycle.
const QUICK_ITERATIONS: usize = 16;

/// A box or a cylinder in the world, the convex shapes the search takes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Convex {
    /// Centre, unit axes and half extents along them.
    Cuboid { center: V, axes: [V; 3], half: [f64; 3] },
    /// Centre, unit axis, half height along the axis and radius (flat caps). Build it with
    /// [`Convex::cylinder`], which makes the axis unit in `f64`.
    Cylinder {
        center: V,
        axis: V,
        half_height: f64,
        radius: f64,
    },
}

fn v(p: Vector) -> V {
    V::new(p.x as f64, p.y as f64, p.z as f64)
}

impl Convex {
    /// A box (centre, unit axes, half extents along them) from parry's `f32` values.
    pub(crate) fn cuboid(center: Vector, axes: [Vector; 3], half: Vector) -> Self {
        Convex::Cuboid {
            center: v(center),
            axes: axes.map(v),
            half: [half.x as f64, half.y as f64, half.z as f64],
        }
    }

    /// A cylinder from parry's `f32` values, its axis normalised again in `f64`: with an axis
    /// a few `f32` ulps off unit length, the side direction of a search direction almost
    /// along the axis would tilt out of the cross-section and put the support point
    /// millimetres outside the cylinder.
    pub(crate) fn cylinder(center: Vector, axis: Vector, half_height: Real, radius: Real) -> Self {
        Convex::Cylinder {
            center: v(center),
            axis: v(axis).normalize(),
            half_height: half_height as f64,
            radius: radius as f64,
        }
    }

    fn center(&self) -> V {
        match self {
            Convex::Cuboid { center, .. } | Convex::Cylinder { center, .. } => *center,
        }
    }

    /// A point of the shape farthest along `d`.
    #[inline]
    fn support(&self, d: &V) -> V {
        match self {
            Convex::Cuboid { center, axes, half } => {
                let mut p = *center;
                for k in 0..3 {
                    let s = if axes[k].dot(d) >= 0.0 { half[k] } else { -half[k] };
                    p += axes[k] * s;
                }
                p
            }
            Convex::Cylinder {
                center,
                axis,
                half_height,
                radius,
            } => {
                let along = axis.dot(d);
                let cap = if along >= 0.0 { *half_height } else { -*half_height };
                let side = d - axis * along;
                let len = side.norm();
                // A side direction shorter than rounding leaves (the search direction along
                // the axis) has no meaning: the cap's centre is a farthest point then.
                let rim = if len > 1e-9 * d.norm() {
                    side * (*radius / len)
                } else {
                    V::zeros()
                };
                center + axis * cap + rim
            }
        }
    }
}

/// Whether `a` and `b` share a point, where the search is sure (see the module docs).
pub(crate) fn touch(a: &Convex, b: &Convex) -> Option<bool> {
    let support = |d: &V| a.support(d) - b.support(&-d);
    let mut d = a.center() - b.center();
    if d.norm_squared() < 1e-24 {
        d = V::x();
    }
    let mut simplex = [V::zeros(); 4];
    simplex[0] = support(&d);
    let mut n = 1;
    d = -simplex[0];
    for step in 0..MAX_ITERATIONS {
        let len = d.norm();
        if len < 1e-12 {
            return None;
        }
        let p = support(&d);
        let reach = p.dot(&d) / len;
        if reach < -SEPARATION {
            return Some(false);
        }
        // No plane through the origin along `d` separates them. With the simplex's nearest
        // point within `NEAR_CONTACT` of the origin the shapes are that close to touching, which
        // is left to the caller; farther, this direction only failed to separate them (a box
        // 1.9 mm from a flat cylinder met such a direction with the simplex 27 mm away).
        if reach < SEPARATION && len <= NEAR_CONTACT {
            return None;
        }
        // The newest point first.
        simplex.copy_within(0..n, 1);
        simplex[0] = p;
        n += 1;
        let next = if step < QUICK_ITERATIONS {
            evolve(&mut simplex, &mut n, &mut d)
        } else {
            nearest_feature(&mut simplex, &mut n, &mut d)
        };
        match next {
            Step::Contains => return Some(true),
            Step::Unsure => return None,
            Step::Go => {}
        }
    }
    None
}

enum Step {
    /// The simplex holds the origin.
    Contains,
    /// The origin lies on the simplex's line: no direction to go on with.
    Unsure,
    /// The simplex was reduced and `d` points from it towards the origin.
    Go,
}

/// Reduces the simplex (newest point first) to the feature nearest the origin and sets the
/// next search direction.
fn evolve(s: &mut [V; 4], n: &mut usize, d: &mut V) -> Step {
    match *n {
        2 => line(s, n, d),
        3 => triangle(s, n, d),
        _ => tetrahedron(s, n, d),
    }
}

/// [`evolve`] by brute force, for the steps after [`QUICK_ITERATIONS`]: of every set of the
/// simplex's points whose affine hull's point nearest the origin lies inside them (all
/// barycentric weights positive), the nearest; the simplex becomes that set and `d` points
/// from that point to the origin. `Contains` when it is the whole tetrahedron, `Unsure` when
/// the origin lies on the simplex (to rounding) or no set qualifies.
fn nearest_feature(s: &mut [V; 4], n: &mut usize, d: &mut V) -> Step {
    let mut best: Option<(f64, u8, V)> = None;
    for mask in 1u8..(1 << *n) {
        let mut points = [V::zeros(); 4];
        let mut k = 0;
        for (i, p) in s.iter().enumerate().take(*n) {
            if mask & (1 << i) != 0 {
                points[k] = *p;
                k += 1;
            }
        }
        let Some(x) = affine_nearest(&points[..k]) else {
            continue;
        };
        let d2 = x.norm_squared();
        if best.is_none_or(|(b, ..)| d2 < b) {
            best = Some((d2, mask, x));
        }
    }
    let Some((d2, mask, x)) = best else {
        return Step::Unsure;
    };
    if *n == 4 && mask == 0b1111 {
        return Step::Contains;
    }
    let scale = s[..*n].iter().map(|p| p.norm_squared()).fold(0.0, f64::max);
    if d2 <= 1e-24 * scale {
        return Step::Unsure;
    }
    let mut k = 0;
    for i in 0..*n {
        if mask & (1 << i) != 0 {
            s[k] = s[i];
            k += 1;
        }
    }
    *n = k;
    *d = -x;
    Step::Go
}

/// The point of the affine hull of `points` (1 to 4 of them) nearest the origin, when it lies
/// strictly inside their convex hull; `None` when it does not, or when the points are
/// (nearly) affinely dependent.
fn affine_nearest(points: &[V]) -> Option<V> {
    let p0 = points[0];
    let m = points.len() - 1;
    if m == 0 {
        return Some(p0);
    }
    // x = p0 + E·μ nearest the origin: (EᵀE)·μ = −Eᵀp0, padded to 3 × 3 with the identity.
    let mut gram = nalgebra::Matrix3::identity();
    let mut rhs = V::zeros();
    let mut size = 1.0;
    for i in 0..m {
        let ei = points[i + 1] - p0;
        size *= ei.norm_squared();
        rhs[i] = -ei.dot(&p0);
        for j in 0..m {
            gram[(i, j)] = ei.dot(&(points[j + 1] - p0));
        }
    }
    if gram.determinant().abs() <= 1e-18 * size {
        return None;
    }
    let mu = gram.lu().solve(&rhs)?;
    let first = 1.0 - mu.iter().take(m).sum::<f64>();
    if first <= 0.0 || mu.iter().take(m).any(|&w| w <= 0.0) {
        return None;
    }
    Some((0..m).fold(p0, |x, i| x + (points[i + 1] - p0) * mu[i]))
}

fn line(s: &mut [V; 4], n: &mut usize, d: &mut V) -> Step {
    let (a, b) = (s[0], s[1]);
    let (ab, ao) = (b - a, -a);
    if ab.dot(&ao) > 0.0 {
        *d = ab.cross(&ao).cross(&ab);
        *n = 2;
        // The origin on the segment's line (to rounding): no direction off it.
        if d.norm_squared() <= 1e-20 * ab.norm_squared() * ab.norm_squared() * ao.norm_squared() {
            return Step::Unsure;
        }
    } else {
        *d = ao;
        *n = 1;
    }
    Step::Go
}

fn triangle(s: &mut [V; 4], n: &mut usize, d: &mut V) -> Step {
    let (a, b, c) = (s[0], s[1], s[2]);
    let (ab, ac, ao) = (b - a, c - a, -a);
    let normal = ab.cross(&ac);
    if normal.cross(&ac).dot(&ao) > 0.0 {
        if ac.dot(&ao) > 0.0 {
            s[1] = c;
            *n = 2;
            *d = ac.cross(&ao).cross(&ac);
            return Step::Go;
        }
        *n = 2;
        return line(s, n, d);
    }
    if ab.cross(&normal).dot(&ao) > 0.0 {
        *n = 2;
        return line(s, n, d);
    }
    *n = 3;
    if normal.dot(&ao) >= 0.0 {
        *d = normal;
    } else {
        s.swap(1, 2);
        *d = -normal;
    }
    Step::Go
}

fn tetrahedron(s: &mut [V; 4], n: &mut usize, d: &mut V) -> Step {
    let a = s[0];
    let ao = -a;
    // A flat tetrahedron cannot be trusted to hold the origin. (The newest point lies at least
    // `SEPARATION` beyond the triangle's plane, so this only catches a degenerate triangle.)
    let (ab, ac, ad) = (s[1] - a, s[2] - a, s[3] - a);
    let scale = ab.norm() * ac.norm() * ad.norm();
    if ab.dot(&ac.cross(&ad)).abs() <= 1e-12 * scale {
        return Step::Unsure;
    }
    for (p, q, r) in [(s[1], s[2], s[3]), (s[2], s[3], s[1]), (s[3], s[1], s[2])] {
        let mut normal = (p - a).cross(&(q - a));
        if normal.dot(&(r - a)) > 0.0 {
            normal = -normal;
        }
        if normal.dot(&ao) > 0.0 {
            (s[1], s[2]) = (p, q);
            *n = 3;
            return triangle(s, n, d);
        }
    }
    Step::Contains
}

#[cfg(test)]
pub(super) mod tests {
    use super::{Convex, V, touch};
    use nalgebra::{Rotation3, Unit};
    use parry3d::math::Vector;
    use proptest::prelude::*;

    fn axes(r: &Rotation3<f64>) -> [V; 3] {
        [r * V::x(), r * V::y(), r * V::z()]
    }

    fn f32s(p: V) -> Vector {
        Vector::new(p.x as f32, p.y as f32, p.z as f32)
    }

    /// A box as the scene builds one, from `f32` values.
    fn cuboid(c: V, r: &Rotation3<f64>, h: [f64; 3]) -> Convex {
        let half = Vector::new(h[0] as f32, h[1] as f32, h[2] as f32);
        Convex::cuboid(f32s(c), axes(r).map(f32s), half)
    }

    /// A cylinder as the scene builds one, from `f32` values, its axis two `f32` ulps longer
    /// than unit, as a rotated parry axis can be.
    fn cylinder(c: V, r: &Rotation3<f64>, h: f64, rad: f64) -> Convex {
        let axis = f32s(r * V::y()) * (1.0 + 2.0 * f32::EPSILON);
        Convex::cylinder(f32s(c), axis, h as f32, rad as f32)
    }

    /// parry's distance between the same two shapes (its GJK in f32).
    fn parry_distance(a: &Convex, b: &Convex) -> f32 {
        let ((sa, pa), (sb, pb)) = (parry_shape(a), parry_shape(b));
        parry3d::query::distance(&pa, sa.as_ref(), &pb, sb.as_ref())
            .unwrap()
            .distance
    }

    /// How deep parry finds the two shapes overlapping (its EPA in f32), 0 when apart.
    pub(in crate::obstacles) fn parry_depth(a: &Convex, b: &Convex) -> f32 {
        let ((sa, pa), (sb, pb)) = (parry_shape(a), parry_shape(b));
        parry3d::query::contact(&pa, sa.as_ref(), &pb, sb.as_ref(), 0.0)
            .unwrap()
            .map_or(0.0, |c| (-c.dist).max(0.0))
    }

    /// The signed distance parry's contact query reports (negative when overlapping), looking
    /// up to 1 cm apart; infinite beyond.
    fn parry_contact_distance(a: &Convex, b: &Convex) -> f32 {
        let ((sa, pa), (sb, pb)) = (parry_shape(a), parry_shape(b));
        parry3d::query::contact(&pa, sa.as_ref(), &pb, sb.as_ref(), 0.01)
            .unwrap()
            .map_or(f32::INFINITY, |c| c.dist)
    }

    /// The point of `s` nearest `x`, in closed form: clamped in the box's frame, or clamped
    /// along the cylinder's axis and then radially.
    pub(in crate::obstacles) fn project(s: &Convex, x: V) -> V {
        match *s {
            Convex::Cuboid { center, axes, half } => {
                let r = x - center;
                (0..3).fold(center, |p, k| p + axes[k] * r.dot(&axes[k]).clamp(-half[k], half[k]))
            }
            Convex::Cylinder {
                center,
                axis,
                half_height,
                radius,
            } => {
                let r = x - center;
                let along = r.dot(&axis);
                let side = r - axis * along;
                let len = side.norm();
                let side = if len > radius { side * (radius / len) } else { side };
                center + axis * along.clamp(-half_height, half_height) + side
            }
        }
    }

    /// Bounds (lower, upper) on the distance between `a` and `b` that share nothing with the
    /// search but the shapes' support points: alternating projections from `a`'s centre (each
    /// step's pair of points gives an upper bound, and they converge to a nearest pair), then
    /// the plane across the last pair's direction (a lower bound, negative when it fails to
    /// separate them). On 20,000 random pairs they left 8 undecided: neither apart nor within
    /// 50 nm of a common point.
    pub(in crate::obstacles) fn distance_bounds(a: &Convex, b: &Convex) -> (f64, f64) {
        let mut pa = project(a, a.center());
        let mut pb = project(b, pa);
        for _ in 0..20_000 {
            let next_a = project(a, pb);
            let next_b = project(b, next_a);
            let moved = (next_a - pa).norm() + (next_b - pb).norm();
            (pa, pb) = (next_a, next_b);
            if moved < 1e-14 || (pb - pa).norm() < 1e-9 {
                break;
            }
        }
        let upper = (pb - pa).norm();
        if upper < 1e-12 {
            return (0.0, upper);
        }
        let n = (pb - pa) / upper;
        let lower = b.support(&-n).dot(&n) - a.support(&n).dot(&n);
        (lower, upper)
    }

    /// The parry shape and pose of `s`.
    pub(in crate::obstacles) fn parry_shape(s: &Convex) -> (Box<dyn parry3d::shape::Shape>, parry3d::math::Pose) {
        use parry3d::math::{Pose, Rotation, Vector};
        use parry3d::shape::{Cuboid, Cylinder};
        let pose = |c: V, ax: [V; 3]| {
            let m = nalgebra::Matrix3::from_columns(&ax);
            let q = nalgebra::UnitQuaternion::from_matrix(&m);
            Pose::from_parts(
                f32s(c),
                Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32),
            )
        };
        match *s {
            Convex::Cuboid { center, axes, half } => (
                Box::new(Cuboid::new(Vector::new(half[0] as f32, half[1] as f32, half[2] as f32))),
                pose(center, axes),
            ),
            Convex::Cylinder {
                center,
                axis,
                half_height,
                radius,
            } => {
                let x = if axis.x.abs() < 0.9 { V::x() } else { V::z() };
                let ex = axis.cross(&x).normalize();
                let ez = ex.cross(&axis);
                (
                    Box::new(Cylinder::new(half_height as f32, radius as f32)),
                    pose(center, [ex, axis, ez]),
                )
            }
        }
    }

    fn rotation(v: [f64; 3], angle: f64) -> Rotation3<f64> {
        let axis = V::new(v[0], v[1], v[2]);
        if axis.norm() < 1e-3 {
            return Rotation3::identity();
        }
        Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle)
    }

    fn shape(kind: bool, c: V, r: Rotation3<f64>, a: f64, b: f64, e: f64) -> Convex {
        if kind {
            cuboid(c, &r, [a, b, e])
        } else {
            cylinder(c, &r, a, b)
        }
    }

    /// A shape of a recorded case, in the property test's terms: a box (`true`) or a
    /// cylinder, its centre, the axis and angle of its rotation, and the three dimensions
    /// [`shape`] takes.
    pub(in crate::obstacles) fn case(kind: bool, c: [f64; 3], axis: [f64; 3], angle: f64, d: [f64; 3]) -> Convex {
        shape(kind, V::from(c), rotation(axis, angle), d[0], d[1], d[2])
    }

    /// The search's answer, asserted to be the same both ways round.
    fn touch_both(a: &Convex, b: &Convex) -> Option<bool> {
        let ab = touch(a, b);
        assert_eq!(ab, touch(b, a), "the answer depends on the order");
        ab
    }

    #[test]
    fn plain_cases() {
        let id = Rotation3::identity();
        let board = cuboid(V::zeros(), &id, [0.5, 0.5, 0.01]);
        let standing = |z: f64| {
            cylinder(
                V::new(0.1, 0.0, z),
                &rotation([1.0, 0.0, 0.0], std::f64::consts::FRAC_PI_2),
                0.1,
                0.03,
            )
        };
        // A cylinder standing on its cap over a thin board (axis along z after the turn).
        assert_eq!(touch(&standing(0.2), &board), Some(false));
        assert_eq!(touch(&standing(0.105), &board), Some(true));
        assert_eq!(touch(&standing(0.0), &board), Some(true));
        // Lying across the board's edge, just beyond it and just over it.
        let lying = |x: f64| cylinder(V::new(x, 0.0, 0.0), &id, 0.2, 0.03);
        assert_eq!(touch(&lying(0.52), &board), Some(true));
        assert_eq!(touch(&lying(0.54), &board), Some(false));
        // Two cylinders: parallel and apart, crossed and touching.
        let a = cylinder(V::zeros(), &id, 0.2, 0.05);
        assert_eq!(
            touch(&a, &cylinder(V::new(0.11, 0.0, 0.0), &id, 0.2, 0.05)),
            Some(false)
        );
        let crossed = rotation([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
        assert_eq!(
            touch(&a, &cylinder(V::new(0.0, 0.0, 0.09), &crossed, 0.2, 0.05)),
            Some(true)
        );
        // The same shape at the same place: the origin lies on every simplex the symmetric
        // difference offers, so the search may leave it to parry, but never says apart.
        assert_ne!(touch(&board, &board), Some(false));
    }

    /// A Fetch gripper box 0.3 mm below a can's bottom cap (parry's distance and an
    /// independent minimisation agree on the gap), the can's axis two `f32` ulps short of unit
    /// length as the scene stores it. Before the axis was normalised again, the search met a
    /// support point 6.7 mm below the cap and reported contact.
    #[test]
    fn a_cylinder_axis_off_unit_length_keeps_its_support_points_on_the_cylinder() {
        let gripper = Convex::cuboid(
            Vector::new(0.33620304, 0.7117336, 0.34433848),
            [
                Vector::new(-0.088_885_29, 0.885_898_8, -0.455_283_1),
                Vector::new(-0.016632438, 0.45570844, 0.8899737),
                Vector::new(0.995_903, 0.086_678_03, -0.025_771_11),
            ],
            Vector::new(0.036, 0.0105, 0.018),
        );
        let can = Convex::cylinder(
            Vector::new(0.37385216, 0.7083426, 0.44),
            Vector::new(0.0, 2.980_232_2e-8, 1.0 - f32::EPSILON),
            0.07,
            0.03,
        );
        assert_eq!(touch(&gripper, &can), Some(false));
        assert_eq!(touch(&can, &gripper), Some(false));
    }

    /// Two boxes 9.8 mm apart (parry's distance) on which the quick region tests cycle through
    /// the same four simplices: the exact reduction after them finds the gap, both ways round.
    #[test]
    fn boxes_that_cycle_the_quick_steps_are_found_apart() {
        let a = case(
            true,
            [0.2335184443914514, 0.044671568462213956, -0.021975402340657944],
            [-0.34504790876118663, -0.6858111939455243, -0.24472981259952453],
            -3.178601409589722,
            [0.059243336182449466, 0.15064482497703532, 0.10087402264150984],
        );
        let b = case(
            true,
            [-0.10312605338813129, 0.09629715138315685, -0.2180019583973017],
            [0.41542853534829305, 0.48824158947494756, -0.7936531007957252],
            1.1798130305286763,
            [0.047335543645589895, 0.14871583386850523, 0.17065349716255868],
        );
        assert!((parry_distance(&a, &b) - 0.0098).abs() < 1e-4);
        assert_eq!(touch_both(&a, &b), Some(false));
    }

    /// A thin rod 2.4 mm beside a long box: a separating plane shows the gap (the box's
    /// farthest point along it −0.10528, the rod's nearest −0.10291), and parry's contact
    /// query measures 2.3 mm, but parry's distance query calls the two touching. The search
    /// finds them apart both ways round, and alternating projections bound the gap below.
    #[test]
    fn a_rod_beside_a_box_is_apart_where_parrys_distance_says_touching() {
        let a = case(
            true,
            [-0.29205482797856797, -0.0551462316605587, -0.2104450665486572],
            [0.05743025347379196, -0.12931100809740476, -0.2064084727646512],
            -0.500564804472953,
            [0.07221259732538152, 0.015151300474150314, 0.2431521951115654],
        );
        let b = case(
            false,
            [-0.01935255387093831, -0.05915222990057486, 0.16575927697795925],
            [0.7920670731433355, 0.5941383752318009, 0.3724927806763808],
            2.701675838101376,
            [0.22358129541594163, 0.02250989939328075, 0.005],
        );
        assert_eq!(parry_distance(&a, &b), 0.0);
        assert!((parry_contact_distance(&a, &b) - 0.0023).abs() < 1e-4);
        assert!(distance_bounds(&a, &b).0 > 0.0023);
        assert_eq!(touch_both(&a, &b), Some(false));
    }

    /// A flat cylinder 1.9 mm from a box (parry's distance and contact queries agree). One way
    /// round, the search met a direction along which the difference reaches the origin's
    /// plane while its simplex was still 27 mm away, and gave up; it now searches on.
    #[test]
    fn a_direction_that_fails_to_separate_far_from_contact_does_not_end_the_search() {
        let a = case(
            false,
            [0.12653560690143134, 0.10034154125407911, 0.24153363725010607],
            [0.4023364421630917, 0.09209927124986128, 0.9635031033653064],
            2.3322922537883666,
            [0.20546101847772474, 0.15101200359886097, 0.005],
        );
        let b = case(
            true,
            [0.25526687466334663, -0.07642842226491763, 0.03626481925461293],
            [-0.3127273227930586, -0.6990231262566216, -0.4274916552648053],
            -0.3008969180341953,
            [0.16455787558584334, 0.08130079142118658, 0.059472206009534234],
        );
        assert!((parry_distance(&a, &b) - 0.0019).abs() < 1e-4);
        assert_eq!(touch_both(&a, &b), Some(false));
    }

    /// Two fat cylinders whose rims cross by 71 µm (an independent maximisation of the
    /// separating gap over directions finds none better than −71 µm), which parry's distance
    /// query puts 5.0 mm apart and its contact query 3.8 mm (parry's issue 396 reports
    /// overlapping cylinders its intersection test calls apart). The search finds them
    /// touching both ways round, and so do alternating projections.
    #[test]
    fn crossed_cylinder_rims_touch_where_parry_measures_a_gap() {
        let a = case(
            false,
            [-0.09430963990525013, -0.07690310651620252, -0.1605112230119456],
            [0.07636588284115754, -0.7322971959854035, 0.5223013789410742],
            -0.8329414550628828,
            [0.11161392656384565, 0.16508026287833516, 0.005],
        );
        let b = case(
            false,
            [0.2796881887315925, -0.03576378897133392, -0.1305220327771132],
            [-0.6555674372049116, -0.6467608410669616, -0.6105929259375106],
            -2.7181363931862883,
            [0.11653100403513764, 0.14324138050620908, 0.005],
        );
        // parry's shapes are these shapes (its support points agree to 0.2 µm)...
        for s in [&a, &b] {
            let (shape, pose) = parry_shape(s);
            let map = shape.as_support_map().unwrap();
            for i in 0..1000 {
                let t = i as f64 * 0.37;
                let d = V::new(t.sin(), (t * 1.7).cos(), (t * 0.3).sin() - 0.2);
                let p = map.support_point(&pose, f32s(d));
                let q = s.support(&d);
                assert!((V::new(p.x as f64, p.y as f64, p.z as f64) - q).norm() < 2e-7);
            }
        }
        // ...but its distance query finds a gap that alternating projections close.
        assert!(parry_distance(&a, &b) > 0.003);
        assert!(distance_bounds(&a, &b).1 < 1e-9);
        assert_eq!(touch_both(&a, &b), Some(true));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]

        /// Against the bounds of [`distance_bounds`]: never a contact where the shapes are
        /// surely a tenth of a millimetre apart, never a gap where they are within 50 nm of a
        /// common point, the same answer both ways round, and an answer for every pair surely
        /// a millimetre apart or overlapping by a millimetre (parry's depth, asked only where
        /// the projections find a common point). parry's distance is no reference here: it
        /// calls shapes touching that a plane separates by 2.4 mm and puts crossed cylinders
        /// 5 mm apart (the tests above).
        #[test]
        fn agrees_with_alternating_projections(
            ka in any::<bool>(), kb in any::<bool>(),
            ca in prop::array::uniform3(-0.3..0.3f64), cb in prop::array::uniform3(-0.3..0.3f64),
            ra in prop::array::uniform3(-1.0..1.0f64), rb in prop::array::uniform3(-1.0..1.0f64),
            aa in -3.2..3.2f64, ab in -3.2..3.2f64,
            da in prop::array::uniform3(0.005..0.25f64), db in prop::array::uniform3(0.005..0.25f64),
        ) {
            let a = case(ka, ca, ra, aa, da);
            let b = case(kb, cb, rb, ab, db);
            let (lower, upper) = distance_bounds(&a, &b);
            let ours = touch(&a, &b);
            let other = touch(&b, &a);
            prop_assert!(ours.is_none() || other.is_none() || ours == other, "{:?} one way, {:?} the other", ours, other);
            if lower > 1e-4 {
                prop_assert_ne!(ours, Some(true), "apart by at least {}", lower);
            }
            if lower > 1e-3 {
                prop_assert_eq!(ours, Some(false), "apart by at least {}", lower);
            }
            // Within 50 nm of a common point, half the gap a separating plane must prove.
            if upper < 5e-8 {
                prop_assert_ne!(ours, Some(false), "a common point within {}", upper);
                if parry_depth(&a, &b) > 1e-3 {
                    prop_assert_eq!(ours, Some(true), "parry finds them overlapping");
                }
            }
        }
    }
}
