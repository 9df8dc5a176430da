//! Known geometry, known answers, on both camera backends through the same [`Camera`] front:
//! depth, normals, point cloud, segmentation, flows, RGB colour, clipping, mounts and bad input.
//! The wgpu backend is skipped with a notice when no adapter exists, unless
//! `HEARTH_REQUIRE_GPU=1`.

use hearth_sim::assets::Material;
use hearth_sim::kinematics::RobotModel;
use hearth_sim::sensors::{
    Backend, Camera, CameraConfig, CameraIntrinsics, Frame, Modality, ModalitySet, Mount, PbrMaterial, Preset,
    RenderOptions, SemanticClass, SensorError, gpu_adapter,
};
use hearth_sim::world::{BodyId, SpawnOptions, World, WorldConfig};
use nalgebra::{Isometry3, Point3, Vector3};

/// The backends to test: ray casting always, wgpu when an adapter exists (required when
/// `HEARTH_REQUIRE_GPU=1`).
fn backends() -> Vec<Backend> {
    let mut out = vec![Backend::Raycast];
    match gpu_adapter() {
        Ok(_) => out.push(Backend::Wgpu),
        Err(reason) => {
            if std::env::var("HEARTH_REQUIRE_GPU").as_deref() == Ok("1") {
                panic!("HEARTH_REQUIRE_GPU=1 but no graphics adapter: {reason}");
            }
            eprintln!("note: wgpu camera checks skipped, no graphics adapter ({reason})");
        }
    }
    out
}

const W: u32 = 64;
const H: u32 = 48;

fn all() -> ModalitySet {
    ModalitySet::ALL
}

/// A world without ground, a camera at (0, 0, 1) looking along +x.
fn empty_world() -> World {
    World::new(WorldConfig {
        ground_plane: false,
        ..WorldConfig::default()
    })
    .unwrap()
}

fn camera_pose() -> Isometry3<f64> {
    let Mount::Free(p) = Mount::look_at(Point3::new(0.0, 0.0, 1.0), Point3::new(5.0, 0.0, 1.0)).unwrap() else {
        unreachable!()
    };
    p
}

fn camera(world: &World, backend: Backend, options: RenderOptions) -> Camera {
    let mut intrinsics = CameraIntrinsics::new(W, H, 60.0).unwrap();
    intrinsics.far = 20.0;
    let config = CameraConfig {
        intrinsics,
        options,
        backend,
        mount: Some(Mount::Free(camera_pose())),
    };
    Camera::new(world, None, config).unwrap()
}

fn add_box(world: &mut World, name: &str, half: [f64; 3], at: [f64; 3]) -> BodyId {
    world
        .add_box(name, half, &Isometry3::translation(at[0], at[1], at[2]), false)
        .unwrap()
}

fn centre(f: &Frame) -> usize {
    f.index(W / 2, H / 2)
}

#[test]
fn a_box_ahead_gives_depth_normal_point_and_ids_at_the_centre() {
    for backend in backends() {
        let mut world = empty_world();
        add_box(&mut world, "crate", [0.5; 3], [3.0, 0.0, 1.0]);
        let mut cam = camera(&world, backend, RenderOptions::default());
        let instance = cam.scene().instances.iter().position(|i| i.name == "crate").unwrap() as u32 + 1;
        let f = cam.render(&world, all()).unwrap();
        let c = centre(f);
        // Pixel centres sit half a pixel off the optical axis; the box face is flat, so depth is exact.
        assert!((f.depth[c] - 2.5).abs() < 0.01, "{backend:?}: depth {}", f.depth[c]);
        let n = Vector3::from(f.normal[c]);
        assert!(
            (n - Vector3::new(0.0, 0.0, -1.0)).norm() < 0.02,
            "{backend:?}: normal {n:?}"
        );
        let p = f.pc[c];
        assert!(
            (p[2] - 2.5).abs() < 0.01 && p[0].abs() < 0.05 && p[1].abs() < 0.05,
            "{backend:?}: {p:?}"
        );
        assert_eq!(f.seg[c], SemanticClass::OBJECT, "{backend:?}");
        assert_eq!(f.ins_seg[c], instance, "{backend:?}");
        // A corner sees the sky: nothing.
        let corner = f.index(0, 0);
        assert_eq!(
            (f.depth[corner], f.seg[corner], f.ins_seg[corner]),
            (0.0, 0, 0),
            "{backend:?}"
        );
        assert_eq!(f.normal[corner], [0.0; 3]);
        assert_eq!(f.rgb.len(), 3 * (W * H) as usize);
    }
}

#[test]
fn segmentation_separates_two_objects_and_names_their_classes() {
    for backend in backends() {
        let mut world = empty_world();
        add_box(&mut world, "left", [0.3, 0.6, 0.6], [3.0, 0.7, 1.0]);
        add_box(&mut world, "right", [0.3, 0.6, 0.6], [3.0, -0.7, 1.0]);
        let mut cam = camera(&world, backend, RenderOptions::default());
        let id = |name: &str| cam.scene().instances.iter().position(|i| i.name == name).unwrap() as u32 + 1;
        let (left, right) = (id("left"), id("right"));
        assert_ne!(left, right);
        let f = cam.render(&world, ModalitySet::EMPTY.with(Modality::InsSeg)).unwrap();
        // World +y is image left (the camera looks along +x with z up).
        assert_eq!(f.ins_seg[f.index(W / 4, H / 2)], left, "{backend:?}");
        assert_eq!(f.ins_seg[f.index(3 * W / 4, H / 2)], right, "{backend:?}");
        assert!(
            f.seg.is_empty() && f.depth.is_empty(),
            "only what was asked is produced"
        );
    }
}

#[test]
fn a_fridge_reads_as_its_category() {
    for backend in backends() {
        let mut world = empty_world();
        let fridge = hearth_sim::assets::Asset::build(hearth_sim::assets::Category::Fridge, 0, 1.0).unwrap();
        let pose = Isometry3::from_parts(
            nalgebra::Translation3::new(2.5, 0.0, 0.0),
            nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::PI),
        );
        world.spawn_model(&fridge.model, &pose, SpawnOptions::fixed()).unwrap();
        let mut cam = camera(&world, backend, RenderOptions::default());
        let f = cam.render(&world, ModalitySet::EMPTY.with(Modality::Seg)).unwrap();
        let want = SemanticClass::of_category(hearth_sim::assets::Category::Fridge);
        assert_eq!(f.seg[centre(f)], want, "{backend:?}");
    }
}

#[test]
fn moving_the_camera_or_the_object_gives_the_expected_flows() {
    for backend in backends() {
        let mut world = empty_world();
        let body = add_box(&mut world, "crate", [0.5, 1.0, 1.0], [3.0, 0.0, 1.0]);
        let mut cam = camera(&world, backend, RenderOptions::default());
        let flows = ModalitySet::EMPTY
            .with(Modality::OpticalFlow)
            .with(Modality::SceneFlow)
            .with(Modality::Depth);
        let pose = camera_pose();
        let f = cam.render_from(&world, &pose, flows).unwrap();
        assert_eq!(f.optical_flow[centre(f)], [0.0; 2], "first frame has no flow");
        // Camera 0.1 m to its right (camera +x): the scene moves left in the image.
        let shifted = pose * nalgebra::Translation3::new(0.1, 0.0, 0.0);
        let f = cam.render_from(&world, &shifted, flows).unwrap();
        let c = centre(f);
        let fx = CameraIntrinsics::new(W, H, 60.0).unwrap().fx() as f32;
        let expect_u = -fx * 0.1 / 2.5;
        let of = f.optical_flow[c];
        assert!(
            (of[0] - expect_u).abs() < 0.05 && of[1].abs() < 0.05,
            "{backend:?}: {of:?} vs {expect_u}"
        );
        let sf = f.scene_flow[c];
        assert!(
            (sf[0] + 0.1).abs() < 2e-3 && sf[1].abs() < 2e-3 && sf[2].abs() < 2e-3,
            "{backend:?}: {sf:?}"
        );
        // Now the object moves 0.1 m to the camera's right (world −y) and the camera stays.
        cam.render_from(&world, &shifted, flows).unwrap();
        world
            .set_body_pose(body, &Isometry3::translation(3.0, -0.1, 1.0))
            .unwrap();
        let f = cam.render_from(&world, &shifted, flows).unwrap();
        let of = f.optical_flow[centre(f)];
        assert!(
            (of[0] + expect_u).abs() < 0.05 && of[1].abs() < 0.05,
            "{backend:?}: {of:?}"
        );
        let sf = f.scene_flow[centre(f)];
        assert!((sf[0] - 0.1).abs() < 2e-3 && sf[1].abs() < 2e-3, "{backend:?}: {sf:?}");
        cam.reset_flow();
        let f = cam.render_from(&world, &shifted, flows).unwrap();
        assert_eq!(f.scene_flow[centre(f)], [0.0; 3]);
    }
}

#[test]
fn rgb_follows_the_material_and_the_sky_is_the_background() {
    for backend in backends() {
        let mut world = empty_world();
        add_box(&mut world, "crate", [0.5; 3], [3.0, 0.0, 1.0]);
        let mut cam = camera(&world, backend, RenderOptions::default());
        let item = cam.scene().items.len() - 1;
        let red = PbrMaterial {
            base_color: [0.8, 0.05, 0.05, 1.0],
            ..PbrMaterial::of(Material::Plastic)
        };
        cam.set_material(item, red).unwrap();
        let rgb = ModalitySet::EMPTY.with(Modality::Rgb);
        let f = cam.render(&world, rgb).unwrap();
        let c = 3 * centre(f);
        let px = &f.rgb[c..c + 3];
        assert!(
            px[0] > px[1] + 40 && px[0] > px[2] + 40,
            "{backend:?}: red box is {px:?}"
        );
        let sky = f.rgb[0..3].to_vec();
        assert!(sky[2] > sky[0], "{backend:?}: the sky is bluish: {sky:?}");
        // Both backends paint empty pixels the same colour (the GPU's within rounding).
        let background = hearth_sim::sensors::shading::BACKGROUND_SRGB;
        assert!(
            sky.iter().zip(background).all(|(&a, b)| a.abs_diff(b) <= 2),
            "{backend:?}: the sky is {sky:?}, not {background:?}"
        );
        let blue = PbrMaterial {
            base_color: [0.05, 0.05, 0.8, 1.0],
            ..red
        };
        cam.set_material(item, blue).unwrap();
        let f = cam.render(&world, rgb).unwrap();
        let px = &f.rgb[c..c + 3];
        assert!(
            px[2] > px[0] + 40 && px[2] > px[1] + 40,
            "{backend:?}: blue box is {px:?}"
        );
        assert!(matches!(
            cam.set_material(10_000, blue),
            Err(SensorError::InvalidParameter { .. })
        ));
    }
}

#[test]
fn depth_outside_near_and_far_reads_zero() {
    for backend in backends() {
        let mut world = empty_world();
        add_box(&mut world, "far", [0.5, 3.0, 3.0], [30.0, 0.0, 1.0]);
        let mut cam = camera(&world, backend, RenderOptions::default());
        let f = cam.render(&world, ModalitySet::EMPTY.with(Modality::Depth)).unwrap();
        assert!(f.depth.iter().all(|&d| d == 0.0), "{backend:?}: beyond far = 20 m");
    }
}

#[test]
fn shadows_darken_what_the_sun_cannot_reach() {
    for backend in backends() {
        let mut world = World::new(WorldConfig::default()).unwrap();
        // A slab hovering over the floor in front of the camera; the default sun comes from above.
        add_box(&mut world, "roof", [1.5, 1.5, 0.05], [3.0, 0.0, 1.2]);
        let mut intrinsics = CameraIntrinsics::new(W, H, 60.0).unwrap();
        intrinsics.far = 50.0;
        let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 3.0), Point3::new(3.0, 0.0, 0.0)).unwrap() else {
            unreachable!()
        };
        let render = |shadows: bool| {
            let config = CameraConfig {
                intrinsics,
                options: RenderOptions {
                    pbr: true,
                    shadows,
                    msaa: 1,
                },
                backend,
                mount: Some(Mount::Free(pose)),
            };
            let mut cam = Camera::new(&world, None, config).unwrap();
            let f = cam.render(&world, ModalitySet::EMPTY.with(Modality::Rgb)).unwrap();
            f.rgb.iter().map(|&c| c as u64).sum::<u64>()
        };
        let (lit, shadowed) = (render(false), render(true));
        assert!(shadowed < lit, "{backend:?}: shadows {shadowed} vs none {lit}");
    }
}

#[test]
fn a_fetch_head_camera_sees_the_world_from_its_eyes() {
    for backend in backends() {
        let mut world = World::new(WorldConfig::default()).unwrap();
        let fetch = RobotModel::builtin("fetch").unwrap();
        let robot = world
            .spawn_model(&fetch, &Isometry3::identity(), SpawnOptions::free())
            .unwrap();
        add_box(&mut world, "wall", [0.1, 3.0, 1.5], [3.0, 0.0, 1.5]);
        let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
        config.backend = backend;
        let mut cam = Camera::new(&world, Some(robot), config).unwrap();
        let eyes = world.link_pose(robot, "eyes").unwrap();
        let pose = cam.pose(&world).unwrap();
        assert!((pose.translation.vector - eyes.translation.vector).norm() < 1e-9);
        let forward = pose.rotation * Vector3::z();
        assert!((forward - eyes.rotation * Vector3::x()).norm() < 1e-9);
        let f = cam.render(&world, ModalitySet::EMPTY.with(Modality::Depth)).unwrap();
        let d = f.depth[f.index(64, 64)];
        let expect = 2.9 - eyes.translation.x;
        assert!((d as f64 - expect).abs() < 0.05, "{backend:?}: {d} vs {expect}");
    }
}

#[test]
fn bad_configurations_are_typed_errors() {
    let world = empty_world();
    let fetch_world = {
        let mut w = World::new(WorldConfig::default()).unwrap();
        let fetch = RobotModel::builtin("fetch").unwrap();
        let r = w
            .spawn_model(&fetch, &Isometry3::identity(), SpawnOptions::free())
            .unwrap();
        (w, r)
    };
    assert!(matches!(
        CameraIntrinsics::new(0, 10, 60.0),
        Err(SensorError::InvalidResolution { .. })
    ));
    assert!(matches!(
        CameraIntrinsics::new(100_000, 10, 60.0),
        Err(SensorError::InvalidResolution { .. })
    ));
    assert!(matches!(
        CameraIntrinsics::new(10, 10, f64::NAN),
        Err(SensorError::InvalidParameter { .. })
    ));
    assert!(matches!(
        Modality::parse_list("rgb,thermal"),
        Err(SensorError::UnknownModality { .. })
    ));
    let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    config.backend = Backend::Raycast;
    assert!(matches!(
        Camera::new(&world, None, config.clone()),
        Err(SensorError::NoDefaultMount { .. })
    ));
    let (w, robot) = &fetch_world;
    config.mount = Some(Mount::link("periscope_link"));
    let err = Camera::new(w, Some(*robot), config.clone()).unwrap_err();
    assert!(
        matches!(err, SensorError::NoSuchLink { ref link, .. } if link == "periscope_link"),
        "{err:?}"
    );
    config.intrinsics.width = 0;
    assert!(Camera::new(w, Some(*robot), config).is_err());
    if gpu_adapter().is_err() {
        let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
        config.backend = Backend::Wgpu;
        config.mount = Some(Mount::Free(Isometry3::identity()));
        assert!(matches!(
            Camera::new(&world, None, config),
            Err(SensorError::NoAdapter { .. })
        ));
    }
}

#[test]
fn frames_save_as_png_and_npy() {
    let mut world = empty_world();
    add_box(&mut world, "crate", [0.5; 3], [3.0, 0.0, 1.0]);
    let mut cam = camera(&world, Backend::Raycast, RenderOptions::default());
    let f = cam.render(&world, all()).unwrap();
    let dir = std::env::temp_dir().join(format!("hearth-frame-save-{}", std::process::id()));
    let written = f.save(&dir, "").unwrap();
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for want in [
        "rgb.png",
        "depth.png",
        "depth.npy",
        "seg.png",
        "ins_seg.npy",
        "optical_flow.png",
        "pc.npy",
    ] {
        assert!(names.iter().any(|n| n == want), "{want} missing from {names:?}");
    }
    // The 16-bit depth PNG holds millimetres.
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.join("depth.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let c = 2 * centre(f);
    let mm = u16::from_be_bytes([buf[c], buf[c + 1]]);
    assert!((mm as i32 - 2500).abs() <= 10, "{mm}");
    std::fs::remove_dir_all(&dir).unwrap();
}

proptest::proptest! {
    /// Any text given as a modality list, preset or backend parses or fails with a typed error,
    /// never a panic; what parses round-trips through the names.
    #[test]
    fn sensor_names_parse_or_fail_cleanly(text in "[a-z_, -]{0,40}") {
        if let Ok(set) = Modality::parse_list(&text) {
            let names: Vec<&str> = set.iter().map(Modality::name).collect();
            proptest::prop_assert_eq!(Modality::parse_list(&names.join(",")).unwrap(), set);
        }
        let _ = text.parse::<Preset>();
        let _ = text.parse::<Backend>();
    }
}
