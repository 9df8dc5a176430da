//! `hearth bench render`: frames per second of each camera modality, as iGibson's rendering
//! speed table reports them (mean, min and max over the frames).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use hearth_sim::sensors::{Modality, ModalitySet};
use serde_json::json;

use super::render::CameraArgs;

#[derive(Args, Debug)]
pub struct BenchRenderArgs {
    #[command(flatten)]
    home: super::home::HomeArgs,
    /// Robot carrying the camera.
    #[arg(long, default_value = "fetch")]
    robot: String,
    #[command(flatten)]
    camera: CameraArgs,
    /// Frames timed per modality (after 5 warm-up frames).
    #[arg(long, default_value_t = 200)]
    frames: usize,
    /// Modalities to time, comma separated (default: all).
    #[arg(long, default_value = "rgb,depth,normal,seg,ins_seg,optical_flow,scene_flow,pc")]
    modalities: String,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `hearth bench render`.
pub fn run(a: BenchRenderArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.frames > 0, "--frames must be positive");
    let modalities = Modality::parse_list(&a.modalities)?;
    let config = a.camera.config()?;
    let (world, _, mut camera) = super::render::robot_camera(&a.home, &a.robot, config.clone())?;
    super::bench::create_json(a.json.as_deref())?;
    let triangles = camera.scene().triangle_estimate(16);
    println!(
        "{} items (~{triangles} triangles), {}×{}, backend {} ({}), preset {}",
        camera.scene().items.len(),
        config.intrinsics.width,
        config.intrinsics.height,
        camera.backend().name(),
        camera.adapter(),
        a.camera.preset
    );
    println!(
        "{:<14} {:>10} {:>10} {:>10}",
        "modality", "fps mean", "fps min", "fps max"
    );
    let mut rows = serde_json::Map::new();
    for m in modalities.iter() {
        let set = ModalitySet::EMPTY.with(m);
        for _ in 0..5 {
            camera.render(&world, set)?;
        }
        let mut times = Vec::with_capacity(a.frames);
        let start = Instant::now();
        for _ in 0..a.frames {
            let t = Instant::now();
            camera.render(&world, set)?;
            times.push(t.elapsed().as_secs_f64());
        }
        let mean = a.frames as f64 / start.elapsed().as_secs_f64();
        let slowest = times.iter().copied().fold(0.0, f64::max);
        let fastest = times.iter().copied().fold(f64::INFINITY, f64::min);
        let (min, max) = (1.0 / slowest, 1.0 / fastest);
        println!("{:<14} {mean:>10.1} {min:>10.1} {max:>10.1}", m.name());
        rows.insert(
            m.name().to_owned(),
            json!({"fps_mean": mean, "fps_min": min, "fps_max": max}),
        );
    }
    if let Some(path) = &a.json {
        let out = json!({
            "preset": a.camera.preset,
            "backend": camera.backend().name(),
            "adapter": camera.adapter(),
            "width": config.intrinsics.width,
            "height": config.intrinsics.height,
            "frames": a.frames,
            "items": camera.scene().items.len(),
            "triangles_estimate": triangles,
            "threads": rayon_threads(),
            "modalities": rows,
        });
        std::fs::write(path, serde_json::to_string_pretty(&out)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Worker threads the ray caster may use.
fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
