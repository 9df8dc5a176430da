//! Obstacles built from arbitrary numbers (NaN, infinities, negative and huge sizes, any
//! quaternion): either `Obstacle::check` refuses them, or a scene built from them answers
//! every query without panicking and agrees with parry's own test of each obstacle (up to a
//! few millimetres of contact).

use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
use parry3d::math::{Pose, Real, Rotation, Vector};
use parry3d::query;
use parry3d::shape::Ball;
use proptest::prelude::*;

/// Mostly ordinary numbers, with the awkward ones mixed in.
fn number() -> impl Strategy<Value = Real> + Clone {
    prop_oneof![
        6 => -2.0f32..2.0,
        1 => Just(Real::NAN),
        1 => Just(Real::INFINITY),
        1 => Just(Real::NEG_INFINITY),
        1 => Just(-0.0),
        1 => Just(0.0),
        1 => Just(1e30),
        1 => Just(-1e-3),
    ]
}

fn vector() -> impl Strategy<Value = Vector> + Clone {
    (number(), number(), number()).prop_map(|(x, y, z)| Vector::new(x, y, z))
}

/// A pose whose quaternion is usually normalised and sometimes left as drawn.
fn pose() -> impl Strategy<Value = Pose> + Clone {
    (vector(), number(), number(), number(), number(), any::<bool>()).prop_map(|(t, x, y, z, w, unit)| {
        let q = Rotation::from_xyzw(x, y, z, w);
        let q = if unit && q.length() > 1e-3 { q.normalize() } else { q };
        Pose::from_parts(t, q)
    })
}

/// An obstacle of each kind from the given numbers, vectors and poses.
fn shaped<N, V, P>(n: N, v: V, p: P) -> impl Strategy<Value = Obstacle>
where
    N: Strategy<Value = Real> + Clone,
    V: Strategy<Value = Vector> + Clone,
    P: Strategy<Value = Pose> + Clone,
{
    prop_oneof![
        (p.clone(), v.clone()).prop_map(|(p, h)| Obstacle::cuboid("box", p, h)),
        (v.clone(), n.clone()).prop_map(|(c, r)| Obstacle::ball("ball", c, r)),
        (p, n.clone(), n.clone()).prop_map(|(p, h, r)| Obstacle::cylinder("can", p, h, r)),
        (v.clone(), v, n).prop_map(|(a, b, r)| Obstacle::capsule("rail", a, b, r)),
    ]
}

/// Mostly sound obstacles (sizes in [0, 1), centres within 2 m, unit quaternions), one in
/// five drawn from any numbers.
fn obstacle() -> impl Strategy<Value = Obstacle> {
    let size = 0.0f32..1.0;
    let at = (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0).prop_map(|(x, y, z)| Vector::new(x, y, z));
    let extents = (size.clone(), size.clone(), size.clone()).prop_map(|(x, y, z)| Vector::new(x, y, z));
    let turned = (at.clone(), -1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, 0.1f32..1.0)
        .prop_map(|(t, x, y, z, w)| Pose::from_parts(t, Rotation::from_xyzw(x, y, z, w).normalize()));
    let sound = prop_oneof![
        shaped(size.clone(), extents, turned.clone()),
        // Capsules and balls take their ends and centres from `at`.
        shaped(size, at, turned),
    ];
    prop_oneof![4 => sound, 1 => shaped(number(), vector(), pose())]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn checked_obstacles_answer_queries_and_others_are_refused(
        obstacles in prop::collection::vec(obstacle(), 1..6),
        probe_at in (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0),
        radius in 0.0f32..0.5,
    ) {
        let all_ok = obstacles.iter().all(|o| o.check().is_ok());
        let built = ParryScene::try_new(obstacles.clone());
        prop_assert_eq!(built.is_ok(), all_ok);
        let Ok(scene) = built else {
            let e = built.unwrap_err();
            prop_assert!(obstacles[e.index].check().is_err());
            prop_assert!(obstacles[..e.index].iter().all(|o| o.check().is_ok()));
            return Ok(());
        };
        let b = scene.aabb().expect("a non-empty scene has bounds");
        prop_assert!(b.mins.is_finite() && b.maxs.is_finite());
        let center = Vector::new(probe_at.0, probe_at.1, probe_at.2);
        let ball = Ball::new(radius);
        let at = Pose::from_translation(center);
        // The scene's answer against parry's test of each obstacle on its own. Within a few
        // millimetres of contact the two may differ (parry's GJK reports some contacts up
        // to ~3 mm apart; the scene's closed forms do not), never farther out.
        let touching: Vec<bool> = obstacles
            .iter()
            .map(|o| query::intersection_test(&o.pose, o.shape.as_ref(), &at, &ball).map_or(true, |i| i.intersecting))
            .collect();
        let gap = |i: usize| {
            let o = &obstacles[i];
            query::distance(&o.pose, o.shape.as_ref(), &at, &ball).map_or(0.0, |d| d.distance)
        };
        const NEAR: Real = 5e-3;
        let hit = scene.first_hit(&ball, &at);
        match hit {
            Some(id) => prop_assert!(touching[id.index()] || gap(id.index()) <= NEAR, "{:?} {:?}", hit, touching),
            None => {
                for i in (0..obstacles.len()).filter(|&i| touching[i]) {
                    prop_assert!(gap(i) <= NEAR, "missed obstacle {} at {}", i, gap(i));
                }
            }
        }
        if scene.ball_hits(center, radius) != hit.is_some() {
            let closest = (0..obstacles.len()).map(gap).fold(Real::INFINITY, Real::min);
            prop_assert!(closest <= NEAR, "ball_hits and first_hit disagree {} from contact", closest);
        }
        if let Some((d, id)) = scene.distance(&ball, &at, 10.0) {
            prop_assert!(d.is_finite() && (0.0..=10.0).contains(&d) && id.index() < obstacles.len());
        }
        if let Some((t, _)) = scene.cast_ray(center, Vector::X, 10.0) {
            prop_assert!(t.is_finite() && (0.0..=10.0).contains(&t));
        }
    }
}
