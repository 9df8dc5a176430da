//! Motion validity: an edge is valid when every state along it, at a fixed resolution, is.

use std::collections::VecDeque;

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
    /// A validator that checks states at most `resolution` apart (in the space's distance).
    pub fn new(space: S, resolution: f64) -> Self {
        let dim = space.dim();
        Self {
            space,
            resolution: if resolution > 0.0 { resolution } else { 0.01 },
            state: vec![0.0; dim],
            batch: Vec::with_capacity(BATCH * dim),
            queue: VecDeque::with_capacity(64),
            motions: 0,
        }
    }

    /// The space.
    pub fn space(&self) -> &S {
        &self.space
    }

    /// The resolution.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Motions checked so far.
    pub fn motions(&self) -> u64 {
        self.motions
    }

    /// Number of segments an edge from `a` to `b` is cut into.
    pub fn segments(&self, a: &[f64], b: &[f64]) -> u32 {
        let d = self.space.distance(a, b);
        ((d / self.resolution).ceil() as u32).max(1)
    }

    /// Whether every intermediate state from `a` to `b` is valid. The states go to the
    /// validator [`BATCH`] at a time in checking order ([`StateValidator::first_invalid`]), so
    /// an implementation can compute them together.
    pub fn check_motion<V: StateValidator + ?Sized>(&mut self, validator: &mut V, a: &[f64], b: &[f64]) -> bool {
        self.motions += 1;
        let n = self.segments(a, b);
        let dim = self.state.len();
        self.queue.clear();
        self.queue.push_back((0, n));
        self.batch.clear();
        while let Some((lo, hi)) = self.queue.pop_front() {
            if hi - lo < 2 {
                continue;
            }
            let mid = lo + (hi - lo) / 2;
            self.space.interpolate(a, b, mid as f64 / n as f64, &mut self.state);
            self.batch.extend_from_slice(&self.state);
            if self.batch.len() == BATCH * dim {
                if validator.first_invalid(&self.batch, dim).is_some() {
                    return false;
                }
                self.batch.clear();
            }
            self.queue.push_back((lo, mid));
            self.queue.push_back((mid, hi));
        }
        self.batch.is_empty() || validator.first_invalid(&self.batch, dim).is_none()
    }
}

/// How many states of an edge [`MotionValidator::check_motion`] hands to the validator at once.
pub const BATCH: usize = 4;
