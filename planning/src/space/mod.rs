//! Configuration spaces: sampling, distance, interpolation and bounds of planner states.
//!
//! The cut follows OMPL's `StateSpace`, with states as plain `&[f64]` / `&mut [f64]` slices
//! so that planners keep them in flat arenas and nothing on the hot path allocates:
//!
//! - [`Space`]: the trait planners are generic over.
//! - [`JointSpace`]: a robot chain's joints, bounded or continuous (wrapping) ones.
//! - [`Se2Space`]: a mobile base `(x, y, yaw)`.
//! - [`CompoundSpace`]: two spaces side by side (e.g. a base and an arm), zero-cost.
//! - [`SpaceError`]: what is wrong with a state or with a space's description.
//!
//! ```
//! use hearth_planning::space::{JointSpace, Space};
//! use rand::SeedableRng;
//!
//! // A bounded joint and a continuous one.
//! let space = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
//! let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
//! let mut q = [0.0; 2];
//! space.sample(&mut rng, &mut q);
//! assert!(space.satisfies_bounds(&q));
//! // The continuous joint goes the short way round, through ±π.
//! assert!((space.distance(&[0.0, 3.1], &[0.0, -3.1]) - 0.0832).abs() < 1e-3);
//! # Ok::<(), hearth_planning::space::SpaceError>(())
//! ```

mod compound;
mod joint;
mod se2;

pub use compound::CompoundSpace;
pub use joint::JointSpace;
pub use se2::Se2Space;

use std::f64::consts::PI;

use hearth_kinematics::wrap_angle;

use crate::error::Num;
use rand::{Rng, RngExt};

/// A configuration space: where planner states live and how far apart they are.
///
/// States are `&[f64]` slices of length [`Space::dim`]. Every method but [`Space::check`] and
/// [`Space::satisfies_bounds`] expects slices of exactly that length and checks it only in
/// debug builds (these run millions of times per plan); validate foreign input, such as a
/// problem file's start and goal, once with [`Space::check`]. None of the methods allocate.
///
/// [`Space::sample`] is generic over the random number generator, so the trait is not
/// dyn-compatible: planners are generic over `S: Space`, which lets the compiler inline the
/// per-coordinate loops of the concrete space (and of both halves of a [`CompoundSpace`])
/// instead of paying a virtual call per state and per random number. A caller holding a
/// `&mut dyn Rng` can still pass it, since `R` may be unsized.
///
/// ```
/// use hearth_planning::space::{Se2Space, Space};
///
/// fn path_length<S: Space>(space: &S, path: &[Vec<f64>]) -> f64 {
///     path.windows(2).map(|w| space.distance(&w[0], &w[1])).sum()
/// }
/// let base = Se2Space::new([0.0, 0.0], [10.0, 10.0])?;
/// let path = vec![vec![0.0, 0.0, 0.0], vec![3.0, 4.0, 0.0]];
/// assert_eq!(path_length(&base, &path), 5.0);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
pub trait Space: Send + Sync {
    /// Number of coordinates of a state.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Se2Space, Space};
    ///
    /// assert_eq!(Se2Space::new([0.0, 0.0], [1.0, 1.0])?.dim(), 3);
    /// assert_eq!(JointSpace::new(&[0.0; 4], &[1.0; 4], &[false; 4])?.dim(), 4);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn dim(&self) -> usize;

    /// Writes a state drawn uniformly inside the bounds into `out` (continuous coordinates in
    /// `[-π, π)`). The same generator state gives the same sample, bit for bit.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    /// use rand::SeedableRng;
    ///
    /// let space = JointSpace::new(&[0.0, -2.0], &[1.0, 2.0], &[false, false])?;
    /// let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
    /// space.sample(&mut rand_pcg::Pcg64Mcg::seed_from_u64(3), &mut a);
    /// space.sample(&mut rand_pcg::Pcg64Mcg::seed_from_u64(3), &mut b);
    /// assert_eq!(a, b);
    /// assert!(space.satisfies_bounds(&a));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]);

    /// The distance between two states: a metric (symmetric, zero on equal states, obeys the
    /// triangle inequality), measured along the shortest way, so continuous coordinates are
    /// compared modulo 2π.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    /// use std::f64::consts::PI;
    ///
    /// let space = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
    /// // 0.3 on the bounded joint, 0.4 through ±π on the continuous one.
    /// let (a, b) = ([0.0, PI - 0.2], [0.3, -PI + 0.2]);
    /// assert!((space.distance(&a, &b) - 0.5).abs() < 1e-12);
    /// assert_eq!(space.distance(&a, &b), space.distance(&b, &a));
    /// assert_eq!(space.distance(&a, &a), 0.0);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn distance(&self, a: &[f64], b: &[f64]) -> f64;

    /// Writes the state a fraction `t` of the way from `a` to `b` into `out`, along the
    /// shortest way (continuous coordinates wrap through ±π when that is shorter).
    ///
    /// `t = 0` gives `a` and `t = 1` gives `b`, bit for bit; `t` outside `[0, 1]` is clamped.
    /// `distance(a, interpolate(a, b, t)) = t · distance(a, b)` up to rounding, and the result
    /// lies within the bounds when `a` and `b` do.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let space = JointSpace::new(&[0.0, 0.0], &[2.0, 2.0], &[false, false])?;
    /// let mut out = [0.0; 2];
    /// space.interpolate(&[0.0, 0.0], &[2.0, 1.0], 0.25, &mut out);
    /// assert_eq!(out, [0.5, 0.25]);
    /// space.interpolate(&[0.0, 0.0], &[2.0, 1.0], 3.0, &mut out); // clamped to t = 1
    /// assert_eq!(out, [2.0, 1.0]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn interpolate(&self, a: &[f64], b: &[f64], t: f64, out: &mut [f64]);

    /// Lower bounds per coordinate (`-π` for continuous coordinates).
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let space = JointSpace::new(&[-1.0, 0.0], &[2.0, 0.0], &[false, true])?;
    /// assert_eq!(space.lower(), &[-1.0, -std::f64::consts::PI]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn lower(&self) -> &[f64];

    /// Upper bounds per coordinate (`π` for continuous coordinates).
    ///
    /// ```
    /// use hearth_planning::space::{Se2Space, Space};
    ///
    /// let base = Se2Space::new([-1.0, -2.0], [3.0, 4.0])?;
    /// assert_eq!(base.upper(), &[3.0, 4.0, std::f64::consts::PI]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn upper(&self) -> &[f64];

    /// Brings `q` into the bounds: bounded coordinates are clamped, continuous ones wrapped
    /// into `(-π, π]`. NaN stays NaN.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    /// use std::f64::consts::TAU;
    ///
    /// let space = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
    /// let mut q = [1.5, 4.0];
    /// space.enforce_bounds(&mut q);
    /// assert_eq!(q[0], 1.0);
    /// assert!((q[1] - (4.0 - TAU)).abs() < 1e-12);
    /// assert!(space.satisfies_bounds(&q));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn enforce_bounds(&self, q: &mut [f64]);

    /// Whether `q` has [`Space::dim`] coordinates, all within their bounds (inclusive;
    /// continuous coordinates within `[-π, π]`). NaN is out of bounds.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let space = JointSpace::new(&[-1.0], &[1.0], &[false])?;
    /// assert!(space.satisfies_bounds(&[1.0]));
    /// assert!(!space.satisfies_bounds(&[1.1]));
    /// assert!(!space.satisfies_bounds(&[f64::NAN]));
    /// assert!(!space.satisfies_bounds(&[0.0, 0.0])); // wrong length
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn satisfies_bounds(&self, q: &[f64]) -> bool;

    /// Writes `b ⊖ a` into `out`: `b[i] - a[i]` per coordinate, wrapped into `(-π, π]` for
    /// continuous ones, so that `a + difference` reaches `b` the short way. Shortcutting and
    /// trajectory timing work on these per-coordinate displacements.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    /// use std::f64::consts::TAU;
    ///
    /// let space = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
    /// let mut d = [0.0; 2];
    /// space.difference(&[0.5, 3.0], &[-0.5, -3.0], &mut d);
    /// assert_eq!(d[0], -1.0);
    /// assert!((d[1] - (TAU - 6.0)).abs() < 1e-12); // +0.28 through π, not -6
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]);

    /// Checks a state from outside (a problem file, a user): its length, that every coordinate
    /// is a finite number and within the bounds. The error names the first bad coordinate.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space, SpaceError};
    ///
    /// let space = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false])?;
    /// assert!(space.check(&[0.5, -0.5]).is_ok());
    /// assert!(matches!(space.check(&[0.5]), Err(SpaceError::DimensionMismatch { expected: 2, got: 1, .. })));
    /// assert!(matches!(space.check(&[0.0, 7.0]), Err(SpaceError::OutOfBounds { index: 1, .. })));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn check(&self, q: &[f64]) -> Result<(), SpaceError>;

    /// The name of coordinate `i` (a joint name, `x`, `y`, `yaw`), or `None` past the end.
    ///
    /// ```
    /// use hearth_planning::space::{Se2Space, Space};
    ///
    /// let base = Se2Space::new([0.0, 0.0], [1.0, 1.0])?;
    /// assert_eq!(base.coordinate_name(2), Some("yaw"));
    /// assert_eq!(base.coordinate_name(3), None);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn coordinate_name(&self, i: usize) -> Option<&str>;

    /// `Some(w)` when [`Space::distance`] is exactly the weighted Euclidean distance
    /// `√Σ (wᵢ (aᵢ − bᵢ))²`, with no wrapping coordinate: nearest-neighbour search then uses
    /// k-d trees. The default, `None`, makes no such promise (the search then relies on the
    /// triangle inequality only).
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let bounded = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false])?;
    /// assert_eq!(bounded.euclidean_weights(), Some(&[1.0, 1.0][..]));
    /// let wrapping = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
    /// assert_eq!(wrapping.euclidean_weights(), None);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn euclidean_weights(&self) -> Option<&[f64]> {
        None
    }

    /// `Some((w, wraps))` when [`Space::distance`] is `√Σ (wᵢ dᵢ)²`, where `dᵢ = bᵢ − aᵢ` for a
    /// coordinate with `wraps[i]` false and that difference wrapped into `(−π, π]` (an angle)
    /// for one with `wraps[i]` true: nearest-neighbour search then uses k-d trees on the torus.
    /// The default, `None`, makes no such promise.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let wrapping = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
    /// let (weights, wraps) = wrapping.wrapping_weights().unwrap();
    /// assert_eq!((weights, wraps), (&[1.0, 1.0][..], &[false, true][..]));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn wrapping_weights(&self) -> Option<(&[f64], &[bool])> {
        None
    }

    /// A weighted Euclidean distance that bounds [`Space::distance`] from both sides
    /// ([`EuclideanBound`]), so that nearest-neighbour search can use k-d trees even where the
    /// metric is not Euclidean itself. The default offers [`Space::euclidean_weights`] or
    /// [`Space::wrapping_weights`] with stretch 1 (the bound is the distance); an
    /// [`Se2Space`] offers its translation and weighted yaw, which its distance (a sum, not a
    /// root of squares) exceeds by at most √2.
    ///
    /// ```
    /// use hearth_planning::space::{JointSpace, Se2Space, Space};
    ///
    /// let arm = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false])?;
    /// let bound = arm.euclidean_bound().unwrap();
    /// assert_eq!((bound.weights, bound.stretch), (&[1.0, 1.0][..], 1.0));
    /// let base = Se2Space::new([0.0, 0.0], [4.0, 4.0])?;
    /// let (a, b) = ([0.0, 0.0, 0.0], [3.0, 4.0, 1.0]);
    /// let bound = base.euclidean_bound().unwrap();
    /// let e = bound.distance(&a, &b);
    /// assert!(e <= base.distance(&a, &b) && base.distance(&a, &b) <= bound.stretch * e);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn euclidean_bound(&self) -> Option<EuclideanBound<'_>> {
        match self.euclidean_weights() {
            Some(weights) => Some(EuclideanBound {
                weights,
                wraps: &[],
                groups: &[],
                stretch: 1.0,
            }),
            None => self.wrapping_weights().map(|(weights, wraps)| EuclideanBound {
                weights,
                wraps,
                groups: &[],
                stretch: 1.0,
            }),
        }
    }
}

/// A weighted Euclidean distance `E(a, b) = √Σ (wᵢ dᵢ)²` that bounds a space's distance `D`
/// from both sides: `E ≤ D ≤ stretch · E`, where `dᵢ = bᵢ − aᵢ`, wrapped into `(−π, π]` for
/// a coordinate that `wraps` marks (an empty `wraps` marks none). Where `D` adds up norms of
/// groups of coordinates (SE(2): the translation's and the yaw's), `groups` names each
/// coordinate's group, and the sum of the groups' weighted norms, `L` ([`lower`]), must be
/// at most `D` too; `E ≤ L` always.
///
/// Nearest-neighbour search ([`NearestNeighbors`](crate::nn::NearestNeighbors)) prunes with
/// `E` (and, for a k-d tree's boxes, `L`) as a lower bound and decides with the space's own
/// distance, so its answers stay exact; the tighter the bound, the more it prunes. A bound
/// with weights that are not finite and non-negative, weights or groups of another length
/// than the space, or a stretch below 1 or not finite is ignored, as is any bound of a space
/// of more than 32 coordinates (the search then relies on the triangle inequality).
///
/// [`lower`]: EuclideanBound::lower
///
/// ```
/// use hearth_planning::space::EuclideanBound;
///
/// let bound = EuclideanBound { weights: &[1.0, 2.0], wraps: &[], groups: &[], stretch: 1.0 };
/// assert_eq!(bound.distance(&[0.0, 0.0], &[3.0, 2.0]), 5.0);
/// let angle = EuclideanBound { weights: &[1.0], wraps: &[true], groups: &[], stretch: 1.0 };
/// assert!((angle.distance(&[3.0], &[-3.0]) - (std::f64::consts::TAU - 6.0)).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EuclideanBound<'a> {
    /// Weight per coordinate.
    pub weights: &'a [f64],
    /// Which coordinates are angles (empty: none).
    pub wraps: &'a [bool],
    /// Per coordinate, the group whose norm it counts in (empty: one group of all).
    pub groups: &'a [u8],
    /// How far the space's distance may exceed `E`, as a factor (at least 1).
    pub stretch: f64,
}

impl EuclideanBound<'_> {
    /// `E(a, b)`, the bound itself.
    ///
    /// ```
    /// use hearth_planning::space::EuclideanBound;
    ///
    /// let bound = EuclideanBound { weights: &[0.5], wraps: &[], groups: &[], stretch: 1.0 };
    /// assert_eq!(bound.distance(&[1.0], &[3.0]), 1.0);
    /// ```
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.group_sums(a, b).iter().sum::<f64>().sqrt()
    }

    /// `L(a, b)`: the sum over the groups of each group's weighted Euclidean norm (`E` when
    /// there is one group).
    ///
    /// ```
    /// use hearth_planning::space::EuclideanBound;
    ///
    /// // Translation, then a weighted angle: SE(2)'s distance.
    /// let se2 = EuclideanBound {
    ///     weights: &[1.0, 1.0, 0.5],
    ///     wraps: &[false, false, true],
    ///     groups: &[0, 0, 1],
    ///     stretch: 2f64.sqrt(),
    /// };
    /// assert_eq!(se2.lower(&[0.0, 0.0, 0.0], &[3.0, 4.0, 1.0]), 5.5);
    /// assert!(se2.distance(&[0.0, 0.0, 0.0], &[3.0, 4.0, 1.0]) < 5.5);
    /// ```
    pub fn lower(&self, a: &[f64], b: &[f64]) -> f64 {
        self.group_sums(a, b).iter().map(|s| s.sqrt()).sum()
    }

    /// Each group's weighted squared norm of `b − a` (groups that no coordinate names: 0).
    fn group_sums(&self, a: &[f64], b: &[f64]) -> [f64; 256] {
        let mut sums = [0.0; 256];
        for (i, ((&x, &y), &w)) in a.iter().zip(b).zip(self.weights).enumerate() {
            let wraps = self.wraps.get(i).copied().unwrap_or(false);
            let d = w * coordinate_difference(wraps, x, y);
            sums[self.groups.get(i).map_or(0, |&g| usize::from(g))] += d * d;
        }
        sums
    }

    /// Whether search can use this bound for `dim`-dimensional states (see the type's
    /// documentation).
    pub(crate) fn usable(&self, dim: usize) -> bool {
        self.weights.len() == dim
            && (self.wraps.is_empty() || self.wraps.len() == dim)
            && (self.groups.is_empty() || self.groups.len() == dim)
            && self.weights.iter().all(|w| w.is_finite() && *w >= 0.0)
            && self.stretch.is_finite()
            && self.stretch >= 1.0
    }
}

/// Writes into `out` the state `range` from `from` on the way to `target`, or `target` itself
/// when it is no farther: the step of a tree planner towards a sample. Returns the distance
/// from `from` to `target`.
pub(crate) fn steer<S: Space + ?Sized>(space: &S, from: &[f64], target: &[f64], range: f64, out: &mut [f64]) -> f64 {
    let d = space.distance(from, target);
    if d > range {
        space.interpolate(from, target, range / d, out);
    } else {
        out.copy_from_slice(target);
    }
    d
}

/// Writes into `out` the point at a uniform random distance of at most `radius` from `centre`
/// on the way to `towards` (all of `towards` when it is nearer): a uniform sample `towards`
/// pulled into the neighbourhood of `centre`. Used to sample near goals (RRT's goal zone) and
/// near failed edges (LazyPRM's node enhancement). Draws one random number when `towards` is
/// not `centre`, none otherwise.
pub(crate) fn pull_towards<S: Space + ?Sized, R: Rng + ?Sized>(
    space: &S,
    centre: &[f64],
    towards: &[f64],
    radius: f64,
    rng: &mut R,
    out: &mut [f64],
) {
    let d = space.distance(centre, towards);
    if d > 0.0 {
        let t = (rng.random::<f64>() * radius / d).min(1.0);
        space.interpolate(centre, towards, t, out);
    } else {
        out.copy_from_slice(towards);
    }
}

/// What is wrong with a state, or with the description of a space.
///
/// ```
/// use hearth_planning::space::{JointSpace, Space, SpaceError};
///
/// let space = JointSpace::new(&[-1.0], &[1.0], &[false])?;
/// assert!(matches!(space.check(&[2.0]), Err(SpaceError::OutOfBounds { index: 0, .. })));
/// assert!(matches!(space.check(&[f64::NAN]), Err(SpaceError::NotFinite { index: 0, .. })));
/// assert!(matches!(JointSpace::new(&[1.0], &[-1.0], &[false]), Err(SpaceError::InvalidBounds { .. })));
/// # Ok::<(), SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SpaceError {
    /// A state or a per-coordinate list has the wrong number of entries.
    #[error("{what} has {got} entries, the space has {expected} coordinates")]
    DimensionMismatch {
        /// What was too long or too short (`state`, `upper bounds`, `weights`, …).
        what: &'static str,
        /// The space's dimension.
        expected: usize,
        /// The number of entries given.
        got: usize,
    },
    /// A coordinate of a state is NaN or infinite.
    #[error("coordinate {index} ({name}) is {v}, not a finite number", v = Num(*.value))]
    NotFinite {
        /// Index of the coordinate in the state.
        index: usize,
        /// Name of the coordinate.
        name: String,
        /// The value found.
        value: f64,
    },
    /// A coordinate of a state lies outside its bounds.
    #[error("coordinate {index} ({name}) is {v}, outside its bounds [{lo}, {hi}]", v = Num(*.value), lo = Num(*.lower), hi = Num(*.upper))]
    OutOfBounds {
        /// Index of the coordinate in the state.
        index: usize,
        /// Name of the coordinate.
        name: String,
        /// The value found.
        value: f64,
        /// Its lower bound.
        lower: f64,
        /// Its upper bound.
        upper: f64,
    },
    /// A space was described with unusable bounds (NaN, infinite, or lower above upper).
    #[error("coordinate {index} ({name}) has bounds [{lo}, {hi}]: {why}", lo = Num(*.lower), hi = Num(*.upper))]
    InvalidBounds {
        /// Index of the coordinate.
        index: usize,
        /// Name of the coordinate.
        name: String,
        /// The lower bound given.
        lower: f64,
        /// The upper bound given.
        upper: f64,
        /// What is wrong with them.
        why: &'static str,
    },
    /// A distance weight is negative, NaN or infinite.
    #[error("weight of {what} is {v}; weights must be finite and non-negative", v = Num(*.value))]
    InvalidWeight {
        /// Whose weight (a coordinate name, `yaw`, `first space`, …).
        what: String,
        /// The value given.
        value: f64,
    },
    /// A velocity limit is not positive (NaN, zero or negative).
    #[error("velocity limit of {name} is {v}; it must be positive (or +inf)", v = Num(*.value))]
    InvalidVelocityLimit {
        /// Name of the coordinate.
        name: String,
        /// The value given.
        value: f64,
    },
}

impl SpaceError {
    /// The same error with coordinate indices shifted by `by` (a sub-space's error reported
    /// in the coordinates of the enclosing [`CompoundSpace`]).
    fn offset(mut self, by: usize) -> Self {
        match &mut self {
            Self::NotFinite { index, .. } | Self::OutOfBounds { index, .. } | Self::InvalidBounds { index, .. } => {
                *index += by
            }
            Self::DimensionMismatch { .. } | Self::InvalidWeight { .. } | Self::InvalidVelocityLimit { .. } => {}
        }
        self
    }
}

/// Whether a weight is usable: finite and non-negative.
fn valid_weight(w: f64) -> bool {
    w.is_finite() && w >= 0.0
}

/// A uniform sample of `[lo, hi)` (`lo` when the interval is a point). Same formula as
/// [`hearth_kinematics::Chain::random_configuration`], so both give the same values from the
/// same generator.
#[inline]
fn sample_interval<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    let r: f64 = rng.random();
    if hi > lo { (lo + (hi - lo) * r).min(hi) } else { lo }
}

/// `b ⊖ a` for one coordinate.
#[inline(always)]
fn coordinate_difference(continuous: bool, a: f64, b: f64) -> f64 {
    if continuous { wrap_angle(b - a) } else { b - a }
}

/// One coordinate a fraction `t ∈ [0, 1]` of the way from `a` to `b`, the short way. The
/// result of a bounded coordinate is kept between `a` and `b`, so rounding never leaves the
/// bounds; a continuous one is wrapped into `(-π, π]`.
#[inline(always)]
fn coordinate_interpolate(continuous: bool, a: f64, b: f64, t: f64) -> f64 {
    if continuous {
        wrap_angle(a + t * wrap_angle(b - a))
    } else {
        (a + t * (b - a)).max(a.min(b)).min(a.max(b))
    }
}

/// One coordinate brought into its bounds: clamped, or wrapped when continuous.
#[inline(always)]
fn coordinate_enforce(continuous: bool, x: f64, lo: f64, hi: f64) -> f64 {
    if continuous { wrap_angle(x) } else { x.max(lo).min(hi) }
}

/// Checks a state against flat bounds; `name(i)` names coordinate `i` for the error.
fn check_state<'a>(q: &[f64], lower: &[f64], upper: &[f64], name: impl Fn(usize) -> &'a str) -> Result<(), SpaceError> {
    if q.len() != lower.len() {
        return Err(SpaceError::DimensionMismatch {
            what: "state",
            expected: lower.len(),
            got: q.len(),
        });
    }
    for (index, ((&value, &lo), &hi)) in q.iter().zip(lower).zip(upper).enumerate() {
        if !value.is_finite() {
            return Err(SpaceError::NotFinite {
                index,
                name: name(index).to_owned(),
                value,
            });
        }
        if value < lo || value > hi {
            return Err(SpaceError::OutOfBounds {
                index,
                name: name(index).to_owned(),
                value,
                lower: lo,
                upper: hi,
            });
        }
    }
    Ok(())
}

/// Whether `q` has the right length and lies within flat bounds (NaN is out).
#[inline]
fn within(q: &[f64], lower: &[f64], upper: &[f64]) -> bool {
    q.len() == lower.len()
        && q.iter()
            .zip(lower)
            .zip(upper)
            .all(|((&x, &lo), &hi)| x >= lo && x <= hi)
}

/// Validates the bounds of one coordinate of a bounded (non-continuous) kind.
fn check_bounds(index: usize, name: &str, lower: f64, upper: f64) -> Result<(), SpaceError> {
    let why = if lower.is_nan() || upper.is_nan() {
        "a bound is NaN"
    } else if lower.is_infinite() || upper.is_infinite() {
        "a bounded coordinate needs finite bounds (mark it continuous if it wraps)"
    } else if lower > upper {
        "lower bound above upper bound"
    } else {
        return Ok(());
    };
    Err(SpaceError::InvalidBounds {
        index,
        name: name.to_owned(),
        lower,
        upper,
        why,
    })
}

/// Bounds of a continuous coordinate.
const CONTINUOUS_BOUNDS: (f64, f64) = (-PI, PI);
