//! [`RayScene`]: ray casting against every visual shape of the live world with parry, shared by
//! the ray-cast camera and the LiDARs.
//!
//! Shapes are parry shapes (cuboids, balls, cylinders, capsules, triangle meshes) in two BVHs:
//! one over the shapes that have not moved recently (rebuilt only when a shape starts moving)
//! and a small one over the movers (rebuilt every update), so a robot driving through a home
//! costs a few microseconds per update, not a full rebuild. Casts take `&self` and run in
//! parallel.

use parry3d::math::{Matrix, Pose, Real, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::{Capsule, TriMesh};

use super::visuals::{VisualScene, VisualShape};
use crate::world::World;
use bvh::{Bounds, FlatBvh};
use hearth_kinematics::to_pose;

mod bvh;
mod camera;

pub use camera::RaycastCamera;

/// A ray's first hit.
///
/// ```
/// # use hearth_sim::sensors::{RayScene, VisualScene};
/// # use hearth_sim::world::{World, WorldConfig};
/// # use nalgebra::Isometry3;
/// # use parry3d::math::Vector;
/// # let mut world = World::new(WorldConfig::default()).unwrap();
/// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
/// # let visuals = VisualScene::from_world(&world);
/// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
/// let mut rays = RayScene::new(&visuals);
/// rays.update(&visuals, &world);
/// let hit = rays.cast(Vector::new(0.0, 0.0, 0.5), Vector::new(1.0, 0.0, 0.0), 10.0).unwrap();
/// assert_eq!(hit.item, 1);
/// assert!((hit.toi - 2.9).abs() < 1e-4 && (hit.normal.x + 1.0).abs() < 1e-4);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the (unit) ray, m.
    pub toi: f32,
    /// World-frame unit normal at the hit, facing the ray's origin.
    pub normal: Vector,
    /// Index of the item hit (into [`VisualScene::items`]).
    pub item: u32,
}

/// A shape in its item's frame, in the form the ray tests want.
#[derive(Clone, Debug)]
enum Prim {
    Box {
        half: Vector,
    },
    Sphere {
        radius: f32,
    },
    /// Along z.
    Cylinder {
        radius: f32,
        half_length: f32,
    },
    /// Along z.
    Capsule(Capsule),
    Mesh(Box<TriMesh>),
    /// Seen as nothing (a mesh without triangles).
    Empty,
}

impl Prim {
    fn of(shape: &VisualShape) -> Self {
        match shape {
            VisualShape::Box { half } => Prim::Box {
                half: Vector::from(*half),
            },
            VisualShape::Sphere { radius } => Prim::Sphere { radius: *radius },
            VisualShape::Cylinder { radius, half_length } => Prim::Cylinder {
                radius: *radius,
                half_length: *half_length,
            },
            VisualShape::Capsule { radius, half_length } => Prim::Capsule(Capsule::new_z(*half_length, *radius)),
            VisualShape::Mesh(mesh) => {
                let vertices: Vec<Vector> = mesh.vertices.iter().map(|v| Vector::from(*v)).collect();
                match TriMesh::new(vertices, mesh.triangles.clone()) {
                    Ok(t) => Prim::Mesh(Box::new(t)),
                    Err(_) => Prim::Empty,
                }
            }
        }
    }

    /// Bounding box in the item frame.
    fn local_bounds(&self) -> Bounds {
        let half = match self {
            Prim::Box { half } => *half,
            Prim::Sphere { radius } => Vector::splat(*radius),
            Prim::Cylinder { radius, half_length } => Vector::new(*radius, *radius, *half_length),
            Prim::Capsule(c) => Vector::new(c.radius, c.radius, c.half_height() + c.radius),
            Prim::Mesh(m) => {
                let aabb = m.local_aabb();
                return Bounds {
                    min: aabb.mins,
                    max: aabb.maxs,
                };
            }
            Prim::Empty => Vector::ZERO,
        };
        Bounds { min: -half, max: half }
    }

    /// Entry hit of a local ray (`o`, unit `d`) before `limit`: distance and local outward
    /// normal. Rays starting inside the shape see nothing of it.
    #[inline]
    fn cast(&self, o: Vector, d: Vector, limit: f32) -> Option<(f32, Vector)> {
        match self {
            Prim::Box { half } => {
                let inv = Vector::ONE / d;
                let t1 = (-*half - o) * inv;
                let t2 = (*half - o) * inv;
                let tmin = t1.min(t2);
                let tmax = t1.max(t2);
                let near = tmin.max_element();
                let far = tmax.min_element();
                if near > far || near <= 0.0 || near >= limit {
                    return None;
                }
                let axis = if near == tmin.x {
                    0
                } else if near == tmin.y {
                    1
                } else {
                    2
                };
                let mut n = Vector::ZERO;
                n[axis] = -d[axis].signum();
                Some((near, n))
            }
            Prim::Sphere { radius } => {
                let b = o.dot(d);
                let c = o.length_squared() - radius * radius;
                if c <= 0.0 {
                    return None;
                }
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let t = -b - disc.sqrt();
                (t > 0.0 && t < limit).then(|| (t, (o + d * t) / *radius))
            }
            Prim::Cylinder { radius, half_length } => {
                let (r, h) = (*radius, *half_length);
                let r2 = r * r;
                if o.z.abs() <= h && o.x * o.x + o.y * o.y <= r2 {
                    return None;
                }
                let mut best: Option<(f32, Vector)> = None;
                let a = d.x * d.x + d.y * d.y;
                if a > 1e-12 {
                    let b = o.x * d.x + o.y * d.y;
                    let c = o.x * o.x + o.y * o.y - r2;
                    let disc = b * b - a * c;
                    if disc >= 0.0 {
                        let t = (-b - disc.sqrt()) / a;
                        let z = o.z + d.z * t;
                        if t > 0.0 && t < limit && z.abs() <= h {
                            let p = o + d * t;
                            best = Some((t, Vector::new(p.x / r, p.y / r, 0.0)));
                        }
                    }
                }
                if d.z.abs() > 1e-12 {
                    let cap = if d.z > 0.0 { -h } else { h };
                    let t = (cap - o.z) / d.z;
                    let p = o + d * t;
                    if t > 0.0 && t < best.map_or(limit, |b| b.0) && p.x * p.x + p.y * p.y <= r2 {
                        best = Some((t, Vector::new(0.0, 0.0, cap.signum())));
                    }
                }
                best
            }
            Prim::Capsule(c) => local_parry(c, o, d, limit),
            Prim::Mesh(m) => local_parry(m.as_ref(), o, d, limit),
            Prim::Empty => None,
        }
    }
}

/// Entry hit through parry's local ray cast, culling hits from inside and back faces.
fn local_parry(shape: &impl RayCast, o: Vector, d: Vector, limit: f32) -> Option<(f32, Vector)> {
    let hit = shape.cast_local_ray_and_get_normal(&Ray::new(o, d), limit, false)?;
    (hit.time_of_impact > 0.0 && hit.normal.dot(d) < 0.0).then_some((hit.time_of_impact, hit.normal))
}

/// The visual shapes of a world, posed, in BVHs for ray casting.
///
/// ```
/// use hearth_sim::sensors::{RayScene, VisualScene};
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::Isometry3;
/// use parry3d::math::Vector;
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), false).unwrap();
/// let visuals = VisualScene::from_world(&world);
/// let mut rays = RayScene::new(&visuals);
/// rays.update(&visuals, &world);
/// let hit = rays.cast(Vector::new(0.0, 0.0, 0.5), Vector::new(1.0, 0.0, 0.0), 10.0).unwrap();
/// assert!((hit.toi - 2.9).abs() < 1e-4);
/// assert!((hit.normal.x + 1.0).abs() < 1e-4);
/// ```
pub struct RayScene {
    prims: Vec<Prim>,
    /// Per item: world pose now.
    poses: Vec<Pose>,
    /// Per item: world-to-item rotation matrix and the item's world position.
    to_local: Vec<(Matrix, Vector)>,
    /// Per item: world bounding box now.
    bounds: Vec<Bounds>,
    /// Per item: world pose at the previous update.
    prev_poses: Vec<Pose>,
    /// Per item: whether it is in the movers' BVH.
    moving: Vec<bool>,
    rest: FlatBvh,
    movers: FlatBvh,
    mover_items: Vec<u32>,
    /// Reused buffer of item poses.
    item_poses: Vec<nalgebra::Isometry3<f64>>,
    updates: u64,
}

impl std::fmt::Debug for RayScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RayScene")
            .field("items", &self.prims.len())
            .field("movers", &self.mover_items.len())
            .finish_non_exhaustive()
    }
}

/// World bounding box of a local box under `pose`.
fn world_bounds(local: &Bounds, pose: &Pose) -> Bounds {
    let c = pose.transform_point((local.min + local.max) * 0.5);
    let h = (local.max - local.min) * 0.5;
    let m = Matrix::from_quat(pose.rotation);
    let abs = Matrix::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
    let e = abs * h;
    Bounds { min: c - e, max: c + e }
}

impl RayScene {
    /// Shapes for every item of `scene` (call [`RayScene::update`] before casting).
    ///
    /// ```
    /// use hearth_sim::sensors::{RayScene, VisualScene};
    /// let rays = RayScene::new(&VisualScene::default());
    /// assert!(rays.is_empty());
    /// ```
    pub fn new(scene: &VisualScene) -> Self {
        let prims: Vec<Prim> = scene.items.iter().map(|i| Prim::of(&i.shape)).collect();
        let n = prims.len();
        Self {
            prims,
            poses: vec![Pose::IDENTITY; n],
            to_local: vec![(Matrix::IDENTITY, Vector::ZERO); n],
            bounds: vec![Bounds::EMPTY; n],
            prev_poses: vec![Pose::IDENTITY; n],
            moving: vec![false; n],
            rest: FlatBvh::default(),
            movers: FlatBvh::default(),
            mover_items: Vec::new(),
            item_poses: Vec::with_capacity(n),
            updates: 0,
        }
    }

    /// Number of shapes.
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// assert_eq!(rays.len(), visuals.items.len());
    /// assert_eq!(rays.len(), 2);
    /// ```
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// Whether the scene has no shapes.
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// assert!(!rays.is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// Reads every shape's pose from `world` (the previous poses are kept for flow) and brings
    /// the BVHs up to date. `scene` must be the one this was built from.
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// world.set_body_pose(wall, &Isometry3::translation(5.0, 0.0, 1.0)).unwrap();
    /// rays.update(&visuals, &world);
    /// let hit = rays.cast(Vector::new(0.0, 0.0, 0.5), Vector::X, 10.0).unwrap();
    /// assert!((hit.toi - 4.9).abs() < 1e-4);
    /// ```
    pub fn update(&mut self, scene: &VisualScene, world: &World) {
        let mut item_poses = std::mem::take(&mut self.item_poses);
        scene.world_poses_into(world, &mut item_poses);
        self.update_from_poses(&item_poses);
        self.item_poses = item_poses;
    }

    /// [`RayScene::update`] from item world poses (one per item).
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// let mut poses = visuals.world_poses(&world);
    /// poses[1] = Isometry3::translation(1.0, 0.0, 1.0);
    /// rays.update_from_poses(&poses);
    /// let hit = rays.cast(Vector::new(0.0, 0.0, 0.5), Vector::X, 10.0).unwrap();
    /// assert!((hit.toi - 0.9).abs() < 1e-4);
    /// ```
    pub fn update_from_poses(&mut self, item_poses: &[nalgebra::Isometry3<f64>]) {
        let first = self.updates == 0;
        self.updates += 1;
        std::mem::swap(&mut self.poses, &mut self.prev_poses);
        let mut new_mover = false;
        for (i, p) in item_poses.iter().enumerate().take(self.prims.len()) {
            let pose = to_pose(p);
            if first || pose != self.prev_poses[i] {
                self.bounds[i] = world_bounds(&self.prims[i].local_bounds(), &pose);
                self.to_local[i] = (Matrix::from_quat(pose.rotation).transpose(), pose.translation);
            }
            self.poses[i] = pose;
            if first {
                self.prev_poses[i] = pose;
            } else if !self.moving[i] && pose != self.prev_poses[i] {
                self.moving[i] = true;
                new_mover = true;
            }
        }
        if first || new_mover {
            let rest: Vec<u32> = (0..self.prims.len() as u32)
                .filter(|&i| !self.moving[i as usize])
                .collect();
            self.mover_items = (0..self.prims.len() as u32)
                .filter(|&i| self.moving[i as usize])
                .collect();
            self.rest = FlatBvh::build(&rest, &self.bounds);
        }
        // The movers' tree is rebuilt every update: reuse its buffers.
        self.movers.rebuild(&self.mover_items, &self.bounds);
    }

    /// World pose of item `item`'s shape now.
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// assert!((rays.pose(1).translation.x - 3.0).abs() < 1e-6);
    /// ```
    pub fn pose(&self, item: u32) -> &Pose {
        &self.poses[item as usize]
    }

    /// World pose of item `item`'s shape at the previous update (the current pose on the first).
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// let mut poses = visuals.world_poses(&world);
    /// poses[1] = Isometry3::translation(4.0, 0.0, 1.0);
    /// rays.update_from_poses(&poses);
    /// assert!((rays.prev_pose(1).translation.x - 3.0).abs() < 1e-6);
    /// assert!((rays.pose(1).translation.x - 4.0).abs() < 1e-6);
    /// ```
    pub fn prev_pose(&self, item: u32) -> &Pose {
        &self.prev_poses[item as usize]
    }

    /// First hit of the ray from `origin` along the unit vector `dir` within `max_toi`.
    /// Shapes that contain the origin are not seen (as back faces are culled by a rasteriser).
    ///
    /// ```
    /// # use hearth_sim::sensors::{RayScene, VisualScene};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// # use parry3d::math::Vector;
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let wall = world.add_box("wall", [0.1, 2.0, 1.0], &Isometry3::translation(3.0, 0.0, 1.0), true).unwrap();
    /// # let visuals = VisualScene::from_world(&world);
    /// // `rays` holds the ground (item 0) and a wall (item 1) whose face is 2.9 m ahead.
    /// let mut rays = RayScene::new(&visuals);
    /// rays.update(&visuals, &world);
    /// let origin = Vector::new(0.0, 0.0, 0.5);
    /// assert!(rays.cast(origin, Vector::X, 2.0).is_none()); // the wall is beyond 2 m
    /// assert!(rays.cast(origin, Vector::NEG_X, 10.0).is_none()); // nothing behind
    /// assert_eq!(rays.cast(origin, Vector::NEG_Z, 10.0).unwrap().item, 0); // the ground below
    /// ```
    pub fn cast(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<RayHit> {
        let inv = Vector::ONE / dir;
        let mut best: Option<(f32, u32)> = None;
        for bvh in [&self.rest, &self.movers] {
            let limit = best.map_or(max_toi, |b| b.0);
            let hit = bvh.cast(origin, inv, limit, |item, best_so_far| {
                let (r, t) = &self.to_local[item as usize];
                let o = *r * (origin - *t);
                let d = *r * dir;
                self.prims[item as usize].cast(o, d, best_so_far).map(|(toi, _)| toi)
            });
            if hit.is_some() {
                best = hit;
            }
        }
        // The normal of the winning item only (one more primitive test per ray).
        let (toi, item) = best?;
        let (r, t) = &self.to_local[item as usize];
        let (_, n) = self.prims[item as usize].cast(*r * (origin - *t), *r * dir, toi * 1.0001 + 1e-6)?;
        Some(RayHit {
            toi,
            normal: r.transpose() * n,
            item,
        })
    }
}
