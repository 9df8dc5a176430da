//! Retraction ([`StateValidator::retract`] for [`RobotValidity`]): a state whose links sink
//! into obstacles, pushed out along the contact normals through the contact points'
//! Jacobians.

use hearth_kinematics::{to_pose, to_vector};
use nalgebra::{Point3, Vector3};

#[cfg(doc)]
use super::StateValidator;
use super::{RobotValidity, TOOL_STEP_DAMPING};

/// Scratch of a retraction, sized for the chain once: the damped normal equations
/// `(JᵀJ + λ²I) Δq = Jᵀe` of the contact rows, so that no round allocates.
#[derive(Clone)]
pub(super) struct RetractScratch {
    /// `JᵀJ + λ²I`, row-major, `dof × dof`; its Cholesky factor after a solve.
    normal: Vec<f64>,
    /// `Jᵀe`, then the joint step.
    rhs: Vec<f64>,
}

impl RetractScratch {
    pub(super) fn new(dof: usize) -> Self {
        Self {
            normal: vec![0.0; dof * dof],
            rhs: vec![0.0; dof],
        }
    }
}

impl RobotValidity {
    /// [`StateValidator::retract`]: up to `rounds` rounds, each finding the first touching
    /// part of every link, asking the obstacle for the contact ([`Obstacles::contact`]) and
    /// taking one damped least-squares joint step that moves every contact point
    /// `clearance` beyond its depth along its normal, away from the obstacle. Rounds stop
    /// early once no link touches an obstacle. The result is then checked as any state is.
    /// Each round's obstacle pass counts as a check.
    ///
    /// [`Obstacles::contact`]: crate::obstacles::Obstacles::contact
    pub(super) fn retract_state(&mut self, q: &[f64], clearance: f64, rounds: usize, out: &mut [f64]) -> bool {
        let dof = self.chain.dof();
        if dof > 32 || q.len() != dof || out.len() != dof || !clearance.is_finite() || clearance < 0.0 {
            return false;
        }
        out.copy_from_slice(q);
        for _ in 0..rounds {
            self.checks += 1;
            if !out.iter().all(|v| v.is_finite()) || !self.update_poses(out) {
                return false;
            }
            self.retract.normal.fill(0.0);
            self.retract.rhs.fill(0.0);
            let mut contacts = 0;
            for g in 0..self.geometric.len() {
                let l = self.geometric[g];
                // Links and parts whose bounding balls are clear touch nothing: the exact
                // tests run on the others alone (the answer is `parts_hit`'s).
                let ball =
                    |c: &Point3<f64>, r: f64| self.obstacles.ball_hits(to_vector(&(self.poses[l] * c)), r as f32);
                if self.broad.radius[l] <= 0.0 || !ball(&self.broad.local_center[l], self.broad.radius[l]) {
                    continue;
                }
                let hit = self.broad.part_range[l].clone().find_map(|k| {
                    let (c, r) = self.broad.parts[k];
                    if !ball(&c, r) {
                        return None;
                    }
                    self.part_hits(l, k).map(|id| (k, id))
                });
                let Some((k, id)) = hit else {
                    continue;
                };
                let (shape, at) = &self.broad.part_shape[k];
                let Some(c) = self
                    .obstacles
                    .contact(id, shape.as_ref(), &to_pose(&(self.poses[l] * at)))
                else {
                    continue;
                };
                let p = Point3::new(f64::from(c.point.x), f64::from(c.point.y), f64::from(c.point.z));
                let n = Vector3::new(f64::from(c.normal.x), f64::from(c.normal.y), f64::from(c.normal.z));
                let local = self.poses[l].inverse_transform_point(&p).coords;
                if self
                    .model
                    .jacobian(&self.poses, &self.chain, l, &local, &mut self.tool_jacobian)
                    .is_err()
                {
                    return false;
                }
                // The contact's row: how fast each joint moves the point along the normal.
                let mut row = [0.0; 32];
                for (j, r) in row.iter_mut().enumerate().take(dof) {
                    *r = n.dot(&self.tool_jacobian.fixed_view::<3, 1>(0, j));
                }
                if row[..dof].iter().all(|r| r.abs() < 1e-9) {
                    continue; // a link the chain does not move
                }
                // Away from the obstacle, through the depth and `clearance` beyond.
                let target = -(f64::from(-c.distance).max(0.0) + clearance);
                for a in 0..dof {
                    self.retract.rhs[a] += row[a] * target;
                    for b in 0..dof {
                        self.retract.normal[a * dof + b] += row[a] * row[b];
                    }
                }
                contacts += 1;
            }
            if contacts == 0 {
                break;
            }
            for d in 0..dof {
                self.retract.normal[d * dof + d] += TOOL_STEP_DAMPING * TOOL_STEP_DAMPING;
            }
            if !solve_positive_definite(&mut self.retract.normal, &mut self.retract.rhs, dof) {
                return false;
            }
            for (o, d) in out.iter_mut().zip(&self.retract.rhs) {
                *o += d;
            }
            self.chain.clamp(out);
        }
        use super::StateValidator as _;
        self.is_valid(out)
    }
}

/// Solves `a x = b` in place for a symmetric positive definite `n × n` matrix `a`
/// (row-major): Cholesky, then the two triangular solves; `x` replaces `b`, the factor `a`'s
/// lower triangle. False when `a` is not positive definite.
fn solve_positive_definite(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * n + k] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k * n + i] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::solve_positive_definite;

    #[test]
    fn the_solver_inverts_a_positive_definite_matrix_and_refuses_others() {
        let m = [4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0];
        let x = [1.0, -2.0, 0.5];
        let mut b: Vec<f64> = (0..3).map(|i| (0..3).map(|k| m[i * 3 + k] * x[k]).sum()).collect();
        let mut a = m.to_vec();
        assert!(solve_positive_definite(&mut a, &mut b, 3));
        for (got, want) in b.iter().zip(x) {
            assert!((got - want).abs() < 1e-12, "{got} against {want}");
        }
        let mut singular = vec![1.0, 1.0, 1.0, 1.0];
        assert!(!solve_positive_definite(&mut singular, &mut [1.0, 2.0], 2));
        let mut nan = vec![f64::NAN];
        assert!(!solve_positive_definite(&mut nan, &mut [1.0], 1));
    }
}
