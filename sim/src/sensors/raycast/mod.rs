//! [`RayScene`]: ray casting against every visual shape of the live world with parry, shared by
//! the ray-cast camera and the LiDARs.
//!
//! Shapes are parry shapes (cuboids, balls, cylinders, capsules, triangle meshes) in two BVHs:
//! one over the shapes that have not moved recently (rebuilt only when a shape starts moving)
//! and a small one over the movers (rebuilt every update), so a robot driving through a home
//! costs a few microseconds per update, not a full rebuild. Casts take `&self` and run in
//! parallel.

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Real, Vector};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::Ray;
use parry3d::shape::{Ball, Capsule, Cuboid, Cylinder, SharedShape, TriMesh};

use super::visuals::{VisualScene, VisualShape};
use crate::world::World;
use hearth_kinematics::to_pose;


/// A ray's first hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the (unit) ray, m.
    pub toi: f32,
    /// World-frame unit normal at the hit, facing the ray's origin.
    pub normal: Vector,
    /// Index of the item hit (into [`VisualScene::items`]).
    pub item: u32,
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
    /// Per item: its parry shape and the shape's pose in the item frame.
    shapes: Vec<(SharedShape, Pose)>,
    /// Per item: world pose of the shape now.
    poses: Vec<Pose>,
    /// Per item: world pose of the shape at the previous update.
    prev_poses: Vec<Pose>,
    /// Per item: whether it is in the movers' BVH.
    moving: Vec<bool>,
    rest: Bvh,
    rest_items: Vec<u32>,
    movers: Bvh,
    mover_items: Vec<u32>,
    /// Reused buffer of item poses.
    item_poses: Vec<nalgebra::Isometry3<f64>>,
    updates: u64,
}

impl std::fmt::Debug for RayScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RayScene")
            .field("items", &self.shapes.len())
            .field("movers", &self.mover_items.len())
            .finish_non_exhaustive()
    }
}

fn parry_shape(shape: &VisualShape) -> (SharedShape, Pose) {
    // parry's cylinders and capsules run along y; visuals along z: turn y onto z.
    let y_to_z = Pose::rotation(Vector::new(std::f32::consts::FRAC_PI_2, 0.0, 0.0));
    match shape {
        VisualShape::Box { half } => (
            SharedShape::new(Cuboid::new(Vector::new(half[0], half[1], half[2]))),
            Pose::IDENTITY,
        ),
        VisualShape::Sphere { radius } => (SharedShape::new(Ball::new(*radius)), Pose::IDENTITY),
        VisualShape::Cylinder { radius, half_length } => {
            (SharedShape::new(Cylinder::new(*half_length, *radius)), y_to_z)
        }
        VisualShape::Capsule { radius, half_length } => {
            (SharedShape::new(Capsule::new_z(*half_length, *radius)), Pose::IDENTITY)
        }
        VisualShape::Mesh(mesh) => {
            let vertices: Vec<Vector> = mesh.vertices.iter().map(|v| Vector::new(v[0], v[1], v[2])).collect();
            match TriMesh::new(vertices, mesh.triangles.clone()) {
                Ok(t) => (SharedShape::new(t), Pose::IDENTITY),
                // A degenerate mesh (no triangles) is seen as nothing: a zero-size ball.
                Err(_) => (SharedShape::new(Ball::new(0.0)), Pose::IDENTITY),
            }
        }
    }
}

impl RayScene {
    /// Shapes for every item of `scene` (call [`RayScene::update`] before casting).
    pub fn new(scene: &VisualScene) -> Self {
        let shapes: Vec<(SharedShape, Pose)> = scene.items.iter().map(|i| parry_shape(&i.shape)).collect();
        let n = shapes.len();
        Self {
            shapes,
            poses: vec![Pose::IDENTITY; n],
            prev_poses: vec![Pose::IDENTITY; n],
            moving: vec![false; n],
            rest: Bvh::new(),
            rest_items: Vec::new(),
            movers: Bvh::new(),
            mover_items: Vec::new(),
            item_poses: Vec::with_capacity(n),
            updates: 0,
        }
    }

    /// Number of shapes.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// Whether the scene has no shapes.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Reads every shape's pose from `world` (the previous poses are kept for flow) and brings
    /// the BVHs up to date. `scene` must be the one this was built from.
    pub fn update(&mut self, scene: &VisualScene, world: &World) {
        let mut item_poses = std::mem::take(&mut self.item_poses);
        scene.world_poses_into(world, &mut item_poses);
        self.update_from_poses(&item_poses);
        self.item_poses = item_poses;
    }

    /// [`RayScene::update`] from item world poses (one per item).
    pub fn update_from_poses(&mut self, item_poses: &[nalgebra::Isometry3<f64>]) {
        let first = self.updates == 0;
        self.updates += 1;
        std::mem::swap(&mut self.poses, &mut self.prev_poses);
        let mut new_mover = false;
        for (i, p) in item_poses.iter().enumerate().take(self.shapes.len()) {
            let pose = to_pose(p) * self.shapes[i].1;
            self.poses[i] = pose;
            if first {
                self.prev_poses[i] = pose;
            } else if !self.moving[i] && pose != self.prev_poses[i] {
                self.moving[i] = true;
                new_mover = true;
            }
        }
        if first || new_mover {
            self.rest_items = (0..self.shapes.len() as u32).filter(|&i| !self.moving[i as usize]).collect();
            self.mover_items = (0..self.shapes.len() as u32).filter(|&i| self.moving[i as usize]).collect();
            self.rest = self.build(&self.rest_items);
        }
        self.movers = self.build(&self.mover_items);
    }

    fn build(&self, items: &[u32]) -> Bvh {
        let aabbs: Vec<Aabb> = items
            .iter()
            .map(|&i| {
                let (shape, _) = &self.shapes[i as usize];
                shape.compute_aabb(&self.poses[i as usize])
            })
            .collect();
        Bvh::from_leaves(BvhBuildStrategy::Binned, &aabbs)
    }

    /// World pose of item `item`'s shape now.
    pub fn pose(&self, item: u32) -> &Pose {
        &self.poses[item as usize]
    }

    /// World pose of item `item`'s shape at the previous update (the current pose on the first).
    pub fn prev_pose(&self, item: u32) -> &Pose {
        &self.prev_poses[item as usize]
    }

    /// First hit of the ray from `origin` along the unit vector `dir` within `max_toi`.
    /// Shapes that contain the origin are not seen (as back faces are culled by a rasteriser).
    pub fn cast(&self, origin: Vector, dir: Vector, max_toi: Real) -> Option<RayHit> {
        let ray = Ray::new(origin, dir);
        let mut best: Option<RayHit> = None;
        for (bvh, items) in [(&self.rest, &self.rest_items), (&self.movers, &self.mover_items)] {
            if items.is_empty() {
                continue;
            }
            let limit = best.map_or(max_toi, |b| b.toi);
            let found = std::cell::Cell::new(None::<RayHit>);
            let hit = bvh.cast_ray(&ray, limit, |leaf, best_so_far| {
                let item = items[leaf as usize];
                let (shape, _) = &self.shapes[item as usize];
                let hit = shape.cast_ray_and_get_normal(&self.poses[item as usize], &ray, best_so_far, true)?;
                if hit.time_of_impact <= 0.0 {
                    return None;
                }
                let n = if hit.normal.dot(dir) > 0.0 { -hit.normal } else { hit.normal };
                found.set(Some(RayHit {
                    toi: hit.time_of_impact,
                    normal: n,
                    item,
                }));
                Some(hit.time_of_impact)
            });
            // Each accepted leaf hit is no farther than the best before it, so the last one
            // recorded is the closest.
            if hit.is_some() && found.get().is_some() {
                best = found.get();
            }
        }
        best
    }
}
