//! Invariants of the configuration spaces: interpolation endpoints and bounds, metric axioms,
//! the short way round for continuous joints, seeded sampling, and typed errors on bad input.

use std::f64::consts::PI;

use hearth_planning::kinematics::{Chain, RobotModel, wrap_angle};
use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space, Space, SpaceError};
use proptest::prelude::*;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

const EPS: f64 = 1e-9;

/// One joint's description: continuous, or bounded `[lo, lo + width]`.
fn joint() -> impl Strategy<Value = (bool, f64, f64)> {
    (
        prop::bool::weighted(0.3),
        -4.0..4.0f64,
        prop_oneof![1 => Just(0.0), 9 => 0.0..6.0f64],
    )
}

fn joint_space() -> impl Strategy<Value = JointSpace> {
    prop::collection::vec((joint(), 0.0..3.0f64), 1..9).prop_map(|joints| {
        let lower: Vec<f64> = joints.iter().map(|((_, lo, _), _)| *lo).collect();
        let upper: Vec<f64> = joints.iter().map(|((_, lo, w), _)| lo + w).collect();
        let continuous: Vec<bool> = joints.iter().map(|((c, _, _), _)| *c).collect();
        let weights: Vec<f64> = joints.iter().map(|(_, w)| *w).collect();
        JointSpace::new(&lower, &upper, &continuous)
            .unwrap()
            .with_weights(&weights)
            .unwrap()
    })
}

fn se2_space() -> impl Strategy<Value = Se2Space> {
    (-10.0..10.0f64, -10.0..10.0f64, 0.0..10.0f64, 0.0..10.0f64, 0.0..2.0f64).prop_map(|(x, y, w, h, yaw)| {
        Se2Space::new([x, y], [x + w, y + h])
            .unwrap()
            .with_yaw_weight(yaw)
            .unwrap()
    })
}

fn compound_space() -> impl Strategy<Value = CompoundSpace<Se2Space, JointSpace>> {
    (se2_space(), joint_space(), 0.0..3.0f64, 0.0..3.0f64)
        .prop_map(|(base, arm, w1, w2)| CompoundSpace::new(base, arm).with_weights(w1, w2).unwrap())
}

/// A fraction in `[0, 1]` that hits both ends often.
fn fraction() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 1 => Just(1.0), 8 => 0.0..=1.0f64]
}

/// A state inside the bounds from per-coordinate fractions (bounds hit exactly, ±π included).
fn state_in<S: Space>(space: &S, f: &[f64]) -> Vec<f64> {
    (0..space.dim())
        .map(|i| {
            let (lo, hi) = (space.lower()[i], space.upper()[i]);
            let f = f[i % f.len()];
            if f == 1.0 { hi } else { lo + f * (hi - lo) }
        })
        .collect()
}

/// Whether two states are the same, angles of continuous coordinates compared modulo 2π.
fn same_state<S: Space>(space: &S, a: &[f64], b: &[f64]) -> bool {
    let mut d = vec![0.0; space.dim()];
    space.difference(a, b, &mut d);
    d.iter().all(|x| x.abs() < 1e-9)
}

/// Every invariant, for any space and any three in-bounds states.
fn check_invariants<S: Space>(space: &S, a: &[f64], b: &[f64], c: &[f64], t: f64) -> Result<(), TestCaseError> {
    let n = space.dim();
    prop_assert!(space.satisfies_bounds(a) && space.satisfies_bounds(b) && space.satisfies_bounds(c));
    prop_assert!(space.check(a).is_ok());
    let mut out = vec![f64::NAN; n];

    // Endpoints, exactly.
    space.interpolate(a, b, 0.0, &mut out);
    prop_assert_eq!(&out[..], a);
    space.interpolate(a, b, 1.0, &mut out);
    prop_assert_eq!(&out[..], b);

    // Interior points stay in bounds and lie the right fraction of the way along.
    let dab = space.distance(a, b);
    space.interpolate(a, b, t, &mut out);
    prop_assert!(space.satisfies_bounds(&out), "{out:?} out of bounds");
    prop_assert!((space.distance(a, &out) - t * dab).abs() < 1e-9 * (1.0 + dab));
    prop_assert!((space.distance(&out, b) - (1.0 - t) * dab).abs() < 1e-9 * (1.0 + dab));

    // Metric axioms.
    prop_assert!(dab >= 0.0);
    prop_assert!(space.distance(a, a).abs() < EPS);
    prop_assert!((dab - space.distance(b, a)).abs() < EPS);
    prop_assert!(space.distance(a, c) <= dab + space.distance(b, c) + EPS);

    // The Euclidean bound, where the space offers one: E ≤ L ≤ distance ≤ stretch·E.
    if let Some(bound) = space.euclidean_bound() {
        prop_assert!(bound.stretch >= 1.0 && bound.weights.len() == n);
        let (e, l) = (bound.distance(a, b), bound.lower(a, b));
        prop_assert!(e <= l * (1.0 + 1e-12) + EPS, "bound {e} above the groups' sum {l}");
        prop_assert!(
            l <= dab * (1.0 + 1e-12) + EPS,
            "groups' sum {l} above the distance {dab}"
        );
        prop_assert!(
            dab <= bound.stretch * e * (1.0 + 1e-12) + EPS,
            "distance {dab} above {} × {e}",
            bound.stretch
        );
    }

    // The difference leads from a to b, the short way.
    let mut d = vec![0.0; n];
    space.difference(a, b, &mut d);
    let mut reached: Vec<f64> = a.iter().zip(&d).map(|(x, y)| x + y).collect();
    space.enforce_bounds(&mut reached);
    prop_assert!(same_state(space, &reached, b));
    prop_assert!(d.iter().all(|x| x.abs() <= (space.upper().iter().zip(space.lower()).map(|(h, l)| h - l)).fold(0.0, f64::max) + EPS));

    // Enforcing bounds keeps in-bounds states (up to the wrap of -π to π) and fixes others.
    let mut kept = a.to_vec();
    space.enforce_bounds(&mut kept);
    prop_assert!(same_state(space, &kept, a));
    let mut far: Vec<f64> = a
        .iter()
        .enumerate()
        .map(|(i, x)| x + if i % 2 == 0 { 100.0 } else { -100.0 })
        .collect();
    space.enforce_bounds(&mut far);
    prop_assert!(space.satisfies_bounds(&far));
    Ok(())
}

proptest! {
    #[test]
    fn joint_space_invariants(space in joint_space(), fa in prop::collection::vec(fraction(), 8),
                              fb in prop::collection::vec(fraction(), 8), fc in prop::collection::vec(fraction(), 8),
                              t in fraction()) {
        let (a, b, c) = (state_in(&space, &fa), state_in(&space, &fb), state_in(&space, &fc));
        check_invariants(&space, &a, &b, &c, t)?;
    }

    #[test]
    fn se2_space_invariants(space in se2_space(), fa in prop::collection::vec(fraction(), 3),
                            fb in prop::collection::vec(fraction(), 3), fc in prop::collection::vec(fraction(), 3),
                            t in fraction()) {
        let (a, b, c) = (state_in(&space, &fa), state_in(&space, &fb), state_in(&space, &fc));
        check_invariants(&space, &a, &b, &c, t)?;
    }

    #[test]
    fn compound_space_invariants(space in compound_space(), fa in prop::collection::vec(fraction(), 11),
                                 fb in prop::collection::vec(fraction(), 11), fc in prop::collection::vec(fraction(), 11),
                                 t in fraction()) {
        let (a, b, c) = (state_in(&space, &fa), state_in(&space, &fb), state_in(&space, &fc));
        check_invariants(&space, &a, &b, &c, t)?;
    }

    #[test]
    fn sampled_states_satisfy_invariants(space in compound_space(), seed in any::<u64>(), t in fraction()) {
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let mut s = vec![vec![0.0; space.dim()]; 3];
        for q in &mut s {
            space.sample(&mut rng, q);
            prop_assert!(space.satisfies_bounds(q));
        }
        check_invariants(&space, &s[0], &s[1], &s[2], t)?;
    }

    #[test]
    fn sampling_is_reproducible(space in joint_space(), seed in any::<u64>()) {
        let draw = |seed| {
            let mut rng = Pcg64Mcg::seed_from_u64(seed);
            let mut q = vec![0.0; space.dim()];
            (0..4).flat_map(|_| { space.sample(&mut rng, &mut q); q.clone() }).collect::<Vec<f64>>()
        };
        prop_assert_eq!(draw(seed), draw(seed));
    }

    #[test]
    fn continuous_joints_take_the_short_way(a in -PI..=PI, b in -PI..=PI, t in fraction()) {
        let space = JointSpace::new(&[0.0], &[0.0], &[true]).unwrap();
        let d = space.distance(&[a], &[b]);
        prop_assert!(d <= PI + EPS);
        prop_assert!((d - (b - a).abs().min(2.0 * PI - (b - a).abs())).abs() < 1e-9);
        let mut out = [0.0];
        space.interpolate(&[a], &[b], t, &mut out);
        prop_assert!((-PI..=PI).contains(&out[0]));
        prop_assert!((wrap_angle(out[0] - a).abs() - t * d).abs() < 1e-9);
    }
}

#[test]
fn continuous_distance_wraps_through_pi() {
    let space = JointSpace::new(&[f64::NEG_INFINITY], &[f64::INFINITY], &[true]).unwrap();
    let d = space.distance(&[3.1], &[-3.1]);
    assert!((d - (2.0 * PI - 6.2)).abs() < 1e-12, "{d}");
    assert!((d - 0.083).abs() < 1e-3);
    let mut mid = [0.0];
    space.interpolate(&[3.1], &[-3.1], 0.5, &mut mid);
    assert!((mid[0].abs() - PI).abs() < 1e-12, "went the long way: {}", mid[0]);
    let mut diff = [0.0];
    space.difference(&[3.1], &[-3.1], &mut diff);
    assert!((diff[0] - (2.0 * PI - 6.2)).abs() < 1e-12);
    let mut q = [7.0];
    space.enforce_bounds(&mut q);
    assert!((q[0] - (7.0 - 2.0 * PI)).abs() < 1e-12);
    assert!(space.satisfies_bounds(&[PI]) && space.satisfies_bounds(&[-PI]) && !space.satisfies_bounds(&[3.2]));
}

#[test]
fn bounded_joints_do_not_wrap() {
    let space = JointSpace::new(&[-3.2], &[3.2], &[false]).unwrap();
    assert!((space.distance(&[3.1], &[-3.1]) - 6.2).abs() < 1e-12);
    let mut q = [7.0];
    space.enforce_bounds(&mut q);
    assert_eq!(q, [3.2]);
}

#[test]
fn sample_is_uniform_over_the_bounds() {
    let space = JointSpace::new(&[0.0, 2.0, 0.0], &[1.0, 2.0, 0.0], &[false, false, true]).unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let mut q = [0.0; 3];
    let (mut low_half, mut neg) = (0, 0);
    for _ in 0..10_000 {
        space.sample(&mut rng, &mut q);
        assert!(space.satisfies_bounds(&q));
        assert_eq!(q[1], 2.0, "a pinned joint stays put");
        low_half += usize::from(q[0] < 0.5);
        neg += usize::from(q[2] < 0.0);
    }
    assert!((4_700..5_300).contains(&low_half), "{low_half}");
    assert!((4_700..5_300).contains(&neg), "{neg}");
}

#[test]
fn fetch_arm_with_torso() -> Result<(), Box<dyn std::error::Error>> {
    let fetch = RobotModel::builtin("fetch")?;
    let chain = Chain::named(&fetch, "arm_with_torso")?;
    let space = JointSpace::from_chain(&chain)?;
    assert_eq!(space.dim(), 8);
    assert_eq!(space.names(), chain.joint_names());
    assert_eq!(space.coordinate_name(0), Some("torso_lift_joint"));
    assert_eq!(space.coordinate_name(8), None);
    assert_eq!(space.velocity_limits(), chain.velocity_limits());
    let continuous: Vec<&str> = (0..8)
        .filter(|&i| space.continuous()[i])
        .map(|i| space.names()[i].as_str())
        .collect();
    assert_eq!(continuous.len(), 3, "{continuous:?}");
    assert!(continuous.iter().all(|n| n.contains("roll")), "{continuous:?}");
    for i in 0..8 {
        if space.continuous()[i] {
            assert_eq!((space.lower()[i], space.upper()[i]), (-PI, PI));
        } else {
            assert_eq!(
                (space.lower()[i], space.upper()[i]),
                (chain.lower()[i], chain.upper()[i])
            );
            assert!(space.lower()[i] < space.upper()[i]);
        }
    }

    // Same samples as the chain's own random configurations, from the same seed.
    let (mut r1, mut r2) = (Pcg64Mcg::seed_from_u64(11), Pcg64Mcg::seed_from_u64(11));
    let (mut q1, mut q2) = ([0.0; 8], [0.0; 8]);
    for _ in 0..100 {
        space.sample(&mut r1, &mut q1);
        chain.random_configuration(&mut r2, &mut q2);
        assert_eq!(q1, q2);
        space.check(&q1)?;
    }

    // A roll joint's error names it.
    let roll = space.continuous().iter().position(|&c| c).unwrap();
    let mut bad = q1;
    bad[roll] = 4.0;
    let err = space.check(&bad).unwrap_err();
    assert!(matches!(err, SpaceError::OutOfBounds { index, .. } if index == roll));
    assert!(err.to_string().contains(&space.names()[roll]), "{err}");
    Ok(())
}

#[test]
fn bad_descriptions_are_typed_errors() {
    use SpaceError::*;
    assert!(matches!(
        JointSpace::new(&[0.0, 0.0], &[1.0], &[false, false]),
        Err(DimensionMismatch {
            what: "upper bounds",
            ..
        })
    ));
    assert!(matches!(
        JointSpace::new(&[0.0], &[1.0], &[false, true]),
        Err(DimensionMismatch {
            what: "continuous flags",
            ..
        })
    ));
    assert!(matches!(
        JointSpace::new(&[0.0, 2.0], &[1.0, 1.0], &[false, false]),
        Err(InvalidBounds { index: 1, .. })
    ));
    assert!(matches!(
        JointSpace::new(&[f64::NAN], &[1.0], &[false]),
        Err(InvalidBounds { index: 0, .. })
    ));
    assert!(matches!(
        JointSpace::new(&[0.0], &[f64::INFINITY], &[false]),
        Err(InvalidBounds { index: 0, .. })
    ));
    // Continuous joints ignore whatever bounds they were given.
    assert!(JointSpace::new(&[f64::NAN], &[f64::NAN], &[true]).is_ok());

    let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false]).unwrap();
    assert!(matches!(
        space.clone().with_weights(&[1.0]),
        Err(DimensionMismatch { what: "weights", .. })
    ));
    assert!(matches!(
        space.clone().with_weights(&[1.0, f64::NAN]),
        Err(InvalidWeight { .. })
    ));
    assert!(matches!(
        space.clone().with_weights(&[1.0, -0.1]),
        Err(InvalidWeight { .. })
    ));
    assert!(matches!(
        space.clone().with_names(["a"]),
        Err(DimensionMismatch { what: "names", .. })
    ));
    assert!(matches!(
        space.clone().with_velocity_limits(&[1.0, 0.0]),
        Err(InvalidVelocityLimit { .. })
    ));
    assert!(space.clone().with_velocity_limits(&[1.0, f64::INFINITY]).is_ok());

    assert!(matches!(
        Se2Space::new([0.0, 0.0], [-1.0, 1.0]),
        Err(InvalidBounds { index: 0, .. })
    ));
    assert!(matches!(
        Se2Space::new([0.0, f64::NAN], [1.0, 1.0]),
        Err(InvalidBounds { index: 1, .. })
    ));
    let base = Se2Space::new([0.0, 0.0], [1.0, 1.0]).unwrap();
    assert!(matches!(base.clone().with_yaw_weight(-1.0), Err(InvalidWeight { .. })));
    assert!(matches!(
        CompoundSpace::new(base, space).with_weights(1.0, f64::INFINITY),
        Err(InvalidWeight { .. })
    ));
}

#[test]
fn bad_states_are_typed_errors_naming_the_coordinate() {
    use SpaceError::*;
    let arm = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, true])
        .unwrap()
        .with_names(["lift", "roll"])
        .unwrap();
    assert_eq!(
        arm.check(&[0.0]),
        Err(DimensionMismatch {
            what: "state",
            expected: 2,
            got: 1
        })
    );
    assert!(!arm.satisfies_bounds(&[0.0]));
    let err = arm.check(&[0.0, f64::NAN]).unwrap_err();
    assert!(
        matches!(&err, NotFinite { index: 1, name, .. } if name == "roll"),
        "{err}"
    );
    assert!(err.to_string().contains("roll"));
    assert!(matches!(
        arm.check(&[f64::INFINITY, 0.0]),
        Err(NotFinite { index: 0, .. })
    ));
    assert!(!arm.satisfies_bounds(&[f64::NAN, 0.0]));
    let err = arm.check(&[1.5, 0.0]).unwrap_err();
    assert_eq!(
        err,
        OutOfBounds {
            index: 0,
            name: "lift".into(),
            value: 1.5,
            lower: -1.0,
            upper: 1.0
        }
    );
    assert!(err.to_string().contains("lift"));
    assert!(arm.check(&[1.0, -PI]).is_ok());

    let base = Se2Space::new([0.0, 0.0], [2.0, 2.0]).unwrap();
    assert!(matches!(
        base.check(&[1.0, 3.0, 0.0]),
        Err(OutOfBounds { index: 1, .. })
    ));
    assert!(base.check(&[1.0, 1.0, 4.0]).unwrap_err().to_string().contains("yaw"));
    let both = CompoundSpace::new(base, arm);
    assert!(matches!(
        both.check(&[1.0; 4]),
        Err(DimensionMismatch {
            expected: 5,
            got: 4,
            ..
        })
    ));
    assert!(
        matches!(both.check(&[1.0, 1.0, 0.0, 0.0, 9.0]), Err(OutOfBounds { index: 4, ref name, .. }) if name == "roll")
    );
    assert!(matches!(
        both.check(&[1.0, 1.0, 0.0, f64::NAN, 0.0]),
        Err(NotFinite { index: 3, .. })
    ));
    assert_eq!(both.coordinate_name(2), Some("yaw"));
    assert_eq!(both.coordinate_name(4), Some("roll"));
    assert_eq!(both.coordinate_name(5), None);
    assert!(!both.satisfies_bounds(&[1.0; 6]));
}

#[test]
fn se2_distance_and_yaw_weight() {
    let base = Se2Space::new([-10.0, -10.0], [10.0, 10.0]).unwrap();
    assert_eq!(base.yaw_weight(), Se2Space::DEFAULT_YAW_WEIGHT);
    let d = base.distance(&[0.0, 0.0, 3.1], &[3.0, 4.0, -3.1]);
    assert!((d - (5.0 + 0.5 * (2.0 * PI - 6.2))).abs() < 1e-12);
    let mut q = [20.0, -20.0, 3.0 * PI];
    base.enforce_bounds(&mut q);
    assert_eq!(&q[..2], &[10.0, -10.0]);
    assert!((q[2].abs() - PI).abs() < 1e-12);
    let mut diff = [0.0; 3];
    base.difference(&[1.0, 1.0, 3.0], &[0.0, 2.0, -3.0], &mut diff);
    assert!((diff[0] + 1.0).abs() < 1e-12 && (diff[1] - 1.0).abs() < 1e-12);
    assert!((diff[2] - (2.0 * PI - 6.0)).abs() < 1e-12);
}

#[test]
fn compound_matches_its_parts() {
    let base = Se2Space::new([-1.0, -1.0], [1.0, 1.0]).unwrap();
    let arm = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true]).unwrap();
    let space = CompoundSpace::new(base.clone(), arm.clone())
        .with_weights(2.0, 0.5)
        .unwrap();
    assert_eq!(space.dim(), 5);
    assert_eq!(space.lower(), &[-1.0, -1.0, -PI, -1.0, -PI]);
    assert_eq!(space.upper(), &[1.0, 1.0, PI, 1.0, PI]);
    let a = [0.1, 0.2, 3.0, -0.5, -3.0];
    let b = [-0.4, 0.9, -3.0, 0.7, 3.0];
    let expected = 2.0 * base.distance(&a[..3], &b[..3]) + 0.5 * arm.distance(&a[3..], &b[3..]);
    assert_eq!(space.distance(&a, &b), expected);
    let (mut whole, mut parts) = ([0.0; 5], [0.0; 5]);
    space.interpolate(&a, &b, 0.3, &mut whole);
    base.interpolate(&a[..3], &b[..3], 0.3, &mut parts[..3]);
    arm.interpolate(&a[3..], &b[3..], 0.3, &mut parts[3..]);
    assert_eq!(whole, parts);

    // Sampling draws the base first, then the arm, from the same generator.
    let (mut r1, mut r2) = (Pcg64Mcg::seed_from_u64(5), Pcg64Mcg::seed_from_u64(5));
    space.sample(&mut r1, &mut whole);
    base.sample(&mut r2, &mut parts[..3]);
    arm.sample(&mut r2, &mut parts[3..]);
    assert_eq!(whole, parts);

    // Nesting: base + arm + another arm.
    let nested = CompoundSpace::new(base, CompoundSpace::new(arm.clone(), arm));
    assert_eq!(nested.dim(), 7);
    assert!(matches!(
        nested.check(&[0.0, 0.0, 0.0, 0.0, 0.0, 5.0, 0.0]),
        Err(SpaceError::OutOfBounds { index: 5, .. })
    ));
}

#[test]
fn spaces_are_send_and_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<JointSpace>();
    assert_send_sync::<Se2Space>();
    assert_send_sync::<CompoundSpace<Se2Space, JointSpace>>();
}

/// The distance of a space with continuous joints (four coordinates per lane step inside)
/// equals, bit for bit, the sum in coordinate order of the weighted squared differences taken
/// the short way round: for wrapped states, for states given unwrapped (several turns off) and
/// with a NaN, over spaces of 1 to 11 joints.
#[test]
fn continuous_distances_are_the_coordinate_by_coordinate_sum() {
    use rand::RngExt;
    let mut rng = Pcg64Mcg::seed_from_u64(41);
    for _ in 0..3000 {
        let n = rng.random_range(1..12usize);
        let continuous: Vec<bool> = (0..n).map(|i| i == 0 || rng.random_bool(0.5)).collect();
        let lower: Vec<f64> = (0..n).map(|_| rng.random_range(-4.0..0.0)).collect();
        let upper: Vec<f64> = lower.iter().map(|l| l + rng.random_range(0.0..6.0)).collect();
        let weights: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..2.0)).collect();
        let space = JointSpace::new(&lower, &upper, &continuous)
            .unwrap()
            .with_weights(&weights)
            .unwrap();
        let turns = if rng.random_bool(0.1) { 40.0 } else { 1.0 };
        let mut state = |space: &JointSpace| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let (lo, hi) = (space.lower()[i], space.upper()[i]);
                    let x = rng.random_range(lo..=hi);
                    if continuous[i] { x * turns } else { x }
                })
                .collect()
        };
        let a = state(&space);
        let mut b = state(&space);
        if rng.random_bool(0.02) {
            b[rng.random_range(0..n)] = f64::NAN;
        }
        let mut sum = 0.0;
        for i in 0..n {
            let diff = if continuous[i] {
                wrap_angle(b[i] - a[i])
            } else {
                b[i] - a[i]
            };
            let d = weights[i] * diff;
            sum += d * d;
        }
        let got = space.distance(&a, &b);
        assert!(
            got.to_bits() == sum.sqrt().to_bits() || (got.is_nan() && sum.is_nan()),
            "{got} against {}",
            sum.sqrt()
        );
    }
}
