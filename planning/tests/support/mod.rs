//! Test data shared by the problem-file tests.

/// A minimal valid set with one problem of each obstacle kind.
pub const GOOD: &str = r#"{"robot": "toy", "family": "unit", "joint_names": ["j1", "j2"],
 "problems": [{"id": 5, "valid": true,
  "obstacles": [
   {"kind": "box", "center": [1, 0, 0], "half_extents": [0.1, 0.2, 0.3], "quat_xyzw": [0, 0, 0, 1], "name": "b"},
   {"kind": "sphere", "center": [0, 1, 0], "radius": 0.2},
   {"kind": "cylinder", "center": [0, 0, 1], "radius": 0.1, "half_length": 0.5, "quat_xyzw": [0, 0, 0, 1]}],
  "start": [0, 0], "goals": [[1, 1], [2, 2]]}]}"#;
