//! Jerk limiting by a moving average (`Trajectory::with_jerk_limits`): the averaged motion is
//! the exact mean of its source, keeps the velocity, acceleration and position bounds, bounds
//! the jerk, rests at both ends and stays within `a w² / 24` of the source.

use hearth_planning::planner::Path;
use hearth_planning::shortcut::{self, ShortcutSettings};
use hearth_planning::space::JointSpace;
use hearth_planning::trajectory::{Limits, Trajectory, TrajectoryError};
use hearth_planning::validity::StateValidator;
use proptest::prelude::*;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

const V: [f64; 2] = [1.0, 0.5];
const A: [f64; 2] = [2.0, 1.0];
const J: [f64; 2] = [40.0, 20.0];
/// `max 2 a / j` over the two coordinates.
const W: f64 = 0.1;

fn square() -> JointSpace {
    JointSpace::new(&[0., 0.], &[1., 1.], &[false, false]).unwrap()
}

fn jerk_limits() -> Limits {
    Limits::new(V.to_vec(), A.to_vec(), J.to_vec())
        .unwrap()
        .with_position_bounds(vec![0.0; 2], vec![1.0; 2])
        .unwrap()
}

struct Free;

impl StateValidator for Free {
    fn is_valid(&mut self, _: &[f64]) -> bool {
        true
    }
    fn checks(&self) -> u64 {
        0
    }
}

/// A parabolic motion through `states`: rest to rest, then shortcut with ramps that pass the
/// corners without stopping.
fn parabolic(states: Vec<Vec<f64>>, seed: u64) -> Trajectory {
    let limits = jerk_limits().without_jerk();
    let mut t = Trajectory::rest_to_rest(&square(), &Path { states }, &limits).unwrap();
    let mut motion = hearth_planning::motion::MotionValidator::new(square(), 0.01);
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let settings = ShortcutSettings {
        attempts: 20,
        ..Default::default()
    };
    shortcut::parabolic(&mut motion, &mut Free, &mut t, &limits, &settings, &mut rng).unwrap();
    t
}

/// The mean of `source` over `[t - W, t]` by the midpoint rule on 4,000 steps.
fn brute_mean(source: &Trajectory, t: f64) -> [f64; 2] {
    let n = 4000;
    let mut sum = [0.0; 2];
    let mut q = [0.0; 2];
    for k in 0..n {
        source.sample(t - W + W * (k as f64 + 0.5) / n as f64, &mut q, None);
        sum[0] += q[0] / n as f64;
        sum[1] += q[1] / n as f64;
    }
    sum
}

/// `smooth` equals the brute-force mean of `source` at 41 times across it.
fn assert_is_mean_of(source: &Trajectory, smooth: &Trajectory) {
    let mut q = [0.0; 2];
    for k in 0..=40 {
        let t = smooth.duration() * k as f64 / 40.0;
        smooth.sample(t, &mut q, None);
        let mean = brute_mean(source, t);
        assert!(
            (q[0] - mean[0]).abs() < 1e-7 && (q[1] - mean[1]).abs() < 1e-7,
            "{q:?} {mean:?} at {t}"
        );
    }
}

/// Checks everything the averaged motion promises, sampling every `dt`.
fn assert_averaged(source: &Trajectory, smooth: &Trajectory) -> Result<(), TestCaseError> {
    prop_assert!((smooth.duration() - source.duration() - W).abs() < 1e-12);
    let (mut q, mut v, mut p) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    // At rest where the source starts and ends.
    for (t, s) in [(0.0, 0.0), (smooth.duration(), source.duration())] {
        smooth.sample(t, &mut q, Some(&mut v));
        source.sample(s, &mut p, None);
        prop_assert!(
            (q[0] - p[0]).abs() < 1e-12 && (q[1] - p[1]).abs() < 1e-12,
            "{q:?} {p:?}"
        );
        prop_assert!(v[0].abs() < 1e-12 && v[1].abs() < 1e-12, "{v:?}");
    }
    // Velocity and acceleration within the limits.
    let (vmax, amax) = smooth.peak_velocity_acceleration(1e-4).unwrap();
    for i in 0..2 {
        prop_assert!(vmax[i] <= V[i] + 1e-9, "{vmax:?}");
        prop_assert!(amax[i] <= A[i] + 1e-6, "{amax:?}");
    }
    // Jerk within the limits: second differences of the velocity.
    let h = 1e-3;
    let (mut v0, mut v1, mut v2) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    let steps = (smooth.duration() / h) as usize;
    for k in 1..steps {
        let t = k as f64 * h;
        smooth.sample(t - h, &mut q, Some(&mut v0));
        smooth.sample(t, &mut q, Some(&mut v1));
        smooth.sample(t + h, &mut q, Some(&mut v2));
        for i in 0..2 {
            let jerk = (v2[i] - 2.0 * v1[i] + v0[i]) / (h * h);
            prop_assert!(jerk.abs() <= J[i] * (1.0 + 1e-6) + 1e-6, "jerk {jerk} at {t}");
        }
        // Inside the position bounds, near the source half a window earlier, and its exact mean.
        prop_assert!(q.iter().all(|x| (-1e-12..=1.0 + 1e-12).contains(x)), "{q:?}");
        smooth.sample(t, &mut q, None);
        source.sample(t - W / 2.0, &mut p, None);
        for i in 0..2 {
            prop_assert!((q[i] - p[i]).abs() <= A[i] * W * W / 24.0 + 1e-12, "{q:?} {p:?} at {t}");
        }
        if k % 50 == 0 {
            let mean = brute_mean(source, t);
            for i in 0..2 {
                prop_assert!((q[i] - mean[i]).abs() < 1e-7, "{q:?} {mean:?} at {t}");
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn the_average_of_a_parabolic_motion_keeps_its_promises(
        states in prop::collection::vec(prop::collection::vec(0.0f64..1.0, 2), 2..6),
        seed in 0u64..1000,
    ) {
        let source = parabolic(states, seed);
        let smooth = source.with_jerk_limits(&jerk_limits()).unwrap();
        assert_averaged(&source, &smooth)?;
    }

    #[test]
    fn the_average_of_a_jerk_limited_motion_keeps_its_promises(
        states in prop::collection::vec(prop::collection::vec(0.0f64..1.0, 2), 2..5),
    ) {
        // Cubic pieces (Ruckig's), stopping at every waypoint.
        let source = Trajectory::jerk_limited_stops(&square(), &Path { states }, &jerk_limits()).unwrap();
        let smooth = source.with_jerk_limits(&jerk_limits()).unwrap();
        assert_averaged(&source, &smooth)?;
    }
}

#[test]
fn a_ramp_from_a_moving_start_and_a_line_are_averaged_exactly() {
    // Ruckig phases that do not begin at rest, then a straight segment.
    let limits = jerk_limits().without_jerk();
    let ramp = Trajectory::ramp(&[0.2, 0.3], &[0.8, -0.4], &[0.9, 0.5], &[0.0, 0.0], &limits).unwrap();
    let motion = Trajectory::rest_to_rest(
        &square(),
        &Path {
            states: vec![vec![0.9, 0.5], vec![0.1, 0.9]],
        },
        &limits,
    )
    .unwrap();
    let source = ramp.then(motion).unwrap();
    let smooth = source.with_jerk_limits(&jerk_limits()).unwrap();
    assert_is_mean_of(&source, &smooth);
}

#[test]
fn averaging_twice_is_still_exact() {
    let source = parabolic(vec![vec![0.1, 0.1], vec![0.9, 0.2], vec![0.4, 0.9]], 3);
    let once = source.with_jerk_limits(&jerk_limits()).unwrap();
    let twice = once.with_jerk_limits(&jerk_limits()).unwrap();
    assert!((twice.duration() - source.duration() - 2.0 * W).abs() < 1e-12);
    assert_is_mean_of(&once, &twice);
}

#[test]
fn without_a_jerk_limit_or_motion_nothing_changes() {
    let source = parabolic(vec![vec![0.1, 0.1], vec![0.9, 0.2]], 1);
    let same = source.with_jerk_limits(&jerk_limits().without_jerk()).unwrap();
    assert_eq!(same.duration(), source.duration());
    let still = Trajectory::rest_to_rest(
        &square(),
        &Path {
            states: vec![vec![0.5, 0.5]],
        },
        &jerk_limits(),
    )
    .unwrap();
    assert_eq!(still.with_jerk_limits(&jerk_limits()).unwrap().duration(), 0.0);
}

#[test]
fn limits_of_another_dimension_are_refused() {
    let source = parabolic(vec![vec![0.1, 0.1], vec![0.9, 0.2]], 1);
    let three = Limits::new(vec![1.0; 3], vec![1.0; 3], vec![10.0; 3]).unwrap();
    assert_eq!(
        source.with_jerk_limits(&three).unwrap_err(),
        TrajectoryError::Dimension {
            what: "limits",
            expected: 2,
            got: 3
        }
    );
}
