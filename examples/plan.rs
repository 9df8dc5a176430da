//! Plan a Panda's move between two shelf slots, given as end-effector poses, smooth it into a timed motion
//! within the arm's velocity, acceleration and jerk limits, and check it at a fine resolution.
//!
//! `cargo run --release --example plan`
//!
//! The steps are the ones `hearth bench plan` and the arm skills take: obstacles in a
//! `ParryScene`, exact state validity (forward kinematics, links against obstacles,
//! self-collision), goal configurations by collision-aware IK, BiRRT, then random and
//! acceleration-bounded (parabolic) shortcutting and a jerk-limited pass. At the end the same
//! plan is made in one call with `pipeline::MotionPlanner`.

use std::sync::Arc;
use std::time::Duration;

use hearth::kinematics::nalgebra::{Isometry3, Translation3, UnitQuaternion};
use hearth::kinematics::{
    Chain, IkSettings, IkSolver, IkTarget, RobotModel, SelfCollisionMatrix, SelfCollisionSettings,
};
use hearth::planning::goal::PoseGoal;
use hearth::planning::obstacles::Obstacle;
use hearth::planning::pipeline::{MotionPlanner, MotionSettings};
use hearth::planning::shortcut::{ShortcutSettings, Smoothing, smooth};
use hearth::planning::space::JointSpace;
use hearth::planning::trajectory::Limits;
use hearth::planning::{BiRrt, Budget, MotionValidator, ParryScene, PlanRequest, Planner, RobotValidity};
use parry3d::math::{Pose, Vector};
use rand::SeedableRng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The robot, the planned chain, and which link pairs can never touch.
    let panda = RobotModel::builtin("panda")?;
    let arm = Chain::named(&panda, "arm")?;
    let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings::default());

    // A table in front of the robot with a two-board shelf on it. `try_new` refuses an
    // obstacle with a NaN pose or a negative size, naming it.
    let board =
        |name: &str, z: f32| Obstacle::cuboid(name, Pose::translation(0.6, 0.0, z), Vector::new(0.15, 0.4, 0.01));
    let scene = ParryScene::try_new(vec![
        Obstacle::cuboid("table", Pose::translation(0.6, 0.0, 0.29), Vector::new(0.25, 0.5, 0.01)),
        board("lower board", 0.6),
        board("upper board", 0.86),
        Obstacle::cuboid(
            "left side",
            Pose::translation(0.6, 0.4, 0.58),
            Vector::new(0.15, 0.01, 0.28),
        ),
    ])?;
    let mut validity = RobotValidity::new(arm.clone(), acm, Arc::new(scene));
    let space = JointSpace::from_chain(&arm)?;
    // Edges are checked every 1/32 rad, midpoint first.
    let mut motion = MotionValidator::try_new(space.clone(), 1.0 / 32.0)?;

    // The gripper points forward into the shelf: it starts under the lower board and must
    // move to the slot between the two boards, so it has to back out and go round the
    // board's front edge. IK turns each pose into collision-free configurations: one for the
    // start, up to eight for the goal (the planner may end at any of them).
    let forward = UnitQuaternion::from_euler_angles(0.0, std::f64::consts::FRAC_PI_2, 0.0);
    let reach = |z: f64| IkTarget::Pose(Isometry3::from_parts(Translation3::new(0.55, 0.0, z), forward));
    let mut ik = IkSolver::new(arm.clone(), "panda_hand_tcp", IkSettings::default())?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7); // the same seed gives the same motion
    let home = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    let lower = PoseGoal {
        solutions: 1,
        ..PoseGoal::new(reach(0.47))
    };
    let start = lower.sample(&mut ik, &mut validity, &home, &mut rng)?.states()[0].clone();
    let goal = PoseGoal::new(reach(0.73)).sample(&mut ik, &mut validity, &start, &mut rng)?;
    println!("goal: {} collision-free IK solutions", goal.states().len());

    let direct = goal
        .states()
        .iter()
        .any(|g| motion.check_motion(&mut validity, &start, g));
    println!(
        "a straight motion to a goal is {}",
        if direct { "free" } else { "blocked" }
    );

    // Plan. A start in collision, goals in collision, NaNs and a spent budget are typed errors.
    let request = PlanRequest::new(start, goal);
    let solution = BiRrt::default().plan(&mut motion, &mut validity, &request, &Budget::time(1.0), &mut rng)?;
    let stats = &solution.stats;
    println!(
        "BiRRT: {} waypoints, length {:.2} rad, {:.2} ms, {} iterations, {} states checked",
        solution.path.states.len(),
        solution.path.length(&space),
        stats.time.as_secs_f64() * 1e3,
        stats.iterations,
        stats.states_checked
    );

    // Smooth into a timed motion within the Panda's limits (velocity from the model,
    // acceleration and jerk from Franka's datasheet), its states checked every 0.002 rad.
    let limits = Limits::for_chain(&arm);
    let fine = 0.002;
    let settings = ShortcutSettings {
        fine_resolution: Some(fine),
        verify_resolution: Some(fine),
        ..ShortcutSettings::default()
    };
    let smoothed = smooth(
        Smoothing::Parabolic,
        &mut motion,
        &mut validity,
        &solution.path,
        &limits,
        &settings,
        Duration::from_secs(1),
        &mut rng,
    )?;
    let trajectory = &smoothed.trajectory;
    trajectory.check(&space, &mut validity, fine)?;
    println!(
        "parabolic: {:.3} s of motion, length {:.2} rad, collision-free at {fine} rad",
        trajectory.duration(),
        trajectory.length(&space, fine)?
    );

    // A jerk-limited version for execution, checked the same way.
    let jerk_limited = trajectory.with_jerk_limits(&limits)?;
    jerk_limited.check(&space, &mut validity, fine)?;
    println!("jerk-limited: {:.3} s of motion", jerk_limited.duration());

    // Sample position and velocity at any time, e.g. for a controller at 100 Hz.
    let (mut q, mut v) = (vec![0.0; 7], vec![0.0; 7]);
    let steps = (jerk_limited.duration() * 100.0).ceil() as usize;
    let mut fastest: f64 = 0.0;
    for i in 0..=steps {
        jerk_limited.sample(i as f64 / 100.0, &mut q, Some(&mut v));
        fastest = v
            .iter()
            .zip(limits.velocity())
            .fold(fastest, |m, (v, max)| m.max(v.abs() / max));
    }
    println!(
        "{} samples at 100 Hz; the fastest joint at {:.1} % of its velocity limit",
        steps + 1,
        fastest * 100.0
    );
    let tool = ik.tool_pose(&q)?;
    println!("the gripper ends at {:?}", tool.translation.vector.as_slice());

    // The same chain in one call, as `hearth bench plan` sets it up: BiRRT in the joints'
    // reach metric (a wrist weighs less than a shoulder), parabolic smoothing within the
    // chain's limits, every motion checked at 0.002 rad.
    let mut planner = MotionPlanner::new(validity, MotionSettings::default())?;
    let planned = planner.plan(&request.start, request.goal.clone(), &Budget::time(1.0), &mut rng)?;
    println!(
        "MotionPlanner: {:.2} ms planning ({} iterations), {:.2} ms smoothing, {:.3} s of motion",
        planned.stats.time.as_secs_f64() * 1e3,
        planned.stats.iterations,
        planned.smoothing_time.as_secs_f64() * 1e3,
        planned.trajectory.duration()
    );
    Ok(())
}
