//! LiDARs and the local occupancy grid: ranges against known geometry, no-return rays,
//! seeded noise, multi-beam floor hits, grid cells, typed errors, and a Fetch in a home.

use hearth_sim::scene::{GenerateOptions, generate};
use hearth_sim::sensors::{
    CulledRays, FREE, IgnoredHits, Lidar, LidarNoise, LidarSpec, NO_ITEM, OCCUPIED, OccupancyGrid, OccupancyGridSpec,
    RayScene, Scan, SensorError, UNKNOWN, VisualScene, lidar_pose, lidar_pose_in_base, model_items,
};
use hearth_sim::world::{World, WorldConfig};
use nalgebra::{Isometry3, Vector3};

/// A world with a 0.1 m thick wall whose near face is `near` m ahead of the origin along x.
fn wall_world(near: f64) -> (World, VisualScene, RayScene) {
    let mut world = World::new(WorldConfig::default()).unwrap();
    world
        .add_box(
            "wall",
            [0.05, 20.0, 2.0],
            &Isometry3::translation(near + 0.05, 0.0, 2.0),
            false,
        )
        .unwrap();
    let visuals = VisualScene::from_world(&world);
    let mut rays = RayScene::new(&visuals);
    rays.update(&visuals, &world);
    (world, visuals, rays)
}

/// A planar scanner with an odd ray count, so ray `rays / 2` points straight ahead.
fn odd_planar(rays: usize, max: f64) -> LidarSpec {
    LidarSpec::planar(rays, 180f64.to_radians(), 0.05, max).unwrap()
}

#[test]
fn a_ray_at_a_wall_returns_the_wall_distance() {
    let (_w, _v, rays) = wall_world(1.95);
    let spec = odd_planar(181, 10.0);
    let mut lidar = Lidar::new(spec.clone(), LidarNoise::NONE, 1).unwrap();
    let mut scan = Scan::default();
    let pose = Isometry3::translation(0.0, 0.0, 0.5);
    lidar.scan(&rays, &pose, &mut scan);
    assert_eq!(scan.len(), 181);
    let centre = scan.ranges[90];
    // Wall centre 2 m ahead, half thickness 5 cm.
    assert!((centre - 1.95).abs() < 1e-3, "centre ray read {centre}");
    assert!(scan.hit[90] && scan.items[90] != NO_ITEM);
    // Off-centre rays read the slant distance to the plane.
    for i in [60, 75, 100, 120] {
        let az = spec.azimuth(i);
        let expected = 1.95 / az.cos();
        assert!(
            (scan.ranges[i] as f64 - expected).abs() < 1e-3,
            "ray {i}: {} vs {expected}",
            scan.ranges[i]
        );
    }
    // Points in the sensor frame lie on the plane x = 1.95; in the world frame as well.
    for p in scan.points_sensor() {
        assert!((p.x - 1.95).abs() < 1e-3);
    }
    for p in scan.points_world() {
        assert!((p.x - 1.95).abs() < 1e-3 && (p.z - 0.5).abs() < 1e-4);
    }
}

#[test]
fn a_rotated_sensor_sees_the_wall_behind_its_back() {
    let (_w, _v, rays) = wall_world(1.95);
    let mut lidar = Lidar::new(odd_planar(181, 10.0), LidarNoise::NONE, 1).unwrap();
    let mut scan = Scan::default();
    // Facing −x, 1 m back: the wall is now 2.95 m behind, out of the 180° view.
    let pose = Isometry3::new(
        Vector3::new(-1.0, 0.0, 0.5),
        Vector3::new(0.0, 0.0, std::f64::consts::PI),
    );
    lidar.scan(&rays, &pose, &mut scan);
    assert_eq!(scan.hit_count(), 0);
    // Turned left by 90° instead: the rightmost ray (azimuth −90°) faces the wall.
    let pose = Isometry3::new(
        Vector3::new(-1.0, 0.0, 0.5),
        Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
    );
    lidar.scan(&rays, &pose, &mut scan);
    assert!((scan.ranges[0] - 2.95).abs() < 1e-3, "{}", scan.ranges[0]);
    assert!(!scan.hit[180]);
}

#[test]
fn rays_beyond_max_range_read_max_range_and_no_hit() {
    let (_w, _v, rays) = wall_world(6.0);
    let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 1).unwrap();
    let mut scan = Scan::default();
    lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    assert_eq!(scan.len(), 228);
    assert_eq!(scan.hit_count(), 0);
    assert!(scan.ranges.iter().all(|&r| r == 5.6));
    assert!(scan.items.iter().all(|&i| i == NO_ITEM));
    assert!(scan.normalized().iter().all(|&v| v == 1.0));
    assert!(scan.points_sensor().is_empty());
    // Closer than the minimum range: no return either.
    let (_w, _v, rays) = wall_world(0.3);
    let spec = LidarSpec::planar(11, 0.2, 0.5, 5.0).unwrap();
    let mut lidar = Lidar::new(spec, LidarNoise::NONE, 1).unwrap();
    lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, 0.5), &mut scan);
    assert_eq!(scan.hit_count(), 0);
    assert!(scan.ranges.iter().all(|&r| r == 5.0));
}

#[test]
fn dropout_rate_matches_its_probability() {
    let (_w, _v, rays) = wall_world(1.95);
    let spec = LidarSpec::planar(1001, 120f64.to_radians(), 0.05, 10.0).unwrap();
    let p = 0.3;
    let noise = LidarNoise {
        dropout: p,
        gaussian_std: 0.0,
    };
    let mut lidar = Lidar::new(spec, noise, 42).unwrap();
    let mut scan = Scan::default();
    let pose = Isometry3::translation(0.0, 0.0, 0.5);
    let (mut dropped, mut total) = (0usize, 0usize);
    for _ in 0..20 {
        lidar.scan(&rays, &pose, &mut scan);
        dropped += scan.hit.iter().filter(|&&h| !h).count();
        total += scan.len();
        // Dropped rays read max range; the others are untouched.
        for (r, h) in scan.ranges.iter().zip(&scan.hit) {
            if *h {
                assert!(*r < 4.0);
            } else {
                assert_eq!(*r, 10.0);
            }
        }
    }
    let rate = dropped as f64 / total as f64;
    let sigma = (p * (1.0 - p) / total as f64).sqrt();
    assert!(
        (rate - p).abs() < 3.0 * sigma,
        "dropout rate {rate} vs {p} ± {}",
        3.0 * sigma
    );
}

#[test]
fn the_same_seed_reproduces_scans_and_another_seed_does_not() {
    let (_w, _v, rays) = wall_world(1.95);
    // Enough rays for several parallel chunks.
    let spec = LidarSpec::multi_beam(720, 120f64.to_radians(), 0.05, 10.0, vec![-0.1, 0.0, 0.1]).unwrap();
    let noise = LidarNoise {
        dropout: 0.2,
        gaussian_std: 0.02,
    };
    let pose = Isometry3::translation(0.0, 0.0, 0.5);
    let take = |seed: u64| {
        let mut lidar = Lidar::new(spec.clone(), noise, seed).unwrap();
        let mut scans = Vec::new();
        for _ in 0..3 {
            let mut s = Scan::default();
            lidar.scan(&rays, &pose, &mut s);
            scans.push((s.ranges.iter().map(|r| r.to_bits()).collect::<Vec<_>>(), s.hit.clone()));
        }
        scans
    };
    let a = take(7);
    let b = take(7);
    assert_eq!(a, b, "same seed, same scans bit for bit");
    assert_ne!(a[0], a[1], "successive scans draw fresh noise");
    let c = take(8);
    assert_ne!(a[0].1, c[0].1, "another seed drops other rays");
    assert_ne!(a[0].0, c[0].0, "another seed gives other ranges");
    // Reseeding repeats the stream; so does a single-threaded pool.
    let mut lidar = Lidar::new(spec.clone(), noise, 99).unwrap();
    let mut s = Scan::default();
    lidar.scan(&rays, &pose, &mut s);
    let first = s.ranges.clone();
    lidar.reseed(99);
    lidar.scan(&rays, &pose, &mut s);
    assert_eq!(first, s.ranges);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    lidar.reseed(99);
    pool.install(|| lidar.scan(&rays, &pose, &mut s));
    assert_eq!(first, s.ranges);
}

#[test]
fn gaussian_noise_has_the_configured_std() {
    let (_w, _v, rays) = wall_world(1.95);
    let spec = odd_planar(181, 10.0);
    let std = 0.02;
    let mut clean = Lidar::new(spec.clone(), LidarNoise::NONE, 0).unwrap();
    let mut noisy = Lidar::new(
        spec,
        LidarNoise {
            dropout: 0.0,
            gaussian_std: std,
        },
        5,
    )
    .unwrap();
    let pose = Isometry3::translation(0.0, 0.0, 0.5);
    let (mut truth, mut scan) = (Scan::default(), Scan::default());
    clean.scan(&rays, &pose, &mut truth);
    let mut errors = Vec::new();
    for _ in 0..40 {
        noisy.scan(&rays, &pose, &mut scan);
        for i in 0..scan.len() {
            if truth.hit[i] {
                assert!(scan.hit[i]);
                errors.push(scan.ranges[i] as f64 - truth.ranges[i] as f64);
            }
        }
    }
    let n = errors.len() as f64;
    assert!(n > 3000.0);
    let mean = errors.iter().sum::<f64>() / n;
    let sd = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 3.0 * std / n.sqrt() + 1e-4, "mean error {mean}");
    // The sample std of n normals has a relative standard error of about 1/sqrt(2n).
    assert!((sd - std).abs() < 4.0 * std / (2.0 * n).sqrt(), "std {sd} vs {std}");
}

#[test]
fn vlp16_beams_hit_the_floor_at_the_expected_distance() {
    let world = World::new(WorldConfig::default()).unwrap();
    let visuals = VisualScene::from_world(&world);
    let mut rays = RayScene::new(&visuals);
    rays.update(&visuals, &world);
    // The ground's top surface is z = 0.
    let probe = rays
        .cast(
            parry3d::math::Vector::new(0.0, 0.0, 1.0),
            parry3d::math::Vector::new(0.0, 0.0, -1.0),
            10.0,
        )
        .expect("the default world has a ground");
    let ground = 1.0 - probe.toi as f64;
    let spec = LidarSpec::velodyne_vlp16(1.0).unwrap();
    assert_eq!(spec.rays(), 5760);
    let h = 1.0;
    let mut lidar = Lidar::new(spec.clone(), LidarNoise::NONE, 0).unwrap();
    let mut scan = Scan::default();
    lidar.scan(&rays, &Isometry3::translation(0.0, 0.0, ground + h), &mut scan);
    assert_eq!((scan.beams, scan.horizontal_rays), (16, 360));
    for beam in 0..16 {
        let el = spec.elevations[beam];
        for az in [0, 90, 180, 270, 359] {
            let r = scan.range(beam, az).unwrap();
            if el < 0.0 {
                let expected = h / (-el).sin();
                assert!((r as f64 - expected).abs() < 2e-3, "beam {beam}: {r} vs {expected}");
            } else {
                // Level and rising beams see nothing within 100 m in an empty world.
                assert_eq!(r, 100.0);
            }
        }
    }
    // The −15° beam: h / sin 15°.
    let r = scan.range(0, 0).unwrap() as f64;
    assert!((r - h / 15f64.to_radians().sin()).abs() < 2e-3);
}

#[test]
fn the_occupancy_grid_marks_wall_free_unknown_and_footprint() {
    // The wall face at x = 1.975 lies mid-cell (cells of 5 cm span x in (1.95, 2.0]).
    let (_w, _v, rays) = wall_world(1.975);
    let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 1).unwrap();
    let mut scan = Scan::default();
    // Base at the world origin; the laser 0.2 m ahead of it, 0.3 m up.
    let sensor_in_base = Isometry3::translation(0.2, 0.0, 0.3);
    lidar.scan(&rays, &sensor_in_base, &mut scan);
    let spec = OccupancyGridSpec {
        size: 128,
        resolution: 0.05,
        footprint_radius: 0.3,
        no_return_is_free: true,
    };
    let mut grid = OccupancyGrid::new(spec).unwrap();
    grid.update(&scan, &sensor_in_base).unwrap();
    // The cells holding the wall face are occupied across the view.
    for y in [-1.5, -0.7, 0.0, 0.4, 1.2] {
        assert_eq!(grid.at(1.97, y), Some(OCCUPIED), "wall cell at y {y}");
        assert_eq!(grid.at(1.0, y), Some(FREE), "between robot and wall at y {y}");
        assert_eq!(grid.at(2.6, y), Some(UNKNOWN), "behind the wall at y {y}");
    }
    // Behind the robot, outside the 240° view: unknown except for the footprint.
    assert_eq!(grid.at(-1.5, 0.0), Some(UNKNOWN));
    for (x, y) in [(0.0, 0.0), (-0.25, 0.0), (0.0, 0.25), (-0.15, -0.15)] {
        assert_eq!(grid.at(x, y), Some(FREE), "footprint at ({x}, {y})");
    }
    // Layout: forward is up (row 0), left is column 0.
    let (r, c) = grid.cell_of(1.97, 0.5).unwrap();
    assert!(r < 64 && c < 64);
    let (x, y) = grid.cell_center(r, c);
    assert!((x - 1.97).abs() <= 0.025 + 1e-9 && (y - 0.5).abs() <= 0.025 + 1e-9);
    assert!(grid.count(OCCUPIED) > 40);
    let mut f = Vec::new();
    grid.to_f32_into(&mut f);
    assert_eq!(f.len(), 128 * 128);
    assert!(f.iter().all(|&v| v == 0.0 || v == 0.5 || v == 1.0));
    // Without free no-return rays, the sides beyond the wall's reach stay unknown.
    let (_w, _v, rays) = wall_world(1.0);
    let narrow = LidarSpec::planar(361, std::f64::consts::TAU, 0.05, 5.6).unwrap();
    let mut lidar = Lidar::new(narrow, LidarNoise::NONE, 1).unwrap();
    lidar.scan(&rays, &sensor_in_base, &mut scan);
    let mut grid = OccupancyGrid::new(OccupancyGridSpec {
        no_return_is_free: false,
        ..spec
    })
    .unwrap();
    grid.update(&scan, &sensor_in_base).unwrap();
    assert_eq!(grid.at(-1.5, 0.0), Some(UNKNOWN));
    assert_eq!(grid.at(0.6, 0.0), Some(FREE));
}

#[test]
fn a_flipped_sensor_still_maps_the_wall_in_front() {
    // A laser mounted upside down (rolled by π, as the Fetch's): its y axis points right.
    let (_w, _v, rays) = wall_world(1.45);
    let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 1).unwrap();
    let mut scan = Scan::default();
    let sensor_in_base = Isometry3::new(
        Vector3::new(0.2, 0.0, 0.3),
        Vector3::new(std::f64::consts::PI, 0.0, 0.0),
    );
    lidar.scan(&rays, &sensor_in_base, &mut scan);
    let mut grid = OccupancyGrid::new(OccupancyGridSpec::default()).unwrap();
    grid.update(&scan, &sensor_in_base).unwrap();
    for y in [-1.0, 0.0, 1.0] {
        assert_eq!(grid.at(1.47, y), Some(OCCUPIED));
        assert_eq!(grid.at(0.8, y), Some(FREE));
    }
}

#[test]
fn bad_specs_give_typed_errors() {
    let bad = |r: Result<LidarSpec, SensorError>, name: &str| match r {
        Err(SensorError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
        other => panic!("expected InvalidParameter({name}), got {other:?}"),
    };
    bad(LidarSpec::planar(0, 1.0, 0.1, 5.0), "horizontal_rays");
    bad(LidarSpec::planar(2_000_000, 1.0, 0.1, 5.0), "horizontal_rays");
    bad(LidarSpec::planar(100, f64::NAN, 0.1, 5.0), "horizontal_fov");
    bad(LidarSpec::planar(100, 7.0, 0.1, 5.0), "horizontal_fov");
    bad(LidarSpec::planar(100, 1.0, 5.0, 5.0), "min_range");
    bad(LidarSpec::planar(100, 1.0, 6.0, 5.0), "min_range");
    bad(LidarSpec::planar(100, 1.0, -1.0, 5.0), "min_range");
    bad(LidarSpec::planar(100, 1.0, 0.1, f64::INFINITY), "max_range");
    bad(LidarSpec::multi_beam(100, 1.0, 0.1, 5.0, vec![]), "beams");
    bad(
        LidarSpec::multi_beam(100, 1.0, 0.1, 5.0, vec![0.0, f64::NAN]),
        "elevation",
    );
    bad(LidarSpec::multi_beam(100_000, 1.0, 0.1, 5.0, vec![0.0; 16]), "rays");
    bad(LidarSpec::velodyne_vlp16(0.0), "horizontal_resolution_deg");
    bad(LidarSpec::velodyne_vlp16(f64::NAN), "horizontal_resolution_deg");
    let mut spec = LidarSpec::sick_tim571();
    spec.horizontal_rays = 0;
    assert!(matches!(
        Lidar::new(spec, LidarNoise::NONE, 0),
        Err(SensorError::InvalidParameter { .. })
    ));
    for noise in [
        LidarNoise {
            dropout: -0.1,
            gaussian_std: 0.0,
        },
        LidarNoise {
            dropout: f64::NAN,
            gaussian_std: 0.0,
        },
        LidarNoise {
            dropout: 0.0,
            gaussian_std: -1.0,
        },
    ] {
        assert!(matches!(
            Lidar::new(LidarSpec::sick_tim571(), noise, 0),
            Err(SensorError::InvalidParameter { .. })
        ));
    }
    for spec in [
        OccupancyGridSpec {
            size: 0,
            ..Default::default()
        },
        OccupancyGridSpec {
            resolution: 0.0,
            ..Default::default()
        },
        OccupancyGridSpec {
            footprint_radius: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(matches!(
            OccupancyGrid::new(spec),
            Err(SensorError::InvalidParameter { .. })
        ));
    }
    // A multi-beam scan does not make a grid.
    let (_w, _v, rays) = wall_world(1.95);
    let mut lidar = Lidar::new(LidarSpec::velodyne_vlp16(10.0).unwrap(), LidarNoise::NONE, 0).unwrap();
    let mut scan = Scan::default();
    lidar.scan(&rays, &Isometry3::identity(), &mut scan);
    let mut grid = OccupancyGrid::new(OccupancyGridSpec::default()).unwrap();
    assert!(matches!(
        grid.update(&scan, &Isometry3::identity()),
        Err(SensorError::InvalidParameter { name: "beams", .. })
    ));
    // A non-finite pose scans nothing instead of panicking.
    let mut lidar = Lidar::new(LidarSpec::sick_tim571(), LidarNoise::NONE, 0).unwrap();
    lidar.scan(&rays, &Isometry3::translation(f64::NAN, 0.0, 0.0), &mut scan);
    assert_eq!(scan.hit_count(), 0);
}

/// The generated home of seed 1 in a world, with its Fetch.
fn fetch_home() -> (World, hearth_sim::world::LoadedScene, hearth_sim::world::ModelHandle) {
    let scene = generate(&GenerateOptions {
        seed: 1,
        ..Default::default()
    })
    .unwrap();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = loaded.robot.expect("generated homes place a Fetch");
    (world, loaded, fetch)
}

#[test]
fn a_fetch_in_a_generated_home_scans_from_its_laser_link() {
    let (world, loaded, fetch) = fetch_home();
    assert_eq!(world.model(fetch).unwrap().name(), "fetch");
    let visuals = VisualScene::from_world(&world);
    let mut rays = RayScene::new(&visuals);
    rays.update(&visuals, &world);

    let pose = lidar_pose(&world, fetch, None).unwrap();
    let base = world.base_pose(fetch).unwrap();
    let in_base = lidar_pose_in_base(&world, fetch, None).unwrap();
    assert!(((base * in_base).translation.vector - pose.translation.vector).norm() < 1e-9);
    // The Fetch's laser sits about 0.29 m above the base, 0.235 m ahead.
    assert!((in_base.translation.vector - Vector3::new(0.235, 0.0, 0.2878)).norm() < 0.02);

    let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 3).unwrap();
    let own = model_items(&visuals, &world, fetch).unwrap();
    // Seen, the Fetch's own base blocks part of the view.
    let mut scan = Scan::default();
    lidar.scan(&rays, &pose, &mut scan);
    let self_hits = scan.items.iter().filter(|i| own.contains(i)).count();
    let seen_hits = scan.hit_count();
    assert!(self_hits > 0);
    // Passed through, no ray reports it, and more rays see the home.
    lidar.ignore_items(own.iter().copied(), IgnoredHits::PassThrough);
    assert!(lidar.ignored_count() > 0);
    lidar.scan(&rays, &pose, &mut scan);
    assert!(scan.ranges.iter().all(|r| r.is_finite() && *r > 0.0 && *r <= 5.6));
    let hits = scan.hit_count();
    assert!(
        hits * 10 >= scan.len() * 6,
        "only {hits} of {} rays returned",
        scan.len()
    );
    // No ray reports the robot itself.
    assert!(scan.items.iter().all(|i| !own.contains(i)));
    // As iGibson: a ray that meets the robot gives no return.
    let mut igibson = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 3).unwrap();
    igibson.ignore_items(own.iter().copied(), IgnoredHits::NoReturn);
    let mut s2 = Scan::default();
    igibson.scan(&rays, &pose, &mut s2);
    assert_eq!(s2.hit_count(), seen_hits - self_hits);
    assert!(hits > seen_hits - self_hits);
    // Points land inside the home, at the laser's height.
    for p in scan.points_world() {
        assert!((p.z - pose.translation.z).abs() < 0.05);
    }
    // The grid around it has free space, obstacles and unknown cells.
    let mut grid = OccupancyGrid::new(OccupancyGridSpec::default()).unwrap();
    grid.update(&scan, &in_base).unwrap();
    assert!(grid.count(FREE) > 500 && grid.count(OCCUPIED) > 20 && grid.count(UNKNOWN) > 0);

    // Typed errors for bad links.
    assert!(matches!(
        lidar_pose(&world, fetch, Some("no_such_link")),
        Err(SensorError::NoSuchLink { .. })
    ));
    let door = loaded.objects.values().next().copied().unwrap();
    assert!(matches!(
        lidar_pose(&world, door, None),
        Err(SensorError::NoDefaultMount { .. })
    ));
}

/// A culled scan reads what the full scan reads at step `k`: the same hits and items, ranges
/// within 0.1 mm.
fn assert_same_scan(k: usize, a: &Scan, b: &Scan) {
    assert_eq!(a.hit, b.hit, "step {k}");
    assert_eq!(a.items, b.items, "step {k}");
    for (x, y) in a.ranges.iter().zip(&b.ranges) {
        assert!((x - y).abs() < 1e-4, "step {k}: {x} vs {y}");
    }
}

#[test]
fn culled_scans_match_full_scans_as_the_robot_moves() {
    let (world, _, fetch) = fetch_home();
    let visuals = VisualScene::from_world(&world);
    let mut rays = RayScene::new(&visuals);
    let own = model_items(&visuals, &world, fetch).unwrap();
    for (spec, mode) in [
        (LidarSpec::hokuyo_urg_04lx(), IgnoredHits::PassThrough),
        (LidarSpec::hokuyo_urg_04lx(), IgnoredHits::NoReturn),
        (LidarSpec::velodyne_vlp16(4.0).unwrap(), IgnoredHits::PassThrough),
    ] {
        let mut lidar = Lidar::new(spec, LidarNoise::NONE, 0).unwrap();
        lidar.ignore_items(own.iter().copied(), mode);
        let mut culled = CulledRays::default();
        let (mut a, mut b) = (Scan::default(), Scan::default());
        let start = lidar_pose(&world, fetch, None).unwrap();
        // The sensor glides along x, a little at a time, then jumps.
        for k in 0..12 {
            let step = if k < 10 { 0.03 * k as f64 } else { 0.8 * (k - 9) as f64 };
            let pose = Isometry3::translation(step, 0.0, 0.0) * start;
            rays.update(&visuals, &world);
            lidar.scan(&rays, &pose, &mut a);
            lidar.scan_culled(&mut culled, &visuals, &world, &pose, &mut b);
            assert_same_scan(k, &a, &b);
        }
        assert!(culled.len() < visuals.items.len());
        // Small moves reuse the copy; the jumps rebuild it.
        assert!(
            culled.rebuilds() >= 2 && culled.rebuilds() <= 6,
            "{} rebuilds",
            culled.rebuilds()
        );
    }
}

#[test]
fn turning_in_place_keeps_the_culled_copy_and_matches_full_scans() {
    let (world, _, fetch) = fetch_home();
    let visuals = VisualScene::from_world(&world);
    let mut rays = RayScene::new(&visuals);
    rays.update(&visuals, &world);
    let own = model_items(&visuals, &world, fetch).unwrap();
    let mut lidar = Lidar::new(LidarSpec::hokuyo_urg_04lx(), LidarNoise::NONE, 0).unwrap();
    lidar.ignore_items(own.iter().copied(), IgnoredHits::PassThrough);
    let mut culled = CulledRays::default();
    let (mut a, mut b) = (Scan::default(), Scan::default());
    let start = lidar_pose(&world, fetch, None).unwrap();
    // A full turn about the scanner's own z axis, 0.3 rad at a time: the scan plane stays.
    for k in 0..21 {
        let pose = start * nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3 * k as f64);
        lidar.scan(&rays, &pose, &mut a);
        lidar.scan_culled(&mut culled, &visuals, &world, &pose, &mut b);
        assert_same_scan(k, &a, &b);
    }
    assert_eq!(culled.rebuilds(), 1);
    // Tilting the plane does rebuild it.
    let tilted = start * nalgebra::UnitQuaternion::from_euler_angles(0.05, 0.0, 0.0);
    lidar.scan_culled(&mut culled, &visuals, &world, &tilted, &mut b);
    assert_eq!(culled.rebuilds(), 2);
}

#[test]
fn culled_scans_follow_bodies_that_move_into_reach() {
    let mut world = World::new(WorldConfig::default()).unwrap();
    let far = world
        .add_box("crate", [0.2, 0.2, 0.5], &Isometry3::translation(30.0, 0.0, 0.5), false)
        .unwrap();
    world
        .add_box("wall", [0.05, 5.0, 1.0], &Isometry3::translation(4.0, 0.0, 1.0), false)
        .unwrap();
    let visuals = VisualScene::from_world(&world);
    let mut rays = RayScene::new(&visuals);
    let spec = odd_planar(181, 10.0);
    let mut lidar = Lidar::new(spec, LidarNoise::NONE, 0).unwrap();
    let mut culled = CulledRays::default();
    let pose = Isometry3::translation(0.0, 0.0, 0.3);
    let (mut a, mut b) = (Scan::default(), Scan::default());
    for (k, x) in [30.0, 30.0, 2.0, 2.0, 2.1, 1.0].into_iter().enumerate() {
        world.set_body_pose(far, &Isometry3::translation(x, 0.0, 0.5)).unwrap();
        rays.update(&visuals, &world);
        lidar.scan(&rays, &pose, &mut a);
        lidar.scan_culled(&mut culled, &visuals, &world, &pose, &mut b);
        assert_eq!(a.items, b.items, "step {k}");
        assert_eq!(a.ranges, b.ranges, "step {k}");
        let expected = if x < 4.0 { x - 0.2 } else { 3.95 };
        assert!(
            (b.ranges[90] as f64 - expected).abs() < 1e-3,
            "step {k}: {}",
            b.ranges[90]
        );
    }
}
