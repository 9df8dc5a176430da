//! Command-line interface definitions and dispatch.

mod bench;
mod bench_compare;
mod bench_env;
mod bench_lidar;
mod bench_plan;
mod bench_render;
mod bench_sim;
mod dataset;
mod demo;
mod home;
mod kin;
mod render;
mod scene;
mod weight_schedule;

use clap::{Parser, Subcommand};

/// Hearth: motion planning and mobile manipulation with a physics-simulator backend.
#[derive(Parser, Debug)]
#[command(name = "hearth", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the main job on the embedded defaults and print a short report.
    Demo(demo::DemoArgs),
    /// Inspect robot models: links, joints, forward and inverse kinematics.
    #[command(subcommand)]
    Kin(kin::KinCommand),
    /// Measure speed.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Scenes: generate homes, summarise scene files, export them as URDF.
    #[command(subcommand)]
    Scene(scene::SceneCommand),
    /// Render camera modalities (RGB, depth, normals, segmentation, flows, point cloud) from
    /// a robot in a home and write PNG images and NumPy arrays.
    Render(render::RenderArgs),
    /// Datasets for learning (push outcomes per pixel).
    #[command(subcommand)]
    Dataset(dataset::DatasetCommand),
}

/// Runs one parsed command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Kin(c) => kin::run(c),
        Command::Bench(c) => bench::run(c),
        Command::Scene(c) => scene::run(c),
        Command::Render(a) => render::run(a),
        Command::Dataset(c) => dataset::run(c),
    }
}

/// Parses `"a,b,c"` into numbers, naming the bad item.
pub(crate) fn parse_list(text: &str, what: &str) -> anyhow::Result<Vec<f64>> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(Vec::new());
    }
    text.split(',')
        .enumerate()
        .map(|(i, s)| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| anyhow::anyhow!("{what}: item {i} `{}` is not a number", s.trim()))
        })
        .collect()
}
