//! `hearth demo`: the main job on the embedded defaults.

use std::time::Instant;

use clap::Args;
use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};

use super::bench::{bench_chain, ik_random_poses};

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// IK queries per robot.
    #[arg(long, default_value_t = 200)]
    queries: usize,
    /// RNG seed.
    #[arg(long, default_value_t = 7)]
    seed: u64,
}

pub fn run(a: DemoArgs) -> anyhow::Result<()> {
    println!("Hearth demo: built-in robots, forward and inverse kinematics\n");
    for name in ["panda", "fetch"] {
        let t0 = Instant::now();
        let m = RobotModel::builtin(name)?;
        let load_ms = t0.elapsed().as_secs_f64() * 1e3;
        let chain = bench_chain(&m, None)?;
        let tip = chain.tip().map(|t| m.links()[t].name.clone()).unwrap_or_default();
        println!(
            "{name}: {} links, {} joints, {} DOF (loaded in {load_ms:.1} ms)",
            m.links().len(),
            m.joints().len(),
            m.dof()
        );
        println!(
            "  chain `{}`: {} -> {tip}",
            chain.name(),
            chain.joint_names().join(", ")
        );
        let t0 = Instant::now();
        let sc = SelfCollisionMatrix::compute(
            &m,
            &SelfCollisionSettings {
                samples: 500,
                ..Default::default()
            },
        );
        println!(
            "  self-collision: {} link pairs to check ({} samples, {:.0} ms)",
            sc.checked_geometric_pairs(&m).len(),
            500,
            t0.elapsed().as_secs_f64() * 1e3
        );
        let stats = ik_random_poses(&chain, a.queries, a.seed)?;
        println!(
            "  IK: {}/{} random reachable poses solved to 1 mm / 0.01 rad ({:.1} %), median {:.1} µs, p95 {:.1} µs",
            stats.successes,
            stats.samples,
            100.0 * stats.success_rate(),
            stats.percentile(0.5),
            stats.percentile(0.95)
        );
        println!();
    }
    plan_demo(a.seed)?;
    sim_demo(a.seed)?;
    println!("Next: `hearth kin info --robot fetch`, `hearth bench kin --robot panda`.");
    Ok(())
}

/// A pick above a table with a post in the way: IK pose goal, BiRRT, smoothing, trajectory.
fn plan_demo(seed: u64) -> anyhow::Result<()> {
    use std::sync::Arc;
    use std::time::Duration;

    use hearth_kinematics::nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use hearth_kinematics::parry3d::math::{Pose, Vector};
    use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget};
    use hearth_planning::goal::PoseGoal;
    use hearth_planning::obstacles::{Obstacle, ParryScene};
    use hearth_planning::shortcut::{ShortcutSettings, Smoothing, smooth};
    use hearth_planning::space::JointSpace;
    use hearth_planning::trajectory::{Limits, Trajectory};
    use hearth_planning::{BiRrt, Budget, MotionValidator, PlanRequest, Planner, RobotValidity};
    use rand::SeedableRng;

    println!("Planning: Panda over a table with a post between start and goal");
    let m = RobotModel::builtin("panda")?;
    let arm = Chain::named(&m, "arm")?;
    let mut reference = m.neutral_configuration();
    Chain::new(&m, &["panda_finger_joint1"])?.scatter(&[0.04], &mut reference);
    let acm = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 500,
            ..Default::default()
        },
    );
    let scene = ParryScene::new(vec![
        Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.2), Vector::new(0.3, 0.6, 0.02)),
        Obstacle::cuboid("post", Pose::translation(0.5, 0.0, 0.45), Vector::new(0.05, 0.05, 0.25)),
    ]);
    let mut validity = RobotValidity::new(arm.clone(), acm, Arc::new(scene));
    validity.set_reference(&reference)?;
    let mut ik = IkSolver::new(arm.clone(), "panda_hand_tcp", IkSettings::default())?;
    ik.set_reference(&reference)?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let start = vec![-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
    let down = UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0);
    let target = Isometry3::from_parts(Translation3::new(0.5, 0.3, 0.35), down);
    let t0 = Instant::now();
    let goal = PoseGoal::new(IkTarget::Pose(target)).sample(&mut ik, &mut validity, &start, &mut rng)?;
    println!(
        "  goal pose (0.50, 0.30, 0.35), gripper down: {} collision-free IK solutions in {:.1} ms",
        goal.states().len(),
        t0.elapsed().as_secs_f64() * 1e3
    );
    let space = JointSpace::from_chain(&arm).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut motion = MotionValidator::new(space.clone(), 0.02);
    let request = PlanRequest::new(start, goal);
    let solution = BiRrt::default().plan(&mut motion, &mut validity, &request, &Budget::time(1.0), &mut rng)?;
    println!(
        "  BiRRT: {} waypoints, length {:.2} rad, {:.1} ms, {} state checks",
        solution.path.states.len(),
        solution.path.length(&space),
        solution.stats.time.as_secs_f64() * 1e3,
        solution.stats.states_checked
    );
    let limits = Limits::for_chain(&arm);
    let settings = ShortcutSettings {
        fine_resolution: Some(0.001),
        ..Default::default()
    };
    let t0 = Instant::now();
    let out = smooth(
        Smoothing::Parabolic,
        &mut motion,
        &mut validity,
        &solution.path,
        &limits,
        &settings,
        Duration::from_secs(1),
        &mut rng,
    )?;
    let raw = Trajectory::rest_to_rest(&space, &solution.path, &limits)?;
    println!(
        "  smoothing: {:.2} s of motion stopping at every waypoint -> {:.2} s acceleration-bounded ({} shortcuts, {:.1} ms)",
        raw.duration(),
        out.trajectory.duration(),
        out.random.accepted + out.parabolic.accepted,
        t0.elapsed().as_secs_f64() * 1e3
    );
    let waypoints = out.trajectory.to_path(&space, 0.2);
    let jerk = Trajectory::jerk_limited(&space, &waypoints, &limits)?;
    let valid = jerk.check(&space, &mut validity, 0.002).is_ok();
    println!(
        "  jerk-limited (Ruckig) execution through {} waypoints: {:.2} s, collision-free at 0.002 rad: {valid}\n",
        waypoints.states.len(),
        jerk.duration()
    );
    Ok(())
}

/// A generated home in the physics world: the Fetch drives 2 m down the corridor, then plans an
/// arm motion against the live colliders and executes it with its joint controllers.
fn sim_demo(seed: u64) -> anyhow::Result<()> {
    use std::sync::Arc;
    use std::time::Duration;

    use anyhow::Context;
    use hearth_kinematics::nalgebra::Point3;
    use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget};
    use hearth_planning::goal::PoseGoal;
    use hearth_planning::shortcut::{ShortcutSettings, Smoothing, smooth};
    use hearth_planning::space::JointSpace;
    use hearth_planning::trajectory::Limits;
    use hearth_planning::{BiRrt, Budget, MotionValidator, PlanRequest, Planner, RobotValidity};
    use hearth_sim::scene::{GenerateOptions, SceneInfo, generate};
    use hearth_sim::world::{World, WorldConfig};
    use rand::SeedableRng;

    const SUPPORT_LINKS: [&str; 3] = ["base_link", "l_wheel_link", "r_wheel_link"];

    println!("Simulation: a generated home, the Fetch driving and moving its arm in it");
    let t0 = Instant::now();
    let home = generate(&GenerateOptions {
        seed,
        rooms: 3,
        ..Default::default()
    })?;
    let mut world = World::new(WorldConfig::default())?;
    let loaded = world.load_scene(&home)?;
    let fetch = loaded.robot.context("the generated home has no robot placement")?;
    let settle = world.settle(300);
    println!(
        "  home seed {seed}: {} rooms, {} objects, {} bodies; loaded and settled in {:.2} s ({} control steps, at rest: {})",
        SceneInfo::of(&home).rooms.len(),
        home.objects.len(),
        world.body_count(),
        t0.elapsed().as_secs_f64(),
        settle.steps,
        settle.at_rest
    );

    // Differential drive down the corridor until 2 m are covered (or 15 s have passed).
    let origin = world.base_pose(fetch)?.translation.vector;
    let t_drive = world.time();
    world.drive(fetch, 0.4, 0.0)?;
    let mut driven = 0.0;
    while driven < 2.0 && world.time() - t_drive < 15.0 {
        world.step();
        driven = (world.base_pose(fetch)?.translation.vector - origin).xy().norm();
    }
    world.drive(fetch, 0.0, 0.0)?;
    for _ in 0..30 {
        world.step();
    }
    let heading = world.base_pose(fetch)?.rotation.euler_angles().2;
    println!(
        "  drive (v = 0.4 m/s, ω = 0): {driven:.2} m in {:.2} s of simulated time, heading {heading:+.3} rad",
        world.time() - t_drive
    );

    // An arm motion from the tuck to a point 60 cm ahead at shoulder height, planned against
    // the live world from where the base stands now.
    let model = world.model(fetch)?.clone();
    let arm = Chain::named(&model, "arm_with_torso")?;
    let mut held = world.joint_positions(fetch)?;
    for (v, x) in held.iter_mut().enumerate() {
        *x = x.clamp(model.lower()[v], model.upper()[v]);
    }
    let base = world.base_pose(fetch)?;
    let acm = SelfCollisionMatrix::compute(
        &model,
        &SelfCollisionSettings {
            samples: 500,
            ..Default::default()
        },
    );
    // What the base stands on (floor, rug) is no obstacle for the arm's planner.
    let under: Vec<_> = world
        .contacts(fetch)?
        .into_iter()
        .filter(|c| SUPPORT_LINKS.contains(&c.link.as_str()))
        .map(|c| c.other)
        .chain(world.ground())
        .collect();
    let live = world
        .obstacles_view(&[fetch])?
        .excluding_bodies(&under)
        .with_margin(0.01);
    let mut validity = RobotValidity::new(arm.clone(), acm, Arc::new(live));
    validity.set_reference(&held)?;
    validity.set_base(base);
    let mut start = vec![0.0; arm.dof()];
    arm.gather(&held, &mut start);
    let mut ik = IkSolver::new(arm.clone(), "gripper_link", IkSettings::default())?;
    ik.set_reference(&held)?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let t_plan = Instant::now();
    let goal = PoseGoal::new(IkTarget::Position(Point3::new(0.6, 0.0, 1.0))).sample(
        &mut ik,
        &mut validity,
        &start,
        &mut rng,
    )?;
    let space = JointSpace::from_chain(&arm).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut motion = MotionValidator::new(space.clone(), 0.02);
    let found = BiRrt::default().plan(
        &mut motion,
        &mut validity,
        &PlanRequest::new(start, goal),
        &Budget::time(2.0),
        &mut rng,
    )?;
    let smoothed = smooth(
        Smoothing::Parabolic,
        &mut motion,
        &mut validity,
        &found.path,
        &Limits::for_chain(&arm),
        &ShortcutSettings::default(),
        Duration::from_secs(1),
        &mut rng,
    )?;
    let plan_ms = t_plan.elapsed().as_secs_f64() * 1e3;
    let motion_s = smoothed.trajectory.duration();
    println!(
        "  arm plan (IK goal + BiRRT + parabolic smoothing) against the live world: {plan_ms:.0} ms, {} waypoints, {motion_s:.2} s of motion",
        found.path.states.len()
    );

    // Execute: position targets sampled from the trajectory at the 30 Hz control rate.
    let dt = world.config().control_dt();
    let mut target = held.clone();
    let mut sample = vec![0.0; arm.dof()];
    let mut touches = std::collections::BTreeSet::new();
    let mut t = 0.0;
    while t < motion_s + 1.0 {
        t += dt;
        smoothed.trajectory.sample(t.min(motion_s), &mut sample, None);
        arm.scatter(&sample, &mut target);
        world.set_position_targets(fetch, &target)?;
        world.step();
        let pushing = world.contacts(fetch)?.into_iter().filter(|c| c.force.norm() > 0.0);
        touches.extend(
            pushing
                .filter(|c| !SUPPORT_LINKS.contains(&c.link.as_str()))
                .map(|c| format!("{} on {}", c.link, c.other_name)),
        );
    }
    let goal_q = smoothed.path.states.last().context("empty smoothed path")?;
    let mut reached = vec![0.0; arm.dof()];
    arm.gather(&world.joint_positions(fetch)?, &mut reached);
    let error = reached
        .iter()
        .zip(goal_q)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let tip = base.inverse_transform_point(&Point3::from(
        world.link_pose(fetch, "gripper_link")?.translation.vector,
    ));
    println!(
        "  executed: largest joint error at the end {error:.4} rad, gripper at ({:.2}, {:.2}, {:.2}) in the base frame (target 0.60, 0.00, 1.00)",
        tip.x, tip.y, tip.z
    );
    if touches.is_empty() {
        println!("  contacts of the arm during execution: none (base and wheels rest on the floor)\n");
    } else {
        let list: Vec<String> = touches.into_iter().collect();
        println!("  contacts of the arm during execution: {}\n", list.join(", "));
    }
    sensors_demo(&world, fetch)
}

/// What the Fetch sees where the simulation demo left it: a visual-rl camera frame from its
/// eyes (wgpu when an adapter exists, otherwise the ray caster), written as images.
fn sensors_demo(world: &hearth_sim::world::World, fetch: hearth_sim::world::ModelHandle) -> anyhow::Result<()> {
    use hearth_sim::sensors::{Camera, CameraConfig, ModalitySet, Preset, SemanticClass};

    println!("Sensors: the Fetch's head camera (visual-rl preset)");
    let t = Instant::now();
    let mut camera = Camera::new(world, Some(fetch), CameraConfig::preset(Preset::VisualRl)?)?;
    let setup_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    camera.render(world, ModalitySet::ALL)?;
    let frame = camera.frame();
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let seen: Vec<f32> = frame.depth.iter().copied().filter(|&d| d > 0.0).collect();
    let mut classes = std::collections::BTreeMap::<u32, usize>::new();
    for &c in &frame.seg {
        *classes.entry(c).or_default() += 1;
    }
    let mut by_area: Vec<(usize, u32)> = classes.into_iter().map(|(c, n)| (n, c)).collect();
    by_area.sort_unstable_by(|a, b| b.cmp(a));
    let pixels = frame.seg.len().max(1) as f64;
    let top: Vec<String> = by_area
        .iter()
        .take(5)
        .map(|&(n, c)| {
            format!(
                "{} {:.0}%",
                SemanticClass::name(c).unwrap_or("?"),
                100.0 * n as f64 / pixels
            )
        })
        .collect();
    let nearest = seen.iter().copied().fold(f32::INFINITY, f32::min);
    println!(
        "  {} backend ({}): all 8 modalities of a {}×{} frame in {render_ms:.1} ms (set-up {setup_ms:.0} ms)",
        camera.backend().name(),
        camera.adapter(),
        frame.width,
        frame.height
    );
    println!(
        "  depth: {:.0}% of pixels see a surface, nearest {nearest:.2} m; classes in view: {}",
        100.0 * seen.len() as f64 / pixels,
        top.join(", ")
    );
    let out = std::env::temp_dir().join("hearth-demo-camera");
    let written = frame.save(&out, "")?;
    println!("  wrote {} images and arrays to {}\n", written.len(), out.display());
    Ok(())
}
