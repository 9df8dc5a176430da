//! `hearth bench plan`: planners on benchmark problem files (MotionBenchMaker JSON), every
//! returned path re-validated at 10× finer resolution before it counts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use hearth_kinematics::{Chain, DisabledReason, RobotModel, SelfCollisionMatrix, SelfCollisionSettings, wrap_angle};
use hearth_planning::problem::{JointsInfo, ProblemSet, load_dir};
use hearth_planning::space::JointSpace;
use hearth_planning::{
    BiRrt, Budget, Goal, LazyPrm, LazyPrmSettings, MotionValidator, PlanRequest, Planner, RobotValidity, Rrt,
    StateValidator,
};
use rand::SeedableRng;
use serde_json::{Value, json};

use super::bench::percentile;

/// Which planner to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PlannerKind {
    /// RRT with goal bias.
    Rrt,
    /// RRT-Connect.
    Birrt,
    /// Lazy PRM (the roadmap is rebuilt for every problem: each has its own obstacles).
    Lazyprm,
}

#[derive(Args, Debug)]
pub struct BenchPlanArgs {
    /// Problem files or folders of them (`joints.json` in a folder is read for limits and
    /// fixed finger positions).
    #[arg(long, num_args = 1.., required = true)]
    problems: Vec<PathBuf>,
    /// Planner.
    #[arg(long, value_enum, default_value_t = PlannerKind::Birrt)]
    planner: PlannerKind,
    /// Time limit per plan, in seconds.
    #[arg(long, default_value_t = 1.0)]
    time_limit: f64,
    /// Edge-check resolution (joint-space distance between checked states).
    #[arg(long, default_value_t = 0.01)]
    resolution: f64,
    /// RNG seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Plans per problem.
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Include every path's waypoints in the JSON.
    #[arg(long)]
    emit_paths: bool,
    /// Write results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

struct RobotSetup {
    chain: Chain,
    matrix: SelfCollisionMatrix,
    reference: Vec<f64>,
    note: String,
}

fn setup(robot: &str, joint_names: &[String], joints_file: Option<&Path>) -> anyhow::Result<RobotSetup> {
    let model = RobotModel::builtin(robot)?;
    let chain = Chain::new(&model, joint_names)?;
    let mut matrix = SelfCollisionMatrix::compute(
        &model,
        &SelfCollisionSettings {
            samples: 2000,
            ..Default::default()
        },
    );
    let mut reference = model.neutral_configuration();
    let mut note = String::new();
    if let Some(path) = joints_file {
        let info = JointsInfo::load(path)?;
        for [a, b] in &info.notes.self_collision_allowed_pairs {
            if let (Ok(a), Ok(b)) = (model.link_index(a), model.link_index(b)) {
                matrix.disable(a, b, DisabledReason::Never);
            }
        }
        let fingers: &[&str] = match robot {
            "panda" => &["panda_finger_joint1"],
            "fetch" => &["r_gripper_finger_joint"],
            _ => &[],
        };
        if let Some(values) = info.finger_positions() {
            for (name, &v) in fingers.iter().zip(values) {
                let j = model.joint_index(name)?;
                if let Some(var) = model.joints()[j].variable {
                    let clamped = v.clamp(model.lower()[var], model.upper()[var]);
                    reference[var] = clamped;
                    note.push_str(&format!("{name} = {clamped} (problem set: {v}); "));
                }
            }
        }
        note.push_str(&format!(
            "{} allowed pairs from joints.json",
            info.notes.self_collision_allowed_pairs.len()
        ));
    }
    Ok(RobotSetup {
        chain,
        matrix,
        reference,
        note,
    })
}

/// Wraps continuous joints into (-π, π] (MBM writes some at ±π plus rounding).
fn wrap_continuous(chain: &Chain, q: &[f64]) -> Vec<f64> {
    q.iter()
        .zip(chain.continuous())
        .map(|(&v, &c)| if c { wrap_angle(v) } else { v })
        .collect()
}

pub fn run(a: BenchPlanArgs) -> anyhow::Result<()> {
    if a.time_limit.is_nan() || a.time_limit <= 0.0 || a.resolution.is_nan() || a.resolution <= 0.0 {
        bail!("--time-limit and --resolution must be positive");
    }
    let mut sets: Vec<(ProblemSet, Option<PathBuf>)> = Vec::new();
    for p in &a.problems {
        if p.is_dir() {
            let joints = p.join("joints.json");
            let joints = joints.is_file().then_some(joints);
            for s in load_dir(p)? {
                sets.push((s, joints.clone()));
            }
        } else {
            let s = ProblemSet::load(p)?;
            let joints = p.parent().map(|d| d.join("joints.json")).filter(|j| j.is_file());
            sets.push((s, joints));
        }
    }
    let total: usize = sets.iter().map(|(s, _)| s.problems.len()).sum::<usize>() * a.repeat as usize;
    let mut setups: BTreeMap<String, RobotSetup> = BTreeMap::new();
    let mut results = Vec::new();
    let mut done = 0usize;
    for (set, joints) in &sets {
        if !setups.contains_key(&set.robot) {
            let s = setup(&set.robot, &set.joint_names, joints.as_deref())
                .with_context(|| format!("setting up robot `{}`", set.robot))?;
            eprintln!("{}: {}", set.robot, s.note);
            setups.insert(set.robot.clone(), s);
        }
        let rs = &setups[&set.robot];
        let space = JointSpace::from_chain(&rs.chain).map_err(|e| anyhow::anyhow!("{e}"))?;
        for problem in &set.problems {
            for rep in 0..a.repeat {
                done += 1;
                if done.is_multiple_of(10) || done == total {
                    eprint!("\r{done}/{total} plans");
                }
                let mut row = json!({"family": set.family, "id": problem.id, "planner": format!("{:?}", a.planner).to_lowercase(), "repeat": rep});
                if !problem.valid {
                    row["skipped"] = json!("marked invalid in the problem set");
                    results.push(row);
                    continue;
                }
                let mut v = RobotValidity::new(rs.chain.clone(), rs.matrix.clone(), Arc::new(problem.scene()));
                v.set_reference(&rs.reference)?;
                let start = wrap_continuous(&rs.chain, &problem.start);
                if let Some(c) = v.explain(&start) {
                    row["skipped"] = json!(format!("start collides in our model: {c}"));
                    results.push(row);
                    continue;
                }
                let goals: Vec<Vec<f64>> = problem.goals.iter().map(|g| wrap_continuous(&rs.chain, g)).collect();
                let mut motion = MotionValidator::new(space.clone(), a.resolution);
                let request = PlanRequest::new(start, Goal::AnyOf(goals));
                let budget = Budget::time(a.time_limit);
                let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(a.seed ^ ((problem.id as u64) << 20) ^ rep as u64);
                let before = v.checks();
                let outcome = match a.planner {
                    PlannerKind::Rrt => Rrt::default().plan(&mut motion, &mut v, &request, &budget, &mut rng),
                    PlannerKind::Birrt => BiRrt::default().plan(&mut motion, &mut v, &request, &budget, &mut rng),
                    PlannerKind::Lazyprm => {
                        LazyPrm::new(LazyPrmSettings::default()).plan(&mut motion, &mut v, &request, &budget, &mut rng)
                    }
                };
                let checks = v.checks() - before;
                match outcome {
                    Err(hearth_planning::PlanError::InvalidGoals { .. }) => {
                        row["skipped"] = json!("every goal collides in our model");
                    }
                    Err(hearth_planning::PlanError::BadInput(msg)) => {
                        row["skipped"] = json!(format!("outside our model's limits: {msg}"));
                    }
                    Err(e) => {
                        row["success"] = json!(false);
                        row["error"] = json!(e.to_string());
                        row["checks"] = json!(checks);
                    }
                    Ok(sol) => {
                        // Re-validate at 10x finer resolution.
                        let mut fine = MotionValidator::new(space.clone(), a.resolution / 10.0);
                        let states = &sol.path.states;
                        let valid = states.iter().all(|s| v.is_valid(s))
                            && states.windows(2).all(|w| fine.check_motion(&mut v, &w[0], &w[1]));
                        row["success"] = json!(valid);
                        if !valid {
                            row["error"] = json!("path fails re-validation at 10x finer resolution");
                        }
                        row["plan_time_s"] = json!(sol.stats.time.as_secs_f64());
                        row["shortcut_time_s"] = json!(0.0);
                        row["path_length"] = json!(sol.path.length(&space));
                        row["checks"] = json!(checks);
                        if a.emit_paths {
                            row["path"] = json!(states);
                        }
                    }
                }
                results.push(row);
            }
        }
    }
    eprintln!();
    // Summary per family.
    let mut families: BTreeMap<String, Vec<&Value>> = BTreeMap::new();
    for r in &results {
        families
            .entry(r["family"].as_str().unwrap_or("?").to_owned())
            .or_default()
            .push(r);
    }
    println!(
        "{:<18} {:>6} {:>7} {:>9} {:>11} {:>11} {:>9} {:>9}",
        "family", "plans", "skipped", "success", "median ms", "p95 ms", "length", "checks"
    );
    let mut summary = serde_json::Map::new();
    for (family, rows) in &families {
        let attempted: Vec<&&Value> = rows.iter().filter(|r| r.get("skipped").is_none()).collect();
        let ok: Vec<&&Value> = attempted
            .iter()
            .filter(|r| r["success"] == json!(true))
            .copied()
            .collect();
        let times: Vec<f64> = ok
            .iter()
            .filter_map(|r| r["plan_time_s"].as_f64())
            .map(|t| t * 1e3)
            .collect();
        let lengths: Vec<f64> = ok.iter().filter_map(|r| r["path_length"].as_f64()).collect();
        let checks: Vec<f64> = ok.iter().filter_map(|r| r["checks"].as_f64()).collect();
        let rate = ok.len() as f64 / attempted.len().max(1) as f64;
        println!(
            "{:<18} {:>6} {:>7} {:>8.1}% {:>11.3} {:>11.3} {:>9.3} {:>9.0}",
            family,
            rows.len(),
            rows.len() - attempted.len(),
            100.0 * rate,
            percentile(&times, 0.5),
            percentile(&times, 0.95),
            percentile(&lengths, 0.5),
            percentile(&checks, 0.5)
        );
        summary.insert(
            family.clone(),
            json!({"plans": rows.len(), "skipped": rows.len() - attempted.len(), "success_rate": rate,
                   "plan_time_ms_median": percentile(&times, 0.5), "plan_time_ms_p95": percentile(&times, 0.95),
                   "path_length_median": percentile(&lengths, 0.5), "checks_median": percentile(&checks, 0.5)}),
        );
    }
    if let Some(path) = a.json {
        let out = json!({"results": results, "summary": summary});
        std::fs::write(&path, serde_json::to_string(&out)?).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
