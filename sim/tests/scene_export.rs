//! URDF export of scenes and the scene summary.

use hearth_kinematics::RobotModel;
use hearth_sim::scene::{GenerateOptions, Manifest, SceneError, SceneInfo, export_urdf, generate};

#[test]
fn every_exported_urdf_loads_back() {
    let home = generate(&GenerateOptions {
        seed: 3,
        rooms: 4,
        ..Default::default()
    })
    .unwrap();
    let dir = std::env::temp_dir().join(format!("hearth_export_{}", std::process::id()));
    let manifest = export_urdf(&home, &dir, Some("fetch")).unwrap();
    assert_eq!(manifest.bodies.len(), home.objects.len() + 2);
    let written: Manifest = serde_json::from_str(&std::fs::read_to_string(dir.join("scene.json")).unwrap()).unwrap();
    assert_eq!(written, manifest);
    let robots: Vec<_> = manifest.bodies.iter().filter(|b| b.robot).collect();
    assert_eq!(robots.len(), 1);
    assert_eq!(robots[0].position, home.robot.as_ref().unwrap().position);
    for body in &manifest.bodies {
        let model = RobotModel::from_urdf_file(dir.join(&body.urdf)).unwrap_or_else(|e| panic!("{}: {e}", body.urdf));
        let norm: f64 = body.quat_xyzw.iter().map(|q| q * q).sum();
        assert!((norm - 1.0).abs() < 1e-9);
        for j in body.joints.keys() {
            assert!(model.variable_names().contains(j), "{}: {j}", body.name);
        }
        if let Some(o) = home.objects.iter().find(|o| o.name == body.name) {
            assert_eq!(o.fixed, body.fixed);
            assert_eq!(o.position, body.position);
        }
    }
    // The building: floors, walls and ceilings as boxes, openings cut out.
    let building = RobotModel::from_urdf_file(dir.join("building.urdf")).unwrap();
    let boxes = building.links()[0].collisions.len();
    assert!(boxes > home.building.walls.len() + 2 * home.building.rooms.len());
    // Articulated objects keep their joints.
    let door = manifest.bodies.iter().find(|b| b.name.starts_with("door_")).unwrap();
    let m = RobotModel::from_urdf_file(dir.join(&door.urdf)).unwrap();
    assert_eq!(m.variable_names(), ["leaf_hinge"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unknown_robot_is_a_typed_error() {
    let home = generate(&GenerateOptions {
        seed: 1,
        rooms: 2,
        ..Default::default()
    })
    .unwrap();
    let dir = std::env::temp_dir().join(format!("hearth_export_bad_{}", std::process::id()));
    match export_urdf(&home, &dir, Some("r2d2")) {
        Err(SceneError::UnknownRobot { name, known }) => {
            assert_eq!(name, "r2d2");
            assert!(known.contains("fetch"));
        }
        other => panic!("{other:?}"),
    }
    assert!(!dir.exists());
}

#[test]
fn info_counts_rooms_objects_categories_and_articulation() {
    let home = generate(&GenerateOptions {
        seed: 8,
        ..Default::default()
    })
    .unwrap();
    let info = SceneInfo::of(&home);
    assert_eq!(info.rooms.len(), home.building.rooms.len());
    assert_eq!(
        info.rooms.iter().map(|r| r.objects).sum::<usize>() + info.unassigned,
        info.objects
    );
    assert_eq!(info.categories.values().sum::<usize>(), info.objects);
    assert!(info.categories.len() >= 25, "{} categories used", info.categories.len());
    assert!(info.categories["door"] == home.building.rooms.len() - 1);
    let json: serde_json::Value = serde_json::from_str(&info.to_json().unwrap()).unwrap();
    for key in ["rooms", "objects", "objects_per_room", "categories", "articulated"] {
        assert!(json.get(key).is_some(), "{key}");
    }
    assert!(info.articulated.len() >= 15);
}

#[test]
fn names_that_sanitise_alike_get_distinct_files() {
    use hearth_sim::scene::{SceneFile, SceneObject};
    let mut s = SceneFile::empty("names");
    s.objects.push(SceneObject::new("a/b", "mug", 0, [0.0, 0.0, 0.0]));
    s.objects.push(SceneObject::new("a_b", "mug", 0, [1.0, 0.0, 0.0]));
    let dir = std::env::temp_dir().join(format!("hearth_export_names_{}", std::process::id()));
    let m = export_urdf(&s, &dir, None).unwrap();
    assert_ne!(m.bodies[1].urdf, m.bodies[2].urdf);
    std::fs::remove_dir_all(&dir).ok();
}
