//! Fuzzing the URDF loader with mutated text: whatever the bytes, `RobotModel::from_urdf_str`
//! must return (never panic), and a model it accepts must be internally consistent.
//!
//! Cases: 300 by default, or `PROPTEST_CASES`. Failing inputs are printed (not persisted).

use std::path::PathBuf;
use std::sync::OnceLock;

use hearth_kinematics::{JointKind, LoadOptions, MeshCollision, RobotModel};
use proptest::prelude::*;
use proptest::test_runner::Config;

mod common;

/// A valid robot using every supported joint kind, a mimic (and a mimic of a mimic), every
/// primitive geometry, inertials, dynamics, materials and a branch.
const BASE: &str = r#"<?xml version="1.0"?>
<robot name="fuzzbot">
  <material name="grey"><color rgba="0.5 0.5 0.5 1.0"/></material>
  <link name="base">
    <inertial><origin xyz="0 0 0.05" rpy="0 0 0"/><mass value="2.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.02"/></inertial>
    <visual><origin xyz="0 0 0.05"/><geometry><box size="0.3 0.3 0.1"/></geometry><material name="grey"/></visual>
    <collision><origin xyz="0 0 0.05" rpy="0 0 0"/><geometry><box size="0.3 0.3 0.1"/></geometry></collision>
  </link>
  <link name="turret">
    <collision><origin xyz="0 0 0.1"/><geometry><cylinder radius="0.08" length="0.2"/></geometry></collision>
  </link>
  <link name="upper_arm">
    <inertial><mass value="1.2"/><inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial>
    <collision><origin xyz="0 0 0.2" rpy="0.1 -0.2 0.3"/><geometry><cylinder radius="0.04" length="0.4"/></geometry></collision>
    <collision><origin xyz="0 0 0.4"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="slider">
    <collision><geometry><box size="0.05 0.05 0.2"/></geometry></collision>
  </link>
  <link name="wrist">
    <collision><geometry><sphere radius="0.04"/></geometry></collision>
  </link>
  <link name="tool"/>
  <link name="finger_left"><collision><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <link name="finger_right"><collision><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <link name="finger_tip"><visual><geometry><sphere radius="0.005"/></geometry></visual></link>
  <link name="sensor"><visual><geometry><cylinder radius="0.01" length="0.02"/></geometry></visual></link>

  <joint name="pan" type="continuous">
    <origin xyz="0 0 0.1" rpy="0 0 0"/><parent link="base"/><child link="turret"/><axis xyz="0 0 1"/>
    <limit effort="20" velocity="1.5"/><dynamics damping="0.1" friction="0.01"/>
  </joint>
  <joint name="shoulder" type="revolute">
    <origin xyz="0 0 0.2" rpy="0 0 0"/><parent link="turret"/><child link="upper_arm"/><axis xyz="0 1 0"/>
    <limit lower="-1.57" upper="2.0" effort="30" velocity="1.0"/>
  </joint>
  <joint name="extend" type="prismatic">
    <origin xyz="0 0 0.45" rpy="0 0 0"/><parent link="upper_arm"/><child link="slider"/><axis xyz="0 0 1"/>
    <limit lower="0.0" upper="0.3" effort="100" velocity="0.2"/>
  </joint>
  <joint name="wrist_roll" type="revolute">
    <origin xyz="0 0 0.1" rpy="0 0.5 0"/><parent link="slider"/><child link="wrist"/><axis xyz="1 0 0"/>
    <limit lower="-2.9" upper="2.9" effort="5" velocity="3.0"/>
  </joint>
  <joint name="tool_mount" type="fixed">
    <origin xyz="0 0 0.05" rpy="3.14159 0 0"/><parent link="wrist"/><child link="tool"/>
  </joint>
  <joint name="finger_left_joint" type="prismatic">
    <origin xyz="0 0.02 0.02"/><parent link="tool"/><child link="finger_left"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" effort="10" velocity="0.1"/>
  </joint>
  <joint name="finger_right_joint" type="prismatic">
    <origin xyz="0 -0.02 0.02"/><parent link="tool"/><child link="finger_right"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="0.04" effort="10" velocity="0.1"/>
    <mimic joint="finger_left_joint" multiplier="1" offset="0"/>
  </joint>
  <joint name="finger_tip_joint" type="revolute">
    <origin xyz="0 0 0.05"/><parent link="finger_right"/><child link="finger_tip"/><axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/>
    <mimic joint="finger_right_joint" multiplier="-2.0" offset="0.1"/>
  </joint>
  <joint name="sensor_mount" type="fixed">
    <origin xyz="0.1 0 0.05" rpy="0 0 1.57"/><parent link="base"/><child link="sensor"/>
  </joint>
</robot>
"#;

/// Characters a single-character mutation writes.
const CHARS: &[u8] = b"<>/\"= -0.9eNn";

/// Tokens a number is replaced with.
const NUMBERS: &[&str] = &[
    "nan", "NaN", "inf", "-inf", "-1e309", "1e400", "0", "-0", "1e-320", "", "--1", "1.2.3",
];

#[derive(Clone, Debug)]
enum Mutation {
    /// Delete `len` bytes at `at`.
    Delete { at: usize, len: usize },
    /// Copy `len` bytes from `from` and insert them at `to`.
    Duplicate { from: usize, len: usize, to: usize },
    /// Overwrite the byte at `at` with `CHARS[c]`.
    Replace { at: usize, c: usize },
    /// Keep only the first `keep` bytes.
    Truncate { keep: usize },
    /// Swap two ranges of `len` bytes (the second one moved past the first).
    Swap { a: usize, b: usize, len: usize },
    /// Replace the `which`-th number in the text with `NUMBERS[token]`.
    Number { which: usize, token: usize },
    /// Replace the `which`-th `name="…"`/`link="…"`/`joint="…"` value with the `with`-th one
    /// (duplicates, dangling references, cycles, several parents, mimic loops).
    Name { which: usize, with: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let pos = any::<usize>();
    prop_oneof![
        1 => (pos, 1usize..64).prop_map(|(at, len)| Mutation::Delete { at, len }),
        1 => (pos, 1usize..128, pos).prop_map(|(from, len, to)| Mutation::Duplicate { from, len, to }),
        2 => (pos, 0..CHARS.len()).prop_map(|(at, c)| Mutation::Replace { at, c }),
        1 => pos.prop_map(|keep| Mutation::Truncate { keep }),
        1 => (pos, pos, 1usize..48).prop_map(|(a, b, len)| Mutation::Swap { a, b, len }),
        4 => (pos, 0..NUMBERS.len()).prop_map(|(which, token)| Mutation::Number { which, token }),
        3 => (pos, pos).prop_map(|(which, with)| Mutation::Name { which, with }),
    ]
}

/// Byte ranges of the numbers in `text` (a sign, digits, a dot and an exponent).
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (text[i] == b'-' && text.get(i + 1).is_some_and(|c| c.is_ascii_digit() || *c == b'.'));
        let inside_name = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_');
        if starts && !inside_name {
            let start = i;
            i += 1;
            while i < text.len() && (text[i].is_ascii_digit() || matches!(text[i], b'.' | b'e' | b'E' | b'-' | b'+')) {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of the values of `name=`, `link=` and `joint=` attributes.
fn names(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for key in [&b"name=\""[..], b"link=\"", b"joint=\""] {
        let mut i = 0;
        while i + key.len() <= text.len() {
            if &text[i..i + key.len()] == key {
                let start = i + key.len();
                if let Some(len) = text[start..].iter().position(|&c| c == b'"') {
                    out.push((start, start + len));
                }
                i = start;
            } else {
                i += 1;
            }
        }
    }
    out.sort_unstable();
    out
}

fn apply(text: &mut Vec<u8>, m: &Mutation) {
    let n = text.len();
    if n == 0 {
        return;
    }
    match *m {
        Mutation::Delete { at, len } => {
            let at = at % n;
            let end = (at + len).min(n);
            text.drain(at..end);
        }
        Mutation::Duplicate { from, len, to } => {
            let from = from % n;
            let end = (from + len).min(n);
            let piece = text[from..end].to_vec();
            let to = to % (n + 1);
            text.splice(to..to, piece);
        }
        Mutation::Replace { at, c } => text[at % n] = CHARS[c],
        Mutation::Truncate { keep } => text.truncate(keep % n),
        Mutation::Swap { a, b, len } => {
            let (mut a, mut b) = (a % n, b % n);
            if a > b {
                std::mem::swap(&mut a, &mut b);
            }
            let len = len.min(b - a).min(n - b);
            if len == 0 {
                return;
            }
            let first = text[a..a + len].to_vec();
            let second = text[b..b + len].to_vec();
            text[a..a + len].copy_from_slice(&second);
            text[b..b + len].copy_from_slice(&first);
        }
        Mutation::Number { which, token } => {
            let spans = numbers(text);
            if spans.is_empty() {
                return;
            }
            let (s, e) = spans[which % spans.len()];
            text.splice(s..e, NUMBERS[token].bytes());
        }
        Mutation::Name { which, with } => {
            let spans = names(text);
            if spans.is_empty() {
                return;
            }
            let (s, e) = spans[which % spans.len()];
            let (s2, e2) = spans[with % spans.len()];
            let value = text[s2..e2].to_vec();
            text.splice(s..e, value);
        }
    }
}

/// Everything a model the loader accepted must satisfy.
fn check_model(m: &RobotModel, text: &str) -> Result<(), TestCaseError> {
    let links = m.links();
    let joints = m.joints();
    prop_assert!(!links.is_empty());
    prop_assert_eq!(m.root(), 0);
    prop_assert!(links[0].parent_joint.is_none(), "the root has no parent joint");
    prop_assert_eq!(joints.len(), links.len() - 1, "a tree has one joint per non-root link");

    // Joints: valid indices, parents before children, each child's parent joint is this one.
    for (ji, j) in joints.iter().enumerate() {
        prop_assert!(
            j.parent < links.len() && j.child < links.len(),
            "joint {}: bad link index",
            j.name
        );
        prop_assert!(j.parent < j.child, "joint {}: links are not parents-first", j.name);
        prop_assert_eq!(
            links[j.child].parent_joint,
            Some(ji),
            "joint {}: child link disagrees",
            &j.name
        );
        prop_assert!((j.axis.norm() - 1.0).abs() < 1e-9, "joint {}: axis not unit", j.name);
        prop_assert!(
            j.origin.translation.vector.iter().all(|v| v.is_finite()),
            "joint {}: origin",
            j.name
        );
        prop_assert!(
            j.origin.rotation.coords.iter().all(|v| v.is_finite()),
            "joint {}: rotation",
            j.name
        );
        prop_assert!(
            j.limits.lower <= j.limits.upper || j.limits.lower.is_nan(),
            "joint {}: inverted limits",
            j.name
        );
        prop_assert_eq!(m.joint_index(&j.name).ok(), Some(ji));
        if let Some(mm) = j.mimic {
            prop_assert!(
                mm.joint < joints.len() && mm.joint != ji,
                "joint {}: bad mimic target",
                j.name
            );
            prop_assert!(
                joints[mm.joint].variable.is_some(),
                "joint {}: mimics a non-variable",
                j.name
            );
            prop_assert!(j.variable.is_none());
            prop_assert!(mm.multiplier.is_finite() && mm.offset.is_finite());
        }
        if j.kind == JointKind::Fixed {
            prop_assert!(j.variable.is_none() && j.mimic.is_none());
        }
    }
    for (i, l) in links.iter().enumerate() {
        prop_assert_eq!(m.link_index(&l.name).ok(), Some(i), "link {}: name lookup", &l.name);
        if i > 0 {
            let pj = l.parent_joint;
            prop_assert!(
                pj.is_some_and(|j| j < joints.len() && joints[j].child == i),
                "link {}",
                &l.name
            );
        }
    }

    // Variables.
    let dof = m.dof();
    prop_assert_eq!(dof, m.variable_names().len());
    prop_assert_eq!(dof, m.variables().len());
    prop_assert_eq!(dof, m.lower().len());
    prop_assert_eq!(dof, m.upper().len());
    prop_assert_eq!(dof, m.velocity_limits().len());
    prop_assert_eq!(dof, m.effort_limits().len());
    for (k, (&ji, name)) in m.variables().iter().zip(m.variable_names()).enumerate() {
        prop_assert!(ji < joints.len());
        prop_assert_eq!(&joints[ji].name, name);
        prop_assert_eq!(joints[ji].variable, Some(k));
        prop_assert!(joints[ji].kind.is_movable());
        prop_assert!(
            m.lower()[k] <= m.upper()[k],
            "variable {}: {} > {}",
            name,
            m.lower()[k],
            m.upper()[k]
        );
        prop_assert!(m.velocity_limits()[k] > 0.0 && m.effort_limits()[k] > 0.0);
    }
    let movable_non_mimic = joints
        .iter()
        .filter(|j| j.kind.is_movable() && j.mimic.is_none())
        .count();
    prop_assert_eq!(dof, movable_non_mimic);

    // FK at the neutral configuration: succeeds, finite, and agrees with link_pose.
    let q = m.neutral_configuration();
    prop_assert_eq!(q.len(), dof);
    prop_assert!(
        m.within_limits(&q, 0.0),
        "neutral configuration outside the limits: {:?}",
        q
    );
    let mut poses = m.pose_buffer();
    if let Err(e) = m.fk(&q, &mut poses) {
        return Err(TestCaseError::fail(format!(
            "fk on the neutral configuration {q:?} failed: {e}\n{text}"
        )));
    }
    for (l, p) in links.iter().zip(&poses) {
        let finite = p
            .translation
            .vector
            .iter()
            .chain(p.rotation.coords.iter())
            .all(|v| v.is_finite());
        prop_assert!(finite, "link {}: non-finite pose {:?}\n{}", l.name, p, text);
    }
    for (i, p) in poses.iter().enumerate() {
        let single = m.link_pose(&q, i).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert!((single.translation.vector - p.translation.vector).norm() < 1e-9);
        prop_assert!(single.rotation.angle_to(&p.rotation) < 1e-9);
    }
    for (i, _) in links.iter().enumerate() {
        if let Some(s) = m.link_shape(i) {
            let aabb = s.shape.compute_local_aabb();
            prop_assert!(
                aabb.mins.is_finite() && aabb.maxs.is_finite(),
                "link {}: shape",
                links[i].name
            );
        }
    }
    Ok(())
}

fn config() -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300);
    Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }
}

#[test]
fn base_robot_is_valid() {
    let m = RobotModel::from_urdf_str(BASE, None).unwrap();
    assert_eq!(m.links().len(), 10);
    assert_eq!(
        m.variable_names(),
        ["pan", "shoulder", "extend", "wrist_roll", "finger_left_joint"]
    );
    let tip = &m.joints()[m.joint_index("finger_tip_joint").unwrap()];
    let mm = tip.mimic.expect("mimic of a mimic resolves");
    assert_eq!(m.joints()[mm.joint].name, "finger_left_joint");
    assert!((mm.multiplier + 2.0).abs() < 1e-12 && (mm.offset - 0.1).abs() < 1e-12);
    check_model(&m, BASE).unwrap();
    assert!(numbers(BASE.as_bytes()).len() > 100);
    assert!(names(BASE.as_bytes()).len() > 40);
}

/// [`BASE`] with meshes: one beside the upper arm's cylinder and sphere (a link's compound of
/// several elements, which a convex decomposition or a triangle mesh must not nest in) and one
/// alone as the wrist's collision, read from [`mesh_dir`].
fn base_with_meshes() -> String {
    BASE.replacen(
        r#"<collision><origin xyz="0 0 0.4"/><geometry><sphere radius="0.05"/></geometry></collision>"#,
        r#"<collision><origin xyz="0 0 0.4"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0 0 0.3"/><geometry><mesh filename="cube.obj" scale="0.1 0.1 0.1"/></geometry></collision>"#,
        1,
    )
    .replacen(
        r#"<link name="wrist">
    <collision><geometry><sphere radius="0.04"/></geometry></collision>"#,
        r#"<link name="wrist">
    <collision><geometry><mesh filename="cube.obj" scale="0.08 0.08 0.08"/></geometry></collision>"#,
        1,
    )
}

/// A folder (made once per process) holding `cube.obj`, the cube [-0.5, 0.5]³.
fn mesh_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("hearth_urdf_fuzz_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("cube.obj"), common::cube_obj()).unwrap();
        dir
    })
}

const MESH_MODES: [MeshCollision; 3] = [
    MeshCollision::ConvexHull,
    MeshCollision::ConvexDecomposition,
    MeshCollision::TriMesh,
];

#[test]
fn base_robot_with_meshes_is_valid_in_every_mesh_mode() {
    let text = base_with_meshes();
    assert_eq!(text.matches("<mesh").count(), 2);
    for mode in MESH_MODES {
        let opts = LoadOptions {
            mesh_collision: mode,
            ..Default::default()
        };
        let m = RobotModel::from_urdf_str_with(&text, "fuzz.urdf", Some(mesh_dir()), &opts).unwrap();
        check_model(&m, &text).unwrap();
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn mutated_urdf_with_meshes_never_panics_in_any_mesh_mode(
        mutations in prop::collection::vec(mutation(), 1..5),
        mode in 0..MESH_MODES.len(),
    ) {
        let mut bytes = base_with_meshes().into_bytes();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let opts = LoadOptions {
            mesh_collision: MESH_MODES[mode],
            ..Default::default()
        };
        let result =
            std::panic::catch_unwind(|| RobotModel::from_urdf_str_with(&text, "fuzz.urdf", Some(mesh_dir()), &opts));
        match result {
            Err(_) => prop_assert!(false, "from_urdf_str_with ({:?}) panicked on:\n{}", MESH_MODES[mode], text),
            Ok(Ok(model)) => check_model(&model, &text)?,
            Ok(Err(e)) => prop_assert!(!e.to_string().is_empty()),
        }
    }

    #[test]
    fn mutated_urdf_never_panics_and_accepted_models_are_consistent(
        mutations in prop::collection::vec(mutation(), 1..5)
    ) {
        let mut bytes = BASE.as_bytes().to_vec();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let result = std::panic::catch_unwind(|| RobotModel::from_urdf_str(&text, None));
        match result {
            Err(_) => prop_assert!(false, "from_urdf_str panicked on:\n{}", text),
            Ok(Ok(model)) => check_model(&model, &text)?,
            Ok(Err(e)) => {
                // Every error renders, and names where it came from.
                let msg = e.to_string();
                prop_assert!(!msg.is_empty());
            }
        }
    }
}
