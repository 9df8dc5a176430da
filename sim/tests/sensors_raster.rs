//! The CPU rasteriser camera backend against the ray caster on fixed scenes: the same depth,
//! points and ids within a tolerance, nothing stale after bodies or the camera move, the inside
//! of a closed shape unseen, and a typed error for the modalities it does not draw.

use hearth_sim::scene::{GenerateOptions, generate};
use hearth_sim::sensors::{
    Backend, Camera, CameraConfig, CameraIntrinsics, Frame, Modality, ModalitySet, Mount, RenderOptions, SensorError,
};
use hearth_sim::world::{World, WorldConfig};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};

const W: u32 = 64;
const H: u32 = 48;

fn geometric() -> ModalitySet {
    ModalitySet::EMPTY
        .with(Modality::Depth)
        .with(Modality::Pc)
        .with(Modality::Normal)
        .with(Modality::Seg)
        .with(Modality::InsSeg)
}

fn look(eye: [f64; 3], at: [f64; 3]) -> Mount {
    Mount::look_at(Point3::from(eye), Point3::from(at)).unwrap()
}

fn camera(world: &World, backend: Backend, mount: Mount, w: u32, h: u32) -> Camera {
    let mut intrinsics = CameraIntrinsics::new(w, h, 70.0).unwrap();
    intrinsics.far = 12.0;
    let config = CameraConfig {
        intrinsics,
        options: RenderOptions::default(),
        backend,
        mount: Some(mount),
    };
    Camera::new(world, None, config).unwrap()
}

/// Boxes at odd angles and heights on the ground plane, one hanging in the air.
fn boxes() -> World {
    let mut world = World::new(WorldConfig::default()).unwrap();
    let yaw = |a: f64| UnitQuaternion::from_euler_angles(0.0, 0.0, a);
    let at = |x: f64, y: f64, z: f64, r: UnitQuaternion<f64>| Isometry3::from_parts(Vector3::new(x, y, z).into(), r);
    world
        .add_box("crate", [0.4, 0.3, 0.5], &at(3.0, 0.5, 0.5, yaw(0.3)), false)
        .unwrap();
    world
        .add_box("wall", [0.1, 4.0, 1.2], &at(6.0, 0.0, 1.2, yaw(0.0)), false)
        .unwrap();
    world
        .add_box(
            "tilted",
            [0.3, 0.3, 0.3],
            &at(2.5, -1.0, 1.4, UnitQuaternion::from_euler_angles(0.4, 0.7, 0.2)),
            false,
        )
        .unwrap();
    world
        .add_box("low", [1.0, 0.2, 0.1], &at(2.0, -0.2, 0.1, yaw(-0.6)), false)
        .unwrap();
    world
}

/// Share of pixels whose depth agrees within `tol` (m), and share whose instance id agrees.
fn agreement(a: &Frame, b: &Frame, tol: f32) -> (f64, f64) {
    let n = a.depth.len();
    assert_eq!(n, b.depth.len());
    let depth = (0..n).filter(|&i| (a.depth[i] - b.depth[i]).abs() <= tol).count();
    let ids = (0..n).filter(|&i| a.ins_seg[i] == b.ins_seg[i]).count();
    (depth as f64 / n as f64, ids as f64 / n as f64)
}

#[test]
fn boxes_read_the_same_depth_points_normals_and_ids_as_the_ray_caster() {
    let world = boxes();
    for (eye, at) in [
        ([0.0, 0.0, 1.0], [5.0, 0.0, 0.8]),
        ([0.5, 2.0, 2.0], [3.0, -0.5, 0.3]),
        ([4.5, -2.5, 0.4], [2.0, 0.5, 0.6]),
    ] {
        let mut ray = camera(&world, Backend::Raycast, look(eye, at), W, H);
        let mut raster = camera(&world, Backend::Raster, look(eye, at), W, H);
        assert_eq!(raster.backend(), Backend::Raster);
        let a = ray.render(&world, geometric()).unwrap().clone();
        let b = raster.render(&world, geometric()).unwrap();
        let (depth, ids) = agreement(&a, b, 1e-3);
        assert!(depth >= 0.995 && ids >= 0.995, "from {eye:?}: depth {depth}, ids {ids}");
        assert!(b.depth.iter().filter(|&&z| z > 0.0).count() > (W * H / 2) as usize);
        for i in 0..a.depth.len() {
            if a.depth[i] > 0.0 && (a.depth[i] - b.depth[i]).abs() <= 1e-3 && a.ins_seg[i] == b.ins_seg[i] {
                let (p, q) = (Vector3::from(a.pc[i]), Vector3::from(b.pc[i]));
                assert!((p - q).norm() < 2e-3, "pixel {i}: {p:?} vs {q:?}");
                assert_eq!(a.seg[i], b.seg[i]);
                let (m, n) = (Vector3::from(a.normal[i]), Vector3::from(b.normal[i]));
                assert!((m - n).norm() < 1e-3, "pixel {i}: {m:?} vs {n:?}");
            }
        }
    }
}

#[test]
fn a_generated_home_reads_the_same_depth_as_the_ray_caster() {
    let home = generate(&GenerateOptions {
        seed: 2,
        rooms: 2,
        robot: Some("turtlebot".into()),
        small_objects: true,
    })
    .unwrap();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&home).unwrap();
    let robot = loaded.robot.unwrap();
    let base = world.base_pose(robot).unwrap().translation.vector;
    let mut total = 0.0;
    for yaw in [0.0f64, 1.6, 3.2, 4.8] {
        let eye = [base.x, base.y, 0.6];
        let at = [base.x + yaw.cos(), base.y + yaw.sin(), 0.45];
        let mut ray = camera(&world, Backend::Raycast, look(eye, at), 128, 128);
        let mut raster = camera(&world, Backend::Raster, look(eye, at), 128, 128);
        let set = ModalitySet::EMPTY.with(Modality::Depth).with(Modality::InsSeg);
        let a = ray.render(&world, set).unwrap().clone();
        let b = raster.render(&world, set).unwrap();
        // Round shapes are 16-sided polygons in the rasteriser: 2 cm of slack.
        let (depth, ids) = agreement(&a, b, 0.02);
        assert!(depth >= 0.97 && ids >= 0.97, "yaw {yaw}: depth {depth}, ids {ids}");
        total += b.depth.iter().filter(|&&z| z > 0.0).count() as f64;
    }
    assert!(total > 4.0 * 128.0 * 128.0 * 0.3, "the camera sees little of the home");
}

#[test]
fn moved_bodies_and_a_moved_camera_leave_nothing_stale() {
    let mut world = boxes();
    let mover = world
        .add_box("mover", [0.3; 3], &Isometry3::translation(3.0, -0.8, 0.3), true)
        .unwrap();
    let mount = look([0.0, 0.0, 1.0], [5.0, 0.0, 0.8]);
    let mut cam = camera(&world, Backend::Raster, mount.clone(), W, H);
    let set = ModalitySet::EMPTY.with(Modality::Depth).with(Modality::InsSeg);
    let before = cam.render(&world, set).unwrap().clone();
    world
        .set_body_pose(mover, &Isometry3::translation(1.5, 0.8, 0.3))
        .unwrap();
    let after = cam.render(&world, set).unwrap().clone();
    assert_ne!(before.depth, after.depth);
    // The same as a camera built on the moved world.
    let mut fresh = camera(&world, Backend::Raster, mount, W, H);
    assert_eq!(fresh.render(&world, set).unwrap().depth, after.depth);
    // And the same as the ray caster there.
    let mut ray = camera(&world, Backend::Raycast, look([0.0, 0.0, 1.0], [5.0, 0.0, 0.8]), W, H);
    let r = ray.render(&world, set).unwrap().clone();
    let (depth, _) = agreement(&r, &after, 1e-3);
    assert!(depth >= 0.995, "{depth}");
    // A new camera pose: the same as a camera built there.
    let pose = Isometry3::from_parts(
        Vector3::new(0.5, 1.0, 1.5).into(),
        cam.pose(&world).unwrap().rotation * UnitQuaternion::from_euler_angles(0.1, -0.3, 0.0),
    );
    let moved = cam.render_from(&world, &pose, set).unwrap().clone();
    let mut there = camera(&world, Backend::Raster, Mount::Free(pose), W, H);
    assert_eq!(there.render(&world, set).unwrap().depth, moved.depth);
    assert_ne!(moved.depth, after.depth);
}

#[test]
fn the_inside_of_a_closed_box_is_not_seen() {
    let mut world = World::new(WorldConfig {
        ground_plane: false,
        ..WorldConfig::default()
    })
    .unwrap();
    world
        .add_box("shell", [0.5; 3], &Isometry3::translation(0.0, 0.0, 1.0), false)
        .unwrap();
    world
        .add_box("ahead", [0.2, 2.0, 2.0], &Isometry3::translation(3.0, 0.0, 1.0), false)
        .unwrap();
    let mount = look([0.0, 0.0, 1.0], [3.0, 0.0, 1.0]);
    for backend in [Backend::Raycast, Backend::Raster] {
        let mut cam = camera(&world, backend, mount.clone(), W, H);
        let f = cam.render(&world, ModalitySet::EMPTY.with(Modality::Depth)).unwrap();
        let c = f.depth[f.index(W / 2, H / 2)];
        assert!((c - 2.8).abs() < 1e-3, "{backend:?}: {c}");
    }
}

#[test]
fn colour_and_flows_are_typed_errors_and_bad_poses_are_refused() {
    let world = boxes();
    let mut cam = camera(&world, Backend::Raster, look([0.0, 0.0, 1.0], [5.0, 0.0, 0.8]), W, H);
    for m in [Modality::Rgb, Modality::OpticalFlow, Modality::SceneFlow] {
        let err = cam
            .render(&world, ModalitySet::EMPTY.with(Modality::Depth).with(m))
            .unwrap_err();
        assert!(
            matches!(err, SensorError::Unsupported { backend: "raster", modality } if modality == m.name()),
            "{err}"
        );
    }
    let bad = Isometry3::translation(f64::NAN, 0.0, 0.0);
    assert!(matches!(
        cam.render_from(&world, &bad, ModalitySet::EMPTY.with(Modality::Depth)),
        Err(SensorError::InvalidParameter { .. })
    ));
    assert_eq!("raster".parse::<Backend>().unwrap(), Backend::Raster);
    assert!(
        cam.set_material(10_000, hearth_sim::sensors::PbrMaterial::from_urdf(None, None))
            .is_err()
    );
}
