//! `hearth kin info|fk|ik|self-collision`.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use hearth_kinematics::{
    Chain, IkSettings, IkSolver, IkTarget, JointKind, RobotModel, SelfCollisionMatrix, SelfCollisionSettings,
};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use rand::SeedableRng;
use serde_json::{Value, json};

use super::parse_list;

#[derive(Subcommand, Debug)]
pub enum KinCommand {
    /// Links, joints, DOF, limits and chains of a robot.
    Info(InfoArgs),
    /// World pose of every link for a configuration.
    Fk(FkArgs),
    /// Joint configuration that puts a link at a pose.
    Ik(IkArgs),
    /// Compute the self-collision matrix (pairs never checked) and optionally save it.
    SelfCollision(SelfCollisionArgs),
}

#[derive(Args, Debug)]
pub struct RobotArg {
    /// Built-in robot name (panda, fetch, locobot, turtlebot) or a URDF path.
    #[arg(long)]
    robot: String,
}

impl RobotArg {
    fn load(&self) -> anyhow::Result<RobotModel> {
        RobotModel::load(&self.robot).with_context(|| format!("loading robot `{}`", self.robot))
    }
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    robot: RobotArg,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct FkArgs {
    #[command(flatten)]
    robot: RobotArg,
    /// Values of the movable joints in model order, comma separated (see `kin info`).
    #[arg(long, allow_hyphen_values = true)]
    q: String,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct IkArgs {
    #[command(flatten)]
    robot: RobotArg,
    /// Link to place.
    #[arg(long)]
    tip: String,
    /// Target `x,y,z,qx,qy,qz,qw` in the robot's root frame (or `x,y,z` with --position-only).
    #[arg(long, allow_hyphen_values = true)]
    pose: String,
    /// Seed for the chain joints (default: mid-range of the limits).
    #[arg(long, allow_hyphen_values = true)]
    seed_q: Option<String>,
    /// Named chain to solve with (default: the chain ending at --tip, else every movable
    /// joint between the root and --tip).
    #[arg(long)]
    chain: Option<String>,
    /// Only reach the position.
    #[arg(long)]
    position_only: bool,
    /// Use the clarabel QP step instead of damped least squares.
    #[arg(long)]
    qp: bool,
    /// RNG seed for restarts.
    #[arg(long, default_value_t = 0)]
    rng_seed: u64,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct SelfCollisionArgs {
    #[command(flatten)]
    robot: RobotArg,
    /// Random configurations sampled.
    #[arg(long, default_value_t = 10_000)]
    samples: usize,
    /// RNG seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Write the matrix (JSON) here.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(cmd: KinCommand) -> anyhow::Result<()> {
    match cmd {
        KinCommand::Info(a) => info(a),
        KinCommand::Fk(a) => fk(a),
        KinCommand::Ik(a) => ik(a),
        KinCommand::SelfCollision(a) => self_collision(a),
    }
}

fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn info(a: InfoArgs) -> anyhow::Result<()> {
    let m = a.robot.load()?;
    let links: Vec<&str> = m.links().iter().map(|l| l.name.as_str()).collect();
    if a.json {
        let joints: Vec<Value> = m
            .joints()
            .iter()
            .map(|j| {
                json!({
                    "name": j.name,
                    "type": j.kind.as_str(),
                    "parent": m.links()[j.parent].name,
                    "child": m.links()[j.child].name,
                    "axis": [j.axis.x, j.axis.y, j.axis.z],
                    "limits": if j.kind == JointKind::Fixed { Value::Null } else { json!({
                        "lower": num(j.limits.lower), "upper": num(j.limits.upper),
                        "velocity": num(j.limits.velocity), "effort": num(j.limits.effort)}) },
                    "mimic": j.mimic.map(|mm| json!({"joint": m.joints()[mm.joint].name, "multiplier": mm.multiplier, "offset": mm.offset})),
                })
            })
            .collect();
        let out = json!({
            "name": m.name(),
            "source": m.source_name(),
            "root": m.links()[m.root()].name,
            "links": links,
            "joints": joints,
            "movable_joints": m.variable_names(),
            "dof": m.dof(),
            "chains": m.chains(),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("robot {} ({})", m.name(), m.source_name());
    println!(
        "{} links, {} joints, {} DOF; root `{}`",
        links.len(),
        m.joints().len(),
        m.dof(),
        links[m.root()]
    );
    println!("\nmovable joints (the order --q takes):");
    println!(
        "  {:>3}  {:<28} {:<11} {:>10} {:>10} {:>9} {:>9}",
        "#", "joint", "type", "lower", "upper", "velocity", "effort"
    );
    for (i, name) in m.variable_names().iter().enumerate() {
        let j = &m.joints()[m.variables()[i]];
        println!(
            "  {:>3}  {:<28} {:<11} {:>10.4} {:>10.4} {:>9.3} {:>9.2}",
            i,
            name,
            j.kind.as_str(),
            j.limits.lower,
            j.limits.upper,
            j.limits.velocity,
            j.limits.effort
        );
    }
    let mimics: Vec<_> = m.joints().iter().filter(|j| j.mimic.is_some()).collect();
    if !mimics.is_empty() {
        println!("\nmimic joints:");
        for j in mimics {
            let mm = j.mimic.expect("filtered");
            println!(
                "  {} = {} * {} + {}",
                j.name,
                mm.multiplier,
                m.joints()[mm.joint].name,
                mm.offset
            );
        }
    }
    if !m.chains().is_empty() {
        println!("\nchains:");
        for c in m.chains() {
            println!(
                "  {:<16} {} DOF -> {}: {}",
                c.name,
                c.joints.len(),
                c.tip,
                c.joints.join(", ")
            );
        }
    }
    println!("\nlinks:");
    for l in m.links() {
        let parent = l
            .parent_joint
            .map(|j| m.links()[m.joints()[j].parent].name.as_str())
            .unwrap_or("-");
        println!(
            "  {:<28} parent {:<24} {} collision, {} visual",
            l.name,
            parent,
            l.collisions.len(),
            l.visuals.len()
        );
    }
    Ok(())
}

fn fk(a: FkArgs) -> anyhow::Result<()> {
    let m = a.robot.load()?;
    let q = parse_list(&a.q, "--q")?;
    let mut poses = m.pose_buffer();
    m.fk(&q, &mut poses)
        .with_context(|| format!("--q must list {} values: {}", m.dof(), m.variable_names().join(", ")))?;
    if a.json {
        let mut links = serde_json::Map::new();
        for (l, p) in m.links().iter().zip(&poses) {
            let t = p.translation.vector;
            let r = p.rotation.quaternion();
            links.insert(
                l.name.clone(),
                json!({"position": [t.x, t.y, t.z], "quat_xyzw": [r.i, r.j, r.k, r.w]}),
            );
        }
        println!("{}", serde_json::to_string_pretty(&json!({ "links": links }))?);
    } else {
        println!(
            "{:<28} {:>9} {:>9} {:>9}   {:>8} {:>8} {:>8} {:>8}",
            "link", "x", "y", "z", "qx", "qy", "qz", "qw"
        );
        for (l, p) in m.links().iter().zip(&poses) {
            let t = p.translation.vector;
            let r = p.rotation.quaternion();
            println!(
                "{:<28} {:>9.5} {:>9.5} {:>9.5}   {:>8.5} {:>8.5} {:>8.5} {:>8.5}",
                l.name, t.x, t.y, t.z, r.i, r.j, r.k, r.w
            );
        }
    }
    Ok(())
}

/// The chain to solve for `tip`: a named one if given, the named chain ending at `tip`, or every
/// movable joint from the root to `tip`.
pub(crate) fn chain_for(m: &RobotModel, chain: Option<&str>, tip: &str) -> anyhow::Result<Chain> {
    if let Some(name) = chain {
        return Ok(Chain::named(m, name)?);
    }
    let tip_link = m.link_index(tip)?;
    if let Some(spec) = m.chains().iter().find(|c| c.tip == tip) {
        return Ok(Chain::named(m, &spec.name)?);
    }
    if let Some(spec) = m.chains().iter().find(|c| {
        m.link_index(&c.tip)
            .is_ok_and(|t| m.is_ancestor(t, tip_link) || m.is_ancestor(tip_link, t))
    }) {
        return Ok(Chain::named(m, &spec.name)?);
    }
    let root = &m.links()[m.root()].name;
    let c = Chain::between(m, root, tip)?;
    if c.dof() == 0 {
        bail!("no movable joint moves link `{tip}`");
    }
    Ok(c)
}

fn ik(a: IkArgs) -> anyhow::Result<()> {
    let m = a.robot.load()?;
    let chain = chain_for(&m, a.chain.as_deref(), &a.tip)?;
    let v = parse_list(&a.pose, "--pose")?;
    let target = match (a.position_only, v.len()) {
        (true, 3) | (true, 7) => IkTarget::Position(nalgebra::Point3::new(v[0], v[1], v[2])),
        (false, 7) => {
            let q = Quaternion::new(v[6], v[3], v[4], v[5]);
            if v.iter().any(|x| !x.is_finite()) || q.norm() <= 1e-9 {
                bail!("--pose: the quaternion must be finite and non-zero");
            }
            IkTarget::Pose(Isometry3::from_parts(
                Translation3::new(v[0], v[1], v[2]),
                UnitQuaternion::from_quaternion(q),
            ))
        }
        (po, n) => bail!(
            "--pose: expected {} comma-separated numbers, got {n}",
            if po { "3 (x,y,z)" } else { "7 (x,y,z,qx,qy,qz,qw)" }
        ),
    };
    let seed = match &a.seed_q {
        Some(s) => parse_list(s, "--seed-q")?,
        None => chain
            .lower()
            .iter()
            .zip(chain.upper())
            .map(|(&l, &u)| {
                if l.is_finite() && u.is_finite() {
                    0.5 * (l + u)
                } else {
                    0.0
                }
            })
            .collect(),
    };
    chain.check(&seed).context("--seed-q")?;
    let names = chain.joint_names().to_vec();
    let settings = IkSettings {
        method: if a.qp {
            hearth_kinematics::IkMethod::Qp
        } else {
            hearth_kinematics::IkMethod::Dls
        },
        time_limit: Some(std::time::Duration::from_millis(500)),
        max_attempts: 2000,
        ..IkSettings::default()
    };
    let mut solver = IkSolver::new(chain, &a.tip, settings)?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(a.rng_seed);
    let t0 = std::time::Instant::now();
    let sol = solver.solve(&target, &seed, &mut rng)?;
    let us = t0.elapsed().as_secs_f64() * 1e6;
    if a.json {
        let joints: serde_json::Map<String, Value> =
            names.iter().zip(&sol.q).map(|(n, v)| (n.clone(), json!(v))).collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({
                "success": true,
                "tip": a.tip,
                "joint_names": names,
                "q": sol.q,
                "joints": joints,
                "position_error": sol.position_error,
                "orientation_error": sol.orientation_error,
                "attempts": sol.attempts,
                "iterations": sol.iterations,
                "time_us": us,
            }))?
        );
    } else {
        println!(
            "solved in {us:.1} µs ({} attempts, {} iterations)",
            sol.attempts, sol.iterations
        );
        println!(
            "residual: {:.2e} m, {:.2e} rad",
            sol.position_error, sol.orientation_error
        );
        for (n, v) in names.iter().zip(&sol.q) {
            println!("  {n:<28} {v:>10.5}");
        }
        let list: Vec<String> = sol.q.iter().map(|v| format!("{v:.6}")).collect();
        println!("q = {}", list.join(","));
    }
    Ok(())
}

fn self_collision(a: SelfCollisionArgs) -> anyhow::Result<()> {
    let m = a.robot.load()?;
    let settings = SelfCollisionSettings {
        samples: a.samples,
        seed: a.seed,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let matrix = SelfCollisionMatrix::compute(&m, &settings);
    let pairs = matrix.checked_geometric_pairs(&m);
    println!(
        "{}: {} link pairs to check after {} samples ({:.2} s)",
        m.name(),
        pairs.len(),
        a.samples,
        t0.elapsed().as_secs_f64()
    );
    for (x, y) in &pairs {
        println!("  check {} <-> {}", m.links()[*x].name, m.links()[*y].name);
    }
    if let Some(path) = a.out {
        matrix.save(&path, &m, &settings)?;
        println!("saved to {}", path.display());
    }
    Ok(())
}
