//! World stepping, determinism, snapshots and the live-world collision view.

use hearth_sim::kinematics::{RobotModel, to_pose};
use hearth_sim::planning::obstacles::Obstacles;
use hearth_sim::world::{SpawnOptions, World, WorldConfig, WorldError};
use nalgebra::{Isometry3, Vector3};
use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::shape::{Ball, Cuboid};

fn world_with_boxes(n: usize) -> World {
    let mut world = World::new(WorldConfig::default()).unwrap();
    for i in 0..n {
        let pose = Isometry3::translation((i % 5) as f64 * 0.3, (i / 5) as f64 * 0.3, 0.3 + 0.05 * i as f64);
        world.add_box(&format!("box{i}"), [0.1, 0.1, 0.1], &pose, true).unwrap();
    }
    world
}

#[test]
fn config_is_validated() {
    for bad in [
        WorldConfig {
            timestep: f64::NAN,
            ..WorldConfig::default()
        },
        WorldConfig {
            substeps: 0,
            ..WorldConfig::default()
        },
        WorldConfig {
            solver_iterations: 0,
            ..WorldConfig::default()
        },
        WorldConfig {
            gravity: [0.0, f64::INFINITY, 0.0],
            ..WorldConfig::default()
        },
    ] {
        assert!(matches!(World::new(bad), Err(WorldError::InvalidConfig { .. })));
    }
    let world = World::new(WorldConfig::default()).unwrap();
    assert_eq!(world.body_count(), 1, "only the ground");
}

#[test]
fn boxes_fall_and_rest() {
    let mut world = world_with_boxes(1);
    let b = world.bodies().iter().map(|(h, _)| h).last().unwrap();
    let id = hearth_sim::world::BodyId::from_handle(b);
    for _ in 0..45 {
        world.step();
    }
    let z = world.body_pose(id).unwrap().translation.z;
    assert!((z - 0.1).abs() < 0.01, "z = {z}");
    assert_eq!(world.physics_steps(), 45 * 4);
}

#[test]
fn same_actions_give_identical_hashes() {
    let fetch = RobotModel::builtin("fetch").unwrap();
    let run = |v: f64| {
        let mut world = world_with_boxes(6);
        let robot = world
            .spawn_model(&fetch, &Isometry3::translation(-1.0, 0.0, 0.0), SpawnOptions::free())
            .unwrap();
        for i in 0..20 {
            world.drive(robot, v, if i > 10 { 0.3 } else { 0.0 }).unwrap();
            world.step();
        }
        world.state_hash()
    };
    let a = run(0.3);
    assert_eq!(a, run(0.3));
    assert_ne!(a, run(0.31));
}

#[test]
fn snapshot_restore_reproduces_the_run() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = world_with_boxes(4);
    let arm = world
        .spawn_model(&panda, &Isometry3::translation(0.0, -1.0, 0.0), SpawnOptions::fixed())
        .unwrap();
    for _ in 0..5 {
        world.step();
    }
    let snap = world.snapshot();
    let mut q = panda.neutral_configuration();
    q[0] = 0.5;
    q[3] = -1.0;
    let drive = |world: &mut World| {
        world.set_position_targets(arm, &q).unwrap();
        for _ in 0..10 {
            world.step();
        }
        world.state_hash()
    };
    let reference = drive(&mut world);
    // Diverge, then roll back.
    world.set_efforts(arm, &vec![0.0; panda.dof()]).unwrap();
    for _ in 0..7 {
        world.step();
    }
    assert_ne!(world.state_hash(), reference);
    world.restore(&snap).unwrap();
    assert!((world.time() - snap.time()).abs() < 1e-12);
    assert_eq!(drive(&mut world), reference);
}

#[test]
fn obstacles_view_matches_parry() {
    let mut world = World::new(WorldConfig {
        ground_plane: false,
        ..WorldConfig::default()
    })
    .unwrap();
    let box_pose = Isometry3::new(Vector3::new(1.0, 0.5, 0.4), Vector3::new(0.0, 0.0, 0.3));
    let half = [0.2, 0.3, 0.1];
    world.add_box("crate", half, &box_pose, false).unwrap();
    let view = world.obstacles_view(&[]).unwrap();
    let cuboid = Cuboid::new(Vector::new(0.2, 0.3, 0.1));
    let bp = to_pose(&box_pose);
    let ball = Ball::new(0.05);
    for (x, y, z) in [
        (1.0, 0.5, 0.52),
        (1.0, 0.5, 0.7),
        (1.3, 0.5, 0.4),
        (0.0, 0.0, 0.0),
        (1.1, 0.8, 0.45),
    ] {
        let p = Pose::translation(x, y, z);
        let exact = query::distance(&p, &ball, &bp, &cuboid).unwrap().distance;
        assert_eq!(view.intersects(&ball, &p), exact <= 0.0, "at {x},{y},{z}");
        match view.distance(&ball, &p, 10.0) {
            Some((d, id)) => {
                assert!((d - exact).abs() < 1e-5, "{d} vs {exact}");
                assert_eq!(view.name(id), Some("crate"));
            }
            None => panic!("distance within 10 m expected"),
        }
        assert!(view.distance(&ball, &p, exact * 0.5).is_none() || exact <= 0.0);
        // Contacts: where the ball overlaps the crate, the same as parry's in world terms.
        let id = view.first_hit(&ball, &p);
        match (id, query::contact(&p, &ball, &bp, &cuboid, 0.0).unwrap()) {
            (Some(id), Some(want)) => {
                let got = view.contact(id, &ball, &p).expect("a contact where the ball touches");
                assert!((got.distance - want.dist).abs() < 1e-5, "{got:?} vs {want:?}");
                assert!((got.normal - want.normal1).length() < 1e-5, "{got:?} vs {want:?}");
                assert!((got.point - want.point1).length() < 1e-5, "{got:?} vs {want:?}");
            }
            (None, _) => assert!(exact > 0.0, "at {x},{y},{z}"),
            (Some(_), None) => panic!("a hit without a contact at {x},{y},{z}"),
        }
    }
    // A contact that parry finds only within the margin is reported as overlap.
    let near = Pose::translation(1.0, 0.5, 0.56);
    let loose = world.obstacles_view(&[]).unwrap().with_margin(0.02);
    let id = loose.first_hit(&ball, &near).expect("within the margin");
    let c = loose.contact(id, &ball, &near).unwrap();
    assert!((c.distance - (0.01 - 0.02)).abs() < 1e-5, "{c:?}");
    assert!(view.contact(id, &ball, &near).is_none(), "apart without a margin");
    // Rays: along -z from above the box centre.
    let top = 0.5f32;
    let (t, id) = view
        .cast_ray(Vector::new(1.0, 0.5, 2.0), Vector::new(0.0, 0.0, -1.0), 10.0)
        .unwrap();
    assert!((t - (2.0 - top)).abs() < 1e-4, "t = {t}");
    assert_eq!(view.name(id), Some("crate"));
    assert!(
        view.cast_ray(Vector::new(1.0, 0.5, 2.0), Vector::new(0.0, 0.0, 1.0), 10.0)
            .is_none()
    );
    assert!(
        view.cast_ray(Vector::new(1.0, 0.5, 2.0), Vector::new(0.0, 0.0, -1.0), 1.0)
            .is_none()
    );
    let aabb = view.aabb().unwrap();
    assert!(aabb.maxs.z > 0.49 && aabb.mins.z < 0.31);
    // Margins.
    let near = Pose::translation(1.0, 0.5, 0.56);
    assert!(!view.intersects(&ball, &near));
    let loose = world.obstacles_view(&[]).unwrap().with_margin(0.02);
    assert!(loose.intersects(&ball, &near));
}

#[test]
fn obstacles_view_ignores_the_robot_and_sees_moved_bodies() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let arm = world
        .spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())
        .unwrap();
    let hand = world.link_pose(arm, "panda_hand").unwrap();
    let probe = Ball::new(0.02);
    let at_hand = to_pose(&hand);
    assert!(world.obstacles_view(&[]).unwrap().intersects(&probe, &at_hand));
    let view = world.obstacles_view(&[arm]).unwrap();
    assert!(!view.intersects(&probe, &at_hand));
    // The ground is still there.
    assert!(view.intersects(&probe, &Pose::translation(2.0, 0.0, 0.01)));
    let (_, id) = view
        .cast_ray(Vector::new(0.0, 0.0, 3.0), Vector::new(0.0, 0.0, -1.0), 10.0)
        .unwrap();
    assert_eq!(view.name(id), Some("ground"));

    // A teleported box is seen at its new place before any step, and after steps.
    let b = world
        .add_box("crate", [0.1, 0.1, 0.1], &Isometry3::translation(3.0, 0.0, 0.1), true)
        .unwrap();
    let probe_at = Pose::translation(5.0, 0.0, 0.1);
    assert!(!world.obstacles_view(&[arm]).unwrap().intersects(&probe, &probe_at));
    world.set_body_pose(b, &Isometry3::translation(5.0, 0.0, 0.1)).unwrap();
    assert!(world.obstacles_view(&[arm]).unwrap().intersects(&probe, &probe_at));
    for _ in 0..10 {
        world.step();
    }
    let view = world.obstacles_view(&[arm]).unwrap().excluding_bodies(&[b]);
    assert!(!view.intersects(&probe, &probe_at));
    assert!(world.obstacles_view(&[arm]).unwrap().intersects(&probe, &probe_at));
}

#[test]
fn view_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<hearth_sim::world::WorldObstacles>();
    check::<hearth_sim::world::Snapshot>();
    fn send<T: Send>() {}
    send::<World>();
    fn as_dyn(world: &World) -> Box<dyn Obstacles + '_> {
        Box::new(world.obstacles_view(&[]).unwrap())
    }
    let world = World::new(WorldConfig::default()).unwrap();
    assert!(as_dyn(&world).aabb().is_some());
}

#[test]
fn planner_validity_against_the_live_world() {
    use hearth_sim::kinematics::{Chain, SelfCollisionMatrix};
    use hearth_sim::planning::validity::RobotValidity;
    use std::sync::Arc;

    let panda = RobotModel::builtin("panda").unwrap();
    let mut world = World::new(WorldConfig::default()).unwrap();
    // Mounted above the floor (link0's collision reaches 2 cm below its frame): the floor is an
    // obstacle like any other.
    let base = Isometry3::translation(0.0, 0.0, 0.03);
    let arm = world.spawn_model(&panda, &base, SpawnOptions::fixed()).unwrap();
    // A wall in front of the robot, at x = 0.5.
    world
        .add_box("wall", [0.05, 0.5, 0.5], &Isometry3::translation(0.55, 0.0, 0.5), false)
        .unwrap();
    let view = world.obstacles_view(&[arm]).unwrap();
    let chain = Chain::named(&panda, "arm").unwrap();
    let mut validity = RobotValidity::new(
        chain,
        SelfCollisionMatrix::adjacent_only(&panda),
        Arc::new(view.clone()),
    );
    validity.set_base(base);
    let mut reference = panda.neutral_configuration();
    reference[7] = 0.04; // fingers open
    validity.set_reference(&reference).unwrap();
    let home = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    assert!(
        validity.is_valid_exact(&home),
        "the ready pose clears the wall: {:?}",
        validity.explain(&home)
    );
    let reach = [0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.785];
    assert!(!validity.is_valid_exact(&reach), "stretching forward hits the wall");

    // The view keeps its picture while the world moves on (copy on write).
    let probe = Ball::new(0.05);
    let spot = Pose::translation(2.0, 2.0, 0.3);
    let b = world
        .add_box("late", [0.1, 0.1, 0.3], &Isometry3::translation(2.0, 2.0, 0.3), true)
        .unwrap();
    for _ in 0..3 {
        world.step();
    }
    assert!(!view.intersects(&probe, &spot), "taken before the box existed");
    assert!(world.obstacles_view(&[]).unwrap().intersects(&probe, &spot));
    assert!(world.body_pose(b).is_ok());
}
