//! Trajectories and shortcutting: limits respected, durations and lengths never grow, paths
//! stay valid (also at a finer resolution), jerk-limited motions stay on their edges, and bad
//! input gives typed errors.

use hearth_planning::BiRrt;
use hearth_planning::motion::MotionValidator;
use hearth_planning::planner::{Budget, Goal, Path, PlanRequest, Planner};
use hearth_planning::shortcut::{self, ShortcutSettings};
use hearth_planning::space::{JointSpace, Space};
use hearth_planning::trajectory::{Limits, Trajectory, TrajectoryError};
use hearth_planning::validity::StateValidator;
use proptest::prelude::*;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

/// Two walls with gaps at opposite ends: a zig-zag world where shortcuts matter. `shrink`
/// thins the walls on every side (a sampled check can graze a corner by less than its
/// resolution; final checks use a shrunk copy to allow for that).
#[derive(Default)]
struct Walls {
    checks: u64,
    shrink: f64,
}

impl Walls {
    fn shrunk(by: f64) -> Self {
        Self { checks: 0, shrink: by }
    }
}

impl StateValidator for Walls {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        let e = self.shrink;
        let wall1 = (0.3 + e..=0.35 - e).contains(&q[0]) && q[1] < 0.8 - e;
        let wall2 = (0.65 + e..=0.7 - e).contains(&q[0]) && q[1] > 0.2 + e;
        !(wall1 || wall2)
    }
    fn checks(&self) -> u64 {
        self.checks
    }
}

fn square() -> JointSpace {
    JointSpace::new(&[0., 0.], &[1., 1.], &[false, false]).unwrap()
}

fn limits2() -> Limits {
    Limits::new(vec![1.0, 0.5], vec![2.0, 1.0], vec![f64::INFINITY; 2])
        .unwrap()
        .with_position_bounds(vec![0.0, 0.0], vec![1.0, 1.0])
        .unwrap()
}

fn planned(seed: u64) -> (MotionValidator<JointSpace>, Path) {
    let mut motion = MotionValidator::new(square(), 0.005);
    let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let solution = BiRrt::default()
        .plan(
            &mut motion,
            &mut Walls::default(),
            &request,
            &Budget::iterations(20_000),
            &mut rng,
        )
        .unwrap();
    (motion, solution.path)
}

fn path_valid(motion: &mut MotionValidator<JointSpace>, path: &Path) -> bool {
    let mut v = Walls::default();
    path.states.iter().all(|q| v.is_valid(q))
        && path
            .states
            .windows(2)
            .all(|w| motion.check_motion(&mut v, &w[0], &w[1]))
}

#[test]
fn rest_to_rest_respects_limits_and_follows_the_path() {
    let (motion, path) = planned(1);
    let t = Trajectory::rest_to_rest(motion.space(), &path, &limits2()).unwrap();
    let (v, a) = t.peak_velocity_acceleration(1e-4).expect("a positive step");
    assert!(v[0] <= 1.0 + 1e-9 && v[1] <= 0.5 + 1e-9, "{v:?}");
    assert!(a[0] <= 2.0 + 1e-6 && a[1] <= 1.0 + 1e-6, "{a:?}");
    let mut q = [0.0; 2];
    t.sample(0.0, &mut q, None);
    assert_eq!(q.to_vec(), path.states[0]);
    t.sample(t.duration(), &mut q, None);
    assert!(motion.space().distance(&q, path.states.last().unwrap()) < 1e-12);
    assert!(t.check(motion.space(), &mut Walls::default(), 0.001).is_ok());
}

#[test]
fn parabolic_shortcutting_shortens_time_keeps_validity_and_limits() {
    for seed in 0..5 {
        let (mut motion, path) = planned(seed);
        let limits = limits2();
        let mut t = Trajectory::rest_to_rest(motion.space(), &path, &limits).unwrap();
        let before = t.duration();
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let settings = ShortcutSettings {
            attempts: 200,
            fine_resolution: Some(0.0005),
            ..Default::default()
        };
        let stats =
            shortcut::parabolic(&mut motion, &mut Walls::default(), &mut t, &limits, &settings, &mut rng).unwrap();
        assert!(stats.accepted > 0, "seed {seed}: nothing accepted");
        assert!(t.duration() < before, "seed {seed}: {} !< {before}", t.duration());
        assert!(
            t.check(motion.space(), &mut Walls::default(), 0.0005).is_ok(),
            "seed {seed}: in collision"
        );
        let (v, a) = t.peak_velocity_acceleration(1e-4).expect("a positive step");
        assert!(v[0] <= 1.0 + 1e-6 && v[1] <= 0.5 + 1e-6, "seed {seed}: {v:?}");
        assert!(a[0] <= 2.0 + 1e-3 && a[1] <= 1.0 + 1e-3, "seed {seed}: {a:?}");
        let mut q = [0.0; 2];
        t.sample(t.duration(), &mut q, None);
        assert!(
            motion.space().distance(&q, &[0.9, 0.9]) < 1e-9,
            "seed {seed}: ends at {q:?}"
        );
        let dense = t.to_path(motion.space(), 0.001).unwrap();
        assert!(path_valid(&mut motion, &dense));
    }
}

#[test]
fn parabolic_shortcutting_is_deterministic() {
    let run = || {
        let (mut motion, path) = planned(3);
        let mut t = Trajectory::rest_to_rest(motion.space(), &path, &limits2()).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(9);
        shortcut::parabolic(
            &mut motion,
            &mut Walls::default(),
            &mut t,
            &limits2(),
            &ShortcutSettings::default(),
            &mut rng,
        )
        .unwrap();
        t.to_path(motion.space(), 0.01).unwrap()
    };
    assert_eq!(run(), run());
}

#[test]
fn random_shortcutting_never_lengthens_nor_invalidates() {
    for seed in 0..10 {
        let (mut motion, path) = planned(seed);
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let settings = ShortcutSettings {
            fine_resolution: Some(0.0005),
            ..Default::default()
        };
        let (short, _) = shortcut::random(&mut motion, &mut Walls::default(), &path, &settings, &mut rng);
        assert!(short.length(motion.space()) <= path.length(motion.space()) + 1e-12);
        assert_eq!(short.states.first(), path.states.first());
        assert_eq!(short.states.last(), path.states.last());
        assert!(path_valid(&mut motion, &short), "seed {seed}");
    }
}

/// Valid where `free` says so; counts its checks.
struct Region(fn(&[f64]) -> bool, u64);

impl StateValidator for Region {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.1 += 1;
        (self.0)(q)
    }
    fn checks(&self) -> u64 {
        self.1
    }
}

/// `path`, one edge that checks 5 cm apart pass in the world `free`, repaired at 0.5 mm: the
/// edge is repaired and every edge of the result passes at 0.5 mm.
fn repaired_finely(free: fn(&[f64]) -> bool, path: &Path) -> Path {
    let space = square();
    let mut coarse = MotionValidator::new(space.clone(), 0.05);
    assert!(
        coarse.check_motion(&mut Region(free, 0), &path.states[0], &path.states[1]),
        "the fixture needs a coarse miss"
    );
    let mut rng = Pcg64Mcg::seed_from_u64(0);
    let (fixed, repaired) = shortcut::repair(
        &space,
        &mut Region(free, 0),
        path,
        0.0005,
        std::time::Duration::from_secs(5),
        &mut rng,
    )
    .unwrap();
    assert_eq!(repaired, 1);
    let mut fine = MotionValidator::new(space, 0.0005);
    assert!(
        fixed
            .states
            .windows(2)
            .all(|w| fine.check_motion(&mut Region(free, 0), &w[0], &w[1]))
    );
    fixed
}

#[test]
fn repair_replaces_edges_that_fail_finely() {
    // A wall thinner than the coarse resolution, open above y = 0.9: the straight edge passes
    // between samples.
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.9, 0.1]],
    };
    let fixed = repaired_finely(|q| !((0.52..=0.522).contains(&q[0]) && q[1] < 0.9), &path);
    assert!(fixed.states.iter().any(|q| q[1] >= 0.9));
}

/// An edge into a pocket (a corridor 2 cm wide and 40 cm deep in a block) that grazes a speck
/// on the way: the repair moves one waypoint sideways instead of re-planning, so the path keeps
/// its way into the pocket (a re-planned edge would have to find the corridor's mouth again).
#[test]
fn repair_bypasses_a_graze_with_one_sideways_waypoint() {
    let pocket = |q: &[f64]| {
        let (x, y) = (q[0], q[1]);
        let block = (0.55..=1.0).contains(&x) && (0.4..=0.6).contains(&y);
        let corridor = x < 0.95 && (y - 0.5).abs() < 0.01;
        let speck = (0.311..=0.313).contains(&x) && (y - 0.5).abs() <= 0.0005;
        (!block || corridor) && !speck
    };
    let path = Path {
        states: vec![vec![0.1, 0.5], vec![0.9, 0.5]],
    };
    let fixed = repaired_finely(pocket, &path);
    assert_eq!(fixed.states.len(), 3, "one waypoint added: {:?}", fixed.states);
    assert_eq!((&fixed.states[0], &fixed.states[2]), (&path.states[0], &path.states[1]));
    assert!(square().distance(&fixed.states[1], &[0.312, 0.5]) <= 0.2 + 1e-3);
}

/// A band 0.2 mm thick across the square at y = 0.5, left of `x_max`: sampled checks at
/// millimetre spacing mostly miss it, a check at 0.1 mm spacing cannot (consecutive samples
/// are closer than it is thick).
struct Band {
    x_max: f64,
    thickness: f64,
    checks: u64,
}

impl Band {
    /// Across the left quarter: paths can go around it on the right.
    fn left() -> Self {
        Self {
            x_max: 0.25,
            thickness: 2e-4,
            checks: 0,
        }
    }

    /// Across the whole square: every path from bottom to top crosses it.
    fn wall() -> Self {
        Self {
            x_max: f64::INFINITY,
            thickness: 2e-4,
            checks: 0,
        }
    }
}

impl StateValidator for Band {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        !((0.5..=0.5 + self.thickness).contains(&q[1]) && q[0] < self.x_max)
    }
    fn checks(&self) -> u64 {
        self.checks
    }
}

#[test]
fn smoothing_returns_only_motions_that_pass_the_verification_check() {
    use hearth_planning::shortcut::{Smoothing, smooth};
    // The zig-zag passes the band on its right; shortcuts cut across the left.
    let zigzag = Path {
        states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]],
    };
    let space = square();
    let limits = limits2();
    let settings = ShortcutSettings {
        attempts: 100,
        fine_resolution: Some(0.005),
        ..Default::default()
    };
    let verify = 1e-4;
    let (mut unverified_fails, mut fell_back) = (0, 0);
    for seed in 0..8 {
        let run = |settings: &ShortcutSettings| {
            let mut motion = MotionValidator::new(space.clone(), 0.01);
            let mut rng = Pcg64Mcg::seed_from_u64(seed);
            smooth(
                Smoothing::Parabolic,
                &mut motion,
                &mut Band::left(),
                &zigzag,
                &limits,
                settings,
                std::time::Duration::from_secs(1),
                &mut rng,
            )
            .expect("the zig-zag itself is clear")
        };
        let plain = run(&settings);
        assert!(!plain.fell_back, "no verification asked for");
        if plain.trajectory.check(&space, &mut Band::left(), verify).is_err() {
            unverified_fails += 1;
        }
        let verified = run(&ShortcutSettings {
            verify_resolution: Some(verify),
            ..settings.clone()
        });
        assert!(
            verified.trajectory.check(&space, &mut Band::left(), verify).is_ok(),
            "seed {seed}: the returned motion fails the verification check"
        );
        if verified.fell_back {
            fell_back += 1;
        }
    }
    // The band does slip between the shortcutter's samples, and verification catches it.
    assert!(
        unverified_fails > 0,
        "the band never slipped through: the test shows nothing"
    );
    assert_eq!(fell_back, unverified_fails);
}

/// With a verification check asked for, the first parabolic run checks its ramps at four times
/// the fine spacing (here capped at the coarse one); a band that slips between those samples is
/// caught by the verification, and the run is redone at the fine spacing, which cannot miss it.
#[test]
fn a_first_run_that_misses_a_band_is_redone_at_the_fine_spacing() {
    use hearth_planning::shortcut::{Smoothing, smooth};
    let zigzag = Path {
        states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]],
    };
    let (fine, attempts) = (0.005, 100);
    let settings = ShortcutSettings {
        attempts,
        fine_resolution: Some(fine),
        verify_resolution: Some(fine),
        ..Default::default()
    };
    // Thicker than the fine spacing, thinner than the first run's.
    let band = || Band {
        thickness: 1.5 * fine,
        ..Band::left()
    };
    let mut redone = 0;
    for seed in 0..16 {
        let mut motion = MotionValidator::new(square(), 0.02);
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let out = smooth(
            Smoothing::Parabolic,
            &mut motion,
            &mut band(),
            &zigzag,
            &limits2(),
            &settings,
            std::time::Duration::from_secs(1),
            &mut rng,
        )
        .expect("the zig-zag itself is clear");
        assert!(
            out.trajectory.check(&square(), &mut band(), fine).is_ok(),
            "seed {seed}"
        );
        assert!(
            !out.fell_back,
            "seed {seed}: a run at the fine spacing cannot miss the band"
        );
        if out.parabolic.attempts > attempts as u64 {
            redone += 1;
        }
    }
    assert!(
        redone > 0,
        "no first run slipped through the band: the test shows nothing"
    );
}

#[test]
fn smoothing_reports_a_motion_that_no_fallback_can_verify() {
    use hearth_planning::PlanError;
    use hearth_planning::shortcut::{Smoothing, smooth};
    // Checks at 5 mm miss the band, so the zig-zag passes the coarse and fine checks; the
    // verification at 0.1 mm finds it, and no repair can get around a wall.
    let zigzag = Path {
        states: vec![vec![0.0, 0.0], vec![0.5, 0.503], vec![0.0, 1.0]],
    };
    let settings = ShortcutSettings {
        fine_resolution: Some(0.005),
        verify_resolution: Some(1e-4),
        ..Default::default()
    };
    for smoothing in [Smoothing::None, Smoothing::Parabolic] {
        let mut motion = MotionValidator::new(square(), 0.01);
        let mut rng = Pcg64Mcg::seed_from_u64(0);
        let out = smooth(
            smoothing,
            &mut motion,
            &mut Band::wall(),
            &zigzag,
            &limits2(),
            &settings,
            std::time::Duration::from_millis(200),
            &mut rng,
        );
        match out {
            Err(PlanError::InvalidMotion { time }) => assert!(time > 0.0, "{smoothing:?}: time {time}"),
            other => panic!(
                "{smoothing:?}: expected InvalidMotion, got {:?}",
                other.map(|o| o.fell_back)
            ),
        }
    }
}

#[test]
fn jerk_limited_stops_stay_on_edges_and_respect_limits() {
    let space = square();
    let limits = Limits::new(vec![1.0, 0.5], vec![2.0, 1.0], vec![20.0, 10.0]).unwrap();
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.8, 0.3], vec![0.2, 0.9]],
    };
    let t = Trajectory::jerk_limited_stops(&space, &path, &limits).unwrap();
    let mut q = [0.0; 2];
    let steps = 2000;
    for k in 0..=steps {
        t.sample(t.duration() * k as f64 / steps as f64, &mut q, None);
        // Distance to the nearer of the two edges.
        let d = path
            .states
            .windows(2)
            .map(|w| {
                let (a, b) = (&w[0], &w[1]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let s = (((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
                ((q[0] - a[0] - s * dx).powi(2) + (q[1] - a[1] - s * dy).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(d < 1e-6, "left the edges by {d} at step {k}");
    }
    let (v, a) = t.peak_velocity_acceleration(1e-4).expect("a positive step");
    assert!(v[0] <= 1.0 + 1e-6 && v[1] <= 0.5 + 1e-6, "{v:?}");
    assert!(a[0] <= 2.0 + 1e-2 && a[1] <= 1.0 + 1e-2, "{a:?}");
}

#[test]
fn jerk_limited_passes_through_waypoints() {
    let space = square();
    let limits = Limits::new(vec![1.0, 1.0], vec![2.0, 2.0], vec![20.0, 20.0]).unwrap();
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.5, 0.6], vec![0.9, 0.2]],
    };
    let t = Trajectory::jerk_limited(&space, &path, &limits).unwrap();
    let dense = t.to_path(&space, 0.0005).unwrap();
    let nearest = dense
        .states
        .iter()
        .map(|q| space.distance(q, &path.states[1]))
        .fold(f64::INFINITY, f64::min);
    assert!(nearest < 1e-3, "misses the middle waypoint by {nearest}");
    assert!(
        t.duration()
            < Trajectory::jerk_limited_stops(&space, &path, &limits)
                .unwrap()
                .duration()
    );
}

#[test]
fn continuous_joints_take_the_short_way() {
    let space = JointSpace::new(&[0.0], &[0.0], &[true]).unwrap();
    let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY]).unwrap();
    let path = Path {
        states: vec![vec![3.0], vec![-3.0]],
    };
    let t = Trajectory::rest_to_rest(&space, &path, &limits).unwrap();
    // 2π − 6 ≈ 0.283 rad, not 6 rad.
    assert!(t.duration() < 1.2, "{}", t.duration());
    let dense = t.to_path(&space, 0.01).unwrap();
    assert!(dense.states.iter().all(|q| q[0].abs() <= std::f64::consts::PI + 1e-12));
}

#[test]
fn bad_input_gives_typed_errors() {
    let space = square();
    let limits = limits2();
    let nan = Path {
        states: vec![vec![0.1, 0.1], vec![f64::NAN, 0.2]],
    };
    assert_eq!(
        Trajectory::rest_to_rest(&space, &nan, &limits).unwrap_err(),
        TrajectoryError::NonFinite { index: 1 }
    );
    assert_eq!(
        Trajectory::rest_to_rest(&space, &Path::default(), &limits).unwrap_err(),
        TrajectoryError::EmptyPath
    );
    let short = Path {
        states: vec![vec![0.1]],
    };
    assert!(matches!(
        Trajectory::rest_to_rest(&space, &short, &limits),
        Err(TrajectoryError::Dimension {
            what: "path state",
            expected: 2,
            got: 1
        })
    ));
    let three = Limits::new(vec![1.0; 3], vec![1.0; 3], vec![1.0; 3]).unwrap();
    assert!(matches!(
        Trajectory::rest_to_rest(
            &space,
            &Path {
                states: vec![vec![0.1, 0.1]]
            },
            &three
        ),
        Err(TrajectoryError::Dimension { what: "limits", .. })
    ));
    assert!(matches!(
        Limits::new(vec![1.0, f64::NAN], vec![1.0; 2], vec![1.0; 2]),
        Err(TrajectoryError::BadLimit {
            what: "velocity",
            index: 1,
            ..
        })
    ));
    assert!(matches!(
        Limits::new(vec![1.0; 2], vec![f64::INFINITY; 2], vec![1.0; 2]),
        Err(TrajectoryError::BadLimit {
            what: "acceleration",
            index: 0,
            ..
        })
    ));
    assert!(matches!(
        Trajectory::ramp(&[0.0, 0.0], &[0.0, 0.0], &[1.0, f64::NAN], &[0.0, 0.0], &limits),
        Err(TrajectoryError::NonFinite { .. })
    ));
}

/// A resolution of 0 would sample an edge without end: `repair`, `smooth` and a trajectory's
/// `check` refuse any resolution that is not positive and finite, naming it, before they check
/// anything.
#[test]
fn resolutions_that_are_not_positive_are_bad_input() {
    use hearth_planning::PlanError;
    let space = square();
    // A wall the straight edge crosses, so that a repair has work to do.
    let wall: fn(&[f64]) -> bool = |q| !(0.5..=0.52).contains(&q[0]) || q[1] > 0.8;
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.9, 0.1]],
    };
    let budget = std::time::Duration::from_millis(100);
    for r in [0.0, -0.01, f64::NAN, f64::INFINITY] {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
        let mut v = Region(wall, 0);
        match shortcut::repair(&space, &mut v, &path, r, budget, &mut rng) {
            Err(PlanError::BadInput(m)) => assert!(m.contains("fine_resolution"), "{m}"),
            other => panic!("repair at {r}: {other:?}"),
        }
        assert_eq!(v.1, 0, "repair at {r} checked states");
        for (fine, verify, name) in [
            (Some(r), None, "fine_resolution"),
            (Some(0.001), Some(r), "verify_resolution"),
        ] {
            let settings = ShortcutSettings {
                fine_resolution: fine,
                verify_resolution: verify,
                ..ShortcutSettings::default()
            };
            let mut motion = MotionValidator::new(space.clone(), 0.01);
            let out = shortcut::smooth(
                shortcut::Smoothing::Parabolic,
                &mut motion,
                &mut v,
                &path,
                &limits2(),
                &settings,
                budget,
                &mut rng,
            );
            match out {
                Err(PlanError::BadInput(m)) => assert!(m.contains(name), "{m}"),
                other => panic!("smooth with {name} {r}: {other:?}"),
            }
            assert_eq!(v.1, 0, "smooth with {name} {r} checked states");
        }
        let trajectory = Trajectory::rest_to_rest(&space, &path, &limits2()).unwrap();
        match trajectory.check(&space, &mut v, r) {
            Err(TrajectoryError::BadResolution { value }) => assert!(value.to_bits() == r.to_bits()),
            other => panic!("check at {r}: {other:?}"),
        }
        assert_eq!(v.1, 0, "a trajectory's check at {r} checked states");
        // The motion validator refuses it too, and its infallible constructor reads it as 0.01
        // (an infinite spacing would check nothing); the trajectory's sampling refuses it.
        match MotionValidator::try_new(space.clone(), r) {
            Err(PlanError::BadInput(m)) => assert!(m.contains("resolution"), "{m}"),
            other => panic!("try_new at {r}: {:?}", other.map(|m| m.resolution())),
        }
        assert_eq!(MotionValidator::new(space.clone(), r).resolution(), 0.01);
        for sampled in [
            trajectory.to_path(&space, r).map(|p| p.states.len() as f64),
            trajectory.length(&space, r),
        ] {
            match sampled {
                Err(TrajectoryError::BadResolution { value }) => assert!(value.to_bits() == r.to_bits()),
                other => panic!("sampling at {r}: {other:?}"),
            }
        }
    }
}

/// A ramp joins two states, `(q0, v0)` and `(q1, v1)`: a NaN or infinite value is reported
/// against the state it belongs to, 0 or 1, the first one when both are bad.
#[test]
fn ramp_names_the_non_finite_state() {
    let limits = limits2();
    let ok = [0.5, 0.5];
    let zero = [0.0, 0.0];
    for bad in [[f64::NAN, 0.5], [0.5, f64::INFINITY], [f64::NEG_INFINITY, f64::NAN]] {
        let cases = [
            (Trajectory::ramp(&bad, &zero, &ok, &zero, &limits), 0),
            (Trajectory::ramp(&ok, &bad, &ok, &zero, &limits), 0),
            (Trajectory::ramp(&ok, &zero, &bad, &zero, &limits), 1),
            (Trajectory::ramp(&ok, &zero, &ok, &bad, &limits), 1),
            (Trajectory::ramp(&ok, &bad, &bad, &zero, &limits), 0),
        ];
        for (case, (r, index)) in cases.into_iter().enumerate() {
            assert_eq!(
                r.unwrap_err(),
                TrajectoryError::NonFinite { index },
                "case {case}, {bad:?}"
            );
        }
    }
}

/// Position bounds are numbers (`-∞` below and `+∞` above allowed, for continuous joints) with
/// lower ≤ upper; anything else is refused, naming the coordinate and both bounds.
#[test]
fn position_bounds_are_checked() {
    let limits = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![f64::INFINITY; 2]).unwrap();
    let bounds = |lower: [f64; 2], upper: [f64; 2]| limits.clone().with_position_bounds(lower.to_vec(), upper.to_vec());
    let (inf, nan) = (f64::INFINITY, f64::NAN);
    for (lower, upper) in [
        ([-1.0, -1.0], [1.0, 1.0]),
        ([-inf, 0.5], [inf, 0.5]),
        ([-inf, -inf], [inf, -3.0]),
        ([2.0, 4.0], [inf, inf]),
    ] {
        let limits = bounds(lower, upper).unwrap();
        assert_eq!(limits.position_bounds(), Some((&lower[..], &upper[..])));
    }
    for (lower, upper, index) in [
        ([-1.0, nan], [1.0, 1.0], 1),
        ([-1.0, -1.0], [nan, 1.0], 0),
        ([1.0, -1.0], [-1.0, 1.0], 0),
        ([-1.0, 0.5 + 1e-12], [1.0, 0.5], 1),
        ([inf, -1.0], [inf, 1.0], 0),
        ([-1.0, -inf], [1.0, -inf], 1),
    ] {
        let e = bounds(lower, upper).unwrap_err();
        assert!(
            matches!(e, TrajectoryError::BadPositionBounds { index: i, lower: l, upper: u }
                if i == index && l.total_cmp(&lower[i]).is_eq() && u.total_cmp(&upper[i]).is_eq()),
            "{lower:?} {upper:?}: {e:?}"
        );
        assert!(e.to_string().contains(&format!("coordinate {index}")), "{e}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn ramps_respect_limits(
        q0 in prop::collection::vec(-1.0f64..1.0, 3),
        q1 in prop::collection::vec(-1.0f64..1.0, 3),
        v0 in prop::collection::vec(-0.9f64..0.9, 3),
        v1 in prop::collection::vec(-0.9f64..0.9, 3),
    ) {
        let limits = Limits::new(vec![1.0; 3], vec![3.0, 2.0, 1.0], vec![f64::INFINITY; 3]).unwrap();
        let t = Trajectory::ramp(&q0, &v0, &q1, &v1, &limits).unwrap();
        let (v, a) = t.peak_velocity_acceleration(1e-4).expect("a positive step");
        for i in 0..3 {
            prop_assert!(v[i] <= 1.0 + 1e-6, "v {v:?}");
            prop_assert!(a[i] <= limits.acceleration()[i] * 1.001 + 1e-6, "a {a:?}");
        }
        let (mut q, mut v) = ([0.0; 3], [0.0; 3]);
        t.sample(t.duration(), &mut q, Some(&mut v));
        for i in 0..3 {
            prop_assert!((q[i] - q1[i]).abs() < 1e-6 && (v[i] - v1[i]).abs() < 1e-6);
        }
    }

    #[test]
    fn rest_to_rest_interpolation_endpoints(states in prop::collection::vec(prop::collection::vec(0.0f64..1.0, 2), 1..6)) {
        let path = Path { states: states.clone() };
        let t = Trajectory::rest_to_rest(&square(), &path, &limits2()).unwrap();
        let mut q = [0.0; 2];
        t.sample(0.0, &mut q, None);
        prop_assert_eq!(q.to_vec(), states[0].clone());
        t.sample(t.duration(), &mut q, None);
        prop_assert!(square().distance(&q, states.last().unwrap()) < 1e-9);
    }

    /// A trajectory's check samples states at most the spacing apart, and not many more than
    /// its length needs: the time step follows the speed.
    #[test]
    fn checks_sample_at_the_spacing_and_not_much_closer(
        states in prop::collection::vec(prop::collection::vec(0.0f64..1.0, 2), 2..6),
        v in prop::collection::vec(-0.4f64..0.4, 2),
        resolution in 0.001f64..0.05,
    ) {
        let mut t = Trajectory::rest_to_rest(&square(), &Path { states }, &limits2()).unwrap();
        // A ramp from the middle of the first edge into one with a moving start as well.
        let mut q = [0.0; 2];
        t.sample(0.5 * t.duration(), &mut q, None);
        let ramp = Trajectory::ramp(&[0.5, 0.5], &v, &q, &[0.0; 2], &limits2().without_jerk()).unwrap();
        for t in [&mut t, &mut ramp.clone()] {
            let mut seen = Record::default();
            t.check(&square(), &mut seen, resolution).unwrap();
            let path = t.to_path(&square(), resolution).unwrap();
            prop_assert_eq!(seen.0.len(), path.states.len());
            let gaps: Vec<f64> = path.states.windows(2).map(|w| square().distance(&w[0], &w[1])).collect();
            prop_assert!(gaps.iter().all(|&g| g <= resolution + 1e-12), "{gaps:?}");
            let length: f64 = gaps.iter().sum();
            // The first step is an eighth of the duration and steps at most double, so even a
            // motion shorter than the spacing takes four steps (five states).
            prop_assert!(
                path.states.len() as f64 <= length / (0.75 * resolution) + 5.0,
                "{} states for {length} at {resolution}", path.states.len()
            );
        }
    }

    #[test]
    fn shortcutting_never_lengthens_or_invalidates(seed in 0u64..1000) {
        let (mut motion, path) = planned(seed % 7);
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let settings = ShortcutSettings { attempts: 30, fine_resolution: Some(0.0005), ..Default::default() };
        let (short, _) = shortcut::random(&mut motion, &mut Walls::default(), &path, &settings, &mut rng);
        prop_assert!(short.length(motion.space()) <= path.length(motion.space()) + 1e-12);
        prop_assert!(path_valid(&mut motion, &short));
        let limits = limits2();
        let mut t = Trajectory::rest_to_rest(motion.space(), &short, &limits).unwrap();
        let before = t.duration();
        shortcut::parabolic(&mut motion, &mut Walls::default(), &mut t, &limits, &settings, &mut rng).unwrap();
        prop_assert!(t.duration() <= before + 1e-12);
        // Planner edges are checked every 0.005: a corner may be grazed by less than that.
        prop_assert!(t.check(motion.space(), &mut Walls::shrunk(0.003), 0.0005).is_ok());
    }
}

/// Invalid only within 1e-9 of one state: a graze so thin that only a sample landing on it
/// finds it.
struct Pin {
    at: Vec<f64>,
    checks: u64,
}

impl StateValidator for Pin {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        (q[0] - self.at[0]).hypot(q[1] - self.at[1]) > 1e-9
    }
    fn checks(&self) -> u64 {
        self.checks
    }
}

/// Valid everywhere; remembers what it was asked.
#[derive(Default)]
struct Record(Vec<Vec<f64>>);

impl StateValidator for Record {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.0.push(q.to_vec());
        true
    }
    fn checks(&self) -> u64 {
        self.0.len() as u64
    }
}

/// The straight 2-D edge of the graze tests, and the states its verification at spacing
/// `GRAZE_R` samples farther than 10⁻⁴ from every state its edge check at the same spacing
/// samples.
fn graze_edge() -> (Path, Vec<Vec<f64>>) {
    let (space, limits) = (square(), limits2());
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.9, 0.3]],
    };
    let mut verified = Record::default();
    Trajectory::rest_to_rest(&space, &path, &limits)
        .unwrap()
        .check(&space, &mut verified, GRAZE_R)
        .unwrap();
    let mut edge = Record::default();
    assert!(MotionValidator::new(space.clone(), GRAZE_R).check_motion(&mut edge, &path.states[0], &path.states[1]));
    let unsampled = verified
        .0
        .into_iter()
        .filter(|q| edge.0.iter().all(|p| space.distance(p, q) > 1e-4))
        .collect();
    (path, unsampled)
}

/// Spacing of the repair and the final check in the graze tests.
const GRAZE_R: f64 = 0.01;

/// `path` smoothed (without shortcuts, then with parabolic ones) against a single colliding
/// point `pin` that only the final check samples: each run must fall back, and what it returns
/// must pass the final check. Returns the re-planned paths.
fn smooth_around_pin(path: &Path, pin: &[f64]) -> Vec<Path> {
    use hearth_planning::shortcut::{Smoothing, smooth};
    let space = square();
    let settings = ShortcutSettings {
        fine_resolution: Some(GRAZE_R),
        verify_resolution: Some(GRAZE_R),
        ..Default::default()
    };
    let mut paths = Vec::new();
    for smoothing in [Smoothing::None, Smoothing::Parabolic] {
        let mut motion = MotionValidator::new(space.clone(), 0.02);
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let mut validator = Pin {
            at: pin.to_vec(),
            checks: 0,
        };
        let out = smooth(
            smoothing,
            &mut motion,
            &mut validator,
            path,
            &limits2(),
            &settings,
            std::time::Duration::from_secs(1),
            &mut rng,
        )
        .unwrap_or_else(|e| panic!("{smoothing:?}: {e}"));
        assert!(
            out.fell_back,
            "{smoothing:?}: the straight edge should have failed verification"
        );
        assert!(out.trajectory.check(&space, &mut validator, GRAZE_R).is_ok());
        paths.push(out.path);
    }
    paths
}

#[test]
fn smoothing_detours_around_a_graze_only_the_verification_samples() {
    let (path, unsampled) = graze_edge();
    // A state the verification samples in the middle of the edge, far from every state the
    // edge check samples.
    let pin = unsampled
        .iter()
        .find(|q| (0.3..0.7).contains(&q[0]))
        .expect("the two sample sets differ");
    for out in smooth_around_pin(&path, pin) {
        assert!(out.states.len() > 2, "the edge was not re-planned");
    }
}

/// A graze a hair's breadth from the final goal: the re-planned edge must leave the goal on the
/// side away from the colliding state (the avoided ball contains the goal itself).
#[test]
fn smoothing_detours_around_a_graze_next_to_the_goal() {
    let (path, unsampled) = graze_edge();
    let space = square();
    let goal = path.states[1].clone();
    // The verification sample nearest the goal (the goal itself excepted) that no edge check
    // sampled.
    let pin = unsampled
        .iter()
        .filter(|q| space.distance(q, &goal) > 1e-9)
        .min_by(|a, b| space.distance(a, &goal).total_cmp(&space.distance(b, &goal)))
        .expect("the two sample sets differ");
    assert!(
        space.distance(pin, &goal) < 0.25 * GRAZE_R,
        "the pinned state should sit next to the goal: {pin:?}"
    );
    for out in smooth_around_pin(&path, pin) {
        assert_eq!(out.states.last(), Some(&goal), "the goal moved");
    }
}

/// With a verification check asked for, a parabolic run is tried before any repair: when its
/// shortcuts cut away the one edge that grazes at the fine spacing, nothing is repaired, and
/// the motion still passes the verification.
#[test]
fn an_edge_the_shortcuts_cut_away_is_not_repaired() {
    use hearth_planning::shortcut::{Smoothing, smooth};
    // A wall from the left up to x = 0.6, and a speck on the first edge, next to the corner.
    fn free(q: &[f64]) -> bool {
        let wall = q[0] < 0.6 && (0.45..=0.55).contains(&q[1]);
        let speck = (q[0] - 0.64).hypot(q[1] - 0.46) < 0.003;
        !wall && !speck
    }
    // The speck sits on the first edge, at 0.9 of its length.
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.7, 0.5], vec![0.1, 0.9]],
    };
    let (fine, coarse) = (0.002, 0.02);
    let settings = ShortcutSettings {
        fine_resolution: Some(fine),
        verify_resolution: Some(fine),
        ..Default::default()
    };
    let (mut kept, mut cut_away) = (0, 0);
    for seed in 0..16 {
        let mut motion = MotionValidator::new(square(), coarse);
        let out = smooth(
            Smoothing::Parabolic,
            &mut motion,
            &mut Region(free, 0),
            &path,
            &limits2(),
            &settings,
            std::time::Duration::from_secs(1),
            &mut Pcg64Mcg::seed_from_u64(seed),
        )
        .expect("the corner path is clear but for the speck");
        assert!(
            out.trajectory.check(&square(), &mut Region(free, 0), fine).is_ok(),
            "seed {seed}"
        );
        // The same random shortcutting that `smooth` starts with (same seed, same stream).
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let no_fine = ShortcutSettings {
            fine_resolution: None,
            ..settings.clone()
        };
        let (shortcut, _) = shortcut::random(&mut motion, &mut Region(free, 0), &path, &no_fine, &mut rng);
        let (_, grazing) = shortcut::repair(
            &square(),
            &mut Region(free, 0),
            &shortcut,
            fine,
            std::time::Duration::from_secs(1),
            &mut rng,
        )
        .unwrap();
        if grazing > 0 {
            kept += 1;
            if out.repaired == 0 {
                cut_away += 1;
            }
        }
    }
    eprintln!(
        "the grazing edge survived random shortcutting in {kept} of 16 seeds, and the parabolic run cut it away in {cut_away}"
    );
    assert!(
        kept > 0,
        "random shortcutting never kept the grazing edge: the test shows nothing"
    );
    assert!(cut_away > 0, "no parabolic run cut the grazing edge away");
}
