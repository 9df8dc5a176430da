//! The navigate skill on small fixed scenes with the Fetch: an open room, two rooms joined
//! by a doorway with an open door, an obstacle that is not on the map; failures that must
//! leave the world untouched; reproducibility.

use std::f64::consts::FRAC_PI_2;

use hearth_sim::assets::RoomType;
use hearth_sim::scene::{
    MapOptions, Opening, OpeningKind, RobotPlacement, Room, SceneFile, SceneMaps, SceneObject, Wall,
};
use hearth_sim::world::{ModelHandle, World, WorldConfig};
use hearth_skills::Execution;
use hearth_skills::navigate::{
    BaseFootprint, FootprintValidity, NavigateReport, NavigateSettings, Navigator, navigate,
};
use hearth_skills::{SkillError, SkillResult};
use nalgebra::Isometry3;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

const WALL_H: f64 = 2.5;
const WALL_T: f64 = 0.12;

fn room(name: &str, x0: f64, x1: f64, y1: f64) -> Room {
    Room {
        name: name.into(),
        room_type: RoomType::Office,
        polygon: vec![[x0, 0.0], [x1, 0.0], [x1, y1], [x0, y1]],
    }
}

/// Outer walls of the rectangle [0, x1] × [0, y1].
fn outer_walls(x1: f64, y1: f64) -> Vec<Wall> {
    vec![
        Wall::new("south", [0.0, 0.0], [x1, 0.0], WALL_H, WALL_T),
        Wall::new("north", [0.0, y1], [x1, y1], WALL_H, WALL_T),
        Wall::new("west", [0.0, 0.0], [0.0, y1], WALL_H, WALL_T),
        Wall::new("east", [x1, 0.0], [x1, y1], WALL_H, WALL_T),
    ]
}

/// One 5 × 4 m room with the Fetch at (1, 2).
fn open_room() -> SceneFile {
    let mut s = SceneFile::empty("open room");
    s.building.rooms.push(room("office", 0.0, 5.0, 4.0));
    s.building.walls = outer_walls(5.0, 4.0);
    s.robot = Some(RobotPlacement {
        name: "fetch".into(),
        position: [1.0, 2.0, 0.0],
        yaw: 0.0,
    });
    s
}

/// Two 4 × 3 m rooms side by side, split at x = 4 by a wall with a 1 m doorway at y = 1.5
/// holding an open door (or no doorway at all), the Fetch at (1.5, 1.5) in the west room.
fn two_rooms(doorway: bool) -> SceneFile {
    let mut s = SceneFile::empty("two rooms");
    s.building.rooms.push(room("west_room", 0.0, 4.0, 3.0));
    s.building.rooms.push(room("east_room", 4.0, 8.0, 3.0));
    s.building.walls = outer_walls(8.0, 3.0);
    let mut split = Wall::new("split", [4.0, 0.0], [4.0, 3.0], WALL_H, WALL_T);
    if doorway {
        split.openings.push(Opening {
            kind: OpeningKind::Door,
            center: 1.5,
            width: 1.0,
            bottom: 0.0,
            height: 2.1,
        });
        let mut door = SceneObject::new("door", "door", 2, [4.0, 1.5, 0.0]);
        door.fixed = true;
        door.joints.insert("leaf_hinge".into(), 1.45);
        s.objects.push(door);
    }
    s.building.walls.push(split);
    s.robot = Some(RobotPlacement {
        name: "fetch".into(),
        position: [1.5, 1.5, 0.0],
        yaw: 0.0,
    });
    s
}

/// The world of a scene with its robot settled, and the scene's maps for the Fetch.
fn load(scene: &SceneFile) -> (World, ModelHandle, SceneMaps) {
    let mut world = World::new(WorldConfig::default()).unwrap();
    let fetch = world.load_scene(scene).unwrap().robot.unwrap();
    world.settle(120);
    let maps = SceneMaps::build(
        scene,
        &MapOptions {
            robot_radius: 0.38,
            ..Default::default()
        },
    )
    .unwrap();
    (world, fetch, maps)
}

fn run(
    world: &mut World,
    robot: ModelHandle,
    maps: &SceneMaps,
    goal: [f64; 3],
    execution: Execution,
    seed: u64,
) -> SkillResult<NavigateReport> {
    let settings = NavigateSettings {
        execution,
        ..Default::default()
    };
    navigate(world, robot, maps, goal, &settings, &mut Pcg64Mcg::seed_from_u64(seed))
}

fn assert_reached(world: &World, robot: ModelHandle, goal: [f64; 3], r: &NavigateReport) {
    let p = world.base_pose(robot).unwrap();
    let yaw = p.rotation.euler_angles().2;
    let e_pos = (p.translation.x - goal[0]).hypot(p.translation.y - goal[1]);
    let e_yaw = hearth_sim::kinematics::wrap_angle(yaw - goal[2]).abs();
    assert!(
        e_pos <= 0.1 && e_yaw <= 0.1,
        "ended {e_pos:.3} m / {e_yaw:.3} rad off: {r:?}"
    );
    assert!((r.position_error - e_pos).abs() < 1e-9 && (r.yaw_error - e_yaw).abs() < 1e-9);
}

#[test]
fn reaches_a_goal_in_the_open() {
    let (mut world, fetch, maps) = load(&open_room());
    let goal = [3.8, 3.0, FRAC_PI_2];
    let r = run(&mut world, fetch, &maps, goal, Execution::Physics, 1).unwrap();
    assert_reached(&world, fetch, goal, &r);
    let straight = (3.8f64 - 1.0).hypot(1.0);
    assert!(r.distance > straight - 0.15 && r.distance < straight + 1.0, "{r:?}");
    assert_eq!((r.replans, r.refined_segments), (0, 0), "{r:?}");
    assert!(r.sim_time > straight / 0.4, "{r:?}");
}

#[test]
fn the_turtlebot_drives_too() {
    let mut scene = open_room();
    scene.robot.as_mut().unwrap().name = "turtlebot".into();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let bot = world.load_scene(&scene).unwrap().robot.unwrap();
    world.settle(120);
    let small = MapOptions {
        robot_radius: 0.3,
        ..Default::default()
    };
    let maps = SceneMaps::build(&scene, &small).unwrap();
    let goal = [3.5, 1.0, -FRAC_PI_2];
    let r = run(&mut world, bot, &maps, goal, Execution::Physics, 12).unwrap();
    assert_reached(&world, bot, goal, &r);
}

#[test]
fn drives_through_a_doorway_into_the_next_room() {
    let (mut world, fetch, maps) = load(&two_rooms(true));
    let goal = [6.5, 1.2, 0.0];
    let r = run(&mut world, fetch, &maps, goal, Execution::Physics, 2).unwrap();
    assert_reached(&world, fetch, goal, &r);
    assert!(r.distance > 4.5, "{r:?}");
    assert_eq!(r.replans, 0, "{r:?}");
    // The door stayed where it was (the base never shoved it).
    let door = world
        .models()
        .find(|&m| world.model_name(m).unwrap() == "door")
        .unwrap();
    let leaf = world.joint_positions(door).unwrap()[0];
    assert!((leaf - 1.45).abs() < 0.05, "door leaf at {leaf}");
}

#[test]
fn kinematic_execution_teleports_through_the_doorway() {
    let (mut world, fetch, maps) = load(&two_rooms(true));
    let goal = [6.5, 1.2, -FRAC_PI_2];
    let t0 = world.time();
    let r = run(&mut world, fetch, &maps, goal, Execution::Kinematic, 3).unwrap();
    assert_reached(&world, fetch, goal, &r);
    assert!(r.position_error < 1e-6 && r.yaw_error < 1e-6, "{r:?}");
    assert_eq!(world.time(), t0, "kinematic execution does not step");
    assert!(r.steps > 100 && (r.distance - r.plan.length).abs() < 1e-9, "{r:?}");
    // Every pose of the plan was checked: the base's footprint is free at the goal.
    let fp = BaseFootprint::for_builtin("fetch").unwrap();
    let plan_again = Navigator::new(NavigateSettings::default())
        .unwrap()
        .plan(&world, fetch, &maps, goal, &mut Pcg64Mcg::seed_from_u64(0))
        .unwrap();
    assert!(plan_again.length < 0.05 + fp.radius, "{plan_again:?}");
    // The planner sees the door: a base centred in its frame post touches it.
    let view = world.obstacles_view(&[fetch]).unwrap();
    let check = FootprintValidity::new(view, fp);
    let what = check.touching(&[4.0, 1.0, 0.0]).unwrap();
    assert!(what.starts_with("door") || what.contains("split"), "{what}");
    assert!(check.touching(&[4.0, 1.5, 0.0]).is_none());
}

#[test]
fn avoids_an_obstacle_that_is_not_on_the_map() {
    let (mut world, fetch, maps) = load(&open_room());
    // A crate in the way, added to the world only: the map thinks the line is free.
    world
        .add_box("crate", [0.3, 0.3, 0.4], &Isometry3::translation(2.5, 2.0, 0.4), false)
        .unwrap();
    let goal = [4.0, 2.0, 0.0];
    let r = run(&mut world, fetch, &maps, goal, Execution::Physics, 4).unwrap();
    assert_reached(&world, fetch, goal, &r);
    assert!(r.refined_segments >= 1, "{r:?}");
    assert!(r.distance > 3.1, "went around, not through: {r:?}");
    let min_clear = r
        .plan
        .poses
        .iter()
        .map(|p| (p[0] - 2.5).abs().max((p[1] - 2.0).abs()))
        .fold(f64::INFINITY, f64::min);
    assert!(min_clear > 0.3, "the plan keeps the base off the crate: {min_clear}");
}

#[test]
fn a_crate_that_falls_into_the_way_after_planning_makes_it_replan() {
    let (mut world, fetch, maps) = load(&open_room());
    // High above the straight path when the plan is made (above the footprint), on the
    // floor in the way by the time the base gets there; far too heavy to shove.
    world
        .add_box("crate", [0.3, 0.3, 0.3], &Isometry3::translation(2.6, 2.0, 2.5), true)
        .unwrap();
    let goal = [4.2, 2.0, 0.0];
    let r = run(&mut world, fetch, &maps, goal, Execution::Physics, 13).unwrap();
    assert_reached(&world, fetch, goal, &r);
    assert!(r.replans >= 1 && r.refined_segments >= 1, "{r:?}");
}

#[test]
fn unreachable_goals_fail_and_change_nothing() {
    // Inside the split wall, and in a room with no doorway.
    let (mut world, fetch, maps) = load(&two_rooms(false));
    let before = world.state_hash();
    for goal in [[4.0, 1.5, 0.0], [6.0, 1.5, 0.0], [50.0, 1.0, 0.0]] {
        for execution in [Execution::Physics, Execution::Kinematic] {
            let err = run(&mut world, fetch, &maps, goal, execution, 5).unwrap_err();
            assert!(matches!(err, SkillError::Unreachable(_)), "{goal:?}: {err}");
            assert_eq!(err.reason(), "unreachable");
            assert_eq!(world.state_hash(), before, "{goal:?}");
        }
    }
    // A goal where the base would overlap a crate that is not on the map.
    world
        .add_box("crate", [0.3, 0.3, 0.3], &Isometry3::translation(2.5, 1.5, 0.3), false)
        .unwrap();
    let before = world.state_hash();
    let err = run(&mut world, fetch, &maps, [2.6, 1.5, 0.0], Execution::Physics, 5).unwrap_err();
    assert!(err.to_string().contains("crate"), "{err}");
    assert_eq!(err.reason(), "unreachable");
    assert_eq!(world.state_hash(), before);
}

#[test]
fn bad_input_is_refused_before_anything_moves() {
    let (mut world, fetch, maps) = load(&open_room());
    let before = world.state_hash();
    for goal in [[f64::NAN, 1.0, 0.0], [1.0, f64::INFINITY, 0.0], [2.0, 2.0, f64::NAN]] {
        let err = run(&mut world, fetch, &maps, goal, Execution::Physics, 6).unwrap_err();
        assert_eq!(err.reason(), "bad_input", "{err}");
    }
    let bad = NavigateSettings {
        position_tolerance: 0.0,
        ..Default::default()
    };
    let err = navigate(
        &mut world,
        fetch,
        &maps,
        [3.0, 2.0, 0.0],
        &bad,
        &mut Pcg64Mcg::seed_from_u64(0),
    )
    .unwrap_err();
    assert!(err.to_string().contains("position_tolerance"), "{err}");
    assert_eq!(world.state_hash(), before);
}

#[test]
fn a_closed_gap_with_a_tiny_budget_is_a_planning_timeout() {
    let (mut world, fetch, maps) = load(&two_rooms(true));
    // Block the doorway in the world (not on the map).
    world
        .add_box("crate", [0.2, 0.6, 0.5], &Isometry3::translation(4.4, 1.5, 0.5), false)
        .unwrap();
    let before = world.state_hash();
    let settings = NavigateSettings {
        plan_iterations: 300,
        ..Default::default()
    };
    let err = navigate(
        &mut world,
        fetch,
        &maps,
        [6.5, 1.5, 0.0],
        &settings,
        &mut Pcg64Mcg::seed_from_u64(7),
    )
    .unwrap_err();
    assert_eq!(err.reason(), "planning_timeout", "{err}");
    assert_eq!(world.state_hash(), before);
}

#[test]
fn a_base_that_does_not_fit_is_blocked_after_its_replans() {
    // Two crates leave a 0.3 m gap on the straight line; a footprint that claims the Fetch
    // is 5 cm wide plans through it, and the real base gets stuck there.
    let (mut world, fetch, _) = load(&open_room());
    for (name, y) in [("crate_a", 1.45), ("crate_b", 2.55)] {
        world
            .add_box(name, [0.2, 0.4, 0.4], &Isometry3::translation(2.5, y, 0.4), false)
            .unwrap();
    }
    let thin = MapOptions {
        robot_radius: 0.1,
        ..Default::default()
    };
    let maps = SceneMaps::build(&open_room(), &thin).unwrap();
    let settings = NavigateSettings {
        footprint: Some(BaseFootprint {
            radius: 0.05,
            z_min: 0.03,
            z_max: 1.1,
        }),
        margin: 0.01,
        max_replans: 1,
        stall_time: 2.0,
        ..Default::default()
    };
    let err = navigate(
        &mut world,
        fetch,
        &maps,
        [4.0, 2.0, 0.0],
        &settings,
        &mut Pcg64Mcg::seed_from_u64(8),
    )
    .unwrap_err();
    assert_eq!(err.reason(), "blocked", "{err}");
    assert!(err.to_string().contains("after 1 replans"), "{err}");
    let x = world.base_pose(fetch).unwrap().translation.x;
    assert!(x > 1.3 && x < 2.5, "stopped in front of the gap, at x = {x}");
}

#[test]
fn same_seed_same_final_state() {
    let goal = [6.5, 2.0, FRAC_PI_2];
    let once = || {
        let (mut world, fetch, maps) = load(&two_rooms(true));
        let r = run(&mut world, fetch, &maps, goal, Execution::Physics, 11).unwrap();
        (world.state_hash(), r.steps, r.plan.poses)
    };
    let a = once();
    let b = once();
    assert_eq!(a, b);
}
