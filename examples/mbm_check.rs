//! How many MotionBenchMaker start/goal configurations collide with the built-in robots'
//! collision geometry (the configurations are collision-free for the real robot meshes).
//!
//! `cargo run --release --example mbm_check -- panda [BENCH_DIR]` (default `../shared/bench`).
//! Self-collision uses the benchmark's allowed pairs plus adjacent links; fingers are held at
//! the real robots' widest opening.

use std::collections::BTreeMap;
use std::sync::Arc;

use hearth::kinematics::{Chain, DisabledReason, RobotModel, SelfCollisionMatrix};
use hearth::planning::RobotValidity;
use hearth::planning::problem::{JointsInfo, load_dir};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robot = std::env::args().nth(1).unwrap_or("panda".into());
    let bench = std::env::args().nth(2).unwrap_or("../shared/bench".into());
    let dir = format!("{bench}/mbm/{robot}");
    let m = RobotModel::builtin(&robot)?;
    let info = JointsInfo::load(format!("{dir}/joints.json"))?;
    let mut matrix = SelfCollisionMatrix::adjacent_only(&m);
    for [a, b] in &info.notes.self_collision_allowed_pairs {
        if let (Ok(a), Ok(b)) = (m.link_index(a), m.link_index(b)) {
            matrix.disable(a, b, DisabledReason::Never);
        }
    }
    let chain = Chain::new(&m, &info.joint_names)?;
    let (finger, opening) = if robot == "panda" {
        ("panda_finger_joint1", 0.04)
    } else {
        ("r_gripper_finger_joint", 0.05)
    };
    let mut reference = m.neutral_configuration();
    if let Some(var) = m.joint_index(finger).ok().and_then(|j| m.joints()[j].variable) {
        reference[var] = opening;
    }
    let mut stats: BTreeMap<String, usize> = BTreeMap::new();
    let (mut total, mut bad) = (0, 0);
    for set in load_dir(&dir)? {
        for problem in set.valid_problems() {
            let mut v = RobotValidity::new(chain.clone(), matrix.clone(), Arc::new(problem.scene()));
            v.set_reference(&reference)?;
            for q in std::iter::once(&problem.start).chain(&problem.goals) {
                total += 1;
                if let Some(contact) = v.explain(q) {
                    bad += 1;
                    *stats.entry(format!("{}: {contact}", set.family)).or_default() += 1;
                }
            }
        }
    }
    println!("{robot}: {bad} / {total} valid start/goal configurations collide with our geometry");
    for (k, v) in stats {
        println!("  {v:4}  {k}");
    }
    Ok(())
}
