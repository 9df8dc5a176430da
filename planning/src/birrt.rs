//! [`BiRrt`]: RRT-Connect (Kuffner & LaValle 2000), OMPL's `RRTConnect`.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
pub use crate::escape::Escape;
use crate::escape::{Grows, Helper, try_step};
use crate::motion::MotionValidator;
use crate::planner::{Budget, Path, PlanRequest, Planner, Run, Solution, Tree, resolve_range, valid_goals};
use crate::space::Space;
use crate::validity::StateValidator;

/// RRT-Connect: a tree from the start and a tree from the goals (seeded with every valid goal),
/// grown in turns. Each iteration extends one tree a step of at most `range` towards a random
/// sample, then greedily joins the trees along a straight line in equal steps of at most
/// `range` until it is reached or blocked: by default the other tree grows from its nearest
/// state towards the new one ([`Connect::Other`], Kuffner & LaValle's and OMPL's);
/// [`Connect::Onward`] lets the tree that just grew go on towards the other tree instead (as
/// VAMP's RRT-Connect does; measured, it helps neither robot's MotionBenchMaker problems). Tree balancing
/// ([`BiRrt::balance`], as in VAMP's RRT-Connect), shorter steps for a tree that has barely
/// grown ([`ShortSteps`]), the retraction of some of its blocked steps ([`Retraction`]) and
/// the pocket escape ([`Escape`]: a helper tree of short steps for a tree that still barely
/// grows) are on by default; dynamic-domain
/// sampling ([`DynamicDomain`]) is available but off, because it lowered success on the
/// MotionBenchMaker problems (`docs/planning-log.md`). [`BiRrt::plain`] is the textbook
/// algorithm; [`BiRrt::plan_with_metrics`] changes the metric part-way through a plan.
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
    /// Fetch (`docs/planning-log.md`). A step that is not positive and finite, or shorter than
    /// [`finest_resolution`](crate::motion::finest_resolution), is [`PlanError::BadInput`].
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
    /// Shorter steps for a tree that has barely grown ([`ShortSteps`]). `None` turns them off.
    pub short_steps: Option<ShortSteps>,
    /// Blocked short steps of a wedged tree pushed out of the obstacles ([`Retraction`]).
    /// `None` turns it off. It acts only while [`short_steps`](BiRrt::short_steps) finds a
    /// tree wedged.
    pub retraction: Option<Retraction>,
}

/// Retraction of a wedged tree's blocked steps: while [`ShortSteps`] finds a tree of
/// [`BiRrt`] wedged, every [`every`](Retraction::every)-th blocked extension hands the blocked
/// state to [`StateValidator::retract`], which pushes it out of the obstacles it sinks into
/// along the contact normals ([`rounds`](Retraction::rounds) joint steps, to
/// [`clearance`](Retraction::clearance) metres beyond the surface). When the pushed state is
/// valid, within 1.5 short steps of the tree's nearest state and joined to it by a valid
/// motion, it joins the tree. A narrow channel is thin in some directions: a sample beside
/// it lands in an obstacle, and the push brings it into the channel, where uniform samples
/// seldom fall (after the retraction-based RRT of Zhang & Manocha, ICRA 2008). Validators
/// that know no geometry retract nothing, and their plans are the same with or without it.
/// Measured on the MotionBenchMaker problems (`docs/planning-log.md`, fifty-sixth round):
/// the Fetch's five hardest bookshelf problems solve 75 of 90 plans within 1 s against 59,
/// and the Panda's cage goals plan in 2.32 ms against 2.51 ms at the median of 48 plans.
///
/// ```
/// use hearth_planning::birrt::{BiRrt, Retraction};
/// let r = Retraction::default();
/// assert!(r.every >= 1 && r.rounds > 0 && r.clearance > 0.0);
/// let without = BiRrt { retraction: None, ..BiRrt::default() };
/// assert_ne!(without, BiRrt::default());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Retraction {
    /// One blocked extension of a wedged tree in this many is retracted (at least 1).
    pub every: u64,
    /// Joint steps of one retraction, 1 to 64.
    pub rounds: usize,
    /// How far beyond the obstacles' surfaces a retraction aims, in metres, in [0, 1).
    pub clearance: f64,
}

impl Default for Retraction {
    /// One blocked extension in thirty, three joint steps, 1 cm beyond the surfaces.
    fn default() -> Self {
        Self {
            every: 30,
            rounds: 3,
            clearance: 0.01,
        }
    }
}

impl Retraction {
    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        if self.every == 0 || !(1..=64).contains(&self.rounds) || !(0.0..1.0).contains(&self.clearance) {
            return Err(PlanError::BadInput(format!(
                "retraction {self:?}: `every` must be at least 1, `rounds` in 1..=64 and `clearance` in [0, 1) m"
            )));
        }
        Ok(())
    }
}

/// Shorter steps for a wedged tree: once a tree of [`BiRrt`] has made
/// [`after`](ShortSteps::after) extension attempts and grown by fewer than one state per
/// [`per`](ShortSteps::per) of them, its extensions towards samples step
/// [`scale`](ShortSteps::scale) of the planner's step (the line that joins the trees keeps the
/// full step). A goal wedged in a pocket or at the end of a narrow channel is left only
/// through short free stretches, which full steps towards random samples overshoot into
/// the obstacles. Measured on the MotionBenchMaker problems (`docs/planning-log.md`,
/// fifty-fifth round): the Panda's cage goals plan in 2.1–2.5 ms against 3.0–3.6 ms at the
/// median over 24 plans a problem, and the Fetch's five hardest bookshelf problems solve 57
/// of 90 plans within 1 s against 48.
///
/// ```
/// use hearth_planning::birrt::{BiRrt, ShortSteps};
/// let s = ShortSteps::default();
/// assert!(s.scale > 0.0 && s.scale < 1.0 && s.per > 1);
/// assert_eq!(BiRrt::default().short_steps, Some(s));
/// let full_steps = BiRrt { short_steps: None, ..BiRrt::default() };
/// assert_ne!(full_steps, BiRrt::default());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ShortSteps {
    /// Extension attempts a tree makes before it can count as wedged.
    pub after: u64,
    /// A tree is wedged while it has grown by fewer than one state per this many attempts
    /// (at least 1).
    pub per: u64,
    /// A wedged tree's step, as a fraction of the planner's step, in (0, 1]; 1 keeps every
    /// step full, as `None` does (a settings file can write it, having no `None`).
    pub scale: f64,
}

impl Default for ShortSteps {
    /// After 100 attempts, fewer than one state per 500, steps of 0.4 of the planner's.
    fn default() -> Self {
        Self {
            after: 100,
            per: 500,
            scale: 0.4,
        }
    }
}

impl ShortSteps {
    fn validate(&self) -> Result<(), PlanError> {
        if self.per == 0 || !(self.scale > 0.0 && self.scale <= 1.0) {
            return Err(PlanError::BadInput(format!(
                "short steps {self:?}: `per` must be at least 1 and `scale` in (0, 1]"
            )));
        }
        Ok(())
    }

    /// Whether a tree that has grown by `grown` states in `attempts` attempts is wedged.
    fn wedged(&self, attempts: u64, grown: u64) -> bool {
        attempts >= self.after && grown.saturating_mul(self.per) < attempts
    }
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
            short_steps: Some(ShortSteps::default()),
            retraction: Some(Retraction::default()),
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
    /// assert!(plain.short_steps.is_none());
    /// ```
    pub fn plain(range: Option<f64>) -> Self {
        Self {
            range,
            dynamic_domain: None,
            balance: false,
            escape: None,
            connect: Connect::Other,
            short_steps: None,
            retraction: None,
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

impl Grows for Grown {
    fn grow<S: Space>(&mut self, _: &S, q: &[f64], parent: usize) -> usize {
        self.add(q, Some(parent))
    }
}

/// Scratch buffers and settings shared by the extension steps.
struct Stepper {
    range: f64,
    /// Dynamic domain in absolute units: (radius, min radius, alpha).
    domain: Option<(f64, f64, f64)>,
    step: Vec<f64>,
    from: Vec<f64>,
    /// Whether the last extension stepped towards its sample and was blocked (`step` then
    /// holds the blocked state).
    blocked: bool,
}

/// How far, in steps, a retracted state may lie from the tree state it joins ([`Retraction`]).
const RETRACTION_REACH: f64 = 1.5;

impl Stepper {
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
        self.blocked = false;
        if self.domain.is_some() && space.distance(grown.tree.state(near), target) > grown.radius[near] {
            return None;
        }
        let ok = try_step(
            motion,
            validator,
            grown.tree.state(near),
            target,
            self.range,
            &mut self.step,
        );
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
        self.blocked = !ok;
        ok.then(|| grown.add(&self.step, Some(near)))
    }

    /// Retracts the blocked step last taken ([`Retraction`]): the pushed state joins `grown`
    /// when it is valid, within 1.5 steps of its nearest state and joined to it by a valid
    /// motion. Returns its index.
    fn retract<S: Space, V: StateValidator + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        grown: &mut Grown,
        r: &Retraction,
    ) -> Option<usize> {
        if !validator.retract(&self.step, r.clearance, r.rounds, &mut self.from) {
            return None;
        }
        let space = motion.space();
        let near = grown.tree.nn.nearest(space, &self.from).expect("trees are never empty");
        let d = space.distance(grown.tree.state(near), &self.from);
        (d > 0.0
            && d <= RETRACTION_REACH * self.range
            && motion.check_motion(validator, grown.tree.state(near), &self.from))
        .then(|| grown.add(&self.from, Some(near)))
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
        self.plan_with_metrics(motion, validator, request, budget, rng, &mut [])
    }
}

impl BiRrt {
    /// Plans as [`Planner::plan`] does, but changes the metric part-way: after `later[k].0`
    /// iterations (in increasing order) the planner measures, steps and checks edges in the
    /// space `later[k].1` (the same coordinates and bounds, other distance weights) instead of
    /// the motion validator's. The trees are kept and their nearest-neighbour indexes rebuilt
    /// for the new metric. Switching after a number of iterations, not of seconds, keeps a
    /// plan reproducible: the same seed gives the same path on any machine. When the call
    /// returns, every space is back where it was. A space of another dimension than the
    /// motion validator's is [`PlanError::BadInput`].
    ///
    /// Different problems prefer different metrics: on the Fetch's MotionBenchMaker problems
    /// strong distance weights (the joints' reach, squared) solve goals between cage bars
    /// fastest and milder ones (its square roots) wedged bookshelf goals
    /// (`docs/planning-log.md`, fifty-first round).
    ///
    /// ```
    /// use hearth_planning::birrt::BiRrt;
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::planner::{Budget, Goal, PlanRequest};
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
    /// let mild = space.clone().with_weights(&[1.0, 0.5])?;
    /// let mut motion = MotionValidator::new(space.clone(), 0.01);
    /// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]));
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let mut later = [(100, mild.clone())];
    /// let solution = BiRrt::default()
    ///     .plan_with_metrics(&mut motion, &mut Wall(0), &request, &Budget::iterations(10_000), &mut rng, &mut later)
    ///     .unwrap();
    /// assert!(solution.path.states.iter().any(|q| q[1] > 0.8));
    /// assert_eq!((motion.space(), &later[0].1), (&space, &mild));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn plan_with_metrics<S: Space, V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
        later: &mut [(u64, S)],
    ) -> Result<Solution, PlanError> {
        let mut switched = 0;
        let result = self.plan_switching(motion, validator, request, budget, rng, later, &mut switched);
        // Swapped back in reverse order: every space where it was.
        for (_, space) in later[..switched].iter_mut().rev() {
            motion.swap_space(space);
        }
        result
    }

    #[allow(clippy::too_many_arguments)]
    fn plan_switching<S: Space, V: StateValidator + ?Sized, R: Rng + ?Sized>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
        later: &mut [(u64, S)],
        switched: &mut usize,
    ) -> Result<Solution, PlanError> {
        let mut run = Run::start(budget, motion, validator)?;
        let space = motion.space();
        if let Some(k) = later.iter().position(|(_, s)| s.dim() != space.dim()) {
            return Err(PlanError::BadInput(format!(
                "metric {k} of the schedule has {} coordinates, the planning space {}",
                later[k].1.dim(),
                space.dim()
            )));
        }
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
        if let Some(e) = &self.escape {
            e.validate()?;
        }
        if let Some(s) = &self.short_steps {
            s.validate()?;
        }
        if let Some(r) = &self.retraction {
            r.validate()?;
        }
        let escape = self.escape;
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
            blocked: false,
        };
        let roots = [1, goals.len()];
        let mut attempts = [0u64; 2];
        let mut helpers: [Option<Helper>; 2] = [None, None];
        let mut target = request.start.clone();
        // Try connecting the goal tree straight to the start first.
        let mut joined = stepper
            .connect(motion, validator, &mut trees[1], &target)
            .map(|gi| (0, gi));
        let mut grow = 0usize;
        // Blocked extensions of wedged trees, counted for [`Retraction::every`].
        let mut blocked = 0u64;
        while joined.is_none() {
            if !run.next() {
                return Err(PlanError::Timeout {
                    stats: run.stats(motion, validator, vec![trees[0].len(), trees[1].len()]),
                });
            }
            if let Some((at, space)) = later.get_mut(*switched)
                && run.iterations >= *at
            {
                *switched += 1;
                motion.swap_space(space);
                for t in &mut trees {
                    t.tree.nn.reindex(motion.space());
                }
                for h in helpers.iter_mut().flatten() {
                    h.reindex(motion.space());
                }
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
            // A stuck tree gives a share of its turns to its helper ([`Escape`]).
            let grown = (attempts[grow], (this.len() - roots[grow]) as u64);
            let helper = escape.and_then(|e| {
                e.helper_turn(&mut helpers[grow], grown, range, rng, || {
                    Helper::new((0..roots[grow]).map(|r| (r, this.tree.state(r))), dim)
                })
            });
            let extended = match helper {
                Some((h, steps)) => h.turn(motion, validator, this, &target, steps),
                None => {
                    let short = self.short_steps.filter(|s| s.wedged(grown.0, grown.1));
                    stepper.range = short.map_or(range, |s| range * s.scale);
                    let mut new = stepper.extend(motion, validator, this, &target);
                    if stepper.blocked
                        && short.is_some()
                        && let Some(r) = &self.retraction
                    {
                        blocked += 1;
                        if blocked.is_multiple_of(r.every) {
                            new = stepper.retract(motion, validator, this, r);
                        }
                    }
                    stepper.range = range;
                    new
                }
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
