//! One test per kind of bad URDF input: each asserts the exact `KinematicsError` variant and
//! that the message names the culprit (file, element, value), so a user can fix the input
//! without a debugger.

use std::path::PathBuf;

use hearth_kinematics::{KinematicsError, RobotModel};

/// Name passed as the URDF's source, so messages can be checked to name the file.
const SRC: &str = "bad_robot.urdf";

fn load(text: &str) -> Result<RobotModel, KinematicsError> {
    RobotModel::from_urdf_str_with(text, SRC, None, &Default::default())
}

/// Loads `text`, which must fail; returns the error and its message.
fn fail(text: &str) -> (KinematicsError, String) {
    match load(text) {
        Ok(m) => panic!("expected an error, got a model with {} links:\n{text}", m.links().len()),
        Err(e) => {
            let msg = e.to_string();
            (e, msg)
        }
    }
}

/// Asserts that `msg` contains every one of `parts`.
#[track_caller]
fn names(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message should mention `{p}`: {msg}");
    }
}

/// A robot with links `base`, `arm` and one joint `j1` (base → arm) whose element body is `joint`.
fn one_joint(kind: &str, joint: &str) -> String {
    format!(
        r#"<robot name="r">
  <link name="base"/>
  <link name="arm"/>
  <joint name="j1" type="{kind}">
    <parent link="base"/><child link="arm"/>
    {joint}
  </joint>
</robot>"#
    )
}

const LIMIT: &str = r#"<limit lower="-1" upper="1" effort="10" velocity="2"/>"#;

/// A robot with one link whose only collision geometry is `geometry`.
fn one_geometry(geometry: &str) -> String {
    format!(
        r#"<robot name="r">
  <link name="body"><collision><geometry>{geometry}</geometry></collision></link>
</robot>"#
    )
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hearth_urdf_errors_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn sanity_the_templates_are_valid() {
    // The fixtures below each break one thing in otherwise valid input.
    let m = load(&one_joint("revolute", &format!(r#"<axis xyz="0 0 1"/>{LIMIT}"#))).unwrap();
    assert_eq!(m.variable_names(), ["j1"]);
    let m = load(&one_geometry(r#"<box size="1 1 1"/>"#)).unwrap();
    assert!(m.link_shape(0).is_some());
}

#[test]
fn malformed_xml() {
    let (e, msg) = fail(r#"<robot name="r"><link name="a"></robot>"#);
    assert!(
        matches!(e, KinematicsError::Xml { ref source_name, .. } if source_name == SRC),
        "{e:?}"
    );
    names(&msg, &[SRC, "malformed"]);

    // Unclosed root element.
    let (e, _) = fail(r#"<robot name="r"><link name="a"/>"#);
    assert!(matches!(e, KinematicsError::Xml { .. }), "{e:?}");

    // Not XML at all.
    let (e, _) = fail("this is not xml");
    assert!(matches!(e, KinematicsError::Xml { .. }), "{e:?}");
}

#[test]
fn malformed_xml_from_file_names_the_file() {
    let dir = temp_dir("malformed_file");
    let path = dir.join("broken.urdf");
    std::fs::write(&path, r#"<robot name="r"><link name="a"><visual></link></robot>"#).unwrap();
    let e = RobotModel::from_urdf_file(&path).unwrap_err();
    assert!(matches!(e, KinematicsError::Xml { .. }), "{e:?}");
    names(&e.to_string(), &[&path.display().to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_file_is_io_naming_the_path() {
    let e = RobotModel::from_urdf_file("/nonexistent/hearth/robot.urdf").unwrap_err();
    assert!(matches!(e, KinematicsError::Io { .. }), "{e:?}");
    names(&e.to_string(), &["/nonexistent/hearth/robot.urdf"]);
}

#[test]
fn joint_with_missing_parent_link() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="base"/><link name="arm"/>
  <joint name="j1" type="fixed"><parent link="ghost"/><child link="arm"/></joint>
</robot>"#,
    );
    assert!(
        matches!(e, KinematicsError::MissingLink { ref joint, role: "parent", ref link, .. } if joint == "j1" && link == "ghost"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "parent", "`ghost`"]);
}

#[test]
fn joint_with_missing_child_link() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="base"/><link name="arm"/>
  <joint name="j1" type="fixed"><parent link="base"/><child link="arm"/></joint>
  <joint name="j2" type="fixed"><parent link="arm"/><child link="phantom"/></joint>
</robot>"#,
    );
    assert!(
        matches!(e, KinematicsError::MissingLink { ref joint, role: "child", ref link, .. } if joint == "j2" && link == "phantom"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j2`", "child", "`phantom`"]);
}

#[test]
fn joint_cycle_without_root() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="a"/><link name="b"/>
  <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>
</robot>"#,
    );
    match &e {
        KinematicsError::JointCycle { link, source_name } => {
            assert!(link == "a" || link == "b", "{e:?}");
            assert_eq!(source_name, SRC);
            names(&msg, &[SRC, "cycle", &format!("`{link}`")]);
        }
        other => panic!("expected JointCycle, got {other:?}"),
    }
}

#[test]
fn joint_cycle_beside_a_root() {
    // `root` is a proper root, but `a` and `b` form a cycle that no root reaches.
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="root"/><link name="a"/><link name="b"/>
  <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>
</robot>"#,
    );
    match &e {
        KinematicsError::JointCycle { link, .. } => {
            assert!(link == "a" || link == "b", "the cycle is a-b, not {link}");
            names(&msg, &[SRC, &format!("`{link}`")]);
        }
        other => panic!("expected JointCycle, got {other:?}"),
    }
}

#[test]
fn two_roots() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="base"/><link name="arm"/><link name="island"/>
  <joint name="j1" type="fixed"><parent link="base"/><child link="arm"/></joint>
</robot>"#,
    );
    assert!(matches!(e, KinematicsError::MultipleRoots { .. }), "{e:?}");
    names(&msg, &[SRC, "base", "island"]);
    assert!(!msg.contains("arm"), "`arm` is not a root: {msg}");
}

#[test]
fn link_with_two_parent_joints() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="ac" type="fixed"><parent link="a"/><child link="c"/></joint>
  <joint name="bc" type="fixed"><parent link="b"/><child link="c"/></joint>
</robot>"#,
    );
    assert!(
        matches!(e, KinematicsError::MultipleParents { ref link, ref first, ref second, .. }
            if link == "c" && first == "ac" && second == "bc"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`c`", "`ac`", "`bc`"]);
}

#[test]
fn duplicate_link_name() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="base"/><link name="twin"/><link name="twin"/>
  <joint name="j1" type="fixed"><parent link="base"/><child link="twin"/></joint>
</robot>"#,
    );
    assert!(
        matches!(e, KinematicsError::DuplicateName { element: "link", ref name, .. } if name == "twin"),
        "{e:?}"
    );
    names(&msg, &[SRC, "link", "`twin`"]);
}

#[test]
fn duplicate_joint_name() {
    let (e, msg) = fail(
        r#"<robot name="r">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="same" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="same" type="fixed"><parent link="b"/><child link="c"/></joint>
</robot>"#,
    );
    assert!(
        matches!(e, KinematicsError::DuplicateName { element: "joint", ref name, .. } if name == "same"),
        "{e:?}"
    );
    names(&msg, &[SRC, "joint", "`same`"]);
}

#[test]
fn unknown_joint_type_is_an_xml_error_naming_it() {
    let (e, msg) = fail(&one_joint("hinge", &format!(r#"<axis xyz="0 0 1"/>{LIMIT}"#)));
    assert!(matches!(e, KinematicsError::Xml { .. }), "{e:?}");
    names(&msg, &[SRC, "hinge"]);
}

#[test]
fn planar_and_floating_joints_are_unsupported() {
    for kind in ["planar", "floating"] {
        let (e, msg) = fail(&one_joint(kind, &format!(r#"<axis xyz="0 0 1"/>{LIMIT}"#)));
        assert!(
            matches!(e, KinematicsError::UnsupportedJoint { ref joint, kind: ref k, .. } if joint == "j1" && k == kind),
            "{kind}: {e:?}"
        );
        names(&msg, &[SRC, "`j1`", &format!("`{kind}`")]);
    }
}

#[test]
fn nan_in_an_origin() {
    let (e, msg) = fail(&one_joint(
        "revolute",
        &format!(r#"<origin xyz="0 NaN 0"/><axis xyz="0 0 1"/>{LIMIT}"#),
    ));
    assert!(
        matches!(e, KinematicsError::InvalidValue { ref element, what: "origin xyz", value, .. }
            if element.contains("j1") && value.is_nan()),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "origin xyz", "NaN"]);

    // And in a link's collision origin.
    let (e, msg) = fail(
        r#"<robot name="r"><link name="body"><collision><origin rpy="0 0 nan"/>
           <geometry><sphere radius="0.1"/></geometry></collision></link></robot>"#,
    );
    assert!(
        matches!(e, KinematicsError::InvalidValue { ref element, what: "origin rpy", value, .. }
            if element.contains("body") && value.is_nan()),
        "{e:?}"
    );
    names(&msg, &[SRC, "`body`", "origin rpy", "NaN"]);
}

#[test]
fn inverted_limits() {
    let (e, msg) = fail(&one_joint(
        "revolute",
        r#"<axis xyz="0 0 1"/><limit lower="1" upper="-1" effort="10" velocity="2"/>"#,
    ));
    assert!(
        matches!(e, KinematicsError::InvertedLimits { ref joint, lower, upper, .. }
            if joint == "j1" && lower == 1.0 && upper == -1.0),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "lower 1", "upper -1"]);
}

#[test]
fn nan_limit() {
    let (e, msg) = fail(&one_joint(
        "revolute",
        r#"<axis xyz="0 0 1"/><limit lower="-1" upper="nan" effort="10" velocity="2"/>"#,
    ));
    assert!(
        matches!(e, KinematicsError::InvalidValue { ref element, what: "limit upper", value, .. }
            if element.contains("j1") && value.is_nan()),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "limit upper", "NaN"]);
}

#[test]
fn negative_velocity() {
    let (e, msg) = fail(&one_joint(
        "revolute",
        r#"<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="-2"/>"#,
    ));
    assert!(
        matches!(e, KinematicsError::InvalidValue { ref element, what: "limit velocity", value, .. }
            if element.contains("j1") && value == -2.0),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "limit velocity", "-2"]);
}

#[test]
fn zero_length_axis() {
    let (e, msg) = fail(&one_joint("revolute", &format!(r#"<axis xyz="0 0 0"/>{LIMIT}"#)));
    assert!(
        matches!(e, KinematicsError::ZeroAxis { ref joint, .. } if joint == "j1"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "axis"]);
}

#[test]
fn revolute_without_limit() {
    let (e, msg) = fail(&one_joint("revolute", r#"<axis xyz="0 0 1"/>"#));
    assert!(
        matches!(e, KinematicsError::MissingLimit { ref joint, kind: "revolute", .. } if joint == "j1"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j1`", "revolute", "<limit"]);

    let (e, _) = fail(&one_joint("prismatic", r#"<axis xyz="1 0 0"/>"#));
    assert!(
        matches!(e, KinematicsError::MissingLimit { kind: "prismatic", .. }),
        "{e:?}"
    );

    // A continuous joint needs no limit.
    load(&one_joint("continuous", r#"<axis xyz="0 0 1"/>"#)).unwrap();
}

/// Links `l0..l3`, revolute `j1..j3` in a chain; `mimics` is inserted into joint `j2` and
/// `mimics3` into `j3`.
fn mimic_robot(mimic2: &str, mimic3: &str) -> String {
    format!(
        r#"<robot name="r">
  <link name="l0"/><link name="l1"/><link name="l2"/><link name="l3"/>
  <joint name="j1" type="revolute"><parent link="l0"/><child link="l1"/><axis xyz="0 0 1"/>{LIMIT}</joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 0 1"/>{LIMIT}{mimic2}</joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><axis xyz="0 0 1"/>{LIMIT}{mimic3}</joint>
</robot>"#
    )
}

#[test]
fn mimic_of_a_missing_joint() {
    let (e, msg) = fail(&mimic_robot(r#"<mimic joint="nobody"/>"#, ""));
    assert!(
        matches!(e, KinematicsError::BadMimic { ref joint, ref target, .. } if joint == "j2" && target == "nobody"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j2`", "`nobody`"]);

    // Sanity: a proper mimic loads and removes a variable.
    let m = load(&mimic_robot(r#"<mimic joint="j1" multiplier="2"/>"#, "")).unwrap();
    assert_eq!(m.variable_names(), ["j1", "j3"]);
}

/// A fixed joint's `<mimic>` is left out (it has no position to follow), unless it names a
/// joint that does not exist.
#[test]
fn mimic_on_a_fixed_joint_is_ignored() {
    let fixed = |mimic: &str| {
        format!(
            r#"<robot name="r">
  <link name="l0"/><link name="l1"/><link name="l2"/>
  <joint name="j1" type="fixed"><parent link="l0"/><child link="l1"/></joint>
  <joint name="j2" type="fixed"><parent link="l0"/><child link="l2"/>{mimic}</joint>
</robot>"#
        )
    };
    let m = load(&fixed(r#"<mimic joint="j1"/>"#)).unwrap();
    assert!(m.variable_names().is_empty());
    let (e, msg) = fail(&fixed(r#"<mimic joint="nobody"/>"#));
    assert!(
        matches!(e, KinematicsError::BadMimic { ref joint, ref target, .. } if joint == "j2" && target == "nobody"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j2`", "`nobody`"]);
}

#[test]
fn mimic_loop() {
    let (e, msg) = fail(&mimic_robot(r#"<mimic joint="j3"/>"#, r#"<mimic joint="j2"/>"#));
    match &e {
        KinematicsError::BadMimic {
            joint, target, reason, ..
        } => {
            assert!(
                (joint == "j2" && target == "j3") || (joint == "j3" && target == "j2"),
                "{e:?}"
            );
            assert!(reason.contains("loop"), "{e:?}");
            names(&msg, &[SRC, &format!("`{joint}`"), &format!("`{target}`"), "loop"]);
        }
        other => panic!("expected BadMimic, got {other:?}"),
    }

    // A joint mimicking itself.
    let (e, msg) = fail(&mimic_robot(r#"<mimic joint="j2"/>"#, ""));
    assert!(
        matches!(e, KinematicsError::BadMimic { ref joint, ref target, .. } if joint == "j2" && target == "j2"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j2`"]);
}

#[test]
fn box_with_a_negative_size() {
    let (e, msg) = fail(&one_geometry(r#"<box size="0.1 -0.2 0.3"/>"#));
    assert!(
        matches!(e, KinematicsError::InvalidValue { ref element, what: "box size y", value, .. }
            if element.contains("body") && value == -0.2),
        "{e:?}"
    );
    names(&msg, &[SRC, "`body`", "box size y", "-0.2"]);
}

#[test]
fn sphere_with_radius_zero() {
    let (e, msg) = fail(&one_geometry(r#"<sphere radius="0"/>"#));
    assert!(
        matches!(e, KinematicsError::InvalidValue { ref element, what: "sphere radius", value, .. }
            if element.contains("body") && value == 0.0),
        "{e:?}"
    );
    names(&msg, &[SRC, "`body`", "sphere radius"]);
}

#[test]
fn missing_mesh_file_lists_the_searched_paths() {
    let dir = temp_dir("missing_mesh");
    let text = one_geometry(r#"<mesh filename="meshes/nowhere.stl"/>"#);
    let e = RobotModel::from_urdf_str_with(&text, SRC, Some(&dir), &Default::default()).unwrap_err();
    let msg = e.to_string();
    let expected = dir.join("meshes/nowhere.stl");
    assert!(
        matches!(e, KinematicsError::MeshNotFound { ref link, ref uri, ref searched, .. }
            if link == "body" && uri == "meshes/nowhere.stl" && searched.contains(&expected.display().to_string())),
        "{e:?}"
    );
    names(
        &msg,
        &[SRC, "`body`", "meshes/nowhere.stl", &expected.display().to_string()],
    );

    // A package:// URI lists every candidate (the URDF folder and its parents).
    let text = one_geometry(r#"<mesh filename="package://no_such_pkg/meshes/x.stl"/>"#);
    let e = RobotModel::from_urdf_str_with(&text, SRC, Some(&dir), &Default::default()).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, KinematicsError::MeshNotFound { .. }), "{e:?}");
    let in_dir = dir.join("no_such_pkg/meshes/x.stl").display().to_string();
    let in_parent = dir
        .parent()
        .unwrap()
        .join("no_such_pkg/meshes/x.stl")
        .display()
        .to_string();
    names(&msg, &["package://no_such_pkg/meshes/x.stl", &in_dir, &in_parent]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn empty_robot_has_no_links() {
    let (e, msg) = fail(r#"<robot name="r"></robot>"#);
    assert!(
        matches!(e, KinematicsError::NoLinks { ref source_name } if source_name == SRC),
        "{e:?}"
    );
    names(&msg, &[SRC, "<link>"]);
}

fn two_dof() -> RobotModel {
    load(&mimic_robot("", "")).unwrap()
}

#[test]
fn fk_with_a_wrong_length_configuration() {
    let m = two_dof();
    assert_eq!(m.dof(), 3);
    let mut poses = m.pose_buffer();
    let e = m.fk(&[0.0, 0.0], &mut poses).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::DimensionMismatch {
                expected: 3,
                got: 2,
                ..
            }
        ),
        "{e:?}"
    );
    names(&e.to_string(), &["expected 3", "got 2"]);

    let e = m.fk(&[0.0; 4], &mut poses).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::DimensionMismatch {
                expected: 3,
                got: 4,
                ..
            }
        ),
        "{e:?}"
    );

    // Wrong pose buffer.
    let mut short = vec![nalgebra::Isometry3::identity(); 2];
    let e = m.fk(&[0.0; 3], &mut short).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::DimensionMismatch {
                expected: 4,
                got: 2,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn fk_with_a_nan() {
    let m = two_dof();
    let mut poses = m.pose_buffer();
    let e = m.fk(&[0.0, f64::NAN, 0.0], &mut poses).unwrap_err();
    assert!(
        matches!(e, KinematicsError::NonFinite { index: 1, ref name, value, .. } if name == "j2" && value.is_nan()),
        "{e:?}"
    );
    names(&e.to_string(), &["j2", "NaN"]);

    let e = m.fk(&[0.0, 0.0, f64::INFINITY], &mut poses).unwrap_err();
    assert!(matches!(e, KinematicsError::NonFinite { index: 2, .. }), "{e:?}");
}

#[test]
fn unknown_builtin_robot() {
    let e = RobotModel::builtin("nope").unwrap_err();
    assert!(
        matches!(e, KinematicsError::UnknownRobot { ref name, .. } if name == "nope"),
        "{e:?}"
    );
    names(&e.to_string(), &["`nope`", "panda", "fetch"]);
}

// ---------------------------------------------------------------------------------------------
// Inputs the loader accepted although the model it built cannot be evaluated or checked.
// ---------------------------------------------------------------------------------------------

/// Loads `text`; if the loader accepts it, FK at the neutral configuration must work and give
/// finite poses, and every collision shape must have a finite bounding box.
fn accepted_model_is_usable(text: &str) -> Result<(), String> {
    let m = match load(text) {
        Ok(m) => m,
        Err(_) => return Ok(()),
    };
    let q = m.neutral_configuration();
    let mut poses = m.pose_buffer();
    m.fk(&q, &mut poses)
        .map_err(|e| format!("accepted, but fk(neutral_configuration() = {q:?}) fails: {e}"))?;
    for (l, p) in m.links().iter().zip(&poses) {
        if !p
            .translation
            .vector
            .iter()
            .chain(p.rotation.coords.iter())
            .all(|v| v.is_finite())
        {
            return Err(format!(
                "accepted, but link `{}` has a non-finite pose at q = {q:?}: {p:?}",
                l.name
            ));
        }
    }
    for (i, l) in m.links().iter().enumerate() {
        if let Some(s) = m.link_shape(i) {
            let aabb = s.shape.compute_local_aabb();
            if !(aabb.mins.is_finite() && aabb.maxs.is_finite()) {
                return Err(format!(
                    "accepted, but link `{}` has an unbounded collision shape: {aabb:?}",
                    l.name
                ));
            }
        }
    }
    Ok(())
}

#[test]
fn limits_infinite_on_the_same_side_are_rejected() {
    // `lower = upper = -inf`: no finite position at all. neutral_configuration() gives -inf.
    for (lower, upper) in [("-inf", "-inf"), ("1e400", "1e400")] {
        let text = one_joint(
            "revolute",
            &format!(r#"<axis xyz="0 0 1"/><limit lower="{lower}" upper="{upper}" effort="1" velocity="1"/>"#),
        );
        let r = accepted_model_is_usable(&text);
        assert!(r.is_ok(), "lower={lower} upper={upper}: {}", r.unwrap_err());
        let (e, msg) = fail(&text);
        assert!(
            matches!(
                e,
                KinematicsError::InvalidValue { .. } | KinematicsError::InvertedLimits { .. }
            ),
            "{e:?}"
        );
        names(&msg, &[SRC, "`j1`"]);
    }
}

#[test]
fn mimic_chain_whose_multiplier_overflows_is_rejected() {
    // Each multiplier is finite; composed through the chain j3 → j2 → j1 it is 1e400 = inf, and
    // fk then computes inf · 0 = NaN for j3.
    let text = mimic_robot(
        r#"<mimic joint="j1" multiplier="1e200"/>"#,
        r#"<mimic joint="j2" multiplier="1e200"/>"#,
    );
    let r = accepted_model_is_usable(&text);
    assert!(r.is_ok(), "{}", r.unwrap_err());
    let (e, msg) = fail(&text);
    assert!(
        matches!(e, KinematicsError::BadMimic { ref joint, .. } if joint == "j3"),
        "{e:?}"
    );
    names(&msg, &[SRC, "`j3`"]);
}

#[test]
fn geometry_too_large_for_f32_collision_shapes_is_rejected() {
    // Finite as f64, but parry shapes are f32: 1e300 and 1e39 become infinite.
    for geometry in [r#"<box size="1e300 1 1"/>"#, r#"<cylinder radius="1" length="1e39"/>"#] {
        let text = one_geometry(geometry);
        let r = accepted_model_is_usable(&text);
        assert!(r.is_ok(), "{geometry}: {}", r.unwrap_err());
        let (e, msg) = fail(&text);
        assert!(matches!(e, KinematicsError::InvalidValue { .. }), "{geometry}: {e:?}");
        names(&msg, &[SRC, "`body`"]);
    }
}

#[test]
fn urdf_1_2_limit_without_effort_loads() {
    // URDF 1.2: omitted limits mean "no limit" (urdf-rs fills in inf). The model documents that
    // an unspecified effort or velocity is stored as +inf, so this must load.
    let text = one_joint(
        "revolute",
        r#"<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="2"/>"#,
    )
    .replace(r#"<robot name="r">"#, r#"<robot name="r" version="1.2">"#);
    let m = load(&text).unwrap_or_else(|e| panic!("a valid URDF 1.2 joint is rejected: {e}"));
    assert_eq!(m.lower(), [-1.0]);
    assert_eq!(m.upper(), [1.0]);
    assert_eq!(m.velocity_limits(), [2.0]);
    assert_eq!(m.effort_limits(), [f64::INFINITY]);
}
