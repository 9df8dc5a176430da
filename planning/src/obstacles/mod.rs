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
mod contact;
mod cylinder_box;
mod gjk;
mod scene;

use std::fmt;

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Real, Rotation, Vector};
use parry3d::shape::{Shape, SharedShape, TriMeshBuilderError};

use crate::error::Num;

pub use balls::BallBatch;
pub use contact::shape_contact;
pub use scene::ParryScene;
pub(crate) use scene::shapes_touch;

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
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("a", Vector::ZERO, 0.1), Obstacle::ball("b", Vector::X, 0.1)]);
    /// assert_eq!(scene.obstacles()[ObstacleId(1).index()].name, "b");
    /// ```
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
///
/// An implementation provides five queries; the ball queries have defaults built on
/// [`Obstacles::first_hit`]:
///
/// ```
/// use hearth_planning::obstacles::{ObstacleId, Obstacles};
/// use parry3d::bounding_volume::Aabb;
/// use parry3d::math::{Pose, Real, Vector};
/// use parry3d::shape::Shape;
///
/// // The ground: a slab whose top face is z = 0, wide and deep enough to stand for z ≤ 0.
/// struct Ground;
/// impl Obstacles for Ground {
///     fn first_hit(&self, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleId> {
///         (shape.compute_aabb(pose).mins.z <= 0.0).then_some(ObstacleId(0))
///     }
///     fn distance(&self, shape: &dyn Shape, pose: &Pose, max_dist: Real) -> Option<(Real, ObstacleId)> {
///         let d = shape.compute_aabb(pose).mins.z.max(0.0);
///         (d <= max_dist).then_some((d, ObstacleId(0)))
///     }
///     fn cast_ray(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<(Real, ObstacleId)> {
///         let t = if origin.z <= 0.0 { 0.0 } else { -origin.z / dir.z };
///         (0.0..=max_toi).contains(&t).then_some((t, ObstacleId(0)))
///     }
///     fn aabb(&self) -> Option<Aabb> {
///         Some(Aabb::new(Vector::new(-1e3, -1e3, -1e3), Vector::new(1e3, 1e3, 0.0)))
///     }
///     fn name(&self, id: ObstacleId) -> Option<&str> {
///         (id == ObstacleId(0)).then_some("ground")
///     }
/// }
/// assert!(Ground.ball_hits(Vector::new(0.0, 0.0, 0.05), 0.1));
/// assert!(!Ground.ball_hits(Vector::new(0.0, 0.0, 0.15), 0.1));
/// assert_eq!(Ground.cast_ray(Vector::new(0.0, 0.0, 2.0), -Vector::Z, 10.0), Some((2.0, ObstacleId(0))));
/// ```
pub trait Obstacles: Send + Sync {
    /// The first obstacle found that `shape` placed at `pose` touches (or comes within the
    /// implementation's margin of), or `None` if it is collision-free. Which obstacle is
    /// reported when several are touched is unspecified; use it for error messages.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::Ball;
    ///
    /// let scene = ParryScene::new(vec![
    ///     Obstacle::ball("lamp", Vector::new(0.0, 0.0, 1.0), 0.1),
    ///     Obstacle::cuboid("wall", Pose::translation(1.0, 0.0, 0.5), Vector::new(0.05, 1.0, 0.5)),
    /// ]);
    /// let probe = Ball::new(0.1);
    /// assert_eq!(scene.first_hit(&probe, &Pose::translation(0.9, 0.0, 0.5)), scene.find("wall"));
    /// assert_eq!(scene.first_hit(&probe, &Pose::translation(0.5, 0.0, 0.5)), None);
    /// ```
    fn first_hit(&self, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleId>;

    /// Does `shape` placed at `pose` touch anything? Equivalent to `first_hit(..).is_some()`.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::Cuboid;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("ball", Vector::ZERO, 0.5)]);
    /// let cube = Cuboid::new(Vector::splat(0.1));
    /// assert!(scene.intersects(&cube, &Pose::translation(0.55, 0.0, 0.0)));
    /// assert!(!scene.intersects(&cube, &Pose::translation(0.65, 0.0, 0.0)));
    /// ```
    fn intersects(&self, shape: &dyn Shape, pose: &Pose) -> bool {
        self.first_hit(shape, pose).is_some()
    }

    /// Does a ball of `radius` at `center` touch anything (within the margin)? The broad phase
    /// of every state check asks this many times; implementations may answer it faster than
    /// [`Obstacles::intersects`] with a [`Ball`](parry3d::shape::Ball), and must give the same
    /// answer.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::Ball;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::cuboid("box", Pose::IDENTITY, Vector::splat(0.5))]);
    /// let near = Vector::new(0.0, 0.0, 0.63); // 3 cm of clearance for a 10 cm ball
    /// assert!(!scene.ball_hits(near, 0.1));
    /// assert!(scene.clone().with_margin(0.05).ball_hits(near, 0.1));
    /// assert_eq!(scene.ball_hits(near, 0.1), scene.intersects(&Ball::new(0.1), &Pose::from_translation(near)));
    /// ```
    fn ball_hits(&self, center: Vector, radius: Real) -> bool {
        self.intersects(&parry3d::shape::Ball::new(radius), &Pose::from_translation(center))
    }

    /// Which balls of `balls` touch anything (within the margin): bit `i` of the answer is
    /// [`Obstacles::ball_hits`] for ball `i`. Implementations may test the balls together
    /// (the default asks about them one by one) and must give the same answer.
    ///
    /// ```
    /// use hearth_planning::obstacles::{BallBatch, Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("ball", Vector::ZERO, 0.5)]);
    /// let mut balls = BallBatch::new();
    /// for x in [0.0, 1.0, 0.55, 2.0] {
    ///     balls.push(Vector::new(x, 0.0, 0.0), 0.1);
    /// }
    /// assert_eq!(scene.balls_touching(&balls), 0b0101);
    /// for i in 0..balls.len() {
    ///     let (c, r) = balls.ball(i);
    ///     assert_eq!(scene.balls_touching(&balls) >> i & 1 == 1, scene.ball_hits(c, r));
    /// }
    /// ```
    fn balls_touching(&self, balls: &BallBatch) -> u64 {
        balls_one_by_one(self, balls)
    }

    /// How far each ball of `balls` is from the obstacles: `out[i]` is the distance from ball
    /// `i`'s surface to the nearest obstacle, less the margin (0 or negative when it touches
    /// something), or `max` when that is farther than `max`. A ball grown by less than its
    /// value is then reported clear by [`Obstacles::balls_touching`]. `false` (and `out`
    /// unspecified) when the implementation cannot tell cheaply (the default); callers then
    /// assume no clearance. State checks use it to prove the states near a checked one valid
    /// without checking them ([`StateValidator::first_invalid_along`]).
    ///
    /// [`StateValidator::first_invalid_along`]: crate::validity::StateValidator::first_invalid_along
    ///
    /// ```
    /// use hearth_planning::obstacles::{BallBatch, Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let scene = ParryScene::new(vec![Obstacle::cuboid("box", Pose::IDENTITY, Vector::splat(0.5))]);
    /// let mut balls = BallBatch::new();
    /// balls.push(Vector::new(0.0, 0.0, 1.0), 0.1); // 0.4 m above the box
    /// balls.push(Vector::new(0.8, 0.0, 0.0), 0.1); // 0.2 m beside it
    /// let mut out = [0.0; BallBatch::CAPACITY];
    /// assert!(scene.balls_clearance(&balls, 1.0, &mut out));
    /// assert!((out[0] - 0.4).abs() < 1e-6 && (out[1] - 0.2).abs() < 1e-6);
    /// assert!(scene.balls_clearance(&balls, 0.3, &mut out));
    /// assert_eq!(out[0], 0.3); // capped
    /// assert!(scene.with_margin(0.05).balls_clearance(&balls, 1.0, &mut out));
    /// assert!((out[1] - 0.15).abs() < 1e-6);
    /// ```
    fn balls_clearance(&self, balls: &BallBatch, max: Real, out: &mut [Real; BallBatch::CAPACITY]) -> bool {
        let _ = (balls, max, out);
        false
    }

    /// The smallest distance from `shape` at `pose` to any obstacle, and which obstacle, if it
    /// is at most `max_dist` (0 when touching or penetrating). `None` when nothing lies within
    /// `max_dist`.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::Ball;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("ball", Vector::ZERO, 0.5)]).with_margin(0.1);
    /// let probe = Ball::new(0.1);
    /// let (d, id) = scene.distance(&probe, &Pose::translation(1.0, 0.0, 0.0), 1.0).unwrap();
    /// assert!((d - 0.4).abs() < 1e-6 && id == ObstacleId(0)); // the margin plays no part
    /// assert_eq!(scene.distance(&probe, &Pose::translation(1.0, 0.0, 0.0), 0.3), None);
    /// assert_eq!(scene.distance(&probe, &Pose::IDENTITY, 1.0), Some((0.0, ObstacleId(0))));
    /// ```
    fn distance(&self, shape: &dyn Shape, pose: &Pose, max_dist: Real) -> Option<(Real, ObstacleId)>;

    /// Casts the ray `origin + t·dir`, `0 ≤ t ≤ max_toi`, and returns the smallest `t` at which
    /// it hits an obstacle (in units of `|dir|`; 0 if `origin` is inside one) and which one.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let wall = Obstacle::cuboid("wall", Pose::translation(2.0, 0.0, 0.0), Vector::splat(0.5));
    /// let scene = ParryScene::new(vec![wall]);
    /// let (t, _) = scene.cast_ray(Vector::ZERO, Vector::X, 10.0).unwrap();
    /// assert!((t - 1.5).abs() < 1e-6);
    /// let (t, _) = scene.cast_ray(Vector::ZERO, 2.0 * Vector::X, 10.0).unwrap();
    /// assert!((t - 0.75).abs() < 1e-6); // in units of |dir|
    /// assert!(scene.cast_ray(Vector::ZERO, Vector::X, 1.0).is_none()); // too short
    /// assert_eq!(scene.cast_ray(Vector::new(2.0, 0.0, 0.0), Vector::Y, 1.0).map(|(t, _)| t), Some(0.0));
    /// ```
    fn cast_ray(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<(Real, ObstacleId)>;

    /// World-space bounds of all obstacles, `None` when there are none.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![
    ///     Obstacle::ball("a", Vector::new(-1.0, 0.0, 0.0), 0.5),
    ///     Obstacle::ball("b", Vector::new(2.0, 0.0, 1.0), 0.5),
    /// ]);
    /// let bounds = scene.aabb().unwrap();
    /// assert_eq!((bounds.mins.x, bounds.maxs.x, bounds.maxs.z), (-1.5, 2.5, 1.5));
    /// assert!(ParryScene::new(vec![]).aabb().is_none());
    /// ```
    fn aabb(&self) -> Option<Aabb>;

    /// The obstacle's name, for messages; `None` for an unknown id.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, Obstacles, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("lamp", Vector::ZERO, 0.1)]);
    /// assert_eq!(scene.name(ObstacleId(0)), Some("lamp"));
    /// assert_eq!(scene.name(ObstacleId(1)), None);
    /// ```
    fn name(&self, id: ObstacleId) -> Option<&str>;

    /// Where `shape` at `pose` touches obstacle `id`: the shape's deepest point, the normal
    /// towards the obstacle and the signed distance ([`ObstacleContact`]); `None` when they do
    /// not touch, for an unknown id, or where the implementation cannot tell (the default).
    /// [`RobotValidity`](crate::validity::RobotValidity) uses it to push a colliding state out
    /// of the obstacles ([`StateValidator::retract`](crate::validity::StateValidator::retract)).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    /// use parry3d::shape::Cuboid;
    ///
    /// let floor = Obstacle::cuboid("floor", Pose::translation(0.0, 0.0, -0.5), Vector::splat(0.5));
    /// let scene = ParryScene::new(vec![floor]);
    /// let block = Cuboid::new(Vector::splat(0.1));
    /// let c = scene.contact(ObstacleId(0), &block, &Pose::translation(0.0, 0.0, 0.08)).unwrap();
    /// assert!((c.distance + 0.02).abs() < 1e-6 && (c.normal.z + 1.0).abs() < 1e-6);
    /// assert_eq!(scene.contact(ObstacleId(0), &block, &Pose::translation(0.0, 0.0, 0.2)), None);
    /// assert_eq!(scene.contact(ObstacleId(7), &block, &Pose::IDENTITY), None);
    /// ```
    fn contact(&self, id: ObstacleId, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleContact> {
        let _ = (id, shape, pose);
        None
    }
}

/// Where a shape touches one obstacle ([`Obstacles::contact`]), in world coordinates.
///
/// ```
/// use hearth_planning::obstacles::{Obstacle, ObstacleId, Obstacles, ParryScene};
/// use parry3d::math::{Pose, Vector};
/// use parry3d::shape::Ball;
///
/// let scene = ParryScene::new(vec![Obstacle::ball("ball", Vector::ZERO, 0.5)]);
/// let c = scene.contact(ObstacleId(0), &Ball::new(0.1), &Pose::translation(0.55, 0.0, 0.0)).unwrap();
/// assert!((c.distance + 0.05).abs() < 1e-6); // 5 cm deep
/// assert!((c.normal - Vector::new(-1.0, 0.0, 0.0)).length() < 1e-6); // towards the obstacle
/// assert!((c.point.x - 0.45).abs() < 1e-6); // the probe's deepest point
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleContact {
    /// The shape's point deepest in the obstacle (or nearest it, when apart).
    pub point: Vector,
    /// Unit normal at that point, from the shape towards the obstacle: moving the shape along
    /// `-normal` by `-distance` separates them.
    pub normal: Vector,
    /// Signed distance: negative when they overlap (the penetration depth), positive when apart.
    pub distance: Real,
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
    ///
    /// ```
    /// use hearth_planning::obstacles::Obstacle;
    /// use parry3d::math::Pose;
    /// use parry3d::shape::SharedShape;
    ///
    /// let post = Obstacle::new("post", SharedShape::cuboid(0.05, 0.05, 0.5), Pose::translation(1.0, 0.0, 0.5));
    /// assert_eq!(post.name, "post");
    /// assert_eq!((post.aabb().mins.z, post.aabb().maxs.z), (0.0, 1.0));
    /// ```
    pub fn new(name: impl Into<String>, shape: SharedShape, pose: Pose) -> Self {
        Self {
            name: name.into(),
            shape,
            pose,
        }
    }

    /// A box centred at `pose` with the given half-extents along its local axes.
    ///
    /// ```
    /// use hearth_planning::obstacles::Obstacle;
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let table = Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.4), Vector::new(0.3, 0.6, 0.02));
    /// let aabb = table.aabb();
    /// assert!((aabb.maxs.x - 0.8).abs() < 1e-6 && (aabb.mins.y + 0.6).abs() < 1e-6);
    /// assert!((aabb.maxs.z - 0.42).abs() < 1e-6);
    /// ```
    pub fn cuboid(name: impl Into<String>, pose: Pose, half_extents: Vector) -> Self {
        Self::new(
            name,
            SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z),
            pose,
        )
    }

    /// A sphere of `radius` centred at `center`.
    ///
    /// ```
    /// use hearth_planning::obstacles::Obstacle;
    /// use parry3d::math::Vector;
    ///
    /// let ball = Obstacle::ball("ball", Vector::new(0.0, 0.0, 1.0), 0.25);
    /// assert_eq!(ball.pose.translation, Vector::new(0.0, 0.0, 1.0));
    /// assert_eq!(ball.aabb().mins, Vector::new(-0.25, -0.25, 0.75));
    /// ```
    pub fn ball(name: impl Into<String>, center: Vector, radius: Real) -> Self {
        Self::new(name, SharedShape::ball(radius), Pose::from_translation(center))
    }

    /// A flat-capped cylinder centred at `pose` whose axis is `pose`'s **local z axis**, spanning
    /// `±half_length` along it (parry's cylinder axis is y; the rotation is applied here).
    ///
    /// ```
    /// use hearth_planning::obstacles::Obstacle;
    /// use parry3d::math::{Pose, Rotation, Vector};
    ///
    /// // Laid along the world x axis: local z turned a quarter turn about y.
    /// let lying = Pose::from_parts(Vector::ZERO, Rotation::from_rotation_y(std::f32::consts::FRAC_PI_2));
    /// let pipe = Obstacle::cylinder("pipe", lying, 0.5, 0.05);
    /// let aabb = pipe.aabb();
    /// assert!((aabb.maxs.x - 0.5).abs() < 1e-5 && (aabb.maxs.z - 0.05).abs() < 1e-5);
    /// ```
    pub fn cylinder(name: impl Into<String>, pose: Pose, half_length: Real, radius: Real) -> Self {
        // R_x(+90°) maps local y (parry's axis) onto local z.
        let y_to_z = Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2);
        // Built field by field: parry's `Cylinder::new` panics on a negative size, which
        // `check` reports instead.
        let cylinder = parry3d::shape::Cylinder {
            half_height: half_length,
            radius,
        };
        Self::new(name, SharedShape::new(cylinder), pose * y_to_z)
    }

    /// A capsule (segment `a`–`b` in world coordinates, swept by a ball of `radius`).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let rail = Obstacle::capsule("rail", Vector::ZERO, Vector::new(1.0, 0.0, 0.0), 0.05);
    /// let scene = ParryScene::new(vec![rail]);
    /// assert!(scene.ball_hits(Vector::new(0.5, 0.0, 0.1), 0.06));
    /// assert!(!scene.ball_hits(Vector::new(1.2, 0.0, 0.0), 0.1));
    /// ```
    pub fn capsule(name: impl Into<String>, a: Vector, b: Vector, radius: Real) -> Self {
        Self::new(name, SharedShape::capsule(a, b, radius), Pose::IDENTITY)
    }

    /// The convex hull of `points` (given in the obstacle frame) at `pose`; `None` when parry
    /// cannot build it (e.g. no points).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let corners = [Vector::ZERO, Vector::X, Vector::Y, Vector::Z];
    /// let wedge = Obstacle::convex_hull("wedge", Pose::IDENTITY, &corners).unwrap();
    /// let scene = ParryScene::new(vec![wedge]);
    /// assert!(scene.ball_hits(Vector::splat(0.2), 0.01)); // solid inside
    /// assert!(!scene.ball_hits(Vector::splat(0.6), 0.01));
    /// assert!(Obstacle::convex_hull("nothing", Pose::IDENTITY, &[]).is_none());
    /// ```
    pub fn convex_hull(name: impl Into<String>, pose: Pose, points: &[Vector]) -> Option<Self> {
        SharedShape::convex_hull(points).map(|s| Self::new(name, s, pose))
    }

    /// A triangle mesh at `pose`. Triangle meshes are **hollow** for intersection tests: a shape
    /// entirely inside a closed mesh does not touch it (use a convex hull or decomposition for
    /// solid obstacles).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let corners = vec![Vector::ZERO, Vector::X, Vector::Y, Vector::Z];
    /// let faces = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    /// let shell = Obstacle::trimesh("shell", Pose::IDENTITY, corners, faces)?;
    /// let scene = ParryScene::new(vec![shell]);
    /// assert!(!scene.ball_hits(Vector::splat(0.2), 0.01)); // hollow: inside touches nothing
    /// assert!(scene.ball_hits(Vector::new(0.2, 0.2, 0.0), 0.01)); // on a face
    /// assert!(Obstacle::trimesh("empty", Pose::IDENTITY, vec![], vec![]).is_err());
    /// # Ok::<(), parry3d::shape::TriMeshBuilderError>(())
    /// ```
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
    ///
    /// ```
    /// use hearth_planning::obstacles::Obstacle;
    /// use parry3d::math::{Pose, Rotation, Vector};
    ///
    /// // A unit cube turned 45° about z is √2 wide along x and y.
    /// let turned = Pose::from_parts(Vector::ZERO, Rotation::from_rotation_z(std::f32::consts::FRAC_PI_4));
    /// let aabb = Obstacle::cuboid("cube", turned, Vector::splat(0.5)).aabb();
    /// assert!((aabb.maxs.x - 0.5 * 2f32.sqrt()).abs() < 1e-5 && (aabb.maxs.z - 0.5).abs() < 1e-6);
    /// ```
    pub fn aabb(&self) -> Aabb {
        self.shape.compute_aabb(&self.pose)
    }

    /// Checks that the obstacle describes a solid that collision queries can answer for: a
    /// finite pose whose rotation is a unit quaternion, finite sizes that are not negative
    /// (box half-extents, ball, cylinder, cone and capsule radii, half-lengths), finite
    /// points (a capsule's segment, a hull's or a mesh's vertices) and a bounding box within
    /// 1,000 km of the origin. parry takes such input without complaint and then answers
    /// queries wrongly (a NaN pose puts its bounding box everywhere);
    /// [`ParryScene::try_new`] runs this check on every obstacle.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleDefect};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// assert_eq!(Obstacle::ball("ok", Vector::ZERO, 0.1).check(), Ok(()));
    /// let nan = Obstacle::cuboid("nan", Pose::translation(f32::NAN, 0.0, 0.0), Vector::splat(0.1));
    /// assert_eq!(nan.check(), Err(ObstacleDefect::Pose));
    /// let inside_out = Obstacle::cuboid("box", Pose::IDENTITY, Vector::new(0.1, -0.2, 0.1));
    /// assert_eq!(inside_out.check(), Err(ObstacleDefect::Size { what: "half-extent", value: -0.2 }));
    /// ```
    ///
    /// # Errors
    /// The first [`ObstacleDefect`] found.
    pub fn check(&self) -> Result<(), ObstacleDefect> {
        let (t, q) = (self.pose.translation, self.pose.rotation);
        if !t.is_finite() || !q.is_finite() {
            return Err(ObstacleDefect::Pose);
        }
        let norm = q.length();
        if (norm - 1.0).abs() > 1e-3 {
            return Err(ObstacleDefect::Rotation { norm });
        }
        let sizes: Vec<(&'static str, Real)> = if let Some(c) = self.shape.as_cuboid() {
            c.half_extents.to_array().map(|v| ("half-extent", v)).to_vec()
        } else if let Some(b) = self.shape.as_ball() {
            vec![("radius", b.radius)]
        } else if let Some(c) = self.shape.as_cylinder() {
            vec![("half-length", c.half_height), ("radius", c.radius)]
        } else if let Some(c) = self.shape.as_cone() {
            vec![("half-length", c.half_height), ("radius", c.radius)]
        } else if let Some(c) = self.shape.as_capsule() {
            vec![("radius", c.radius)]
        } else {
            Vec::new()
        };
        if let Some(&(what, value)) = sizes.iter().find(|(_, v)| !v.is_finite() || *v < 0.0) {
            return Err(ObstacleDefect::Size { what, value });
        }
        // Points that shape the solid: a bounding box of min and max can pass over a NaN.
        let points: &[Vector] = if let Some(c) = self.shape.as_capsule() {
            &[c.segment.a, c.segment.b]
        } else if let Some(h) = self.shape.as_convex_polyhedron() {
            h.points()
        } else if let Some(m) = self.shape.as_trimesh() {
            m.vertices()
        } else {
            &[]
        };
        if !points.iter().all(|p| p.is_finite()) {
            return Err(ObstacleDefect::Bounds);
        }
        let aabb = self.aabb();
        if !aabb.mins.is_finite() || !aabb.maxs.is_finite() || aabb.mins.cmpgt(aabb.maxs).any() {
            return Err(ObstacleDefect::Bounds);
        }
        // f32 queries lose their precision (and squared lengths overflow) far beyond any
        // real scene: the limit benchmark problem files have too.
        let reach = aabb.mins.abs().max(aabb.maxs.abs()).max_element();
        if f64::from(reach) > crate::problem::MAX_EXTENT {
            return Err(ObstacleDefect::Extent { reach });
        }
        Ok(())
    }
}

/// What is wrong with an [`Obstacle`] ([`Obstacle::check`]).
///
/// ```
/// use hearth_planning::obstacles::ObstacleDefect;
/// assert_eq!(ObstacleDefect::Pose.to_string(), "its pose is not finite");
/// // Huge or tiny sizes print short, not as 31 digits.
/// let far = ObstacleDefect::Extent { reach: 1e30 };
/// assert!(far.to_string().starts_with("its bounding box reaches 1e30 m"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ObstacleDefect {
    /// The pose's translation or rotation holds a NaN or an infinity.
    #[error("its pose is not finite")]
    Pose,
    /// The rotation is not a unit quaternion (it would scale the shape).
    #[error("its rotation is not a unit quaternion (norm {})", Num(*norm))]
    Rotation {
        /// The quaternion's norm.
        norm: Real,
    },
    /// A size of the shape is negative or not finite.
    #[error("its {what} is {}, not a finite size of 0 or more", Num(*value))]
    Size {
        /// Which size (`half-extent`, `radius`, `half-length`).
        what: &'static str,
        /// Its value.
        value: Real,
    },
    /// The shape's bounding box, or a point that shapes it (a capsule's segment ends, a
    /// hull's or a mesh's vertices), is not finite.
    #[error("its shape has a point or bound that is not finite")]
    Bounds,
    /// The shape reaches farther from the origin than
    /// [`MAX_EXTENT`](crate::problem::MAX_EXTENT) (1,000 km), where f32 queries lose their
    /// precision.
    #[error("its bounding box reaches {} m from the origin, beyond the 1,000 km that queries can answer for", Num(*reach))]
    Extent {
        /// The largest coordinate of its bounding box, in metres.
        reach: Real,
    },
}

/// An obstacle that [`ParryScene::try_new`] refused: its position in the list, its name and
/// its defect.
///
/// ```
/// use hearth_planning::obstacles::{Obstacle, ParryScene};
/// use parry3d::math::Vector;
///
/// let e = ParryScene::try_new(vec![
///     Obstacle::ball("ok", Vector::ZERO, 0.1),
///     Obstacle::ball("bad", Vector::X, -0.1),
/// ])
/// .unwrap_err();
/// assert_eq!((e.index, e.name.as_str()), (1, "bad"));
/// assert_eq!(e.to_string(), "obstacle 1 (\"bad\"): its radius is -0.1, not a finite size of 0 or more");
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("obstacle {index} ({name:?}): {defect}")]
pub struct ObstacleError {
    /// Position of the obstacle in the list given.
    pub index: usize,
    /// The obstacle's name.
    pub name: String,
    /// What is wrong with it.
    pub defect: ObstacleDefect,
}
