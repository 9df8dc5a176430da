//! `hearth bench kin`: FK, Jacobian and IK speed, measured the same way every time.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
use nalgebra::{Matrix6xX, Vector3};
use rand::SeedableRng;
use serde_json::json;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Forward kinematics, Jacobian and inverse kinematics of one robot.
    Kin(BenchKinArgs),
    /// Planners on benchmark problem files (MotionBenchMaker JSON).
    Plan(super::bench_plan::BenchPlanArgs),
    /// Physics steps per second of a settled home, with and without the robot.
    Sim(super::bench_sim::BenchSimArgs),
    /// LiDAR scans per second in a generated home (1- or 16-beam).
    Lidar(super::bench_lidar::BenchLidarArgs),
    /// Camera frames per second per modality (iGibson's rendering speed table).
    Render(super::bench_render::BenchRenderArgs),
    /// Env steps per second (one env, and N envs together) and memory per env.
    Env(super::bench_env::BenchEnvArgs),
    /// Two `bench plan --json` files side by side, plan by plan: solved counts, times over the
    /// plans both solved, and how many plans are the same plan in both.
    Compare(super::bench_compare::BenchCompareArgs),
}

#[derive(Args, Debug)]
pub struct BenchKinArgs {
    /// Built-in robot name or URDF path.
    #[arg(long)]
    robot: String,
    /// Random reachable poses for the IK part (at least 1).
    #[arg(long, default_value_t = 1000)]
    samples: usize,
    /// Chain to use (default: the robot's first named chain).
    #[arg(long)]
    chain: Option<String>,
    /// RNG seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Kin(a) => kin(a),
        BenchCommand::Plan(a) => super::bench_plan::run(a),
        BenchCommand::Sim(a) => super::bench_sim::run(a),
        BenchCommand::Lidar(a) => super::bench_lidar::run(a),
        BenchCommand::Render(a) => super::bench_render::run(a),
        BenchCommand::Env(a) => super::bench_env::run(a),
        BenchCommand::Compare(a) => super::bench_compare::run(a),
    }
}

/// Results of one IK run over random reachable poses.
pub(crate) struct IkStats {
    pub samples: usize,
    pub successes: usize,
    pub times_us: Vec<f64>,
}

impl IkStats {
    pub fn success_rate(&self) -> f64 {
        self.successes as f64 / self.samples.max(1) as f64
    }
    pub fn percentile(&self, p: f64) -> f64 {
        percentile(&self.times_us, p)
    }
}

pub(crate) fn percentile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let idx = ((v.len() - 1) as f64 * p).round() as usize;
    v[idx]
}

/// Creates (or empties) a benchmark's `--json` results file, so that a path that cannot be
/// written is reported before anything is measured. Each benchmark calls it once its other
/// arguments are checked, so that bad input leaves no file behind.
pub(crate) fn create_json(path: Option<&Path>) -> anyhow::Result<()> {
    if let Some(path) = path {
        std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The chain a benchmark uses: the named one, or the robot's first.
pub(crate) fn bench_chain(m: &RobotModel, name: Option<&str>) -> anyhow::Result<Chain> {
    let name = match name {
        Some(n) => n.to_owned(),
        None => match m.chains().first() {
            Some(c) => c.name.clone(),
            None => bail!("robot `{}` has no arm chain to benchmark (pass --chain)", m.name()),
        },
    };
    Ok(Chain::named(m, &name)?)
}

/// IK on `samples` random reachable full poses, each from an unrelated random seed.
/// Every reported success is re-checked with an independent forward-kinematics call.
pub(crate) fn ik_random_poses(chain: &Chain, samples: usize, seed: u64) -> anyhow::Result<IkStats> {
    let m = chain.model().clone();
    let tip = chain
        .tip()
        .map(|t| m.links()[t].name.clone())
        .context("chain has no tip link")?;
    let settings = IkSettings::default();
    let (ptol, rtol) = (settings.position_tolerance, settings.orientation_tolerance);
    let mut solver = IkSolver::new(chain.clone(), &tip, settings)?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut goal = vec![0.0; chain.dof()];
    let mut start = vec![0.0; chain.dof()];
    let mut times = Vec::with_capacity(samples);
    let mut successes = 0;
    for _ in 0..samples {
        chain.random_configuration(&mut rng, &mut goal);
        chain.random_configuration(&mut rng, &mut start);
        let target = solver.tool_pose(&goal)?;
        let t0 = Instant::now();
        let result = solver.solve(&IkTarget::Pose(target), &start, &mut rng);
        times.push(t0.elapsed().as_secs_f64() * 1e6);
        if let Ok(sol) = result {
            let reached = solver.tool_pose(&sol.q)?;
            let dp = (reached.translation.vector - target.translation.vector).norm();
            let dr = reached.rotation.angle_to(&target.rotation);
            let within = chain
                .lower()
                .iter()
                .zip(chain.upper())
                .zip(&sol.q)
                .all(|((&lo, &hi), &v)| v >= lo - 1e-9 && v <= hi + 1e-9);
            if dp <= ptol + 1e-9 && dr <= rtol + 1e-9 && within {
                successes += 1;
            }
        }
    }
    Ok(IkStats {
        samples,
        successes,
        times_us: times,
    })
}

/// Median nanoseconds per call of `f` over `batches` batches of `inner` calls.
fn median_ns(batches: usize, inner: usize, mut f: impl FnMut(usize)) -> f64 {
    let mut per_call = Vec::with_capacity(batches);
    let mut k = 0;
    for _ in 0..batches {
        let t0 = Instant::now();
        for _ in 0..inner {
            f(k);
            k += 1;
        }
        per_call.push(t0.elapsed().as_secs_f64() * 1e9 / inner as f64);
    }
    percentile(&per_call, 0.5)
}

fn kin(a: BenchKinArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.samples > 0, "--samples must be at least 1");
    let m = RobotModel::load(&a.robot).with_context(|| format!("loading robot `{}`", a.robot))?;
    let chain = bench_chain(&m, a.chain.as_deref())?;
    let tip = chain.tip().context("chain has no tip")?;
    create_json(a.json.as_deref())?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(a.seed);
    let configs: Vec<Vec<f64>> = (0..1024)
        .map(|_| {
            let mut q = vec![0.0; m.dof()];
            m.random_configuration(&mut rng, &mut q);
            q
        })
        .collect();
    let mut poses = m.pose_buffer();
    // Warm up, then measure.
    for q in &configs {
        m.fk(q, &mut poses)?;
    }
    let fk_ns = median_ns(300, 1000, |k| {
        m.fk(black_box(&configs[k & 1023]), &mut poses).ok();
        black_box(&poses);
    });
    let all_poses: Vec<_> = configs
        .iter()
        .map(|q| {
            let mut p = m.pose_buffer();
            m.fk(q, &mut p).ok();
            p
        })
        .collect();
    let mut jac = Matrix6xX::zeros(chain.dof());
    let zero = Vector3::zeros();
    let jac_ns = median_ns(300, 1000, |k| {
        m.jacobian(black_box(&all_poses[k & 1023]), &chain, tip, &zero, &mut jac)
            .ok();
        black_box(&jac);
    });
    let ik = ik_random_poses(&chain, a.samples, a.seed)?;
    let report = json!({
        "robot": m.name(),
        "links": m.links().len(),
        "chain": chain.name(),
        "chain_dof": chain.dof(),
        "tip": m.links()[tip].name,
        "fk_ns_median": fk_ns,
        "jacobian_ns_median": jac_ns,
        "ik_samples": ik.samples,
        "ik_success_rate": ik.success_rate(),
        "ik_us_median": ik.percentile(0.5),
        "ik_us_p95": ik.percentile(0.95),
        "ik_position_tolerance_m": IkSettings::default().position_tolerance,
        "ik_orientation_tolerance_rad": IkSettings::default().orientation_tolerance,
    });
    println!(
        "robot {} ({} links), chain `{}` ({} DOF) -> {}",
        m.name(),
        m.links().len(),
        chain.name(),
        chain.dof(),
        m.links()[tip].name
    );
    println!("  FK, all links       median {fk_ns:>9.1} ns");
    println!("  Jacobian (6x{})      median {jac_ns:>9.1} ns", chain.dof());
    println!(
        "  IK full pose, {} random reachable poses, random seeds: success {:.2} %, median {:.1} µs, p95 {:.1} µs",
        ik.samples,
        100.0 * ik.success_rate(),
        ik.percentile(0.5),
        ik.percentile(0.95)
    );
    if let Some(path) = a.json {
        std::fs::write(&path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
