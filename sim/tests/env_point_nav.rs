//! The Gymnasium-shaped env: configs, spaces, determinism, rewards, bad actions, vectorised
//! stepping with auto-reset.

use hearth_sim::env::{Ending, Env, EnvConfig, EnvError, ObsData, VecEnv};

fn config_file(name: &str) -> EnvConfig {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/configs")
        .join(name);
    EnvConfig::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A small fast config: point_nav_fixed down the corridor of the seed-1 home, no camera.
fn corridor(modalities: &[&str]) -> EnvConfig {
    let mut c = config_file("point_nav_fixed.toml");
    c.sensors.modalities = modalities.iter().map(|s| s.to_string()).collect();
    c.scene.small_objects = false;
    c
}

#[test]
fn example_configs_parse_and_bad_keys_are_named() {
    for name in ["point_nav_random.toml", "point_nav_fixed.toml"] {
        config_file(name);
    }
    let err = EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\n[robot]\nname = \"fetch\"\nwheels = 3\n")
        .unwrap_err();
    assert!(err.to_string().contains("wheels"), "{err}");
    let err = EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\ngoal_tolerance = -1.0\n").unwrap_err();
    assert!(
        matches!(err, EnvError::Config { ref key, .. } if key == "task.goal_tolerance"),
        "{err}"
    );
    let err =
        EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\n[sensors]\nmodalities = [\"sonar\"]\n").unwrap_err();
    assert!(err.to_string().contains("sonar"), "{err}");
    let err = EnvConfig::from_toml("[task]\nname = \"point_nav_fixed\"\n").unwrap_err();
    assert!(matches!(err, EnvError::Config { .. }), "{err}");
}

#[test]
fn observations_match_their_declared_spaces() {
    let mut config = corridor(&[
        "task_obs",
        "proprioception",
        "scan",
        "occupancy_grid",
        "depth",
        "seg",
        "bump",
    ]);
    config.sensors.camera.backend = "raycast".into();
    config.sensors.camera.width = 32;
    config.sensors.camera.height = 24;
    let mut env = Env::new(config).unwrap();
    let (obs, info) = env.reset(3).unwrap();
    assert_eq!(info.metrics.episode_length, 0);
    let spaces = env.observation_spaces().to_vec();
    assert_eq!(obs.entries.len(), spaces.len());
    for (space, (name, data)) in spaces.iter().zip(&obs.entries) {
        assert_eq!(&space.name, name);
        assert_eq!(data.len(), space.size(), "{name}");
    }
    let scan = obs.get("scan").and_then(ObsData::as_f32).unwrap();
    assert_eq!(scan.len(), 228, "Hokuyo URG-04LX rays");
    assert!(scan.iter().all(|r| (0.0..=1.0).contains(r)));
    assert!(scan.iter().any(|&r| r < 1.0), "the corridor walls are within 5.6 m");
    let depth = obs.get("depth").and_then(ObsData::as_f32).unwrap();
    assert!(depth.iter().any(|&d| d > 0.0));
    // Goal 2.5 m straight ahead in the robot frame.
    let task = obs.get("task_obs").and_then(ObsData::as_f32).unwrap();
    assert!((task[0] - 2.5).abs() < 0.05 && task[1].abs() < 0.05, "{task:?}");
}

#[test]
fn driving_to_the_goal_succeeds_with_positive_rewards_and_spl() {
    // The Fetch: its wheels take the corridor rug, which stops the TurtleBot's low base.
    let mut config = corridor(&["task_obs"]);
    config.robot.name = "fetch".into();
    let mut env = Env::new(config).unwrap();
    env.reset(0).unwrap();
    let mut total = 0.0;
    let mut last = None;
    for _ in 0..200 {
        let obs_goal = {
            let step = env.step(&[1.0, 0.0]).unwrap();
            total += step.reward;
            if step.terminated || step.truncated {
                last = Some(step);
                break;
            }
            step.obs
        };
        // Steer towards the goal.
        let t = obs_goal.get("task_obs").and_then(ObsData::as_f32).unwrap();
        let heading = t[1].atan2(t[0]);
        if heading.abs() > 0.2 {
            let step = env.step(&[0.3, heading.signum()]).unwrap();
            total += step.reward;
        }
    }
    let step = last.expect("the episode ends");
    assert_eq!(step.info.ending, Some(Ending::Success), "{:?}", step.info);
    assert!(step.terminated && !step.truncated);
    assert!(total > 10.0, "potential progress plus the success reward: {total}");
    let m = step.info.metrics;
    assert!(m.success && m.spl > 0.5 && m.spl <= 1.0, "{m:?}");
    assert!(m.path_length > 2.0, "{m:?}");
}

#[test]
fn the_same_seed_reproduces_an_episode_bit_for_bit() {
    let run = |seed: u64| {
        let mut c = corridor(&["task_obs", "scan"]);
        c.task.name = "point_nav_random".into();
        c.task.start = None;
        c.task.goal = None;
        c.sensors.lidar.dropout = 0.1;
        let mut env = Env::new(c).unwrap();
        let (obs, _) = env.reset(seed).unwrap();
        let mut rewards = Vec::new();
        let mut last = obs;
        for k in 0..20 {
            let s = env.step(&[0.8, if k % 5 == 0 { 0.5 } else { 0.0 }]).unwrap();
            rewards.push(s.reward.to_bits());
            last = s.obs;
        }
        (env.start_and_goal(), rewards, last, env.world().state_hash())
    };
    let a = run(11);
    assert_eq!(a, run(11));
    assert_ne!(a.0, run(12).0, "another seed, another start and goal");
}

#[test]
fn auto_depth_is_rasterised_repeatable_and_agrees_with_the_ray_caster() {
    let run = |backend: &str| {
        let mut c = corridor(&["task_obs", "scan", "depth"]);
        c.sensors.camera.backend = backend.into();
        c.sensors.camera.width = 32;
        c.sensors.camera.height = 24;
        let mut env = Env::new(c).unwrap();
        env.reset(5).unwrap();
        let mut out = Vec::new();
        for k in 0..12 {
            let s = env.step(&[0.7, if k % 4 == 0 { 0.6 } else { -0.2 }]).unwrap();
            out.push((s.reward.to_bits(), s.obs));
        }
        (out, env.world().state_hash())
    };
    let auto = run("auto");
    assert_eq!(auto, run("auto"), "same seed, same observations bit for bit");
    let ray = run("raycast");
    // The camera does not touch the episode: same rewards, scans and world.
    assert_eq!(auto.1, ray.1);
    for ((ra, oa), (rb, ob)) in auto.0.iter().zip(&ray.0) {
        assert_eq!(ra, rb);
        assert_eq!(oa.get("scan"), ob.get("scan"));
        let da = oa.get("depth").and_then(ObsData::as_f32).unwrap();
        let db = ob.get("depth").and_then(ObsData::as_f32).unwrap();
        let close = da.iter().zip(db).filter(|(x, y)| (*x - *y).abs() <= 0.02).count();
        assert!(close * 100 >= da.len() * 95, "{close} of {} pixels agree", da.len());
        assert!(da.iter().any(|&d| d > 0.0));
    }
}

#[test]
fn bad_actions_change_nothing() {
    let mut env = Env::new(corridor(&["task_obs"])).unwrap();
    assert!(matches!(env.step(&[0.0, 0.0]), Err(EnvError::NotReset)));
    env.reset(1).unwrap();
    let before = env.world().state_hash();
    assert!(matches!(env.step(&[f32::NAN, 0.0]), Err(EnvError::BadAction(_))));
    assert!(matches!(env.step(&[0.1]), Err(EnvError::BadAction(_))));
    assert_eq!(env.world().state_hash(), before);
}

#[test]
fn vectorised_envs_batch_and_auto_reset() {
    let mut c = corridor(&["task_obs", "scan"]);
    c.episode.max_steps = 3;
    let mut envs = VecEnv::new(&c, 2).unwrap();
    let obs = envs.reset(5).unwrap();
    assert_eq!(obs.get("scan").unwrap().len(), 2 * 228);
    assert!(envs.step(&[0.0; 3]).is_err(), "2 values per env");
    let mut truncations = 0;
    for _ in 0..3 {
        let s = envs.step(&[0.2, 0.0, 0.2, 0.0]).unwrap();
        assert_eq!(s.rewards.len(), 2);
        assert_eq!(s.obs.get("task_obs").unwrap().len(), 10);
        truncations += s.truncated.iter().filter(|&&t| t).count();
        if s.truncated.iter().all(|&t| t) {
            assert_eq!(s.infos[0].ending, Some(Ending::Timeout));
            assert_eq!(s.infos[0].metrics.episode_length, 3);
        }
    }
    assert_eq!(truncations, 2, "both envs hit the 3-step limit once and were reset");
    let s = envs.step(&[0.2, 0.0, 0.2, 0.0]).unwrap();
    assert_eq!(
        s.infos[0].metrics.episode_length, 1,
        "a fresh episode after the auto-reset"
    );
}

/// Driving straight at the goal never scores a negative shaping reward, the first step
/// included: the potential is measured from where the robot stands after the reset, the same
/// way as at every step.
#[test]
fn driving_straight_at_the_goal_earns_no_negative_reward() {
    for robot in ["fetch", "turtlebot"] {
        let mut config = corridor(&["task_obs"]);
        config.robot.name = robot.into();
        let mut env = Env::new(config).unwrap();
        env.reset(0).unwrap();
        let rewards: Vec<f64> = (0..12).map(|_| env.step(&[1.0, 0.0]).unwrap().reward).collect();
        assert!(rewards.iter().all(|&r| r >= 0.0), "{robot}: {rewards:?}");
        assert!(rewards.iter().sum::<f64>() > 0.0, "{robot}: {rewards:?}");
    }
    // A bare hall whose start lies on a cell corner, not a cell centre.
    let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
        "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
      "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    let path = std::env::temp_dir().join(format!("hearth_first_reward_{}.json", std::process::id()));
    std::fs::write(&path, hall).unwrap();
    let toml = "[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n[sensors]\nmodalities = [\"task_obs\"]\n";
    let mut config = EnvConfig::from_toml(toml).unwrap();
    config.scene.file = Some(path.clone());
    let mut env = Env::new(config).unwrap();
    std::fs::remove_file(&path).unwrap();
    env.reset(0).unwrap();
    let rewards: Vec<f64> = (0..12).map(|_| env.step(&[1.0, 0.0]).unwrap().reward).collect();
    assert!(rewards.iter().all(|&r| r >= 0.0), "hall: {rewards:?}");
    assert!(rewards.iter().sum::<f64>() > 0.0, "hall: {rewards:?}");
}
