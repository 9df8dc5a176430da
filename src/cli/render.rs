//! `hearth render`: images and arrays of every camera modality from a robot in a home.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use hearth_sim::sensors::{Backend, Camera, CameraConfig, Modality, Mount, Preset};
use hearth_sim::world::{World, WorldConfig};

/// Camera options shared by `hearth render` and `hearth bench render`.
#[derive(Args, Debug, Clone)]
pub struct CameraArgs {
    /// Render preset: visual-rl (128×128, PBR) or high-fidelity (512×512, PBR, MSAA, shadows).
    #[arg(long, default_value = "visual-rl")]
    pub preset: String,
    /// Camera backend: auto (wgpu when an adapter exists), wgpu, or raycast (no driver needed).
    #[arg(long, default_value = "auto")]
    pub backend: String,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 90.0)]
    pub vfov: f64,
    /// Camera link of the robot (default: the robot's camera, `eyes` on the Fetch).
    #[arg(long)]
    pub link: Option<String>,
}

impl CameraArgs {
    /// The camera configuration these options describe.
    pub fn config(&self) -> anyhow::Result<CameraConfig> {
        let preset: Preset = self.preset.parse()?;
        let backend: Backend = self.backend.parse()?;
        let mut config = CameraConfig::preset(preset)?;
        config.intrinsics.vfov_deg = self.vfov;
        config.intrinsics.validate()?;
        config.backend = backend;
        config.mount = self.link.as_deref().map(Mount::link);
        Ok(config)
    }
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    home: super::home::HomeArgs,
    /// Robot carrying the camera (fetch, locobot, turtlebot).
    #[arg(long, default_value = "fetch")]
    robot: String,
    /// Modalities, comma separated: rgb,depth,normal,seg,ins_seg,optical_flow,scene_flow,pc.
    #[arg(long, default_value = "rgb,depth,normal,seg,ins_seg,optical_flow,scene_flow,pc")]
    modalities: String,
    #[command(flatten)]
    camera: CameraArgs,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

/// The home in a settled world, its robot, and a camera on the robot.
pub(crate) fn robot_camera(
    home: &super::home::HomeArgs,
    robot: &str,
    config: CameraConfig,
) -> anyhow::Result<(World, hearth_sim::world::ModelHandle, Camera)> {
    let scene = home.load(Some(robot))?;
    let mut world = World::new(WorldConfig::default())?;
    let loaded = world.load_scene(&scene).context("loading the home into the world")?;
    let robot = loaded.robot.context("the scene places no robot to carry the camera")?;
    world.settle(120);
    let camera = Camera::new(&world, Some(robot), config)?;
    Ok((world, robot, camera))
}

/// Runs `hearth render`: loads the home, settles it, renders a first frame, drives the robot
/// forward while turning for a quarter second (so the flows show motion), and writes the
/// second frame.
pub fn run(a: RenderArgs) -> anyhow::Result<()> {
    let modalities = Modality::parse_list(&a.modalities)?;
    anyhow::ensure!(!modalities.is_empty(), "--modalities names no modality");
    let (mut world, robot, mut camera) = robot_camera(&a.home, &a.robot, a.camera.config()?)?;
    camera.render(&world, modalities)?;
    world.drive(robot, 0.4, 0.4)?;
    for _ in 0..8 {
        world.step();
    }
    let t = Instant::now();
    camera.render(&world, modalities)?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let frame = camera.frame();
    let written = frame.save(&a.out, "")?;
    println!(
        "rendered {}×{} with the {} backend ({}) in {ms:.1} ms; wrote {} files to {}",
        frame.width,
        frame.height,
        camera.backend().name(),
        camera.adapter(),
        written.len(),
        a.out.display()
    );
    for p in written {
        println!("  {}", p.display());
    }
    Ok(())
}
