//! Robots in physics: position holding, joint limits, differential drive, grippers, mimic
//! joints, efforts, readout, and bad-input errors for every command.

use hearth_sim::kinematics::RobotModel;
use hearth_sim::world::{
    BaseMode, DiffDriveConfig, GripperConfig, JointCommand, JointGains, ModelHandle, SpawnOptions, World, WorldConfig,
    WorldError,
};
use nalgebra::{Isometry3, Vector3};

fn world() -> World {
    World::new(WorldConfig::default()).unwrap()
}

fn steps(world: &mut World, n: usize) {
    for _ in 0..n {
        world.step();
    }
}

fn yaw(pose: &Isometry3<f64>) -> f64 {
    pose.rotation.euler_angles().2
}

#[test]
fn panda_holds_a_position_target_under_gravity() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = world();
    let arm = world
        .spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    let q: Vec<f64> = vec![0.3, 0.6, -0.2, -1.2, 0.1, 1.8, 0.5, 0.02];
    world.set_position_targets(arm, &q).unwrap();
    steps(&mut world, 60); // 2 s
    let got = world.joint_positions(arm).unwrap();
    for (i, (a, b)) in got.iter().zip(&q).enumerate() {
        assert!((a - b).abs() < 1e-2, "joint {i}: {a} vs {b}");
    }
    let efforts = world.joint_efforts(arm).unwrap();
    assert!(efforts[1].abs() > 1.0, "shoulder carries the arm: {efforts:?}");
    for (e, limit) in efforts.iter().zip(panda.effort_limits()) {
        assert!(e.abs() <= *limit + 1e-9);
    }
    let v = world.joint_velocities(arm).unwrap();
    assert!(v.iter().all(|x| x.abs() < 0.05), "{v:?}");
}

#[test]
fn mimic_finger_follows_its_leader() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = world();
    let arm = world
        .spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    world.gripper_open(arm).unwrap();
    steps(&mut world, 20);
    let hand = world.link_pose(arm, "panda_hand").unwrap();
    let l = world.link_pose(arm, "panda_leftfinger").unwrap();
    let r = world.link_pose(arm, "panda_rightfinger").unwrap();
    let gap = (l.translation.vector - r.translation.vector).norm();
    assert!((gap - 0.08).abs() < 5e-3, "fingers 2 × 0.04 apart: {gap}");
    assert!((hand.inverse() * l).translation.y > 0.035);
    assert!((hand.inverse() * r).translation.y < -0.035);
    world.gripper_close(arm, 20.0).unwrap();
    steps(&mut world, 20);
    let l = world.link_pose(arm, "panda_leftfinger").unwrap();
    let r = world.link_pose(arm, "panda_rightfinger").unwrap();
    assert!((l.translation.vector - r.translation.vector).norm() < 5e-3);
}

#[test]
fn gripper_fingers_move_at_their_velocity_limit() {
    let fetch = RobotModel::builtin("fetch").unwrap();
    let mut world = world();
    let robot = world
        .spawn_model(&fetch, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    let finger = fetch
        .variable_names()
        .iter()
        .position(|n| n == "r_gripper_finger_joint")
        .unwrap();
    world.gripper_open(robot).unwrap();
    steps(&mut world, 45); // 1.5 s: 5 cm at 5 cm/s
    let open = world.joint_positions(robot).unwrap()[finger];
    assert!(open > 0.049, "open: {open}");
    world.gripper_close(robot, 40.0).unwrap();
    steps(&mut world, 15); // 0.5 s
    let half = world.joint_positions(robot).unwrap()[finger];
    assert!((half - 0.025).abs() < 0.004, "after 0.5 s at 5 cm/s: {half}");
    // Nothing slows it on the way or puts it to sleep before it gets there.
    steps(&mut world, 30);
    let closed = world.joint_positions(robot).unwrap()[finger];
    assert!(closed < 0.002, "closed: {closed}");
}

const DRAWER: &str = r#"<?xml version="1.0"?>
<robot name="drawer">
  <link name="cabinet">
    <inertial><mass value="20"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0 0 0.3"/><geometry><box size="0.5 0.5 0.02"/></geometry></collision>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="cabinet"/><child link="tray"/>
    <origin xyz="0 0 0.4"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.3" effort="50" velocity="1"/>
    <dynamics damping="1.0" friction="0.5"/>
  </joint>
  <link name="tray">
    <inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><geometry><box size="0.4 0.4 0.05"/></geometry></collision>
  </link>
</robot>"#;

#[test]
fn drawer_respects_its_limits_when_pushed() {
    let drawer = RobotModel::from_urdf_str(DRAWER, None).unwrap();
    let mut world = world();
    let h = world
        .spawn_model(&drawer, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    world
        .set_joint_command(h, "slide", JointCommand::Effort { value: 50.0 })
        .unwrap();
    steps(&mut world, 45);
    let q = world.joint_positions(h).unwrap()[0];
    assert!(q > 0.28 && q < 0.31, "pulled open to the upper limit: {q}");
    let tray_x = world.link_pose(h, "tray").unwrap().translation.x;
    assert!((tray_x - q).abs() < 1e-3);
    world
        .set_joint_command(h, "slide", JointCommand::Effort { value: -50.0 })
        .unwrap();
    steps(&mut world, 45);
    let q = world.joint_positions(h).unwrap()[0];
    assert!(q > -0.01 && q < 0.02, "pushed shut to the lower limit: {q}");
    assert_eq!(world.joint_efforts(h).unwrap(), vec![-50.0]);
    // Free: damping and friction keep it still.
    world.set_joint_command(h, "slide", JointCommand::Off).unwrap();
    steps(&mut world, 10);
    assert!(world.joint_velocities(h).unwrap()[0].abs() < 0.05);
}

/// The Fetch with its arm stretched out level in front of the base, held for 2 s.
fn fetch_arm_out(compensate: bool) -> (World, ModelHandle, Vec<f64>) {
    let fetch = RobotModel::builtin("fetch").unwrap();
    let mut world = world();
    let h = world
        .spawn_model(&fetch, &Isometry3::identity(), SpawnOptions::free())
        .unwrap();
    world.set_gravity_compensation(h, compensate).unwrap();
    let mut q = world.joint_positions(h).unwrap();
    // The torso up, the arm stretched out level (every arm joint at zero).
    let chain = hearth_sim::kinematics::Chain::named(&fetch, "arm_with_torso").unwrap();
    let mut arm = vec![0.0; chain.dof()];
    arm[0] = 0.3;
    chain.scatter(&arm, &mut q);
    world.set_position_targets(h, &q).unwrap();
    steps(&mut world, 60);
    (world, h, q)
}

#[test]
fn gravity_compensation_holds_an_outstretched_arm_on_target() {
    // How far the gripper is from where the targets put it, over the base as it stands.
    let tip_error = |world: &World, h: ModelHandle, q: &[f64]| {
        let model = world.model(h).unwrap().clone();
        let mut poses = model.pose_buffer();
        model.fk_from(&world.base_pose(h).unwrap(), q, &mut poses).unwrap();
        let want = poses[model.link_index("gripper_link").unwrap()].translation.vector;
        let got = world.link_pose(h, "gripper_link").unwrap().translation.vector;
        (want - got).norm()
    };
    let (world, h, q) = fetch_arm_out(true);
    let held = tip_error(&world, h, &q);
    let (plain_world, plain, _) = fetch_arm_out(false);
    let sagged = tip_error(&plain_world, plain, &q);
    assert!(held < 3e-3, "the gripper is {held} m off its target with compensation");
    assert!(
        sagged > 3.0 * held,
        "without compensation the arm sags more: {sagged} vs {held} m"
    );
    // The wheels carry the base and the casters keep it level under the outstretched arm.
    let (roll, pitch, _) = world.base_pose(h).unwrap().rotation.euler_angles();
    assert!(roll.abs() < 0.01 && pitch.abs() < 0.01, "base tilts by {roll}, {pitch}");
}

fn drive_straight(robot: &str, v: f64, seconds: f64) -> (World, ModelHandle) {
    let model = RobotModel::builtin(robot).unwrap();
    let mut world = world();
    let h = world
        .spawn_model(&model, &Isometry3::identity(), SpawnOptions::free())
        .unwrap();
    if robot == "fetch" {
        world.tuck(h).unwrap();
    }
    steps(&mut world, 10);
    let start = world.base_pose(h).unwrap();
    world.drive(h, v, 0.0).unwrap();
    steps(&mut world, (seconds * 30.0) as usize);
    let end = world.base_pose(h).unwrap();
    let d = (start.inverse() * end).translation.vector;
    assert!((d.x - v * seconds).abs() < 0.25 * v * seconds, "{robot} moved {d:?}");
    assert!(d.y.abs() < 0.1 * v * seconds, "{robot} drifted sideways {d:?}");
    (world, h)
}

#[test]
fn fetch_drives_forward_and_turns() {
    let (mut world, h) = drive_straight("fetch", 0.3, 2.0);
    let twist = world.base_twist(h).unwrap();
    assert!((twist.linear.x - 0.3).abs() < 0.1, "{twist:?}");
    let before = yaw(&world.base_pose(h).unwrap());
    world.drive(h, 0.0, 0.5).unwrap();
    steps(&mut world, 60);
    let turned = yaw(&world.base_pose(h).unwrap()) - before;
    assert!(turned > 0.5 && turned < 1.3, "turned {turned} rad, expected about 1");
}

#[test]
fn turtlebot_drives_forward() {
    drive_straight("turtlebot", 0.3, 2.0);
}

#[test]
fn holonomic_base_follows_velocity_in_its_frame() {
    let model = RobotModel::builtin("turtlebot").unwrap();
    let mut world = world();
    let opts = SpawnOptions {
        base: BaseMode::Holonomic,
        ..SpawnOptions::default()
    };
    let start = Isometry3::new(
        Vector3::new(0.0, 0.0, 0.02),
        Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
    );
    let h = world.spawn_model(&model, &start, opts).unwrap();
    world.drive_holonomic(h, 0.3, 0.0, 0.0).unwrap();
    steps(&mut world, 30);
    let p = world.base_pose(h).unwrap().translation.vector;
    assert!(p.x.abs() < 0.01 && (p.y - 0.3).abs() < 0.01, "{p:?}");
    // Its twist is the one it is driven with, in the world frame (the pose is set each
    // physics step, so the body's own velocity would read zero): base +x is world +y.
    world.drive_holonomic(h, 0.3, -0.1, 0.0).unwrap();
    steps(&mut world, 2);
    let before = world.base_pose(h).unwrap().translation.vector;
    world.step_physics();
    let t = world.base_twist(h).unwrap();
    assert!((t.linear - Vector3::new(0.1, 0.3, 0.0)).norm() < 1e-3, "{t:?}");
    assert!(t.angular.norm() < 1e-3, "{t:?}");
    let moved = (world.base_pose(h).unwrap().translation.vector - before) / world.config().timestep;
    assert!(
        (moved - t.linear).norm() < 1e-2,
        "the base moves with it: {moved:?} vs {t:?}"
    );
    // Turning in place: the yaw rate, and no linear speed at the base's origin.
    world.drive_holonomic(h, 0.0, 0.0, 0.5).unwrap();
    steps(&mut world, 1);
    let t = world.base_twist(h).unwrap();
    assert!((t.angular - Vector3::new(0.0, 0.0, 0.5)).norm() < 1e-3, "{t:?}");
    assert!(t.linear.norm() < 1e-3, "{t:?}");
    // Placing the base zeroes its velocities until the next step, as for other bases.
    world.place(h, &start).unwrap();
    assert_eq!(world.base_twist(h).unwrap(), Default::default());
    assert!(matches!(world.drive(h, 0.1, 0.0), Ok(())), "its wheels still spin");
}

#[test]
fn reset_place_tuck_and_contacts() {
    let fetch = RobotModel::builtin("fetch").unwrap();
    let mut world = world();
    let h = world
        .spawn_model(&fetch, &Isometry3::identity(), SpawnOptions::free())
        .unwrap();
    world.tuck(h).unwrap();
    steps(&mut world, 15);
    let names = fetch.variable_names();
    let q = world.joint_positions(h).unwrap();
    let idx = |n: &str| names.iter().position(|x| x == n).unwrap();
    assert!((q[idx("shoulder_lift_joint")] - 1.40).abs() < 2e-2, "{q:?}");
    let contacts = world.contacts(h).unwrap();
    assert!(
        contacts
            .iter()
            .any(|c| c.other_name == "ground" && c.link.contains("wheel"))
    );
    let weight: f64 = contacts.iter().map(|c| c.force.z).sum();
    assert!(weight > 100.0, "the ground carries the robot: {weight} N");
    for c in &contacts {
        assert!(c.point.z.abs() < 0.02, "contacts lie on the floor: {c:?}");
        assert!(c.torque.iter().all(|t| t.is_finite()));
    }
    let target = Isometry3::new(Vector3::new(2.0, 1.0, 0.0), Vector3::new(0.0, 0.0, 1.0));
    world.place(h, &target).unwrap();
    let p = world.base_pose(h).unwrap();
    assert!((p.translation.vector - target.translation.vector).norm() < 1e-5);
    assert!((world.link_pose(h, "gripper_link").unwrap().translation.x - 2.0).abs() < 1.0);
    let mut q = fetch.neutral_configuration();
    q[idx("torso_lift_joint")] = 0.3;
    world.reset_configuration(h, &q).unwrap();
    assert!((world.joint_positions(h).unwrap()[idx("torso_lift_joint")] - 0.3).abs() < 1e-5);
    assert!(world.joint_velocities(h).unwrap().iter().all(|v| *v == 0.0));
    steps(&mut world, 15);
    assert!((world.joint_positions(h).unwrap()[idx("torso_lift_joint")] - 0.3).abs() < 1e-2);
}

#[test]
fn bad_commands_give_typed_errors_and_change_nothing() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = world();
    let arm = world
        .spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    steps(&mut world, 2);
    let hash = world.state_hash();
    let commands = world.joint_commands(arm).unwrap().to_vec();
    let n = panda.dof();
    let nan = vec![f64::NAN; n];
    let ghost = ModelHandle::from_index(99);

    let dim = |r: Result<(), WorldError>| assert!(matches!(r, Err(WorldError::DimensionMismatch { .. })), "{r:?}");
    let non_finite = |r: Result<(), WorldError>| assert!(matches!(r, Err(WorldError::NonFinite { .. })), "{r:?}");
    let range = |r: Result<(), WorldError>| assert!(matches!(r, Err(WorldError::OutOfRange { .. })), "{r:?}");
    let unknown = |r: Result<(), WorldError>| assert!(matches!(r, Err(WorldError::UnknownModel { .. })), "{r:?}");

    dim(world.set_position_targets(arm, &[0.0; 3]));
    dim(world.set_velocity_targets(arm, &[0.0; 3]));
    dim(world.set_efforts(arm, &[0.0; 3]));
    dim(world.reset_configuration(arm, &[0.0; 3]));
    non_finite(world.set_position_targets(arm, &nan));
    non_finite(world.set_velocity_targets(arm, &nan));
    non_finite(world.set_efforts(arm, &nan));
    non_finite(world.reset_configuration(arm, &nan));
    let mut far = panda.neutral_configuration();
    far[0] = 10.0;
    range(world.set_position_targets(arm, &far));
    range(world.reset_configuration(arm, &far));
    range(world.set_velocity_targets(arm, &far));
    let mut strong = vec![0.0; n];
    strong[0] = 1e6;
    range(world.set_efforts(arm, &strong));
    range(world.gripper_close(arm, -1.0));
    range(world.gripper_close(arm, 1e6));
    non_finite(world.gripper_close(arm, f64::NAN));
    range(world.set_joint_command(arm, "panda_joint4", JointCommand::Position { target: 1.0 }));
    non_finite(world.set_joint_command(arm, "panda_joint4", JointCommand::Velocity { target: f64::INFINITY }));
    let r = world.set_joint_command(arm, "nope", JointCommand::Off);
    assert!(
        matches!(r, Err(WorldError::UnknownJoint { ref joint, .. }) if joint == "nope"),
        "{r:?}"
    );
    let r = world.set_joint_command(arm, "panda_finger_joint2", JointCommand::Off);
    assert!(matches!(r, Err(WorldError::JointNotCommandable { .. })), "{r:?}");
    let r = world.set_joint_command(arm, "panda_hand_joint", JointCommand::Off);
    assert!(
        matches!(
            r,
            Err(WorldError::JointNotCommandable { .. }) | Err(WorldError::UnknownJoint { .. })
        ),
        "{r:?}"
    );
    let bad_gains = JointGains {
        stiffness: -1.0,
        damping: 1.0,
        velocity_gain: 1.0,
        max_effort: 1.0,
    };
    range(world.set_joint_gains(arm, "panda_joint1", bad_gains));
    let r = world.drive(arm, 0.1, 0.0);
    assert!(matches!(r, Err(WorldError::NoController { .. })), "{r:?}");
    let r = world.drive_holonomic(arm, 0.1, 0.0, 0.0);
    assert!(matches!(r, Err(WorldError::NoController { .. })), "{r:?}");
    let r = world.set_named_configuration(arm, "dance");
    assert!(matches!(r, Err(WorldError::UnknownConfiguration { .. })), "{r:?}");
    non_finite(world.place(arm, &Isometry3::translation(f64::NAN, 0.0, 0.0)));
    let r = world.link_pose(arm, "nope").map(|_| ());
    assert!(matches!(r, Err(WorldError::UnknownLink { .. })), "{r:?}");
    unknown(world.set_position_targets(ghost, &[]));
    unknown(world.drive(ghost, 0.0, 0.0));
    unknown(world.gripper_open(ghost));
    unknown(world.obstacles_view(&[ghost]).map(|_| ()));
    unknown(world.joint_positions(ghost).map(|_| ()));

    assert_eq!(world.state_hash(), hash, "failed commands must not change the world");
    assert_eq!(world.joint_commands(arm).unwrap(), &commands[..]);

    // Diff drive: NaN and wheel speeds beyond the limit.
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(3.0, 0.0, 0.0), SpawnOptions::free())
        .unwrap();
    non_finite(world.drive(robot, f64::NAN, 0.0));
    range(world.drive(robot, 100.0, 0.0));
    // Bad spawn options.
    let opts = SpawnOptions {
        diff_drive: Some(DiffDriveConfig {
            wheel_radius: -1.0,
            ..DiffDriveConfig::for_builtin("fetch").unwrap()
        }),
        ..SpawnOptions::default()
    };
    range(world.spawn_model(&fetch, &Isometry3::identity(), opts).map(|_| ()));
    let opts = SpawnOptions {
        gripper: Some(GripperConfig {
            joints: vec!["nope".into()],
            open: vec![0.0],
            closed: vec![0.0],
        }),
        ..SpawnOptions::default()
    };
    let r = world.spawn_model(&fetch, &Isometry3::identity(), opts).map(|_| ());
    assert!(matches!(r, Err(WorldError::UnknownJoint { .. })), "{r:?}");
    let opts = SpawnOptions {
        configuration: Some(vec![0.0]),
        ..SpawnOptions::default()
    };
    dim(world.spawn_model(&fetch, &Isometry3::identity(), opts).map(|_| ()));
}

#[test]
fn velocity_and_effort_control() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = World::new(WorldConfig {
        gravity: [0.0; 3],
        ..WorldConfig::default()
    })
    .unwrap();
    let arm = world
        .spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    world
        .set_joint_command(arm, "panda_joint1", JointCommand::Velocity { target: 0.5 })
        .unwrap();
    steps(&mut world, 30);
    let v = world.joint_velocities(arm).unwrap()[0];
    assert!((v - 0.5).abs() < 0.02, "{v}");
    let q = world.joint_positions(arm).unwrap()[0];
    assert!((q - 0.5).abs() < 0.1, "{q}");
    world
        .set_joint_command(arm, "panda_joint7", JointCommand::Effort { value: 1.0 })
        .unwrap();
    steps(&mut world, 5);
    assert!(world.joint_velocities(arm).unwrap()[6] > 0.1);
}

const MUG: &str = r#"<?xml version="1.0"?>
<robot name="mug">
  <link name="body">
    <collision><geometry><cylinder radius="0.04" length="0.1"/></geometry></collision>
  </link>
</robot>"#;

#[test]
fn loose_objects_fall_and_rest_with_density_mass() {
    let mug = RobotModel::from_urdf_str(MUG, None).unwrap();
    let mut world = world();
    let h = world
        .spawn_model(&mug, &Isometry3::translation(0.0, 0.0, 0.5), SpawnOptions::free())
        .unwrap();
    assert_eq!(world.joint_positions(h).unwrap().len(), 0);
    steps(&mut world, 30);
    let p = world.base_pose(h).unwrap();
    assert!((p.translation.z - 0.05).abs() < 5e-3, "{p:?}");
    let body = world.link_body(h, "body").unwrap();
    let mass = world.bodies()[body.handle()].mass();
    let expected = 500.0 * std::f64::consts::PI * 0.04 * 0.04 * 0.1;
    assert!(
        (f64::from(mass) - expected).abs() < 0.05 * expected,
        "{mass} vs {expected}"
    );
    assert_eq!(world.model_name(h).unwrap(), "mug");
    assert_eq!(world.body_name(body), Some("mug/body"));
}

#[test]
fn self_collision_ignores_adjacent_links() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = World::new(WorldConfig {
        gravity: [0.0; 3],
        ..WorldConfig::default()
    })
    .unwrap();
    let opts = SpawnOptions {
        self_collision: true,
        ..SpawnOptions::fixed()
    };
    let arm = world
        .spawn_model(&panda, &Isometry3::translation(0.0, 0.0, 0.03), opts)
        .unwrap();
    world.set_named_configuration(arm, "ready").unwrap();
    steps(&mut world, 30);
    let ready = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    let q = world.joint_positions(arm).unwrap();
    for (a, b) in q.iter().zip(&ready) {
        assert!((a - b).abs() < 1e-2, "adjacent links touch but must not push: {q:?}");
    }
}

#[test]
fn a_slow_velocity_command_keeps_its_joint_moving() {
    // 0.05 rad/s is below the speed at which a body may fall asleep; the motor must not be put
    // to sleep with it.
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = world();
    let arm = world
        .spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    steps(&mut world, 90);
    let q0 = world.joint_positions(arm).unwrap()[0];
    world
        .set_joint_command(arm, "panda_joint1", JointCommand::Velocity { target: 0.05 })
        .unwrap();
    steps(&mut world, 150); // 5 s
    let moved = world.joint_positions(arm).unwrap()[0] - q0;
    assert!((moved - 0.25).abs() < 0.03, "moved {moved:.3} rad in 5 s at 0.05 rad/s");
}
