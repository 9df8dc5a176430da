//! Opening and closing: a Fetch pulls a kitchen cabinet's top drawer open by the handle and
//! pushes it closed again; bad joints are typed errors.

use hearth_sim::kinematics::RobotModel;
use hearth_sim::scene::{Orientation, SceneFile, SceneObject};
use hearth_sim::world::{JointCommand, ModelHandle, SpawnOptions, World, WorldConfig};
use hearth_skills::arm::{Arm, ArmSettings};
use hearth_skills::articulated::{ArticulatedSettings, close, open};
use hearth_skills::{Execution, SkillError};
use nalgebra::Isometry3;
use rand::SeedableRng;

const CABINET_X: f64 = 1.3;
const JOINT: &str = "drawer_2_slide";

/// A three-drawer kitchen cabinet facing a Fetch; its drawers run freely (spawned models hold
/// their joints with motors, furniture runners are passive).
fn cabinet_scene(opening: f64) -> (World, ModelHandle, ModelHandle) {
    let mut scene = SceneFile::empty("cabinet in front of a fetch");
    let mut cabinet = SceneObject::new("cabinet", "bottom_cabinet", 1, [CABINET_X, 0.0, 0.0]);
    cabinet.orientation = Orientation::Yaw(std::f64::consts::PI);
    cabinet.fixed = true;
    cabinet.joints.insert(JOINT.into(), opening);
    scene.objects.push(cabinet);
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    let cabinet = loaded.object("cabinet").unwrap();
    let joints = world.model(cabinet).unwrap().variable_names().to_vec();
    for joint in &joints {
        world.set_joint_command(cabinet, joint, JointCommand::Off).unwrap();
    }
    world.settle(60);
    (world, robot, cabinet)
}

fn drawer(world: &World, cabinet: ModelHandle) -> f64 {
    let model = world.model(cabinet).unwrap();
    let v = model.variable_names().iter().position(|n| n == JOINT).unwrap();
    world.joint_positions(cabinet).unwrap()[v]
}

#[test]
fn the_fetch_pulls_the_drawer_open_by_its_handle() {
    let (mut world, robot, cabinet) = cabinet_scene(0.0);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let s = ArticulatedSettings::default();
    let hash = world.state_hash();
    let dry = ArticulatedSettings {
        dry_run: true,
        ..s.clone()
    };
    let plan = open(
        &mut world,
        &mut arm,
        cabinet,
        JOINT,
        0.25,
        &dry,
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    assert!(plan.motion.is_none() && world.state_hash() == hash);
    // The handle is on the drawer front, facing the robot: the gripper approaches along +x.
    assert!((plan.grasp.rotation * nalgebra::Vector3::x()).x > 0.99, "{plan:?}");

    let r = open(
        &mut world,
        &mut arm,
        cabinet,
        JOINT,
        0.25,
        &s,
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    let opened = drawer(&world, cabinet);
    assert!(opened >= 0.15, "the drawer opened {opened:.3} m: {r:?}");
    assert!((r.end - opened).abs() < 0.02);
}

#[test]
fn the_fetch_closes_an_open_drawer_by_its_handle() {
    let (mut world, robot, cabinet) = cabinet_scene(0.25);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let r = close(
        &mut world,
        &mut arm,
        cabinet,
        JOINT,
        0.2,
        &ArticulatedSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    let now = drawer(&world, cabinet);
    assert!(now < 0.13, "the drawer is still {now:.3} m open: {r:?}");
}

#[test]
fn bad_joints_are_typed_errors() {
    let (mut world, robot, cabinet) = cabinet_scene(0.0);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let s = ArticulatedSettings::default();
    for (joint, amount) in [("no_such_joint", 0.2), (JOINT, -0.2), (JOINT, f64::NAN)] {
        let e = open(
            &mut world,
            &mut arm,
            cabinet,
            joint,
            amount,
            &s,
            Execution::Physics,
            &mut rng,
        )
        .unwrap_err();
        assert!(matches!(e, SkillError::BadInput(_)), "{joint} {amount}: {e}");
    }
    // Already closed: nothing to close.
    let e = close(
        &mut world,
        &mut arm,
        cabinet,
        JOINT,
        0.2,
        &s,
        Execution::Physics,
        &mut rng,
    )
    .unwrap_err();
    assert!(matches!(e, SkillError::BadInput(_)), "{e}");
}

#[test]
fn the_fetch_swings_a_cabinet_door_open_along_its_arc() {
    let mut scene = SceneFile::empty("two-door cabinet in front of a fetch");
    // Closer than the drawer cabinet: the handle sits lower, and the leaf swings towards the robot.
    let mut cabinet = SceneObject::new("cabinet", "bottom_cabinet", 0, [CABINET_X - 0.2, 0.0, 0.0]);
    cabinet.orientation = Orientation::Yaw(std::f64::consts::PI);
    cabinet.fixed = true;
    scene.objects.push(cabinet);
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    let cabinet = loaded.object("cabinet").unwrap();
    let joints = world.model(cabinet).unwrap().variable_names().to_vec();
    for joint in &joints {
        world.set_joint_command(cabinet, joint, JointCommand::Off).unwrap();
    }
    world.settle(60);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let r = open(
        &mut world,
        &mut arm,
        cabinet,
        "door_0_hinge",
        0.8,
        &ArticulatedSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    assert!(r.end > 0.5, "{r:?}");
    let model = world.model(cabinet).unwrap();
    let v = model.variable_names().iter().position(|n| n == "door_0_hinge").unwrap();
    assert!(world.joint_positions(cabinet).unwrap()[v] > 0.5);
}

#[test]
fn kinematic_execution_opens_the_drawer_too() {
    let (mut world, robot, cabinet) = cabinet_scene(0.0);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let r = open(
        &mut world,
        &mut arm,
        cabinet,
        JOINT,
        0.25,
        &ArticulatedSettings::default(),
        Execution::Kinematic,
        &mut rng,
    )
    .unwrap();
    assert!(drawer(&world, cabinet) >= 0.15, "{r:?}");
}
