//! [`ParryScene`]: static named obstacles in a parry BVH.

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Real, Vector};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::{self, Ray};
use parry3d::shape::Shape;

use std::ops::{Add, Mul, Sub};

use wide::f32x8;

use super::gjk::{self, Convex};
use super::{
    BallBatch, Obstacle, ObstacleContact, ObstacleError, ObstacleId, Obstacles, balls_one_by_one, nearest_leaf,
    shape_contact,
};

/// Up to this many obstacles, ball queries scan every obstacle's bounding box (eight at a
/// time) instead of descending the BVH.
const SCAN_LIMIT: usize = 64;

/// A static obstacle scene: named parry shapes at fixed world poses, with a BVH over their
/// bounding boxes built once at construction.
///
/// Queries descend the BVH (pruning by bounding box) and run exact parry tests only on the
/// candidates; they do not allocate. Build one per benchmark problem
/// ([`crate::problem::Problem::scene`]) or from your own [`Obstacle`]s.
///
/// **Margin.** With [`ParryScene::with_margin`]`(m)`, [`Obstacles::intersects`] and
/// [`Obstacles::first_hit`] report a hit when the exact distance is `≤ m` (the query box is
/// loosened by `m` for the BVH descent). `distance` and `cast_ray` ignore the margin.
///
/// **Unsupported shape pairs.** If parry cannot test a pair (it returns `Unsupported`), the
/// pair counts as colliding (distance 0): conservative for planning.
///
/// ```
/// use hearth_planning::obstacles::{Obstacle, Obstacles, ObstacleId, ParryScene};
/// use parry3d::math::{Pose, Vector};
/// use parry3d::shape::Ball;
///
/// let scene = ParryScene::new(vec![
///     Obstacle::ball("ball", Vector::new(1.0, 0.0, 0.0), 0.1),
///     Obstacle::cuboid("wall", Pose::translation(2.0, 0.0, 0.0), Vector::new(0.05, 1.0, 1.0)),
/// ])
/// .with_margin(0.02);
/// let probe = Ball::new(0.1);
/// // 0.01 m of clearance is inside the 2 cm margin:
/// assert_eq!(scene.first_hit(&probe, &Pose::translation(1.21, 0.0, 0.0)), Some(ObstacleId(0)));
/// assert!(!scene.intersects(&probe, &Pose::translation(1.5, 0.0, 0.0)));
/// let (t, id) = scene.cast_ray(Vector::new(1.5, 0.0, 0.0), Vector::X, 10.0).unwrap();
/// assert_eq!(scene.name(id), Some("wall"));
/// assert!((t - 0.45).abs() < 1e-5);
/// ```
#[derive(Clone, Debug, Default)]
pub struct ParryScene {
    obstacles: Vec<Obstacle>,
    /// Closed-form ball tests per obstacle, for [`Obstacles::ball_hits`].
    quick: Vec<Quick>,
    /// Per obstacle: a box or a cylinder as the exact search of [`gjk::touch`] takes it
    /// (`None` for other shapes), built once here rather than per test.
    convex: Vec<Option<Convex>>,
    /// Bounding boxes of every obstacle as structure-of-arrays, the first rejection test of
    /// [`Obstacles::ball_hits`] (eight obstacles per step).
    boxes: SoaBoxes,
    bvh: Bvh,
    bounds: Option<Aabb>,
    margin: Real,
}

impl ParryScene {
    /// Builds the scene and its BVH. Obstacle `i` gets [`ObstacleId`]`(i)`.
    ///
    /// The obstacles are taken as they are: an obstacle with a NaN pose or a negative size
    /// makes queries answer wrongly. For geometry that comes from outside the program (a
    /// file, a sensor), build with [`ParryScene::try_new`], which refuses such obstacles.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, Obstacles, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let scene = ParryScene::new(vec![
    ///     Obstacle::ball("ball", Vector::new(0.0, 0.0, 1.0), 0.1),
    ///     Obstacle::cuboid("floor", Pose::translation(0.0, 0.0, -0.05), Vector::new(2.0, 2.0, 0.05)),
    /// ]);
    /// assert_eq!(scene.name(ObstacleId(1)), Some("floor"));
    /// assert!(scene.ball_hits(Vector::new(1.0, 1.0, 0.05), 0.1));
    /// ```
    pub fn new(obstacles: Vec<Obstacle>) -> Self {
        let aabbs: Vec<Aabb> = obstacles.iter().map(Obstacle::aabb).collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &aabbs);
        let bounds = aabbs.iter().copied().reduce(|a, b| a.merged(&b));
        let quick: Vec<Quick> = obstacles.iter().map(Quick::of).collect();
        let convex = quick.iter().map(Quick::convex).collect();
        let boxes = SoaBoxes::new(&aabbs);
        Self {
            quick,
            convex,
            boxes,
            obstacles,
            bvh,
            bounds,
            margin: 0.0,
        }
    }

    /// Builds the scene after [`Obstacle::check`]ing every obstacle; the first defect found is
    /// returned with the obstacle's position and name, and no scene is built.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleDefect, ParryScene};
    /// use parry3d::math::{Pose, Vector};
    ///
    /// let table = Obstacle::cuboid("table", Pose::translation(0.5, 0.0, 0.4), Vector::new(0.3, 0.6, 0.02));
    /// assert_eq!(ParryScene::try_new(vec![table.clone()])?.obstacles().len(), 1);
    /// let lost = Obstacle::cuboid("lost", Pose::translation(0.0, f32::INFINITY, 0.0), Vector::splat(0.1));
    /// let e = ParryScene::try_new(vec![table, lost]).unwrap_err();
    /// assert_eq!((e.index, e.defect), (1, ObstacleDefect::Pose));
    /// # Ok::<(), hearth_planning::obstacles::ObstacleError>(())
    /// ```
    ///
    /// # Errors
    /// [`ObstacleError`] for the first obstacle whose check fails.
    pub fn try_new(obstacles: Vec<Obstacle>) -> Result<Self, ObstacleError> {
        for (index, o) in obstacles.iter().enumerate() {
            o.check().map_err(|defect| ObstacleError {
                index,
                name: o.name.clone(),
                defect,
            })?;
        }
        Ok(Self::new(obstacles))
    }

    /// Sets the collision margin (see the type's docs). Negative or non-finite values count as 0.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, Obstacles, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let ball = || vec![Obstacle::ball("ball", Vector::ZERO, 0.5)];
    /// let near = Vector::new(0.65, 0.0, 0.0); // 5 cm from the ball's surface
    /// assert!(!ParryScene::new(ball()).ball_hits(near, 0.1));
    /// assert!(ParryScene::new(ball()).with_margin(0.06).ball_hits(near, 0.1));
    /// assert_eq!(ParryScene::new(ball()).with_margin(-1.0).margin(), 0.0);
    /// ```
    pub fn with_margin(mut self, margin: Real) -> Self {
        self.set_margin(margin);
        self
    }

    /// Sets the collision margin in place. Negative or non-finite values count as 0.
    ///
    /// ```
    /// use hearth_planning::obstacles::ParryScene;
    ///
    /// let mut scene = ParryScene::new(vec![]);
    /// scene.set_margin(0.01);
    /// assert_eq!(scene.margin(), 0.01);
    /// scene.set_margin(f32::NAN);
    /// assert_eq!(scene.margin(), 0.0);
    /// ```
    pub fn set_margin(&mut self, margin: Real) {
        self.margin = if margin.is_finite() && margin > 0.0 {
            margin
        } else {
            0.0
        };
    }

    /// The collision margin applied by `intersects` / `first_hit` (0 unless set).
    ///
    /// ```
    /// use hearth_planning::obstacles::ParryScene;
    ///
    /// assert_eq!(ParryScene::new(vec![]).margin(), 0.0);
    /// assert_eq!(ParryScene::new(vec![]).with_margin(0.02).margin(), 0.02);
    /// ```
    pub fn margin(&self) -> Real {
        self.margin
    }

    /// All obstacles, indexed by [`ObstacleId`].
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("a", Vector::ZERO, 0.1), Obstacle::ball("b", Vector::X, 0.2)]);
    /// let names: Vec<&str> = scene.obstacles().iter().map(|o| o.name.as_str()).collect();
    /// assert_eq!(names, ["a", "b"]);
    /// ```
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The obstacle with this id, `None` for an id past the end.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("ball", Vector::X, 0.1)]);
    /// assert_eq!(scene.get(ObstacleId(0)).unwrap().pose.translation, Vector::X);
    /// assert!(scene.get(ObstacleId(1)).is_none());
    /// ```
    pub fn get(&self, id: ObstacleId) -> Option<&Obstacle> {
        self.obstacles.get(id.index())
    }

    /// The id of the first obstacle with this name (names need not be unique).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ObstacleId, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![
    ///     Obstacle::ball("can", Vector::ZERO, 0.1),
    ///     Obstacle::ball("cup", Vector::X, 0.1),
    ///     Obstacle::ball("can", Vector::Y, 0.1),
    /// ]);
    /// assert_eq!(scene.find("can"), Some(ObstacleId(0)));
    /// assert_eq!(scene.find("cup"), Some(ObstacleId(1)));
    /// assert_eq!(scene.find("plate"), None);
    /// ```
    pub fn find(&self, name: &str) -> Option<ObstacleId> {
        self.obstacles
            .iter()
            .position(|o| o.name == name)
            .map(|i| ObstacleId(i as u32))
    }

    /// Number of obstacles.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let scene = ParryScene::new(vec![Obstacle::ball("a", Vector::ZERO, 0.1), Obstacle::ball("b", Vector::X, 0.1)]);
    /// assert_eq!(scene.len(), 2);
    /// ```
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// Whether the scene has no obstacles (then every query misses).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacles, ParryScene};
    /// use parry3d::math::Vector;
    ///
    /// let empty = ParryScene::new(vec![]);
    /// assert!(empty.is_empty());
    /// assert!(!empty.ball_hits(Vector::ZERO, 1.0));
    /// ```
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// Exact test of one obstacle against `shape` at `pose`, honouring the margin.
    fn touches(&self, index: u32, shape: &dyn Shape, pose: &Pose) -> bool {
        let o = &self.obstacles[index as usize];
        if self.margin > 0.0 {
            return match query::distance(pose, shape, &o.pose, &*o.shape) {
                Ok(d) => d.distance <= self.margin,
                Err(_) => true,
            };
        }
        parry_touch(shape, pose, &*o.shape, &o.pose)
    }
}

impl ParryScene {
    /// [`Obstacles::first_hit`] for small scenes without a margin: a scan of the bounding
    /// boxes, closed forms for a ball (against every obstacle kind but meshes) and for a box
    /// against a box; a cylinder against a box is tested as the box around it first, then by
    /// the closed-form certificates of [`cylinder_meets_box`], then by the exact search of
    /// [`gjk::touch`]; a box or a cylinder against a cylinder by that search; parry where
    /// none of these settles it, and for the rest.
    ///
    /// The search replaced parry's GJK test on these pairs (3.9 % fewer planner instructions
    /// per check on the Fetch's bookshelf and table plans). It also answers better: in 2.4
    /// million searches over the Fetch's table_pick, box, bookshelf_thin and cage plans,
    /// parry called 0.37 % of the pairs touching that the search found apart, a fifth of them
    /// with a parry distance of 0 too; each of the 14 of those sampled was 0.003–2 mm apart by
    /// an independent minimisation. The search never found contact where parry did not.
    fn scan_first_hit(&self, shape: &dyn Shape, pose: &Pose) -> Option<usize> {
        if let Some(ball) = shape.as_ball() {
            return self.scan_ball(pose.translation, ball.radius);
        }
        // A box is its own box; a cylinder (axis local y) is tested as the box around it
        // first, then in closed form, then by the search.
        let (obb, exact) = if let Some(cuboid) = shape.as_cuboid() {
            (Obb::at(pose, cuboid.half_extents), true)
        } else if let Some(c) = shape.as_cylinder() {
            (Obb::at(pose, Vector::new(c.radius, c.half_height, c.radius)), false)
        } else {
            return self
                .boxes
                .first_overlapping(&shape.compute_aabb(pose), |i| self.touches(i as u32, shape, pose));
        };
        let part = || if exact { obb.convex() } else { obb.cylinder_convex() };
        let search = |i: usize| self.convex[i].as_ref().and_then(|other| gjk::touch(&part(), other));
        self.boxes.first_overlapping(&obb.aabb(), |i| match &self.quick[i] {
            Quick::Cuboid(other) => {
                obb.touches(other)
                    && (exact
                        || cylinder_meets_box(&obb, other)
                            .or_else(|| search(i))
                            .unwrap_or_else(|| self.touches(i as u32, shape, pose)))
            }
            Quick::Cylinder { .. } => search(i).unwrap_or_else(|| self.touches(i as u32, shape, pose)),
            _ => self.touches(i as u32, shape, pose),
        })
    }

    /// The first obstacle that a ball of `radius` at `center` touches (within the margin),
    /// for small scenes: a scan of the bounding boxes, closed forms where the obstacle has one.
    fn scan_ball(&self, center: Vector, radius: Real) -> Option<usize> {
        let r = radius + self.margin;
        self.boxes.first_near(center, r, |i| {
            self.quick[i].ball(center, r).unwrap_or_else(|| {
                self.touches(
                    i as u32,
                    &parry3d::shape::Ball::new(radius),
                    &Pose::from_translation(center),
                )
            })
        })
    }
}

impl FromIterator<Obstacle> for ParryScene {
    fn from_iter<I: IntoIterator<Item = Obstacle>>(iter: I) -> Self {
        Self::new(iter.into_iter().collect())
    }
}

/// Axis-aligned boxes as structure-of-arrays, padded to a multiple of 8 with empty boxes.
#[derive(Clone, Debug, Default)]
struct SoaBoxes {
    /// min x, min y, min z, max x, max y, max z.
    bounds: [Vec<Real>; 6],
    len: usize,
}

impl SoaBoxes {
    fn new(aabbs: &[Aabb]) -> Self {
        let padded = aabbs.len().div_ceil(8) * 8;
        let mut bounds: [Vec<Real>; 6] =
            std::array::from_fn(|k| vec![if k < 3 { Real::MAX } else { Real::MIN }; padded]);
        for (i, a) in aabbs.iter().enumerate() {
            for (k, v) in [a.mins.x, a.mins.y, a.mins.z, a.maxs.x, a.maxs.y, a.maxs.z]
                .into_iter()
                .enumerate()
            {
                bounds[k][i] = v;
            }
        }
        Self {
            bounds,
            len: aabbs.len(),
        }
    }

    /// The first box `i` (in index order) for which `near(lanes)` marks the lane and
    /// `exact(i)` holds; `near` sees eight boxes at a time as `[min x, min y, min z, max x,
    /// max y, max z]` lanes and returns a lane mask.
    #[inline(always)]
    fn scan(&self, near: impl Fn([f32x8; 6]) -> f32x8, mut exact: impl FnMut(usize) -> bool) -> Option<usize> {
        for chunk in 0..self.bounds[0].len() / 8 {
            let base = chunk * 8;
            let b = &self.bounds;
            let load = |k: usize| {
                let mut lane = [0.0; 8];
                lane.copy_from_slice(&b[k][base..base + 8]);
                f32x8::new(lane)
            };
            let mut mask = near([load(0), load(1), load(2), load(3), load(4), load(5)]).to_bitmask();
            while mask != 0 {
                let i = base + mask.trailing_zeros() as usize;
                if i < self.len && exact(i) {
                    return Some(i);
                }
                mask &= mask - 1;
            }
        }
        None
    }

    /// The first box `i` within `r` of `c` for which `exact(i)` holds.
    #[inline]
    fn first_near(&self, c: Vector, r: Real, exact: impl FnMut(usize) -> bool) -> Option<usize> {
        let (x, y, z) = (f32x8::splat(c.x), f32x8::splat(c.y), f32x8::splat(c.z));
        let r2 = f32x8::splat(r * r);
        self.scan(
            |[x0, y0, z0, x1, y1, z1]| {
                let dx = (x0 - x).max(x - x1).max0();
                let dy = (y0 - y).max(y - y1).max0();
                let dz = (z0 - z).max(z - z1).max0();
                (dx * dx + dy * dy + dz * dz).simd_le(r2)
            },
            exact,
        )
    }

    /// The first box `i` overlapping `aabb` for which `exact(i)` holds.
    #[inline]
    fn first_overlapping(&self, aabb: &Aabb, exact: impl FnMut(usize) -> bool) -> Option<usize> {
        let (lo, hi) = (aabb.mins, aabb.maxs);
        let lo = [f32x8::splat(lo.x), f32x8::splat(lo.y), f32x8::splat(lo.z)];
        let hi = [f32x8::splat(hi.x), f32x8::splat(hi.y), f32x8::splat(hi.z)];
        self.scan(
            |[x0, y0, z0, x1, y1, z1]| {
                x0.simd_le(hi[0])
                    & y0.simd_le(hi[1])
                    & z0.simd_le(hi[2])
                    & lo[0].simd_le(x1)
                    & lo[1].simd_le(y1)
                    & lo[2].simd_le(z1)
            },
            exact,
        )
    }
}

/// Parry's exact test of two shapes without a margin; a pair parry cannot test counts as
/// touching when its distance query finds no gap (or cannot measure it either).
fn parry_touch(a: &dyn Shape, pa: &Pose, b: &dyn Shape, pb: &Pose) -> bool {
    match query::intersection_test(pa, a, pb, b) {
        Ok(hit) => hit.intersecting,
        Err(_) => query::distance(pa, a, pb, b).map_or(true, |d| d.distance <= 0.0),
    }
}

/// Whether two shapes at their world poses share a point, by the tests
/// [`ParryScene::first_hit`] gives a robot part against an obstacle: a ball in closed form
/// against a box, a ball, a cylinder or a capsule; two boxes by the separating-axis test; a
/// cylinder against a box by that test on the box around the cylinder, then the closed-form
/// certificates of [`cylinder_meets_box`], then the exact search of [`gjk::touch`]; two
/// cylinders by the box test, then the search; parry where none of these settles it, and for
/// every other pair. Self-collision asks it of the part pairs whose bounding balls meet when
/// parry's test of one link's compound shape against the other's reports contact, which
/// parry's GJK does for some shapes that are apart.
pub(crate) fn shapes_touch(a: &dyn Shape, pa: &Pose, b: &dyn Shape, pb: &Pose) -> bool {
    let parry = || parry_touch(a, pa, b, pb);
    if let Some(ball) = a.as_ball() {
        return Quick::at(b, pb).ball(pa.translation, ball.radius).unwrap_or_else(parry);
    }
    if let Some(ball) = b.as_ball() {
        return Quick::at(a, pa).ball(pb.translation, ball.radius).unwrap_or_else(parry);
    }
    // A box is its own box; a cylinder (axis local y) first the box around it.
    let boxed = |s: &dyn Shape, pose: &Pose| {
        if let Some(c) = s.as_cuboid() {
            Some((Obb::at(pose, c.half_extents), true))
        } else {
            s.as_cylinder()
                .map(|c| (Obb::at(pose, Vector::new(c.radius, c.half_height, c.radius)), false))
        }
    };
    let (Some((oa, box_a)), Some((ob, box_b))) = (boxed(a, pa), boxed(b, pb)) else {
        return parry();
    };
    if !oa.touches(&ob) {
        return false;
    }
    match (box_a, box_b) {
        (true, true) => true,
        (false, true) => cylinder_meets_box(&oa, &ob)
            .or_else(|| gjk::touch(&oa.cylinder_convex(), &ob.convex()))
            .unwrap_or_else(parry),
        (true, false) => cylinder_meets_box(&ob, &oa)
            .or_else(|| gjk::touch(&ob.cylinder_convex(), &oa.convex()))
            .unwrap_or_else(parry),
        (false, false) => gjk::touch(&oa.cylinder_convex(), &ob.cylinder_convex()).unwrap_or_else(parry),
    }
}

/// An oriented box: centre, local axes in the world (the rows of the world-to-box rotation)
/// and half extents along them.
#[derive(Clone, Copy, Debug)]
struct Obb {
    center: Vector,
    axes: [Vector; 3],
    half: Vector,
}

impl Obb {
    fn at(pose: &Pose, half: Vector) -> Self {
        Self {
            center: pose.translation,
            axes: [
                pose.rotation * Vector::X,
                pose.rotation * Vector::Y,
                pose.rotation * Vector::Z,
            ],
            half,
        }
    }

    /// The box as the exact search of [`gjk::touch`] takes it.
    fn convex(&self) -> Convex {
        Convex::cuboid(self.center, self.axes, self.half)
    }

    /// The cylinder that this box was built around by [`Obb::at`] (axis `axes[1]`, half
    /// height `half.y`, radius `half.x`), as [`gjk::touch`] takes it.
    fn cylinder_convex(&self) -> Convex {
        Convex::cylinder(self.center, self.axes[1], self.half.y, self.half.x)
    }

    /// Its point nearest to `p` (`p` itself when inside).
    fn nearest_point(&self, p: Vector) -> Vector {
        let q = p - self.center;
        self.center
            + self.axes[0] * q.dot(self.axes[0]).clamp(-self.half.x, self.half.x)
            + self.axes[1] * q.dot(self.axes[1]).clamp(-self.half.y, self.half.y)
            + self.axes[2] * q.dot(self.axes[2]).clamp(-self.half.z, self.half.z)
    }

    /// Whether `p` lies inside it by more than `margin` along every axis.
    fn holds(&self, p: Vector, margin: Real) -> bool {
        let q = p - self.center;
        (0..3).all(|k| q.dot(self.axes[k]).abs() <= self.half[k] - margin)
    }

    /// The world-aligned box around it.
    fn aabb(&self) -> Aabb {
        let [a, b, c] = self.axes;
        let h = self.half;
        let extent = a.abs() * h.x + b.abs() * h.y + c.abs() * h.z;
        Aabb::new(self.center - extent, self.center + extent)
    }

    /// Whether the two boxes touch: the separating-axis test on their 15 candidate axes
    /// (Gottschalk, Lin & Manocha 1996; the form of Ericson, *Real-Time Collision Detection*,
    /// §4.4.1). [`OBB_PARALLEL_SLACK`] on every rotation term keeps near-parallel edge pairs,
    /// whose cross product is numerically meaningless, from reporting a false separation; it
    /// only ever reports contact, never clearance.
    fn touches(&self, other: &Obb) -> bool {
        let (a, b) = (self, other);
        let ha = a.half.to_array();
        let hb = b.half.to_array();
        let d = b.center - a.center;
        let t = [a.axes[0].dot(d), a.axes[1].dot(d), a.axes[2].dot(d)];
        let mut r = [[0.0; 3]; 3];
        let mut abs_r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = a.axes[i].dot(b.axes[j]);
                abs_r[i][j] = r[i][j].abs() + OBB_PARALLEL_SLACK;
            }
        }
        for i in 0..3 {
            let rb = hb[0] * abs_r[i][0] + hb[1] * abs_r[i][1] + hb[2] * abs_r[i][2];
            if t[i].abs() > ha[i] + rb {
                return false;
            }
        }
        for j in 0..3 {
            let ra = ha[0] * abs_r[0][j] + ha[1] * abs_r[1][j] + ha[2] * abs_r[2][j];
            let s = t[0] * r[0][j] + t[1] * r[1][j] + t[2] * r[2][j];
            if s.abs() > ra + hb[j] {
                return false;
            }
        }
        for i in 0..3 {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            for j in 0..3 {
                let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
                let ra = ha[i1] * abs_r[i2][j] + ha[i2] * abs_r[i1][j];
                let rb = hb[j1] * abs_r[i][j2] + hb[j2] * abs_r[i][j1];
                let s = t[i2] * r[i1][j] - t[i1] * r[i2][j];
                if s.abs() > ra + rb {
                    return false;
                }
            }
        }
        true
    }
}

/// Added to every absolute rotation term of the box-box test (see [`Obb::touches`]).
const OBB_PARALLEL_SLACK: Real = 1e-6;

/// Distance by which the closed-form cylinder-box certificates below stay on the safe side of
/// every comparison, far above f32 rounding at the sizes of robots and furniture.
const CYLINDER_BOX_SLACK: Real = 1e-5;

/// Whether a cylinder meets a box, where a closed form settles it: `Some(false)` when one of
/// eight candidate axes separates them, `Some(true)` when a point lies inside both, `None`
/// otherwise (the caller then asks [`gjk::touch`]). On cylinders whose bounding boxes
/// overlap a board, [`ParryScene::first_hit`] takes ~100 ns with these forms against ~220 ns
/// without them (parry's test alone: ~410 ns); the Panda's MotionBenchMaker cage plans leave
/// one cylinder-box test in thirty to parry, the Fetch's wedged bookshelf goals one in eight.
///
/// `cylinder` is the cylinder's bounding box as [`Obb::at`] builds it from parry's cylinder:
/// axis `axes[1]`, half height `half.y`, radius `half.x`.
///
/// - *Separation.* The box's three face normals, the cylinder's axis, the axis crossed with
///   each box edge direction, and the direction from the axis to the box's centre. Along a unit
///   direction `n` the cylinder reaches `h |n·a| + r √(1 − (n·a)²)` from its centre and the box
///   `Σ e_i |n·u_i|` from its centre; a gap between the two intervals proves them apart. These
///   are the exact separating directions for a box face against the cylinder, and for a box
///   edge against the cylinder's side, which is how a link grazes a shelf board.
/// - *Contact.* The cylinder's farthest point inside the box (shrunk by the slack) along each
///   face normal, along the direction to the box's centre or along the direction to the box's
///   point nearest the cylinder's centre; or a point of the box inside the cylinder
///   ([`box_point_in_cylinder`]). Either proves contact: a link dipping into a board, lying
///   across its edge, or a thin slice of a link cutting its corner.
fn cylinder_meets_box(cylinder: &Obb, b: &Obb) -> Option<bool> {
    let (c, a) = (cylinder.center, cylinder.axes[1]);
    let (h, r) = (cylinder.half.y, cylinder.half.x);
    let d = b.center - c;
    let reach_cylinder = |n: Vector| {
        let na = n.dot(a);
        h * na.abs() + r * (1.0 - na * na).max(0.0).sqrt()
    };
    let reach_box = |n: Vector| {
        b.half.x * n.dot(b.axes[0]).abs() + b.half.y * n.dot(b.axes[1]).abs() + b.half.z * n.dot(b.axes[2]).abs()
    };
    let apart = |n: Vector| d.dot(n).abs() > reach_cylinder(n) + reach_box(n) + CYLINDER_BOX_SLACK;
    let across = d - a * d.dot(a);
    let towards_centre = (across.length_squared() > 1e-12).then(|| across.normalize());
    if b.axes.iter().any(|&u| apart(u)) || apart(a) {
        return Some(false);
    }
    for u in b.axes.iter().map(|&u| a.cross(u)).chain(towards_centre) {
        let len2 = u.length_squared();
        if len2 > 1e-6 && apart(u / len2.sqrt()) {
            return Some(false);
        }
    }
    // The cylinder's farthest point along `n` (unit), pulled in by the slack.
    let farthest = |n: Vector| {
        let na = n.dot(a);
        let side = n - a * na;
        let len = side.length();
        let rim = if len > 1e-6 {
            side * ((r - CYLINDER_BOX_SLACK).max(0.0) / len)
        } else {
            Vector::ZERO
        };
        c + a * ((h - CYLINDER_BOX_SLACK).max(0.0) * na.signum()) + rim
    };
    let toward_box = b.axes.map(|u| if u.dot(d) >= 0.0 { u } else { -u });
    let towards_nearest = (b.nearest_point(c) - c).try_normalize();
    let hit = toward_box
        .into_iter()
        .chain(towards_centre)
        .chain(towards_nearest)
        .any(|n| b.holds(farthest(n), CYLINDER_BOX_SLACK))
        || box_point_in_cylinder(c, a, h, r, b);
    hit.then_some(true)
}

/// Whether a point of the box certainly lies inside the cylinder (centre `c`, unit axis `a`,
/// half height `h`, radius `r`, all shrunk by the slack): the box points nearest to the axis,
/// found by alternating projections between the axis and the box (which converge to a closest
/// pair of the two convex sets), eight rounds at most. Answers `false` when unsure, never
/// `true` wrongly. This settles a link lying across the edge of a board.
fn box_point_in_cylinder(c: Vector, a: Vector, h: Real, r: Real, b: &Obb) -> bool {
    let (h, r) = (h - CYLINDER_BOX_SLACK, r - CYLINDER_BOX_SLACK);
    if h <= 0.0 || r <= 0.0 {
        return false;
    }
    let mut t = (b.center - c).dot(a).clamp(-h, h);
    for _ in 0..8 {
        let from_centre = b.nearest_point(c + a * t) - c;
        let along = from_centre.dot(a);
        if along.abs() <= h && (from_centre - a * along).length_squared() <= r * r {
            return true;
        }
        let next = along.clamp(-h, h);
        if (next - t).abs() < 1e-6 {
            return false;
        }
        t = next;
    }
    false
}

/// A ball test in closed form: the obstacle's shape in its own frame.
#[derive(Clone, Debug)]
enum Quick {
    /// A box in the world.
    Cuboid(Obb),
    Ball {
        center: Vector,
        radius: Real,
    },
    /// Parry's cylinder (axis y, `±half_height`) in the world: centre and unit axis.
    Cylinder {
        center: Vector,
        axis: Vector,
        half_height: Real,
        radius: Real,
    },
    Capsule {
        a: Vector,
        b: Vector,
        radius: Real,
    },
    /// Anything else goes through parry.
    Other,
}

/// The arithmetic the closed forms below need, on one value (`f32`) or on eight lanes
/// (`f32x8`), so that a ball asked alone and a ball asked in a batch get the same answer to
/// the last bit.
trait Lane: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    fn splat(v: Real) -> Self;
    fn abs(self) -> Self;
    fn max0(self) -> Self;
    fn sqrt(self) -> Self;
}

impl Lane for Real {
    #[inline(always)]
    fn splat(v: Real) -> Self {
        v
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Real::abs(self)
    }
    #[inline(always)]
    fn max0(self) -> Self {
        self.max(0.0)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Real::sqrt(self)
    }
}

impl Lane for f32x8 {
    #[inline(always)]
    fn splat(v: Real) -> Self {
        f32x8::splat(v)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x8::abs(self)
    }
    #[inline(always)]
    fn max0(self) -> Self {
        self.max(f32x8::ZERO)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x8::sqrt(self)
    }
}

/// Squared distance from the point at offset `(dx, dy, dz)` from the box's centre to the box.
#[inline(always)]
fn cuboid_gap2<L: Lane>(dx: L, dy: L, dz: L, obb: &Obb) -> L {
    let (axes, half) = (&obb.axes, obb.half);
    let out = |a: Vector, h: Real| (dx * L::splat(a.x) + dy * L::splat(a.y) + dz * L::splat(a.z)).abs() - L::splat(h);
    let (ox, oy, oz) = (
        out(axes[0], half.x).max0(),
        out(axes[1], half.y).max0(),
        out(axes[2], half.z).max0(),
    );
    ox * ox + oy * oy + oz * oz
}

/// Squared distance from the point at offset `(dx, dy, dz)` from a cylinder's centre to the
/// cylinder (unit `axis`, `±half_height` along it, `radius` around it). The radial part is
/// measured on the offset with its axial part removed, which stays accurate near the axis.
#[inline(always)]
fn cylinder_gap2<L: Lane>(dx: L, dy: L, dz: L, axis: Vector, half_height: Real, radius: Real) -> L {
    let (ax, ay, az) = (L::splat(axis.x), L::splat(axis.y), L::splat(axis.z));
    let along = dx * ax + dy * ay + dz * az;
    let (px, py, pz) = (dx - along * ax, dy - along * ay, dz - along * az);
    let dr = ((px * px + py * py + pz * pz).sqrt() - L::splat(radius)).max0();
    let da = (along.abs() - L::splat(half_height)).max0();
    dr * dr + da * da
}

/// Squared distance between the centres of two balls, and the square of the largest one at
/// which they touch (`r + rc`).
#[inline(always)]
fn balls_gap2<L: Lane>(dx: L, dy: L, dz: L, rc: Real, r: L) -> (L, L) {
    let reach = r + L::splat(rc);
    (dx * dx + dy * dy + dz * dz, reach * reach)
}

/// Lanes `o..o + 8` of a batch's column.
#[inline(always)]
fn load8(v: &[Real; BallBatch::CAPACITY], o: usize) -> f32x8 {
    let mut lane = [0.0; 8];
    lane.copy_from_slice(&v[o..o + 8]);
    f32x8::new(lane)
}

/// A box or a cylinder `s` at `pose` as [`gjk::touch`] takes it; `None` for other shapes.
pub(super) fn convex_at(s: &dyn Shape, pose: &Pose) -> Option<Convex> {
    Quick::at(s, pose).convex()
}

impl Quick {
    fn of(o: &Obstacle) -> Self {
        Self::at(&*o.shape, &o.pose)
    }

    /// `s` at `pose` in the world.
    fn at(s: &dyn Shape, pose: &Pose) -> Self {
        if let Some(c) = s.as_cuboid() {
            Quick::Cuboid(Obb::at(pose, c.half_extents))
        } else if let Some(b) = s.as_ball() {
            Quick::Ball {
                center: pose.translation,
                radius: b.radius,
            }
        } else if let Some(c) = s.as_cylinder() {
            Quick::Cylinder {
                center: pose.translation,
                axis: pose.transform_vector(Vector::Y),
                half_height: c.half_height,
                radius: c.radius,
            }
        } else if let Some(c) = s.as_capsule() {
            Quick::Capsule {
                a: pose.transform_point(c.segment.a),
                b: pose.transform_point(c.segment.b),
                radius: c.radius,
            }
        } else {
            Quick::Other
        }
    }

    /// The obstacle as [`gjk::touch`] takes it, for a box or a cylinder.
    fn convex(&self) -> Option<Convex> {
        match *self {
            Quick::Cuboid(ref obb) => Some(obb.convex()),
            Quick::Cylinder {
                center,
                axis,
                half_height,
                radius,
            } => Some(Convex::cylinder(center, axis, half_height, radius)),
            _ => None,
        }
    }

    /// `Some(touches)` for a ball of `radius` at `center`, `None` when parry must decide.
    #[inline]
    fn ball(&self, center: Vector, radius: Real) -> Option<bool> {
        Some(match self {
            Quick::Cuboid(b) => {
                let d = center - b.center;
                cuboid_gap2(d.x, d.y, d.z, b) <= radius * radius
            }
            Quick::Ball { center: c, radius: r } => {
                let d = center - *c;
                let (d2, reach2) = balls_gap2(d.x, d.y, d.z, *r, radius);
                d2 <= reach2
            }
            Quick::Cylinder {
                center: c,
                axis,
                half_height,
                radius: r,
            } => {
                let d = center - *c;
                cylinder_gap2(d.x, d.y, d.z, *axis, *half_height, *r) <= radius * radius
            }
            Quick::Capsule { a, b, radius: r } => {
                let ab = *b - *a;
                let len2 = ab.length_squared();
                let t = if len2 > 0.0 {
                    ((center - *a).dot(ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (center - (*a + ab * t)).length_squared() <= (radius + r) * (radius + r)
            }
            Quick::Other => return None,
        })
    }

    /// Bits of the balls `0..n` of `b` (radii grown by `margin`) this obstacle touches, eight
    /// balls per step; `None` when parry must decide. Bits at and above `n` are garbage.
    #[inline]
    fn balls(&self, b: &BallBatch, n: usize, margin: Real) -> Option<u64> {
        /// Bits of the lanes where `touch(x, y, z, r)` holds, eight balls per step.
        #[inline(always)]
        fn lanes(b: &BallBatch, n: usize, margin: Real, touch: impl Fn(f32x8, f32x8, f32x8, f32x8) -> f32x8) -> u64 {
            let margin = f32x8::splat(margin);
            let mut hit = 0u64;
            for chunk in 0..n.div_ceil(8) {
                let o = chunk * 8;
                let m = touch(load8(&b.x, o), load8(&b.y, o), load8(&b.z, o), load8(&b.r, o) + margin);
                hit |= u64::from(m.to_bitmask()) << o;
            }
            hit
        }
        let at = |c: Vector| (f32x8::splat(c.x), f32x8::splat(c.y), f32x8::splat(c.z));
        Some(match *self {
            Quick::Cuboid(ref obb) => {
                let (cx, cy, cz) = at(obb.center);
                lanes(b, n, margin, |x, y, z, r| {
                    cuboid_gap2(x - cx, y - cy, z - cz, obb).simd_le(r * r)
                })
            }
            Quick::Ball { center, radius: rc } => {
                let (cx, cy, cz) = at(center);
                lanes(b, n, margin, |x, y, z, r| {
                    let (d2, reach2) = balls_gap2(x - cx, y - cy, z - cz, rc, r);
                    d2.simd_le(reach2)
                })
            }
            Quick::Cylinder {
                center,
                axis,
                half_height,
                radius: rc,
            } => {
                let (cx, cy, cz) = at(center);
                lanes(b, n, margin, |x, y, z, r| {
                    cylinder_gap2(x - cx, y - cy, z - cz, axis, half_height, rc).simd_le(r * r)
                })
            }
            Quick::Capsule { .. } => {
                let mut hit = 0u64;
                for j in 0..n {
                    let (c, r) = b.ball(j);
                    hit |= u64::from(self.ball(c, r + margin)?) << j;
                }
                hit
            }
            Quick::Other => return None,
        })
    }

    /// Lowers `out[j]` to the clearance of ball `j` of `b` (surface to this obstacle, less
    /// `margin`) for the balls `0..n`, eight balls per step; `false` when parry would have to
    /// measure it.
    #[inline]
    fn clearance(&self, b: &BallBatch, n: usize, margin: Real, out: &mut [Real; BallBatch::CAPACITY]) -> bool {
        /// `out[j] = min(out[j], gap(x, y, z) − r)` over the balls, eight at a time.
        #[inline(always)]
        fn lanes(
            b: &BallBatch,
            n: usize,
            margin: Real,
            out: &mut [Real; BallBatch::CAPACITY],
            gap: impl Fn(f32x8, f32x8, f32x8) -> f32x8,
        ) {
            let margin = f32x8::splat(margin);
            for chunk in 0..n.div_ceil(8) {
                let o = chunk * 8;
                let c = gap(load8(&b.x, o), load8(&b.y, o), load8(&b.z, o)) - load8(&b.r, o) - margin;
                let least = c.min(load8(out, o)).to_array();
                out[o..o + 8].copy_from_slice(&least);
            }
        }
        let at = |c: Vector| (f32x8::splat(c.x), f32x8::splat(c.y), f32x8::splat(c.z));
        match *self {
            Quick::Cuboid(ref obb) => {
                let (cx, cy, cz) = at(obb.center);
                lanes(b, n, margin, out, |x, y, z| {
                    cuboid_gap2(x - cx, y - cy, z - cz, obb).sqrt()
                });
            }
            Quick::Ball { center, radius: rc } => {
                let (cx, cy, cz) = at(center);
                lanes(b, n, margin, out, |x, y, z| {
                    let (d2, _) = balls_gap2(x - cx, y - cy, z - cz, rc, f32x8::ZERO);
                    d2.sqrt() - f32x8::splat(rc)
                });
            }
            Quick::Cylinder {
                center,
                axis,
                half_height,
                radius: rc,
            } => {
                let (cx, cy, cz) = at(center);
                lanes(b, n, margin, out, |x, y, z| {
                    cylinder_gap2(x - cx, y - cy, z - cz, axis, half_height, rc).sqrt()
                });
            }
            Quick::Capsule { a, b: tip, radius: rc } => {
                let ab = tip - a;
                let len2 = ab.length_squared();
                for (j, o) in out.iter_mut().enumerate().take(n) {
                    let (c, r) = b.ball(j);
                    let t = if len2 > 0.0 {
                        ((c - a).dot(ab) / len2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    *o = o.min((c - (a + ab * t)).length() - rc - r - margin);
                }
            }
            Quick::Other => return false,
        }
        true
    }
}

impl Obstacles for ParryScene {
    fn balls_touching(&self, balls: &BallBatch) -> u64 {
        if self.quick.len() > SCAN_LIMIT {
            return balls_one_by_one(self, balls);
        }
        let all = balls.mask();
        let n = balls.len();
        // A ball that is not finite counts as touching. The others' bounding box picks the
        // obstacles worth testing lane by lane.
        let (mut hit, lo, hi) = balls.bounds(self.margin);
        // Eight obstacles' boxes at a time against the batch's box, in index order, until
        // every ball touches something.
        self.boxes.first_overlapping(&Aabb::new(lo, hi), |i| {
            match self.quick[i].balls(balls, n, self.margin) {
                Some(m) => hit |= m & all,
                None => {
                    for j in 0..n {
                        if hit & (1 << j) == 0 {
                            let (c, r) = balls.ball(j);
                            if self.touches(i as u32, &parry3d::shape::Ball::new(r), &Pose::from_translation(c)) {
                                hit |= 1 << j;
                            }
                        }
                    }
                }
            }
            hit == all
        });
        hit
    }

    fn balls_clearance(&self, balls: &BallBatch, max: Real, out: &mut [Real; BallBatch::CAPACITY]) -> bool {
        let n = balls.len();
        out.fill(max);
        let (mut lo, mut hi) = (Vector::splat(Real::MAX), Vector::splat(Real::MIN));
        for j in 0..n {
            let (c, r) = balls.ball(j);
            let reach = r + self.margin + max.max(0.0);
            if !(c.is_finite() && reach.is_finite()) {
                return false;
            }
            lo = lo.min(c - Vector::splat(reach));
            hi = hi.max(c + Vector::splat(reach));
        }
        if n == 0 {
            return true;
        }
        // Only obstacles whose box meets the balls' box grown by `max` can come nearer.
        if self.quick.len() <= SCAN_LIMIT {
            self.boxes
                .first_overlapping(&Aabb::new(lo, hi), |i| {
                    !self.quick[i].clearance(balls, n, self.margin, out)
                })
                .is_none()
        } else {
            self.bvh
                .intersect_aabb(&Aabb::new(lo, hi))
                .all(|i| self.quick[i as usize].clearance(balls, n, self.margin, out))
        }
    }

    fn first_hit(&self, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleId> {
        if self.obstacles.is_empty() {
            return None;
        }
        if self.quick.len() <= SCAN_LIMIT && self.margin == 0.0 && pose.is_finite() {
            return self.scan_first_hit(shape, pose).map(|i| ObstacleId(i as u32));
        }
        let query_box = shape.compute_aabb(pose).loosened(self.margin);
        self.bvh
            .intersect_aabb(&query_box)
            .find(|&i| self.touches(i, shape, pose))
            .map(ObstacleId)
    }

    fn ball_hits(&self, center: Vector, radius: Real) -> bool {
        let r = radius + self.margin;
        if !(center.is_finite() && r.is_finite()) {
            return true;
        }
        if self.quick.len() <= SCAN_LIMIT {
            return self.scan_ball(center, radius).is_some();
        }
        let query_box = Aabb::new(center - Vector::splat(r), center + Vector::splat(r));
        self.bvh.intersect_aabb(&query_box).any(|i| {
            self.quick[i as usize]
                .ball(center, r)
                .unwrap_or_else(|| self.touches(i, &parry3d::shape::Ball::new(radius), &Pose::from_translation(center)))
        })
    }

    fn distance(&self, shape: &dyn Shape, pose: &Pose, max_dist: Real) -> Option<(Real, ObstacleId)> {
        if self.obstacles.is_empty() {
            return None;
        }
        nearest_leaf(&self.bvh, &shape.compute_aabb(pose), max_dist, |i| {
            let o = &self.obstacles[i as usize];
            Some(query::distance(pose, shape, &o.pose, &*o.shape).map_or(0.0, |d| d.distance))
        })
    }

    fn cast_ray(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<(Real, ObstacleId)> {
        if self.obstacles.is_empty() || !origin.is_finite() || !dir.is_finite() || dir == Vector::ZERO {
            return None;
        }
        if max_toi.is_nan() || max_toi < 0.0 {
            return None;
        }
        let ray = Ray::new(origin, dir);
        // `find_best` keeps strictly smaller costs: nudge the bound so a hit exactly at
        // `max_toi` counts.
        let bound = max_toi.next_up();
        self.bvh
            .cast_ray(&ray, bound, |i, best| {
                let o = &self.obstacles[i as usize];
                o.shape.cast_ray(&o.pose, &ray, best.min(max_toi), true)
            })
            .map(|(i, t)| (t, ObstacleId(i)))
    }

    fn aabb(&self) -> Option<Aabb> {
        self.bounds
    }

    fn contact(&self, id: ObstacleId, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleContact> {
        let o = self.obstacles.get(id.index())?;
        shape_contact(shape, pose, &*o.shape, &o.pose, self.margin)
    }

    fn name(&self, id: ObstacleId) -> Option<&str> {
        self.get(id).map(|o| o.name.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::super::gjk::Convex;
    use super::super::gjk::tests::{case, distance_bounds, parry_depth, parry_shape, project};
    use super::shapes_touch;
    use nalgebra::Vector3;
    use parry3d::math::{Pose, Vector};
    use parry3d::shape::{Ball, Shape};
    use proptest::prelude::*;

    /// A robot part of the property test: a box or a cylinder, or a ball (centre, radius).
    enum Part {
        Convex(Convex),
        Ball(Vector3<f64>, f64),
    }

    /// Kind 0 a box, 1 a cylinder, 2 a ball of radius `d[0]`, in the terms of [`case`].
    fn part(kind: u8, c: [f64; 3], axis: [f64; 3], angle: f64, d: [f64; 3]) -> Part {
        if kind == 2 {
            // As the parry ball is built: f32 centre and radius.
            let c = Vector3::from(c.map(|x| f64::from(x as f32)));
            Part::Ball(c, f64::from(d[0] as f32))
        } else {
            Part::Convex(case(kind == 0, c, axis, angle, d))
        }
    }

    fn parry_of(p: &Part) -> (Box<dyn Shape>, Pose) {
        match p {
            Part::Convex(c) => parry_shape(c),
            Part::Ball(c, r) => (
                Box::new(Ball::new(*r as f32)),
                Pose::from_translation(Vector::new(c.x as f32, c.y as f32, c.z as f32)),
            ),
        }
    }

    /// (certainly apart, certainly overlapping): apart by more than 0.1 mm, or overlapping
    /// by more than 0.1 mm (a ball) or a millimetre by parry's depth (two convex parts, whose
    /// reference bounds only say "within 50 nm of a common point").
    fn reference(a: &Part, b: &Part) -> (bool, bool) {
        let ball_gap = |c: &Vector3<f64>, r: f64, other: &Part| match other {
            Part::Convex(s) => (project(s, *c) - c).norm() - r,
            Part::Ball(c2, r2) => (c2 - c).norm() - r - r2,
        };
        let gap = match (a, b) {
            (Part::Ball(c, r), other) | (other, Part::Ball(c, r)) => ball_gap(c, *r, other),
            (Part::Convex(x), Part::Convex(y)) => {
                let (lower, upper) = distance_bounds(x, y);
                if lower > 1e-4 {
                    return (true, false);
                }
                return (false, upper < 5e-8 && parry_depth(x, y) > 1e-3);
            }
        };
        // A ball whose centre lies inside the other part is at least its radius deep.
        (gap > 1e-4, gap < -1e-4)
    }

    fn touch_both(a: &Part, b: &Part) -> (bool, bool) {
        let ((sa, pa), (sb, pb)) = (parry_of(a), parry_of(b));
        (
            shapes_touch(sa.as_ref(), &pa, sb.as_ref(), &pb),
            shapes_touch(sb.as_ref(), &pb, sa.as_ref(), &pa),
        )
    }

    #[test]
    fn plain_pairs() {
        let id = [0.0; 3];
        let boxed = |x: f64| part(0, [x, 0.0, 0.0], id, 0.0, [0.1; 3]);
        // A cylinder along y at the origin, and one along z centred at `x`.
        let upright = || part(1, [0.0; 3], id, 0.0, [0.2, 0.05, 0.0]);
        let crossed = |x: f64| {
            part(
                1,
                [x, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                std::f64::consts::FRAC_PI_2,
                [0.2, 0.05, 0.0],
            )
        };
        let ball = |y: f64| part(2, [0.0, y, 0.0], id, 0.0, [0.01; 3]);
        let cases = [
            // Two boxes 5 cm apart along x, then overlapping by 5 cm.
            (boxed(0.0), boxed(0.25), false),
            (boxed(0.0), boxed(0.15), true),
            // A cylinder standing 1 cm off a box's face, then through it.
            (upright(), boxed(0.16), false),
            (upright(), boxed(0.14), true),
            // A ball near a cylinder's rim, outside and inside.
            (ball(0.22), upright(), false),
            (ball(0.205), upright(), true),
            // Two crossed cylinders 1 mm apart, then 3 mm into each other.
            (upright(), crossed(0.101), false),
            (upright(), crossed(0.097), true),
        ];
        for (i, (a, b, touching)) in cases.iter().enumerate() {
            assert_eq!(reference(a, b), (!touching, *touching), "reference of case {i}");
            assert_eq!(touch_both(a, b), (*touching, *touching), "case {i}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]

        /// Never a contact between parts surely 0.1 mm apart, always one between parts
        /// surely overlapping, for every pair of a box, a cylinder and a ball, both ways round.
        #[test]
        fn agrees_with_the_reference(
            ka in 0u8..3, kb in 0u8..3,
            ca in prop::array::uniform3(-0.3..0.3f64), cb in prop::array::uniform3(-0.3..0.3f64),
            ra in prop::array::uniform3(-1.0..1.0f64), rb in prop::array::uniform3(-1.0..1.0f64),
            aa in -3.2..3.2f64, ab in -3.2..3.2f64,
            da in prop::array::uniform3(0.005..0.25f64), db in prop::array::uniform3(0.005..0.25f64),
        ) {
            let (a, b) = (part(ka, ca, ra, aa, da), part(kb, cb, rb, ab, db));
            let (apart, overlapping) = reference(&a, &b);
            let (ab_touch, ba_touch) = touch_both(&a, &b);
            if apart {
                prop_assert!(!ab_touch && !ba_touch, "apart, yet touching ({}, {})", ab_touch, ba_touch);
            }
            if overlapping {
                prop_assert!(ab_touch && ba_touch, "overlapping, yet apart ({}, {})", ab_touch, ba_touch);
            }
        }
    }
}
