//! [`BallBatch`]: up to 64 balls asked about in one call ([`Obstacles::balls_touching`]).

use parry3d::math::{Real, Vector};
use wide::f32x8;

#[cfg(doc)]
use super::Obstacles;

/// Up to [`BallBatch::CAPACITY`] balls as structure-of-arrays, so an implementation of
/// [`Obstacles::balls_touching`] can test several at once against each obstacle (the state
/// check's broad phase asks about every link's bounding ball, then about the balls covering
/// one link).
///
/// ```
/// use hearth_planning::obstacles::{BallBatch, Obstacle, Obstacles, ParryScene};
/// use parry3d::math::{Pose, Vector};
///
/// let scene = ParryScene::new(vec![Obstacle::cuboid("box", Pose::IDENTITY, Vector::splat(0.5))]);
/// let mut balls = BallBatch::new();
/// assert!(balls.push(Vector::new(0.0, 0.0, 2.0), 0.1)); // clear
/// assert!(balls.push(Vector::new(0.55, 0.0, 0.0), 0.1)); // touches the box
/// assert_eq!(scene.balls_touching(&balls), 0b10);
/// ```
#[derive(Clone, Debug)]
pub struct BallBatch {
    pub(crate) x: [Real; Self::CAPACITY],
    pub(crate) y: [Real; Self::CAPACITY],
    pub(crate) z: [Real; Self::CAPACITY],
    pub(crate) r: [Real; Self::CAPACITY],
    len: usize,
}

impl Default for BallBatch {
    fn default() -> Self {
        Self::new()
    }
}

impl BallBatch {
    /// Most balls one batch holds (one bit each in the answer).
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// for _ in 0..BallBatch::CAPACITY {
    ///     assert!(balls.push(Vector::ZERO, 0.1));
    /// }
    /// assert!(!balls.push(Vector::ZERO, 0.1));
    /// assert_eq!(balls.mask(), u64::MAX);
    /// ```
    pub const CAPACITY: usize = 64;

    /// An empty batch (the same as [`BallBatch::default`]).
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    ///
    /// let balls = BallBatch::new();
    /// assert!(balls.is_empty());
    /// assert_eq!(balls.mask(), 0);
    /// ```
    pub fn new() -> Self {
        Self {
            x: [0.0; Self::CAPACITY],
            y: [0.0; Self::CAPACITY],
            z: [0.0; Self::CAPACITY],
            r: [-1.0; Self::CAPACITY],
            len: 0,
        }
    }

    /// Empties the batch, so that it can be filled again without allocating.
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// balls.push(Vector::ZERO, 0.1);
    /// balls.clear();
    /// assert!(balls.is_empty());
    /// ```
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Adds a ball as ball number [`BallBatch::len`]; `false` (and nothing added) when the batch
    /// is full.
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// assert!(balls.push(Vector::new(1.0, 2.0, 3.0), 0.5));
    /// assert_eq!(balls.ball(0), (Vector::new(1.0, 2.0, 3.0), 0.5));
    /// ```
    pub fn push(&mut self, center: Vector, radius: Real) -> bool {
        if self.len == Self::CAPACITY {
            return false;
        }
        let i = self.len;
        (self.x[i], self.y[i], self.z[i], self.r[i]) = (center.x, center.y, center.z, radius);
        self.len += 1;
        true
    }

    /// Appends balls given in a local frame (`local`: x, y, z and radius, one slice each, of
    /// equal lengths), placed by the rigid transform `rotation` (row-major) and `translation`:
    /// one pass over the slices, which the compiler vectorises. `false`, with nothing
    /// appended, when they do not fit or the slices' lengths differ.
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// let quarter_turn_z = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    /// let local = [&[1.0, 0.0][..], &[0.0, 2.0][..], &[0.0, 0.0][..], &[0.1, 0.2][..]];
    /// assert!(balls.push_placed(&quarter_turn_z, [0.0, 0.0, 5.0], local));
    /// assert_eq!(balls.ball(0), (Vector::new(0.0, 1.0, 5.0), 0.1));
    /// assert_eq!(balls.ball(1), (Vector::new(-2.0, 0.0, 5.0), 0.2));
    /// ```
    pub fn push_placed(&mut self, rotation: &[[Real; 3]; 3], translation: [Real; 3], local: [&[Real]; 4]) -> bool {
        let [xs, ys, zs, rs] = local;
        let (at, n) = (self.len, xs.len());
        if at + n > Self::CAPACITY || ys.len() != n || zs.len() != n || rs.len() != n {
            return false;
        }
        let [r0, r1, r2] = rotation;
        let [tx, ty, tz] = translation;
        let (x, y, z) = (
            &mut self.x[at..at + n],
            &mut self.y[at..at + n],
            &mut self.z[at..at + n],
        );
        for j in 0..n {
            let (px, py, pz) = (xs[j], ys[j], zs[j]);
            x[j] = r0[0] * px + r0[1] * py + r0[2] * pz + tx;
            y[j] = r1[0] * px + r1[1] * py + r1[2] * pz + ty;
            z[j] = r2[0] * px + r2[1] * py + r2[2] * pz + tz;
        }
        self.r[at..at + n].copy_from_slice(rs);
        self.len += n;
        true
    }

    /// The balls grown by `margin`: which are not finite (bit per ball: a centre coordinate
    /// or the grown radius is infinite or NaN), and the box around the others (lower and upper
    /// corner; inverted, `Real::MAX` above `Real::MIN`, when there is none). Eight balls per
    /// step; the same bits as ball-by-ball `min` and `max`.
    pub(crate) fn bounds(&self, margin: Real) -> (u64, Vector, Vector) {
        const LANES: usize = 8;
        let iota = f32x8::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        let (low, high) = (f32x8::splat(Real::MAX), f32x8::splat(Real::MIN));
        let mut lo = [low; 3];
        let mut hi = [high; 3];
        let mut bad = 0u64;
        let lanes =
            |v: &[Real; Self::CAPACITY], at: usize| f32x8::new(v[at..at + LANES].try_into().expect("eight lanes"));
        for step in 0..self.len.div_ceil(LANES) {
            let at = step * LANES;
            let held = iota.simd_lt(f32x8::splat((self.len - at) as f32));
            let r = lanes(&self.r, at) + f32x8::splat(margin);
            let c = [lanes(&self.x, at), lanes(&self.y, at), lanes(&self.z, at)];
            let finite = c[0].is_finite() & c[1].is_finite() & c[2].is_finite() & r.is_finite();
            bad |= u64::from((held & !finite).to_bitmask()) << at;
            let counted = held & finite;
            for k in 0..3 {
                lo[k] = lo[k].fast_min(counted.select(c[k] - r, low));
                hi[k] = hi[k].fast_max(counted.select(c[k] + r, high));
            }
        }
        let fold = |v: f32x8, start: Real, f: fn(Real, Real) -> Real| v.to_array().into_iter().fold(start, f);
        let least = |k: usize| fold(lo[k], Real::MAX, Real::min);
        let most = |k: usize| fold(hi[k], Real::MIN, Real::max);
        (
            bad,
            Vector::new(least(0), least(1), least(2)),
            Vector::new(most(0), most(1), most(2)),
        )
    }

    /// How many balls the batch holds.
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// balls.push(Vector::ZERO, 0.1);
    /// balls.push(Vector::X, 0.1);
    /// assert_eq!(balls.len(), 2);
    /// ```
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the batch holds no ball.
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// assert!(balls.is_empty());
    /// balls.push(Vector::ZERO, 0.1);
    /// assert!(!balls.is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Centre and radius of ball `i` (`i < len`; slots past `len` hold stale values, and `i` ≥
    /// [`BallBatch::CAPACITY`] panics).
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// balls.push(Vector::ZERO, 0.1);
    /// balls.push(Vector::new(0.0, 0.0, 1.0), 0.2);
    /// assert_eq!(balls.ball(1), (Vector::new(0.0, 0.0, 1.0), 0.2));
    /// ```
    pub fn ball(&self, i: usize) -> (Vector, Real) {
        (Vector::new(self.x[i], self.y[i], self.z[i]), self.r[i])
    }

    /// A mask with one bit per ball held: bits `0..len` set, the others clear.
    ///
    /// ```
    /// use hearth_planning::obstacles::BallBatch;
    /// use parry3d::math::Vector;
    ///
    /// let mut balls = BallBatch::new();
    /// for _ in 0..3 {
    ///     balls.push(Vector::ZERO, 0.1);
    /// }
    /// assert_eq!(balls.mask(), 0b111);
    /// ```
    pub fn mask(&self) -> u64 {
        if self.len == Self::CAPACITY {
            u64::MAX
        } else {
            (1u64 << self.len) - 1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    /// Eight-lane bounds give the bits of a ball-by-ball pass over the finite balls, and mark
    /// exactly the balls that are not finite.
    #[test]
    fn bounds_match_ball_by_ball_min_and_max() {
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let odd = [Real::NAN, Real::INFINITY, Real::NEG_INFINITY];
        for round in 0..2000 {
            let mut balls = BallBatch::new();
            // Stale lanes past the end must not count: fill, clear, refill fewer.
            for _ in 0..BallBatch::CAPACITY {
                balls.push(Vector::splat(-1e6), 1e6);
            }
            balls.clear();
            let n = rng.random_range(0..=BallBatch::CAPACITY);
            for _ in 0..n {
                let mut v: [Real; 4] = [0.0; 4];
                for x in &mut v {
                    *x = rng.random_range(-3.0..3.0);
                    if rng.random_bool(0.01) {
                        *x = odd[rng.random_range(0..3)];
                    }
                }
                balls.push(Vector::new(v[0], v[1], v[2]), v[3].abs());
            }
            let margin = if round % 2 == 0 { 0.0 } else { 0.01 };
            let (mut bad, mut lo, mut hi) = (0u64, Vector::splat(Real::MAX), Vector::splat(Real::MIN));
            for j in 0..n {
                let (c, r) = balls.ball(j);
                let r = r + margin;
                if !(c.is_finite() && r.is_finite()) {
                    bad |= 1 << j;
                    continue;
                }
                lo = lo.min(c - Vector::splat(r));
                hi = hi.max(c + Vector::splat(r));
            }
            let (b, l, h) = balls.bounds(margin);
            assert_eq!(b, bad, "round {round}");
            assert_eq!(
                l.to_array().map(Real::to_bits),
                lo.to_array().map(Real::to_bits),
                "round {round}"
            );
            assert_eq!(
                h.to_array().map(Real::to_bits),
                hi.to_array().map(Real::to_bits),
                "round {round}"
            );
        }
    }
}
