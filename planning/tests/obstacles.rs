//! `ParryScene` through the `Obstacles` seam: known poses, the cylinder axis convention,
//! distances, ray casts, margin, and BVH results against a brute-force loop.

use std::f32::consts::FRAC_PI_4;
use std::sync::Arc;

use hearth_planning::obstacles::{Obstacle, ObstacleId, Obstacles, ParryScene};
use parry3d::math::{Pose, Real, Rotation, Vector};
use parry3d::query;
use parry3d::shape::{Ball, Cuboid};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

const BOX: ObstacleId = ObstacleId(0);
const BALL: ObstacleId = ObstacleId(1);
const POLE: ObstacleId = ObstacleId(2);

/// A box turned 45° about z at (1, 0, 0.5), a ball at (-1, 0, 0.5), a thin pole along z at
/// (0, 1, 0.5) spanning z ∈ [0, 1].
fn fixture() -> ParryScene {
    ParryScene::new(vec![
        Obstacle::cuboid(
            "box",
            Pose::from_parts(Vector::new(1.0, 0.0, 0.5), Rotation::from_rotation_z(FRAC_PI_4)),
            Vector::splat(0.2),
        ),
        Obstacle::ball("ball", Vector::new(-1.0, 0.0, 0.5), 0.25),
        Obstacle::cylinder("pole", Pose::translation(0.0, 1.0, 0.5), 0.5, 0.02),
    ])
}

fn point() -> Ball {
    Ball::new(1e-3)
}

fn at(x: Real, y: Real, z: Real) -> Pose {
    Pose::translation(x, y, z)
}

#[test]
fn intersects_at_known_poses() {
    let s = fixture();
    assert_eq!(s.len(), 3);
    // Box corner points along +x after the 45° turn: reaches x = 1 + 0.2·√2 ≈ 1.2828.
    assert_eq!(s.first_hit(&point(), &at(1.27, 0.0, 0.5)), Some(BOX));
    assert!(!s.intersects(&point(), &at(1.30, 0.0, 0.5)));
    // The y corner (0.2828) reaches past an unturned box's 0.2 …
    assert_eq!(s.first_hit(&point(), &at(1.0, 0.27, 0.69)), Some(BOX));
    // … but not above its top face.
    assert!(!s.intersects(&point(), &at(1.0, 0.27, 0.71)));
    assert_eq!(s.first_hit(&point(), &at(-1.0, 0.0, 0.74)), Some(BALL));
    assert!(!s.intersects(&point(), &at(-1.0, 0.0, 0.76)));
    assert!(!s.intersects(&point(), &at(0.0, 0.0, 0.0)));
    assert!(!s.intersects(&point(), &at(5.0, 5.0, 5.0)));
    // A shape straddling two obstacles reports one of them.
    let big = Cuboid::new(Vector::new(1.5, 0.05, 0.05));
    let hit = s.first_hit(&big, &at(0.0, 0.0, 0.5)).unwrap();
    assert!(hit == BOX || hit == BALL);
}

#[test]
fn cylinder_axis_is_local_z() {
    let s = fixture();
    // Above the centre, inside the span z ∈ [0, 1].
    assert_eq!(s.first_hit(&point(), &at(0.0, 1.0, 0.9)), Some(POLE));
    assert_eq!(s.first_hit(&point(), &at(0.0, 1.0, 0.05)), Some(POLE));
    // Beside the centre (would be inside if the axis were x or y).
    assert!(!s.intersects(&point(), &at(0.2, 1.0, 0.5)));
    assert!(!s.intersects(&point(), &at(0.0, 1.3, 0.5)));
    // Beyond the flat cap.
    assert!(!s.intersects(&point(), &at(0.0, 1.0, 1.01)));
    let aabb = s.get(POLE).unwrap().aabb();
    assert!((aabb.mins.z - 0.0).abs() < 1e-5 && (aabb.maxs.z - 1.0).abs() < 1e-5);
    assert!((aabb.maxs.x - 0.02).abs() < 1e-5);

    // A tilted cylinder: axis z turned 90° about x now lies along -y.
    let tilted = ParryScene::new(vec![Obstacle::cylinder(
        "tilted",
        Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2)),
        0.5,
        0.02,
    )]);
    assert!(tilted.intersects(&point(), &at(0.0, 0.4, 0.0)));
    assert!(!tilted.intersects(&point(), &at(0.0, 0.0, 0.4)));
}

#[test]
fn distance_values() {
    let s = fixture();
    let probe = Ball::new(0.1);
    // Above the ball: 0.5 - 0.25 - 0.1.
    let (d, id) = s.distance(&probe, &at(-1.0, 0.0, 1.0), 1.0).unwrap();
    assert_eq!(id, BALL);
    assert!((d - 0.15).abs() < 1e-5, "{d}");
    assert_eq!(s.distance(&probe, &at(-1.0, 0.0, 1.0), 0.1), None);
    // Beside the pole: 0.5 - 0.02 - 0.1, nearer than anything else.
    let (d, id) = s.distance(&probe, &at(0.0, 1.5, 0.5), 10.0).unwrap();
    assert_eq!(id, POLE);
    assert!((d - 0.38).abs() < 1e-5, "{d}");
    // Touching gives 0.
    let (d, id) = s.distance(&probe, &at(1.0, 0.0, 0.5), 1.0).unwrap();
    assert_eq!((d, id), (0.0, BOX));
    // max_dist is inclusive enough to find a hit right at the bound.
    assert!(s.distance(&probe, &at(-1.0, 0.0, 1.0), 0.1501).is_some());
    assert_eq!(s.distance(&probe, &at(-1.0, 0.0, 1.0), -1.0), None);
}

#[test]
fn ray_cast_hits_the_nearest_obstacle() {
    let s = fixture();
    let (t, id) = s.cast_ray(Vector::new(-3.0, 0.0, 0.5), Vector::X, 10.0).unwrap();
    assert_eq!(id, BALL);
    assert!((t - 1.75).abs() < 1e-5, "{t}");
    let (t, id) = s.cast_ray(Vector::new(3.0, 0.0, 0.5), -Vector::X, 10.0).unwrap();
    assert_eq!(id, BOX);
    assert!((t - (2.0 - 0.2 * 2f32.sqrt())).abs() < 1e-5, "{t}");
    let (t, id) = s.cast_ray(Vector::new(0.0, 3.0, 0.5), -Vector::Y, 10.0).unwrap();
    assert_eq!(id, POLE);
    assert!((t - 1.98).abs() < 1e-5, "{t}");
    // Time of impact in units of |dir|.
    let (t, _) = s
        .cast_ray(Vector::new(-3.0, 0.0, 0.5), Vector::new(2.0, 0.0, 0.0), 10.0)
        .unwrap();
    assert!((t - 0.875).abs() < 1e-5, "{t}");
    // Too short, missing, degenerate.
    assert_eq!(s.cast_ray(Vector::new(-3.0, 0.0, 0.5), Vector::X, 1.7), None);
    assert_eq!(s.cast_ray(Vector::new(-3.0, 0.0, 3.0), Vector::X, 10.0), None);
    assert_eq!(s.cast_ray(Vector::new(-3.0, 0.0, 0.5), Vector::ZERO, 10.0), None);
    assert_eq!(
        s.cast_ray(Vector::new(-3.0, 0.0, 0.5), Vector::new(Real::NAN, 0.0, 0.0), 10.0),
        None
    );
    // From inside: 0.
    let (t, id) = s.cast_ray(Vector::new(-1.0, 0.0, 0.5), Vector::Z, 10.0).unwrap();
    assert_eq!((t, id), (0.0, BALL));
}

#[test]
fn margin_inflates_intersection_tests() {
    let probe = Ball::new(0.1);
    // 0.03 m of clearance above the ball.
    let pose = at(-1.0, 0.0, 0.5 + 0.25 + 0.1 + 0.03);
    assert!(!fixture().intersects(&probe, &pose));
    assert!(!fixture().with_margin(0.01).intersects(&probe, &pose));
    let s = fixture().with_margin(0.05);
    assert_eq!(s.margin(), 0.05);
    assert_eq!(s.first_hit(&probe, &pose), Some(BALL));
    // Distance ignores the margin.
    let (d, _) = s.distance(&probe, &pose, 1.0).unwrap();
    assert!((d - 0.03).abs() < 1e-5);
    assert_eq!(fixture().with_margin(-1.0).margin(), 0.0);
    assert_eq!(fixture().with_margin(Real::NAN).margin(), 0.0);
}

#[test]
fn bounds_names_and_empty_scene() {
    let s = fixture();
    let aabb = s.aabb().unwrap();
    assert!((aabb.mins.x - -1.25).abs() < 1e-5);
    assert!((aabb.maxs.y - 1.02).abs() < 1e-5);
    assert!((aabb.maxs.z - 1.0).abs() < 1e-5);
    assert_eq!(s.name(POLE), Some("pole"));
    assert_eq!(s.name(ObstacleId(7)), None);
    assert_eq!(s.find("ball"), Some(BALL));

    let empty = ParryScene::default();
    assert!(empty.is_empty());
    assert_eq!(empty.aabb(), None);
    assert!(!empty.intersects(&point(), &Pose::IDENTITY));
    assert_eq!(empty.distance(&point(), &Pose::IDENTITY, 100.0), None);
    assert_eq!(empty.cast_ray(Vector::ZERO, Vector::X, 100.0), None);

    let one = ParryScene::new(vec![Obstacle::ball("only", Vector::ZERO, 1.0)]);
    assert_eq!(one.first_hit(&point(), &Pose::IDENTITY), Some(ObstacleId(0)));
    assert_eq!(
        one.distance(&point(), &at(3.0, 0.0, 0.0), 5.0).map(|(_, id)| id),
        Some(ObstacleId(0))
    );
    assert_eq!(
        one.cast_ray(Vector::new(-3.0, 0.0, 0.0), Vector::X, 5.0)
            .map(|(t, _)| t),
        Some(2.0)
    );
}

#[test]
fn other_shapes_capsule_convex_trimesh() {
    let floor = Obstacle::trimesh(
        "floor",
        Pose::IDENTITY,
        vec![
            Vector::new(-5.0, -5.0, 0.0),
            Vector::new(5.0, -5.0, 0.0),
            Vector::new(0.0, 5.0, 0.0),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let tetra = Obstacle::convex_hull(
        "tetra",
        Pose::translation(0.0, 0.0, 2.0),
        &[Vector::ZERO, Vector::X, Vector::Y, Vector::Z],
    )
    .unwrap();
    let capsule = Obstacle::capsule("capsule", Vector::new(3.0, 0.0, 1.0), Vector::new(3.0, 0.0, 2.0), 0.1);
    assert!(Obstacle::convex_hull("none", Pose::IDENTITY, &[]).is_none());
    assert!(Obstacle::trimesh("none", Pose::IDENTITY, vec![], vec![]).is_err());

    let s = ParryScene::new(vec![floor, tetra, capsule]);
    let probe = Ball::new(0.05);
    assert_eq!(s.first_hit(&probe, &at(0.0, 0.0, 0.04)), Some(ObstacleId(0)));
    assert!(!s.intersects(&probe, &at(0.0, 0.0, 0.06)));
    assert_eq!(s.first_hit(&probe, &at(0.1, 0.1, 2.1)), Some(ObstacleId(1)));
    assert_eq!(s.first_hit(&probe, &at(3.0, 0.0, 2.14)), Some(ObstacleId(2)));
    assert!(!s.intersects(&probe, &at(3.0, 0.0, 2.16)));
    let (t, id) = s.cast_ray(Vector::new(0.2, 0.2, 5.0), -Vector::Z, 10.0).unwrap();
    assert_eq!(id, ObstacleId(1));
    assert!((t - (5.0 - 2.6)).abs() < 1e-5, "{t}");
}

#[test]
fn object_safe_and_shareable() {
    let shared: Arc<dyn Obstacles> = Arc::new(fixture());
    let worker = {
        let shared = Arc::clone(&shared);
        std::thread::spawn(move || shared.intersects(&point(), &at(-1.0, 0.0, 0.5)))
    };
    assert!(worker.join().unwrap());
    assert_eq!(shared.name(BALL), Some("ball"));
}

/// A random scene of boxes, balls, cylinders and capsules.
fn random_scene(rng: &mut Pcg64, n: usize) -> ParryScene {
    let mut v = || {
        Vector::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(0.0..2.0),
        )
    };
    let centers: Vec<Vector> = (0..n).map(|_| v()).collect();
    centers
        .into_iter()
        .enumerate()
        .map(|(i, c)| {
            let rot = Rotation::from_rotation_z(i as Real * 0.7) * Rotation::from_rotation_x(i as Real * 0.3);
            let pose = Pose::from_parts(c, rot);
            match i % 4 {
                0 => Obstacle::cuboid(format!("box{i}"), pose, Vector::new(0.1, 0.2, 0.05 + 0.01 * i as Real)),
                1 => Obstacle::ball(format!("ball{i}"), c, 0.05 + 0.005 * i as Real),
                2 => Obstacle::cylinder(format!("cyl{i}"), pose, 0.3, 0.03),
                _ => Obstacle::capsule(format!("cap{i}"), c, c + Vector::new(0.2, 0.1, 0.3), 0.04),
            }
        })
        .collect()
}

fn brute_distance(s: &ParryScene, shape: &Ball, pose: &Pose) -> Real {
    s.obstacles()
        .iter()
        .map(|o| query::distance(pose, shape, &o.pose, &*o.shape).unwrap().distance)
        .fold(Real::INFINITY, Real::min)
}

#[test]
fn bvh_matches_brute_force_on_random_ball_queries() {
    let mut rng = Pcg64::seed_from_u64(7);
    let scene = random_scene(&mut rng, 60);
    let margins = [0.0, 0.05];
    let (mut hits, mut misses) = (0, 0);
    for k in 0..1000 {
        let radius: Real = rng.random_range(0.01..0.3);
        let c = Vector::new(
            rng.random_range(-2.5..2.5),
            rng.random_range(-2.5..2.5),
            rng.random_range(-0.5..2.5),
        );
        let ball = Ball::new(radius);
        let pose = Pose::from_translation(c);
        let margin = margins[k % 2];
        let s = scene.clone().with_margin(margin);

        let brute: Vec<usize> = s
            .obstacles()
            .iter()
            .enumerate()
            .filter(|(_, o)| {
                let d = query::distance(&pose, &ball, &o.pose, &*o.shape).unwrap().distance;
                if margin > 0.0 {
                    d <= margin
                } else {
                    query::intersection_test(&pose, &ball, &o.pose, &*o.shape)
                        .unwrap()
                        .intersecting
                }
            })
            .map(|(i, _)| i)
            .collect();
        match s.first_hit(&ball, &pose) {
            Some(id) => {
                assert!(brute.contains(&id.index()), "query {k}: {id} not in {brute:?}");
                hits += 1;
            }
            None => {
                assert!(brute.is_empty(), "query {k}: BVH missed {brute:?}");
                misses += 1;
            }
        }

        let best = brute_distance(&s, &ball, &pose);
        let max_dist = 0.5;
        match s.distance(&ball, &pose, max_dist) {
            Some((d, id)) => {
                assert!((d - best).abs() < 1e-5, "query {k}: {d} vs {best}");
                let o = s.get(id).unwrap();
                let did = query::distance(&pose, &ball, &o.pose, &*o.shape).unwrap().distance;
                assert!((did - best).abs() < 1e-5);
            }
            None => assert!(best > max_dist, "query {k}: missed distance {best}"),
        }

        let dir = Vector::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let ray = query::Ray::new(c, dir);
        let brute_ray = s
            .obstacles()
            .iter()
            .filter_map(|o| parry3d::query::RayCast::cast_ray(&*o.shape, &o.pose, &ray, 3.0, true))
            .fold(None, |m: Option<Real>, t| Some(m.map_or(t, |m| m.min(t))));
        let bvh_ray = s.cast_ray(c, dir, 3.0).map(|(t, _)| t);
        match (bvh_ray, brute_ray) {
            (Some(a), Some(b)) => assert!((a - b).abs() < 1e-5, "query {k}: ray {a} vs {b}"),
            (a, b) => assert_eq!(a, b, "query {k}: ray"),
        }
    }
    assert!(
        hits > 50 && misses > 50,
        "degenerate test: {hits} hits, {misses} misses"
    );
}

/// One of each primitive (and a convex hull, which falls back to parry), tilted.
fn primitives() -> Vec<Obstacle> {
    let tilt = Rotation::from_euler(parry3d::glamx::EulerRot::XYZ, 0.3, -0.5, 0.9);
    vec![
        Obstacle::cuboid(
            "box",
            Pose::from_parts(Vector::new(0.5, 0.0, 0.2), tilt),
            Vector::new(0.2, 0.1, 0.05),
        ),
        Obstacle::ball("ball", Vector::new(-0.4, 0.3, 0.1), 0.15),
        Obstacle::cylinder("can", Pose::from_parts(Vector::new(0.0, -0.5, 0.3), tilt), 0.12, 0.05),
        Obstacle::capsule("rod", Vector::new(-0.3, -0.3, 0.0), Vector::new(0.2, 0.4, 0.5), 0.04),
        Obstacle::convex_hull(
            "wedge",
            Pose::translation(0.0, 0.6, 0.0),
            &[Vector::ZERO, Vector::X * 0.2, Vector::Y * 0.2, Vector::Z * 0.2],
        )
        .unwrap(),
    ]
}

/// The closed-form ball test gives the same answer as parry's, for every primitive (and a
/// convex hull, which falls back to parry), with and without a margin.
#[test]
fn ball_hits_agrees_with_parry() {
    let obstacles = primitives();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
    let probe = ParryScene::new(obstacles.clone());
    assert!(probe.intersects(&Ball::new(0.05), &Pose::translation(0.5, 0.0, 0.2)));
    assert!(probe.ball_hits(Vector::new(0.5, 0.0, 0.2), 0.05));
    for margin in [0.0, 0.03] {
        let scene = ParryScene::new(obstacles.clone()).with_margin(margin);
        let (mut hits, mut total) = (0, 0);
        for _ in 0..20_000 {
            let c = Vector::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.5..0.8),
            );
            let r = rng.random_range(0.001..0.2);
            let expected = scene.intersects(&Ball::new(r), &Pose::from_translation(c));
            // Parry's tests carry ~1e-6 of rounding: skip balls that graze within it.
            let d = scene
                .distance(&Ball::new(r), &Pose::from_translation(c), 1.0)
                .map_or(1.0, |(d, _)| d);
            if d > 0.0 && (d - margin).abs() < 1e-4 {
                continue;
            }
            assert_eq!(scene.ball_hits(c, r), expected, "ball at {c:?} r {r} margin {margin}");
            hits += expected as usize;
            total += 1;
        }
        assert!(hits > 1000 && total - hits > 1000, "{hits} hits of {total}");
    }
}

/// A batch of balls gets, bit for bit, the answers of asking ball by ball (the eight-lane
/// closed forms of boxes, balls and cylinders against the one-ball forms), with and without a
/// margin, for batches of every size up to the capacity.
#[test]
fn balls_touching_agrees_with_ball_hits() {
    use hearth_planning::obstacles::BallBatch;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
    for margin in [0.0, 0.03] {
        let scene = ParryScene::new(primitives()).with_margin(margin);
        let mut hits = 0;
        for round in 0..400 {
            let n = 1 + round % BallBatch::CAPACITY;
            let mut batch = BallBatch::new();
            let mut expected = 0u64;
            for j in 0..n {
                let c = Vector::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-0.5..0.8),
                );
                let r = rng.random_range(0.001..0.15);
                assert!(batch.push(c, r));
                expected |= u64::from(scene.ball_hits(c, r)) << j;
            }
            assert_eq!(
                scene.balls_touching(&batch),
                expected,
                "round {round}, {n} balls, margin {margin}"
            );
            hits += expected.count_ones();
        }
        assert!(hits > 300, "degenerate test: {hits} hits");
    }
}

/// `first_hit` (which answers small scenes by a scan with closed forms for balls and the
/// box-box separating-axis test) agrees with parry's own test of every obstacle, for box,
/// ball and cylinder probes at random poses. Answers may differ only within a hair of contact,
/// where f32 rounding (and parry's own GJK tolerance, ~1e-4 m) decides either way.
#[test]
fn first_hit_agrees_with_parry_per_obstacle() {
    use parry3d::shape::{Cylinder, Shape};
    let obstacles = primitives();
    let scene = ParryScene::new(obstacles.clone());
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(23);
    let probes: [Box<dyn Shape>; 4] = [
        Box::new(Cuboid::new(Vector::new(0.1, 0.03, 0.05))),
        Box::new(Cuboid::new(Vector::new(0.004, 0.2, 0.02))),
        Box::new(Ball::new(0.07)),
        Box::new(Cylinder::new(0.06, 0.04)),
    ];
    let (mut hits, mut near_contact) = (0, 0);
    for round in 0..40_000 {
        let probe = &probes[round % probes.len()];
        let rotation = Rotation::from_euler(
            parry3d::glamx::EulerRot::XYZ,
            rng.random_range(-3.2..3.2),
            rng.random_range(-3.2..3.2),
            rng.random_range(-3.2..3.2),
        );
        let pose = Pose::from_parts(
            Vector::new(
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.3..0.7),
            ),
            rotation,
        );
        let parry_hit = obstacles.iter().position(|o| {
            query::intersection_test(&pose, probe.as_ref(), &o.pose, o.shape.as_ref())
                .unwrap()
                .intersecting
        });
        let ours = scene.first_hit(probe.as_ref(), &pose);
        assert_eq!(ours.is_some(), scene.intersects(probe.as_ref(), &pose));
        if ours.is_some() != parry_hit.is_some() {
            let gap = obstacles
                .iter()
                .map(|o| {
                    query::distance(&pose, probe.as_ref(), &o.pose, o.shape.as_ref())
                        .unwrap()
                        .distance
                })
                .fold(Real::MAX, Real::min);
            assert!(
                gap < 1e-4,
                "round {round}: ours {ours:?}, parry {parry_hit:?}, gap {gap}"
            );
            near_contact += 1;
        }
        if let Some(id) = ours {
            let o = &obstacles[id.index()];
            let d = query::distance(&pose, probe.as_ref(), &o.pose, o.shape.as_ref())
                .unwrap()
                .distance;
            assert!(d < 1e-4, "round {round}: reported obstacle {id:?} is {d} away");
            hits += 1;
        }
    }
    assert!(hits > 2000 && hits < 38_000, "degenerate test: {hits} hits");
    assert!(near_contact < 10, "{near_contact} answers differ from parry's");
}

/// Cylinders against boxes, placed within 3 mm of touching: `first_hit` (closed-form
/// separating axes and contact points, parry's GJK only where those do not settle it) agrees
/// with parry wherever parry's own queries agree with each other. Near contact they do not
/// always: its distance query can answer 0 for shapes a quarter of a millimetre apart, and its
/// contact query can miss an overlap of a tenth of a millimetre. So a cylinder reported clear
/// must not be found overlapping by all three of parry's intersection, distance and contact
/// queries, and one reported touching must not be found apart by the intersection test and by
/// more than 0.1 mm by the distance query.
#[test]
fn cylinder_against_box_agrees_with_parry_near_contact() {
    use parry3d::shape::{Cylinder, Shape};
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(31);
    let euler = |rng: &mut rand_pcg::Pcg64Mcg| {
        Rotation::from_euler(
            parry3d::glamx::EulerRot::XYZ,
            rng.random_range(-3.2..3.2),
            rng.random_range(-3.2..3.2),
            rng.random_range(-3.2..3.2),
        )
    };
    let (mut hits, mut misses) = (0, 0);
    for round in 0..20_000 {
        // Thin boards and bars as well as chunky boxes, long and flat cylinders.
        let half = Vector::new(
            rng.random_range(0.005..0.4),
            rng.random_range(0.005..0.4),
            rng.random_range(0.005..0.1),
        );
        let board = Cuboid::new(half);
        let box_pose = Pose::from_parts(Vector::ZERO, euler(&mut rng));
        let scene = ParryScene::new(vec![Obstacle::cuboid("box", box_pose, half)]);
        let cylinder = Cylinder::new(rng.random_range(0.01..0.15), rng.random_range(0.01..0.08));
        let dir = Vector::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vector::X);
        let rotation = euler(&mut rng);
        let at = |t: Real| Pose::from_parts(dir * t, rotation);
        let apart = |t: Real| {
            !query::intersection_test(&at(t), &cylinder as &dyn Shape, &box_pose, &board)
                .unwrap()
                .intersecting
        };
        // Where the cylinder, moved out along `dir`, clears the box; then within 3 mm of it.
        let (mut lo, mut hi) = (0.0, half.length() + cylinder.half_height.hypot(cylinder.radius));
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if apart(mid) { hi = mid } else { lo = mid }
        }
        let t = hi + rng.random_range(-0.003..0.003);
        let pose = at(t);
        let distance = query::distance(&pose, &cylinder as &dyn Shape, &box_pose, &board)
            .unwrap()
            .distance;
        if scene.first_hit(&cylinder, &pose).is_some() {
            assert!(
                !(apart(t) && distance > 1e-4),
                "round {round}: reported touching, {distance} apart"
            );
            hits += 1;
        } else {
            let contact = query::contact(&pose, &cylinder as &dyn Shape, &box_pose, &board, 0.0).unwrap();
            assert!(
                apart(t) || distance > 0.0 || contact.is_none_or(|c| c.dist > -1e-5),
                "round {round}: reported clear, overlapping ({contact:?})"
            );
            misses += 1;
        }
    }
    assert!(
        hits > 3000 && misses > 3000,
        "degenerate test: {hits} hits, {misses} misses"
    );
}

/// Obstacles that parry would take and then answer for wrongly are refused by
/// `ParryScene::try_new`, naming the obstacle and its defect; good ones build the same scene
/// as `ParryScene::new`.
#[test]
fn try_new_refuses_obstacles_that_would_answer_wrongly() {
    use hearth_planning::obstacles::ObstacleDefect;
    use parry3d::math::Vector;
    let ok = || Obstacle::ball("ok", Vector::new(0.0, 2.0, 0.0), 0.1);
    let nan_point = [Vector::ZERO, Vector::X, Vector::Y, Vector::new(0.0, 0.0, Real::NAN)];
    let cases: Vec<(Obstacle, ObstacleDefect)> = vec![
        (
            Obstacle::cuboid("nan", at(Real::NAN, 0.0, 0.0), Vector::splat(0.1)),
            ObstacleDefect::Pose,
        ),
        (
            Obstacle::cuboid(
                "scaled",
                Pose::from_parts(Vector::ZERO, Rotation::from_xyzw(0.0, 0.0, 0.0, 2.0)),
                Vector::splat(0.1),
            ),
            ObstacleDefect::Rotation { norm: 2.0 },
        ),
        (
            Obstacle::cuboid("inside out", at(1.0, 0.0, 0.0), Vector::new(0.1, 0.1, -0.1)),
            ObstacleDefect::Size {
                what: "half-extent",
                value: -0.1,
            },
        ),
        (
            Obstacle::ball("huge", Vector::ZERO, Real::INFINITY),
            ObstacleDefect::Size {
                what: "radius",
                value: Real::INFINITY,
            },
        ),
        (
            Obstacle::cylinder("can", at(0.0, 0.0, 0.0), -0.05, 0.03),
            ObstacleDefect::Size {
                what: "half-length",
                value: -0.05,
            },
        ),
        (
            Obstacle::capsule("rail", Vector::ZERO, Vector::X, -0.01),
            ObstacleDefect::Size {
                what: "radius",
                value: -0.01,
            },
        ),
        // A bounding box of min and max passes over a NaN end: the ends are checked.
        (
            Obstacle::capsule("bent rail", Vector::new(0.0, Real::NAN, 0.0), Vector::X, 0.01),
            ObstacleDefect::Bounds,
        ),
        (
            Obstacle::cuboid("far", at(2e6, 0.0, 0.0), Vector::splat(1.0)),
            ObstacleDefect::Extent { reach: 2e6 + 1.0 },
        ),
    ];
    for (bad, defect) in cases {
        let name = bad.name.clone();
        assert_eq!(bad.check(), Err(defect), "{name}");
        let e = ParryScene::try_new(vec![ok(), bad]).unwrap_err();
        assert_eq!((e.index, e.name.as_str(), e.defect), (1, name.as_str(), defect));
        assert!(
            e.to_string().starts_with(&format!("obstacle 1 ({name:?}): its ")),
            "{e}"
        );
    }
    // A hull of a non-finite point: parry builds none, or one whose bounds are not finite.
    if let Some(hull) = Obstacle::convex_hull("hull", Pose::IDENTITY, &nan_point) {
        assert!(hull.check().is_err());
    }
    // Zero sizes (points, flat boxes) and a quaternion within rounding of unit are fine.
    let fine = vec![
        ok(),
        Obstacle::ball("point", Vector::ZERO, 0.0),
        Obstacle::cuboid("sheet", at(0.0, 0.0, 1.0), Vector::new(0.5, 0.5, 0.0)),
        Obstacle::cuboid(
            "turned",
            Pose::from_parts(Vector::ZERO, Rotation::from_xyzw(0.0, 0.0, 0.3827, 0.9239)),
            Vector::splat(0.1),
        ),
    ];
    let scene = ParryScene::try_new(fine.clone()).unwrap();
    let plain = ParryScene::new(fine);
    assert_eq!(scene.obstacles().len(), 4);
    let probe = point();
    for p in [at(0.0, 2.0, 0.0), at(0.0, 0.0, 1.0), at(0.5, 0.5, 0.5)] {
        assert_eq!(scene.first_hit(&probe, &p), plain.first_hit(&probe, &p));
    }
}
