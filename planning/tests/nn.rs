//! Nearest-neighbour search is exact: it agrees with a brute-force scan under the space's own
//! metric, continuous (wrapping) joints and SE(2) yaw included.

use hearth_planning::nn::NearestNeighbors;
use hearth_planning::space::{CompoundSpace, EuclideanBound, JointSpace, Se2Space, Space};
use proptest::prelude::*;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn joint_space() -> JointSpace {
    // Two bounded joints, two continuous ones; weights make the metric anisotropic.
    JointSpace::new(
        &[-1.0, 0.0, 0.0, -2.0],
        &[1.0, 0.0, 0.0, 0.5],
        &[false, true, true, false],
    )
    .unwrap()
    .with_weights(&[1.0, 0.7, 1.3, 0.4])
    .unwrap()
}

/// Bounded joints only: a weighted Euclidean metric, indexed by k-d trees. One weight is 0
/// (a joint that does not count) and the bounds are far apart, so cells are long and thin.
fn euclidean_space() -> JointSpace {
    JointSpace::new(&[-1.0, 0.0, -3.0, -0.1, -2.0], &[1.0, 0.5, 3.0, 0.1, 0.5], &[false; 5])
        .unwrap()
        .with_weights(&[1.0, 0.0, 1.3, 2.0, 0.4])
        .unwrap()
}

fn se2_space() -> Se2Space {
    Se2Space::new([-2.0, -2.0], [2.0, 2.0]).unwrap()
}

/// A mobile manipulator's space: an SE(2) base and an arm with a continuous joint, the arm
/// weighted down (its metric is bounded by a weighted Euclidean one with stretch 2).
fn base_and_arm(yaw_weight: f64, arm_weight: f64) -> CompoundSpace<Se2Space, JointSpace> {
    let base = se2_space().with_yaw_weight(yaw_weight).unwrap();
    let arm = JointSpace::new(&[-1.0, 0.0, -2.0], &[1.0, 0.0, 0.5], &[false, true, false])
        .unwrap()
        .with_weights(&[1.0, 0.7, 0.4])
        .unwrap();
    CompoundSpace::new(base, arm).with_weights(1.0, arm_weight).unwrap()
}

/// Inserts `n` samples (removing every `remove_every`-th), then compares queries with a scan.
fn agrees_with_brute_force<S: Space>(space: &S, seed: u64, n: usize, remove_every: usize, k: usize, radius: f64) {
    agrees_after_reindex(space, space, seed, n, remove_every, k, radius);
}

/// As [`agrees_with_brute_force`], but the states are inserted and queried under `first`'s
/// metric, then re-indexed for `space` ([`NearestNeighbors::reindex`]) and compared under it.
fn agrees_after_reindex<S: Space>(
    first: &S,
    space: &S,
    seed: u64,
    n: usize,
    remove_every: usize,
    k: usize,
    radius: f64,
) {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let dim = space.dim();
    let mut nn = NearestNeighbors::new(dim);
    let mut states = Vec::new();
    let mut q = vec![0.0; dim];
    for i in 0..n {
        space.sample(&mut rng, &mut q);
        assert_eq!(nn.insert(&q), i);
        states.push(q.clone());
        if remove_every > 0 && i % remove_every == remove_every - 1 {
            nn.remove(i / 2);
        }
    }
    if !std::ptr::eq(first, space) {
        // Queries under the first metric index the buffer in trees built for it.
        space.sample(&mut rng, &mut q);
        nn.nearest(first, &q);
        nn.reindex(space);
    }
    let live: Vec<usize> = (0..n).filter(|&i| !nn.is_removed(i)).collect();
    assert_eq!(nn.len(), live.len());
    for _ in 0..20 {
        space.sample(&mut rng, &mut q);
        let mut by_distance: Vec<(f64, usize)> = live.iter().map(|&i| (space.distance(&q, &states[i]), i)).collect();
        by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        match nn.nearest(space, &q) {
            None => assert!(live.is_empty()),
            Some(i) => assert_eq!(space.distance(&q, &states[i]), by_distance[0].0),
        }
        let expected: Vec<usize> = by_distance.iter().take(k).map(|e| e.1).collect();
        assert_eq!(nn.k_nearest(space, &q, k), expected);
        let expected: Vec<usize> = by_distance.iter().filter(|e| e.0 <= radius).map(|e| e.1).collect();
        assert_eq!(nn.within_radius(space, &q, radius), expected);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn joint_space_with_continuous_joints(seed in any::<u64>(), n in 0usize..600, remove in 0usize..7, k in 0usize..12) {
        agrees_with_brute_force(&joint_space(), seed, n, remove, k, 1.0);
    }

    #[test]
    fn reindexed_for_other_weights(seed in any::<u64>(), n in 0usize..600, remove in 0usize..7, k in 0usize..12, w in proptest::collection::vec(0.0f64..3.0, 5)) {
        let other = euclidean_space().with_weights(&w).unwrap();
        agrees_after_reindex(&euclidean_space(), &other, seed, n, remove, k, 1.0);
        let wrapping = joint_space().with_weights(&w[..4]).unwrap();
        agrees_after_reindex(&joint_space(), &wrapping, seed, n, remove, k, 1.0);
    }

    #[test]
    fn euclidean_joint_space(seed in any::<u64>(), n in 0usize..600, remove in 0usize..7, k in 0usize..12) {
        prop_assert!(euclidean_space().euclidean_weights().is_some());
        agrees_with_brute_force(&euclidean_space(), seed, n, remove, k, 1.0);
    }

    /// Angles given unwrapped (a state at 3.0 + 4π is the state at 3.0), as a user may pass
    /// them: the k-d trees on the torus wrap them and still agree with the space's metric.
    #[test]
    fn unwrapped_angles(seed in any::<u64>(), n in 1usize..400, k in 1usize..12, turns in proptest::collection::vec(-3i32..=3, 8)) {
        let space = joint_space();
        prop_assert!(space.euclidean_weights().is_none() && space.wrapping_weights().is_some());
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let mut nn = NearestNeighbors::new(4);
        let mut states = Vec::new();
        let mut q = vec![0.0; 4];
        let unwrap = |q: &mut Vec<f64>, i: usize| {
            q[1] += f64::from(turns[i % 8]) * std::f64::consts::TAU;
            q[2] -= f64::from(turns[(i + 3) % 8]) * std::f64::consts::TAU;
        };
        for i in 0..n {
            space.sample(&mut rng, &mut q);
            unwrap(&mut q, i);
            nn.insert(&q);
            states.push(q.clone());
        }
        for j in 0..20 {
            space.sample(&mut rng, &mut q);
            unwrap(&mut q, j + 1);
            let mut by_distance: Vec<(f64, usize)> =
                states.iter().enumerate().map(|(i, p)| (space.distance(&q, p), i)).collect();
            by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let expected: Vec<usize> = by_distance.iter().take(k).map(|e| e.1).collect();
            prop_assert_eq!(nn.k_nearest(&space, &q, k), expected);
        }
    }

    /// A tree stuck in a pocket, queried from the whole space: the states lie within `spread`
    /// of one state (on the angles possibly across ±π), every query far from all of them. The
    /// k-d trees prune with their nodes' boxes here, and must stay exact.
    #[test]
    fn pocketed_states_queried_from_afar(seed in any::<u64>(), n in 1usize..700, k in 1usize..12, spread in 0.01f64..0.6, across in any::<bool>()) {
        let space = joint_space();
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let mut centre = vec![0.0; 4];
        space.sample(&mut rng, &mut centre);
        if across {
            centre[1] = std::f64::consts::PI - 0.5 * spread;
        }
        let mut nn = NearestNeighbors::new(4);
        let mut states = Vec::new();
        let mut q = vec![0.0; 4];
        for i in 0..n {
            for (x, c) in q.iter_mut().zip(&centre) {
                *x = c + spread * (2.0 * rand::RngExt::random::<f64>(&mut rng) - 1.0);
            }
            space.enforce_bounds(&mut q);
            prop_assert_eq!(nn.insert(&q), i);
            states.push(q.clone());
        }
        for _ in 0..20 {
            space.sample(&mut rng, &mut q);
            let mut by_distance: Vec<(f64, usize)> =
                states.iter().enumerate().map(|(i, p)| (space.distance(&q, p), i)).collect();
            by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let expected: Vec<usize> = by_distance.iter().take(k).map(|e| e.1).collect();
            prop_assert_eq!(nn.k_nearest(&space, &q, k), expected);
            prop_assert_eq!(nn.nearest(&space, &q), Some(by_distance[0].1));
        }
    }

    #[test]
    fn se2_space_with_wrapping_yaw(seed in any::<u64>(), n in 0usize..600, remove in 0usize..7, k in 0usize..12) {
        agrees_with_brute_force(&se2_space(), seed, n, remove, k, 0.8);
    }

    /// Yaw weights from none to dominant: the Euclidean bound's k-d trees still give the
    /// SE(2) metric's exact answers.
    #[test]
    fn se2_space_with_any_yaw_weight(seed in any::<u64>(), n in 0usize..600, k in 0usize..12, yaw in prop_oneof![Just(0.0), 0.0f64..5.0, Just(40.0)]) {
        let space = se2_space().with_yaw_weight(yaw).unwrap();
        agrees_with_brute_force(&space, seed, n, 3, k, 0.8);
    }

    #[test]
    fn base_and_arm_compound(seed in any::<u64>(), n in 0usize..600, remove in 0usize..7, k in 0usize..12, yaw in 0.0f64..3.0, arm in 0.0f64..3.0) {
        agrees_with_brute_force(&base_and_arm(yaw, arm), seed, n, remove, k, 1.2);
    }

    /// A bound with NaN or negative weights, weights or groups of the wrong length, or with a
    /// stretch below 1 or infinite is ignored: the index falls back on the triangle inequality and stays
    /// exact.
    #[test]
    fn unusable_bounds_are_ignored(seed in any::<u64>(), n in 0usize..400, k in 0usize..8, bad in 0usize..6) {
        let space = Counting { inner: se2_space(), calls: Default::default(), euclidean: true, bad: Some(bad) };
        agrees_with_brute_force(&space, seed, n, 4, k, 0.8);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// States on a shell around the query, far from the origin (coordinates near ±40, one of
    /// them an angle), whose distances differ by parts in 10¹⁰: far below what f32 resolves,
    /// so every filter that rounds must let the exact distance decide.
    #[test]
    fn near_ties_far_from_the_origin(seed in any::<u64>(), n in 1usize..1200, k in 1usize..6) {
        let space = JointSpace::new(&[-50.0, -50.0, -50.0, 0.0], &[50.0, 50.0, 50.0, 0.0], &[false, false, false, true])
            .unwrap()
            .with_weights(&[1.0, 0.5, 2.0, 0.8])
            .unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let q = [40.0, -39.0, 38.5, 3.1];
        let mut nn = NearestNeighbors::new(4);
        let mut states = Vec::new();
        for i in 0..n {
            // A random direction scaled to weighted length 1 + i·1e-10 (a shuffled order).
            let mut d: [f64; 4] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let w = [1.0, 0.5, 2.0, 0.8];
            let len = d.iter().zip(&w).map(|(x, w)| (x * w).powi(2)).sum::<f64>().sqrt();
            let r = 1.0 + ((i * 7919) % n) as f64 * 1e-10;
            for x in &mut d {
                *x *= r / len;
            }
            let s: Vec<f64> = q.iter().zip(&d).map(|(a, b)| a + b).collect();
            nn.insert(&s);
            states.push(s);
        }
        let mut by_distance: Vec<(f64, usize)> = states.iter().enumerate().map(|(i, s)| (space.distance(&q, s), i)).collect();
        by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        prop_assert_eq!(nn.nearest(&space, &q), Some(by_distance[0].1));
        let expected: Vec<usize> = by_distance.iter().take(k).map(|e| e.1).collect();
        prop_assert_eq!(nn.k_nearest(&space, &q, k), expected);
    }
}

#[test]
fn wraps_through_pi() {
    let space = se2_space();
    let mut nn = NearestNeighbors::new(3);
    for i in 0..200 {
        let yaw = -3.0 + 6.0 * i as f64 / 200.0;
        nn.insert(&[0.0, 0.0, yaw]);
    }
    let far = nn.insert(&[0.0, 0.0, 3.1]);
    // -3.1 is 0.083 from 3.1 the short way round, closer than any yaw in [-3, 3).
    assert_eq!(nn.nearest(&space, &[0.0, 0.0, -3.1]), Some(far));
    nn.clear();
    assert!(nn.is_empty());
    assert_eq!(nn.nearest(&space, &[0.0, 0.0, 0.0]), None);
}

/// A space that counts its distance evaluations; it declares its metric Euclidean, or bounded
/// by a Euclidean one (so the index builds k-d trees), only when `euclidean` is set. `bad`
/// makes it declare an unusable bound of one of six kinds instead.
struct Counting<S = JointSpace> {
    inner: S,
    calls: std::sync::atomic::AtomicU64,
    euclidean: bool,
    bad: Option<usize>,
}

/// A [`Counting`] space over `inner` that declares a usable bound when `euclidean` is set.
fn counting<S: Space>(inner: S, euclidean: bool) -> Counting<S> {
    Counting {
        inner,
        calls: Default::default(),
        euclidean,
        bad: None,
    }
}

impl<S: Space> Space for Counting<S> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn sample<R: rand::Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        self.inner.sample(rng, out)
    }
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.inner.distance(a, b)
    }
    fn interpolate(&self, a: &[f64], b: &[f64], t: f64, out: &mut [f64]) {
        self.inner.interpolate(a, b, t, out)
    }
    fn lower(&self) -> &[f64] {
        self.inner.lower()
    }
    fn upper(&self) -> &[f64] {
        self.inner.upper()
    }
    fn enforce_bounds(&self, q: &mut [f64]) {
        self.inner.enforce_bounds(q)
    }
    fn satisfies_bounds(&self, q: &[f64]) -> bool {
        self.inner.satisfies_bounds(q)
    }
    fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        self.inner.difference(a, b, out)
    }
    fn check(&self, q: &[f64]) -> Result<(), hearth_planning::space::SpaceError> {
        self.inner.check(q)
    }
    fn coordinate_name(&self, i: usize) -> Option<&str> {
        self.inner.coordinate_name(i)
    }
    fn euclidean_weights(&self) -> Option<&[f64]> {
        if self.euclidean {
            self.inner.euclidean_weights()
        } else {
            None
        }
    }
    fn euclidean_bound(&self) -> Option<EuclideanBound<'_>> {
        let bound = self.inner.euclidean_bound().filter(|_| self.euclidean)?;
        Some(match self.bad {
            None => bound,
            Some(0) => EuclideanBound {
                weights: &[1.0, f64::NAN, 0.5],
                ..bound
            },
            Some(1) => EuclideanBound {
                weights: &[1.0, -1.0, 0.5],
                ..bound
            },
            Some(2) => EuclideanBound {
                weights: &[1.0, 1.0],
                ..bound
            },
            Some(3) => EuclideanBound { stretch: 0.9, ..bound },
            Some(4) => EuclideanBound {
                groups: &[0, 1],
                ..bound
            },
            Some(_) => EuclideanBound {
                stretch: f64::INFINITY,
                ..bound
            },
        })
    }
}

/// Distance evaluations per nearest query among `n` states inserted with interleaved
/// queries, as in a tree planner.
fn evaluations_per_query<S: Space>(space: &Counting<S>, n: usize) -> u64 {
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    let dim = space.dim();
    let mut nn = NearestNeighbors::new(dim);
    let mut q = vec![0.0; dim];
    for _ in 0..n {
        space.sample(&mut rng, &mut q);
        nn.insert(&q);
        nn.nearest(space, &q);
    }
    let before = space.calls.load(std::sync::atomic::Ordering::Relaxed);
    let queries = 100;
    for _ in 0..queries {
        space.sample(&mut rng, &mut q);
        nn.nearest(space, &q);
    }
    (space.calls.load(std::sync::atomic::Ordering::Relaxed) - before) / queries
}

#[test]
fn k_d_trees_prune_better_than_vantage_points_in_seven_dimensions() {
    // A Panda-like space: seven bounded joints.
    let joints = || {
        JointSpace::new(
            &[-2.9, -1.76, -2.9, -3.07, -2.9, -0.02, -2.9],
            &[2.9, 1.76, 2.9, -0.07, 2.9, 3.75, 2.9],
            &[false; 7],
        )
        .unwrap()
    };
    prunes_better_with_k_d_trees("seven-dimensional", joints);
}

/// Distance evaluations per nearest query among 20,000 states of `make()`'s space: with
/// k-d trees fewer than half those with vantage-point trees.
fn prunes_better_with_k_d_trees<S: Space>(what: &str, make: impl Fn() -> S) {
    let count = |euclidean| evaluations_per_query(&counting(make(), euclidean), 20_000);
    let (kd, vp) = (count(true), count(false));
    println!("nearest among 20000 {what} states: k-d {kd}, vantage points {vp} distance evaluations");
    assert!(kd * 2 < vp, "k-d {kd}, vantage points {vp}");
}

#[test]
fn k_d_trees_on_the_euclidean_bound_prune_better_for_a_mobile_manipulator() {
    // The SE(2) base and a four-joint arm (one continuous): no Euclidean metric, but one
    // bounded by a Euclidean metric with stretch 2.
    prunes_better_with_k_d_trees("base + arm", || base_and_arm(0.5, 1.0));
}

#[test]
fn queries_are_not_a_linear_scan() {
    let space = counting(
        JointSpace::new(&[0.0, 0.0, 0.0], &[1.0, 1.0, 0.0], &[false, false, true]).unwrap(),
        false,
    );
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    let mut nn = NearestNeighbors::new(3);
    let mut q = [0.0; 3];
    let n = 20_000;
    for _ in 0..n {
        space.sample(&mut rng, &mut q);
        nn.insert(&q);
        nn.nearest(&space, &q); // interleaved queries, as in a tree planner
    }
    let before = space.calls.load(std::sync::atomic::Ordering::Relaxed);
    let queries = 100;
    for _ in 0..queries {
        space.sample(&mut rng, &mut q);
        nn.nearest(&space, &q);
    }
    let per_query = (space.calls.load(std::sync::atomic::Ordering::Relaxed) - before) / queries;
    assert!(
        per_query < n / 20,
        "{per_query} distance evaluations per query among {n} states"
    );
    println!("{per_query} distance evaluations per nearest query among {n} states");
}

/// Interleaved inserts and queries, as in a tree planner, so that trees are merged many times
/// (the logarithmic method rebuilds at query time); clustered states, as a planner's are.
/// Every 25th query is compared with a brute-force scan.
fn interleaved_agrees_with_brute_force<S: Space>(space: &S, n: usize) {
    let dim = space.dim();
    let mut nn = NearestNeighbors::new(dim);
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let (mut q, mut near) = (vec![0.0; dim], vec![0.0; dim]);
    let mut states: Vec<Vec<f64>> = Vec::new();
    for i in 0..n {
        space.sample(&mut rng, &mut q);
        if i % 3 == 0 && !states.is_empty() {
            // A state near an earlier one.
            let t: f64 = rand::RngExt::random(&mut rng);
            near.copy_from_slice(&q);
            space.interpolate(&states[i % states.len()], &near, 0.05 * t, &mut q);
        }
        let found = nn.k_nearest(space, &q, 11);
        if i % 25 == 0 {
            let mut scan: Vec<(f64, usize)> = states
                .iter()
                .enumerate()
                .map(|(j, p)| (space.distance(&q, p), j))
                .collect();
            scan.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let expected: Vec<usize> = scan.iter().take(11).map(|e| e.1).collect();
            assert_eq!(found, expected, "query {i}");
        }
        assert_eq!(nn.insert(&q), i);
        states.push(q.clone());
    }
    assert_eq!(nn.len(), n);
}

#[test]
fn no_state_is_lost_when_trees_merge() {
    // k-d trees on the torus (wrapping joints), k-d trees (bounded joints only) and
    // vantage-point trees (SE(2), whose yaw adds to the planar distance).
    // 9,000 states: a tree of 8,192, which a k-nearest query descends, beside smaller ones
    // that it scans.
    interleaved_agrees_with_brute_force(&joint_space(), 9_000);
    let bounded = JointSpace::new(&[0.0; 7], &[1.0; 7], &[false; 7]).unwrap();
    assert!(bounded.euclidean_weights().is_some());
    interleaved_agrees_with_brute_force(&bounded, 9_000);
    interleaved_agrees_with_brute_force(&se2_space(), 3_000);
}

#[test]
fn buffered_states_are_filtered_in_lanes_and_removed_ones_skipped() {
    // 31 states stay in the linear buffer (it is indexed by a tree at 32).
    let space = counting(
        JointSpace::new(&[-1.0, -1.0], &[1.0, 1.0], &[false, false]).unwrap(),
        true,
    );
    let mut nn = NearestNeighbors::new(2);
    let mut rng = Pcg64Mcg::seed_from_u64(4);
    let mut states = Vec::new();
    for _ in 0..31 {
        let mut s = [0.0; 2];
        space.sample(&mut rng, &mut s);
        nn.insert(&s);
        states.push(s);
    }
    let q = [0.05, -0.3];
    let mut order: Vec<usize> = (0..31).collect();
    order.sort_by(|&a, &b| {
        space
            .distance(&q, &states[a])
            .total_cmp(&space.distance(&q, &states[b]))
    });
    let before = space.calls.load(std::sync::atomic::Ordering::Relaxed);
    assert_eq!(nn.nearest(&space, &q), Some(order[0]));
    let evaluations = space.calls.load(std::sync::atomic::Ordering::Relaxed) - before;
    // The f32 lanes pass a few states to the exact distance, not all 31.
    assert!(
        evaluations < 8,
        "{evaluations} distance evaluations among 31 buffered states"
    );
    // The nearest state's lane holds the smallest sum; removed, it must not hide the next.
    nn.remove(order[0]);
    assert_eq!(nn.nearest(&space, &q), Some(order[1]));
    nn.remove(order[1]);
    assert_eq!(nn.k_nearest(&space, &q, 3), order[2..5].to_vec());
}
