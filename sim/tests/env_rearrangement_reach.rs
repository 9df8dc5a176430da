//! The articulated tasks close only joints within the Fetch's reach: handles above
//! `task.handle_height` (wall-cabinet doors) are left out, those below it kept.

use std::collections::BTreeMap;

use hearth_sim::env::{Env, EnvConfig, EnvError};
use hearth_sim::scene::{GenerateOptions, SceneFile, generate};
use hearth_sim::world::ModelHandle;
use nalgebra::Point3;

/// `examples/configs/room_rearrangement.toml` (home seed 1, two rooms, the kitchen).
fn config(task: &str) -> EnvConfig {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/configs/room_rearrangement.toml");
    let mut c = EnvConfig::load(&path).unwrap();
    c.task.name = task.into();
    if task != "room_rearrangement" {
        c.task.room = None;
    }
    c
}

/// The home that config builds, for the objects' categories.
fn home(c: &EnvConfig) -> SceneFile {
    generate(&GenerateOptions {
        seed: c.scene.generate,
        rooms: c.scene.rooms,
        robot: Some(c.robot.name.clone()),
        small_objects: c.scene.small_objects,
    })
    .unwrap()
}

fn model_named(env: &Env, name: &str) -> ModelHandle {
    env.world()
        .model_named(name)
        .unwrap_or_else(|| panic!("no model `{name}`"))
}

/// Height of the handle of `joint` of `object` in an env that was not reset (every joint
/// closed): the centre of the visual part of the moving link farthest out of the front.
fn handle_height(env: &Env, object: &str, joint: &str) -> f64 {
    let h = model_named(env, object);
    let model = env.world().model(h).unwrap();
    let pose = env.world().base_pose(h).unwrap();
    let j = model.joint_index(joint).unwrap();
    let link = &model.links()[model.joints()[j].child];
    let at = env.world().link_pose(h, &link.name).unwrap();
    link.visuals
        .iter()
        .map(|v| at * Point3::from(v.origin.translation.vector))
        .max_by(|a, b| {
            let x = |p: &Point3<f64>| pose.inverse_transform_point(p).x;
            x(a).total_cmp(&x(b))
        })
        .map_or(at.translation.z, |p| p.z)
}

/// object → joints of the episode's targets.
fn targets(env: &Env) -> BTreeMap<String, Vec<String>> {
    env.task_objects().into_iter().collect()
}

#[test]
fn rearrangement_leaves_out_wall_cabinet_doors_above_the_band() {
    let c = config("room_rearrangement");
    let home = home(&c);
    let category = |name: &str| {
        home.objects
            .iter()
            .find(|o| o.name == name)
            .map(|o| o.category.clone())
            .unwrap()
    };
    let mut env = Env::new(c.clone()).unwrap();
    env.reset(0).unwrap();
    let kept = targets(&env);
    let mut wide = c.clone();
    wide.task.handle_height = [0.0, 10.0];
    let mut all_env = Env::new(wide.clone()).unwrap();
    all_env.reset(0).unwrap();
    let all = targets(&all_env);
    // The home as built, every joint closed.
    let closed = Env::new(wide).unwrap();

    let count = |m: &BTreeMap<String, Vec<String>>| m.values().map(Vec::len).sum::<usize>();
    eprintln!(
        "kitchen: {} joints on {} pieces in reach, {} on {} in all",
        count(&kept),
        kept.len(),
        count(&all),
        all.len()
    );
    for (object, joints) in &all {
        for j in joints {
            let h = handle_height(&closed, object, j);
            let k = kept.get(object).is_some_and(|js| js.contains(j));
            eprintln!(
                "  {object} ({}) {j}: handle {h:.2} m {}",
                category(object),
                if k { "kept" } else { "dropped" }
            );
            // Kept exactly when within the band.
            assert_eq!(k, (0.1..=1.5).contains(&h), "{object} {j} at {h:.2} m");
        }
    }
    // Every kept joint is one of all, and none above the band.
    for (object, joints) in &kept {
        for j in joints {
            assert!(all[object].contains(j));
            assert!(handle_height(&closed, object, j) <= 1.5);
        }
    }
    // A wall cabinet's doors are all out of reach, so the cabinet is no target; the bottom
    // cabinets' doors are kept.
    let tops: Vec<&String> = all.keys().filter(|o| category(o) == "top_cabinet").collect();
    assert!(!tops.is_empty(), "the kitchen has wall cabinets");
    assert!(tops.iter().all(|o| !kept.contains_key(*o)), "{tops:?}");
    let bottom_doors = kept
        .iter()
        .filter(|(o, _)| matches!(category(o).as_str(), "bottom_cabinet" | "counter"))
        .flat_map(|(_, js)| js.iter().filter(|j| j.starts_with("door_")))
        .count();
    assert!(bottom_doors > 0, "{kept:?}");
    assert!(count(&kept) < count(&all));

    // Episodes stay reproducible.
    let mut again = Env::new(c).unwrap();
    again.reset(0).unwrap();
    assert_eq!(targets(&again), kept);
}

#[test]
fn a_room_whose_joints_are_all_out_of_reach_is_not_drawn() {
    let mut c = config("room_rearrangement");
    // A band no handle reaches: the kitchen is no candidate.
    c.task.handle_height = [3.0, 4.0];
    match Env::new(c.clone()) {
        Err(EnvError::Config { key, reason }) => {
            assert_eq!(key, "task.room");
            assert!(reason.contains("in reach"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    c.task.room = None;
    assert!(matches!(Env::new(c), Err(EnvError::Task(_))));
    // Bad bands are configuration errors naming the key.
    for band in ["[1.5, 0.5]", "[-0.2, 1.0]", "[0.1, nan]"] {
        let toml =
            format!("[robot]\nname = \"fetch\"\n[task]\nname = \"room_rearrangement\"\nhandle_height = {band}\n");
        match EnvConfig::from_toml(&toml) {
            Err(EnvError::Config { key, .. }) => assert_eq!(key, "task.handle_height", "{band}"),
            other => panic!("{band}: {other:?}"),
        }
    }
}

#[test]
fn push_tasks_keep_every_bottom_cabinet_joint() {
    // Bottom cabinets' handles all lie within the band: the filter changes nothing there.
    for task in ["push_drawer", "push_cabinet"] {
        let c = config(task);
        let home = home(&c);
        let mut checked = 0;
        for o in home.objects.iter().filter(|o| o.category == "bottom_cabinet") {
            let mut c = c.clone();
            c.task.target_object = Some(o.name.clone());
            let mut wide = c.clone();
            wide.task.handle_height = [0.0, 10.0];
            let (Ok(mut a), Ok(mut b)) = (Env::new(c), Env::new(wide)) else {
                continue;
            };
            a.reset(0).unwrap();
            b.reset(0).unwrap();
            assert_eq!(targets(&a), targets(&b), "{task} {}", o.name);
            checked += 1;
        }
        eprintln!("{task}: {checked} bottom cabinets unchanged");
        assert!(checked > 0, "{task}");
    }
}

#[test]
fn opened_fronts_do_not_start_inside_their_neighbours() {
    // Without the clearance checks, seeds 0, 4 and 6 open the fridge's left door into the
    // cabinet beside it and the joints blow up within a step.
    let mut env = Env::new(config("room_rearrangement")).unwrap();
    let robot = env.robot();
    for seed in 0..8 {
        env.reset(seed).unwrap();
        let action = vec![0.0f32; env.action_space().size()];
        for _ in 0..10 {
            env.step(&action).unwrap();
        }
        let world = env.world();
        for h in world.models().filter(|&h| h != robot) {
            let model = world.model(h).unwrap();
            let q = world.joint_positions(h).unwrap();
            for (v, x) in q.iter().enumerate() {
                assert!(
                    x.is_finite() && *x >= model.lower()[v] - 0.05 && *x <= model.upper()[v] + 0.05,
                    "seed {seed}: {} {} at {x}",
                    world.model_name(h).unwrap(),
                    model.variable_names()[v]
                );
            }
        }
    }
}
