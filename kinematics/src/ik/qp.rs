//! The joint-limit-constrained IK step as a small QP, solved by clarabel.
//!
//! `min ½ dqᵀ (JᵀJ + λ²I) dq − (Jᵀe)ᵀ dq   s.t.   max(lo − q, −s) ≤ dq ≤ min(hi − q, s)`
//!
//! The solver is built once per chain with a dense upper-triangular `P` and `A = [I; −I]`;
//! every iteration only overwrites `P`, the linear term and the bounds, so the symbolic
//! factorisation is reused.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};
use nalgebra::Matrix6xX;

pub(crate) struct QpStep {
    n: usize,
    solver: DefaultSolver<f64>,
    p_values: Vec<f64>,
    linear: Vec<f64>,
    bounds: Vec<f64>,
}

impl QpStep {
    pub(crate) fn new(n: usize) -> Option<Self> {
        let mut colptr = Vec::with_capacity(n + 1);
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        colptr.push(0);
        for c in 0..n {
            for r in 0..=c {
                rowval.push(r);
                nzval.push(if r == c { 1.0 } else { 0.0 });
            }
            colptr.push(rowval.len());
        }
        let p = CscMatrix::new(n, n, colptr, rowval, nzval);
        let mut a_col = Vec::with_capacity(n + 1);
        let mut a_row = Vec::with_capacity(2 * n);
        let mut a_val = Vec::with_capacity(2 * n);
        a_col.push(0);
        for c in 0..n {
            a_row.push(c);
            a_val.push(1.0);
            a_row.push(n + c);
            a_val.push(-1.0);
            a_col.push(a_row.len());
        }
        let a = CscMatrix::new(2 * n, n, a_col, a_row, a_val);
        let settings = DefaultSettings {
            verbose: false,
            presolve_enable: false,
            input_sparse_dropzeros: false,
            max_iter: 50,
            ..DefaultSettings::default()
        };
        let linear = vec![0.0; n];
        let bounds = vec![1.0; 2 * n];
        let cones = [NonnegativeConeT(2 * n)];
        let solver = DefaultSolver::new(&p, &linear, &a, &bounds, &cones, settings).ok()?;
        Some(Self {
            n,
            p_values: vec![0.0; n * (n + 1) / 2],
            solver,
            linear,
            bounds,
        })
    }

    /// Solves for `dq`; rows of `j` and `e` beyond `rows` are ignored. Returns `false` if the
    /// solver did not converge.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn step(
        &mut self,
        j: &Matrix6xX<f64>,
        rows: usize,
        e: &[f64; 6],
        lambda: f64,
        q: &[f64],
        lo: &[f64],
        hi: &[f64],
        max_step: f64,
        dq: &mut [f64],
    ) -> bool {
        let n = self.n;
        let mut k = 0;
        for c in 0..n {
            for r in 0..=c {
                let mut s = 0.0;
                for row in 0..rows {
                    s += j[(row, r)] * j[(row, c)];
                }
                if r == c {
                    s += lambda * lambda;
                }
                self.p_values[k] = s;
                k += 1;
            }
            let mut g = 0.0;
            for row in 0..rows {
                g += j[(row, c)] * e[row];
            }
            self.linear[c] = -g;
            self.bounds[c] = (hi[c] - q[c]).min(max_step).max(0.0);
            self.bounds[n + c] = (q[c] - lo[c]).min(max_step).max(0.0);
        }
        if self.solver.update_P(&self.p_values).is_err()
            || self.solver.update_q(&self.linear).is_err()
            || self.solver.update_b(&self.bounds).is_err()
        {
            return false;
        }
        self.solver.solve();
        match self.solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                dq.copy_from_slice(&self.solver.solution.x[..n]);
                dq.iter().all(|x| x.is_finite())
            }
            _ => false,
        }
    }
}
