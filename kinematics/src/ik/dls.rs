//! The damped-least-squares (Levenberg–Marquardt) IK step.

use nalgebra::{Matrix3, Matrix6, Matrix6xX, Vector3, Vector6};

/// One damped-least-squares step: `dq = Jᵀ (J Jᵀ + λ² I)⁻¹ e` over the first `rows` rows of
/// the Jacobian `j` (3: position only, 6: full pose; rows 0–2 linear, 3–5 angular, as
/// [`RobotModel::jacobian`](crate::RobotModel::jacobian) writes them), for the task-space
/// change `e` and the damping `lambda`. Writes the first `j.ncols()` entries of `dq`; returns
/// `false` if the damped normal matrix is singular or `dq` is not finite. Does not allocate.
///
/// ```
/// use hearth_kinematics::{damped_least_squares_step, Chain, RobotModel};
/// use nalgebra::{Matrix6xX, Vector3};
/// let panda = RobotModel::builtin("panda").unwrap();
/// let arm = Chain::named(&panda, "arm").unwrap();
/// let mut poses = panda.pose_buffer();
/// panda.fk(&panda.neutral_configuration(), &mut poses).unwrap();
/// let mut j = Matrix6xX::zeros(arm.dof());
/// panda.jacobian(&poses, &arm, arm.tip().unwrap(), &Vector3::zeros(), &mut j).unwrap();
/// // 1 mm up, orientation held.
/// let e = [0.0, 0.0, 0.001, 0.0, 0.0, 0.0];
/// let mut dq = [0.0; 7];
/// assert!(damped_least_squares_step(&j, 6, &e, 1e-2, &mut dq));
/// // The tip moves up by about that much (the damping shortens the step a little).
/// let moved = &j * nalgebra::DVector::from_row_slice(&dq);
/// assert!((moved[2] - 0.001).abs() < 5e-5 && moved[0].abs() < 1e-5 && moved[1].abs() < 1e-5);
/// ```
pub fn damped_least_squares_step(j: &Matrix6xX<f64>, rows: usize, e: &[f64; 6], lambda: f64, dq: &mut [f64]) -> bool {
    let n = j.ncols();
    let l2 = lambda * lambda;
    if rows == 3 {
        let mut a = Matrix3::<f64>::zeros();
        for c in 0..n {
            let col = Vector3::new(j[(0, c)], j[(1, c)], j[(2, c)]);
            a += col * col.transpose();
        }
        for d in 0..3 {
            a[(d, d)] += l2;
        }
        let Some(ch) = a.cholesky() else { return false };
        let y = ch.solve(&Vector3::new(e[0], e[1], e[2]));
        for (c, out) in dq.iter_mut().enumerate().take(n) {
            *out = j[(0, c)] * y[0] + j[(1, c)] * y[1] + j[(2, c)] * y[2];
        }
    } else {
        let mut a = Matrix6::<f64>::zeros();
        for c in 0..n {
            let col: Vector6<f64> = j.column(c).into_owned();
            a.ger(1.0, &col, &col, 1.0);
        }
        for d in 0..6 {
            a[(d, d)] += l2;
        }
        let Some(ch) = a.cholesky() else { return false };
        let y = ch.solve(&Vector6::from_row_slice(e));
        for (c, out) in dq.iter_mut().enumerate().take(n) {
            *out = j.column(c).dot(&y);
        }
    }
    dq.iter().all(|x| x.is_finite())
}
