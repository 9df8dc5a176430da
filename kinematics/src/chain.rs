//! Chains: ordered subsets of a model's configuration variables (e.g. Fetch torso + arm).

use rand::Rng;

use crate::error::{KinematicsError, Result};
use crate::model::{JointKind, RobotModel, sample_interval};

/// An ordered subset of a model's joints, the space that planners and IK work in.
///
/// Joints outside the chain keep the values of a full reference configuration
/// ([`Chain::scatter`] writes chain values into it).
///
/// ```
/// use hearth_kinematics::{Chain, RobotModel};
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// let arm = Chain::named(&fetch, "arm_with_torso").unwrap();
/// assert_eq!(arm.dof(), 8);
/// assert_eq!(arm.joint_names()[0], "torso_lift_joint");
/// ```
#[derive(Clone, Debug)]
pub struct Chain {
    model: RobotModel,
    name: String,
    joints: Vec<usize>,
    variables: Vec<usize>,
    column_of_variable: Vec<Option<usize>>,
    names: Vec<String>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    velocity: Vec<f64>,
    continuous: Vec<bool>,
    tip: Option<usize>,
}

impl Chain {
    /// A chain of the named joints, in the given order.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let c = Chain::new(&panda, &["panda_joint1", "panda_joint2"]).unwrap();
    /// assert_eq!(c.dof(), 2);
    /// assert!(Chain::new(&panda, &["panda_joint8"]).is_err()); // fixed joint
    /// ```
    pub fn new<S: AsRef<str>>(model: &RobotModel, joints: &[S]) -> Result<Self> {
        let mut idx = Vec::with_capacity(joints.len());
        for name in joints {
            let j = model.joint_index(name.as_ref())?;
            let joint = &model.joints()[j];
            if joint.kind == JointKind::Fixed {
                return Err(KinematicsError::NotAVariable {
                    name: joint.name.clone(),
                    why: "fixed",
                });
            }
            if joint.mimic.is_some() {
                return Err(KinematicsError::NotAVariable {
                    name: joint.name.clone(),
                    why: "a mimic joint",
                });
            }
            idx.push(j);
        }
        Ok(Self::from_joints(model, "custom", idx, None))
    }

    /// One of the model's named chains ([`RobotModel::chains`]), with its tip link.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// assert_eq!((arm.name(), arm.dof()), ("arm", 7));
    /// assert_eq!(arm.tip(), Some(panda.link_index("panda_hand_tcp").unwrap()));
    /// assert!(Chain::named(&panda, "leg").is_err());
    /// ```
    pub fn named(model: &RobotModel, name: &str) -> Result<Self> {
        let spec = model
            .chains()
            .iter()
            .find(|c| c.name == name)
            .ok_or_else(|| KinematicsError::UnknownChain {
                robot: model.name().to_owned(),
                name: name.to_owned(),
                known: model
                    .chains()
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })?;
        let mut chain = Self::new(model, &spec.joints)?;
        chain.name = spec.name.clone();
        chain.tip = Some(model.link_index(&spec.tip)?);
        Ok(chain)
    }

    /// Every movable joint between link `base` and link `tip` (which must descend from
    /// `base`), root side first.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let c = Chain::between(&panda, "panda_link2", "panda_hand").unwrap();
    /// assert_eq!(c.joint_names()[0], "panda_joint3");
    /// assert_eq!(c.dof(), 5);
    /// assert!(Chain::between(&panda, "panda_hand", "panda_link2").is_err());
    /// ```
    pub fn between(model: &RobotModel, base: &str, tip: &str) -> Result<Self> {
        let b = model.link_index(base)?;
        let t = model.link_index(tip)?;
        if !model.is_ancestor(b, t) {
            return Err(KinematicsError::InvalidTarget(format!(
                "link `{tip}` does not descend from `{base}`"
            )));
        }
        let joints: Vec<usize> = model
            .joints_to(t)
            .into_iter()
            .filter(|&j| {
                let joint = &model.joints()[j];
                joint.variable.is_some() && model.is_ancestor(b, joint.parent)
            })
            .collect();
        let mut chain = Self::from_joints(model, &format!("{base}..{tip}"), joints, Some(t));
        chain.tip = Some(t);
        Ok(chain)
    }

    /// All configuration variables of the model, in `q` order.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let all = Chain::all(&panda);
    /// assert_eq!(all.dof(), panda.dof());
    /// assert_eq!(all.joint_names(), panda.variable_names());
    /// ```
    pub fn all(model: &RobotModel) -> Self {
        Self::from_joints(model, "all", model.variables().to_vec(), None)
    }

    fn from_joints(model: &RobotModel, name: &str, joints: Vec<usize>, tip: Option<usize>) -> Self {
        let variables: Vec<usize> = joints
            .iter()
            .map(|&j| model.joints()[j].variable.expect("checked: chain joints are variables"))
            .collect();
        let mut column_of_variable = vec![None; model.dof()];
        for (col, &v) in variables.iter().enumerate() {
            column_of_variable[v] = Some(col);
        }
        Self {
            model: model.clone(),
            name: name.to_owned(),
            names: joints.iter().map(|&j| model.joints()[j].name.clone()).collect(),
            lower: variables.iter().map(|&v| model.lower()[v]).collect(),
            upper: variables.iter().map(|&v| model.upper()[v]).collect(),
            velocity: variables.iter().map(|&v| model.velocity_limits()[v]).collect(),
            continuous: joints
                .iter()
                .map(|&j| model.joints()[j].kind == JointKind::Continuous)
                .collect(),
            joints,
            variables,
            column_of_variable,
            tip,
        }
    }

    /// The model the chain belongs to.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// assert_eq!(arm.model().fingerprint(), panda.fingerprint());
    /// ```
    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    /// Chain name (`custom` for [`Chain::new`]).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// assert_eq!(Chain::named(&panda, "arm").unwrap().name(), "arm");
    /// assert_eq!(Chain::new(&panda, &["panda_joint1"]).unwrap().name(), "custom");
    /// ```
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of joints.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// assert_eq!(Chain::named(&fetch, "head").unwrap().dof(), 2);
    /// ```
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Joint indices in chain order.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let c = Chain::new(&panda, &["panda_joint2", "panda_joint1"]).unwrap();
    /// assert_eq!(c.joints(), [1, 0]);
    /// ```
    pub fn joints(&self) -> &[usize] {
        &self.joints
    }

    /// Model configuration-variable index of each chain joint.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let head = Chain::named(&fetch, "head").unwrap();
    /// let v = head.variables()[0];
    /// assert_eq!(fetch.variable_names()[v], "head_pan_joint");
    /// ```
    pub fn variables(&self) -> &[usize] {
        &self.variables
    }

    /// Chain column of a model variable, if the chain has it.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let c = Chain::new(&panda, &["panda_joint3", "panda_joint1"]).unwrap();
    /// assert_eq!(c.column_of_variable(0), Some(1));
    /// assert_eq!(c.column_of_variable(1), None);
    /// ```
    pub fn column_of_variable(&self, variable: usize) -> Option<usize> {
        self.column_of_variable.get(variable).copied().flatten()
    }

    /// Joint names in chain order.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let head = Chain::named(&fetch, "head").unwrap();
    /// assert_eq!(head.joint_names(), ["head_pan_joint", "head_tilt_joint"]);
    /// ```
    pub fn joint_names(&self) -> &[String] {
        &self.names
    }

    /// Lower limits (`-∞` for continuous joints).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// assert!(arm.lower()[0].is_finite()); // shoulder_pan_joint
    /// assert_eq!(arm.lower()[2], f64::NEG_INFINITY); // upperarm_roll_joint is continuous
    /// ```
    pub fn lower(&self) -> &[f64] {
        &self.lower
    }

    /// Upper limits (`+∞` for continuous joints).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// assert!(arm.lower().iter().zip(arm.upper()).all(|(lo, hi)| lo < hi));
    /// ```
    pub fn upper(&self) -> &[f64] {
        &self.upper
    }

    /// Velocity limits.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// assert_eq!(arm.velocity_limits(), &panda.velocity_limits()[..7]);
    /// ```
    pub fn velocity_limits(&self) -> &[f64] {
        &self.velocity
    }

    /// Which joints are continuous (unbounded).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// assert_eq!(arm.continuous(), [false, false, true, false, true, false, true]);
    /// ```
    pub fn continuous(&self) -> &[bool] {
        &self.continuous
    }

    /// The tip link the chain is solved for, if it has one.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let tcp = panda.link_index("panda_hand_tcp").unwrap();
    /// assert_eq!(Chain::named(&panda, "arm").unwrap().tip(), Some(tcp));
    /// assert_eq!(Chain::all(&panda).tip(), None);
    /// ```
    pub fn tip(&self) -> Option<usize> {
        self.tip
    }

    /// Writes chain values into a full configuration.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let c = Chain::new(&panda, &["panda_joint2", "panda_joint6"]).unwrap();
    /// let mut q = vec![0.0; panda.dof()];
    /// c.scatter(&[0.5, 1.5], &mut q);
    /// assert_eq!((q[1], q[5], q[0]), (0.5, 1.5, 0.0));
    /// ```
    pub fn scatter(&self, q_chain: &[f64], q_full: &mut [f64]) {
        for (&v, &x) in self.variables.iter().zip(q_chain) {
            q_full[v] = x;
        }
    }

    /// Reads chain values out of a full configuration.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let c = Chain::new(&panda, &["panda_joint2", "panda_joint6"]).unwrap();
    /// let q: Vec<f64> = (0..panda.dof()).map(|i| i as f64).collect();
    /// let mut qc = [0.0; 2];
    /// c.gather(&q, &mut qc);
    /// assert_eq!(qc, [1.0, 5.0]);
    /// ```
    pub fn gather(&self, q_full: &[f64], q_chain: &mut [f64]) {
        for (x, &v) in q_chain.iter_mut().zip(&self.variables) {
            *x = q_full[v];
        }
    }

    /// Uniform random chain configuration inside the limits (continuous joints in `[-π, π)`).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// use rand::SeedableRng;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let mut q = vec![0.0; arm.dof()];
    /// arm.random_configuration(&mut rng, &mut q);
    /// assert!(q.iter().all(|x| x.abs() <= std::f64::consts::PI));
    /// let mut clamped = q.clone();
    /// arm.clamp(&mut clamped);
    /// assert_eq!(clamped, q); // already inside the limits
    /// ```
    pub fn random_configuration<R: Rng + ?Sized>(&self, rng: &mut R, q: &mut [f64]) {
        for ((x, &lo), &hi) in q.iter_mut().zip(&self.lower).zip(&self.upper) {
            *x = sample_interval(rng, lo, hi);
        }
    }

    /// Clamps `q` into the limits (continuous joints are wrapped into `(-π, π]`).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// let mut q = vec![0.0; 7];
    /// q[0] = 100.0; // shoulder_pan_joint: clamped
    /// q[2] = 7.0; // upperarm_roll_joint (continuous): wrapped
    /// arm.clamp(&mut q);
    /// assert_eq!(q[0], arm.upper()[0]);
    /// assert!((q[2] - (7.0 - 2.0 * std::f64::consts::PI)).abs() < 1e-12);
    /// ```
    pub fn clamp(&self, q: &mut [f64]) {
        for (i, x) in q.iter_mut().enumerate() {
            if self.continuous[i] {
                *x = wrap_angle(*x);
            } else {
                *x = x.clamp(self.lower[i], self.upper[i]);
            }
        }
    }

    /// Checks the length and finiteness of a chain configuration.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// assert!(arm.check(&[0.0; 7]).is_ok());
    /// assert!(arm.check(&[0.0; 8]).is_err());
    /// assert!(arm.check(&[0.0, 0.0, 0.0, f64::INFINITY, 0.0, 0.0, 0.0]).is_err());
    /// ```
    pub fn check(&self, q: &[f64]) -> Result<()> {
        crate::model::check_values("chain configuration", q, &self.names)
    }
}

/// Wraps an angle into `(-π, π]`.
///
/// ```
/// use hearth_kinematics::wrap_angle;
/// use std::f64::consts::PI;
/// assert_eq!(wrap_angle(1.0), 1.0);
/// assert!((wrap_angle(1.5 * PI) + 0.5 * PI).abs() < 1e-12);
/// assert_eq!(wrap_angle(-PI), PI);
/// ```
#[inline]
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if a > -PI && a <= PI {
        return a;
    }
    // One turn off, as the difference of two wrapped angles always is: the same value as the
    // remainder below (which is exact), without the library call.
    if a > PI && a < TAU {
        return a - TAU;
    }
    if a > -TAU && a <= -PI {
        return a + TAU;
    }
    let mut r = a.rem_euclid(TAU);
    if r > PI {
        r -= TAU;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::wrap_angle;
    use std::f64::consts::{PI, TAU};

    /// The remainder alone, as `wrap_angle` was before its one-turn shortcuts.
    fn by_remainder(a: f64) -> f64 {
        if a > -PI && a <= PI {
            return a;
        }
        let r = a.rem_euclid(TAU);
        if r > PI { r - TAU } else { r }
    }

    #[test]
    fn one_turn_shortcuts_give_the_remainders_value_to_the_last_bit() {
        let mut edges = vec![PI, -PI, TAU, -TAU, 3.0 * PI, -3.0 * PI, 0.0, -0.0];
        for e in edges.clone() {
            edges.extend([e.next_up(), e.next_down()]);
        }
        // Differences of wrapped angles, as distances and interpolation take them, and beyond.
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        let randoms = (0..200_000).map(move |_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 * 8.0 * PI - 4.0 * PI
        });
        let differences = (0..2_000).map(|k| {
            let a = by_remainder(k as f64 * 0.731);
            let b = by_remainder(k as f64 * -1.913 + 0.4);
            b - a
        });
        for a in edges.into_iter().chain(randoms).chain(differences) {
            assert_eq!(wrap_angle(a).to_bits(), by_remainder(a).to_bits(), "{a:e}");
        }
    }
}
