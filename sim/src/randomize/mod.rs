//! Domain randomisation: object models, visual materials, physical materials, start and
//! sensor poses, and sensor noise, all seeded and reproducible bit for bit.
//!
//! - **Objects** ([`randomize_objects`], scene level): every eligible object becomes another
//!   shape variant of its category, scaled into the original's bounding box; names,
//!   categories, rooms and supports stay. Doors and windows are never swapped.
//! - **Visual materials** ([`VisualRandomization`], camera level): each part gets a new
//!   material of its class (wood → another wood), colour, roughness and metalness drawn from
//!   [`class_look`]; geometry and segmentation are untouched.
//! - **Physical materials** ([`randomize_physics`], world level): friction, restitution and
//!   mass from each material's span ([`crate::assets::Material::ranges`]), joint damping by a
//!   factor, set through [`World::set_body_friction`], [`World::set_body_restitution`],
//!   [`World::set_body_mass`] and [`World::set_joint_damping`].
//! - **Poses and noise** ([`perturb_robot_start`], [`camera_offset`], [`add_depth_noise`],
//!   and [`Randomizer::lidar_noise`] for the LiDAR's own [`LidarNoise`]).
//!
//! [`RandomizationConfig`] (the `[randomization]` TOML section, every kind off by default)
//! says what to do; a [`Randomizer`] holds it with a run seed and applies episode `e`'s draw.
//! Objects, visual and physical materials are drawn anew every
//! [`RandomizationConfig::every_k_episodes`] episodes (episodes `e` with the same
//! `e / every_k_episodes` share a draw); pose perturbations are drawn every episode.
//!
//! # Intended call order at an episode's reset
//!
//! 1. Keep the **base** scene; never randomise an already randomised one.
//!    `let mut scene = base.clone(); randomizer.apply_scene(episode, &mut scene)?;`
//!    (object swaps, then the robot's start pose on the result's traversability map).
//!    When [`Randomizer::scene_changes`] is false the base scene can be reused as is.
//! 2. Build the world from it: `World::new(..)`, `world.load_scene(&scene)` (a new scene
//!    means a new world: rapier bodies are not swapped in place).
//! 3. `randomizer.apply_world(episode, &mut world, &loaded)?` (physical properties), then
//!    settle and take the reset snapshot: a snapshot captures the randomised properties, and
//!    restoring it keeps them.
//! 4. Cameras: `Camera::new(&world, ..)` (or `camera.rebuild(&world)` for an existing one),
//!    then `randomizer.apply_camera(episode, &world, &mut camera)?`. A rebuild re-reads the
//!    world's own materials, so call `apply_camera` again after every rebuild.
//! 5. Sensors: LiDAR with `randomizer.lidar_noise()`; render with
//!    `camera.render_from(&world, &(camera.pose(&world)? * randomizer.camera_offset(episode)), m)`
//!    and pass depth through [`add_depth_noise`] with `randomizer.rng(episode, Stream::Noise)`
//!    (one stream per episode, drawn from frame after frame).
//!
//! ```
//! use hearth_sim::randomize::{RandomizationConfig, Randomizer};
//! use hearth_sim::scene::{SceneFile, SceneObject};
//! use hearth_sim::world::{World, WorldConfig};
//!
//! let config = RandomizationConfig::from_toml_str(r#"
//! [objects]
//! enabled = true
//! [physics]
//! enabled = true
//! friction = true
//! "#)?;
//! let randomizer = Randomizer::new(config, 42)?;
//! let mut base = SceneFile::empty("kitchenette");
//! base.objects.push(SceneObject::new("table", "table", 0, [0.0, 0.0, 0.0]));
//! base.objects.push(SceneObject::new("chair", "chair", 0, [1.2, 0.0, 0.0]));
//!
//! let mut scene = base.clone();
//! let report = randomizer.apply_scene(0, &mut scene)?;
//! assert_eq!(report.objects.swapped.len(), 2);
//! let mut world = World::new(WorldConfig::default())?;
//! let loaded = world.load_scene(&scene).expect("randomised scenes validate");
//! randomizer.apply_world(0, &mut world, &loaded)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod config;
mod error;
mod noise;
mod objects;
mod physics;
mod sampling;
mod visual;

use nalgebra::Isometry3;
use rand_pcg::Pcg64Mcg;

pub use config::{
    ObjectRandomization, PhysicsRandomization, PoseRandomization, RandomizationConfig, SensorNoiseConfig,
    VisualRandomizationConfig,
};
pub use error::RandomizeError;
pub use noise::{DepthNoise, START_POSE_TRIES, add_depth_noise, camera_offset, perturb_pose2d, perturb_robot_start};
pub use objects::{ObjectReport, ObjectSwap, randomize_objects};
pub use physics::{PhysicsReport, randomize_physics};
pub use sampling::{Stream, mix, stream};
pub use visual::{ClassLook, VisualRandomization, class_look};

use crate::scene::{MapOptions, SceneFile, SceneMaps};
use crate::sensors::{Camera, LidarNoise};
use crate::world::{LoadedScene, World};

/// What [`Randomizer::apply_scene`] did.
///
/// ```
/// let r = hearth_sim::randomize::SceneReport::default();
/// assert!(!r.robot_moved);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneReport {
    /// Object swaps.
    pub objects: ObjectReport,
    /// Whether the robot's start pose was perturbed.
    pub robot_moved: bool,
}

/// A validated [`RandomizationConfig`] with a run seed: applies episode `e`'s draw.
///
/// ```
/// use hearth_sim::randomize::{RandomizationConfig, Randomizer};
/// let config = RandomizationConfig { every_k_episodes: 3, ..Default::default() };
/// let r = Randomizer::new(config, 7).unwrap();
/// assert_eq!((r.epoch(0), r.epoch(2), r.epoch(3)), (0, 0, 1));
/// assert!(r.redraws_at(3) && !r.redraws_at(4));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Randomizer {
    config: RandomizationConfig,
    seed: u64,
}

impl Randomizer {
    /// Validates `config` and keeps it with the run seed.
    ///
    /// # Errors
    /// [`RandomizeError::InvalidValue`] naming the first bad key.
    ///
    /// ```
    /// use hearth_sim::randomize::{RandomizationConfig, Randomizer};
    /// let mut config = RandomizationConfig::default();
    /// config.objects.probability = 2.0;
    /// assert!(Randomizer::new(config, 1).is_err());
    /// ```
    pub fn new(config: RandomizationConfig, seed: u64) -> Result<Self, RandomizeError> {
        config.validate()?;
        Ok(Randomizer { config, seed })
    }

    /// The configuration.
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert_eq!(r.config().every_k_episodes, 1);
    /// ```
    pub fn config(&self) -> &RandomizationConfig {
        &self.config
    }

    /// The draw episode `episode` uses for objects and materials: `episode / every_k_episodes`.
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert_eq!(r.epoch(5), 5);
    /// ```
    pub fn epoch(&self, episode: u64) -> u64 {
        episode / self.config.every_k_episodes
    }

    /// Whether episode `episode` starts a new draw of objects and materials.
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert!(r.redraws_at(5));
    /// ```
    pub fn redraws_at(&self, episode: u64) -> bool {
        episode.is_multiple_of(self.config.every_k_episodes)
    }

    /// Whether [`Randomizer::apply_scene`] can change a scene (object swaps or a robot start
    /// perturbation are on).
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert!(!r.scene_changes());
    /// ```
    pub fn scene_changes(&self) -> bool {
        let p = &self.config.pose;
        self.config.objects.enabled || p.robot_xy_std > 0.0 || p.robot_yaw_std > 0.0
    }

    /// The random stream of `kind` for `episode`: per draw epoch for objects, visual and
    /// physical materials, per episode for poses and noise.
    ///
    /// ```
    /// use hearth_sim::randomize::{Randomizer, Stream};
    /// use rand::RngExt;
    /// let r = Randomizer::new(Default::default(), 1).unwrap();
    /// let a: u64 = r.rng(4, Stream::Noise).random();
    /// assert_eq!(a, r.rng(4, Stream::Noise).random::<u64>());
    /// assert_ne!(a, r.rng(5, Stream::Noise).random::<u64>());
    /// ```
    pub fn rng(&self, episode: u64, kind: Stream) -> Pcg64Mcg {
        match kind {
            Stream::Objects | Stream::Visual | Stream::Physics => stream(self.seed, self.epoch(episode), kind, ""),
            Stream::RobotPose | Stream::CameraPose | Stream::Noise => stream(self.seed, episode, kind, "episode"),
        }
    }

    /// Object swaps, then the robot start perturbation (on the randomised scene's
    /// traversability map when the scene has rooms). The result validates.
    ///
    /// # Errors
    /// [`RandomizeError::Scene`] when `scene` itself does not validate (it is unchanged then).
    ///
    /// ```
    /// use hearth_sim::randomize::{RandomizationConfig, Randomizer};
    /// use hearth_sim::scene::{RobotPlacement, SceneFile};
    /// let config = RandomizationConfig::from_toml_str("[pose]\nrobot_xy_std = 0.1").unwrap();
    /// let r = Randomizer::new(config, 1).unwrap();
    /// let mut scene = SceneFile::empty("open");
    /// scene.robot = Some(RobotPlacement { name: "fetch".into(), position: [0.0; 3], yaw: 0.0 });
    /// assert!(r.apply_scene(0, &mut scene).unwrap().robot_moved);
    /// ```
    pub fn apply_scene(&self, episode: u64, scene: &mut SceneFile) -> Result<SceneReport, RandomizeError> {
        let mut report = SceneReport::default();
        if self.config.objects.enabled {
            report.objects = randomize_objects(scene, &self.config.objects, &mut self.rng(episode, Stream::Objects))?;
        }
        let pose = &self.config.pose;
        if scene.robot.is_some() && (pose.robot_xy_std > 0.0 || pose.robot_yaw_std > 0.0) {
            let maps = if scene.building.rooms.is_empty() {
                None
            } else {
                Some(SceneMaps::build(scene, &MapOptions::default())?)
            };
            report.robot_moved =
                perturb_robot_start(scene, pose, maps.as_ref(), &mut self.rng(episode, Stream::RobotPose));
        }
        Ok(report)
    }

    /// Physical properties of the loaded scene's objects (and building, when configured).
    ///
    /// # Errors
    /// [`RandomizeError::World`] when `loaded` does not belong to `world`.
    ///
    /// ```
    /// use hearth_sim::randomize::{RandomizationConfig, Randomizer};
    /// use hearth_sim::scene::{SceneFile, SceneObject};
    /// use hearth_sim::world::{World, WorldConfig};
    /// let config = RandomizationConfig::from_toml_str("[physics]\nenabled = true\nfriction = true").unwrap();
    /// let r = Randomizer::new(config, 1).unwrap();
    /// let mut scene = SceneFile::empty("one chair");
    /// scene.objects.push(SceneObject::new("chair", "chair", 0, [0.0; 3]));
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let loaded = world.load_scene(&scene).unwrap();
    /// let before = world.properties_hash();
    /// assert!(r.apply_world(0, &mut world, &loaded).unwrap().bodies > 0);
    /// assert_ne!(world.properties_hash(), before);
    /// ```
    pub fn apply_world(
        &self,
        episode: u64,
        world: &mut World,
        loaded: &LoadedScene,
    ) -> Result<PhysicsReport, RandomizeError> {
        if !self.config.physics_active() {
            return Ok(PhysicsReport::default());
        }
        randomize_physics(
            world,
            loaded,
            &self.config.physics,
            &mut self.rng(episode, Stream::Physics),
        )
    }

    /// The visual draw of `episode` (the same for every episode of one draw epoch).
    ///
    /// ```
    /// let config = hearth_sim::randomize::RandomizationConfig { every_k_episodes: 2, ..Default::default() };
    /// let r = hearth_sim::randomize::Randomizer::new(config, 1).unwrap();
    /// assert_eq!(r.visuals(0), r.visuals(1));
    /// assert_ne!(r.visuals(1), r.visuals(2));
    /// ```
    pub fn visuals(&self, episode: u64) -> VisualRandomization {
        use rand::RngExt;
        VisualRandomization::new(self.rng(episode, Stream::Visual).random(), self.config.visual.clone())
    }

    /// Gives `camera` the visual draw of `episode` ([`VisualRandomization::apply_to_camera`]);
    /// with visual randomisation off it restores the world's own materials. Returns how many
    /// items differ from the world's materials.
    ///
    /// # Errors
    /// [`RandomizeError::Sensor`].
    ///
    /// ```
    /// use hearth_sim::randomize::{RandomizationConfig, Randomizer};
    /// use hearth_sim::scene::{SceneFile, SceneObject};
    /// use hearth_sim::sensors::{Backend, Camera, CameraConfig, Mount, Preset};
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Point3;
    /// let mut scene = SceneFile::empty("one table");
    /// scene.objects.push(SceneObject::new("table", "table", 0, [0.0; 3]));
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.load_scene(&scene).unwrap();
    /// let mut config = CameraConfig::preset(Preset::VisualRl).unwrap();
    /// config.backend = Backend::Raycast;
    /// config.mount = Some(Mount::look_at(Point3::new(2.0, 0.0, 1.0), Point3::origin()).unwrap());
    /// let mut camera = Camera::new(&world, None, config).unwrap();
    /// let r = Randomizer::new(RandomizationConfig::from_toml_str("[visual]\nenabled = true").unwrap(), 1).unwrap();
    /// assert!(r.apply_camera(0, &world, &mut camera).unwrap() > 0);
    /// ```
    pub fn apply_camera(&self, episode: u64, world: &World, camera: &mut Camera) -> Result<usize, RandomizeError> {
        self.visuals(episode).apply_to_camera(world, camera)
    }

    /// The camera mount offset of `episode` (identity when off); see [`camera_offset`].
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert_eq!(r.camera_offset(0), nalgebra::Isometry3::identity());
    /// ```
    pub fn camera_offset(&self, episode: u64) -> Isometry3<f64> {
        camera_offset(&self.config.pose, &mut self.rng(episode, Stream::CameraPose))
    }

    /// The configured depth noise.
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert!(r.depth_noise().is_none());
    /// ```
    pub fn depth_noise(&self) -> DepthNoise {
        let n = &self.config.noise;
        DepthNoise {
            std: n.depth_std,
            quadratic: n.depth_quadratic,
            dropout: n.depth_dropout,
        }
    }

    /// The configured LiDAR noise, for [`crate::sensors::Lidar::new`] or
    /// [`crate::sensors::Lidar::set_noise`].
    ///
    /// ```
    /// let r = hearth_sim::randomize::Randomizer::new(Default::default(), 1).unwrap();
    /// assert!(r.lidar_noise().is_none());
    /// ```
    pub fn lidar_noise(&self) -> LidarNoise {
        LidarNoise {
            dropout: self.config.noise.lidar_dropout,
            gaussian_std: self.config.noise.lidar_std,
        }
    }
}
