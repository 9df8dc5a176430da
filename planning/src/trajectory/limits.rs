//! Per-joint velocity, acceleration and jerk limits.

use hearth_kinematics::Chain;

use super::TrajectoryError;

/// Acceleration and jerk defaults of the built-in robots, per joint: `(robot, joint,
/// acceleration, jerk)`. URDF carries velocity limits only.
///
/// - Panda: the manufacturer's published joint limits (Franka Control Interface documentation,
///   "robot and interface specifications"), the values in MotionBenchMaker's `joints.json`.
/// - Fetch: the manufacturer publishes no acceleration or jerk limits; these are Hearth's
///   conservative defaults (about one second to full speed for the arm, jerk 20× acceleration).
const DEFAULTS: &[(&str, &str, f64, f64)] = &[
    ("panda", "panda_joint1", 15.0, 7500.0),
    ("panda", "panda_joint2", 7.5, 3750.0),
    ("panda", "panda_joint3", 10.0, 5000.0),
    ("panda", "panda_joint4", 12.5, 6250.0),
    ("panda", "panda_joint5", 15.0, 7500.0),
    ("panda", "panda_joint6", 20.0, 10000.0),
    ("panda", "panda_joint7", 20.0, 10000.0),
    ("fetch", "torso_lift_joint", 0.5, 10.0),
    ("fetch", "shoulder_pan_joint", 1.5, 30.0),
    ("fetch", "shoulder_lift_joint", 1.5, 30.0),
    ("fetch", "upperarm_roll_joint", 1.5, 30.0),
    ("fetch", "elbow_flex_joint", 1.5, 30.0),
    ("fetch", "forearm_roll_joint", 1.5, 30.0),
    ("fetch", "wrist_flex_joint", 2.5, 50.0),
    ("fetch", "wrist_roll_joint", 2.5, 50.0),
];

/// Velocity, acceleration and jerk limits per coordinate, all positive; jerk may be `+∞`
/// (acceleration-bounded, "parabolic" motion).
///
/// ```
/// use hearth_planning::kinematics::{Chain, RobotModel};
/// use hearth_planning::trajectory::Limits;
///
/// let panda = RobotModel::builtin("panda").unwrap();
/// let limits = Limits::for_chain(&Chain::named(&panda, "arm").unwrap());
/// assert_eq!(limits.acceleration()[1], 7.5);
/// assert_eq!(limits.jerk()[1], 3750.0);
/// assert!((limits.velocity()[0] - 2.175).abs() < 1e-3);
/// let slow = Limits::new(vec![1.0], vec![2.0], vec![f64::INFINITY]).unwrap();
/// assert!(Limits::new(vec![1.0], vec![-2.0], vec![10.0]).is_err());
/// # let _ = slow;
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
    jerk: Vec<f64>,
    /// Position bounds (`±∞` for continuous joints), when known.
    bounds: Option<(Vec<f64>, Vec<f64>)>,
}

impl Limits {
    /// Limits from explicit values: velocity and acceleration finite and positive, jerk positive
    /// (`+∞` allowed), all of the same length. No position bounds are set.
    ///
    /// ```
    /// use hearth_planning::trajectory::{Limits, TrajectoryError};
    ///
    /// let limits = Limits::new(vec![1.0, 2.0], vec![4.0, 4.0], vec![f64::INFINITY, 100.0])?;
    /// assert_eq!(limits.dim(), 2);
    /// assert!(matches!(
    ///     Limits::new(vec![1.0], vec![f64::INFINITY], vec![10.0]),
    ///     Err(TrajectoryError::BadLimit { what: "acceleration", index: 0, .. })
    /// ));
    /// let short = Limits::new(vec![1.0; 2], vec![1.0], vec![1.0; 2]);
    /// assert!(matches!(short, Err(TrajectoryError::Dimension { what: "acceleration", expected: 2, got: 1 })));
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn new(velocity: Vec<f64>, acceleration: Vec<f64>, jerk: Vec<f64>) -> Result<Self, TrajectoryError> {
        let n = velocity.len();
        for (what, v) in [("acceleration", &acceleration), ("jerk", &jerk)] {
            if v.len() != n {
                return Err(TrajectoryError::Dimension {
                    what,
                    expected: n,
                    got: v.len(),
                });
            }
        }
        for (what, values, inf_ok) in [
            ("velocity", &velocity, false),
            ("acceleration", &acceleration, false),
            ("jerk", &jerk, true),
        ] {
            for (index, &value) in values.iter().enumerate() {
                let ok = value > 0.0 && (value.is_finite() || (inf_ok && value == f64::INFINITY));
                if !ok {
                    return Err(TrajectoryError::BadLimit { what, index, value });
                }
            }
        }
        Ok(Self {
            velocity,
            acceleration,
            jerk,
            bounds: None,
        })
    }

    /// The limits of a chain: velocity from the robot model (a joint without one gets
    /// 1 rad/s or m/s), acceleration and jerk from the built-in robot's defaults, else
    /// 2× velocity per second and 50× acceleration per second. Position bounds are the joint
    /// limits (`±∞` for continuous joints).
    ///
    /// ```
    /// use hearth_planning::kinematics::{Chain, RobotModel};
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let head = Chain::named(&fetch, "head").unwrap();
    /// let limits = Limits::for_chain(&head);
    /// // No built-in defaults for the head: derived from its velocity limits.
    /// let v = limits.velocity()[0];
    /// assert_eq!(limits.acceleration()[0], 2.0 * v);
    /// assert_eq!(limits.jerk()[0], 50.0 * limits.acceleration()[0]);
    /// assert_eq!(limits.position_bounds().unwrap().0, head.lower());
    /// ```
    pub fn for_chain(chain: &Chain) -> Self {
        let robot = chain.model().name().to_owned();
        let mut velocity = Vec::with_capacity(chain.dof());
        let mut acceleration = Vec::with_capacity(chain.dof());
        let mut jerk = Vec::with_capacity(chain.dof());
        for (name, &v) in chain.joint_names().iter().zip(chain.velocity_limits()) {
            let v = if v.is_finite() && v > 0.0 { v } else { 1.0 };
            let (a, j) = DEFAULTS
                .iter()
                .find(|(r, joint, _, _)| *r == robot && joint == name)
                .map(|&(_, _, a, j)| (a, j))
                .unwrap_or((2.0 * v, 100.0 * v));
            velocity.push(v);
            acceleration.push(a);
            jerk.push(j);
        }
        let lower = chain
            .lower()
            .iter()
            .zip(chain.continuous())
            .map(|(&l, &c)| if c { f64::NEG_INFINITY } else { l });
        let upper = chain
            .upper()
            .iter()
            .zip(chain.continuous())
            .map(|(&u, &c)| if c { f64::INFINITY } else { u });
        Self {
            velocity,
            acceleration,
            jerk,
            bounds: Some((lower.collect(), upper.collect())),
        }
    }

    /// The same limits with position bounds (`-∞` below and `+∞` above for unbounded
    /// coordinates) that generated motions must respect.
    ///
    /// # Errors
    /// [`TrajectoryError::Dimension`] when either list does not have [`Limits::dim`] entries;
    /// [`TrajectoryError::BadPositionBounds`] for the first coordinate whose bounds are NaN,
    /// inverted (lower above upper), a lower bound of `+∞` or an upper bound of `-∞`.
    ///
    /// ```
    /// use hearth_planning::trajectory::{Limits, TrajectoryError};
    ///
    /// let limits = Limits::new(vec![1.0], vec![2.0], vec![f64::INFINITY])?;
    /// let bounded = limits.clone().with_position_bounds(vec![-0.5], vec![0.5])?;
    /// assert_eq!(bounded.position_bounds(), Some((&[-0.5][..], &[0.5][..])));
    /// assert!(limits.clone().with_position_bounds(vec![f64::NEG_INFINITY], vec![f64::INFINITY]).is_ok());
    /// assert!(limits.clone().with_position_bounds(vec![], vec![0.5]).is_err());
    /// assert_eq!(
    ///     limits.with_position_bounds(vec![0.5], vec![-0.5]).unwrap_err(),
    ///     TrajectoryError::BadPositionBounds { index: 0, lower: 0.5, upper: -0.5 }
    /// );
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn with_position_bounds(mut self, lower: Vec<f64>, upper: Vec<f64>) -> Result<Self, TrajectoryError> {
        for (what, v) in [("lower bounds", &lower), ("upper bounds", &upper)] {
            if v.len() != self.dim() {
                return Err(TrajectoryError::Dimension {
                    what,
                    expected: self.dim(),
                    got: v.len(),
                });
            }
        }
        for (index, (&lower, &upper)) in lower.iter().zip(&upper).enumerate() {
            // False for NaN too.
            if !(lower <= upper && lower < f64::INFINITY && upper > f64::NEG_INFINITY) {
                return Err(TrajectoryError::BadPositionBounds { index, lower, upper });
            }
        }
        self.bounds = Some((lower, upper));
        Ok(self)
    }

    /// The position bounds (lower, upper), when set.
    ///
    /// ```
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let limits = Limits::new(vec![1.0], vec![2.0], vec![f64::INFINITY])?;
    /// assert_eq!(limits.position_bounds(), None);
    /// let limits = limits.with_position_bounds(vec![f64::NEG_INFINITY], vec![1.0])?;
    /// assert_eq!(limits.position_bounds().unwrap().1, &[1.0]);
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn position_bounds(&self) -> Option<(&[f64], &[f64])> {
        self.bounds.as_ref().map(|(l, u)| (l.as_slice(), u.as_slice()))
    }

    /// The same limits with jerk unbounded (acceleration-bounded motion).
    ///
    /// ```
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let limits = Limits::new(vec![1.0, 2.0], vec![3.0, 4.0], vec![50.0, 60.0])?;
    /// let parabolic = limits.without_jerk();
    /// assert_eq!(parabolic.jerk(), &[f64::INFINITY; 2]);
    /// assert_eq!(parabolic.velocity(), limits.velocity());
    /// assert_eq!(parabolic.acceleration(), limits.acceleration());
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn without_jerk(&self) -> Self {
        Self {
            jerk: vec![f64::INFINITY; self.velocity.len()],
            ..self.clone()
        }
    }

    /// Velocity and acceleration scaled by `velocity_scale` and `acceleration_scale`, like
    /// MoveIt's scaling factors. Jerk and position bounds stay as they are.
    ///
    /// # Errors
    ///
    /// [`TrajectoryError::BadScale`] when a factor is not in `(0, 1]` (NaN included).
    ///
    /// ```
    /// use hearth_planning::trajectory::{Limits, TrajectoryError};
    ///
    /// let limits = Limits::new(vec![2.0], vec![4.0], vec![100.0])?;
    /// let slow = limits.scaled(0.5, 0.25)?;
    /// assert_eq!((slow.velocity(), slow.acceleration(), slow.jerk()), (&[1.0][..], &[1.0][..], &[100.0][..]));
    /// assert!(matches!(limits.scaled(2.0, 0.5), Err(TrajectoryError::BadScale { what: "velocity_scale", .. })));
    /// assert!(matches!(limits.scaled(1.0, f64::NAN), Err(TrajectoryError::BadScale { what: "acceleration_scale", .. })));
    /// # Ok::<(), TrajectoryError>(())
    /// ```
    pub fn scaled(&self, velocity_scale: f64, acceleration_scale: f64) -> Result<Self, TrajectoryError> {
        for (what, value) in [
            ("velocity_scale", velocity_scale),
            ("acceleration_scale", acceleration_scale),
        ] {
            if !(value > 0.0 && value <= 1.0) {
                return Err(TrajectoryError::BadScale { what, value });
            }
        }
        Ok(Self {
            velocity: self.velocity.iter().map(|v| v * velocity_scale).collect(),
            acceleration: self.acceleration.iter().map(|a| a * acceleration_scale).collect(),
            jerk: self.jerk.clone(),
            bounds: self.bounds.clone(),
        })
    }

    /// Number of coordinates.
    ///
    /// ```
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let limits = Limits::new(vec![1.0; 3], vec![1.0; 3], vec![1.0; 3])?;
    /// assert_eq!(limits.dim(), 3);
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn dim(&self) -> usize {
        self.velocity.len()
    }

    /// Velocity limits.
    ///
    /// ```
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let limits = Limits::new(vec![1.5, 2.0], vec![3.0; 2], vec![f64::INFINITY; 2])?;
    /// assert_eq!(limits.velocity(), &[1.5, 2.0]);
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }

    /// Acceleration limits.
    ///
    /// ```
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let limits = Limits::new(vec![1.0; 2], vec![3.0, 0.5], vec![f64::INFINITY; 2])?;
    /// assert_eq!(limits.acceleration(), &[3.0, 0.5]);
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn acceleration(&self) -> &[f64] {
        &self.acceleration
    }

    /// Jerk limits (`+∞` when unbounded).
    ///
    /// ```
    /// use hearth_planning::trajectory::Limits;
    ///
    /// let limits = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![20.0, f64::INFINITY])?;
    /// assert_eq!(limits.jerk(), &[20.0, f64::INFINITY]);
    /// # Ok::<(), hearth_planning::trajectory::TrajectoryError>(())
    /// ```
    pub fn jerk(&self) -> &[f64] {
        &self.jerk
    }
}
