//! `hearth bench env`: steps per second of one env and of N envs stepped together, and memory
//! per env.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use hearth_sim::env::{Env, EnvConfig, VecEnv};
use rand::{RngExt, SeedableRng};
use serde_json::json;

#[derive(Args, Debug)]
pub struct BenchEnvArgs {
    /// Env configuration (TOML), e.g. examples/configs/point_nav_random.toml.
    #[arg(long)]
    config: PathBuf,
    /// Envs stepped together for the vectorised figure.
    #[arg(long, default_value_t = 2)]
    envs: usize,
    /// Steps timed (per env).
    #[arg(long, default_value_t = 500)]
    steps: usize,
    /// Seed of the episodes and of the random actions.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Resident memory of this process in MiB (Linux; `None` elsewhere).
fn rss_mib() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = text.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0 / (1024.0 * 1024.0))
}

/// Runs `hearth bench env`.
pub fn run(a: BenchEnvArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.envs > 0 && a.steps > 0, "--envs and --steps must be positive");
    let config = EnvConfig::load(&a.config).with_context(|| format!("loading {}", a.config.display()))?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(a.seed);
    // Uniform random actions over the whole action space (base, and the arm for the
    // manipulation tasks), drawn into a reused buffer.
    let mut fill = |out: &mut [f32]| {
        for x in out {
            *x = rng.random_range(-1.0f32..1.0);
        }
    };

    let mut env = Env::new(config.clone())?;
    super::bench::create_json(a.json.as_deref())?;
    let backend = env.camera_backend().map(|b| b.name());
    let dim = env.action_space().size();
    let mut action = vec![0.0f32; dim];
    env.reset(a.seed)?;
    let start = Instant::now();
    let mut episodes = 0;
    for _ in 0..a.steps {
        fill(&mut action);
        let s = env.step(&action)?;
        if s.terminated || s.truncated {
            episodes += 1;
            env.reset(a.seed + episodes)?;
        }
    }
    let single = a.steps as f64 / start.elapsed().as_secs_f64();
    drop(env);

    let before = rss_mib();
    let mut envs = VecEnv::new(&config, a.envs)?;
    let after = rss_mib();
    envs.reset(a.seed)?;
    let mut actions = vec![0.0f32; dim * a.envs];
    let start = Instant::now();
    for _ in 0..a.steps {
        fill(&mut actions);
        envs.step(&actions)?;
    }
    let vec_rate = (a.steps * a.envs) as f64 / start.elapsed().as_secs_f64();
    let mem = before.zip(after).map(|(b, a2)| (a2 - b) / envs.len() as f64);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "{} with {}{}: {single:.0} steps/s for one env; {vec_rate:.0} env-steps/s for {} envs on {threads} threads; memory per env {}",
        config.task.name,
        config.sensors.modalities.join("+"),
        backend.map_or(String::new(), |b| format!(" (camera: {b})")),
        a.envs,
        mem.map_or("n/a".into(), |m| format!("{m:.0} MiB"))
    );
    if let Some(path) = &a.json {
        let out = json!({
            "task": config.task.name,
            "robot": config.robot.name,
            "modalities": config.sensors.modalities,
            "camera_backend": backend,
            "steps": a.steps,
            "envs": a.envs,
            "threads": threads,
            "steps_per_s_single": single,
            "steps_per_s_vec": vec_rate,
            "mem_per_env_mb": mem,
        });
        std::fs::write(path, serde_json::to_string_pretty(&out)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
