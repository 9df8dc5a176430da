//! IK round trips: random reachable poses (FK of random configurations), solved from
//! unrelated random seeds, re-checked with forward kinematics.

use hearth_kinematics::{Chain, IkError, IkMethod, IkSettings, IkSolver, IkTarget, RobotModel};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use rand::SeedableRng;

struct Outcome {
    solved: usize,
    total: usize,
}

fn round_trip(robot: &str, chain: &str, samples: usize, settings: IkSettings, position_only: bool) -> Outcome {
    let m = RobotModel::builtin(robot).unwrap();
    let chain = Chain::named(&m, chain).unwrap();
    let tip = m.links()[chain.tip().unwrap()].name.clone();
    let (ptol, rtol) = (settings.position_tolerance, settings.orientation_tolerance);
    let mut ik = IkSolver::new(chain.clone(), &tip, settings).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2024);
    let mut goal = vec![0.0; chain.dof()];
    let mut seed = vec![0.0; chain.dof()];
    let mut solved = 0;
    for _ in 0..samples {
        chain.random_configuration(&mut rng, &mut goal);
        chain.random_configuration(&mut rng, &mut seed);
        let pose = ik.tool_pose(&goal).unwrap();
        let target = if position_only {
            IkTarget::Position(Point3::from(pose.translation.vector))
        } else {
            IkTarget::Pose(pose)
        };
        if let Ok(sol) = ik.solve(&target, &seed, &mut rng) {
            // Independent check: FK of the full model at the solution.
            let mut q_full = m.neutral_configuration();
            chain.scatter(&sol.q, &mut q_full);
            let reached = m.link_pose(&q_full, chain.tip().unwrap()).unwrap();
            let dp = (reached.translation.vector - pose.translation.vector).norm();
            let dr = reached.rotation.angle_to(&pose.rotation);
            assert!(dp <= ptol + 1e-12, "{robot}: reported success {dp} m off");
            if !position_only {
                assert!(dr <= rtol + 1e-12, "{robot}: reported success {dr} rad off");
            }
            assert!(
                m.within_limits(&q_full, 1e-12),
                "{robot}: solution outside limits {:?}",
                sol.q
            );
            solved += 1;
        }
    }
    Outcome { solved, total: samples }
}

fn assert_rate(label: &str, o: Outcome, min: f64) {
    let rate = o.solved as f64 / o.total as f64;
    assert!(
        rate >= min,
        "{label}: {}/{} = {:.2} % < {:.1} %",
        o.solved,
        o.total,
        rate * 100.0,
        min * 100.0
    );
}

#[test]
fn panda_full_pose_1000() {
    assert_rate(
        "panda",
        round_trip("panda", "arm", 1000, IkSettings::default(), false),
        0.995,
    );
}

#[test]
fn fetch_arm_with_torso_full_pose_1000() {
    assert_rate(
        "fetch 8-DOF",
        round_trip("fetch", "arm_with_torso", 1000, IkSettings::default(), false),
        0.995,
    );
}

#[test]
fn fetch_arm_full_pose_1000() {
    assert_rate(
        "fetch 7-DOF",
        round_trip("fetch", "arm", 1000, IkSettings::default(), false),
        0.995,
    );
}

#[test]
fn locobot_arm_full_pose_1000() {
    assert_rate(
        "locobot 5-DOF",
        round_trip("locobot", "arm", 1000, IkSettings::default(), false),
        0.995,
    );
}

#[test]
fn panda_position_only() {
    assert_rate(
        "panda position",
        round_trip("panda", "arm", 300, IkSettings::default(), true),
        0.995,
    );
}

#[test]
fn panda_qp_step() {
    let s = IkSettings {
        method: IkMethod::Qp,
        time_limit: None,
        max_attempts: 50,
        ..IkSettings::default()
    };
    assert_rate("panda qp", round_trip("panda", "arm", 60, s, false), 0.98);
}

#[test]
fn same_seed_same_answer() {
    let m = RobotModel::builtin("panda").unwrap();
    let chain = Chain::named(&m, "arm").unwrap();
    let mut ik = IkSolver::new(
        chain,
        "panda_hand_tcp",
        IkSettings {
            time_limit: None,
            ..Default::default()
        },
    )
    .unwrap();
    let target = IkTarget::Pose(ik.tool_pose(&[0.5, 0.2, -0.4, -1.9, 0.3, 2.2, 0.1]).unwrap());
    let seed = [-1.0, 1.0, 1.0, -0.5, -2.0, 0.5, 2.0];
    let a = ik
        .solve(&target, &seed, &mut rand_pcg::Pcg64Mcg::seed_from_u64(3))
        .unwrap();
    let b = ik
        .solve(&target, &seed, &mut rand_pcg::Pcg64Mcg::seed_from_u64(3))
        .unwrap();
    assert_eq!(a, b);
}

#[test]
fn seed_closest_selection_prefers_the_seed_branch() {
    let m = RobotModel::builtin("panda").unwrap();
    let chain = Chain::named(&m, "arm").unwrap();
    let goal = [0.4, -0.3, 0.2, -2.1, 0.2, 1.9, 0.6];
    let settings = IkSettings {
        candidates: 8,
        time_limit: None,
        ..Default::default()
    };
    let mut ik = IkSolver::new(chain, "panda_hand_tcp", settings).unwrap();
    let target = IkTarget::Pose(ik.tool_pose(&goal).unwrap());
    // Seed near the goal: the answer must be that branch, not another of the 8 candidates.
    let seed: Vec<f64> = goal.iter().map(|v| v + 0.05).collect();
    let sol = ik
        .solve(&target, &seed, &mut rand_pcg::Pcg64Mcg::seed_from_u64(1))
        .unwrap();
    let d: f64 = sol
        .q
        .iter()
        .zip(&goal)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(d < 0.05, "solution {:?} is {d} from the seed branch", sol.q);
}

#[test]
fn validity_callback_rejects_solutions() {
    let m = RobotModel::builtin("panda").unwrap();
    let chain = Chain::named(&m, "arm").unwrap();
    let mut ik = IkSolver::new(
        chain,
        "panda_hand_tcp",
        IkSettings {
            max_attempts: 30,
            ..Default::default()
        },
    )
    .unwrap();
    let target = IkTarget::Pose(ik.tool_pose(&[0.4, -0.3, 0.2, -2.1, 0.2, 1.9, 0.6]).unwrap());
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    // Reject every solution with joint 1 > 0: the answer must have joint 1 ≤ 0 or be an error.
    match ik.solve_with(&target, &[0.0; 7], &mut rng, |q| q[0] <= 0.0) {
        Ok(sol) => assert!(sol.q[0] <= 0.0),
        Err(IkError::NotFound { rejected, .. }) => assert!(rejected > 0),
        Err(e) => panic!("{e}"),
    }
    // Rejecting everything: a typed error that counts the rejections.
    let err = ik.solve_with(&target, &[0.0; 7], &mut rng, |_| false).unwrap_err();
    assert!(
        matches!(err, IkError::NotFound { rejected, .. } if rejected > 0),
        "{err}"
    );
}

#[test]
fn unreachable_and_bad_targets_are_errors() {
    let m = RobotModel::builtin("panda").unwrap();
    let chain = Chain::named(&m, "arm").unwrap();
    let settings = IkSettings {
        max_attempts: 20,
        ..Default::default()
    };
    let mut ik = IkSolver::new(chain, "panda_hand_tcp", settings).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let far = IkTarget::Pose(Isometry3::from_parts(
        Translation3::new(3.0, 0.0, 0.5),
        UnitQuaternion::identity(),
    ));
    assert!(matches!(
        ik.solve(&far, &[0.0; 7], &mut rng),
        Err(IkError::NotFound { .. })
    ));
    let nan = IkTarget::Position(Point3::new(f64::NAN, 0.0, 0.0));
    assert!(matches!(ik.solve(&nan, &[0.0; 7], &mut rng), Err(IkError::Input(_))));
    assert!(matches!(ik.solve(&far, &[0.0; 3], &mut rng), Err(IkError::Input(_))));
    assert!(matches!(
        ik.solve(&far, &[f64::NAN; 7], &mut rng),
        Err(IkError::Input(_))
    ));
}
