//! BiRRT, RRT and LazyPRM on a fixed subset of MotionBenchMaker problems (the Panda
//! table_pick problems in `planning/tests/data`, fingers at 0.04 m), and the smoothing
//! pipeline (repair at the fine resolution + random + parabolic shortcutting) on their paths,
//! then the two jerk-limited passes over the smoothed motions (`jerk/…`: the moving average,
//! built and sampled at 1 ms, and Ruckig's waypoint solver through states 0.2 rad apart).
//! Each plan uses the same seed, so every iteration plans the same path. `nn/…` times one
//! nearest-neighbour query (and one query for the 10 nearest) among 20,000 random Panda
//! configurations, with k-d trees (the Panda's bounded joints) and with k-d trees
//! on the torus (the same space with its first joint made continuous), and one query among
//! 1,000 states packed in a pocket (±0.3 rad) from samples of the whole space;
//! `nn/k10_4k_fetch` queries the 10 nearest among 4,000 random configurations of the Fetch's
//! torso and arm (three continuous joints), the size of a LazyPRM roadmap after a few tenths
//! of a second. `nn/nearest_2k_se2` queries among 2,000 poses of a mobile base in a 10 m × 8 m
//! home and `nn/nearest_20k_base_arm` among 20,000 states of the Fetch's base, torso and arm:
//! metrics that are no Euclidean ones, searched with k-d trees on their Euclidean bound.
//! `queries/…` plans 16 queries between random valid configurations in one
//! scene: BiRRT, a fresh LazyPRM per query, and one LazyPRM that keeps its roadmap.
//! `pipeline/…` plans the table_pick problems through `MotionPlanner` (BiRRT, parabolic
//! smoothing, the check at 0.002 rad), in the joints' reach metric and without it.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_planning::pipeline::{MotionPlanner, MotionSettings};
use hearth_planning::problem::ProblemSet;
use hearth_planning::shortcut::{ShortcutSettings, Smoothing, smooth};
use hearth_planning::space::JointSpace;
use hearth_planning::trajectory::{Limits, Trajectory};
use hearth_planning::{
    BiRrt, Budget, Goal, LazyPrm, LazyPrmSettings, MotionValidator, PlanRequest, Planner, RobotValidity, Rrt,
};
use rand::{RngExt, SeedableRng};

const RESOLUTION: f64 = 0.02;

struct Fixture {
    space: JointSpace,
    validity: Vec<RobotValidity>,
    requests: Vec<PlanRequest>,
    limits: Limits,
}

fn fixture() -> Fixture {
    let set = ProblemSet::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../planning/tests/data/panda_table_pick.json"
    ))
    .expect("problem data");
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let acm = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 2000,
            ..Default::default()
        },
    );
    let mut reference = m.neutral_configuration();
    Chain::new(&m, &["panda_finger_joint1"])
        .unwrap()
        .scatter(&[0.04], &mut reference);
    let mut validity = Vec::new();
    let mut requests = Vec::new();
    for p in set.valid_problems() {
        let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(p.scene()));
        v.set_reference(&reference).unwrap();
        validity.push(v);
        requests.push(PlanRequest::new(p.start.clone(), Goal::AnyOf(p.goals.clone())));
    }
    Fixture {
        space: JointSpace::from_chain(&arm).unwrap(),
        validity,
        requests,
        limits: Limits::for_chain(&arm),
    }
}

/// Plans `queries` in the first problem's scene, with a fresh planner per query or (`keep`)
/// one planner for the whole sequence; returns how many were solved.
fn plan_queries<P: Planner<JointSpace>>(
    f: &mut Fixture,
    queries: &[PlanRequest],
    make: impl Fn() -> P,
    keep: bool,
) -> usize {
    let mut motion = MotionValidator::new(f.space.clone(), RESOLUTION);
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let mut kept = make();
    let mut solved = 0;
    for (i, r) in queries.iter().enumerate() {
        if !keep && i > 0 {
            kept = make();
        }
        solved += kept
            .plan(&mut motion, &mut f.validity[0], r, &Budget::time(1.0), &mut rng)
            .is_ok() as usize;
    }
    solved
}

fn plan_all<P: Planner<JointSpace>>(f: &mut Fixture, make: impl Fn() -> P) -> usize {
    let mut solved = 0;
    for (v, r) in f.validity.iter_mut().zip(&f.requests) {
        let mut motion = MotionValidator::new(f.space.clone(), RESOLUTION);
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
        let mut planner = make();
        solved += planner.plan(&mut motion, v, r, &Budget::time(1.0), &mut rng).is_ok() as usize;
    }
    solved
}

fn planners(c: &mut Criterion) {
    let mut f = fixture();
    let mut g = c.benchmark_group("plan/panda_table_pick");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("birrt", |b| b.iter(|| black_box(plan_all(&mut f, BiRrt::default))));
    g.bench_function("rrt", |b| b.iter(|| black_box(plan_all(&mut f, Rrt::default))));
    g.bench_function("lazyprm", |b| {
        b.iter(|| black_box(plan_all(&mut f, || LazyPrm::new(LazyPrmSettings::default()))))
    });
    g.finish();

    // The whole chain through `MotionPlanner` (BiRRT, parabolic smoothing, checked at 0.002
    // rad) with its defaults, in the joints' reach metric and without it.
    let mut g = c.benchmark_group("pipeline/panda_table_pick");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    for (name, reach_weights) in [("reach", true), ("unweighted", false)] {
        let settings = MotionSettings {
            reach_weights,
            ..MotionSettings::default()
        };
        let mut planners: Vec<MotionPlanner> = f
            .validity
            .iter()
            .map(|v| MotionPlanner::new(v.clone(), settings.clone()).expect("default settings"))
            .collect();
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
                let mut solved = 0;
                for (p, r) in planners.iter_mut().zip(&f.requests) {
                    solved += p.plan(&r.start, r.goal.clone(), &Budget::time(1.0), &mut rng).is_ok() as usize;
                }
                black_box(solved)
            })
        });
    }
    g.finish();

    // Many queries in one static scene (the first table_pick problem's): 16 queries between
    // random valid configurations, each planned by a fresh planner, or by one LazyPRM that
    // keeps its roadmap from query to query (each iteration starts from an empty roadmap, so
    // the time is the whole sequence's, roadmap building included).
    let queries = {
        use hearth_planning::space::Space;
        use hearth_planning::validity::StateValidator;
        let v = &mut f.validity[0];
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let mut q = vec![0.0; f.space.dim()];
        let mut states = Vec::new();
        while states.len() < 17 {
            f.space.sample(&mut rng, &mut q);
            if v.is_valid(&q) {
                states.push(q.clone());
            }
        }
        states
            .windows(2)
            .map(|w| PlanRequest::new(w[0].clone(), Goal::Config(w[1].clone())))
            .collect::<Vec<_>>()
    };
    let prm = || LazyPrm::new(LazyPrmSettings::default());
    let solved = [
        ("BiRRT", plan_queries(&mut f, &queries, BiRrt::default, false)),
        ("LazyPRM, fresh", plan_queries(&mut f, &queries, prm, false)),
        ("LazyPRM, kept", plan_queries(&mut f, &queries, prm, true)),
    ];
    for (name, solved) in solved {
        eprintln!(
            "queries/panda_table_pick_16: {name} solves {solved} of {}",
            queries.len()
        );
    }
    let mut g = c.benchmark_group("queries/panda_table_pick_16");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("birrt", |b| {
        b.iter(|| black_box(plan_queries(&mut f, &queries, BiRrt::default, false)))
    });
    g.bench_function("lazyprm_fresh", |b| {
        b.iter(|| black_box(plan_queries(&mut f, &queries, prm, false)))
    });
    g.bench_function("lazyprm_kept", |b| {
        b.iter(|| black_box(plan_queries(&mut f, &queries, prm, true)))
    });
    g.finish();

    // Smoothing of the BiRRT paths.
    let mut paths = Vec::new();
    for (i, (v, r)) in f.validity.iter_mut().zip(&f.requests).enumerate() {
        let mut motion = MotionValidator::new(f.space.clone(), RESOLUTION);
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
        if let Ok(s) = BiRrt::default().plan(&mut motion, v, r, &Budget::time(1.0), &mut rng) {
            paths.push((i, s.path));
        }
    }
    // As `hearth bench plan`: ramps checked at a tenth of the planning resolution, and the
    // finished motion verified there.
    let settings = ShortcutSettings {
        fine_resolution: Some(RESOLUTION / 10.0),
        verify_resolution: Some(RESOLUTION / 10.0),
        ..Default::default()
    };
    let mut g = c.benchmark_group("smooth/panda_table_pick");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    for (name, smoothing) in [("random", Smoothing::Random), ("parabolic", Smoothing::Parabolic)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                for (i, p) in &paths {
                    let v = &mut f.validity[*i];
                    let mut motion = MotionValidator::new(f.space.clone(), RESOLUTION);
                    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
                    let out = smooth(
                        smoothing,
                        &mut motion,
                        v,
                        p,
                        &f.limits,
                        &settings,
                        Duration::from_secs(1),
                        &mut rng,
                    );
                    black_box(out.ok());
                }
            })
        });
    }
    g.finish();

    // Jerk-limited passes over the smoothed motions.
    let smoothed: Vec<Trajectory> = paths
        .iter()
        .filter_map(|(i, p)| {
            let mut motion = MotionValidator::new(f.space.clone(), RESOLUTION);
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
            let v = &mut f.validity[*i];
            smooth(
                Smoothing::Parabolic,
                &mut motion,
                v,
                p,
                &f.limits,
                &settings,
                Duration::from_secs(1),
                &mut rng,
            )
            .ok()
            .map(|s| s.trajectory)
        })
        .collect();
    let mut g = c.benchmark_group("jerk/panda_table_pick");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("average", |b| {
        let mut q = vec![0.0; 7];
        b.iter(|| {
            for t in &smoothed {
                let j = t.with_jerk_limits(&f.limits).unwrap();
                let steps = (j.duration() / 1e-3) as usize;
                for k in 0..=steps {
                    j.sample(k as f64 * 1e-3, &mut q, None);
                }
                black_box(&q);
            }
        })
    });
    g.bench_function("ruckig_waypoints", |b| {
        b.iter(|| {
            for t in &smoothed {
                let path = t.to_path(&f.space, 0.2).expect("0.2 is a valid resolution");
                black_box(Trajectory::jerk_limited(&f.space, &path, &f.limits).ok());
            }
        })
    });
    g.finish();
}

fn nearest_neighbours(c: &mut Criterion) {
    use hearth_planning::nn::NearestNeighbors;
    use hearth_planning::space::Space;
    let (lower, upper) = (
        [-2.9, -1.76, -2.9, -3.07, -2.9, -0.02, -2.9],
        [2.9, 1.76, 2.9, -0.07, 2.9, 3.75, 2.9],
    );
    let mut continuous = [false; 7];
    let kd = JointSpace::new(&lower, &upper, &continuous).expect("valid bounds");
    continuous[0] = true;
    let torus = JointSpace::new(&lower, &upper, &continuous).expect("valid bounds");
    let mut g = c.benchmark_group("nn");
    // Random states of the whole space, or (`pocket`) a tree stuck in a pocket: 1,000 states
    // within ±0.3 rad of one configuration, queried with samples from the whole space (every
    // query is far from every state).
    let cases = [
        ("20k_kd", &kd, false),
        ("20k_torus", &torus, false),
        ("1k_pocket_kd", &kd, true),
        ("1k_pocket_torus", &torus, true),
    ];
    for (name, space, pocket) in cases {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(if pocket { 5 } else { 4 });
        let mut centre = [0.0; 7];
        if pocket {
            space.sample(&mut rng, &mut centre);
        }
        let mut nn = NearestNeighbors::new(7);
        let mut q = [0.0; 7];
        for _ in 0..if pocket { 1_000 } else { 20_000 } {
            if pocket {
                for (x, c) in q.iter_mut().zip(&centre) {
                    *x = c + rng.random_range(-0.3..0.3);
                }
                space.enforce_bounds(&mut q);
            } else {
                space.sample(&mut rng, &mut q);
            }
            nn.insert(&q);
            nn.nearest(space, &q);
        }
        let queries = random_queries(space, &mut rng);
        time_nearest(&mut g, name, &mut nn, space, &queries);
        let mut i = 0;
        if !pocket {
            g.bench_function(format!("k10_{name}"), |b| {
                b.iter(|| {
                    i = (i + 1) % queries.len();
                    black_box(nn.k_nearest(space, &queries[i], 10))
                })
            });
        }
    }
    // The Fetch's torso and arm, with interleaved queries as LazyPRM makes them: each new
    // vertex asks for its 10 nearest before it is inserted.
    let model = RobotModel::builtin("fetch").expect("built-in robot");
    let fetch =
        JointSpace::from_chain(&Chain::named(&model, "arm_with_torso").expect("built-in chain")).expect("valid bounds");
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(6);
    let mut nn = NearestNeighbors::new(8);
    let mut q = [0.0; 8];
    for _ in 0..4_000 {
        fetch.sample(&mut rng, &mut q);
        black_box(nn.k_nearest(&fetch, &q, 10));
        nn.insert(&q);
    }
    let queries: Vec<[f64; 8]> = (0..256)
        .map(|_| {
            fetch.sample(&mut rng, &mut q);
            q
        })
        .collect();
    let mut i = 0;
    g.bench_function("k10_4k_fetch", |b| {
        b.iter(|| {
            i = (i + 1) % queries.len();
            black_box(nn.k_nearest(&fetch, &queries[i], 10))
        })
    });
    // A tree growing from nothing to 4,000 of the Fetch's states, one nearest query before
    // each insert as a tree planner makes them: the index's rebuilds as it grows.
    let states: Vec<[f64; 8]> = (0..4_000)
        .map(|_| {
            fetch.sample(&mut rng, &mut q);
            q
        })
        .collect();
    g.bench_function("grow_4k_fetch", |b| {
        b.iter(|| {
            let mut nn = NearestNeighbors::new(8);
            for s in &states {
                black_box(nn.nearest(&fetch, s));
                nn.insert(s);
            }
            nn
        })
    });
    g.finish();
}

/// One nearest-state query among `n` random states of `space`, inserted with interleaved
/// queries as a tree planner makes them.
fn nearest_among<S: hearth_planning::space::Space>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    space: &S,
    n: usize,
) {
    use hearth_planning::nn::NearestNeighbors;
    let dim = space.dim();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
    let mut nn = NearestNeighbors::new(dim);
    let mut q = vec![0.0; dim];
    for _ in 0..n {
        space.sample(&mut rng, &mut q);
        nn.insert(&q);
        nn.nearest(space, &q);
    }
    let queries = random_queries(space, &mut rng);
    time_nearest(g, name, &mut nn, space, &queries);
}

/// 256 random states of `space`, the queries of a nearest-neighbour bench.
fn random_queries<S: hearth_planning::space::Space>(space: &S, rng: &mut rand_pcg::Pcg64Mcg) -> Vec<Vec<f64>> {
    let mut q = vec![0.0; space.dim()];
    (0..256)
        .map(|_| {
            space.sample(rng, &mut q);
            q.clone()
        })
        .collect()
}

/// Times `nn/nearest_{name}`: one nearest-state query per iteration, cycling through `queries`.
fn time_nearest<S: hearth_planning::space::Space>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    nn: &mut hearth_planning::nn::NearestNeighbors,
    space: &S,
    queries: &[Vec<f64>],
) {
    let mut i = 0;
    g.bench_function(format!("nearest_{name}"), |b| {
        b.iter(|| {
            i = (i + 1) % queries.len();
            black_box(nn.nearest(space, &queries[i]))
        })
    });
}

/// The navigation planner's SE(2) poses and a mobile manipulator's base + torso + arm.
fn mobile_nearest_neighbours(c: &mut Criterion) {
    use hearth_planning::space::{CompoundSpace, Se2Space};
    let mut g = c.benchmark_group("nn");
    let base = Se2Space::new([0.0, 0.0], [10.0, 8.0]).expect("valid bounds");
    nearest_among(&mut g, "2k_se2", &base, 2_000);
    let model = RobotModel::builtin("fetch").expect("built-in robot");
    let arm =
        JointSpace::from_chain(&Chain::named(&model, "arm_with_torso").expect("built-in chain")).expect("valid bounds");
    nearest_among(&mut g, "20k_base_arm", &CompoundSpace::new(base, arm), 20_000);
    g.finish();
}

criterion_group!(benches, planners, nearest_neighbours, mobile_nearest_neighbours);
criterion_main!(benches);
