//! Path post-processing: repair at a fine resolution, random shortcutting of geometric paths,
//! and acceleration-bounded ("parabolic") shortcutting of trajectories (Hauser &
//! Ng-Thow-Hing, ICRA 2010), with the ramps computed by Ruckig with unbounded jerk.
//!
//! Every shortcut is checked at the motion validator's resolution first (cheap rejection) and,
//! when [`ShortcutSettings::fine_resolution`] is set, again at that resolution before it is
//! accepted, so a path that was valid at the fine resolution stays valid.
//!
//! ```
//! use hearth_planning::motion::MotionValidator;
//! use hearth_planning::planner::Path;
//! use hearth_planning::shortcut::{self, ShortcutSettings};
//! use hearth_planning::space::JointSpace;
//! use hearth_planning::validity::StateValidator;
//! use rand::SeedableRng;
//!
//! struct Free(u64);
//! impl StateValidator for Free {
//!     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
//!     fn checks(&self) -> u64 { self.0 }
//! }
//! let space = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false])?;
//! let mut motion = MotionValidator::new(space, 0.01);
//! let zigzag = Path { states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]] };
//! let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
//! let (short, stats) = shortcut::random(&mut motion, &mut Free(0), &zigzag, &ShortcutSettings::default(), &mut rng);
//! assert!(short.length(motion.space()) < zigzag.length(motion.space()));
//! assert!(stats.accepted > 0);
//! # Ok::<(), hearth_planning::space::SpaceError>(())
//! ```

use std::time::{Duration, Instant};

use rand::{Rng, RngExt};

use crate::birrt::BiRrt;
use crate::error::PlanError;
use crate::motion::{MotionValidator, checked_resolution};
use crate::planner::{Budget, Goal, Path, PlanRequest, Planner};
use crate::space::{Space, steer};
use crate::trajectory::{Limits, Ramps, Trajectory, TrajectoryError, usable_resolution};
use crate::validity::StateValidator;

/// Parabolic shortcut attempts between fine checks.
const ROUND: usize = 10;

/// Edges re-planned around a missed graze (see [`smooth`]) before a fallback motion that still
/// fails the verification check is given up.
const VERIFY_ROUNDS: usize = 8;

/// Fresh parabolic shortcutting runs after one whose motion fails the verification check,
/// before [`smooth`] falls back to the unshortcut motion.
const PARABOLIC_RETRIES: usize = 2;

/// How many times the fine spacing [`smooth`]'s first parabolic run checks each round's ramps
/// at, when a verification check follows. Measured on the MBM sets (BiRRT, 100 attempts),
/// before the run ahead of the repair was added: the Panda's post-processing made 36 % fewer
/// checks at the median (Fetch 34 %), one run in eight was redone (one in nineteen at the fine
/// spacing), and the motions were as fast.
const FIRST_RUN_SPACING: f64 = 4.0;

/// Sideways moves [`bypass`] tries before an edge is re-planned.
const BYPASS_TRIES: usize = 64;

/// Checks [`bypass`] may spend, in full checks of the edge it bypasses (its length over the
/// fine spacing), before it gives the edge up to a re-plan. Most bypasses that succeed cost
/// less than one; the ones that fail could cost 60 (two 4 rad Panda edges took about 117,000
/// checks each). Measured on the MBM Panda set (BiRRT, parabolic): with 4, the 99th percentile
/// of post-processing checks fell from 40,455 to 30,512 and the largest from 151,059 to 62,398,
/// with the same edges repaired and motions as fast (2 gave a higher 99th percentile, 8 a
/// higher mean).
const BYPASS_CHECKS: u64 = 4;

/// The shortest and the longest of those moves (joint-space distance from the grazed state);
/// the tries grow geometrically from one to the other.
const BYPASS_REACH: [f64; 2] = [0.005, 0.2];

/// Clearances (m) to which [`retracted_bypass`] pushes a grazed state out of the obstacle it
/// touches, nearest first, and the retraction rounds of each push.
const RETRACTED_BYPASS: ([f64; 3], usize) = ([0.005, 0.01, 0.02], 3);

/// How long to shortcut and how carefully.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut::{self, ShortcutSettings};
/// use hearth_planning::space::JointSpace;
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // `Free` is a validator that accepts every state.
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let zigzag = Path { states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]] };
/// let none = ShortcutSettings { attempts: 0, ..ShortcutSettings::default() };
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let (same, stats) = shortcut::random(&mut motion, &mut Free(0), &zigzag, &none, &mut rng);
/// assert_eq!((same, stats.attempts), (zigzag, 0));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ShortcutSettings {
    /// Shortcut attempts (random pairs of points).
    pub attempts: usize,
    /// Stop after this long even if attempts are left.
    pub time_limit: Option<Duration>,
    /// Also check accepted shortcuts at this finer resolution (e.g. a tenth of the planner's).
    pub fine_resolution: Option<f64>,
    /// [`smooth`] only: re-check the finished trajectory with [`Trajectory::check`] at this
    /// resolution and return it only if it passes (falling back to the unshortcut timing of
    /// the repaired path, see [`Smoothed::fell_back`]). Two sample sets at different spacings
    /// can disagree about a graze shorter than either spacing; this makes the returned motion
    /// pass exactly the check a caller re-runs at this resolution.
    pub verify_resolution: Option<f64>,
}

impl Default for ShortcutSettings {
    fn default() -> Self {
        Self {
            attempts: 100,
            time_limit: None,
            fine_resolution: None,
            verify_resolution: None,
        }
    }
}

/// What a shortcutter did.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut::{self, ShortcutSettings};
/// use hearth_planning::space::JointSpace;
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // `Free` is a validator that accepts every state.
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let zigzag = Path { states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]] };
/// let settings = ShortcutSettings { attempts: 20, ..ShortcutSettings::default() };
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let (_, stats) = shortcut::random(&mut motion, &mut Free(0), &zigzag, &settings, &mut rng);
/// assert!(stats.attempts <= 20 && stats.accepted <= stats.attempts);
/// assert!(stats.accepted > 0);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShortcutStats {
    /// Attempts made.
    pub attempts: u64,
    /// Shortcuts accepted.
    pub accepted: u64,
    /// Time spent.
    pub time: Duration,
}

impl ShortcutStats {
    /// Adds another run's counts and time to these.
    fn absorb(&mut self, other: &ShortcutStats) {
        self.attempts += other.attempts;
        self.accepted += other.accepted;
        self.time += other.time;
    }
}

struct Clock {
    start: Instant,
    limit: Option<Duration>,
}

impl Clock {
    fn new(limit: Option<Duration>) -> Self {
        Self {
            start: Instant::now(),
            limit,
        }
    }

    fn expired(&self) -> bool {
        self.limit.is_some_and(|l| self.start.elapsed() >= l)
    }
}

/// Cumulative lengths of a path's states, written into `acc`.
fn cumulative_into<S: Space>(space: &S, states: &[Vec<f64>], acc: &mut Vec<f64>) {
    acc.clear();
    let mut total = 0.0;
    acc.push(0.0);
    for w in states.windows(2) {
        total += space.distance(&w[0], &w[1]);
        acc.push(total);
    }
}

/// The point at arc length `u` along a path, written into `q`; returns the index of its edge.
fn point_at<S: Space>(space: &S, states: &[Vec<f64>], acc: &[f64], u: f64, q: &mut [f64]) -> usize {
    let i = acc.partition_point(|&a| a <= u).saturating_sub(1).min(states.len() - 2);
    let len = acc[i + 1] - acc[i];
    let t = if len > 0.0 {
        ((u - acc[i]) / len).clamp(0.0, 1.0)
    } else {
        0.0
    };
    space.interpolate(&states[i], &states[i + 1], t, q);
    i
}

/// Random shortcutting of a geometric path: connects random pairs of points (half the time
/// two of its states, half the time two points anywhere along it) by a straight edge when that
/// edge is valid and shorter. Never lengthens the path; every new edge is checked by `motion`
/// (and at the fine resolution when set).
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut::{self, ShortcutSettings};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// // The square's lower right is blocked: paths go round its upper left corner.
/// struct Block(u64);
/// impl StateValidator for Block {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; q[0] < 0.2 || q[1] > 0.8 }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let corner = Path { states: vec![vec![0.0, 0.0], vec![0.0, 1.0], vec![1.0, 1.0]] };
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
/// let settings = ShortcutSettings::default();
/// let (short, _) = shortcut::random(&mut motion, &mut Block(0), &corner, &settings, &mut rng);
/// assert!(short.length(motion.space()) < corner.length(motion.space()));
/// assert_eq!((short.states.first(), short.states.last()), (corner.states.first(), corner.states.last()));
/// assert!(short.states.windows(2).all(|w| motion.check_motion(&mut Block(0), &w[0], &w[1])));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
pub fn random<S: Space + Clone, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    motion: &mut MotionValidator<S>,
    validator: &mut V,
    path: &Path,
    settings: &ShortcutSettings,
    rng: &mut R,
) -> (Path, ShortcutStats) {
    let clock = Clock::new(settings.time_limit);
    let mut fine = settings
        .fine_resolution
        .map(|r| MotionValidator::new(motion.space().clone(), r));
    let mut states = path.states.clone();
    let mut stats = ShortcutStats::default();
    let space = motion.space().clone();
    // Arc lengths change only when a shortcut is accepted.
    let mut acc = Vec::with_capacity(states.len());
    cumulative_into(&space, &states, &mut acc);
    // The shortcut's ends, kept between attempts: an attempt that fails allocates nothing.
    let (mut a, mut b) = (vec![0.0; space.dim()], vec![0.0; space.dim()]);
    for _ in 0..settings.attempts {
        if states.len() < 3 || clock.expired() {
            break;
        }
        stats.attempts += 1;
        let total = *acc.last().unwrap_or(&0.0);
        let (i, j) = if rng.random_bool(0.5) {
            let (mut x, mut y) = (rng.random_range(0..states.len()), rng.random_range(0..states.len()));
            if x > y {
                std::mem::swap(&mut x, &mut y);
            }
            if y < x + 2 {
                continue;
            }
            a.clear();
            a.extend_from_slice(&states[x]);
            b.clear();
            b.extend_from_slice(&states[y]);
            (x, y - 1)
        } else {
            let (mut u, mut w) = (rng.random::<f64>() * total, rng.random::<f64>() * total);
            if u > w {
                std::mem::swap(&mut u, &mut w);
            }
            a.resize(space.dim(), 0.0);
            b.resize(space.dim(), 0.0);
            let i = point_at(&space, &states, &acc, u, &mut a);
            let j = point_at(&space, &states, &acc, w, &mut b);
            if i == j {
                continue;
            }
            (i, j)
        };
        let along = space.distance(&a, &states[i + 1]) + (acc[j] - acc[i + 1]) + space.distance(&states[j], &b);
        if space.distance(&a, &b) >= along - 1e-9 {
            continue;
        }
        // Points inside edges were never checked themselves: check them first.
        if !validator.is_valid(&a)
            || !validator.is_valid(&b)
            || !motion.check_motion(validator, &a, &b)
            || !fine.as_mut().is_none_or(|f| f.check_motion(validator, &a, &b))
        {
            continue;
        }
        // The states between the ends give way to the ends (those not already states), in
        // place: only the new ends are allocated.
        let keep_a = space.distance(&a, &states[i]) > 0.0;
        let keep_b = space.distance(&b, &states[j + 1]) > 0.0;
        let ends = [keep_a.then(|| a.clone()), keep_b.then(|| b.clone())];
        states.splice(i + 1..=j, ends.into_iter().flatten());
        cumulative_into(&space, &states, &mut acc);
        stats.accepted += 1;
    }
    stats.time = clock.start.elapsed();
    (Path { states }, stats)
}

/// Acceleration-bounded shortcutting of a trajectory (usually
/// [`Trajectory::rest_to_rest`] of a planned path): picks two random times, computes the
/// time-optimal ramp between the states (position and velocity) there within the velocity and
/// acceleration limits (and position bounds) of `limits`, and splices it in when it is faster
/// and collision-free. The duration never grows; the velocity stays continuous.
///
/// Fails only when `limits` do not have the trajectory's dimension.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut::{self, ShortcutSettings};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::trajectory::{Limits, Trajectory};
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // `Free` is a validator that accepts every state.
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![f64::INFINITY; 2])?;
/// let zigzag = Path { states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]] };
/// let mut t = Trajectory::rest_to_rest(motion.space(), &zigzag, &limits)?;
/// let before = t.duration();
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let settings = ShortcutSettings::default();
/// let stats = shortcut::parabolic(&mut motion, &mut Free(0), &mut t, &limits, &settings, &mut rng)?;
/// assert!(stats.accepted > 0 && t.duration() < before);
/// let (mut q, mut v) = ([0.0; 2], [0.0; 2]);
/// t.sample(t.duration(), &mut q, Some(&mut v));
/// assert!(q[0].abs() < 1e-9 && (q[1] - 1.0).abs() < 1e-9 && v == [0.0; 2]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parabolic<S: Space + Clone, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    motion: &mut MotionValidator<S>,
    validator: &mut V,
    trajectory: &mut Trajectory,
    limits: &Limits,
    settings: &ShortcutSettings,
    rng: &mut R,
) -> Result<ShortcutStats, TrajectoryError> {
    let n = trajectory.dim();
    if limits.dim() != n {
        return Err(TrajectoryError::Dimension {
            what: "limits",
            expected: n,
            got: limits.dim(),
        });
    }
    let clock = Clock::new(settings.time_limit);
    let mut ramps = Ramps::new(&limits.without_jerk());
    let space = motion.space().clone();
    let coarse = motion.resolution();
    // (A resolution the space cannot use proves no ramp valid.)
    let coarse_usable = usable_resolution(&space, coarse).is_ok();
    let mut stats = ShortcutStats::default();
    let (mut q1, mut v1, mut q2, mut v2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut flat = Vec::new();
    trajectory.mark_verified();
    let mut snapshot = trajectory.clone();
    let mut round_accepted = 0;
    for attempt in 0..settings.attempts {
        if clock.expired() {
            break;
        }
        let total = trajectory.duration();
        if total <= 0.0 {
            break;
        }
        stats.attempts += 1;
        let (mut t1, mut t2) = (rng.random::<f64>() * total, rng.random::<f64>() * total);
        if t1 > t2 {
            std::mem::swap(&mut t1, &mut t2);
        }
        if t2 - t1 >= 1e-3 * total {
            trajectory.sample(t1, &mut q1, Some(&mut v1));
            trajectory.sample(t2, &mut q2, Some(&mut v2));
            if let Some(duration) = ramps.compute(&q1, &v1, &q2, &v2)
                && duration < t2 - t1 - 1e-6
                && coarse_usable
                && ramps.is_valid(&space, validator, coarse, &mut flat)
            {
                trajectory.splice_trajectory(t1, t2, ramps.take());
                round_accepted += 1;
            }
        }
        // Fine checks once per round, of the ramps that survived it; a round that fails is
        // undone.
        let round_end = (attempt + 1) % ROUND == 0 || attempt + 1 == settings.attempts || clock.expired();
        if round_end && round_accepted > 0 {
            let fine_ok = settings
                .fine_resolution
                .is_none_or(|r| trajectory.verify_new(&space, validator, r, &mut flat));
            if fine_ok {
                stats.accepted += round_accepted;
                trajectory.mark_verified();
                snapshot = trajectory.clone();
            } else {
                *trajectory = snapshot.clone();
            }
            round_accepted = 0;
        }
    }
    stats.time = clock.start.elapsed();
    Ok(stats)
}

/// Makes a path valid at a finer resolution: every edge is checked at `fine_resolution`, and
/// an edge that fails goes through one waypoint near its first colliding state (a random
/// sideways move, or that state pushed out of the obstacle along the contact normal when the
/// validator can [retract](StateValidator::retract)), or else is replaced by a BiRRT path
/// between its ends planned at that resolution (within `budget` for all repairs together). Returns the path and the number of edges
/// repaired; fails with [`PlanError::Timeout`] when a repair does not succeed, and with
/// [`PlanError::BadInput`] when `fine_resolution` is not positive and finite, or finer than
/// [`finest_resolution`](crate::motion::finest_resolution).
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut;
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// // A wall 2 mm thick at x = 0.503, with a gap above y = 0.9.
/// struct Thin(u64);
/// impl StateValidator for Thin {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; !(q[0] > 0.503 && q[0] < 0.505 && q[1] < 0.9) }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?;
/// let across = Path { states: vec![vec![0.1, 0.1], vec![0.9, 0.1]] };
/// // Checked every centimetre, the edge misses the wall.
/// let (a, b) = (&across.states[0], &across.states[1]);
/// assert!(MotionValidator::new(space.clone(), 0.01).check_motion(&mut Thin(0), a, b));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let budget = std::time::Duration::from_secs(1);
/// let (fixed, repaired) = shortcut::repair(&space, &mut Thin(0), &across, 0.001, budget, &mut rng).unwrap();
/// assert_eq!(repaired, 1);
/// let mut fine = MotionValidator::new(space, 0.001);
/// assert!(fixed.states.windows(2).all(|w| fine.check_motion(&mut Thin(0), &w[0], &w[1])));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
pub fn repair<S: Space + Clone, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    space: &S,
    validator: &mut V,
    path: &Path,
    fine_resolution: f64,
    budget: Duration,
    rng: &mut R,
) -> Result<(Path, usize), PlanError> {
    // A resolution of 0 would sample an edge without end.
    checked_resolution(space, "fine_resolution", fine_resolution)?;
    let clock = Clock::new(Some(budget));
    let mut fine = MotionValidator::new(space.clone(), fine_resolution);
    let mut out: Vec<Vec<f64>> = Vec::with_capacity(path.states.len());
    let mut repaired = 0;
    if let Some(first) = path.states.first() {
        out.push(first.clone());
    }
    for w in path.states.windows(2) {
        if fine.check_motion(validator, &w[0], &w[1]) {
            out.push(w[1].clone());
            continue;
        }
        repaired += 1;
        let graze = first_collision(space, validator, &w[0], &w[1], fine_resolution);
        let left = budget.saturating_sub(clock.start.elapsed());
        let ends = [&w[0][..], &w[1][..]];
        out.extend(reroute(
            &mut fine,
            validator,
            ends,
            graze.as_deref(),
            fine_resolution,
            left,
            rng,
        )?);
        out.push(w[1].clone());
    }
    Ok((Path { states: out }, repaired))
}

/// The states strictly between `ends` of a motion that replaces the straight one between them
/// and passes `fine`: one sideways waypoint near `graze` ([`bypass`], then
/// [`retracted_bypass`]) when there is a graze and one is found, else a BiRRT path planned at `fine`'s resolution with a step of a quarter
/// of the edge (at least 10 × `resolution`, at most 0.25) within `budget` (at least 1 ms).
fn reroute<S: Space + Clone, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    fine: &mut MotionValidator<S>,
    validator: &mut V,
    ends: [&[f64]; 2],
    graze: Option<&[f64]>,
    resolution: f64,
    budget: Duration,
    rng: &mut R,
) -> Result<Vec<Vec<f64>>, PlanError> {
    let space = fine.space().clone();
    if let Some(graze) = graze
        && let Some(via) =
            bypass(&space, fine, validator, ends, graze, rng).or_else(|| retracted_bypass(fine, validator, ends, graze))
    {
        return Ok(vec![via]);
    }
    let request = PlanRequest::new(ends[0].to_vec(), Goal::Config(ends[1].to_vec()));
    let range = (space.distance(ends[0], ends[1]) / 4.0).clamp(10.0 * resolution, 0.25);
    let budget = Budget::time(budget.as_secs_f64().max(1e-3));
    let states = BiRrt::with_range(Some(range))
        .plan(fine, validator, &request, &budget, rng)?
        .path
        .states;
    let inner = states.len().saturating_sub(1);
    Ok(states.into_iter().take(inner).skip(1).collect())
}

/// The first state on the straight motion `a → b`, sampled at `resolution`, that `validator`
/// rejects (`a` and `b` excluded).
fn first_collision<S: Space, V: StateValidator + ?Sized>(
    space: &S,
    validator: &mut V,
    a: &[f64],
    b: &[f64],
    resolution: f64,
) -> Option<Vec<f64>> {
    let n = (space.distance(a, b) / resolution).ceil().max(1.0) as usize;
    let mut q = vec![0.0; space.dim()];
    (1..n).find_map(|k| {
        space.interpolate(a, b, k as f64 / n as f64, &mut q);
        (!validator.is_valid(&q)).then(|| q.clone())
    })
}

/// A state `via` near `graze` (a colliding state on the straight motion between `ends`) such
/// that `ends[0] → via → ends[1]` passes `fine`: states a step of growing length from `graze`
/// towards random samples, [`BYPASS_TRIES`] of them from [`BYPASS_REACH`]`[0]` to `[1]`, until
/// the tries have spent [`BYPASS_CHECKS`] full checks of the edge. A
/// thin graze usually clears with a small sideways move, which is much cheaper than
/// re-planning the edge, and keeps the path where it was; a re-plan also struggles where an
/// end sits in a pocket (a grasp between shelf boards).
fn bypass<S: Space, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    space: &S,
    fine: &mut MotionValidator<S>,
    validator: &mut V,
    ends: [&[f64]; 2],
    graze: &[f64],
    rng: &mut R,
) -> Option<Vec<f64>> {
    let (mut sample, mut via) = (vec![0.0; space.dim()], vec![0.0; space.dim()]);
    let growth = (BYPASS_REACH[1] / BYPASS_REACH[0]).powf(1.0 / (BYPASS_TRIES - 1) as f64);
    let mut reach = BYPASS_REACH[0];
    let (start, allowed) = (
        validator.checks(),
        BYPASS_CHECKS * u64::from(fine.segments(ends[0], ends[1])),
    );
    for _ in 0..BYPASS_TRIES {
        if validator.checks().saturating_sub(start) > allowed {
            return None;
        }
        space.sample(rng, &mut sample);
        steer(space, graze, &sample, reach, &mut via);
        reach *= growth;
        if validator.is_valid(&via)
            && fine.check_motion(validator, ends[0], &via)
            && fine.check_motion(validator, &via, ends[1])
        {
            return Some(via);
        }
    }
    None
}

/// The grazed state pushed out of the obstacle it touches ([`StateValidator::retract`]) to
/// each clearance of [`RETRACTED_BYPASS`] in turn, as a waypoint `via` such that
/// `ends[0] → via → ends[1]` passes `fine`; tried after [`bypass`]'s random sideways moves,
/// before a re-plan. Where an end sits in a pocket (a Fetch grasp deep in the cage), the
/// random moves can all fail and the re-plan at the fine spacing run out of time, while the
/// contact's normal points the short way out. Validators that know no geometry retract
/// nothing, so for them this adds no work and no random draw.
fn retracted_bypass<S: Space, V: StateValidator + ?Sized>(
    fine: &mut MotionValidator<S>,
    validator: &mut V,
    ends: [&[f64]; 2],
    graze: &[f64],
) -> Option<Vec<f64>> {
    let mut via = vec![0.0; graze.len()];
    let (clearances, rounds) = RETRACTED_BYPASS;
    clearances.into_iter().find_map(|clearance| {
        (validator.retract(graze, clearance, rounds, &mut via)
            && fine.check_motion(validator, ends[0], &via)
            && fine.check_motion(validator, &via, ends[1]))
        .then(|| via.clone())
    })
}

/// Which shortcutting [`smooth`] applies; serde names are lowercase (`"none"`, `"random"`,
/// `"parabolic"`).
///
/// ```
/// use hearth_planning::shortcut::Smoothing;
///
/// assert_eq!(Smoothing::default(), Smoothing::Parabolic);
/// assert_eq!(serde_json::from_str::<Smoothing>(r#""random""#).unwrap(), Smoothing::Random);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Smoothing {
    /// Keep the planner's path (still repaired, and timed rest to rest).
    None,
    /// [`random`] shortcutting, then rest-to-rest timing.
    Random,
    /// [`random`] then acceleration-bounded [`parabolic`] shortcutting.
    #[default]
    Parabolic,
}

/// A post-processed path and its timing: what [`smooth`] returns.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut::{smooth, ShortcutSettings, Smoothing};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::trajectory::Limits;
/// use rand::SeedableRng;
/// # use hearth_planning::validity::StateValidator;
/// # struct Free(u64);
/// # impl StateValidator for Free {
/// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
/// #     fn checks(&self) -> u64 { self.0 }
/// # }
/// // `Free` is a validator that accepts every state.
/// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
/// let zigzag = Path { states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]] };
/// let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![f64::INFINITY; 2])?;
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let out = smooth(Smoothing::Random, &mut motion, &mut Free(0), &zigzag, &limits,
///                  &ShortcutSettings::default(), std::time::Duration::from_millis(10), &mut rng)?;
/// assert!(out.random.accepted > 0 && out.parabolic.attempts == 0);
/// assert_eq!((out.repaired, out.fell_back), (0, false));
/// // Random smoothing times the shortcut waypoints rest to rest: one span per edge.
/// assert_eq!(out.trajectory.spans(), out.path.states.len() - 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Smoothed {
    /// The time-parametrised motion.
    pub trajectory: Trajectory,
    /// Its geometric path: states at most the motion validator's resolution apart for a
    /// parabolic trajectory, the shortcut waypoints otherwise.
    pub path: Path,
    /// Edges that failed at the fine resolution and were re-planned.
    pub repaired: usize,
    /// Random shortcutting statistics.
    pub random: ShortcutStats,
    /// Parabolic shortcutting statistics.
    pub parabolic: ShortcutStats,
    /// Whether the shortcut trajectory failed the check at
    /// [`ShortcutSettings::verify_resolution`] and an unshortcut rest-to-rest timing (of the
    /// repaired path, or of that path with edges re-planned around missed grazes), which passed it, was
    /// returned instead.
    pub fell_back: bool,
}

/// The post-processing pipeline from a planner's path to an executable trajectory: random
/// shortcutting at the motion validator's resolution (unless `smoothing` is `None`), [`repair`]
/// of the result at `settings.fine_resolution` (when set, within `repair_budget`), timing
/// within `limits`, and, for `Parabolic`, acceleration-bounded shortcutting whose ramps are
/// checked at both resolutions.
///
/// With `settings.verify_resolution`, the finished trajectory is checked once more at that
/// resolution, and that check backs two savings. First, a `Parabolic` run is tried before any
/// repair, on the rest-to-rest timing of the shortcut path, since its ramps often cut away
/// the edges that graze at the fine spacing; it is returned if it passes. Second, the first
/// parabolic run (that one, or the first after the repair) checks its ramps at four times the
/// fine spacing (at most the motion validator's). When the motion after the repair fails
/// (a graze between the samples of the earlier checks), the parabolic shortcutting runs afresh
/// from the rest-to-rest timing at the full fine spacing, up to twice more, and then the
/// rest-to-rest timing of the repaired path is returned if it passes; if it fails too, the
/// edge holding the colliding state is re-planned around that state, a few times (within what
/// is left of `repair_budget`), and [`PlanError::InvalidMotion`] is returned if no such motion
/// passes. A `fine_resolution` or `verify_resolution` that is not positive and finite, or finer
/// than [`finest_resolution`](crate::motion::finest_resolution), is [`PlanError::BadInput`],
/// before anything is checked.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::Path;
/// use hearth_planning::shortcut::{smooth, ShortcutSettings, Smoothing};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::trajectory::Limits;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// struct Free(u64);
/// impl StateValidator for Free {
///     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false])?;
/// let mut motion = MotionValidator::new(space, 0.01);
/// let zigzag = Path { states: vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![0.0, 1.0]] };
/// let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![f64::INFINITY; 2]).unwrap();
/// let settings = ShortcutSettings { fine_resolution: Some(0.001), ..Default::default() };
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let out = smooth(Smoothing::Parabolic, &mut motion, &mut Free(0), &zigzag, &limits, &settings,
///                  std::time::Duration::from_millis(100), &mut rng).unwrap();
/// assert!(out.trajectory.duration() < 2.5);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[allow(clippy::too_many_arguments)]
pub fn smooth<S: Space + Clone, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    smoothing: Smoothing,
    motion: &mut MotionValidator<S>,
    validator: &mut V,
    path: &Path,
    limits: &Limits,
    settings: &ShortcutSettings,
    repair_budget: Duration,
    rng: &mut R,
) -> Result<Smoothed, PlanError> {
    for (what, r) in [
        ("fine_resolution", settings.fine_resolution),
        ("verify_resolution", settings.verify_resolution),
    ] {
        if let Some(r) = r {
            checked_resolution(motion.space(), what, r)?;
        }
    }
    let started = std::time::Instant::now();
    let space = motion.space().clone();
    let bad_input = |e: TrajectoryError| PlanError::BadInput(e.to_string());
    // Random shortcuts at the coarse resolution, then one fine pass over what is left.
    let mut current = path.clone();
    let mut out_random = ShortcutStats::default();
    if smoothing != Smoothing::None {
        let coarse = ShortcutSettings {
            fine_resolution: None,
            ..settings.clone()
        };
        let (p, s) = random(motion, validator, &current, &coarse, rng);
        current = p;
        out_random = s;
    }
    let mut out_parabolic = ShortcutStats::default();
    // Whether a trajectory passes the verification check (or none is asked for).
    let verify = |trajectory: &Trajectory, validator: &mut V| {
        settings
            .verify_resolution
            .is_none_or(|r| trajectory.check(&space, validator, r).is_ok())
    };
    // The first parabolic run checks each round's ramps at a coarser spacing, leaning on the
    // verification; a run that fails it is redone at the fine spacing.
    let first_run = ShortcutSettings {
        fine_resolution: settings
            .fine_resolution
            .map(|r| (r * FIRST_RUN_SPACING).min(motion.resolution().max(r))),
        ..settings.clone()
    };
    // An optimistic run before any repair: the shortcuts often cut away the edges that graze
    // at the fine spacing, and the verification catches any that stay.
    if smoothing == Smoothing::Parabolic && settings.fine_resolution.is_some() && settings.verify_resolution.is_some() {
        let mut trajectory = Trajectory::rest_to_rest(&space, &current, limits).map_err(bad_input)?;
        let stats = parabolic(motion, validator, &mut trajectory, limits, &first_run, rng).map_err(bad_input)?;
        out_parabolic.absorb(&stats);
        if verify(&trajectory, validator) {
            return Ok(Smoothed {
                path: trajectory.to_path(&space, motion.resolution()).map_err(bad_input)?,
                trajectory,
                repaired: 0,
                random: out_random,
                parabolic: out_parabolic,
                fell_back: false,
            });
        }
    }
    let (repaired_path, repaired) = match settings.fine_resolution {
        Some(r) => repair(&space, validator, &current, r, repair_budget, rng)?,
        None => (current, 0),
    };
    let rest_to_rest = Trajectory::rest_to_rest(&space, &repaired_path, limits).map_err(bad_input)?;
    let mut trajectory = rest_to_rest.clone();
    let mut current = repaired_path.clone();
    let passes = if smoothing == Smoothing::Parabolic {
        let mut ok = false;
        // A shortcut motion that fails the verification (a graze between the samples of its
        // ramp checks) is shortcut afresh from the rest-to-rest timing, with other random
        // pairs, before the pipeline falls back to an unshortcut motion.
        for attempt in 0..=PARABOLIC_RETRIES {
            if attempt > 0 {
                trajectory = rest_to_rest.clone();
            }
            let s = if attempt == 0 && settings.verify_resolution.is_some() {
                &first_run
            } else {
                settings
            };
            let stats = parabolic(motion, validator, &mut trajectory, limits, s, rng).map_err(bad_input)?;
            out_parabolic.absorb(&stats);
            ok = verify(&trajectory, validator);
            if ok {
                break;
            }
        }
        current = trajectory.to_path(&space, motion.resolution()).map_err(bad_input)?;
        ok
    } else {
        verify(&trajectory, validator)
    };
    let mut fell_back = false;
    if let Some(r) = settings.verify_resolution
        && !passes
    {
        // Fall back to the unshortcut timing of the repaired path. Its edges passed at the
        // fine spacing, but a path can graze a surface so thinly that samples at one spacing
        // pass and samples at another hit it; then the edge holding the state that failed is
        // re-planned around that state (a few times). Whatever is returned has passed the very
        // check the caller re-runs.
        fell_back = true;
        let (mut candidate, mut candidate_path) = (rest_to_rest, repaired_path);
        let mut verified = false;
        let mut bad = vec![0.0; space.dim()];
        for _ in 0..VERIFY_ROUNDS {
            let time = match candidate.check(&space, validator, r) {
                Ok(()) => {
                    verified = true;
                    break;
                }
                Err(TrajectoryError::InCollision { time }) => time,
                Err(e) => return Err(invalid_motion(e)),
            };
            candidate.sample(time, &mut bad, None);
            let left = repair_budget.saturating_sub(started.elapsed());
            let edge = candidate.span_at(time);
            match detour(&space, validator, &candidate_path, edge, &bad, r, left, rng) {
                Ok(p) => {
                    candidate = Trajectory::rest_to_rest(&space, &p, limits).map_err(bad_input)?;
                    candidate_path = p;
                }
                Err(_) => return Err(PlanError::InvalidMotion { time }),
            }
        }
        if !verified {
            candidate.check(&space, validator, r).map_err(invalid_motion)?;
        }
        trajectory = candidate;
        current = candidate_path;
    }
    Ok(Smoothed {
        trajectory,
        path: current,
        repaired,
        random: out_random,
        parabolic: out_parabolic,
        fell_back,
    })
}

/// Rejects states within `radius` of `avoid` (in the space's distance), on top of `inner`,
/// except the two states in `keep` (the ends of the re-planned stretch) and, when an end lies
/// inside the ball itself, the states nearer to that end than to `avoid` (so a motion can
/// still leave the end on the side away from `avoid`; one coming in past `avoid` still
/// crosses the rejected half of the ball).
struct Avoiding<'a, S, V: ?Sized> {
    space: &'a S,
    inner: &'a mut V,
    avoid: &'a [f64],
    radius: f64,
    keep: [&'a [f64]; 2],
    /// Whether each end of `keep` lies inside the avoided ball.
    inside: [bool; 2],
}

impl<S: Space, V: StateValidator + ?Sized> StateValidator for Avoiding<'_, S, V> {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        let d = self.space.distance(q, self.avoid);
        let allowed = d > self.radius
            || self
                .keep
                .iter()
                .zip(self.inside)
                .any(|(&end, inside)| end == q || (inside && self.space.distance(q, end) < d));
        allowed && self.inner.is_valid(q)
    }

    fn checks(&self) -> u64 {
        self.inner.checks()
    }

    fn tool_step(&mut self, q: &[f64], axis: usize, length: f64, out: &mut [f64]) -> bool {
        self.inner.tool_step(q, axis, length, out)
    }
}

/// `path` with edge `edge` (from state `edge` to `edge + 1`) re-planned around `bad`, a
/// colliding state on it that the edge's samples missed. States within two spacings of `bad`
/// count as invalid, so the new edges keep clear of where the old one grazed; when `bad` lies
/// that close to an end of the edge, the neighbouring edges are re-planned with it. The ends of
/// the whole path cannot move: when `bad` is next to one, the avoided ball shrinks to half the
/// distance (but not below ¾ of a spacing, the end itself excepted) and the new edges are
/// checked at half the spacing, so that an edge coming in past `bad` has a sample inside it.
#[allow(clippy::too_many_arguments)]
fn detour<S: Space + Clone, V: StateValidator + ?Sized, R: Rng + ?Sized>(
    space: &S,
    validator: &mut V,
    path: &Path,
    edge: usize,
    bad: &[f64],
    resolution: f64,
    budget: Duration,
    rng: &mut R,
) -> Result<Path, PlanError> {
    let states = &path.states;
    let last = states.len().saturating_sub(1);
    let radius = 2.0 * resolution;
    let (mut from, mut to) = (edge.min(last), (edge + 1).min(last));
    while from > 0 && space.distance(&states[from], bad) <= radius {
        from -= 1;
    }
    while to < last && space.distance(&states[to], bad) <= radius {
        to += 1;
    }
    let end_gaps = [space.distance(&states[from], bad), space.distance(&states[to], bad)];
    let radius = radius.min(0.5 * end_gaps[0].min(end_gaps[1])).max(0.75 * resolution);
    let mut avoiding = Avoiding {
        space,
        inner: validator,
        avoid: bad,
        radius,
        keep: [&states[from], &states[to]],
        inside: end_gaps.map(|g| g <= radius),
    };
    let mut fine = MotionValidator::new(space.clone(), 0.5 * resolution);
    let mut out = states[..=from].to_vec();
    let ends = [&states[from][..], &states[to][..]];
    out.extend(reroute(
        &mut fine,
        &mut avoiding,
        ends,
        Some(bad),
        resolution,
        budget,
        rng,
    )?);
    out.extend(states[to..].iter().cloned());
    Ok(Path { states: out })
}

fn invalid_motion(e: TrajectoryError) -> PlanError {
    match e {
        TrajectoryError::InCollision { time } => PlanError::InvalidMotion { time },
        other => PlanError::BadInput(other.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::{BYPASS_CHECKS, RETRACTED_BYPASS, bypass, first_collision, retracted_bypass};
    use crate::motion::MotionValidator;
    use crate::space::JointSpace;
    use crate::validity::StateValidator;

    /// A wall 1.05 mm thick across the whole unit square at y = 0.5: no sideways move gets
    /// round it, and a check at millimetre spacing finds it only among its last samples.
    struct Wall(u64);

    impl StateValidator for Wall {
        fn is_valid(&mut self, q: &[f64]) -> bool {
            self.0 += 1;
            !(0.5..=0.50105).contains(&q[1])
        }
        fn checks(&self) -> u64 {
            self.0
        }
    }

    /// A graze that no sideways move clears costs the cap's few full checks of the edge (plus
    /// one try's overshoot), not all 64 tries: those cost 12,500–13,800 checks here, about 32
    /// full checks of the 400-segment edge.
    #[test]
    fn a_bypass_that_cannot_succeed_gives_up_within_its_checks() {
        let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2]).unwrap();
        let mut fine = MotionValidator::new(space.clone(), 0.001);
        let ends: [&[f64]; 2] = [&[0.1, 0.3], &[0.1, 0.7]];
        let edge = u64::from(fine.segments(ends[0], ends[1]));
        for seed in 0..8 {
            let mut wall = Wall(0);
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
            let via = bypass(&space, &mut fine, &mut wall, ends, &[0.1, 0.5005], &mut rng);
            assert!(via.is_none(), "seed {seed}: {via:?} gets through the wall");
            assert!(
                wall.0 <= (BYPASS_CHECKS + 2) * edge && wall.0 < 4_000,
                "seed {seed}: {} checks for an edge of {edge} segments",
                wall.0
            );
        }
    }

    /// A disc of radius 0.1 whose top the line y = 0.5 cuts 1 mm deep, with exact retraction:
    /// a state inside moves radially out to `clearance` beyond the rim.
    struct Disc(u64);

    const DISC: ([f64; 2], f64) = ([0.5, 0.401], 0.1);

    impl StateValidator for Disc {
        fn is_valid(&mut self, q: &[f64]) -> bool {
            self.0 += 1;
            (q[0] - DISC.0[0]).hypot(q[1] - DISC.0[1]) >= DISC.1
        }
        fn checks(&self) -> u64 {
            self.0
        }
        fn retract(&mut self, q: &[f64], clearance: f64, _: usize, out: &mut [f64]) -> bool {
            let (dx, dy) = (q[0] - DISC.0[0], q[1] - DISC.0[1]);
            let d = dx.hypot(dy);
            if d == 0.0 {
                return false;
            }
            let r = (DISC.1 + clearance).max(d);
            out[0] = DISC.0[0] + dx * r / d;
            out[1] = DISC.0[1] + dy * r / d;
            self.is_valid(out)
        }
    }

    /// The grazed state pushed out along the contact normal to the first clearance makes a
    /// waypoint whose two edges pass the fine check; a validator without geometry gets none,
    /// at the cost of no check.
    #[test]
    fn a_graze_is_bypassed_along_the_contact_normal() {
        let space = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2]).unwrap();
        let mut fine = MotionValidator::new(space.clone(), 0.001);
        let ends: [&[f64]; 2] = [&[0.1, 0.5], &[0.9, 0.5]];
        assert!(!fine.check_motion(&mut Disc(0), ends[0], ends[1]));
        let graze = first_collision(&space, &mut Disc(0), ends[0], ends[1], 0.001).unwrap();
        let via = retracted_bypass(&mut fine, &mut Disc(0), ends, &graze).expect("a waypoint");
        let rim = (via[0] - DISC.0[0]).hypot(via[1] - DISC.0[1]);
        assert!(
            (rim - DISC.1 - RETRACTED_BYPASS.0[0]).abs() < 1e-9,
            "{via:?}: {rim} from the centre"
        );
        assert!(
            (via[0] - graze[0]).hypot(via[1] - graze[1]) < 0.01,
            "{via:?} far from {graze:?}"
        );
        assert!(fine.check_motion(&mut Disc(0), ends[0], &via) && fine.check_motion(&mut Disc(0), &via, ends[1]));
        let mut wall = Wall(0);
        assert_eq!(retracted_bypass(&mut fine, &mut wall, ends, &[0.5, 0.5005]), None);
        assert_eq!(wall.0, 0, "no geometry, no checks");
    }
}
