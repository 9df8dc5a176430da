//! The single-configuration check (FK + every link against the obstacles + self-collision),
//! the hot loop of every planner, on a MotionBenchMaker Panda problem.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_planning::problem::ProblemSet;
use hearth_planning::validity::{RobotValidity, StateValidator};
use rand::SeedableRng;

fn state_validity(c: &mut Criterion) {
    let set = ProblemSet::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../planning/tests/data/panda_table_pick.json"
    ))
    .expect("problem data");
    let problem = set.valid_problems().next().expect("a valid problem");
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let acm = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 2000,
            ..Default::default()
        },
    );
    let mut v = RobotValidity::new(arm.clone(), acm, Arc::new(problem.scene()));
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    let qs: Vec<Vec<f64>> = (0..256)
        .map(|_| {
            let mut q = vec![0.0; 7];
            arm.random_configuration(&mut rng, &mut q);
            q
        })
        .collect();
    let mut k = 0;
    c.bench_function("state_validity/panda_table_pick_random", |b| {
        b.iter(|| {
            k = (k + 1) & 255;
            black_box(v.is_valid(black_box(&qs[k])))
        })
    });
    c.bench_function("state_validity/panda_table_pick_random_exact", |b| {
        b.iter(|| {
            k = (k + 1) & 255;
            black_box(v.is_valid_exact(black_box(&qs[k])))
        })
    });
    let start = problem.start.clone();
    c.bench_function("state_validity/panda_table_pick_start", |b| {
        b.iter(|| black_box(v.is_valid(black_box(&start))))
    });
    c.bench_function("state_validity/panda_table_pick_start_exact", |b| {
        b.iter(|| black_box(v.is_valid_exact(black_box(&start))))
    });
}

criterion_group!(benches, state_validity);
criterion_main!(benches);
