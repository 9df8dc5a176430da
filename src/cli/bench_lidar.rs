//! `hearth bench lidar`: LiDAR scans per second in a generated home.

use clap::Args;

#[derive(Args, Debug)]
pub struct BenchLidarArgs {
    /// Beams: 1 (Hokuyo-style planar scan) or 16 (Velodyne VLP-16).
    #[arg(long, default_value_t = 1)]
    beams: u32,
}

pub fn run(a: BenchLidarArgs) -> anyhow::Result<()> {
    anyhow::bail!("bench lidar with {} beams: the LiDAR is being written", a.beams)
}
