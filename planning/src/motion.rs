//! Motion validity: an edge is valid when every state along it, at a fixed resolution, is.

use std::collections::VecDeque;

use crate::error::{Num, PlanError};
use crate::planner::{diameter, positive_finite, resolution_or_default};
use crate::space::Space;
use crate::validity::StateValidator;

/// Checks straight-line motions in a [`Space`], coarse to fine: the midpoint first, then the
/// midpoints of the halves, and so on (a colliding edge usually fails within the first few
/// checks). The end points are not checked (planners check states when they add them).
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
///
/// struct Wall { checks: u64 }
/// impl StateValidator for Wall {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.checks += 1; q[0] < 0.5 }
///     fn checks(&self) -> u64 { self.checks }
/// }
/// let space = JointSpace::new(&[-1.0], &[1.0], &[false]).unwrap();
/// let mut mv = MotionValidator::new(space, 0.01);
/// let mut wall = Wall { checks: 0 };
/// assert!(mv.check_motion(&mut wall, &[-1.0], &[0.4]));
/// assert!(!mv.check_motion(&mut wall, &[-1.0], &[1.0]));
/// ```
#[derive(Clone)]
pub struct MotionValidator<S: Space> {
    space: S,
    resolution: f64,
    state: Vec<f64>,
    queue: VecDeque<(u32, u32)>,
    /// The states of the edge being checked, in checking order, a few at a time.
    batch: Vec<f64>,
    motions: u64,
}

impl<S: Space> MotionValidator<S> {
    /// A validator that checks states at most `resolution` apart (in the space's distance). A
    /// resolution that is not positive and finite (0, negative, NaN, infinite) counts as 0.01,
    /// and one finer than [`finest_resolution`] as that; [`MotionValidator::try_new`] refuses
    /// both instead.
    ///
    /// ```
    /// use hearth_planning::motion::{MotionValidator, finest_resolution};
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?;
    /// assert_eq!(MotionValidator::new(space.clone(), 0.05).resolution(), 0.05);
    /// assert_eq!(MotionValidator::new(space.clone(), 0.0).resolution(), 0.01);
    /// // An infinite spacing would check no state between an edge's ends.
    /// assert_eq!(MotionValidator::new(space.clone(), f64::INFINITY).resolution(), 0.01);
    /// // Nor may an edge take without end.
    /// assert_eq!(MotionValidator::new(space.clone(), 1e-300).resolution(), finest_resolution(&space));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn new(space: S, resolution: f64) -> Self {
        let resolution = resolution_or_default(resolution).max(finest_resolution(&space));
        Self::with_resolution(space, resolution)
    }

    /// A validator that checks states at most `resolution` apart, or
    /// [`PlanError::BadInput`] naming the value when `resolution` is not positive and finite
    /// or is finer than [`finest_resolution`] (an edge across the space would take more than
    /// [`MAX_SEGMENTS`] segments: on a Panda's arm, 1 µrad asks for 10⁷ states an edge).
    ///
    /// ```
    /// use hearth_planning::PlanError;
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?;
    /// assert_eq!(MotionValidator::try_new(space.clone(), 0.05)?.resolution(), 0.05);
    /// for bad in [0.0, -0.01, f64::NAN, f64::INFINITY, 1e-300] {
    ///     let err = MotionValidator::try_new(space.clone(), bad).err().unwrap();
    ///     assert!(matches!(err, PlanError::BadInput(ref m) if m.contains("resolution")));
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn try_new(space: S, resolution: f64) -> Result<Self, PlanError> {
        let resolution = checked_resolution(&space, "resolution", resolution)?;
        Ok(Self::with_resolution(space, resolution))
    }

    fn with_resolution(space: S, resolution: f64) -> Self {
        let dim = space.dim();
        Self {
            space,
            resolution,
            state: vec![0.0; dim],
            batch: Vec::with_capacity(BATCH * dim),
            queue: VecDeque::with_capacity(64),
            motions: 0,
        }
    }

    /// The space edges are interpolated and measured in.
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let mv = MotionValidator::new(JointSpace::new(&[0.0; 3], &[1.0; 3], &[false; 3])?, 0.01);
    /// assert_eq!(mv.space().dim(), 3);
    /// assert_eq!(mv.space().distance(&[0.0; 3], &[0.0, 0.3, 0.4]), 0.5);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn space(&self) -> &S {
        &self.space
    }

    /// Swaps the validator's space with `space` (the resolution and the motion count stay).
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::{JointSpace, Space};
    ///
    /// let plain = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// let mut mv = MotionValidator::new(plain.clone(), 0.01);
    /// let mut other = plain.clone().with_weights(&[0.5, 0.5])?;
    /// mv.swap_space(&mut other);
    /// assert_eq!(other.weights(), &[1.0, 1.0]);
    /// assert_eq!(mv.space().distance(&[0.0; 2], &[1.0, 0.0]), 0.5);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn swap_space(&mut self, space: &mut S) {
        std::mem::swap(&mut self.space, space);
    }

    /// The resolution: the largest distance between two consecutive states checked along an
    /// edge.
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let mv = MotionValidator::new(JointSpace::new(&[0.0], &[1.0], &[false])?, 0.02);
    /// assert_eq!(mv.resolution(), 0.02);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Motions checked so far (calls to [`MotionValidator::check_motion`], valid or not).
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::JointSpace;
    /// # use hearth_planning::validity::StateValidator;
    /// # struct Free(u64);
    /// # impl StateValidator for Free {
    /// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
    /// #     fn checks(&self) -> u64 { self.0 }
    /// # }
    /// // `Free` is a validator that accepts every state.
    /// let mut mv = MotionValidator::new(JointSpace::new(&[0.0], &[1.0], &[false])?, 0.1);
    /// assert_eq!(mv.motions(), 0);
    /// mv.check_motion(&mut Free(0), &[0.0], &[1.0]);
    /// mv.check_motion(&mut Free(0), &[1.0], &[0.5]);
    /// assert_eq!(mv.motions(), 2);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn motions(&self) -> u64 {
        self.motions
    }

    /// Number of segments an edge from `a` to `b` is cut into: its length over the resolution,
    /// rounded up, at least 1 and at most [`MAX_SEGMENTS`] (which only an edge longer than the
    /// space's diameter, from a state outside the bounds, can reach: its states are then
    /// further apart than the resolution). [`MotionValidator::check_motion`] checks the
    /// `segments - 1` states between them.
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let mv = MotionValidator::new(JointSpace::new(&[0.0], &[2.0], &[false])?, 0.25);
    /// assert_eq!(mv.segments(&[0.0], &[1.0]), 4);
    /// assert_eq!(mv.segments(&[0.0], &[1.1]), 5);
    /// assert_eq!(mv.segments(&[0.5], &[0.5]), 1);
    /// assert_eq!(mv.segments(&[0.0], &[1e300]), hearth_planning::motion::MAX_SEGMENTS);
    /// assert_eq!(mv.segments(&[0.0], &[f64::NAN]), 1);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn segments(&self, a: &[f64], b: &[f64]) -> u32 {
        let n = (self.space.distance(a, b) / self.resolution).ceil();
        // (A NaN length fails the comparison: one segment, as before the cap.)
        if n > 1.0 { n.min(MAX_SEGMENTS as f64) as u32 } else { 1 }
    }

    /// Whether every intermediate state from `a` to `b` is valid. The states go to the
    /// validator in checking order ([`StateValidator::first_invalid`]): the midpoint alone,
    /// then [`BATCH`] at a time, so an implementation can compute them together. (A colliding
    /// edge fails at its midpoint most often; computing states after it together would be
    /// wasted work then: alone, the midpoint takes 4.7 % off the Fetch planner's instructions
    /// on median bookshelf_thin and table_pick plans.)
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::validity::StateValidator;
    ///
    /// // Records the states it is asked about.
    /// struct Log(Vec<f64>);
    /// impl StateValidator for Log {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0.push(q[0]); true }
    ///     fn checks(&self) -> u64 { self.0.len() as u64 }
    /// }
    /// let mut mv = MotionValidator::new(JointSpace::new(&[0.0], &[1.0], &[false])?, 0.25);
    /// let mut log = Log(Vec::new());
    /// assert!(mv.check_motion(&mut log, &[0.0], &[1.0]));
    /// assert_eq!(log.0, [0.5, 0.25, 0.75]); // midpoint first, end points never
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn check_motion<V: StateValidator + ?Sized>(&mut self, validator: &mut V, a: &[f64], b: &[f64]) -> bool {
        self.motions += 1;
        let n = self.segments(a, b);
        let dim = self.state.len();
        self.queue.clear();
        self.queue.push_back((0, n));
        self.batch.clear();
        // The midpoint alone, then `BATCH` states at a time.
        let mut size = 1;
        while let Some((lo, hi)) = self.queue.pop_front() {
            if hi - lo < 2 {
                continue;
            }
            let mid = lo + (hi - lo) / 2;
            self.space.interpolate(a, b, mid as f64 / n as f64, &mut self.state);
            self.batch.extend_from_slice(&self.state);
            if self.batch.len() == size * dim {
                if validator.first_invalid(&self.batch, dim).is_some() {
                    return false;
                }
                self.batch.clear();
                size = BATCH;
            }
            self.queue.push_back((lo, mid));
            self.queue.push_back((mid, hi));
        }
        self.batch.is_empty() || validator.first_invalid(&self.batch, dim).is_none()
    }
}

/// Most segments [`MotionValidator`] cuts one edge into (2²⁰). The finest resolution a space
/// allows ([`finest_resolution`]) cuts an edge across the whole space into this many, so an
/// edge's check takes bounded time and memory (its queue holds at most half as many entries)
/// whatever resolution a caller asks for.
///
/// ```
/// assert_eq!(hearth_planning::motion::MAX_SEGMENTS, 1 << 20);
/// ```
pub const MAX_SEGMENTS: u32 = 1 << 20;

/// The finest check resolution usable in `space`: its diameter (twice the distance from its
/// lower bounds to its centre, the longest edge within the bounds of a space without
/// continuous coordinates) over [`MAX_SEGMENTS`]; 0 for a space whose diameter is not finite.
/// About 1.2 · 10⁻⁵ rad for a Panda's arm, 6 · 10⁻⁶ rad for one continuous joint.
///
/// ```
/// use hearth_planning::motion::{MAX_SEGMENTS, finest_resolution};
/// use hearth_planning::space::JointSpace;
///
/// let square = JointSpace::new(&[0.0, 0.0], &[3.0, 4.0], &[false, false])?;
/// assert!((finest_resolution(&square) - 5.0 / MAX_SEGMENTS as f64).abs() < 1e-15);
/// // A continuous joint's longest edge is half a turn; the diameter counts a whole one.
/// let wheel = JointSpace::new(&[0.0], &[0.0], &[true])?;
/// assert!((finest_resolution(&wheel) - 2.0 * std::f64::consts::PI / MAX_SEGMENTS as f64).abs() < 1e-15);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
pub fn finest_resolution<S: Space>(space: &S) -> f64 {
    let r = diameter(space) / MAX_SEGMENTS as f64;
    if r.is_finite() { r } else { 0.0 }
}

/// `resolution` if it is positive, finite and no finer than [`finest_resolution`], else
/// [`PlanError::BadInput`] naming the setting `what`.
pub(crate) fn checked_resolution<S: Space>(space: &S, what: &str, resolution: f64) -> Result<f64, PlanError> {
    let r = positive_finite(what, resolution)?;
    let finest = finest_resolution(space);
    if r < finest {
        return Err(PlanError::BadInput(format!(
            "{what} is {}; the finest this space allows is {} (an edge across it, {:.3} long, in at most {MAX_SEGMENTS} segments)",
            Num(r),
            Num(finest),
            diameter(space)
        )));
    }
    Ok(r)
}

/// How many states of an edge [`MotionValidator::check_motion`] hands to the validator at once,
/// after the midpoint, which goes alone.
///
/// ```
/// use hearth_planning::motion::{MotionValidator, BATCH};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
///
/// // Records how many states each call to `first_invalid` gets.
/// struct Batches(Vec<usize>);
/// impl StateValidator for Batches {
///     fn is_valid(&mut self, _: &[f64]) -> bool { true }
///     fn checks(&self) -> u64 { 0 }
///     fn first_invalid(&mut self, states: &[f64], dim: usize) -> Option<usize> {
///         self.0.push(states.len() / dim);
///         None
///     }
/// }
/// let mut mv = MotionValidator::new(JointSpace::new(&[0.0], &[1.0], &[false])?, 0.125);
/// let mut batches = Batches(Vec::new());
/// assert!(mv.check_motion(&mut batches, &[0.0], &[1.0])); // 7 states between the ends
/// assert_eq!(batches.0, [1, BATCH, 7 - 1 - BATCH]); // the midpoint alone first
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
pub const BATCH: usize = 4;
