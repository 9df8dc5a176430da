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
