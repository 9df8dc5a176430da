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
    println!("Next: `hearth kin info --robot fetch`, `hearth bench kin --robot panda`.");
    Ok(())
}
