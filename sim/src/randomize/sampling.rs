//! Seeded random streams and the few distributions randomisation draws from.
//!
//! Every draw comes from a [`Pcg64Mcg`] stream whose seed mixes the run seed, the draw epoch,
//! the kind of randomisation and a key (an object name, a material part): a draw depends only
//! on these, not on what else is randomised or in which order things are visited.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// The kinds of randomisation, each with its own streams.
///
/// ```
/// use hearth_sim::randomize::Stream;
/// assert_ne!(Stream::Objects as u64, Stream::Physics as u64);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stream {
    /// Object model swaps.
    Objects = 1,
    /// Visual materials.
    Visual = 2,
    /// Physical properties.
    Physics = 3,
    /// Robot start pose.
    RobotPose = 4,
    /// Camera mount offset.
    CameraPose = 5,
    /// Sensor noise (depth images, LiDAR seeds).
    Noise = 6,
}

/// SplitMix64 finaliser: a bijective 64-bit mixer, for deriving unrelated seeds from
/// related numbers (a run seed and an index).
///
/// ```
/// use hearth_sim::randomize::mix;
/// assert_ne!(mix(0), mix(1));
/// assert_ne!(mix(mix(0) ^ 1), mix(mix(1) ^ 0));
/// ```
pub fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// FNV-1a of a string.
pub(crate) fn hash_str(s: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in s.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The stream of `kind` for `key` in draw `epoch` of the run seeded `seed`.
///
/// ```
/// use hearth_sim::randomize::{Stream, stream};
/// use rand::RngExt;
/// let a: f64 = stream(7, 0, Stream::Objects, "chair_1").random();
/// let b: f64 = stream(7, 0, Stream::Objects, "chair_1").random();
/// let c: f64 = stream(7, 1, Stream::Objects, "chair_1").random();
/// assert_eq!(a, b);
/// assert_ne!(a, c);
/// ```
pub fn stream(seed: u64, epoch: u64, kind: Stream, key: &str) -> Pcg64Mcg {
    let s = mix(mix(mix(seed) ^ epoch) ^ (kind as u64)) ^ hash_str(key);
    Pcg64Mcg::seed_from_u64(mix(s))
}

/// A standard normal sample (Box–Muller, one of the pair).
pub(crate) fn standard_normal(rng: &mut Pcg64Mcg) -> f64 {
    // 1 − u lies in (0, 1], so the logarithm is finite.
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Uniform in `[lo, hi]` (exactly `lo` when the span is empty).
pub(crate) fn uniform(rng: &mut Pcg64Mcg, [lo, hi]: [f64; 2]) -> f64 {
    let u: f64 = rng.random();
    if hi > lo { lo + (hi - lo) * u } else { lo }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_samples_have_unit_variance() {
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| standard_normal(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
    }

    #[test]
    fn uniform_stays_in_range() {
        let mut rng = Pcg64Mcg::seed_from_u64(2);
        for _ in 0..1000 {
            let x = uniform(&mut rng, [0.3, 0.5]);
            assert!((0.3..=0.5).contains(&x));
        }
        assert_eq!(uniform(&mut rng, [0.4, 0.4]), 0.4);
    }
}
