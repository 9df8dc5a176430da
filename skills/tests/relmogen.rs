//! The ReLMoGen env on a small room with a kitchen cabinet (Fetch, `push_drawer`, a low-res
//! raycast camera, kinematic execution): spaces, arm and base subgoals, refused actions,
//! failed subgoals, reproducibility, the vectorised env, and the push dataset writer.

use hearth_sim::assets::RoomType;
use hearth_sim::env::DType;
use hearth_sim::scene::{Orientation, RobotPlacement, Room, SceneFile, SceneObject, Wall};
use hearth_sim::sensors::Backend;
use hearth_sim::world::ModelHandle;
use hearth_skills::Execution;
use hearth_skills::relmogen::{
    ActionForm, DatasetSettings, PushDataset, ReLMoGenConfig, ReLMoGenEnv, ReLMoGenError, ReLMoGenVecEnv, UNTRIED,
    read_mask,
};
use nalgebra::Point3;

const SIDE: u32 = 64;

/// A 5 × 4 m kitchen: a bottom cabinet with drawers against the east wall, the Fetch at
/// (2, 2) facing it.
fn kitchen() -> SceneFile {
    kitchen_with(1)
}

/// The kitchen with bottom cabinet `variant` (1: three drawers, 0: two doors).
fn kitchen_with(variant: usize) -> SceneFile {
    let mut s = SceneFile::empty("relmogen kitchen");
    s.building.rooms.push(Room {
        name: "kitchen".into(),
        room_type: RoomType::Kitchen,
        polygon: vec![[0.0, 0.0], [5.0, 0.0], [5.0, 4.0], [0.0, 4.0]],
    });
    s.building.walls = vec![
        Wall::new("south", [0.0, 0.0], [5.0, 0.0], 2.5, 0.12),
        Wall::new("north", [0.0, 4.0], [5.0, 4.0], 2.5, 0.12),
        Wall::new("west", [0.0, 0.0], [0.0, 4.0], 2.5, 0.12),
        Wall::new("east", [5.0, 0.0], [5.0, 4.0], 2.5, 0.12),
    ];
    let mut cabinet = SceneObject::new("cabinet", "bottom_cabinet", variant, [4.55, 2.0, 0.0]);
    cabinet.orientation = Orientation::Yaw(std::f64::consts::PI);
    cabinet.fixed = true;
    s.objects.push(cabinet);
    s.robot = Some(RobotPlacement {
        name: "fetch".into(),
        position: [2.0, 2.0, 0.0],
        yaw: 0.0,
    });
    s
}

fn scene_file(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("hearth-relmogen-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("kitchen.json");
    kitchen().save(&path).unwrap();
    path
}

fn config(tag: &str, action: &str, extra: &str) -> ReLMoGenConfig {
    let path = scene_file(tag);
    let toml = format!(
        "action = \"{action}\"\n{extra}\n[env.scene]\nfile = {path:?}\n[env.robot]\nname = \"fetch\"\n\
         [env.task]\nname = \"push_drawer\"\nopen_range = [0.6, 0.9]\n\
         [env.sensors]\nmodalities = [\"rgb\", \"task_obs\"]\n\
         [env.sensors.camera]\nwidth = {SIDE}\nheight = {SIDE}\nbackend = \"raycast\"\n[env.episode]\nmax_steps = 20\n"
    );
    ReLMoGenConfig::from_toml(&toml).unwrap()
}

fn cabinet(env: &ReLMoGenEnv) -> ModelHandle {
    let world = env.env().world();
    world
        .models()
        .find(|&m| world.model_name(m).unwrap() == "cabinet")
        .unwrap()
}

/// Total opening of the task's joints (Σ position / range).
fn opening(env: &ReLMoGenEnv) -> f64 {
    let world = env.env().world();
    let cab = cabinet(env);
    let model = world.model(cab).unwrap();
    let q = world.joint_positions(cab).unwrap();
    let mut total = 0.0;
    for (object, joints) in env.env().task_objects() {
        assert_eq!(object, "cabinet");
        for j in joints {
            let v = model.variable_names().iter().position(|n| *n == j).unwrap();
            total += (q[v] - model.lower()[v]).abs() / (model.upper()[v] - model.lower()[v]);
        }
    }
    total
}

/// The continuous action pushing the front of the highest open drawer straight ahead.
fn push_drawer_action(env: &ReLMoGenEnv) -> [f32; 8] {
    let world = env.env().world();
    let cab = cabinet(env);
    let (_, joints) = env.env().task_objects().pop().unwrap();
    let camera = env.camera();
    let from_camera = camera.pose(world).unwrap().inverse();
    let mut best: Option<(f64, (f64, f64))> = None;
    for j in joints {
        let link = j.trim_end_matches("_slide");
        let front = world.link_pose(cab, link).unwrap() * Point3::new(0.02, 0.0, -0.03);
        let inside = |(u, v): (f64, f64)| (0.0..f64::from(SIDE)).contains(&u) && (0.0..f64::from(SIDE)).contains(&v);
        if let Some(px) = camera.config().intrinsics.project(&(from_camera * front))
            && inside(px)
            && best.is_none_or(|(z, _)| front.z > z)
        {
            best = Some((front.z, px));
        }
    }
    let (_, (u, v)) = best.expect("a drawer front is in view");
    let scale = |x: f64| (2.0 * x.floor() / f64::from(SIDE - 1) - 1.0) as f32;
    [1.0, 0.0, 0.0, 0.0, scale(u), scale(v), 0.0, -1.0]
}

#[test]
fn spaces_and_config_errors() {
    let env = ReLMoGenEnv::new(config("spaces", "continuous", "")).unwrap();
    let a = env.action_space();
    assert_eq!(
        (a.shape.clone(), a.dtype, a.low, a.high),
        (vec![8], DType::F32, -1.0, 1.0)
    );
    let names: Vec<&str> = env.observation_spaces().iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["rgb", "task_obs"]);
    assert_eq!(env.observation_spaces()[0].shape, vec![SIDE as usize, SIDE as usize, 3]);

    let c = config("spaces", "discrete", "direction_bins = 4");
    assert_eq!((c.action, c.direction_bins), (ActionForm::Discrete, 4));
    let spec = hearth_skills::relmogen::ActionSpec {
        form: ActionForm::Discrete,
        width: SIDE,
        height: SIDE,
        bins: 4,
        max_base_distance: 2.0,
    };
    assert_eq!(spec.space().high, (2 * 16 * 16 * 4 - 1) as f64);

    let e = ReLMoGenConfig::from_toml("bogus_key = 1\n").unwrap_err();
    assert!(
        matches!(e, ReLMoGenError::Parse(ref m) if m.contains("bogus_key")),
        "{e}"
    );
    let e = ReLMoGenConfig::from_toml(
        "[env.task]\nname = \"push_drawer\"\n[env.robot]\nname = \"fetch\"\n[push]\nspeed = -1\n",
    )
    .unwrap_err();
    assert!(
        matches!(e, ReLMoGenError::Config { ref key, .. } if key == "push.speed"),
        "{e}"
    );
    let e = ReLMoGenConfig::from_toml("[env.task]\nname = \"reaching\"\n[env.robot]\nname = \"fetch\"\n").unwrap_err();
    assert!(
        matches!(e, ReLMoGenError::Config { ref key, .. } if key == "env.task.name"),
        "{e}"
    );
    let e =
        ReLMoGenConfig::from_toml("[env.task]\nname = \"push_drawer\"\n[env.robot]\nname = \"fetch\"\n[env.tsak]\n")
            .unwrap_err();
    assert!(e.to_string().contains("tsak"), "{e}");
    let example =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/configs/relmogen_push_drawer.toml");
    let loaded = ReLMoGenConfig::load(&example).unwrap();
    assert_eq!(loaded.env_config().unwrap().task.name, "push_drawer");
    assert_eq!(loaded.execution, Execution::Kinematic);
}

#[test]
fn an_arm_subgoal_on_the_open_drawer_closes_it_and_records_the_planner() {
    let mut env = ReLMoGenEnv::new(config("arm", "continuous", "")).unwrap();
    env.reset(3).unwrap();
    let before = opening(&env);
    assert!(before > 0.5, "{before}");
    let action = push_drawer_action(&env);
    let step = env.step(&action).unwrap();
    let info = &step.info;
    assert_eq!(info.subgoal, "arm");
    assert!(info.planner_success, "{info:?}");
    assert!(info.failure_reason.is_none() && info.target.is_some());
    assert!(info.planning_time > 0.0 && info.path_length > 0.0 && info.skill_time >= info.planning_time);
    assert!(info.moved > 0.1, "{info:?}");
    let after = opening(&env);
    assert!(after < before - 0.1, "opening {before:.3} → {after:.3}");
    // The env's potential reward is the closing the push did.
    assert!(step.reward > 0.05, "{}", step.reward);
    assert_eq!(info.env.metrics.episode_length, 1);
}

#[test]
fn a_base_subgoal_moves_the_base() {
    let mut env = ReLMoGenEnv::new(config("base", "continuous", "")).unwrap();
    env.reset(1).unwrap();
    let robot = env.robot();
    let p0 = env.env().world().base_pose(robot).unwrap().translation;
    // Back up 0.5 m (bearing π) and keep the heading.
    let step = env.step(&[-1.0, 1.0, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    let info = &step.info;
    assert_eq!(info.subgoal, "base");
    assert!(info.planner_success, "{info:?}");
    let p1 = env.env().world().base_pose(robot).unwrap().translation;
    let moved = (p1.vector - p0.vector).xy().norm();
    assert!((moved - 0.5).abs() < 0.12, "moved {moved:.3}: {info:?}");
    assert!(info.path_length > 0.3 && info.planning_time > 0.0, "{info:?}");
}

#[test]
fn bad_actions_are_refused_and_leave_the_world_alone() {
    let mut env = ReLMoGenEnv::new(config("bad", "continuous", "")).unwrap();
    assert!(matches!(env.step(&[0.0; 8]), Err(ReLMoGenError::NotReset)));
    env.reset(0).unwrap();
    let hash = env.env().world().state_hash();
    for action in [
        vec![f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        vec![0.0, 1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        vec![0.0; 7],
    ] {
        let e = env.step(&action).unwrap_err();
        assert!(matches!(e, ReLMoGenError::BadAction(_)), "{e}");
    }
    assert_eq!(env.env().world().state_hash(), hash);

    let mut d = ReLMoGenEnv::new(config("bad", "discrete", "")).unwrap();
    d.reset(0).unwrap();
    let hash = d.env().world().state_hash();
    let top = d.action_space().high as f32;
    for action in [[-1.0], [2.5], [top + 1.0], [f32::INFINITY]] {
        let e = d.step(&action).unwrap_err();
        assert!(matches!(e, ReLMoGenError::BadAction(_)), "{e}");
    }
    assert_eq!(d.env().world().state_hash(), hash);
}

#[test]
fn a_failed_subgoal_is_penalised_with_its_reason() {
    let mut env = ReLMoGenEnv::new(config("fail", "discrete", "failure_penalty = 5.0")).unwrap();
    env.reset(2).unwrap();
    let spec = *env.action_spec();
    // The base map's top row looks over the cabinet at the far wall: no floor there.
    let top = spec.base_index(0, 8, 0).unwrap();
    let step = env.step(&[top as f32]).unwrap();
    assert_eq!(step.info.subgoal, "base");
    assert!(!step.info.planner_success);
    assert_eq!(step.info.failure_reason, Some("bad_input"), "{:?}", step.info);
    assert!(step.info.failure_message.as_deref().unwrap().contains("not the floor"));
    assert!(step.reward < -4.9 && step.reward > -5.1, "{}", step.reward);

    // A continuous base goal inside the cabinet is unreachable.
    let mut c = ReLMoGenEnv::new(config("fail", "continuous", "failure_penalty = 5.0")).unwrap();
    c.reset(2).unwrap();
    let step = c.step(&[-1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert!(!step.info.planner_success);
    assert_eq!(step.info.failure_reason, Some("unreachable"), "{:?}", step.info);
    assert!(step.reward < -4.9, "{}", step.reward);
}

#[test]
fn the_same_seed_gives_the_same_episode() {
    let mut env = ReLMoGenEnv::new(config("seed", "continuous", "")).unwrap();
    let mut runs = Vec::new();
    for _ in 0..2 {
        env.reset(3).unwrap();
        let push = push_drawer_action(&env);
        let a = env.step(&push).unwrap();
        let b = env.step(&[-1.0, 0.8, -0.6, 0.2, 0.0, 0.0, 0.0, 0.0]).unwrap();
        runs.push((env.env().world().state_hash(), a.reward, b.reward, b.info.path_length));
    }
    assert_eq!(runs[0], runs[1]);
}

#[test]
fn the_vector_env_steps_and_auto_resets() {
    let mut c = config("vec", "discrete", "");
    c.env.as_mut().unwrap().episode.max_steps = 1;
    let mut envs = ReLMoGenVecEnv::new(&c, 2).unwrap();
    let obs = envs.reset(4).unwrap();
    assert_eq!(obs.get("rgb").unwrap().len(), 2 * (SIDE * SIDE * 3) as usize);
    let spec = *envs.envs()[0].action_spec();
    let a = spec.base_index(15, 8, 0).unwrap() as f32;
    let e = envs.step(&[a, f32::NAN]).unwrap_err();
    assert!(matches!(e, ReLMoGenError::BadAction(_)), "{e}");
    let step = envs.step(&[a, a]).unwrap();
    assert_eq!(step.rewards.len(), 2);
    assert!(step.truncated.iter().all(|&t| t), "max_steps = 1 truncates");
    assert!(step.infos.iter().all(|i| i.subgoal == "base"));
    assert_eq!(step.obs.get("task_obs").unwrap().len(), 2 * 11);
}

#[test]
fn the_push_dataset_writes_and_resumes() {
    let dir = std::env::temp_dir().join(format!("hearth-relmogen-data-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let settings = DatasetSettings {
        locations: 2,
        pushes_per_location: 3,
        execution: Execution::Kinematic,
        seed: 5,
        width: 32,
        height: 32,
        backend: Backend::Raycast,
        ..Default::default()
    };
    let mut data = PushDataset::new(&kitchen(), settings.clone()).unwrap();
    let mut seen = Vec::new();
    let first = data.write(&dir, |p| seen.push(p.locations_done)).unwrap();
    assert_eq!((first.written, first.skipped, first.pushes), (2, 0, 6));
    assert!(first.pushes_per_second > 0.0);
    assert_eq!(seen, [1, 2]);
    for i in 0..2 {
        let folder = hearth_skills::relmogen::location_dir(&dir, i);
        for f in ["rgb.png", "mask.npy", "mask_rgb.png", "pushes.json"] {
            assert!(folder.join(f).is_file(), "{f} missing in {folder:?}");
        }
        let (h, w, mask) = read_mask(&folder.join("mask.npy")).unwrap();
        assert_eq!((h, w), (32, 32));
        let tried = mask.iter().filter(|&&m| m != UNTRIED).count();
        assert!((1..=3).contains(&tried), "{tried}");
        assert!(mask.iter().all(|&m| m <= 1 || m == UNTRIED));
        let index: hearth_skills::relmogen::LocationIndex =
            serde_json::from_str(&std::fs::read_to_string(folder.join("pushes.json")).unwrap()).unwrap();
        assert_eq!(index.pushes.len(), 3);
        for p in &index.pushes {
            let m = mask[(p.pixel[1] * 32 + p.pixel[0]) as usize];
            assert!(m != UNTRIED && (p.success || p.reason.is_some()));
        }
    }
    // A second run skips both; removing one location's index redoes exactly that one, the same.
    let again = data.write(&dir, |_| {}).unwrap();
    assert_eq!((again.written, again.skipped, again.pushes), (0, 2, 0));
    let one = hearth_skills::relmogen::location_dir(&dir, 1).join("pushes.json");
    let old = std::fs::read_to_string(&one).unwrap();
    std::fs::remove_file(&one).unwrap();
    let mut fresh = PushDataset::new(&kitchen(), settings).unwrap();
    let redo = fresh.write(&dir, |_| {}).unwrap();
    assert_eq!((redo.written, redo.skipped), (1, 1));
    assert_eq!(std::fs::read_to_string(&one).unwrap(), old);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn interactive_nav_takes_base_subgoals_towards_the_goal() {
    let path = scene_file("nav");
    let toml = format!(
        "action = \"continuous\"\n[env.scene]\nfile = {path:?}\n[env.robot]\nname = \"fetch\"\n\
         [env.task]\nname = \"interactive_nav\"\ngeodesic_range = [1.0, 3.0]\npotential = \"l2\"\n\
         [env.sensors]\nmodalities = [\"task_obs\"]\n\
         [env.sensors.camera]\nwidth = 32\nheight = 32\nbackend = \"raycast\"\n"
    );
    let mut env = ReLMoGenEnv::new(ReLMoGenConfig::from_toml(&toml).unwrap()).unwrap();
    assert_eq!(env.observation_spaces()[0].name, "task_obs");
    env.reset(6).unwrap();
    let robot = env.robot();
    let base = env.env().world().base_pose(robot).unwrap();
    let (start, goal) = env.env().start_and_goal();
    // Half-way to the goal, straight: bearing and distance in the robot frame.
    let (dx, dy) = (goal[0] - start[0], goal[1] - start[1]);
    let heading = base.rotation.euler_angles().2;
    let bearing = hearth_sim::kinematics::wrap_angle(dy.atan2(dx) - heading);
    let half = (0.5 * dx.hypot(dy)).min(2.0);
    let action = [
        -1.0,
        (bearing / std::f64::consts::PI) as f32,
        (half - 1.0) as f32,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let step = env.step(&action).unwrap();
    // A chair may stand on the straight line; the planner goes round or reports why not.
    if step.info.planner_success {
        assert!(step.reward > 0.3 * half, "{} {:?}", step.reward, step.info);
    } else {
        assert!(
            step.info.failure_reason.is_some() && step.reward < 0.0,
            "{:?}",
            step.info
        );
    }
    assert_eq!(step.info.env.metrics.episode_length, 1);
}

#[test]
fn a_discrete_arm_index_pushes_the_drawer_in_physics() {
    let mut env = ReLMoGenEnv::new(config("physics", "discrete", "execution = \"physics\"")).unwrap();
    env.reset(3).unwrap();
    let before = opening(&env);
    // The score-map cell holding the drawer front's pixel, pushed along −normal (bin 0).
    let continuous = push_drawer_action(&env);
    let pixel = |x: f32| ((x + 1.0) * 0.5 * (SIDE - 1) as f32).round() as u32;
    let (u, v) = (pixel(continuous[4]), pixel(continuous[5]));
    let index = env.action_spec().arm_index(v / 4, u / 4, 0).unwrap();
    let step = env.step(&[index as f32]).unwrap();
    let info = &step.info;
    assert_eq!(info.subgoal, "arm");
    assert!(info.planner_success, "{info:?}");
    let after = opening(&env);
    assert!(after < before - 0.1, "opening {before:.3} → {after:.3}: {info:?}");
    assert!(step.reward > 0.05 && info.moved > 0.1, "{} {info:?}", step.reward);
}

#[test]
fn a_discrete_base_index_drives_to_the_floor_point_it_sees() {
    let mut env = ReLMoGenEnv::new(config("floor", "discrete", "")).unwrap();
    env.reset(2).unwrap();
    // Face the open west half of the room (a test hook: the next step scores what it finds).
    let robot = env.robot();
    let z = env.env().world().base_pose(robot).unwrap().translation.z;
    let west = nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::new(2.5, 2.0, z),
        nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::PI),
    );
    env.env_mut().world_mut().place(robot, &west).unwrap();
    let spec = *env.action_spec();
    // Bottom-centre cell of the base map, yaw bin 2 of 8: a quarter turn to the left.
    let index = spec.base_index(SIDE / 4 - 2, SIDE / 8, 2).unwrap();
    let step = env.step(&[index as f32]).unwrap();
    let info = &step.info;
    assert!(info.planner_success, "{info:?}");
    let [gx, gy, gyaw] = info.target.unwrap();
    assert!(gx < 2.0 && (gy - 2.0).abs() < 0.3, "the floor ahead: {:?}", info.target);
    let pose = env.env().world().base_pose(robot).unwrap();
    assert!(
        (pose.translation.x - gx).hypot(pose.translation.y - gy) < 0.12,
        "{pose:?} {info:?}"
    );
    let yaw = pose.rotation.euler_angles().2;
    assert!(hearth_sim::kinematics::wrap_angle(yaw - gyaw).abs() < 0.12);
    assert!(
        hearth_sim::kinematics::wrap_angle(gyaw - (std::f64::consts::PI + std::f64::consts::FRAC_PI_2)).abs() < 1e-6
    );
}

#[test]
fn push_cabinet_runs_arm_subgoals_on_the_doors() {
    let dir = std::env::temp_dir().join(format!("hearth-relmogen-doors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("kitchen.json");
    kitchen_with(0).save(&path).unwrap();
    let toml = format!(
        "[env.scene]\nfile = {path:?}\n[env.robot]\nname = \"fetch\"\n[env.task]\nname = \"push_cabinet\"\n\
         [env.sensors]\nmodalities = [\"depth\"]\n[env.sensors.camera]\nwidth = 32\nheight = 32\nbackend = \"raycast\"\n"
    );
    let mut env = ReLMoGenEnv::new(ReLMoGenConfig::from_toml(&toml).unwrap()).unwrap();
    env.reset(1).unwrap();
    let (object, joints) = env.env().task_objects().pop().unwrap();
    assert_eq!(object, "cabinet");
    assert!(
        !joints.is_empty() && joints.iter().all(|j| j.starts_with("door_")),
        "{joints:?}"
    );
    // Push what the image centre sees, straight ahead.
    let step = env.step(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    let info = &step.info;
    assert_eq!(info.subgoal, "arm");
    assert!(info.planner_success != info.failure_reason.is_some(), "{info:?}");
    assert!(info.planning_time > 0.0 && info.skill_time > 0.0, "{info:?}");
    assert_eq!(step.obs.get("depth").unwrap().len(), 32 * 32);
}
