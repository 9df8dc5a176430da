//! State validity: robot model + chain + obstacles + self-collision + attached objects.

use std::sync::Arc;

use hearth_kinematics::{
    Chain, FkSubset, PairTable, RobotModel, SelfCollisionMatrix, from_pose, links_touch, to_pose, to_vector,
};
use nalgebra::{Isometry3, Point3};
use parry3d::math::{Pose, Real, Vector};
use parry3d::shape::{Ball, SharedShape};

use crate::error::PlanError;
use crate::obstacles::shapes_touch;
use crate::obstacles::{BallBatch, ObstacleId, Obstacles};
use crate::pair_lanes::PairLanes;
use crate::reach::{Reach, Row};
use crate::twins::Twins;

mod retract;

/// Decides whether one configuration is collision-free. Planners only see this trait, so a
/// vectorised or approximate checker can slot in without touching them.
///
/// ```
/// use hearth_planning::validity::StateValidator;
///
/// // Valid inside the unit disc; counts its checks.
/// struct Disc(u64);
/// impl StateValidator for Disc {
///     fn is_valid(&mut self, q: &[f64]) -> bool {
///         self.0 += 1;
///         q[0].hypot(q[1]) < 1.0
///     }
///     fn checks(&self) -> u64 {
///         self.0
///     }
/// }
/// let mut disc = Disc(0);
/// assert!(disc.is_valid(&[0.5, 0.5]) && !disc.is_valid(&[1.0, 1.0]));
/// assert_eq!(disc.first_invalid(&[0.0, 0.0, 2.0, 0.0], 2), Some(1));
/// assert_eq!(disc.checks(), 4);
/// ```
pub trait StateValidator {
    /// Whether `q` (a configuration of the planned space) is valid.
    ///
    /// ```
    /// use hearth_planning::validity::StateValidator;
    ///
    /// // Valid while every coordinate stays below its cap.
    /// struct Below(Vec<f64>, u64);
    /// impl StateValidator for Below {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool {
    ///         self.1 += 1;
    ///         q.len() == self.0.len() && q.iter().zip(&self.0).all(|(v, cap)| v < cap)
    ///     }
    ///     fn checks(&self) -> u64 { self.1 }
    /// }
    /// let mut v = Below(vec![1.0, 2.0], 0);
    /// assert!(v.is_valid(&[0.5, 1.5]));
    /// assert!(!v.is_valid(&[0.5, 2.5]) && !v.is_valid(&[f64::NAN, 0.0]));
    /// ```
    fn is_valid(&mut self, q: &[f64]) -> bool;
    /// How many configurations have been checked so far: planners report the difference over a
    /// call as [`PlanStats::states_checked`](crate::planner::PlanStats::states_checked).
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::validity::StateValidator;
    ///
    /// struct Free(u64);
    /// impl StateValidator for Free {
    ///     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
    ///     fn checks(&self) -> u64 { self.0 }
    /// }
    /// let mut free = Free(0);
    /// free.is_valid(&[0.0]);
    /// let mut mv = MotionValidator::new(JointSpace::new(&[0.0], &[1.0], &[false])?, 0.25);
    /// mv.check_motion(&mut free, &[0.0], &[1.0]); // the three states between the ends
    /// assert_eq!(free.checks(), 4);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn checks(&self) -> u64;

    /// Checks the states in `states` (`dim` values each, one after another) in order and
    /// returns the index of the first invalid one, or `None` when all are valid. States after
    /// the first invalid one are not checked (nor counted). Implementations may compute several
    /// states together (the default asks [`StateValidator::is_valid`] one by one) and must give
    /// the same answer.
    ///
    /// ```
    /// use hearth_planning::validity::StateValidator;
    /// struct Positive(u64);
    /// impl StateValidator for Positive {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; q[0] > 0.0 }
    ///     fn checks(&self) -> u64 { self.0 }
    /// }
    /// let mut v = Positive(0);
    /// assert_eq!(v.first_invalid(&[1.0, 2.0, -1.0, 3.0], 1), Some(2));
    /// assert_eq!(v.checks(), 3);
    /// assert_eq!(v.first_invalid(&[1.0, 2.0], 1), None);
    /// ```
    fn first_invalid(&mut self, states: &[f64], dim: usize) -> Option<usize> {
        states.chunks_exact(dim.max(1)).position(|q| !self.is_valid(q))
    }

    /// Index of an invalid state among `states` (`dim` values each), which follow one another
    /// along a motion (neighbours close together), or `None` when all are valid. Which invalid
    /// state is reported when there are several is unspecified. The default checks midpoints
    /// coarse to fine and the two ends last (a colliding stretch is found early), handing the
    /// states to [`StateValidator::first_invalid`] a few at a time. An implementation may
    /// skip states it can prove valid from a checked neighbour ([`RobotValidity`] does);
    /// skipped states are not counted as checks.
    ///
    /// ```
    /// use hearth_planning::validity::StateValidator;
    /// struct Below(Vec<f64>);
    /// impl StateValidator for Below {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0.push(q[0]); q[0] < 0.7 }
    ///     fn checks(&self) -> u64 { self.0.len() as u64 }
    /// }
    /// let line: Vec<f64> = (0..=10).map(|i| i as f64 / 10.0).collect();
    /// let mut v = Below(Vec::new());
    /// let bad = v.first_invalid_along(&line, 1).unwrap();
    /// assert!(line[bad] >= 0.7);
    /// assert_eq!(v.0[0], 0.5); // the middle first
    /// assert_eq!(Below(Vec::new()).first_invalid_along(&line[..6], 1), None);
    /// ```
    fn first_invalid_along(&mut self, states: &[f64], dim: usize) -> Option<usize> {
        bisect_first_invalid(self, states, dim)
    }

    /// A short straight move of the robot's tool from `q`, for planners that need to leave a
    /// tight spot ([`Escape`](crate::birrt::Escape)): writes into `out` the configuration
    /// that moves the tool (the planned chain's last link) by `length` metres along one of
    /// its own axes with its orientation held, to first order (joints that would pass a limit
    /// stop at it), and returns true; false when there is no such move (the default: the
    /// validator knows no robot) or the limits stop every joint. `axis` 0–2 are the tool frame's x, y and z, 3–5 the same axes
    /// negated. A grasp between shelf boards is left by backing straight out along the
    /// gripper's axis: a narrow channel in joint space that random steps seldom find. The
    /// result is not checked for validity.
    ///
    /// ```
    /// use hearth_planning::validity::StateValidator;
    /// struct Free;
    /// impl StateValidator for Free {
    ///     fn is_valid(&mut self, _: &[f64]) -> bool { true }
    ///     fn checks(&self) -> u64 { 0 }
    /// }
    /// let mut out = [0.0; 2];
    /// assert!(!Free.tool_step(&[0.0, 0.0], 0, 0.01, &mut out)); // no robot, no tool
    /// ```
    fn tool_step(&mut self, q: &[f64], axis: usize, length: f64, out: &mut [f64]) -> bool {
        let _ = (q, axis, length, out);
        false
    }

    /// Pushes a state whose robot sinks into obstacles out of them, for planners that grow
    /// along narrow channels ([`BiRrt::retraction`](crate::BiRrt::retraction)): writes into
    /// `out` the state reached by up to `rounds` joint steps, each moving the contact points
    /// (one per touching link) out of the obstacles along the contact normals to `clearance`
    /// metres beyond the surface, to first order, and returns whether `out` is valid (checked
    /// and counted). A sample that lands in an obstacle next to a channel becomes a state in
    /// the channel, where random samples seldom fall. The default knows no geometry: it
    /// returns false and leaves `out` as it was.
    ///
    /// ```
    /// use hearth_planning::validity::StateValidator;
    /// struct Free;
    /// impl StateValidator for Free {
    ///     fn is_valid(&mut self, _: &[f64]) -> bool { true }
    ///     fn checks(&self) -> u64 { 0 }
    /// }
    /// let mut out = [0.0; 2];
    /// assert!(!Free.retract(&[0.5, 0.5], 0.01, 3, &mut out)); // no robot, no contacts
    /// assert_eq!(out, [0.0; 2]);
    /// ```
    fn retract(&mut self, q: &[f64], clearance: f64, rounds: usize, out: &mut [f64]) -> bool {
        let _ = (q, clearance, rounds, out);
        false
    }
}

/// [`StateValidator::first_invalid_along`]'s default: midpoints coarse to fine, then the two
/// ends, [`crate::motion::BATCH`] states at a time through [`StateValidator::first_invalid`]. The
/// group's states are copied into a buffer on the stack (on the heap only for spaces of over
/// 32 dimensions).
fn bisect_first_invalid<V: StateValidator + ?Sized>(validator: &mut V, flat: &[f64], dim: usize) -> Option<usize> {
    let dim = dim.max(1);
    let n = flat.len() / dim;
    if n == 0 {
        return None;
    }
    let state = |i: usize| &flat[i * dim..(i + 1) * dim];
    const BATCH: usize = crate::motion::BATCH;
    let mut stack = [0.0; BATCH * 32];
    let mut heap = Vec::new();
    let buf = if BATCH * dim <= stack.len() {
        &mut stack[..BATCH * dim]
    } else {
        heap.resize(BATCH * dim, 0.0);
        &mut heap[..]
    };
    // The intervals still to split, first in first out (coarse to fine): a ring, on the stack
    // for up to 256 states. The intervals it holds at once share at most their ends, and each
    // spans at least one step (or is the one state), so there are at most `n` of them.
    let mut ring_stack = [(0usize, 0usize); 256];
    let mut ring_heap = Vec::new();
    let ring = if n <= ring_stack.len() {
        &mut ring_stack[..]
    } else {
        ring_heap.resize(n, (0, 0));
        &mut ring_heap[..]
    };
    ring[0] = (0usize, n - 1);
    let (mut head, mut queued) = (0usize, 1usize);
    let mids = std::iter::from_fn(|| {
        while queued > 0 {
            let (lo, hi) = ring[head];
            head = (head + 1) % ring.len();
            queued -= 1;
            if hi - lo >= 2 {
                let mid = lo + (hi - lo) / 2;
                for half in [(lo, mid), (mid, hi)] {
                    ring[(head + queued) % ring.len()] = half;
                    queued += 1;
                }
                return Some(mid);
            }
        }
        None
    });
    let mut group = [0usize; BATCH];
    let mut len = 0;
    for i in mids.chain([n - 1, 0].into_iter().take(n.min(2))) {
        buf[len * dim..(len + 1) * dim].copy_from_slice(state(i));
        group[len] = i;
        len += 1;
        if len == BATCH {
            if let Some(k) = validator.first_invalid(buf, dim) {
                return Some(group[k]);
            }
            len = 0;
        }
    }
    if len == 0 {
        return None;
    }
    validator.first_invalid(&buf[..len * dim], dim).map(|k| group[k])
}

/// What makes a configuration invalid, with names for messages
/// ([`RobotValidity::explain`]).
///
/// ```
/// use hearth_planning::validity::Contact;
///
/// let c = Contact::Obstacle { link: "panda_hand".into(), obstacle: "shelf".into() };
/// assert_eq!(c.to_string(), "link `panda_hand` touches obstacle `shelf`");
/// let s = Contact::SelfCollision { a: "panda_link2".into(), b: "panda_hand".into() };
/// assert_eq!(s.to_string(), "link `panda_link2` touches link `panda_hand`");
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Two robot links (or an attached object, named `attached:NAME`) touch.
    SelfCollision {
        /// First link.
        a: String,
        /// Second link.
        b: String,
    },
    /// A robot link (or attached object) touches an obstacle.
    Obstacle {
        /// The link.
        link: String,
        /// The obstacle's name.
        obstacle: String,
    },
}

impl std::fmt::Display for Contact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Contact::SelfCollision { a, b } => write!(f, "link `{a}` touches link `{b}`"),
            Contact::Obstacle { link, obstacle } => write!(f, "link `{link}` touches obstacle `{obstacle}`"),
        }
    }
}

/// An object held by the robot: it moves rigidly with `link` and is checked like a link
/// ([`RobotValidity::attach`]).
///
/// ```
/// use hearth_planning::kinematics::nalgebra::Isometry3;
/// use hearth_planning::obstacles::{Obstacle, ParryScene};
/// use hearth_planning::validity::{Attached, Contact, RobotValidity};
/// use parry3d::math::{Pose, Vector};
/// use parry3d::shape::SharedShape;
/// # use std::sync::Arc;
/// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
/// # let panda = RobotModel::builtin("panda").unwrap();
/// # let arm = Chain::named(&panda, "arm").unwrap();
/// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
///
/// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
/// // A 50 cm rod held in the hand, pointing down at a low table.
/// let rod = Attached {
///     name: "rod".into(),
///     link: panda.link_index("panda_hand")?,
///     offset: Isometry3::translation(0.0, 0.0, 0.25),
///     shape: SharedShape::cuboid(0.01, 0.01, 0.25),
/// };
/// let table = Obstacle::cuboid("table", Pose::translation(0.3, 0.0, 0.15), Vector::new(0.2, 0.2, 0.05));
/// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![table])));
/// v.attach(rod)?;
/// let over_table = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
/// let hit = Contact::Obstacle { link: "attached:rod".into(), obstacle: "table".into() };
/// assert_eq!(v.explain(&over_table), Some(hit));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone)]
pub struct Attached {
    /// Name used in messages.
    pub name: String,
    /// The link it is fixed to.
    pub link: usize,
    /// Its pose in the link frame.
    pub offset: Isometry3<f64>,
    /// Its shape.
    pub shape: SharedShape,
}

/// The moving links whose poses a check reads: links with collision geometry or an attached
/// object, and their ancestors. Frames with neither below them (the Fetch's six head-camera
/// frames, the Panda's tool point) are left out of the per-check kinematics.
fn checked_moving_fk(model: &RobotModel, moves: &[bool], attached: &[Attached]) -> FkSubset {
    let anchors: Vec<usize> = (0..model.links().len())
        .filter(|&l| model.link_shape(l).is_some())
        .chain(attached.iter().map(|a| a.link).filter(|&l| l < model.links().len()))
        .collect();
    model.fk_subset(|l| anchors.iter().any(|&g| moving_ancestry(model, moves, l, g)))
}

/// Whether link `l` moves with the chain and is link `g` or one of its ancestors.
fn moving_ancestry(model: &RobotModel, moves: &[bool], l: usize, g: usize) -> bool {
    moves[l] && (l == g || model.is_ancestor(l, g))
}

/// Per geometric link: the moving links from the root down to it (itself included).
fn ancestry_subsets(model: &RobotModel, geometric: &[usize], moves: &[bool]) -> Vec<FkSubset> {
    geometric
        .iter()
        .map(|&g| model.fk_subset(|l| moving_ancestry(model, moves, l, g)))
        .collect()
}

/// Per geometric link: the links of `moving` that are neither it nor its ancestors (the
/// complement of its ancestry within `moving`).
fn rest_subsets(model: &RobotModel, geometric: &[usize], moving: &FkSubset, moves: &[bool]) -> Vec<FkSubset> {
    geometric
        .iter()
        .map(|&g| model.fk_subset(|l| moving.contains(l) && !moving_ancestry(model, moves, l, g)))
        .collect()
}

/// The lightest weight [`RobotValidity::joint_weights`] gives a joint (one that moves nothing
/// checked).
const MIN_JOINT_WEIGHT: f64 = 1e-3;

/// The exact checker: forward kinematics of the whole robot, every link with geometry against
/// the obstacles, the self-collision matrix's pairs against each other, and attached objects
/// against both. Buffers are allocated once; checking does not allocate.
///
/// ```
/// use std::sync::Arc;
/// use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
/// use hearth_planning::obstacles::{Obstacle, ParryScene};
/// use hearth_planning::validity::{RobotValidity, StateValidator};
/// use parry3d::math::{Pose, Vector};
///
/// let panda = RobotModel::builtin("panda").unwrap();
/// let arm = Chain::named(&panda, "arm").unwrap();
/// let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
/// let wall = Obstacle::cuboid("wall", Pose::translation(0.45, 0.0, 0.5), Vector::new(0.02, 1.0, 1.0));
/// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![wall])));
/// let folded = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
/// assert!(v.is_valid(&folded));
/// let reaching = [0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.785]; // stretched forward into the wall
/// assert!(!v.is_valid(&reaching));
/// assert!(v.explain(&reaching).unwrap().to_string().contains("wall"));
/// ```
#[derive(Clone)]
pub struct RobotValidity {
    model: RobotModel,
    chain: Chain,
    matrix: SelfCollisionMatrix,
    obstacles: Arc<dyn Obstacles>,
    geometric: Vec<usize>,
    pairs: Vec<(usize, usize)>,
    attached: Vec<Attached>,
    base: Isometry3<f64>,
    q_full: Vec<f64>,
    poses: Vec<Isometry3<f64>>,
    checks: u64,
    broad: BroadPhase,
    /// Per geometric link: whether its pose depends on the chain's joints.
    link_moves: Vec<bool>,
    /// Per checked pair: whether either link moves with the chain.
    pair_moves: Vec<bool>,
    /// Per checked pair: the model's clearance table for it, where it has one (pairs whose
    /// relative pose depends on one or two joints), consulted before any geometry.
    pair_tables: Vec<Option<Arc<PairTable>>>,
    /// Whether the links and pairs that never move with the chain are clear, once known for
    /// the current reference, base and obstacles.
    fixed_clear: Option<bool>,
    /// The links that move with the chain and that a check reads (`checked_moving_fk`): after
    /// one full pass for the current reference and base, forward kinematics recomputes only
    /// these.
    moving_fk: FkSubset,
    /// Whether `poses` of the links that do not move are current.
    fixed_poses_current: bool,
    /// Per geometric link that moves with the chain: the moving links from the root down to
    /// it (itself included), so that a state can be tested against the link that hit last
    /// before the rest of the robot's forward kinematics is computed
    /// ([`RobotValidity::hint_link_hits`]).
    ancestry_fk: Vec<FkSubset>,
    /// Per geometric link that moves with the chain: the other links of `moving_fk`, whose
    /// poses [`RobotValidity::hint_link_hits`] computes only once the hinted link is clear.
    rest_fk: Vec<FkSubset>,
    /// Set by [`RobotValidity::hint_link_hits`] when it found the hinted link clear on the
    /// current poses, so that [`RobotValidity::robot_blocked`] does not test it again.
    hint_clear: bool,
    /// Four configurations checked together ([`StateValidator::first_invalid`]): full
    /// configurations and pose buffers, one per lane.
    lane_q: [Vec<f64>; 4],
    lane_poses: [Vec<Isometry3<f64>>; 4],
    /// Whether the lane buffers hold the current poses of the links that do not move.
    lanes_current: bool,
    /// Displacement bounds for free regions ([`StateValidator::first_invalid_along`]).
    reach: Reach,
    /// Per lane: the free region of the state last found valid in it, as (bound row,
    /// clearance) constraints ([`RobotValidity::free_region`]).
    free: [Vec<(Row, f64)>; 4],
    /// Per lane: the largest change per joint from the state to either neighbour along the
    /// motion; a free region that cannot hold them is given up as soon as that shows.
    next_to: [[f64; 32]; 4],
    /// Scratch: the stretches of states not yet checked nor certified.
    stretches: std::collections::VecDeque<(usize, usize)>,
    /// Scratch of [`StateValidator::tool_step`]: a full configuration, a pose buffer and the
    /// tool's Jacobian, so that the escape's walks do not allocate.
    tool_q: Vec<f64>,
    tool_poses: Vec<Isometry3<f64>>,
    tool_jacobian: nalgebra::Matrix6xX<f64>,
    /// Scratch of [`StateValidator::retract`].
    retract: retract::RetractScratch,
    /// Links and pairs that duplicate others for the current reference ([`Twins`]): left out
    /// of the per-check tests.
    twins: Twins,
}

/// States a stretch must hold before a check along a motion finds the free region of its
/// middle state ([`RobotValidity::first_invalid_along`]).
const FREE_RADIUS_MIN_STATES: usize = 3;
/// Clearance (m) a free region leaves unused: covers f32 rounding in the distances.
const FREE_RADIUS_SLACK: f64 = 1e-4;
/// Damping λ (m; λ² is added to the diagonal of J·Jᵀ) of [`RobotValidity`]'s tool steps:
/// keeps the joint step bounded near singular configurations.
const TOOL_STEP_DAMPING: f64 = 1e-2;

/// Parts meeting a link's touching cover balls from which their bounding balls are asked
/// about in one batch before the exact tests ([`RobotValidity::touched_parts_hit`]).
const PART_BATCH_MIN: u32 = 2;

/// Absolute slack (m) added to every bounding radius so that f32/f64 rounding and parry's
/// tolerances can never make the broad phase prune a pair that the exact test reports.
const BOUND_SLACK_ABS: f64 = 1e-4;
/// Relative slack added to every bounding radius (same purpose).
const BOUND_SLACK_REL: f64 = 1e-3;

/// Conservative broad phase: one bounding sphere per link with geometry (in the link frame,
/// slightly inflated), used to skip exact tests that provably cannot report contact.
///
/// * Against obstacles: if the link's bounding ball touches nothing (asked through
///   [`Obstacles::first_hit`], so any margin the implementation applies is honoured), the link
///   shape, which lies inside the ball, touches nothing either.
/// * Self-collision: if two links' balls are apart, the links are apart.
///
/// Nothing is cached across calls except which check failed last (tried first next time), so
/// moving obstacles stay correct and answers are exactly the exact-geometry answers.
#[derive(Clone)]
struct BroadPhase {
    /// Per link (indexed by link id): centre of the bounding sphere in the link frame.
    local_center: Vec<Point3<f64>>,
    /// Geometric links (indices into `geometric`) that move with the chain, asked about in
    /// one batch (at most `BallBatch::CAPACITY`; the rest one by one).
    moving: Vec<usize>,
    /// Scratch batch of balls (reused, no allocation per check).
    batch: BallBatch,
    /// The bounding balls of the first [`BallBatch::CAPACITY`] links of `moving`, in that
    /// order, for the current poses (filled with their centres by `update_centers`).
    moving_batch: BallBatch,
    /// Per link: inflated bounding radius (0 for links without geometry).
    radius: Vec<f64>,
    /// Per geometric link (same order as `RobotValidity::geometric`): the bounding ball.
    balls: Vec<Ball>,
    /// Per checked pair: squared sum of the two radii.
    pair_reach2: Vec<f64>,
    /// Per link: range into `parts` of its parts' bounding spheres (one for a non-compound).
    part_range: Vec<std::ops::Range<usize>>,
    /// Bounding spheres of every link's parts: centre in the link frame and inflated radius.
    parts: Vec<(Point3<f64>, f64)>,
    /// Per link: range into `cover` of the balls covering it (empty: no cover, exact tests).
    cover_range: Vec<std::ops::Range<usize>>,
    /// Balls whose union covers each link (see `RobotModel::link_spheres`): centre in the
    /// link frame and inflated radius. Tested against the obstacles before exact tests.
    cover: Vec<(Point3<f64>, f64)>,
    /// `cover` in `f32`, as structure-of-arrays (x, y, z, radius), for placing a link's balls
    /// into a [`BallBatch`] in one vectorised pass ([`BallBatch::push_placed`]).
    cover_local: [Vec<Real>; 4],
    /// Per part (same indices as `parts`): its shape and its pose in the link frame, for
    /// exact tests of single parts.
    part_shape: Vec<(SharedShape, Isometry3<f64>)>,
    /// Per part: a ball inside it (centre in the link frame, radius; radius 0 for none), for
    /// parts whose exact test goes to parry's GJK. An obstacle that touches the ball touches
    /// the part, so a hit there settles the part's test at the cost of a ball query.
    part_inner: Vec<(Point3<f64>, f64)>,
    /// Per part: the balls of its link's cover (bit `k` = the `k`-th ball of the link's
    /// `cover_range`) that meet it. A part can touch an obstacle only where one of these
    /// balls does, so the exact test runs only on parts whose balls touched something.
    part_cover: Vec<u64>,
    /// The pairs that move with the chain, in pair order: the two links and the squared sum
    /// of their bounding radii (`pair_reach2`), for the per-check loop over pairs.
    moving_pairs: Vec<(u32, u32, f64)>,
    /// Per entry of `moving_pairs`: the pair's index.
    moving_pair_index: Vec<u32>,
    /// `moving_pairs`' bounding-ball tests in f32 lanes, a filter before the exact one.
    pair_lanes: PairLanes,
    /// Per link: its shape as one box, when it is one (pose in the link frame, half extents),
    /// for the self-collision test of its pairs against the other link's cover.
    boxes: Vec<Option<(Isometry3<f64>, nalgebra::Vector3<f64>)>>,
    /// Per checked pair: `(field, covered)` when one link has a distance field
    /// ([`RobotModel::link_field`]) and the other a cover, for the field test of the cover's
    /// balls (the link with more parts holds the field when both have one), and the same the
    /// other way round when both links have a field and a cover.
    pair_field: Vec<[Option<(usize, usize)>; 2]>,
    /// World centres of `parts` for the current configuration, filled lazily per link.
    parts_world: Vec<Point3<f64>>,
    /// Per link: the value of `epoch` when its `parts_world` were last filled.
    parts_epoch: Vec<u64>,
    /// Incremented per check.
    epoch: u64,
    /// Scratch lists of part indices near the other link (reused, no allocation per check).
    near_a: Vec<usize>,
    near_b: Vec<usize>,
    /// `near_b`'s part spheres as f32 structure-of-arrays, centres relative to link `a`'s
    /// sphere centre (so values stay small and f32 rounding stays far below the slack):
    /// x, y, z, radius.
    near_soa: [Vec<f32>; 4],
    /// Per link: world centre of the bounding sphere for the current configuration.
    world_center: Vec<Point3<f64>>,
    /// The check that failed last, tried first.
    hint: Hint,
    /// With `Hint::Link`: the part of that link (index into `parts`) that touched an obstacle
    /// (tried before the rest of the link).
    hint_part: usize,
    /// How many checks in a row that part settled (a tree wedged in a pocket fails the same way
    /// again and again), 0 after a check that passed (which should not pay for testing it). It
    /// is read only with a link hint, and every link hint is set where a part is recorded.
    hint_streak: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hint {
    None,
    Link(usize),
    Pair(usize),
}

impl BroadPhase {
    /// `link_moves`: per geometric link, whether it moves with the chain; `pair_moves`: per
    /// pair, whether either of its links does.
    fn new(
        model: &RobotModel,
        geometric: &[usize],
        pairs: &[(usize, usize)],
        link_moves: &[bool],
        pair_moves: &[bool],
    ) -> Self {
        let n = model.links().len();
        let mut local_center = vec![Point3::origin(); n];
        let mut radius = vec![0.0; n];
        let mut balls = Vec::with_capacity(geometric.len());
        let mut part_range = vec![0..0; n];
        let mut parts = Vec::new();
        let mut cover_range = vec![0..0; n];
        let mut cover = Vec::new();
        let mut part_shape = Vec::new();
        let mut boxes = vec![None; n];
        let inflate_f64 = |r: f64| {
            if r.is_finite() {
                r * (1.0 + BOUND_SLACK_REL) + BOUND_SLACK_ABS
            } else {
                f64::INFINITY
            }
        };
        let inflate = |r: f32| inflate_f64(f64::from(r));
        let p64 = |c: Vector| Point3::new(f64::from(c.x), f64::from(c.y), f64::from(c.z));
        for &l in geometric {
            let s = model.link_shape(l).expect("geometric link has a shape");
            let start = parts.len();
            let cover_start = cover.len();
            cover.extend(model.link_spheres(l).iter().map(|b| (b.center, inflate_f64(b.radius))));
            cover_range[l] = cover_start..cover.len();
            if let Some(compound) = s.shape.as_compound() {
                for (pose, part) in compound.shapes() {
                    let bs = part.compute_bounding_sphere(pose);
                    parts.push((s.origin * p64(bs.center()), inflate(bs.radius())));
                    part_shape.push((part.clone(), s.origin * from_pose(pose)));
                }
            } else {
                let bs = s.shape.compute_local_bounding_sphere();
                parts.push((s.origin * p64(bs.center()), inflate(bs.radius())));
                part_shape.push((s.shape.clone(), s.origin));
            }
            part_range[l] = start..parts.len();
            if let [(shape, at)] = &part_shape[start..]
                && let Some(cuboid) = shape.as_cuboid()
            {
                boxes[l] = Some((*at, p64(cuboid.half_extents).coords));
            }
            let bs = s.shape.compute_local_bounding_sphere();
            let c = bs.center();
            let c = Point3::new(f64::from(c.x), f64::from(c.y), f64::from(c.z));
            local_center[l] = s.origin * c;
            // The smaller of the shape's own bounding sphere and a sphere around the parts'
            // (inflated) spheres; both contain the whole shape.
            let around_parts = parts[start..]
                .iter()
                .map(|(pc, pr)| (pc - local_center[l]).norm() + pr)
                .fold(0.0f64, f64::max);
            let r = inflate(bs.radius()).min(around_parts * (1.0 + 1e-9) + 1e-9);
            radius[l] = r;
            balls.push(Ball::new(if r.is_finite() { r as f32 } else { f32::MAX }));
        }
        let pair_reach2: Vec<f64> = pairs
            .iter()
            .map(|&(a, b)| {
                let s = radius[a] + radius[b];
                s * s
            })
            .collect();
        let (moving_pairs, moving_pair_index): (Vec<_>, Vec<_>) = pairs
            .iter()
            .enumerate()
            .filter(|&(i, _)| pair_moves[i])
            .map(|(i, &(a, b))| ((a as u32, b as u32, pair_reach2[i]), i as u32))
            .unzip();
        let n_parts = parts.len();
        let pair_field = pairs
            .iter()
            .map(|&(a, b)| {
                let (big, small) = if part_range[a].len() >= part_range[b].len() {
                    (a, b)
                } else {
                    (b, a)
                };
                let mut ways = [(big, small), (small, big)]
                    .into_iter()
                    .filter(|&(f, c)| model.link_field(f).is_some() && !cover_range[c].is_empty());
                [ways.next(), ways.next()]
            })
            .collect();
        let part_inner = part_shape.iter().map(inner_ball).collect();
        let part_cover = (0..n)
            .flat_map(|l| part_range[l].clone().map(move |k| (l, k)))
            .map(|(l, k)| cover_mask(&cover[cover_range[l].clone()], &part_shape[k]))
            .collect();
        Self {
            cover_range,
            cover_local: [
                cover.iter().map(|(c, _)| c.x as Real).collect(),
                cover.iter().map(|(c, _)| c.y as Real).collect(),
                cover.iter().map(|(c, _)| c.z as Real).collect(),
                cover.iter().map(|&(_, r)| r as Real).collect(),
            ],
            cover,
            part_shape,
            part_inner,
            part_cover,
            moving: (0..geometric.len()).filter(|&i| link_moves[i]).collect(),
            batch: BallBatch::new(),
            moving_batch: BallBatch::new(),
            local_center,
            radius,
            balls,
            pair_reach2,
            part_range,
            parts,
            pair_lanes: PairLanes::new(&moving_pairs),
            moving_pairs,
            moving_pair_index,
            boxes,
            pair_field,
            parts_world: vec![Point3::origin(); n_parts],
            parts_epoch: vec![u64::MAX; n],
            epoch: 0,
            near_a: Vec::with_capacity(n_parts),
            near_b: Vec::with_capacity(n_parts),
            near_soa: std::array::from_fn(|_| Vec::with_capacity(n_parts)),
            world_center: vec![Point3::origin(); n],
            hint: Hint::None,
            hint_part: usize::MAX,
            hint_streak: 0,
        }
    }

    /// Appends link `l`'s cover balls, placed at `pose`, to `batch` (the caller checks that
    /// they fit). The rotation and translation go to `f32` once; the balls are placed in one
    /// vectorised pass, within ~1e-7 m of the `f64` placement rounded to `f32`, far inside
    /// the covers' inflation.
    fn push_cover(&mut self, l: usize, pose: &Isometry3<f64>) {
        let range = self.cover_range[l].clone();
        let m = pose.rotation.to_rotation_matrix();
        let rotation: [[Real; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)] as Real));
        let t = &pose.translation.vector;
        let [x, y, z, r] = &self.cover_local;
        self.batch.push_placed(
            &rotation,
            [t.x as Real, t.y as Real, t.z as Real],
            [&x[range.clone()], &y[range.clone()], &z[range.clone()], &r[range]],
        );
    }
}

/// Deepest a ball inside a part must sit below its surface, so that a ball touching an
/// obstacle means the part's exact test reports contact whatever its tolerance.
const INNER_BALL_SINK: f64 = 5e-4;
/// Smallest inner ball worth a query (m).
const INNER_BALL_MIN: f64 = 2e-3;

/// A ball inside `part` (shape and pose in the link frame) for cylinders and convex
/// polyhedra: centred on the cylinder's centre or the polyhedron's centre of mass, its radius
/// that point's depth below the surface (the nearest cap or the side; the nearest face plane)
/// less [`INNER_BALL_SINK`]. Radius 0 (no ball) for other shapes, whose exact tests are closed
/// forms or rare, and where the ball would be smaller than [`INNER_BALL_MIN`].
fn inner_ball(part: &(SharedShape, Isometry3<f64>)) -> (Point3<f64>, f64) {
    let (shape, at) = part;
    let (center, depth) = if let Some(c) = shape.as_cylinder() {
        (Vector::ZERO, c.radius.min(c.half_height))
    } else if let Some(p) = shape.as_convex_polyhedron() {
        let com = shape.mass_properties(1.0).local_com;
        let depth = p
            .faces()
            .iter()
            .map(|f| {
                let reach = p.points().iter().map(|v| v.dot(f.normal)).fold(f32::MIN, f32::max);
                reach - com.dot(f.normal)
            })
            .fold(f32::MAX, f32::min);
        (com, depth)
    } else {
        (Vector::ZERO, 0.0)
    };
    let r = f64::from(depth) - INNER_BALL_SINK;
    if r.is_nan() || r < INNER_BALL_MIN {
        return (Point3::origin(), 0.0);
    }
    let c = at * Point3::new(f64::from(center.x), f64::from(center.y), f64::from(center.z));
    (c, r)
}

/// Which balls of a link's `cover` (inflated radii, link frame) meet `part` (shape and pose in
/// the link frame): all bits when the link has no cover or one too big for a [`BallBatch`]
/// (such links get exact tests only), and the ball's bit when parry cannot tell.
fn cover_mask(cover: &[(Point3<f64>, f64)], part: &(SharedShape, Isometry3<f64>)) -> u64 {
    if cover.is_empty() || cover.len() > BallBatch::CAPACITY {
        return u64::MAX;
    }
    let part_pose = to_pose(&part.1);
    cover.iter().enumerate().fold(0, |mask, (k, (c, r))| {
        // Grown a little more, so that f32 rounding can only add balls.
        let ball = Ball::new((r * (1.0 + BOUND_SLACK_REL) + BOUND_SLACK_ABS) as f32);
        let at = to_pose(&Isometry3::translation(c.x, c.y, c.z));
        let meets = parry3d::query::intersection_test(&at, &ball, &part_pose, part.0.as_ref())
            .map(|r| r.intersecting)
            .unwrap_or(true);
        mask | (u64::from(meets) << k)
    })
}

impl RobotValidity {
    /// A checker for `chain`'s configurations. Joints outside the chain keep the model's
    /// neutral configuration (see [`RobotValidity::set_reference`]); the robot root sits at
    /// the world origin (see [`RobotValidity::set_base`]).
    ///
    /// ```
    /// use std::sync::Arc;
    /// use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{RobotValidity, StateValidator};
    /// use parry3d::math::Vector;
    ///
    /// let panda = RobotModel::builtin("panda")?;
    /// let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    /// let lamp = Obstacle::ball("lamp", Vector::new(0.0, 0.0, 1.2), 0.1); // above the robot's root
    /// let mut v = RobotValidity::new(Chain::named(&panda, "arm")?, acm, Arc::new(ParryScene::new(vec![lamp])));
    /// assert!(v.is_valid(&[0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])); // folded
    /// assert!(!v.is_valid(&[0.0, 0.0, 0.0, -0.1, 0.0, 3.0, 0.0])); // stretched up into the lamp
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(chain: Chain, matrix: SelfCollisionMatrix, obstacles: Arc<dyn Obstacles>) -> Self {
        let model = chain.model().clone();
        let geometric: Vec<usize> = (0..model.links().len())
            .filter(|&l| model.link_shape(l).is_some())
            .collect();
        let pairs = matrix.checked_geometric_pairs(&model);
        let twins = Twins::new(&model, &chain, geometric.len(), pairs.len());
        let moves = twins.moving_links();
        let moving_fk = checked_moving_fk(&model, &moves, &[]);
        let ancestry_fk = ancestry_subsets(&model, &geometric, &moves);
        let rest_fk = rest_subsets(&model, &geometric, &moving_fk, &moves);
        let link_moves: Vec<bool> = geometric.iter().map(|&l| moves[l]).collect();
        let pair_moves: Vec<bool> = pairs.iter().map(|&(a, b)| moves[a] || moves[b]).collect();
        let broad = BroadPhase::new(&model, &geometric, &pairs, &link_moves, &pair_moves);
        let pair_tables: Vec<Option<Arc<PairTable>>> = pairs
            .iter()
            .zip(&pair_moves)
            .map(|(&(a, b), &m)| if m { model.pair_table(a, b) } else { None })
            .collect();
        let tables: Vec<Vec<(usize, f64)>> = pair_tables
            .iter()
            .map(|t| t.as_ref().map(|t| t.reach().collect()).unwrap_or_default())
            .collect();
        let reach = Reach::new(&model, &chain, &geometric, &pairs, &tables, |l| {
            let centres = broad.cover[broad.cover_range[l].clone()].iter().map(|(c, _)| c);
            centres
                .chain([&broad.local_center[l]])
                .map(|c| c.coords.norm())
                .fold(0.0, f64::max)
        });
        Self {
            broad,
            link_moves,
            pair_moves,
            pair_tables,
            fixed_clear: None,
            moving_fk,
            ancestry_fk,
            rest_fk,
            hint_clear: false,
            fixed_poses_current: false,
            lane_q: std::array::from_fn(|_| model.neutral_configuration()),
            lane_poses: std::array::from_fn(|_| model.pose_buffer()),
            lanes_current: false,
            reach,
            stretches: std::collections::VecDeque::with_capacity(64),
            tool_q: model.neutral_configuration(),
            tool_poses: model.pose_buffer(),
            tool_jacobian: nalgebra::Matrix6xX::zeros(chain.dof()),
            retract: retract::RetractScratch::new(chain.dof()),
            free: std::array::from_fn(|_| Vec::with_capacity(64)),
            next_to: [[0.0; 32]; 4],
            twins,
            q_full: model.neutral_configuration(),
            poses: model.pose_buffer(),
            model,
            chain,
            matrix,
            obstacles,
            geometric,
            pairs,
            attached: Vec::new(),
            base: Isometry3::identity(),
            checks: 0,
        }
    }

    /// The chain being planned: its configurations are what [`StateValidator::is_valid`] takes.
    ///
    /// ```
    /// use hearth_planning::obstacles::ParryScene;
    /// use hearth_planning::validity::RobotValidity;
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
    /// assert_eq!(v.chain().dof(), 7);
    /// ```
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Distance weights per chain joint for [`JointSpace::with_weights`](crate::space::JointSpace::with_weights),
    /// from how far a joint's motion can carry the robot's own checked geometry (held objects
    /// do not change them): a revolute joint's bound on the distance of any point below it
    /// from the joint (metres moved per radian), a prismatic joint's 1 (metre per metre), each
    /// divided by the largest of them.
    ///
    /// With these weights, the bound on how far a step of a given length can move any point
    /// of the robot (`Σⱼ Rⱼ·|Δⱼ| ≤ max R · √n · length`, as for [`RobotValidity`]'s free
    /// regions) is the same as without them, but for it a wrist turns further than a
    /// shoulder. A tree then steps about equally far in the workspace whichever joints it
    /// moves, and a planner's edges are checked about equally densely in the workspace. A
    /// joint that moves nothing checked weighs the least allowed, 0.001, so that every joint
    /// still counts in the distance (a goal differs from a state short of it); a chain that
    /// moves nothing checked gets weights of 1.
    ///
    /// ```
    /// use hearth_planning::obstacles::ParryScene;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::validity::RobotValidity;
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let v = RobotValidity::new(arm.clone(), acm, Arc::new(ParryScene::new(vec![])));
    /// let w = v.joint_weights();
    /// assert_eq!(w.iter().cloned().fold(0.0, f64::max), 1.0);
    /// assert!(w[6] < 0.5 * w[0]); // the last wrist joint carries only the hand
    /// let space = JointSpace::from_chain(&arm)?.with_weights(&w)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn joint_weights(&self) -> Vec<f64> {
        let w = &self.reach.weights;
        let top = w.iter().cloned().filter(|x| x.is_finite()).fold(0.0f64, f64::max);
        w.iter()
            .map(|&x| match (top > 0.0, x.is_finite()) {
                (true, true) => (x / top).max(MIN_JOINT_WEIGHT),
                _ => 1.0,
            })
            .collect()
    }

    /// Sets the full configuration that joints outside the chain keep (fingers, head, …).
    ///
    /// ```
    /// use hearth_planning::obstacles::ParryScene;
    /// use hearth_planning::validity::RobotValidity;
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
    /// let mut q_full = panda.neutral_configuration(); // seven arm joints, then the fingers
    /// q_full[7] = 0.04; // fingers open 4 cm each side
    /// v.set_reference(&q_full)?;
    /// assert!(v.set_reference(&[0.0; 3]).is_err());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// The model's error for a configuration of the wrong length or outside the joint limits;
    /// the reference is then unchanged.
    pub fn set_reference(&mut self, q_full: &[f64]) -> Result<(), hearth_kinematics::KinematicsError> {
        self.model.check_configuration(q_full)?;
        self.q_full.copy_from_slice(q_full);
        self.fixed_clear = None;
        self.fixed_poses_current = false;
        self.lanes_current = false;
        Ok(())
    }

    /// Replaces the obstacles (e.g. a fresh view of a world that has moved on). The obstacles a
    /// validator holds must not change their answers while it holds them: links that do not
    /// move with the chain are checked once per reference, base and obstacle set.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{RobotValidity, StateValidator};
    /// use parry3d::math::{Pose, Vector};
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
    /// let reaching = [0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.785];
    /// assert!(v.is_valid(&reaching));
    /// let wall = Obstacle::cuboid("wall", Pose::translation(0.45, 0.0, 0.5), Vector::new(0.02, 1.0, 1.0));
    /// v.set_obstacles(Arc::new(ParryScene::new(vec![wall])));
    /// assert!(!v.is_valid(&reaching));
    /// ```
    pub fn set_obstacles(&mut self, obstacles: Arc<dyn Obstacles>) {
        self.obstacles = obstacles;
        self.fixed_clear = None;
    }

    /// Places the robot root in the world (e.g. a mobile base pose).
    ///
    /// ```
    /// use hearth_planning::kinematics::nalgebra::Isometry3;
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{RobotValidity, StateValidator};
    /// use parry3d::math::{Pose, Vector};
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// // A pillar standing where the robot's root is.
    /// let pillar = Obstacle::cuboid("pillar", Pose::translation(0.0, 0.0, 0.5), Vector::new(0.1, 0.1, 0.5));
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![pillar])));
    /// let folded = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    /// assert!(!v.is_valid(&folded));
    /// v.set_base(Isometry3::translation(2.0, 0.0, 0.0));
    /// assert!(v.is_valid(&folded));
    /// ```
    pub fn set_base(&mut self, base: Isometry3<f64>) {
        self.base = base;
        self.fixed_clear = None;
        self.fixed_poses_current = false;
        self.lanes_current = false;
    }

    /// Attaches an object (a held object moves with the gripper). It is checked against the
    /// obstacles and against every link except `link` and links adjacent to it.
    ///
    /// # Errors
    /// [`PlanError::BadInput`], with nothing attached, for a link the model does not have,
    /// an offset that is not finite, or a shape that [`Obstacle::check`](crate::obstacles::Obstacle::check)
    /// refuses (a negative or non-finite size, a non-finite point).
    ///
    /// ```
    /// use hearth_planning::kinematics::nalgebra::Isometry3;
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{Attached, RobotValidity, StateValidator};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::SharedShape;
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let table = Obstacle::cuboid("table", Pose::translation(0.3, 0.0, 0.15), Vector::new(0.2, 0.2, 0.05));
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![table])));
    /// let over_table = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    /// assert!(v.is_valid(&over_table));
    /// // A 50 cm rod held in the hand reaches down into the table.
    /// let hand = panda.link_index("panda_hand")?;
    /// let shape = SharedShape::cuboid(0.01, 0.01, 0.25);
    /// v.attach(Attached { name: "rod".into(), link: hand, offset: Isometry3::translation(0.0, 0.0, 0.25), shape })?;
    /// assert!(!v.is_valid(&over_table));
    /// // A link the model does not have, or a rod of negative length, is refused.
    /// let rod = |link, half: f32| Attached { name: "rod".into(), link, offset: Isometry3::identity(), shape: SharedShape::cuboid(0.01, 0.01, half) };
    /// assert!(v.attach(rod(99, 0.25)).is_err());
    /// assert!(v.attach(rod(hand, -0.25)).is_err());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn attach(&mut self, object: Attached) -> Result<(), PlanError> {
        let link = object.link;
        let links = self.model.links().len();
        if link >= links {
            return Err(PlanError::BadInput(format!(
                "attached object {:?}: link {link} does not exist (the model has {links} links)",
                object.name
            )));
        }
        // The shape as an obstacle at its offset: the same checks of pose, sizes and points.
        let probe = crate::obstacles::Obstacle::new(String::new(), object.shape.clone(), to_pose(&object.offset));
        if let Err(defect) = probe.check() {
            let what = match defect {
                crate::obstacles::ObstacleDefect::Pose => "its offset is not finite".to_owned(),
                defect => defect.to_string(),
            };
            return Err(PlanError::BadInput(format!(
                "attached object {:?}: {what}",
                object.name
            )));
        }
        self.attached.push(object);
        if !self.moving_fk.contains(link) {
            // A frame without geometry may now hold an object: follow it, from a full pass.
            let moves = self.twins.moving_links();
            self.moving_fk = checked_moving_fk(&self.model, &moves, &self.attached);
            self.rest_fk = rest_subsets(&self.model, &self.geometric, &self.moving_fk, &moves);
            self.fixed_poses_current = false;
        }
        Ok(())
    }

    /// Removes every attached object.
    ///
    /// ```
    /// use hearth_planning::kinematics::nalgebra::Isometry3;
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{Attached, RobotValidity, StateValidator};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::SharedShape;
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let table = Obstacle::cuboid("table", Pose::translation(0.3, 0.0, 0.15), Vector::new(0.2, 0.2, 0.05));
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![table])));
    /// let hand = panda.link_index("panda_hand")?;
    /// let shape = SharedShape::cuboid(0.01, 0.01, 0.25); // a 50 cm rod
    /// v.attach(Attached { name: "rod".into(), link: hand, offset: Isometry3::translation(0.0, 0.0, 0.25), shape })?;
    /// let over_table = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
    /// assert!(!v.is_valid(&over_table));
    /// v.detach_all();
    /// assert!(v.is_valid(&over_table));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn detach_all(&mut self) {
        self.attached.clear();
    }

    fn update_poses(&mut self, q: &[f64]) -> bool {
        if q.len() != self.chain.dof() {
            return false;
        }
        self.chain.scatter(q, &mut self.q_full);
        if self.fixed_poses_current {
            return self
                .model
                .fk_update(&self.moving_fk, &self.q_full, &mut self.poses)
                .is_ok();
        }
        self.fixed_poses_current = self.model.fk_from(&self.base, &self.q_full, &mut self.poses).is_ok();
        self.lanes_current = false;
        if self.fixed_poses_current {
            self.twins
                .update(&self.model, &self.geometric, &self.pairs, &self.poses);
        }
        // The joints the chain does not move (the Fetch's head, fingers and bellows) are held
        // at this pass's values in the per-check kinematics: composed once, not per check.
        let vars = self.chain.variables();
        for subset in std::iter::once(&mut self.moving_fk)
            .chain(&mut self.ancestry_fk)
            .chain(&mut self.rest_fk)
        {
            if self
                .model
                .fk_subset_hold(subset, &self.q_full, |v| vars.contains(&v))
                .is_err()
            {
                self.fixed_poses_current = false;
            }
        }
        // The only pass that moves the links that do not move with the chain: their centres
        // here, the others' in every check (`update_centers`).
        let b = &mut self.broad;
        for &l in &self.geometric {
            b.world_center[l] = self.poses[l] * b.local_center[l];
        }
        self.fixed_poses_current
    }

    /// With a link hint (a link that settled an earlier check) and the poses of the links
    /// the chain does not move current: the poses of that link and its moving ancestors
    /// first, then that link's test (its hinted part first, as in
    /// [`RobotValidity::robot_blocked`]). `Some(true)` when it touches an obstacle: the other
    /// links' poses are then stale, and the next check recomputes them. Otherwise the rest of
    /// the moving links' poses, `hint_clear` set, and `Some(false)`: the poses are complete,
    /// as [`RobotValidity::update_poses`] leaves them. `None` when the hint does not apply.
    /// The two passes together compute each moving link's pose once, so a state that passes
    /// pays nothing for it, and one that the hinted link settles (most colliding states on
    /// the Fetch's bookshelves) skips the links below and beside it.
    fn hint_link_hits(&mut self, q: &[f64]) -> Option<bool> {
        let Hint::Link(i) = self.broad.hint else {
            return None;
        };
        if !self.fixed_poses_current || q.len() != self.chain.dof() || !self.link_moves[i] {
            return None;
        }
        self.chain.scatter(q, &mut self.q_full);
        if self
            .model
            .fk_update(&self.ancestry_fk[i], &self.q_full, &mut self.poses)
            .is_err()
        {
            return None;
        }
        let l = self.geometric[i];
        let b = &mut self.broad;
        b.epoch = b.epoch.wrapping_add(1);
        b.world_center[l] = self.poses[l] * b.local_center[l];
        if let Some((_, _, k)) = self.hinted_part()
            && self.part_hits(l, k).is_some()
        {
            self.broad.hint_streak += 1;
            return Some(true);
        }
        if self.link_blocked(i) {
            return Some(true);
        }
        if self
            .model
            .fk_update(&self.rest_fk[i], &self.q_full, &mut self.poses)
            .is_err()
        {
            return None;
        }
        self.hint_clear = true;
        Some(false)
    }

    /// With a link hint and right after a check that one of its parts settled: (geometric
    /// link number, link, part).
    fn hinted_part(&self) -> Option<(usize, usize, usize)> {
        let Hint::Link(i) = self.broad.hint else {
            return None;
        };
        let (l, k) = (self.geometric[i], self.broad.hint_part);
        (self.broad.hint_streak > 0 && self.broad.part_range[l].contains(&k)).then_some((i, l, k))
    }

    /// Checks up to four states (`dim` values each) with one four-lane forward kinematics
    /// pass, then each state's obstacles and self-collision in order. `None` when the lanes
    /// cannot be used for them (the caller checks them one by one).
    fn first_invalid4(&mut self, states: &[f64], dim: usize) -> Option<Option<usize>> {
        self.first_invalid4_free(states, dim, None)
    }

    /// [`RobotValidity::first_invalid4`], also finding the free region of each valid state
    /// `k` ([`RobotValidity::free_region`] with cap `free.0[k]`; whether it has one in
    /// `free.1[k]`).
    fn first_invalid4_free(
        &mut self,
        states: &[f64],
        dim: usize,
        mut free: Option<([f64; 4], &mut [bool; 4])>,
    ) -> Option<Option<usize>> {
        let n = states.len() / dim;
        // (A non-finite value makes `fk_update4` fail, which also sends the states one by one.)
        if !(2..=4).contains(&n) || dim != self.chain.dof() || !self.fixed_poses_current {
            return None;
        }
        if !self.lanes_current {
            for (buf, q) in self.lane_poses.iter_mut().zip(&mut self.lane_q) {
                buf.copy_from_slice(&self.poses);
                q.copy_from_slice(&self.q_full);
            }
            self.lanes_current = true;
        }
        for k in 0..4 {
            let q = &states[k.min(n - 1) * dim..][..dim];
            self.chain.scatter(q, &mut self.lane_q[k]);
        }
        let [a, b, c, d] = &self.lane_q;
        if self
            .model
            .fk_update4(&self.moving_fk, [a, b, c, d], &mut self.lane_poses)
            .is_err()
        {
            return None;
        }
        for k in 0..n {
            self.checks += 1;
            std::mem::swap(&mut self.poses, &mut self.lane_poses[k]);
            std::mem::swap(&mut self.q_full, &mut self.lane_q[k]);
            let ok = !self.robot_blocked() && !self.attached_blocked();
            if ok && let Some((caps, certified)) = free.as_mut() {
                certified[k] = self.free_region(k, caps[k]);
            }
            std::mem::swap(&mut self.poses, &mut self.lane_poses[k]);
            std::mem::swap(&mut self.q_full, &mut self.lane_q[k]);
            if !ok {
                return Some(Some(k));
            }
        }
        Some(None)
    }

    /// The region around the state just found valid (its poses current) within which every
    /// state passes the check, as constraints on the straight motion to a state: each moving
    /// link must move less than its covering balls' clearance to the obstacles, and each
    /// checked pair's distance must change by less than the pair's clearance (from its
    /// bounding balls when those are apart, else from its clearance table, else from its
    /// covering balls). Within the region each covering ball stays clear, so the exact tests
    /// are never reached, and each pair stays apart. Constraints that a motion of at most
    /// `cap` in [`Reach::distance`] cannot reach are left out. Fills `self.free[lane]` and
    /// returns `false` when nothing can be certified (an attached object, obstacles that
    /// cannot measure clearance, a link without covering balls, a clearance of 0).
    fn free_region(&mut self, lane: usize, cap: f64) -> bool {
        let mut free = std::mem::take(&mut self.free[lane]);
        free.clear();
        let ok = self.fill_free_region(lane, cap, &mut free);
        self.free[lane] = free;
        ok
    }

    fn fill_free_region(&mut self, lane: usize, cap: f64, free: &mut Vec<(Row, f64)>) -> bool {
        if !self.attached.is_empty() || cap.is_nan() || cap <= 0.0 || self.broad.moving.len() > BallBatch::CAPACITY {
            return false;
        }
        let (reach, next) = (&self.reach, &self.next_to[lane][..self.chain.dof()]);
        // Keeps the constraint that row `row` moves less than `c`, unless no motion within
        // `cap` can break it; `false` when it cannot even hold the state's neighbours.
        let admit = |row: Row, c: f64, free: &mut Vec<(Row, f64)>| {
            if c >= reach.scale(row) * cap {
                return true;
            }
            free.push((row, c));
            c > reach.motion(row, next)
        };
        let b = &mut self.broad;
        let mut clearance = [0.0; BallBatch::CAPACITY];
        // The moving links' bounding balls in one batch: a link whose ball stays clear is clear.
        b.batch.clear();
        let mut farthest = 0.0f64;
        for &i in &b.moving {
            let l = self.geometric[i];
            let scale = self.reach.scale(Row::Link(i));
            if !scale.is_finite() || !b.radius[l].is_finite() {
                return false;
            }
            farthest = farthest.max(scale * cap);
            b.batch.push(to_vector(&b.world_center[l]), b.balls[i].radius);
        }
        let look = (farthest + FREE_RADIUS_SLACK) as f32;
        if !self.obstacles.balls_clearance(&b.batch, look, &mut clearance) {
            return false;
        }
        // The links whose bounding ball could reach an obstacle: their covering balls, as
        // many links to a batch as fit.
        let mut near = [(0usize, 0.0f64); BallBatch::CAPACITY];
        let mut n_near = 0;
        for (k, &i) in b.moving.iter().enumerate() {
            let scale = self.reach.scale(Row::Link(i));
            let c = f64::from(clearance[k]) - FREE_RADIUS_SLACK;
            if scale > 0.0 && c < scale * cap {
                near[n_near] = (i, c);
                n_near += 1;
            }
        }
        let mut start = 0;
        while start < n_near {
            b.batch.clear();
            let mut end = start;
            while end < n_near {
                let l = self.geometric[near[end].0];
                let range = b.cover_range[l].clone();
                if range.is_empty() || range.len() > BallBatch::CAPACITY {
                    return false;
                }
                if b.batch.len() + range.len() > BallBatch::CAPACITY {
                    break;
                }
                b.push_cover(l, &self.poses[l]);
                end += 1;
            }
            if !self.obstacles.balls_clearance(&b.batch, look, &mut clearance) {
                return false;
            }
            let mut ball = 0;
            for &(i, bounding) in &near[start..end] {
                let count = b.cover_range[self.geometric[i]].len();
                let cover = clearance[ball..ball + count].iter().fold(Real::MAX, |a, &c| a.min(c));
                ball += count;
                let c = bounding.max(f64::from(cover) - FREE_RADIUS_SLACK);
                if c <= 0.0 {
                    return false;
                }
                if !admit(Row::Link(i), c, free) {
                    return false;
                }
            }
            start = end;
        }
        for (p, &(a, l)) in self.pairs.iter().enumerate() {
            let scale = self.reach.scale(Row::Pair(p));
            if !self.pair_moves[p] || scale == 0.0 {
                continue;
            }
            if !scale.is_finite() {
                return false;
            }
            let apart = (b.world_center[a] - b.world_center[l]).norm() - b.radius[a] - b.radius[l] - FREE_RADIUS_SLACK;
            if apart > 0.0 {
                if !admit(Row::Pair(p), apart, free) {
                    return false;
                }
                continue;
            }
            // A pair near each other: its table's certificate, where it has one.
            let tabled = self.pair_tables[p]
                .as_ref()
                .and_then(|t| t.clearance_bound(&self.q_full))
                .map(|c| c - FREE_RADIUS_SLACK);
            if let Some(c) = tabled
                && c > 0.0
            {
                if !admit(Row::Table(p), c, free) {
                    return false;
                }
                continue;
            }
            // Else their covering balls.
            let (ra, rl) = (b.cover_range[a].clone(), b.cover_range[l].clone());
            if ra.len() > BallBatch::CAPACITY || rl.len() > BallBatch::CAPACITY {
                return false;
            }
            let (pa, pl) = (&self.poses[a], &self.poses[l]);
            let mut far = [(Point3::origin(), 0.0); BallBatch::CAPACITY];
            for (f, k) in far.iter_mut().zip(rl) {
                *f = (pl * b.cover[k].0, b.cover[k].1);
            }
            let far = &far[..b.cover_range[l].len()];
            let mut least = f64::INFINITY;
            for i in ra {
                let (ci, ri) = (pa * b.cover[i].0, b.cover[i].1);
                for (ck, rk) in far {
                    least = least.min((ck - ci).norm() - ri - rk);
                }
            }
            let c = least - FREE_RADIUS_SLACK;
            if c.is_nan() || c <= 0.0 || !admit(Row::Pair(p), c, free) {
                return false;
            }
        }
        true
    }

    /// [`StateValidator::first_invalid_along`] with free regions: each stretch of unchecked
    /// states has its middle state checked (four stretches share one forward kinematics
    /// pass); the states next to it inside its free region are then valid without a check,
    /// and only what lies beyond is split again.
    fn first_invalid_along_free(&mut self, states: &[f64], dim: usize) -> Option<usize> {
        let n = states.len() / dim;
        let state = |i: usize| &states[i * dim..(i + 1) * dim];
        let mut stretches = std::mem::take(&mut self.stretches);
        stretches.clear();
        stretches.push_back((0usize, n - 1));
        let mut buf = [0.0; 4 * 32];
        let mut found = None;
        while !stretches.is_empty() {
            let mut group = [(0usize, 0usize, 0usize); 4];
            let mut len = 0;
            while len < 4 {
                let Some((lo, hi)) = stretches.pop_front() else { break };
                group[len] = (lo, lo + (hi - lo) / 2, hi);
                len += 1;
            }
            let mut caps = [0.0; 4];
            for (k, &(lo, mid, hi)) in group[..len].iter().enumerate() {
                buf[k * dim..(k + 1) * dim].copy_from_slice(state(mid));
                let next = &mut self.next_to[k][..dim];
                next.fill(0.0);
                for side in [mid.saturating_sub(1).max(lo), (mid + 1).min(hi)] {
                    for (d, (a, b)) in next.iter_mut().zip(state(side).iter().zip(state(mid))) {
                        *d = d.max((a - b).abs());
                    }
                }
                if hi - lo + 1 >= FREE_RADIUS_MIN_STATES {
                    let reach = &self.reach;
                    caps[k] = reach
                        .distance(state(mid), state(lo))
                        .max(reach.distance(state(mid), state(hi)));
                }
            }
            let mut certified = [false; 4];
            let batch = &buf[..len * dim];
            let invalid = match self.first_invalid4_free(batch, dim, Some((caps, &mut certified))) {
                Some(r) => r,
                None => (0..len).find(|&k| {
                    if !self.is_valid(&batch[k * dim..(k + 1) * dim]) {
                        return true;
                    }
                    certified[k] = self.free_region(k, caps[k]);
                    false
                }),
            };
            if let Some(k) = invalid {
                found = Some(group[k].1);
                break;
            }
            let mut delta = [0.0; 32];
            for (k, &(lo, mid, hi)) in group[..len].iter().enumerate() {
                let (mut left, mut right) = (mid, mid);
                if certified[k] {
                    let free = &self.free[k];
                    let reach = &self.reach;
                    let mut within = |i: usize| {
                        for ((d, a), b) in delta.iter_mut().zip(state(i)).zip(state(mid)) {
                            *d = (a - b).abs();
                        }
                        free.iter().all(|&(row, c)| reach.motion(row, &delta[..dim]) < c)
                    };
                    while left > lo && within(left - 1) {
                        left -= 1;
                    }
                    while right < hi && within(right + 1) {
                        right += 1;
                    }
                }
                if left > lo {
                    stretches.push_back((lo, left - 1));
                }
                if right < hi {
                    stretches.push_back((right + 1, hi));
                }
            }
        }
        self.stretches = stretches;
        found
    }

    /// The first obstacle that link `l` touches (exact, part by part).
    fn link_hits(&self, l: usize) -> Option<ObstacleId> {
        self.parts_hit(l, u64::MAX).map(|(_, id)| id)
    }

    /// The first obstacle that a part of link `l` meeting one of the cover balls in `balls`
    /// (bits as in `BroadPhase::part_cover`) touches, and which part (index into
    /// `BroadPhase::parts`) touches it.
    fn parts_hit(&self, l: usize, balls: u64) -> Option<(usize, ObstacleId)> {
        self.broad.part_range[l].clone().find_map(|k| {
            if self.broad.part_cover[k] & balls == 0 {
                return None;
            }
            self.part_hits(l, k).map(|id| (k, id))
        })
    }

    /// The first obstacle that part `k` of link `l` touches. Every exact link test goes
    /// through here, so all of them compose part poses the same way and agree to the last bit.
    ///
    /// A contact from parry's exact test counts only if the part's bounding ball touches an
    /// obstacle too: parry's GJK intersection test (0.31) can report contact between a box and
    /// a cylinder that are millimetres apart (its distance query gives the gap), and a part
    /// whose bounding ball is clear is clear. Asking only on contacts keeps the ball query off
    /// the clear tests; it also makes the answer the same whether or not a batch of the parts'
    /// balls was asked first ([`RobotValidity::touched_parts_hit`]).
    #[inline]
    fn part_hits(&self, l: usize, k: usize) -> Option<ObstacleId> {
        let shape = &self.broad.part_shape[k].0;
        let (c, r) = self.broad.part_inner[k];
        if r > 0.0 {
            let w = self.poses[l] * c;
            let at_w = Pose::from_translation(to_vector(&w));
            if let Some(id) = self.obstacles.first_hit(&Ball::new(r as f32), &at_w) {
                return Some(id);
            }
        }
        let hit = self.obstacles.first_hit(shape.as_ref(), &self.part_pose(l, k))?;
        let (c, r) = self.broad.parts[k];
        let c = self.poses[l] * c;
        self.obstacles.ball_hits(to_vector(&c), r as f32).then_some(hit)
    }

    /// World centres of the bounding spheres of the links that move with the chain, for the
    /// current poses. The other links' centres (the Fetch's base, wheels, casters and fixed
    /// torso parts: 10 of its 25 links) change only with a full forward kinematics pass,
    /// which sets them ([`RobotValidity::update_poses`]). The first [`BallBatch::CAPACITY`]
    /// moving links' bounding balls go to `moving_batch` on the way.
    fn update_centers(&mut self) {
        let b = &mut self.broad;
        b.epoch = b.epoch.wrapping_add(1);
        b.moving_batch.clear();
        for (k, &i) in b.moving.iter().enumerate() {
            let l = self.geometric[i];
            let c = self.poses[l] * b.local_center[l];
            b.world_center[l] = c;
            if k < BallBatch::CAPACITY {
                b.moving_batch.push(to_vector(&c), b.balls[i].radius);
            }
        }
    }

    /// Broad phase + exact test of geometric link number `i` against the obstacles.
    #[inline]
    fn link_blocked(&mut self, i: usize) -> bool {
        let l = self.geometric[i];
        let c = &self.broad.world_center[l];
        if self.broad.radius[l].is_finite() {
            let center = to_vector(c);
            if !self.obstacles.ball_hits(center, self.broad.balls[i].radius) {
                return false;
            }
        }
        self.covered_link_blocked(i)
    }

    /// Geometric link number `i`, whose bounding ball touches something: the balls covering
    /// it (one batch), then the exact test of the parts that those of its balls that touch
    /// meet.
    fn covered_link_blocked(&mut self, i: usize) -> bool {
        let l = self.geometric[i];
        let b = &mut self.broad;
        let range = b.cover_range[l].clone();
        let balls = if range.is_empty() || range.len() > BallBatch::CAPACITY || !b.radius[l].is_finite() {
            u64::MAX
        } else {
            b.batch.clear();
            b.push_cover(l, &self.poses[l]);
            let touched = self.obstacles.balls_touching(&b.batch);
            if touched == 0 {
                return false;
            }
            touched
        };
        let Some(k) = self.touched_parts_hit(l, balls) else {
            return false;
        };
        self.broad.hint_part = k;
        self.broad.hint_streak = 1;
        true
    }

    /// [`RobotValidity::parts_hit`] with the parts' bounding balls asked in one batch: when
    /// several parts meet the touching cover balls, their bounding balls go to the obstacles
    /// together (a ball gets the same answer alone and in a batch), and only the parts whose
    /// ball touches go on to [`RobotValidity::part_hits`]. The same part answers, as the
    /// order is kept; in the Panda's cage the bounding ball settles about four in five of
    /// these part tests.
    fn touched_parts_hit(&mut self, l: usize, balls: u64) -> Option<usize> {
        let range = self.broad.part_range[l].clone();
        let mut candidates = 0u64;
        if range.len() <= BallBatch::CAPACITY {
            for (bit, k) in range.clone().enumerate() {
                if self.broad.part_cover[k] & balls != 0 {
                    candidates |= 1 << bit;
                }
            }
        }
        if candidates.count_ones() < PART_BATCH_MIN {
            return self.parts_hit(l, balls).map(|(k, _)| k);
        }
        self.part_centers(l);
        let b = &mut self.broad;
        b.batch.clear();
        let mut slots = [0u8; BallBatch::CAPACITY];
        let mut rest = candidates;
        while rest != 0 {
            let bit = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let k = range.start + bit;
            let c = b.parts_world[k];
            slots[b.batch.len()] = bit as u8;
            b.batch.push(to_vector(&c), b.parts[k].1 as f32);
        }
        let mut touched = self.obstacles.balls_touching(&self.broad.batch);
        while touched != 0 {
            let k = range.start + slots[touched.trailing_zeros() as usize] as usize;
            touched &= touched - 1;
            if self.part_hits(l, k).is_some() {
                return Some(k);
            }
        }
        None
    }

    /// World centres of link `l`'s part spheres, computed once per check.
    fn part_centers(&mut self, l: usize) {
        let b = &mut self.broad;
        if b.parts_epoch[l] != b.epoch {
            b.parts_epoch[l] = b.epoch;
            let pose = &self.poses[l];
            for k in b.part_range[l].clone() {
                b.parts_world[k] = pose * b.parts[k].0;
            }
        }
    }

    /// Broad phase + exact test of checked self-collision pair number `i`.
    #[inline]
    fn pair_blocked(&mut self, i: usize) -> bool {
        let (a, b) = self.pairs[i];
        let d2 = (self.broad.world_center[a] - self.broad.world_center[b]).norm_squared();
        if d2 > self.broad.pair_reach2[i] {
            return false;
        }
        self.pair_blocked_within_reach(i)
    }

    /// [`RobotValidity::pair_blocked`] past its bounding-ball test (which the caller did).
    #[inline(never)]
    fn pair_blocked_within_reach(&mut self, i: usize) -> bool {
        let (a, b) = self.pairs[i];
        if let Some(table) = &self.pair_tables[i]
            && table.certainly_clear(&self.model, &self.q_full)
        {
            return false;
        }
        if self.cover_clears_box(a, b) || self.field_clears(i) {
            return false;
        }
        // Second level: every part sphere of `a` against every part sphere of `b`.
        self.part_centers(a);
        self.part_centers(b);
        let bp = &mut self.broad;
        // Parts of one link near the other link's whole sphere, then those part pairs.
        let near = |bp: &BroadPhase, l: usize, other: usize, out: &mut Vec<usize>| {
            out.clear();
            let (co, ro) = (bp.world_center[other], bp.radius[other]);
            for k in bp.part_range[l].clone() {
                let r = bp.parts[k].1 + ro;
                if (bp.parts_world[k] - co).norm_squared() <= r * r {
                    out.push(k);
                }
            }
        };
        let mut near_a = std::mem::take(&mut bp.near_a);
        let mut near_b = std::mem::take(&mut bp.near_b);
        near(bp, a, b, &mut near_a);
        let mut close = false;
        if !near_a.is_empty() {
            near(bp, b, a, &mut near_b);
            // All near part pairs, vectorised over `b`'s parts in f32 (relative coordinates,
            // errors ~1e-7 m against a slack of 1e-4 m per radius).
            let origin = bp.world_center[a];
            let [xs, ys, zs, rs] = &mut bp.near_soa;
            for v in [&mut *xs, &mut *ys, &mut *zs, &mut *rs] {
                v.clear();
            }
            for &kb in &near_b {
                let d = bp.parts_world[kb] - origin;
                xs.push(d.x as f32);
                ys.push(d.y as f32);
                zs.push(d.z as f32);
                rs.push(bp.parts[kb].1 as f32);
            }
            close = near_a.iter().any(|&ka| {
                let d = bp.parts_world[ka] - origin;
                let (ax, ay, az, ra) = (d.x as f32, d.y as f32, d.z as f32, bp.parts[ka].1 as f32);
                let mut hit = false;
                for j in 0..xs.len() {
                    let (dx, dy, dz, r) = (xs[j] - ax, ys[j] - ay, zs[j] - az, rs[j] + ra);
                    hit |= dx * dx + dy * dy + dz * dz <= r * r;
                }
                hit
            });
        }
        bp.near_a = near_a;
        bp.near_b = near_b;
        close && self.pair_touches(a, b)
    }

    /// Part `k` of link `l` at the current poses, as parry takes it. Every exact part test
    /// composes the part's pose this way.
    #[inline]
    fn part_pose(&self, l: usize, k: usize) -> Pose {
        to_pose(&(self.poses[l] * self.broad.part_shape[k].1))
    }

    /// Whether part `ka` of link `a` touches part `kb` of link `b` at the current poses
    /// ([`shapes_touch`]).
    #[inline]
    fn parts_touch(&self, a: usize, ka: usize, b: usize, kb: usize) -> bool {
        let (sa, sb) = (&self.broad.part_shape[ka].0, &self.broad.part_shape[kb].0);
        shapes_touch(sa.as_ref(), &self.part_pose(a, ka), sb.as_ref(), &self.part_pose(b, kb))
    }

    /// Whether links `a` and `b` touch at the current poses: the exact test of every
    /// self-collision check, [`RobotValidity::is_valid_exact`] and [`RobotValidity::explain`].
    ///
    /// Parry's test of one link's compound shape against the other's ([`links_touch`]) comes
    /// first: its box trees prune the part pairs well, and where it finds the links apart they
    /// are (the exact search never found contact where parry's test did not). Its "touching"
    /// is confirmed part pair by part pair ([`RobotValidity::parts_touch`], on the pairs whose
    /// bounding balls meet): parry 0.31's GJK answers "intersecting" when it stalls, and so
    /// refused every goal of the Fetch's table_pick 87 for a head box and an upper-arm
    /// cylinder that the exact search separates by a plane (a fine sampling puts them within
    /// 0.25 mm). Testing every pair part by part alone took 2–11 % more instructions per
    /// check (thirty-fourth round); the confirmation runs only on contact.
    fn pair_touches(&self, a: usize, b: usize) -> bool {
        if !links_touch(&self.model, &self.poses, a, b) {
            return false;
        }
        let bp = &self.broad;
        let world = |l: usize, k: usize| self.poses[l] * bp.parts[k].0;
        bp.part_range[a].clone().any(|ka| {
            let ca = world(a, ka);
            bp.part_range[b].clone().any(|kb| {
                let r = bp.parts[ka].1 + bp.parts[kb].1;
                (world(b, kb) - ca).norm_squared() <= r * r && self.parts_touch(a, ka, b, kb)
            })
        })
    }

    /// Whether one link of the pair `(a, b)` is a single box that no ball of the other link's
    /// cover touches, which proves the pair apart: the cover contains its link. The Fetch's
    /// fixed torso and its bellows are single boxes whose bounding balls (radius 0.29 m and
    /// 0.23 m) hold the folded arm's links in most configurations, so the part spheres met
    /// and parry's exact test ran there, and almost never found contact (37 times in 1.3
    /// million such tests over the Fetch's table_pick plans). Tried on every single-part link and, where part
    /// spheres meet, on the other link's nearby parts: more instructions than parry's test.
    fn cover_clears_box(&self, a: usize, b: usize) -> bool {
        let bp = &self.broad;
        let (covered, boxed, (at, half)) = if let Some(bx) = &bp.boxes[b]
            && !bp.cover_range[a].is_empty()
        {
            (a, b, bx)
        } else if let Some(bx) = &bp.boxes[a]
            && !bp.cover_range[b].is_empty()
        {
            (b, a, bx)
        } else {
            return false;
        };
        // The covered link's frame in the box's frame.
        let to_box = (self.poses[boxed] * at).inv_mul(&self.poses[covered]);
        bp.cover[bp.cover_range[covered].clone()].iter().all(|(c, r)| {
            let p = to_box * c;
            let outside = nalgebra::Vector3::new(
                (p.x.abs() - half.x).max(0.0),
                (p.y.abs() - half.y).max(0.0),
                (p.z.abs() - half.z).max(0.0),
            );
            outside.norm_squared() > r * r
        })
    }

    /// Whether pair number `i` is proved apart by one link's distance field: every ball of
    /// the other link's cover is clear of it. Compound links such as the Fetch's base and
    /// torso lift (15 and 25 boxes) otherwise sent their pairs to part-sphere tests and
    /// parry's exact test about once per check, though almost none touched. Where both links
    /// have a field, the second way round (the bigger link's cover against the smaller
    /// link's field) clears a third of the Fetch table_pick pairs the first way leaves.
    fn field_clears(&self, i: usize) -> bool {
        let [first, second] = self.broad.pair_field[i];
        first.is_some_and(|(f, c)| self.field_clears_cover(f, c))
            || second.is_some_and(|(f, c)| self.field_clears_cover(f, c))
    }

    /// Whether every ball of link `c`'s cover is clear of link `f`'s distance field (after
    /// the check's `update_centers`).
    fn field_clears_cover(&self, f: usize, c: usize) -> bool {
        let Some(field) = self.model.link_field(f) else {
            return false;
        };
        let bp = &self.broad;
        // The link's bounding ball first, from its world centre (already known): one lookup
        // settles the pairs that are far apart but within the field link's (large) bounding
        // ball, without composing the two poses.
        if field.clears_ball(
            &self.poses[f].inverse_transform_point(&bp.world_center[c]),
            bp.radius[c],
        ) {
            return true;
        }
        let to_field = self.poses[f].inv_mul(&self.poses[c]);
        let (rot, at) = (to_field.rotation.to_rotation_matrix(), to_field.translation.vector);
        bp.cover[bp.cover_range[c].clone()]
            .iter()
            .all(|(p, r)| field.clears_ball(&Point3::from(rot * p.coords + at), *r))
    }

    /// Links and pairs that do not move with the chain, checked once per reference, base and
    /// obstacle set (the poses of the current configuration are used; theirs do not change).
    fn fixed_blocked(&mut self) -> bool {
        if let Some(clear) = self.fixed_clear {
            return !clear;
        }
        let links = (0..self.geometric.len())
            .filter(|&i| !self.link_moves[i])
            .collect::<Vec<_>>();
        let pairs = (0..self.pairs.len())
            .filter(|&i| !self.pair_moves[i])
            .collect::<Vec<_>>();
        let blocked =
            links.into_iter().any(|i| self.link_blocked(i)) || pairs.into_iter().any(|i| self.pair_blocked(i));
        self.fixed_clear = Some(!blocked);
        blocked
    }

    /// The robot's own links (obstacles and self-collision), hint first.
    fn robot_blocked(&mut self) -> bool {
        self.update_centers();
        if self.fixed_blocked() {
            return true;
        }
        // After a check that one part settled: that part alone first (unless
        // `hint_link_hits` found its link clear on these poses).
        let hint_clear = std::mem::take(&mut self.hint_clear);
        if !hint_clear
            && let Some((_, l, k)) = self.hinted_part()
            && self.part_hits(l, k).is_some()
        {
            self.broad.hint_streak += 1;
            return true;
        }
        let first = match self.broad.hint {
            Hint::Link(_) if hint_clear => false,
            Hint::Link(i) => self.link_blocked(i),
            Hint::Pair(i) => self.pair_blocked(i),
            Hint::None => false,
        };
        if first {
            return true;
        }
        let skip = self.broad.hint;
        // Every moving link's bounding ball in one batch, then the links whose ball touches,
        // the last moving link first: the links far down the chain (a gripper among shelf
        // boards or cage bars) collide most often, so a colliding state is settled sooner
        // (1–4 % on the MotionBenchMaker cage and wedged Fetch plans; the answers are the same
        // in any order).
        let mut near = self.obstacles.balls_touching(&self.broad.moving_batch);
        while near != 0 {
            let bit = 63 - near.leading_zeros() as usize;
            let i = self.broad.moving[bit];
            near &= !(1u64 << bit);
            if skip != Hint::Link(i) && !self.twins.link(i) && self.covered_link_blocked(i) {
                self.broad.hint = Hint::Link(i);
                return true;
            }
        }
        for k in BallBatch::CAPACITY..self.broad.moving.len() {
            let i = self.broad.moving[k];
            if skip != Hint::Link(i) && !self.twins.link(i) && self.link_blocked(i) {
                self.broad.hint = Hint::Link(i);
                return true;
            }
        }
        // The moving pairs' bounding balls first, eight pairs per step (most are apart), the
        // rest of the pair test only for those within reach. (Pair by pair, the ball test
        // alone cost about twenty instructions per pair.)
        let b = &mut self.broad;
        b.pair_lanes.refresh(&b.world_center);
        for t in 0..self.broad.pair_lanes.steps() {
            let mut lanes = self.broad.pair_lanes.step(t);
            while lanes != 0 {
                let k = self.broad.pair_lanes.entry(t, lanes.trailing_zeros() as usize);
                lanes &= lanes - 1;
                // The lanes' f32 test is widened: the exact one decides.
                let (a, b, reach2) = self.broad.moving_pairs[k];
                let d2 = (self.broad.world_center[a as usize] - self.broad.world_center[b as usize]).norm_squared();
                if d2 <= reach2 {
                    let i = self.broad.moving_pair_index[k] as usize;
                    if skip != Hint::Pair(i) && !self.twins.pair(i) && self.pair_blocked_within_reach(i) {
                        self.broad.hint = Hint::Pair(i);
                        return true;
                    }
                }
            }
        }
        self.broad.hint_streak = 0;
        false
    }

    /// Certifies the self-collision pair-table cells ([`hearth_kinematics::PairTable`]) that
    /// `samples` random configurations of the chain visit, on every core, and returns how long
    /// that took. The tables belong to the robot model and are shared by every validator of it
    /// in the process, so later checks find those cells certified instead of paying one
    /// closest-points query (~50 µs) for each on first use. Answers never change: a cell holds
    /// the same certificate whenever it is filled. Worth it before timing many plans (the
    /// planning benchmark does it), or at the start of a long-running loop. Obstacles play no
    /// part (the check runs against an empty scene); the reference configuration is this
    /// validator's.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// use hearth_planning::obstacles::ParryScene;
    /// use hearth_planning::validity::RobotValidity;
    ///
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = Chain::named(&panda, "arm").unwrap();
    /// let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    /// let v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![])));
    /// let took = v.warm_pair_tables(100, 7);
    /// assert!(took.as_secs_f64() < 60.0);
    /// ```
    pub fn warm_pair_tables(&self, samples: usize, seed: u64) -> std::time::Duration {
        use rand::SeedableRng;
        let started = std::time::Instant::now();
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, 16);
        let empty: Arc<dyn Obstacles> = Arc::new(crate::obstacles::ParryScene::new(Vec::new()));
        std::thread::scope(|scope| {
            for t in 0..threads {
                let n = samples / threads + usize::from(t < samples % threads);
                let mut v = RobotValidity::new(self.chain.clone(), self.matrix.clone(), empty.clone());
                v.q_full.copy_from_slice(&self.q_full);
                scope.spawn(move || {
                    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed ^ ((t as u64 + 1) << 32));
                    let mut q = vec![0.0; v.chain.dof()];
                    for _ in 0..n {
                        v.chain.random_configuration(&mut rng, &mut q);
                        v.is_valid(&q);
                    }
                });
            }
        });
        started.elapsed()
    }

    /// The reference check without any broad phase (every link against the obstacles, every
    /// checked pair with the exact test). Same answer as [`StateValidator::is_valid`], slower;
    /// for tests and benchmarks. Does not count as a check.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{RobotValidity, StateValidator};
    /// use parry3d::math::{Pose, Vector};
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let wall = Obstacle::cuboid("wall", Pose::translation(0.45, 0.0, 0.5), Vector::new(0.02, 1.0, 1.0));
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![wall])));
    /// for q in [[0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785], [0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.785]] {
    ///     assert_eq!(v.is_valid_exact(&q), v.is_valid(&q));
    /// }
    /// assert_eq!(v.checks(), 2);
    /// ```
    pub fn is_valid_exact(&mut self, q: &[f64]) -> bool {
        if !q.iter().all(|v| v.is_finite()) || !self.update_poses(q) {
            return false;
        }
        if self.geometric.iter().any(|&l| self.link_hits(l).is_some()) {
            return false;
        }
        if self.pairs.iter().any(|&(a, b)| self.pair_touches(a, b)) {
            return false;
        }
        !self.attached_blocked()
    }

    fn attached_blocked(&self) -> bool {
        for a in &self.attached {
            let pose = to_pose(&(self.poses[a.link] * a.offset));
            if self.obstacles.intersects(a.shape.as_ref(), &pose) {
                return true;
            }
            if self.geometric.iter().any(|&l| self.attached_touches_link(a, l)) {
                return true;
            }
        }
        false
    }

    fn attached_touches_link(&self, a: &Attached, l: usize) -> bool {
        if l == a.link || self.matrix.is_disabled(l, a.link) {
            return false;
        }
        let Some(s) = self.model.link_shape(l) else {
            return false;
        };
        let pa = to_pose(&(self.poses[a.link] * a.offset));
        let pl = to_pose(&(self.poses[l] * s.origin));
        parry3d::query::intersection_test(&pa, a.shape.as_ref(), &pl, s.shape.as_ref())
            .map(|r| r.intersecting)
            .unwrap_or(true)
    }

    /// Why `q` is invalid (the first contact found), or `None` if it is valid. Wrong-length or
    /// non-finite input reports no contact; check it with [`Chain::check`] first.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::{Contact, RobotValidity};
    /// use parry3d::math::{Pose, Vector};
    /// # use std::sync::Arc;
    /// # use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// # let panda = RobotModel::builtin("panda").unwrap();
    /// # let arm = Chain::named(&panda, "arm").unwrap();
    /// # let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
    ///
    /// // `panda`: the Panda model; `arm`: its arm chain; `acm`: its self-collision matrix.
    /// let wall = Obstacle::cuboid("wall", Pose::translation(0.45, 0.0, 0.5), Vector::new(0.02, 1.0, 1.0));
    /// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![wall])));
    /// assert_eq!(v.explain(&[0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]), None);
    /// match v.explain(&[0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.785]) {
    ///     Some(Contact::Obstacle { link, obstacle }) => assert!(link.starts_with("panda_") && obstacle == "wall"),
    ///     other => panic!("expected the wall, got {other:?}"),
    /// }
    /// assert_eq!(v.explain(&[f64::NAN; 7]), None);
    /// ```
    pub fn explain(&mut self, q: &[f64]) -> Option<Contact> {
        if !self.update_poses(q) {
            return None;
        }
        let names = |l: usize| self.model.links()[l].name.clone();
        for &l in &self.geometric {
            if let Some(id) = self.link_hits(l) {
                return Some(Contact::Obstacle {
                    link: names(l),
                    obstacle: self.obstacles.name(id).unwrap_or("?").to_owned(),
                });
            }
        }
        if let Some(&(a, b)) = self.pairs.iter().find(|&&(a, b)| self.pair_touches(a, b)) {
            return Some(Contact::SelfCollision {
                a: names(a),
                b: names(b),
            });
        }
        for a in &self.attached {
            let pose = to_pose(&(self.poses[a.link] * a.offset));
            if let Some(id) = self.obstacles.first_hit(a.shape.as_ref(), &pose) {
                return Some(Contact::Obstacle {
                    link: format!("attached:{}", a.name),
                    obstacle: self.obstacles.name(id).unwrap_or("?").to_owned(),
                });
            }
            if let Some(&l) = self.geometric.iter().find(|&&l| self.attached_touches_link(a, l)) {
                return Some(Contact::SelfCollision {
                    a: format!("attached:{}", a.name),
                    b: names(l),
                });
            }
        }
        None
    }
}

impl RobotValidity {
    /// The link [`StateValidator::tool_step`] moves: the chain's tip when it names one, else
    /// the deepest link its joints move (the child of its last joint down the tree).
    fn tool(&self) -> Option<usize> {
        if let Some(tip) = self.chain.tip() {
            return Some(tip);
        }
        let (links, joints) = (self.model.links(), self.model.joints());
        let depth = |mut l: usize| {
            let mut d = 0usize;
            while let Some(j) = links[l].parent_joint {
                l = joints[j].parent;
                d += 1;
            }
            d
        };
        self.chain
            .joints()
            .iter()
            .map(|&j| joints[j].child)
            .max_by_key(|&l| depth(l))
    }
}

impl StateValidator for RobotValidity {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        if !q.iter().all(|v| v.is_finite()) {
            return false;
        }
        match self.hint_link_hits(q) {
            Some(true) => return false,
            Some(false) => {}
            None => {
                if !self.update_poses(q) {
                    return false;
                }
            }
        }
        !self.robot_blocked() && !self.attached_blocked()
    }

    fn checks(&self) -> u64 {
        self.checks
    }

    /// Skips the states that a checked neighbour's free region proves valid: where each moving
    /// link's covering balls stay clear of the obstacles and each checked pair stays apart,
    /// given how far the joints' change can move them. Along a fine motion most states lie
    /// well within one.
    fn first_invalid_along(&mut self, states: &[f64], dim: usize) -> Option<usize> {
        let dim = dim.max(1);
        if dim != self.chain.dof() || dim > 32 || states.len() / dim < FREE_RADIUS_MIN_STATES {
            return bisect_first_invalid(self, states, dim);
        }
        self.first_invalid_along_free(states, dim)
    }

    /// One damped least-squares step through the chain tip's Jacobian (at the current
    /// reference, base and attachments), the tip's origin moving by `length` along its axis
    /// and its angular velocity held at zero.
    fn tool_step(&mut self, q: &[f64], axis: usize, length: f64, out: &mut [f64]) -> bool {
        let dof = self.chain.dof();
        let Some(tip) = self.tool() else {
            return false;
        };
        if axis >= 6 || q.len() != dof || out.len() != dof || !length.is_finite() || !q.iter().all(|v| v.is_finite()) {
            return false;
        }
        let (full, poses, jacobian) = (&mut self.tool_q, &mut self.tool_poses, &mut self.tool_jacobian);
        full.copy_from_slice(&self.q_full);
        self.chain.scatter(q, full);
        if self.model.fk_from(&self.base, full, poses).is_err()
            || self
                .model
                .jacobian(poses, &self.chain, tip, &nalgebra::Vector3::zeros(), jacobian)
                .is_err()
        {
            return false;
        }
        let mut local = nalgebra::Vector3::zeros();
        local[axis % 3] = if axis < 3 { length } else { -length };
        let along = poses[tip].rotation * local;
        let twist = [along.x, along.y, along.z, 0.0, 0.0, 0.0];
        if !hearth_kinematics::damped_least_squares_step(jacobian, 6, &twist, TOOL_STEP_DAMPING, out) {
            return false;
        }
        for (o, q) in out.iter_mut().zip(q) {
            *o += q;
        }
        self.chain.clamp(out);
        out != q
    }

    /// Each round moves the first touching part of every link that touches an obstacle (the
    /// links the chain moves; self-collisions are left to the final check). `out` holds the
    /// state reached, valid or not.
    fn retract(&mut self, q: &[f64], clearance: f64, rounds: usize, out: &mut [f64]) -> bool {
        self.retract_state(q, clearance, rounds, out)
    }

    /// Four states at a time share one four-lane forward kinematics pass (bit for bit the
    /// poses of one-by-one checks, so the answers and the check count are the same).
    fn first_invalid(&mut self, states: &[f64], dim: usize) -> Option<usize> {
        let dim = dim.max(1);
        let n = states.len() / dim;
        let mut start = 0;
        while start < n {
            let m = (n - start).min(4);
            let chunk = &states[start * dim..(start + m) * dim];
            let found = match self.first_invalid4(chunk, dim) {
                Some(found) => found,
                None => chunk.chunks_exact(dim).position(|q| !self.is_valid(q)),
            };
            if let Some(k) = found {
                return Some(start + k);
            }
            start += m;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over 2,000 random Fetch states, runs `proof` on the checked pairs that `applies`
    /// selects and asserts that it never clears a pair parry finds touching. Returns the
    /// pairs selected and (cleared, touching, tested) counts.
    fn proof_on_fetch_pairs(
        applies: impl Fn(&RobotValidity, usize) -> bool,
        proof: impl Fn(&RobotValidity, usize) -> bool,
    ) -> (usize, [usize; 3]) {
        use rand::SeedableRng;
        let fetch = RobotModel::builtin("fetch").unwrap();
        let chain = Chain::named(&fetch, "arm_with_torso").unwrap();
        let matrix = SelfCollisionMatrix::adjacent_only(&fetch);
        let mut v = RobotValidity::new(chain.clone(), matrix, Arc::new(crate::ParryScene::new(vec![])));
        let selected: Vec<usize> = (0..v.pairs.len()).filter(|&i| applies(&v, i)).collect();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let mut q = vec![0.0; chain.dof()];
        let (mut cleared, mut touching, mut tested) = (0, 0, 0);
        for _ in 0..2000 {
            chain.random_configuration(&mut rng, &mut q);
            assert!(v.update_poses(&q));
            v.update_centers();
            for &i in &selected {
                let (a, b) = v.pairs[i];
                let touch = links_touch(&v.model, &v.poses, a, b);
                let clear = proof(&v, i);
                assert!(!(touch && clear), "{:?} cleared while touching", (a, b));
                tested += 1;
                cleared += usize::from(clear);
                touching += usize::from(touch);
            }
        }
        (selected.len(), [cleared, touching, tested])
    }

    /// The cover-against-box proof never clears a Fetch pair that parry finds touching, and it
    /// does clear most of the arm's pairs with the torso and the bellows in random states.
    #[test]
    fn single_box_pairs_are_cleared_only_when_apart() {
        let (pairs, [cleared, touching, tested]) = proof_on_fetch_pairs(
            |v, i| {
                let (a, b) = v.pairs[i];
                v.broad.boxes[a].is_some() || v.broad.boxes[b].is_some()
            },
            |v, i| v.cover_clears_box(v.pairs[i].0, v.pairs[i].1),
        );
        assert!(pairs >= 10, "the torso's and bellows' pairs: {pairs}");
        assert!(touching > 50, "some pairs touch: {touching}");
        assert!(
            cleared * 10 > tested * 8,
            "most pairs are cleared: {cleared} of {tested}"
        );
    }

    /// The distance-field proof never clears a Fetch pair that parry finds touching, and it
    /// clears most pairs of compound links (the base, the torso lift, the head and the arm's
    /// compound links against the others' covers) in random states.
    #[test]
    fn field_pairs_are_cleared_only_when_apart() {
        let (pairs, [cleared, touching, tested]) =
            proof_on_fetch_pairs(|v, i| v.broad.pair_field[i][0].is_some(), |v, i| v.field_clears(i));
        assert!(pairs >= 20, "pairs with a field: {pairs}");
        assert!(touching > 50, "some pairs touch: {touching}");
        assert!(
            cleared * 100 > (tested - touching) * 97,
            "most pairs apart are cleared: {cleared} of {}",
            tested - touching
        );
        // Where both links have a field, the second way round clears pairs the first
        // cannot: the same states, with one way only (6 % of the pairs apart it leaves, in
        // these random states; a third of those left to parry in the table_pick plans).
        let (_, [one_way, ..]) = proof_on_fetch_pairs(
            |v, i| v.broad.pair_field[i][0].is_some(),
            |v, i| v.broad.pair_field[i][0].is_some_and(|(f, c)| v.field_clears_cover(f, c)),
        );
        assert!(
            (cleared - one_way) * 100 > (tested - touching - one_way) * 3,
            "the second way clears some of the rest: {cleared} against {one_way} of {}",
            tested - touching
        );
    }

    /// Points on the surface of the ball (`centre`, `radius`), spread by a Fibonacci spiral.
    fn surface(centre: Point3<f64>, radius: f64, n: usize) -> impl Iterator<Item = Vector> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n).map(move |i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let (s, c) = (golden * i as f64).sin_cos();
            let ring = (1.0 - z * z).sqrt();
            let p = centre + nalgebra::Vector3::new(ring * c, ring * s, z) * radius;
            to_vector(&p)
        })
    }

    fn assert_inside(part: &SharedShape, what: &str) -> bool {
        let (c, r) = inner_ball(&(part.clone(), Isometry3::identity()));
        if r == 0.0 {
            return false;
        }
        for p in surface(c, r + INNER_BALL_SINK * 0.5, 400) {
            assert!(
                part.contains_local_point(p),
                "{what}: inner ball ({c}, {r}) leaves the part at {p}"
            );
        }
        true
    }

    #[test]
    fn a_short_cylinders_inner_ball_stays_between_its_caps() {
        // parry projects a cylinder's centre onto its side when the caps are equally near,
        // even when they are nearer than the side: the depth must be the nearer of the two.
        let short = SharedShape::cylinder(0.03, 0.06);
        assert!(assert_inside(&short, "short cylinder"));
        let (_, r) = inner_ball(&(short, Isometry3::identity()));
        assert!((r - (0.03 - INNER_BALL_SINK)).abs() < 1e-6, "radius {r}");
        assert!(assert_inside(&SharedShape::cylinder(0.2, 0.05), "long cylinder"));
        assert_eq!(
            inner_ball(&(SharedShape::cuboid(0.1, 0.1, 0.1), Isometry3::identity())).1,
            0.0
        );
    }

    #[test]
    fn every_inner_ball_of_the_builtin_robots_lies_inside_its_part() {
        for name in ["panda", "fetch"] {
            let model = RobotModel::builtin(name).unwrap();
            let (mut parts, mut with_ball) = (0, 0);
            for l in 0..model.links().len() {
                let Some(s) = model.link_shape(l) else { continue };
                let shapes: Vec<SharedShape> = match s.shape.as_compound() {
                    Some(c) => c.shapes().iter().map(|(_, p)| p.clone()).collect(),
                    None => vec![s.shape.clone()],
                };
                for part in &shapes {
                    parts += 1;
                    with_ball += usize::from(assert_inside(part, &format!("{name} link {l}")));
                }
            }
            // Boxes and balls have none (their exact tests are closed forms); the links'
            // convex hulls and cylinders do.
            println!("{name}: {with_ball} of {parts} parts have an inner ball");
            assert!(
                with_ball >= 10,
                "{name}: only {with_ball} of {parts} parts have an inner ball"
            );
        }
    }
}
