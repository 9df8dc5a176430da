//! [`WorldObstacles`]: the live world as planning's [`Obstacles`], queried through rapier's
//! own query pipeline (its broad-phase BVH and collider set), without copying.

use std::sync::Arc;

use hearth_planning::obstacles::{
    Obstacle, ObstacleContact, ObstacleId, Obstacles, ParryScene, nearest_leaf, shape_contact,
};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Real, Vector};
use parry3d::query::{DefaultQueryDispatcher, QueryDispatcher, Ray};
use parry3d::shape::Shape;
use rapier3d::prelude::{
    BroadPhaseBvh, Collider, ColliderHandle, ColliderSet, QueryFilter, QueryPipeline, RigidBodyHandle, RigidBodySet,
};

use super::error::WorldResult;
use super::physics::{BodyId, World};
use super::spawn::ModelHandle;

/// A read-only view of the world's colliders for planners, excluding some bodies (the
/// planning robot's own links, whatever its gripper holds).
///
/// [`ObstacleId`]s are rapier collider indices; [`Obstacles::name`] gives the body name
/// (`ground`, `MODEL/LINK`, …).
///
/// The view shares the world's collider set, body set and broad-phase BVH (reference-counted,
/// no copy), so it is `'static + Send + Sync` and fits `Arc<dyn Obstacles>` for planner
/// threads. It answers for the state at the moment it was taken: if the world steps while a
/// view is alive, the world copies those sets before changing them (copy on write) and the
/// view keeps its consistent picture; take a new view to see the new state.
///
/// **Margin.** With [`WorldObstacles::with_margin`]`(m)`, `intersects` / `first_hit` report a
/// hit when the exact distance is `≤ m`; `distance` and `cast_ray` are exact.
///
/// ```
/// use hearth_sim::world::{World, WorldConfig};
/// use hearth_sim::planning::obstacles::Obstacles;
/// use nalgebra::Isometry3;
/// use parry3d::math::Pose;
/// use parry3d::shape::Ball;
///
/// let mut world = World::new(WorldConfig { ground_plane: false, ..WorldConfig::default() })?;
/// world.add_box("table", [0.5, 0.5, 0.05], &Isometry3::translation(1.0, 0.0, 0.5), false)?;
/// let view = world.obstacles_view(&[])?;
/// let probe = Ball::new(0.05);
/// assert!(view.intersects(&probe, &Pose::translation(1.0, 0.0, 0.58)));
/// assert!(!view.intersects(&probe, &Pose::translation(1.0, 0.0, 0.7)));
/// let (d, id) = view.distance(&probe, &Pose::translation(1.0, 0.0, 0.7), 1.0).unwrap();
/// assert!((d - 0.1).abs() < 1e-4);
/// assert_eq!(view.name(id), Some("table"));
/// # Ok::<(), hearth_sim::world::WorldError>(())
/// ```
#[derive(Clone)]
pub struct WorldObstacles {
    bodies: Arc<RigidBodySet>,
    colliders: Arc<ColliderSet>,
    broad_phase: Arc<BroadPhaseBvh>,
    names: Arc<Vec<String>>,
    /// Excluded bodies, sorted by raw handle parts.
    excluded: Vec<(u32, u32)>,
    margin: Real,
}

impl std::fmt::Debug for WorldObstacles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldObstacles")
            .field("colliders", &self.colliders.len())
            .field("excluded_bodies", &self.excluded.len())
            .field("margin", &self.margin)
            .finish()
    }
}

impl World {
    /// A collision view of the live world that ignores the bodies of the `exclude` models.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`] for a handle that names no model.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::planning::obstacles::Obstacles;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// # use parry3d::{math::Pose, shape::Ball};
    /// let mut world = World::new(WorldConfig { ground_plane: false, ..WorldConfig::default() })?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let probe = (Ball::new(0.05), Pose::translation(0.0, 0.0, 0.1));
    /// assert!(world.obstacles_view(&[])?.intersects(&probe.0, &probe.1));
    /// assert!(!world.obstacles_view(&[arm])?.intersects(&probe.0, &probe.1));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn obstacles_view(&self, exclude: &[ModelHandle]) -> WorldResult<WorldObstacles> {
        let mut excluded = Vec::new();
        for &m in exclude {
            excluded.extend(self.entry(m)?.bodies.iter().map(|h| h.into_raw_parts()));
        }
        excluded.sort_unstable();
        excluded.dedup();
        let s = &self.state;
        Ok(WorldObstacles {
            bodies: Arc::clone(&s.bodies),
            colliders: Arc::clone(&s.colliders),
            broad_phase: Arc::clone(&s.broad_phase),
            names: Arc::clone(&s.names),
            excluded,
            margin: 0.0,
        })
    }
}

impl WorldObstacles {
    /// Also ignores these bodies (e.g. the object held by the gripper).
    ///
    /// ```
    /// # use hearth_sim::planning::obstacles::Obstacles;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use parry3d::{math::Pose, shape::Ball};
    /// let mut world = World::new(WorldConfig { ground_plane: false, ..WorldConfig::default() })?;
    /// let held = world.add_box("mug", [0.05; 3], &nalgebra::Isometry3::translation(0.0, 0.0, 1.0), true)?;
    /// let view = world.obstacles_view(&[])?.excluding_bodies(&[held]);
    /// assert!(!view.intersects(&Ball::new(0.02), &Pose::translation(0.0, 0.0, 1.0)));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn excluding_bodies(mut self, bodies: &[BodyId]) -> Self {
        self.excluded.extend(bodies.iter().map(|b| b.0.into_raw_parts()));
        self.excluded.sort_unstable();
        self.excluded.dedup();
        self
    }

    /// Sets the collision margin. Negative or non-finite values count as 0.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert_eq!(world.obstacles_view(&[]).unwrap().with_margin(0.02).margin(), 0.02);
    /// assert_eq!(world.obstacles_view(&[]).unwrap().with_margin(-1.0).margin(), 0.0);
    /// ```
    pub fn with_margin(mut self, margin: Real) -> Self {
        self.margin = if margin.is_finite() && margin > 0.0 {
            margin
        } else {
            0.0
        };
        self
    }

    /// The view's obstacles copied into a static [`ParryScene`]: the same colliders at their
    /// poses now (shapes shared, not copied), compound shapes split into their parts, each
    /// named after its collider, and the same margin. It answers as the view does, faster for
    /// planning: a robot's ball broad phase and the exact tests of its links meet the parts
    /// one by one through the scene's closed forms (boxes, balls, cylinders, capsules) instead
    /// of rapier's query pipeline and GJK. A Fetch arm's state checks over a table take about
    /// half the time. The copy does not follow the world: make a new one after the world moves.
    ///
    /// ```
    /// # use hearth_sim::planning::obstacles::Obstacles;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use parry3d::{math::Pose, shape::Ball};
    /// let mut world = World::new(WorldConfig { ground_plane: false, ..WorldConfig::default() })?;
    /// world.add_box("crate", [0.2; 3], &nalgebra::Isometry3::translation(1.0, 0.0, 0.2), false)?;
    /// let view = world.obstacles_view(&[])?.with_margin(0.01);
    /// let scene = view.to_scene();
    /// assert_eq!((scene.len(), scene.margin()), (1, 0.01));
    /// for x in [0.5, 0.75, 1.0] {
    ///     let probe = (Ball::new(0.05), Pose::translation(x, 0.0, 0.2));
    ///     assert_eq!(scene.intersects(&probe.0, &probe.1), view.intersects(&probe.0, &probe.1));
    /// }
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn to_scene(&self) -> ParryScene {
        let obstacles = self
            .colliders
            .iter()
            .filter(|(_, co)| self.keeps(co))
            .flat_map(|(_, co)| {
                let name = self.names.get(co.user_data as usize).cloned().unwrap_or_default();
                let pose = *co.position();
                match co.shape().as_compound() {
                    Some(c) => c
                        .shapes()
                        .iter()
                        .map(|(part_pose, part)| Obstacle::new(name.clone(), part.clone(), pose * *part_pose))
                        .collect::<Vec<_>>(),
                    None => vec![Obstacle::new(name, co.shared_shape().clone(), pose)],
                }
            })
            .collect();
        ParryScene::new(obstacles).with_margin(self.margin)
    }

    /// The collision margin applied by `intersects` / `first_hit`.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert_eq!(world.obstacles_view(&[]).unwrap().margin(), 0.0);
    /// ```
    pub fn margin(&self) -> Real {
        self.margin
    }

    fn is_excluded(&self, body: Option<RigidBodyHandle>) -> bool {
        body.is_some_and(|b| self.excluded.binary_search(&b.into_raw_parts()).is_ok())
    }

    /// The dispatcher rapier's narrow phase uses by default.
    fn dispatcher(&self) -> &'static dyn QueryDispatcher {
        &DefaultQueryDispatcher
    }

    /// Runs `f` with rapier's query pipeline over this view (exclusions as a filter).
    fn with_pipeline<T>(&self, f: impl FnOnce(&QueryPipeline<'_>) -> T) -> T {
        let keep = |_: ColliderHandle, co: &Collider| !self.is_excluded(co.parent());
        let filter = QueryFilter::default().exclude_sensors().predicate(&keep);
        let pipeline = self
            .broad_phase
            .as_query_pipeline(self.dispatcher(), &self.bodies, &self.colliders, filter);
        f(&pipeline)
    }

    /// Whether a collider counts as an obstacle of this view: enabled, solid and not excluded.
    fn keeps(&self, co: &Collider) -> bool {
        co.is_enabled() && !co.is_sensor() && !self.is_excluded(co.parent())
    }

    /// The collider behind a BVH leaf, if it passes the exclusions.
    fn candidate(&self, leaf: u32) -> Option<&Collider> {
        let (co, _) = self.colliders.get_unknown_gen(leaf)?;
        self.keeps(co).then_some(co)
    }

    fn touches(&self, co: &Collider, shape: &dyn Shape, pose: &Pose) -> bool {
        let pos12 = pose.inv_mul(co.position());
        // The broad phase's boxes are loosened by rapier's prediction distance, so first the
        // exact boxes in the collider's frame: apart, they cannot touch, and GJK is not asked
        // about a small shape near a huge one (the ground), where f32 rounding can report
        // contact centimetres away.
        let near = shape
            .compute_aabb(&pos12.inverse())
            .loosened(self.margin)
            .intersects(&co.shape().compute_local_aabb());
        if !near {
            return false;
        }
        let d = self.dispatcher();
        if self.margin > 0.0 {
            return d
                .distance(&pos12, shape, co.shape())
                .map_or(true, |dist| dist.distance <= self.margin);
        }
        match d.intersection_test(&pos12, shape, co.shape()) {
            Ok(hit) => hit.intersecting,
            Err(_) => d
                .distance(&pos12, shape, co.shape())
                .map_or(true, |dist| dist.distance <= 0.0),
        }
    }
}

impl Obstacles for WorldObstacles {
    fn first_hit(&self, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleId> {
        let query = shape.compute_aabb(pose).loosened(self.margin);
        self.with_pipeline(|qp| {
            qp.bvh
                .intersect_aabb(&query)
                .find(|&leaf| self.candidate(leaf).is_some_and(|co| self.touches(co, shape, pose)))
                .map(ObstacleId)
        })
    }

    fn distance(&self, shape: &dyn Shape, pose: &Pose, max_dist: Real) -> Option<(Real, ObstacleId)> {
        let query = shape.compute_aabb(pose);
        self.with_pipeline(|qp| {
            nearest_leaf(qp.bvh, &query, max_dist, |leaf| {
                let co = self.candidate(leaf)?;
                let pos12 = pose.inv_mul(co.position());
                Some(
                    self.dispatcher()
                        .distance(&pos12, shape, co.shape())
                        .map_or(0.0, |dist| dist.distance),
                )
            })
        })
    }

    fn cast_ray(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<(Real, ObstacleId)> {
        if !origin.is_finite() || !dir.is_finite() || dir == Vector::ZERO || max_toi.is_nan() || max_toi < 0.0 {
            return None;
        }
        let ray = Ray::new(origin, dir);
        self.with_pipeline(|qp| qp.cast_ray(&ray, max_toi, true))
            .map(|(h, t)| (t, ObstacleId(h.into_raw_parts().0)))
    }

    fn aabb(&self) -> Option<Aabb> {
        self.colliders
            .iter()
            .filter(|(_, co)| self.keeps(co))
            .map(|(_, co)| co.compute_aabb())
            .reduce(|a, b| a.merged(&b))
    }

    fn contact(&self, id: ObstacleId, shape: &dyn Shape, pose: &Pose) -> Option<ObstacleContact> {
        let co = self.candidate(id.0)?;
        shape_contact(shape, pose, co.shape(), co.position(), self.margin)
    }

    fn name(&self, id: ObstacleId) -> Option<&str> {
        let (co, _) = self.colliders.get_unknown_gen(id.0)?;
        self.names.get(co.user_data as usize).map(String::as_str)
    }
}
