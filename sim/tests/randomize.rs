//! Domain randomisation: each kind changes what it should and nothing else, the same seed
//! gives the same result bit for bit, another seed another result, and bad configurations are
//! refused naming the key.

use hearth_sim::assets::{Asset, AssetSpec, Category, Material};
use hearth_sim::randomize::{
    ObjectRandomization, PhysicsRandomization, RandomizationConfig, RandomizeError, Randomizer, Stream,
    VisualRandomization, VisualRandomizationConfig, add_depth_noise, randomize_objects, randomize_physics,
};
use hearth_sim::scene::{GenerateOptions, SceneFile, SceneObject, generate};
use hearth_sim::sensors::{
    Backend, Camera, CameraConfig, Modality, ModalitySet, Mount, Preset, SemanticClass, VisualScene,
};
use hearth_sim::world::{LoadedScene, World, WorldConfig};
use nalgebra::{Isometry3, Point3, Vector3};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

/// A small home with furniture and small objects on surfaces (so supports get swapped).
fn home() -> SceneFile {
    generate(&GenerateOptions {
        seed: 3,
        rooms: 2,
        robot: Some("fetch".into()),
        small_objects: true,
    })
    .unwrap()
}

/// A hand-made room: a cabinet with drawers, a table with a mug on it, a chair.
fn kitchenette() -> SceneFile {
    let mut s = SceneFile::empty("kitchenette");
    let mut cabinet = SceneObject::new("cabinet", "bottom_cabinet", 1, [0.0, 2.0, 0.0]);
    cabinet.fixed = true;
    s.objects.push(cabinet);
    s.objects.push(SceneObject::new("table", "table", 0, [0.0, 0.0, 0.0]));
    let top = Asset::build(Category::Table, 0, 1.0).unwrap().surfaces[0].z;
    let mut mug = SceneObject::new("mug", "mug", 0, [0.1, 0.0, top]);
    mug.on = Some("table".into());
    s.objects.push(mug);
    s.objects.push(SceneObject::new("chair", "chair", 0, [1.5, 0.0, 0.0]));
    s
}

fn asset_of(o: &SceneObject) -> Asset {
    Asset::build_spec(&AssetSpec {
        category: Category::from_name(&o.category).unwrap(),
        variant: o.variant,
        scale: o.scale,
        material: o.material,
    })
    .unwrap()
}

/// The corners of an object's box, in the world.
fn corners(o: &SceneObject, a: &Asset) -> Vec<Point3<f64>> {
    (0..8)
        .map(|k| {
            let c = Vector3::new(
                if k & 1 == 0 { a.aabb_min.x } else { a.aabb_max.x },
                if k & 2 == 0 { a.aabb_min.y } else { a.aabb_max.y },
                if k & 4 == 0 { a.aabb_min.z } else { a.aabb_max.z },
            );
            o.pose() * Point3::from(c)
        })
        .collect()
}

#[test]
fn object_swaps_keep_the_layout_and_fit_the_original_boxes() {
    let base = home();
    let mut scene = base.clone();
    let cfg = ObjectRandomization {
        enabled: true,
        ..Default::default()
    };
    let report = randomize_objects(&mut scene, &cfg, &mut rng(5)).unwrap();
    assert!(scene.validate().is_ok());

    // Same objects, categories, rooms, supports and headings; the building is untouched.
    assert_eq!(scene.objects.len(), base.objects.len());
    assert_eq!(scene.building, base.building);
    assert_eq!(scene.robot, base.robot);
    for (a, b) in base.objects.iter().zip(&scene.objects) {
        assert_eq!(
            (&a.name, &a.category, &a.room, &a.on, a.fixed),
            (&b.name, &b.category, &b.room, &b.on, b.fixed)
        );
        assert!((a.orientation.yaw() - b.orientation.yaw()).abs() < 1e-12, "{}", a.name);
    }
    let swapped = base
        .objects
        .iter()
        .zip(&scene.objects)
        .filter(|(a, b)| a.variant != b.variant)
        .count();
    assert!(
        swapped * 2 > base.objects.len(),
        "{swapped} of {} swapped",
        base.objects.len()
    );
    assert_eq!(swapped, report.swapped.len());
    assert!(
        !report.reseated.is_empty(),
        "small objects follow their swapped supports"
    );

    for (a, b) in base.objects.iter().zip(&scene.objects) {
        if a.variant == b.variant || b.on.is_some() {
            continue;
        }
        let (old, new) = (asset_of(a), asset_of(b));
        // Every corner of the new box lies in the old box (old object frame), one axis is tight,
        // and the bottom stays where it was.
        let inv = a.pose().inverse();
        let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
        for p in corners(b, &new) {
            let q = inv * p;
            lo = lo.inf(&q.coords);
            hi = hi.sup(&q.coords);
        }
        let tol = 1e-6;
        for k in 0..3 {
            assert!(
                lo[k] >= old.aabb_min[k] - tol && hi[k] <= old.aabb_max[k] + tol,
                "{} axis {k}",
                a.name
            );
        }
        assert!((lo.z - old.aabb_min.z).abs() < tol, "{} bottom moved", a.name);
        let tight = (0..3).any(|k| ((hi[k] - lo[k]) - (old.aabb_max[k] - old.aabb_min[k])).abs() < 1e-5);
        assert!(tight, "{}: the new model fills its box along one axis", a.name);
        // The box written in the scene follows the new model.
        let bb = b.bbox.expect("generated objects carry boxes");
        assert!((Vector3::from(bb.max) - new.aabb_max).norm() < 1e-12);
    }

    // Small objects on swapped supports rest on one of the new support's surfaces.
    for (i, b) in scene.objects.iter().enumerate() {
        let Some(sup) = &b.on else { continue };
        let s = scene.objects.iter().find(|o| &o.name == sup).unwrap();
        if s == &base.objects.iter().find(|o| &o.name == sup).unwrap().clone() {
            continue;
        }
        let (sa, da) = (asset_of(s), asset_of(b));
        let bottom = corners(b, &da)
            .into_iter()
            .map(|p| (s.pose().inverse() * p).z)
            .fold(f64::INFINITY, f64::min);
        assert!(
            sa.surfaces.iter().any(|f| (f.z - bottom).abs() < 1e-6),
            "object {i} `{}` floats over `{sup}` at {bottom}",
            b.name
        );
    }

    // The result loads and comes to rest without objects being thrown about.
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let before: Vec<_> = loaded.objects.values().map(|&h| world.base_pose(h).unwrap()).collect();
    world.settle(60);
    for ((name, &h), p0) in loaded.objects.iter().zip(&before) {
        let p1 = world.base_pose(h).unwrap();
        let d = (p1.translation.vector - p0.translation.vector).norm();
        assert!(d < 0.05, "`{name}` moved {d} m while settling");
    }
}

#[test]
fn object_swaps_are_reproducible_per_seed() {
    let base = home();
    let cfg = ObjectRandomization {
        enabled: true,
        ..Default::default()
    };
    let run = |seed: u64| {
        let mut s = base.clone();
        randomize_objects(&mut s, &cfg, &mut rng(seed)).unwrap();
        s.to_json_string()
    };
    assert_eq!(run(11), run(11));
    assert_ne!(run(11), run(12));

    // Probability 0 and a category filter limit what changes.
    let mut none = base.clone();
    let off = ObjectRandomization {
        probability: 0.0,
        ..cfg.clone()
    };
    assert!(
        randomize_objects(&mut none, &off, &mut rng(1))
            .unwrap()
            .swapped
            .is_empty()
    );
    assert_eq!(none, base);
    let mut chairs = base.clone();
    let only = ObjectRandomization {
        categories: vec!["chair".into()],
        ..cfg
    };
    let r = randomize_objects(&mut chairs, &only, &mut rng(1)).unwrap();
    assert!(!r.swapped.is_empty());
    assert!(r.swapped.iter().all(|s| s.category == Category::Chair));

    // An invalid scene is refused and left as it was.
    let mut bad = base.clone();
    bad.objects[0].category = "spaceship".into();
    let copy = bad.clone();
    let err = randomize_objects(&mut bad, &only, &mut rng(1)).unwrap_err();
    assert!(
        matches!(err, RandomizeError::Scene(_)) && err.to_string().contains("spaceship"),
        "{err}"
    );
    assert_eq!(bad, copy);
}

fn loaded(scene: &SceneFile) -> (World, LoadedScene) {
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(scene).unwrap();
    (world, loaded)
}

fn physics_all() -> PhysicsRandomization {
    PhysicsRandomization {
        enabled: true,
        friction: true,
        restitution: true,
        mass: true,
        joint_damping: [0.5, 2.0],
        ..Default::default()
    }
}

#[test]
fn physics_changes_properties_within_ranges_and_leaves_poses_alone() {
    let scene = kitchenette();
    let (mut world, loaded) = loaded(&scene);
    let hash0 = world.state_hash();
    let props0 = world.properties_hash();
    let cabinet = loaded.object("cabinet").unwrap();
    let mug = loaded.object("mug").unwrap();
    let mug_body = world.model_bodies(mug).unwrap()[0];
    let mug_mass0 = world.body_mass(mug_body).unwrap();
    let drawer = world.link_body(cabinet, "drawer_0").unwrap();
    let drawer_mass0 = world.body_mass(drawer).unwrap();
    let damping0 = world.joint_damping(cabinet, "drawer_0_slide").unwrap();
    let before = world.snapshot();

    let report = randomize_physics(&mut world, &loaded, &physics_all(), &mut rng(9)).unwrap();
    assert!(report.bodies >= 4 && report.joints >= 3, "{report:?}");
    assert_eq!(world.state_hash(), hash0, "poses and velocities are untouched");
    assert_ne!(world.properties_hash(), props0);

    // The mug is ceramic: friction, restitution and density from the ceramic span.
    let r = Material::Ceramic.ranges();
    let f = world.body_friction(mug_body).unwrap().unwrap();
    let e = world.body_restitution(mug_body).unwrap().unwrap();
    assert!(f >= r.friction[0] - 1e-6 && f <= r.friction[1] + 1e-6, "{f}");
    assert!(e >= r.restitution[0] - 1e-6 && e <= r.restitution[1] + 1e-6, "{e}");
    let ratio = world.body_mass(mug_body).unwrap() / mug_mass0;
    let typ = Material::Ceramic.props().density;
    assert!(
        ratio >= r.density[0] / typ - 1e-5 && ratio <= r.density[1] / typ + 1e-5,
        "{ratio}"
    );
    // Drawers are wooden and heavier or lighter within the wood span; damping within the factors.
    let wr = Material::Wood.ranges();
    let wt = Material::Wood.props().density;
    let dratio = world.body_mass(drawer).unwrap() / drawer_mass0;
    assert!(
        dratio >= wr.density[0] / wt - 1e-5 && dratio <= wr.density[1] / wt + 1e-5,
        "{dratio}"
    );
    let d = world.joint_damping(cabinet, "drawer_0_slide").unwrap();
    assert!(d >= 0.5 * damping0 - 1e-6 && d <= 2.0 * damping0 + 1e-6 && (d - damping0).abs() > 1e-9);

    // Applying the same draw again changes nothing (values come from the typical ones).
    let once = world.properties_hash();
    randomize_physics(&mut world, &loaded, &physics_all(), &mut rng(9)).unwrap();
    assert_eq!(world.properties_hash(), once);

    // Same seed on a fresh world: identical properties and, after stepping, identical states.
    let (mut other, other_loaded) = self::loaded(&scene);
    randomize_physics(&mut other, &other_loaded, &physics_all(), &mut rng(9)).unwrap();
    assert_eq!(other.properties_hash(), once);
    for _ in 0..20 {
        world.step();
        other.step();
    }
    assert_eq!(world.state_hash(), other.state_hash());
    // Another seed: other properties.
    let (mut third, third_loaded) = self::loaded(&scene);
    randomize_physics(&mut third, &third_loaded, &physics_all(), &mut rng(10)).unwrap();
    assert_ne!(third.properties_hash(), once);

    // Snapshots carry the properties: the one taken before brings the typical values back.
    let after = world.snapshot();
    world.restore(&before).unwrap();
    assert_eq!(world.properties_hash(), props0);
    assert!((world.body_mass(mug_body).unwrap() - mug_mass0).abs() < 1e-9);
    world.restore(&after).unwrap();
    assert_eq!(world.properties_hash(), other.properties_hash());
}

#[test]
fn heavier_drawers_open_slower_and_bouncier_boxes_bounce() {
    // Mass: the same push opens a drawer of twice the mass about half as far.
    let open = |scale: f64| {
        let mut world = World::new(WorldConfig::default()).unwrap();
        let cabinet = Asset::build(Category::BottomCabinet, 1, 1.0).unwrap();
        let h = world
            .spawn_model(
                &cabinet.model,
                &Isometry3::identity(),
                hearth_sim::world::SpawnOptions::fixed(),
            )
            .unwrap();
        let drawer = world.link_body(h, "drawer_0").unwrap();
        let m = world.body_mass(drawer).unwrap();
        world.set_body_mass(drawer, m * scale).unwrap();
        world.set_joint_damping(h, "drawer_0_slide", 0.0).unwrap();
        let mut tau = vec![0.0; cabinet.model.dof()];
        let v = cabinet
            .model
            .variable_names()
            .iter()
            .position(|n| n == "drawer_0_slide")
            .unwrap();
        tau[v] = 2.0;
        world.set_efforts(h, &tau).unwrap();
        for _ in 0..6 {
            world.step();
        }
        world.joint_positions(h).unwrap()[v]
    };
    let (light, heavy) = (open(1.0), open(2.0));
    assert!(light > 0.0 && heavy > 0.0, "{light} {heavy}");
    assert!((heavy / light - 0.5).abs() < 0.15, "light {light}, heavy {heavy}");

    // Restitution: a box with restitution 1 rebounds, one with 0 does not.
    let peak_after_bounce = |restitution: f64| {
        let mut world = World::new(WorldConfig::default()).unwrap();
        let ground = world.ground().unwrap();
        world.set_body_restitution(ground, restitution).unwrap();
        let b = world
            .add_box("box", [0.05; 3], &Isometry3::translation(0.0, 0.0, 0.6), true)
            .unwrap();
        world.set_body_restitution(b, restitution).unwrap();
        let mut landed = false;
        let mut peak: f64 = 0.0;
        for _ in 0..40 {
            world.step();
            let z = world.body_pose(b).unwrap().translation.z;
            if z < 0.07 {
                landed = true;
            } else if landed {
                peak = peak.max(z);
            }
        }
        peak
    };
    assert!(peak_after_bounce(1.0) > 0.2);
    assert!(peak_after_bounce(0.0) < 0.1);
}

#[test]
fn visual_randomisation_changes_materials_not_geometry() {
    let scene = kitchenette();
    let (world, _) = loaded(&scene);
    let original = VisualScene::from_world(&world);
    let cfg = VisualRandomizationConfig {
        enabled: true,
        ..Default::default()
    };
    let mut a = original.clone();
    let changed = VisualRandomization::new(4, cfg.clone()).apply_to_scene(&mut a);
    let objects = original
        .items
        .iter()
        .filter(|i| i.semantic >= SemanticClass::FIRST_CATEGORY)
        .count();
    assert!(changed * 10 >= objects * 9, "{changed} of {objects}");
    for (o, n) in original.items.iter().zip(&a.items) {
        assert_eq!(
            (o.body, o.local, o.semantic, o.instance),
            (n.body, n.local, n.semantic, n.instance)
        );
        assert_eq!(format!("{:?}", o.shape), format!("{:?}", n.shape));
        assert_eq!(o.material.class, n.material.class, "the class is kept");
        if o.semantic == SemanticClass::FLOOR {
            assert_eq!(o.material, n.material, "the building is left alone by default");
        }
        if n.material.class == Some(Material::Metal) {
            assert!(n.material.metallic >= 0.85);
        }
    }
    // The parts of one object made of one material share the new material.
    let wood: Vec<_> = a
        .items
        .iter()
        .filter(|i| a.instances[i.instance as usize - 1].name == "table" && i.material.class == Some(Material::Wood))
        .map(|i| i.material)
        .collect();
    assert!(wood.len() > 1 && wood.iter().all(|m| *m == wood[0]));
    // Same seed, same look; another seed, another.
    let mut b = original.clone();
    VisualRandomization::new(4, cfg.clone()).apply_to_scene(&mut b);
    let mut c = original.clone();
    VisualRandomization::new(5, cfg).apply_to_scene(&mut c);
    let mats = |s: &VisualScene| s.items.iter().map(|i| i.material).collect::<Vec<_>>();
    assert_eq!(mats(&a), mats(&b));
    assert_ne!(mats(&a), mats(&c));
}

#[test]
fn cameras_show_the_randomised_materials_with_unchanged_depth() {
    let scene = kitchenette();
    let (world, _) = loaded(&scene);
    let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    config.backend = Backend::Raycast;
    config.mount = Some(Mount::look_at(Point3::new(3.0, 0.5, 1.2), Point3::new(0.0, 0.5, 0.5)).unwrap());
    let mut camera = Camera::new(&world, None, config).unwrap();
    let both = ModalitySet::EMPTY.with(Modality::Rgb).with(Modality::Depth);
    let plain = camera.render(&world, both).unwrap().clone();

    let text = "[visual]\nenabled = true\nbuilding = true\n";
    let randomizer = Randomizer::new(RandomizationConfig::from_toml_str(text).unwrap(), 8).unwrap();
    let changed = randomizer.apply_camera(0, &world, &mut camera).unwrap();
    assert!(changed > 0);
    let varied = camera.render(&world, both).unwrap().clone();
    assert_eq!(plain.depth, varied.depth);
    assert_ne!(plain.rgb, varied.rgb);
    // Applying twice gives the same picture; a rebuild loses the draw until it is applied again.
    randomizer.apply_camera(0, &world, &mut camera).unwrap();
    assert_eq!(camera.render(&world, both).unwrap().rgb, varied.rgb);
    camera.rebuild(&world).unwrap();
    assert_eq!(camera.render(&world, both).unwrap().rgb, plain.rgb);
    randomizer.apply_camera(0, &world, &mut camera).unwrap();
    assert_eq!(camera.render(&world, both).unwrap().rgb, varied.rgb);
    // A randomizer with visuals off puts the world's materials back.
    let off = Randomizer::new(RandomizationConfig::default(), 8).unwrap();
    assert_eq!(off.apply_camera(0, &world, &mut camera).unwrap(), 0);
    assert_eq!(camera.render(&world, both).unwrap().rgb, plain.rgb);
}

#[test]
fn randomizer_redraws_every_k_episodes_and_perturbs_starts() {
    let text = r#"
every_k_episodes = 2
[objects]
enabled = true
[pose]
robot_xy_std = 0.15
robot_yaw_std = 0.3
camera_xyz_std = 0.01
camera_rpy_std = 0.02
[noise]
depth_std = 0.002
depth_quadratic = 0.002
"#;
    let randomizer = Randomizer::new(RandomizationConfig::from_toml_str(text).unwrap(), 77).unwrap();
    let base = home();
    let at = |episode: u64| {
        let mut s = base.clone();
        let report = randomizer.apply_scene(episode, &mut s).unwrap();
        (s, report)
    };
    let (s0, r0) = at(0);
    let (s1, _) = at(1);
    let (s2, _) = at(2);
    let (again, _) = at(0);
    assert_eq!(s0.to_json_string(), again.to_json_string(), "same episode, same scene");
    // Episodes 0 and 1 share the object draw; the start pose is drawn every episode.
    assert_eq!(s0.objects, s1.objects);
    assert_ne!(s0.objects, s2.objects);
    assert!(r0.robot_moved);
    let (p0, p1) = (s0.robot.clone().unwrap(), s1.robot.clone().unwrap());
    assert_ne!(p0.position, p1.position);
    let start = base.robot.clone().unwrap();
    let moved = ((p0.position[0] - start.position[0]).powi(2) + (p0.position[1] - start.position[1]).powi(2)).sqrt();
    assert!(moved > 0.0 && moved < 1.0, "{moved}");
    let maps = hearth_sim::scene::SceneMaps::build(&s0, &Default::default()).unwrap();
    assert!(maps.is_traversable([p0.position[0], p0.position[1]]));
    // The randomised scene loads, robot included.
    let (world, loaded) = loaded(&s0);
    assert!(loaded.robot.is_some() && world.body_count() > 10);

    // Camera offsets and depth noise are reproducible per episode.
    assert_eq!(randomizer.camera_offset(3), randomizer.camera_offset(3));
    assert_ne!(randomizer.camera_offset(3), randomizer.camera_offset(4));
    assert_ne!(randomizer.camera_offset(3), Isometry3::identity());
    let noisy = |episode: u64| {
        let mut depth = vec![1.5f32; 256];
        add_depth_noise(
            &mut depth,
            &randomizer.depth_noise(),
            &mut randomizer.rng(episode, Stream::Noise),
        );
        depth
    };
    assert_eq!(noisy(1), noisy(1));
    assert_ne!(noisy(1), noisy(2));
    assert!(randomizer.lidar_noise().is_none());
}

#[test]
fn physics_through_the_randomizer_touches_the_building_when_asked() {
    let scene = home();
    let (mut world, loaded) = loaded(&scene);
    let ground = world.ground().unwrap();
    let g0 = world.body_friction(ground).unwrap();
    let robot = loaded.robot.unwrap();
    let robot_friction = |world: &World| -> Vec<Option<f64>> {
        world
            .model_bodies(robot)
            .unwrap()
            .into_iter()
            .map(|b| world.body_friction(b).unwrap())
            .collect()
    };
    let robot_before = robot_friction(&world);
    let text = "[physics]\nenabled = true\nfriction = true\nbuilding = true\nspread = 0.5\n";
    let randomizer = Randomizer::new(RandomizationConfig::from_toml_str(text).unwrap(), 3).unwrap();
    let report = randomizer.apply_world(0, &mut world, &loaded).unwrap();
    assert!(report.bodies > loaded.objects.len());
    assert_eq!(report.joints, 0, "damping factors [1, 1] leave joints alone");
    let g1 = world.body_friction(ground).unwrap();
    assert_ne!(g0, g1);
    // Within half the span around the typical value of a floor material.
    let f = g1.unwrap();
    let floors: Vec<Material> = world
        .static_visuals()
        .iter()
        .filter(|v| v.name.contains("floor/"))
        .map(|v| v.material)
        .collect();
    assert!(!floors.is_empty());
    let within = |m: &Material| {
        let (r, t) = (m.ranges().friction, m.props().friction);
        f >= t - 0.5 * (t - r[0]) - 1e-6 && f <= t + 0.5 * (r[1] - t) + 1e-6
    };
    assert!(floors.iter().any(within), "{f} {floors:?}");
    // Robots are never changed.
    assert_eq!(robot_friction(&world), robot_before);
}

#[test]
fn configurations_with_unknown_keys_or_bad_values_are_refused_naming_the_key() {
    let cases: &[(&str, &str)] = &[
        ("every_k_episode = 2", "every_k_episode"),
        ("[objects]\nenabeld = true", "enabeld"),
        ("[physics]\njoint_damping = [2.0, 1.0]", "physics.joint_damping"),
        ("[physics]\njoint_damping = [-1.0, 1.0]", "physics.joint_damping"),
        ("[physics]\nspread = 1.5", "physics.spread"),
        ("[objects]\nprobability = 1.2", "objects.probability"),
        ("[objects]\ncategories = [\"spaceship\"]", "objects.categories"),
        ("[objects]\ncategories = [\"door\"]", "objects.categories"),
        ("[objects]\nmin_fill = 0.0", "objects.min_fill"),
        ("every_k_episodes = 0", "every_k_episodes"),
        ("[pose]\nrobot_yaw_std = 4.0", "pose.robot_yaw_std"),
        ("[noise]\ndepth_dropout = -0.1", "noise.depth_dropout"),
        ("[noise]\nlidar_std = nan", "noise.lidar_std"),
        ("[nosie]\nlidar_std = 0.1", "nosie"),
    ];
    for (text, key) in cases {
        let err = RandomizationConfig::from_toml_str(text).unwrap_err();
        match &err {
            RandomizeError::UnknownKey { key: k, .. } => assert_eq!(k, key, "{text}"),
            RandomizeError::InvalidValue { key: k, .. } => assert_eq!(k, key, "{text}"),
            other => panic!("{text}: unexpected {other}"),
        }
        assert!(err.to_string().contains(key), "{err}");
    }
    let err = RandomizationConfig::from_toml_str("[physics]\nfriction = 3").unwrap_err();
    assert!(
        matches!(err, RandomizeError::Parse { .. }) && err.to_string().contains("friction"),
        "{err}"
    );
    // The defaults are off and validate.
    let c = RandomizationConfig::from_toml_str("").unwrap();
    assert_eq!(c, RandomizationConfig::default());
    assert!(!c.any());
}

#[test]
fn the_documented_example_parses() {
    let doc = include_str!("../../docs/randomization.md");
    let start = doc.find("```toml\n").expect("the docs carry a TOML example") + "```toml\n".len();
    let end = start + doc[start..].find("```").unwrap();
    // The example is a whole `[randomization]` section: strip the prefix off its tables.
    let body = doc[start..end]
        .lines()
        .filter(|l| l.trim() != "[randomization]")
        .map(|l| l.replace("[randomization.", "["))
        .collect::<Vec<_>>()
        .join("\n");
    let c = RandomizationConfig::from_toml_str(&body).unwrap();
    assert!(c.any() && c.objects.enabled && c.visual.enabled && c.physics.enabled);
}
