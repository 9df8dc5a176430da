//! The self-collision matrix: adjacency, sampling, caching and stale-cache refusal.

use hearth_kinematics::{BUILTIN_ROBOTS, DisabledReason, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};

fn settings() -> SelfCollisionSettings {
    SelfCollisionSettings {
        samples: 1000,
        ..Default::default()
    }
}

#[test]
fn adjacent_links_are_disabled_and_neutral_pose_is_free() {
    for robot in BUILTIN_ROBOTS {
        let m = RobotModel::builtin(robot.name).unwrap();
        let matrix = SelfCollisionMatrix::compute(&m, &settings());
        for j in m.joints() {
            assert!(
                matrix.is_disabled(j.parent, j.child),
                "{}: {} adjacent",
                robot.name,
                j.name
            );
        }
        let mut poses = m.pose_buffer();
        m.fk(&m.neutral_configuration(), &mut poses).unwrap();
        assert_eq!(matrix.first_collision(&m, &poses), None, "{}", robot.name);
    }
}

#[test]
fn panda_keeps_the_pairs_that_can_collide() {
    let m = RobotModel::builtin("panda").unwrap();
    let matrix = SelfCollisionMatrix::compute(&m, &settings());
    let id = |n: &str| m.link_index(n).unwrap();
    // The hand can fold back onto the base and the upper arm: those pairs must stay checked.
    assert!(!matrix.is_disabled(id("panda_hand"), id("panda_link0")));
    assert!(!matrix.is_disabled(id("panda_hand"), id("panda_link2")));
    assert_eq!(
        matrix.reason(id("panda_link0"), id("panda_link1")),
        Some(DisabledReason::Adjacent)
    );
}

#[test]
fn no_samples_call_no_pair_never() {
    // Without samples there is no evidence that a pair never touches: only adjacent pairs and
    // those touching in the neutral configuration may be skipped.
    let m = RobotModel::builtin("panda").unwrap();
    let none = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 0,
            ..settings()
        },
    );
    let id = |n: &str| m.link_index(n).unwrap();
    assert!(!none.is_disabled(id("panda_hand"), id("panda_link0")));
    assert!(!none.is_disabled(id("panda_link0"), id("panda_link7")));
    assert!(none.is_disabled(id("panda_link0"), id("panda_link1")));
    for (a, b) in [("panda_link0", "panda_link1"), ("panda_link0", "panda_link7")] {
        let reason = none.reason(id(a), id(b));
        assert_ne!(reason, Some(DisabledReason::Never), "{a}-{b}");
    }
    // Far more pairs are checked than after sampling (where far links are `never`).
    let sampled = SelfCollisionMatrix::compute(&m, &settings());
    assert!(none.checked_pairs().len() > sampled.checked_pairs().len());
}

#[test]
fn deterministic_for_a_seed() {
    let m = RobotModel::builtin("fetch").unwrap();
    let s = SelfCollisionSettings {
        samples: 300,
        seed: 4,
        ..Default::default()
    };
    assert_eq!(
        SelfCollisionMatrix::compute(&m, &s),
        SelfCollisionMatrix::compute(&m, &s)
    );
}

#[test]
fn cache_round_trip_and_stale_refusal() {
    let panda = RobotModel::builtin("panda").unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let s = settings();
    let matrix = SelfCollisionMatrix::compute(&panda, &s);
    let dir = std::env::temp_dir().join(format!("hearth_sc_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("panda.json");
    matrix.save(&path, &panda, &s).unwrap();
    assert_eq!(SelfCollisionMatrix::load(&path, &panda).unwrap(), matrix);
    let err = SelfCollisionMatrix::load(&path, &fetch).unwrap_err();
    assert!(
        matches!(err, hearth_kinematics::KinematicsError::StaleCache { .. }),
        "{err}"
    );
    std::fs::write(&path, "{ not json").unwrap();
    assert!(matches!(
        SelfCollisionMatrix::load(&path, &panda).unwrap_err(),
        hearth_kinematics::KinematicsError::BadCache { .. }
    ));
    // load_or_compute replaces the broken file.
    let again = SelfCollisionMatrix::load_or_compute(&path, &panda, &s).unwrap();
    assert_eq!(again, matrix);
    assert_eq!(SelfCollisionMatrix::load(&path, &panda).unwrap(), matrix);
    std::fs::remove_dir_all(&dir).ok();
}
