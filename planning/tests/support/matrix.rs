//! A built-in robot's self-collision matrix from 300 samples, computed once per test binary
//! and robot. Included by `#[path]` from the planners' and the allocation tests.

use std::sync::OnceLock;

use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};

/// The matrix of the built-in `robot` (`"panda"` or `"fetch"`).
pub fn matrix(robot: &str) -> SelfCollisionMatrix {
    static PANDA: OnceLock<SelfCollisionMatrix> = OnceLock::new();
    static FETCH: OnceLock<SelfCollisionMatrix> = OnceLock::new();
    let cell = match robot {
        "panda" => &PANDA,
        "fetch" => &FETCH,
        _ => panic!("no shared matrix for {robot}"),
    };
    cell.get_or_init(|| {
        SelfCollisionMatrix::compute(
            &RobotModel::builtin(robot).unwrap(),
            &SelfCollisionSettings {
                samples: 300,
                ..Default::default()
            },
        )
    })
    .clone()
}
