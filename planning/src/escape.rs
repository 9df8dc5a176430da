//! The pocket escape ([`Escape`]): a helper tree of short steps, steered through the free
//! directions its probes found, for a tree ([`BiRrt`]) or a roadmap's query end ([`LazyPrm`])
//! that barely grows because it sits in a pocket.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::motion::MotionValidator;
use crate::planner::Tree;
use crate::space::{Space, steer};
use crate::validity::StateValidator;
#[cfg(doc)]
use crate::{BiRrt, LazyPrm};

/// Settings of the pocket escape of [`BiRrt`] and of [`LazyPrm`]'s wedged query ends.
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
/// A tree's first helper begins by walking each root's tool straight along the tool's six
/// axis directions, in steps of 1 cm for up to 40 cm, while the states and motions stay valid
/// ([`StateValidator::tool_step`], which [`RobotValidity`](crate::validity::RobotValidity)
/// implements through the Jacobian), and keeps the walks as its first branches: a grasp
/// between shelf boards is left by backing straight out, a narrow channel in joint space.
/// On MotionBenchMaker's Fetch problems (BiRRT, seeds 0 and 1, every plan capped at 300,000
/// iterations so that both builds make the same plans), the 257 plans in which the escape
/// fired needed 0.72–0.77 of the iterations without the walks (geometric means; fewer in 148
/// of them, more in 82; `docs/planning-log.md`). Validators that know no tool add nothing.
/// The helpers that replace it after a [`reset`](Escape::reset) do not walk again: their
/// walks would be the same branches.
///
/// [`LazyPrm`] uses the same helper for a query end wedged in a small part of its roadmap
/// ([`LazyPrmSettings::escape`](crate::lazy_prm::LazyPrmSettings::escape)): there `range` is
/// the wedged end's tree step, the attempts are that end's growth turns, and a helper's branch
/// joins the roadmap as valid edges.
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
    /// out starts near the roots. A fresh helper draws its first steps anew (and does not
    /// repeat the first helper's tool walks). `u64::MAX`
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
/// state the state it became in what it joins ([`Grows`]), once it joined.
pub(crate) struct Helper {
    tree: Tree,
    joined: Vec<Option<usize>>,
    channel: Channel,
    /// Helper turns since it last grew or joined its tree.
    idle: u64,
    /// Whether the roots' tool retreats were walked ([`Helper::retreat`]).
    retreated: bool,
    /// Scratch: the state a step reaches, and a branch being joined.
    step: Vec<f64>,
    chain: Vec<usize>,
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

/// Length (m) of one tool step of a helper's retreat ([`Helper::retreat`]).
const RETREAT_STEP: f64 = 0.01;
/// Most tool steps of one retreat.
const RETREAT_STEPS: usize = 40;

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

impl Escape {
    /// [`PlanError::BadInput`] unless share is in (0, 1), 0 < step ≤ join ≤ 1, probe in
    /// [0, 1), and `stuck_ratio` and `reset` are positive.
    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        let e = self;
        if e.share > 0.0
            && e.share < 1.0
            && e.step > 0.0
            && e.step <= e.join
            && e.join <= 1.0
            && (0.0..1.0).contains(&e.probe)
            && e.stuck_ratio > 0
            && e.reset > 0
        {
            Ok(())
        } else {
            Err(PlanError::BadInput(format!(
                "escape {e:?}: share must be in (0, 1), 0 < step ≤ join ≤ 1, probe in [0, 1), stuck_ratio and reset positive"
            )))
        }
    }

    /// The helper that takes this turn of a tree (or a roadmap's wedged part) that has grown by
    /// `grown` states in `attempts` turns, with the step lengths of that turn for a planner step
    /// `range` (the helper's own step, the joining step, and the probe's when the turn is a
    /// probe); `None` when the turn is the tree's own. The helper in `slot` is replaced first
    /// by a fresh one from `new`, which does not walk its tools ([`Helper::retreat`]), when it
    /// has been idle for [`reset`](Escape::reset) turns; a stuck tree's first helper is made by
    /// `new` on first use. Both planners draw from `rng` in the same order through here.
    pub(crate) fn helper_turn<'h, R: Rng + ?Sized>(
        &self,
        slot: &'h mut Option<Helper>,
        (attempts, grown): (u64, u64),
        range: f64,
        rng: &mut R,
        new: impl FnOnce() -> Helper,
    ) -> Option<(&'h mut Helper, Steps)> {
        let stuck = attempts >= self.after && grown.saturating_mul(self.stuck_ratio) < attempts;
        if !(stuck && rng.random::<f64>() < self.share) {
            return None;
        }
        // An idle helper is only counted up on its own turns, so it is replaced at the next
        // one. The fresh helper does not walk again: its walks would be the same branches,
        // and a walled-in helper is replaced to draw its first steps anew.
        let replaced = slot.as_ref().is_some_and(|h| h.idle >= self.reset);
        if replaced {
            *slot = None;
        }
        let helper = slot.get_or_insert_with(new);
        helper.retreated |= replaced;
        let probe = (self.probe > 0.0 && rng.random::<f64>() < self.probe).then(|| self.step * range / 3.0);
        let (short, long) = (self.step * range, self.join * range);
        Some((helper, Steps { short, long, probe }))
    }
}

/// The step lengths of one helper turn ([`Escape::helper_turn`]).
pub(crate) struct Steps {
    /// The step that grows the helper.
    short: f64,
    /// The step that joins the helper's branch to its tree.
    long: f64,
    /// A probe's step, when the turn is a probe.
    probe: Option<f64>,
}

/// What a helper's branch joins once a long step from it is free: a planner's tree, or the
/// part of a roadmap around a wedged query end.
pub(crate) trait Grows {
    /// Adds `q`, reached from this structure's state `parent` by a motion found valid, and
    /// returns its index.
    fn grow<S: Space>(&mut self, space: &S, q: &[f64], parent: usize) -> usize;
}

/// Steps from `from` towards `target` by at most `length` into `out`; whether that state and
/// the motion to it are valid.
pub(crate) fn try_step<S: Space, V: StateValidator + ?Sized>(
    motion: &mut MotionValidator<S>,
    validator: &mut V,
    from: &[f64],
    target: &[f64],
    length: f64,
    out: &mut [f64],
) -> bool {
    steer(motion.space(), from, target, length, out);
    validator.is_valid(out) && motion.check_motion(validator, from, out)
}

impl Helper {
    /// Rebuilds the helper tree's nearest-neighbour index for `space` (a planner that changed
    /// its metric).
    pub(crate) fn reindex<S: Space>(&mut self, space: &S) {
        self.tree.nn.reindex(space);
    }

    /// Rooted at `roots`: each root's index in what the helper joins, and its state.
    pub(crate) fn new<'a>(roots: impl IntoIterator<Item = (usize, &'a [f64])>, dim: usize) -> Self {
        let mut tree = Tree::new(dim);
        let mut joined = Vec::new();
        for (at, q) in roots {
            tree.add(q, None);
            joined.push(Some(at));
        }
        Self {
            tree,
            joined,
            channel: Channel::new(dim),
            idle: 0,
            retreated: false,
            step: vec![0.0; dim],
            chain: Vec::new(),
        }
    }

    /// Adds helper state `h`'s branch to `into` where it is not there yet; returns the index
    /// of `h` there.
    fn join<S: Space, G: Grows>(&mut self, space: &S, h: usize, into: &mut G) -> usize {
        self.chain.clear();
        let mut at = h;
        let mut above = loop {
            if let Some(t) = self.joined[at] {
                break t;
            }
            self.chain.push(at);
            at = self.tree.parent(at).expect("helper roots have joined");
        };
        for &k in self.chain.iter().rev() {
            above = into.grow(space, self.tree.state(k), above);
            self.joined[k] = Some(above);
        }
        above
    }

    /// Walks the tool of each root straight along each of its six axis directions
    /// ([`StateValidator::tool_step`]), [`RETREAT_STEPS`] steps of [`RETREAT_STEP`] at most,
    /// each state and motion checked, and keeps the walks as helper branches: a grasp between
    /// shelf boards is left by backing straight out, which random joint steps seldom do. A
    /// validator that knows no tool leaves the helper as it was.
    fn retreat<S: Space, V: StateValidator + ?Sized>(&mut self, motion: &mut MotionValidator<S>, validator: &mut V) {
        let roots = self.joined.len();
        for root in 0..roots {
            for axis in 0..6 {
                let mut at = root;
                for _ in 0..RETREAT_STEPS {
                    if !validator.tool_step(self.tree.state(at), axis, RETREAT_STEP, &mut self.step) {
                        break;
                    }
                    let from = self.tree.state(at);
                    if !(validator.is_valid(&self.step) && motion.check_motion(validator, from, &self.step)) {
                        break;
                    }
                    at = self.tree.add(&self.step, Some(at));
                    self.joined.push(None);
                }
            }
        }
    }

    /// One helper turn from the helper state nearest `target`: either a `probe` step in the
    /// sample's direction that teaches the helper's [`Channel`] when it is free, or, with the
    /// target shaped by the channel once it has learnt enough, a `long` step, which joins
    /// `into` with its branch when valid (returns the new state's index there), else a `short`
    /// step that grows the helper.
    pub(crate) fn turn<S: Space, V: StateValidator + ?Sized, G: Grows>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        into: &mut G,
        target: &[f64],
        Steps { short, long, probe }: Steps,
    ) -> Option<usize> {
        if !self.retreated {
            self.retreated = true;
            self.retreat(motion, validator);
        }
        let near = self
            .tree
            .nn
            .nearest(motion.space(), target)
            .expect("helpers are never empty");
        // Counted back to 0 below when the helper grows or joins.
        self.idle += 1;
        if let Some(p) = probe {
            if try_step(motion, validator, self.tree.state(near), target, p, &mut self.step) {
                self.channel.record(motion.space(), self.tree.state(near), &self.step);
            }
            return None;
        }
        let aim: &[f64] = if self.channel.ready() {
            self.channel.shape(motion.space(), self.tree.state(near), target)
        } else {
            target
        };
        if try_step(motion, validator, self.tree.state(near), aim, long, &mut self.step) {
            self.idle = 0;
            let at = self.join(motion.space(), near, into);
            return Some(into.grow(motion.space(), &self.step, at));
        }
        if try_step(motion, validator, self.tree.state(near), aim, short, &mut self.step) {
            self.idle = 0;
            self.tree.add(&self.step, Some(near));
            self.joined.push(None);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::space::JointSpace;

    /// Free everywhere; its tool steps move along x and are counted.
    struct Tool(u64);
    impl StateValidator for Tool {
        fn is_valid(&mut self, _: &[f64]) -> bool {
            true
        }
        fn checks(&self) -> u64 {
            0
        }
        fn tool_step(&mut self, q: &[f64], axis: usize, length: f64, out: &mut [f64]) -> bool {
            self.0 += 1;
            out.copy_from_slice(q);
            out[0] += if axis < 3 { length } else { -length };
            axis.is_multiple_of(3)
        }
    }

    /// A tree's first helper walks its root's tool before its first turn (two walks of
    /// `RETREAT_STEPS` steps, along x and back, and one refused step for each other axis);
    /// the helper that replaces it after `reset` idle turns does not walk again.
    #[test]
    fn only_a_trees_first_helper_walks_its_tools() {
        let space = JointSpace::new(&[-2.0; 2], &[2.0; 2], &[false; 2]).unwrap();
        let mut motion = MotionValidator::new(space, 0.01);
        let mut tool = Tool(0);
        let escape = Escape {
            after: 0,
            stuck_ratio: 1,
            share: 0.999_999,
            probe: 0.0,
            reset: 3,
            ..Escape::default()
        };
        let mut into = crate::planner::Tree::new(2);
        into.add(&[0.0, 0.0], None);
        struct Into<'a>(&'a mut Tree);
        impl Grows for Into<'_> {
            fn grow<S: Space>(&mut self, _: &S, q: &[f64], parent: usize) -> usize {
                self.0.add(q, Some(parent))
            }
        }
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(3);
        let mut slot = None;
        let new = || Helper::new([(0, &[0.0, 0.0][..])], 2);
        // A target straight along y: no step towards it is refused, but the walks along x
        // come first.
        let (h, steps) = escape.helper_turn(&mut slot, (1, 0), 0.1, &mut rng, new).unwrap();
        h.turn(&mut motion, &mut tool, &mut Into(&mut into), &[0.0, 1.0], steps);
        assert_eq!(tool.0, 2 * RETREAT_STEPS as u64 + 4);
        let walked = 1 + 2 * RETREAT_STEPS;
        assert!(slot.as_ref().unwrap().tree.len() >= walked);
        slot.as_mut().unwrap().idle = escape.reset;
        let (h, steps) = escape.helper_turn(&mut slot, (1, 0), 0.1, &mut rng, new).unwrap();
        assert_eq!(h.tree.len(), 1, "a fresh helper");
        h.turn(&mut motion, &mut tool, &mut Into(&mut into), &[0.0, 1.0], steps);
        assert_eq!(tool.0, 2 * RETREAT_STEPS as u64 + 4, "no second walk");
    }

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
