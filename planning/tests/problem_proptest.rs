//! Property tests of the problem-file parsers: no input makes them panic, and whatever they
//! accept is a set the planners can use (finite values, unit quaternions, a scene that builds
//! with finite bounds).

use hearth_planning::obstacles::Obstacles;
use hearth_planning::problem::{JointsInfo, ObstacleSpec, ProblemError, ProblemSet};
use proptest::prelude::*;

mod support;
use support::GOOD;

const JOINTS: &str = r#"{"robot": "r", "joint_names": ["a", "b"], "lower": [-1, -1], "upper": [1, 1],
 "velocity": [1, 1], "acceleration": [2, 2], "continuous": [false, true],
 "notes": {"self_collision_allowed_pairs": [["l1", "l2"]]}}"#;

/// Pieces an edit splices in: JSON punctuation, literals, and numbers at the edges of what a
/// float holds.
const TOKENS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "\"",
    "-",
    "0",
    "1",
    ".",
    "e",
    "null",
    "true",
    "false",
    "\"box\"",
    "\"cone\"",
    "1e308",
    "-1e308",
    "3.4e38",
    "1e39",
    "1e-320",
    "-0",
    "123456789012345678901234567890",
    "[]",
    "{}",
    "[0, 0, 0, 0]",
    "[1, 0, 0, 0]",
    "[0, 0]",
    "\"valid\"",
    "\"id\": 5",
    "NaN",
    "\u{e9}",
];

/// Applies `edits` (position as a fraction of the length, what to do, which token) to `text`,
/// on character boundaries.
fn edit(text: &str, edits: &[(f64, u8, usize)]) -> String {
    let mut s: Vec<char> = text.chars().collect();
    for &(at, what, token) in edits {
        let i = ((at * s.len() as f64) as usize).min(s.len());
        let t: Vec<char> = TOKENS[token % TOKENS.len()].chars().collect();
        match what % 4 {
            0 => {
                s.splice(i..i, t);
            }
            1 if i < s.len() => {
                s.remove(i);
            }
            2 => {
                let end = (i + t.len()).min(s.len());
                s.splice(i..end, t);
            }
            _ => s.truncate(i),
        }
    }
    s.into_iter().collect()
}

/// What an accepted set must satisfy.
fn usable(set: &ProblemSet) -> Result<(), String> {
    set.validate().map_err(|e| format!("accepted but invalid: {e}"))?;
    for p in &set.problems {
        for o in &p.obstacles {
            let unit = |q: &[f64; 4]| (q.iter().map(|x| x * x).sum::<f64>().sqrt() - 1.0).abs() < 1e-9;
            let ok = match o {
                ObstacleSpec::Box { quat_xyzw, .. } | ObstacleSpec::Cylinder { quat_xyzw, .. } => unit(quat_xyzw),
                ObstacleSpec::Sphere { .. } => true,
            };
            if !ok {
                return Err(format!("quaternion not normalised: {o:?}"));
            }
        }
        let scene = p.scene();
        // What the loader accepts, the scene's own check accepts too.
        for o in scene.obstacles() {
            o.check()
                .map_err(|e| format!("obstacle {:?} fails its check: {e}", o.name))?;
        }
        if let Some(b) = scene.aabb()
            && !(b.mins.is_finite() && b.maxs.is_finite())
        {
            return Err(format!("scene bounds not finite: {b:?} for {:?}", p.obstacles));
        }
    }
    let again = ProblemSet::from_json_str(&serde_json::to_string(set).unwrap()).map_err(|e| e.to_string())?;
    if &again != set {
        return Err("does not survive a round trip".into());
    }
    Ok(())
}

/// A number for a size or coordinate: ordinary, zero, negative, huge or tiny.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -3.0..3.0f64,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => prop_oneof![Just(1e30), Just(3.5e38), Just(-1e300), Just(1e-320), Just(f64::MAX)],
    ]
}

fn num_json(x: f64) -> String {
    // Rust's shortest round-trip form; JSON reads it back exactly.
    format!("{x:e}")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn any_text_is_rejected_or_usable(text in "\\PC{0,300}") {
        if let Ok(set) = ProblemSet::from_json_str(&text) {
            prop_assert!(usable(&set).is_ok(), "{:?}", usable(&set));
        }
        let _ = JointsInfo::from_json_str(&text);
    }

    #[test]
    fn edited_sets_are_rejected_with_a_reason_or_usable(
        edits in prop::collection::vec((0.0..1.0f64, any::<u8>(), any::<usize>()), 1..5)
    ) {
        let text = edit(GOOD, &edits);
        match ProblemSet::from_json_str(&text) {
            Ok(set) => prop_assert!(usable(&set).is_ok(), "{:?}\n{text}", usable(&set)),
            Err(e) => {
                // Every error names where it was read from, and says what is wrong.
                let msg = e.to_string();
                prop_assert!(msg.contains("<string>") && msg.len() > 12, "{msg}");
                if let ProblemError::Invalid { field, .. } = &e {
                    prop_assert!(!field.is_empty(), "{msg}");
                }
            }
        }
        let text = edit(JOINTS, &edits);
        if let Ok(info) = JointsInfo::from_json_str(&text) {
            let n = info.joint_names.len();
            prop_assert!(info.lower.len() == n && info.upper.len() == n && info.velocity.len() == n, "{text}");
            prop_assert!(info.lower.iter().zip(&info.upper).all(|(l, u)| l.is_finite() && u.is_finite() && l <= u), "{text}");
        }
    }

    #[test]
    fn obstacles_of_any_size_and_orientation_are_rejected_or_usable(
        kind in 0usize..4,
        center in prop::array::uniform3(number()),
        sizes in prop::array::uniform3(number()),
        quat in prop::array::uniform4(number()),
    ) {
        let v = |a: &[f64]| format!("[{}]", a.iter().map(|&x| num_json(x)).collect::<Vec<_>>().join(", "));
        let obstacle = match kind {
            0 => format!(r#"{{"kind": "box", "center": {}, "half_extents": {}, "quat_xyzw": {}}}"#, v(&center), v(&sizes), v(&quat)),
            1 => format!(r#"{{"kind": "sphere", "center": {}, "radius": {}}}"#, v(&center), num_json(sizes[0])),
            2 => format!(
                r#"{{"kind": "cylinder", "center": {}, "radius": {}, "half_length": {}, "quat_xyzw": {}}}"#,
                v(&center), num_json(sizes[0]), num_json(sizes[1]), v(&quat)
            ),
            _ => format!(r#"{{"kind": "capsule", "center": {}, "radius": {}}}"#, v(&center), num_json(sizes[0])),
        };
        let text = format!(
            r#"{{"robot": "toy", "family": "unit", "joint_names": ["j1"],
              "problems": [{{"id": 1, "valid": true, "obstacles": [{obstacle}], "start": [0], "goals": [[1]]}}]}}"#
        );
        match ProblemSet::from_json_str(&text) {
            Ok(set) => prop_assert!(usable(&set).is_ok(), "{:?}\n{text}", usable(&set)),
            Err(e) => prop_assert!(
                matches!(&e, ProblemError::Invalid { field, .. } if field.starts_with("obstacles[0]")),
                "{e}\n{text}"
            ),
        }
    }
}

/// Sizes of -0 are not negative: they load, and make obstacles (parry refuses a sign bit on a
/// size); a quaternion a little off unit length is normalised once, so the set survives being
/// written and read again.
#[test]
fn negative_zero_sizes_and_nearly_unit_quaternions_load_and_round_trip() {
    let text = r#"{"robot": "toy", "family": "unit", "joint_names": ["j1"],
      "problems": [{"id": 1, "valid": true, "obstacles": [
        {"kind": "cylinder", "center": [0, 0, 0], "radius": -0.0, "half_length": -0.0, "quat_xyzw": [0, 0, 0.9960494029650668, -0.08895937776906854]},
        {"kind": "box", "center": [1, 0, 0], "half_extents": [-0.0, 0.1, 0.1], "quat_xyzw": [0, 0, 0, 1]},
        {"kind": "sphere", "center": [2, 0, 0], "radius": -0.0}],
      "start": [0], "goals": [[1]]}]}"#;
    let set = ProblemSet::from_json_str(text).unwrap();
    assert_eq!(usable(&set), Ok(()));
}
