//! Push at a pixel: a Fetch in front of a kitchen cabinet whose top drawer is open pushes the
//! drawer front it sees and closes the drawer; bad pixels are typed errors.

use hearth_sim::kinematics::RobotModel;
use hearth_sim::scene::{Orientation, SceneFile, SceneObject};
use hearth_sim::sensors::{Backend, Camera, CameraConfig, Preset};
use hearth_sim::world::{JointCommand, ModelHandle, SpawnOptions, World, WorldConfig};
use hearth_skills::arm::{Arm, ArmSettings};
use hearth_skills::push::{PushSettings, push_at_pixel};
use hearth_skills::{Execution, SkillError};
use nalgebra::{Isometry3, Point3};
use rand::SeedableRng;

/// Where the cabinet's centre stands (its front faces the robot).
const CABINET_X: f64 = 1.3;
const DRAWER: &str = "drawer_2";
const OPEN: f64 = 0.25;

fn cabinet_scene() -> (World, ModelHandle, ModelHandle) {
    let mut scene = SceneFile::empty("open drawer in front of a fetch");
    let mut cabinet = SceneObject::new("cabinet", "bottom_cabinet", 1, [CABINET_X, 0.0, 0.0]);
    cabinet.orientation = Orientation::Yaw(std::f64::consts::PI);
    cabinet.fixed = true;
    cabinet.joints.insert(format!("{DRAWER}_slide"), OPEN);
    scene.objects.push(cabinet);
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    // Spawned models hold every joint with a position motor; furniture runners are passive.
    let cabinet = loaded.object("cabinet").unwrap();
    let joints = world.model(cabinet).unwrap().variable_names().to_vec();
    for joint in &joints {
        world.set_joint_command(cabinet, joint, JointCommand::Off).unwrap();
    }
    world.settle(60);
    (world, robot, cabinet)
}

fn camera(world: &World, robot: ModelHandle) -> Camera {
    let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    config.backend = Backend::Raycast;
    Camera::new(world, Some(robot), config).unwrap()
}

fn drawer_opening(world: &World, cabinet: ModelHandle) -> f64 {
    let model = world.model(cabinet).unwrap();
    let v = model
        .variable_names()
        .iter()
        .position(|n| *n == format!("{DRAWER}_slide"))
        .unwrap();
    world.joint_positions(cabinet).unwrap()[v]
}

/// The pixel where the camera sees the centre of the drawer front.
fn drawer_pixel(world: &World, camera: &Camera, cabinet: ModelHandle) -> (i64, i64) {
    let front = world.link_pose(cabinet, DRAWER).unwrap() * Point3::new(0.02, 0.0, -0.03);
    let in_camera = camera.pose(world).unwrap().inverse() * front;
    let (u, v) = camera.config().intrinsics.project(&in_camera).unwrap();
    (u.floor() as i64, v.floor() as i64)
}

#[test]
fn pushing_the_open_drawer_front_closes_the_drawer() {
    let (mut world, robot, cabinet) = cabinet_scene();
    assert!((drawer_opening(&world, cabinet) - OPEN).abs() < 0.01);
    let mut cam = camera(&world, robot);
    let (u, v) = drawer_pixel(&world, &cam, cabinet);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);

    // A dry run plans the approach and moves nothing.
    let hash = world.state_hash();
    let dry = PushSettings {
        dry_run: true,
        ..Default::default()
    };
    let plan = push_at_pixel(&mut world, &mut arm, &mut cam, u, v, &dry, Execution::Physics, &mut rng).unwrap();
    assert!(plan.push.is_none() && plan.approach.duration > 0.0);
    assert!(
        plan.normal.x < -0.9,
        "the drawer front faces the robot: {:?}",
        plan.normal
    );
    assert_eq!(world.state_hash(), hash);

    let report = push_at_pixel(
        &mut world,
        &mut arm,
        &mut cam,
        u,
        v,
        &PushSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    let open = drawer_opening(&world, cabinet);
    assert!(report.moved > 0.15, "{report:?}");
    assert!(open < 0.08, "the drawer is still {open:.3} m open: {report:?}");
    let push = report.push.unwrap();
    assert!(push.travelled > 0.15 && !push.stopped_by_force, "{push:?}");
}

#[test]
fn bad_pixels_are_typed_errors() {
    let (mut world, robot, _) = cabinet_scene();
    let mut cam = camera(&world, robot);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let s = PushSettings::default();
    for (u, v) in [(-1, 10), (10, 128), (500, 500)] {
        let e = push_at_pixel(&mut world, &mut arm, &mut cam, u, v, &s, Execution::Physics, &mut rng).unwrap_err();
        assert!(matches!(e, SkillError::BadInput(_)), "{e}");
    }
    // The top row looks over everything: nothing there.
    let e = push_at_pixel(&mut world, &mut arm, &mut cam, 64, 0, &s, Execution::Physics, &mut rng).unwrap_err();
    assert!(matches!(e, SkillError::BadInput(_)), "{e}");
    // The floor far to the side is out of reach.
    let bad = PushSettings {
        distance: f64::NAN,
        ..Default::default()
    };
    let e = push_at_pixel(
        &mut world,
        &mut arm,
        &mut cam,
        64,
        64,
        &bad,
        Execution::Physics,
        &mut rng,
    )
    .unwrap_err();
    assert!(matches!(e, SkillError::BadInput(_)), "{e}");
}

#[test]
fn a_drawer_held_by_its_motor_stops_the_push_at_the_force_limit() {
    let (mut world, robot, cabinet) = cabinet_scene();
    world
        .set_joint_command(
            cabinet,
            &format!("{DRAWER}_slide"),
            JointCommand::Position { target: OPEN },
        )
        .unwrap();
    let mut cam = camera(&world, robot);
    let (u, v) = drawer_pixel(&world, &cam, cabinet);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let e = push_at_pixel(
        &mut world,
        &mut arm,
        &mut cam,
        u,
        v,
        &PushSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap_err();
    assert_eq!(e.reason(), "no_effect", "{e}");
    assert!((drawer_opening(&world, cabinet) - OPEN).abs() < 0.05);
}

#[test]
fn kinematic_execution_closes_the_drawer_too() {
    let (mut world, robot, cabinet) = cabinet_scene();
    let mut cam = camera(&world, robot);
    let (u, v) = drawer_pixel(&world, &cam, cabinet);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let report = push_at_pixel(
        &mut world,
        &mut arm,
        &mut cam,
        u,
        v,
        &PushSettings::default(),
        Execution::Kinematic,
        &mut rng,
    )
    .unwrap();
    let open = drawer_opening(&world, cabinet);
    assert!(open < 0.1, "the drawer is still {open:.3} m open: {report:?}");
}

#[test]
fn the_same_seed_gives_the_same_push() {
    let (mut world, robot, cabinet) = cabinet_scene();
    let start = world.snapshot();
    let mut hashes = Vec::new();
    for _ in 0..2 {
        world.restore(&start).unwrap();
        let mut cam = camera(&world, robot);
        let (u, v) = drawer_pixel(&world, &cam, cabinet);
        let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        push_at_pixel(
            &mut world,
            &mut arm,
            &mut cam,
            u,
            v,
            &PushSettings::default(),
            Execution::Physics,
            &mut rng,
        )
        .unwrap();
        hashes.push(world.state_hash());
    }
    assert_eq!(hashes[0], hashes[1]);
}
