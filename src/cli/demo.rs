//! `hearth demo`: the mobile-manipulation story in a generated home.
//!
//! One seed: a stage-by-stage report, the camera images and the trajectory under `--out`.
//! `--seeds N`: N homes in a row, the success rate and the failure reasons, optionally as JSON.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use hearth_skills::Execution;
use hearth_skills::story::{StoryOptions, StoryReport, run_story};

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Seed of the home (the first one with --seeds).
    #[arg(long, default_value_t = 3)]
    seed: u64,
    /// Run this many homes (seed, seed + 1, …) and report the success rate.
    #[arg(long)]
    seeds: Option<u64>,
    /// Write the runs and the success rate as JSON here (with --seeds, or one run).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Rooms of the generated home besides the corridor (2 to 12; the kitchen comes first).
    #[arg(long, default_value_t = 2)]
    rooms: usize,
    /// Teleport along the plans instead of driving the controllers in physics.
    #[arg(long)]
    kinematic: bool,
    /// Where the images, report and trajectory of a single run go.
    #[arg(long, default_value = "/tmp/hearth-demo")]
    out: PathBuf,
}

fn options(a: &DemoArgs, seed: u64, out_dir: Option<PathBuf>) -> StoryOptions {
    StoryOptions {
        seed,
        rooms: a.rooms,
        execution: if a.kinematic {
            Execution::Kinematic
        } else {
            Execution::Physics
        },
        out_dir,
        ..Default::default()
    }
}

fn run_json(r: &StoryReport) -> serde_json::Value {
    serde_json::json!({
        "seed": r.seed,
        "success": r.success,
        "failure": r.failure,
        "wall_time": r.wall_time,
        "stages": r.stages.iter().map(|s| serde_json::json!({
            "name": s.name, "success": s.success, "sim_time": s.sim_time, "wall_time": s.wall_time,
        })).collect::<Vec<_>>(),
    })
}

pub fn run(a: DemoArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (2..=12).contains(&a.rooms),
        "--rooms is {}; it must be 2 to 12",
        a.rooms
    );
    match a.seeds {
        None => single(&a),
        Some(0) => anyhow::bail!("--seeds must be at least 1"),
        Some(n) => many(&a, n),
    }
}

fn single(a: &DemoArgs) -> anyhow::Result<()> {
    let mode = if a.kinematic { "kinematic" } else { "physics" };
    println!(
        "Hearth demo: a Fetch in a generated home (seed {}, {} rooms, {mode} execution) opens a kitchen drawer\nand puts a bowl from the worktop into the sink.\n",
        a.seed, a.rooms
    );
    let r = run_story(&options(a, a.seed, Some(a.out.clone())));
    for (i, s) in r.stages.iter().enumerate() {
        println!(
            "{i}. {:<20} {:<4} {:>6.1} s sim {:>6.1} s wall  {}",
            s.name,
            if s.success { "ok" } else { "FAIL" },
            s.sim_time,
            s.wall_time,
            s.detail
        );
    }
    println!();
    match &r.failure {
        None => println!("Success in {:.1} s.", r.wall_time),
        Some(f) => println!(
            "Failed at `{}` ({}) after {:.1} s: {}",
            f.stage, f.reason, r.wall_time, f.message
        ),
    }
    let images = r.stages.iter().filter(|s| s.image.is_some()).count();
    println!(
        "Wrote {images} camera images, report.json and trajectory.json ({} samples) to {}",
        r.trajectory.len(),
        a.out.display()
    );
    if let Some(path) = &a.json {
        let doc = serde_json::json!({
            "runs": [run_json(&r)],
            "success_rate": if r.success { 1.0 } else { 0.0 },
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn many(a: &DemoArgs, n: u64) -> anyhow::Result<()> {
    let clock = Instant::now();
    let mut runs = Vec::new();
    let mut reports = Vec::new();
    for seed in a.seed..a.seed + n {
        let r = run_story(&options(a, seed, None));
        match &r.failure {
            None => println!("seed {seed:>3}: ok ({:.1} s)", r.wall_time),
            Some(f) => println!(
                "seed {seed:>3}: FAIL at {} ({}): {} ({:.1} s)",
                f.stage, f.reason, f.message, r.wall_time
            ),
        }
        runs.push(run_json(&r));
        reports.push(r);
    }
    let ok = reports.iter().filter(|r| r.success).count();
    let rate = ok as f64 / n as f64;
    let mut reasons = std::collections::BTreeMap::<String, usize>::new();
    for f in reports.iter().filter_map(|r| r.failure.as_ref()) {
        *reasons.entry(format!("{} at {}", f.reason, f.stage)).or_default() += 1;
    }
    println!(
        "\nsuccess rate {:.0} % ({ok}/{n}), {:.1} s per seed",
        100.0 * rate,
        clock.elapsed().as_secs_f64() / n as f64
    );
    for (why, count) in &reasons {
        println!("  {count} × {why}");
    }
    if let Some(path) = &a.json {
        let doc = serde_json::json!({ "runs": runs, "success_rate": rate });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
