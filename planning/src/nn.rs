//! Exact nearest-neighbour search under a [`Space`]'s metric, with incremental insertion.
//!
//! [`NearestNeighbors`] keeps the states in a flat arena and indexes them with vantage-point
//! trees, which only use [`Space::distance`] and the triangle inequality, so continuous
//! (wrapping) coordinates, SE(2) yaw and weighted or compound metrics are all handled exactly.
//! Spaces whose metric is a weighted Euclidean one ([`Space::euclidean_weights`]: bounded
//! joints only), or one on a torus ([`Space::wrapping_weights`]: bounded and continuous
//! joints, the angles' differences taken the short way round), or one bounded by such a
//! metric from both sides ([`Space::euclidean_bound`]: SE(2) bases, compound base + arm
//! spaces; the bound prunes, the metric decides) get k-d trees instead, which prune far better
//! in 7 or 8 dimensions (a nearest-neighbour query among 20,000 Panda states takes about 5 µs
//! with k-d trees and 38 µs with vantage-point trees; with one joint continuous, 8 µs; among
//! 20,000 states of a mobile base and arm, 65 µs against 129 µs). The k-d trees keep each
//! node's bounding box, which prunes queries far from every state: 1,000 states in a pocket
//! answer a sample of the whole space in about 3 µs, against 7 µs with the cells' split
//! planes alone. Trees of up to a few hundred
//! states, trees of up to 2,048 far from the query, and, for a k-nearest query, trees of up
//! to 4,096 are scanned instead of descended: an f32 copy of their weighted states, eight per
//! step, filters with a bound widened past its rounding, and the space's distance decides.
//! All give the exact answer, ties broken by id.
//! Insertion follows the logarithmic method (Bentley–Saxe): new states go into a small
//! buffer that is scanned linearly; a full buffer is merged with the equal-sized trees into a
//! new tree, so every state is re-indexed `O(log n)` times and a query visits `O(log n)`
//! trees. A merge builds the new k-d tree in the arrays of the trees it retires, so a growing
//! index allocates only when it reaches a new size, as a growing vector does, and queries
//! never allocate (`planning/tests/allocations.rs` counts both).

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::{PI, TAU};

use hearth_kinematics::wrap_angle;
use wide::f32x8;

use crate::space::{EuclideanBound, Space};

/// States in the linear buffer before they are indexed by a tree.
const BUFFER: usize = 32;
/// Buffers of at least this many states are scanned in lanes ([`BufferLanes`]); smaller ones
/// cost less state by state.
const BUFFER_SCAN: usize = 5;
/// Retired k-d trees kept for their arrays ([`NearestNeighbors::flush`]): more than the
/// trees of an index of 2³² states can need at once.
const SPARE_TREES: usize = 40;
/// Most states in a tree leaf.
const LEAF: usize = 8;
/// Entries of a search's stack: more than the height + 1 of any tree over u32 ids.
const STACK: usize = 64;
/// Slack on the triangle-inequality pruning bounds, so rounding never prunes the exact answer.
const SLACK: f64 = 1e-9;
/// Spaces of at most this many coordinates with a weighted Euclidean metric get k-d trees.
const KD_MAX_DIM: usize = 32;
/// k-d trees of at most this many states keep an f32 copy of their states, so that they can be
/// scanned eight states at a time instead of descended ([`KdTree::scanned`]).
///
/// A query for the k nearest states scans every tree with lanes: its radius stays as wide as
/// its k-th state, so in the planners' seven or eight dimensions descent visits most leaves
/// of a tree of a few thousand states. Among uniform states of the Fetch's joint space, the
/// ten nearest of 4,000 took 9.7 µs by scan and 15.6 µs by descent; at 12,000 states the two
/// are even, so larger trees are descended.
const SCAN_MAX: usize = 4096;
/// A nearest-state query scans a tree of at most this many states when the query is far from
/// it: a tree stuck in a pocket is about equally far from every sample of the whole space, so
/// descent would visit most of its leaves anyway.
const SCAN_FAR: usize = 2048;
/// k-d trees of at most this many states are scanned whatever the query.
const SCAN_ALWAYS: usize = 256;
/// States a scanned tree tests per step (the lanes of an `f32x8`).
const LANES: usize = 8;

/// An exact nearest-neighbour index over states of one [`Space`] (ids are insertion indices).
///
/// The index does not own the space: pass the same space to every call.
///
/// ```
/// use hearth_planning::nn::NearestNeighbors;
/// use hearth_planning::space::{JointSpace, Space};
///
/// // One continuous joint: 3.1 and -3.1 are close, the short way round through ±π.
/// let space = JointSpace::new(&[0.0], &[0.0], &[true])?;
/// let mut nn = NearestNeighbors::new(1);
/// for q in [0.0, 1.0, -3.1, 2.0] {
///     nn.insert(&[q]);
/// }
/// assert_eq!(nn.nearest(&space, &[3.1]), Some(2));
/// assert_eq!(nn.k_nearest(&space, &[0.4], 2), vec![0, 1]);
/// assert_eq!(nn.within_radius(&space, &[1.5], 0.6), vec![1, 3]);
/// nn.remove(1);
/// assert_eq!(nn.nearest(&space, &[0.9]), Some(0));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug)]
pub struct NearestNeighbors {
    dim: usize,
    states: Vec<f64>,
    removed: Vec<bool>,
    live: usize,
    buffer: Vec<u32>,
    /// The buffer's states in f32 lanes, as a scanned tree keeps its own.
    buffer_lanes: BufferLanes,
    trees: Vec<Tree>,
    /// The k-nearest query's heap, kept between queries so that a query does not allocate.
    heap: BinaryHeap<Entry>,
    /// Retired k-d trees, whose arrays the next rebuilds fill again: once the trees have
    /// reached a size, merging them allocates nothing (at most [`SPARE_TREES`] kept).
    spare: Vec<KdTree>,
    /// The ids of the states a rebuild merges, kept between rebuilds.
    merging: Vec<u32>,
}

impl NearestNeighbors {
    /// An empty index of `dim`-dimensional states.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let nn = NearestNeighbors::new(3);
    /// assert!(nn.is_empty());
    /// assert_eq!((nn.dim(), nn.len(), nn.ids()), (3, 0, 0));
    /// ```
    pub fn new(dim: usize) -> Self {
        Self {
            dim,
            states: Vec::new(),
            removed: Vec::new(),
            live: 0,
            buffer: Vec::with_capacity(BUFFER),
            buffer_lanes: BufferLanes::default(),
            trees: Vec::new(),
            heap: BinaryHeap::new(),
            spare: Vec::new(),
            merging: Vec::new(),
        }
    }

    /// Dimension of the states.
    ///
    /// ```
    /// assert_eq!(hearth_planning::nn::NearestNeighbors::new(7).dim(), 7);
    /// ```
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of states held (removed ones excluded).
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(1);
    /// let a = nn.insert(&[0.0]);
    /// nn.insert(&[1.0]);
    /// nn.remove(a);
    /// assert_eq!(nn.len(), 1);
    /// ```
    pub fn len(&self) -> usize {
        self.live
    }

    /// Whether no state is held (all removed counts as empty).
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(1);
    /// let id = nn.insert(&[0.5]);
    /// assert!(!nn.is_empty());
    /// nn.remove(id);
    /// assert!(nn.is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Number of ids handed out so far (removed ones included): every id below it is valid for
    /// [`NearestNeighbors::state`].
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(1);
    /// for q in [0.0, 1.0, 2.0] {
    ///     nn.insert(&[q]);
    /// }
    /// nn.remove(1);
    /// assert_eq!((nn.ids(), nn.len()), (3, 2));
    /// ```
    pub fn ids(&self) -> usize {
        self.removed.len()
    }

    /// The state with id `id` (removed states included).
    ///
    /// Panics if `id` was never handed out.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(2);
    /// let id = nn.insert(&[0.25, -1.0]);
    /// nn.remove(id);
    /// assert_eq!(nn.state(id), &[0.25, -1.0]);
    /// ```
    #[inline]
    pub fn state(&self, id: usize) -> &[f64] {
        &self.states[id * self.dim..(id + 1) * self.dim]
    }

    /// Whether `id` was removed.
    ///
    /// Panics if `id` was never handed out.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(1);
    /// let (a, b) = (nn.insert(&[0.0]), nn.insert(&[1.0]));
    /// nn.remove(b);
    /// assert!(!nn.is_removed(a) && nn.is_removed(b));
    /// ```
    pub fn is_removed(&self, id: usize) -> bool {
        self.removed[id]
    }

    /// Removes every state and forgets the ids: the next insertion gets id 0 again.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(1);
    /// nn.insert(&[0.0]);
    /// nn.insert(&[1.0]);
    /// nn.clear();
    /// assert_eq!((nn.len(), nn.ids()), (0, 0));
    /// assert_eq!(nn.insert(&[2.0]), 0);
    /// ```
    pub fn clear(&mut self) {
        *self = Self::new(self.dim);
    }

    /// Adds a state and returns its id (ids count up from 0).
    ///
    /// Panics if `q` does not have [`NearestNeighbors::dim`] coordinates.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    ///
    /// let mut nn = NearestNeighbors::new(2);
    /// assert_eq!(nn.insert(&[0.0, 0.0]), 0);
    /// assert_eq!(nn.insert(&[1.0, 0.0]), 1);
    /// assert_eq!(nn.state(1), &[1.0, 0.0]);
    /// ```
    pub fn insert(&mut self, q: &[f64]) -> usize {
        assert_eq!(q.len(), self.dim, "state dimension");
        let id = self.removed.len();
        self.states.extend_from_slice(q);
        self.removed.push(false);
        self.live += 1;
        self.buffer.push(id as u32);
        id
    }

    /// Marks a state removed: queries no longer return it (its id stays taken). Removing it
    /// again does nothing.
    ///
    /// Panics if `id` was never handed out.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[10.0], &[false])?;
    /// let mut nn = NearestNeighbors::new(1);
    /// let (a, b) = (nn.insert(&[1.0]), nn.insert(&[5.0]));
    /// nn.remove(a);
    /// nn.remove(a);
    /// assert_eq!(nn.len(), 1);
    /// assert_eq!(nn.nearest(&space, &[0.0]), Some(b));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn remove(&mut self, id: usize) {
        if !self.removed[id] {
            self.removed[id] = true;
            self.live -= 1;
        }
    }

    /// Rebuilds the whole index for `space`: after it, pass that space to every call. For a
    /// planner that changes its metric part-way (the states and their ids stay).
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let plain = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
    /// let heavy_x = plain.clone().with_weights(&[10.0, 1.0])?;
    /// let mut nn = NearestNeighbors::new(2);
    /// nn.insert(&[0.2, 0.0]);
    /// nn.insert(&[0.0, 0.5]);
    /// assert_eq!(nn.nearest(&plain, &[0.0, 0.0]), Some(0));
    /// nn.reindex(&heavy_x);
    /// assert_eq!(nn.nearest(&heavy_x, &[0.0, 0.0]), Some(1));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn reindex<S: Space>(&mut self, space: &S) {
        let mut ids: Vec<u32> = std::mem::take(&mut self.trees)
            .into_iter()
            .flat_map(Tree::into_ids)
            .collect();
        ids.append(&mut self.buffer);
        ids.retain(|&i| !self.removed[i as usize]);
        ids.sort_unstable();
        self.index(space, &mut ids);
    }

    /// Indexes a full buffer: merges it with the trees of equal size into one new tree. The
    /// merged k-d trees' arrays are kept for later rebuilds ([`NearestNeighbors::spare`]), so
    /// the rebuilds of a growing index allocate only when it reaches a new size, as a growing
    /// vector does.
    fn flush<S: Space>(&mut self, space: &S) {
        if self.buffer.len() < BUFFER {
            return;
        }
        let mut ids = std::mem::take(&mut self.merging);
        ids.clear();
        ids.append(&mut self.buffer);
        while self.trees.last().is_some_and(|t| t.len() <= ids.len()) {
            match self.trees.pop().expect("checked above") {
                Tree::Kd(t) => {
                    ids.extend_from_slice(&t.ids);
                    self.spare.push(t);
                }
                t @ Tree::Vp(_) => ids.extend(t.into_ids()),
            }
        }
        // Drop removed states while rebuilding.
        ids.retain(|&i| !self.removed[i as usize]);
        self.index(space, &mut ids);
        self.merging = ids;
    }

    /// Builds one tree over the live states `ids` (none for no ids; `ids` is reordered) and
    /// starts an empty buffer.
    fn index<S: Space>(&mut self, space: &S, ids: &mut [u32]) {
        if !ids.is_empty() {
            let tree = match weighted_metric(space, self.dim) {
                Some(bound) => {
                    // The spare tree with the most room: the largest rebuild takes the largest.
                    let roomiest = (0..self.spare.len()).max_by_key(|&k| self.spare[k].ids.capacity());
                    let shell = roomiest.map(|k| self.spare.swap_remove(k));
                    Tree::Kd(KdTree::build(&self.states, self.dim, bound, ids, shell))
                }
                None => Tree::Vp(VpTree::build(space, &self.states, self.dim, ids.to_vec())),
            };
            self.trees.push(tree);
        }
        if self.spare.len() > SPARE_TREES {
            // Keep the roomiest.
            self.spare.sort_unstable_by_key(|t| std::cmp::Reverse(t.ids.capacity()));
            self.spare.truncate(SPARE_TREES);
        }
        self.buffer.clear();
        self.buffer_lanes.written = 0;
    }

    /// Indexes the buffer and brings its lanes up to date: every query calls this first.
    fn prepare<S: Space>(&mut self, space: &S) {
        self.flush(space);
        if self.buffer.len() < BUFFER_SCAN {
            return;
        }
        if self.buffer_lanes.written == 0 {
            self.buffer_lanes.start(space, self.dim);
        }
        while self.buffer_lanes.written < self.buffer.len() {
            let id = self.buffer[self.buffer_lanes.written] as usize;
            self.buffer_lanes.push(&self.states[id * self.dim..(id + 1) * self.dim]);
        }
    }

    fn search<S: Space, C: Collector>(&self, space: &S, q: &[f64], c: &mut C) {
        let lanes = &self.buffer_lanes;
        if lanes.usable && self.buffer.len() >= BUFFER_SCAN {
            let view = LaneView {
                lanes: &lanes.lanes[..self.buffer.len().div_ceil(LANES) * self.dim * LANES],
                ids: &self.buffer,
                weights: &lanes.weights,
                lane_periods: &lanes.lane_periods,
                reach: lanes.reach,
                stretch: lanes.stretch,
            };
            if lanes.wraps.is_empty() {
                view.scan::<S, C, false>(space, self, q, q, c);
            } else {
                let wrapped = wrap_query(q, &lanes.wraps);
                view.scan::<S, C, true>(space, self, q, &wrapped[..q.len()], c);
            }
        } else {
            for &id in &self.buffer {
                if !self.removed[id as usize] {
                    c.offer(space.distance(q, self.state(id as usize)), id);
                }
            }
        }
        for t in &self.trees {
            match t {
                Tree::Vp(t) => t.search(space, self, q, c),
                Tree::Kd(t) => t.search(space, self, q, c),
            }
        }
    }

    /// Id of the nearest state to `q` under `space.distance` (the lowest id among equally
    /// near ones), or `None` when empty.
    ///
    /// Takes `&mut self` because queries index the buffered insertions first.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
    /// let mut nn = NearestNeighbors::new(2);
    /// assert_eq!(nn.nearest(&space, &[0.5, 0.5]), None);
    /// for q in [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
    ///     nn.insert(&q);
    /// }
    /// assert_eq!(nn.nearest(&space, &[0.1, 0.8]), Some(2));
    /// // Ids 0, 1 and 2 are equally far from the centre: the lowest wins.
    /// assert_eq!(nn.nearest(&space, &[0.5, 0.5]), Some(0));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn nearest<S: Space>(&mut self, space: &S, q: &[f64]) -> Option<usize> {
        self.prepare(space);
        let mut c = Nearest {
            best: f64::INFINITY,
            id: u32::MAX,
        };
        self.search(space, q, &mut c);
        (c.id != u32::MAX).then_some(c.id as usize)
    }

    /// Ids of the `k` nearest states to `q`, nearest first (ties by id); all of them when
    /// fewer than `k` are held.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[10.0], &[false])?;
    /// let mut nn = NearestNeighbors::new(1);
    /// for q in [0.0, 4.0, 5.0, 9.0] {
    ///     nn.insert(&[q]);
    /// }
    /// assert_eq!(nn.k_nearest(&space, &[8.0], 2), vec![3, 2]);
    /// assert_eq!(nn.k_nearest(&space, &[8.0], 10), vec![3, 2, 1, 0]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn k_nearest<S: Space>(&mut self, space: &S, q: &[f64], k: usize) -> Vec<usize> {
        let mut out = Vec::with_capacity(k.min(self.len()));
        self.k_nearest_into(space, q, k, &mut out);
        out
    }

    /// [`NearestNeighbors::k_nearest`] into `out` (cleared first): with a reused `out`, a
    /// query allocates nothing once the index has answered one with this `k`.
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[10.0], &[false])?;
    /// let mut nn = NearestNeighbors::new(1);
    /// for q in [0.0, 4.0, 5.0, 9.0] {
    ///     nn.insert(&[q]);
    /// }
    /// let mut near = Vec::new();
    /// nn.k_nearest_into(&space, &[4.6], 2, &mut near);
    /// assert_eq!(near, [2, 1]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn k_nearest_into<S: Space>(&mut self, space: &S, q: &[f64], k: usize, out: &mut Vec<usize>) {
        out.clear();
        if k == 0 {
            return;
        }
        self.prepare(space);
        let mut heap = std::mem::take(&mut self.heap);
        // (No more than the states held: `k` is a setting, and may be huge.)
        heap.reserve(k.min(self.len()).saturating_add(1));
        let mut c = KNearest { k, heap };
        self.search(space, q, &mut c);
        let mut found = c.heap.into_vec();
        found.sort_unstable();
        out.extend(found.iter().map(|e| e.1 as usize));
        found.clear();
        self.heap = BinaryHeap::from(found);
    }

    /// Ids of every state within `radius` of `q` (inclusive), nearest first (ties by id).
    ///
    /// ```
    /// use hearth_planning::nn::NearestNeighbors;
    /// use hearth_planning::space::JointSpace;
    ///
    /// let space = JointSpace::new(&[0.0], &[10.0], &[false])?;
    /// let mut nn = NearestNeighbors::new(1);
    /// for q in [0.0, 4.0, 5.0, 7.0] {
    ///     nn.insert(&[q]);
    /// }
    /// assert_eq!(nn.within_radius(&space, &[5.5], 1.5), vec![2, 1, 3]);
    /// assert!(nn.within_radius(&space, &[2.0], 1.0).is_empty());
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn within_radius<S: Space>(&mut self, space: &S, q: &[f64], radius: f64) -> Vec<usize> {
        self.prepare(space);
        let mut c = Radius {
            radius,
            found: Vec::new(),
        };
        self.search(space, q, &mut c);
        c.found.sort_unstable();
        c.found.into_iter().map(|e| e.1 as usize).collect()
    }
}

/// A distance and an id, ordered by distance then id.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry(f64, u32);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// What a search collects: it offers every candidate and prunes with the current radius.
trait Collector {
    /// Whether only the nearest state is collected: then any state's distance bounds the
    /// radius, and a scan may filter with its lanes' smallest sum so far.
    const NEAREST: bool = false;
    /// Whether the k nearest states are collected: a scan serves such a query better than
    /// descent on every tree with lanes ([`SCAN_MAX`]).
    const K_NEAREST: bool = false;
    /// Current search radius: states farther than this cannot be collected.
    fn radius(&self) -> f64;
    /// A live state at distance `d`.
    fn offer(&mut self, d: f64, id: u32);
}

struct Nearest {
    best: f64,
    id: u32,
}

impl Collector for Nearest {
    const NEAREST: bool = true;
    #[inline]
    fn radius(&self) -> f64 {
        self.best
    }
    #[inline]
    fn offer(&mut self, d: f64, id: u32) {
        if d < self.best || (d == self.best && id < self.id) {
            self.best = d;
            self.id = id;
        }
    }
}

struct KNearest {
    k: usize,
    heap: BinaryHeap<Entry>,
}

impl Collector for KNearest {
    const K_NEAREST: bool = true;
    #[inline]
    fn radius(&self) -> f64 {
        if self.heap.len() < self.k {
            f64::INFINITY
        } else {
            self.heap.peek().map_or(f64::INFINITY, |e| e.0)
        }
    }
    #[inline]
    fn offer(&mut self, d: f64, id: u32) {
        let e = Entry(d, id);
        if self.heap.len() < self.k {
            self.heap.push(e);
        } else if self.heap.peek().is_some_and(|top| e < *top) {
            self.heap.pop();
            self.heap.push(e);
        }
    }
}

struct Radius {
    radius: f64,
    found: Vec<Entry>,
}

impl Collector for Radius {
    #[inline]
    fn radius(&self) -> f64 {
        self.radius
    }
    #[inline]
    fn offer(&mut self, d: f64, id: u32) {
        if d <= self.radius {
            self.found.push(Entry(d, id));
        }
    }
}

#[derive(Clone, Debug)]
enum Node {
    /// States `ids[start..end]`.
    Leaf { start: u32, end: u32 },
    /// A vantage point; `inside` holds states at distance ≤ `mu`, `outside` those at ≥ `mu`.
    Inner {
        vp: u32,
        mu: f64,
        inside: u32,
        outside: u32,
    },
}

/// A static vantage-point tree over some of the arena's states.
#[derive(Clone, Debug)]
struct VpTree {
    /// The states in the leaves, leaf by leaf.
    ids: Vec<u32>,
    /// The vantage points of the inner nodes (every state of the tree is in `ids` or here).
    vps: Vec<u32>,
    nodes: Vec<Node>,
}

impl VpTree {
    fn build<S: Space>(space: &S, states: &[f64], dim: usize, ids: Vec<u32>) -> Self {
        let mut work: Vec<(u32, f64)> = ids.iter().map(|&i| (i, 0.0)).collect();
        let mut tree = Self {
            ids: Vec::with_capacity(ids.len()),
            vps: Vec::new(),
            nodes: Vec::new(),
        };
        tree.build_node(space, states, dim, &mut work);
        tree
    }

    fn build_node<S: Space>(&mut self, space: &S, states: &[f64], dim: usize, work: &mut [(u32, f64)]) -> u32 {
        let index = self.nodes.len() as u32;
        if work.len() <= LEAF {
            let start = self.ids.len() as u32;
            self.ids.extend(work.iter().map(|w| w.0));
            self.nodes.push(Node::Leaf {
                start,
                end: self.ids.len() as u32,
            });
            return index;
        }
        let vp = work[0].0;
        self.vps.push(vp);
        let vq = &states[vp as usize * dim..(vp as usize + 1) * dim];
        let rest = &mut work[1..];
        for w in rest.iter_mut() {
            w.1 = space.distance(vq, &states[w.0 as usize * dim..(w.0 as usize + 1) * dim]);
        }
        let m = rest.len() / 2;
        rest.select_nth_unstable_by(m, |a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        let mu = rest[m].1;
        self.nodes.push(Node::Leaf { start: 0, end: 0 }); // placeholder
        let (inside, outside) = rest.split_at_mut(m);
        let inside = self.build_node(space, states, dim, inside);
        let outside = self.build_node(space, states, dim, outside);
        self.nodes[index as usize] = Node::Inner {
            vp,
            mu,
            inside,
            outside,
        };
        index
    }

    /// Offers `c` the live states of this tree that may be within its radius of `q`.
    fn search<S: Space, C: Collector>(&self, space: &S, index: &NearestNeighbors, q: &[f64], c: &mut C) {
        // Nodes to visit with a lower bound on the distance from `q` to any of their states,
        // on the stack frame: each visited inner node replaces itself with its two children, so
        // the stack never holds more than the tree's height + 1 entries, and each child has at
        // most half its parent's states, so the height is at most 33 for u32 ids.
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut top = 1usize;
        let state = |i: u32| index.state(i as usize);
        while top > 0 {
            top -= 1;
            let (n, bound) = stack[top];
            if bound > c.radius() + SLACK {
                continue;
            }
            match self.nodes[n as usize] {
                Node::Leaf { start, end } => {
                    for &id in &self.ids[start as usize..end as usize] {
                        if !index.is_removed(id as usize) {
                            c.offer(space.distance(q, state(id)), id);
                        }
                    }
                }
                Node::Inner {
                    vp,
                    mu,
                    inside,
                    outside,
                } => {
                    let d = space.distance(q, state(vp));
                    if !index.is_removed(vp as usize) {
                        c.offer(d, vp);
                    }
                    // Inside states p have d(p, vp) ≤ mu, so d(q, p) ≥ d - mu; outside ones have
                    // d(p, vp) ≥ mu, so d(q, p) ≥ mu - d. The nearer side is pushed last.
                    let (b_in, b_out) = ((d - mu).max(0.0), (mu - d).max(0.0));
                    let (far, near) = if d <= mu {
                        ((outside, b_out), (inside, b_in))
                    } else {
                        ((inside, b_in), (outside, b_out))
                    };
                    stack[top] = far;
                    stack[top + 1] = near;
                    top += 2;
                }
            }
        }
    }
}

/// One static index over some of the arena's states.
#[derive(Clone, Debug)]
enum Tree {
    Vp(VpTree),
    Kd(KdTree),
}

impl Tree {
    /// Number of states indexed (removed ones included until the next rebuild).
    fn len(&self) -> usize {
        match self {
            Tree::Vp(t) => t.ids.len() + t.vps.len(),
            Tree::Kd(t) => t.ids.len(),
        }
    }

    /// Every state indexed, for a rebuild.
    fn into_ids(self) -> Vec<u32> {
        match self {
            Tree::Vp(mut t) => {
                t.ids.append(&mut t.vps);
                t.ids
            }
            Tree::Kd(t) => t.ids,
        }
    }
}

#[derive(Clone, Debug)]
enum KdNode {
    /// States `ids[start..end]`.
    Leaf { start: u32, end: u32 },
    /// States of `low` have coordinate `axis` ≤ `split`, those of `high` ≥ `split`.
    Inner { axis: u32, split: f64, low: u32, high: u32 },
}

/// A static k-d tree over some of the arena's states, for a weighted Euclidean metric or a
/// metric it bounds ([`EuclideanBound`](crate::space::EuclideanBound)).
#[derive(Clone, Debug, Default)]
struct KdTree {
    ids: Vec<u32>,
    /// How far the space's distance may exceed the weighted Euclidean one (1: they are equal).
    stretch: f64,
    /// Per coordinate, the group of the metric's norms it counts in, numbered from 0 in order
    /// of first appearance (empty: one norm of all): the boxes' distance adds up the groups'
    /// norms, a tighter lower bound of the metric ([`EuclideanBound::lower`]).
    groups: Vec<u8>,
    /// The states' coordinates in `ids` order, so that a leaf reads contiguous memory.
    points: Vec<f64>,
    nodes: Vec<KdNode>,
    /// The metric's weight per coordinate.
    weights: Vec<f64>,
    /// Which coordinates are angles (empty: none). Their copies in `points` and the splits on
    /// them lie in `(−π, π]`.
    wraps: Vec<bool>,
    /// Per coordinate of a tree with angles: 2π for an angle, infinity otherwise, so that the
    /// leaves' short way round, `min(d, period − d)`, needs no branch (or mask) per coordinate.
    periods: Vec<f64>,
    /// Per node, the bounding box of its states' copies in `points`: `dim` lower corners then
    /// `dim` upper corners. A query far from every state (a sample of the whole space against a
    /// tree stuck in a pocket) is pruned by the boxes' distance, where the cells' split planes
    /// alone leave most leaves to visit.
    boxes: Vec<f64>,
    /// For a tree of at most [`SCAN_MAX`] states: `points` times their weights in f32, in
    /// blocks of [`LANES`] states (`dim` rows of [`LANES`] values per block, the last block
    /// padded with NaN, which no filter passes); empty for a tree searched by descent.
    lanes: Vec<f32>,
    /// Per coordinate of a scanned tree: its weighted period (`periods` times the weight) in
    /// f32, infinite for a coordinate that is no angle.
    lane_periods: Vec<f32>,
    /// Largest weighted magnitude of a coordinate in `points` or a period (bounds the f32
    /// rounding of `lanes`).
    reach: f64,
    /// The root box's weighted squared diagonal.
    diagonal2: f64,
}

impl KdTree {
    /// A tree over the states `ids` (reordered), in the arrays of `shell` (a retired tree,
    /// whose contents are all replaced) when given.
    fn build(states: &[f64], dim: usize, bound: EuclideanBound<'_>, ids: &mut [u32], shell: Option<Self>) -> Self {
        let EuclideanBound {
            weights,
            wraps,
            groups,
            stretch,
        } = bound;
        let mut tree = shell.unwrap_or_default();
        tree.clear();
        tree.stretch = stretch;
        tree.ids.reserve(ids.len());
        tree.points.reserve(ids.len() * dim);
        dense_groups_into(groups, &mut tree.groups);
        tree.weights.extend_from_slice(weights);
        if wraps.contains(&true) {
            tree.wraps.extend_from_slice(wraps);
            tree.periods
                .extend(wraps.iter().map(|&w| if w { TAU } else { f64::INFINITY }));
        }
        tree.build_node(states, dim, ids);
        for k in 0..tree.ids.len() {
            let i = tree.ids[k] as usize;
            for axis in 0..dim {
                let x = tree.coordinate(states, dim, i, axis);
                tree.points.push(x);
            }
        }
        tree.build_boxes(dim);
        if tree.ids.len() <= SCAN_MAX {
            tree.build_lanes(dim);
        }
        tree
    }

    /// Empties every array (keeping its room) and zeroes the numbers.
    fn clear(&mut self) {
        let Self {
            ids,
            stretch,
            groups,
            points,
            nodes,
            weights,
            wraps,
            periods,
            boxes,
            lanes,
            lane_periods,
            reach,
            diagonal2,
        } = self;
        ids.clear();
        groups.clear();
        nodes.clear();
        wraps.clear();
        lanes.clear();
        lane_periods.clear();
        for v in [points, weights, periods, boxes] {
            v.clear();
        }
        (*stretch, *reach, *diagonal2) = (0.0, 0.0, 0.0);
    }

    /// Fills `lanes`, `lane_periods`, `reach` and `diagonal2` (leaves `lanes` empty when the
    /// weighted coordinates are too large for f32 to bound their rounding).
    fn build_lanes(&mut self, dim: usize) {
        let (lo, hi) = self.boxes[..2 * dim].split_at(dim);
        self.diagonal2 = lo
            .iter()
            .zip(hi)
            .zip(&self.weights)
            .map(|((l, h), w)| (w * (h - l)).powi(2))
            .sum();
        let mut reach = 0.0f64;
        for p in self.points.chunks_exact(dim) {
            for (x, w) in p.iter().zip(&self.weights) {
                reach = reach.max((w * x).abs());
            }
        }
        for (axis, w) in self.weights.iter().enumerate() {
            let period = self.periods.get(axis).copied().unwrap_or(f64::INFINITY);
            if period.is_finite() {
                reach = reach.max(w * period);
            }
            self.lane_periods.push((w * period) as f32);
        }
        if reach.is_nan() || reach >= 1e6 {
            self.lane_periods.clear();
            return;
        }
        self.reach = reach;
        let blocks = self.ids.len().div_ceil(LANES);
        self.lanes.clear();
        self.lanes.resize(blocks * dim * LANES, f32::NAN);
        for (k, p) in self.points.chunks_exact(dim).enumerate() {
            let block = &mut self.lanes[(k / LANES) * dim * LANES..][..dim * LANES];
            for (axis, (&x, &w)) in p.iter().zip(&self.weights).enumerate() {
                block[axis * LANES + k % LANES] = (w * x) as f32;
            }
        }
    }

    /// Fills `boxes`: children come after their parent in `nodes`, so one backward pass sees
    /// every child's box before its parent's.
    fn build_boxes(&mut self, dim: usize) {
        let mut boxes = std::mem::take(&mut self.boxes);
        boxes.clear();
        boxes.resize(self.nodes.len() * 2 * dim, 0.0);
        for n in (0..self.nodes.len()).rev() {
            let (done, rest) = boxes.split_at_mut((n + 1) * 2 * dim);
            let (lo, hi) = done[n * 2 * dim..].split_at_mut(dim);
            lo.fill(f64::INFINITY);
            hi.fill(f64::NEG_INFINITY);
            let mut widen = |a: &[f64], b: &[f64]| {
                for (((l, h), &x), &y) in lo.iter_mut().zip(hi.iter_mut()).zip(a).zip(b) {
                    *l = l.min(x);
                    *h = h.max(y);
                }
            };
            match self.nodes[n] {
                KdNode::Leaf { start, end } => {
                    for p in self.points[start as usize * dim..end as usize * dim].chunks_exact(dim) {
                        widen(p, p);
                    }
                }
                KdNode::Inner { low, high, .. } => {
                    for child in [low, high] {
                        let at = (child as usize - n - 1) * 2 * dim;
                        let (clo, chi) = rest[at..at + 2 * dim].split_at(dim);
                        widen(clo, chi);
                    }
                }
            }
        }
        self.boxes = boxes;
    }

    /// Weighted squared distance from `q` (angles wrapped) to node `n`'s box: a lower bound on
    /// the weighted squared distance to any of its states that never exceeds the leaves' own
    /// sums (both round the same monotone operations). For a metric of several norms
    /// (`groups`), the square of the sum of the groups' distances to the box instead: a lower
    /// bound of the metric itself, which prunes more.
    #[inline]
    fn box_distance2<const WRAP: bool>(&self, n: u32, q: &[f64]) -> f64 {
        let dim = self.weights.len();
        let b = &self.boxes[n as usize * 2 * dim..(n as usize + 1) * 2 * dim];
        let (lo, hi) = b.split_at(dim);
        if !self.groups.is_empty() {
            return self.grouped_box_distance2::<WRAP>(q, lo, hi);
        }
        let mut d2 = 0.0;
        if !WRAP {
            for (((&x, &l), &h), &w) in q.iter().zip(lo).zip(hi).zip(&self.weights) {
                let d = w * (l - x).max(x - h).max(0.0);
                d2 += d * d;
            }
        } else {
            // Outside its interval, an angle's short way to any state of the box passes one of
            // the interval's ends: across the nearer end (`d`), or round through ±π to the
            // farther one (`period − width − d`, infinite for a coordinate that is no angle).
            for ((((&x, &l), &h), &w), &period) in q.iter().zip(lo).zip(hi).zip(&self.weights).zip(&self.periods) {
                let d = (l - x).max(x - h).max(0.0);
                let d = w * d.min(period - (h - l) - d);
                d2 += d * d;
            }
        }
        d2
    }

    /// [`KdTree::box_distance2`] for a metric of several norms: each coordinate's gap to the
    /// box as there, squared into its group's sum; the groups' roots added up, squared.
    /// Kept out of line, so that the one-norm path of [`KdTree::box_distance2`] stays as small
    /// as before it.
    #[inline(never)]
    fn grouped_box_distance2<const WRAP: bool>(&self, q: &[f64], lo: &[f64], hi: &[f64]) -> f64 {
        let mut sums = [0.0f64; KD_MAX_DIM];
        let mut used = 0;
        for (axis, (((&x, &l), &h), &w)) in q.iter().zip(lo).zip(hi).zip(&self.weights).enumerate() {
            let mut d = (l - x).max(x - h).max(0.0);
            if WRAP {
                d = d.min(self.periods[axis] - (h - l) - d);
            }
            let d = w * d;
            let g = usize::from(self.groups[axis]);
            sums[g] += d * d;
            used = used.max(g + 1);
        }
        let sum: f64 = sums[..used].iter().map(|s| s.sqrt()).sum();
        sum * sum
    }

    /// Coordinate `axis` of state `i`, wrapped into `(−π, π]` when it is an angle.
    #[inline]
    fn coordinate(&self, states: &[f64], dim: usize, i: usize, axis: usize) -> f64 {
        let x = states[i * dim + axis];
        if self.wraps.get(axis).copied().unwrap_or(false) {
            wrap_angle(x)
        } else {
            x
        }
    }

    fn build_node(&mut self, states: &[f64], dim: usize, work: &mut [u32]) -> u32 {
        let index = self.nodes.len() as u32;
        let coordinate = |i: u32, axis: usize| self.coordinate(states, dim, i as usize, axis);
        // Split along the coordinate of widest weighted spread (none: all states coincide).
        let mut best = (0.0, 0);
        if work.len() > LEAF {
            for axis in 0..dim {
                let (lo, hi) = work.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
                    let x = coordinate(i, axis);
                    (lo.min(x), hi.max(x))
                });
                let spread = self.weights[axis] * (hi - lo);
                if spread > best.0 {
                    best = (spread, axis);
                }
            }
        }
        if work.len() <= LEAF || best.0 <= 0.0 {
            let start = self.ids.len() as u32;
            self.ids.extend_from_slice(work);
            self.nodes.push(KdNode::Leaf {
                start,
                end: self.ids.len() as u32,
            });
            return index;
        }
        let axis = best.1;
        let m = work.len() / 2;
        work.select_nth_unstable_by(m, |&a, &b| coordinate(a, axis).total_cmp(&coordinate(b, axis)));
        let split = coordinate(work[m], axis);
        self.nodes.push(KdNode::Leaf { start: 0, end: 0 }); // placeholder
        let (low, high) = work.split_at_mut(m);
        let low = self.build_node(states, dim, low);
        let high = self.build_node(states, dim, high);
        self.nodes[index as usize] = KdNode::Inner {
            axis: axis as u32,
            split,
            low,
            high,
        };
        index
    }

    /// Offers `c` the live states of this tree that may be within its radius of `q`.
    fn search<S: Space, C: Collector>(&self, space: &S, index: &NearestNeighbors, q: &[f64], c: &mut C) {
        if self.wraps.is_empty() {
            if self.scanned(C::K_NEAREST, || self.far::<false>(q)) {
                return self.lane_view().scan::<S, C, false>(space, index, q, q, c);
            }
            let mut search = KdSearch {
                tree: self,
                space,
                index,
                q,
                wrapped: q,
            };
            search.visit::<C, false>(0, 0.0, self.box_distance2::<false>(0, q), &mut [0.0; KD_MAX_DIM], c);
        } else {
            // The query with its angles wrapped like the tree's copies of the states.
            let wrapped = wrap_query(q, &self.wraps);
            let wrapped = &wrapped[..q.len()];
            if self.scanned(C::K_NEAREST, || self.far::<true>(wrapped)) {
                return self.lane_view().scan::<S, C, true>(space, index, q, wrapped, c);
            }
            let mut search = KdSearch {
                tree: self,
                space,
                index,
                q,
                wrapped,
            };
            let root2 = self.box_distance2::<true>(0, wrapped);
            search.visit::<C, true>(0, 0.0, root2, &mut [0.0; KD_MAX_DIM], c);
        }
    }

    /// Whether to scan this tree rather than descend it (only a tree with `lanes`): a small
    /// tree always (a scan of a few hundred states costs less than descent's bookkeeping),
    /// for a k-nearest query always (see [`SCAN_MAX`]), and for a nearest-state
    /// query a tree of at most [`SCAN_FAR`] states when the query is [`KdTree::far`] from it.
    #[inline]
    fn scanned(&self, k_nearest: bool, far: impl FnOnce() -> bool) -> bool {
        !self.lanes.is_empty() && (k_nearest || self.ids.len() <= SCAN_ALWAYS || (self.ids.len() <= SCAN_FAR && far()))
    }

    /// Whether `q` (angles wrapped) lies farther from the root's box than half the box's
    /// diagonal (weighted): there every state is about equally far, and descent would visit
    /// most leaves.
    #[inline]
    fn far<const WRAP: bool>(&self, wrapped: &[f64]) -> bool {
        4.0 * self.box_distance2::<WRAP>(0, wrapped) >= self.diagonal2
    }

    /// The tree's `lanes`, for [`KdTree::search`] by [`LaneView::scan`].
    #[inline]
    fn lane_view(&self) -> LaneView<'_> {
        LaneView {
            lanes: &self.lanes,
            ids: &self.ids,
            weights: &self.weights,
            lane_periods: &self.lane_periods,
            reach: self.reach,
            stretch: self.stretch,
        }
    }
}

/// States held as weighted f32 coordinates in blocks of [`LANES`] (`dim` rows of [`LANES`]
/// values per block, the last block padded with NaN, which no filter passes): a scanned
/// tree's states or the buffer's.
struct LaneView<'a> {
    lanes: &'a [f32],
    /// The state in each lane, block by block.
    ids: &'a [u32],
    weights: &'a [f64],
    /// Per coordinate: its weighted period in f32, infinite for a coordinate that is no angle.
    lane_periods: &'a [f32],
    /// Largest weighted magnitude of a coordinate or a period (bounds the f32 rounding).
    reach: f64,
    /// How far the space's distance may exceed the weighted Euclidean one.
    stretch: f64,
}

impl LaneView<'_> {
    /// Every state's weighted squared distance in f32, eight states per step, as a filter that
    /// passes every state the leaves' own f64 filter would pass (its bound is widened by more
    /// than the f32 rounding of the states, the query and the sums can move a distance); the
    /// space's own distance decides, as in a leaf, so the answers are the descent's to the
    /// last bit. A nearest-state query also filters the first block with its smallest sum of
    /// a live state: that state is at most that far (widened the same way, and times the
    /// stretch of a bounding metric), so the nearest state's own sum lies within that and the
    /// widening. Without that bound every state of the first block would reach the space's
    /// distance while the radius is still infinite; after it, the radius set by the states
    /// offered prunes as well.
    fn scan<S: Space, C: Collector, const WRAP: bool>(
        &self,
        space: &S,
        index: &NearestNeighbors,
        q: &[f64],
        wrapped: &[f64],
        c: &mut C,
    ) {
        let dim = self.weights.len();
        let mut query = [0.0f32; KD_MAX_DIM];
        let mut reach = self.reach;
        for ((out, &x), &w) in query.iter_mut().zip(wrapped).zip(self.weights) {
            reach = reach.max((w * x).abs());
            *out = (w * x) as f32;
        }
        // How far f32 rounding can move a weighted distance: per coordinate a few units in
        // the last place of the largest weighted magnitude (state, query, period), over every
        // coordinate; 2⁻¹⁹ is several times what the roundings can add up to. (A query too
        // large for that bound sends every state to the space's distance.)
        let slop = if reach < 1e6 {
            (dim as f64).sqrt() * reach * 2f64.powi(-19) + 1e-12
        } else {
            f64::INFINITY
        };
        let query = &query[..dim];
        let to_f32 = |r: f64| {
            let bound = r * r * (1.0 + 1e-5);
            if bound < f64::from(f32::MAX) {
                bound as f32
            } else {
                f32::INFINITY
            }
        };
        // The nearest-state bound from the smallest sum so far (infinite until one is seen).
        let mut least = f32::INFINITY;
        let mut least_bound = f32::INFINITY;
        // The filter's bound from the collector's radius, which changes only when a state is
        // offered.
        let mut radius_bound = to_f32(c.radius() + SLACK + slop);
        for (block, lanes) in self.lanes.chunks_exact(dim * LANES).enumerate() {
            // One block's weighted squared distances: a sum per state, in coordinate order.
            let mut sum = f32x8::ZERO;
            for ((lane, &x), &period) in lanes.chunks_exact(LANES).zip(query).zip(self.lane_periods) {
                let mut d = (f32x8::splat(x) - f32x8::new(lane.try_into().expect("LANES values"))).abs();
                if WRAP {
                    d = d.min(f32x8::splat(period) - d);
                }
                sum += d * d;
            }
            let mut bound = radius_bound;
            if C::NEAREST && block == 0 {
                // NaN (padding) lanes drop out of `f32::min`.
                let smallest = sum.to_array().into_iter().fold(f32::INFINITY, f32::min);
                // (Only a live state's sum bounds the answer.)
                let live = || {
                    let lane = sum.simd_eq(f32x8::splat(smallest)).to_bitmask().trailing_zeros() as usize;
                    self.ids
                        .get(block * LANES + lane)
                        .is_some_and(|&id| !index.is_removed(id as usize))
                };
                if smallest < least && live() {
                    least = smallest;
                    // That state's distance ≤ stretch·(√(sum·(1 + 10⁻⁵)) + SLACK + slop), and
                    // so is the nearest state's, whose sum (a lower bound of its distance)
                    // then passes this bound.
                    let far = self.stretch * ((f64::from(least) * (1.0 + 1e-5)).sqrt() + SLACK + slop);
                    least_bound = to_f32(far + SLACK + slop);
                }
                bound = bound.min(least_bound);
            }
            let mut pass = sum.simd_le(f32x8::splat(bound)).to_bitmask();
            if pass == 0 {
                continue;
            }
            while pass != 0 {
                let k = block * LANES + pass.trailing_zeros() as usize;
                pass &= pass - 1;
                let Some(&id) = self.ids.get(k) else { break };
                if !index.is_removed(id as usize) {
                    c.offer(space.distance(q, index.state(id as usize)), id);
                }
            }
            radius_bound = to_f32(c.radius() + SLACK + slop);
        }
    }
}

/// The space's weighted Euclidean metric or bound ([`Space::euclidean_bound`]), when an index
/// of `dim`-dimensional states can use it for k-d trees and lanes.
fn weighted_metric<S: Space>(space: &S, dim: usize) -> Option<EuclideanBound<'_>> {
    space.euclidean_bound().filter(|b| dim <= KD_MAX_DIM && b.usable(dim))
}

/// `groups` numbered from 0 in order of first appearance, written into `dense` (left empty
/// when they name one group or none), so that a k-d tree can sum them in an array of
/// [`KD_MAX_DIM`] entries.
fn dense_groups_into(groups: &[u8], dense: &mut Vec<u8>) {
    // At most 256 groups (`u8`); a stack array keeps a rebuild from allocating.
    let mut seen = [0u8; 256];
    let mut count = 0usize;
    dense.clear();
    for g in groups {
        let k = match seen[..count].iter().position(|s| s == g) {
            Some(k) => k,
            None => {
                seen[count] = *g;
                count += 1;
                count - 1
            }
        };
        dense.push(k as u8);
    }
    if count <= 1 {
        dense.clear();
    }
}

/// `q` with the coordinates that `wraps` marks wrapped into `(−π, π]` (the first `q.len()`
/// entries).
#[inline(always)]
fn wrap_query(q: &[f64], wraps: &[bool]) -> [f64; KD_MAX_DIM] {
    let mut wrapped = [0.0f64; KD_MAX_DIM];
    for ((w, &x), &wraps) in wrapped.iter_mut().zip(q).zip(wraps) {
        *w = if wraps { wrap_angle(x) } else { x };
    }
    wrapped
}

/// The linear buffer's states as lanes ([`LaneView`]), written by the queries, which know the
/// space's weights.
#[derive(Clone, Debug, Default)]
struct BufferLanes {
    /// Room for [`BUFFER`] states.
    lanes: Vec<f32>,
    weights: Vec<f64>,
    /// Which coordinates are angles (empty: none); their lanes hold them wrapped into
    /// `(−π, π]`.
    wraps: Vec<bool>,
    lane_periods: Vec<f32>,
    reach: f64,
    /// The metric's stretch ([`EuclideanBound`](crate::space::EuclideanBound)).
    stretch: f64,
    /// Buffer entries written so far (0 after a flush: the next query starts anew).
    written: usize,
    /// Whether the space has a weighted metric and every written state is small enough for
    /// the lanes' rounding bound; else the buffer is searched by the space's distance alone.
    usable: bool,
}

impl BufferLanes {
    /// Reads the space's metric for a new buffer, as [`NearestNeighbors::flush`] does for a
    /// tree, and clears the lanes.
    fn start<S: Space>(&mut self, space: &S, dim: usize) {
        self.weights.clear();
        self.wraps.clear();
        self.lane_periods.clear();
        self.reach = 0.0;
        self.usable = false;
        let Some(bound) = weighted_metric(space, dim) else {
            return;
        };
        self.stretch = bound.stretch;
        self.weights.extend_from_slice(bound.weights);
        if bound.wraps.contains(&true) {
            self.wraps.extend_from_slice(bound.wraps);
        }
        for (axis, &w) in bound.weights.iter().enumerate() {
            if self.wraps.get(axis) == Some(&true) {
                self.reach = self.reach.max(w * TAU);
                self.lane_periods.push((w * TAU) as f32);
            } else {
                self.lane_periods.push(f32::INFINITY);
            }
        }
        self.lanes.clear();
        self.lanes.resize(BUFFER.div_ceil(LANES) * dim * LANES, f32::NAN);
        self.usable = self.reach.is_finite() && self.reach < 1e6;
    }

    /// Writes the next buffer entry's lanes.
    fn push(&mut self, q: &[f64]) {
        let (k, dim) = (self.written, self.weights.len());
        self.written += 1;
        if !self.usable {
            return;
        }
        let block = &mut self.lanes[(k / LANES) * dim * LANES..][..dim * LANES];
        for (axis, (&x, &w)) in q.iter().zip(&self.weights).enumerate() {
            let x = if self.wraps.get(axis) == Some(&true) {
                wrap_angle(x)
            } else {
                x
            };
            let v = w * x;
            self.reach = self.reach.max(v.abs());
            block[axis * LANES + k % LANES] = v as f32;
        }
        self.usable = self.reach < 1e6;
    }
}

/// The fixed arguments of one k-d tree query.
struct KdSearch<'a, S> {
    tree: &'a KdTree,
    space: &'a S,
    index: &'a NearestNeighbors,
    q: &'a [f64],
    /// `q` with its angles wrapped into `(−π, π]`.
    wrapped: &'a [f64],
}

impl<S: Space> KdSearch<'_, S> {
    /// Visits node `n`, whose cell lies `cell2` (weighted, squared: Arya & Mount's incremental
    /// distance, the sum of the squared `offsets` per coordinate) and whose box or an
    /// ancestor's lies `bound2 ≥ cell2` from the query. `WRAP`: the tree has angles
    /// (`tree.wraps` is not empty).
    fn visit<C: Collector, const WRAP: bool>(
        &mut self,
        n: u32,
        cell2: f64,
        bound2: f64,
        offsets: &mut [f64; KD_MAX_DIM],
        c: &mut C,
    ) {
        let r = c.radius() + SLACK;
        if bound2 > r * r * (1.0 + 1e-12) {
            return;
        }
        match self.tree.nodes[n as usize] {
            KdNode::Leaf { start, end } => {
                let (tree, dim) = (self.tree, self.tree.weights.len());
                let (start, end) = (start as usize, end as usize);
                for (k, &id) in tree.ids[start..end].iter().enumerate() {
                    // The weighted squared distance from the leaf's own copy of the state
                    // filters; the space's own distance decides (so answers are the space's
                    // to the last bit).
                    let p = &tree.points[(start + k) * dim..(start + k + 1) * dim];
                    let mut d2 = 0.0;
                    if !WRAP {
                        for ((&x, &y), &w) in self.wrapped.iter().zip(p).zip(&tree.weights) {
                            let d = w * (x - y);
                            d2 += d * d;
                        }
                    } else {
                        // Both in (−π, π]: the short way round is the shorter of the two.
                        for (((&x, &y), &w), &period) in
                            self.wrapped.iter().zip(p).zip(&tree.weights).zip(&tree.periods)
                        {
                            let d = (x - y).abs();
                            let d = w * d.min(period - d);
                            d2 += d * d;
                        }
                    }
                    let r = c.radius() + SLACK;
                    if d2 <= r * r * (1.0 + 1e-9) && !self.index.is_removed(id as usize) {
                        c.offer(self.space.distance(self.q, self.index.state(id as usize)), id);
                    }
                }
            }
            KdNode::Inner { axis, split, low, high } => {
                let axis = axis as usize;
                let x = self.wrapped[axis];
                let diff = x - split;
                let (near, far) = if diff <= 0.0 { (low, high) } else { (high, low) };
                self.visit::<C, WRAP>(near, cell2, bound2, offsets, c);
                let old = offsets[axis];
                let new = if WRAP && self.tree.wraps[axis] {
                    // The far cell lies within [split, π] (or [−π, split]): reached either
                    // across the split or the other way round, through ±π. Both bound the
                    // distance to the far cell, and so does the offset to its parent.
                    let around = if diff <= 0.0 { x + PI } else { PI - x };
                    (self.tree.weights[axis] * diff.abs().min(around.max(0.0))).max(old)
                } else {
                    self.tree.weights[axis] * diff.abs()
                };
                let far_cell2 = cell2 - old * old + new * new;
                let r = c.radius() + SLACK;
                if far_cell2.max(bound2) > r * r * (1.0 + 1e-12) {
                    return;
                }
                // The split planes leave the far cell unbounded along the axes not split yet:
                // its box is the tighter bound when the query is far from every state.
                let far2 = far_cell2.max(self.tree.box_distance2::<WRAP>(far, self.wrapped));
                offsets[axis] = new;
                self.visit::<C, WRAP>(far, far_cell2, far2, offsets, c);
                offsets[axis] = old;
            }
        }
    }
}
