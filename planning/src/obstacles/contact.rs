//! Contacts between convex shapes without allocation: parry's GJK, then its EPA for
//! overlapping shapes, with the EPA's buffers kept per thread ([`ParryScene`]'s
//! [`Obstacles::contact`]).

use std::cell::RefCell;

use parry3d::math::{Pose, Real, Vector};
use parry3d::query::epa::EPA;
use parry3d::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d::shape::SupportMap;

#[cfg(doc)]
use super::{Obstacles, ParryScene};

thread_local! {
    /// The EPA's polytope buffers, reused by every contact this thread asks for (parry's
    /// `query::contact` builds a new one per overlapping pair).
    static EPA_BUFFERS: RefCell<EPA> = RefCell::new(EPA::new());
}

/// Contact between `a` and `b` placed at `pos12` in `a`'s frame, when they are at most
/// `prediction` apart: `a`'s deepest (or nearest) point, the unit normal from `a` towards `b`
/// and the signed distance, all in `a`'s frame. The same answer as parry's
/// `contact_support_map_support_map`.
pub(super) fn support_map_contact(
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
    use super::support_map_contact;
    use parry3d::math::{Pose, Vector};
    use parry3d::query;
    use parry3d::shape::{Cuboid, Cylinder};

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
}
