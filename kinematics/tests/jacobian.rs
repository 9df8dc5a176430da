//! The geometric Jacobian against central finite differences of forward kinematics.

use hearth_kinematics::{Chain, RobotModel};
use nalgebra::{Matrix6xX, Vector3};
use proptest::prelude::*;

fn check(model: &RobotModel, chain: &Chain, tip: usize, point: Vector3<f64>, q: &[f64]) -> Result<(), TestCaseError> {
    let mut poses = model.pose_buffer();
    model.fk(q, &mut poses).unwrap();
    let mut j = Matrix6xX::zeros(chain.dof());
    model.jacobian(&poses, chain, tip, &point, &mut j).unwrap();
    let h = 1e-6;
    for (col, &var) in chain.variables().iter().enumerate() {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[var] += h;
        qm[var] -= h;
        let pp = model.link_pose(&qp, tip).unwrap();
        let pm = model.link_pose(&qm, tip).unwrap();
        let lin = ((pp * nalgebra::Point3::from(point)) - (pm * nalgebra::Point3::from(point))) / (2.0 * h);
        let ang = (pp.rotation * pm.rotation.inverse()).scaled_axis() / (2.0 * h);
        for r in 0..3 {
            prop_assert!(
                (j[(r, col)] - lin[r]).abs() < 1e-6,
                "linear row {r} col {col}: {} vs {}",
                j[(r, col)],
                lin[r]
            );
            prop_assert!(
                (j[(r + 3, col)] - ang[r]).abs() < 1e-6,
                "angular row {r} col {col}: {} vs {}",
                j[(r + 3, col)],
                ang[r]
            );
        }
    }
    Ok(())
}

fn config(model: &RobotModel, unit: &[f64]) -> Vec<f64> {
    (0..model.dof())
        .map(|i| {
            let (lo, hi) = (model.lower()[i], model.upper()[i]);
            let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (-3.0, 3.0) };
            lo + (hi - lo) * unit[i % unit.len()]
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn panda_jacobian_matches_finite_differences(unit in prop::collection::vec(0.0f64..1.0, 8), px in -0.1f64..0.1, pz in 0.0f64..0.2) {
        let m = RobotModel::builtin("panda").unwrap();
        let arm = Chain::named(&m, "arm").unwrap();
        let q = config(&m, &unit);
        check(&m, &arm, m.link_index("panda_hand_tcp").unwrap(), Vector3::new(px, 0.0, pz), &q)?;
        // A link in the middle of the chain: later columns must be zero.
        check(&m, &arm, m.link_index("panda_link4").unwrap(), Vector3::zeros(), &q)?;
    }

    #[test]
    fn fetch_jacobian_with_prismatic_torso(unit in prop::collection::vec(0.0f64..1.0, 16)) {
        let m = RobotModel::builtin("fetch").unwrap();
        let arm = Chain::named(&m, "arm_with_torso").unwrap();
        let q = config(&m, &unit);
        check(&m, &arm, m.link_index("gripper_link").unwrap(), Vector3::new(0.05, 0.0, 0.0), &q)?;
    }

    #[test]
    fn all_joint_jacobian_every_builtin(unit in prop::collection::vec(0.0f64..1.0, 24)) {
        for robot in hearth_kinematics::BUILTIN_ROBOTS {
            let m = RobotModel::builtin(robot.name).unwrap();
            let all = Chain::all(&m);
            let q = config(&m, &unit);
            for tip in 0..m.links().len() {
                check(&m, &all, tip, Vector3::zeros(), &q)?;
            }
        }
    }
}

#[test]
fn mimic_finger_column_counts_the_multiplier() {
    // The Panda's right finger mimics the left: its Jacobian column for the finger variable
    // is along the right finger's own (negated) axis.
    let m = RobotModel::builtin("panda").unwrap();
    let all = Chain::all(&m);
    let mut poses = m.pose_buffer();
    m.fk(&m.neutral_configuration(), &mut poses).unwrap();
    let right = m.link_index("panda_rightfinger").unwrap();
    let left = m.link_index("panda_leftfinger").unwrap();
    let mut jr = Matrix6xX::zeros(all.dof());
    let mut jl = Matrix6xX::zeros(all.dof());
    m.jacobian(&poses, &all, right, &Vector3::zeros(), &mut jr).unwrap();
    m.jacobian(&poses, &all, left, &Vector3::zeros(), &mut jl).unwrap();
    let finger = all.dof() - 1;
    let lin_r = jr.fixed_view::<3, 1>(0, finger).into_owned();
    let lin_l = jl.fixed_view::<3, 1>(0, finger).into_owned();
    assert!((lin_r + lin_l).norm() < 1e-12 && lin_l.norm() > 0.99);
}

#[test]
fn wrong_jacobian_width_is_an_error() {
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let poses = m.pose_buffer();
    let mut j = Matrix6xX::zeros(3);
    assert!(m.jacobian(&poses, &arm, 1, &Vector3::zeros(), &mut j).is_err());
}
