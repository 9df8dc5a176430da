//! State and motion validity against real robot geometry.

use std::sync::Arc;

use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_planning::PlanError;
use hearth_planning::motion::MotionValidator;
use hearth_planning::obstacles::{Obstacle, ParryScene};
use hearth_planning::space::JointSpace;
use hearth_planning::validity::{Attached, Contact, RobotValidity, StateValidator};
use nalgebra::Isometry3;
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

const FOLDED: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

fn panda(obstacles: Vec<Obstacle>) -> RobotValidity {
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let acm = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 500,
            ..Default::default()
        },
    );
    RobotValidity::new(arm, acm, Arc::new(ParryScene::new(obstacles)))
}

#[test]
fn free_space_and_obstacle_contact() {
    let mut free = panda(vec![]);
    assert!(free.is_valid(&FOLDED));
    assert_eq!(free.explain(&FOLDED), None);

    let table = Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.2), Vector::new(0.3, 0.5, 0.02));
    let mut v = panda(vec![table]);
    assert!(v.is_valid(&FOLDED));
    // Reaching down onto the table top.
    let down = [0.0, 0.9, 0.0, -1.2, 0.0, 2.0, 0.785];
    assert!(!v.is_valid(&down));
    match v.explain(&down) {
        Some(Contact::Obstacle { obstacle, .. }) => assert_eq!(obstacle, "table"),
        other => panic!("expected a table contact, got {other:?}"),
    }
    assert_eq!(v.checks(), 2, "explain() does not count as a planner check");
}

#[test]
fn self_collision_is_found_and_named() {
    let mut v = panda(vec![]);
    // Elbow folded fully with the wrist turned back into the upper arm.
    let mut found = None;
    let mut rng = 1u64;
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    for _ in 0..5000 {
        let mut q = [0.0; 7];
        for (i, x) in q.iter_mut().enumerate() {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (rng >> 11) as f64 / (1u64 << 53) as f64;
            *x = arm.lower()[i] + u * (arm.upper()[i] - arm.lower()[i]);
        }
        if let Some(c @ Contact::SelfCollision { .. }) = v.explain(&q) {
            assert!(!v.is_valid(&q));
            found = Some(c);
            break;
        }
    }
    let c = found.expect("some random Panda configuration collides with itself");
    assert!(c.to_string().contains("panda_"), "{c}");
}

#[test]
fn bad_input_is_invalid_not_a_panic() {
    let mut v = panda(vec![]);
    assert!(!v.is_valid(&[0.0; 3]));
    assert!(!v.is_valid(&[f64::NAN; 7]));
    assert_eq!(v.explain(&[0.0; 3]), None);
}

#[test]
fn attached_object_moves_with_the_hand() {
    let m = RobotModel::builtin("panda").unwrap();
    let hand = m.link_index("panda_hand_tcp").unwrap();
    // A shelf just above the folded pose's hand: the bare arm clears it, a held 10 cm ball does not.
    let mut bare = panda(vec![]);
    assert!(bare.is_valid(&FOLDED));
    let mut q_full = m.neutral_configuration();
    q_full[..7].copy_from_slice(&FOLDED);
    let tcp = m.link_pose(&q_full, hand).unwrap();
    let shelf_z = tcp.translation.z as f32 - 0.12;
    let shelf = Obstacle::cuboid(
        "shelf",
        Pose::translation(tcp.translation.x as f32, 0.0, shelf_z),
        Vector::new(0.05, 0.05, 0.005),
    );
    let mut v = panda(vec![shelf]);
    assert!(v.is_valid(&FOLDED), "{:?}", v.explain(&FOLDED));
    v.attach(Attached {
        name: "ball".into(),
        link: hand,
        offset: Isometry3::translation(0.0, 0.0, 0.05),
        shape: SharedShape::ball(0.1),
    })
    .unwrap();
    assert!(!v.is_valid(&FOLDED));
    assert!(v.explain(&FOLDED).unwrap().to_string().contains("attached:ball"));
    v.detach_all();
    assert!(v.is_valid(&FOLDED));
}

#[test]
fn an_object_held_at_a_frame_without_geometry_follows_every_state() {
    // The tool point has no collision shape, so the check's kinematics leave it out until an
    // object hangs from it; from then on it must follow every state, one by one and in lanes.
    let m = RobotModel::builtin("panda").unwrap();
    let tcp_link = m.link_index("panda_hand_tcp").unwrap();
    assert!(m.link_shape(tcp_link).is_none());
    let mut q_full = m.neutral_configuration();
    q_full[..7].copy_from_slice(&FOLDED);
    let tcp = m.link_pose(&q_full, tcp_link).unwrap();
    let shelf = Obstacle::cuboid(
        "shelf",
        Pose::translation(tcp.translation.x as f32, 0.0, tcp.translation.z as f32 - 0.12),
        Vector::new(0.05, 0.05, 0.005),
    );
    let mut raised = FOLDED;
    raised[1] -= 0.5;
    let mut v = panda(vec![shelf]);
    // Bare: both clear; the last full pass saw the tool point at FOLDED.
    assert!(v.is_valid(&FOLDED) && v.is_valid(&raised));
    v.attach(Attached {
        name: "ball".into(),
        link: tcp_link,
        offset: Isometry3::translation(0.0, 0.0, 0.12),
        shape: SharedShape::ball(0.05),
    })
    .unwrap();
    assert!(v.is_valid(&raised), "{:?}", v.explain(&raised));
    assert!(!v.is_valid(&FOLDED));
    assert!(v.is_valid(&raised), "{:?}", v.explain(&raised));
    let states: Vec<f64> = [raised, raised, FOLDED, raised].concat();
    assert_eq!(v.first_invalid(&states, 7), Some(2));
    let states: Vec<f64> = [raised; 4].concat();
    assert_eq!(v.first_invalid(&states, 7), None);
}

#[test]
fn motion_validator_finds_the_wall_between_two_free_states() {
    let wall = Obstacle::cuboid("wall", Pose::translation(0.0, 0.45, 0.5), Vector::new(0.3, 0.02, 0.3));
    let mut v = panda(vec![wall]);
    let m = RobotModel::builtin("panda").unwrap();
    let space = JointSpace::from_chain(&Chain::named(&m, "arm").unwrap()).unwrap();
    let mut mv = MotionValidator::new(space, 0.02);
    // Swing joint 1 from one side to the other: the arm sweeps through the wall at +y.
    let mut a = [0.0, 0.3, 0.0, -1.6, 0.0, 1.9, 0.785];
    let mut b = a;
    a[0] = 0.0;
    b[0] = 2.8;
    assert!(v.is_valid(&a), "{:?}", v.explain(&a));
    assert!(v.is_valid(&b), "{:?}", v.explain(&b));
    let before = v.checks();
    assert!(!mv.check_motion(&mut v, &a, &b));
    let used = v.checks() - before;
    assert!(
        used < mv.segments(&a, &b) as u64,
        "midpoint-first stops early ({used} checks)"
    );
    // A short motion on the free side is valid, and checks every intermediate state.
    let mut c = a;
    c[0] = -0.5;
    let before = v.checks();
    assert!(mv.check_motion(&mut v, &a, &c));
    assert_eq!(v.checks() - before, mv.segments(&a, &c) as u64 - 1);
}

/// Links that do not move with the chain (the Fetch's base, wheels, head mount) are checked
/// once per reference and base; moving the base must re-check them.
#[test]
fn fixed_links_are_rechecked_when_the_base_moves() {
    use hearth_planning::obstacles::{Obstacle, ParryScene};
    let m = hearth_kinematics::RobotModel::builtin("fetch").unwrap();
    let arm = hearth_kinematics::Chain::named(&m, "arm").unwrap();
    let acm = hearth_kinematics::SelfCollisionMatrix::compute(
        &m,
        &hearth_kinematics::SelfCollisionSettings {
            samples: 300,
            ..Default::default()
        },
    );
    // A low block 2 m in front of the robot: only the base can reach it.
    let block = Obstacle::cuboid(
        "block",
        parry3d::math::Pose::translation(2.0, 0.0, 0.05),
        parry3d::math::Vector::new(0.2, 0.2, 0.05),
    );
    let mut v = RobotValidity::new(arm, acm, std::sync::Arc::new(ParryScene::new(vec![block])));
    let tucked = [1.32, 1.4, -0.2, 1.72, 0.0, 1.66, 0.0];
    assert!(v.is_valid(&tucked));
    v.set_base(nalgebra::Isometry3::translation(2.0, 0.0, 0.0));
    assert!(!v.is_valid(&tucked), "the base now stands in the block");
    assert!(!v.is_valid(&[0.0; 7]));
    v.set_base(nalgebra::Isometry3::translation(0.0, 0.0, 0.0));
    assert!(v.is_valid(&tucked));
}

/// Joints outside the chain (here the torso under the `arm` chain) move the chain's links too:
/// a new reference must recompute every pose, not only the links the chain moves.
#[test]
fn a_new_reference_moves_the_links_above_it() {
    use hearth_planning::obstacles::{Obstacle, ParryScene};
    let m = hearth_kinematics::RobotModel::builtin("fetch").unwrap();
    let arm = hearth_kinematics::Chain::named(&m, "arm").unwrap();
    let torso = m.variable_names().iter().position(|n| n == "torso_lift_joint").unwrap();
    let gripper = m.link_index("gripper_link").unwrap();
    let (mut low, mut high) = (m.neutral_configuration(), m.neutral_configuration());
    low[torso] = 0.0;
    high[torso] = 0.38;
    let mut poses = m.pose_buffer();
    m.fk(&high, &mut poses).unwrap();
    let g = poses[gripper].translation.vector;
    // A small block where the gripper is with the torso up, 0.38 m above it with the torso down.
    let block = Obstacle::cuboid(
        "block",
        parry3d::math::Pose::translation(g.x as f32, g.y as f32, g.z as f32),
        parry3d::math::Vector::new(0.03, 0.03, 0.03),
    );
    let acm = hearth_kinematics::SelfCollisionMatrix::compute(
        &m,
        &hearth_kinematics::SelfCollisionSettings {
            samples: 300,
            ..Default::default()
        },
    );
    let mut v = RobotValidity::new(arm.clone(), acm, std::sync::Arc::new(ParryScene::new(vec![block])));
    let mut q = vec![0.0; arm.dof()];
    arm.gather(&high, &mut q);
    v.set_reference(&low).unwrap();
    assert!(v.is_valid(&q), "torso down: the gripper is below the block");
    v.set_reference(&high).unwrap();
    assert!(!v.is_valid(&q), "torso up: the gripper is in the block");
    v.set_reference(&low).unwrap();
    assert!(v.is_valid(&q));
}

/// The tool's pose at chain configuration `q` (the rest of the robot at its neutral
/// configuration), with the robot's base at `base`.
fn tool_pose(chain: &Chain, q: &[f64], tool: usize, base: &Isometry3<f64>) -> Isometry3<f64> {
    let model = chain.model();
    let mut full = model.neutral_configuration();
    chain.scatter(q, &mut full);
    let mut poses = model.pose_buffer();
    model.fk_from(base, &full, &mut poses).unwrap();
    poses[tool]
}

/// `tool_step` moves the chain's tool by the length asked along its own axis and keeps its
/// orientation, to first order: the Panda's named arm moves its TCP; a chain named by its
/// joints (the Fetch's torso and arm, as MotionBenchMaker plans them), whose tip is not named,
/// moves its deepest link. It counts no check, keeps to the joint limits and refuses bad input.
#[test]
fn tool_steps_move_the_tool_straight_along_its_axes() {
    let check = |v: &mut RobotValidity, q: &[f64], tool: usize, base: Isometry3<f64>| {
        let chain = v.chain().clone();
        let before = tool_pose(&chain, q, tool, &base);
        let mut out = vec![0.0; q.len()];
        let checks = v.checks();
        for axis in 0..6 {
            assert!(v.tool_step(q, axis, 0.01, &mut out), "axis {axis}");
            let after = tool_pose(&chain, &out, tool, &base);
            let mut local = nalgebra::Vector3::zeros();
            local[axis % 3] = if axis < 3 { 0.01 } else { -0.01 };
            let wanted = before.translation.vector + before.rotation * local;
            let off = (after.translation.vector - wanted).norm();
            let turned = before.rotation.angle_to(&after.rotation);
            assert!(
                off < 5e-4 && turned < 1e-3,
                "axis {axis}: {off} m off, turned {turned} rad"
            );
        }
        assert_eq!(v.checks(), checks, "a tool step is not a check");
    };
    let mut v = panda(Vec::new());
    let tcp = v.chain().model().link_index("panda_hand_tcp").unwrap();
    check(&mut v, &FOLDED, tcp, Isometry3::identity());
    let base = Isometry3::new(nalgebra::Vector3::new(1.0, -2.0, 0.0), nalgebra::Vector3::z() * 1.2);
    v.set_base(base);
    check(&mut v, &FOLDED, tcp, base);

    let m = RobotModel::builtin("fetch").unwrap();
    // The named chain's joints, without its tip.
    let joints = Chain::named(&m, "arm_with_torso").unwrap().joint_names().to_vec();
    let chain = Chain::new(&m, &joints).unwrap();
    assert_eq!(chain.tip(), None);
    let acm = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 300,
            ..Default::default()
        },
    );
    let mut fetch = RobotValidity::new(chain, acm, Arc::new(ParryScene::new(Vec::new())));
    let wrist = m.link_index("wrist_roll_link").unwrap();
    let reach = [0.2, 0.5, -0.3, 0.4, 1.2, 0.3, 0.8, 0.1];
    check(&mut fetch, &reach, wrist, Isometry3::identity());

    // The limits hold: the Panda's elbow at its upper limit stays there or below.
    let arm = v.chain().clone();
    let mut q = FOLDED;
    q[3] = arm.upper()[3];
    let mut out = [0.0; 7];
    for axis in 0..6 {
        if v.tool_step(&q, axis, 0.05, &mut out) {
            assert!(
                out.iter()
                    .zip(arm.lower().iter().zip(arm.upper()))
                    .all(|(x, (lo, hi))| (lo..=hi).contains(&x))
            );
        }
    }
    // Bad input: no step, `out` untouched.
    let mut out = [7.0; 7];
    let mut nan = FOLDED;
    nan[2] = f64::NAN;
    assert!(!v.tool_step(&nan, 0, 0.01, &mut out));
    assert!(!v.tool_step(&FOLDED, 6, 0.01, &mut out));
    assert!(!v.tool_step(&FOLDED, 0, f64::INFINITY, &mut out));
    assert!(!v.tool_step(&FOLDED[..6], 0, 0.01, &mut out[..6]));
    assert_eq!(out, [7.0; 7]);
}

/// An attached object with a link the model lacks, a non-finite offset or a broken shape is
/// refused with `BadInput` naming it, and leaves the validator as it was (before, a link
/// out of range panicked at the first check and a NaN shape answered wrongly).
#[test]
fn attaching_a_broken_object_is_refused_and_changes_nothing() {
    let m = RobotModel::builtin("panda").unwrap();
    let hand = m.link_index("panda_hand").unwrap();
    let links = m.links().len();
    let shelf = Obstacle::cuboid(
        "shelf",
        Pose::translation(0.3, 0.0, 0.2),
        Vector::new(0.05, 0.05, 0.005),
    );
    let mut v = panda(vec![shelf]);
    let before = v.is_valid(&FOLDED);
    let object = |link: usize, offset: Isometry3<f64>, shape: SharedShape| Attached {
        name: "mug".into(),
        link,
        offset,
        shape,
    };
    let nan_offset = Isometry3::translation(f64::NAN, 0.0, 0.0);
    let cases = [
        (
            object(links, Isometry3::identity(), SharedShape::ball(0.05)),
            "does not exist",
        ),
        (
            object(hand, nan_offset, SharedShape::ball(0.05)),
            "offset is not finite",
        ),
        (
            object(hand, Isometry3::identity(), SharedShape::ball(f32::NAN)),
            "radius is NaN",
        ),
        (
            object(hand, Isometry3::identity(), SharedShape::cuboid(0.1, -0.1, 0.1)),
            "half-extent is -0.1",
        ),
    ];
    for (bad, says) in cases {
        match v.attach(bad) {
            Err(PlanError::BadInput(m)) => assert!(m.contains("\"mug\"") && m.contains(says), "{m}"),
            other => panic!("{says}: {other:?}"),
        }
        assert_eq!(v.is_valid(&FOLDED), before);
        assert!(v.explain(&FOLDED).is_none_or(|c| !c.to_string().contains("mug")));
    }
}

/// `retract` pushes a state whose hand sinks a little into the table out of it, by a small
/// joint move, and checks the result; a valid state stays where it is; zero rounds only
/// check; bad input is refused.
#[test]
fn retraction_pushes_a_state_out_of_the_table() {
    let table = Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.2), Vector::new(0.3, 0.5, 0.02));
    let mut v = panda(vec![table]);
    let down = [0.0, 0.9, 0.0, -1.2, 0.0, 2.0, 0.785];
    // The first state on the way down that touches the table: millimetres deep.
    let lerp = |t: f64| -> [f64; 7] { std::array::from_fn(|i| FOLDED[i] + t * (down[i] - FOLDED[i])) };
    let t = (0..=2000)
        .map(|i| f64::from(i) / 2000.0)
        .find(|&t| !v.is_valid(&lerp(t)))
        .expect("the way down meets the table");
    let q = lerp(t);
    let mut out = [0.0; 7];
    let before = v.checks();
    assert!(v.retract(&q, 0.01, 3, &mut out));
    assert!(v.is_valid(&out) && v.explain(&out).is_none());
    let moved = q.iter().zip(&out).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    assert!(moved > 0.0 && moved < 0.1, "moved {moved} rad");
    assert!(v.checks() >= before + 2, "each round and the result are checks");
    // Deeper in: pushed out too, or refused, never left colliding with true.
    let deep = lerp((t + 0.02).min(1.0));
    if v.retract(&deep, 0.01, 3, &mut out) {
        assert!(v.is_valid(&out));
    }
    // A valid state stays where it is.
    assert!(v.retract(&FOLDED, 0.01, 3, &mut out));
    assert_eq!(out, FOLDED);
    // Zero rounds: the state as it is, checked.
    assert!(!v.retract(&q, 0.01, 0, &mut out));
    assert_eq!(out, q);
    // Bad input.
    assert!(!v.retract(&[f64::NAN; 7], 0.01, 3, &mut out));
    assert!(!v.retract(&q[..3], 0.01, 3, &mut out));
    assert!(!v.retract(&q, -0.01, 3, &mut out));
    assert!(!v.retract(&q, f64::NAN, 3, &mut out));
}
