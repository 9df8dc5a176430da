//! Loading MotionBenchMaker problem files: real excerpts, folders, joints files, and every kind
//! of bad input giving its typed error.

use std::path::{Path, PathBuf};

use hearth_planning::obstacles::{ObstacleId, Obstacles};
use hearth_planning::problem::{Defect, JointsInfo, ObstacleSpec, ProblemError, ProblemSet, load_dir};
use parry3d::math::Pose;
use parry3d::shape::Ball;
use support::GOOD;

mod support;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

#[test]
fn loads_panda_excerpt() {
    let set = ProblemSet::load(data("panda_table_pick.json")).unwrap();
    assert_eq!((set.robot.as_str(), set.family.as_str()), ("panda", "table_pick"));
    assert_eq!(set.joint_names.len(), 7);
    assert_eq!(set.joint_names[0], "panda_joint1");
    assert_eq!(set.problems.iter().map(|p| p.id).collect::<Vec<_>>(), [1, 41]);
    assert_eq!(set.valid_problems().map(|p| p.id).collect::<Vec<_>>(), [1]);
    assert!(set.source.is_some());

    let p = set.problem(1).unwrap();
    assert_eq!(p.obstacles.len(), 12);
    assert_eq!(p.obstacles.iter().filter(|o| o.kind() == "cylinder").count(), 2);
    assert_eq!(p.obstacles.iter().filter(|o| o.kind() == "box").count(), 10);
    assert_eq!(p.start, [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]);
    assert_eq!(p.goals.len(), 1);
    assert_eq!(p.goals[0].len(), 7);
    match &p.obstacles[0] {
        ObstacleSpec::Cylinder {
            center,
            radius,
            half_length,
            quat_xyzw,
            name,
        } => {
            assert_eq!(*center, [0.308907161037877, 0.8398608492910964, 0.2984669621486253]);
            assert_eq!((*radius, *half_length), (0.03, 0.06));
            assert!((quat_xyzw[2] - 0.4966790222940755).abs() < 1e-12);
            assert_eq!(name.as_deref(), Some("Can1"));
        }
        other => panic!("expected the can, got {other:?}"),
    }
    match &p.obstacles[1] {
        ObstacleSpec::Box { half_extents, name, .. } => {
            assert_eq!(*half_extents, [0.125; 3]);
            assert_eq!(name.as_deref(), Some("Cube"));
        }
        other => panic!("expected the cube, got {other:?}"),
    }
}

#[test]
fn problem_scene_places_obstacles() {
    let set = ProblemSet::load(data("panda_table_pick.json")).unwrap();
    let p = set.problem(1).unwrap();
    let scene = p.scene();
    assert_eq!(scene.len(), 12);
    assert_eq!(scene.name(ObstacleId(0)), Some("Can1"));
    let probe = Ball::new(1e-3);
    let [x, y, z] = p.obstacles[0].center().map(|v| v as f32);
    // The can stands upright (rotated about z only): hit 5 cm above its centre, miss 7 cm above
    // and 4 cm beside.
    assert_eq!(
        scene.first_hit(&probe, &Pose::translation(x, y, z + 0.05)),
        Some(ObstacleId(0))
    );
    assert!(!scene.intersects(&probe, &Pose::translation(x, y, z + 0.07)));
    assert!(!scene.intersects(&probe, &Pose::translation(x + 0.04, y, z)));
    // The robot base region is free, a point inside the cube is not.
    assert!(!scene.intersects(&probe, &Pose::translation(0.0, 0.0, 0.3)));
    let [cx, cy, cz] = p.obstacles[1].center().map(|v| v as f32);
    assert_eq!(
        scene.first_hit(&probe, &Pose::translation(cx, cy, cz)),
        Some(ObstacleId(1))
    );
}

#[test]
fn loads_fetch_excerpt() {
    let set = ProblemSet::load(data("fetch_table_pick.json")).unwrap();
    assert_eq!(set.robot, "fetch");
    assert_eq!(set.joint_names.len(), 8);
    assert_eq!(set.joint_names[0], "torso_lift_joint");
    let p = &set.problems[0];
    assert_eq!((p.id, p.valid, p.obstacles.len()), (7, true, 12));
    assert_eq!(p.start.len(), 8);
    let top = p.obstacles.iter().find(|o| o.name() == Some("table_top")).unwrap();
    match top {
        ObstacleSpec::Box {
            center, half_extents, ..
        } => {
            assert_eq!(*half_extents, [0.6, 1.0, 0.02]);
            assert!((center[2] - 0.6712042850974372).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn load_dir_skips_joints_and_sorts() {
    let sets = load_dir(data("")).unwrap();
    let names: Vec<_> = sets.iter().map(|s| s.robot.as_str()).collect();
    assert_eq!(names, ["fetch", "panda"]);
    assert!(matches!(load_dir(data("missing")), Err(ProblemError::Io { .. })));
}

#[test]
fn loads_joints_info() {
    let info = JointsInfo::load(data("joints.json")).unwrap();
    assert_eq!(info.robot, "panda");
    assert_eq!(info.joint_names.len(), 7);
    assert_eq!(info.lower[3], -3.0718);
    assert_eq!(info.upper[5], 3.7525);
    assert_eq!(info.velocity[6], 2.61);
    assert_eq!(info.acceleration.as_ref().unwrap()[0], 15.0);
    assert_eq!(info.jerk.as_ref().unwrap()[6], 10000.0);
    assert_eq!(info.finger_positions(), Some(&[0.065, 0.065][..]));
    let pairs = &info.notes.self_collision_allowed_pairs;
    assert_eq!(pairs.len(), 34);
    assert_eq!(pairs[0], ["panda_hand".to_string(), "panda_leftfinger".to_string()]);
    assert_eq!(info.notes.mbm_model_bounds.as_ref().unwrap().upper[3], 0.0873);

    let fetch = JointsInfo::from_json_str(
        r#"{"robot": "fetch", "joint_names": ["torso", "roll"], "lower": [0, -3.14], "upper": [0.4, 3.14],
            "velocity": [0.1, 1.5], "continuous": [false, true],
            "notes": {"mbm_gripper_finger_positions": [0.05, 0.05]}}"#,
    )
    .unwrap();
    assert_eq!(fetch.finger_positions(), Some(&[0.05, 0.05][..]));
    assert_eq!(fetch.continuous, Some(vec![false, true]));
    assert!(fetch.jerk.is_none() && fetch.notes.self_collision_allowed_pairs.is_empty());
}

#[test]
fn bad_joints_info() {
    let base = r#"{"robot": "r", "joint_names": ["a", "b"], "lower": [-1, -1], "upper": [1, 1], "velocity": [1, 1]}"#;
    assert!(JointsInfo::from_json_str(base).is_ok());
    let e = JointsInfo::from_json_str(&base.replace(r#""velocity": [1, 1]"#, r#""velocity": [1]"#)).unwrap_err();
    assert_eq!(e.field(), Some("velocity"));
    assert_eq!(e.defect(), Some(&Defect::WrongLength { expected: 2, found: 1 }));
    let e = JointsInfo::from_json_str(&base.replace(r#""lower": [-1, -1]"#, r#""lower": [-1, 2]"#)).unwrap_err();
    assert_eq!(e.field(), Some("lower[1]"));
    assert!(matches!(e.defect(), Some(Defect::InvertedLimits { .. })));
    let e = JointsInfo::from_json_str(r#"{"robot": "r"}"#).unwrap_err();
    assert!(matches!(e, ProblemError::Json { .. }), "{e}");
}

fn invalid(json: &str) -> (Option<u32>, String, Defect) {
    match ProblemSet::from_json_str(json) {
        Err(ProblemError::Invalid {
            file,
            problem,
            field,
            defect,
        }) => {
            assert_eq!(file, Path::new("<string>"));
            (problem, field, defect)
        }
        other => panic!("expected Invalid, got {other:?}"),
    }
}

#[test]
fn good_minimal_set_and_round_trip() {
    let set = ProblemSet::from_json_str(GOOD).unwrap();
    let p = &set.problems[0];
    assert_eq!(p.goals.len(), 2);
    assert_eq!(p.obstacles[1].name(), None);
    let scene = p.scene();
    assert_eq!(scene.name(ObstacleId(1)), Some("sphere1"));
    assert_eq!(scene.name(ObstacleId(2)), Some("cylinder2"));
    set.validate().unwrap();
    // Serialising gives the file format back.
    let again = ProblemSet::from_json_str(&serde_json::to_string(&set).unwrap()).unwrap();
    assert_eq!(again, set);
}

#[test]
fn unknown_obstacle_kind() {
    let (problem, field, defect) = invalid(&GOOD.replace(r#""kind": "sphere""#, r#""kind": "cone""#));
    assert_eq!((problem, field.as_str()), (Some(5), "obstacles[1].kind"));
    assert_eq!(defect, Defect::UnknownKind("cone".into()));
}

#[test]
fn wrong_length_configurations() {
    let (problem, field, defect) = invalid(&GOOD.replace(r#""start": [0, 0]"#, r#""start": [0, 0, 0]"#));
    assert_eq!((problem, field.as_str()), (Some(5), "start"));
    assert_eq!(defect, Defect::WrongLength { expected: 2, found: 3 });
    let (_, field, defect) = invalid(&GOOD.replace("[2, 2]", "[2]"));
    assert_eq!(field, "goals[1]");
    assert_eq!(defect, Defect::WrongLength { expected: 2, found: 1 });
    let (_, field, defect) = invalid(&GOOD.replace(r#""goals": [[1, 1], [2, 2]]"#, r#""goals": []"#));
    assert_eq!((field.as_str(), defect), ("goals", Defect::Empty));
    let (_, field, defect) = invalid(&GOOD.replace(r#""center": [1, 0, 0]"#, r#""center": [1, 0]"#));
    assert_eq!(field, "obstacles[0].center");
    assert_eq!(defect, Defect::WrongLength { expected: 3, found: 2 });
    let (problem, field, defect) = invalid(&GOOD.replace(r#"["j1", "j2"]"#, "[]"));
    assert_eq!((problem, field.as_str(), defect), (None, "joint_names", Defect::Empty));
}

#[test]
fn bad_quaternions() {
    let (_, field, defect) = invalid(&GOOD.replacen(r#""quat_xyzw": [0, 0, 0, 1]"#, r#""quat_xyzw": [0, 0, 0, 2]"#, 1));
    assert_eq!(field, "obstacles[0].quat_xyzw");
    assert_eq!(defect, Defect::NotUnitQuaternion(2.0));
    let (_, field, defect) = invalid(&GOOD.replace(
        r#""half_length": 0.5, "quat_xyzw": [0, 0, 0, 1]"#,
        r#""half_length": 0.5, "quat_xyzw": [0, 0, 0, 0]"#,
    ));
    assert_eq!(field, "obstacles[2].quat_xyzw");
    assert_eq!(defect, Defect::NotUnitQuaternion(0.0));
    // Slightly off-unit input is accepted and normalised.
    let set = ProblemSet::from_json_str(&GOOD.replacen("[0, 0, 0, 1]", "[0, 0, 0, 1.00001]", 1)).unwrap();
    match &set.problems[0].obstacles[0] {
        ObstacleSpec::Box { quat_xyzw, .. } => assert_eq!(quat_xyzw[3], 1.0),
        other => panic!("{other:?}"),
    }
}

#[test]
fn negative_and_missing_sizes() {
    let (_, field, defect) = invalid(&GOOD.replace(r#""radius": 0.2"#, r#""radius": -0.2"#));
    assert_eq!(
        (field.as_str(), defect),
        ("obstacles[1].radius", Defect::Negative(-0.2))
    );
    let (_, field, defect) = invalid(&GOOD.replace("[0.1, 0.2, 0.3]", "[0.1, -0.2, 0.3]"));
    assert_eq!(
        (field.as_str(), defect),
        ("obstacles[0].half_extents[1]", Defect::Negative(-0.2))
    );
    let (_, field, defect) = invalid(&GOOD.replace(r#""half_length": 0.5"#, r#""half_length": -0.5"#));
    assert_eq!(
        (field.as_str(), defect),
        ("obstacles[2].half_length", Defect::Negative(-0.5))
    );
    let (_, field, defect) = invalid(&GOOD.replace(r#", "radius": 0.2"#, ""));
    assert_eq!((field.as_str(), defect), ("obstacles[1].radius", Defect::Missing));
}

#[test]
fn typos_and_fields_of_another_kind_are_errors() {
    // A misspelt optional field would otherwise load as its default: no obstacles at all, or a
    // problem the set marks invalid counted as valid.
    for (from, to, says) in [
        (r#""obstacles":"#, r#""obstacle":"#, "unknown field `obstacle`"),
        (r#""valid": true"#, r#""vaild": false"#, "unknown field `vaild`"),
        (
            r#""family": "unit""#,
            r#""family": "unit", "familly": "x""#,
            "unknown field `familly`",
        ),
        (r#""radius": 0.2"#, r#""raduis": 0.2"#, "unknown field `raduis`"),
    ] {
        let json = GOOD.replacen(from, to, 1);
        assert_ne!(json, GOOD, "{from}");
        let e = ProblemSet::from_json_str(&json).unwrap_err();
        assert!(
            matches!(e, ProblemError::Json { .. }) && e.to_string().contains(says),
            "{e}"
        );
    }
    // A field that belongs to another kind of obstacle names the obstacle and the field.
    let (problem, field, defect) = invalid(&GOOD.replace(r#""radius": 0.2"#, r#""radius": 0.2, "half_length": 1"#));
    assert_eq!((problem, field.as_str()), (Some(5), "obstacles[1].half_length"));
    assert_eq!(defect, Defect::NotForKind("sphere"));
    let (_, field, defect) = invalid(&GOOD.replace(r#""name": "b""#, r#""name": "b", "radius": 0.1"#));
    assert_eq!(
        (field.as_str(), defect),
        ("obstacles[0].radius", Defect::NotForKind("box"))
    );
    let (_, field, defect) = invalid(&GOOD.replace(
        r#""radius": 0.1, "half_length": 0.5"#,
        r#""radius": 0.1, "half_length": 0.5, "half_extents": [1, 1, 1]"#,
    ));
    assert_eq!(
        (field.as_str(), defect),
        ("obstacles[2].half_extents", Defect::NotForKind("cylinder"))
    );
    let e = ProblemSet::from_json_str(&GOOD.replace(r#""radius": 0.2"#, r#""radius": 0.2, "quat_xyzw": [0, 0, 0, 1]"#))
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "<string>: problem 5: obstacles[1].quat_xyzw does not belong to a sphere"
    );
}

#[test]
fn non_finite_values() {
    // JSON has no NaN literal; out-of-range numbers are a parse error …
    let e = ProblemSet::from_json_str(&GOOD.replace(r#""start": [0, 0]"#, r#""start": [0, 1e999]"#)).unwrap_err();
    assert!(matches!(e, ProblemError::Json { .. }), "{e}");
    // … and sets built in code are checked by `validate`.
    let mut set = ProblemSet::from_json_str(GOOD).unwrap();
    set.problems[0].goals[1][0] = f64::NAN;
    let e = set.validate().unwrap_err();
    assert_eq!((e.problem(), e.field()), (Some(5), Some("goals[1][0]")));
    assert!(matches!(e.defect(), Some(Defect::NotFinite(v)) if v.is_nan()));
    let mut set = ProblemSet::from_json_str(GOOD).unwrap();
    if let ObstacleSpec::Sphere { radius, .. } = &mut set.problems[0].obstacles[1] {
        *radius = f64::INFINITY;
    }
    assert_eq!(set.validate().unwrap_err().field(), Some("obstacles[1].radius"));
    // A huge number is named as a short one.
    let e = ProblemSet::from_json_str(&GOOD.replace(r#""radius": 0.2"#, r#""radius": 1e300"#)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "<string>: problem 5: obstacles[1].radius is 1e300, beyond ±1000000 m"
    );
}

#[test]
fn malformed_json_and_missing_files_name_the_file() {
    let e = ProblemSet::from_json_str("{\"robot\": ").unwrap_err();
    assert!(matches!(e, ProblemError::Json { .. }));
    let e = ProblemSet::load(data("nope.json")).unwrap_err();
    assert!(matches!(e, ProblemError::Io { .. }));
    assert!(e.to_string().contains("nope.json"), "{e}");

    let dir = std::env::temp_dir().join(format!("hearth-problem-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a_good.json"), GOOD).unwrap();
    std::fs::write(
        dir.join("b_bad.json"),
        GOOD.replace(r#""kind": "box""#, r#""kind": "boxx""#),
    )
    .unwrap();
    std::fs::write(dir.join("c_broken.json"), "[1, 2").unwrap();
    std::fs::write(dir.join("notes.txt"), "not a problem").unwrap();
    let e = ProblemSet::load(dir.join("b_bad.json")).unwrap_err();
    assert_eq!(e.file(), dir.join("b_bad.json"));
    let msg = e.to_string();
    assert!(
        msg.contains("b_bad.json: problem 5: obstacles[0].kind unknown obstacle kind `boxx`"),
        "{msg}"
    );
    let e = ProblemSet::load(dir.join("c_broken.json")).unwrap_err();
    assert!(
        matches!(e, ProblemError::Json { .. }) && e.to_string().contains("c_broken.json"),
        "{e}"
    );
    // The folder loader stops at the first bad file, in name order.
    let e = load_dir(&dir).unwrap_err();
    assert_eq!(e.file(), dir.join("b_bad.json"));
    std::fs::remove_file(dir.join("b_bad.json")).unwrap();
    std::fs::remove_file(dir.join("c_broken.json")).unwrap();
    assert_eq!(load_dir(&dir).unwrap().len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}
