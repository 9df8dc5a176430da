//! Model-level behaviour: sharing, chains, limits that match the published specifications.

use hearth_kinematics::{BUILTIN_ROBOTS, Chain, JointKind, RobotModel};
use rand::SeedableRng;

#[test]
fn models_are_send_sync_and_cheap_to_clone() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<RobotModel>();
    assert_send_sync::<Chain>();
    let m = RobotModel::builtin("fetch").unwrap();
    let handles: Vec<_> = (0..2)
        .map(|i| {
            let m = m.clone();
            std::thread::spawn(move || {
                let mut poses = m.pose_buffer();
                let mut q = m.neutral_configuration();
                q[0] = i as f64 * 0.1;
                m.fk(&q, &mut poses).unwrap();
                poses[m.links().len() - 1]
            })
        })
        .collect();
    for h in handles {
        h.join().unwrap();
    }
}

/// Names, limits and velocities of the planned joints, as the benchmark problems list them
/// (Franka's published limits; Fetch Robotics' published limits).
#[test]
fn panda_arm_matches_franka_limits() {
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let names: Vec<String> = (1..=7).map(|i| format!("panda_joint{i}")).collect();
    assert_eq!(arm.joint_names(), names.as_slice());
    let lower = [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973];
    let upper = [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973];
    let velocity = [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61];
    assert_eq!(arm.lower(), lower);
    assert_eq!(arm.upper(), upper);
    assert_eq!(arm.velocity_limits(), velocity);
    let fingers = m.joint_index("panda_finger_joint2").unwrap();
    assert!(m.joints()[fingers].mimic.is_some());
}

#[test]
fn fetch_arm_matches_published_limits() {
    let m = RobotModel::builtin("fetch").unwrap();
    let arm = Chain::named(&m, "arm_with_torso").unwrap();
    let names = [
        "torso_lift_joint",
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "upperarm_roll_joint",
        "elbow_flex_joint",
        "forearm_roll_joint",
        "wrist_flex_joint",
        "wrist_roll_joint",
    ];
    assert_eq!(arm.joint_names(), names);
    let velocity = [0.1, 1.256, 1.454, 1.571, 1.521, 1.571, 2.268, 2.268];
    assert_eq!(arm.velocity_limits(), velocity);
    let bounded = [
        (0, 0.0, 0.38615),
        (1, -1.6056, 1.6056),
        (2, -1.221, 1.518),
        (4, -2.251, 2.251),
        (6, -2.16, 2.16),
    ];
    for (i, lo, hi) in bounded {
        assert_eq!((arm.lower()[i], arm.upper()[i]), (lo, hi), "{}", names[i]);
    }
    assert_eq!(arm.continuous(), [false, false, false, true, false, true, false, true]);
    for l in [
        "base_link",
        "eyes",
        "head_camera_link",
        "laser_link",
        "l_gripper_finger_link",
        "r_gripper_finger_link",
    ] {
        assert!(m.link_index(l).is_ok(), "fetch has {l}");
    }
    let torso = &m.joints()[m.joint_index("torso_lift_joint").unwrap()];
    assert_eq!(torso.kind, JointKind::Prismatic);
}

#[test]
fn builtin_robots_have_their_parts() {
    let locobot = RobotModel::builtin("locobot").unwrap();
    for l in ["camera_link", "laser_link", "gripper_link"] {
        assert!(locobot.link_index(l).is_ok(), "locobot has {l}");
    }
    assert_eq!(Chain::named(&locobot, "arm").unwrap().dof(), 5);
    let turtlebot = RobotModel::builtin("turtlebot").unwrap();
    for l in ["camera_link", "laser_link"] {
        assert!(turtlebot.link_index(l).is_ok(), "turtlebot has {l}");
    }
    for robot in BUILTIN_ROBOTS {
        let m = RobotModel::builtin(robot.name).unwrap();
        assert!(RobotModel::load(robot.name).is_ok());
        // Differential-drive robots expose their wheels as continuous joints.
        if robot.name != "panda" {
            let wheels = m
                .joints()
                .iter()
                .filter(|j| j.kind == JointKind::Continuous && j.name.contains("wheel"))
                .count();
            assert!(wheels >= 2, "{} has {wheels} wheel joints", robot.name);
        }
        // Every link with collision geometry also has mass.
        for l in m.links() {
            if !l.collisions.is_empty() {
                assert!(
                    l.inertial.as_ref().is_some_and(|i| i.mass > 0.0),
                    "{} {} has no mass",
                    robot.name,
                    l.name
                );
            }
        }
    }
}

#[test]
fn chains_scatter_gather_and_between() {
    let m = RobotModel::builtin("fetch").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let mut full = m.neutral_configuration();
    arm.scatter(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7], &mut full);
    let mut back = vec![0.0; 7];
    arm.gather(&full, &mut back);
    assert_eq!(back, [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]);
    let between = Chain::between(&m, "torso_lift_link", "gripper_link").unwrap();
    assert_eq!(between.joint_names(), arm.joint_names());
    assert!(Chain::between(&m, "gripper_link", "base_link").is_err());
    assert!(Chain::new(&m, &["no_such_joint"]).is_err());
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
    let mut q = vec![0.0; arm.dof()];
    for _ in 0..100 {
        arm.random_configuration(&mut rng, &mut q);
        let mut clamped = q.clone();
        arm.clamp(&mut clamped);
        assert_eq!(q, clamped, "samples lie inside the limits");
    }
}

#[test]
fn neutral_configuration_is_within_limits() {
    for robot in BUILTIN_ROBOTS {
        let m = RobotModel::builtin(robot.name).unwrap();
        assert!(m.within_limits(&m.neutral_configuration(), 0.0), "{}", robot.name);
    }
}

#[test]
fn same_seed_same_samples() {
    let m = RobotModel::builtin("panda").unwrap();
    let draw = |seed| {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let mut q = vec![0.0; m.dof()];
        m.random_configuration(&mut rng, &mut q);
        q
    };
    assert_eq!(draw(3), draw(3));
    assert_ne!(draw(3), draw(4));
}

#[test]
fn unknown_chain_names_the_known_ones() {
    let m = RobotModel::builtin("fetch").unwrap();
    let err = Chain::named(&m, "leg").unwrap_err();
    let text = err.to_string();
    assert!(text.contains("leg") && text.contains("arm_with_torso"), "{text}");
}
