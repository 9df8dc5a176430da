//! [`Env`]: one environment, Gymnasium-shaped: `reset(seed) -> (obs, info)`,
//! `step(action) -> Step`.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

use super::arm::Arm;
use super::config::EnvConfig;
use super::error::{EnvError, EnvResult};
use super::spaces::{DType, Obs, ObsData, Space};
use super::tasks::viewpoints::CameraView;
use super::tasks::{BuildContext, Ending, Metrics, ResetContext, StepContext, Task};
use crate::assets::Category as AssetCategory;
use crate::randomize::{Randomizer, Stream, add_depth_noise, perturb_pose2d, randomize_objects};
use crate::scene::{GenerateOptions, MapOptions, SceneFile, SceneMaps, generate};
use crate::sensors::{
    Backend, Camera, CameraConfig, CameraIntrinsics, CulledRays, IgnoredHits, Lidar, LidarNoise, LidarSpec, Modality,
    ModalitySet, OccupancyGrid, OccupancyGridSpec, RASTER_MODALITIES, RenderOptions, Scan, VisualScene,
    lidar_pose_in_base, model_items,
};
use crate::world::{BUILDING_PREFIX, LoadedScene, ModelHandle, Snapshot, World, WorldConfig};

/// What an env reports besides observations and reward.
///
/// ```
/// let i = hearth_sim::env::Info::default();
/// assert!(i.ending.is_none());
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Info {
    /// Episode metrics so far.
    pub metrics: Metrics,
    /// Why the episode ended, when it did.
    pub ending: Option<Ending>,
    /// Whether this step had a collision.
    pub collision: bool,
    /// Seed of the current episode.
    pub episode_seed: u64,
}

/// The result of [`Env::step`].
///
/// ```
/// # use hearth_sim::env::{Env, EnvConfig};
/// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
/// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
/// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
/// # let path = std::env::temp_dir().join("hearth_sim_doc_step_struct.json");
/// # let written_file = path.clone();
/// # std::fs::write(&path, hall).unwrap();
/// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
///     "[sensors]\nmodalities = [\"task_obs\"]\n");
/// let mut config = EnvConfig::from_toml(toml)?;
/// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
/// let mut env = Env::new(config)?;
/// env.reset(0)?;
/// let step = env.step(&[1.0, 0.0])?;
/// assert!(step.reward.is_finite() && step.info.metrics.path_length > 0.0);
/// assert!(!step.terminated && !step.truncated);
/// assert_eq!(step.info.metrics.episode_length, 1);
/// # std::fs::remove_file(&written_file).ok();
/// # Ok::<(), hearth_sim::env::EnvError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// Observations after the step.
    pub obs: Obs,
    /// Reward of the step.
    pub reward: f64,
    /// The episode ended by the task (success, too many collisions, out of bounds).
    pub terminated: bool,
    /// The episode hit the step limit.
    pub truncated: bool,
    /// Metrics and the ending.
    pub info: Info,
}

struct LidarRig {
    visuals: VisualScene,
    planar: Option<(Lidar, Scan, CulledRays)>,
    multi: Option<(Lidar, Scan, CulledRays)>,
    grid: Option<OccupancyGrid>,
    sensor_in_base: Isometry3<f64>,
}

/// One environment: a home in the physics world, a wheeled robot under differential drive,
/// the configured sensors, and a task (see the [module docs](super) and `docs/env.md`).
///
/// Action: a box in [−1, 1]² scaled to (linear, angular) velocity by `robot.max_linear_speed`
/// and `robot.max_angular_speed`; for the manipulation tasks (`reaching`, `push_drawer`,
/// `push_cabinet`, `room_rearrangement`) 8 more entries command the Fetch's torso and arm
/// joint velocities as fractions of their limits. Each step is `physics.substeps` physics
/// steps.
///
/// ```no_run
/// use hearth_sim::env::{Env, EnvConfig};
/// let config = EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\n")?;
/// let mut env = Env::new(config)?;
/// let (obs, _info) = env.reset(7)?;
/// let step = env.step(&[0.5, 0.0])?;
/// println!("{} {}", step.reward, obs.entries.len());
/// # Ok::<(), hearth_sim::env::EnvError>(())
/// ```
pub struct Env {
    config: EnvConfig,
    world: World,
    robot: ModelHandle,
    /// The settled world with the robot, restored at every reset.
    home: Snapshot,
    maps: SceneMaps,
    task: Task,
    arm: Option<Arm>,
    camera: Option<Camera>,
    camera_set: ModalitySet,
    lidar: Option<LidarRig>,
    spaces: Vec<Space>,
    action_space: Space,
    /// Names of the scene's rug objects (contacts with them are not collisions).
    rug_names: Vec<String>,
    rng: Pcg64Mcg,
    episode_seed: u64,
    started: bool,
    /// Scratch for `task_obs`.
    task_obs: Vec<f32>,
    /// What `load_scene` spawned (physical randomisation works on it).
    loaded: LoadedScene,
    /// Domain randomisation, when the config turns any on.
    randomization: Option<Randomization>,
    /// This episode's camera mount perturbation (identity without one).
    camera_offset: Isometry3<f64>,
    /// This episode's depth-noise stream.
    noise_rng: Pcg64Mcg,
}

/// Domain-randomisation state of an env: the unrandomised home, the draws so far.
struct Randomization {
    randomizer: Randomizer,
    /// The home as configured; every draw starts from it.
    base: SceneFile,
    /// Resets so far: reset `e` gets draw `e`.
    resets: u64,
    /// Draw epoch the world now carries.
    epoch: Option<u64>,
}

impl std::fmt::Debug for Env {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Env")
            .field("task", &self.config.task.name)
            .field("robot", &self.config.robot.name)
            .finish_non_exhaustive()
    }
}

fn home_of(config: &EnvConfig) -> EnvResult<SceneFile> {
    let s = &config.scene;
    let mut scene = match &s.file {
        Some(path) => SceneFile::load(path)?,
        None => generate(&GenerateOptions {
            seed: s.generate,
            rooms: s.rooms,
            robot: Some(config.robot.name.clone()),
            small_objects: s.small_objects,
        })?,
    };
    match scene.robot.as_mut() {
        Some(r) => r.name = config.robot.name.clone(),
        None => {
            return Err(EnvError::Config {
                key: "scene.file".into(),
                reason: "the scene places no robot".into(),
            });
        }
    }
    Ok(scene)
}

impl Env {
    /// Builds the env: loads and settles the home, places the robot, creates the sensors.
    ///
    /// # Errors
    /// Configuration, scene, world or sensor errors, each naming the problem.
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_new.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config.clone())?;
    /// assert_eq!(env.config().robot.name, "turtlebot");
    /// config.scene.file = Some("no/such/scene.json".into());
    /// assert!(Env::new(config).is_err());
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn new(config: EnvConfig) -> EnvResult<Self> {
        config.validate()?;
        let home = home_of(&config)?;
        let randomization = if config.randomization.any() {
            Some(Randomization {
                randomizer: Randomizer::new(config.randomization.clone(), config.randomization.seed)?,
                base: home.clone(),
                resets: 0,
                epoch: None,
            })
        } else {
            None
        };
        let mut env = Self::build(config, &home)?;
        env.randomization = randomization;
        Ok(env)
    }

    /// Builds the env's world, maps, task and sensors on `home`.
    fn build(config: EnvConfig, home: &SceneFile) -> EnvResult<Self> {
        let home = home.clone();
        let world_config = WorldConfig {
            timestep: config.physics.timestep,
            substeps: config.physics.substeps,
            sleeping: config.physics.sleeping,
            ..WorldConfig::default()
        };
        let mut world = World::new(world_config)?;
        let loaded = world.load_scene(&home)?;
        let robot = loaded
            .robot
            .ok_or_else(|| EnvError::Task("the scene placed no robot".into()))?;
        world.settle(120);
        let maps = SceneMaps::build(
            &home,
            &MapOptions {
                resolution: 0.05,
                // A margin keeps sampled starts and planned paths off the furniture's edges.
                robot_radius: robot_radius(&config.robot.name) + 0.05,
                floor_clearance: ground_clearance(&config.robot.name),
                ..MapOptions::default()
            },
        )?;
        let task = Task::new(
            &config.task,
            BuildContext {
                home: &home,
                loaded: &loaded,
                world: &mut world,
                maps: &maps,
                robot,
                camera: CameraView::of(&config.sensors.camera),
            },
        )?;
        let arm = if task.uses_arm() {
            Some(Arm::new(&world, robot)?)
        } else {
            None
        };
        let names: Vec<&str> = config.sensors.modalities.iter().map(String::as_str).collect();
        let mut camera_set: ModalitySet = names.iter().filter_map(|n| n.parse::<Modality>().ok()).collect();
        if task.needs_seg() {
            // object_nav judges success on the semantic image, listed or not.
            camera_set = camera_set.with(Modality::Seg);
        }
        let camera = if camera_set.is_empty() {
            None
        } else {
            let c = &config.sensors.camera;
            let intrinsics = CameraIntrinsics {
                width: c.width,
                height: c.height,
                vfov_deg: c.vfov,
                near: c.near,
                far: c.far,
            };
            intrinsics.validate()?;
            let mut backend: Backend = c.backend.parse()?;
            // Depth, point clouds, normals and ids need no colour pipeline: `auto` takes the CPU
            // rasteriser for them (same triangles as wgpu, a fraction of the cost per frame).
            if backend == Backend::Auto && camera_set.iter().all(|m| RASTER_MODALITIES.contains(m)) {
                backend = Backend::Raster;
            }
            Some(Camera::new(
                &world,
                Some(robot),
                CameraConfig {
                    intrinsics,
                    options: RenderOptions::default(),
                    backend,
                    mount: None,
                },
            )?)
        };
        let wants = |n: &str| names.contains(&n);
        let lidar = if wants("scan") || wants("scan_16") || wants("occupancy_grid") {
            let l = &config.sensors.lidar;
            let extra = &config.randomization.noise;
            // Randomisation's LiDAR noise, when set, replaces the sensor's own.
            let noise = if extra.lidar_dropout > 0.0 || extra.lidar_std > 0.0 {
                LidarNoise {
                    dropout: extra.lidar_dropout,
                    gaussian_std: extra.lidar_std,
                }
            } else {
                LidarNoise {
                    dropout: l.dropout,
                    gaussian_std: l.noise_std,
                }
            };
            let visuals = VisualScene::from_world(&world);
            let own = model_items(&visuals, &world, robot)?;
            let planar_spec = if l.model == "sick" {
                LidarSpec::sick_tim571()
            } else {
                LidarSpec::hokuyo_urg_04lx()
            };
            let make = |spec: LidarSpec, salt: u64| -> EnvResult<(Lidar, Scan, CulledRays)> {
                let mut lidar = Lidar::new(spec, noise, salt)?;
                lidar.ignore_items(own.iter().copied(), IgnoredHits::PassThrough);
                Ok((lidar, Scan::default(), CulledRays::default()))
            };
            let planar = if wants("scan") || wants("occupancy_grid") {
                Some(make(planar_spec, 1)?)
            } else {
                None
            };
            let multi = if wants("scan_16") {
                Some(make(LidarSpec::velodyne_vlp16(l.vlp16_resolution_deg)?, 2)?)
            } else {
                None
            };
            let grid = if wants("occupancy_grid") {
                Some(OccupancyGrid::new(OccupancyGridSpec {
                    size: l.grid_size,
                    resolution: l.grid_resolution,
                    footprint_radius: robot_radius(&config.robot.name),
                    ..OccupancyGridSpec::default()
                })?)
            } else {
                None
            };
            Some(LidarRig {
                visuals,
                planar,
                multi,
                grid,
                sensor_in_base: lidar_pose_in_base(&world, robot, None)?,
            })
        } else {
            None
        };
        let rug_names = home
            .objects
            .iter()
            .filter(|o| o.category == AssetCategory::Rug.name())
            .map(|o| o.name.clone())
            .collect();
        let mut env = Self {
            rug_names,
            home: world.snapshot(),
            world,
            robot,
            maps,
            action_space: Space::boxed("action", &[2 + arm.as_ref().map_or(0, Arm::len)], DType::F32, -1.0, 1.0),
            task,
            arm,
            camera,
            camera_set,
            lidar,
            spaces: Vec::new(),
            task_obs: Vec::new(),
            rng: Pcg64Mcg::seed_from_u64(0),
            episode_seed: 0,
            started: false,
            config,
            loaded,
            randomization: None,
            camera_offset: Isometry3::identity(),
            noise_rng: Pcg64Mcg::seed_from_u64(0),
        };
        env.spaces = env.describe();
        Ok(env)
    }

    /// The observation spaces, in the order observations come.
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_spaces.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config)?;
    /// let spaces = env.observation_spaces();
    /// assert_eq!(spaces.len(), 1);
    /// assert_eq!(spaces[0].name, "task_obs");
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn observation_spaces(&self) -> &[Space] {
        &self.spaces
    }

    /// The action space: (linear, angular) in [−1, 1], then for the manipulation tasks the
    /// velocities of the torso and the 7 arm joints in [−1, 1] (fractions of their limits).
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_action.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config)?;
    /// assert_eq!(env.action_space().shape, [2]); // (linear, angular)
    /// assert_eq!((env.action_space().low, env.action_space().high), (-1.0, 1.0));
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn action_space(&self) -> &Space {
        &self.action_space
    }

    /// The configuration.
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_config.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config)?;
    /// assert_eq!(env.config().task.name, "point_nav_fixed");
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn config(&self) -> &EnvConfig {
        &self.config
    }

    /// The physics world (read-only).
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_world.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config)?;
    /// assert_eq!(env.world().models().count(), 1); // the robot
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The robot's model handle.
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_robot.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config)?;
    /// assert_eq!(env.world().model(env.robot())?.name(), "turtlebot");
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn robot(&self) -> ModelHandle {
        self.robot
    }

    /// The home's traversability map (cells the robot's footprint fits), for scripted policies
    /// and planners (`SceneMaps::shortest_path`).
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_maps.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let env = Env::new(config)?;
    /// assert!(env.maps().is_traversable([3.0, 1.0]));
    /// assert!(!env.maps().is_traversable([3.0, 5.0]));
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn maps(&self) -> &SceneMaps {
        &self.maps
    }

    /// Start (x, y, yaw) and goal (x, y) of the current episode (for tasks without a point
    /// goal, the (x, y) of [`Env::goal`]).
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_start_goal.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let mut env = Env::new(config)?;
    /// env.reset(0)?;
    /// let (start, goal) = env.start_and_goal();
    /// assert_eq!((start, goal), ([1.0, 1.0, 0.0], [4.0, 1.0]));
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn start_and_goal(&self) -> ([f64; 3], [f64; 2]) {
        let g = self.task.goal();
        (self.task.start(), [g[0], g[1]])
    }

    /// The camera backend in use (`auto` resolved: [`Backend::Raster`], [`Backend::Wgpu`] or
    /// [`Backend::Raycast`]), or `None` without camera observations.
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// use hearth_sim::sensors::Backend;
    /// let toml = "[task]\nname = \"point_nav_random\"\n[sensors]\nmodalities = [\"task_obs\", \"depth\"]\n";
    /// let env = Env::new(EnvConfig::from_toml(toml)?)?;
    /// assert_eq!(env.camera_backend(), Some(Backend::Raster));
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn camera_backend(&self) -> Option<Backend> {
        self.camera.as_ref().map(Camera::backend)
    }

    /// The task's name (`config.task.name`).
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// let env = Env::new(EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\n")?)?;
    /// assert_eq!(env.task_name(), "point_nav_random");
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn task_name(&self) -> &str {
        &self.config.task.name
    }

    /// The current episode's goal as a world point: the navigation goal (z = 0), the reaching
    /// goal of the gripper, the nearest instance of the `object_nav` category (z = 0), or the
    /// front of the piece of furniture an articulated task starts the robot at (z = 0).
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// let toml = "[robot]\nname = \"fetch\"\n[task]\nname = \"reaching\"\n";
    /// let mut env = Env::new(EnvConfig::from_toml(toml)?)?;
    /// env.reset(0)?;
    /// let [_, _, z] = env.goal();
    /// assert!((0.5..=1.2).contains(&z));
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn goal(&self) -> [f64; 3] {
        self.task.goal()
    }

    /// The category `object_nav` looks for this episode (`None` for other tasks).
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// let toml = "[task]\nname = \"object_nav\"\ntarget_category = \"fridge\"\n";
    /// let mut env = Env::new(EnvConfig::from_toml(toml)?)?;
    /// env.reset(0)?;
    /// assert_eq!(env.target_category().map(|c| c.name()), Some("fridge"));
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn target_category(&self) -> Option<AssetCategory> {
        match &self.task {
            Task::ObjectNav(t) => Some(t.category()),
            _ => None,
        }
    }

    /// The furniture an articulated task closes this episode: (object name, joint names).
    /// Empty for other tasks.
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// let toml = "[robot]\nname = \"fetch\"\n[task]\nname = \"push_drawer\"\n";
    /// let mut env = Env::new(EnvConfig::from_toml(toml)?)?;
    /// env.reset(0)?;
    /// for (object, joints) in env.task_objects() {
    ///     assert!(joints.iter().all(|j| j.starts_with("drawer_")), "{object}");
    /// }
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn task_objects(&self) -> Vec<(String, Vec<String>)> {
        match &self.task {
            Task::Articulated(t) => t.targets(),
            _ => Vec::new(),
        }
    }

    /// The physics world, writable: for scripted set-ups and tests (teleporting the arm to a
    /// goal, closing a drawer). Nothing checks such changes against the task; the next
    /// [`Env::step`] scores whatever state it finds.
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// let toml = "[robot]\nname = \"fetch\"\n[task]\nname = \"reaching\"\n";
    /// let mut env = Env::new(EnvConfig::from_toml(toml)?)?;
    /// env.reset(0)?;
    /// let robot = env.robot();
    /// env.world_mut().tuck(robot)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    fn describe(&self) -> Vec<Space> {
        let c = &self.config.sensors.camera;
        let (h, w) = (c.height as usize, c.width as usize);
        let mut out = Vec::new();
        for name in &self.config.sensors.modalities {
            let space = match name.as_str() {
                "rgb" => Space::boxed("rgb", &[h, w, 3], DType::U8, 0.0, 255.0),
                "depth" => Space::boxed("depth", &[h, w, 1], DType::F32, 0.0, c.far),
                "normal" => Space::boxed("normal", &[h, w, 3], DType::F32, -1.0, 1.0),
                "seg" => Space::boxed("seg", &[h, w], DType::U32, 0.0, u32::MAX as f64),
                "ins_seg" => Space::boxed("ins_seg", &[h, w], DType::U32, 0.0, u32::MAX as f64),
                "optical_flow" => Space::boxed("optical_flow", &[h, w, 2], DType::F32, f64::MIN, f64::MAX),
                "scene_flow" => Space::boxed("scene_flow", &[h, w, 3], DType::F32, f64::MIN, f64::MAX),
                "pc" => Space::boxed("pc", &[h, w, 3], DType::F32, -c.far, c.far),
                "scan" => {
                    let rays = self.lidar_rays(false);
                    Space::boxed("scan", &[rays, 1], DType::F32, 0.0, 1.0)
                }
                "scan_16" => {
                    let rays = self.lidar_rays(true);
                    Space::boxed("scan_16", &[rays, 1], DType::F32, 0.0, 1.0)
                }
                "occupancy_grid" => {
                    let n = self.config.sensors.lidar.grid_size;
                    Space::boxed("occupancy_grid", &[n, n, 1], DType::F32, 0.0, 1.0)
                }
                "task_obs" => Space::boxed("task_obs", &[self.task.obs_len()], DType::F32, f64::MIN, f64::MAX),
                "proprioception" => Space::boxed(
                    "proprioception",
                    &[2 + self.arm.as_ref().map_or(0, Arm::len)],
                    DType::F32,
                    f64::MIN,
                    f64::MAX,
                ),
                "bump" => Space::boxed("bump", &[1], DType::F32, 0.0, 1.0),
                _ => continue,
            };
            out.push(space);
        }
        out
    }

    fn lidar_rays(&self, multi: bool) -> usize {
        let Some(rig) = &self.lidar else { return 0 };
        let l = if multi { &rig.multi } else { &rig.planar };
        l.as_ref().map_or(0, |(l, _, _)| l.spec().rays())
    }

    /// Starts an episode: restores the settled home, lets the task pick the start (and goal,
    /// target, open joints, obstacles) from `seed`, places the robot, and observes.
    ///
    /// # Errors
    /// [`EnvError::Task`] when no start and goal fit the task; sensor errors.
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_reset.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let mut env = Env::new(config)?;
    /// let (obs, info) = env.reset(7)?;
    /// assert_eq!(info.episode_seed, 7);
    /// let task = obs.get("task_obs").and_then(|d| d.as_f32()).unwrap();
    /// assert!((task[0] - 3.0).abs() < 0.05, "the goal is 3 m ahead: {task:?}");
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn reset(&mut self, seed: u64) -> EnvResult<(Obs, Info)> {
        let episode = self.randomize()?;
        self.world.restore(&self.home)?;
        self.rng = Pcg64Mcg::seed_from_u64(seed);
        self.episode_seed = seed;
        let start = self.task.reset(ResetContext {
            world: &mut self.world,
            maps: &self.maps,
            rng: &mut self.rng,
        })?;
        let [x, y, yaw] = self.perturb_start(episode, start);
        let z = self.world.base_pose(self.robot)?.translation.z;
        let pose = Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        );
        self.world.place(self.robot, &pose)?;
        self.world.drive(self.robot, 0.0, 0.0)?;
        if let Some(camera) = &mut self.camera {
            camera.reset_flow();
        }
        if let Some(rig) = &mut self.lidar {
            for (l, _, _) in rig.planar.iter_mut().chain(rig.multi.iter_mut()) {
                l.reseed(seed);
            }
        }
        self.sense()?;
        let base = self.world.base_pose(self.robot)?;
        let ctx = StepContext {
            world: &self.world,
            robot: self.robot,
            base,
            collided: false,
            touched: false,
            on_map: true,
            seg: seg_of(&self.task, self.camera.as_ref()),
        };
        self.task.begin(&ctx)?;
        self.started = true;
        let obs = self.observe(false)?;
        Ok((
            obs,
            Info {
                metrics: self.task.metrics(),
                ending: None,
                collision: false,
                episode_seed: seed,
            },
        ))
    }

    /// Applies `action` for one control step and observes.
    ///
    /// # Errors
    /// [`EnvError::NotReset`] before the first reset; [`EnvError::BadAction`] for a wrong
    /// length or a non-finite entry (the world is not touched).
    ///
    /// ```
    /// # use hearth_sim::env::{Env, EnvConfig};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_env_step.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let mut env = Env::new(config)?;
    /// assert!(env.step(&[0.0, 0.0]).is_err(), "reset first");
    /// env.reset(0)?;
    /// assert!(env.step(&[0.5]).is_err(), "two values");
    /// let before = env.world().time();
    /// env.step(&[0.5, 0.0])?;
    /// assert!(env.world().time() > before);
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn step(&mut self, action: &[f32]) -> EnvResult<Step> {
        if !self.started {
            return Err(EnvError::NotReset);
        }
        let want = self.action_space.size();
        if action.len() != want {
            return Err(EnvError::BadAction(format!(
                "expected {want} values, got {}",
                action.len()
            )));
        }
        if let Some(bad) = action.iter().find(|a| !a.is_finite()) {
            return Err(EnvError::BadAction(format!("non-finite entry {bad}")));
        }
        let r = &self.config.robot;
        let v = action[0].clamp(-1.0, 1.0) as f64 * r.max_linear_speed;
        let w = action[1].clamp(-1.0, 1.0) as f64 * r.max_angular_speed;
        self.world.drive(self.robot, v, w)?;
        if let Some(arm) = &mut self.arm {
            arm.apply(&mut self.world, self.robot, &action[2..])?;
        }
        self.world.step();
        let (collided, touched) = self.contacts()?;
        self.sense()?;
        let base = self.world.base_pose(self.robot)?;
        let on_map = self.maps.cell_of([base.translation.x, base.translation.y]).is_some() && base.translation.z > -0.5;
        let ctx = StepContext {
            world: &self.world,
            robot: self.robot,
            base,
            collided,
            touched,
            on_map,
            seg: seg_of(&self.task, self.camera.as_ref()),
        };
        let (reward, ending) = self.task.step(&ctx);
        let metrics = self.task.metrics();
        let truncated = ending.is_none() && metrics.episode_length >= self.config.episode.max_steps;
        let ending = ending.or(truncated.then_some(Ending::Timeout));
        let obs = self.observe(collided)?;
        Ok(Step {
            obs,
            reward,
            terminated: ending.is_some() && !truncated,
            truncated,
            info: Info {
                metrics,
                ending,
                collision: collided,
                episode_seed: self.episode_seed,
            },
        })
    }

    /// Whether the robot touches anything but the floor, rugs and the task's objects (a
    /// collision), and whether it touches one of the task's objects.
    fn contacts(&self) -> EnvResult<(bool, bool)> {
        let floor = |name: &str| {
            let model = name.split('/').next().unwrap_or(name);
            name == "ground"
                || name
                    .strip_prefix(BUILDING_PREFIX)
                    .is_some_and(|rest| rest.starts_with("floor/"))
                || self.rug_names.iter().any(|r| r == model)
        };
        let own = self.task.own_objects();
        let (mut collided, mut touched) = (false, false);
        self.world.for_each_contact(self.robot, |c| {
            if c.force.norm() <= 0.0 || floor(c.other_name) {
                return;
            }
            let model = c.other_name.split('/').next().unwrap_or(c.other_name);
            if own.iter().any(|o| o == model) {
                touched = true;
            } else {
                collided = true;
            }
        })?;
        Ok((collided, touched))
    }

    /// Renders the camera and scans the LiDARs.
    /// Applies the randomisation of the coming episode: a new draw (object models → a rebuilt
    /// world; physical properties; visual materials) when the episode starts a new draw epoch,
    /// and this episode's camera offset and noise stream. Returns the episode's index.
    fn randomize(&mut self) -> EnvResult<Option<u64>> {
        let Some(mut r) = self.randomization.take() else {
            return Ok(None);
        };
        let result = self.apply_draw(&mut r);
        self.randomization = Some(r);
        result
    }

    fn apply_draw(&mut self, r: &mut Randomization) -> EnvResult<Option<u64>> {
        let e = r.resets;
        let epoch = r.randomizer.epoch(e);
        if r.epoch != Some(epoch) {
            let config = r.randomizer.config().clone();
            if config.objects.enabled {
                let mut scene = r.base.clone();
                randomize_objects(&mut scene, &config.objects, &mut r.randomizer.rng(e, Stream::Objects))?;
                *self = Self::build(self.config.clone(), &scene)?;
            }
            self.world.restore(&self.home)?;
            r.randomizer.apply_world(e, &mut self.world, &self.loaded)?;
            if let Some(camera) = &mut self.camera {
                r.randomizer.apply_camera(e, &self.world, camera)?;
            }
            self.home = self.world.snapshot();
            r.epoch = Some(epoch);
        }
        self.camera_offset = r.randomizer.camera_offset(e);
        self.noise_rng = r.randomizer.rng(e, Stream::Noise);
        r.resets += 1;
        Ok(Some(e))
    }

    /// The task's start, perturbed by the configured start-pose noise when that lands on the
    /// traversability map (otherwise unperturbed).
    fn perturb_start(&self, episode: Option<u64>, start: [f64; 3]) -> [f64; 3] {
        let (Some(e), Some(r)) = (episode, &self.randomization) else {
            return start;
        };
        let p = &r.randomizer.config().pose;
        if p.robot_xy_std <= 0.0 && p.robot_yaw_std <= 0.0 {
            return start;
        }
        let mut rng = r.randomizer.rng(e, Stream::RobotPose);
        let (xy, yaw) = perturb_pose2d(
            [start[0], start[1]],
            start[2],
            p.robot_xy_std,
            p.robot_yaw_std,
            &mut rng,
        );
        if self.maps.is_traversable(xy) {
            [xy[0], xy[1], yaw]
        } else {
            [start[0], start[1], yaw]
        }
    }

    /// The episode index and draw epoch of the last reset, when randomisation is on.
    ///
    /// ```no_run
    /// use hearth_sim::env::{Env, EnvConfig};
    /// let toml = "[task]\nname = \"point_nav_random\"\n[randomization.physics]\nenabled = true\nfriction = true\n";
    /// let mut env = Env::new(EnvConfig::from_toml(toml)?)?;
    /// env.reset(0)?;
    /// assert_eq!(env.randomization_episode(), Some((0, 0)));
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn randomization_episode(&self) -> Option<(u64, u64)> {
        let r = self.randomization.as_ref()?;
        let e = r.resets.checked_sub(1)?;
        Some((e, r.randomizer.epoch(e)))
    }

    fn sense(&mut self) -> EnvResult<()> {
        let world = &self.world;
        let (robot, offset, set) = (self.robot, self.camera_offset, self.camera_set);
        let render = |camera: &mut Camera| -> EnvResult<()> {
            if offset == Isometry3::identity() {
                camera.render(world, set)?;
            } else {
                let pose = camera.pose(world)? * offset;
                camera.render_from(world, &pose, set)?;
            }
            Ok(())
        };
        let scan = |rig: &mut LidarRig| -> EnvResult<()> {
            let base = world.base_pose(robot)?;
            let sensor = base * rig.sensor_in_base;
            for (l, scan, culled) in rig.planar.iter_mut().chain(rig.multi.iter_mut()) {
                l.scan_culled(culled, &rig.visuals, world, &sensor, scan);
            }
            if let (Some(grid), Some((_, scan, _))) = (&mut rig.grid, &rig.planar) {
                grid.update(scan, &rig.sensor_in_base)?;
            }
            Ok(())
        };
        // The camera and the LiDARs read the world only: with both, they run side by side.
        match (&mut self.camera, &mut self.lidar) {
            (Some(camera), Some(rig)) => {
                let (a, b) = rayon::join(|| render(camera), || scan(rig));
                a?;
                b?;
            }
            (Some(camera), None) => render(camera)?,
            (None, Some(rig)) => scan(rig)?,
            (None, None) => {}
        }
        Ok(())
    }

    /// Assembles the observations from what [`Env::sense`] measured.
    fn observe(&mut self, bump: bool) -> EnvResult<Obs> {
        let pose = self.world.base_pose(self.robot)?;
        let twist = self.world.base_twist(self.robot)?;
        let yaw = pose.rotation.euler_angles().2;
        // Forward speed and yaw rate in the base frame.
        let (s, c) = yaw.sin_cos();
        let v = c * twist.linear.x + s * twist.linear.y;
        let omega = twist.angular.z;
        {
            let ctx = StepContext {
                world: &self.world,
                robot: self.robot,
                base: pose,
                collided: bump,
                touched: false,
                on_map: true,
                seg: None,
            };
            self.task.task_obs(&ctx, v, omega, &mut self.task_obs);
        }
        let mut obs = Obs::default();
        for space in &self.spaces {
            let data = match space.name.as_str() {
                "scan" | "scan_16" | "occupancy_grid" => {
                    let rig = self.lidar.as_ref().expect("LiDAR observations come with a LiDAR rig");
                    let mut out = Vec::new();
                    match space.name.as_str() {
                        "scan" => {
                            if let Some((_, scan, _)) = &rig.planar {
                                scan.normalized_into(&mut out);
                            }
                        }
                        "scan_16" => {
                            if let Some((_, scan, _)) = &rig.multi {
                                scan.normalized_into(&mut out);
                            }
                        }
                        _ => {
                            if let Some(grid) = &rig.grid {
                                grid.to_f32_into(&mut out);
                            }
                        }
                    }
                    ObsData::F32(out)
                }
                "task_obs" => ObsData::F32(self.task_obs.clone()),
                "proprioception" => {
                    let mut out = vec![v as f32, omega as f32];
                    if let Some(arm) = &self.arm {
                        arm.positions(&self.world, self.robot, &mut out)?;
                    }
                    ObsData::F32(out)
                }
                "bump" => ObsData::F32(vec![if bump { 1.0 } else { 0.0 }]),
                name => {
                    let camera = self.camera.as_ref().expect("camera observations come with a camera");
                    let f = camera.frame();
                    match name {
                        "rgb" => ObsData::U8(f.rgb.clone()),
                        "depth" => {
                            let mut depth = f.depth.clone();
                            if let Some(r) = &self.randomization {
                                let noise = r.randomizer.depth_noise();
                                if !noise.is_none() {
                                    add_depth_noise(&mut depth, &noise, &mut self.noise_rng);
                                }
                            }
                            ObsData::F32(depth)
                        }
                        "normal" => ObsData::F32(f.normal.iter().flatten().copied().collect()),
                        "seg" => ObsData::U32(f.seg.clone()),
                        "ins_seg" => ObsData::U32(f.ins_seg.clone()),
                        "optical_flow" => ObsData::F32(f.optical_flow.iter().flatten().copied().collect()),
                        "scene_flow" => ObsData::F32(f.scene_flow.iter().flatten().copied().collect()),
                        _ => ObsData::F32(f.pc.iter().flatten().copied().collect()),
                    }
                }
            };
            obs.entries.push((space.name.clone(), data));
        }
        Ok(obs)
    }
}

/// The semantic image, for the tasks that read it.
fn seg_of<'a>(task: &Task, camera: Option<&'a Camera>) -> Option<&'a [u32]> {
    if task.needs_seg() {
        camera.map(|c| c.frame().seg.as_slice())
    } else {
        None
    }
}

/// Height under which floor coverings do not block the robot's base (m): the TurtleBot's and
/// LoCoBot's bases clear about 1 cm, so rugs block them; the Fetch drives over them.
fn ground_clearance(name: &str) -> f64 {
    match name {
        "fetch" => 0.03,
        _ => 0.008,
    }
}

/// Footprint radius of the built-in wheeled robots (m).
fn robot_radius(name: &str) -> f64 {
    match name {
        "fetch" => 0.32,
        "locobot" => 0.2,
        _ => 0.18,
    }
}
