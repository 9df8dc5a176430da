//! Collision queries against the environment: the [`Obstacles`] seam and its static
//! implementation [`ParryScene`].
//!
//! Every planner asks the environment the same few questions through [`Obstacles`]: "does this
//! shape at this pose touch anything?", "how far is it from the nearest obstacle?", "where does
//! this ray hit first?". Two implementations exist: [`ParryScene`] (static named obstacles in a
//! parry BVH, built once — benchmark problems) and, in `hearth-sim`, the live rapier world.
//!
//! Poses at this seam are parry's `f32` [`Pose`]; convert kinematics poses with
//! [`hearth_kinematics::to_pose`].
//!
//! ```
//! use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
//! use parry3d::math::{Pose, Vector};
//! use parry3d::shape::Ball;
//!
//! let scene = ParryScene::new(vec![Obstacle::cuboid(
//!     "table",
//!     Pose::translation(0.5, 0.0, 0.2),
//!     Vector::new(0.3, 0.5, 0.02),
//! )]);
//! let probe = Ball::new(0.05);
//! assert!(scene.intersects(&probe, &Pose::translation(0.5, 0.0, 0.25)));
//! assert!(!scene.intersects(&probe, &Pose::translation(0.5, 0.0, 0.4)));
//! let (d, id) = scene.distance(&probe, &Pose::translation(0.5, 0.0, 0.4), 1.0).unwrap();
//! assert!((d - 0.13).abs() < 1e-5);
//! assert_eq!(scene.name(id), Some("table"));
//! ```

mod balls;
mod scene;

use std::fmt;

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Real, Rotation, Vector};
use parry3d::shape::{Shape, SharedShape, TriMeshBuilderError};

pub use balls::BallBatch;
pub use scene::ParryScene;

/// The nearest leaf of `bvh` to the box `query` within `max_dist`, for implementations of
/// [`Obstacles::distance`] over a parry [`Bvh`](parry3d::partitioning::Bvh): subtrees whose
/// boxes are farther than the best distance so far are pruned, and `distance(leaf)` gives a
/// leaf's exact distance (`None` skips the leaf, e.g. an excluded collider). Ties keep the
/// first leaf found; a distance of 0 ends the search.
///
/// ```
/// use hearth_planning::obstacles::nearest_leaf;
/// use parry3d::bounding_volume::Aabb;
/// use parry3d::math::Vector;
/// use parry3d::partitioning::{Bvh, BvhBuildStrategy};
///
/// let boxes = [Aabb::new(Vector::ZERO, Vector::ONE), Aabb::new(Vector::splat(3.0), Vector::splat(4.0))];
/// let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
/// let query = Aabb::new(Vector::splat(2.0), Vector::splat(2.5));
/// // Leaf distances here are just box gaps; leaf 0 is skipped.
/// let gap = |i: u32| boxes[i as usize].mins.x - 2.5;
/// assert_eq!(nearest_leaf(&bvh, &query, 10.0, |i| Some(gap(i).abs())).map(|(_, id)| id.0), Some(1));
/// assert_eq!(nearest_leaf(&bvh, &query, 10.0, |i| (i == 1).then(|| gap(i))).map(|(d, _)| d), Some(0.5));
/// assert_eq!(nearest_leaf(&bvh, &query, 0.1, |i| Some(gap(i).abs())), None);
/// ```
pub fn nearest_leaf(
    bvh: &parry3d::partitioning::Bvh,
    query: &Aabb,
    max_dist: Real,
    mut distance: impl FnMut(u32) -> Option<Real>,
) -> Option<(Real, ObstacleId)> {
    use parry3d::partitioning::{BvhNode, TraversalAction};
    if max_dist.is_nan() || max_dist < 0.0 {
        return None;
    }
    let mut best = max_dist;
    let mut best_id: Option<u32> = None;
    bvh.traverse(|node: &BvhNode| {
        let gap = aabb_gap(&node.aabb(), query);
        if gap > best || (best_id.is_some() && gap >= best) {
            return TraversalAction::Prune;
        }
        if let Some(leaf) = node.leaf_data()
            && let Some(d) = distance(leaf)
            && (d < best || (best_id.is_none() && d <= best))
        {
            best = d;
            best_id = Some(leaf);
            if d <= 0.0 {
                return TraversalAction::EarlyExit;
            }
        }
        TraversalAction::Continue
    });
    best_id.map(|i| (best, ObstacleId(i)))
}

/// Euclidean gap between two boxes (0 when they overlap): a lower bound on the distance between
/// anything inside them.
#[inline]
fn aabb_gap(a: &Aabb, b: &Aabb) -> Real {
    (a.mins - b.maxs).max(b.mins - a.maxs).max(Vector::ZERO).length()
}

/// Index of an obstacle in an [`Obstacles`] implementation (for [`ParryScene`]: its position in
/// [`ParryScene::obstacles`]).
///
/// ```
/// use hearth_planning::obstacles::ObstacleId;
/// assert_eq!(ObstacleId(3).index(), 3);
/// assert_eq!(ObstacleId(3).to_string(), "#3");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObstacleId(pub u32);

impl ObstacleId {
    /// The id as a `usize` index.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for ObstacleId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// The environment as planners see it: collision, distance and ray queries against everything
/// that is not the robot.
///
/// Small and object-safe so that `&dyn Obstacles` / `Arc<dyn Obstacles>` can be shared between
/// planner threads. Implementations must not allocate per query.
///
/// An implementation may apply its own safety margin to [`Obstacles::intersects`] /
/// [`Obstacles::first_hit`] (see [`ParryScene::with_margin`]); [`Obstacles::distance`] and
/// [`Obstacles::cast_ray`] are always exact geometry.
pub trait Obstacles: Send + Sync {
    /// The first obstacle found that `shape` placed at `pose` touches (or comes within the
    /// implementation's margin of), or `None` if it is collision-free. Which obstacle is
    /// reported when several are touched is unspecified; use it for error messages.
    fn first_hit(&self, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleId>;

    /// Does `shape` placed at `pose` touch anything? Equivalent to `first_hit(..).is_some()`.
    fn intersects(&self, shape: &dyn Shape, pose: &Pose) -> bool {
        self.first_hit(shape, pose).is_some()
    }

    /// Does a ball of `radius` at `center` touch anything (within the margin)? The broad phase
    /// of every state check asks this many times; implementations may answer it faster than
    /// [`Obstacles::intersects`] with a [`Ball`](parry3d::shape::Ball), and must give the same
    /// answer.
    fn ball_hits(&self, center: Vector, radius: Real) -> bool {
        self.intersects(&parry3d::shape::Ball::new(radius), &Pose::from_translation(center))
    }

    /// Which balls of `balls` touch anything (within the margin): bit `i` of the answer is
    /// [`Obstacles::ball_hits`] for ball `i`. Implementations may test the balls together
    /// (the default asks about them one by one) and must give the same answer.
    fn balls_touching(&self, balls: &BallBatch) -> u64 {
        balls_one_by_one(self, balls)
    }

    /// The smallest distance from `shape` at `pose` to any obstacle, and which obstacle, if it
    /// is at most `max_dist` (0 when touching or penetrating). `None` when nothing lies within
    /// `max_dist`.
    fn distance(&self, shape: &dyn Shape, pose: &Pose, max_dist: Real) -> Option<(Real, ObstacleId)>;

    /// Casts the ray `origin + t·dir`, `0 ≤ t ≤ max_toi`, and returns the smallest `t` at which
    /// it hits an obstacle (in units of `|dir|`; 0 if `origin` is inside one) and which one.
    fn cast_ray(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<(Real, ObstacleId)>;

    /// World-space bounds of all obstacles, `None` when there are none.
    fn aabb(&self) -> Option<Aabb>;

    /// The obstacle's name, for messages; `None` for an unknown id.
    fn name(&self, id: ObstacleId) -> Option<&str>;
}

/// [`Obstacles::balls_touching`] answered through [`Obstacles::ball_hits`], one ball at a time.
pub(crate) fn balls_one_by_one<O: Obstacles + ?Sized>(obstacles: &O, balls: &BallBatch) -> u64 {
    let mut hit = 0;
    for i in 0..balls.len() {
        let (c, r) = balls.ball(i);
        hit |= u64::from(obstacles.ball_hits(c, r)) << i;
    }
    hit
}

/// One named static obstacle: a parry shape at a world pose.
///
/// The constructors follow the benchmark conventions (boxes by half-extents, cylinders along
/// their **local z axis**).
///
/// ```
/// use hearth_planning::obstacles::Obstacle;
/// use parry3d::math::{Pose, Vector};
/// let can = Obstacle::cylinder("can", Pose::translation(0.0, 0.0, 0.1), 0.1, 0.03);
/// let aabb = can.aabb();
/// assert!((aabb.maxs.z - 0.2).abs() < 1e-6 && (aabb.maxs.x - 0.03).abs() < 1e-6);
/// ```
#[derive(Clone, Debug)]
pub struct Obstacle {
    /// Name used in messages (e.g. the MotionBenchMaker collision-object id).
    pub name: String,
    /// The geometry, in its own frame.
    pub shape: SharedShape,
    /// Pose of `shape`'s frame in the world.
    pub pose: Pose,
}

impl Obstacle {
    /// An obstacle from any parry shape.
    pub fn new(name: impl Into<String>, shape: SharedShape, pose: Pose) -> Self {
        Self {
            name: name.into(),
            shape,
            pose,
        }
    }

    /// A box centred at `pose` with the given half-extents along its local axes.
    pub fn cuboid(name: impl Into<String>, pose: Pose, half_extents: Vector) -> Self {
        Self::new(
            name,
            SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z),
            pose,
        )
    }

    /// A sphere.
    pub fn ball(name: impl Into<String>, center: Vector, radius: Real) -> Self {
        Self::new(name, SharedShape::ball(radius), Pose::from_translation(center))
    }

    /// A flat-capped cylinder centred at `pose` whose axis is `pose`'s **local z axis**, spanning
    /// `±half_length` along it (parry's cylinder axis is y; the rotation is applied here).
    pub fn cylinder(name: impl Into<String>, pose: Pose, half_length: Real, radius: Real) -> Self {
        // R_x(+90°) maps local y (parry's axis) onto local z.
        let y_to_z = Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2);
        Self::new(name, SharedShape::cylinder(half_length, radius), pose * y_to_z)
    }

    /// A capsule (segment `a`–`b` in world coordinates, swept by a ball of `radius`).
    pub fn capsule(name: impl Into<String>, a: Vector, b: Vector, radius: Real) -> Self {
        Self::new(name, SharedShape::capsule(a, b, radius), Pose::IDENTITY)
    }

    /// The convex hull of `points` (given in the obstacle frame) at `pose`; `None` when parry
    /// cannot build it (e.g. no points).
    pub fn convex_hull(name: impl Into<String>, pose: Pose, points: &[Vector]) -> Option<Self> {
        SharedShape::convex_hull(points).map(|s| Self::new(name, s, pose))
    }

    /// A triangle mesh at `pose`. Triangle meshes are **hollow** for intersection tests: a shape
    /// entirely inside a closed mesh does not touch it (use a convex hull or decomposition for
    /// solid obstacles).
    ///
    /// # Errors
    /// parry's [`TriMeshBuilderError`] for an empty or invalid mesh.
    pub fn trimesh(
        name: impl Into<String>,
        pose: Pose,
        vertices: Vec<Vector>,
        indices: Vec<[u32; 3]>,
    ) -> Result<Self, TriMeshBuilderError> {
        Ok(Self::new(name, SharedShape::trimesh(vertices, indices)?, pose))
    }

    /// The obstacle's world-space bounding box.
    pub fn aabb(&self) -> Aabb {
        self.shape.compute_aabb(&self.pose)
    }
}
