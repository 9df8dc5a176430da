//! Contacts between shapes for [`Obstacles::contact`], without allocation for convex pairs and
//! composite obstacles: parry's GJK, then its EPA for overlapping shapes, with the EPA's
//! buffers kept per thread.

use std::cell::RefCell;

use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::{Pose, Real, Vector};
use parry3d::query::epa::EPA;
use parry3d::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d::query::{self};
use parry3d::shape::{Shape, SupportMap};

use super::ObstacleContact;
#[cfg(doc)]
use super::Obstacles;

/// Where `shape` at `pose` touches `other` at `other_pose`, counting a gap of up to `margin`
/// as contact ([`ObstacleContact`], its distance less the margin), or `None`: the answer of
/// every [`Obstacles::contact`] in the workspace (`ParryScene` and the live world's view).
/// Balls take parry's closed forms; other convex pairs GJK and the per-thread EPA, which
/// parry's own `query::contact` would build anew for each overlap; a composite obstacle (a
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
    if let (Some(a), Some(b)) = (shape.as_support_map(), other.as_support_map())
        && shape.as_ball().is_none()
        && other.as_ball().is_none()
    {
        let (p, n, d) = support_map_contact(&pose.inv_mul(other_pose), a, b, margin)?;
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
                        assert!((w.point1 - c.point).length() < 1e-4, "{w:?} against {c:?}");
                    }
                    (w, g) => panic!("at {x},{y},{z}: parry {w:?}, ours {g:?}"),
                }
            }
        }
        assert!(answered >= 4, "only {answered} contacts to compare");
    }
}
