//! [`JointSpace`]: the joints of a robot chain, bounded or continuous.

use hearth_kinematics::Chain;
use rand::Rng;

use super::{
    CONTINUOUS_BOUNDS, Space, SpaceError, check_bounds, check_state, coordinate_difference, coordinate_enforce,
    coordinate_interpolate, sample_interval, valid_weight, within,
};

/// The joint space of a robot chain: one coordinate per joint, bounded by its limits, or
/// continuous (wrapping, bounds `[-π, π]`).
///
/// The distance is the weighted Euclidean one, `sqrt(Σ (wᵢ·dᵢ)²)`, where `dᵢ` is the
/// per-joint displacement ([`Space::difference`], the short way round for continuous joints)
/// and the weights `wᵢ` default to 1.
///
/// ```
/// use hearth_planning::kinematics::{Chain, RobotModel};
/// use hearth_planning::space::{JointSpace, Space};
///
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// let arm = Chain::named(&fetch, "arm_with_torso").unwrap();
/// let space = JointSpace::from_chain(&arm)?;
/// assert_eq!(space.dim(), 8);
/// assert_eq!(space.coordinate_name(0), Some("torso_lift_joint"));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct JointSpace {
    names: Vec<String>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    continuous: Vec<bool>,
    /// Whether any joint is continuous (distances of all-bounded spaces skip the wrap test).
    any_continuous: bool,
    /// `continuous` four coordinates to an entry, 1.0 where continuous (the lane masks of
    /// [`squared_differences4`]).
    wrap_lanes: Vec<[f64; 4]>,
    weights: Vec<f64>,
    velocity_limits: Vec<f64>,
}

impl JointSpace {
    /// A joint space from explicit bounds and continuity flags, with joints named `q0`, `q1`, …
    /// (see [`JointSpace::with_names`]).
    ///
    /// The bounds given for continuous joints are ignored (they become `[-π, π]`); bounded
    /// joints need finite bounds with `lower ≤ upper` (equal bounds pin a joint). Velocity
    /// limits start at `+∞`.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space, SpaceError};
    ///
    /// let space = JointSpace::new(&[-1.0, f64::NEG_INFINITY], &[1.0, f64::INFINITY], &[false, true])?;
    /// assert_eq!(space.upper(), &[1.0, std::f64::consts::PI]);
    /// assert!(matches!(
    ///     JointSpace::new(&[0.0], &[1.0, 2.0], &[false]),
    ///     Err(SpaceError::DimensionMismatch { what: "upper bounds", expected: 1, got: 2 })
    /// ));
    /// # Ok::<(), SpaceError>(())
    /// ```
    pub fn new(lower: &[f64], upper: &[f64], continuous: &[bool]) -> Result<Self, SpaceError> {
        let names = (0..lower.len()).map(|i| format!("q{i}")).collect();
        Self::build(names, lower, upper, continuous)
    }

    /// The joint space of a kinematic chain: its joint names, limits, continuous joints and
    /// velocity limits, in chain order.
    ///
    /// Fails only if the model's limits are unusable for a bounded joint (NaN or infinite).
    ///
    /// ```
    /// use hearth_planning::kinematics::{Chain, RobotModel};
    /// use hearth_planning::space::JointSpace;
    ///
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// let space = JointSpace::from_chain(&arm)?;
    /// assert_eq!(space.names(), arm.joint_names());
    /// assert_eq!(space.velocity_limits(), arm.velocity_limits());
    /// // The upper-arm, forearm and wrist roll joints turn without limit.
    /// assert_eq!(space.continuous().iter().filter(|&&c| c).count(), 3);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn from_chain(chain: &Chain) -> Result<Self, SpaceError> {
        let mut space = Self::build(
            chain.joint_names().to_vec(),
            chain.lower(),
            chain.upper(),
            chain.continuous(),
        )?;
        space.velocity_limits.copy_from_slice(chain.velocity_limits());
        Ok(space)
    }

    fn build(names: Vec<String>, lower: &[f64], upper: &[f64], continuous: &[bool]) -> Result<Self, SpaceError> {
        let n = lower.len();
        for (what, got) in [("upper bounds", upper.len()), ("continuous flags", continuous.len())] {
            if got != n {
                return Err(SpaceError::DimensionMismatch { what, expected: n, got });
            }
        }
        let mut lo = Vec::with_capacity(n);
        let mut hi = Vec::with_capacity(n);
        for i in 0..n {
            let (l, u) = if continuous[i] {
                CONTINUOUS_BOUNDS
            } else {
                check_bounds(i, &names[i], lower[i], upper[i])?;
                (lower[i], upper[i])
            };
            lo.push(l);
            hi.push(u);
        }
        Ok(Self {
            names,
            lower: lo,
            upper: hi,
            continuous: continuous.to_vec(),
            any_continuous: continuous.contains(&true),
            wrap_lanes: continuous
                .chunks_exact(4)
                .map(|c| std::array::from_fn(|k| f64::from(u8::from(c[k]))))
                .collect(),
            weights: vec![1.0; n],
            velocity_limits: vec![f64::INFINITY; n],
        })
    }

    /// The same space with per-joint distance weights (finite, non-negative; 0 makes a joint
    /// not count towards the distance).
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let space = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false])?.with_weights(&[2.0, 0.0])?;
    /// assert_eq!(space.distance(&[0.0, 0.0], &[0.5, 1.0]), 1.0);
    /// assert!(space.clone().with_weights(&[-1.0, 1.0]).is_err());
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn with_weights(mut self, weights: &[f64]) -> Result<Self, SpaceError> {
        self.expect_len("weights", weights.len())?;
        if let Some((i, &value)) = weights.iter().enumerate().find(|&(_, &w)| !valid_weight(w)) {
            return Err(SpaceError::InvalidWeight {
                what: self.names[i].clone(),
                value,
            });
        }
        self.weights.copy_from_slice(weights);
        Ok(self)
    }

    /// The same space with the given joint names (used in error messages).
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?.with_names(["lift"])?;
    /// assert_eq!(space.coordinate_name(0), Some("lift"));
    /// assert!(space.check(&[2.0]).unwrap_err().to_string().contains("lift"));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn with_names<S: Into<String>>(mut self, names: impl IntoIterator<Item = S>) -> Result<Self, SpaceError> {
        let names: Vec<String> = names.into_iter().map(Into::into).collect();
        self.expect_len("names", names.len())?;
        self.names = names;
        Ok(self)
    }

    /// The same space with per-joint velocity limits (positive; `+∞` for none), for
    /// trajectory timing.
    ///
    /// ```
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?.with_velocity_limits(&[0.5])?;
    /// assert_eq!(space.velocity_limits(), &[0.5]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn with_velocity_limits(mut self, limits: &[f64]) -> Result<Self, SpaceError> {
        self.expect_len("velocity limits", limits.len())?;
        if let Some((i, &value)) = limits.iter().enumerate().find(|&(_, &v)| v.is_nan() || v <= 0.0) {
            return Err(SpaceError::InvalidVelocityLimit {
                name: self.names[i].clone(),
                value,
            });
        }
        self.velocity_limits.copy_from_slice(limits);
        Ok(self)
    }

    fn expect_len(&self, what: &'static str, got: usize) -> Result<(), SpaceError> {
        if got == self.dim() {
            Ok(())
        } else {
            Err(SpaceError::DimensionMismatch {
                what,
                expected: self.dim(),
                got,
            })
        }
    }

    /// Joint names, in coordinate order (`q0`, `q1`, … unless set with
    /// [`JointSpace::with_names`]).
    ///
    /// ```
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// assert_eq!(space.names(), ["q0", "q1"]);
    /// assert_eq!(space.with_names(["lift", "pan"])?.names(), ["lift", "pan"]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Which joints are continuous.
    ///
    /// ```
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
    /// assert_eq!(space.continuous(), &[false, true]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn continuous(&self) -> &[bool] {
        &self.continuous
    }

    /// Distance weights per joint (1 unless set with [`JointSpace::with_weights`]).
    ///
    /// ```
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// assert_eq!(space.weights(), &[1.0, 1.0]);
    /// assert_eq!(space.with_weights(&[0.5, 2.0])?.weights(), &[0.5, 2.0]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Velocity limits per joint (`+∞` where none was given).
    ///
    /// ```
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// assert_eq!(space.velocity_limits(), &[f64::INFINITY; 2]);
    /// assert_eq!(space.with_velocity_limits(&[0.5, f64::INFINITY])?.velocity_limits(), &[0.5, f64::INFINITY]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn velocity_limits(&self) -> &[f64] {
        &self.velocity_limits
    }
}

impl Space for JointSpace {
    #[inline]
    fn dim(&self) -> usize {
        self.lower.len()
    }

    #[inline]
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.dim());
        for ((x, &lo), &hi) in out.iter_mut().zip(&self.lower).zip(&self.upper) {
            *x = sample_interval(rng, lo, hi);
        }
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        debug_assert_eq!(a.len(), self.dim());
        debug_assert_eq!(b.len(), self.dim());
        // Indexed over equal-length slices, so that the loop carries no bounds checks; the
        // sum runs in coordinate order either way.
        let n = self.weights.len().min(a.len()).min(b.len());
        let (a, b, w) = (&a[..n], &b[..n], &self.weights[..n]);
        let mut sum = 0.0;
        if self.any_continuous {
            let c = &self.continuous[..n];
            // Four coordinates at a time: the differences, wrapped where continuous, weighted
            // and squared in lanes (the same operations as one at a time, so the same bits),
            // then summed in coordinate order.
            let mut i = 0;
            while i + 4 <= n {
                let wrap = &self.wrap_lanes[i / 4];
                let squares = squared_differences4(&a[i..i + 4], &b[i..i + 4], &w[i..i + 4], wrap);
                for q in squares {
                    sum += q;
                }
                i += 4;
            }
            for i in i..n {
                let d = w[i] * coordinate_difference(c[i], a[i], b[i]);
                sum += d * d;
            }
        } else {
            for i in 0..n {
                let d = w[i] * (b[i] - a[i]);
                sum += d * d;
            }
        }
        sum.sqrt()
    }

    #[inline]
    fn interpolate(&self, a: &[f64], b: &[f64], t: f64, out: &mut [f64]) {
        debug_assert_eq!(a.len(), self.dim());
        debug_assert_eq!(b.len(), self.dim());
        debug_assert_eq!(out.len(), self.dim());
        let t = t.clamp(0.0, 1.0);
        if t <= 0.0 {
            out.copy_from_slice(a);
        } else if t >= 1.0 {
            out.copy_from_slice(b);
        } else {
            for (((o, &x), &y), &c) in out.iter_mut().zip(a).zip(b).zip(&self.continuous) {
                *o = coordinate_interpolate(c, x, y, t);
            }
        }
    }

    #[inline]
    fn lower(&self) -> &[f64] {
        &self.lower
    }

    #[inline]
    fn upper(&self) -> &[f64] {
        &self.upper
    }

    #[inline]
    fn enforce_bounds(&self, q: &mut [f64]) {
        debug_assert_eq!(q.len(), self.dim());
        for (((x, &c), &lo), &hi) in q.iter_mut().zip(&self.continuous).zip(&self.lower).zip(&self.upper) {
            *x = coordinate_enforce(c, *x, lo, hi);
        }
    }

    #[inline]
    fn satisfies_bounds(&self, q: &[f64]) -> bool {
        within(q, &self.lower, &self.upper)
    }

    #[inline]
    fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        debug_assert_eq!(a.len(), self.dim());
        debug_assert_eq!(b.len(), self.dim());
        debug_assert_eq!(out.len(), self.dim());
        for (((o, &x), &y), &c) in out.iter_mut().zip(a).zip(b).zip(&self.continuous) {
            *o = coordinate_difference(c, x, y);
        }
    }

    fn check(&self, q: &[f64]) -> Result<(), SpaceError> {
        check_state(q, &self.lower, &self.upper, |i| &self.names[i])
    }

    fn coordinate_name(&self, i: usize) -> Option<&str> {
        self.names.get(i).map(String::as_str)
    }

    fn euclidean_weights(&self) -> Option<&[f64]> {
        (!self.any_continuous).then_some(&self.weights[..])
    }

    fn wrapping_weights(&self) -> Option<(&[f64], &[bool])> {
        Some((&self.weights, &self.continuous))
    }
}

/// `(w·(b − a))²` for four coordinates, the difference wrapped into `(-π, π]` in the lanes
/// where `wrap` is 1, bit for bit as [`coordinate_difference`] one at a time: differences of
/// wrapped angles are within a turn of that range, which lane selects settle; anything else
/// (a NaN, an angle given unwrapped) goes one at a time.
#[inline(always)]
fn squared_differences4(a: &[f64], b: &[f64], w: &[f64], wrap: &[f64; 4]) -> [f64; 4] {
    use std::f64::consts::{PI, TAU};
    use wide::f64x4;
    let lanes = |v: &[f64]| f64x4::new([v[0], v[1], v[2], v[3]]);
    let x = lanes(b) - lanes(a);
    let wraps = f64x4::new(*wrap).simd_eq(f64x4::splat(1.0));
    let (pi, tau) = (f64x4::splat(PI), f64x4::splat(TAU));
    let inside = x.simd_gt(-pi) & x.simd_le(pi);
    let above = x.simd_gt(pi) & x.simd_lt(tau);
    let below = x.simd_gt(-tau) & x.simd_le(-pi);
    if (inside | above | below | !wraps).to_bitmask() != 0b1111 {
        return std::array::from_fn(|k| {
            let d = w[k] * coordinate_difference(wrap[k] == 1.0, a[k], b[k]);
            d * d
        });
    }
    let wrapped = above.select(x - tau, below.select(x + tau, x));
    let d = lanes(w) * wraps.select(wrapped, x);
    (d * d).to_array()
}
