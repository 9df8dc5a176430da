//! Load a built-in robot, run forward kinematics, and solve IK for the arm.
//!
//! `cargo run --release --example quickstart`

use hearth::kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
use rand::SeedableRng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let fetch = RobotModel::builtin("fetch")?; // or RobotModel::from_urdf_file("robot.urdf")?
    let mut poses = fetch.pose_buffer(); // one pose per link, reused
    fetch.fk(&fetch.neutral_configuration(), &mut poses)?; // no allocation
    let gripper = fetch.link_index("gripper_link")?;
    println!("gripper at {:?}", poses[gripper].translation.vector.as_slice());

    let arm = Chain::named(&fetch, "arm_with_torso")?; // torso + 7 arm joints
    let mut ik = IkSolver::new(arm, "gripper_link", IkSettings::default())?;
    let target = ik.tool_pose(&[0.2, 0.5, -0.3, 0.4, 1.2, 0.0, 0.8, 0.0])?;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
    let solution = ik.solve(&IkTarget::Pose(target), &[0.0; 8], &mut rng)?;
    println!("IK: {:?} ({} attempts)", solution.q, solution.attempts);

    assert!(solution.position_error <= 1e-3 && solution.orientation_error <= 1e-2);
    let reached = ik.tool_pose(&solution.q)?;
    assert!((reached.translation.vector - target.translation.vector).norm() <= 1e-3);
    Ok(())
}
