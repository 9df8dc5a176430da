//! Every planner on the same fixture worlds: a 2-D narrow passage, a Panda over a table with a
//! post on it, and a MotionBenchMaker problem; plus bad input for every [`PlanError`] case.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use hearth_kinematics::{Chain, RobotModel};
use hearth_planning::motion::{MAX_SEGMENTS, finest_resolution};
use hearth_planning::obstacles::{Obstacle, ParryScene};
use hearth_planning::problem::ProblemSet;
use hearth_planning::shortcut::{self, ShortcutSettings};
use hearth_planning::space::{JointSpace, Space};
use hearth_planning::trajectory::Limits;
use hearth_planning::validity::{RobotValidity, StateValidator};
use hearth_planning::{
    BiRrt, Budget, Connect, DynamicDomain, Escape, Goal, LazyPrm, LazyPrmSettings, MotionValidator, Path, PlanError,
    PlanRequest, Planner, Race, Retraction, Rrt, ShortSteps, Solution,
};
use parry3d::math::{Pose, Vector};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

#[path = "support/matrix.rs"]
mod matrix;
use matrix::matrix;

/// A 2-D world given by which states are free; it counts its checks.
struct Region {
    free: fn(&[f64]) -> bool,
    checks: u64,
}

impl StateValidator for Region {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        (self.free)(q)
    }
    fn checks(&self) -> u64 {
        self.checks
    }
}

/// A wall at x ∈ [0.45, 0.55] with a gap at y ∈ [0.48, 0.52].
fn narrow_passage() -> Region {
    Region {
        free: |q| !(0.45..=0.55).contains(&q[0]) || (0.48..=0.52).contains(&q[1]),
        checks: 0,
    }
}

fn square() -> JointSpace {
    JointSpace::new(&[0., 0.], &[1., 1.], &[false, false]).unwrap()
}

/// Fine enough that an edge clipping a corner of the gap by more than 1e-4 is caught; the
/// paths are checked again at a 10× finer resolution.
const PASSAGE_RESOLUTION: f64 = 0.001;

/// From below the gap on one side to below it on the other: the straight line is blocked.
fn passage_request() -> PlanRequest {
    PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]))
}

/// The Panda arm, fingers open at 0.04, among `obstacles`.
fn panda(obstacles: ParryScene) -> (JointSpace, RobotValidity) {
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let space = JointSpace::from_chain(&arm).unwrap();
    let mut v = RobotValidity::new(arm, matrix("panda"), Arc::new(obstacles));
    let mut q_full = m.neutral_configuration();
    Chain::new(&m, &["panda_finger_joint1"])
        .unwrap()
        .scatter(&[0.04], &mut q_full);
    v.set_reference(&q_full).unwrap();
    (space, v)
}

const PANDA_RESOLUTION: f64 = 0.02;

/// A table in front of the Panda with a post standing on it between the start and the goal.
fn table_world() -> (JointSpace, RobotValidity) {
    let table = Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.2), Vector::new(0.3, 0.6, 0.02));
    let post = Obstacle::cuboid("post", Pose::translation(0.5, 0.0, 0.45), Vector::new(0.05, 0.05, 0.25));
    panda(ParryScene::new(vec![table, post]))
}

fn table_request() -> PlanRequest {
    PlanRequest::new(
        vec![-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785],
        Goal::Config(vec![0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785]),
    )
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// Whether `a` and `b` are the same state (up to rounding).
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
}

/// Checks a solution: it starts at the start, ends at a goal, every state is valid and every
/// motion passes the motion validator at the planning resolution; then the path repaired at a
/// 10× finer resolution (what the smoothing pipeline does first) passes at that resolution.
fn check_solution<S: Space + Clone, V: StateValidator>(
    space: &S,
    resolution: f64,
    validator: &mut V,
    request: &PlanRequest,
    solution: &Solution,
) {
    let states = &solution.path.states;
    assert!(states.len() >= 2, "a path has at least two states");
    assert_eq!(states[0], request.start, "the path starts at the start");
    let last = states.last().unwrap();
    assert!(
        request.goal.states().iter().any(|g| same(g, last)),
        "the path ends at a goal: {last:?}"
    );
    let mut coarse = MotionValidator::new(space.clone(), resolution);
    for (i, w) in states.windows(2).enumerate() {
        assert!(validator.is_valid(&w[1]), "state {} is invalid", i + 1);
        assert!(
            coarse.check_motion(validator, &w[0], &w[1]),
            "motion {i} → {} is invalid",
            i + 1
        );
    }
    let mut rng = Pcg64Mcg::seed_from_u64(0);
    let fine_resolution = resolution / 10.0;
    let (repaired, _) = hearth_planning::shortcut::repair(
        space,
        validator,
        &solution.path,
        fine_resolution,
        std::time::Duration::from_secs(5),
        &mut rng,
    )
    .expect("repair at the fine resolution");
    let mut fine = MotionValidator::new(space.clone(), fine_resolution);
    assert_eq!(repaired.states.first(), states.first());
    assert_eq!(repaired.states.last(), states.last());
    for (i, w) in repaired.states.windows(2).enumerate() {
        assert!(
            fine.check_motion(validator, &w[0], &w[1]),
            "repaired motion {i} → {} is invalid",
            i + 1
        );
    }
}

fn solve<S: Space + Clone, V: StateValidator, P: Planner<S>>(
    label: &str,
    make: impl Fn() -> P,
    space: &S,
    resolution: f64,
    validator: &mut V,
    request: &PlanRequest,
    budget: &Budget,
) -> Solution {
    let mut runs = Vec::new();
    for _ in 0..2 {
        let mut motion = MotionValidator::new(space.clone(), resolution);
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let t = Instant::now();
        let solution = make()
            .plan(&mut motion, validator, request, budget, &mut rng)
            .unwrap_or_else(|e| panic!("{label}: {e}"));
        println!(
            "{label}: {:.2} ms, {} states, length {:.3}, {:?}",
            t.elapsed().as_secs_f64() * 1e3,
            solution.path.states.len(),
            solution.path.length(space),
            solution.stats
        );
        runs.push(solution);
    }
    assert_eq!(runs[0].path, runs[1].path, "{label}: same seed, same path");
    let solution = runs.pop().unwrap();
    check_solution(space, resolution, validator, request, &solution);
    solution
}

/// Iteration budgets keep runs reproducible; the time limit is only a safety net.
fn budget(iterations: u64) -> Budget {
    Budget::iterations(iterations).with_time(20.0)
}

/// Solves the narrow passage and checks the path crosses the wall's plane x = 0.5 in the gap.
fn passage<P: Planner<JointSpace>>(label: &str, make: impl Fn() -> P) {
    let s = solve(
        label,
        make,
        &square(),
        PASSAGE_RESOLUTION,
        &mut narrow_passage(),
        &passage_request(),
        &budget(200_000),
    );
    let crossings: Vec<f64> = s
        .path
        .states
        .windows(2)
        .filter(|w| (w[0][0] - 0.5) * (w[1][0] - 0.5) <= 0.0 && w[0][0] != w[1][0])
        .map(|w| w[0][1] + (0.5 - w[0][0]) / (w[1][0] - w[0][0]) * (w[1][1] - w[0][1]))
        .collect();
    assert!(!crossings.is_empty(), "{label}: the path crosses the wall");
    for y in crossings {
        assert!(
            (0.48..=0.52).contains(&y),
            "{label}: crosses x = 0.5 at y = {y}, outside the gap"
        );
    }
}

#[test]
fn narrow_passage_rrt() {
    passage("passage/rrt", Rrt::default);
}

#[test]
fn narrow_passage_birrt() {
    passage("passage/birrt", BiRrt::default);
}

/// Textbook RRT-Connect: strictly alternating trees, no dynamic domain.
#[test]
fn narrow_passage_birrt_plain() {
    passage("passage/birrt_plain", || BiRrt::plain(None));
}

/// The tree that just grew goes on along the joining line (VAMP's RRT-Connect) instead of the
/// other tree (the default, OMPL's).
#[test]
fn narrow_passage_birrt_connect_onward() {
    passage("passage/birrt_onward", || BiRrt {
        connect: Connect::Onward,
        ..BiRrt::default()
    });
}

/// Dynamic-domain sampling: states wedged against the wall only accept near samples.
#[test]
fn narrow_passage_birrt_dynamic_domain() {
    passage("passage/birrt_dd", || BiRrt {
        dynamic_domain: Some(DynamicDomain::default()),
        ..BiRrt::default()
    });
}

/// A pocket: the goal sits at the closed end of a corridor x ∈ (0.6, 0.9), y ∈ (0.45, 0.55)
/// inside a block x ∈ [0.55, 0.95], y ∈ [0.4, 0.6], whose only way out is a hole
/// x ∈ (0.6, 0.63) through the top wall (coordinates relative to (100, 100), the middle of
/// [`pocket_space`]). No straight line from the goal leaves the corridor
/// (it would have to pass the hole's bottom with a slope under 0.2 and its top with one over
/// 0.35), so a goal tree of 0.4-long steps grows only from samples that land within a step
/// of it inside the corridor: in the 200 × 200 square of [`pocket_space`], about one in 10⁶.
fn pocket() -> Region {
    Region {
        free: |q| {
            let (x, y) = (q[0] - 100.0, q[1] - 100.0);
            let block = (0.55..=0.95).contains(&x) && (0.4..=0.6).contains(&y);
            let corridor = x > 0.6 && x < 0.9 && y > 0.45 && y < 0.55;
            let hole = x > 0.6 && x < 0.63 && y >= 0.55;
            !block || corridor || hole
        },
        checks: 0,
    }
}

/// Edge checks in the pocket world: a tenth of the hole's width.
const POCKET_RESOLUTION: f64 = 0.003;

fn pocket_space() -> JointSpace {
    JointSpace::new(&[0., 0.], &[200., 200.], &[false, false]).unwrap()
}

/// [`solve`] in [`pocket`] within 200,000 iterations, asserting that the path leaves through
/// the hole (some point of an edge, sampled a hundred times, lies in it).
fn solve_pocket<P: Planner<JointSpace>>(label: &str, make: impl Fn() -> P, request: &PlanRequest) -> Solution {
    let s = solve(
        label,
        make,
        &pocket_space(),
        POCKET_RESOLUTION,
        &mut pocket(),
        request,
        &budget(200_000),
    );
    let through_hole = s.path.states.windows(2).any(|w| {
        (0..=100).any(|i| {
            let t = f64::from(i) / 100.0;
            let (x, y) = (w[0][0] + t * (w[1][0] - w[0][0]), w[0][1] + t * (w[1][1] - w[0][1]));
            x > 100.6 && x < 100.63 && y > 100.55 && y < 100.6
        })
    });
    assert!(through_hole, "{label}: {:?}", s.path.states);
    s
}

#[test]
fn pocketed_goal_birrt_escape() {
    pocketed_goal_escape("pocket/birrt", Connect::Other);
}

#[test]
fn pocketed_goal_birrt_escape_onward() {
    pocketed_goal_escape("pocket/birrt_onward", Connect::Onward);
}

/// The goal in [`pocket`] is reached through the hole with the escape, and never without it
/// (with full steps only: [`pocketed_goal_birrt_short_steps`] leaves by shorter ones).
fn pocketed_goal_escape(label: &str, connect: Connect) {
    let request = PlanRequest::new(vec![20.0, 20.0], Goal::Config(vec![100.88, 100.5]));
    let with = |escape| BiRrt {
        range: Some(0.4),
        escape,
        connect,
        short_steps: None,
        ..BiRrt::default()
    };
    solve_pocket(label, || with(Some(Escape::default())), &request);
    // Without the escape the goal tree stays at the goal.
    let mut motion = MotionValidator::new(pocket_space(), POCKET_RESOLUTION);
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    match with(None).plan(&mut motion, &mut pocket(), &request, &budget(200_000), &mut rng) {
        Err(PlanError::Timeout { stats }) => assert_eq!(stats.tree_sizes[1], 1, "{stats:?}"),
        other => panic!("{label}: expected a timeout, got {other:?}"),
    }
}

/// (plans solved, iterations in all) of `birrt` in [`pocket`] from (20, 20) over sixteen
/// streams, each within 400,000 iterations.
fn pocket_runs(birrt: &BiRrt) -> (usize, u64) {
    let request = PlanRequest::new(vec![20.0, 20.0], Goal::Config(vec![100.88, 100.5]));
    sixteen_streams(birrt, (pocket_space(), POCKET_RESOLUTION), pocket, &request, false)
}

/// A wedged tree's shorter steps ([`ShortSteps`]) in [`pocket`]: steps of 0.16 fit along the
/// corridor, so the goal tree spreads through it, and a near-vertical one from below the hole
/// sometimes clears it. Over sixteen streams: with the escape as well every plan succeeds in
/// about two thirds of the iterations the escape alone takes (217,700 against 322,790), and
/// alone they solve 7 plans where full steps alone solve none.
#[test]
fn pocketed_goal_birrt_short_steps() {
    let request = PlanRequest::new(vec![20.0, 20.0], Goal::Config(vec![100.88, 100.5]));
    let with = |escape, short_steps| BiRrt {
        range: Some(0.4),
        escape,
        short_steps,
        ..BiRrt::default()
    };
    let run = |escape, short_steps| pocket_runs(&with(escape, short_steps));
    let (e, s) = (Some(Escape::default()), Some(ShortSteps::default()));
    let (both, escape, short, neither) = (run(e, s), run(e, None), run(None, s), run(None, None));
    println!(
        "pocket (solved, iterations): both {both:?}, escape {escape:?}, short steps {short:?}, neither {neither:?}"
    );
    assert_eq!((both.0, escape.0, neither.0), (16, 16, 0));
    assert!(
        4 * both.1 < 3 * escape.1,
        "with short steps {both:?}, without {escape:?}"
    );
    assert!(short.0 >= 4, "short steps alone: {short:?}");
    // Bad settings (scale, per) are refused before planning.
    for (scale, per) in [(0.0, 500), (1.5, 500), (f64::NAN, 500), (0.4, 0)] {
        let bad = ShortSteps {
            scale,
            per,
            ..ShortSteps::default()
        };
        let mut motion = MotionValidator::new(pocket_space(), POCKET_RESOLUTION);
        let mut rng = Pcg64Mcg::seed_from_u64(0);
        let got = with(None, Some(bad)).plan(&mut motion, &mut pocket(), &request, &budget(10), &mut rng);
        assert!(
            matches!(&got, Err(PlanError::BadInput(m)) if m.contains("short steps")),
            "{bad:?}: {got:?}"
        );
    }
}

/// Half the width of [`channel_free`]'s channel.
const CHANNEL_HALF_WIDTH: f64 = 0.0002;

/// A block x ∈ [0.3, 0.9], y ∈ [0.3, 0.7] with a straight channel 0.4 mm wide cut into it
/// from its left face, x < 0.85, |y − 0.5| < [`CHANNEL_HALF_WIDTH`]: a goal at its far end is
/// left only along it. A step of 0.2 from the goal is free for about one sample direction in
/// 1,600, a uniform sample lands in it once in 4,500 draws.
fn channel_free(q: &[f64]) -> bool {
    let (x, y) = (q[0], q[1]);
    let block = (0.3..=0.9).contains(&x) && (0.3..=0.7).contains(&y);
    !block || (x < 0.85 && (y - 0.5).abs() < CHANNEL_HALF_WIDTH)
}

/// [`channel_free`] with its exact retraction when `retracts`: a state in the block moves
/// to the nearest free point (outside the block or in the channel), `clearance` inside it.
struct Channel {
    retracts: bool,
    checks: u64,
}

impl StateValidator for Channel {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        channel_free(q)
    }
    fn checks(&self) -> u64 {
        self.checks
    }
    fn retract(&mut self, q: &[f64], clearance: f64, _rounds: usize, out: &mut [f64]) -> bool {
        if !self.retracts {
            return false;
        }
        let (x, y, c) = (q[0], q[1], clearance.min(CHANNEL_HALF_WIDTH / 2.0));
        // The free boxes: around the block, and the channel shrunk by the clearance.
        let boxes = [
            (f64::MIN, 0.3 - c, f64::MIN, f64::MAX),
            (0.9 + c, f64::MAX, f64::MIN, f64::MAX),
            (f64::MIN, f64::MAX, f64::MIN, 0.3 - c),
            (f64::MIN, f64::MAX, 0.7 + c, f64::MAX),
            (
                f64::MIN,
                0.85 - c,
                0.5 - CHANNEL_HALF_WIDTH + c,
                0.5 + CHANNEL_HALF_WIDTH - c,
            ),
        ];
        out.copy_from_slice(&nearest_in_boxes(&boxes, x, y));
        self.is_valid(out)
    }
}

/// The point of the boxes `(x0, x1, y0, y1)` nearest to `(x, y)`: the exact retraction of
/// the test worlds whose free space is a union of boxes.
fn nearest_in_boxes(boxes: &[(f64, f64, f64, f64)], x: f64, y: f64) -> [f64; 2] {
    let (nx, ny) = boxes
        .iter()
        .map(|&(x0, x1, y0, y1)| (x.clamp(x0, x1), y.clamp(y0, y1)))
        .min_by(|a, b| f64::hypot(a.0 - x, a.1 - y).total_cmp(&f64::hypot(b.0 - x, b.1 - y)))
        .expect("at least one box");
    [nx, ny]
}

/// Plans `request` in `space` over sixteen streams (seeds 0–15, 400,000 iterations each) with
/// a fresh `planner` and a fresh validator from `world` for each, edges checked at
/// `resolution`; when `check`, every solution is checked against another fresh validator.
/// Returns the plans solved and the iterations of all sixteen together.
fn sixteen_streams<P: Planner<JointSpace> + Clone + std::fmt::Debug, V: StateValidator>(
    planner: &P,
    (space, resolution): (JointSpace, f64),
    world: impl Fn() -> V,
    request: &PlanRequest,
    check: bool,
) -> (usize, u64) {
    let (mut solved, mut iterations) = (0, 0);
    for seed in 0..16u64 {
        let mut motion = MotionValidator::new(space.clone(), resolution);
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        match planner
            .clone()
            .plan(&mut motion, &mut world(), request, &budget(400_000), &mut rng)
        {
            Ok(s) => {
                if check {
                    check_solution(&space, resolution, &mut world(), request, &s);
                }
                solved += 1;
                iterations += s.stats.iterations;
            }
            Err(PlanError::Timeout { stats }) => iterations += stats.iterations,
            Err(e) => panic!("{planner:?}: {e}"),
        }
    }
    (solved, iterations)
}

/// A wedged tree's blocked steps retracted ([`Retraction`]) in [`channel_free`]'s world: the
/// goal tree's steps along the channel are blocked unless aimed within a few degrees of its
/// axis, and a blocked step pushed back into the channel lies further along it. Over sixteen
/// streams, every plan succeeds with and without retraction, with retraction in 0.54 of the
/// iterations (71,608 against 131,722); a validator that knows no geometry plans exactly as without (the same
/// iterations: retraction draws no random numbers). Bad settings are
/// [`PlanError::BadInput`].
#[test]
fn channel_goal_birrt_retraction() {
    let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.8, 0.5]));
    let with = |retraction| BiRrt {
        range: Some(0.2),
        retraction,
        ..BiRrt::default()
    };
    let runs = |birrt: &BiRrt, retracts: bool| {
        sixteen_streams(
            birrt,
            (square(), PASSAGE_RESOLUTION),
            || Channel { retracts, checks: 0 },
            &request,
            true,
        )
    };
    let on = Some(Retraction::default());
    let (retracted, without, no_geometry) = (runs(&with(on), true), runs(&with(None), true), runs(&with(on), false));
    println!(
        "channel (solved, iterations): retraction {retracted:?}, without {without:?}, no geometry {no_geometry:?}"
    );
    assert_eq!((retracted.0, without.0), (16, 16));
    assert!(
        10 * retracted.1 < 7 * without.1,
        "retracted {retracted:?}, without {without:?}"
    );
    assert_eq!(no_geometry, without, "no geometry, nothing retracted");
    // Bad settings (every, rounds, clearance) are refused before planning.
    for (every, rounds, clearance) in [
        (0, 3, 0.01),
        (30, 0, 0.01),
        (30, 65, 0.01),
        (30, 3, -0.01),
        (30, 3, f64::NAN),
        (30, 3, 1.0),
    ] {
        let bad = Retraction {
            every,
            rounds,
            clearance,
        };
        let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
        let mut rng = Pcg64Mcg::seed_from_u64(0);
        let mut world = Channel {
            retracts: true,
            checks: 0,
        };
        let got = with(Some(bad)).plan(&mut motion, &mut world, &request, &budget(10), &mut rng);
        assert!(
            matches!(&got, Err(PlanError::BadInput(m)) if m.contains("retraction")),
            "{bad:?}: {got:?}"
        );
    }
}

/// Half the width of [`Elbow`]'s channel.
const ELBOW_HALF_WIDTH: f64 = 0.02;

/// [`channel_free`]'s block with a channel 4 cm wide that turns a corner: in from the left
/// face along y = 0.5 to x = 0.72, then up along x = 0.7 to y = 0.66. A goal at the top of the
/// upright leg is seen from no state outside the block. With its exact retraction when
/// `retracts`: a state in the block moves to the nearest free point, `clearance` inside it.
struct Elbow {
    retracts: bool,
    checks: u64,
}

impl Elbow {
    /// The free boxes `(x0, x1, y0, y1)`, each shrunk by `c`: around the block, then the two
    /// legs.
    fn free_boxes(c: f64) -> [(f64, f64, f64, f64); 6] {
        let h = ELBOW_HALF_WIDTH;
        [
            (f64::MIN, 0.3 - c, f64::MIN, f64::MAX),
            (0.9 + c, f64::MAX, f64::MIN, f64::MAX),
            (f64::MIN, f64::MAX, f64::MIN, 0.3 - c),
            (f64::MIN, f64::MAX, 0.7 + c, f64::MAX),
            (f64::MIN, 0.72 - c, 0.5 - h + c, 0.5 + h - c),
            (0.7 - h + c, 0.7 + h - c, 0.5 - h + c, 0.66 - c),
        ]
    }
}

impl StateValidator for Elbow {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        let inside = |(x0, x1, y0, y1): (f64, f64, f64, f64)| (x0..x1).contains(&q[0]) && (y0..y1).contains(&q[1]);
        Self::free_boxes(0.0).into_iter().any(inside)
    }
    fn checks(&self) -> u64 {
        self.checks
    }
    fn retract(&mut self, q: &[f64], clearance: f64, _rounds: usize, out: &mut [f64]) -> bool {
        if !self.retracts {
            return false;
        }
        let boxes = Self::free_boxes(clearance.min(ELBOW_HALF_WIDTH / 2.0));
        out.copy_from_slice(&nearest_in_boxes(&boxes, q[0], q[1]));
        self.is_valid(out)
    }
}

/// RRT's goal-zone samples that land in [`Elbow`]'s block retracted
/// ([`Rrt::zone_retraction`]) with a step longer than the square, as the benchmark's RRT takes
/// for the robots (so every sample is within a step of the tree and checked itself): most
/// pushed samples land in the channel's legs, where uniform and zone samples seldom fall, and
/// one at the corner sees the goal. Over sixteen streams with every colliding zone sample
/// retracted, every plan succeeds, in 0.65 of the iterations without (14,841 against 23,003); a
/// validator that knows no geometry plans exactly as without (retraction draws no random
/// numbers). Bad settings are [`PlanError::BadInput`].
#[test]
fn elbow_goal_rrt_zone_retraction() {
    let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.7, 0.64]));
    let with = |zone_retraction| Rrt {
        range: Some(2.0),
        zone_retraction,
        ..Rrt::default()
    };
    let runs = |rrt: &Rrt, retracts: bool| {
        sixteen_streams(
            rrt,
            (square(), PASSAGE_RESOLUTION),
            || Elbow { retracts, checks: 0 },
            &request,
            true,
        )
    };
    let every = Some(Retraction {
        every: 1,
        ..Retraction::default()
    });
    let (retracted, without, no_geometry) = (
        runs(&with(every), true),
        runs(&with(None), true),
        runs(&with(every), false),
    );
    println!(
        "elbow RRT (solved, iterations): zone retraction {retracted:?}, without {without:?}, no geometry {no_geometry:?}"
    );
    assert_eq!(retracted.0, 16, "retracted {retracted:?}");
    assert!(
        retracted.0 >= without.0 && 5 * retracted.1 < 4 * without.1,
        "retracted {retracted:?}, without {without:?}"
    );
    assert_eq!(no_geometry, without, "no geometry, nothing retracted");
    for bad in [(0, 3, 0.01), (1, 0, 0.01), (1, 3, f64::NAN)] {
        let (every, rounds, clearance) = bad;
        let rrt = with(Some(Retraction {
            every,
            rounds,
            clearance,
        }));
        let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
        let mut world = Elbow {
            retracts: true,
            checks: 0,
        };
        let got = rrt.clone().plan(
            &mut motion,
            &mut world,
            &request,
            &budget(10),
            &mut Pcg64Mcg::seed_from_u64(0),
        );
        assert!(
            matches!(&got, Err(PlanError::BadInput(m)) if m.contains("retraction")),
            "{bad:?}: {got:?}"
        );
    }
}

/// In [`pocket`], a helper can wall itself in: once it fills the corridor's far end, its
/// states there are the nearest to almost every sample and no step from them is free, while
/// the hole starts at the other end. Dropping a helper that has stopped growing
/// ([`Escape::reset`]) lets a fresh one draw its first steps anew: over sixteen streams every
/// plan succeeds, in under half the iterations the streams need when a helper is kept for
/// the whole plan (one of which does not succeed within the budget).
#[test]
fn pocketed_goal_birrt_escape_reset() {
    let run = |reset: u64| {
        pocket_runs(&BiRrt {
            range: Some(0.4),
            escape: Some(Escape {
                reset,
                ..Escape::default()
            }),
            ..BiRrt::default()
        })
    };
    let (reset, kept) = (run(Escape::default().reset), run(u64::MAX));
    println!("pocket: {reset:?} (solved, iterations) with resets, {kept:?} without");
    assert_eq!(reset.0, 16, "with resets: {reset:?}");
    assert!(2 * reset.1 < kept.1, "with resets {reset:?}, without {kept:?}");
}

/// LazyPRM in [`pocket`]: the goal's part of the roadmap grows like a tree of 0.4-long steps
/// (`tree_step` × `range`), none of which leaves the corridor, and uniform samples land in it
/// about once in 10⁶. The pocket escape ([`LazyPrmSettings::escape`], the helper BiRRT uses)
/// takes the goal's part out through the hole; without it the part stays at the goal.
#[test]
fn lazy_prm_escapes_a_pocketed_goal() {
    let request = PlanRequest::new(vec![99.0, 100.0], Goal::Config(vec![100.88, 100.5]));
    let with = |escape| {
        LazyPrm::new(LazyPrmSettings {
            range: Some(1.6),
            escape,
            ..LazyPrmSettings::default()
        })
    };
    solve_pocket("pocket/lazy_prm_escape", || with(Some(Escape::default())), &request);
    let mut motion = MotionValidator::new(pocket_space(), POCKET_RESOLUTION);
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    match with(None).plan(&mut motion, &mut pocket(), &request, &budget(200_000), &mut rng) {
        Err(PlanError::Timeout { .. }) => {}
        other => panic!("pocket/lazy_prm without the escape: expected a timeout, got {other:?}"),
    }
}

/// A 6-D slab: below x₀ = 4 only states within 0.03 of 5 in x₂…x₅ are free, so a goal at
/// x₀ = 0.5 leaves through a channel thin in four directions and long in two.
fn slab() -> Region {
    Region {
        free: |q| q[0] > 4.0 || q[2..].iter().all(|v| (v - 5.0).abs() < 0.03),
        checks: 0,
    }
}

/// [`slab`]'s space (0 to 10 in each of six coordinates) and the query, from outside the slab to
/// a goal deep inside it.
fn slab_problem() -> (JointSpace, PlanRequest) {
    let space = JointSpace::new(&[0.0; 6], &[10.0; 6], &[false; 6]).unwrap();
    let request = PlanRequest::new(
        vec![8.0, 2.0, 2.0, 8.0, 2.0, 8.0],
        Goal::Config(vec![0.5, 5.0, 5.0, 5.0, 5.0, 5.0]),
    );
    (space, request)
}

/// In [`slab`], the helper's channel (`Escape::probe`) learns the four thin directions from
/// its probes and steers its steps along the slab: with the same streams it reaches the goal
/// in under half the iterations it needs without the channel.
#[test]
fn slab_goal_birrt_escape_channel() {
    let (space, request) = slab_problem();
    let with = |probe| BiRrt {
        range: Some(1.0),
        escape: Some(Escape {
            probe,
            ..Escape::default()
        }),
        ..BiRrt::default()
    };
    let s = solve(
        "slab/birrt",
        || with(Escape::default().probe),
        &space,
        0.01,
        &mut slab(),
        &request,
        &budget(400_000),
    );
    assert!(s.path.states.iter().any(|q| q[0] < 4.0 && q[0] > 1.0));
    let iterations = |probe: f64| {
        (0..4u64)
            .map(|seed| {
                let mut motion = MotionValidator::new(space.clone(), 0.01);
                let mut rng = Pcg64Mcg::seed_from_u64(seed);
                match with(probe).plan(&mut motion, &mut slab(), &request, &budget(400_000), &mut rng) {
                    Ok(s) => s.stats.iterations,
                    Err(PlanError::Timeout { stats }) => stats.iterations,
                    Err(e) => panic!("slab, probe {probe}: {e}"),
                }
            })
            .sum::<u64>()
    };
    let (channel, straight) = (iterations(Escape::default().probe), iterations(0.0));
    println!("slab: {channel} iterations over four seeds with the channel, {straight} without");
    assert!(
        2 * channel < straight,
        "iterations with the channel {channel}, without {straight}"
    );
}

/// [`slab`] with a "tool" whose steps ([`StateValidator::tool_step`]) move along x₀ only, ten
/// units per metre: the way a robot's gripper backs straight out of a shelf. Without
/// `tool`, it has none (the trait's default).
struct ToolSlab {
    slab: Region,
    tool: bool,
}

impl StateValidator for ToolSlab {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.slab.is_valid(q)
    }
    fn checks(&self) -> u64 {
        self.slab.checks()
    }
    fn tool_step(&mut self, q: &[f64], axis: usize, length: f64, out: &mut [f64]) -> bool {
        if !self.tool || !axis.is_multiple_of(3) {
            return false;
        }
        out.copy_from_slice(q);
        out[0] += if axis < 3 { 10.0 * length } else { -10.0 * length };
        (0.0..=10.0).contains(&out[0])
    }
}

/// A stuck tree's escape helper first walks its roots' tools straight along their axes (the
/// retreat): in [`slab`], whose tool backs out along x₀, BiRRT and LazyPRM with the same
/// streams reach the goal in under half the iterations they need when the validator has no
/// tool, and the path leaves the slab along the retreat (a state with x₀ in (0.5, 4) and the
/// thin coordinates at the goal's).
#[test]
fn slab_goal_escape_retreats_along_the_tool() {
    let (space, request) = slab_problem();
    let validator = |tool| ToolSlab { slab: slab(), tool };
    // A tree counts as stuck after 1,000 turns (10,000 by default), so that the iterations
    // compared are mostly the escape's.
    let escape = Some(Escape {
        after: 1_000,
        stuck_ratio: 200,
        ..Escape::default()
    });
    let birrt = || BiRrt {
        range: Some(1.0),
        escape,
        ..BiRrt::default()
    };
    let lazy = || {
        LazyPrm::new(LazyPrmSettings {
            range: Some(4.0),
            escape,
            ..LazyPrmSettings::default()
        })
    };
    fn iterations<P: Planner<JointSpace>>(
        make: impl Fn() -> P,
        space: &JointSpace,
        mut validator: impl FnMut() -> ToolSlab,
        request: &PlanRequest,
    ) -> (u64, Vec<Path>) {
        let (mut total, mut paths) = (0, Vec::new());
        for seed in 0..4u64 {
            let mut motion = MotionValidator::new(space.clone(), 0.01);
            let mut rng = Pcg64Mcg::seed_from_u64(seed);
            match make().plan(&mut motion, &mut validator(), request, &budget(400_000), &mut rng) {
                Ok(s) => {
                    total += s.stats.iterations;
                    paths.push(s.path);
                }
                Err(PlanError::Timeout { stats }) => total += stats.iterations,
                Err(e) => panic!("slab with a tool: {e}"),
            }
        }
        (total, paths)
    }
    for (label, (with, paths), (without, _)) in [
        (
            "birrt",
            iterations(birrt, &space, || validator(true), &request),
            iterations(birrt, &space, || validator(false), &request),
        ),
        (
            "lazy_prm",
            iterations(lazy, &space, || validator(true), &request),
            iterations(lazy, &space, || validator(false), &request),
        ),
    ] {
        println!("slab/{label}: {with} iterations over four seeds with the tool, {without} without");
        assert!(2 * with < without, "{label}: with the tool {with}, without {without}");
        assert_eq!(paths.len(), 4, "{label}: every seed solves with the tool");
        for path in &paths {
            let retreated = path
                .states
                .iter()
                .any(|q| q[0] > 0.6 && q[0] < 4.0 && q[2..].iter().all(|v| (v - 5.0).abs() < 1e-9));
            assert!(retreated, "{label}: {:?}", path.states);
        }
    }
}

#[test]
fn narrow_passage_lazy_prm() {
    passage("passage/lazy_prm", LazyPrm::default);
}

#[test]
fn panda_table_rrt() {
    let (space, mut v) = table_world();
    solve(
        "table/rrt",
        Rrt::default,
        &space,
        PANDA_RESOLUTION,
        &mut v,
        &table_request(),
        &budget(50_000),
    );
}

#[test]
fn panda_table_birrt() {
    let (space, mut v) = table_world();
    solve(
        "table/birrt",
        BiRrt::default,
        &space,
        PANDA_RESOLUTION,
        &mut v,
        &table_request(),
        &budget(50_000),
    );
}

#[test]
fn panda_table_lazy_prm() {
    let (space, mut v) = table_world();
    solve(
        "table/lazy_prm",
        LazyPrm::default,
        &space,
        PANDA_RESOLUTION,
        &mut v,
        &table_request(),
        &budget(50_000),
    );
}

/// The three planners in the joint space weighted by the joints' reach
/// ([`RobotValidity::joint_weights`], as the benchmark plans): solved, valid and reproducible.
#[test]
fn panda_table_planners_with_reach_weights() {
    let (space, mut v) = table_world();
    let w = v.joint_weights();
    assert_eq!(w.iter().cloned().fold(0.0, f64::max), 1.0, "{w:?}");
    assert!(w.iter().all(|&x| x > 0.0 && x <= 1.0), "{w:?}");
    assert!(
        w[6] < w[3] && w[3] < w[1],
        "the hand's joint lightest, the shoulder's heaviest: {w:?}"
    );
    let weighted = space.clone().with_weights(&w).unwrap();
    let request = table_request();
    // A radian of the hand's joint is a short way in the weighted space, one of the shoulder's
    // as long as before.
    let (mut wrist, mut shoulder) = (request.start.clone(), request.start.clone());
    wrist[6] += 1.0;
    shoulder[0] += 1.0;
    assert!((weighted.distance(&request.start, &wrist) - w[6]).abs() < 1e-12);
    assert!((weighted.distance(&request.start, &shoulder) - space.distance(&request.start, &shoulder)).abs() < 1e-12);
    let budget = budget(50_000);
    // The three planners' types differ: one call each, the same arguments.
    macro_rules! weighted_solve {
        ($label:literal, $make:expr) => {
            solve(
                $label,
                $make,
                &weighted,
                PANDA_RESOLUTION,
                &mut v,
                &request,
                &budget,
            )
        };
    }
    weighted_solve!("table/birrt/weighted", BiRrt::default);
    weighted_solve!("table/rrt/weighted", Rrt::default);
    weighted_solve!("table/lazy_prm/weighted", LazyPrm::default);
}

/// BiRRT that changes its metric part-way ([`BiRrt::plan_with_metrics`]): the reach weights
/// squared first, their square roots after a few iterations. Solved, valid in the plain space,
/// the same path for the same seed, and every space back where it was.
#[test]
fn panda_table_birrt_switching_metrics() {
    let (space, mut v) = table_world();
    let w = v.joint_weights();
    let powered = |p: f64| {
        let wp: Vec<f64> = w.iter().map(|x| x.powf(p)).collect();
        space.clone().with_weights(&wp).unwrap()
    };
    let (strong, mild) = (powered(2.0), powered(0.5));
    let request = table_request();
    // Plans from the strong metric, switching to `then` after `at` iterations; every space
    // must be back in place afterwards.
    let mut plan = |at: u64, then: &JointSpace| {
        let mut motion = MotionValidator::new(strong.clone(), PANDA_RESOLUTION);
        let mut later = [(at, then.clone())];
        let s = BiRrt::default().plan_with_metrics(
            &mut motion,
            &mut v,
            &request,
            &budget(50_000),
            &mut Pcg64Mcg::seed_from_u64(5),
            &mut later,
        );
        assert_eq!((motion.space(), &later[0].1), (&strong, then), "spaces swapped back");
        s
    };
    let (a, b) = (plan(3, &mild).unwrap(), plan(3, &mild).unwrap());
    assert_eq!(a.path, b.path);
    assert!(a.stats.iterations > 3, "the switch happened: {:?}", a.stats);
    // Switching at once is not the same as never switching: the mild metric chose other states.
    let never = plan(u64::MAX, &mild).unwrap();
    assert_ne!(a.path, never.path);
    // A metric of another dimension is bad input.
    let flat = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2]).unwrap();
    let e = plan(3, &flat).unwrap_err();
    assert!(
        matches!(&e, PlanError::BadInput(m) if m.contains("2 coordinates")),
        "{e}"
    );
    for s in [&a, &never] {
        check_solution(&space, PANDA_RESOLUTION, &mut v, &request, s);
    }
}

/// The robot's own validator in a [`Race`] of two BiRRT copies: valid, and the same path twice.
#[test]
fn panda_table_birrt_race() {
    let (space, mut v) = table_world();
    let mut paths = Vec::new();
    for _ in 0..2 {
        let mut motion = MotionValidator::new(space.clone(), PANDA_RESOLUTION);
        let s = Race::new(BiRrt::default(), 2)
            .plan(
                &mut motion,
                &mut v,
                &table_request(),
                &budget(50_000),
                &mut Pcg64Mcg::seed_from_u64(11),
            )
            .unwrap();
        check_solution(&space, PANDA_RESOLUTION, &mut v, &table_request(), &s);
        paths.push(s.path);
    }
    assert_eq!(paths[0], paths[1]);
}

/// Runs `make`'s planner on every MBM problem of the excerpt whose start and goals are valid
/// in our (slightly padded) model; asserts at least one is solved.
fn mbm<P: Planner<JointSpace>>(label: &str, make: impl Fn() -> P) {
    let set = ProblemSet::load(data("panda_table_pick.json")).unwrap();
    let mut solved = 0;
    for p in set.valid_problems() {
        let (space, mut v) = panda(p.scene());
        let request = PlanRequest::new(p.start.clone(), Goal::AnyOf(p.goals.clone()));
        if let Some(c) = v.explain(&p.start) {
            println!("{label}: skipping problem {}: start invalid in our model ({c})", p.id);
            continue;
        }
        if p.goals.iter().all(|g| v.explain(g).is_some()) {
            println!("{label}: skipping problem {}: goals invalid in our model", p.id);
            continue;
        }
        solve(
            &format!("{label}/{}", p.id),
            &make,
            &space,
            PANDA_RESOLUTION,
            &mut v,
            &request,
            &budget(50_000),
        );
        solved += 1;
    }
    assert!(solved >= 1, "{label}: no MBM problem solved");
}

#[test]
fn mbm_rrt() {
    mbm("mbm/rrt", Rrt::default);
}

#[test]
fn mbm_birrt() {
    mbm("mbm/birrt", BiRrt::default);
}

#[test]
fn mbm_birrt_connect_onward() {
    mbm("mbm/birrt_onward", || BiRrt {
        connect: Connect::Onward,
        ..BiRrt::default()
    });
}

#[test]
fn mbm_lazy_prm() {
    mbm("mbm/lazy_prm", LazyPrm::default);
}

#[test]
fn any_of_goals_skips_invalid_ones() {
    let request = PlanRequest::new(
        vec![0.1, 0.1],
        Goal::AnyOf(vec![vec![0.5, 0.9], vec![0.9, 0.9], vec![0.9, 0.1]]),
    );
    for s in [
        solve(
            "any/rrt",
            Rrt::default,
            &square(),
            PASSAGE_RESOLUTION,
            &mut narrow_passage(),
            &request,
            &budget(100_000),
        ),
        solve(
            "any/birrt",
            BiRrt::default,
            &square(),
            PASSAGE_RESOLUTION,
            &mut narrow_passage(),
            &request,
            &budget(100_000),
        ),
        solve(
            "any/lazy",
            LazyPrm::default,
            &square(),
            PASSAGE_RESOLUTION,
            &mut narrow_passage(),
            &request,
            &budget(100_000),
        ),
    ] {
        assert_ne!(
            s.path.states.last().unwrap(),
            &vec![0.5, 0.9],
            "the goal in the wall is never reached"
        );
    }
}

#[test]
fn birrt_seeds_goal_tree_with_every_valid_goal() {
    let request = PlanRequest::new(
        vec![0.1, 0.1],
        Goal::AnyOf(vec![vec![0.5, 0.9], vec![0.9, 0.9], vec![0.9, 0.1]]),
    );
    let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let s = BiRrt::default()
        .plan(&mut motion, &mut narrow_passage(), &request, &budget(100_000), &mut rng)
        .unwrap();
    assert_eq!(s.stats.tree_sizes.len(), 2);
    assert!(s.stats.tree_sizes[1] >= 2, "two valid goals seed the goal tree");
}

#[test]
fn lazy_prm_reuses_its_roadmap_and_clears_it() {
    let mut prm = LazyPrm::new(LazyPrmSettings {
        k: 8,
        ..Default::default()
    });
    let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
    let mut v = narrow_passage();
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let first = prm
        .plan(&mut motion, &mut v, &passage_request(), &budget(200_000), &mut rng)
        .unwrap();
    let size = prm.roadmap_size();
    assert!(size > 10);
    let request = PlanRequest::new(vec![0.2, 0.8], Goal::Config(vec![0.8, 0.2]));
    let second = prm
        .plan(&mut motion, &mut v, &request, &budget(200_000), &mut rng)
        .unwrap();
    assert!(prm.roadmap_size() >= size);
    assert!(
        second.stats.iterations < first.stats.iterations,
        "the second query reuses the roadmap: {} vs {}",
        second.stats.iterations,
        first.stats.iterations
    );
    check_solution(&square(), PASSAGE_RESOLUTION, &mut v, &request, &second);
    prm.clear();
    assert_eq!(prm.roadmap_size(), 0);
}

#[test]
fn lazy_prm_takes_a_start_joined_to_nothing_for_a_goal_it_knows() {
    // The first query stops after its first search, leaving a roadmap of its start and goal.
    // The second asks for the same goal from a start farther than `range` from both, so the
    // new start joins no edge: the search must treat it as cut off, then grow the roadmap.
    let mut prm = LazyPrm::new(LazyPrmSettings {
        range: Some(0.2),
        ..Default::default()
    });
    let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
    let mut v = narrow_passage();
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    let first = prm.plan(&mut motion, &mut v, &passage_request(), &budget(0), &mut rng);
    assert!(matches!(first, Err(PlanError::Timeout { .. })), "{first:?}");
    assert_eq!(prm.roadmap_size(), 2);
    let request = PlanRequest::new(vec![0.1, 0.9], Goal::Config(vec![0.9, 0.1]));
    let second = prm
        .plan(&mut motion, &mut v, &request, &budget(200_000), &mut rng)
        .unwrap();
    check_solution(&square(), PASSAGE_RESOLUTION, &mut v, &request, &second);
}

/// Every planner, boxed behind a closure so the bad-input tests can run all of them.
fn every_planner(
    request: &PlanRequest,
    budget: &Budget,
    validator: &mut Region,
) -> Vec<(&'static str, Result<Solution, PlanError>)> {
    let mut out = Vec::new();
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
    out.push((
        "rrt",
        Rrt::default().plan(&mut motion, validator, request, budget, &mut rng),
    ));
    out.push((
        "birrt",
        BiRrt::default().plan(&mut motion, validator, request, budget, &mut rng),
    ));
    out.push((
        "lazy_prm",
        LazyPrm::default().plan(&mut motion, validator, request, budget, &mut rng),
    ));
    out
}

fn expect_bad_input(request: PlanRequest, budget: Budget, needle: &str) {
    for (name, r) in every_planner(&request, &budget, &mut narrow_passage()) {
        match r {
            Err(PlanError::BadInput(m)) => assert!(m.contains(needle), "{name}: `{m}` should name `{needle}`"),
            other => panic!("{name}: expected BadInput({needle}), got {other:?}"),
        }
    }
}

#[test]
fn bad_input_is_named() {
    let goal = || Goal::Config(vec![0.9, 0.9]);
    expect_bad_input(passage_request(), Budget::default(), "budget");
    expect_bad_input(PlanRequest::new(vec![0.1], goal()), budget(10), "start");
    expect_bad_input(
        PlanRequest::new(vec![0.1, f64::NAN], goal()),
        budget(10),
        "start: coordinate 1",
    );
    expect_bad_input(
        PlanRequest::new(vec![1.5, 0.1], goal()),
        budget(10),
        "start: coordinate 0",
    );
    expect_bad_input(
        PlanRequest::new(vec![0.1, 0.1], Goal::AnyOf(vec![vec![0.9, 0.9], vec![0.9, 2.0]])),
        budget(10),
        "goal 1",
    );
    expect_bad_input(
        PlanRequest::new(vec![0.1, 0.1], Goal::AnyOf(vec![])),
        budget(10),
        "no goal",
    );

    // Settings.
    let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let mut v = narrow_passage();
    let r = passage_request();
    let bad = |e: Result<Solution, PlanError>| matches!(e, Err(PlanError::BadInput(_)));
    let rrt = Rrt {
        range: Some(0.0),
        ..Default::default()
    };
    assert!(bad(rrt.clone().plan(&mut motion, &mut v, &r, &budget(10), &mut rng)));
    let rrt = Rrt {
        goal_bias: 1.5,
        ..Default::default()
    };
    assert!(bad(rrt.clone().plan(&mut motion, &mut v, &r, &budget(10), &mut rng)));
    // (goal bias, goal zone, zone radius): a negative zone, bias + zone over 1, bad radii.
    for (goal_bias, goal_zone, goal_zone_radius) in [
        (0.05, -0.1, 0.3),
        (0.5, 0.6, 0.3),
        (0.05, 0.1, 0.0),
        (0.05, 0.1, f64::NAN),
    ] {
        let rrt = Rrt {
            range: None,
            goal_bias,
            goal_zone,
            goal_zone_radius,
            ..Rrt::default()
        };
        let before = v.checks();
        assert!(
            bad(rrt.clone().plan(&mut motion, &mut v, &r, &budget(10), &mut rng)),
            "{rrt:?}"
        );
        assert_eq!(v.checks(), before, "bad settings check nothing: {rrt:?}");
    }
    let birrt = BiRrt::with_range(Some(f64::NAN));
    assert!(bad(birrt.clone().plan(&mut motion, &mut v, &r, &budget(10), &mut rng)));
    for dd in [
        DynamicDomain {
            radius: 0.0,
            ..Default::default()
        },
        DynamicDomain {
            min_radius: f64::NAN,
            ..Default::default()
        },
        DynamicDomain {
            radius: f64::INFINITY,
            ..Default::default()
        },
        DynamicDomain {
            alpha: 1.0,
            ..Default::default()
        },
        DynamicDomain {
            alpha: -0.1,
            ..Default::default()
        },
    ] {
        let mut birrt = BiRrt {
            dynamic_domain: Some(dd),
            ..BiRrt::default()
        };
        let e = birrt.plan(&mut motion, &mut v, &r, &budget(10), &mut rng).unwrap_err();
        assert!(
            matches!(&e, PlanError::BadInput(m) if m.contains("dynamic domain")),
            "{dd:?}: {e}"
        );
    }
    let e = Escape::default();
    for (escape, needle) in [
        (Escape { share: 0.0, ..e }, "share: 0.0"),
        (Escape { share: 1.0, ..e }, "share: 1.0"),
        (Escape { share: f64::NAN, ..e }, "share: NaN"),
        (Escape { step: 0.0, ..e }, "step: 0.0"),
        (Escape { step: 0.75, ..e }, "step: 0.75"),
        (Escape { join: 1.5, ..e }, "join: 1.5"),
        (Escape { stuck_ratio: 0, ..e }, "stuck_ratio: 0"),
        (Escape { reset: 0, ..e }, "reset: 0"),
        (Escape { probe: 1.0, ..e }, "probe: 1.0"),
        (Escape { probe: -0.1, ..e }, "probe: -0.1"),
    ] {
        let mut birrt = BiRrt {
            escape: Some(escape),
            ..BiRrt::default()
        };
        let e = birrt.plan(&mut motion, &mut v, &r, &budget(10), &mut rng).unwrap_err();
        assert!(
            matches!(&e, PlanError::BadInput(m) if m.contains("escape") && m.contains(needle)),
            "{escape:?}: {e}"
        );
        // LazyPRM's wedged query ends take the same escape, refused the same way.
        let mut prm = LazyPrm::new(LazyPrmSettings {
            escape: Some(escape),
            ..LazyPrmSettings::default()
        });
        let e = prm.plan(&mut motion, &mut v, &r, &budget(10), &mut rng).unwrap_err();
        assert!(
            matches!(&e, PlanError::BadInput(m) if m.contains("escape") && m.contains(needle)),
            "{needle}: {e}"
        );
    }
    let mut prm = LazyPrm::new(LazyPrmSettings {
        k: 0,
        ..Default::default()
    });
    assert!(bad(prm.plan(&mut motion, &mut v, &r, &budget(10), &mut rng)));
    let with = |f: fn(&mut LazyPrmSettings)| {
        let mut s = LazyPrmSettings::default();
        f(&mut s);
        s
    };
    let cases: [(LazyPrmSettings, &str); 13] = [
        (with(|s| s.enhance = 1.5), "enhance is 1.5"),
        (with(|s| s.enhance = f64::NAN), "enhance is NaN"),
        (with(|s| s.enhance_radius = Some(0.0)), "enhance_radius is 0"),
        (
            with(|s| s.enhance_radius = Some(f64::INFINITY)),
            "enhance_radius is inf",
        ),
        (with(|s| s.search_weight = 0.5), "search_weight is 0.5"),
        (with(|s| s.search_weight = f64::NAN), "search_weight is NaN"),
        (with(|s| s.tree_share = -0.1), "tree_share is -0.1"),
        (with(|s| s.tree_share = f64::NAN), "tree_share is NaN"),
        (with(|s| s.late_tree_share = 1.01), "late_tree_share is 1.01"),
        (with(|s| s.late_tree_share = f64::NAN), "late_tree_share is NaN"),
        (with(|s| s.tree_step = 0.0), "tree_step is 0"),
        (with(|s| s.tree_step = 1.5), "tree_step is 1.5"),
        (with(|s| s.tree_step = f64::NAN), "tree_step is NaN"),
    ];
    for (settings, needle) in cases {
        let mut prm = LazyPrm::new(settings);
        let e = prm.plan(&mut motion, &mut v, &r, &budget(10), &mut rng).unwrap_err();
        assert!(
            matches!(&e, PlanError::BadInput(m) if m.contains(needle)),
            "{needle}: {e}"
        );
        assert_eq!(prm.roadmap_size(), 0, "bad settings leave the roadmap untouched");
    }
}

/// A NaN or negative time limit is bad input that names the time limit, whichever
/// constructor set it, and checks nothing; a zero time limit is a valid budget that runs out at
/// once, and `+∞` sets no time limit.
#[test]
fn bad_time_limit_is_named() {
    for budget in [
        Budget::time(f64::NAN),
        Budget::time(-1.0),
        Budget::time(f64::NEG_INFINITY),
        Budget::iterations(10).with_time(f64::NAN),
        Budget::time(1.0).with_time(-1e-9),
        Budget::time(f64::NAN).with_iterations(10),
    ] {
        let mut v = narrow_passage();
        for (name, r) in every_planner(&passage_request(), &budget, &mut v) {
            match r {
                Err(PlanError::BadInput(m)) => assert!(m.contains("time limit"), "{name}: `{m}` for {budget:?}"),
                other => panic!("{name}: expected BadInput for {budget:?}, got {other:?}"),
            }
        }
        assert_eq!(v.checks(), 0, "{budget:?}: a bad budget checks nothing");
        let mut prm = LazyPrm::default();
        let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
        let r = prm.plan(
            &mut motion,
            &mut v,
            &passage_request(),
            &budget,
            &mut Pcg64Mcg::seed_from_u64(1),
        );
        assert!(matches!(r, Err(PlanError::BadInput(_))), "{r:?}");
        assert_eq!(
            prm.roadmap_size(),
            0,
            "{budget:?}: a bad budget leaves the roadmap untouched"
        );
    }
    for (name, r) in every_planner(&passage_request(), &Budget::time(0.0), &mut narrow_passage()) {
        assert!(matches!(r, Err(PlanError::Timeout { .. })), "{name}: {r:?}");
    }
    let unbounded = Budget::time(f64::INFINITY).with_iterations(3);
    for (name, r) in every_planner(&passage_request(), &unbounded, &mut narrow_passage()) {
        assert!(
            matches!(&r, Err(PlanError::Timeout { stats }) if stats.iterations == 3),
            "{name}: {r:?}"
        );
    }
}

/// A resolution far finer than the space allows (1e-300 cut an edge into 2³² states, and the
/// bisection's queue filled the memory): refused where the caller can be told, raised to the
/// finest usable spacing where it cannot, so an edge's check stays bounded; the refusals
/// check nothing.
#[test]
fn a_resolution_finer_than_the_space_allows_is_refused_or_raised() {
    let finest = finest_resolution(&square());
    assert!(finest > 0.0 && finest < 1e-5, "{finest}");
    for what in [1e-300, 0.5 * finest] {
        let r = MotionValidator::try_new(square(), what);
        assert!(
            matches!(&r, Err(PlanError::BadInput(m)) if m.contains("resolution") && m.contains("finest")),
            "{what}: {:?}",
            r.err()
        );
    }
    assert!(MotionValidator::try_new(square(), finest).is_ok());
    let mut motion = MotionValidator::new(square(), 1e-300);
    assert_eq!(motion.resolution(), finest);
    // The diagonal is the longest edge in the square: at most `MAX_SEGMENTS - 1` states.
    let mut open = Region {
        free: |_| true,
        checks: 0,
    };
    assert!(motion.check_motion(&mut open, &[0.0, 0.0], &[1.0, 1.0]));
    assert!(
        open.checks < u64::from(MAX_SEGMENTS) && open.checks > 1 << 19,
        "{}",
        open.checks
    );
    // Post-processing refuses such a re-check spacing before it checks anything.
    let path = Path {
        states: vec![vec![0.1, 0.1], vec![0.9, 0.9]],
    };
    let mut v = narrow_passage();
    let r = shortcut::repair(
        &square(),
        &mut v,
        &path,
        1e-300,
        std::time::Duration::from_secs(1),
        &mut Pcg64Mcg::seed_from_u64(1),
    );
    assert!(
        matches!(&r, Err(PlanError::BadInput(m)) if m.contains("fine_resolution")),
        "{r:?}"
    );
    let limits = Limits::new(vec![1.0; 2], vec![1.0; 2], vec![f64::INFINITY; 2]).unwrap();
    for settings in [
        ShortcutSettings {
            fine_resolution: Some(1e-300),
            ..ShortcutSettings::default()
        },
        ShortcutSettings {
            verify_resolution: Some(1e-300),
            ..ShortcutSettings::default()
        },
    ] {
        let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
        let r = shortcut::smooth(
            shortcut::Smoothing::Parabolic,
            &mut motion,
            &mut v,
            &path,
            &limits,
            &settings,
            std::time::Duration::from_secs(1),
            &mut Pcg64Mcg::seed_from_u64(1),
        );
        assert!(
            matches!(&r, Err(PlanError::BadInput(m)) if m.contains("finest")),
            "{:?}",
            r.err()
        );
    }
    // So is a planner step that short (BiRRT's straight connection of 10⁻⁹ rad steps added
    // states by the billion and ran for minutes past a 1 s budget).
    let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let (request, budget) = (passage_request(), Budget::time(1.0));
    let range = Some(1e-9);
    let rrt = Rrt {
        range,
        ..Default::default()
    };
    let lazy = LazyPrmSettings {
        range,
        ..Default::default()
    };
    let results = [
        rrt.clone().plan(&mut motion, &mut v, &request, &budget, &mut rng),
        BiRrt::with_range(range).plan(&mut motion, &mut v, &request, &budget, &mut rng),
        LazyPrm::new(lazy).plan(&mut motion, &mut v, &request, &budget, &mut rng),
    ];
    for r in results {
        assert!(
            matches!(&r, Err(PlanError::BadInput(m)) if m.contains("range")),
            "{:?}",
            r.err()
        );
    }
    assert_eq!(v.checks, 0);
}

/// LazyPRM settings that are huge but valid plan like any others, within their budget: a `k`
/// of `usize::MAX` reserved that many neighbours (a capacity-overflow panic), and a batch
/// near `usize::MAX` overflowed the wedged-part test.
#[test]
fn huge_lazy_prm_settings_stay_within_the_budget() {
    for settings in [
        LazyPrmSettings {
            k: usize::MAX,
            ..Default::default()
        },
        LazyPrmSettings {
            k: 1 << 40,
            ..Default::default()
        },
        LazyPrmSettings {
            batch: usize::MAX / 3,
            ..Default::default()
        },
    ] {
        let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
        let r = LazyPrm::new(settings.clone()).plan(
            &mut motion,
            &mut narrow_passage(),
            &passage_request(),
            &Budget::iterations(2_000),
            &mut Pcg64Mcg::seed_from_u64(1),
        );
        assert!(
            matches!(&r, Ok(_) | Err(PlanError::Timeout { .. })),
            "{settings:?}: {:?}",
            r.err()
        );
    }
}

#[test]
fn invalid_start_and_goals() {
    let in_wall = vec![0.5, 0.1];
    let request = PlanRequest::new(in_wall.clone(), Goal::Config(vec![0.9, 0.9]));
    for (name, r) in every_planner(&request, &budget(10), &mut narrow_passage()) {
        assert_eq!(r, Err(PlanError::InvalidStart { contact: None }), "{name}");
    }
    let request = PlanRequest::new(vec![0.1, 0.1], Goal::AnyOf(vec![in_wall.clone(), vec![0.5, 0.9]]));
    for (name, r) in every_planner(&request, &budget(10), &mut narrow_passage()) {
        let e = r.unwrap_err();
        assert_eq!(
            e,
            PlanError::InvalidGoals {
                count: 2,
                first_contact: None
            },
            "{name}"
        );
        let e = e.explain_with(&request, |q| (q[0] == 0.5).then(|| "touches the wall".to_owned()));
        assert_eq!(
            e,
            PlanError::InvalidGoals {
                count: 2,
                first_contact: Some("touches the wall".to_owned())
            }
        );
        assert!(
            e.to_string()
                .contains("all 2 goal state(s) are invalid: touches the wall"),
            "{e}"
        );
    }
}

#[test]
fn invalid_start_names_the_contact_with_robot_validity() {
    let (space, mut v) = table_world();
    let into_table = vec![0.0, 0.9, 0.0, -1.2, 0.0, 2.0, 0.785];
    let request = PlanRequest::new(into_table, table_request().goal);
    let mut motion = MotionValidator::new(space, PANDA_RESOLUTION);
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let e = BiRrt::default()
        .plan(&mut motion, &mut v, &request, &budget(10), &mut rng)
        .unwrap_err()
        .explain_with(&request, |q| v.explain(q).map(|c| c.to_string()));
    match &e {
        PlanError::InvalidStart { contact: Some(c) } => assert!(c.contains("touches obstacle"), "{c}"),
        other => panic!("expected an invalid start touching the table, got {other:?}"),
    }
    assert!(e.to_string().starts_with("the start state is invalid: link `"), "{e}");
}

#[test]
fn timeout_reports_stats() {
    for (name, r) in every_planner(&passage_request(), &Budget::iterations(3), &mut narrow_passage()) {
        match r {
            Err(e @ PlanError::Timeout { .. }) => {
                let PlanError::Timeout { stats } = &e else {
                    unreachable!()
                };
                let sizes = format!("trees of {:?} states", stats.tree_sizes);
                assert!(
                    e.to_string().contains(&sizes),
                    "{name}: the message names the tree sizes: {e}"
                );
                assert_eq!(stats.iterations, 3, "{name}");
                assert!(stats.states_checked >= 2, "{name}: start and goal are checked");
                assert!(!stats.tree_sizes.is_empty(), "{name}");
            }
            other => panic!("{name}: expected a timeout, got {other:?}"),
        }
    }
    // A zero time budget stops at once.
    for (name, r) in every_planner(&passage_request(), &Budget::time(0.0), &mut narrow_passage()) {
        assert!(matches!(r, Err(PlanError::Timeout { .. })), "{name}: {r:?}");
    }
}

/// Whether every motion of `path` passes a motion validator at `resolution`.
fn path_valid<S: Space + Clone, V: StateValidator>(
    space: &S,
    resolution: f64,
    validator: &mut V,
    path: &[Vec<f64>],
) -> bool {
    let mut mv = MotionValidator::new(space.clone(), resolution);
    path.windows(2)
        .all(|w| validator.is_valid(&w[1]) && mv.check_motion(validator, &w[0], &w[1]))
}

/// Success rate and median time of `make`'s planner over `seeds` seeds. Every path is checked
/// at the planner's resolution (which must hold); how many also pass at a 10× finer one is
/// printed (a path's edge can clip an obstacle's corner by less than the resolution, most
/// often with LazyPRM, whose shortest paths hug corners).
#[allow(clippy::too_many_arguments)]
fn success_rate<S: Space + Clone, V: StateValidator, P: Planner<S>>(
    label: &str,
    make: impl Fn() -> P,
    space: &S,
    resolution: f64,
    validator: &mut V,
    request: &PlanRequest,
    budget: &Budget,
    seeds: u64,
) -> f64 {
    let mut times = Vec::new();
    let (mut solved, mut fine) = (0, 0);
    for seed in 0..seeds {
        let mut motion = MotionValidator::new(space.clone(), resolution);
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let t = Instant::now();
        let r = make().plan(&mut motion, validator, request, budget, &mut rng);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        if let Ok(s) = r {
            assert_eq!(s.path.states[0], request.start);
            assert!(
                path_valid(space, resolution, validator, &s.path.states),
                "{label}: seed {seed}"
            );
            fine += usize::from(path_valid(space, resolution / 10.0, validator, &s.path.states));
            solved += 1;
        }
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{label}: solved {solved}/{seeds} ({fine} also valid at 10x finer resolution), median {:.3} ms, max {:.3} ms",
        times[times.len() / 2],
        times[times.len() - 1]
    );
    solved as f64 / seeds as f64
}

#[test]
fn narrow_passage_is_solved_for_every_seed() {
    let r = passage_request();
    let b = budget(100_000);
    let (space, res) = (square(), PASSAGE_RESOLUTION);
    let mut v = narrow_passage();
    assert_eq!(
        success_rate("passage/rrt", Rrt::default, &space, res, &mut v, &r, &b, 10),
        1.0
    );
    assert_eq!(
        success_rate("passage/birrt", BiRrt::default, &space, res, &mut v, &r, &b, 10),
        1.0
    );
    assert_eq!(
        success_rate("passage/lazy_prm", LazyPrm::default, &space, res, &mut v, &r, &b, 10),
        1.0
    );
}

fn panda_ik() -> hearth_kinematics::IkSolver {
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let mut ik = hearth_kinematics::IkSolver::new(arm, "panda_hand_tcp", Default::default()).unwrap();
    let mut q_full = m.neutral_configuration();
    Chain::new(&m, &["panda_finger_joint1"])
        .unwrap()
        .scatter(&[0.04], &mut q_full);
    ik.set_reference(&q_full).unwrap();
    ik
}

#[test]
fn pose_goals_are_sampled_collision_free_and_reached() {
    use hearth_kinematics::IkTarget;
    use hearth_kinematics::nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use hearth_planning::goal::PoseGoal;
    let (space, mut v) = table_world();
    let mut ik = panda_ik();
    // Beside the post, above the table, gripper pointing down.
    let down = UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0);
    let target = Isometry3::from_parts(Translation3::new(0.45, 0.3, 0.35), down);
    let start = table_request().start;
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let goal = PoseGoal::new(IkTarget::Pose(target))
        .sample(&mut ik, &mut v, &start, &mut rng)
        .unwrap();
    assert!(!goal.states().is_empty());
    for q in goal.states() {
        assert!(v.is_valid(q));
        let reached = ik.tool_pose(q).unwrap();
        assert!((reached.translation.vector - target.translation.vector).norm() < 2e-3);
    }
    let request = PlanRequest::new(start, goal);
    let mut motion = MotionValidator::new(space.clone(), PANDA_RESOLUTION);
    let solution = BiRrt::default()
        .plan(&mut motion, &mut v, &request, &Budget::iterations(20_000), &mut rng)
        .unwrap();
    check_solution(&space, PANDA_RESOLUTION, &mut v, &request, &solution);
    let end = solution.path.states.last().unwrap();
    let reached = ik.tool_pose(end).unwrap();
    assert!((reached.translation.vector - target.translation.vector).norm() < 2e-3);

    // Out of reach, inside the table, or NaN: typed errors.
    let far = IkTarget::Position(hearth_kinematics::nalgebra::Point3::new(3.0, 0.0, 0.5));
    let quick = PoseGoal {
        max_calls: 3,
        ..PoseGoal::new(far)
    };
    assert!(matches!(
        quick.sample(&mut ik, &mut v, &request.start, &mut rng),
        Err(PlanError::NoGoalConfiguration { .. })
    ));
    let in_table = IkTarget::Position(hearth_kinematics::nalgebra::Point3::new(0.5, -0.3, 0.2));
    let quick = PoseGoal {
        max_calls: 3,
        ..PoseGoal::new(in_table)
    };
    assert!(matches!(
        quick.sample(&mut ik, &mut v, &request.start, &mut rng),
        Err(PlanError::NoGoalConfiguration { .. })
    ));
    let nan = IkTarget::Position(hearth_kinematics::nalgebra::Point3::new(f64::NAN, 0.0, 0.5));
    assert!(matches!(
        PoseGoal::new(nan).sample(&mut ik, &mut v, &request.start, &mut rng),
        Err(PlanError::BadInput(_))
    ));
}

/// A two-board shelf in front of the Panda; start and goal are IK solutions with the gripper
/// pointing into the lower and the upper compartment.
fn shelf_world_and_request() -> (JointSpace, RobotValidity, PlanRequest) {
    use hearth_kinematics::IkTarget;
    use hearth_kinematics::nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use hearth_planning::goal::PoseGoal;
    let board =
        |name: &str, z: f32| Obstacle::cuboid(name, Pose::translation(0.7, 0.0, z), Vector::new(0.2, 0.4, 0.01));
    let side = |name: &str, y: f32| Obstacle::cuboid(name, Pose::translation(0.7, y, 0.6), Vector::new(0.2, 0.01, 0.3));
    let scene = ParryScene::new(vec![
        board("bottom", 0.35),
        board("middle", 0.6),
        board("top", 0.85),
        side("left", 0.41),
        side("right", -0.41),
        Obstacle::cuboid("back", Pose::translation(0.91, 0.0, 0.6), Vector::new(0.01, 0.4, 0.3)),
    ]);
    let (space, mut v) = panda(scene);
    let mut ik = panda_ik();
    // Gripper pointing along +x (into the shelf).
    let forward = UnitQuaternion::from_euler_angles(0.0, std::f64::consts::FRAC_PI_2, 0.0);
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    let seed = [0.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.785];
    let mut solve_at = |z: f64| {
        let target = IkTarget::Pose(Isometry3::from_parts(Translation3::new(0.56, 0.0, z), forward));
        PoseGoal::new(target).sample(&mut ik, &mut v, &seed, &mut rng).unwrap()
    };
    let start = solve_at(0.5).states()[0].clone();
    let goal = solve_at(0.73);
    (space, v, PlanRequest::new(start, goal))
}

#[test]
fn panda_shelf_every_planner() {
    let (space, mut v, request) = shelf_world_and_request();
    solve(
        "shelf/birrt",
        BiRrt::default,
        &space,
        PANDA_RESOLUTION,
        &mut v,
        &request,
        &budget(50_000),
    );
    solve(
        "shelf/rrt",
        Rrt::default,
        &space,
        PANDA_RESOLUTION,
        &mut v,
        &request,
        &budget(100_000),
    );
    solve(
        "shelf/lazy_prm",
        LazyPrm::default,
        &space,
        PANDA_RESOLUTION,
        &mut v,
        &request,
        &budget(100_000),
    );
}

/// A slot x ∈ [0.7, 1.0], y ∈ [0.495, 0.505] cut into a block x ∈ [0.7, 1.0], y ∈ [0.3, 0.7],
/// open on the left.
fn slot() -> Region {
    Region {
        free: |q| {
            let in_block = (0.7..=1.0).contains(&q[0]) && (0.3..=0.7).contains(&q[1]);
            !in_block || (0.495..=0.505).contains(&q[1])
        },
        checks: 0,
    }
}

#[test]
fn lazy_prm_node_enhancement_reaches_a_goal_in_a_slot() {
    // The goal sits at the bottom of the slot; its roadmap edges to uniform samples all cross
    // the block, so it needs samples near it, which node enhancement puts there.
    let request = PlanRequest::new(vec![0.1, 0.5], Goal::Config(vec![0.97, 0.5]));
    let mut v = slot();
    // Roadmap vertices when solved, median over 21 seeds.
    let mut median_size = |enhance: f64| {
        let mut sizes: Vec<usize> = (0..21)
            .map(|seed| {
                let mut motion = MotionValidator::new(square(), PASSAGE_RESOLUTION);
                let mut rng = Pcg64Mcg::seed_from_u64(seed);
                let mut prm = LazyPrm::new(LazyPrmSettings {
                    enhance,
                    // Node enhancement alone.
                    tree_share: 0.0,
                    ..Default::default()
                });
                let s = prm
                    .plan(&mut motion, &mut v, &request, &budget(200_000), &mut rng)
                    .unwrap();
                check_solution(&square(), PASSAGE_RESOLUTION, &mut v, &request, &s);
                s.stats.tree_sizes[0]
            })
            .collect();
        sizes.sort_unstable();
        sizes[sizes.len() / 2]
    };
    let (uniform, enhanced) = (median_size(0.0), median_size(0.5));
    println!("slot: median roadmap size when solved: uniform {uniform}, enhanced {enhanced}");
    assert!(4 * enhanced < 3 * uniform, "enhanced {enhanced}, uniform {uniform}");
}

/// [`pocket`]'s goal at the closed end of its corridor, in a 2 × 2 square around the block,
/// with four free dimensions more (6-D, as the roadmap's arms are high-dimensional): the space
/// and the request.
fn pocket_6d() -> (JointSpace, PlanRequest) {
    let (mut lo, mut hi) = (vec![99.75, 99.5], vec![101.75, 101.5]);
    lo.extend([0.0; 4]);
    hi.extend([1.0; 4]);
    let space = JointSpace::new(&lo, &hi, &[false; 6]).unwrap();
    let request = PlanRequest::new(
        vec![99.85, 99.6, 0.5, 0.5, 0.5, 0.5],
        Goal::Config(vec![100.88, 100.5, 0.5, 0.5, 0.5, 0.5]),
    );
    (space, request)
}

/// LazyPRM with steps of 0.4 and otherwise `settings` in [`pocket_6d`], seeds 0–14, each path
/// checked: the medians of the iterations to a solution (the budget when none) and of the
/// roadmap's size.
fn pocket_6d_lazy_prm_medians(settings: &LazyPrmSettings) -> (u64, usize) {
    let (space, request) = pocket_6d();
    let mut v = pocket();
    let (mut its, mut sizes): (Vec<u64>, Vec<usize>) = (0..15)
        .map(|seed| {
            let mut motion = MotionValidator::new(space.clone(), POCKET_RESOLUTION);
            let mut rng = Pcg64Mcg::seed_from_u64(seed);
            let mut prm = LazyPrm::new(LazyPrmSettings {
                range: Some(0.4),
                ..settings.clone()
            });
            let its = match prm.plan(&mut motion, &mut v, &request, &budget(40_000), &mut rng) {
                Ok(s) => {
                    check_solution(&space, POCKET_RESOLUTION, &mut v, &request, &s);
                    s.stats.iterations
                }
                Err(PlanError::Timeout { stats }) => stats.iterations,
                Err(e) => panic!("seed {seed}: {e}"),
            };
            (its, prm.roadmap_size())
        })
        .unzip();
    its.sort_unstable();
    sizes.sort_unstable();
    (its[its.len() / 2], sizes[sizes.len() / 2])
}

#[test]
fn lazy_prm_grows_a_wedged_goal_out_of_a_pocket() {
    // In `pocket_6d`, lazy edges into the corridor fail unless they end in it, and out of it
    // unless they leave through the hole. Growing the goal's part like a tree gets it out.
    let (space, request) = pocket_6d();
    let mut v = pocket();
    let median_iterations = |tree_share: f64| {
        pocket_6d_lazy_prm_medians(&LazyPrmSettings {
            tree_share,
            ..Default::default()
        })
        .0
    };
    let (without, with) = (
        median_iterations(0.0),
        median_iterations(LazyPrmSettings::default().tree_share),
    );
    println!("pocket: median LazyPRM iterations: without wedged-end growth {without}, with {with}");
    assert!(2 * with < without, "with {with}, without {without}");
    // The growth draws from the planner's generator only: same seed, same path.
    solve(
        "pocket/lazy_prm",
        || {
            LazyPrm::new(LazyPrmSettings {
                range: Some(0.4),
                ..Default::default()
            })
        },
        &space,
        POCKET_RESOLUTION,
        &mut v,
        &request,
        &budget(40_000),
    );
    // The late share replaces the share once the roadmap holds `late_roadmap` vertices: from
    // the first vertex, a late share of 0.6 plans as a share of 0.6 does, check for check.
    let mut run = |settings: LazyPrmSettings| {
        let mut motion = MotionValidator::new(space.clone(), POCKET_RESOLUTION);
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let mut prm = LazyPrm::new(LazyPrmSettings {
            range: Some(0.4),
            ..settings
        });
        let out = prm.plan(&mut motion, &mut v, &request, &budget(40_000), &mut rng);
        out.map(|s| (s.stats.iterations, s.stats.states_checked, s.path.states))
    };
    let early = run(LazyPrmSettings {
        tree_share: 0.6,
        late_roadmap: usize::MAX,
        ..Default::default()
    });
    let late = run(LazyPrmSettings {
        late_tree_share: 0.6,
        late_roadmap: 0,
        ..Default::default()
    });
    assert!(early.is_ok(), "{early:?}");
    assert_eq!(early, late);
    let default = run(LazyPrmSettings::default());
    assert_ne!(default.map(|(i, c, _)| (i, c)), early.map(|(i, c, _)| (i, c)));
}

/// In [`pocket_6d`], LazyPRM's wedged-end growth with and without the greedy extension
/// ([`LazyPrmSettings::tree_connect`]): a free step goes on towards its sample, so a growth
/// turn adds several vertices (the roadmap is about three times larger when solved) and the
/// plans take no more iterations (449 against 468 in the median); every path is checked. Off,
/// as by default, the growth is one step a turn.
#[test]
fn lazy_prm_wedged_growth_extends_greedily() {
    let medians = |tree_connect: bool| {
        pocket_6d_lazy_prm_medians(&LazyPrmSettings {
            tree_connect,
            ..Default::default()
        })
    };
    let (one_step, greedy) = (medians(false), medians(true));
    println!("pocket: median LazyPRM (iterations, roadmap size): one step a turn {one_step:?}, greedy {greedy:?}");
    assert!(greedy.1 > 2 * one_step.1, "greedy {greedy:?}, one step {one_step:?}");
    assert!(greedy.0 <= one_step.0, "greedy {greedy:?}, one step {one_step:?}");
}

/// One coordinate of a request: inside the square, on or beyond its edges, or not a number.
fn coordinate() -> impl proptest::strategy::Strategy<Value = f64> {
    use proptest::prelude::*;
    prop_oneof![
        6 => 0.0..=1.0f64,
        1 => prop_oneof![Just(0.0), Just(1.0), Just(-1e-12), Just(1.0 + 1e-12), Just(-5.0), Just(1e300)],
        1 => prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)],
    ]
}

/// A configuration of one to three coordinates (the square has two).
fn configuration() -> impl proptest::strategy::Strategy<Value = Vec<f64>> {
    use proptest::prelude::*;
    prop_oneof![
        8 => proptest::collection::vec(coordinate(), 2),
        1 => proptest::collection::vec(coordinate(), 1),
        1 => proptest::collection::vec(coordinate(), 3),
    ]
}

/// A budget's limits, `(iterations, seconds)`: either, both or neither, the time sometimes NaN
/// or negative. Without an iteration limit the time is at most a millisecond, so that each case
/// stays quick.
fn budget_limits() -> impl proptest::strategy::Strategy<Value = (Option<u64>, Option<f64>)> {
    use proptest::prelude::*;
    let bad = || prop_oneof![Just(f64::NAN), Just(-1.0), Just(-1e-300), Just(f64::NEG_INFINITY)];
    let with_iterations = prop_oneof![
        4 => Just(20.0),
        1 => prop_oneof![Just(0.0), Just(f64::INFINITY), Just(1e300)],
        1 => bad(),
    ];
    prop_oneof![
        4 => (1u64..400, with_iterations).prop_map(|(n, t)| (Some(n), Some(t))),
        1 => (1u64..400).prop_map(|n| (Some(n), None)),
        2 => prop_oneof![Just(0.0), Just(1e-3), bad()].prop_map(|t| (None, Some(t))),
        2 => Just((None, None)),
    ]
}

/// The budget of those limits, set through the constructors.
fn budget_of(iterations: Option<u64>, secs: Option<f64>) -> Budget {
    match (iterations, secs) {
        (Some(n), Some(t)) if n % 2 == 0 => Budget::iterations(n).with_time(t),
        (Some(n), Some(t)) => Budget::time(t).with_iterations(n),
        (Some(n), None) => Budget::iterations(n),
        (None, Some(t)) => Budget::time(t),
        (None, None) => Budget::default(),
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(150))]

    /// Whatever the start, goals and budget, every planner either returns a path from the
    /// start to one of the goals whose states are free and inside the square, or a typed
    /// error; none panics, and bad input is [`PlanError::BadInput`] before any check.
    #[test]
    fn any_request_is_planned_or_refused(
        start in configuration(),
        goals in proptest::collection::vec(configuration(), 0..3),
        (iterations, secs) in budget_limits(),
    ) {
        let request = PlanRequest::new(start.clone(), Goal::AnyOf(goals.clone()));
        let budget = budget_of(iterations, secs);
        let inside = |q: &[f64]| q.len() == 2 && q.iter().all(|x| (0.0..=1.0).contains(x));
        let budget_ok = (iterations.is_some() || secs.is_some()) && secs.is_none_or(|t| t >= 0.0);
        let well_formed = inside(&start) && !goals.is_empty() && goals.iter().all(|g| inside(g)) && budget_ok;
        let mut region = narrow_passage();
        for (name, r) in every_planner(&request, &budget, &mut region) {
            match r {
                Ok(s) => {
                    let states = &s.path.states;
                    proptest::prop_assert!(well_formed, "{name} planned bad input {start:?} {goals:?} {budget:?}");
                    proptest::prop_assert_eq!(states.first(), Some(&start), "{}", name);
                    proptest::prop_assert!(goals.iter().any(|g| Some(g) == states.last()), "{name}");
                    proptest::prop_assert!(states.iter().all(|q| inside(q) && (narrow_passage().free)(q)), "{name}: {states:?}");
                }
                Err(PlanError::BadInput(m)) => proptest::prop_assert!(!well_formed, "{name}: {m} for {start:?} {goals:?} {budget:?}"),
                Err(e) => proptest::prop_assert!(
                    well_formed && matches!(e, PlanError::Timeout { .. } | PlanError::InvalidStart { .. } | PlanError::InvalidGoals { .. }),
                    "{name}: {e:?} for {start:?} {goals:?} {budget:?}"
                ),
            }
        }
    }
}
