//! Geometric Jacobians.

use nalgebra::{Isometry3, Matrix6xX, Vector3};

use crate::chain::Chain;
use crate::error::{KinematicsError, Result};
use crate::model::{JointKind, RobotModel};

impl RobotModel {
    /// Geometric Jacobian of a point on link `tip` with respect to the joints of `chain`.
    ///
    /// `poses` are the link poses from [`RobotModel::fk`] at the configuration of interest;
    /// `point` is the point in the tip link's frame (zero for the link origin). Rows 0–2 are
    /// the point's linear velocity, rows 3–5 the link's angular velocity, both in the world
    /// frame. `out` must be 6 × `chain.dof()`; it is overwritten. Mimic joints add their
    /// multiplier times their column to the joint they follow. Does not allocate.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// use nalgebra::{Matrix6xX, Vector3};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// let mut poses = panda.pose_buffer();
    /// panda.fk(&panda.neutral_configuration(), &mut poses).unwrap();
    /// let mut j = Matrix6xX::zeros(arm.dof());
    /// let tip = panda.link_index("panda_link8").unwrap();
    /// panda.jacobian(&poses, &arm, tip, &Vector3::zeros(), &mut j).unwrap();
    /// assert!((j[(5, 0)] - 1.0).abs() < 1e-12); // joint 1 turns about world z
    /// ```
    pub fn jacobian(
        &self,
        poses: &[Isometry3<f64>],
        chain: &Chain,
        tip: usize,
        point: &Vector3<f64>,
        out: &mut Matrix6xX<f64>,
    ) -> Result<()> {
        if out.ncols() != chain.dof() {
            return Err(KinematicsError::DimensionMismatch {
                what: "Jacobian columns",
                expected: chain.dof(),
                got: out.ncols(),
            });
        }
        if poses.len() != self.links().len() || tip >= poses.len() {
            return Err(KinematicsError::DimensionMismatch {
                what: "pose buffer",
                expected: self.links().len(),
                got: poses.len(),
            });
        }
        out.fill(0.0);
        let p = poses[tip] * nalgebra::Point3::from(*point);
        let links = self.links();
        let joints = self.joints();
        let mut cur = tip;
        while let Some(j) = links[cur].parent_joint {
            let joint = &joints[j];
            cur = joint.parent;
            let (var, mult) = match (joint.variable, joint.mimic) {
                (Some(v), _) => (v, 1.0),
                (None, Some(m)) => match joints[m.joint].variable {
                    Some(v) => (v, m.multiplier),
                    None => continue,
                },
                _ => continue,
            };
            let Some(col) = chain.column_of_variable(var) else {
                continue;
            };
            let frame = &poses[joint.child];
            let axis = frame.rotation * joint.axis.into_inner();
            let mut c = out.column_mut(col);
            match joint.kind {
                JointKind::Revolute | JointKind::Continuous => {
                    let lin = axis.cross(&(p.coords - frame.translation.vector));
                    c[0] += mult * lin.x;
                    c[1] += mult * lin.y;
                    c[2] += mult * lin.z;
                    c[3] += mult * axis.x;
                    c[4] += mult * axis.y;
                    c[5] += mult * axis.z;
                }
                JointKind::Prismatic => {
                    c[0] += mult * axis.x;
                    c[1] += mult * axis.y;
                    c[2] += mult * axis.z;
                }
                JointKind::Fixed => {}
            }
        }
        Ok(())
    }
}
