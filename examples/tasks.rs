//! Runs a simple scripted policy for a few short episodes of every task and prints the episode
//! metrics. Trains nothing.
//!
//! - navigation tasks follow the shortest path on the traversability map (for `object_nav`,
//!   to the free cell nearest the target's nearest instance, then turn towards it);
//! - `reaching` solves IK for the goal once and drives the arm joints towards the solution
//!   with velocity commands;
//! - the articulated tasks drive the base slowly into the furniture (the bumper pushes what
//!   it meets) — a baseline, not a solution.
//!
//! ```sh
//! cargo run --release --example tasks
//! ```

use std::f64::consts::{PI, TAU};

use hearth::kinematics::{Chain, IkSettings, IkSolver, IkTarget};
use hearth::sim::env::{Ending, Env, EnvConfig, TASK_NAMES};
use nalgebra::Point3;
use rand::SeedableRng;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn main() -> Result<()> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/configs");
    for task in TASK_NAMES {
        let mut config = EnvConfig::load(&dir.join(format!("{task}.toml")))?;
        // Small and fast: a low-resolution ray-cast camera where the task has one.
        config.sensors.camera.backend = "raycast".into();
        config.sensors.camera.width = 64;
        config.sensors.camera.height = 48;
        // Navigation needs time to cover a home; the others are judged in a few seconds.
        config.episode.max_steps = if task.contains("nav") { 600 } else { 200 };
        let mut env = Env::new(config)?;
        println!(
            "{task}: action size {}, observations {:?}",
            env.action_space().size(),
            env.observation_spaces()
                .iter()
                .map(|s| format!("{}{:?}", s.name, s.shape))
                .collect::<Vec<_>>()
        );
        for episode in 0..2u64 {
            env.reset(episode)?;
            let mut policy = Policy::new(&env)?;
            let mut total = 0.0;
            loop {
                let action = policy.act(&env)?;
                let step = env.step(&action)?;
                total += step.reward;
                if step.terminated || step.truncated {
                    let m = step.info.metrics;
                    println!(
                        "  episode {episode}: {:?} after {} steps, return {total:.2}, SPL {:.2}, path {:.2} m, {} collision steps, {} object contacts, remaining {:.2}",
                        step.info.ending.unwrap_or(Ending::Timeout),
                        m.episode_length,
                        m.spl,
                        m.path_length,
                        m.collisions,
                        m.object_contacts,
                        m.remaining
                    );
                    break;
                }
            }
        }
    }
    Ok(())
}

/// A scripted policy for one episode.
enum Policy {
    /// Follow waypoints, then face `look_at` (if any).
    Path {
        path: Vec<[f64; 2]>,
        next: usize,
        look_at: Option<[f64; 2]>,
    },
    /// Drive the arm joints towards a configuration (indices into the robot's joints).
    Arm { target: Vec<(usize, f64, f64)> },
    /// Creep forward.
    Push,
}

impl Policy {
    fn new(env: &Env) -> Result<Self> {
        let (start, goal) = env.start_and_goal();
        let s = [start[0], start[1]];
        Ok(match env.task_name() {
            "reaching" => Self::arm_towards_goal(env)?,
            "push_drawer" | "push_cabinet" | "room_rearrangement" => Policy::Push,
            "object_nav" => {
                let free = nearest_traversable(env, goal);
                Policy::Path {
                    path: env.maps().shortest_path(s, free)?,
                    next: 1,
                    look_at: Some(goal),
                }
            }
            _ => Policy::Path {
                path: env.maps().shortest_path(s, goal)?,
                next: 1,
                look_at: None,
            },
        })
    }

    /// IK for the reaching goal in the base frame; the arm then moves towards the solution.
    fn arm_towards_goal(env: &Env) -> Result<Self> {
        let world = env.world();
        let robot = env.robot();
        let model = world.model(robot)?.clone();
        let chain = Chain::named(&model, "arm_with_torso")?;
        let mut ik = IkSolver::new(chain.clone(), "gripper_link", IkSettings::default())?;
        let q = world.joint_positions(robot)?;
        ik.set_reference(&q)?;
        let g = env.goal();
        let local = world
            .base_pose(robot)?
            .inverse_transform_point(&Point3::new(g[0], g[1], g[2]));
        let mut seed = vec![0.0; chain.dof()];
        chain.gather(&q, &mut seed);
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
        let Ok(solution) = ik.solve(&IkTarget::Position(local), &seed, &mut rng) else {
            return Ok(Policy::Push);
        };
        let mut full = q.clone();
        chain.scatter(&solution.q, &mut full);
        let target = chain
            .variables()
            .iter()
            .map(|&v| (v, full[v], model.velocity_limits()[v]))
            .collect();
        Ok(Policy::Arm { target })
    }

    fn act(&mut self, env: &Env) -> Result<Vec<f32>> {
        let mut action = vec![0.0f32; env.action_space().size()];
        let base = env.world().base_pose(env.robot())?;
        let (x, y) = (base.translation.x, base.translation.y);
        let yaw = base.rotation.euler_angles().2;
        let heading_to = |p: [f64; 2]| ((p[1] - y).atan2(p[0] - x) - yaw + PI).rem_euclid(TAU) - PI;
        match self {
            Policy::Path { path, next, look_at } => {
                while *next + 1 < path.len() && (path[*next][0] - x).hypot(path[*next][1] - y) < 0.15 {
                    *next += 1;
                }
                let last = path.len() - 1;
                let arrived = *next == last && (path[last][0] - x).hypot(path[last][1] - y) < 0.15;
                let (h, drive) = match (arrived, look_at) {
                    (true, Some(p)) => (heading_to(*p), false),
                    _ => (heading_to(path[(*next).min(last)]), true),
                };
                let h = h as f32;
                if !drive {
                    action[1] = (2.0 * h).clamp(-1.0, 1.0);
                } else if h.abs() > 0.2 {
                    action[1] = h.signum();
                } else {
                    action[0] = 1.0;
                    action[1] = 2.0 * h;
                }
            }
            Policy::Arm { target } => {
                let q = env.world().joint_positions(env.robot())?;
                // Arm entries follow the action's joint order: torso, then the 7 arm joints,
                // which is the order of the `arm_with_torso` chain.
                let dt = env.world().config().control_dt();
                for (k, &(v, goal, vmax)) in target.iter().enumerate() {
                    if let Some(a) = action.get_mut(2 + k) {
                        *a = ((goal - q[v]) / (vmax * dt * 3.0)).clamp(-1.0, 1.0) as f32;
                    }
                }
            }
            Policy::Push => {
                let g = env.goal();
                let h = heading_to([g[0], g[1]]) as f32;
                action[0] = 0.3;
                action[1] = (2.0 * h).clamp(-1.0, 1.0);
            }
        }
        Ok(action)
    }
}

/// The traversable cell centre nearest to `p`.
fn nearest_traversable(env: &Env, p: [f64; 2]) -> [f64; 2] {
    let maps = env.maps();
    let mut best = (f64::INFINITY, p);
    for (i, _) in maps.traversable.iter().enumerate().filter(|(_, t)| **t) {
        let c = maps.cell_center(i % maps.width, i / maps.width);
        let d = (c[0] - p[0]).hypot(c[1] - p[1]);
        if d < best.0 {
            best = (d, c);
        }
    }
    best.1
}
