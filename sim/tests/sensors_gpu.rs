//! The wgpu camera against known geometry: depth, normals, point cloud and ids of a box in
//! front of the camera; instance ids of two boxes; optical and scene flow of a known motion;
//! colour and material changes; far clipping; shadows; refused input.
//!
//! Each test needs a graphics adapter (Mesa's lavapipe is enough). Without one it prints a
//! notice and passes, unless `HEARTH_REQUIRE_GPU=1`, which makes a missing adapter a failure.

use hearth_sim::sensors::{
    CameraIntrinsics, Frame, GpuCamera, Modality, ModalitySet, Mount, PbrMaterial, Preset, RenderOptions, SensorError,
    VisualScene, gpu_adapter,
};
use hearth_sim::world::{World, WorldConfig};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};

/// Whether an adapter exists; panics when none does and `HEARTH_REQUIRE_GPU=1`.
fn gpu_available() -> bool {
    match gpu_adapter() {
        Ok(_) => true,
        Err(why) => {
            if std::env::var("HEARTH_REQUIRE_GPU").as_deref() == Ok("1") {
                panic!("HEARTH_REQUIRE_GPU=1 but there is no graphics adapter: {why}");
            }
            eprintln!("skipping the wgpu camera test: no graphics adapter ({why})");
            false
        }
    }
}

/// Odd image sides, so the centre pixel's ray is the optical axis.
const SIDE: u32 = 63;
const CENTRE: u32 = SIDE / 2;

fn intrinsics() -> CameraIntrinsics {
    CameraIntrinsics::new(SIDE, SIDE, 60.0).unwrap()
}

fn world_without_ground() -> World {
    World::new(WorldConfig {
        ground_plane: false,
        ..Default::default()
    })
    .unwrap()
}

/// A camera at (0, 0, 1) looking along +x.
fn eye() -> Isometry3<f64> {
    let Mount::Free(pose) = Mount::look_at(Point3::new(0.0, 0.0, 1.0), Point3::new(3.0, 0.0, 1.0)).unwrap() else {
        unreachable!()
    };
    pose
}

/// A world with one cube (half extent 0.5) centred 3 m in front of the camera.
fn one_box() -> (World, VisualScene) {
    let mut world = world_without_ground();
    world
        .add_box("cube", [0.5; 3], &Isometry3::translation(3.0, 0.0, 1.0), false)
        .unwrap();
    let scene = VisualScene::from_world(&world);
    (world, scene)
}

fn set(ms: &[Modality]) -> ModalitySet {
    ms.iter().copied().collect()
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn box_in_front_gives_depth_normal_points_and_ids() {
    if !gpu_available() {
        return;
    }
    let (world, scene) = one_box();
    let mut cam = GpuCamera::new(&scene, intrinsics(), RenderOptions::default()).unwrap();
    assert!(!cam.adapter_name().is_empty());
    let mut frame = Frame::default();
    let all = set(&[
        Modality::Depth,
        Modality::Normal,
        Modality::Pc,
        Modality::Seg,
        Modality::InsSeg,
    ]);
    cam.render(&scene.world_poses(&world), &eye(), all, &mut frame).unwrap();
    assert_eq!((frame.width, frame.height), (SIDE, SIDE));

    let c = frame.index(CENTRE, CENTRE);
    assert!(close(frame.depth[c], 2.5, 0.01), "centre depth {}", frame.depth[c]);
    let n = frame.normal[c];
    assert!(
        close(n[0], 0.0, 0.01) && close(n[1], 0.0, 0.01) && close(n[2], -1.0, 0.01),
        "normal {n:?}"
    );
    let p = frame.pc[c];
    assert!(
        close(p[0], 0.0, 0.01) && close(p[1], 0.0, 0.01) && close(p[2], 2.5, 0.01),
        "pc {p:?}"
    );
    assert_eq!(frame.seg[c], scene.items[0].semantic);
    assert_eq!(frame.ins_seg[c], scene.items[0].instance);
    assert_ne!(frame.ins_seg[c], 0);

    // The point cloud is the depth along each pixel's ray, off-centre too.
    let k = intrinsics();
    let i = frame.index(CENTRE + 5, CENTRE - 4);
    let ray = k.pixel_ray((CENTRE + 5) as f64, (CENTRE - 4) as f64) * frame.depth[i] as f64;
    assert!((Vector3::from(frame.pc[i]).cast::<f64>() - ray).norm() < 1e-4);

    // A corner sees nothing.
    let corner = frame.index(0, 0);
    assert_eq!(frame.depth[corner], 0.0);
    assert_eq!(frame.seg[corner], 0);
    assert_eq!(frame.ins_seg[corner], 0);
    assert_eq!(frame.normal[corner], [0.0; 3]);
    assert_eq!(frame.pc[corner], [0.0; 3]);
}

#[test]
fn two_boxes_get_their_own_instance_ids_in_their_image_halves() {
    if !gpu_available() {
        return;
    }
    let mut world = world_without_ground();
    // The camera looks along +x with world z up, so world +y is image left.
    world
        .add_box("left", [0.4; 3], &Isometry3::translation(3.0, 0.6, 1.0), false)
        .unwrap();
    world
        .add_box("right", [0.4; 3], &Isometry3::translation(3.0, -0.6, 1.0), false)
        .unwrap();
    let scene = VisualScene::from_world(&world);
    let id = |name: &str| scene.instances.iter().position(|i| i.name == name).unwrap() as u32 + 1;
    let (left, right) = (id("left"), id("right"));
    assert_ne!(left, right);
    let mut cam = GpuCamera::new(&scene, intrinsics(), RenderOptions::default()).unwrap();
    let mut frame = Frame::default();
    cam.render(&scene.world_poses(&world), &eye(), set(&[Modality::InsSeg]), &mut frame)
        .unwrap();
    let (mut in_left, mut in_right) = (0, 0);
    for v in 0..SIDE {
        for u in 0..SIDE {
            let got = frame.ins_seg[frame.index(u, v)];
            if u < CENTRE {
                assert_ne!(got, right, "right box at ({u}, {v})");
                in_left += usize::from(got == left);
            } else if u > CENTRE {
                assert_ne!(got, left, "left box at ({u}, {v})");
                in_right += usize::from(got == right);
            }
        }
    }
    assert!(in_left > 50 && in_right > 50, "{in_left} / {in_right} pixels");
    assert_eq!(frame.ins_seg[frame.index(CENTRE, CENTRE)], 0, "a gap between the boxes");
}

#[test]
fn sideways_motion_gives_the_expected_flows() {
    if !gpu_available() {
        return;
    }
    let (world, scene) = one_box();
    let k = intrinsics();
    let mut cam = GpuCamera::new(&scene, k, RenderOptions::default()).unwrap();
    let flows = set(&[Modality::Depth, Modality::OpticalFlow, Modality::SceneFlow]);
    let poses = scene.world_poses(&world);
    let c = (CENTRE * SIDE + CENTRE) as usize;
    let mut frame = Frame::default();

    // First frame: both flows are 0.
    cam.render(&poses, &eye(), flows, &mut frame).unwrap();
    assert!(frame.optical_flow.iter().all(|f| *f == [0.0; 2]));
    assert!(frame.scene_flow.iter().all(|f| *f == [0.0; 3]));

    // The camera moves 0.1 m along its x axis: the box moves -0.1 m in the camera frame.
    let moved = eye() * Translation3::new(0.1, 0.0, 0.0);
    cam.render(&poses, &moved, flows, &mut frame).unwrap();
    let depth = frame.depth[c];
    assert!(close(depth, 2.5, 0.01));
    let expected_du = -(k.fx() * 0.1) as f32 / depth;
    let [du, dv] = frame.optical_flow[c];
    assert!(
        close(du, expected_du, 0.05) && close(dv, 0.0, 0.01),
        "optical flow ({du}, {dv})"
    );
    let sf = frame.scene_flow[c];
    assert!(
        close(sf[0], -0.1, 1e-3) && close(sf[1], 0.0, 1e-3) && close(sf[2], 0.0, 1e-3),
        "scene flow {sf:?}"
    );
    // Background has no flow.
    assert_eq!(frame.optical_flow[0], [0.0; 2]);

    // After a reset the flows are 0 again; then the box moves +0.1 m along the camera x axis
    // (world -y) with the camera still: the same flows with the opposite sign.
    cam.reset_flow();
    cam.render(&poses, &eye(), flows, &mut frame).unwrap();
    assert!(frame.optical_flow.iter().all(|f| *f == [0.0; 2]));
    let shift = eye().rotation * Vector3::new(0.1, 0.0, 0.0);
    let shifted: Vec<Isometry3<f64>> = poses.iter().map(|p| Translation3::from(shift) * p).collect();
    cam.render(&shifted, &eye(), flows, &mut frame).unwrap();
    let [du, dv] = frame.optical_flow[c];
    assert!(
        close(du, -expected_du, 0.05) && close(dv, 0.0, 0.01),
        "optical flow ({du}, {dv})"
    );
    let sf = frame.scene_flow[c];
    assert!(
        close(sf[0], 0.1, 1e-3) && close(sf[1], 0.0, 1e-3) && close(sf[2], 0.0, 1e-3),
        "scene flow {sf:?}"
    );
}

fn coloured(r: f32, g: f32, b: f32) -> PbrMaterial {
    PbrMaterial {
        base_color: [r, g, b, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        class: None,
    }
}

fn pixel(frame: &Frame, u: u32, v: u32) -> [u8; 3] {
    let i = 3 * frame.index(u, v);
    [frame.rgb[i], frame.rgb[i + 1], frame.rgb[i + 2]]
}

fn sky_like(px: [u8; 3]) -> bool {
    px.iter().zip(GpuCamera::SKY_RGB).all(|(&a, b)| a.abs_diff(b) <= 2)
}

#[test]
fn material_colour_shows_and_follows_set_material() {
    if !gpu_available() {
        return;
    }
    let (world, scene) = one_box();
    let poses = scene.world_poses(&world);
    for options in [RenderOptions::default(), RenderOptions::from(Preset::HighFidelity)] {
        let mut cam = GpuCamera::new(&scene, intrinsics(), options).unwrap();
        let mut frame = Frame::default();
        cam.set_material(0, coloured(0.8, 0.05, 0.05)).unwrap();
        cam.render(&poses, &eye(), set(&[Modality::Rgb]), &mut frame).unwrap();
        assert_eq!(frame.rgb.len(), (3 * SIDE * SIDE) as usize);
        let [r, g, b] = pixel(&frame, CENTRE, CENTRE);
        assert!(r > g + 20 && r > b + 20, "red box looks {:?} ({options:?})", [r, g, b]);
        assert!(sky_like(pixel(&frame, 0, 0)), "corner {:?}", pixel(&frame, 0, 0));

        cam.set_material(0, coloured(0.05, 0.05, 0.8)).unwrap();
        cam.render(&poses, &eye(), set(&[Modality::Rgb]), &mut frame).unwrap();
        let [r, g, b] = pixel(&frame, CENTRE, CENTRE);
        assert!(b > r + 20 && b > g + 20, "blue box looks {:?} ({options:?})", [r, g, b]);
    }
}

#[test]
fn objects_beyond_far_read_zero() {
    if !gpu_available() {
        return;
    }
    let (world, scene) = one_box();
    let k = CameraIntrinsics {
        far: 2.0,
        ..intrinsics()
    };
    let mut cam = GpuCamera::new(&scene, k, RenderOptions::default()).unwrap();
    let mut frame = Frame::default();
    let ms = set(&[Modality::Depth, Modality::InsSeg, Modality::Rgb]);
    cam.render(&scene.world_poses(&world), &eye(), ms, &mut frame).unwrap();
    assert!(frame.depth.iter().all(|&d| d == 0.0));
    assert!(frame.ins_seg.iter().all(|&i| i == 0));
    assert!(sky_like(pixel(&frame, CENTRE, CENTRE)));

    // Within range again with a farther clipping plane.
    let mut cam = GpuCamera::new(&scene, CameraIntrinsics { far: 2.6, ..k }, RenderOptions::default()).unwrap();
    cam.render(&scene.world_poses(&world), &eye(), ms, &mut frame).unwrap();
    assert!(close(frame.depth[frame.index(CENTRE, CENTRE)], 2.5, 0.01));
}

#[test]
fn the_sun_casts_a_shadow_with_shadows_on() {
    if !gpu_available() {
        return;
    }
    // A floating cube over the default ground, lit by the default sun travelling along
    // (0.3, 0.4, -1): the ground point (3.3, 0.4, 0) lies in its shadow, (3.3, -1.5, 0) does not.
    let mut world = World::new(WorldConfig::default()).unwrap();
    world
        .add_box("cube", [0.5; 3], &Isometry3::translation(3.0, 0.0, 1.0), false)
        .unwrap();
    let scene = VisualScene::from_world(&world);
    let k = intrinsics();
    let cam_pose = eye();
    let to_pixel = |p: Point3<f64>| {
        let (u, v) = k.project(&(cam_pose.inverse() * p)).unwrap();
        (u as u32, v as u32)
    };
    let (shade_px, lit_px) = (
        to_pixel(Point3::new(3.3, 0.4, 0.0)),
        to_pixel(Point3::new(3.3, -1.5, 0.0)),
    );
    let luma = |px: [u8; 3]| px.iter().map(|&c| c as u32).sum::<u32>();
    let mut frame = Frame::default();
    let ms = set(&[Modality::Rgb, Modality::Seg]);
    for shadows in [true, false] {
        let options = RenderOptions {
            shadows,
            ..RenderOptions::from(Preset::HighFidelity)
        };
        let mut cam = GpuCamera::new(&scene, k, options).unwrap();
        cam.render(&scene.world_poses(&world), &cam_pose, ms, &mut frame)
            .unwrap();
        let ground = scene.items[0].semantic;
        assert_eq!(frame.seg[frame.index(shade_px.0, shade_px.1)], ground);
        assert_eq!(frame.seg[frame.index(lit_px.0, lit_px.1)], ground);
        let (dark, bright) = (
            luma(pixel(&frame, shade_px.0, shade_px.1)),
            luma(pixel(&frame, lit_px.0, lit_px.1)),
        );
        if shadows {
            assert!(dark + 30 < bright, "shadowed {dark} vs lit {bright}");
        } else {
            assert!(dark.abs_diff(bright) < 30, "no shadow expected: {dark} vs {bright}");
        }
    }
}

#[test]
fn bad_input_is_refused() {
    if !gpu_available() {
        return;
    }
    let (world, scene) = one_box();
    let mut cam = GpuCamera::new(&scene, intrinsics(), RenderOptions::default()).unwrap();
    let mut frame = Frame::default();
    let mut poses = scene.world_poses(&world);
    poses.push(Isometry3::identity());
    let err = cam.render(&poses, &eye(), ModalitySet::ALL, &mut frame).unwrap_err();
    assert!(
        matches!(err, SensorError::InvalidParameter { name: "item_poses", .. }),
        "{err}"
    );
    let err = cam
        .set_material(scene.items.len(), coloured(1.0, 0.0, 0.0))
        .unwrap_err();
    assert!(matches!(err, SensorError::InvalidParameter { .. }), "{err}");
    // The camera still works after refusing.
    poses.pop();
    cam.render(&poses, &eye(), ModalitySet::ALL, &mut frame).unwrap();
    assert!(close(frame.depth[frame.index(CENTRE, CENTRE)], 2.5, 0.01));

    let zero = CameraIntrinsics {
        width: 0,
        ..intrinsics()
    };
    let err = GpuCamera::new(&scene, zero, RenderOptions::default()).unwrap_err();
    assert!(matches!(err, SensorError::InvalidResolution { .. }), "{err}");
    let huge = CameraIntrinsics {
        width: 100_000,
        ..intrinsics()
    };
    assert!(GpuCamera::new(&scene, huge, RenderOptions::default()).is_err());
}
