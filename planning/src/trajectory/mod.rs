//! Time-parametrised trajectories: rest-to-rest straight segments, acceleration-bounded
//! ("parabolic") ramps from shortcutting, jerk-limited motions through waypoints computed by
//! Ruckig (the pure-Rust `rsruckig`, entirely local), and any of these jerk-limited by a
//! moving average ([`Trajectory::with_jerk_limits`]).
//!
//! A [`Trajectory`] is a sequence of spans, each a time window of one piece (a straight line
//! with a trapezoidal speed profile, a ruckig motion, or another trajectory's moving
//! average). Coordinates are *unwrapped*: continuous joints may leave `(-π, π]` so that
//! velocities stay continuous; [`Trajectory::to_path`] wraps them back.
//!
//! ```
//! use hearth_planning::planner::Path;
//! use hearth_planning::space::JointSpace;
//! use hearth_planning::trajectory::{Limits, Trajectory};
//!
//! let space = JointSpace::new(&[-2.0, -2.0], &[2.0, 2.0], &[false, false])?;
//! let limits = Limits::new(vec![1.0, 1.0], vec![2.0, 2.0], vec![f64::INFINITY; 2])?;
//! let path = Path { states: vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![1.0, 1.0]] };
//! let t = Trajectory::rest_to_rest(&space, &path, &limits)?;
//! // 1 rad at 1 rad/s with 2 rad/s²: 0.5 s up, 0.5 s cruise, 0.5 s down, twice.
//! assert!((t.duration() - 3.0).abs() < 1e-9);
//! let (mut q, mut v) = ([0.0; 2], [0.0; 2]);
//! t.sample(1.5, &mut q, Some(&mut v));
//! assert_eq!((q, v), ([1.0, 0.0], [0.0, 0.0]));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod average;
mod generator;
mod limits;
mod ramp;

use std::sync::Arc;

pub use limits::Limits;

use crate::error::Num;
use crate::motion::finest_resolution;
use crate::planner::{Path, positive, resolution_or_default};
use crate::space::Space;
use crate::validity::StateValidator;
use average::Averaged;
use generator::{Generated, Sync};
use ramp::LineRamp;

/// Why a trajectory could not be built, or why it is unusable.
///
/// ```
/// use hearth_planning::planner::Path;
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::trajectory::{Limits, Trajectory, TrajectoryError};
///
/// let space = JointSpace::new(&[-1.0], &[1.0], &[false])?;
/// let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY])?;
/// let empty = Path { states: vec![] };
/// assert_eq!(Trajectory::rest_to_rest(&space, &empty, &limits).unwrap_err(), TrajectoryError::EmptyPath);
/// let nan = Path { states: vec![vec![0.0], vec![f64::NAN]] };
/// let error = Trajectory::rest_to_rest(&space, &nan, &limits).unwrap_err();
/// assert_eq!(error, TrajectoryError::NonFinite { index: 1 });
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TrajectoryError {
    /// Inputs of different lengths.
    #[error("{what} has {got} values, expected {expected}")]
    Dimension {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// A sampling step that is not positive and finite, or so small that sampling would not
    /// end in reasonable time (more than [`Trajectory::MAX_SAMPLES`] samples).
    #[error("{what} is {v} s; it must be positive, finite and at least the duration / {max_samples}", v = Num(*.value))]
    BadStep {
        /// Which step.
        what: &'static str,
        /// Its value.
        value: f64,
        /// The most samples a step may ask for.
        max_samples: u64,
    },
    /// A limit that is not positive (or not finite, where that is required).
    #[error("{what} limit {index} is {v}; it must be positive and finite", v = Num(*.value))]
    BadLimit {
        /// Which limit.
        what: &'static str,
        /// Coordinate.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Position bounds that no number satisfies, or NaN: a lower bound above its upper bound,
    /// a lower bound of `+∞` or an upper bound of `-∞`.
    #[error(
        "position bounds of coordinate {index} are [{lo}, {hi}]; they must be numbers (or -∞ below, +∞ above) with lower ≤ upper",
        lo = Num(*.lower),
        hi = Num(*.upper)
    )]
    BadPositionBounds {
        /// Coordinate.
        index: usize,
        /// Its lower bound.
        lower: f64,
        /// Its upper bound.
        upper: f64,
    },
    /// A path state with a NaN or infinite coordinate. [`Trajectory::ramp`] joins two states,
    /// `(q0, v0)` and `(q1, v1)`: for it, a NaN or infinite position or velocity of state 0 or 1.
    #[error("path state {index} has a non-finite coordinate")]
    NonFinite {
        /// Index of the state (the first such state).
        index: usize,
    },
    /// A check resolution (a distance in the space) that is not positive and finite.
    #[error("the check resolution is {v}; it must be positive and finite", v = Num(*.value))]
    BadResolution {
        /// Its value.
        value: f64,
    },
    /// A check resolution finer than the space allows ([`finest_resolution`]): sampling at it
    /// could take without end.
    #[error("the check resolution is {v}; the finest this space allows is {f}", v = Num(*.value), f = Num(*.finest))]
    ResolutionTooFine {
        /// Its value.
        value: f64,
        /// The finest resolution of the space.
        finest: f64,
    },
    /// A path without states.
    #[error("the path has no states")]
    EmptyPath,
    /// Two motions joined where the first does not end at rest where the second starts.
    #[error(
        "the motions do not meet at rest: coordinate {index} is {e} and {s}, velocities {ve} and {vs}",
        e = Num(*.end),
        s = Num(*.start),
        ve = Num(*.v_end),
        vs = Num(*.v_start)
    )]
    Discontinuous {
        /// Coordinate that differs.
        index: usize,
        /// Its position at the end of the first motion.
        end: f64,
        /// Its position at the start of the second.
        start: f64,
        /// Its velocity at the end of the first motion.
        v_end: f64,
        /// Its velocity at the start of the second.
        v_start: f64,
    },
    /// A scaling factor outside `(0, 1]` (or NaN).
    #[error("{what} is {v}; it must be in (0, 1]", v = Num(*.value))]
    BadScale {
        /// Which factor (`velocity_scale`, `acceleration_scale`).
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// The trajectory generator found no motion.
    #[error("the trajectory generator failed: {0}")]
    Generator(String),
    /// The trajectory leaves the free space.
    #[error("the trajectory is in collision at t = {time:.4} s")]
    InCollision {
        /// First colliding time found.
        time: f64,
    },
}

/// One motion primitive.
#[derive(Debug)]
enum Piece {
    Line(LineRamp),
    Generated(Box<Generated>),
    Averaged(Box<Averaged>),
}

impl Piece {
    fn duration(&self) -> f64 {
        match self {
            Piece::Line(l) => l.duration(),
            Piece::Generated(g) => g.get_duration(),
            Piece::Averaged(a) => a.duration(),
        }
    }

    /// Appends the piece's own times (from its start) where its polynomials change.
    fn knots(&self, out: &mut Vec<f64>) {
        match self {
            Piece::Line(l) => out.extend(l.knots()),
            Piece::Generated(g) => generator::knots(g, out),
            Piece::Averaged(a) => a.knots(out),
        }
    }

    fn eval(&self, t: f64, q: &mut [f64], v: Option<&mut [f64]>) {
        match self {
            Piece::Line(l) => l.eval(t, q, v),
            Piece::Generated(g) => generator::eval(g, t, q, v),
            Piece::Averaged(a) => a.eval(t, q, v),
        }
    }
}

/// A time window `[offset, offset + duration]` of a piece.
#[derive(Clone, Debug)]
struct Span {
    piece: Arc<Piece>,
    offset: f64,
    duration: f64,
    /// Checked at the fine resolution (or part of the motion shortcutting started from).
    verified: bool,
}

/// A time-parametrised motion through configuration space; see the [module](self) docs.
/// Cloning copies the list of spans only; the motion pieces are shared.
///
/// ```
/// use hearth_planning::planner::Path;
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::trajectory::{Limits, Trajectory};
///
/// let space = JointSpace::new(&[0.0], &[4.0], &[false])?;
/// let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY])?;
/// let t = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![0.0], vec![2.0]] }, &limits)?;
/// // 1 s speeding up to 1 rad/s, 1 s at that speed, 1 s slowing down.
/// assert!((t.duration() - 3.0).abs() < 1e-9);
/// let (mut q, mut v) = ([0.0], [0.0]);
/// t.sample(1.5, &mut q, Some(&mut v));
/// assert!((q[0] - 1.0).abs() < 1e-9 && (v[0] - 1.0).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Trajectory {
    dim: usize,
    spans: Vec<Span>,
    /// End time of each span.
    ends: Vec<f64>,
}

/// The path with continuous coordinates unwrapped so that each step is the short way.
fn unwrapped<S: Space>(space: &S, path: &Path) -> Result<Vec<Vec<f64>>, TrajectoryError> {
    let dim = space.dim();
    let first = path.states.first().ok_or(TrajectoryError::EmptyPath)?;
    for (index, q) in path.states.iter().enumerate() {
        if q.len() != dim {
            return Err(TrajectoryError::Dimension {
                what: "path state",
                expected: dim,
                got: q.len(),
            });
        }
        if q.iter().any(|x| !x.is_finite()) {
            return Err(TrajectoryError::NonFinite { index });
        }
    }
    let mut out: Vec<Vec<f64>> = Vec::with_capacity(path.states.len());
    let mut delta = vec![0.0; dim];
    out.push(first.clone());
    for pair in path.states.windows(2) {
        space.difference(&pair[0], &pair[1], &mut delta);
        let prev = out.last().cloned().unwrap_or_default();
        out.push(prev.iter().zip(&delta).map(|(p, d)| p + d).collect());
    }
    Ok(out)
}

fn check_dim_of(what: &'static str, expected: usize, got: usize) -> Result<(), TrajectoryError> {
    if expected == got {
        Ok(())
    } else {
        Err(TrajectoryError::Dimension { what, expected, got })
    }
}

fn check_dim(limits: &Limits, dim: usize) -> Result<(), TrajectoryError> {
    if limits.dim() == dim {
        Ok(())
    } else {
        Err(TrajectoryError::Dimension {
            what: "limits",
            expected: dim,
            got: limits.dim(),
        })
    }
}

impl Trajectory {
    /// The most samples [`Trajectory::peak_velocity_acceleration`] takes (10⁸).
    ///
    /// ```
    /// assert_eq!(hearth_planning::trajectory::Trajectory::MAX_SAMPLES, 100_000_000);
    /// ```
    pub const MAX_SAMPLES: u64 = 100_000_000;

    fn from_pieces(dim: usize, pieces: Vec<Piece>) -> Self {
        let mut t = Self {
            dim,
            spans: Vec::with_capacity(pieces.len()),
            ends: Vec::with_capacity(pieces.len()),
        };
        for piece in pieces {
            let duration = piece.duration();
            t.spans.push(Span {
                piece: Arc::new(piece),
                offset: 0.0,
                duration,
                verified: false,
            });
        }
        t.recompute_ends();
        t
    }

    /// Index of the span playing at time `t` (the first whose end is not before `t`; the last
    /// one past the end). For [`Trajectory::rest_to_rest`] this is the path's segment index.
    pub(crate) fn span_at(&self, t: f64) -> usize {
        self.ends
            .partition_point(|&end| end < t)
            .min(self.spans.len().saturating_sub(1))
    }

    /// Appends the times where the motion's polynomials change: the spans' starts and the
    /// knots of their pieces within them.
    pub(crate) fn knots(&self, out: &mut Vec<f64>) {
        let mut local = Vec::new();
        let mut start = 0.0;
        for s in &self.spans {
            out.push(start);
            local.clear();
            s.piece.knots(&mut local);
            out.extend(
                local
                    .iter()
                    .filter(|&&k| k > s.offset && k < s.offset + s.duration)
                    .map(|&k| start + (k - s.offset)),
            );
            start += s.duration;
        }
    }

    fn recompute_ends(&mut self) {
        self.ends.clear();
        let mut end = 0.0;
        for s in &self.spans {
            end += s.duration;
            self.ends.push(end);
        }
    }

    /// Stops at every waypoint and moves along the straight edges between them with
    /// trapezoidal (acceleration-bounded) speed: exactly the geometric path, so its collision
    /// checks carry over. The usual input of [`parabolic
    /// shortcutting`](crate::shortcut::parabolic). A path of one state gives a motion of
    /// duration 0.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[-2.0, -2.0], &[2.0, 2.0], &[false, false])?;
    /// let limits = Limits::new(vec![1.0, 1.0], vec![2.0, 2.0], vec![f64::INFINITY; 2])?;
    /// let path = Path { states: vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![1.0, 1.0]] };
    /// let t = Trajectory::rest_to_rest(&space, &path, &limits)?;
    /// assert_eq!(t.spans(), 2);
    /// // Both edges take as long, so half way the motion is at rest at the corner.
    /// let (mut q, mut v) = ([0.0; 2], [0.0; 2]);
    /// t.sample(t.duration() / 2.0, &mut q, Some(&mut v));
    /// assert_eq!((q, v), ([1.0, 0.0], [0.0, 0.0]));
    /// let still = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![0.5, 0.5]] }, &limits)?;
    /// assert_eq!(still.duration(), 0.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn rest_to_rest<S: Space>(space: &S, path: &Path, limits: &Limits) -> Result<Self, TrajectoryError> {
        check_dim(limits, space.dim())?;
        let states = unwrapped(space, path)?;
        let mut pieces = Vec::with_capacity(states.len());
        let mut delta = vec![0.0; space.dim()];
        for pair in states.windows(2) {
            for ((d, a), b) in delta.iter_mut().zip(&pair[0]).zip(&pair[1]) {
                *d = b - a;
            }
            pieces.push(Piece::Line(LineRamp::new(&pair[0], &delta, limits)));
        }
        if pieces.is_empty() {
            pieces.push(Piece::Line(LineRamp::new(&states[0], &vec![0.0; space.dim()], limits)));
        }
        Ok(Self::from_pieces(space.dim(), pieces))
    }

    /// This motion followed by `next`, which must start where this one ends (within 1e-6),
    /// both at rest there.
    ///
    /// # Errors
    /// [`TrajectoryError::Dimension`] for motions of different dimensions;
    /// [`TrajectoryError::Discontinuous`] when they do not meet at rest.
    ///
    /// ```
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    /// use hearth_planning::Path;
    /// let space = JointSpace::new(&[-3.0], &[3.0], &[false])?;
    /// let limits = Limits::new(vec![1.0], vec![2.0], vec![f64::INFINITY])?;
    /// let leg = |a: f64, b: f64| Trajectory::rest_to_rest(&space, &Path { states: vec![vec![a], vec![b]] }, &limits);
    /// let both = leg(0.0, 1.0)?.then(leg(1.0, -1.0)?)?;
    /// let mut q = [0.0];
    /// both.sample(both.duration(), &mut q, None);
    /// assert!((q[0] + 1.0).abs() < 1e-9);
    /// assert!(leg(0.0, 1.0)?.then(leg(0.5, 1.0)?).is_err());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn then(mut self, next: Trajectory) -> Result<Trajectory, TrajectoryError> {
        check_dim_of("the second motion", self.dim, next.dim)?;
        let (mut q_end, mut v_end) = (vec![0.0; self.dim], vec![0.0; self.dim]);
        let (mut q_start, mut v_start) = (vec![0.0; self.dim], vec![0.0; self.dim]);
        self.sample(self.duration(), &mut q_end, Some(&mut v_end));
        next.sample(0.0, &mut q_start, Some(&mut v_start));
        for i in 0..self.dim {
            if (q_end[i] - q_start[i]).abs() > 1e-6 || v_end[i].abs() > 1e-6 || v_start[i].abs() > 1e-6 {
                return Err(TrajectoryError::Discontinuous {
                    index: i,
                    end: q_end[i],
                    start: q_start[i],
                    v_end: v_end[i],
                    v_start: v_start[i],
                });
            }
        }
        self.spans.extend(next.spans);
        self.recompute_ends();
        Ok(self)
    }

    /// A jerk-limited motion (Ruckig) from rest at the first waypoint to rest at the last that
    /// passes through the others without stopping. It may cut corners between waypoints, so
    /// check it ([`Trajectory::check`]) or use [`Trajectory::jerk_limited_stops`].
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![20.0; 2])?;
    /// let path = Path { states: vec![vec![0.1, 0.1], vec![0.5, 0.6], vec![0.9, 0.2]] };
    /// let through = Trajectory::jerk_limited(&space, &path, &limits)?;
    /// // Not stopping at the middle waypoint is faster.
    /// assert!(through.duration() < Trajectory::jerk_limited_stops(&space, &path, &limits)?.duration());
    /// let mut q = [0.0; 2];
    /// through.sample(through.duration(), &mut q, None);
    /// assert!((q[0] - 0.9).abs() < 1e-9 && (q[1] - 0.2).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn jerk_limited<S: Space>(space: &S, path: &Path, limits: &Limits) -> Result<Self, TrajectoryError> {
        Self::jerk_limited_with(space, path, limits, Self::DEFAULT_REFINEMENT_SWEEPS)
    }

    /// Sweeps of the waypoint solver's local search in [`Trajectory::jerk_limited`]: the
    /// `rsruckig` default.
    ///
    /// ```
    /// assert_eq!(hearth_planning::trajectory::Trajectory::DEFAULT_REFINEMENT_SWEEPS, 4);
    /// ```
    pub const DEFAULT_REFINEMENT_SWEEPS: usize = rsruckig::calculator_waypoints::DEFAULT_REFINEMENT_SWEEPS;

    /// [`Trajectory::jerk_limited`] with up to `refinement_sweeps` sweeps of the waypoint
    /// solver's local search. The solver first picks a velocity and acceleration for each
    /// waypoint by a rule of thumb, then each sweep tries changes to them, one full
    /// state-to-state solve per try, and keeps those that shorten the motion. Its cost grows
    /// with the sweeps, the waypoints and the joints; 0 keeps the first choice: the same
    /// limits and waypoints, a slower motion, computed much sooner (see `docs/benchmarks.md`,
    /// "Jerk-limited motions").
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![20.0; 2])?;
    /// let path = Path { states: vec![vec![0.1, 0.1], vec![0.5, 0.6], vec![0.9, 0.2], vec![0.4, 0.8]] };
    /// let quick = Trajectory::jerk_limited_with(&space, &path, &limits, 0)?;
    /// let refined = Trajectory::jerk_limited(&space, &path, &limits)?;
    /// // The refinement keeps only the changes that shorten the motion.
    /// assert!(refined.duration() < quick.duration());
    /// let mut q = [0.0; 2];
    /// quick.sample(quick.duration(), &mut q, None);
    /// assert!((q[0] - 0.4).abs() < 1e-9 && (q[1] - 0.8).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn jerk_limited_with<S: Space>(
        space: &S,
        path: &Path,
        limits: &Limits,
        refinement_sweeps: usize,
    ) -> Result<Self, TrajectoryError> {
        check_dim(limits, space.dim())?;
        let states = unwrapped(space, path)?;
        let g = generator::through(&states, limits, refinement_sweeps)?;
        Ok(Self::from_pieces(space.dim(), vec![Piece::Generated(Box::new(g))]))
    }

    /// A jerk-limited motion (Ruckig, phase-synchronised) that stops at every waypoint and
    /// stays on the straight edges between them: one span per edge.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// let limits = Limits::new(vec![1.0, 0.5], vec![2.0, 1.0], vec![20.0, 10.0])?;
    /// let path = Path { states: vec![vec![0.0, 0.0], vec![0.8, 0.4]] };
    /// let t = Trajectory::jerk_limited_stops(&space, &path, &limits)?;
    /// assert_eq!(t.spans(), 1);
    /// let mut q = [0.0; 2];
    /// for k in 0..=10 {
    ///     t.sample(t.duration() * k as f64 / 10.0, &mut q, None);
    ///     assert!((q[1] - 0.5 * q[0]).abs() < 1e-9); // on the edge
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn jerk_limited_stops<S: Space>(space: &S, path: &Path, limits: &Limits) -> Result<Self, TrajectoryError> {
        check_dim(limits, space.dim())?;
        let states = unwrapped(space, path)?;
        let zero = vec![0.0; space.dim()];
        let mut pieces = Vec::with_capacity(states.len());
        for pair in states.windows(2) {
            let g = generator::between(&pair[0], &zero, &pair[1], &zero, limits, Sync::Phase)?;
            pieces.push(Piece::Generated(Box::new(g)));
        }
        if pieces.is_empty() {
            pieces.push(Piece::Line(LineRamp::new(&states[0], &zero, limits)));
        }
        Ok(Self::from_pieces(space.dim(), pieces))
    }

    /// This motion with its jerk bounded by `limits`: its moving average over a window of
    /// `w = max 2 a_i / j_i` seconds (the largest over coordinates with a finite jerk limit).
    /// Averaging keeps the motion's velocity and acceleration bounds and its position bounds,
    /// and bounds its jerk by `2 a_i / w ≤ j_i` when the motion respects the acceleration
    /// limits of `limits` (as one built with them or with [`Limits::scaled`] ones does). The
    /// result lasts `w` longer, starts and ends at rest with zero acceleration, and stays
    /// within `a_i w² / 24` of this motion delayed by `w / 2` (Panda: 1.3 × 10⁻⁵ rad;
    /// Fetch: 6 × 10⁻⁴ rad), so unlike [`Trajectory::jerk_limited`] it follows the checked
    /// motion instead of re-solving a path through its samples, and takes microseconds
    /// instead of up to a second (see `docs/benchmarks.md`, "Jerk-limited motions"). It may
    /// still leave a tight passage by that much: check it ([`Trajectory::check`]). With no
    /// finite jerk limit, or a motion of duration 0, the motion is returned as it is.
    ///
    /// # Errors
    /// [`TrajectoryError::Dimension`] when `limits` has another number of coordinates.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![40.0; 2])?;
    /// let path = Path { states: vec![vec![0.1, 0.1], vec![0.8, 0.1], vec![0.8, 0.9]] };
    /// let steps = Trajectory::rest_to_rest(&space, &path, &limits)?; // acceleration steps
    /// let smooth = steps.with_jerk_limits(&limits)?;
    /// let w = 2.0 * 2.0 / 40.0; // the window: 0.1 s
    /// assert!((smooth.duration() - (steps.duration() + w)).abs() < 1e-12);
    /// let (mut q, mut v) = ([0.0; 2], [0.0; 2]);
    /// smooth.sample(smooth.duration(), &mut q, Some(&mut v));
    /// assert!((q[0] - 0.8).abs() < 1e-12 && (q[1] - 0.9).abs() < 1e-12 && v == [0.0; 2]);
    /// // Within a w²/24 · a of the stepped motion, half a window later.
    /// let mut p = [0.0; 2];
    /// for k in 0..=100 {
    ///     let t = steps.duration() * k as f64 / 100.0;
    ///     steps.sample(t, &mut p, None);
    ///     smooth.sample(t + w / 2.0, &mut q, None);
    ///     assert!((0..2).all(|i| (q[i] - p[i]).abs() <= 2.0 * w * w / 24.0 + 1e-12));
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_jerk_limits(&self, limits: &Limits) -> Result<Self, TrajectoryError> {
        check_dim(limits, self.dim)?;
        let width = limits
            .acceleration()
            .iter()
            .zip(limits.jerk())
            .map(|(&a, &j)| if j.is_finite() { 2.0 * a / j } else { 0.0 })
            .fold(0.0, f64::max);
        if !(width > 0.0 && width.is_finite()) || self.duration() <= 0.0 {
            return Ok(self.clone());
        }
        Ok(Self::from_pieces(
            self.dim,
            vec![Piece::Averaged(Box::new(Averaged::new(self.clone(), width)))],
        ))
    }

    /// The time-optimal motion from `(q0, v0)` to `(q1, v1)` within `limits` (Ruckig; with
    /// unbounded jerk this is the parabolic ramp of acceleration-bounded shortcutting).
    ///
    /// # Errors
    /// [`TrajectoryError::Dimension`] for an input of the wrong length;
    /// [`TrajectoryError::NonFinite`] for a NaN or infinite value, with `index` 0 when it is in
    /// `q0` or `v0` and 1 when it is in `q1` or `v1` (and not in `q0` or `v0`);
    /// [`TrajectoryError::Generator`] when Ruckig finds no motion.
    ///
    /// ```
    /// use hearth_planning::trajectory::{Limits, Trajectory, TrajectoryError};
    ///
    /// let limits = Limits::new(vec![1.0], vec![2.0], vec![f64::INFINITY])?;
    /// // From 0 at full speed to rest at 1: 0.75 s cruising, then 0.5 s braking over 0.25 rad.
    /// let ramp = Trajectory::ramp(&[0.0], &[1.0], &[1.0], &[0.0], &limits)?;
    /// assert!((ramp.duration() - 1.25).abs() < 1e-6);
    /// let (mut q, mut v) = ([0.0], [0.0]);
    /// ramp.sample(ramp.duration(), &mut q, Some(&mut v));
    /// assert!((q[0] - 1.0).abs() < 1e-9 && v[0].abs() < 1e-9);
    /// assert!(Trajectory::ramp(&[0.0, 0.0], &[0.0], &[1.0], &[0.0], &limits).is_err());
    /// let nan = Trajectory::ramp(&[0.0], &[1.0], &[1.0], &[f64::NAN], &limits);
    /// assert_eq!(nan.unwrap_err(), TrajectoryError::NonFinite { index: 1 });
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn ramp(q0: &[f64], v0: &[f64], q1: &[f64], v1: &[f64], limits: &Limits) -> Result<Self, TrajectoryError> {
        let n = limits.dim();
        // (name, values, state)
        let inputs = [("q0", q0, 0), ("v0", v0, 0), ("q1", q1, 1), ("v1", v1, 1)];
        for (what, x, _) in inputs {
            check_dim_of(what, n, x.len())?;
        }
        if let Some((_, _, index)) = inputs.iter().find(|(_, x, _)| x.iter().any(|c| !c.is_finite())) {
            return Err(TrajectoryError::NonFinite { index: *index });
        }
        let g = generator::between(q0, v0, q1, v1, limits, Sync::Time)?;
        Ok(Self::from_pieces(n, vec![Piece::Generated(Box::new(g))]))
    }

    /// Replaces `[t1, t2]` by `other` (one span), which must join the states at both times.
    pub(crate) fn splice_trajectory(&mut self, t1: f64, t2: f64, other: Trajectory) {
        if let Some(span) = other.spans.into_iter().next() {
            self.splice_span(t1, t2, span);
        }
    }

    /// Marks every span as verified: later checks by [`Trajectory::verify_new`] cover only
    /// what is spliced in afterwards.
    pub(crate) fn mark_verified(&mut self) {
        for s in &mut self.spans {
            s.verified = true;
        }
    }

    /// Checks the spans spliced in since the last call (or [`Trajectory::mark_verified`]) at
    /// `resolution`; marks them verified and returns `true` when all are valid.
    pub(crate) fn verify_new<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        space: &S,
        validator: &mut V,
        resolution: f64,
        flat: &mut Vec<f64>,
    ) -> bool {
        for i in 0..self.spans.len() {
            if self.spans[i].verified {
                continue;
            }
            let span = self.spans[i].clone();
            flat.clear();
            let sample = |t: f64, q: &mut [f64]| span.piece.eval(span.offset + t, q, None);
            discretise_timed(self.dim, span.duration, sample, space, resolution, flat, None);
            if first_invalid(flat, self.dim, validator).is_some() {
                return false;
            }
            self.spans[i].verified = true;
        }
        true
    }

    /// Number of coordinates.
    ///
    /// ```
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let limits = Limits::new(vec![1.0; 3], vec![1.0; 3], vec![f64::INFINITY; 3])?;
    /// assert_eq!(Trajectory::ramp(&[0.0; 3], &[0.0; 3], &[1.0; 3], &[0.0; 3], &limits)?.dim(), 3);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Total duration in seconds.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?;
    /// let limits = Limits::new(vec![2.0], vec![1.0], vec![f64::INFINITY])?;
    /// // Too short an edge to reach 2 rad/s: 1 s speeding up, 1 s slowing down.
    /// let t = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![0.0], vec![1.0]] }, &limits)?;
    /// assert!((t.duration() - 2.0).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn duration(&self) -> f64 {
        self.ends.last().copied().unwrap_or(0.0)
    }

    /// Number of spans (straight segments and ramps).
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0], &[3.0], &[false])?;
    /// let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY])?;
    /// let path = Path { states: vec![vec![0.0], vec![1.0], vec![3.0], vec![2.0]] };
    /// let t = Trajectory::rest_to_rest(&space, &path, &limits)?;
    /// assert_eq!(t.spans(), 3);
    /// let back = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![2.0], vec![0.0]] }, &limits)?;
    /// assert_eq!(t.then(back)?.spans(), 4);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn spans(&self) -> usize {
        self.spans.len()
    }

    /// Position (and velocity) at time `t`, clamped to `[0, duration]`. Does not allocate.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?;
    /// let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY])?;
    /// let t = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![0.2], vec![0.8]] }, &limits)?;
    /// let (mut q, mut v) = ([0.0], [0.0]);
    /// t.sample(-1.0, &mut q, None);
    /// assert_eq!(q, [0.2]);
    /// t.sample(t.duration() + 1.0, &mut q, Some(&mut v));
    /// assert!((q[0] - 0.8).abs() < 1e-12 && v[0].abs() < 1e-12);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn sample(&self, t: f64, q: &mut [f64], v: Option<&mut [f64]>) {
        let t = t.clamp(0.0, self.duration());
        let i = self.span_at(t);
        let start = if i == 0 { 0.0 } else { self.ends[i - 1] };
        let span = &self.spans[i];
        span.piece.eval(span.offset + (t - start).min(span.duration), q, v);
    }

    /// Replaces the motion between `t1` and `t2` by `piece` of length `duration` (which must
    /// start and end in the states the trajectory has at those times).
    fn splice_span(&mut self, t1: f64, t2: f64, new: Span) {
        let mut spans = Vec::with_capacity(self.spans.len() + 2);
        let mut inserted = false;
        let mut start = 0.0;
        for (s, &end) in self.spans.iter().zip(&self.ends) {
            if start < t1 {
                let d = end.min(t1) - start;
                if d > 0.0 {
                    spans.push(Span {
                        duration: d,
                        ..s.clone()
                    });
                }
            }
            if !inserted && end >= t1 {
                spans.push(new.clone());
                inserted = true;
            }
            if end > t2 {
                let from = t2.max(start);
                spans.push(Span {
                    piece: s.piece.clone(),
                    offset: s.offset + (from - start),
                    duration: end - from,
                    verified: s.verified,
                });
            }
            start = end;
        }
        if !inserted {
            spans.push(new);
        }
        self.spans = spans;
        self.recompute_ends();
    }

    /// States along the trajectory no more than `resolution` apart (in the space's distance),
    /// from the first state to the last, with continuous coordinates wrapped back. A
    /// `resolution` that is not positive and finite is [`TrajectoryError::BadResolution`].
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::{JointSpace, Space};
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0], &[0.0], &[true])?;
    /// let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY])?;
    /// // The short way from 3 to -3 rad is through π: the motion ends at 2π - 3, unwrapped.
    /// let t = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![3.0], vec![-3.0]] }, &limits)?;
    /// let path = t.to_path(&space, 0.05)?;
    /// assert!(path.states.windows(2).all(|w| space.distance(&w[0], &w[1]) <= 0.05));
    /// assert!((path.states.last().unwrap()[0] + 3.0).abs() < 1e-9);
    /// assert!(t.to_path(&space, f64::NAN).is_err());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn to_path<S: Space>(&self, space: &S, resolution: f64) -> Result<Path, TrajectoryError> {
        let mut flat = Vec::new();
        self.discretise(space, resolution, &mut flat)?;
        let dim = self.dim.max(1);
        Ok(Path {
            states: flat
                .chunks(dim)
                .map(|q| {
                    let mut q = q.to_vec();
                    space.enforce_bounds(&mut q);
                    q
                })
                .collect(),
        })
    }

    /// Length of the trajectory's path in the space's metric, sampled at `resolution` (one that
    /// is not positive and finite is [`TrajectoryError::BadResolution`]).
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory, TrajectoryError};
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
    /// let limits = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![f64::INFINITY; 2])?;
    /// let path = Path { states: vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![1.0, 1.0]] };
    /// let t = Trajectory::rest_to_rest(&space, &path, &limits)?;
    /// // The samples are joined by straight lines, which may cut the corner by a little.
    /// let length = t.length(&space, 0.01)?;
    /// assert!(length <= path.length(&space) + 1e-9 && length > path.length(&space) - 0.01);
    /// assert_eq!(t.length(&space, 0.0), Err(TrajectoryError::BadResolution { value: 0.0 }));
    /// // Standing still: length +0.
    /// let still = Trajectory::rest_to_rest(&space, &Path { states: vec![vec![0.5; 2]] }, &limits)?;
    /// let none = still.length(&space, 0.01)?;
    /// assert!(none == 0.0 && none.is_sign_positive());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn length<S: Space>(&self, space: &S, resolution: f64) -> Result<f64, TrajectoryError> {
        let mut flat = Vec::new();
        self.discretise(space, resolution, &mut flat)?;
        let dim = self.dim.max(1);
        // (A fold from +0: an empty float sum is -0, which a table would print as "-0.000".)
        Ok(flat
            .chunks(dim)
            .zip(flat.chunks(dim).skip(1))
            .fold(0.0, |sum, (a, b)| sum + space.distance(a, b)))
    }

    /// Appends states (flat, `dim` per state) at most `resolution` apart to `out`, adapting the
    /// time step to the local speed; a `resolution` that is not positive and finite is refused.
    fn discretise<S: Space>(&self, space: &S, resolution: f64, out: &mut Vec<f64>) -> Result<(), TrajectoryError> {
        usable_resolution(space, resolution)?;
        discretise_timed(
            self.dim,
            self.duration(),
            |t, q| self.sample(t, q, None),
            space,
            resolution,
            out,
            None,
        );
        Ok(())
    }

    /// Checks every state along the trajectory, at most `resolution` apart, coarse to fine
    /// (midpoints first); `Err(InCollision)` carries the time of the first colliding state
    /// found (not necessarily the earliest one). A resolution that is not positive and finite
    /// is [`TrajectoryError::BadResolution`], one finer than the space allows
    /// [`TrajectoryError::ResolutionTooFine`], before any state is checked.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory, TrajectoryError};
    /// use hearth_planning::validity::StateValidator;
    ///
    /// // Everything right of x = 0.5 is blocked.
    /// struct Left(u64);
    /// impl StateValidator for Left {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; q[0] < 0.5 }
    ///     fn checks(&self) -> u64 { self.0 }
    /// }
    /// let space = JointSpace::new(&[0.0], &[1.0], &[false])?;
    /// let limits = Limits::new(vec![1.0], vec![1.0], vec![f64::INFINITY])?;
    /// let leg = |b: f64| Trajectory::rest_to_rest(&space, &Path { states: vec![vec![0.1], vec![b]] }, &limits);
    /// assert!(leg(0.4)?.check(&space, &mut Left(0), 0.01).is_ok());
    /// let across = leg(0.9)?;
    /// let Err(TrajectoryError::InCollision { time }) = across.check(&space, &mut Left(0), 0.01) else {
    ///     panic!("the motion crosses x = 0.5")
    /// };
    /// let mut q = [0.0];
    /// across.sample(time, &mut q, None);
    /// assert!(q[0] >= 0.5);
    /// let zero = across.check(&space, &mut Left(0), 0.0);
    /// assert_eq!(zero, Err(TrajectoryError::BadResolution { value: 0.0 }));
    /// let tiny = across.check(&space, &mut Left(0), 1e-300);
    /// assert!(matches!(tiny, Err(TrajectoryError::ResolutionTooFine { .. })));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn check<S: Space, V: StateValidator + ?Sized>(
        &self,
        space: &S,
        validator: &mut V,
        resolution: f64,
    ) -> Result<(), TrajectoryError> {
        usable_resolution(space, resolution)?;
        let mut flat = Vec::new();
        let mut times = Vec::new();
        let sample = |t: f64, q: &mut [f64]| self.sample(t, q, None);
        discretise_timed(
            self.dim,
            self.duration(),
            sample,
            space,
            resolution,
            &mut flat,
            Some(&mut times),
        );
        match first_invalid(&flat, self.dim, validator) {
            Some(i) => Err(TrajectoryError::InCollision { time: times[i] }),
            None => Ok(()),
        }
    }

    /// Largest absolute velocity and acceleration per coordinate, measured by sampling every
    /// `dt` seconds (accelerations by finite differences of velocities).
    ///
    /// # Errors
    /// [`TrajectoryError::BadStep`] when `dt` is not positive and finite, or would take more
    /// than [`Trajectory::MAX_SAMPLES`] samples.
    ///
    /// ```
    /// use hearth_planning::planner::Path;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::trajectory::{Limits, Trajectory};
    ///
    /// let space = JointSpace::new(&[0.0; 2], &[2.0; 2], &[false; 2])?;
    /// let limits = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![f64::INFINITY; 2])?;
    /// let path = Path { states: vec![vec![0.0, 0.0], vec![2.0, 1.0]] };
    /// let t = Trajectory::rest_to_rest(&space, &path, &limits)?;
    /// let (v, a) = t.peak_velocity_acceleration(1e-3)?;
    /// // The first coordinate moves twice as far, so it sets the pace at its limits.
    /// assert!((v[0] - 1.0).abs() < 1e-6 && (a[0] - 1.0).abs() < 1e-6);
    /// assert!((v[1] - 0.5).abs() < 1e-6 && (a[1] - 0.5).abs() < 1e-6);
    /// assert!(t.peak_velocity_acceleration(0.0).is_err());
    /// assert!(t.peak_velocity_acceleration(1e-12).is_err()); // 3 s in 3 · 10¹² samples
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn peak_velocity_acceleration(&self, dt: f64) -> Result<(Vec<f64>, Vec<f64>), TrajectoryError> {
        let steps = (self.duration() / dt).ceil().max(1.0);
        if !(dt > 0.0 && dt.is_finite() && steps <= Self::MAX_SAMPLES as f64) {
            return Err(TrajectoryError::BadStep {
                what: "the sampling step",
                value: dt,
                max_samples: Self::MAX_SAMPLES,
            });
        }
        let steps = steps as usize;
        let n = self.dim;
        let (mut q, mut v, mut prev) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let (mut vmax, mut amax) = (vec![0.0f64; n], vec![0.0f64; n]);
        self.sample(0.0, &mut q, Some(&mut prev));
        for k in 1..=steps {
            let t = (k as f64 * dt).min(self.duration());
            self.sample(t, &mut q, Some(&mut v));
            for i in 0..n {
                vmax[i] = vmax[i].max(v[i].abs());
                amax[i] = amax[i].max(((v[i] - prev[i]) / dt).abs());
            }
            prev.copy_from_slice(&v);
        }
        Ok((vmax, amax))
    }
}

/// The share of the spacing that [`discretise_timed`] aims its steps at: close to 1 for few
/// states, below it so that a slightly faster next step still lands within the spacing.
const SPACING_AIM: f64 = 0.96;

/// [`TrajectoryError::BadResolution`] unless `resolution` is positive and finite, and
/// [`TrajectoryError::ResolutionTooFine`] when it is finer than `space` allows: the check
/// every sampling of a whole trajectory makes before it samples.
pub(crate) fn usable_resolution<S: Space>(space: &S, resolution: f64) -> Result<(), TrajectoryError> {
    positive(resolution).ok_or(TrajectoryError::BadResolution { value: resolution })?;
    let finest = finest_resolution(space);
    if resolution < finest {
        return Err(TrajectoryError::ResolutionTooFine {
            value: resolution,
            finest,
        });
    }
    Ok(())
}

/// Appends states (flat, `dim` per state) of a motion `sample(t, q)` over `[0, duration]`,
/// consecutive ones at most `resolution` apart, to `out` (and their times to `times`). Each
/// time step is scaled from the last one's measured distance so that states come about
/// [`SPACING_AIM`] of `resolution` apart (a step that lands too far is retried shorter in the
/// same way); on the benchmark's trajectories that takes about a third fewer states than
/// halving and growing the step by fixed factors.
fn discretise_timed<S: Space>(
    dim: usize,
    duration: f64,
    mut sample: impl FnMut(f64, &mut [f64]),
    space: &S,
    resolution: f64,
    out: &mut Vec<f64>,
    mut times: Option<&mut Vec<f64>>,
) {
    let resolution = resolution_or_default(resolution);
    // Two states of scratch, on the stack for up to 32 coordinates.
    let mut stack = [0.0f64; 64];
    let mut heap = Vec::new();
    let both = if dim <= 32 {
        &mut stack[..2 * dim]
    } else {
        heap.resize(2 * dim, 0.0);
        &mut heap[..]
    };
    let (mut prev, mut q) = both.split_at_mut(dim);
    sample(0.0, prev);
    out.extend_from_slice(prev);
    if let Some(times) = times.as_deref_mut() {
        times.push(0.0);
    }
    let (mut t, mut dt) = (0.0, (duration / 8.0).max(1e-6));
    while t < duration {
        let mut next = (t + dt).min(duration);
        let mut d;
        loop {
            sample(next, q);
            d = space.distance(prev, q);
            if d <= resolution || next - t < 1e-9 {
                break;
            }
            // Too far: retry at the step the measured speed suggests (a NaN distance takes the
            // smallest factor, so the loop still ends).
            let factor = SPACING_AIM * resolution / d;
            dt = (next - t) * if factor.is_nan() { 0.1 } else { factor.clamp(0.1, 0.9) };
            next = t + dt;
        }
        out.extend_from_slice(q);
        if let Some(times) = times.as_deref_mut() {
            times.push(next);
        }
        // The next step aims at the same share of the spacing, from this step's speed.
        dt = (next - t)
            * if d > 0.0 {
                (SPACING_AIM * resolution / d).clamp(0.5, 2.0)
            } else {
                2.0
            };
        t = next;
        std::mem::swap(&mut prev, &mut q);
    }
}

/// The shortcutter's time-optimal ramps ([`Trajectory::ramp`]), computed one after another in
/// the same generator and output: computing and checking a ramp allocates nothing; only one
/// that is taken ([`Ramps::take`]) becomes a trajectory of its own.
pub(crate) struct Ramps {
    generator: generator::RampGenerator,
    ramp: Generated,
    dim: usize,
}

impl Ramps {
    /// Ramps within `limits` (their jerk limits are the generator's: pass
    /// [`Limits::without_jerk`] for parabolic ramps).
    pub(crate) fn new(limits: &Limits) -> Self {
        Self {
            generator: generator::RampGenerator::new(limits, Sync::Time),
            ramp: Generated::new(Some(limits.dim())),
            dim: limits.dim(),
        }
    }

    /// Computes the ramp from `(q0, v0)` to `(q1, v1)` (of the limits' dimension) and returns
    /// its duration, or `None` when there is none (the generator fails, or a value is not
    /// finite).
    pub(crate) fn compute(&mut self, q0: &[f64], v0: &[f64], q1: &[f64], v1: &[f64]) -> Option<f64> {
        debug_assert!([q0, v0, q1, v1].iter().all(|x| x.len() == self.dim));
        if [q0, v0, q1, v1].iter().any(|x| x.iter().any(|c| !c.is_finite())) {
            return None;
        }
        if !self.generator.try_between(q0, v0, q1, v1, &mut self.ramp) {
            return None;
        }
        Some(self.ramp.get_duration())
    }

    /// Whether every state along the last computed ramp, at most `resolution` apart, is valid
    /// (as [`Trajectory::check`] of the ramp as a trajectory would find); `resolution` must be usable
    /// ([`usable_resolution`]); `flat` is scratch space.
    pub(crate) fn is_valid<S: Space, V: StateValidator + ?Sized>(
        &self,
        space: &S,
        validator: &mut V,
        resolution: f64,
        flat: &mut Vec<f64>,
    ) -> bool {
        flat.clear();
        let ramp = &self.ramp;
        let sample = |t: f64, q: &mut [f64]| generator::eval(ramp, t, q, None);
        discretise_timed(self.dim, ramp.get_duration(), sample, space, resolution, flat, None);
        first_invalid(flat, self.dim, validator).is_none()
    }

    /// The last computed ramp as a trajectory (the next is computed into a new output).
    pub(crate) fn take(&mut self) -> Trajectory {
        let ramp = std::mem::replace(&mut self.ramp, Generated::new(Some(self.dim)));
        Trajectory::from_pieces(self.dim, vec![Piece::Generated(Box::new(ramp))])
    }
}

/// Index of an invalid state among `flat` (`dim` per state), which follow one another along
/// the motion, or `None` when all are valid ([`StateValidator::first_invalid_along`]).
pub(crate) fn first_invalid<V: StateValidator + ?Sized>(flat: &[f64], dim: usize, validator: &mut V) -> Option<usize> {
    validator.first_invalid_along(flat, dim)
}
