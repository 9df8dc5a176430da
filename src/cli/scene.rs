//! `hearth scene generate|info|export`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};
use hearth_sim::scene::{GenerateOptions, SceneFile, SceneInfo, export_urdf, generate};

#[derive(Subcommand, Debug)]
pub enum SceneCommand {
    /// Build a procedurally generated multi-room home and save it as a scene file.
    Generate(GenerateArgs),
    /// Rooms (name, type, area), objects per room, categories and articulated objects.
    Info(InfoArgs),
    /// Write a scene as URDF files (building, one per object, robot) plus DIR/scene.json.
    Export(ExportArgs),
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// Random seed: the same seed gives the same home.
    #[arg(long)]
    seed: u64,
    /// Rooms besides the corridor (2 to 12).
    #[arg(long, default_value_t = 5)]
    rooms: usize,
    /// Built-in robot placed in the corridor; `none` for no robot.
    #[arg(long, default_value = "fetch")]
    robot: String,
    /// Leave the surfaces empty (furniture only).
    #[arg(long)]
    no_small_objects: bool,
    /// Scene file to write (JSON).
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene file (JSON).
    file: PathBuf,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Scene file (JSON).
    file: PathBuf,
    /// Built-in robot to write and place at the scene's robot pose.
    #[arg(long)]
    robot: Option<String>,
    /// Directory to write the URDF files and scene.json into.
    #[arg(long)]
    urdf_dir: PathBuf,
}

/// Runs one `scene` subcommand.
pub fn run(cmd: SceneCommand) -> anyhow::Result<()> {
    match cmd {
        SceneCommand::Generate(a) => run_generate(a),
        SceneCommand::Info(a) => run_info(a),
        SceneCommand::Export(a) => run_export(a),
    }
}

fn load(file: &PathBuf) -> anyhow::Result<SceneFile> {
    SceneFile::load(file).with_context(|| format!("loading scene `{}`", file.display()))
}

fn run_generate(a: GenerateArgs) -> anyhow::Result<()> {
    let opts = GenerateOptions {
        seed: a.seed,
        rooms: a.rooms,
        robot: (a.robot != "none").then_some(a.robot),
        small_objects: !a.no_small_objects,
    };
    let start = Instant::now();
    let scene = generate(&opts).with_context(|| format!("generating a home with seed {}", a.seed))?;
    let took = start.elapsed();
    scene
        .save(&a.out)
        .with_context(|| format!("writing `{}`", a.out.display()))?;
    let info = SceneInfo::of(&scene);
    println!(
        "wrote {}: {} rooms, {} objects ({:.1} per room), {} articulated, generated in {:.0} ms",
        a.out.display(),
        info.rooms.len(),
        info.objects,
        info.objects_per_room,
        info.articulated.len(),
        took.as_secs_f64() * 1e3
    );
    Ok(())
}

fn run_info(a: InfoArgs) -> anyhow::Result<()> {
    let scene = load(&a.file)?;
    let info = SceneInfo::of(&scene);
    if a.json {
        println!("{}", info.to_json()?);
        return Ok(());
    }
    println!(
        "scene `{}`: {} objects in {} rooms ({:.1} per room)",
        info.name,
        info.objects,
        info.rooms.len(),
        info.objects_per_room
    );
    println!("{:<16} {:<12} {:>8} {:>8}", "room", "type", "area m²", "objects");
    for r in &info.rooms {
        println!(
            "{:<16} {:<12} {:>8.1} {:>8}",
            r.name,
            r.room_type.name(),
            r.area,
            r.objects
        );
    }
    if info.unassigned > 0 {
        println!("{} objects lie outside every room", info.unassigned);
    }
    let cats: Vec<String> = info.categories.iter().map(|(c, n)| format!("{c} {n}")).collect();
    println!("categories ({}): {}", info.categories.len(), cats.join(", "));
    println!(
        "articulated ({}): {}",
        info.articulated.len(),
        info.articulated.join(", ")
    );
    Ok(())
}

fn run_export(a: ExportArgs) -> anyhow::Result<()> {
    let scene = load(&a.file)?;
    let manifest = export_urdf(&scene, &a.urdf_dir, a.robot.as_deref())
        .with_context(|| format!("exporting `{}` to `{}`", a.file.display(), a.urdf_dir.display()))?;
    println!(
        "wrote {} bodies to {} (manifest {})",
        manifest.bodies.len(),
        a.urdf_dir.display(),
        a.urdf_dir.join("scene.json").display()
    );
    Ok(())
}
