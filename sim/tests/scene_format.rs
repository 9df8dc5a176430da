//! Scene files: round trips, and a typed error naming the culprit for every kind of bad input.

use hearth_sim::assets::AssetError;
use hearth_sim::scene::{GenerateOptions, Orientation, SceneError, SceneFile, SceneObject, Wall, generate};
use proptest::prelude::*;

fn small_scene() -> SceneFile {
    let mut s = SceneFile::empty("small");
    s.building
        .walls
        .push(Wall::new("north", [0.0, 3.0], [4.0, 3.0], 2.5, 0.2));
    s.objects.push(SceneObject::new("table", "table", 3, [2.0, 1.0, 0.0]));
    let mut mug = SceneObject::new("mug", "mug", 1, [2.0, 1.0, 0.75]);
    mug.on = Some("table".into());
    s.objects.push(mug);
    let mut laptop = SceneObject::new("laptop", "laptop", 0, [2.2, 0.8, 0.75]);
    laptop.on = Some("table".into());
    laptop.joints.insert("lid_hinge".into(), 1.5);
    laptop.orientation = Orientation::QuatXyzw([0.0, 0.0, 0.3826834, 0.9238795]);
    s.objects.push(laptop);
    s
}

#[test]
fn generated_home_round_trips_through_json_and_files() {
    let home = generate(&GenerateOptions {
        seed: 11,
        rooms: 4,
        ..Default::default()
    })
    .unwrap();
    let text = home.to_json_string();
    let back = SceneFile::from_json_str(&text).unwrap();
    assert_eq!(home, back);
    let path = std::env::temp_dir().join(format!("hearth_scene_roundtrip_{}.json", std::process::id()));
    home.save(&path).unwrap();
    assert_eq!(SceneFile::load(&path).unwrap(), home);
    std::fs::remove_file(&path).ok();
}

#[test]
fn same_seed_same_home_and_different_seed_different_home() {
    let a = generate(&GenerateOptions {
        seed: 42,
        ..Default::default()
    })
    .unwrap()
    .to_json_string();
    let b = generate(&GenerateOptions {
        seed: 42,
        ..Default::default()
    })
    .unwrap()
    .to_json_string();
    let c = generate(&GenerateOptions {
        seed: 43,
        ..Default::default()
    })
    .unwrap()
    .to_json_string();
    assert_eq!(a, b);
    assert_ne!(a, c);
}

fn json_error(text: &str) -> String {
    match SceneFile::from_json_str(text) {
        Err(SceneError::Json { message, .. }) => message,
        other => panic!("expected a JSON error, got {other:?}"),
    }
}

#[test]
fn typos_and_wrong_types_are_named() {
    let good = small_scene().to_json_string();
    assert!(json_error(&good.replacen("\"position\"", "\"postion\"", 1)).contains("postion"));
    assert!(json_error(&good.replacen("\"walls\"", "\"wals\"", 1)).contains("wals"));
    assert!(json_error(&good.replacen("\"material\": \"plaster\"", "\"material\": \"cheese\"", 1)).contains("cheese"));
    assert!(
        json_error(
            r#"{"name": "x", "building": {}, "objects": [{"name": "a", "category": "mug", "position": [0, 0, 1e400]}]}"#
        )
        .contains("number")
    );
    assert!(json_error("{\"name\": \"x\"").contains("EOF"));
}

#[test]
fn unknown_category_and_variant_are_named() {
    let mut s = small_scene();
    s.objects[0].category = "spaceship".into();
    match s.validate() {
        Err(SceneError::UnknownCategory { object, category }) => {
            assert_eq!((object.as_str(), category.as_str()), ("table", "spaceship"))
        }
        other => panic!("{other:?}"),
    }
    let mut s = small_scene();
    s.objects[1].variant = 9;
    match s.validate() {
        Err(SceneError::Asset { object, reason }) => {
            assert_eq!(object, "mug");
            assert!(matches!(*reason, AssetError::VariantOutOfRange { variant: 9, .. }));
        }
        other => panic!("{other:?}"),
    }
    let mut s = small_scene();
    s.objects[1].scale = -2.0;
    match s.validate() {
        Err(SceneError::Asset { reason, .. }) => assert!(matches!(*reason, AssetError::BadScale { .. })),
        other => panic!("{other:?}"),
    }
}

#[test]
fn non_finite_numbers_are_named() {
    let mut s = small_scene();
    s.objects[2].position[1] = f64::NAN;
    match s.validate() {
        Err(SceneError::NonFinite { field, .. }) => {
            assert!(field.contains("laptop") && field.contains("position"), "{field}")
        }
        other => panic!("{other:?}"),
    }
    let mut s = small_scene();
    s.building.walls[0].height = f64::INFINITY;
    assert!(matches!(s.validate(), Err(SceneError::NonFinite { field, .. }) if field.contains("north")));
}

#[test]
fn overlaps_are_errors_unless_resting_on_the_support() {
    assert!(small_scene().validate().is_ok());
    // Touching the table top is not overlapping; sinking into it is.
    let mut s = small_scene();
    s.objects[1].on = None;
    assert!(s.validate().is_ok());
    s.objects[1].position[2] = 0.7;
    match s.validate() {
        Err(SceneError::Overlap { a, b, depth }) => {
            assert!([a.as_str(), b.as_str()].contains(&"mug") && [a.as_str(), b.as_str()].contains(&"table"));
            assert!(depth > 0.0);
        }
        other => panic!("{other:?}"),
    }
    let mut s = small_scene();
    s.objects.push(SceneObject::new("chair", "chair", 0, [2.3, 1.2, 0.0]));
    assert!(matches!(s.validate(), Err(SceneError::Overlap { .. })));
    // A chair into the wall.
    let mut s = small_scene();
    s.objects.push(SceneObject::new("chair", "chair", 0, [3.0, 2.9, 0.0]));
    assert!(
        matches!(s.validate(), Err(SceneError::WallOverlap { object, wall, .. }) if object == "chair" && wall == "north")
    );
}

#[test]
fn joints_supports_and_names_are_checked() {
    let mut s = small_scene();
    s.objects[2].joints.insert("lid_hinj".into(), 0.5);
    match s.validate() {
        Err(SceneError::UnknownJoint { object, joint, known }) => {
            assert_eq!((object.as_str(), joint.as_str()), ("laptop", "lid_hinj"));
            assert!(known.contains("lid_hinge"));
        }
        other => panic!("{other:?}"),
    }
    let mut s = small_scene();
    s.objects[2].joints.insert("lid_hinge".into(), 3.5);
    assert!(matches!(s.validate(), Err(SceneError::JointOutOfRange { value, .. }) if value == 3.5));
    let mut s = small_scene();
    s.objects[1].on = Some("tabel".into());
    assert!(matches!(s.validate(), Err(SceneError::UnknownSupport { support, .. }) if support == "tabel"));
    let mut s = small_scene();
    s.objects[1].name = "table".into();
    assert!(matches!(
        s.validate(),
        Err(SceneError::DuplicateName { kind: "object", .. })
    ));
    let mut s = small_scene();
    s.building.walls[0].end = s.building.walls[0].start;
    assert!(matches!(s.validate(), Err(SceneError::Invalid { .. })));
}

#[test]
fn load_reports_missing_files() {
    let err = SceneFile::load("/definitely/not/here.json").unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutated scene text never panics the loader: it loads or gives an error.
    #[test]
    fn mutated_json_never_panics(edits in prop::collection::vec((any::<prop::sample::Index>(), 0u8..4, any::<u8>()), 1..6)) {
        let mut bytes = small_scene().to_json_string().into_bytes();
        for (at, op, byte) in edits {
            if bytes.is_empty() {
                break;
            }
            let i = at.index(bytes.len());
            match op {
                0 => { bytes.remove(i); }
                1 => bytes.insert(i, byte),
                2 => bytes[i] = byte,
                _ => {
                    // Replace a digit with a wild number.
                    if bytes[i].is_ascii_digit() {
                        let wild = ["-1e308", "1e999", "0.0000001", "-0", "999999999999"][byte as usize % 5];
                        bytes.splice(i..=i, wild.bytes());
                    }
                }
            }
        }
        let text = String::from_utf8_lossy(&bytes);
        let _ = SceneFile::from_json_str(&text);
    }
}
