//! [`BiRrt`]: RRT-Connect (Kuffner & LaValle 2000), OMPL's `RRTConnect`.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::motion::MotionValidator;
use crate::planner::{Budget, Path, PlanRequest, Planner, Run, Solution, Tree, resolve_range, valid_goals};
use crate::space::{Space, steer};
use crate::validity::StateValidator;

/// RRT-Connect: a tree from the start and a tree from the goals (seeded with every valid goal),
/// grown in turns. Each iteration extends one tree a step of at most `range` towards a random
/// sample, then greedily joins the trees along a straight line in equal steps of at most
/// `range` until it is reached or blocked: by default the other tree grows from its nearest
/// state towards the new one ([`Connect::Other`], Kuffner & LaValle's and OMPL's);
/// [`Connect::Onward`] lets the tree that just grew go on towards the other tree instead (as
/// VAMP's RRT-Connect does; measured, it helps neither robot's MotionBenchMaker problems). Tree balancing
/// ([`BiRrt::balance`], as in VAMP's RRT-Connect) and the pocket escape ([`Escape`]: a helper
/// tree of short steps for a tree that barely grows) are on by default; dynamic-domain
/// sampling ([`DynamicDomain`]) is available but off, because it lowered success on the
/// MotionBenchMaker problems (`docs/planning-log.md`). [`BiRrt::plain`] is the textbook
/// algorithm.
///
/// One iteration is one sample. Settings are serde-derivable.
///
/// ```
/// use hearth_planning::birrt::BiRrt;
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest, Planner};
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use rand::SeedableRng;
///
/// // A wall at x = 0.5 with a gap above y = 0.8.
/// struct Wall(u64);
/// impl StateValidator for Wall {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; (q[0] - 0.5).abs() > 0.05 || q[1] > 0.8 }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
/// let mut motion = MotionValidator::new(space, 0.01);
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]));
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let solution = BiRrt::default()
///     .plan(&mut motion, &mut Wall(0), &request, &Budget::iterations(10_000), &mut rng)
///     .unwrap();
/// assert!(solution.path.states.iter().any(|q| q[1] > 0.8));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BiRrt {
    /// Longest step; `None` is a tenth of [`default_range`](crate::planner::default_range)
    /// (0.02 × the space's extent, ≈ 0.26 rad for the Panda and the Fetch), the step the
    /// skills were validated with. OMPL's default, 0.2 × the extent, made each extension check
    /// up to ~120 states on MotionBenchMaker problems and cost success. Longer steps suit some
    /// problem sets: `hearth bench plan` takes 0.65 rad for the Panda and 1.2 rad for the
    /// Fetch (`docs/planning-log.md`).
    pub range: Option<f64>,
    /// Dynamic-domain sampling (Yershova, Jaillet, Siméon & LaValle, ICRA 2005): a state whose
    /// extension failed only accepts samples within its domain radius afterwards, so states
    /// wedged against obstacles stop spending collision checks on far samples. `None` turns it
    /// off (the default).
    pub dynamic_domain: Option<DynamicDomain>,
    /// Grow the smaller tree while it has less than half the other's states, instead of
    /// strictly alternating (a tree stuck in a pocket gets the samples it needs to get out).
    pub balance: bool,
    /// Escape from pockets ([`Escape`]): a tree that almost never grows gets a helper tree of
    /// short steps from its roots. `None` turns it off.
    pub escape: Option<Escape>,
    /// Which tree grows along the joining line after an extension ([`Connect`]).
    pub connect: Connect,
}

/// Which tree [`BiRrt`] grows along the line that joins the trees after an extension.
///
/// ```
/// use hearth_planning::birrt::{BiRrt, Connect};
/// assert_eq!(BiRrt::default().connect, Connect::Other);
/// let vamp_like = BiRrt { connect: Connect::Onward, ..BiRrt::default() };
/// assert_ne!(vamp_like, BiRrt::default());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Connect {
    /// The other tree grows from its state nearest to the new state towards it (the textbook
    /// algorithm; OMPL's `RRTConnect`). The faster choice on open problems: the Panda's
    /// MotionBenchMaker box problems take 0.59 ms against 0.77 ms with [`Connect::Onward`]
    /// (`docs/planning-log.md`).
    #[default]
    Other,
    /// The tree that just grew goes on from its new state towards the other tree's state
    /// nearest to it (VAMP's RRT-Connect): a tree outside a pocket heads for the pocketed
    /// tree, and a pocketed tree that found a way out goes on along it. Measured on the
    /// MotionBenchMaker problems it does not pay: the hardest Fetch problems (goals wedged
    /// between shelf boards or cage bars) are solved in 54 of 176 plans within 1 s against 74
    /// with [`Connect::Other`], and the Panda's open problems are planned more slowly
    /// (`docs/planning-log.md`).
    Onward,
}

impl Default for BiRrt {
    fn default() -> Self {
        Self {
            range: None,
            dynamic_domain: None,
            balance: true,
            escape: Some(Escape::default()),
            connect: Connect::Other,
        }
    }
}

impl BiRrt {
    /// Plain RRT-Connect with step `range`: no dynamic domain, strictly alternating trees, no
    /// pocket escape.
    ///
    /// ```
    /// let plain = hearth_planning::BiRrt::plain(Some(0.3));
    /// assert!(plain.dynamic_domain.is_none() && !plain.balance && plain.escape.is_none());
    /// ```
    pub fn plain(range: Option<f64>) -> Self {
        Self {
            range,
            dynamic_domain: None,
            balance: false,
            escape: None,
            connect: Connect::Other,
        }
    }

    /// Default settings with step `range`.
    ///
    /// ```
    /// let b = hearth_planning::BiRrt::with_range(Some(1.2));
    /// assert_eq!(b.range, Some(1.2));
    /// assert!(b.balance && b.dynamic_domain.is_none());
    /// ```
    pub fn with_range(range: Option<f64>) -> Self {
        Self {
            range,
            ..Self::default()
        }
    }
}

/// Settings of dynamic-domain sampling, in multiples of the planner's step (`range`).
///
/// ```
/// let dd = hearth_planning::birrt::DynamicDomain::default();
/// assert!(dd.min_radius <= dd.radius && dd.alpha > 0.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DynamicDomain {
    /// Domain radius given to a state at its first failed extension.
    pub radius: f64,
    /// The radius never shrinks below this.
    pub min_radius: f64,
    /// Each further failure shrinks the radius by this fraction; each success grows it by it.
    pub alpha: f64,
}

impl Default for DynamicDomain {
    /// Twice the step, at least half the step, 10⁻⁴ per outcome: the ratios VAMP's RRT-Connect
    /// uses (radius 4, minimum 1, step 2).
    fn default() -> Self {
        Self {
            radius: 2.0,
            min_radius: 0.5,
            alpha: 1e-4,
        }
    }
}

/// Settings of the pocket escape of [`BiRrt`].
///
/// A goal wedged among obstacles (a gripper between two cans on a shelf) can leave almost no
/// straight step of the full `range` free: its tree then stays at its roots for hundreds of
/// thousands of tries, while shorter steps would find the way out. Once a tree has grown by
/// fewer than one state per `stuck_ratio` extension attempts (after at least `after`
/// attempts), a share `share` of its turns goes to a helper tree rooted at its roots and
/// grown with steps of `step × range`. A share `probe` of the helper's turns are probes: a
/// step of a third of the helper's step from the helper state nearest the sample towards it,
/// whose direction the helper remembers when it is free. The recent free directions give the
/// shape of the pocket's way out (the helper's channel, see [`probe`](Escape::probe)). The
/// other helper turns steer from the helper state nearest the sample towards the sample bent
/// by that shape, and first try a step of `join × range`: when that succeeds, the helper's
/// branch and the new state join the tree, which goes on as before from outside the pocket;
/// else a step of `step × range` grows the helper. The helper's short steps never become the
/// tree's own states otherwise, so states inside the pocket do not become the
/// nearest neighbours of later samples. A helper that has not grown for `reset` of its turns
/// is replaced by a fresh one.
///
/// ```
/// let e = hearth_planning::birrt::Escape::default();
/// assert!(e.step < 1.0 && e.share > 0.0 && e.share < 1.0);
/// assert!(e.probe > 0.0 && e.probe < 1.0);
/// assert!(e.reset > 0 && e.reset < u64::MAX); // helpers that stop growing are replaced
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Escape {
    /// Extension attempts on a tree before it can count as stuck.
    pub after: u64,
    /// A tree is stuck while it has grown by fewer than one state per this many attempts.
    pub stuck_ratio: u64,
    /// Share of a stuck tree's turns given to its helper tree, in (0, 1).
    pub share: f64,
    /// The helper tree's step, as a fraction of the planner's step, in (0, 1].
    pub step: f64,
    /// The step that lets a helper state join the tree, as a fraction of the planner's step,
    /// in [`step`](Escape::step), 1].
    pub join: f64,
    /// Share of the helper's turns, in [0, 1), spent on probes: steps of a third of the
    /// helper's step towards the sample (a uniformly random direction), which teach the
    /// helper which directions are free near its frontier. Once eight probes were free, the
    /// other turns steer through the learnt channel: the displacement to the sample is
    /// multiplied by the second moment of the last 32 free probe directions (plus a twentieth
    /// of its mean eigenvalue), which squashes the directions the pocket leaves no room in.
    /// 0 turns the channel off: every helper turn steers straight at its sample.
    pub probe: f64,
    /// Helper turns without growth (no new helper state, nothing joined to the tree) after
    /// which the helper is dropped, and the next helper turn starts a new one from the
    /// tree's roots with an empty channel. A helper can wall itself in: its frontier ends in a
    /// cul-de-sac of the pocket, whose states stay the nearest to every sample, while the way
    /// out starts near the roots. A fresh helper draws its first steps anew. `u64::MAX`
    /// keeps a helper for the whole plan.
    pub reset: u64,
}

impl Default for Escape {
    fn default() -> Self {
        Self {
            after: 10_000,
            stuck_ratio: 2_000,
            share: 0.5,
            step: 0.25,
            join: 0.5,
            probe: 0.5,
            reset: 20_000,
        }
    }
}

/// A stuck tree's helper ([`Escape`]): short steps from the tree's roots, and for each helper
/// state the tree state it became, once it joined the tree.
struct Helper {
    tree: Tree,
    joined: Vec<Option<usize>>,
    channel: Channel,
    /// Helper turns since it last grew or joined its tree.
    idle: u64,
}

/// Directions recently found free by a helper's probes: the shape of the channel a wedged
/// tree has to leave through.
///
/// A goal wedged between shelf boards leaves free motions that are long in some directions
/// and very short in others: at the Fetch's eleven hardest MotionBenchMaker goals the second
/// moment of the free 0.1 rad steps' directions has two eigenvalues of 0.003–0.03, against
/// 0.06–0.27 for the other six. Steering towards a sample through that second moment (the
/// displacement multiplied by it, so the thin directions are squashed) makes 6–17× more
/// 0.3 rad steps from those goals free than steering straight at the sample
/// (`docs/planning-log.md`, fifteenth round). This is principal-component analysis of the local free space, as in
/// Dalibard & Laumond's PCA-guided RRT ("Control of probabilistic diffusion in motion
/// planning", WAFR 2008), learnt here from short probes rather than from the tree's states. The memory is short ([`CHANNEL_MEMORY`] directions), so the shape follows the
/// helper's frontier as the channel turns.
struct Channel {
    dim: usize,
    /// Ring of unit directions, `CHANNEL_MEMORY × dim`.
    dirs: Vec<f64>,
    /// Directions held (at most `CHANNEL_MEMORY`) and the next slot to write.
    held: usize,
    next: usize,
    /// Sum of the held directions' outer products, `dim × dim`.
    moment: Vec<f64>,
    /// Scratch: a displacement, its shaped image, and the shaped target.
    delta: Vec<f64>,
    shaped: Vec<f64>,
    target: Vec<f64>,
}

/// Euclidean length of a displacement.
fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Free directions a [`Channel`] remembers.
const CHANNEL_MEMORY: usize = 32;
/// Free directions a [`Channel`] needs before it shapes steps.
const CHANNEL_READY: usize = 8;
/// Share of the mean eigenvalue added to every direction of a channel's shape, so that no
/// direction is shut off entirely.
const CHANNEL_FLOOR: f64 = 0.05;

impl Channel {
    fn new(dim: usize) -> Self {
        Self {
            dim,
            dirs: vec![0.0; CHANNEL_MEMORY * dim],
            held: 0,
            next: 0,
            moment: vec![0.0; dim * dim],
            delta: vec![0.0; dim],
            shaped: vec![0.0; dim],
            target: vec![0.0; dim],
        }
    }

    /// Remembers the direction from `from` to `to` (a free motion), forgetting the oldest.
    fn record<S: Space>(&mut self, space: &S, from: &[f64], to: &[f64]) {
        let d = self.dim;
        space.difference(from, to, &mut self.delta);
        let length = norm(&self.delta);
        if !(length > 0.0 && length.is_finite()) {
            return;
        }
        let slot = &mut self.dirs[self.next * d..][..d];
        for (s, x) in slot.iter_mut().zip(&self.delta) {
            *s = x / length;
        }
        self.next = (self.next + 1) % CHANNEL_MEMORY;
        self.held = (self.held + 1).min(CHANNEL_MEMORY);
        // Recomputed from the held directions (rare: once per free probe), so no rounding
        // drifts in from forgotten ones.
        self.moment.fill(0.0);
        for u in self.dirs.chunks_exact(d).take(self.held) {
            for i in 0..d {
                for j in 0..d {
                    self.moment[i * d + j] += u[i] * u[j];
                }
            }
        }
    }

    fn ready(&self) -> bool {
        self.held >= CHANNEL_READY
    }

    /// A target as far from `from` as `target` is, in the direction of `target`'s
    /// displacement multiplied by the channel's shape (its second moment with a floor of
    /// [`CHANNEL_FLOOR`]), within the bounds.
    fn shape<S: Space>(&mut self, space: &S, from: &[f64], target: &[f64]) -> &[f64] {
        let d = self.dim;
        space.difference(from, target, &mut self.delta);
        let trace: f64 = (0..d).map(|i| self.moment[i * d + i]).sum();
        let floor = CHANNEL_FLOOR * trace / d as f64;
        for i in 0..d {
            let row = &self.moment[i * d..][..d];
            self.shaped[i] = row.iter().zip(&self.delta).map(|(m, x)| m * x).sum::<f64>() + floor * self.delta[i];
        }
        let scale = norm(&self.delta) / norm(&self.shaped);
        let scale = if scale.is_finite() { scale } else { 0.0 };
        for ((o, f), s) in self.target.iter_mut().zip(from).zip(&self.shaped) {
            *o = f + s * scale;
        }
        space.enforce_bounds(&mut self.target);
        &self.target
    }
}

impl Helper {
    /// Rooted at the first `roots` states of `grown` (its roots, added first).
    fn new(grown: &Grown, roots: usize, dim: usize) -> Self {
        let mut tree = Tree::new(dim);
        for r in 0..roots {
            tree.add(grown.tree.state(r), None);
        }
        Self {
            tree,
            joined: (0..roots).map(Some).collect(),
            channel: Channel::new(dim),
            idle: 0,
        }
    }

    /// Adds helper state `h`'s branch to `grown` where it is not there yet; returns the tree
    /// index of `h`.
    fn join(&mut self, h: usize, grown: &mut Grown, chain: &mut Vec<usize>) -> usize {
        chain.clear();
        let mut at = h;
        let mut above = loop {
            if let Some(t) = self.joined[at] {
                break t;
            }
            chain.push(at);
            at = self.tree.parent(at).expect("helper roots have joined");
        };
        for &k in chain.iter().rev() {
            above = grown.add(self.tree.state(k), Some(above));
            self.joined[k] = Some(above);
        }
        above
    }
}

/// [`BiRrt`]'s default step as a fraction of [`default_range`](crate::planner::default_range).
const BIRRT_RANGE_SCALE: f64 = 0.1;

/// One tree of the search with each state's dynamic-domain radius.
struct Grown {
    tree: Tree,
    radius: Vec<f64>,
}

impl Grown {
    fn new(dim: usize) -> Self {
        Self {
            tree: Tree::new(dim),
            radius: Vec::new(),
        }
    }

    fn add(&mut self, q: &[f64], parent: Option<usize>) -> usize {
        self.radius.push(f64::INFINITY);
        self.tree.add(q, parent)
    }

    fn len(&self) -> usize {
        self.tree.len()
    }
}

/// Scratch buffers and settings shared by the extension steps.
struct Stepper {
    range: f64,
    /// Dynamic domain in absolute units: (radius, min radius, alpha).
    domain: Option<(f64, f64, f64)>,
    step: Vec<f64>,
    from: Vec<f64>,
}

impl Stepper {
    /// Steps from `from` towards `target` by at most `range` into `self.step`; whether that
    /// state and the motion to it are valid.
    fn try_step<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        from: &[f64],
        target: &[f64],
        range: f64,
    ) -> bool {
        steer(motion.space(), from, target, range, &mut self.step);
        validator.is_valid(&self.step) && motion.check_motion(validator, from, &self.step)
    }

    /// A helper turn of a stuck tree ([`Escape`]) from the helper state nearest `target`:
    /// either a `probe` step in the sample's direction that teaches the helper's [`Channel`]
    /// when it is free, or, with the target shaped by the channel once it has learnt enough,
    /// a `long` step, which joins the tree with its branch when valid (returns its tree
    /// index), else a `short` step that grows the helper.
    #[allow(clippy::too_many_arguments)]
    fn escape<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        grown: &mut Grown,
        helper: &mut Helper,
        target: &[f64],
        (short, long, probe): (f64, f64, Option<f64>),
        chain: &mut Vec<usize>,
    ) -> Option<usize> {
        let near = helper
            .tree
            .nn
            .nearest(motion.space(), target)
            .expect("helpers are never empty");
        // Counted back to 0 below when the helper grows or joins its tree.
        helper.idle += 1;
        if let Some(p) = probe {
            if self.try_step(motion, validator, helper.tree.state(near), target, p) {
                helper
                    .channel
                    .record(motion.space(), helper.tree.state(near), &self.step);
            }
            return None;
        }
        let aim: &[f64] = if helper.channel.ready() {
            helper.channel.shape(motion.space(), helper.tree.state(near), target)
        } else {
            target
        };
        if self.try_step(motion, validator, helper.tree.state(near), aim, long) {
            helper.idle = 0;
            let at = helper.join(near, grown, chain);
            return Some(grown.add(&self.step, Some(at)));
        }
        if self.try_step(motion, validator, helper.tree.state(near), aim, short) {
            helper.idle = 0;
            helper.tree.add(&self.step, Some(near));
            helper.joined.push(None);
        }
        None
    }

    /// Extends `grown` one step towards the sample `target`. Returns the new state's index, or
    /// `None` when the sample was outside the nearest state's domain or the step was blocked.
    fn extend<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        grown: &mut Grown,
        target: &[f64],
    ) -> Option<usize> {
        let space = motion.space();
        let near = grown.tree.nn.nearest(space, target).expect("trees are never empty");
        if self.domain.is_some() && space.distance(grown.tree.state(near), target) > grown.radius[near] {
            return None;
        }
        let ok = self.try_step(motion, validator, grown.tree.state(near), target, self.range);
        if let Some((radius, min_radius, alpha)) = self.domain {
            let r = &mut grown.radius[near];
            if ok {
                if r.is_finite() {
                    *r *= 1.0 + alpha;
                }
            } else if r.is_finite() {
                *r = (*r * (1.0 - alpha)).max(min_radius);
            } else {
                *r = radius;
            }
        }
        ok.then(|| grown.add(&self.step, Some(near)))
    }

    /// Grows `grown` from its state nearest to `target` straight towards it ([`Stepper::line`]).
    /// Returns the index of `target` once reached.
    fn connect<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        grown: &mut Grown,
        target: &[f64],
    ) -> Option<usize> {
        let at = grown
            .tree
            .nn
            .nearest(motion.space(), target)
            .expect("trees are never empty");
        self.line(motion, validator, grown, at, target)
    }

    /// Grows `grown` from its state `at` straight towards `target`, in equal steps of at most
    /// `range`, each added to the tree until one is blocked. Returns the index of `target` once
    /// reached.
    fn line<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        grown: &mut Grown,
        mut at: usize,
        target: &[f64],
    ) -> Option<usize> {
        let d = motion.space().distance(grown.tree.state(at), target);
        let n = ((d / self.range).ceil() as usize).max(1);
        self.from.copy_from_slice(grown.tree.state(at));
        for k in 1..=n {
            if k == n {
                self.step.copy_from_slice(target);
            } else {
                motion
                    .space()
                    .interpolate(&self.from, target, k as f64 / n as f64, &mut self.step);
            }
            if !validator.is_valid(&self.step) || !motion.check_motion(validator, grown.tree.state(at), &self.step) {
                return None;
            }
            at = grown.add(&self.step, Some(at));
        }
        Some(at)
    }
}

impl<S: Space> Planner<S> for BiRrt {
    fn plan<V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<Solution, PlanError> {
        let mut run = Run::start(budget, motion, validator)?;
        let space = motion.space();
        let range = resolve_range(space, self.range, BIRRT_RANGE_SCALE)?;
        let domain = match self.dynamic_domain {
            None => None,
            Some(dd) => {
                let ok = |v: f64| v.is_finite() && v > 0.0;
                if !ok(dd.radius) || !ok(dd.min_radius) || !(0.0..1.0).contains(&dd.alpha) {
                    return Err(PlanError::BadInput(format!(
                        "dynamic domain {dd:?}: radii must be positive and finite, alpha in [0, 1)"
                    )));
                }
                Some((dd.radius * range, dd.min_radius.min(dd.radius) * range, dd.alpha))
            }
        };
        let escape = match self.escape {
            None => None,
            Some(e) => {
                if !(e.share > 0.0
                    && e.share < 1.0
                    && e.step > 0.0
                    && e.step <= e.join
                    && e.join <= 1.0
                    && (0.0..1.0).contains(&e.probe)
                    && e.stuck_ratio > 0
                    && e.reset > 0)
                {
                    return Err(PlanError::BadInput(format!(
                        "escape {e:?}: share must be in (0, 1), 0 < step ≤ join ≤ 1, probe in [0, 1), stuck_ratio and reset positive"
                    )));
                }
                Some(e)
            }
        };
        let goals = valid_goals(space, validator, request)?;
        let dim = space.dim();
        // trees[0] grows from the start, trees[1] from the goals.
        let mut trees = [Grown::new(dim), Grown::new(dim)];
        trees[0].add(&request.start, None);
        for g in &goals {
            trees[1].add(g, None);
        }
        let mut stepper = Stepper {
            range,
            domain,
            step: vec![0.0; dim],
            from: vec![0.0; dim],
        };
        let roots = [1, goals.len()];
        let mut attempts = [0u64; 2];
        let mut helpers: [Option<Helper>; 2] = [None, None];
        let mut chain = Vec::new();
        let mut target = request.start.clone();
        // Try connecting the goal tree straight to the start first.
        let mut joined = stepper
            .connect(motion, validator, &mut trees[1], &target)
            .map(|gi| (0, gi));
        let mut grow = 0usize;
        while joined.is_none() {
            if !run.next() {
                return Err(PlanError::Timeout {
                    stats: run.stats(motion, validator, vec![trees[0].len(), trees[1].len()]),
                });
            }
            // Alternate, unless balancing keeps the smaller tree growing.
            let (a, b) = (trees[grow].len(), trees[1 - grow].len());
            if !(self.balance && 2 * a <= b) {
                grow = 1 - grow;
            }
            motion.space().sample(rng, &mut target);
            attempts[grow] += 1;
            let [t0, t1] = &mut trees;
            let (this, other) = if grow == 0 { (t0, t1) } else { (t1, t0) };
            // A helper that stopped growing is dropped ([`Escape::reset`]).
            if let Some(e) = escape
                && helpers[grow].as_ref().is_some_and(|h| h.idle >= e.reset)
            {
                helpers[grow] = None;
            }
            let helper = match escape {
                Some(e)
                    if attempts[grow] >= e.after
                        && ((this.len() - roots[grow]) as u64).saturating_mul(e.stuck_ratio) < attempts[grow]
                        && rng.random::<f64>() < e.share =>
                {
                    Some((
                        helpers[grow].get_or_insert_with(|| Helper::new(this, roots[grow], dim)),
                        e,
                    ))
                }
                _ => None,
            };
            let extended = match helper {
                Some((h, e)) => {
                    let probe = (e.probe > 0.0 && rng.random::<f64>() < e.probe).then(|| e.step * range / 3.0);
                    stepper.escape(
                        motion,
                        validator,
                        this,
                        h,
                        &target,
                        (e.step * range, e.join * range, probe),
                        &mut chain,
                    )
                }
                None => stepper.extend(motion, validator, this, &target),
            };
            let Some(i) = extended else {
                continue;
            };
            let reached = match self.connect {
                Connect::Other => {
                    target.copy_from_slice(this.tree.state(i));
                    stepper.connect(motion, validator, other, &target).map(|j| (i, j))
                }
                Connect::Onward => {
                    let j = other
                        .tree
                        .nn
                        .nearest(motion.space(), this.tree.state(i))
                        .expect("trees are never empty");
                    target.copy_from_slice(other.tree.state(j));
                    stepper.line(motion, validator, this, i, &target).map(|k| (k, j))
                }
            };
            if let Some((mine, theirs)) = reached {
                joined = Some(if grow == 0 { (mine, theirs) } else { (theirs, mine) });
            }
        }
        let (si, gi) = joined.expect("loop ends when joined");
        let mut states = trees[0].tree.branch(si);
        let mut back = trees[1].tree.branch(gi);
        back.reverse();
        states.extend(back.into_iter().skip(1));
        let stats = run.stats(motion, validator, vec![trees[0].len(), trees[1].len()]);
        Ok(Solution {
            path: Path { states },
            stats,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::space::JointSpace;

    /// A channel that has only seen free directions in the x-y plane steers a target off that
    /// plane back into it (up to the floor), keeps the displacement's length and stays in
    /// the bounds; it forgets all but its last `CHANNEL_MEMORY` directions.
    #[test]
    fn a_channel_squashes_the_directions_it_never_saw_free() {
        let space = JointSpace::new(&[-2.0; 3], &[2.0; 3], &[false; 3]).unwrap();
        let mut channel = Channel::new(3);
        let origin = [0.0; 3];
        for k in 0..CHANNEL_READY {
            assert!(!channel.ready());
            let a = k as f64 * 0.7;
            channel.record(&space, &origin, &[a.cos() * 0.1, a.sin() * 0.1, 0.0]);
        }
        assert!(channel.ready());
        let out = channel.shape(&space, &origin, &[0.5, 0.5, 0.5]).to_vec();
        assert!((norm(&out) - norm(&[0.5; 3])).abs() < 1e-12, "{out:?}");
        // The floor leaves z a twentieth or so of what x and y get.
        assert!(out[2] > 0.0 && out[2] < 0.1 * out[0].min(out[1]), "{out:?}");
        // Clamped into the bounds.
        assert_eq!(channel.shape(&space, &[1.9, 0.0, 0.0], &[10.0, 0.0, 0.0])[0], 2.0);
        // Directions along z, recorded past the memory, replace the x-y ones entirely.
        for _ in 0..CHANNEL_MEMORY {
            channel.record(&space, &origin, &[0.0, 0.0, -0.2]);
        }
        let out = channel.shape(&space, &origin, &[0.5, 0.5, 0.5]);
        assert!(out[2] > 0.8 && out[0] < 0.1 * out[2], "{out:?}");
        // A zero displacement is not a direction.
        channel.record(&space, &origin, &origin);
        assert_eq!(channel.held, CHANNEL_MEMORY);
    }
}
