//! Grasping: a Fetch lifts a mug from a table, and a wide bowl by its rim; candidates from
//! geometry; typed failures.

use hearth_sim::assets::{Asset, Category};
use hearth_sim::kinematics::RobotModel;
use hearth_sim::scene::{SceneFile, SceneObject};
use hearth_sim::world::{ModelHandle, SpawnOptions, World, WorldConfig};
use hearth_skills::arm::{Arm, ArmSettings};
use hearth_skills::grasp::{GraspKind, GraspSettings, grasp, grasp_candidates};
use hearth_skills::{Execution, SkillError};
use nalgebra::{Isometry3, Point3};
use rand::SeedableRng;

const TABLE_X: f64 = 1.05;

/// A table with a mug and a wide bowl, in front of a Fetch bolted 2 cm above the floor.
fn table_scene() -> (World, ModelHandle, ModelHandle, ModelHandle) {
    let table = Asset::build(Category::Table, 0, 1.0).unwrap();
    let top = table.aabb_max[2];
    let mut scene = SceneFile::empty("mug on a table");
    scene
        .objects
        .push(SceneObject::new("table", "table", 0, [TABLE_X, 0.0, 0.0]));
    for (name, category, variant, y) in [("mug", "mug", 0, 0.0), ("bowl", "bowl", 2, 0.3)] {
        let mut o = SceneObject::new(name, category, variant, [TABLE_X - 0.25, y, top]);
        o.on = Some("table".into());
        scene.objects.push(o);
    }
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    world.settle(120);
    (
        world,
        robot,
        loaded.object("mug").unwrap(),
        loaded.object("bowl").unwrap(),
    )
}

#[test]
fn candidates_fit_the_object() {
    let (world, _, mug, bowl) = table_scene();
    let s = GraspSettings::default();
    let c = grasp_candidates(&world, mug, &Point3::origin(), &s).unwrap();
    assert!(c.iter().any(|c| c.kind == GraspKind::Side) && c.iter().any(|c| c.kind == GraspKind::Top));
    let mug_at = world.base_pose(mug).unwrap().translation.vector;
    for g in &c {
        assert!(g.width <= s.max_width && g.width > 0.05, "{g:?}");
        let d = (g.pose.translation.vector - mug_at).xy().norm();
        assert!(d < 0.04, "grasp {:?} is {d:.3} m off the mug's axis", g.kind);
        // The approach axis of the tip is the candidate's approach.
        assert!((g.pose.rotation * nalgebra::Vector3::x() - g.approach).norm() < 1e-9);
    }
    // The first side grasp comes from the robot's side.
    assert!(c[0].approach.x > 0.99, "{:?}", c[0]);
    // The large bowl (22 cm) fits no way across the fingers...
    let no_rim = GraspSettings {
        rim: false,
        ..s.clone()
    };
    assert!(
        grasp_candidates(&world, bowl, &Point3::origin(), &no_rim)
            .unwrap()
            .is_empty()
    );
    // ...but its 5 mm wall does: rim grasps all around, the nearest to the robot first.
    let c = grasp_candidates(&world, bowl, &Point3::origin(), &s).unwrap();
    assert_eq!(c.len(), 8, "{c:?}");
    let bowl_at = world.base_pose(bowl).unwrap().translation.vector;
    let rim_top = bowl_at.z + 0.07;
    for g in &c {
        assert_eq!(g.kind, GraspKind::Rim);
        // Measured by probes 2 mm apart.
        assert!((g.width - 0.005).abs() <= 0.0015, "wall {:.4}", g.width);
        let out = g.pose.translation.vector - bowl_at;
        // On the wall's middle (16 staves: between 0.1075 and 0.1096 m from the axis)...
        let r = out.xy().norm();
        assert!((0.104..=0.111).contains(&r), "{r:.4} m from the axis");
        // ...pointing down, the fingers closing along the radius...
        assert!((g.approach + nalgebra::Vector3::z()).norm() < 1e-9);
        let fingers = g.pose.rotation * nalgebra::Vector3::y();
        assert!(
            fingers.dot(&out.xy().push(0.0).normalize()).abs() > 0.999,
            "{fingers:?}"
        );
        // ...the pads over the wall's top 1.5 cm at least, their tips above the bottom.
        assert!(g.pose.translation.z < rim_top + 1e-6);
        assert!(g.pose.translation.z - s.finger_reach > bowl_at.z + 0.005);
        assert!(g.pose.translation.z - s.finger_reach < rim_top - 0.015);
    }
    let first = c[0].pose.translation.vector - bowl_at;
    assert!(first.x < -0.1, "the first rim grasp is on the far side: {first:?}");
    // A solid cylinder has no rim.
    assert!(
        grasp_candidates(&world, mug, &Point3::origin(), &s)
            .unwrap()
            .iter()
            .all(|g| g.kind != GraspKind::Rim)
    );
}

#[test]
fn the_fetch_lifts_a_wide_bowl_by_its_rim() {
    let (mut world, robot, _, bowl) = table_scene();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let z0 = world.base_pose(bowl).unwrap().translation.z;
    let r = grasp(
        &mut world,
        &mut arm,
        bowl,
        &GraspSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    assert_eq!(r.candidate.kind, GraspKind::Rim);
    assert!(r.lifted > 0.07, "{r:?}");
    for _ in 0..30 {
        world.step();
    }
    let pose = world.base_pose(bowl).unwrap();
    assert!(pose.translation.z > z0 + 0.07, "the bowl slipped");
    // Held by one side, it hangs nearly level.
    let up = pose.rotation * nalgebra::Vector3::z();
    assert!(up.z > 0.95, "the bowl tilts {:.2} rad", up.z.acos());
    assert_eq!(arm.held().map(|h| h.object), Some(bowl));
}

#[test]
fn the_fetch_lifts_a_mug_from_the_table() {
    let (mut world, robot, mug, _) = table_scene();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let hash = world.state_hash();
    let dry = GraspSettings {
        dry_run: true,
        ..Default::default()
    };
    let plan = grasp(&mut world, &mut arm, mug, &dry, Execution::Physics, &mut rng).unwrap();
    assert!(plan.lift.is_none() && world.state_hash() == hash);

    let z0 = world.base_pose(mug).unwrap().translation.z;
    let r = grasp(
        &mut world,
        &mut arm,
        mug,
        &GraspSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap();
    assert!(r.lifted > 0.07, "{r:?}");
    assert!(world.base_pose(mug).unwrap().translation.z > z0 + 0.07);
    assert_eq!(arm.held().map(|h| h.object), Some(mug));
    // Held for a second more.
    for _ in 0..30 {
        world.step();
    }
    assert!(
        world.base_pose(mug).unwrap().translation.z > z0 + 0.07,
        "the mug slipped"
    );
    // A second grasp while holding is refused.
    let e = grasp(
        &mut world,
        &mut arm,
        mug,
        &GraspSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap_err();
    assert!(matches!(e, SkillError::BadInput(_)), "{e}");
}

#[test]
fn too_wide_objects_and_bad_settings_are_typed_errors() {
    let (mut world, robot, mug, bowl) = table_scene();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let across_only = GraspSettings {
        rim: false,
        ..Default::default()
    };
    let e = grasp(&mut world, &mut arm, bowl, &across_only, Execution::Physics, &mut rng).unwrap_err();
    assert_eq!(e.reason(), "unreachable", "{e}");
    let bad = GraspSettings {
        force: -1.0,
        ..Default::default()
    };
    let e = grasp(&mut world, &mut arm, mug, &bad, Execution::Physics, &mut rng).unwrap_err();
    assert!(matches!(e, SkillError::BadInput(_)), "{e}");
}

#[test]
fn kinematic_execution_lifts_the_mug_too() {
    let (mut world, robot, mug, _) = table_scene();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let z0 = world.base_pose(mug).unwrap().translation.z;
    let r = grasp(
        &mut world,
        &mut arm,
        mug,
        &GraspSettings::default(),
        Execution::Kinematic,
        &mut rng,
    )
    .unwrap();
    assert!(r.lifted > 0.07, "{r:?}");
    assert!(world.base_pose(mug).unwrap().translation.z > z0 + 0.07);
}

#[test]
fn a_mug_glued_to_the_table_is_reported_as_slipped() {
    let table = Asset::build(Category::Table, 0, 1.0).unwrap();
    let top = table.aabb_max[2];
    let mut scene = SceneFile::empty("glued mug");
    scene
        .objects
        .push(SceneObject::new("table", "table", 0, [TABLE_X, 0.0, 0.0]));
    let mut mug = SceneObject::new("mug", "mug", 0, [TABLE_X - 0.25, 0.0, top]);
    mug.fixed = true;
    scene.objects.push(mug);
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    world.settle(60);
    let mug = loaded.object("mug").unwrap();
    let mut arm = Arm::new(&world, robot, ArmSettings::fetch()).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let e = grasp(
        &mut world,
        &mut arm,
        mug,
        &GraspSettings::default(),
        Execution::Physics,
        &mut rng,
    )
    .unwrap_err();
    assert_eq!(e.reason(), "slipped", "{e}");
    assert!(arm.held().is_none());
}
