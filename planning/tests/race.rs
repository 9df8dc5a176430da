//! [`Race`]: several copies of a planner on their own threads. The winner is the copy that found
//! its path in the fewest iterations, so a race is reproducible; it answers bad input as the
//! planner alone does. (The Panda's own validator races in `planners.rs`.)

use hearth_planning::space::JointSpace;
use hearth_planning::validity::StateValidator;
use hearth_planning::{
    BiRrt, Budget, Goal, LazyPrm, LazyPrmSettings, MotionValidator, PlanError, PlanRequest, Planner, Race, Rrt,
    Solution,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A wall at x ∈ [0.45, 0.55] with a gap at y ∈ [0.48, 0.52]; it counts its checks.
#[derive(Clone)]
struct Passage(u64);

impl StateValidator for Passage {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.0 += 1;
        !(0.45..=0.55).contains(&q[0]) || (0.48..=0.52).contains(&q[1])
    }
    fn checks(&self) -> u64 {
        self.0
    }
}

fn square() -> JointSpace {
    JointSpace::new(&[0., 0.], &[1., 1.], &[false, false]).unwrap()
}

fn passage_request() -> PlanRequest {
    PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]))
}

/// Races `planner` on `threads` threads through the passage, seeded with `seed`.
fn race<P: Planner<JointSpace> + Clone + Send>(planner: P, threads: usize, seed: u64) -> Result<Solution, PlanError> {
    let mut motion = MotionValidator::new(square(), 0.002);
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    Race::new(planner, threads).plan(
        &mut motion,
        &mut Passage(0),
        &passage_request(),
        &Budget::iterations(200_000),
        &mut rng,
    )
}

/// Each copy of a race alone, with the seeds the race draws: (iterations, path) per copy.
fn copies_alone<P: Planner<JointSpace> + Clone>(planner: &P, threads: usize, seed: u64) -> Vec<(u64, Vec<Vec<f64>>)> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let seeds: Vec<u64> = (0..threads).map(|_| rng.random()).collect();
    seeds
        .into_iter()
        .map(|s| {
            let mut motion = MotionValidator::new(square(), 0.002);
            let solution = planner
                .clone()
                .plan(
                    &mut motion,
                    &mut Passage(0),
                    &passage_request(),
                    &Budget::iterations(200_000),
                    &mut Pcg64Mcg::seed_from_u64(s),
                )
                .unwrap();
            (solution.stats.iterations, solution.path.states)
        })
        .collect()
}

#[test]
fn the_copy_with_the_fewest_iterations_wins_whatever_thread_finishes_first() {
    for (label, threads, seed) in [("birrt", 2, 1), ("birrt", 3, 2), ("birrt", 4, 3)] {
        let alone = copies_alone(&BiRrt::default(), threads, seed);
        let fewest = alone.iter().map(|(n, _)| *n).min().unwrap();
        let winner = alone.iter().find(|(n, _)| *n == fewest).unwrap();
        for _ in 0..3 {
            let s = race(BiRrt::default(), threads, seed).unwrap();
            assert_eq!(s.stats.iterations, fewest, "{label} × {threads}: {alone:?}");
            assert_eq!(s.path.states, winner.1, "{label} × {threads}");
        }
    }
    // RRT's copies differ more from one another; the rule is the same.
    let alone = copies_alone(&Rrt::default(), 2, 5);
    let s = race(Rrt::default(), 2, 5).unwrap();
    assert_eq!(s.stats.iterations, alone.iter().map(|(n, _)| *n).min().unwrap());
}

#[test]
fn one_thread_plans_as_the_planner_alone() {
    let mut motion = MotionValidator::new(square(), 0.002);
    let alone = BiRrt::default()
        .plan(
            &mut motion,
            &mut Passage(0),
            &passage_request(),
            &Budget::iterations(200_000),
            &mut Pcg64Mcg::seed_from_u64(9),
        )
        .unwrap();
    for threads in [0, 1] {
        let raced = race(BiRrt::default(), threads, 9).unwrap();
        assert_eq!(raced.path, alone.path, "{threads} threads");
        assert_eq!(raced.stats.iterations, alone.stats.iterations);
    }
}

#[test]
fn bad_input_and_invalid_starts_are_reported_as_alone() {
    let mut motion = MotionValidator::new(square(), 0.002);
    let mut plan = |request: PlanRequest, budget: Budget| {
        Race::new(BiRrt::default(), 3).plan(
            &mut motion,
            &mut Passage(0),
            &request,
            &budget,
            &mut Pcg64Mcg::seed_from_u64(0),
        )
    };
    let e = plan(
        PlanRequest::new(vec![f64::NAN, 0.1], Goal::Config(vec![0.9, 0.1])),
        Budget::iterations(100),
    )
    .unwrap_err();
    assert!(matches!(e, PlanError::BadInput(_)), "{e}");
    let e = plan(
        PlanRequest::new(vec![0.5, 0.1], Goal::Config(vec![0.9, 0.1])),
        Budget::iterations(100),
    )
    .unwrap_err();
    assert!(matches!(e, PlanError::InvalidStart { .. }), "{e}");
    let e = plan(passage_request(), Budget::default()).unwrap_err();
    assert!(matches!(e, PlanError::BadInput(_)), "{e}");
    // Too few iterations for any copy: a timeout, with thread 0's statistics.
    let e = plan(passage_request(), Budget::iterations(3)).unwrap_err();
    match e {
        PlanError::Timeout { stats } => assert_eq!(stats.iterations, 3),
        other => panic!("{other}"),
    }
}

#[test]
fn lazy_prm_keeps_the_winners_roadmap() {
    let settings = LazyPrmSettings::default();
    let mut race = Race::new(LazyPrm::new(settings.clone()), 2);
    let mut motion = MotionValidator::new(square(), 0.002);
    let mut rng = Pcg64Mcg::seed_from_u64(4);
    let first = race
        .plan(
            &mut motion,
            &mut Passage(0),
            &passage_request(),
            &Budget::iterations(200_000),
            &mut rng,
        )
        .unwrap();
    assert!(first.path.states.iter().any(|q| (0.48..=0.52).contains(&q[1])));
    // The kept roadmap answers a second query in the same world.
    let again = PlanRequest::new(vec![0.9, 0.9], Goal::Config(vec![0.1, 0.9]));
    let second = race
        .plan(
            &mut motion,
            &mut Passage(0),
            &again,
            &Budget::iterations(200_000),
            &mut rng,
        )
        .unwrap();
    assert!(second.path.states.iter().any(|q| (0.48..=0.52).contains(&q[1])));
}
