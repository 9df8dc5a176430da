//! [`LazyPrm`]: the lazy probabilistic roadmap (Bohlin & Kavraki 2000), OMPL's `LazyPRM`.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::escape::{Escape, Grows, Helper, try_step};
use crate::motion::MotionValidator;
use crate::nn::NearestNeighbors;
use crate::planner::{Budget, Path, PlanRequest, Planner, Run, Solution, resolve_range, valid_goals};
use crate::space::{Space, pull_towards};
use crate::validity::StateValidator;

/// Settings of [`LazyPrm`], serde-derivable so a TOML file can set them; fields left out
/// keep their defaults.
///
/// ```
/// use hearth_planning::lazy_prm::LazyPrmSettings;
///
/// let settings: LazyPrmSettings = serde_json::from_str(r#"{ "k": 6, "range": 0.5 }"#).unwrap();
/// assert_eq!((settings.k, settings.range), (6, Some(0.5)));
/// assert_eq!(settings.batch, LazyPrmSettings::default().batch);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LazyPrmSettings {
    /// Each new vertex is joined to at most this many nearest vertices (default 10).
    pub k: usize,
    /// Longest roadmap edge; `None` is [`default_range`](crate::planner::default_range)
    /// (0.2 × the space's extent, OMPL's `maxDistance` default). An edge length that is not
    /// positive and finite, or shorter than
    /// [`finest_resolution`](crate::motion::finest_resolution), is [`PlanError::BadInput`].
    pub range: Option<f64>,
    /// Fewest samples added each time the roadmap has no candidate path (default 50); the
    /// roadmap grows by at least a quarter of its size, so growth is geometric.
    pub batch: usize,
    /// Share of each batch sampled near where the roadmap failed (default 0: off): around both
    /// ends of edges found invalid — after the node enhancement step of Bohlin & Kavraki's
    /// Lazy PRM, which puts samples in the narrow places a uniform batch rarely hits. The
    /// growth of a wedged query end ([`LazyPrmSettings::tree_share`]) now does that job for a
    /// goal between shelf boards, and better: on MotionBenchMaker, with enhancement off, the
    /// Fetch solved 275 of its 310 bookshelf and cage problems within 1 s against 217 with a
    /// share of 0.5, and the Panda 559/559 against 558 (`docs/planning-log.md`, twenty-third
    /// round). A share above 0 still helps where no query end is wedged and the narrow place
    /// lies elsewhere.
    pub enhance: f64,
    /// Samples near a failure lie within this distance of it; `None` is 0.4 × `range`.
    pub enhance_radius: Option<f64>,
    /// Weight of the A* heuristic (default 1.5, at least 1; the heuristic is each vertex's
    /// roadmap distance to the search's far end, from a Dijkstra search, lowered over the
    /// edges added since; the search runs from the start, or from the goals while only their
    /// part of the roadmap is wedged, see [`LazyPrmSettings::tree_share`]):
    /// candidate paths are at most this many times longer than the roadmap's shortest, and
    /// each search expands fewer vertices.
    /// A search runs after every candidate that fails its checks, so on large roadmaps the
    /// searches are a large share of the time; 1.5 solved 1–3 % more MotionBenchMaker
    /// bookshelf problems within 1 s than the exact search (`docs/planning-log.md`).
    pub search_weight: f64,
    /// Share of each batch spent growing a *wedged* query end (default 0.9; 0 turns it off):
    /// when no candidate path is left and the start's or the goals' part of the roadmap holds
    /// at most an eighth of its vertices, that part grows like an RRT tree — steps of
    /// `tree_step` × `range` from its vertex nearest a uniform sample, each checked at once and
    /// kept as a valid edge, each new vertex joined lazily to its nearest roadmap vertices. A
    /// goal between shelf boards, whose long lazy edges all fail, otherwise gets about `k`
    /// new edge attempts per batch however large the batch.
    pub tree_share: f64,
    /// The share of each batch spent growing a wedged query end once the roadmap holds
    /// [`LazyPrmSettings::late_roadmap`] vertices (default 0.99, in [0, 1]; equal to
    /// `tree_share` to keep one share; unused when `tree_share` is 0, which turns the growth
    /// off). By then a wedged end's way out is what is missing, and each uniform sample added
    /// costs a neighbour query over the whole roadmap (about half of a lost plan's time on the
    /// Fetch's bookshelves). On MotionBenchMaker's Fetch bookshelf_small, bookshelf_thin and
    /// cage, seeds 0–2, 1 s: 696 of 720 solved against 689 with 0.9 throughout
    /// (`docs/planning-log.md`, forty-second round).
    pub late_tree_share: f64,
    /// Roadmap size from which [`LazyPrmSettings::late_tree_share`] applies (default 4,096).
    pub late_roadmap: usize,
    /// Step of the wedged-end growth as a fraction of `range` (default 0.25).
    pub tree_step: f64,
    /// Whether a free growth step of a wedged end goes on towards the same sample, step after
    /// step, until one is blocked or the sample is reached (default false): RRT-Connect's
    /// greedy extension, where `false` takes one step a turn, as RRT does. Each state reached
    /// joins the roadmap like the first. It pays where wedged ends are common and plans long:
    /// on MotionBenchMaker's Fetch bookshelf and cage families, seeds 0–5, 1 s, 1,815 of 1,866
    /// plans solved against 1,810, cage 560 against 555 with per-plan times 0.84× in the
    /// geometric mean (bookshelf_small and bookshelf_tall 0.94–0.95×, bookshelf_thin 1.05×).
    /// It costs where they are short: the Panda's whole set plans 1.5× slower (geometric mean)
    /// with it, as the extensions fill a small roadmap with vertices; applied only once the
    /// roadmap holds [`LazyPrmSettings::late_roadmap`] vertices it gains nothing on the Fetch
    /// (`docs/planning-log.md`, forty-fifth round).
    ///
    /// ```
    /// use hearth_planning::lazy_prm::{LazyPrm, LazyPrmSettings};
    ///
    /// let prm = LazyPrm::new(LazyPrmSettings { tree_connect: true, ..LazyPrmSettings::default() });
    /// assert!(prm.settings().tree_connect && !LazyPrmSettings::default().tree_connect);
    /// ```
    pub tree_connect: bool,
    /// The pocket escape for a wedged query end ([`Escape`], as [`BiRrt`](crate::BiRrt)'s):
    /// once that end's growth turns add fewer than one vertex per `stuck_ratio` turns, a share
    /// of them goes to a helper tree of short steps, steered through the free directions its
    /// probes find, whose branch joins the roadmap as valid edges once a longer step from it
    /// is free. Step lengths are fractions of the growth's step (`tree_step` × `range`).
    /// `None` turns it off.
    pub escape: Option<Escape>,
}

impl Default for LazyPrmSettings {
    fn default() -> Self {
        Self {
            k: 10,
            range: None,
            batch: 50,
            enhance: 0.0,
            enhance_radius: None,
            search_weight: 1.5,
            tree_share: 0.9,
            late_tree_share: 0.99,
            late_roadmap: 4096,
            tree_step: 0.25,
            tree_connect: false,
            escape: Some(Escape::default()),
        }
    }
}

/// Lazy PRM: a roadmap of valid samples, each joined to its `k` nearest neighbours within
/// `range` *without* checking the edge. A query searches the roadmap with A*, then checks only
/// the candidate path's unchecked edges with the motion validator; the invalid ones are removed
/// and the search repeated. When no candidate is left, the roadmap grows by a batch of samples
/// (uniform by default; [`LazyPrmSettings::enhance`] puts a share of them near the ends of
/// edges that failed: node enhancement), and the start and goal vertices are joined to their
/// new nearest neighbours, while the budget lasts.
/// A query end that stays cut off in a small part of a large roadmap (a grasp between shelf
/// boards) is *wedged*: most of each batch then grows that part like an RRT tree, in steps
/// checked at once ([`LazyPrmSettings::tree_share`]), until its new vertices' lazy edges reach
/// the rest of the roadmap. A part that barely grows even so (no step of that length leaves
/// its pocket) gets [`BiRrt`](crate::BiRrt)'s pocket escape: a helper tree of shorter steps
/// ([`LazyPrmSettings::escape`]). While the goals' part alone is wedged, the graph search runs
/// from the goals to the start, so that the candidates fail near where it begins; a candidate
/// whose search begins in a wedged part ends at its first failing edge.
///
/// Vertices are checked when sampled, unlike Bohlin & Kavraki's fully lazy original: one
/// state check costs about a microsecond here, far less than the neighbour query and the
/// repeated graph searches an invalid vertex would cost on the roadmap (on MotionBenchMaker's
/// Panda problems this raised success within 1 s from 91.7 to 97.6 % on table_pick and from
/// 73.7 to 92.6 % on bookshelf_thin, `docs/planning-log.md`).
///
/// The roadmap (and what was found valid on it) persists across [`Planner::plan`] calls, so
/// later queries in the same scene are cheaper. **It assumes a static scene and the same space
/// and validator for every query**: call [`LazyPrm::clear`] when the obstacles, the robot or
/// the space change (a query in a space of another dimension clears it by itself).
///
/// One iteration is one sample added or one candidate path checked.
///
/// ```
/// use hearth_planning::lazy_prm::LazyPrm;
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// struct Wall(u64);
/// impl StateValidator for Wall {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; (q[0] - 0.5).abs() > 0.05 || q[1] > 0.8 }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
/// let mut motion = MotionValidator::new(space, 0.01);
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let mut prm = LazyPrm::default();
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]));
/// let first = prm.plan(&mut motion, &mut Wall(0), &request, &Budget::iterations(10_000), &mut rng).unwrap();
/// // The roadmap is reused: a second query in the same scene needs fewer new samples.
/// let request = PlanRequest::new(vec![0.1, 0.2], Goal::Config(vec![0.9, 0.2]));
/// let second = prm.plan(&mut motion, &mut Wall(0), &request, &Budget::iterations(10_000), &mut rng).unwrap();
/// assert!(second.stats.iterations <= first.stats.iterations);
/// assert!(prm.roadmap_size() >= first.stats.tree_sizes[0]);
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct LazyPrm {
    settings: LazyPrmSettings,
    roadmap: Option<Roadmap>,
}

#[derive(Clone, Debug)]
struct Roadmap {
    /// The vertices, all valid states.
    nn: NearestNeighbors,
    /// Per vertex: its neighbours and the length of the edge to each.
    adjacency: Vec<Vec<(u32, f64)>>,
    /// Edges checked valid, as (lower id, higher id).
    valid_edges: HashSet<(u32, u32)>,
    /// Edges found invalid (removed, never joined again).
    invalid_edges: HashSet<(u32, u32)>,
    /// Where the roadmap failed (both ends of invalid edges), the last [`MAX_FAILURES`] of
    /// them, flat: the centres of node enhancement.
    failures: Vec<f64>,
    /// Next slot of `failures` to overwrite once it is full.
    next_failure: usize,
    /// The graph search's arrays.
    scratch: SearchScratch,
    /// Each vertex's roadmap distance to the nearest of the graph search's targets (infinite
    /// when none is joined to it), computed by one search from them and lowered over the edges
    /// added since ([`Roadmap::update_to_target`]): the search's heuristic. Removing an edge
    /// can only lengthen distances, so these stay a consistent lower bound.
    to_target: Vec<f64>,
    /// Edges added since `to_target` was computed (each once, as its two ends and length):
    /// what [`Roadmap::update_to_target`] lowers the distances over.
    fresh: Vec<(u32, u32, f64)>,
    /// `edges_added` and the targets when `to_target` was computed.
    to_target_of: Option<(u64, Vec<u32>)>,
    /// Edges added to the roadmap so far.
    edges_added: u64,
    /// Neighbour ids of the vertex being added or connected (reused, so adding allocates only
    /// its edges and connecting nothing).
    near: Vec<usize>,
    /// A copy of the connected vertex's state (reused).
    query: Vec<f64>,
    /// The start's and the goals' parts of the roadmap while they are wedged (empty when not).
    wedged: [Vec<u32>; 2],
    /// An index of each wedged part's states (its ids are positions in `wedged[side]`).
    wedged_nn: [NearestNeighbors; 2],
    /// Breadth-first search stamps: a vertex was reached in the walk numbered `walk`.
    seen: Vec<u32>,
    walk: u32,
}

/// Most steps one greedy extension of a wedged end takes ([`LazyPrmSettings::tree_connect`]).
const MAX_CONNECT_STEPS: usize = 1024;

/// How many failure points node enhancement remembers.
const MAX_FAILURES: usize = 512;

/// A wedged query end's part of the roadmap, as what an escape helper's branch joins.
struct WedgedEnd<'a> {
    roadmap: &'a mut Roadmap,
    side: usize,
    k: usize,
    range: f64,
}

impl Grows for WedgedEnd<'_> {
    fn grow<S: Space>(&mut self, space: &S, q: &[f64], parent: usize) -> usize {
        self.roadmap
            .add_reached(space, self.side, parent as u32, q, self.k, self.range) as usize
    }
}

impl LazyPrm {
    /// A planner with these settings and an empty roadmap.
    ///
    /// ```
    /// use hearth_planning::lazy_prm::{LazyPrm, LazyPrmSettings};
    ///
    /// let prm = LazyPrm::new(LazyPrmSettings { k: 6, ..LazyPrmSettings::default() });
    /// assert_eq!(prm.settings().k, 6);
    /// assert_eq!(prm.roadmap_size(), 0);
    /// ```
    pub fn new(settings: LazyPrmSettings) -> Self {
        Self {
            settings,
            roadmap: None,
        }
    }

    /// The settings.
    ///
    /// ```
    /// use hearth_planning::lazy_prm::{LazyPrm, LazyPrmSettings};
    ///
    /// assert_eq!(LazyPrm::default().settings(), &LazyPrmSettings::default());
    /// ```
    pub fn settings(&self) -> &LazyPrmSettings {
        &self.settings
    }

    /// Forgets the roadmap (call it when the scene changes); the settings stay.
    ///
    /// ```
    /// # use hearth_planning::lazy_prm::LazyPrm;
    /// # use hearth_planning::motion::MotionValidator;
    /// # use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
    /// # use hearth_planning::space::JointSpace;
    /// # use hearth_planning::validity::StateValidator;
    /// # use rand::SeedableRng;
    /// # struct Free(u64);
    /// # impl StateValidator for Free {
    /// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
    /// #     fn checks(&self) -> u64 { self.0 }
    /// # }
    /// // `Free` is a validator that accepts every state.
    /// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
    /// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let mut prm = LazyPrm::default();
    /// prm.plan(&mut motion, &mut Free(0), &request, &Budget::iterations(1_000), &mut rng).unwrap();
    /// assert!(prm.roadmap_size() > 0);
    /// prm.clear();
    /// assert_eq!(prm.roadmap_size(), 0);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn clear(&mut self) {
        self.roadmap = None;
    }

    /// Number of roadmap vertices (0 before the first query and after [`LazyPrm::clear`]).
    ///
    /// ```
    /// # use hearth_planning::lazy_prm::LazyPrm;
    /// # use hearth_planning::motion::MotionValidator;
    /// # use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
    /// # use hearth_planning::space::JointSpace;
    /// # use hearth_planning::validity::StateValidator;
    /// # use rand::SeedableRng;
    /// # struct Free(u64);
    /// # impl StateValidator for Free {
    /// #     fn is_valid(&mut self, _: &[f64]) -> bool { self.0 += 1; true }
    /// #     fn checks(&self) -> u64 { self.0 }
    /// # }
    /// // `Free` is a validator that accepts every state.
    /// let mut motion = MotionValidator::new(JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?, 0.01);
    /// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.9]));
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let mut prm = LazyPrm::default();
    /// assert_eq!(prm.roadmap_size(), 0);
    /// let budget = Budget::iterations(1_000);
    /// let solution = prm.plan(&mut motion, &mut Free(0), &request, &budget, &mut rng).unwrap();
    /// // The start and the goal are roadmap vertices too.
    /// assert!(prm.roadmap_size() >= solution.path.states.len());
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn roadmap_size(&self) -> usize {
        self.roadmap.as_ref().map_or(0, |r| r.nn.len())
    }
}

fn edge(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Roadmap {
    fn new(dim: usize) -> Self {
        Self {
            nn: NearestNeighbors::new(dim),
            adjacency: Vec::new(),
            valid_edges: HashSet::new(),
            invalid_edges: HashSet::new(),
            failures: Vec::new(),
            next_failure: 0,
            scratch: SearchScratch::default(),
            to_target: Vec::new(),
            to_target_of: None,
            fresh: Vec::new(),
            edges_added: 0,
            near: Vec::new(),
            query: Vec::new(),
            wedged: [Vec::new(), Vec::new()],
            wedged_nn: [NearestNeighbors::new(dim), NearestNeighbors::new(dim)],
            seen: Vec::new(),
            walk: 0,
        }
    }

    /// Collects into `wedged[side]` the vertices joined to `from` (by edges not found
    /// invalid), and keeps them only if there are at most `limit`: whether they were few.
    fn wedged_part(&mut self, side: usize, from: &[u32], limit: usize) -> bool {
        self.walk = self.walk.wrapping_add(1);
        if self.walk == 0 {
            self.seen.fill(0);
            self.walk = 1;
        }
        self.seen.resize(self.adjacency.len(), 0);
        let part = &mut self.wedged[side];
        part.clear();
        for &v in from {
            if self.seen[v as usize] != self.walk {
                self.seen[v as usize] = self.walk;
                part.push(v);
            }
        }
        let mut next = 0;
        while next < part.len() && part.len() <= limit {
            for &(u, _) in &self.adjacency[part[next] as usize] {
                if self.seen[u as usize] != self.walk {
                    self.seen[u as usize] = self.walk;
                    part.push(u);
                }
            }
            next += 1;
        }
        if part.len() > limit {
            part.clear();
        }
        let index = &mut self.wedged_nn[side];
        index.clear();
        for &v in part.iter() {
            index.insert(self.nn.state(v as usize));
        }
        !part.is_empty()
    }

    /// The vertex of `wedged[side]` nearest `target` (the part is not empty; the lowest
    /// position among equally near ones).
    fn nearest_wedged<S: Space>(&mut self, space: &S, side: usize, target: &[f64]) -> u32 {
        let at = self.wedged_nn[side]
            .nearest(space, target)
            .expect("wedged parts are not empty");
        self.wedged[side][at]
    }

    /// Adds the state `q`, reached from vertex `from` by a motion found valid, with that edge
    /// marked valid, to the roadmap (or finds an equal vertex) and to `wedged[side]`, and
    /// returns its vertex.
    fn add_reached<S: Space>(&mut self, space: &S, side: usize, from: u32, q: &[f64], k: usize, range: f64) -> u32 {
        let v = self.add(space, q, k, range);
        if v == from {
            return v;
        }
        if !self.adjacency[from as usize].iter().any(|&(u, _)| u == v) {
            let d = space.distance(self.nn.state(from as usize), q);
            self.adjacency[from as usize].push((v, d));
            self.adjacency[v as usize].push((from, d));
            self.fresh.push((from, v, d));
            self.edges_added += 1;
        }
        self.valid_edges.insert(edge(from, v));
        if !self.wedged[side].contains(&v) {
            self.wedged[side].push(v);
            self.wedged_nn[side].insert(self.nn.state(v as usize));
        }
        v
    }

    /// Remembers vertex `v`'s state as a place where the roadmap failed.
    fn note_failure_of(&mut self, v: u32) {
        let q = self.nn.state(v as usize);
        if self.failures.len() < MAX_FAILURES * q.len() {
            self.failures.extend_from_slice(q);
        } else {
            let at = self.next_failure * q.len();
            self.failures[at..at + q.len()].copy_from_slice(q);
            self.next_failure = (self.next_failure + 1) % MAX_FAILURES;
        }
    }

    /// Adds `q` (or finds an equal vertex) and joins it to its `k` nearest vertices within
    /// `range` (one neighbour query for both).
    fn add<S: Space>(&mut self, space: &S, q: &[f64], k: usize, range: f64) -> u32 {
        let mut near = std::mem::take(&mut self.near);
        self.nn.k_nearest_into(space, q, k, &mut near);
        if let Some(&i) = near.first()
            && space.distance(self.nn.state(i), q) == 0.0
        {
            self.near = near;
            return i as u32;
        }
        let v = self.nn.insert(q) as u32;
        // Room for the edges of later vertices too (about as many again), so that a list is
        // allocated once rather than grown as the roadmap fills in around its vertex.
        let mut adjacent = Vec::with_capacity(2 * near.len());
        for &u in &near {
            let d = space.distance(self.nn.state(u), q);
            if d <= range {
                adjacent.push((u as u32, d));
                self.adjacency[u].push((v, d));
            }
        }
        self.edges_added += adjacent.len() as u64;
        self.fresh.extend(adjacent.iter().map(|&(u, d)| (u, v, d)));
        self.adjacency.push(adjacent);
        self.near = near;
        v
    }

    /// Joins `v` to those of its `k` nearest vertices within `range` that it is not joined to
    /// yet (and whose edge was not found invalid).
    fn connect<S: Space>(&mut self, space: &S, v: u32, k: usize, range: f64) {
        let (mut q, mut near) = (std::mem::take(&mut self.query), std::mem::take(&mut self.near));
        q.clear();
        q.extend_from_slice(self.nn.state(v as usize));
        self.nn.k_nearest_into(space, &q, k.saturating_add(1), &mut near);
        for &u in &near {
            let u = u as u32;
            if u == v
                || self.adjacency[v as usize].iter().any(|&(w, _)| w == u)
                || self.invalid_edges.contains(&edge(u, v))
            {
                continue;
            }
            let d = space.distance(self.nn.state(u as usize), &q);
            if d <= range {
                self.adjacency[v as usize].push((u, d));
                self.adjacency[u as usize].push((v, d));
                self.fresh.push((u, v, d));
                self.edges_added += 1;
            }
        }
        (self.query, self.near) = (q, near);
    }

    /// Removes an edge found invalid; both its ends become centres of node enhancement (a
    /// vertex whose edges keep failing sits in a narrow place that needs nearer neighbours).
    fn remove_edge(&mut self, a: u32, b: u32) {
        for v in [a, b] {
            self.note_failure_of(v);
        }
        self.invalid_edges.insert(edge(a, b));
        self.adjacency[a as usize].retain(|&(w, _)| w != b);
        self.adjacency[b as usize].retain(|&(w, _)| w != a);
    }

    /// Whether `to_target` holds the distances to `targets` with every edge added so far.
    fn to_target_current(&self, targets: &[u32]) -> bool {
        self.to_target_of
            .as_ref()
            .is_some_and(|(added, t)| *added == self.edges_added && t == targets)
    }

    /// Fills `to_target` with every vertex's roadmap distance to the nearest of `targets`
    /// (Dijkstra from them), unless no edge was added since it was last computed for them.
    /// For the same targets and fewer new edges than vertices, the distances are lowered over
    /// the new edges instead ([`Roadmap::lower_to_target`]).
    fn update_to_target(&mut self, targets: &[u32]) {
        if self.to_target_current(targets) {
            return;
        }
        let same_targets = self.to_target_of.as_ref().is_some_and(|(_, t)| t == targets);
        if same_targets && self.fresh.len() < self.adjacency.len() {
            self.lower_to_target();
        } else {
            let Self {
                adjacency,
                scratch,
                to_target,
                ..
            } = self;
            to_target.clear();
            to_target.resize(adjacency.len(), f64::INFINITY);
            scratch.best_first(
                adjacency,
                targets,
                |_, c| Some(c),
                |v, c| {
                    to_target[v as usize] = c;
                    false
                },
            );
        }
        self.fresh.clear();
        self.to_target_of = Some((self.edges_added, targets.to_vec()));
    }

    /// Lowers `to_target` over the edges added since it was computed: each new edge that
    /// shortens the way to the targets for one of its ends, and from there every neighbour it
    /// shortens in turn, in order of distance (Dijkstra from the changed vertices). Distances
    /// only fall, and only along roadmap edges, so what they held stays true: a consistent
    /// lower bound on each vertex's distance, 0 at the targets (removed edges can only
    /// lengthen the true distances). Vertices added since start unreached.
    fn lower_to_target(&mut self) {
        let Self {
            adjacency,
            scratch,
            to_target,
            fresh,
            ..
        } = self;
        to_target.resize(adjacency.len(), f64::INFINITY);
        let open = &mut scratch.open;
        open.clear();
        for &(a, b, d) in fresh.iter() {
            for (x, y) in [(a, b), (b, a)] {
                let c = to_target[x as usize] + d;
                if c < to_target[y as usize] {
                    to_target[y as usize] = c;
                    open.push(Reverse((order_key(c), y)));
                }
            }
        }
        while let Some(Reverse((key, v))) = open.pop() {
            let cv = to_target[v as usize];
            // (A vertex lowered again after it was queued is handled at its lower entry.)
            if order_key(cv) != key {
                continue;
            }
            for &(u, d) in &adjacency[v as usize] {
                let c = cv + d;
                if c < to_target[u as usize] {
                    to_target[u as usize] = c;
                    open.push(Reverse((order_key(c), u)));
                }
            }
        }
    }

    /// A roadmap path from one of `sources` to one of `targets`, at most `weight` times longer
    /// than the shortest, or `None` (weighted A*). The heuristic is each vertex's distance to
    /// the targets over every edge the roadmap has had since they were last computed afresh
    /// ([`Roadmap::update_to_target`]): exact until an edge fails, a lower bound after, and
    /// infinite where no target was ever reachable, so a search from sources that were always
    /// cut off from the targets (a wedged goal's part) ends at once.
    fn search(&mut self, sources: &[u32], targets: &[u32], weight: f64) -> Option<Vec<u32>> {
        self.update_to_target(targets);
        let Self {
            adjacency,
            scratch,
            to_target,
            ..
        } = self;
        // A vertex added since the distances were computed has no edge yet (any edge added
        // would have brought a new computation), so no target is joined to it.
        let h = |v: u32| to_target.get(v as usize).copied().unwrap_or(f64::INFINITY);
        if sources.iter().all(|&v| h(v).is_infinite()) {
            return None;
        }
        let priority = |u: u32, c: f64| {
            let hu = h(u);
            hu.is_finite().then_some(c + weight * hu)
        };
        let reached = scratch.best_first(adjacency, sources, priority, |v, _| targets.contains(&v))?;
        let mut path = vec![reached];
        let mut u = reached;
        while scratch.parent[u as usize] != u32::MAX {
            u = scratch.parent[u as usize];
            path.push(u);
        }
        path.reverse();
        Some(path)
    }
}

/// The A* search's per-vertex arrays, kept across searches: a vertex's entries count only when
/// stamped with the current search's number, so a search does not clear (or allocate) arrays
/// the size of the roadmap, only touches the vertices it reaches.
#[derive(Clone, Debug, Default)]
struct SearchScratch {
    search: u32,
    /// The search in which the vertex's `cost` and `parent` were set.
    reached: Vec<u32>,
    /// The search in which the vertex was closed.
    closed: Vec<u32>,
    cost: Vec<f64>,
    parent: Vec<u32>,
    open: BinaryHeap<Reverse<(i64, u32)>>,
}

impl SearchScratch {
    /// Best-first search over `adjacency` (neighbours and edge lengths) from `sources` at
    /// cost 0: each vertex reached at cost `c` is queued at `priority(vertex, c)`, or skipped
    /// when that is `None`; vertices are closed in priority order, each handed to `closed`
    /// with its cost, until `closed` answers true (that vertex is returned) or none is left.
    /// Dijkstra with `priority` = the cost, A* with the cost plus a heuristic.
    fn best_first(
        &mut self,
        adjacency: &[Vec<(u32, f64)>],
        sources: &[u32],
        priority: impl Fn(u32, f64) -> Option<f64>,
        mut closed: impl FnMut(u32, f64) -> bool,
    ) -> Option<u32> {
        self.begin(adjacency.len());
        for &v in sources {
            self.improve(v, 0.0, u32::MAX);
            self.open.push(Reverse((order_key(0.0), v)));
        }
        while let Some(Reverse((_, v))) = self.open.pop() {
            if !self.close(v) {
                continue;
            }
            let cv = self.cost(v);
            if closed(v, cv) {
                return Some(v);
            }
            for &(u, d) in &adjacency[v as usize] {
                if self.is_closed(u) {
                    continue;
                }
                let c = cv + d;
                if c < self.cost(u)
                    && let Some(key) = priority(u, c)
                {
                    self.improve(u, c, v);
                    self.open.push(Reverse((order_key(key), u)));
                }
            }
        }
        None
    }

    /// Starts a search over `n` vertices.
    fn begin(&mut self, n: usize) {
        self.search = self.search.wrapping_add(1);
        if self.search == 0 {
            // Stamps of 2^32 searches ago would read as current: clear them once.
            self.reached.fill(0);
            self.closed.fill(0);
            self.search = 1;
        }
        self.reached.resize(n, 0);
        self.closed.resize(n, 0);
        self.cost.resize(n, 0.0);
        self.parent.resize(n, u32::MAX);
        self.open.clear();
    }

    fn cost(&self, v: u32) -> f64 {
        if self.reached[v as usize] == self.search {
            self.cost[v as usize]
        } else {
            f64::INFINITY
        }
    }

    fn improve(&mut self, v: u32, cost: f64, parent: u32) {
        self.reached[v as usize] = self.search;
        self.cost[v as usize] = cost;
        self.parent[v as usize] = parent;
    }

    fn is_closed(&self, v: u32) -> bool {
        self.closed[v as usize] == self.search
    }

    /// Closes `v`; false when it already was.
    fn close(&mut self, v: u32) -> bool {
        if self.is_closed(v) {
            return false;
        }
        self.closed[v as usize] = self.search;
        true
    }
}

/// An `f64` as an integer with the order of [`f64::total_cmp`] (the transform it applies at
/// each comparison, applied once when a vertex is queued), for the A* queue.
#[inline]
fn order_key(x: f64) -> i64 {
    let bits = x.to_bits() as i64;
    bits ^ (((bits >> 63) as u64) >> 1) as i64
}

impl<S: Space> Planner<S> for LazyPrm {
    fn plan<V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<Solution, PlanError> {
        let k = self.settings.k;
        if k == 0 {
            return Err(PlanError::BadInput("k is 0; LazyPRM needs k ≥ 1".to_owned()));
        }
        let mut run = Run::start(budget, motion, validator)?;
        let space = motion.space();
        let range = resolve_range(space, self.settings.range, 1.0)?;
        let enhance = self.settings.enhance;
        if !(0.0..=1.0).contains(&enhance) {
            return Err(PlanError::BadInput(format!(
                "enhance is {enhance}; it must be in [0, 1]"
            )));
        }
        let enhance_radius = match self.settings.enhance_radius {
            None => 0.4 * range,
            Some(r) if r.is_finite() && r > 0.0 => r,
            Some(r) => {
                return Err(PlanError::BadInput(format!(
                    "enhance_radius is {r}; it must be finite and positive"
                )));
            }
        };
        let weight = self.settings.search_weight;
        if !(weight.is_finite() && weight >= 1.0) {
            return Err(PlanError::BadInput(format!(
                "search_weight is {weight}; it must be finite and at least 1"
            )));
        }
        let tree_share = self.settings.tree_share;
        if !(0.0..=1.0).contains(&tree_share) {
            return Err(PlanError::BadInput(format!(
                "tree_share is {tree_share}; it must be in [0, 1]"
            )));
        }
        let late_tree_share = self.settings.late_tree_share;
        if !(0.0..=1.0).contains(&late_tree_share) {
            return Err(PlanError::BadInput(format!(
                "late_tree_share is {late_tree_share}; it must be in [0, 1]"
            )));
        }
        let tree_step = self.settings.tree_step * range;
        if !(tree_step.is_finite() && tree_step > 0.0 && self.settings.tree_step <= 1.0) {
            return Err(PlanError::BadInput(format!(
                "tree_step is {}; it must be in (0, 1]",
                self.settings.tree_step
            )));
        }
        let escape = self.settings.escape;
        if let Some(e) = &escape {
            e.validate()?;
        }
        let goals = valid_goals(space, validator, request)?;
        let dim = space.dim();
        let roadmap = match &mut self.roadmap {
            Some(r) if r.nn.dim() == dim => r,
            slot => slot.insert(Roadmap::new(dim)),
        };
        let start = roadmap.add(space, &request.start, k, range);
        let goal_ids: Vec<u32> = goals.iter().map(|g| roadmap.add(space, g, k, range)).collect();
        let mut sample = vec![0.0; dim];
        let mut near = vec![0.0; dim];
        // Per query end: its growth turns, how many of them grew it (a greedy turn that adds
        // several vertices counts once, as the escape's stuck test counts turns), and its
        // escape helper.
        let mut turns = [0u64; 2];
        let mut added = [0u64; 2];
        let mut helpers: [Option<Helper>; 2] = [None, None];
        // Whether the search runs from the goals to the start: while the goals' part alone is
        // wedged. The candidates then fail at that part's rim, near the search's sources, and
        // the heuristic (distances to the start, over the rest of the roadmap) stays exact as
        // they fail; searched from the start, each failure there left the heuristic short over
        // the whole roadmap, and a search expanded about three times as many vertices on the
        // Fetch's cage.
        let mut from_goals = false;
        // Whether the search starts in a wedged part (the goals', or the start's).
        let mut from_wedged = false;
        'search: loop {
            let starts = std::slice::from_ref(&start);
            let found = if from_goals {
                roadmap.search(&goal_ids, starts, weight)
            } else {
                roadmap.search(starts, &goal_ids, weight)
            };
            if let Some(mut path) = found {
                if !run.next() {
                    break;
                }
                // The candidate's unchecked edges, in the order searched. From a wedged part,
                // the first failure (most often at the part's rim) ends the candidate: the next
                // search costs little, and the edges past the failure lie on a route that the
                // next candidate, through another rim edge, seldom takes (on the Fetch's cage,
                // 277 of 291 plans over three seeds within 1 s against 269 checking them all;
                // `docs/planning-log.md`). Otherwise all are checked and all that fail removed
                // before the next search: a failure leaves the heuristic short far around it,
                // so a search costs more than a few edge checks.
                let mut blocked = false;
                for w in path.windows(2) {
                    let e = edge(w[0], w[1]);
                    if roadmap.valid_edges.contains(&e) {
                        continue;
                    }
                    let (a, b) = (roadmap.nn.state(w[0] as usize), roadmap.nn.state(w[1] as usize));
                    if motion.check_motion(validator, a, b) {
                        roadmap.valid_edges.insert(e);
                    } else {
                        roadmap.remove_edge(w[0], w[1]);
                        blocked = true;
                        if from_wedged {
                            break;
                        }
                    }
                }
                if blocked {
                    continue 'search;
                }
                if from_goals {
                    path.reverse();
                }
                let states = path.iter().map(|&v| roadmap.nn.state(v as usize).to_vec()).collect();
                let stats = run.stats(motion, validator, vec![roadmap.nn.len()]);
                return Ok(Solution {
                    path: Path { states },
                    stats,
                });
            }
            let grow = self.settings.batch.max(roadmap.nn.len() / 4).max(1);
            // A query end whose part of the roadmap stays small once the roadmap is not.
            let wedged = if tree_share > 0.0 && roadmap.nn.len() >= self.settings.batch.max(1).saturating_mul(4) {
                let limit = roadmap.nn.len() / 8;
                [
                    roadmap.wedged_part(0, &[start], limit),
                    roadmap.wedged_part(1, &goal_ids, limit),
                ]
            } else {
                [false; 2]
            };
            from_goals = wedged[1] && !wedged[0];
            from_wedged = wedged[0] || wedged[1];
            let share = if roadmap.nn.len() >= self.settings.late_roadmap {
                late_tree_share
            } else {
                tree_share
            };
            let mut turn = 0;
            for _ in 0..grow {
                if !run.next() {
                    break 'search;
                }
                let space = motion.space();
                space.sample(rng, &mut sample);
                if (wedged[0] || wedged[1]) && rng.random_bool(share) {
                    // An RRT step of the wedged part (the two take turns when both are), or, once
                    // the part is stuck, a turn of its escape helper.
                    turn = if wedged[0] && wedged[1] {
                        1 - turn
                    } else {
                        usize::from(wedged[1])
                    };
                    turns[turn] += 1;
                    let ends = if turn == 0 {
                        std::slice::from_ref(&start)
                    } else {
                        &goal_ids[..]
                    };
                    let nn = &roadmap.nn;
                    let helper = escape.and_then(|e| {
                        e.helper_turn(&mut helpers[turn], (turns[turn], added[turn]), tree_step, rng, || {
                            Helper::new(ends.iter().map(|&v| (v as usize, nn.state(v as usize))), dim)
                        })
                    });
                    let grown = match helper {
                        Some((h, steps)) => {
                            let mut end = WedgedEnd {
                                roadmap,
                                side: turn,
                                k,
                                range,
                            };
                            h.turn(motion, validator, &mut end, &sample, steps).is_some()
                        }
                        None => {
                            let from = roadmap.nearest_wedged(space, turn, &sample);
                            // One step towards the sample, or with `tree_connect` steps on
                            // until one is blocked or lands on the sample (the cap only guards
                            // against steps that make no headway in floating point).
                            let most = if self.settings.tree_connect {
                                1 + MAX_CONNECT_STEPS
                            } else {
                                1
                            };
                            let (mut at, mut taken) = (from, 0);
                            while taken < most {
                                let q_at = roadmap.nn.state(at as usize);
                                if (taken > 0 && motion.space().distance(q_at, &sample) == 0.0)
                                    || !try_step(motion, validator, q_at, &sample, tree_step, &mut near)
                                {
                                    break;
                                }
                                at = roadmap.add_reached(motion.space(), turn, at, &near, k, range);
                                taken += 1;
                            }
                            taken > 0
                        }
                    };
                    if grown {
                        added[turn] += 1;
                    }
                    continue;
                }
                let failures = roadmap.failures.len() / dim;
                if failures > 0 && rng.random_bool(enhance) {
                    // A point within `enhance_radius` of a random failure, towards the sample.
                    let at = rng.random_range(0..failures) * dim;
                    near.copy_from_slice(&sample);
                    let centre = &roadmap.failures[at..at + dim];
                    pull_towards(space, centre, &near, enhance_radius, rng, &mut sample);
                }
                if validator.is_valid(&sample) {
                    roadmap.add(motion.space(), &sample, k, range);
                }
            }
            // Early vertices keep the few neighbours they had when the roadmap was sparse; the
            // query's own vertices are rejoined to their current nearest ones.
            for &v in std::iter::once(&start).chain(&goal_ids) {
                roadmap.connect(motion.space(), v, k, range);
            }
        }
        Err(PlanError::Timeout {
            stats: run.stats(motion, validator, vec![roadmap.nn.len()]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::space::JointSpace;

    /// A roadmap on a 2 × 4 grid of unit spacing, each vertex joined to its neighbours within
    /// 1.5 (sides and diagonals), and its vertex ids by `(x, y)`.
    fn grid() -> (JointSpace, Roadmap, impl Fn(u32, u32) -> u32) {
        let space = JointSpace::new(&[-1.0; 2], &[5.0; 2], &[false; 2]).unwrap();
        let mut roadmap = Roadmap::new(2);
        for y in 0..2 {
            for x in 0..4 {
                roadmap.add(&space, &[f64::from(x), f64::from(y)], 8, 1.5);
            }
        }
        (space, roadmap, |x, y| y * 4 + x)
    }

    fn length(space: &JointSpace, roadmap: &Roadmap, path: &[u32]) -> f64 {
        path.windows(2)
            .map(|w| space.distance(roadmap.nn.state(w[0] as usize), roadmap.nn.state(w[1] as usize)))
            .sum()
    }

    #[test]
    fn queue_keys_order_like_total_cmp() {
        let values = [
            f64::NEG_INFINITY,
            -1e300,
            -2.5,
            -f64::MIN_POSITIVE,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            1e-300,
            0.1,
            0.1 + 1e-17,
            0.30000000000000004,
            2.5,
            1e300,
            f64::INFINITY,
            f64::NAN,
        ];
        for a in values {
            for b in values {
                assert_eq!(order_key(a).cmp(&order_key(b)), a.total_cmp(&b), "{a} against {b}");
            }
        }
    }

    #[test]
    fn search_runs_from_either_end_and_avoids_removed_edges() {
        let (space, mut roadmap, id) = grid();
        let (start, goal) = (id(0, 0), id(3, 0));
        let forward = roadmap.search(&[start], &[goal], 1.0).unwrap();
        assert_eq!(forward, [id(0, 0), id(1, 0), id(2, 0), id(3, 0)]);
        let backward = roadmap.search(&[goal], &[start], 1.0).unwrap();
        assert_eq!(backward, [id(3, 0), id(2, 0), id(1, 0), id(0, 0)]);
        // Cutting the bottom row's middle edge: both directions go round it, as short as
        // each other (1 + 2·√2).
        roadmap.remove_edge(id(1, 0), id(2, 0));
        let forward = roadmap.search(&[start], &[goal], 1.0).unwrap();
        let backward = roadmap.search(&[goal], &[start], 1.0).unwrap();
        for path in [&forward, &backward] {
            assert!(!path.windows(2).any(|w| edge(w[0], w[1]) == edge(id(1, 0), id(2, 0))));
            assert!((length(&space, &roadmap, path) - (1.0 + 2.0 * 2f64.sqrt())).abs() < 1e-12);
        }
        assert_eq!((forward[0], backward[0]), (start, goal));
        assert_eq!((forward.last(), backward.last()), (Some(&goal), Some(&start)));
        // Cut off from the goal, a search from either end finds nothing.
        for u in [id(1, 1), id(2, 1)] {
            for v in [id(1, 0), id(2, 0)] {
                roadmap.remove_edge(u, v);
            }
        }
        roadmap.remove_edge(id(1, 1), id(2, 1));
        assert_eq!(roadmap.search(&[start], &[goal], 1.5), None);
        assert_eq!(roadmap.search(&[goal], &[start], 1.5), None);
    }

    /// The distances to the targets by a fresh Dijkstra search over the roadmap as it is.
    fn exact_to_target(roadmap: &Roadmap, targets: &[u32]) -> Vec<f64> {
        let mut fresh = roadmap.clone();
        fresh.to_target_of = None;
        fresh.update_to_target(targets);
        fresh.to_target
    }

    #[test]
    fn lowered_distances_stay_exact_while_edges_are_only_added_and_a_consistent_bound_after() {
        use rand::SeedableRng;
        let space = JointSpace::new(&[0.0; 2], &[10.0; 2], &[false; 2]).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let mut roadmap = Roadmap::new(2);
        let mut q = [0.0; 2];
        for _ in 0..40 {
            space.sample(&mut rng, &mut q);
            roadmap.add(&space, &q, 6, 2.5);
        }
        let targets = [0u32, 1];
        roadmap.update_to_target(&targets);
        let mut lowered = 0;
        for batch in 0..30 {
            // Batches of new vertices (fewer new edges than vertices: the distances are lowered).
            for _ in 0..3 {
                space.sample(&mut rng, &mut q);
                roadmap.add(&space, &q, 6, 2.5);
            }
            if roadmap.fresh.len() < roadmap.adjacency.len() {
                lowered += 1;
            }
            roadmap.update_to_target(&targets);
            assert!(roadmap.fresh.is_empty());
            let exact = exact_to_target(&roadmap, &targets);
            if batch < 10 {
                // Only additions so far: the lowered distances are the exact ones.
                for (v, (&h, &e)) in roadmap.to_target.iter().zip(&exact).enumerate() {
                    assert!(
                        h == e || (h - e).abs() <= 1e-9 * e,
                        "batch {batch}, vertex {v}: {h} against {e}"
                    );
                }
            } else {
                // Edges are removed from here on: still at most the exact distance, consistent
                // along every edge, and 0 at the targets.
                for (u, (&h, &e)) in roadmap.to_target.iter().zip(&exact).enumerate() {
                    assert!(h <= e + 1e-9, "batch {batch}, vertex {u}: {h} above {e}");
                    for &(w, d) in &roadmap.adjacency[u] {
                        assert!(h <= d + roadmap.to_target[w as usize] + 1e-9, "edge {u}-{w}");
                    }
                }
                assert!(targets.iter().all(|&t| roadmap.to_target[t as usize] == 0.0));
                let v = rng.random_range(0..roadmap.adjacency.len());
                if let Some(&(w, _)) = roadmap.adjacency[v].first() {
                    roadmap.remove_edge(v as u32, w);
                }
            }
        }
        assert!(lowered >= 20, "the distances were lowered in {lowered} of 30 batches");
    }
}
