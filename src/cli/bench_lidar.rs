//! `hearth bench lidar`: LiDAR scans per second in a home, from the robot's laser link.
//!
//! 1 beam is the Hokuyo URG-04LX (228 rays over 240°, as iGibson's Fetch); 16 beams is the
//! Velodyne VLP-16 at `--resolution` degrees per azimuth step. The default is 1° (360 × 16 =
//! 5,760 rays a scan), coarser than the real sensor's 0.2° at 10 Hz (1800 × 16 = 28,800
//! rays): pass `--resolution 0.2` for that.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use hearth_sim::scene::SceneFile;
use hearth_sim::sensors::{
    CulledRays, IgnoredHits, Lidar, LidarNoise, LidarSpec, RayScene, Scan, VisualScene, lidar_pose, model_items,
};
use hearth_sim::world::{World, WorldConfig};
use nalgebra::Isometry3;
use serde_json::json;

use super::bench::percentile;

/// What rays do at the robot's own body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RobotHits {
    /// Pass through it and report what lies beyond.
    Pass,
    /// No return where a ray meets it (iGibson).
    NoReturn,
    /// Report it like any other surface.
    See,
}

/// Default VLP-16 azimuth step, degrees (the real sensor turns at 0.1°–0.4°; 1° keeps a
/// 16-beam scan at 5,760 rays).
const VLP16_DEFAULT_RES_DEG: f64 = 1.0;

#[derive(Args, Debug)]
pub struct BenchLidarArgs {
    /// Beams: 1 (Hokuyo URG-04LX planar scan) or 16 (Velodyne VLP-16).
    #[arg(long, default_value_t = 1)]
    beams: u32,
    /// Generate a home with this seed (the default when no --scene is given: seed 1).
    #[arg(long, conflicts_with = "scene")]
    generate: Option<u64>,
    /// Scene file (JSON) to load instead of generating a home.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Rooms of the generated home besides the corridor (2 to 12).
    #[arg(long, default_value_t = 5)]
    rooms: usize,
    /// VLP-16 azimuth step in degrees (16 beams only).
    #[arg(long, default_value_t = VLP16_DEFAULT_RES_DEG)]
    resolution: f64,
    /// Scans to time (after a warm-up of a tenth as many).
    #[arg(long)]
    scans: Option<usize>,
    /// Timing chunks the scans are split into; the median chunk rate is reported.
    #[arg(long, default_value_t = 20)]
    chunks: usize,
    /// Dropout probability of the noise model (0 = none).
    #[arg(long, default_value_t = 0.0)]
    dropout: f64,
    /// Gaussian range noise, standard deviation in metres (0 = none).
    #[arg(long, default_value_t = 0.0)]
    gaussian_std: f64,
    /// What rays do at the robot's own body: pass through it (`pass`), give no return there
    /// as iGibson's scans (`no-return`), or report it like anything else (`see`).
    #[arg(long, value_enum, default_value_t = RobotHits::Pass)]
    robot_hits: RobotHits,
    /// Cast against the whole ray scene instead of a copy culled to the sensor's reach
    /// (`Lidar::scan_culled`, the default, which also reads the world's poses every scan).
    #[arg(long)]
    full_scene: bool,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// The home to scan: the file, or a generated one (seed 1 by default, with a Fetch in its
/// corridor).
fn bench_scene(a: &BenchLidarArgs) -> anyhow::Result<SceneFile> {
    super::home::load_home(a.scene.as_deref(), Some(a.generate.unwrap_or(1)), a.rooms, None)
}

/// Runs `hearth bench lidar`.
pub fn run(a: BenchLidarArgs) -> anyhow::Result<()> {
    let (spec, preset) = match a.beams {
        1 => (LidarSpec::hokuyo_urg_04lx(), "hokuyo_urg_04lx".to_owned()),
        16 => (
            LidarSpec::velodyne_vlp16(a.resolution)?,
            format!("velodyne_vlp16@{}deg", a.resolution),
        ),
        b => bail!("--beams must be 1 or 16, not {b}"),
    };
    let scans = a.scans.unwrap_or(if a.beams == 1 { 20_000 } else { 400 });
    if scans == 0 || a.chunks == 0 {
        bail!("--scans and --chunks must be at least 1");
    }
    let scene = bench_scene(&a)?;
    let mut world = World::new(WorldConfig::default())?;
    let loaded = world
        .load_scene(&scene)
        .with_context(|| format!("loading scene `{}` into the world", scene.name))?;
    let visuals = VisualScene::from_world(&world);
    let t0 = Instant::now();
    let mut rays = RayScene::new(&visuals);
    rays.update(&visuals, &world);
    let build_ms = t0.elapsed().as_secs_f64() * 1e3;

    let noise = LidarNoise {
        dropout: a.dropout,
        gaussian_std: a.gaussian_std,
    };
    let mut lidar = Lidar::new(spec.clone(), noise, 1)?;
    super::bench::create_json(a.json.as_deref())?;
    // At the robot's laser link; a scene without a robot is scanned from 0.3 m above its origin.
    let (pose, mount) = match loaded.robot {
        Some(robot) => {
            let own = model_items(&visuals, &world, robot)?;
            match a.robot_hits {
                RobotHits::Pass => lidar.ignore_items(own, IgnoredHits::PassThrough),
                RobotHits::NoReturn => lidar.ignore_items(own, IgnoredHits::NoReturn),
                RobotHits::See => {}
            }
            (
                lidar_pose(&world, robot, None)?,
                format!("{}/laser_link", world.model_name(robot)?),
            )
        }
        None => (Isometry3::translation(0.0, 0.0, 0.3), "origin +0.3 m".to_owned()),
    };

    let mut scan = Scan::default();
    let mut culled = CulledRays::default();
    let mut scan_once = |lidar: &mut Lidar, scan: &mut Scan| {
        if a.full_scene {
            lidar.scan(&rays, &pose, scan);
        } else {
            lidar.scan_culled(&mut culled, &visuals, &world, &pose, scan);
        }
    };
    for _ in 0..scans.div_ceil(10).max(1) {
        scan_once(&mut lidar, &mut scan);
    }
    let hit_fraction = scan.hit_count() as f64 / scan.len().max(1) as f64;

    let chunk = scans.div_ceil(a.chunks).max(1);
    let mut rates = Vec::with_capacity(a.chunks);
    let mut done = 0;
    let start = Instant::now();
    while done < scans {
        let n = chunk.min(scans - done);
        let t0 = Instant::now();
        for _ in 0..n {
            scan_once(&mut lidar, &mut scan);
        }
        rates.push(n as f64 / t0.elapsed().as_secs_f64().max(1e-9));
        done += n;
    }
    let mean = scans as f64 / start.elapsed().as_secs_f64().max(1e-9);
    let median = percentile(&rates, 0.5);
    let rays_per_scan = spec.rays();
    let kept = if a.full_scene { rays.len() } else { culled.len() };
    let threads = Lidar::threads();

    println!(
        "scene `{}`: {} visual shapes, ray scene built in {build_ms:.1} ms; sensor at {mount}, {:.3} m up",
        scene.name,
        rays.len(),
        pose.translation.z
    );
    println!(
        "  casting against {kept} shapes ({})",
        if a.full_scene {
            "whole scene"
        } else {
            "culled to the sensor's reach"
        }
    );
    println!(
        "  {preset}: {} beam(s) × {} rays = {rays_per_scan} rays/scan, {:.2}–{:.1} m, {threads} threads, {:.1} % returns",
        spec.beams(),
        spec.horizontal_rays,
        spec.min_range,
        spec.max_range,
        100.0 * hit_fraction
    );
    println!("  {:<22} {:>12} {:>14}", "", "scans/s", "rays/s");
    println!(
        "  {:<22} {:>12.0} {:>14.3e}",
        "median of chunks",
        median,
        median * rays_per_scan as f64
    );
    println!("  {:<22} {:>12.0} {:>14.3e}", "mean", mean, mean * rays_per_scan as f64);
    println!(
        "  {:<22} {:>12} {:>14}",
        "slowest / fastest chunk",
        format!("{:.0} / {:.0}", percentile(&rates, 0.0), percentile(&rates, 1.0)),
        ""
    );

    let report = json!({
        "beams": spec.beams(),
        "rays_per_scan": rays_per_scan,
        "scans_per_s": median,
        "scans_per_s_mean": mean,
        "rays_per_s": median * rays_per_scan as f64,
        "preset": preset,
        "horizontal_rays": spec.horizontal_rays,
        "horizontal_resolution_deg": if a.beams == 16 { Some(a.resolution) } else { None },
        "threads": threads,
        "scans": scans,
        "chunks": a.chunks,
        "scene": scene.name,
        "visual_shapes": rays.len(),
        "hit_fraction": hit_fraction,
        "dropout": a.dropout,
        "gaussian_std": a.gaussian_std,
        "robot_hits": match a.robot_hits {
            RobotHits::Pass => "pass",
            RobotHits::NoReturn => "no-return",
            RobotHits::See => "see",
        },
        "ray_scene_build_ms": build_ms,
        "culled": !a.full_scene,
        "shapes_cast_against": kept,
    });
    if let Some(path) = &a.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
