//! Hot loops do not allocate: a counting global allocator (`support/counting.rs`, this test
//! binary only) counts the
//! heap allocations each thread makes, and the loops a planner runs millions of times (a
//! state check, an edge check, a nearest-neighbour query, sampling a trajectory) must make
//! none once their scratch space is warm. A whole plan may allocate only as its trees and
//! roadmaps grow: amortised, a few allocations per hundred iterations.

use std::path::PathBuf;
use std::sync::Arc;

use hearth_kinematics::{Chain, RobotModel};
use hearth_planning::motion::MotionValidator;
use hearth_planning::nn::NearestNeighbors;
use hearth_planning::obstacles::{Obstacle, ParryScene};
use hearth_planning::problem::ProblemSet;
use hearth_planning::space::{JointSpace, Space};
use hearth_planning::trajectory::{Limits, Trajectory};
use hearth_planning::validity::{RobotValidity, StateValidator};
use hearth_planning::{BiRrt, Budget, Goal, LazyPrm, PlanError, PlanRequest, Planner, Rrt};
use parry3d::math::{Pose, Vector};
use parry3d::shape::{Cuboid, SharedShape};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

#[path = "support/counting.rs"]
mod counting;
#[path = "support/matrix.rs"]
mod matrix;

use counting::allocations;
use matrix::matrix;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// A robot's planning chain among the obstacles of the first problem of its
/// MotionBenchMaker excerpt, fingers where the benchmark holds them, and a request from the
/// problem's start to its first goal our model admits (the Fetch's excerpt has none: torso
/// against shoulder, see the pipeline tests), else to the first valid state drawn with a fixed
/// seed.
fn world(robot: &str) -> (JointSpace, RobotValidity, PlanRequest) {
    let m = RobotModel::builtin(robot).unwrap();
    let (file, finger, width) = match robot {
        "panda" => ("panda_table_pick.json", "panda_finger_joint1", 0.04),
        _ => ("fetch_table_pick.json", "r_gripper_finger_joint", 0.05),
    };
    let set = ProblemSet::load(data(file)).unwrap();
    let chain = Chain::new(&m, &set.joint_names).unwrap();
    let space = JointSpace::from_chain(&chain).unwrap();
    let p = set.valid_problems().next().unwrap();
    let mut v = RobotValidity::new(chain, matrix(robot), Arc::new(p.scene()));
    let mut reference = m.neutral_configuration();
    Chain::new(&m, &[finger]).unwrap().scatter(&[width], &mut reference);
    v.set_reference(&reference).unwrap();
    assert!(v.is_valid(&p.start), "{robot}: the start is valid");
    let goal = p.goals.iter().find(|g| v.is_valid(g)).cloned().unwrap_or_else(|| {
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let mut q = vec![0.0; space.dim()];
        loop {
            space.sample(&mut rng, &mut q);
            if v.is_valid(&q) {
                break q.clone();
            }
        }
    });
    (space, v, PlanRequest::new(p.start.clone(), Goal::Config(goal)))
}

/// `n` random states of `space`, drawn with a fixed seed.
fn states(space: &JointSpace, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let mut q = vec![0.0; space.dim()];
            space.sample(&mut rng, &mut q);
            q
        })
        .collect()
}

/// State and edge checks of `robot` make no allocation once warm, in free space, in contact
/// and in self-collision alike. The first check that lands in a cell of a self-collision
/// certificate table fills that cell (a one-off per cell, as `warm_pair_tables` does ahead of
/// time), so the counted pass goes over states and edges checked once before.
fn checks_do_not_allocate(robot: &str) {
    let (space, mut v, request) = world(robot);
    let mut qs = states(&space, 2_000, 7);
    // The problem's own start and goal, and the edge between them, last.
    qs.push(request.start.clone());
    qs.push(request.goal.states()[0].clone());
    let mut motions = MotionValidator::new(space, 1.0 / 32.0);
    counting::assert_checks_do_not_allocate(robot, &mut v, &mut motions, &qs);
}

#[test]
fn panda_checks_do_not_allocate() {
    checks_do_not_allocate("panda");
}

#[test]
fn fetch_checks_do_not_allocate() {
    checks_do_not_allocate("fetch");
}

/// Retraction ([`StateValidator::retract`]) of random states, most of them in contact, makes
/// no allocation once the states' certificate cells are warm: its normal equations live in
/// scratch made with the validator.
#[test]
fn retraction_does_not_allocate() {
    for robot in ["panda", "fetch"] {
        let (space, mut v, _) = world(robot);
        assert_retraction_does_not_allocate(robot, &space, &mut v);
    }
}

/// Nor against composite obstacles, a triangle-mesh table and a compound shelf: their parts'
/// contacts go through the same per-thread EPA as convex obstacles' (parry's own composite
/// query builds one per overlapping part).
#[test]
fn retraction_against_meshes_and_compounds_does_not_allocate() {
    let (space, mut v, _) = world("panda");
    let (vertices, indices) = Cuboid::new(Vector::new(0.4, 0.6, 0.02)).to_trimesh();
    let table = Obstacle::trimesh("table", Pose::translation(0.5, 0.0, 0.3), vertices, indices).unwrap();
    let board = || SharedShape::cuboid(0.2, 0.4, 0.01);
    let boards = vec![(Pose::IDENTITY, board()), (Pose::translation(0.0, 0.0, 0.3), board())];
    let shelf = Obstacle::new("shelf", SharedShape::compound(boards), Pose::translation(0.0, 0.5, 0.4));
    v.set_obstacles(Arc::new(ParryScene::new(vec![table, shelf])));
    assert_retraction_does_not_allocate("panda among a mesh and a compound", &space, &mut v);
}

/// Retracts 500 random states of `space` twice: the second pass allocates nothing and
/// pushes the same states out, and some are pushed out.
fn assert_retraction_does_not_allocate(what: &str, space: &JointSpace, v: &mut RobotValidity) {
    let qs = states(space, 500, 11);
    let mut out = vec![0.0; space.dim()];
    let mut pushed = 0;
    for q in &qs {
        pushed += usize::from(v.retract(q, 0.01, 3, &mut out));
    }
    let (counted, again) = allocations(|| {
        qs.iter()
            .map(|q| usize::from(v.retract(q, 0.01, 3, &mut out)))
            .sum::<usize>()
    });
    assert_eq!(counted, 0, "{what}: retraction allocated");
    assert_eq!(again, pushed, "{what}: the same states pushed out");
    assert!(pushed > 0, "{what}: no state was retracted");
}

#[test]
fn nearest_neighbour_queries_do_not_allocate() {
    let (space, _, _) = world("panda");
    let qs = states(&space, 5_000, 11);
    let mut nn = NearestNeighbors::new(space.dim());
    for q in &qs[..4_000] {
        nn.insert(q);
    }
    let mut out = Vec::with_capacity(16);
    // The first query after inserts builds the index; later ones only search it.
    nn.nearest(&space, &qs[4_000]);
    nn.k_nearest_into(&space, &qs[4_000], 10, &mut out);
    let (n, found) = allocations(|| {
        let mut found = 0;
        for q in &qs[4_000..] {
            found += usize::from(nn.nearest(&space, q).is_some());
            nn.k_nearest_into(&space, q, 10, &mut out);
            found += out.len();
        }
        found
    });
    assert_eq!(found, 1_000 * 11);
    assert_eq!(n, 0, "1,000 nearest and 10-nearest queries allocated {n} times");
}

#[test]
fn sampling_a_trajectory_does_not_allocate() {
    let (space, _, request) = world("panda");
    let path = hearth_planning::Path {
        states: vec![request.start.clone(), request.goal.states()[0].clone()],
    };
    let limits = Limits::new(vec![2.0; 7], vec![10.0; 7], vec![5_000.0; 7]).unwrap();
    let t = Trajectory::rest_to_rest(&space, &path, &limits).unwrap();
    let smooth = t.with_jerk_limits(&limits).unwrap();
    let (mut q, mut qd) = ([0.0; 7], [0.0; 7]);
    let (n, _) = allocations(|| {
        for i in 0..=1_000 {
            let s = f64::from(i) / 1_000.0;
            t.sample(s * t.duration(), &mut q, Some(&mut qd));
            smooth.sample(s * smooth.duration(), &mut q, Some(&mut qd));
        }
    });
    assert_eq!(n, 0, "sampling trajectories allocated {n} times");
}

/// A 2-D square in which only the two query ends are free (`Boxed`) or which a wall at
/// x ∈ [0.45, 0.55] splits with no way through: no plan succeeds, so a plan runs its whole
/// iteration budget.
#[derive(Clone, Copy)]
enum Square {
    Boxed,
    Walled,
}

const START: [f64; 2] = [0.1, 0.1];
const GOAL: [f64; 2] = [0.9, 0.1];

impl StateValidator for Square {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        match self {
            Square::Boxed => q == START || q == GOAL,
            Square::Walled => !(0.45..=0.55).contains(&q[0]),
        }
    }
    fn checks(&self) -> u64 {
        0
    }
}

/// The allocations of a plan of `planner` in `world` within `iterations`, and the states its
/// trees or roadmap hold at the end.
fn square_plan<P: Planner<JointSpace>>(planner: &mut P, mut world: Square, iterations: u64) -> (u64, usize) {
    let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false]).unwrap();
    let mut motions = MotionValidator::new(space, 0.005);
    let request = PlanRequest::new(START.to_vec(), Goal::Config(GOAL.to_vec()));
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let budget = Budget::iterations(iterations);
    let (n, result) = allocations(|| planner.plan(&mut motions, &mut world, &request, &budget, &mut rng));
    match result {
        Err(PlanError::Timeout { stats }) => (n, stats.tree_sizes.iter().sum()),
        other => panic!("no way through: {other:?}"),
    }
}

/// A planner's loop allocates nothing in iterations that add no state (20,000 iterations in
/// the boxed square add at most a few allocations: the pocket escape's helpers), and as its
/// trees or roadmap grow, at most `per_state` per state added (amortised: an index's arrays
/// or a vector reaching a new size, a roadmap vertex's list of edges).
fn plans_allocate_as_they_grow<P: Planner<JointSpace>>(label: &str, mut make: impl FnMut() -> P, per_state: f64) {
    let (short, _) = square_plan(&mut make(), Square::Boxed, 1_000);
    let (long, _) = square_plan(&mut make(), Square::Boxed, 21_000);
    println!("{label}, boxed: {short} allocations within 1,000 iterations, {long} within 21,000");
    assert!(
        long <= short + 32,
        "{label}: 20,000 iterations that add no state allocated {} times",
        long.saturating_sub(short)
    );
    let (short, a) = square_plan(&mut make(), Square::Walled, 1_000);
    let (long, b) = square_plan(&mut make(), Square::Walled, 21_000);
    println!(
        "{label}, walled: {short} allocations within 1,000 iterations ({a} states), {long} within 21,000 ({b} states)"
    );
    let (extra, added) = (long.saturating_sub(short), b.saturating_sub(a));
    assert!(
        added > 1_000,
        "{label}: the trees grow in the walled square ({a} → {b} states)"
    );
    assert!(
        extra as f64 <= per_state * added as f64,
        "{label}: {extra} allocations for {added} more states"
    );
}

#[test]
fn birrt_allocates_as_its_trees_grow() {
    plans_allocate_as_they_grow("BiRRT", BiRrt::default, 0.05);
}

#[test]
fn rrt_allocates_as_its_tree_grows() {
    plans_allocate_as_they_grow("RRT", Rrt::default, 0.05);
}

/// A roadmap keeps a list of edges per vertex: one allocation per vertex, and now and then
/// another when a list outgrows the room it was given.
#[test]
fn lazy_prm_allocates_as_its_roadmap_grows() {
    plans_allocate_as_they_grow("LazyPRM", LazyPrm::default, 1.6);
}

/// A plan on a robot allocates what it returns (a vector per path state), its set-up and its
/// trees' growth: counted on a second plan with the same seed, after the first filled the
/// self-collision certificates its checks land in.
#[test]
fn robot_plans_allocate_little() {
    for robot in ["panda", "fetch"] {
        let (space, mut v, request) = world(robot);
        let mut motions = MotionValidator::new(space, 1.0 / 32.0);
        let mut plan = || {
            let mut rng = Pcg64Mcg::seed_from_u64(3);
            allocations(|| {
                BiRrt::default().plan(&mut motions, &mut v, &request, &Budget::iterations(100_000), &mut rng)
            })
        };
        let (_, first) = plan();
        let (n, second) = plan();
        let (first, second) = (first.unwrap(), second.unwrap_or_else(|e| panic!("{robot}: {e}")));
        assert_eq!(first.path, second.path, "{robot}: same seed, same plan");
        let states = second.path.states.len() as u64;
        let grown: usize = second.stats.tree_sizes.iter().sum();
        println!(
            "{robot}: {n} allocations in a plan of {} iterations, {grown} tree states and {states} path states",
            second.stats.iterations
        );
        assert!(
            n <= 64 + 2 * states + grown as u64 / 4,
            "{robot}: {n} allocations for a path of {states} states and trees of {grown}"
        );
    }
}

/// Smoothing allocates for the shortcuts it accepts (the path or trajectory they change), not
/// for the attempts it rejects.
#[test]
fn shortcut_attempts_that_fail_do_not_allocate() {
    use hearth_planning::shortcut::{self, ShortcutSettings};
    let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false]).unwrap();
    // Through the gap at y ∈ [0.48, 0.52] of a wall at x ∈ [0.45, 0.55].
    let mut gap = |q: &[f64]| !(0.45..=0.55).contains(&q[0]) || (0.48..=0.52).contains(&q[1]);
    struct Gap<F>(F);
    impl<F: FnMut(&[f64]) -> bool> StateValidator for Gap<F> {
        fn is_valid(&mut self, q: &[f64]) -> bool {
            (self.0)(q)
        }
        fn checks(&self) -> u64 {
            0
        }
    }
    let path = hearth_planning::Path {
        states: vec![
            vec![0.1, 0.1],
            vec![0.3, 0.5],
            vec![0.5, 0.5],
            vec![0.7, 0.5],
            vec![0.9, 0.1],
        ],
    };
    let limits = Limits::new(vec![1.0; 2], vec![2.0; 2], vec![f64::INFINITY; 2]).unwrap();
    // (allocations, shortcuts accepted) of random then parabolic shortcutting, with `attempts`.
    let mut run = |attempts: usize| {
        let settings = ShortcutSettings {
            attempts,
            ..Default::default()
        };
        let mut motion = MotionValidator::new(space.clone(), 0.002);
        let mut v = Gap(&mut gap);
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let (n, (short, stats)) = allocations(|| shortcut::random(&mut motion, &mut v, &path, &settings, &mut rng));
        let random = (n, stats.accepted);
        let mut t = Trajectory::rest_to_rest(&space, &short, &limits).unwrap();
        let (n, stats) = allocations(|| shortcut::parabolic(&mut motion, &mut v, &mut t, &limits, &settings, &mut rng));
        (random, (n, stats.unwrap().accepted))
    };
    let (few, many) = (run(100), run(2_100));
    for (label, (n0, a0), (n1, a1)) in [("random", few.0, many.0), ("parabolic", few.1, many.1)] {
        println!("{label}: {n0} allocations and {a0} shortcuts in 100 attempts, {n1} and {a1} in 2,100");
        assert!(a1 > a0, "{label}: more attempts shorten more");
        assert!(
            n1 <= n0 + 64 * (a1 - a0),
            "{label}: 2,000 more attempts ({} more shortcuts) allocated {} more times",
            a1 - a0,
            n1.saturating_sub(n0)
        );
    }
}

/// Ramps that the generator refuses cost no allocation either: the shortcutter tests their
/// target states before it asks (`rsruckig` writes the text of every refusal). Here the
/// motion runs to the bound `x ≤ 1` and back, braking at the very acceleration the
/// shortcutter may use: a ramp ending on the way up, where a stop at that acceleration
/// overruns the bound by a rounding error, is refused (as the benchmark's motions near joint
/// limits are).
#[test]
fn refused_ramps_do_not_allocate() {
    use hearth_planning::shortcut::{self, ShortcutSettings};
    use rand::RngExt;
    struct Free;
    impl StateValidator for Free {
        fn is_valid(&mut self, _: &[f64]) -> bool {
            true
        }
        fn checks(&self) -> u64 {
            0
        }
    }
    let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false]).unwrap();
    let path = hearth_planning::Path {
        states: vec![vec![0.0, 0.0], vec![1.0, 0.2], vec![0.0, 0.4], vec![1.0, 0.6]],
    };
    let limits = Limits::new(vec![1.0; 2], vec![0.5; 2], vec![f64::INFINITY; 2])
        .unwrap()
        .with_position_bounds(vec![0.0; 2], vec![1.0; 2])
        .unwrap();
    let start = Trajectory::rest_to_rest(&space, &path, &limits).unwrap();
    // Some ramps between two random times of the motion are refused (36 of 200 with this seed).
    let mut rng = Pcg64Mcg::seed_from_u64(2);
    let (mut q1, mut v1, mut q2, mut v2) = ([0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2]);
    let refused = (0..200)
        .filter(|_| {
            let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
            start.sample(a.min(b) * start.duration(), &mut q1, Some(&mut v1));
            start.sample(a.max(b) * start.duration(), &mut q2, Some(&mut v2));
            Trajectory::ramp(&q1, &v1, &q2, &v2, &limits).is_err()
        })
        .count();
    assert!(refused >= 20, "{refused} of 200 ramps refused");
    let run = |attempts: usize| {
        let settings = ShortcutSettings {
            attempts,
            ..Default::default()
        };
        let mut motion = MotionValidator::new(space.clone(), 0.01);
        let mut t = start.clone();
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let (n, stats) =
            allocations(|| shortcut::parabolic(&mut motion, &mut Free, &mut t, &limits, &settings, &mut rng));
        (n, stats.unwrap().accepted)
    };
    let ((n0, a0), (n1, a1)) = (run(100), run(2_100));
    println!(
        "{refused} of 200 ramps refused; {n0} allocations and {a0} shortcuts in 100 attempts, {n1} and {a1} in 2,100"
    );
    assert!(
        n1 <= n0 + 64 * (a1 - a0),
        "2,000 more attempts ({} more shortcuts) allocated {} more times",
        a1 - a0,
        n1.saturating_sub(n0)
    );
}
