//! [`LazyPrm`]: the lazy probabilistic roadmap (Bohlin & Kavraki 2000), OMPL's `LazyPRM`.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::motion::MotionValidator;
use crate::nn::NearestNeighbors;
use crate::planner::{Budget, Path, PlanRequest, Planner, Run, Solution, resolve_range, valid_goals};
use crate::space::Space;
use crate::validity::StateValidator;

/// Settings of [`LazyPrm`], serde-derivable so a TOML file can set them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LazyPrmSettings {
    /// Each new vertex is joined to at most this many nearest vertices (default 10).
    pub k: usize,
    /// Longest roadmap edge; `None` is [`default_range`](crate::planner::default_range)
    /// (0.2 × the space's extent, OMPL's `maxDistance` default).
    pub range: Option<f64>,
    /// Fewest samples added each time the roadmap has no candidate path (default 50); the
    /// roadmap grows by at least a quarter of its size, so growth is geometric.
    pub batch: usize,
}

impl Default for LazyPrmSettings {
    fn default() -> Self {
        Self {
            k: 10,
            range: None,
            batch: 50,
        }
    }
}

/// Lazy PRM: a roadmap of samples, each joined to its `k` nearest neighbours within `range`
/// *without* checking anything. A query searches the roadmap with A*, then checks only the
/// candidate path: its unchecked vertices with the validator, then its unchecked edges with the
/// motion validator. An invalid vertex or edge is removed and the search repeated; when no
/// candidate is left, the roadmap grows by a batch of samples, and the start and goal
/// vertices are joined to their new nearest neighbours, while the budget lasts.
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

/// What is known about a roadmap vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Status {
    Unchecked,
    Valid,
    Removed,
}

#[derive(Clone, Debug)]
struct Roadmap {
    nn: NearestNeighbors,
    status: Vec<Status>,
    adjacency: Vec<Vec<u32>>,
    /// Edges checked valid, as (lower id, higher id).
    valid_edges: HashSet<(u32, u32)>,
    /// Edges found invalid (removed, never joined again).
    invalid_edges: HashSet<(u32, u32)>,
}

impl LazyPrm {
    /// A planner with these settings and an empty roadmap.
    pub fn new(settings: LazyPrmSettings) -> Self {
        Self {
            settings,
            roadmap: None,
        }
    }

    /// The settings.
    pub fn settings(&self) -> &LazyPrmSettings {
        &self.settings
    }

    /// Forgets the roadmap (call it when the scene changes).
    pub fn clear(&mut self) {
        self.roadmap = None;
    }

    /// Number of roadmap vertices (removed ones excluded).
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
            status: Vec::new(),
            adjacency: Vec::new(),
            valid_edges: HashSet::new(),
            invalid_edges: HashSet::new(),
        }
    }

    /// Adds `q` (or finds an equal vertex) and joins it to its neighbours.
    fn add<S: Space>(&mut self, space: &S, q: &[f64], status: Status, k: usize, range: f64) -> u32 {
        if let Some(i) = self.nn.nearest(space, q)
            && space.distance(self.nn.state(i), q) == 0.0
        {
            if status == Status::Valid {
                self.status[i] = Status::Valid;
            }
            return i as u32;
        }
        let v = self.nn.insert(q) as u32;
        self.status.push(status);
        self.adjacency.push(Vec::with_capacity(k));
        self.connect(space, v, k, range);
        v
    }

    /// Joins `v` to those of its `k` nearest vertices within `range` that it is not joined to
    /// yet (and whose edge was not found invalid).
    fn connect<S: Space>(&mut self, space: &S, v: u32, k: usize, range: f64) {
        let q = self.nn.state(v as usize).to_vec();
        for u in self.nn.k_nearest(space, &q, k + 1) {
            let u = u as u32;
            if u != v
                && !self.adjacency[v as usize].contains(&u)
                && !self.invalid_edges.contains(&edge(u, v))
                && space.distance(self.nn.state(u as usize), &q) <= range
            {
                self.adjacency[v as usize].push(u);
                self.adjacency[u as usize].push(v);
            }
        }
    }

    fn remove_vertex(&mut self, v: u32) {
        self.nn.remove(v as usize);
        self.status[v as usize] = Status::Removed;
        for u in std::mem::take(&mut self.adjacency[v as usize]) {
            self.adjacency[u as usize].retain(|&w| w != v);
        }
    }

    fn remove_edge(&mut self, a: u32, b: u32) {
        self.invalid_edges.insert(edge(a, b));
        self.adjacency[a as usize].retain(|&w| w != b);
        self.adjacency[b as usize].retain(|&w| w != a);
    }

    /// The cheapest roadmap path from `start` to any of `goals` (A*, heuristic: distance to
    /// the nearest goal), or `None`.
    fn search<S: Space>(&self, space: &S, start: u32, goals: &[u32]) -> Option<Vec<u32>> {
        let n = self.status.len();
        let mut is_goal = vec![false; n];
        for &g in goals {
            is_goal[g as usize] = true;
        }
        let h = |v: u32| {
            goals
                .iter()
                .map(|&g| space.distance(self.nn.state(v as usize), self.nn.state(g as usize)))
                .fold(f64::INFINITY, f64::min)
        };
        let mut cost = vec![f64::INFINITY; n];
        let mut parent = vec![u32::MAX; n];
        let mut closed = vec![false; n];
        let mut open = BinaryHeap::new();
        cost[start as usize] = 0.0;
        open.push(Reverse((Key(h(start)), start)));
        while let Some(Reverse((_, v))) = open.pop() {
            if closed[v as usize] {
                continue;
            }
            closed[v as usize] = true;
            if is_goal[v as usize] {
                let mut path = vec![v];
                let mut u = v;
                while parent[u as usize] != u32::MAX {
                    u = parent[u as usize];
                    path.push(u);
                }
                path.reverse();
                return Some(path);
            }
            let qv = self.nn.state(v as usize);
            for &u in &self.adjacency[v as usize] {
                if closed[u as usize] {
                    continue;
                }
                let c = cost[v as usize] + space.distance(qv, self.nn.state(u as usize));
                if c < cost[u as usize] {
                    cost[u as usize] = c;
                    parent[u as usize] = v;
                    open.push(Reverse((Key(c + h(u)), u)));
                }
            }
        }
        None
    }
}

/// An `f64` ordered by `total_cmp`, for the A* queue.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key(f64);

impl Eq for Key {}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
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
        let mut run = Run::start(budget, motion, validator);
        let space = motion.space();
        let range = resolve_range(space, self.settings.range, 1.0)?;
        let goals = valid_goals(space, validator, request, budget)?;
        let dim = space.dim();
        let roadmap = match &mut self.roadmap {
            Some(r) if r.nn.dim() == dim => r,
            slot => slot.insert(Roadmap::new(dim)),
        };
        let start = roadmap.add(space, &request.start, Status::Valid, k, range);
        let goal_ids: Vec<u32> = goals
            .iter()
            .map(|g| roadmap.add(space, g, Status::Valid, k, range))
            .collect();
        let mut sample = vec![0.0; dim];
        'search: loop {
            if let Some(path) = roadmap.search(motion.space(), start, &goal_ids) {
                if !run.next() {
                    break;
                }
                for &v in &path {
                    if roadmap.status[v as usize] == Status::Unchecked {
                        if validator.is_valid(roadmap.nn.state(v as usize)) {
                            roadmap.status[v as usize] = Status::Valid;
                        } else {
                            roadmap.remove_vertex(v);
                            continue 'search;
                        }
                    }
                }
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
                        continue 'search;
                    }
                }
                let states = path.iter().map(|&v| roadmap.nn.state(v as usize).to_vec()).collect();
                let stats = run.stats(motion, validator, vec![roadmap.nn.len()]);
                return Ok(Solution {
                    path: Path { states },
                    stats,
                });
            }
            let grow = self.settings.batch.max(roadmap.nn.len() / 4).max(1);
            for _ in 0..grow {
                if !run.next() {
                    break 'search;
                }
                motion.space().sample(rng, &mut sample);
                roadmap.add(motion.space(), &sample, Status::Unchecked, k, range);
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
