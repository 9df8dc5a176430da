//! [`World`]: the rapier sets and pipeline, stepping, time, simple bodies.

use std::sync::Arc;

use ::nalgebra::Isometry3;
use hearth_kinematics::{from_pose, to_pose};
use rapier3d::prelude::*;

use super::config::WorldConfig;
use super::contact_filter::{BodyOwner, RootContactFilter};
use super::error::{WorldError, WorldResult, check_finite};
use super::spawn::ModelEntry;
use crate::assets::Material;
use crate::scene::Light;

/// A rigid body in the world (a robot link group, an object, the ground).
///
/// Wraps rapier's handle; [`BodyId::handle`] gives it back for direct use of
/// [`World::bodies`].
///
/// ```
/// use hearth_sim::world::{World, WorldConfig};
/// let world = World::new(WorldConfig::default()).unwrap();
/// let ground = world.ground().expect("the default config adds a ground");
/// assert_eq!(world.body_name(ground), Some("ground"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BodyId(pub(crate) RigidBodyHandle);

impl BodyId {
    /// The rapier handle.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// let ground = world.ground().unwrap();
    /// assert!(world.bodies().get(ground.handle()).unwrap().is_fixed());
    /// ```
    pub fn handle(self) -> RigidBodyHandle {
        self.0
    }

    /// Wraps a rapier handle.
    ///
    /// ```
    /// # use hearth_sim::world::{BodyId, World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// let ground = world.ground().unwrap();
    /// assert_eq!(BodyId::from_handle(ground.handle()), ground);
    /// ```
    pub fn from_handle(handle: RigidBodyHandle) -> Self {
        Self(handle)
    }
}

/// A box that is seen but not simulated (see [`World::static_visuals`]).
///
/// ```
/// use hearth_sim::assets::Material;
/// use hearth_sim::world::StaticVisual;
/// let v = StaticVisual { name: "floor/hall".into(), half_extents: [2.0, 1.0, 0.05], pose: nalgebra::Isometry3::identity(), material: Material::Wood };
/// assert_eq!(v.material, Material::Wood);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct StaticVisual {
    /// Name, as building bodies are named (`building/floor/ROOM`).
    pub name: String,
    /// Half extents of the box.
    pub half_extents: [f64; 3],
    /// World pose of the box centre.
    pub pose: Isometry3<f64>,
    /// Its material.
    pub material: Material,
}

/// Everything that evolves with the simulation; cloned whole by snapshots.
///
/// The parts that collision views read are shared (`Arc`): a view keeps the picture it was
/// taken from, and the world copies a part only when it changes it while a view or snapshot
/// still holds it.
#[derive(Clone)]
pub(crate) struct State {
    pub(crate) bodies: Arc<RigidBodySet>,
    pub(crate) colliders: Arc<ColliderSet>,
    pub(crate) impulse_joints: ImpulseJointSet,
    pub(crate) multibody_joints: MultibodyJointSet,
    pub(crate) islands: IslandManager,
    pub(crate) broad_phase: Arc<BroadPhaseBvh>,
    pub(crate) narrow_phase: NarrowPhase,
    pub(crate) ccd: CCDSolver,
    pub(crate) soft_bodies: SoftBodySet,
    pub(crate) models: Vec<ModelEntry>,
    /// Name of every body, indexed by the `user_data` of the body and of its colliders.
    pub(crate) names: Arc<Vec<String>>,
    /// Visual material of bodies that are not model links (building pieces), indexed like
    /// `names`.
    pub(crate) body_materials: Arc<Vec<Option<Material>>>,
    /// What each body is to the split-root contact filter, indexed like `names`.
    pub(crate) owners: Arc<Vec<BodyOwner>>,
    /// Shapes that are seen but not simulated (floor slabs that coincide with the ground).
    pub(crate) static_visuals: Arc<Vec<StaticVisual>>,
    /// Light sources (from the scene), for cameras.
    pub(crate) lights: Arc<Vec<Light>>,
    pub(crate) ground: Option<RigidBodyHandle>,
    pub(crate) time: f64,
    pub(crate) physics_steps: u64,
}

/// The physics world: rapier3d sets and pipeline, z up, gravity along −z.
///
/// Robots and objects enter as [`hearth_kinematics::RobotModel`]s through
/// [`World::spawn_model`]; [`World::step`] runs one control step (`substeps` physics steps);
/// [`World::snapshot`] / [`World::restore`] roll the whole state back; [`World::obstacles_view`]
/// lets planners query the live colliders.
///
/// ```
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::{Isometry3, Vector3};
///
/// let mut world = World::new(WorldConfig::default())?;
/// let crate_box = world.add_box("crate", [0.1, 0.1, 0.1], &Isometry3::translation(0.0, 0.0, 0.5), true)?;
/// for _ in 0..30 {
///     world.step(); // 1 s
/// }
/// let z = world.body_pose(crate_box)?.translation.z;
/// assert!((z - 0.1).abs() < 0.01, "the box rests on the ground: z = {z}");
/// assert!((world.time() - 1.0).abs() < 1e-9);
/// # Ok::<(), hearth_sim::world::WorldError>(())
/// ```
pub struct World {
    pub(crate) config: WorldConfig,
    pub(crate) params: IntegrationParameters,
    pub(crate) gravity: Vector,
    pub(crate) pipeline: PhysicsPipeline,
    pub(crate) state: State,
    /// Per multibody link: subtree mass and first moment (gravity compensation scratch).
    pub(crate) gravity_scratch: Vec<(Real, Vector)>,
    /// Per position-controlled variable: its compensated target (scratch).
    pub(crate) gravity_offsets: Vec<(usize, f64)>,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("time", &self.state.time)
            .field("bodies", &self.state.bodies.len())
            .field("models", &self.state.models.len())
            .finish_non_exhaustive()
    }
}

/// Relative motion (m) below which the physics keeps a touching pair's contacts without
/// recomputing them.
const CONTACT_RECYCLE_DISTANCE: Real = 0.002;

impl World {
    /// An empty world (with a ground box when `config.ground_plane`).
    ///
    /// # Errors
    /// [`WorldError::InvalidConfig`] when the configuration does not validate.
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert_eq!(world.body_count(), 1); // the ground
    /// assert!(World::new(WorldConfig { substeps: 0, ..WorldConfig::default() }).is_err());
    /// ```
    pub fn new(config: WorldConfig) -> WorldResult<Self> {
        config.validate()?;
        let params = IntegrationParameters {
            dt: config.timestep as Real,
            num_solver_iterations: config.solver_iterations as usize,
            // Rapier keeps a touching pair's contacts, unrecomputed, until the two shapes have
            // moved 5 cm relative to each other (contact recycling). A finger that closes at
            // 5 cm/s on a bowl it already touches elsewhere then slides through the bowl's
            // wall unseen. 2 mm (less than half such a wall) keeps the saving for resting
            // objects.
            normalized_contact_recycle_distance: CONTACT_RECYCLE_DISTANCE,
            ..IntegrationParameters::default()
        };
        let g = config.gravity;
        let mut world = Self {
            params,
            gravity: Vector::new(g[0] as Real, g[1] as Real, g[2] as Real),
            pipeline: PhysicsPipeline::new(),
            gravity_scratch: Vec::new(),
            gravity_offsets: Vec::new(),
            state: State {
                bodies: Arc::new(RigidBodySet::new()),
                colliders: Arc::new(ColliderSet::new()),
                impulse_joints: ImpulseJointSet::new(),
                multibody_joints: MultibodyJointSet::new(),
                islands: IslandManager::new(),
                broad_phase: Arc::new(BroadPhaseBvh::new()),
                narrow_phase: NarrowPhase::new(),
                ccd: CCDSolver::new(),
                soft_bodies: SoftBodySet::default(),
                models: Vec::new(),
                names: Arc::new(Vec::new()),
                body_materials: Arc::new(Vec::new()),
                owners: Arc::new(Vec::new()),
                static_visuals: Arc::new(Vec::new()),
                lights: Arc::new(Vec::new()),
                ground: None,
                time: 0.0,
                physics_steps: 0,
            },
            config,
        };
        if world.config.ground_plane {
            let body = RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.0, -0.05));
            let collider = ColliderBuilder::cuboid(100.0, 100.0, 0.05).friction(world.config.ground_friction as Real);
            let handle = world.insert_body("ground", body, std::iter::once(collider));
            world.state.ground = Some(handle);
        }
        Ok(world)
    }

    /// The configuration the world was built with.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig { substeps: 2, ..WorldConfig::default() }).unwrap();
    /// assert_eq!(world.config().substeps, 2);
    /// ```
    pub fn config(&self) -> &WorldConfig {
        &self.config
    }

    /// Simulated time in seconds.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.step();
    /// assert!((world.time() - world.config().control_dt()).abs() < 1e-12);
    /// ```
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// Physics steps run so far.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.step();
    /// world.step_physics();
    /// assert_eq!(world.physics_steps(), 5); // 4 substeps + 1
    /// ```
    pub fn physics_steps(&self) -> u64 {
        self.state.physics_steps
    }

    /// Number of rigid bodies (ground included).
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// assert_eq!(world.body_count(), 2);
    /// ```
    pub fn body_count(&self) -> usize {
        self.state.bodies.len()
    }

    /// Number of colliders.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// assert_eq!(world.collider_count(), 2); // ground and crate
    /// ```
    pub fn collider_count(&self) -> usize {
        self.state.colliders.len()
    }

    /// The ground body, if the world has one.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert!(world.ground().is_some());
    /// let bare = World::new(WorldConfig { ground_plane: false, ..WorldConfig::default() }).unwrap();
    /// assert!(bare.ground().is_none());
    /// ```
    pub fn ground(&self) -> Option<BodyId> {
        self.state.ground.map(BodyId)
    }

    /// Read access to rapier's bodies (for renderers and tools).
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert_eq!(world.bodies().len(), world.body_count());
    /// ```
    pub fn bodies(&self) -> &RigidBodySet {
        &self.state.bodies
    }

    /// Read access to rapier's colliders.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert_eq!(world.colliders().len(), world.collider_count());
    /// ```
    pub fn colliders(&self) -> &ColliderSet {
        &self.state.colliders
    }

    /// Read access to rapier's narrow phase (contact graph).
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// world.step();
    /// assert!(world.narrow_phase().contact_pairs().any(|pair| pair.has_any_active_contact()));
    /// ```
    pub fn narrow_phase(&self) -> &NarrowPhase {
        &self.state.narrow_phase
    }

    /// The name given to a body (`ground`, `MODEL/LINK`, or the name passed to
    /// [`World::add_box`]).
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// assert_eq!(world.body_name(b), Some("crate"));
    /// ```
    pub fn body_name(&self, body: BodyId) -> Option<&str> {
        let rb = self.state.bodies.get(body.0)?;
        self.state.names.get(rb.user_data as usize).map(String::as_str)
    }

    /// The visual material of a body that is not a model link (building pieces carry the
    /// material their scene gives them; [`World::set_body_material`] sets one for any other).
    ///
    /// ```
    /// use hearth_sim::assets::Material;
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// assert_eq!(world.body_material(b), None);
    /// world.set_body_material(b, Material::Wood).unwrap();
    /// assert_eq!(world.body_material(b), Some(Material::Wood));
    /// ```
    pub fn body_material(&self, body: BodyId) -> Option<Material> {
        let rb = self.state.bodies.get(body.0)?;
        self.state.body_materials.get(rb.user_data as usize).copied().flatten()
    }

    /// Sets the visual material [`World::body_material`] reports (cameras shade the body with
    /// it). Model links keep the materials of their URDF visuals.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`].
    ///
    /// ```
    /// # use hearth_sim::assets::Material;
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let ground = world.ground().unwrap();
    /// world.set_body_material(ground, Material::Stone).unwrap();
    /// assert_eq!(world.body_material(ground), Some(Material::Stone));
    /// ```
    pub fn set_body_material(&mut self, body: BodyId, material: Material) -> WorldResult<()> {
        let index = self.rigid_body(body)?.user_data as usize;
        if let Some(slot) = Arc::make_mut(&mut self.state.body_materials).get_mut(index) {
            *slot = Some(material);
        }
        Ok(())
    }

    /// Shapes that cameras and LiDARs see but physics does not simulate: floor slabs whose top
    /// face is the ground plane (the ground already carries them).
    ///
    /// ```
    /// let world = hearth_sim::world::World::new(Default::default()).unwrap();
    /// assert!(world.static_visuals().is_empty());
    /// ```
    pub fn static_visuals(&self) -> &[StaticVisual] {
        &self.state.static_visuals
    }

    /// The lights cameras shade with ([`World::load_scene`] sets the scene's).
    ///
    /// ```
    /// let world = hearth_sim::world::World::new(Default::default()).unwrap();
    /// assert!(world.lights().is_empty());
    /// ```
    pub fn lights(&self) -> &[Light] {
        &self.state.lights
    }

    /// Replaces the lights.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.set_lights(Vec::new());
    /// assert!(world.lights().is_empty());
    /// ```
    pub fn set_lights(&mut self, lights: Vec<Light>) {
        self.state.lights = Arc::new(lights);
    }

    pub(crate) fn add_static_visual(&mut self, visual: StaticVisual) {
        Arc::make_mut(&mut self.state.static_visuals).push(visual);
    }

    /// One control step: `config.substeps` physics steps.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.step();
    /// assert_eq!(world.physics_steps(), u64::from(world.config().substeps));
    /// ```
    pub fn step(&mut self) {
        for _ in 0..self.config.substeps {
            self.step_physics();
        }
    }

    /// One physics step of `config.timestep` seconds (controllers are applied first).
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.step_physics();
    /// assert!((world.time() - world.config().timestep).abs() < 1e-12);
    /// ```
    pub fn step_physics(&mut self) {
        self.apply_controllers();
        let s = &mut self.state;
        let hooks = RootContactFilter { owners: &s.owners };
        self.pipeline.step(
            self.gravity,
            &self.params,
            &mut s.islands,
            Arc::make_mut(&mut s.broad_phase),
            &mut s.narrow_phase,
            Arc::make_mut(&mut s.bodies),
            Arc::make_mut(&mut s.colliders),
            &mut s.impulse_joints,
            &mut s.multibody_joints,
            &mut s.soft_bodies,
            &mut s.ccd,
            &hooks,
            &(),
        );
        s.time += self.config.timestep;
        s.physics_steps += 1;
    }

    /// Adds a box with half extents `half` at `pose`: dynamic (density
    /// `config.default_density`) or fixed.
    ///
    /// # Errors
    /// [`WorldError::NonFinite`] / [`WorldError::OutOfRange`] for bad sizes or poses.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let shelf = world.add_box("shelf", [0.3, 0.2, 0.02], &Isometry3::translation(0.0, 0.0, 1.0), false).unwrap();
    /// world.step();
    /// assert_eq!(world.body_pose(shelf).unwrap().translation.z, 1.0); // fixed: it does not fall
    /// assert!(world.add_box("bad", [0.0; 3], &Isometry3::identity(), true).is_err());
    /// ```
    pub fn add_box(&mut self, name: &str, half: [f64; 3], pose: &Isometry3<f64>, dynamic: bool) -> WorldResult<BodyId> {
        for (i, h) in half.iter().enumerate() {
            super::error::check_range("box half extent", ["x", "y", "z"][i], *h, 1e-6, 1e6)?;
        }
        check_pose("box pose", name, pose)?;
        let builder = if dynamic {
            RigidBodyBuilder::dynamic()
        } else {
            RigidBodyBuilder::fixed()
        }
        .pose(to_pose(pose))
        .can_sleep(self.config.sleeping);
        let collider = ColliderBuilder::cuboid(half[0] as Real, half[1] as Real, half[2] as Real)
            .density(self.config.default_density as Real);
        let handle = self.insert_body(name, builder, std::iter::once(collider));
        Ok(BodyId(handle))
    }

    /// World pose of a body's frame.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`].
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(1.0, 2.0, 0.1), true).unwrap();
    /// let pose = world.body_pose(b).unwrap();
    /// assert!((pose.translation.x - 1.0).abs() < 1e-6 && (pose.translation.y - 2.0).abs() < 1e-6);
    /// ```
    pub fn body_pose(&self, body: BodyId) -> WorldResult<Isometry3<f64>> {
        self.rigid_body(body).map(|rb| from_pose(rb.position()))
    }

    /// Moves a body to `pose` and zeroes its velocity (free bodies and fixed bodies alike;
    /// for robot links use [`World::place`]).
    ///
    /// # Errors
    /// Unknown body or a non-finite pose.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// world.set_body_pose(b, &Isometry3::translation(0.5, 0.0, 0.1)).unwrap();
    /// assert!((world.body_pose(b).unwrap().translation.x - 0.5).abs() < 1e-6);
    /// ```
    pub fn set_body_pose(&mut self, body: BodyId, pose: &Isometry3<f64>) -> WorldResult<()> {
        check_pose("body pose", "body", pose)?;
        self.rigid_body(body)?;
        if let Some(rb) = Arc::make_mut(&mut self.state.bodies).get_mut(body.0) {
            rb.set_position(to_pose(pose), true);
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
        self.sync_bodies(&[body.0]);
        Ok(())
    }

    pub(crate) fn rigid_body(&self, body: BodyId) -> WorldResult<&RigidBody> {
        let (index, generation) = body.0.into_raw_parts();
        self.state
            .bodies
            .get(body.0)
            .ok_or(WorldError::UnknownBody { index, generation })
    }

    /// Inserts a body and its colliders, naming both through `user_data`.
    pub(crate) fn insert_body(
        &mut self,
        name: &str,
        builder: RigidBodyBuilder,
        colliders: impl IntoIterator<Item = ColliderBuilder>,
    ) -> RigidBodyHandle {
        let name_index = self.state.names.len() as u128;
        Arc::make_mut(&mut self.state.names).push(name.to_owned());
        Arc::make_mut(&mut self.state.body_materials).push(None);
        Arc::make_mut(&mut self.state.owners).push(BodyOwner::None);
        let s = &mut self.state;
        let handle = Arc::make_mut(&mut s.bodies).insert(builder.user_data(name_index));
        for collider in colliders {
            Arc::make_mut(&mut s.colliders).insert_with_parent(
                collider.user_data(name_index),
                handle,
                Arc::make_mut(&mut s.bodies),
            );
        }
        self.sync_bodies(&[handle]);
        handle
    }

    /// Records what a body is to the split-root contact filter. The colliders of links whose
    /// contacts with the root are dropped get the filter hook: rapier never recycles the
    /// contacts of a pair with a hook, and the root's pairs with resting objects are the many.
    pub(crate) fn set_body_owner(&mut self, handle: RigidBodyHandle, owner: BodyOwner) {
        let s = &mut self.state;
        let Some(rb) = s.bodies.get(handle) else { return };
        if let Some(slot) = Arc::make_mut(&mut s.owners).get_mut(rb.user_data as usize) {
            *slot = owner;
        }
        if matches!(owner, BodyOwner::Link { skip_root: true, .. }) {
            for &ch in rb.colliders() {
                if let Some(co) = Arc::make_mut(&mut s.colliders).get_mut(ch) {
                    co.set_active_hooks(co.active_hooks() | ActiveHooks::FILTER_CONTACT_PAIRS);
                }
            }
        }
    }

    /// Brings the colliders of teleported bodies and their broad-phase boxes up to date, so
    /// queries see the new poses before the next step.
    pub(crate) fn sync_bodies(&mut self, handles: &[RigidBodyHandle]) {
        let s = &mut self.state;
        for &h in handles {
            let Some(rb) = s.bodies.get(h) else { continue };
            let pose = *rb.position();
            for &ch in rb.colliders() {
                let Some(co) = Arc::make_mut(&mut s.colliders).get_mut(ch) else {
                    continue;
                };
                let local = co.position_wrt_parent().copied().unwrap_or(Pose::IDENTITY);
                co.set_position(pose * local);
                let aabb = co.compute_broad_phase_aabb(&self.params, &s.bodies);
                if aabb.mins.is_finite() && aabb.maxs.is_finite() {
                    Arc::make_mut(&mut s.broad_phase).set_aabb(&self.params, ch, aabb);
                }
            }
        }
    }

    /// Wakes a body (and its island) up.
    pub(crate) fn wake(&mut self, handle: RigidBodyHandle) {
        let s = &mut self.state;
        if s.bodies.contains(handle) {
            s.islands.wake_up(Arc::make_mut(&mut s.bodies), handle, true);
        }
    }
}

/// Checks that a pose has finite entries.
pub(crate) fn check_pose(what: &'static str, name: &str, pose: &Isometry3<f64>) -> WorldResult<()> {
    for v in pose.translation.vector.iter().chain(pose.rotation.coords.iter()) {
        check_finite(what, name, *v)?;
    }
    Ok(())
}
