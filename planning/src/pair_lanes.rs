//! The bounding-ball test of every self-collision pair that moves with the chain, eight pairs
//! per `f32x8` step.
//!
//! Every state check asks, for each such pair (70 on the Fetch), whether the two links'
//! bounding balls meet, before any finer test. One pair at a time that costs about twenty
//! instructions (two indexed centres, their distance, a branch). Here each pair is a lane: the
//! pairs are grouped by one of their links (the *row*: chosen greedily so that few steps hold
//! them all, 16 for the Fetch's 70), the other links' centres sit in f32 lanes, and one step
//! measures a row's centre against eight of them. The f32 test is a filter widened well past
//! its rounding; the caller confirms each passing pair with the exact f64 test, so the answers
//! are those of the pair-by-pair loop.

use nalgebra::Point3;
use wide::f32x8;

/// Lanes per step.
const LANES: usize = 8;

/// Margin (m) added to each pair's reach in the f32 filter: far more than f32 rounding can
/// move a distance between two centres given relative to one of them (~1e-7 m for a robot
/// a few metres across).
const WIDEN: f64 = 1e-4;

/// One step: a row link's centre against eight column links.
#[derive(Clone, Copy, Debug)]
struct Task {
    /// Lane slot of the row link.
    row: u32,
    /// First lane slot of the eight column links.
    block: u32,
    /// Per lane: the widened squared reach (−1 where no pair: a squared distance never
    /// passes it).
    reach2: [f32; LANES],
    /// Per lane: the pair's entry in the caller's list (`u32::MAX` where none).
    entry: [u32; LANES],
}

/// The pairs' links as lane slots, their centres in f32 lanes, and the steps over them.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairLanes {
    /// The link in each slot.
    links: Vec<u32>,
    /// Centres of `links` relative to the first one's, x, y and z rows padded with NaN to
    /// whole steps (refreshed by [`PairLanes::refresh`]).
    centers: [Vec<f32>; 3],
    tasks: Vec<Task>,
}

impl PairLanes {
    /// Lanes for `pairs` (link, link, squared reach): entry `k` of `pairs` is reported as `k`.
    pub(crate) fn new(pairs: &[(u32, u32, f64)]) -> Self {
        let mut links: Vec<u32> = pairs.iter().flat_map(|&(a, b, _)| [a, b]).collect();
        links.sort_unstable();
        links.dedup();
        let slot = |l: u32| links.binary_search(&l).expect("every pair link has a slot") as u32;
        let block_of = |l: u32| slot(l) / LANES as u32 * LANES as u32;
        // Each pair is a lane of a step (row, block) in one of two ways: its first link as the
        // row and the other in the block, or the other way round. Greedy cover: the step that
        // takes the most pairs not yet placed, until all are (ties: the lowest step).
        let mut placed = vec![false; pairs.len()];
        let mut tasks = Vec::new();
        let mut left = pairs.len();
        while left > 0 {
            let mut count = std::collections::BTreeMap::<(u32, u32), usize>::new();
            for (k, &(a, b, _)) in pairs.iter().enumerate() {
                if !placed[k] {
                    *count.entry((a, block_of(b))).or_default() += 1;
                    *count.entry((b, block_of(a))).or_default() += 1;
                }
            }
            let (&(row, block), _) = count
                .iter()
                .max_by_key(|&(&key, &n)| (n, std::cmp::Reverse(key)))
                .expect("a pair is left");
            let mut task = Task {
                row: slot(row),
                block,
                reach2: [-1.0; LANES],
                entry: [u32::MAX; LANES],
            };
            for (k, &(a, b, reach2)) in pairs.iter().enumerate() {
                let col = match () {
                    _ if placed[k] => continue,
                    _ if a == row && block_of(b) == block => b,
                    _ if b == row && block_of(a) == block => a,
                    _ => continue,
                };
                let lane = (slot(col) - block) as usize;
                if task.entry[lane] != u32::MAX {
                    continue; // the same two links listed twice: the next step takes it
                }
                let widened = (reach2.sqrt() + WIDEN).powi(2) * (1.0 + 1e-5);
                task.reach2[lane] = if widened < f64::from(f32::MAX) {
                    widened as f32
                } else {
                    f32::INFINITY
                };
                task.entry[lane] = k as u32;
                placed[k] = true;
                left -= 1;
            }
            tasks.push(task);
        }
        let padded = links.len().div_ceil(LANES) * LANES;
        Self {
            centers: std::array::from_fn(|_| vec![f32::NAN; padded]),
            links,
            tasks,
        }
    }

    /// Copies the links' centres (indexed by link) into the lanes.
    #[inline]
    pub(crate) fn refresh(&mut self, world_center: &[Point3<f64>]) {
        let Some(&first) = self.links.first() else {
            return;
        };
        let origin = world_center[first as usize];
        let [xs, ys, zs] = &mut self.centers;
        for (k, &l) in self.links.iter().enumerate() {
            let d = world_center[l as usize] - origin;
            xs[k] = d.x as f32;
            ys[k] = d.y as f32;
            zs[k] = d.z as f32;
        }
    }

    /// Number of steps.
    #[inline]
    pub(crate) fn steps(&self) -> usize {
        self.tasks.len()
    }

    /// Step `t`: bit `lane` set where that lane's pair may be within reach (after
    /// [`PairLanes::refresh`]).
    #[inline]
    pub(crate) fn step(&self, t: usize) -> u32 {
        let task = &self.tasks[t];
        let [xs, ys, zs] = &self.centers;
        let (r, j) = (task.row as usize, task.block as usize);
        let lanes = |v: &[f32]| f32x8::new(v[j..j + LANES].try_into().expect("whole steps"));
        let dx = lanes(xs) - f32x8::splat(xs[r]);
        let dy = lanes(ys) - f32x8::splat(ys[r]);
        let dz = lanes(zs) - f32x8::splat(zs[r]);
        let d2 = dx * dx + dy * dy + dz * dz;
        d2.simd_le(f32x8::new(task.reach2)).to_bitmask()
    }

    /// The caller's entry for lane `lane` of step `t` (a lane that [`PairLanes::step`]
    /// reported).
    #[inline]
    pub(crate) fn entry(&self, t: usize, lane: usize) -> usize {
        self.tasks[t].entry[lane] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    /// The lanes report every pair within reach, each once, and nothing else that is not
    /// within the widened reach.
    #[test]
    fn lanes_agree_with_pair_by_pair_tests() {
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        for _ in 0..200 {
            let n = rng.random_range(2..30usize);
            let mut pairs = Vec::new();
            for a in 0..n as u32 {
                for b in a + 1..n as u32 {
                    if rng.random_bool(0.4) {
                        let r: f64 = rng.random_range(0.0..0.6);
                        pairs.push((a * 3, b * 3 + 1, r * r));
                        if rng.random_bool(0.05) {
                            pairs.push((b * 3 + 1, a * 3, r * r)); // listed twice
                        }
                    }
                }
            }
            let centers: Vec<Point3<f64>> = (0..3 * n + 2)
                .map(|_| {
                    Point3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(0.0..2.0),
                    )
                })
                .collect();
            let mut lanes = PairLanes::new(&pairs);
            lanes.refresh(&centers);
            let mut seen = vec![0; pairs.len()];
            for t in 0..lanes.steps() {
                let mut m = lanes.step(t);
                while m != 0 {
                    let lane = m.trailing_zeros() as usize;
                    m &= m - 1;
                    seen[lanes.entry(t, lane)] += 1;
                }
            }
            for (k, &(a, b, reach2)) in pairs.iter().enumerate() {
                let d2 = (centers[a as usize] - centers[b as usize]).norm_squared();
                assert!(seen[k] <= 1, "pair {k} reported {} times", seen[k]);
                if d2 <= reach2 {
                    assert_eq!(seen[k], 1, "pair {k} within reach but not reported");
                } else if seen[k] == 1 {
                    assert!(
                        d2.sqrt() <= reach2.sqrt() + 2.0 * WIDEN,
                        "pair {k} reported far out of reach"
                    );
                }
            }
        }
    }

    /// A pair exactly at its reach (the boundary the f64 test accepts) is reported.
    #[test]
    fn touching_balls_are_reported() {
        let pairs = [(0, 1, 0.25)];
        let mut lanes = PairLanes::new(&pairs);
        lanes.refresh(&[Point3::new(10.0, 0.0, 0.0), Point3::new(10.5, 0.0, 0.0)]);
        assert_eq!((lanes.steps(), lanes.step(0).count_ones()), (1, 1));
        lanes.refresh(&[Point3::new(10.0, 0.0, 0.0), Point3::new(10.6, 0.0, 0.0)]);
        assert_eq!(lanes.step(0), 0);
    }
}
