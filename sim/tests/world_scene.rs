//! Scenes in the physics world: a generated home loads, settles and stays put; loading is
//! deterministic; bad scenes are refused without touching the world.

use hearth_sim::kinematics::{JointKind, RobotModel};
use hearth_sim::scene::{GenerateOptions, RobotPlacement, SceneFile, SceneObject, generate};
use hearth_sim::world::{BUILDING_PREFIX, LoadSceneError, LoadedScene, World, WorldConfig};

/// Control steps allowed for settling (10 s of simulated time).
const SETTLE_STEPS: usize = 300;

fn home() -> SceneFile {
    generate(&GenerateOptions {
        seed: 1,
        rooms: 3,
        ..Default::default()
    })
    .unwrap()
}

/// Bodies a model becomes: its root plus one per movable joint (fixed joints merge links),
/// plus the mount its multibody hangs from when it is an object whose links move (see
/// `World::spawn_model`); robots keep their root in the multibody.
fn body_groups(model: &RobotModel, is_robot: bool) -> usize {
    let moving = model.joints().iter().filter(|j| j.kind != JointKind::Fixed).count();
    let mount = usize::from(moving > 0 && !is_robot);
    1 + moving + mount
}

fn loaded_home() -> (SceneFile, World, LoadedScene) {
    let scene = home();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    (scene, world, loaded)
}

#[test]
fn generated_home_loads_settles_and_stays_above_the_floor() {
    let (scene, mut world, loaded) = loaded_home();
    assert_eq!(loaded.objects.len(), scene.objects.len());
    let robot = loaded.robot.expect("the generated home places a Fetch");
    assert_eq!(world.model_name(robot).unwrap(), "fetch");

    // Body count: ground, building pieces, every object's and the robot's link groups.
    let walls: usize = scene.building.walls.iter().map(|w| w.pieces().len()).sum();
    // Floors at z = 0 are the world's ground plane; ceilings and other floors are spawned.
    let raised = scene.building.floors.iter().filter(|f| f.z != 0.0).count();
    let slabs = raised + scene.building.ceilings.len();
    assert_eq!(loaded.building.len(), walls + slabs);
    let model_bodies: usize = loaded
        .models()
        .map(|m| body_groups(world.model(m).unwrap(), Some(m) == loaded.robot))
        .sum();
    assert_eq!(world.body_count(), 1 + walls + slabs + model_bodies);
    for &b in &loaded.building {
        assert!(world.body_name(b).unwrap().starts_with(BUILDING_PREFIX));
    }

    let report = world.settle(SETTLE_STEPS);
    // Nearly everything falls asleep; a few small objects may keep rocking on their shelves.
    let awake = report.dynamic_bodies - report.sleeping_bodies;
    assert!(
        awake * 50 <= report.dynamic_bodies,
        "the home did not come to rest: {report:?}"
    );
    assert!(report.max_linear_speed < 0.5, "something is still flying: {report:?}");
    // The robot stands still: only its own bodies count here.
    let robot_speed = world.base_twist(robot).unwrap().linear.norm();
    assert!(robot_speed < 0.02, "the robot still moves at {robot_speed} m/s");
    for o in scene.objects.iter().filter(|o| !o.fixed) {
        let handle = loaded.object(&o.name).unwrap();
        let z = world.base_pose(handle).unwrap().translation.z;
        assert!(z > -0.05, "`{}` fell through the floor: z = {z}", o.name);
        // Furniture and objects stay near where the scene put them.
        let p = world.base_pose(handle).unwrap().translation.vector;
        let moved = ((p.x - o.position[0]).powi(2) + (p.y - o.position[1]).powi(2)).sqrt();
        assert!(moved < 0.5, "`{}` drifted {moved:.2} m while settling", o.name);
    }
    let base = world.base_pose(robot).unwrap().translation.z;
    assert!(base > -0.05, "the robot sank: z = {base}");

    // The robot drives in its settled home.
    world.drive(robot, 0.3, 0.0).unwrap();
    let x0 = world.base_pose(robot).unwrap().translation.x;
    for _ in 0..30 {
        world.step();
    }
    let dx = world.base_pose(robot).unwrap().translation.x - x0;
    assert!(dx > 0.15, "the Fetch drove only {dx:.3} m in 1 s at 0.3 m/s");
}

#[test]
fn loading_and_settling_is_deterministic() {
    let run = || {
        let (_, mut world, _) = loaded_home();
        let loaded_hash = world.state_hash();
        world.settle(60);
        (loaded_hash, world.state_hash())
    };
    assert_eq!(run(), run());
}

#[test]
fn initial_joint_positions_and_bases_follow_the_scene() {
    let scene = home();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let door = scene
        .objects
        .iter()
        .find(|o| o.category == "door")
        .expect("homes have doors");
    let handle = loaded.object(&door.name).unwrap();
    let model = world.model(handle).unwrap().clone();
    let q = world.joint_positions(handle).unwrap();
    for (joint, &value) in &door.joints {
        let v = model.variable_names().iter().position(|n| n == joint).unwrap();
        assert!((q[v] - value).abs() < 1e-4, "{joint}: {} != {value}", q[v]);
    }
    // A fixed object does not move even when pushed by gravity for a while.
    let before = world.base_pose(handle).unwrap();
    for _ in 0..10 {
        world.step();
    }
    let after = world.base_pose(handle).unwrap();
    assert!((before.translation.vector - after.translation.vector).norm() < 1e-6);
}

#[test]
fn bad_scenes_leave_the_world_unchanged() {
    let mut world = World::new(WorldConfig::default()).unwrap();
    let mut ok = SceneFile::empty("ok");
    ok.objects.push(SceneObject::new("table", "table", 0, [0.0, 0.0, 0.0]));
    world.load_scene(&ok).unwrap();
    let bodies = world.body_count();
    let hash = world.state_hash();
    let models = world.models().count();

    let mut unknown = SceneFile::empty("typo");
    unknown.objects.push(SceneObject::new("t", "tabel", 0, [3.0, 0.0, 0.0]));
    let mut overlap = SceneFile::empty("overlap");
    overlap.objects.push(SceneObject::new("a", "table", 0, [3.0, 0.0, 0.0]));
    overlap.objects.push(SceneObject::new("b", "table", 0, [3.2, 0.0, 0.0]));
    let mut joint = SceneFile::empty("joint");
    let mut fridge = SceneObject::new("f", "fridge", 0, [3.0, 0.0, 0.0]);
    fridge.joints.insert("no_such_hinge".into(), 0.3);
    joint.objects.push(fridge);
    let mut nan = SceneFile::empty("nan");
    nan.objects.push(SceneObject::new("m", "mug", 0, [f64::NAN, 0.0, 0.0]));
    let mut robot = SceneFile::empty("robot");
    robot
        .objects
        .push(SceneObject::new("chair", "chair", 0, [3.0, 0.0, 0.0]));
    robot.robot = Some(RobotPlacement {
        name: "fetchh".into(),
        position: [5.0, 0.0, 0.0],
        yaw: 0.0,
    });

    for (scene, needle) in [
        (&unknown, "tabel"),
        (&overlap, "overlap"),
        (&joint, "no_such_hinge"),
        (&nan, "not a finite"),
        (&robot, "fetchh"),
    ] {
        let err = world.load_scene(scene).unwrap_err();
        assert!(err.to_string().contains(needle), "{}: {err}", scene.name);
        if scene.name == "robot" {
            assert!(matches!(err, LoadSceneError::UnknownRobot { .. }));
        } else {
            assert!(matches!(err, LoadSceneError::Scene(_)));
        }
        assert_eq!(world.body_count(), bodies);
        assert_eq!(world.models().count(), models);
        assert_eq!(world.state_hash(), hash);
    }
}

/// Drawers and vertical-hinge doors of loaded furniture are free: no controller holds them, a
/// reset to a new opening keeps them free, and they stay where they were left. The dishwasher's
/// door, which gravity would swing down, stays held.
#[test]
fn furniture_drawers_are_passive_and_gravity_loaded_doors_are_held() {
    use hearth_sim::world::JointCommand;
    let mut scene = SceneFile::empty("cabinet and dishwasher");
    scene
        .objects
        .push(SceneObject::new("cabinet", "bottom_cabinet", 1, [0.0, 0.0, 0.0]));
    scene
        .objects
        .push(SceneObject::new("dishwasher", "dishwasher", 0, [2.0, 0.0, 0.0]));
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let cabinet = loaded.object("cabinet").unwrap();
    let model = world.model(cabinet).unwrap().clone();
    let names = model.variable_names().to_vec();
    let commands = world.joint_commands(cabinet).unwrap().to_vec();
    let drawers: Vec<usize> = (0..names.len())
        .filter(|&v| {
            model
                .joints()
                .iter()
                .any(|j| j.variable == Some(v) && j.kind == JointKind::Prismatic)
        })
        .collect();
    assert!(!drawers.is_empty(), "bottom cabinet 1 has drawers: {names:?}");
    for &v in &drawers {
        assert_eq!(commands[v], JointCommand::Off, "drawer joint {}", names[v]);
    }
    let mut q = world.joint_positions(cabinet).unwrap();
    let v = drawers[0];
    q[v] = (model.lower()[v] + model.upper()[v]) / 2.0;
    world.reset_configuration(cabinet, &q).unwrap();
    assert_eq!(world.joint_commands(cabinet).unwrap()[v], JointCommand::Off);
    for _ in 0..60 {
        world.step();
    }
    let after = world.joint_positions(cabinet).unwrap()[v];
    assert!(
        (after - q[v]).abs() < 0.01,
        "the drawer stayed at {} (moved to {after})",
        q[v]
    );

    let dishwasher = loaded.object("dishwasher").unwrap();
    let held = world.joint_commands(dishwasher).unwrap();
    assert!(
        held.iter().any(|c| matches!(c, JointCommand::Position { .. })),
        "the dishwasher door is held: {held:?}"
    );
}
