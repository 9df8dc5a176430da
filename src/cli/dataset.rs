//! `hearth dataset`: datasets for learning, written by the skills.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};
use hearth_sim::sensors::Backend;
use hearth_skills::Execution;
use hearth_skills::relmogen::{DatasetSettings, PushDataset};

#[derive(Subcommand, Debug)]
pub enum DatasetCommand {
    /// Push at random pixels from random robot poses and record, per location, the RGB image,
    /// a per-pixel success mask and a JSON index of the pushes (resumable).
    Pushes(PushesArgs),
}

#[derive(Args, Debug)]
pub struct PushesArgs {
    #[command(flatten)]
    home: super::home::HomeArgs,
    /// Robot poses (camera views) to sample.
    #[arg(long, default_value_t = 10)]
    locations: usize,
    /// Pushes at random pixels per location.
    #[arg(long, default_value_t = 20)]
    pushes_per_location: usize,
    /// Output directory (locations already complete there are skipped).
    #[arg(long)]
    out: PathBuf,
    /// Kinematic execution (joints set along the plan) instead of physics.
    #[arg(long)]
    kinematic: bool,
    /// Seed of the poses and pixels.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Image width and height, pixels.
    #[arg(long, default_value_t = 128)]
    size: u32,
    /// Camera backend: auto, wgpu or raycast.
    #[arg(long, default_value = "auto")]
    backend: String,
    /// Fraction of locations facing articulated furniture (drawers and doors opened at random);
    /// the rest are uniform on the floor.
    #[arg(long, default_value_t = 0.75)]
    furniture_views: f64,
}

pub fn run(command: DatasetCommand) -> anyhow::Result<()> {
    match command {
        DatasetCommand::Pushes(a) => pushes(a),
    }
}

fn pushes(a: PushesArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (0.0..=1.0).contains(&a.furniture_views),
        "--furniture-views must be in [0, 1], got {}",
        a.furniture_views
    );
    let home = a.home.load(Some("fetch"))?;
    let backend: Backend = a.backend.parse()?;
    let settings = DatasetSettings {
        locations: a.locations,
        pushes_per_location: a.pushes_per_location,
        execution: if a.kinematic {
            Execution::Kinematic
        } else {
            Execution::Physics
        },
        seed: a.seed,
        width: a.size,
        height: a.size,
        backend,
        furniture_views: a.furniture_views,
        ..DatasetSettings::default()
    };
    let mut data = PushDataset::new(&home, settings).context("setting up the push dataset")?;
    eprintln!(
        "{} pieces of articulated furniture for furniture views",
        data.furniture_count()
    );
    let mut err = std::io::stderr();
    let summary = data
        .write(&a.out, |p| {
            let _ = write!(
                err,
                "\r[{}/{}] locations, {} pushes, {:.2} pushes/s   ",
                p.locations_done, p.locations, p.pushes, p.pushes_per_second
            );
            let _ = err.flush();
        })
        .with_context(|| format!("writing the dataset to `{}`", a.out.display()))?;
    eprintln!();
    println!(
        "{} locations written, {} skipped (complete); {} pushes, {} succeeded, in {:.1} s: {:.2} pushes/s ({})",
        summary.written,
        summary.skipped,
        summary.pushes,
        summary.successes,
        summary.seconds,
        summary.pushes_per_second,
        data.settings().execution
    );
    Ok(())
}
