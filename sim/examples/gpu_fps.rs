//! Frame rate of the wgpu camera, per modality, in a generated home (seed 1, default rooms)
//! seen from the Fetch's head camera turning on the spot; read-back included.
//!
//! ```text
//! cargo run --release -p hearth-sim --example gpu_fps [frames [visual-rl|high-fidelity]]
//! ```

use std::time::Instant;

use hearth_sim::scene::{GenerateOptions, generate};
use hearth_sim::sensors::{
    Frame, GpuCamera, Modality, ModalitySet, Mount, Preset, RenderOptions, VisualScene, gpu_adapter,
};
use hearth_sim::world::{World, WorldConfig};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};

fn main() {
    let frames: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(200);
    // Optional second argument: only this preset (`visual-rl` or `high-fidelity`).
    let only: Option<Preset> = std::env::args().nth(2).and_then(|a| a.parse().ok());
    let adapter = match gpu_adapter() {
        Ok(name) => name,
        Err(why) => {
            eprintln!("no graphics adapter: {why}");
            return;
        }
    };
    let scene_file = generate(&GenerateOptions {
        seed: 1,
        ..Default::default()
    })
    .expect("home");
    let mut world = World::new(WorldConfig::default()).expect("world");
    let loaded = world.load_scene(&scene_file).expect("load");
    let visuals = VisualScene::from_world(&world);
    let poses = visuals.world_poses(&world);
    let robot = loaded.robot.expect("the home places a Fetch");
    let eye = Mount::default_camera("fetch")
        .expect("fetch camera")
        .pose(&world, Some(robot))
        .expect("camera pose");
    println!(
        "adapter: {adapter}; {} items, {} lights, ~{} triangles",
        visuals.items.len(),
        visuals.lights.len(),
        visuals.triangle_estimate(16)
    );

    let mut cases: Vec<(String, ModalitySet)> = Modality::ALL
        .iter()
        .map(|&m| (m.name().to_owned(), ModalitySet::EMPTY.with(m)))
        .collect();
    cases.push(("rgb+depth+seg".into(), "rgb,depth,seg".parse_set()));
    cases.push(("all".into(), ModalitySet::ALL));

    // The two presets with every modality, then colour alone at 512×512 with one switch of
    // the high-fidelity preset at a time, to show what each costs.
    let hifi = RenderOptions::from(Preset::HighFidelity);
    let rgb_only = vec![("rgb".to_owned(), ModalitySet::EMPTY.with(Modality::Rgb))];
    let configs = [
        (Preset::VisualRl, RenderOptions::from(Preset::VisualRl), cases.clone()),
        (Preset::HighFidelity, hifi, cases.clone()),
        (
            Preset::HighFidelity,
            RenderOptions {
                msaa: 1,
                shadows: false,
                ..hifi
            },
            rgb_only.clone(),
        ),
        (
            Preset::HighFidelity,
            RenderOptions { msaa: 1, ..hifi },
            rgb_only.clone(),
        ),
        (
            Preset::HighFidelity,
            RenderOptions { shadows: false, ..hifi },
            rgb_only.clone(),
        ),
        (
            Preset::HighFidelity,
            RenderOptions {
                pbr: false,
                msaa: 1,
                shadows: false,
            },
            rgb_only,
        ),
    ];
    for (preset, options, cases) in configs {
        if only.is_some_and(|p| p != preset) {
            continue;
        }
        let k = preset.intrinsics(90.0).expect("intrinsics");
        let t0 = Instant::now();
        let mut cam = GpuCamera::new(&visuals, k, options).expect("camera");
        println!(
            "\n{} ({}×{}, {:?}): camera created in {:.0} ms",
            preset.name(),
            k.width,
            k.height,
            options,
            t0.elapsed().as_secs_f64() * 1e3
        );
        let mut frame = Frame::default();
        for (name, set) in &cases {
            let n = if preset == Preset::HighFidelity {
                frames / 4
            } else {
                frames
            }
            .max(5);
            // Warm up: pipelines are built on first use.
            for i in 0..3 {
                cam.render(&poses, &turned(&eye, i), *set, &mut frame).expect("render");
            }
            let t = Instant::now();
            for i in 0..n {
                cam.render(&poses, &turned(&eye, i), *set, &mut frame).expect("render");
            }
            let dt = t.elapsed().as_secs_f64();
            println!(
                "  {name:<14} {:7.1} fps  ({:.2} ms/frame)",
                n as f64 / dt,
                dt * 1e3 / n as f64
            );
        }
    }
}

/// The camera turned about the world z axis by `i` degrees.
fn turned(eye: &Isometry3<f64>, i: usize) -> Isometry3<f64> {
    let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (i as f64).to_radians());
    Isometry3::from_parts(eye.translation, yaw * eye.rotation)
}

trait ParseSet {
    fn parse_set(&self) -> ModalitySet;
}

impl ParseSet for str {
    fn parse_set(&self) -> ModalitySet {
        Modality::parse_list(self).expect("modalities")
    }
}
