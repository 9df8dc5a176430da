//! Contacts between shapes for [`Obstacles::contact`], without allocation for convex pairs and
//! composite obstacles: the separating-axis test for overlapping boxes; for a cylinder and a
//! box the exact `f64` search, then their least overlap in closed form (`cylinder_box`); for
//! other shapes parry's GJK, then its EPA for overlapping shapes, with its buffers kept per
//! thread.

use std::cell::RefCell;

use nalgebra::Vector3;

use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::{Pose, Real, Vector};
use parry3d::query::epa::EPA;
use parry3d::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d::query::{self};
use parry3d::shape::{Shape, SupportMap};

use super::ObstacleContact;
#[cfg(doc)]
use super::Obstacles;
use super::cylinder_box::{box_support, cylinder_box_depth, cylinder_support};
use super::gjk::touch;
use super::scene::convex_at;

/// Where `shape` at `pose` touches `other` at `other_pose`, counting a gap of up to `margin`
/// as contact ([`ObstacleContact`], its distance less the margin), or `None`: the answer of
/// every [`Obstacles::contact`] in the workspace (`ParryScene` and the live world's view).
/// Balls take parry's closed forms; two overlapping boxes the separating-axis test (their
/// least overlap over fifteen axes: the exact depth, where parry's EPA can fall a fifth
/// short on deep overlaps); a cylinder and a box the exact search in `f64`, then where they
/// overlap their least overlap (never short of the depth, where the EPA can be); other
/// convex pairs GJK and the per-thread EPA, which parry's own `query::contact` would build
/// anew for each overlap; a composite obstacle (a
/// triangle mesh, a polyline, a compound) the deepest contact of its parts near the shape,
/// found by its own bounding-volume tree; the rest (height fields, composite robot parts)
/// parry's `query::contact`.
///
/// ```
/// use hearth_planning::obstacles::shape_contact;
/// use parry3d::math::{Pose, Vector};
/// use parry3d::shape::Cuboid;
///
/// let block = Cuboid::new(Vector::splat(0.1));
/// let floor = Cuboid::new(Vector::splat(0.5));
/// let under = Pose::translation(0.0, 0.0, -0.5);
/// let c = shape_contact(&block, &Pose::translation(0.0, 0.0, 0.08), &floor, &under, 0.0).unwrap();
/// assert!((c.distance + 0.02).abs() < 1e-6 && (c.normal.z + 1.0).abs() < 1e-6);
/// assert!(shape_contact(&block, &Pose::translation(0.0, 0.0, 0.15), &floor, &under, 0.0).is_none());
/// let near = shape_contact(&block, &Pose::translation(0.0, 0.0, 0.15), &floor, &under, 0.1).unwrap();
/// assert!((near.distance - (0.05 - 0.1)).abs() < 1e-6); // within the margin: overlap
/// ```
pub fn shape_contact(
    shape: &dyn Shape,
    pose: &Pose,
    other: &dyn Shape,
    other_pose: &Pose,
    margin: Real,
) -> Option<ObstacleContact> {
    if let (Some(a), Some(b)) = (shape.as_cuboid(), other.as_cuboid())
        && let Some((p, n, d)) = cuboids_overlap(&pose.inv_mul(other_pose), a.half_extents, b.half_extents)
    {
        return Some(ObstacleContact {
            point: *pose * p,
            normal: pose.rotation * n,
            distance: d - margin,
        });
    }
    if let (Some(a), Some(b)) = (shape.as_support_map(), other.as_support_map())
        && shape.as_ball().is_none()
        && other.as_ball().is_none()
    {
        let pos12 = pose.inv_mul(other_pose);
        let (p, n, d) = match cylinder_box_contact(shape, other, &pos12, margin) {
            Some(settled) => settled?,
            None => support_map_contact(&pos12, a, b, margin)?,
        };
        return Some(ObstacleContact {
            point: *pose * p,
            normal: pose.rotation * n,
            distance: d - margin,
        });
    }
    if let Some(composite) = other.as_composite_shape() {
        // The deepest contact among the parts (a mesh's triangles, a compound's shapes) that
        // the composite's own tree finds near the shape, as parry's composite query answers;
        // each part is a pair for the branches above, so no part builds an EPA.
        let near = shape.compute_aabb(&other_pose.inv_mul(pose)).loosened(margin);
        let mut deepest: Option<ObstacleContact> = None;
        for id in composite.bvh().intersect_aabb(&near) {
            composite.map_part_at(id, &mut |at, part, _| {
                let at = at.map_or(*other_pose, |at| *other_pose * *at);
                if let Some(c) = shape_contact(shape, pose, part, &at, margin)
                    && deepest.is_none_or(|d| c.distance < d.distance)
                {
                    deepest = Some(c);
                }
            });
        }
        return deepest;
    }
    let c = query::contact(pose, shape, other_pose, other, margin).ok()??;
    Some(ObstacleContact {
        point: c.point1,
        normal: c.normal1,
        distance: c.dist - margin,
    })
}

/// Contact of two overlapping boxes by the separating-axis test, in `f64`: box `a` (half
/// extents `ha`) at the origin of its frame, box `b` (half extents `hb`) placed at `pos12` in
/// it. `None` when one of the fifteen candidate axes (the boxes' face normals and the cross
/// products of their edges) separates them; the caller then measures the gap. Otherwise
/// `a`'s point on its supporting feature along the normal nearest `b`'s centre, the unit
/// normal from `a` towards `b` along which they overlap least, and the signed distance (minus
/// that overlap): the penetration depth of two convex polyhedra is their least overlap over
/// these axes, so this is the depth and normal that the EPA approximates, found in a few
/// dozen operations instead of a polytope's expansion. (Retraction asks for such contacts by the thousand a
/// second among box-shaped links and shelf boards.)
fn cuboids_overlap(pos12: &Pose, ha: Vector, hb: Vector) -> Option<(Vector, Vector, Real)> {
    type V3 = [f64; 3];
    let d3 = |v: Vector| [f64::from(v.x), f64::from(v.y), f64::from(v.z)];
    let dot = |u: V3, v: V3| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let (t, ha, hb) = (d3(pos12.translation), d3(ha), d3(hb));
    let rot = pos12.rotation;
    let b_axes = [d3(rot * Vector::X), d3(rot * Vector::Y), d3(rot * Vector::Z)];
    // How far the boxes' projections on the unit axis `l` overlap (negative: a gap).
    let overlap = |l: V3| {
        let ra = ha[0] * l[0].abs() + ha[1] * l[1].abs() + ha[2] * l[2].abs();
        let rb = (0..3).map(|j| hb[j] * dot(b_axes[j], l).abs()).sum::<f64>();
        ra + rb - dot(t, l).abs()
    };
    let mut least = (f64::INFINITY, [0.0; 3]);
    let a_axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for l in a_axes.into_iter().chain(b_axes) {
        let o = overlap(l);
        if o < 0.0 || o.is_nan() {
            return None; // separated (or not finite: the caller's search decides)
        }
        if o < least.0 {
            least = (o, l);
        }
    }
    for e in a_axes {
        for f in b_axes {
            let c = [
                e[1] * f[2] - e[2] * f[1],
                e[2] * f[0] - e[0] * f[2],
                e[0] * f[1] - e[1] * f[0],
            ];
            let len = dot(c, c).sqrt();
            // Near-parallel edges: the face normals already bound the overlap.
            if len < 1e-6 {
                continue;
            }
            let l = c.map(|x| x / len);
            let o = overlap(l);
            if o < 0.0 {
                return None;
            }
            if o < least.0 {
                least = (o, l);
            }
        }
    }
    let (depth, l) = least;
    let n = if dot(t, l) < 0.0 { l.map(|x| -x) } else { l };
    // `a`'s supporting vertex, edge or face along `n`; on an edge or face, the point of it
    // nearest `b`'s centre.
    let p = box_support(ha, &V::from(n), &V::from(t));
    let f = |v: V3| Vector::new(v[0] as Real, v[1] as Real, v[2] as Real);
    Some((f(p.into()), f(n), -depth as Real))
}

type V = Vector3<f64>;

thread_local! {
    /// The EPA's polytope buffers, reused by every contact this thread asks for (parry's
    /// `query::contact` builds a new one per overlapping pair).
    static EPA_BUFFERS: RefCell<EPA> = RefCell::new(EPA::new());
}

/// Contact between `a` and `b` placed at `pos12` in `a`'s frame, when they are at most
/// `prediction` apart: `a`'s deepest (or nearest) point, the unit normal from `a` towards `b`
/// and the signed distance, all in `a`'s frame. The same answer as parry's
/// `contact_support_map_support_map`.
fn support_map_contact(
    pos12: &Pose,
    a: &dyn SupportMap,
    b: &dyn SupportMap,
    prediction: Real,
) -> Option<(Vector, Vector, Real)> {
    let dir = pos12.translation.try_normalize().unwrap_or(Vector::X);
    let mut simplex = VoronoiSimplex::new();
    simplex.reset(CsoPoint::from_shapes(pos12, a, b, dir));
    let (p1, p2, n) = match gjk::closest_points(pos12, a, b, prediction, true, &mut simplex) {
        GJKResult::ClosestPoints(p1, p2, n) => (p1, p2, n),
        GJKResult::Intersection => EPA_BUFFERS.with(|epa| epa.borrow_mut().closest_points(pos12, a, b, &simplex))?,
        GJKResult::NoIntersection(_) | GJKResult::Proximity(_) => return None,
    };
    Some((p1, n, (p2 - p1).dot(n)))
}

/// The contact of a cylinder and a box, either way round, in [`support_map_contact`]'s terms
/// (`b` at `pos12` in `a`'s frame), where it is settled without parry: `Some(None)` when the
/// exact search ([`gjk::touch`](super::gjk::touch), in `f64`) finds them apart and no margin
/// is asked for; for overlapping shapes their least overlap ([`overlap_of_cylinder_and_box`]).
/// `None` (parry's GJK and EPA decide) for other pairs, shapes apart within a margin, where
/// the search is unsure, and where the least overlap finds a separating direction the
/// search did not.
fn cylinder_box_contact(
    a: &dyn Shape,
    b: &dyn Shape,
    pos12: &Pose,
    prediction: Real,
) -> Option<Option<(Vector, Vector, Real)>> {
    let pair = (a.as_cylinder().is_some() && b.as_cuboid().is_some())
        || (a.as_cuboid().is_some() && b.as_cylinder().is_some());
    if !pair {
        return None;
    }
    match touch(&convex_at(a, &Pose::IDENTITY)?, &convex_at(b, pos12)?) {
        Some(true) => overlap_of_cylinder_and_box(a, b, pos12).map(Some),
        Some(false) if prediction <= 0.0 => Some(None),
        _ => None,
    }
}

/// The contact of an overlapping cylinder and box, either way round, in
/// [`support_map_contact`]'s terms: the least overlap ([`cylinder_box_depth`], never below the
/// depth, where parry's EPA can fall short, and rarely a fraction of a millimetre above it),
/// the normal along which it is least and `a`'s farthest point along that normal. `None` for
/// other pairs, and where a direction separates the two.
fn overlap_of_cylinder_and_box(a: &dyn Shape, b: &dyn Shape, pos12: &Pose) -> Option<(Vector, Vector, Real)> {
    let d3 = |v: Vector| V::new(f64::from(v.x), f64::from(v.y), f64::from(v.z));
    let f3 = |v: V| Vector::new(v.x as Real, v.y as Real, v.z as Real);
    // The box's centre and axes in the cylinder's frame.
    let placed = |p: &Pose| {
        (
            d3(p.translation),
            [Vector::X, Vector::Y, Vector::Z].map(|e| d3(p.rotation * e)),
        )
    };
    if let (Some(c), Some(cuboid)) = (a.as_cylinder(), b.as_cuboid()) {
        let (t, axes) = placed(pos12);
        let half = d3(cuboid.half_extents).into();
        let (depth, n) = cylinder_box_depth(f64::from(c.radius), f64::from(c.half_height), t, axes, half)?;
        let p = cylinder_support(f64::from(c.radius), f64::from(c.half_height), &n, &t, &axes, &half);
        return Some((f3(p), f3(n), -depth as Real));
    }
    if let (Some(cuboid), Some(c)) = (a.as_cuboid(), b.as_cylinder()) {
        let (t, axes) = placed(&pos12.inverse());
        let half: [f64; 3] = d3(cuboid.half_extents).into();
        let (depth, n) = cylinder_box_depth(f64::from(c.radius), f64::from(c.half_height), t, axes, half)?;
        // From the box towards the cylinder, in the box's frame.
        let toward = -V::new(axes[0].dot(&n), axes[1].dot(&n), axes[2].dot(&n));
        let p = box_support(half, &toward, &d3(pos12.translation));
        return Some((f3(p), f3(toward), -depth as Real));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::{shape_contact, support_map_contact};
    use parry3d::math::{Pose, Rotation, Vector};
    use parry3d::query;
    use parry3d::shape::{Compound, Cuboid, Cylinder, Shape, SharedShape, TriMesh};

    /// The same contacts as parry's own query, overlapping, touching within the prediction
    /// and apart.
    #[test]
    fn contacts_match_parrys() {
        let a = Cylinder::new(0.1, 0.04);
        let b = Cuboid::new(Vector::new(0.3, 0.2, 0.05));
        let at = Pose::translation(0.2, -0.1, 0.3);
        for (x, y, z, angle) in [
            (0.25, -0.05, 0.32, 0.3),
            (0.0, 0.0, 0.0, 1.1),
            (0.4, -0.1, 0.41, -0.4),
            (0.2, 0.25, 0.3, 0.0),
            (0.9, 0.9, 0.9, 0.2),
        ] {
            let pose = Pose::from_parts(Vector::new(x, y, z), parry3d::math::Rotation::from_rotation_x(angle));
            let want = query::contact(&pose, &a, &at, &b, 0.05).unwrap();
            let got = support_map_contact(&pose.inv_mul(&at), &a, &b, 0.05);
            match (want, got) {
                (None, None) => {}
                (Some(w), Some((p, n, d))) => {
                    assert!((w.dist - d).abs() < 1e-5, "{w:?} against {d}");
                    assert!((w.normal1 - pose.rotation * n).length() < 1e-4, "{w:?} against {n}");
                    assert!((w.point1 - pose * p).length() < 1e-4, "{w:?} against {p}");
                }
                (w, g) => panic!("at {x},{y},{z}: parry {w:?}, ours {g:?}"),
            }
        }
    }

    /// Overlapping boxes take the separating-axis contact, checked against the boxes'
    /// corners: the overlap of their projections on our normal is our depth, no other
    /// direction (parry's normal, 64 spread ones) overlaps less, and moved back by the depth
    /// along the normal the first box clears the second. Our point is on the first box's
    /// face, edge or vertex that supports it along the normal. (Parry's EPA is not the
    /// reference: on deep overlaps it reports depths up to a fifth short of the overlap
    /// along its own normal.) Apart boxes keep GJK's gap, as before.
    fn boxes_against_parry(ha: Vector, hb: Vector, pa: Pose, pb: Pose) {
        let (a, b) = (Cuboid::new(ha), Cuboid::new(hb));
        let want = query::contact(&pa, &a, &pb, &b, 0.01).unwrap();
        let got = shape_contact(&a, &pa, &b, &pb, 0.01);
        let corners = |p: &Pose, h: Vector| -> [Vector; 8] {
            std::array::from_fn(|i| {
                let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
                *p * Vector::new(s(1) * h.x, s(2) * h.y, s(4) * h.z)
            })
        };
        let (ca, cb) = (corners(&pa, ha), corners(&pb, hb));
        // How far the boxes' projections on `n` overlap (negative: a gap).
        let overlap = |n: Vector| {
            let (amax, bmin) = (
                ca.iter().map(|v| v.dot(n)).fold(f32::MIN, f32::max),
                cb.iter().map(|v| v.dot(n)).fold(f32::MAX, f32::min),
            );
            let (bmax, amin) = (
                cb.iter().map(|v| v.dot(n)).fold(f32::MIN, f32::max),
                ca.iter().map(|v| v.dot(n)).fold(f32::MAX, f32::min),
            );
            (amax - bmin).min(bmax - amin)
        };
        let (Some(w), Some(c)) = (want, got) else {
            assert_eq!(want.is_some(), got.is_some(), "parry {want:?}, ours {got:?}");
            return;
        };
        let depth = -(c.distance + 0.01);
        if depth < 1e-4 {
            // Apart (GJK's closest points, as before) or touching.
            assert!((w.dist - 0.01 - c.distance).abs() < 2e-4, "{w:?} against {c:?}");
            if w.dist > 1e-4 {
                assert!((w.normal1 - c.normal).length() < 1e-3, "{w:?} against {c:?}");
            }
            return;
        }
        assert!((c.normal.length() - 1.0).abs() < 1e-5, "{c:?}");
        assert!(
            (overlap(c.normal) - depth).abs() < 1e-5,
            "{c:?}: overlap {} along the normal",
            overlap(c.normal)
        );
        let spread = (0..64).map(|k| {
            let (z, phi) = (1.0 - (2 * k + 1) as f32 / 64.0, k as f32 * 2.399_963);
            let r = (1.0 - z * z).sqrt();
            Vector::new(r * phi.cos(), r * phi.sin(), z)
        });
        for n in spread.chain([w.normal1]) {
            assert!(overlap(n) >= depth - 1e-5, "{c:?}: {n:?} overlaps {} only", overlap(n));
        }
        let moved = Pose::from_parts(pa.translation - c.normal * (depth + 1e-4), pa.rotation);
        assert!(
            !query::intersection_test(&moved, &a, &pb, &b).unwrap().intersecting,
            "{c:?}: still overlapping"
        );
        let local_n = pa.rotation.inverse() * c.normal;
        let local_p = pa.inv_mul(&Pose::from_translation(c.point)).translation;
        let support = ha.x * local_n.x.abs() + ha.y * local_n.y.abs() + ha.z * local_n.z.abs();
        assert!(
            (local_p.dot(local_n) - support).abs() < 1e-5,
            "{c:?}: not on the supporting feature"
        );
        assert!(
            local_p.abs().cmple(ha + Vector::splat(1e-5)).all(),
            "{c:?}: outside the box"
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(3000))]
        #[test]
        fn box_contacts_match_parrys(
            ha in proptest::array::uniform3(0.01f32..0.4),
            hb in proptest::array::uniform3(0.01f32..0.4),
            t in proptest::array::uniform3(-0.6f32..0.6),
            ra in proptest::array::uniform3(-3.2f32..3.2),
            rb in proptest::array::uniform3(-3.2f32..3.2),
        ) {
            let rot = |r: [f32; 3]| {
                Rotation::from_rotation_x(r[0]) * Rotation::from_rotation_y(r[1]) * Rotation::from_rotation_z(r[2])
            };
            let pa = Pose::from_parts(Vector::new(0.1, -0.2, 0.3), rot(ra));
            let pb = Pose::from_parts(Vector::new(0.1 + t[0], -0.2 + t[1], 0.3 + t[2]), rot(rb));
            boxes_against_parry(Vector::from(ha), Vector::from(hb), pa, pb);
        }
    }

    /// Boxes face to face, edge to edge and corner in face, where the least overlap is
    /// along one face normal or one pair of edges.
    #[test]
    fn box_contacts_in_plain_cases() {
        let h = Vector::new(0.2, 0.1, 0.05);
        let cases = [
            (Pose::translation(0.0, 0.0, 0.09), Rotation::IDENTITY),
            (Pose::translation(0.35, 0.05, 0.0), Rotation::from_rotation_z(0.3)),
            (Pose::translation(0.0, 0.17, 0.02), Rotation::from_rotation_x(0.7)),
            (
                Pose::translation(0.25, 0.1, 0.1),
                Rotation::from_rotation_y(0.9) * Rotation::from_rotation_z(0.8),
            ),
        ];
        for (at, rot) in cases {
            boxes_against_parry(h, h, Pose::IDENTITY, Pose::from_parts(at.translation, rot));
        }
        // Face to face: the depth of the stack, along z.
        let c = shape_contact(
            &Cuboid::new(h),
            &Pose::IDENTITY,
            &Cuboid::new(h),
            &Pose::translation(0.05, 0.0, 0.09),
            0.0,
        )
        .unwrap();
        assert!(
            (c.distance + 0.01).abs() < 1e-6 && (c.normal - Vector::Z).length() < 1e-6,
            "{c:?}"
        );
        assert!((c.point - Vector::new(0.05, 0.0, 0.05)).length() < 1e-6, "{c:?}");
    }

    /// A cylinder and a box overlapping, either way round, take the least overlap: the depth
    /// at least parry's EPA's (which measures a polytope inside the shapes' difference; to
    /// 0.05 mm, its `f32` tolerance), the first shape moved back along the normal by the
    /// depth and a tenth of a millimetre clear of the other, and by the depth less a
    /// millimetre not; the point the first shape's farthest along the normal. Apart, no
    /// contact without a margin and the gap within one.
    #[test]
    fn cylinder_box_contacts_either_way() {
        use super::super::gjk::{Convex, touch};
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(7);
        let mut u = |lo: f32, hi: f32| rand::RngExt::random_range(&mut rng, lo..hi);
        let mut checked = 0;
        while checked < 300 {
            let cylinder = Cylinder::new(u(0.02, 0.3), u(0.02, 0.15));
            let cuboid = Cuboid::new(Vector::new(u(0.01, 0.3), u(0.01, 0.3), u(0.01, 0.3)));
            let mut pose = |reach: f32| {
                let rot = Rotation::from_rotation_x(u(-3.2, 3.2)) * Rotation::from_rotation_y(u(-3.2, 3.2));
                Pose::from_parts(Vector::new(u(-reach, reach), u(-reach, reach), u(-reach, reach)), rot)
            };
            let (pc, pb) = (pose(0.05), pose(0.3));
            let convex = |p: &Pose, moved: Vector, cyl: bool| {
                let c = p.translation + moved;
                if cyl {
                    Convex::cylinder(c, p.rotation * Vector::Y, cylinder.half_height, cylinder.radius)
                } else {
                    Convex::cuboid(
                        c,
                        [Vector::X, Vector::Y, Vector::Z].map(|e| p.rotation * e),
                        cuboid.half_extents,
                    )
                }
            };
            if touch(&convex(&pc, Vector::ZERO, true), &convex(&pb, Vector::ZERO, false)) != Some(true) {
                continue;
            }
            for cylinder_first in [true, false] {
                let (a, pa, b, pother): (&dyn Shape, _, &dyn Shape, _) = if cylinder_first {
                    (&cylinder, pc, &cuboid, pb)
                } else {
                    (&cuboid, pb, &cylinder, pc)
                };
                let c = shape_contact(a, &pa, b, &pother, 0.0).expect("overlapping");
                let depth = -c.distance;
                let parry = query::contact(&pa, a, &pother, b, 0.0).unwrap().unwrap();
                assert!(depth >= -parry.dist - 5e-5, "{c:?} against parry's {parry:?}");
                let moved = |by: f32| {
                    touch(
                        &convex(&pa, -c.normal * by, cylinder_first),
                        &convex(&pother, Vector::ZERO, !cylinder_first),
                    )
                };
                assert_ne!(moved(depth + 1e-4), Some(true), "{c:?}: still overlapping");
                if depth > 2e-3 {
                    assert_ne!(moved(depth - 1e-3), Some(false), "{c:?}: clear before the depth");
                }
                let local = pa.rotation.inverse() * c.normal;
                let farthest = pa.rotation.inverse() * (c.point - pa.translation);
                let support = a.as_support_map().unwrap().local_support_point(local);
                assert!(
                    (farthest - support).dot(local).abs() < 1e-5,
                    "{c:?}: not the farthest point"
                );
            }
            checked += 1;
        }
        // Apart: no contact without a margin, parry's gap within one.
        let (cylinder, cuboid) = (Cylinder::new(0.1, 0.05), Cuboid::new(Vector::splat(0.1)));
        let (pc, pb) = (Pose::IDENTITY, Pose::translation(0.18, 0.0, 0.0));
        assert!(shape_contact(&cylinder, &pc, &cuboid, &pb, 0.0).is_none());
        assert!(shape_contact(&cuboid, &pb, &cylinder, &pc, 0.0).is_none());
        let c = shape_contact(&cylinder, &pc, &cuboid, &pb, 0.05).unwrap();
        assert!(
            (c.distance - (0.03 - 0.05)).abs() < 1e-6 && (c.normal - Vector::X).length() < 1e-5,
            "{c:?}"
        );
    }

    /// Shapes with negative or non-finite sizes (parry's constructors refuse some; its fields
    /// are public) get an answer, never a panic.
    #[test]
    fn malformed_shapes_do_not_panic() {
        let sizes = [-0.1, f32::NAN, 0.0, 0.1];
        for a in sizes {
            for b in sizes {
                let cylinder = Cylinder {
                    half_height: a,
                    radius: b,
                };
                let cuboid = Cuboid {
                    half_extents: Vector::new(b, a, 0.1),
                };
                for at in [Pose::IDENTITY, Pose::translation(0.05, 0.02, 0.0)] {
                    let _ = shape_contact(&cylinder, &Pose::IDENTITY, &cuboid, &at, 0.0);
                    let _ = shape_contact(&cuboid, &at, &cylinder, &Pose::IDENTITY, 0.01);
                    let _ = shape_contact(&cuboid, &at, &cuboid, &Pose::IDENTITY, 0.0);
                }
            }
        }
    }

    /// Composite obstacles (a triangle mesh, a compound) answer as parry's own composite
    /// query does: the deepest contact among their parts, or none.
    #[test]
    fn composite_contacts_match_parrys() {
        let (vertices, indices) = Cuboid::new(Vector::new(0.4, 0.3, 0.05)).to_trimesh();
        let mesh = TriMesh::new(vertices, indices).unwrap();
        let compound = Compound::new(vec![
            (Pose::translation(0.0, 0.0, 0.0), SharedShape::cuboid(0.4, 0.3, 0.05)),
            (Pose::translation(0.3, 0.0, 0.2), SharedShape::cylinder(0.2, 0.05)),
        ]);
        let at = Pose::from_parts(Vector::new(0.1, -0.2, 0.4), Rotation::from_rotation_z(0.3));
        let a = Cylinder::new(0.1, 0.04);
        let mut answered = 0;
        for other in [&mesh as &dyn Shape, &compound] {
            for (x, y, z, angle) in [
                (0.1, -0.2, 0.47, 0.3),
                (0.2, -0.1, 0.52, 1.1),
                (0.35, -0.2, 0.6, -0.4),
                (0.1, -0.2, 0.62, 0.0),
                (1.5, 1.5, 1.5, 0.2),
            ] {
                let pose = Pose::from_parts(Vector::new(x, y, z), Rotation::from_rotation_x(angle));
                let want = query::contact(&pose, &a, &at, other, 0.02).unwrap();
                match (want, shape_contact(&a, &pose, other, &at, 0.02)) {
                    (None, None) => {}
                    (Some(w), Some(c)) => {
                        answered += 1;
                        assert!((w.dist - 0.02 - c.distance).abs() < 1e-5, "{w:?} against {c:?}");
                        assert!((w.normal1 - c.normal).length() < 1e-4, "{w:?} against {c:?}");
                        // Where a face is deepest its points tie: parry's EPA picks one, the
                        // cylinder-box contact the one nearest the box. Both lie on the plane.
                        assert!((w.point1 - c.point).dot(c.normal).abs() < 1e-4, "{w:?} against {c:?}");
                    }
                    (w, g) => panic!("at {x},{y},{z}: parry {w:?}, ours {g:?}"),
                }
            }
        }
        assert!(answered >= 4, "only {answered} contacts to compare");
    }
}
