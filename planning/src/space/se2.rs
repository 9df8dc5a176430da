//! [`Se2Space`]: a mobile base's pose in the plane.

use std::f64::consts::PI;

use hearth_kinematics::wrap_angle;
use rand::Rng;

use super::{
    EuclideanBound, Space, SpaceError, check_bounds, check_state, coordinate_difference, coordinate_interpolate,
    sample_interval, valid_weight, within,
};

const NAMES: [&str; 3] = ["x", "y", "yaw"];
/// Which coordinates are angles: yaw.
const WRAPS: [bool; 3] = [false, false, true];
/// The distance's two norms: the translation's and the yaw's.
const GROUPS: [u8; 3] = [0, 0, 1];

/// SE(2): a planar base pose `(x, y, yaw)`, with `x` and `y` in a rectangle and `yaw` wrapping
/// in `[-π, π]`.
///
/// The distance is `sqrt(dx² + dy²) + w·|dyaw|`, with `dyaw` taken the short way round and the
/// yaw weight `w` in metres per radian ([`Se2Space::DEFAULT_YAW_WEIGHT`] unless set with
/// [`Se2Space::with_yaw_weight`]). Interpolation moves `x`, `y` and `yaw` linearly together
/// (a straight line while turning at a constant rate), which is what holonomic bases and
/// geometric planning want; differential-drive constraints are left to the controller.
///
/// ```
/// use hearth_planning::space::{Se2Space, Space};
///
/// let base = Se2Space::new([-5.0, -5.0], [5.0, 5.0])?;
/// assert_eq!(base.dim(), 3);
/// // 5 m apart, and a quarter turn: 5 + 0.5·π/2.
/// let d = base.distance(&[0.0, 0.0, 0.0], &[3.0, 4.0, std::f64::consts::FRAC_PI_2]);
/// assert!((d - (5.0 + 0.25 * std::f64::consts::PI)).abs() < 1e-12);
/// let mut mid = [0.0; 3];
/// base.interpolate(&[0.0, 0.0, 3.0], &[2.0, 0.0, -3.0], 0.5, &mut mid);
/// assert!((mid[2].abs() - std::f64::consts::PI).abs() < 1e-12); // turned through ±π
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Se2Space {
    lower: [f64; 3],
    upper: [f64; 3],
    /// `[1, 1, yaw weight]`: the yaw weight, and the weights of the distance's Euclidean
    /// bound.
    weights: [f64; 3],
}

impl Se2Space {
    /// Default weight of yaw against translation in the distance: 0.5 m per radian, so a half
    /// turn counts like driving about 1.6 m. It is roughly the distance a point on the rim of
    /// a household mobile base (Fetch, LoCoBot, TurtleBot: radius 0.2–0.3 m) or a held arm
    /// sweeps per radian of turning, so neither translation nor rotation dominates
    /// nearest-neighbour queries.
    ///
    /// ```
    /// use hearth_planning::space::{Se2Space, Space};
    /// use std::f64::consts::{FRAC_PI_2, PI};
    ///
    /// let base = Se2Space::new([0.0, 0.0], [1.0, 1.0])?;
    /// assert_eq!(base.yaw_weight(), Se2Space::DEFAULT_YAW_WEIGHT);
    /// // A half turn in place counts like driving π/2 ≈ 1.57 m.
    /// assert!((base.distance(&[0.0, 0.0, 0.0], &[0.0, 0.0, PI]) - FRAC_PI_2).abs() < 1e-12);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub const DEFAULT_YAW_WEIGHT: f64 = 0.5;

    /// A base space with `x ∈ [lower[0], upper[0]]` and `y ∈ [lower[1], upper[1]]`; bounds
    /// must be finite with lower ≤ upper.
    ///
    /// ```
    /// use hearth_planning::space::{Se2Space, SpaceError};
    ///
    /// assert!(Se2Space::new([0.0, 0.0], [10.0, 8.0]).is_ok());
    /// assert!(matches!(
    ///     Se2Space::new([0.0, 9.0], [10.0, 8.0]),
    ///     Err(SpaceError::InvalidBounds { index: 1, .. })
    /// ));
    /// ```
    pub fn new(lower: [f64; 2], upper: [f64; 2]) -> Result<Self, SpaceError> {
        for i in 0..2 {
            check_bounds(i, NAMES[i], lower[i], upper[i])?;
        }
        Ok(Self {
            lower: [lower[0], lower[1], -PI],
            upper: [upper[0], upper[1], PI],
            weights: [1.0, 1.0, Self::DEFAULT_YAW_WEIGHT],
        })
    }

    /// The same space with another yaw weight (metres per radian; finite, non-negative).
    ///
    /// ```
    /// use hearth_planning::space::{Se2Space, Space};
    ///
    /// let base = Se2Space::new([0.0, 0.0], [1.0, 1.0])?.with_yaw_weight(1.0)?;
    /// assert_eq!(base.distance(&[0.0, 0.0, 0.0], &[0.0, 0.0, 1.0]), 1.0);
    /// assert!(base.with_yaw_weight(f64::NAN).is_err());
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn with_yaw_weight(mut self, weight: f64) -> Result<Self, SpaceError> {
        if !valid_weight(weight) {
            return Err(SpaceError::InvalidWeight {
                what: "yaw".to_owned(),
                value: weight,
            });
        }
        self.weights[2] = weight;
        Ok(self)
    }

    /// The yaw weight in metres per radian.
    ///
    /// ```
    /// use hearth_planning::space::Se2Space;
    ///
    /// let base = Se2Space::new([0.0, 0.0], [1.0, 1.0])?;
    /// assert_eq!(base.yaw_weight(), 0.5);
    /// assert_eq!(base.with_yaw_weight(2.0)?.yaw_weight(), 2.0);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn yaw_weight(&self) -> f64 {
        self.weights[2]
    }
}

impl Space for Se2Space {
    #[inline]
    fn dim(&self) -> usize {
        3
    }

    #[inline]
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        debug_assert_eq!(out.len(), 3);
        for ((o, &lo), &hi) in out.iter_mut().zip(&self.lower).zip(&self.upper) {
            *o = sample_interval(rng, lo, hi);
        }
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        debug_assert_eq!(a.len(), 3);
        debug_assert_eq!(b.len(), 3);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        (dx * dx + dy * dy).sqrt() + self.weights[2] * wrap_angle(b[2] - a[2]).abs()
    }

    #[inline]
    fn interpolate(&self, a: &[f64], b: &[f64], t: f64, out: &mut [f64]) {
        debug_assert_eq!(a.len(), 3);
        debug_assert_eq!(b.len(), 3);
        debug_assert_eq!(out.len(), 3);
        let t = t.clamp(0.0, 1.0);
        if t <= 0.0 {
            out.copy_from_slice(a);
        } else if t >= 1.0 {
            out.copy_from_slice(b);
        } else {
            out[0] = coordinate_interpolate(false, a[0], b[0], t);
            out[1] = coordinate_interpolate(false, a[1], b[1], t);
            out[2] = coordinate_interpolate(true, a[2], b[2], t);
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
        debug_assert_eq!(q.len(), 3);
        q[0] = q[0].max(self.lower[0]).min(self.upper[0]);
        q[1] = q[1].max(self.lower[1]).min(self.upper[1]);
        q[2] = wrap_angle(q[2]);
    }

    #[inline]
    fn satisfies_bounds(&self, q: &[f64]) -> bool {
        within(q, &self.lower, &self.upper)
    }

    #[inline]
    fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        debug_assert_eq!(a.len(), 3);
        debug_assert_eq!(b.len(), 3);
        debug_assert_eq!(out.len(), 3);
        out[0] = coordinate_difference(false, a[0], b[0]);
        out[1] = coordinate_difference(false, a[1], b[1]);
        out[2] = coordinate_difference(true, a[2], b[2]);
    }

    fn check(&self, q: &[f64]) -> Result<(), SpaceError> {
        check_state(q, &self.lower, &self.upper, |i| NAMES[i])
    }

    fn coordinate_name(&self, i: usize) -> Option<&str> {
        NAMES.get(i).copied()
    }

    /// `√(dx² + dy² + (w·dyaw)²)`: the distance, `√(dx² + dy²) + w·|dyaw|`, is at least
    /// that and at most √2 times it (a sum of two non-negative terms against the root of
    /// their squares). Its two groups, translation and yaw, make `L` the distance itself.
    fn euclidean_bound(&self) -> Option<EuclideanBound<'_>> {
        Some(EuclideanBound {
            weights: &self.weights,
            wraps: &WRAPS,
            groups: &GROUPS,
            stretch: std::f64::consts::SQRT_2,
        })
    }
}
