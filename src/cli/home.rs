//! The home a command works in: a scene file, or a generated home.

use std::path::Path;

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{ArgGroup, Args};
use hearth_sim::scene::{GenerateOptions, SceneFile, generate};

/// Where a command's home comes from: a scene file or a generated home.
#[derive(Args, Debug, Clone)]
#[command(group(ArgGroup::new("source").required(true).args(["scene", "generate"])))]
pub struct HomeArgs {
    /// Scene file (JSON) to load.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Generate a home with this seed instead of loading a file.
    #[arg(long)]
    pub generate: Option<u64>,
    /// Rooms of the generated home besides the corridor (2 to 12).
    #[arg(long, default_value_t = 5)]
    pub rooms: usize,
}

impl HomeArgs {
    /// The home, with `robot` placed as [`load_home`] does.
    pub fn load(&self, robot: Option<&str>) -> anyhow::Result<SceneFile> {
        load_home(self.scene.as_deref(), self.generate, self.rooms, robot)
    }
}

/// Loads `scene`, or generates a home with `seed` and `rooms` placing `robot` in its corridor.
/// A loaded scene's robot is replaced by `robot` when one is named and the scene places one.
pub(crate) fn load_home(
    scene: Option<&Path>,
    seed: Option<u64>,
    rooms: usize,
    robot: Option<&str>,
) -> anyhow::Result<SceneFile> {
    let mut home = match (scene, seed) {
        (Some(path), _) => SceneFile::load(path).with_context(|| format!("loading scene `{}`", path.display()))?,
        (None, Some(seed)) => generate(&GenerateOptions {
            seed,
            rooms,
            robot: Some(robot.unwrap_or("fetch").to_owned()),
            small_objects: true,
        })
        .with_context(|| format!("generating a home (seed {seed}, {rooms} rooms)"))?,
        (None, None) => bail!("pass --scene FILE or --generate SEED"),
    };
    if let (Some(name), Some(placement)) = (robot, home.robot.as_mut()) {
        placement.name = name.to_owned();
    }
    Ok(home)
}
