//! How far the articulated tasks may open a furniture joint: a door swung into the cabinet
//! beside it, or two neighbours' doors swung into each other, start the episode interpenetrating,
//! and the solver pushes them apart violently enough to blow the joints up.
//!
//! At build time each joint's moving link is swept from closed to fully open in steps of 1/40
//! of its range against the world's colliders (the furniture itself and the robot excluded);
//! its *cap* is the largest opening before the first hit. A link that already touches
//! something when closed is left uncapped (the sweep cannot tell a new hit from that one).
//! At reset the drawn openings are limited to the caps, and each opened link is checked
//! against the links opened before it; one that overlaps is closed halfway, up to four times,
//! and then left closed.

use nalgebra::Isometry3;
use parry3d::query::intersection_test;

use crate::kinematics::{RobotModel, to_pose};
use crate::world::WorldObstacles;
use hearth_planning::obstacles::Obstacles;

/// Sweep steps over a joint's range.
const STEPS: usize = 40;

/// A moving link placed for an opening: its collision shape's world pose.
pub(crate) struct Placed<'a> {
    pub(crate) model: &'a RobotModel,
    pub(crate) link: usize,
    pub(crate) pose: Isometry3<f64>,
}

/// The world pose of the collision shape of `link` with only variable `v` at `x` (the other
/// joints closed), or `None` when the link has no collision shape. `q` and `poses` are
/// scratch of the model's sizes.
pub(crate) fn shape_pose(
    model: &RobotModel,
    base: &Isometry3<f64>,
    v: usize,
    x: f64,
    link: usize,
    q: &mut [f64],
    poses: &mut [Isometry3<f64>],
) -> Option<Isometry3<f64>> {
    let shape = model.link_shape(link)?;
    q.iter_mut().for_each(|a| *a = 0.0);
    q[v] = x;
    model.fk_from(base, q, poses).ok()?;
    Some(poses[link] * shape.origin)
}

/// The largest fraction of its range joint `v` (moving `link`) opens before the link hits
/// anything in `view`, on a grid of 1/40; 1 when the link has no shape or touches something
/// already when closed.
pub(crate) fn free_opening(
    view: &WorldObstacles,
    model: &RobotModel,
    base: &Isometry3<f64>,
    v: usize,
    link: usize,
) -> f64 {
    let Some(shape) = model.link_shape(link) else {
        return 1.0;
    };
    let upper = model.upper()[v];
    let mut q = vec![0.0; model.dof()];
    let mut poses = model.pose_buffer();
    let mut hits = |f: f64| {
        shape_pose(model, base, v, f * upper, link, &mut q, &mut poses)
            .is_none_or(|p| view.intersects(shape.shape.as_ref(), &to_pose(&p)))
    };
    if hits(0.0) {
        return 1.0;
    }
    let mut free = 0.0;
    for k in 1..=STEPS {
        let f = k as f64 / STEPS as f64;
        if hits(f) {
            break;
        }
        free = f;
    }
    free
}

/// Whether the link `a` overlaps any of `others`.
pub(crate) fn overlaps(a: &Placed<'_>, others: &[Placed<'_>]) -> bool {
    let Some(sa) = a.model.link_shape(a.link) else {
        return false;
    };
    let pa = to_pose(&a.pose);
    others.iter().any(|b| {
        b.model.link_shape(b.link).is_some_and(|sb| {
            intersection_test(&pa, sa.shape.as_ref(), &to_pose(&b.pose), sb.shape.as_ref())
                .is_ok_and(|r| r.intersecting)
        })
    })
}
