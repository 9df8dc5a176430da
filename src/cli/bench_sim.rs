//! `hearth bench sim`: physics steps per second of a home after it has settled, with and
//! without the robot.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use hearth_sim::scene::{RobotPlacement, SceneFile};
use hearth_sim::world::{World, WorldConfig};
use serde_json::json;

use super::bench::percentile;

/// Which robot the home holds while it is timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchRobot {
    /// The Fetch (differential drive, free base) at the scene's robot placement; the home is
    /// also timed without it.
    Fetch,
    /// No robot.
    None,
}

#[derive(Args, Debug)]
pub struct BenchSimArgs {
    #[command(flatten)]
    home: super::home::HomeArgs,
    /// Robot in the home.
    #[arg(long, value_enum, default_value_t = BenchRobot::Fetch)]
    robot: BenchRobot,
    /// Physics steps to time (after settling).
    #[arg(long, default_value_t = 600)]
    steps: usize,
    /// Timing chunks the steps are split into; the median chunk rate is reported.
    #[arg(long, default_value_t = 20)]
    chunks: usize,
    /// Control steps allowed for settling before timing starts.
    #[arg(long, default_value_t = 600)]
    settle: usize,
    /// Keep every body awake (rapier's sleeping disabled).
    #[arg(long)]
    no_sleep: bool,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// One timed world.
struct Timing {
    bodies: usize,
    colliders: usize,
    dynamic_bodies: usize,
    sleeping_bodies: usize,
    settle_steps: usize,
    settled: bool,
    hz_median: f64,
    hz_min: f64,
    hz_max: f64,
    state_hash: u64,
}

impl Timing {
    fn json(&self) -> serde_json::Value {
        json!({
            "physics_hz_median": self.hz_median,
            "physics_hz_min": self.hz_min,
            "physics_hz_max": self.hz_max,
            "bodies": self.bodies,
            "colliders": self.colliders,
            "dynamic_bodies": self.dynamic_bodies,
            "sleeping_bodies": self.sleeping_bodies,
            "settle_steps": self.settle_steps,
            "settled": self.settled,
            "state_hash": format!("{:016x}", self.state_hash),
        })
    }
}

/// Loads the scene, settles it, then times `steps` physics steps in `chunks` chunks.
fn time_world(scene: &SceneFile, config: &WorldConfig, a: &BenchSimArgs) -> anyhow::Result<Timing> {
    let mut world = World::new(config.clone())?;
    world
        .load_scene(scene)
        .with_context(|| format!("loading scene `{}` into the world", scene.name))?;
    let settle = world.settle(a.settle);
    let chunk = a.steps.div_ceil(a.chunks).max(1);
    let mut rates = Vec::with_capacity(a.chunks);
    let mut done = 0;
    while done < a.steps {
        let n = chunk.min(a.steps - done);
        let t0 = Instant::now();
        for _ in 0..n {
            world.step_physics();
        }
        let dt = t0.elapsed().as_secs_f64();
        rates.push(n as f64 / dt.max(1e-9));
        done += n;
    }
    let after = world.settle(0);
    Ok(Timing {
        bodies: world.body_count(),
        colliders: world.collider_count(),
        dynamic_bodies: after.dynamic_bodies,
        sleeping_bodies: after.sleeping_bodies,
        settle_steps: settle.steps,
        settled: settle.at_rest,
        hz_median: percentile(&rates, 0.5),
        hz_min: percentile(&rates, 0.0),
        hz_max: percentile(&rates, 1.0),
        state_hash: world.state_hash(),
    })
}

/// The home to time: the file, or a generated one (with a Fetch placement in its corridor).
fn bench_scene(a: &BenchSimArgs) -> anyhow::Result<SceneFile> {
    a.home.load(None)
}

/// Runs `hearth bench sim`.
pub fn run(a: BenchSimArgs) -> anyhow::Result<()> {
    if a.steps == 0 || a.chunks == 0 {
        bail!("--steps and --chunks must be at least 1");
    }
    let mut scene = bench_scene(&a)?;
    let with_robot = a.robot == BenchRobot::Fetch;
    let mut bare = scene.clone();
    bare.robot = None;
    if with_robot {
        // Like `scene export --robot`: the scene's placement, else the origin.
        let (position, yaw) = scene.robot.as_ref().map_or(([0.0; 3], 0.0), |p| (p.position, p.yaw));
        scene.robot = Some(RobotPlacement {
            name: "fetch".to_owned(),
            position,
            yaw,
        });
    } else {
        scene.robot = None;
    }
    let config = WorldConfig {
        sleeping: !a.no_sleep,
        ..WorldConfig::default()
    };
    super::bench::create_json(a.json.as_deref())?;
    let main = time_world(&scene, &config, &a)?;
    let without = if with_robot {
        Some(time_world(&bare, &config, &a)?)
    } else {
        None
    };

    let robot = if with_robot { "fetch" } else { "none" };
    println!(
        "scene `{}`: {} objects, robot {robot}, sleeping {}, timestep {:.5} s, {} physics steps in {} chunks",
        scene.name,
        scene.objects.len(),
        if a.no_sleep { "off" } else { "on" },
        config.timestep,
        a.steps,
        a.chunks
    );
    let line = |label: &str, t: &Timing| {
        println!(
            "  {label:<14} {:>9.0} Hz median ({:.0}..{:.0}), {} bodies ({} dynamic, {} asleep), settled: {} after {} steps",
            t.hz_median, t.hz_min, t.hz_max, t.bodies, t.dynamic_bodies, t.sleeping_bodies, t.settled, t.settle_steps
        );
    };
    line(&format!("with {robot}"), &main);
    if let Some(w) = &without {
        line("without robot", w);
    }
    println!("  state hash {:016x}", main.state_hash);

    let mut report = main.json();
    report["robot"] = json!(robot);
    report["sleeping"] = json!(!a.no_sleep);
    report["scene"] = json!(scene.name);
    report["objects"] = json!(scene.objects.len());
    report["steps"] = json!(a.steps);
    report["chunks"] = json!(a.chunks);
    report["timestep"] = json!(config.timestep);
    if let Some(w) = &without {
        report["physics_hz_median_without_robot"] = json!(w.hz_median);
        report["bodies_without_robot"] = json!(w.bodies);
        report["without_robot"] = w.json();
    }
    if let Some(path) = &a.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
