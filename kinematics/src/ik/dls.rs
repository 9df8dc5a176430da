//! The damped-least-squares (Levenberg–Marquardt) IK step.

use nalgebra::{Matrix3, Matrix6, Matrix6xX, Vector3, Vector6};

/// `dq = Jᵀ (J Jᵀ + λ² I)⁻¹ e` over the first `rows` rows (3: position only, 6: full pose).
/// Returns `false` if the damped normal matrix is singular. Does not allocate.
pub(crate) fn step(j: &Matrix6xX<f64>, rows: usize, e: &[f64; 6], lambda: f64, dq: &mut [f64]) -> bool {
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
