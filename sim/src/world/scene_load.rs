//! Loading a [`SceneFile`] into a [`World`] ([`World::load_scene`]) and letting it come to
//! rest ([`World::settle`]).

use std::collections::BTreeMap;

use ::nalgebra::{Isometry3, Translation3, UnitQuaternion};
use hearth_kinematics::{JointKind, RobotModel, to_pose};
use rapier3d::prelude::*;

use super::control::{DiffDriveConfig, JointCommand};
use super::error::WorldError;
use super::physics::{BodyId, StaticVisual, World};
use super::spawn::{BaseMode, ModelHandle, SpawnOptions, named_configuration};
use crate::assets::Material;
use crate::scene::{SceneError, SceneFile};

/// Name prefix of the building's bodies in the world (`building/floor/…`, `building/wall/…`).
///
/// ```
/// assert_eq!(hearth_sim::world::BUILDING_PREFIX, "building/");
/// ```
pub const BUILDING_PREFIX: &str = "building/";

/// Why a scene could not be loaded. The world is unchanged whenever one is returned.
///
/// ```
/// use hearth_sim::scene::{SceneFile, SceneObject};
/// use hearth_sim::world::{LoadSceneError, World, WorldConfig};
/// let mut world = World::new(WorldConfig::default()).unwrap();
/// let mut scene = SceneFile::empty("typo");
/// scene.objects.push(SceneObject::new("t", "tabel", 0, [0.0, 0.0, 0.0]));
/// let err = world.load_scene(&scene).unwrap_err();
/// assert!(matches!(err, LoadSceneError::Scene(_)));
/// assert!(err.to_string().contains("tabel"));
/// assert_eq!(world.body_count(), 1); // only the ground
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadSceneError {
    /// The scene does not validate (unknown category, overlap, bad joint value, …).
    #[error("invalid scene: {0}")]
    Scene(#[from] SceneError),
    /// The scene's robot is not a built-in robot.
    #[error("scene robot: unknown robot `{name}` (built-in: {known})")]
    UnknownRobot {
        /// The name in the scene file.
        name: String,
        /// The built-in names, comma separated.
        known: String,
    },
    /// The physics world refused a body of the scene.
    #[error("cannot spawn `{name}`: {source}")]
    Spawn {
        /// The object, building piece or robot.
        name: String,
        /// The world's error.
        source: WorldError,
    },
}

/// What [`World::load_scene`] spawned: the building's bodies, one model per object and the
/// robot.
///
/// ```
/// use hearth_sim::scene::{SceneFile, SceneObject};
/// use hearth_sim::world::{World, WorldConfig};
/// let mut scene = SceneFile::empty("one table");
/// scene.objects.push(SceneObject::new("table", "table", 0, [0.0, 0.0, 0.0]));
/// let mut world = World::new(WorldConfig::default())?;
/// let loaded = world.load_scene(&scene).unwrap();
/// let table = loaded.object("table").unwrap();
/// assert_eq!(world.model_name(table)?, "table");
/// assert!(loaded.robot.is_none() && loaded.building.is_empty());
/// # Ok::<(), hearth_sim::world::WorldError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadedScene {
    /// Fixed bodies of the floors (those not on the ground plane), ceilings and wall pieces, named
    /// [`BUILDING_PREFIX`]` + floor/NAME | ceiling/NAME | wall/NAME/PIECE`.
    pub building: Vec<BodyId>,
    /// Each object's model, by object name.
    pub objects: BTreeMap<String, ModelHandle>,
    /// The robot, when the scene places one.
    pub robot: Option<ModelHandle>,
}

impl LoadedScene {
    /// The model of the object named `name`.
    ///
    /// ```
    /// let loaded = hearth_sim::world::LoadedScene::default();
    /// assert!(loaded.object("fridge_0").is_none());
    /// ```
    pub fn object(&self, name: &str) -> Option<ModelHandle> {
        self.objects.get(name).copied()
    }

    /// Every model spawned: the objects in name order, then the robot.
    ///
    /// ```
    /// let loaded = hearth_sim::world::LoadedScene::default();
    /// assert_eq!(loaded.models().count(), 0);
    /// ```
    pub fn models(&self) -> impl Iterator<Item = ModelHandle> + '_ {
        self.objects.values().copied().chain(self.robot)
    }
}

/// The outcome of [`World::settle`].
///
/// ```
/// let r = hearth_sim::world::SettleReport::default();
/// assert!(!r.at_rest && r.steps == 0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SettleReport {
    /// Control steps run.
    pub steps: usize,
    /// Whether every dynamic body was asleep or slower than the rest thresholds at the end.
    pub at_rest: bool,
    /// Largest linear speed of an awake dynamic body at the end, m/s.
    pub max_linear_speed: f64,
    /// Largest angular speed of an awake dynamic body at the end, rad/s.
    pub max_angular_speed: f64,
    /// Dynamic bodies asleep at the end.
    pub sleeping_bodies: usize,
    /// Dynamic bodies in the world.
    pub dynamic_bodies: usize,
}

/// Linear speed (m/s) under which a body counts as resting in [`World::settle`].
///
/// ```
/// assert!(hearth_sim::world::REST_LINEAR_SPEED > 0.0);
/// ```
pub const REST_LINEAR_SPEED: f64 = 0.02;
/// Angular speed (rad/s) under which a body counts as resting in [`World::settle`].
///
/// ```
/// assert!(hearth_sim::world::REST_ANGULAR_SPEED > 0.0);
/// ```
pub const REST_ANGULAR_SPEED: f64 = 0.1;
/// Consecutive resting control steps [`World::settle`] waits for before it stops.
const REST_STREAK: usize = 5;

/// How a scene's robot is spawned: its model, pose and options.
fn robot_spawn(scene: &SceneFile) -> Result<Option<(RobotModel, Isometry3<f64>, SpawnOptions)>, LoadSceneError> {
    let Some(placement) = &scene.robot else {
        return Ok(None);
    };
    let model = RobotModel::builtin(&placement.name).map_err(|_| LoadSceneError::UnknownRobot {
        name: placement.name.clone(),
        known: hearth_kinematics::builtin_names().join(", "),
    })?;
    // Wheeled robots get a free base and their differential drive; arms are bolted down.
    let base = if DiffDriveConfig::for_builtin(model.name()).is_some() {
        BaseMode::Free
    } else {
        BaseMode::Fixed
    };
    // Start tucked where the robot has a tuck, so the arm keeps clear of the furniture.
    let mut q = model.neutral_configuration();
    for (joint, value) in named_configuration(model.name(), "tuck").unwrap_or_default() {
        if let Some(v) = model.variable_names().iter().position(|n| n == joint) {
            q[v] = value.clamp(model.lower()[v], model.upper()[v]);
        }
    }
    let [x, y, z] = placement.position;
    let pose = Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(0.0, 0.0, placement.yaw),
    );
    let options = SpawnOptions {
        name: Some(placement.name.clone()),
        base,
        configuration: Some(q),
        ..SpawnOptions::default()
    };
    Ok(Some((model, pose, options)))
}

impl World {
    /// Spawns a scene: every floor, ceiling and wall piece as a fixed box body (except floor slabs
    /// whose walking face lies on the world's ground plane, z = 0, which the ground already
    /// provides), every object as
    /// a model (fixed or free base as the scene says, its initial joint positions applied,
    /// drawers and vertical-hinge doors free to move with their damping and friction, joints
    /// gravity loads held by their controllers, friction from its material), and the robot when the scene
    /// places one (a built-in robot; wheeled robots such as the Fetch get a free base with
    /// their differential drive, arms a fixed base; the arm starts tucked).
    ///
    /// The scene is validated before anything is spawned, and a failure while spawning rolls
    /// the world back, so an error leaves the world as it was.
    ///
    /// # Errors
    /// [`LoadSceneError::Scene`] when the scene does not validate, [`LoadSceneError::UnknownRobot`]
    /// for a robot that is not built in, [`LoadSceneError::Spawn`] when rapier refuses a body.
    ///
    /// ```
    /// use hearth_sim::scene::{GenerateOptions, generate};
    /// use hearth_sim::world::{World, WorldConfig};
    /// let home = generate(&GenerateOptions { seed: 1, rooms: 2, small_objects: false, ..Default::default() }).unwrap();
    /// let mut world = World::new(WorldConfig::default())?;
    /// let loaded = world.load_scene(&home).unwrap();
    /// assert_eq!(loaded.objects.len(), home.objects.len());
    /// let fetch = loaded.robot.expect("generated homes place a Fetch");
    /// world.drive(fetch, 0.2, 0.0)?;
    /// world.step();
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn load_scene(&mut self, scene: &SceneFile) -> Result<LoadedScene, LoadSceneError> {
        let assets = scene.assets()?;
        let robot = robot_spawn(scene)?;
        let before = self.snapshot();
        let mut loaded = LoadedScene::default();
        let spawn_all = || -> Result<(), LoadSceneError> {
            let has_ground = self.state.ground.is_some();
            for b in scene.building_boxes() {
                let top = b.center[2] + b.size[2] / 2.0;
                let pose = Isometry3::from_parts(
                    Translation3::from(b.center),
                    UnitQuaternion::from_euler_angles(0.0, 0.0, b.yaw),
                );
                let name = format!("{BUILDING_PREFIX}{}", b.name);
                if has_ground && b.name.starts_with("floor/") && top.abs() < 1e-9 {
                    // The ground plane already is this floor: a second support at the same
                    // height makes thin objects (rugs) and what stands on them jitter. Cameras
                    // still see the slab and its material.
                    self.add_static_visual(StaticVisual {
                        name,
                        half_extents: b.size.map(|s| s / 2.0),
                        pose,
                        material: b.material,
                    });
                    continue;
                }
                loaded
                    .building
                    .push(self.add_fixed_box(&name, b.size, &pose, b.material));
            }
            for (object, asset) in scene.objects.iter().zip(&assets) {
                let model = &asset.model;
                let mut q = model.neutral_configuration();
                for (joint, &value) in &object.joints {
                    // Validation checked that the joint exists and the value is in range.
                    if let Some(v) = model.variable_names().iter().position(|n| n == joint) {
                        q[v] = value.clamp(model.lower()[v], model.upper()[v]);
                    }
                }
                let options = SpawnOptions {
                    name: Some(object.name.clone()),
                    base: if object.fixed { BaseMode::Fixed } else { BaseMode::Free },
                    configuration: Some(q),
                    friction: Some(asset.material.props().friction),
                    ..SpawnOptions::default()
                };
                let handle =
                    self.spawn_model(model, &object.pose(), options)
                        .map_err(|source| LoadSceneError::Spawn {
                            name: object.name.clone(),
                            source,
                        })?;
                // Furniture joints that are held are held firmly enough; skipping the per-step
                // gravity pass keeps homes with hundreds of objects fast.
                self.state.models[handle.index()].gravity_compensation = false;
                self.free_passive_joints(handle);
                loaded.objects.insert(object.name.clone(), handle);
            }
            self.set_lights(scene.lights.clone());
            if let Some((model, pose, options)) = robot {
                let name = model.name().to_owned();
                let handle = self
                    .spawn_model(&model, &pose, options)
                    .map_err(|source| LoadSceneError::Spawn { name, source })?;
                loaded.robot = Some(handle);
            }
            Ok(())
        };
        match spawn_all() {
            Ok(()) => Ok(loaded),
            Err(e) => {
                // The snapshot comes from this very world, so restoring cannot mismatch.
                let _ = self.restore(&before);
                Err(e)
            }
        }
    }

    /// A fixed box of full `size` (validated scene data: finite and positive).
    fn add_fixed_box(&mut self, name: &str, size: [f64; 3], pose: &Isometry3<f64>, material: Material) -> BodyId {
        let [hx, hy, hz] = size.map(|s| (s / 2.0).max(1e-4) as Real);
        let collider = ColliderBuilder::cuboid(hx, hy, hz).friction(material.props().friction as Real);
        let body = BodyId(self.insert_body(name, RigidBodyBuilder::fixed().pose(to_pose(pose)), [collider]));
        // The body was just inserted, so it exists.
        let _ = self.set_body_material(body, material);
        body
    }

    /// Steps (control steps, [`World::step`]) until every dynamic body has been asleep or
    /// slower than [`REST_LINEAR_SPEED`] and [`REST_ANGULAR_SPEED`] for 5 consecutive steps, or
    /// `max_steps` have run.
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// world.add_box("crate", [0.1, 0.1, 0.1], &Isometry3::translation(0.0, 0.0, 0.3), true)?;
    /// let report = world.settle(300);
    /// assert!(report.at_rest && report.steps < 300);
    /// assert_eq!(report.dynamic_bodies, 1);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn settle(&mut self, max_steps: usize) -> SettleReport {
        let mut streak = 0;
        let mut report = self.rest_report();
        while report.steps < max_steps {
            self.step();
            let steps = report.steps + 1;
            report = SettleReport {
                steps,
                ..self.rest_report()
            };
            streak = if report.at_rest { streak + 1 } else { 0 };
            if streak >= REST_STREAK {
                break;
            }
        }
        report
    }

    /// Rest statistics of the current state (`steps` = 0).
    fn rest_report(&self) -> SettleReport {
        let mut report = SettleReport::default();
        for (_, rb) in self.state.bodies.iter() {
            if !rb.is_dynamic() {
                continue;
            }
            report.dynamic_bodies += 1;
            if rb.is_sleeping() {
                report.sleeping_bodies += 1;
                continue;
            }
            report.max_linear_speed = report.max_linear_speed.max(f64::from(rb.linvel().length()));
            report.max_angular_speed = report.max_angular_speed.max(f64::from(rb.angvel().length()));
        }
        report.at_rest = report.max_linear_speed <= REST_LINEAR_SPEED && report.max_angular_speed <= REST_ANGULAR_SPEED;
        report
    }
}

impl World {
    /// Switches off the controllers of the object's joints that gravity does not load (drawers
    /// on horizontal runners, doors on vertical hinges): they move freely with their damping and
    /// friction, so a push or pull moves them and they stay where they are left. Joints that
    /// gravity would swing or slide (oven and dishwasher doors, lids, sashes) keep the position
    /// controller that holds their initial value, like a counterbalanced hinge.
    fn free_passive_joints(&mut self, handle: ModelHandle) {
        let Ok(entry) = self.entry(handle) else { return };
        let model = entry.model.clone();
        let mut passive = Vec::new();
        for joint in model.joints() {
            let Some(v) = joint.variable else { continue };
            let Ok(pose) = self.link_pose(handle, &model.links()[joint.child].name) else {
                continue;
            };
            let up = (pose.rotation * joint.axis.into_inner()).z.abs();
            let free = match joint.kind {
                JointKind::Prismatic => up < 0.1,
                JointKind::Revolute | JointKind::Continuous => up > 0.9,
                _ => false,
            };
            if free {
                passive.push(v);
            }
        }
        for v in passive {
            self.state.models[handle.index()].commands[v] = JointCommand::Off;
            self.write_motor(handle, v);
        }
    }
}
