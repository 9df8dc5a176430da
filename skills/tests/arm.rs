//! The arm motion core: planned motions in physics and kinematically, dry runs, straight-line
//! moves, typed failures.

use hearth_sim::assets::{Asset, Category};
use hearth_sim::kinematics::RobotModel;
use hearth_sim::scene::{SceneFile, SceneObject};
use hearth_sim::world::{JointCommand, ModelHandle, SpawnOptions, World, WorldConfig};
use hearth_skills::arm::{Arm, ArmSettings, ArmTarget, JerkPass, LinearMove};
use hearth_skills::planning::StateValidator;
use hearth_skills::{Execution, SkillError};
use nalgebra::{Isometry3, Point3, Vector3};
use rand::SeedableRng;

const TABLE_X: f64 = 1.05;

/// A table in front of a Fetch bolted 2 cm above the floor.
fn table_scene() -> (World, ModelHandle, f64) {
    let table = Asset::build(Category::Table, 0, 1.0).unwrap();
    let top = table.aabb_max[2];
    let mut scene = SceneFile::empty("table in front of a fetch");
    scene
        .objects
        .push(SceneObject::new("table", "table", 0, [TABLE_X, 0.0, 0.0]));
    let mut world = World::new(WorldConfig::default()).unwrap();
    world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    world.settle(60);
    (world, robot, top)
}

fn rng(seed: u64) -> rand_pcg::Pcg64Mcg {
    rand_pcg::Pcg64Mcg::seed_from_u64(seed)
}

/// The table scene with the Fetch's gripper pointing down `height` above the table top (moved
/// there in physics); returns that pose too.
fn gripper_above_table(height: f64) -> (World, ModelHandle, Arm, Isometry3<f64>) {
    let (mut world, robot, top) = table_scene();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let down = nalgebra::UnitQuaternion::from_euler_angles(0.0, std::f64::consts::FRAC_PI_2, 0.0);
    let above = Isometry3::from_parts(nalgebra::Translation3::new(TABLE_X - 0.3, 0.0, top + height), down);
    arm.move_to(&mut world, &ArmTarget::Pose(above), Execution::Physics, &mut rng(2))
        .unwrap();
    (world, robot, arm, above)
}

#[test]
fn planned_motion_reaches_its_goal_in_physics_and_kinematically() {
    let (mut world, robot, top) = table_scene();
    let snapshot = world.snapshot();
    let target = Point3::new(TABLE_X - 0.3, -0.1, top + 0.25);
    for execution in [Execution::Physics, Execution::Kinematic] {
        world.restore(&snapshot).unwrap();
        let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
        let report = arm
            .move_to(&mut world, &ArmTarget::Position(target), execution, &mut rng(4))
            .unwrap();
        assert!(
            report.executed && report.duration > 0.2 && report.path_length > 0.1,
            "{report:?}"
        );
        let tip = arm.tip_pose(&world).unwrap().translation.vector;
        let err = (tip - target.coords).norm();
        assert!(err < 0.03, "{execution}: the gripper is {err:.3} m from its target");
    }
}

#[test]
fn dry_run_is_deterministic_and_leaves_the_world_alone() {
    let (world, robot, top) = table_scene();
    let arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let hash = world.state_hash();
    let target = ArmTarget::Position(Point3::new(TABLE_X - 0.35, 0.15, top + 0.2));
    let a = arm.plan(&world, &target, &[], &mut rng(9)).unwrap();
    let b = arm.plan(&world, &target, &[], &mut rng(9)).unwrap();
    assert_eq!(a.goal, b.goal);
    assert_eq!(a.report.duration, b.report.duration);
    assert!(!a.report.executed);
    assert_eq!(world.state_hash(), hash);
}

/// Every jerk pass ends where the smoothed motion does; the default moving average is used
/// over an open table (it stays within a millimetre of the checked motion) and lasts only its
/// window longer than the smoothed motion; `Off` keeps the smoothed motion itself.
#[test]
fn each_jerk_pass_plans_the_same_goal() {
    let (world, robot, top) = table_scene();
    let target = ArmTarget::Position(Point3::new(TABLE_X - 0.35, 0.15, top + 0.2));
    let plan = |jerk: JerkPass| {
        let arm = Arm::new(
            &world,
            robot,
            ArmSettings {
                jerk,
                ..ArmSettings::fetch()
            },
        )
        .unwrap();
        arm.plan(&world, &target, &[], &mut rng(9)).unwrap()
    };
    let off = plan(JerkPass::Off);
    let average = plan(JerkPass::Average);
    let ruckig = plan(JerkPass::Waypoints {
        max: Some(8),
        sweeps: 0,
    });
    assert!(!off.report.jerk_limited);
    assert!(average.report.jerk_limited, "{:?}", average.report);
    // The Fetch's window: 2 a / j for every joint, its acceleration scaled by 0.6: 0.06 s.
    let window = average.report.duration - off.report.duration;
    assert!((window - 0.06).abs() < 1e-9, "{window}");
    for p in [&average, &ruckig] {
        assert_eq!(p.goal, off.goal);
        let mut end = vec![0.0; off.goal.len()];
        p.trajectory.sample(p.trajectory.duration(), &mut end, None);
        assert!(end.iter().zip(&off.goal).all(|(a, b)| (a - b).abs() < 1e-6), "{end:?}");
    }
}

#[test]
fn unreachable_and_malformed_goals_are_typed_errors() {
    let (world, robot, top) = table_scene();
    let arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let far = ArmTarget::Position(Point3::new(3.0, 0.0, 1.0));
    let e = arm.plan(&world, &far, &[], &mut rng(1)).unwrap_err();
    assert_eq!(e.reason(), "ik_failed", "{e}");
    let inside = ArmTarget::Position(Point3::new(TABLE_X, 0.0, top - 0.01));
    let e = arm.plan(&world, &inside, &[], &mut rng(1)).unwrap_err();
    assert_eq!(e.reason(), "ik_failed", "{e}");
    let nan = ArmTarget::Position(Point3::new(f64::NAN, 0.0, 1.0));
    assert!(matches!(
        arm.plan(&world, &nan, &[], &mut rng(1)),
        Err(SkillError::BadInput(_))
    ));
    let short = ArmTarget::Joints(vec![0.0; 3]);
    assert!(matches!(
        arm.plan(&world, &short, &[], &mut rng(1)),
        Err(SkillError::BadInput(_))
    ));
}

#[test]
fn straight_line_moves_follow_the_line_and_stop_at_the_table() {
    let (mut world, _, mut arm, above) = gripper_above_table(0.25);
    let top = above.translation.z - 0.25;
    // 10 cm sideways, in free space.
    let side = LinearMove::new(Vector3::y(), 0.1);
    let r = arm.move_linear(&mut world, &side, Execution::Physics).unwrap();
    assert!((r.travelled - 0.1).abs() < 0.015 && !r.stopped_by_force, "{r:?}");
    // Down into the table without checking the world: the force limit stops it.
    let mut press = LinearMove::new(-Vector3::z(), 0.4);
    press.check_world = false;
    press.force_limit = 40.0;
    let r = arm.move_linear(&mut world, &press, Execution::Physics).unwrap();
    assert!(r.stopped_by_force, "{r:?}");
    assert!(r.travelled < 0.3, "{r:?}");
    // Checked against the world, the line is cut short above the table.
    let tip = arm.tip_pose(&world).unwrap().translation.vector;
    let (_, covered) = arm.linear_path(&world, &LinearMove::new(-Vector3::z(), 0.4)).unwrap();
    assert!(covered < tip.z - top, "{covered} vs {}", tip.z - top);
    let bad = LinearMove::new(Vector3::zeros(), 0.1);
    assert!(matches!(
        arm.move_linear(&mut world, &bad, Execution::Physics),
        Err(SkillError::BadInput(_))
    ));
}

#[test]
fn an_arm_pressed_onto_the_table_backs_off_and_plans_from_there() {
    let (mut world, _, mut arm, above) = gripper_above_table(0.2);
    let mut press = LinearMove::new(-Vector3::z(), 0.4);
    press.check_world = false;
    press.force_limit = 40.0;
    assert!(
        arm.move_linear(&mut world, &press, Execution::Physics)
            .unwrap()
            .stopped_by_force
    );
    // The fingers touch the table: the start is not free even without a margin.
    let (_, start) = arm.configuration(&world).unwrap();
    let mut check = arm.validity(&world, &[], 0.0).unwrap();
    assert!(!check.is_valid(&start));
    // The plan backs off to a free configuration close by first, then goes up.
    let plan = arm.plan(&world, &ArmTarget::Pose(above), &[], &mut rng(3)).unwrap();
    let mut first = vec![0.0; start.len()];
    plan.trajectory.sample(0.0, &mut first, None);
    for (a, b) in first.iter().zip(&start) {
        assert!((a - b).abs() < 1e-9, "the plan starts where the arm is");
    }
    let r = arm.execute(&mut world, &plan, Execution::Physics).unwrap();
    assert!(r.executed);
    let tip = arm.tip_pose(&world).unwrap().translation.vector;
    assert!((tip - above.translation.vector).norm() < 0.03, "{tip:?}");
}

/// A pull can leave a link pressed against furniture; the next motion starts there and backs
/// off: what the arm already presses on at the start is not a collision of that motion.
#[test]
fn a_motion_may_start_pressed_against_what_it_leaves() {
    let (mut world, robot, mut arm, above) = gripper_above_table(0.2);
    // Teleported 5 mm deeper than the table top and held there: the fingers press on it.
    let mut into = LinearMove::new(-Vector3::z(), 0.3);
    into.check_world = false;
    let (path, _) = arm.linear_path(&world, &into).unwrap();
    let (mut full, _) = arm.configuration(&world).unwrap();
    let z0 = arm.tip_pose(&world).unwrap().translation.z;
    for q in &path {
        arm.chain().scatter(q, &mut full);
        world.reset_configuration(robot, &full).unwrap();
        if arm.tip_pose(&world).unwrap().translation.z < z0 - 0.205 {
            break;
        }
    }
    let names = world.model(robot).unwrap().variable_names().to_vec();
    for &i in arm.chain().variables() {
        let hold = JointCommand::Position { target: full[i] };
        world.set_joint_command(robot, &names[i], hold).unwrap();
    }
    world.step();
    let pressing = world
        .contacts(robot)
        .unwrap()
        .into_iter()
        .filter(|c| c.other_name.starts_with("table") && c.force.norm() > arm.settings().contact_force)
        .count();
    assert!(pressing > 0, "the fingers press on the table");
    let plan = arm.plan(&world, &ArmTarget::Pose(above), &[], &mut rng(3)).unwrap();
    let r = arm.execute(&mut world, &plan, Execution::Physics).unwrap();
    assert!(r.executed);
    let tip = arm.tip_pose(&world).unwrap().translation.vector;
    assert!((tip - above.translation.vector).norm() < 0.03, "{tip:?}");
}

#[test]
fn an_obstacle_appearing_after_planning_is_reported_as_a_collision() {
    let (mut world, robot, top) = table_scene();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let target = Point3::new(TABLE_X - 0.3, -0.1, top + 0.25);
    let plan = arm
        .plan(&world, &ArmTarget::Position(target), &[], &mut rng(4))
        .unwrap();
    // A crate dropped where the gripper is going, after the plan was made.
    world
        .add_box(
            "crate",
            [0.08, 0.08, 0.08],
            &Isometry3::translation(target.x, target.y, target.z),
            false,
        )
        .unwrap();
    let e = arm.execute(&mut world, &plan, Execution::Physics).unwrap_err();
    assert_eq!(e.reason(), "collision", "{e}");
    assert!(e.to_string().contains("crate"), "{e}");
}

#[test]
fn a_free_base_fetch_on_the_floor_moves_its_arm_too() {
    let mut world = World::new(WorldConfig::default()).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.01), SpawnOptions::free())
        .unwrap();
    world.tuck(robot).unwrap();
    world.settle(90);
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let base = world.base_pose(robot).unwrap();
    let target = base * Point3::new(0.6, 0.2, 0.9);
    arm.move_to(
        &mut world,
        &ArmTarget::Position(target),
        Execution::Physics,
        &mut rng(6),
    )
    .unwrap();
    let tip = arm.tip_pose(&world).unwrap().translation.vector;
    assert!((tip - target.coords).norm() < 0.04, "{tip:?} vs {target:?}");
}
