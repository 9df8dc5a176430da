//! Runs a scripted policy for a few episodes of each point-navigation task and prints the
//! episode metrics. Trains nothing. The policy follows the shortest path on the home's
//! traversability map: turn towards the next waypoint, then drive.
//!
//! ```sh
//! cargo run --release --example point_nav
//! ```

use std::f64::consts::{PI, TAU};

use hearth::sim::env::{Ending, Env, EnvConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/configs");
    for task in ["point_nav_fixed", "point_nav_random"] {
        let mut config = EnvConfig::load(&dir.join(format!("{task}.toml")))?;
        // This policy needs no camera.
        config.sensors.modalities = vec!["task_obs".into(), "scan".into()];
        config.episode.max_steps = 1000;
        let mut env = Env::new(config)?;
        let names: Vec<&str> = env.observation_spaces().iter().map(|s| s.name.as_str()).collect();
        println!("{task}: observations {names:?}");
        for episode in 0..3u64 {
            env.reset(episode)?;
            let (start, goal) = env.start_and_goal();
            let path = env.maps().shortest_path([start[0], start[1]], goal)?;
            let mut next = 1;
            let mut total = 0.0;
            loop {
                let base = env.world().base_pose(env.robot())?;
                let (x, y) = (base.translation.x, base.translation.y);
                while next + 1 < path.len() && (path[next][0] - x).hypot(path[next][1] - y) < 0.15 {
                    next += 1;
                }
                let yaw = base.rotation.euler_angles().2;
                let bearing = (path[next][1] - y).atan2(path[next][0] - x);
                let heading = ((bearing - yaw + PI).rem_euclid(TAU) - PI) as f32;
                let action = if heading.abs() > 0.2 {
                    [0.0, heading.signum()]
                } else {
                    [1.0, 2.0 * heading]
                };
                let step = env.step(&action)?;
                total += step.reward;
                if step.terminated || step.truncated {
                    let m = step.info.metrics;
                    println!(
                        "  episode {episode}: {:?} after {} steps, return {total:.2}, SPL {:.2}, path {:.2} m (geodesic {:.2} m), {} collision steps",
                        step.info.ending.unwrap_or(Ending::Timeout),
                        m.episode_length,
                        m.spl,
                        m.path_length,
                        m.geodesic_distance,
                        m.collisions
                    );
                    break;
                }
            }
        }
    }
    Ok(())
}
