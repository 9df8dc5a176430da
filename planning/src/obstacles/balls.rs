//! [`BallBatch`]: up to 64 balls asked about in one call ([`Obstacles::balls_touching`]).

use parry3d::math::{Real, Vector};

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
    pub const CAPACITY: usize = 64;

    /// An empty batch.
    pub fn new() -> Self {
        Self {
            x: [0.0; Self::CAPACITY],
            y: [0.0; Self::CAPACITY],
            z: [0.0; Self::CAPACITY],
            r: [-1.0; Self::CAPACITY],
            len: 0,
        }
    }

    /// Empties the batch.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Adds a ball; `false` (and nothing added) when the batch is full.
    pub fn push(&mut self, center: Vector, radius: Real) -> bool {
        if self.len == Self::CAPACITY {
            return false;
        }
        let i = self.len;
        (self.x[i], self.y[i], self.z[i], self.r[i]) = (center.x, center.y, center.z, radius);
        self.len += 1;
        true
    }

    /// How many balls the batch holds.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the batch holds no ball.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Centre and radius of ball `i` (`i < len`).
    pub fn ball(&self, i: usize) -> (Vector, Real) {
        (Vector::new(self.x[i], self.y[i], self.z[i]), self.r[i])
    }

    /// A mask with one bit per ball held.
    pub fn mask(&self) -> u64 {
        if self.len == Self::CAPACITY {
            u64::MAX
        } else {
            (1u64 << self.len) - 1
        }
    }
}
