//! Inverse kinematics: damped least squares or a joint-limit QP, with random restarts.

pub(crate) mod dls;
mod qp;

use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Matrix6xX, Point3, UnitQuaternion, Vector3};
use rand::Rng;

use crate::chain::{Chain, wrap_angle};
use crate::error::{KinematicsError, Result};
use crate::model::RobotModel;

/// What the end effector should reach.
///
/// ```
/// use hearth_kinematics::IkTarget;
/// use hearth_kinematics::nalgebra::{Isometry3, Point3};
/// let reach = IkTarget::Position(Point3::new(0.4, 0.0, 0.5));
/// let grasp = IkTarget::Pose(Isometry3::translation(0.4, 0.0, 0.5));
/// assert_ne!(reach, grasp);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkTarget {
    /// Full pose (position and orientation) of the tool frame in the world (robot root) frame.
    Pose(Isometry3<f64>),
    /// Position only of the tool point.
    Position(Point3<f64>),
}

impl IkTarget {
    fn check(&self) -> Result<()> {
        let finite = match self {
            IkTarget::Pose(p) => {
                p.translation.vector.iter().all(|v| v.is_finite()) && p.rotation.coords.iter().all(|v| v.is_finite())
            }
            IkTarget::Position(p) => p.coords.iter().all(|v| v.is_finite()),
        };
        if finite {
            Ok(())
        } else {
            Err(KinematicsError::InvalidTarget(format!(
                "{self:?} has non-finite values"
            )))
        }
    }
}

/// The step rule.
///
/// ```
/// use hearth_kinematics::{IkMethod, IkSettings};
/// assert_eq!(IkSettings::default().method, IkMethod::Dls);
/// let exact = IkSettings { method: IkMethod::Qp, ..Default::default() };
/// assert_eq!(exact.method, IkMethod::Qp);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IkMethod {
    /// Damped least squares with adaptive (Levenberg–Marquardt) damping, clamped to the
    /// limits. Fast; the default.
    #[default]
    Dls,
    /// Each step is a QP with the joint limits as constraints, solved by clarabel (the solver
    /// is built once and reused). Respects limits exactly; ~100× slower per step.
    Qp,
}

/// IK settings. `Default` gives 1 mm / 0.01 rad tolerances and no wall-clock limit: a default
/// solve stops after `max_attempts` restarts (200), so its answer is the same on every machine
/// for the same seed.
///
/// ```
/// let s = hearth_kinematics::IkSettings { max_attempts: 10, ..Default::default() };
/// assert_eq!(s.position_tolerance, 1e-3);
/// assert_eq!(s.time_limit, None); // reproducible by default
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct IkSettings {
    /// Step rule.
    pub method: IkMethod,
    /// Position tolerance (m).
    pub position_tolerance: f64,
    /// Orientation tolerance (rad, angle of the residual rotation).
    pub orientation_tolerance: f64,
    /// Iterations per attempt before a random restart.
    pub max_iterations: usize,
    /// Attempts (the first from the seed, the rest from random configurations).
    pub max_attempts: usize,
    /// Wall-clock limit over all attempts (`None`: attempts only). With `None`, a solve is a
    /// pure function of target, seed, settings and RNG state (bit-for-bit reproducible); with a
    /// limit, a solve that runs into it depends on machine speed.
    pub time_limit: Option<Duration>,
    /// Initial damping λ.
    pub damping: f64,
    /// Largest change of one joint in one step (rad or m).
    pub max_step: f64,
    /// Collect this many solutions and return the one closest to the seed (1: the first).
    pub candidates: usize,
    /// Restart an attempt whose cost has not halved within this many iterations.
    pub stall_iterations: usize,
}

impl Default for IkSettings {
    fn default() -> Self {
        Self {
            method: IkMethod::Dls,
            position_tolerance: 1e-3,
            orientation_tolerance: 1e-2,
            max_iterations: 60,
            max_attempts: 200,
            time_limit: None,
            damping: 1e-2,
            max_step: 1.0,
            candidates: 1,
            stall_iterations: 5,
        }
    }
}

/// A solution.
///
/// ```
/// use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
/// use rand::SeedableRng;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let settings = IkSettings { time_limit: None, ..Default::default() };
/// let mut ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand_tcp", settings).unwrap();
/// let seed = [0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0];
/// let target = IkTarget::Position(ik.tool_pose(&seed).unwrap().translation.vector.into());
/// let sol = ik.solve(&target, &seed, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert_eq!((sol.attempts, sol.orientation_error), (1, 0.0)); // the seed already fits
/// assert!(sol.position_error <= 1e-3);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct IkSolution {
    /// Chain configuration.
    pub q: Vec<f64>,
    /// Remaining position error (m).
    pub position_error: f64,
    /// Remaining orientation error (rad; 0 for position targets).
    pub orientation_error: f64,
    /// Attempts used.
    pub attempts: usize,
    /// Iterations used over all attempts.
    pub iterations: usize,
}

/// Why IK found nothing.
///
/// ```
/// use hearth_kinematics::{Chain, IkError, IkSettings, IkSolver, IkTarget, RobotModel};
/// use hearth_kinematics::nalgebra::Point3;
/// use rand::SeedableRng;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let settings = IkSettings { max_attempts: 3, time_limit: None, ..Default::default() };
/// let mut ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand_tcp", settings).unwrap();
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let far = IkTarget::Position(Point3::new(5.0, 0.0, 0.0)); // out of reach
/// assert!(matches!(ik.solve(&far, &[0.0; 7], &mut rng), Err(IkError::NotFound { attempts: 3, .. })));
/// assert!(matches!(ik.solve(&far, &[0.0; 2], &mut rng), Err(IkError::Input(_))));
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IkError {
    /// The request itself is unusable (wrong dimension, NaN, unknown link).
    #[error("{0}")]
    Input(String),
    /// No attempt converged within the budget.
    #[error(
        "no IK solution within {attempts} attempts / {iterations} iterations \
         (best residual {best_position_error:.4} m, {best_orientation_error:.4} rad; {rejected} solutions rejected by the validity check)"
    )]
    NotFound {
        /// Attempts made.
        attempts: usize,
        /// Iterations made.
        iterations: usize,
        /// Smallest position error reached.
        best_position_error: f64,
        /// Orientation error at that point.
        best_orientation_error: f64,
        /// Converged solutions the validity callback rejected.
        rejected: usize,
    },
}

impl From<KinematicsError> for IkError {
    fn from(e: KinematicsError) -> Self {
        IkError::Input(e.to_string())
    }
}

/// An IK solver for one chain and tip frame, with preallocated work buffers.
///
/// Create it once and call [`IkSolver::solve`] many times: solving does not allocate except
/// for the returned solution.
///
/// ```
/// use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
/// use rand::SeedableRng;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let arm = Chain::named(&panda, "arm").unwrap();
/// let mut ik = IkSolver::new(arm, "panda_hand_tcp", IkSettings::default()).unwrap();
/// let goal_q = [0.3, -0.4, 0.2, -2.0, 0.1, 1.8, 0.5];
/// let target = ik.tool_pose(&goal_q).unwrap();
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
/// let sol = ik.solve(&IkTarget::Pose(target), &[0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0], &mut rng).unwrap();
/// assert!(sol.position_error <= 1e-3 && sol.orientation_error <= 1e-2);
/// ```
pub struct IkSolver {
    chain: Chain,
    model: RobotModel,
    tip: usize,
    tool: Isometry3<f64>,
    settings: IkSettings,
    path: Vec<u32>,
    q_full: Vec<f64>,
    poses: Vec<Isometry3<f64>>,
    poses_try: Vec<Isometry3<f64>>,
    jac: Matrix6xX<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    q: Vec<f64>,
    q_try: Vec<f64>,
    dq: Vec<f64>,
    best: Vec<f64>,
    qp: Option<qp::QpStep>,
}

impl std::fmt::Debug for IkSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("IkSolver")
            .field("chain", &self.chain.joint_names())
            .field("tip", &self.model.links()[self.tip].name)
            .field("settings", &self.settings)
            .finish()
    }
}

impl IkSolver {
    /// A solver for `chain` moving link `tip`. Joints outside the chain are held at the
    /// model's neutral configuration (see [`IkSolver::set_reference`]).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// let ik = IkSolver::new(arm.clone(), "panda_hand", IkSettings::default()).unwrap();
    /// assert_eq!(ik.tip(), panda.link_index("panda_hand").unwrap());
    /// assert!(IkSolver::new(arm, "no_such_link", IkSettings::default()).is_err());
    /// ```
    pub fn new(chain: Chain, tip: &str, settings: IkSettings) -> Result<Self> {
        let model = chain.model().clone();
        let tip = model.link_index(tip)?;
        let n = chain.dof();
        let path = model.fk_path(tip);
        let mut poses = model.pose_buffer();
        poses[0] = Isometry3::identity();
        // Continuous joints: no clamping, but bounded steps.
        let lo = chain
            .lower()
            .iter()
            .map(|&l| if l.is_finite() { l } else { f64::NEG_INFINITY })
            .collect();
        let hi = chain.upper().to_vec();
        let qp = match settings.method {
            IkMethod::Qp => qp::QpStep::new(n),
            IkMethod::Dls => None,
        };
        Ok(Self {
            q_full: model.neutral_configuration(),
            poses_try: poses.clone(),
            poses,
            jac: Matrix6xX::zeros(n),
            q: vec![0.0; n],
            q_try: vec![0.0; n],
            dq: vec![0.0; n],
            best: vec![0.0; n],
            lo,
            hi,
            path,
            tip,
            tool: Isometry3::identity(),
            model,
            chain,
            settings,
            qp,
        })
    }

    /// Sets the tool frame: the target is for `tip_pose · tool` (e.g. a fingertip offset).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// use hearth_kinematics::nalgebra::Isometry3;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// let q = [0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0];
    /// let mut tcp = IkSolver::new(arm.clone(), "panda_hand_tcp", IkSettings::default()).unwrap();
    /// let mut tooled = IkSolver::new(arm, "panda_hand", IkSettings::default())
    ///     .unwrap()
    ///     .with_tool(Isometry3::translation(0.0, 0.0, 0.1034)); // the hand-to-TCP offset
    /// let (a, b) = (tooled.tool_pose(&q).unwrap(), tcp.tool_pose(&q).unwrap());
    /// assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
    /// ```
    pub fn with_tool(mut self, tool: Isometry3<f64>) -> Self {
        self.tool = tool;
        self
    }

    /// Sets the full configuration that joints outside the chain keep.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// let mut ik = IkSolver::new(arm, "gripper_link", IkSettings::default()).unwrap();
    /// let low = ik.tool_pose(&[0.0; 7]).unwrap();
    /// let mut q_full = fetch.neutral_configuration();
    /// q_full[fetch.variable_names().iter().position(|n| n == "torso_lift_joint").unwrap()] = 0.3;
    /// ik.set_reference(&q_full).unwrap(); // raise the torso, which the arm chain does not move
    /// let high = ik.tool_pose(&[0.0; 7]).unwrap();
    /// assert!((high.translation.z - low.translation.z - 0.3).abs() < 1e-9);
    /// assert!(ik.set_reference(&[0.0; 2]).is_err());
    /// ```
    pub fn set_reference(&mut self, q_full: &[f64]) -> Result<()> {
        self.model.check_configuration(q_full)?;
        self.q_full.copy_from_slice(q_full);
        Ok(())
    }

    /// The settings.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let settings = IkSettings { max_attempts: 5, ..Default::default() };
    /// let ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand", settings).unwrap();
    /// assert_eq!(ik.settings().max_attempts, 5);
    /// ```
    pub fn settings(&self) -> &IkSettings {
        &self.settings
    }

    /// Replaces the settings (the QP solver is built when first needed).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkMethod, IkSettings, IkSolver, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let mut ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand", IkSettings::default()).unwrap();
    /// ik.set_settings(IkSettings { method: IkMethod::Qp, ..Default::default() });
    /// assert_eq!(ik.settings().method, IkMethod::Qp);
    /// ```
    pub fn set_settings(&mut self, settings: IkSettings) {
        if settings.method == IkMethod::Qp && self.qp.is_none() {
            self.qp = qp::QpStep::new(self.chain.dof());
        }
        self.settings = settings;
    }

    /// The chain being solved.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand", IkSettings::default()).unwrap();
    /// assert_eq!(ik.chain().dof(), 7);
    /// ```
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The tip link index.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand", IkSettings::default()).unwrap();
    /// assert_eq!(panda.links()[ik.tip()].name, "panda_hand");
    /// ```
    pub fn tip(&self) -> usize {
        self.tip
    }

    /// The tool-frame pose for chain configuration `q` (forward kinematics of the tip).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, RobotModel};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// let mut ik = IkSolver::new(arm, "panda_hand_tcp", IkSettings::default()).unwrap();
    /// let q = [0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0];
    /// let mut q_full = panda.neutral_configuration();
    /// q_full[..7].copy_from_slice(&q);
    /// let mut poses = panda.pose_buffer();
    /// panda.fk(&q_full, &mut poses).unwrap();
    /// let tcp = ik.tool_pose(&q).unwrap();
    /// assert!((tcp.translation.vector - poses[ik.tip()].translation.vector).norm() < 1e-12);
    /// assert!(ik.tool_pose(&[0.0; 3]).is_err());
    /// ```
    pub fn tool_pose(&mut self, q: &[f64]) -> Result<Isometry3<f64>> {
        self.chain.check(q)?;
        Ok(self.eval(q))
    }

    #[inline]
    fn eval(&mut self, q: &[f64]) -> Isometry3<f64> {
        self.chain.scatter(q, &mut self.q_full);
        self.model.0.fk.run_subset(&self.path, &self.q_full, &mut self.poses);
        self.poses[self.tip] * self.tool
    }

    /// Residual of the tool frame at `pose`: `[position (3), rotation vector (3)]`, plus norms.
    #[inline]
    fn residual(target: &IkTarget, pose: &Isometry3<f64>) -> ([f64; 6], f64, f64) {
        match target {
            IkTarget::Pose(t) => {
                let dp = t.translation.vector - pose.translation.vector;
                let dr: UnitQuaternion<f64> = t.rotation * pose.rotation.inverse();
                let w = dr.scaled_axis();
                ([dp.x, dp.y, dp.z, w.x, w.y, w.z], dp.norm(), w.norm())
            }
            IkTarget::Position(p) => {
                let dp = p.coords - pose.translation.vector;
                ([dp.x, dp.y, dp.z, 0.0, 0.0, 0.0], dp.norm(), 0.0)
            }
        }
    }

    /// Solves IK from `seed` (a chain configuration).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
    /// use rand::SeedableRng;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let settings = IkSettings { time_limit: None, ..Default::default() };
    /// let mut ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand_tcp", settings).unwrap();
    /// let target = ik.tool_pose(&[0.2, -0.3, 0.1, -2.0, 0.0, 1.8, 0.6]).unwrap();
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    /// let sol = ik.solve(&IkTarget::Pose(target), &[0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0], &mut rng).unwrap();
    /// let reached = ik.tool_pose(&sol.q).unwrap();
    /// assert!((reached.translation.vector - target.translation.vector).norm() <= 1e-3);
    /// ```
    pub fn solve<R: Rng + ?Sized>(
        &mut self,
        target: &IkTarget,
        seed: &[f64],
        rng: &mut R,
    ) -> Result<IkSolution, IkError> {
        self.solve_with(target, seed, rng, |_| true)
    }

    /// Solves IK, accepting only solutions for which `accept` returns `true` (e.g. collision
    /// free); rejected solutions trigger a restart.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
    /// use rand::SeedableRng;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let settings = IkSettings { time_limit: None, ..Default::default() };
    /// let mut ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand_tcp", settings).unwrap();
    /// let pose = ik.tool_pose(&[0.3, -0.3, 0.0, -2.0, 0.0, 1.8, 0.0]).unwrap();
    /// let target = IkTarget::Position(pose.translation.vector.into());
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    /// // Only solutions with the first joint turned left.
    /// let sol = ik.solve_with(&target, &[0.5, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0], &mut rng, |q| q[0] > 0.0).unwrap();
    /// assert!(sol.q[0] > 0.0);
    /// ```
    pub fn solve_with<R: Rng + ?Sized, F: FnMut(&[f64]) -> bool>(
        &mut self,
        target: &IkTarget,
        seed: &[f64],
        rng: &mut R,
        mut accept: F,
    ) -> Result<IkSolution, IkError> {
        self.chain.check(seed)?;
        target.check()?;
        let start = Instant::now();
        let s = self.settings.clone();
        let rows = match target {
            IkTarget::Pose(_) => 6,
            IkTarget::Position(_) => 3,
        };
        let tool_point: Vector3<f64> = self.tool.translation.vector;
        let mut iterations = 0;
        let mut rejected = 0;
        let (mut best_p, mut best_r) = (f64::INFINITY, f64::INFINITY);
        let mut found: Option<(IkSolution, f64)> = None;
        let mut candidates = 0;
        let mut attempts = 0;
        while attempts < s.max_attempts.max(1) {
            if attempts > 0 && s.time_limit.is_some_and(|t| start.elapsed() > t) {
                break;
            }
            attempts += 1;
            if attempts == 1 {
                self.q.copy_from_slice(seed);
                self.clamp_q();
            } else {
                self.chain.random_configuration(rng, &mut self.q);
            }
            // Borrow `q` out for the evaluation (no allocation: `take` leaves an empty Vec).
            let q = std::mem::take(&mut self.q);
            let pose = self.eval(&q);
            self.q = q;
            let (mut e, mut ep, mut er) = Self::residual(target, &pose);
            let mut lambda = s.damping;
            let mut converged = ep <= s.position_tolerance && er <= s.orientation_tolerance;
            let mut it = 0;
            // `self.poses` holds the FK of `self.q` whenever a step starts.
            let mut checkpoint = ep * ep + er * er;
            let mut since_checkpoint = 0;
            while !converged && it < s.max_iterations {
                it += 1;
                if self
                    .model
                    .jacobian(&self.poses, &self.chain, self.tip, &tool_point, &mut self.jac)
                    .is_err()
                {
                    break;
                }
                let stepped = match (&mut self.qp, s.method) {
                    (Some(qp), IkMethod::Qp) => qp.step(
                        &self.jac,
                        rows,
                        &e,
                        lambda,
                        &self.q,
                        &self.lo,
                        &self.hi,
                        s.max_step,
                        &mut self.dq,
                    ),
                    _ => dls::damped_least_squares_step(&self.jac, rows, &e, lambda, &mut self.dq),
                };
                if !stepped {
                    break;
                }
                let largest = self.dq.iter().fold(0.0f64, |m, d| m.max(d.abs()));
                let scale = if largest > s.max_step {
                    s.max_step / largest
                } else {
                    1.0
                };
                for i in 0..self.q.len() {
                    let v = self.q[i] + scale * self.dq[i];
                    self.q_try[i] = v.clamp(self.lo[i], self.hi[i]);
                }
                self.chain.scatter(&self.q_try, &mut self.q_full);
                self.model
                    .0
                    .fk
                    .run_subset(&self.path, &self.q_full, &mut self.poses_try);
                let pose = self.poses_try[self.tip] * self.tool;
                let (e2, ep2, er2) = Self::residual(target, &pose);
                let cost = ep2 * ep2 + er2 * er2;
                if cost < ep * ep + er * er {
                    std::mem::swap(&mut self.q, &mut self.q_try);
                    std::mem::swap(&mut self.poses, &mut self.poses_try);
                    (e, ep, er) = (e2, ep2, er2);
                    lambda = (lambda * 0.5).max(1e-6);
                    converged = ep <= s.position_tolerance && er <= s.orientation_tolerance;
                } else {
                    lambda *= 4.0;
                    if lambda > 1e3 {
                        break;
                    }
                }
                // Restart early when an attempt stops making headway (a local minimum or a
                // joint limit): progress means halving the cost every few iterations.
                since_checkpoint += 1;
                if cost < 0.5 * checkpoint {
                    checkpoint = cost;
                    since_checkpoint = 0;
                } else if since_checkpoint >= s.stall_iterations {
                    break;
                }
            }
            iterations += it;
            if ep * ep + er * er < best_p * best_p + best_r * best_r {
                best_p = ep;
                best_r = er;
                self.best.copy_from_slice(&self.q);
            }
            if !converged {
                continue;
            }
            for (i, x) in self.q.iter_mut().enumerate() {
                if self.chain.continuous()[i] {
                    *x = wrap_angle(*x);
                }
            }
            if !accept(&self.q) {
                rejected += 1;
                continue;
            }
            let dist = self.distance(seed);
            let better = found.as_ref().is_none_or(|(_, d)| dist < *d);
            if better {
                found = Some((
                    IkSolution {
                        q: self.q.clone(),
                        position_error: ep,
                        orientation_error: er,
                        attempts,
                        iterations,
                    },
                    dist,
                ));
            }
            candidates += 1;
            if candidates >= s.candidates.max(1) {
                break;
            }
        }
        match found {
            Some((mut sol, _)) => {
                sol.attempts = attempts;
                sol.iterations = iterations;
                Ok(sol)
            }
            None => Err(IkError::NotFound {
                attempts,
                iterations,
                best_position_error: best_p,
                best_orientation_error: best_r,
                rejected,
            }),
        }
    }

    fn clamp_q(&mut self) {
        for i in 0..self.q.len() {
            self.q[i] = self.q[i].clamp(self.lo[i], self.hi[i]);
        }
    }

    fn distance(&self, seed: &[f64]) -> f64 {
        self.q
            .iter()
            .zip(seed)
            .enumerate()
            .map(|(i, (a, b))| {
                let d = if self.chain.continuous()[i] {
                    wrap_angle(a - b)
                } else {
                    a - b
                };
                d * d
            })
            .sum::<f64>()
            .sqrt()
    }

    /// The best configuration reached by the last failed solve (for diagnostics).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
    /// use hearth_kinematics::nalgebra::Point3;
    /// use rand::SeedableRng;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let settings = IkSettings { max_attempts: 2, time_limit: None, ..Default::default() };
    /// let mut ik = IkSolver::new(Chain::named(&panda, "arm").unwrap(), "panda_hand_tcp", settings).unwrap();
    /// let far = IkTarget::Position(Point3::new(3.0, 0.0, 0.3));
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
    /// assert!(ik.solve(&far, &[0.0; 7], &mut rng).is_err());
    /// let best = ik.best_effort().to_vec();
    /// assert_eq!(best.len(), 7);
    /// // The arm stretched towards the target: the TCP ends up well out in +x.
    /// assert!(ik.tool_pose(&best).unwrap().translation.x > 0.5);
    /// ```
    pub fn best_effort(&self) -> &[f64] {
        &self.best
    }
}
