//! [`MotionPlanner`]: planner, post-processing and check in one call, on the Panda over a table
//! with a post and on MotionBenchMaker problems of both robots; its bad input and settings.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_planning::obstacles::{Obstacle, ParryScene};
use hearth_planning::pipeline::{FETCH_WEIGHT_SCHEDULE, MotionPlanner, MotionSettings, PlannedMotion};
use hearth_planning::problem::ProblemSet;
use hearth_planning::space::{JointSpace, Space};
use hearth_planning::trajectory::Limits;
use hearth_planning::{Budget, Goal, LazyPrm, PlanError, RobotValidity, Rrt};
use parry3d::math::{Pose, Vector};
use proptest::prelude::*;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn matrix(robot: &str) -> SelfCollisionMatrix {
    static PANDA: OnceLock<SelfCollisionMatrix> = OnceLock::new();
    static FETCH: OnceLock<SelfCollisionMatrix> = OnceLock::new();
    let cell = if robot == "panda" { &PANDA } else { &FETCH };
    cell.get_or_init(|| {
        SelfCollisionMatrix::compute(
            &RobotModel::builtin(robot).unwrap(),
            &SelfCollisionSettings {
                samples: 500,
                ..Default::default()
            },
        )
    })
    .clone()
}

/// The Panda arm, fingers open, over a table with a post between the start and the goal.
fn table_validity() -> RobotValidity {
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let table = Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.2), Vector::new(0.3, 0.6, 0.02));
    let post = Obstacle::cuboid("post", Pose::translation(0.5, 0.0, 0.45), Vector::new(0.05, 0.05, 0.25));
    let mut v = RobotValidity::new(arm, matrix("panda"), Arc::new(ParryScene::new(vec![table, post])));
    let mut q = m.neutral_configuration();
    Chain::new(&m, &["panda_finger_joint1"])
        .unwrap()
        .scatter(&[0.04], &mut q);
    v.set_reference(&q).unwrap();
    v
}

const START: [f64; 7] = [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
const GOAL: [f64; 7] = [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];

/// Enough iterations for every plan here, and a time limit only as a safety net: the same
/// seed makes the same plan on any machine.
fn budget() -> Budget {
    Budget::iterations(200_000).with_time(30.0)
}

fn plain(v: &RobotValidity) -> JointSpace {
    JointSpace::from_chain(v.chain()).unwrap()
}

/// The motion starts at `start`, ends at one of `goals`, stays within `limits`' velocities, and
/// passes a check at 0.002 rad with `v`.
fn assert_motion(
    label: &str,
    m: &PlannedMotion,
    v: &mut RobotValidity,
    limits: &Limits,
    start: &[f64],
    goals: &[Vec<f64>],
) {
    let t = &m.trajectory;
    let dof = start.len();
    let space = plain(v);
    let (mut q, mut dq) = (vec![0.0; dof], vec![0.0; dof]);
    t.sample(0.0, &mut q, None);
    // (The distance wraps continuous joints: a roll joint may end a turn away.)
    assert!(space.distance(&q, start) < 1e-9, "{label}: starts at {q:?}");
    t.sample(t.duration(), &mut q, None);
    assert!(
        goals.iter().any(|g| space.distance(&q, g) < 1e-9),
        "{label}: ends at {q:?}"
    );
    for k in 0..=200 {
        t.sample(t.duration() * k as f64 / 200.0, &mut q, Some(&mut dq));
        for (j, (&v, &max)) in dq.iter().zip(limits.velocity()).enumerate() {
            assert!(
                v.abs() <= max * (1.0 + 1e-9),
                "{label}: joint {j} at {v} rad/s, limit {max}"
            );
        }
    }
    t.check(&space, v, 0.002)
        .unwrap_or_else(|e| panic!("{label}: fails the check at 0.002 rad: {e}"));
    assert_eq!(m.planned.states.first().map(Vec::as_slice), Some(start), "{label}");
    assert!(
        m.stats.states_checked > 0 && m.stats.iterations > 0,
        "{label}: {:?}",
        m.stats
    );
}

#[test]
fn table_motion_is_timed_checked_and_reproducible() {
    let mut planner = MotionPlanner::new(table_validity(), MotionSettings::default()).unwrap();
    let limits = planner.limits().clone();
    let plan = |planner: &mut MotionPlanner, seed: u64| {
        planner
            .plan(
                &START,
                Goal::Config(GOAL.to_vec()),
                &budget(),
                &mut Pcg64Mcg::seed_from_u64(seed),
            )
            .unwrap()
    };
    let first = plan(&mut planner, 3);
    assert_motion(
        "table",
        &first,
        &mut table_validity(),
        &limits,
        &START,
        &[GOAL.to_vec()],
    );
    // The straight line goes through the post: the path goes round it.
    assert!(first.planned.states.len() > 2, "{:?}", first.planned.states);
    let again = plan(&mut planner, 3);
    assert_eq!(first.planned.states, again.planned.states, "same seed, same plan");
    assert_eq!(first.path.states, again.path.states, "same seed, same smoothing");
    let other = plan(&mut planner, 4);
    assert_ne!(first.planned.states, other.planned.states, "another seed, another plan");
    println!(
        "table: {} iterations, {} states checked, {:.2} s of motion, smoothing {:?}",
        first.stats.iterations,
        first.stats.states_checked,
        first.trajectory.duration(),
        first.smoothing_time
    );
}

#[test]
fn table_motion_in_either_metric_with_every_planner() {
    let settings = MotionSettings {
        reach_weights: false,
        ..Default::default()
    };
    let mut unweighted = MotionPlanner::new(table_validity(), settings).unwrap();
    // Without the weights the default BiRRT keeps its own step.
    assert_eq!(unweighted.planner().range, None);
    let limits = unweighted.limits().clone();
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let to = |q: [f64; 7]| Goal::Config(q.to_vec());
    let check = |label: &str, m: &PlannedMotion, from: [f64; 7], goal: [f64; 7]| {
        assert_motion(label, m, &mut table_validity(), &limits, &from, &[goal.to_vec()]);
    };
    let m = unweighted.plan(&START, to(GOAL), &budget(), &mut rng).unwrap();
    check("table/unweighted", &m, START, GOAL);

    let defaults = || MotionPlanner::new(table_validity(), MotionSettings::default()).unwrap();
    let mut rrt = defaults().with_planner(Rrt::default());
    let m = rrt.plan(&START, to(GOAL), &budget(), &mut rng).unwrap();
    check("table/rrt", &m, START, GOAL);

    // LazyPRM keeps its roadmap between queries in the same scene.
    let mut prm = defaults().with_planner(LazyPrm::default());
    let there = prm.plan(&START, to(GOAL), &budget(), &mut rng).unwrap();
    let grown = prm.planner().roadmap_size();
    assert!(grown > 0);
    let back = prm.plan(&GOAL, to(START), &budget(), &mut rng).unwrap();
    assert!(prm.planner().roadmap_size() >= grown);
    check("table/lazyprm", &there, START, GOAL);
    check("table/lazyprm back", &back, GOAL, START);
}

#[test]
fn bad_input_is_a_typed_error_and_changes_nothing() {
    let mut planner = MotionPlanner::new(table_validity(), MotionSettings::default()).unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    let goal = || Goal::Config(GOAL.to_vec());
    // The arm swung through the post, at the start and at the goal.
    let mut through = START;
    through[0] = 0.0;
    let e = planner.plan(&through, goal(), &budget(), &mut rng).unwrap_err();
    assert!(
        matches!(&e, PlanError::InvalidStart { contact: Some(c) } if c.contains("post")),
        "{e}"
    );
    let e = planner
        .plan(&START, Goal::Config(through.to_vec()), &budget(), &mut rng)
        .unwrap_err();
    assert!(
        matches!(&e, PlanError::InvalidGoals { count: 1, first_contact: Some(c) } if c.contains("post")),
        "{e}"
    );
    let mut nan = START;
    nan[3] = f64::NAN;
    for (label, start) in [
        ("NaN", nan.to_vec()),
        ("six values", START[..6].to_vec()),
        ("out of limits", {
            let mut q = START.to_vec();
            q[3] = 1.0; // the elbow's upper limit is about -0.07
            q
        }),
    ] {
        let e = planner.plan(&start, goal(), &budget(), &mut rng).unwrap_err();
        assert!(matches!(e, PlanError::BadInput(_)), "{label}: {e}");
    }
    let e = planner.plan(&START, goal(), &Budget::default(), &mut rng).unwrap_err();
    assert!(matches!(e, PlanError::BadInput(_)), "no limit: {e}");
    let e = planner
        .plan(&START, goal(), &Budget::iterations(1), &mut rng)
        .unwrap_err();
    assert!(matches!(e, PlanError::Timeout { .. }), "one iteration: {e}");

    // Nothing changed: the planner makes the plan a fresh one makes with the same seed.
    let after = planner
        .plan(&START, goal(), &budget(), &mut Pcg64Mcg::seed_from_u64(11))
        .unwrap();
    let fresh = MotionPlanner::new(table_validity(), MotionSettings::default())
        .unwrap()
        .plan(&START, goal(), &budget(), &mut Pcg64Mcg::seed_from_u64(11))
        .unwrap();
    assert_eq!(after.planned.states, fresh.planned.states);
    assert_eq!(after.path.states, fresh.path.states);
}

#[test]
fn bad_settings_are_typed_errors() {
    let cases: [(&str, MotionSettings); 7] = [
        (
            "resolution 0",
            MotionSettings {
                resolution: 0.0,
                ..Default::default()
            },
        ),
        (
            "resolution NaN",
            MotionSettings {
                resolution: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "resolution too fine",
            MotionSettings {
                resolution: 1e-12,
                fine_resolution: 1e-13,
                ..Default::default()
            },
        ),
        (
            "fine resolution coarser",
            MotionSettings {
                fine_resolution: 0.1,
                ..Default::default()
            },
        ),
        (
            "fine resolution negative",
            MotionSettings {
                fine_resolution: -0.002,
                ..Default::default()
            },
        ),
        (
            "range negative",
            MotionSettings {
                range: Some(-0.5),
                ..Default::default()
            },
        ),
        (
            "no smoothing time",
            MotionSettings {
                smoothing_time: Duration::ZERO,
                ..Default::default()
            },
        ),
    ];
    for (label, settings) in cases {
        match MotionPlanner::new(table_validity(), settings) {
            Err(PlanError::BadInput(msg)) => println!("{label}: {msg}"),
            Err(e) => panic!("{label}: {e}"),
            Ok(_) => panic!("{label}: accepted"),
        }
    }
    let planner = MotionPlanner::new(table_validity(), MotionSettings::default()).unwrap();
    let two = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![1.0; 2]).unwrap();
    assert!(matches!(planner.with_limits(two), Err(PlanError::BadInput(_))));
}

/// The tests' MotionBenchMaker excerpts with the default settings: the Panda's and the Fetch's
/// table_pick problems, the Fetch with the benchmark's weight schedule. Fingers as the problem
/// sets hold them, clamped to the models.
#[test]
fn motionbenchmaker_problems_of_both_robots() {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for (file, robot, finger) in [
        ("panda_table_pick.json", "panda", ("panda_finger_joint1", 0.04)),
        ("fetch_table_pick.json", "fetch", ("r_gripper_finger_joint", 0.05)),
    ] {
        let set = ProblemSet::load(data.join(file)).unwrap();
        let m = RobotModel::builtin(robot).unwrap();
        let chain = Chain::new(&m, &set.joint_names).unwrap();
        let mut reference = m.neutral_configuration();
        Chain::new(&m, &[finger.0])
            .unwrap()
            .scatter(&[finger.1], &mut reference);
        let p = set.valid_problems().next().unwrap();
        let validity = || {
            let mut v = RobotValidity::new(chain.clone(), matrix(robot), Arc::new(p.scene()));
            v.set_reference(&reference).unwrap();
            v
        };
        let mut planner = MotionPlanner::new(validity(), MotionSettings::default()).unwrap();
        if robot == "fetch" {
            // As the benchmark plans the Fetch.
            planner = planner.with_weight_schedule(&FETCH_WEIGHT_SCHEDULE).unwrap();
        }
        let limits = planner.limits().clone();
        let mut rng = Pcg64Mcg::seed_from_u64(u64::from(p.id));
        let motion = planner
            .plan(&p.start, Goal::AnyOf(p.goals.clone()), &budget(), &mut rng)
            .unwrap_or_else(|e| panic!("{robot} {}: {e}", p.id));
        assert_motion(
            &format!("{robot} {}", p.id),
            &motion,
            &mut validity(),
            &limits,
            &p.start,
            &p.goals,
        );
    }
}

/// Any number, including the awkward ones.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(-1.0),
        Just(0.0),
        Just(1e-300),
        Just(1e300),
        1e-9..10.0f64,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Settings from anywhere (a TOML file, a user's struct literal) give a planner or a typed
    /// error, never a panic; a planner built from them has the settings' resolution.
    #[test]
    fn any_settings_give_a_planner_or_bad_input(
        resolution in number(),
        fine in number(),
        range in prop::option::of(number()),
        reach_weights in any::<bool>(),
        millis in 0u64..2_000,
    ) {
        let settings = MotionSettings {
            reach_weights,
            range,
            resolution,
            fine_resolution: fine,
            smoothing_time: Duration::from_millis(millis),
            ..Default::default()
        };
        match MotionPlanner::new(table_validity(), settings) {
            Ok(p) => {
                prop_assert!(resolution.is_finite() && resolution > 0.0 && fine > 0.0 && fine <= resolution);
                prop_assert!(millis > 0 && range.is_none_or(|r| r.is_finite() && r > 0.0));
                prop_assert!(p.planner().range.is_none_or(|r| r > 0.0));
            }
            Err(PlanError::BadInput(msg)) => prop_assert!(!msg.is_empty()),
            Err(e) => prop_assert!(false, "not BadInput: {e}"),
        }
    }
}

/// A BiRRT that changes its metric part-way: the plan is the same for a seed, checked, and
/// another than in one metric; the plan leaves the starting metric in place.
#[test]
fn table_motion_with_a_weight_schedule() {
    let steps = [(0, 2.0), (3, 1.0), (6, 0.5)];
    let scheduled = || {
        MotionPlanner::new(table_validity(), MotionSettings::default())
            .unwrap()
            .with_weight_schedule(&steps)
            .unwrap()
    };
    let mut planner = scheduled();
    let first_metric = planner.space().clone();
    let limits = planner.limits().clone();
    let plan = |p: &mut MotionPlanner| {
        p.plan(
            &START,
            Goal::Config(GOAL.to_vec()),
            &budget(),
            &mut Pcg64Mcg::seed_from_u64(2),
        )
        .unwrap()
    };
    let m = plan(&mut planner);
    assert!(
        m.stats.iterations > 6,
        "the schedule's last metric was reached: {:?}",
        m.stats
    );
    assert_motion(
        "table/schedule",
        &m,
        &mut table_validity(),
        &limits,
        &START,
        &[GOAL.to_vec()],
    );
    assert_eq!(planner.space(), &first_metric, "the starting metric is back in place");
    assert_eq!(
        plan(&mut planner).planned.states,
        m.planned.states,
        "same seed, same plan"
    );
    assert_eq!(
        plan(&mut scheduled()).planned.states,
        m.planned.states,
        "a fresh planner too"
    );
    let mut one_metric = MotionPlanner::new(table_validity(), MotionSettings::default()).unwrap();
    assert_ne!(plan(&mut one_metric).planned.states, m.planned.states);
    assert_ne!(one_metric.space(), &first_metric);
    // Another planner plans in the settings' metric again.
    let rrt = scheduled().with_planner(Rrt::default());
    assert_eq!(rrt.space(), one_metric.space());
}

#[test]
fn bad_weight_schedules_are_typed_errors() {
    let defaults = || MotionPlanner::new(table_validity(), MotionSettings::default()).unwrap();
    let cases: [(&str, &[(u64, f64)]); 6] = [
        ("no steps", &[]),
        ("first after 0", &[(10, 1.0)]),
        ("iterations not increasing", &[(0, 2.0), (100, 1.0), (100, 0.5)]),
        ("power 5", &[(0, 5.0)]),
        ("negative power", &[(0, 1.0), (10, -1.0)]),
        ("NaN power", &[(0, f64::NAN)]),
    ];
    for (label, steps) in cases {
        match defaults().with_weight_schedule(steps) {
            Err(PlanError::BadInput(msg)) => println!("{label}: {msg}"),
            Err(e) => panic!("{label}: {e}"),
            Ok(_) => panic!("{label}: accepted"),
        }
    }
    let unweighted = MotionSettings {
        reach_weights: false,
        ..Default::default()
    };
    let e = MotionPlanner::new(table_validity(), unweighted)
        .unwrap()
        .with_weight_schedule(&FETCH_WEIGHT_SCHEDULE)
        .unwrap_err();
    assert!(e.to_string().contains("reach weights"), "{e}");
}
