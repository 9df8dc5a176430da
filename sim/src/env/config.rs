//! [`EnvConfig`]: the TOML file that builds an environment. Unknown keys and bad values are
//! errors that name the key.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::error::{EnvError, EnvResult};
use crate::assets::Category;
use crate::randomize::{RandomizationConfig, RandomizeError};

/// Where the home comes from.
///
/// ```
/// use hearth_sim::env::EnvConfig;
/// let c = EnvConfig::from_toml("[scene]\ngenerate = 4\nrooms = 5\n[task]\nname = \"object_nav\"\n").unwrap();
/// assert_eq!((c.scene.generate, c.scene.rooms), (4, 5));
/// assert!(c.scene.file.is_none() && c.scene.small_objects);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// Generate a home with this seed (used when `file` is absent).
    #[serde(default = "default_generate")]
    pub generate: u64,
    /// A scene file (JSON) instead of a generated home.
    #[serde(default)]
    pub file: Option<PathBuf>,
    /// Rooms of a generated home besides the corridor (2 to 12).
    #[serde(default = "default_rooms")]
    pub rooms: usize,
    /// Whether a generated home has small objects (books, mugs, …) on its surfaces.
    #[serde(default = "yes")]
    pub small_objects: bool,
}

fn default_generate() -> u64 {
    1
}
fn default_rooms() -> usize {
    3
}
fn yes() -> bool {
    true
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self {
            generate: default_generate(),
            file: None,
            rooms: default_rooms(),
            small_objects: true,
        }
    }
}

/// The robot and its base controller.
///
/// ```
/// use hearth_sim::env::RobotConfig;
/// let r = RobotConfig::default();
/// assert_eq!(r.name, "turtlebot");
/// assert_eq!((r.max_linear_speed, r.max_angular_speed), (0.5, 1.5));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotConfig {
    /// Built-in wheeled robot: `turtlebot`, `locobot` or `fetch`.
    #[serde(default = "default_robot")]
    pub name: String,
    /// Linear speed (m/s) an action of +1 commands.
    #[serde(default = "default_linear")]
    pub max_linear_speed: f64,
    /// Angular speed (rad/s) an action of +1 commands.
    #[serde(default = "default_angular")]
    pub max_angular_speed: f64,
}

fn default_robot() -> String {
    "turtlebot".into()
}
fn default_linear() -> f64 {
    0.5
}
fn default_angular() -> f64 {
    1.5
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            name: default_robot(),
            max_linear_speed: default_linear(),
            max_angular_speed: default_angular(),
        }
    }
}

/// The task and its reward (see `docs/env.md` for which keys each task reads).
///
/// ```
/// use hearth_sim::env::EnvConfig;
/// let c = EnvConfig::from_toml("[task]\nname = \"point_nav_fixed\"\nstart = [0, 0, 0]\ngoal = [2, 1]\n").unwrap();
/// assert_eq!(c.task.goal, Some([2.0, 1.0]));
/// assert_eq!(c.task.goal_tolerance, 0.36);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskConfig {
    /// One of [`TASK_NAMES`].
    pub name: String,
    /// Fixed start (x, y, yaw) for `point_nav_fixed`.
    #[serde(default)]
    pub start: Option<[f64; 3]>,
    /// Fixed goal (x, y) for `point_nav_fixed`.
    #[serde(default)]
    pub goal: Option<[f64; 2]>,
    /// Navigation success when the base is this close to the goal (m; iGibson: 0.36).
    #[serde(default = "default_tolerance")]
    pub goal_tolerance: f64,
    /// Geodesic start–goal distance range (m) for `point_nav_random`, `interactive_nav` and
    /// `object_nav` (distance to the nearest view of the category).
    #[serde(default = "default_geodesic_range")]
    pub geodesic_range: [f64; 2],
    /// Potential the navigation shaping reward follows: `geodesic` or `l2`.
    #[serde(default = "default_potential")]
    pub potential: String,
    /// Weight of the potential reward (per metre of progress, or per unit of total opening).
    #[serde(default = "one")]
    pub potential_weight: f64,
    /// Penalty per step with a collision (subtracted).
    #[serde(default = "default_collision_penalty")]
    pub collision_penalty: f64,
    /// Reward on success.
    #[serde(default = "default_success")]
    pub success_reward: f64,
    /// Terminate after this many collision steps (0: never).
    #[serde(default)]
    pub max_collisions: u32,
    /// `object_nav`: the category to find (e.g. `fridge`); absent: each episode draws one of
    /// the large-furniture categories present in the home.
    #[serde(default)]
    pub target_category: Option<String>,
    /// `object_nav`: success when the category covers at least this fraction of the `seg`
    /// image.
    #[serde(default = "default_visibility")]
    pub visible_fraction: f64,
    /// `interactive_nav`: movable obstacles placed on the shortest path each episode, as
    /// `category/variant` of the asset library.
    #[serde(default = "default_obstacles")]
    pub obstacles: Vec<String>,
    /// `reaching`: goal distance ahead of the start (m, along the robot's heading).
    #[serde(default = "default_goal_ahead")]
    pub goal_ahead: [f64; 2],
    /// `reaching`: largest sideways goal offset (m, either side).
    #[serde(default = "default_goal_lateral")]
    pub goal_lateral: f64,
    /// `reaching`: goal height above the floor (m).
    #[serde(default = "default_goal_height")]
    pub goal_height: [f64; 2],
    /// `reaching`: success when the gripper is this close to the goal (m; iGibson: 0.1).
    #[serde(default = "default_reach_tolerance")]
    pub reach_tolerance: f64,
    /// `push_drawer`, `push_cabinet`: the object to close (a scene object name); absent: each
    /// episode draws one of the home's bottom cabinets with drawers (doors).
    #[serde(default)]
    pub target_object: Option<String>,
    /// `room_rearrangement`: the room (a scene room name); absent: each episode draws a room
    /// with articulated furniture.
    #[serde(default)]
    pub room: Option<String>,
    /// Articulated tasks: each joint is opened at reset to a uniform fraction of its range in
    /// this interval.
    #[serde(default = "default_open_range")]
    pub open_range: [f64; 2],
    /// Articulated tasks: a joint counts as closed within this fraction of its range from its
    /// closed limit.
    #[serde(default = "default_closed_tolerance")]
    pub closed_tolerance: f64,
    /// Articulated tasks: only joints whose handle (the front-most part of the moving link,
    /// closed) lies in this height band above the floor are closed (m); the default is the
    /// Fetch's reach (see `docs/env.md`).
    #[serde(default = "default_handle_height")]
    pub handle_height: [f64; 2],
}

fn default_tolerance() -> f64 {
    0.36
}
fn default_geodesic_range() -> [f64; 2] {
    [1.0, 10.0]
}
fn default_potential() -> String {
    "geodesic".into()
}
fn one() -> f64 {
    1.0
}
fn default_collision_penalty() -> f64 {
    0.1
}
fn default_success() -> f64 {
    10.0
}
fn default_visibility() -> f64 {
    0.05
}
fn default_obstacles() -> Vec<String> {
    vec!["chair/0".into(), "chair/1".into()]
}
fn default_goal_ahead() -> [f64; 2] {
    [0.4, 0.9]
}
fn default_goal_lateral() -> f64 {
    0.3
}
fn default_goal_height() -> [f64; 2] {
    [0.5, 1.2]
}
fn default_reach_tolerance() -> f64 {
    0.1
}
fn default_open_range() -> [f64; 2] {
    [0.3, 1.0]
}
fn default_closed_tolerance() -> f64 {
    0.05
}
fn default_handle_height() -> [f64; 2] {
    [0.1, 1.5]
}

impl TaskConfig {
    /// A task of this name with every other key at its default.
    ///
    /// ```
    /// let t = hearth_sim::env::TaskConfig::named("reaching");
    /// assert_eq!(t.reach_tolerance, 0.1);
    /// ```
    pub fn named(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            start: None,
            goal: None,
            goal_tolerance: default_tolerance(),
            geodesic_range: default_geodesic_range(),
            potential: default_potential(),
            potential_weight: one(),
            collision_penalty: default_collision_penalty(),
            success_reward: default_success(),
            max_collisions: 0,
            target_category: None,
            visible_fraction: default_visibility(),
            obstacles: default_obstacles(),
            goal_ahead: default_goal_ahead(),
            goal_lateral: default_goal_lateral(),
            goal_height: default_goal_height(),
            reach_tolerance: default_reach_tolerance(),
            target_object: None,
            room: None,
            open_range: default_open_range(),
            closed_tolerance: default_closed_tolerance(),
            handle_height: default_handle_height(),
        }
    }

    /// Whether the task moves the arm (its action has arm joint velocities after (v, ω)).
    ///
    /// ```
    /// use hearth_sim::env::TaskConfig;
    /// assert!(TaskConfig::named("push_drawer").uses_arm());
    /// assert!(!TaskConfig::named("object_nav").uses_arm());
    /// ```
    pub fn uses_arm(&self) -> bool {
        ARM_TASKS.contains(&self.name.as_str())
    }
}

/// Tasks that need the Fetch and move its arm.
const ARM_TASKS: [&str; 4] = ["reaching", "push_drawer", "push_cabinet", "room_rearrangement"];

/// Camera settings for the `rgb`, `depth`, … observations.
///
/// ```
/// use hearth_sim::env::CameraSection;
/// let cam = CameraSection::default();
/// assert_eq!((cam.width, cam.height, cam.backend.as_str()), (128, 128, "auto"));
/// assert!(cam.near < cam.far);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// Image width.
    #[serde(default = "default_side")]
    pub width: u32,
    /// Image height.
    #[serde(default = "default_side")]
    pub height: u32,
    /// Vertical field of view, degrees.
    #[serde(default = "default_vfov")]
    pub vfov: f64,
    /// Near clipping (m).
    #[serde(default = "default_near")]
    pub near: f64,
    /// Far clipping (m); depth beyond reads 0.
    #[serde(default = "default_far")]
    pub far: f64,
    /// `auto`, `wgpu`, `raycast` or `raster`. `auto` takes `raster` when every camera
    /// modality is geometric (depth, point cloud, normals, ids), else wgpu when an adapter
    /// exists, else `raycast`.
    #[serde(default = "default_backend")]
    pub backend: String,
}

fn default_side() -> u32 {
    128
}
fn default_vfov() -> f64 {
    90.0
}
fn default_near() -> f64 {
    0.05
}
fn default_far() -> f64 {
    5.0
}
fn default_backend() -> String {
    "auto".into()
}

impl Default for CameraSection {
    fn default() -> Self {
        Self {
            width: default_side(),
            height: default_side(),
            vfov: default_vfov(),
            near: default_near(),
            far: default_far(),
            backend: default_backend(),
        }
    }
}

/// LiDAR settings for `scan`, `scan_16` and `occupancy_grid`.
///
/// ```
/// use hearth_sim::env::LidarSection;
/// let lidar = LidarSection::default();
/// assert_eq!(lidar.model, "hokuyo");
/// assert_eq!((lidar.dropout, lidar.noise_std), (0.0, 0.0));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LidarSection {
    /// Planar model for `scan`: `hokuyo` (URG-04LX) or `sick` (TIM571).
    #[serde(default = "default_lidar")]
    pub model: String,
    /// Horizontal resolution of the 16-beam `scan_16`, degrees.
    #[serde(default = "default_vlp_resolution")]
    pub vlp16_resolution_deg: f64,
    /// Probability a ray returns nothing.
    #[serde(default)]
    pub dropout: f64,
    /// Gaussian range noise, m.
    #[serde(default)]
    pub noise_std: f64,
    /// Occupancy grid cells per side.
    #[serde(default = "default_grid")]
    pub grid_size: usize,
    /// Occupancy grid cell size, m.
    #[serde(default = "default_grid_resolution")]
    pub grid_resolution: f64,
}

fn default_lidar() -> String {
    "hokuyo".into()
}
fn default_vlp_resolution() -> f64 {
    2.0
}
fn default_grid() -> usize {
    128
}
fn default_grid_resolution() -> f64 {
    5.0 / 128.0
}

impl Default for LidarSection {
    fn default() -> Self {
        Self {
            model: default_lidar(),
            vlp16_resolution_deg: default_vlp_resolution(),
            dropout: 0.0,
            noise_std: 0.0,
            grid_size: default_grid(),
            grid_resolution: default_grid_resolution(),
        }
    }
}

/// Which observations and their sensors.
///
/// ```
/// use hearth_sim::env::EnvConfig;
/// let toml = "[task]\nname = \"object_nav\"\n[sensors]\nmodalities = [\"depth\"]\n[sensors.camera]\nwidth = 64\n";
/// let c = EnvConfig::from_toml(toml).unwrap();
/// assert_eq!(c.sensors.modalities, ["depth"]);
/// assert_eq!((c.sensors.camera.width, c.sensors.camera.height), (64, 128));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorsConfig {
    /// Observation names: `rgb`, `depth`, `normal`, `seg`, `ins_seg`, `optical_flow`,
    /// `scene_flow`, `pc`, `scan`, `scan_16`, `occupancy_grid`, `task_obs`,
    /// `proprioception`, `bump`.
    #[serde(default = "default_modalities")]
    pub modalities: Vec<String>,
    /// Camera settings.
    #[serde(default)]
    pub camera: CameraSection,
    /// LiDAR settings.
    #[serde(default)]
    pub lidar: LidarSection,
}

fn default_modalities() -> Vec<String> {
    vec!["task_obs".into(), "scan".into()]
}

impl Default for SensorsConfig {
    fn default() -> Self {
        Self {
            modalities: default_modalities(),
            camera: CameraSection::default(),
            lidar: LidarSection::default(),
        }
    }
}

/// Physics and control rates.
///
/// ```
/// use hearth_sim::env::PhysicsConfig;
/// let p = PhysicsConfig::default();
/// assert!((p.timestep * f64::from(p.substeps) - 1.0 / 30.0).abs() < 1e-12);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhysicsConfig {
    /// Physics step, s.
    #[serde(default = "default_timestep")]
    pub timestep: f64,
    /// Physics steps per action (4 at 1/120 s = 30 Hz control, as iGibson).
    #[serde(default = "default_substeps")]
    pub substeps: u32,
    /// Let resting bodies sleep (much faster; off for bit-exact comparisons with PyBullet).
    #[serde(default = "yes")]
    pub sleeping: bool,
}

fn default_timestep() -> f64 {
    1.0 / 120.0
}
fn default_substeps() -> u32 {
    4
}

impl Default for PhysicsConfig {
    fn default() -> Self {
        Self {
            timestep: default_timestep(),
            substeps: default_substeps(),
            sleeping: true,
        }
    }
}

/// Episode limits.
///
/// ```
/// use hearth_sim::env::EnvConfig;
/// let c = EnvConfig::from_toml("[task]\nname = \"object_nav\"\n[episode]\nmax_steps = 50\n").unwrap();
/// assert_eq!(c.episode.max_steps, 50);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpisodeConfig {
    /// Steps before an episode is truncated.
    #[serde(default = "default_max_steps")]
    pub max_steps: u32,
}

fn default_max_steps() -> u32 {
    500
}

impl Default for EpisodeConfig {
    fn default() -> Self {
        Self {
            max_steps: default_max_steps(),
        }
    }
}

/// A whole environment configuration (see `examples/configs/`).
///
/// ```
/// use hearth_sim::env::EnvConfig;
/// let c = EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\n").unwrap();
/// assert_eq!(c.robot.name, "turtlebot");
/// let err = EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\nspeed = 3\n").unwrap_err();
/// assert!(err.to_string().contains("speed"), "{err}");
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvConfig {
    /// The home.
    #[serde(default)]
    pub scene: SceneConfig,
    /// The robot.
    #[serde(default)]
    pub robot: RobotConfig,
    /// The task.
    pub task: TaskConfig,
    /// Observations.
    #[serde(default)]
    pub sensors: SensorsConfig,
    /// Physics.
    #[serde(default)]
    pub physics: PhysicsConfig,
    /// Episodes.
    #[serde(default)]
    pub episode: EpisodeConfig,
    /// Domain randomisation (`[randomization]`, every kind off by default; see
    /// `docs/randomization.md`).
    #[serde(default)]
    pub randomization: RandomizationConfig,
}

/// Observation names an env can produce.
///
/// ```
/// use hearth_sim::env::OBSERVATION_NAMES;
/// assert!(OBSERVATION_NAMES.contains(&"scan"));
/// assert!(!OBSERVATION_NAMES.contains(&"sonar"));
/// ```
pub const OBSERVATION_NAMES: [&str; 14] = [
    "rgb",
    "depth",
    "normal",
    "seg",
    "ins_seg",
    "optical_flow",
    "scene_flow",
    "pc",
    "scan",
    "scan_16",
    "occupancy_grid",
    "task_obs",
    "proprioception",
    "bump",
];

/// Task names.
///
/// ```
/// use hearth_sim::env::{TaskConfig, TASK_NAMES};
/// assert!(TASK_NAMES.contains(&"object_nav"));
/// assert_eq!(TASK_NAMES.iter().filter(|t| TaskConfig::named(t).uses_arm()).count(), 4);
/// ```
pub const TASK_NAMES: [&str; 8] = [
    "point_nav_fixed",
    "point_nav_random",
    "object_nav",
    "interactive_nav",
    "reaching",
    "push_drawer",
    "push_cabinet",
    "room_rearrangement",
];

fn bad(key: &str, reason: impl Into<String>) -> EnvError {
    EnvError::Config {
        key: key.to_owned(),
        reason: reason.into(),
    }
}

fn positive(key: &str, x: f64) -> EnvResult<()> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(bad(key, format!("{x} is not a positive number")))
    }
}

impl EnvConfig {
    /// Parses and validates TOML text.
    ///
    /// # Errors
    /// [`EnvError::Parse`] naming the unknown key or bad value and its line;
    /// [`EnvError::Config`] for values out of range.
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, EnvError};
    /// let c = EnvConfig::from_toml("[robot]\nname = \"fetch\"\n[task]\nname = \"reaching\"\n").unwrap();
    /// assert!(c.task.uses_arm());
    /// let err = EnvConfig::from_toml("[robot]\nname = \"turtlebot\"\n[task]\nname = \"reaching\"\n").unwrap_err();
    /// assert!(matches!(err, EnvError::Config { ref key, .. } if key == "robot.name"), "{err}");
    /// ```
    pub fn from_toml(text: &str) -> EnvResult<Self> {
        let config: EnvConfig = toml::from_str(text).map_err(|e| EnvError::Parse(e.to_string()))?;
        config.validate()?;
        Ok(config)
    }

    /// Reads and parses a TOML file.
    ///
    /// # Errors
    /// [`EnvError::Io`] when the file cannot be read, then as [`EnvConfig::from_toml`].
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, EnvError};
    /// let path = std::env::temp_dir().join("hearth_sim_doc_env.toml");
    /// std::fs::write(&path, "[task]\nname = \"object_nav\"\n").unwrap();
    /// assert_eq!(EnvConfig::load(&path).unwrap().task.name, "object_nav");
    /// assert!(matches!(EnvConfig::load(&path.with_extension("missing")), Err(EnvError::Io { .. })));
    /// # std::fs::remove_file(&path).ok();
    /// ```
    pub fn load(path: &std::path::Path) -> EnvResult<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| EnvError::Io {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::from_toml(&text)
    }

    /// Checks every value (what serde's types cannot).
    ///
    /// # Errors
    /// [`EnvError::Config`] naming the key.
    ///
    /// ```
    /// # use hearth_sim::env::EnvConfig;
    /// let mut c = EnvConfig::from_toml("[task]\nname = \"object_nav\"\n").unwrap();
    /// assert!(c.validate().is_ok());
    /// c.sensors.lidar.dropout = 1.5;
    /// assert!(c.validate().unwrap_err().to_string().contains("sensors.lidar.dropout"));
    /// ```
    pub fn validate(&self) -> EnvResult<()> {
        self.randomization.validate().map_err(|e| match e {
            RandomizeError::InvalidValue { key, value, reason } => EnvError::Config {
                key: format!("randomization.{key}"),
                reason: format!("= {value}: {reason}"),
            },
            other => EnvError::Randomize(other),
        })?;
        if !matches!(self.robot.name.as_str(), "turtlebot" | "locobot" | "fetch") {
            return Err(bad(
                "robot.name",
                format!(
                    "`{}` is not a wheeled built-in robot (turtlebot, locobot, fetch)",
                    self.robot.name
                ),
            ));
        }
        positive("robot.max_linear_speed", self.robot.max_linear_speed)?;
        positive("robot.max_angular_speed", self.robot.max_angular_speed)?;
        let t = &self.task;
        if !TASK_NAMES.contains(&t.name.as_str()) {
            return Err(bad(
                "task.name",
                format!("unknown task `{}` (known: {})", t.name, TASK_NAMES.join(", ")),
            ));
        }
        if t.name == "point_nav_fixed" && (t.start.is_none() || t.goal.is_none()) {
            return Err(bad("task.start", "point_nav_fixed needs both `start` and `goal`"));
        }
        for (key, v) in [
            ("task.start", t.start.map(|s| s.to_vec())),
            ("task.goal", t.goal.map(|g| g.to_vec())),
        ] {
            if let Some(v) = v
                && v.iter().any(|x| !x.is_finite())
            {
                return Err(bad(key, "has a non-finite coordinate"));
            }
        }
        positive("task.goal_tolerance", t.goal_tolerance)?;
        let [lo, hi] = t.geodesic_range;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
            return Err(bad(
                "task.geodesic_range",
                format!("[{lo}, {hi}] is not an increasing range ≥ 0"),
            ));
        }
        if t.uses_arm() && self.robot.name != "fetch" {
            return Err(bad(
                "robot.name",
                format!(
                    "task `{}` needs the `fetch` (an arm), not `{}`",
                    t.name, self.robot.name
                ),
            ));
        }
        self.validate_task_keys()?;
        if !matches!(t.potential.as_str(), "geodesic" | "l2") {
            return Err(bad(
                "task.potential",
                format!("`{}` is neither `geodesic` nor `l2`", t.potential),
            ));
        }
        for (key, x) in [
            ("task.potential_weight", t.potential_weight),
            ("task.collision_penalty", t.collision_penalty),
            ("task.success_reward", t.success_reward),
        ] {
            if !x.is_finite() {
                return Err(bad(key, format!("{x} is not finite")));
            }
        }
        for m in &self.sensors.modalities {
            if !OBSERVATION_NAMES.contains(&m.as_str()) {
                return Err(bad(
                    "sensors.modalities",
                    format!("unknown observation `{m}` (known: {})", OBSERVATION_NAMES.join(", ")),
                ));
            }
        }
        let c = &self.sensors.camera;
        if !matches!(c.backend.as_str(), "auto" | "wgpu" | "raycast" | "raster") {
            return Err(bad(
                "sensors.camera.backend",
                format!("`{}` is not auto, wgpu, raycast or raster", c.backend),
            ));
        }
        let l = &self.sensors.lidar;
        if !matches!(l.model.as_str(), "hokuyo" | "sick") {
            return Err(bad(
                "sensors.lidar.model",
                format!("`{}` is neither `hokuyo` nor `sick`", l.model),
            ));
        }
        if !(l.dropout.is_finite() && (0.0..=1.0).contains(&l.dropout)) {
            return Err(bad(
                "sensors.lidar.dropout",
                format!("{} is not a probability", l.dropout),
            ));
        }
        if !(l.noise_std.is_finite() && l.noise_std >= 0.0) {
            return Err(bad("sensors.lidar.noise_std", format!("{} is not ≥ 0", l.noise_std)));
        }
        positive("physics.timestep", self.physics.timestep)?;
        if self.physics.substeps == 0 {
            return Err(bad("physics.substeps", "must be at least 1"));
        }
        if self.episode.max_steps == 0 {
            return Err(bad("episode.max_steps", "must be at least 1"));
        }
        Ok(())
    }

    /// Checks the keys of the newer tasks (ranges, names of categories and assets).
    fn validate_task_keys(&self) -> EnvResult<()> {
        let t = &self.task;
        if let Some(c) = &t.target_category {
            match Category::from_name(c) {
                Some(cat) if !matches!(cat, Category::Door | Category::Window | Category::Rug) => {}
                _ => {
                    return Err(bad(
                        "task.target_category",
                        format!("`{c}` is not an object category to look for (e.g. fridge, bed, sofa)"),
                    ));
                }
            }
        }
        if !(t.visible_fraction.is_finite() && t.visible_fraction > 0.0 && t.visible_fraction <= 1.0) {
            return Err(bad(
                "task.visible_fraction",
                format!("{} is not a fraction in (0, 1]", t.visible_fraction),
            ));
        }
        for o in &t.obstacles {
            parse_asset(o).map_err(|reason| bad("task.obstacles", reason))?;
        }
        for (key, [lo, hi], min) in [
            ("task.goal_ahead", t.goal_ahead, 0.0),
            ("task.goal_height", t.goal_height, 0.0),
            ("task.open_range", t.open_range, 0.0),
            ("task.handle_height", t.handle_height, 0.0),
        ] {
            if !(lo.is_finite() && hi.is_finite() && lo >= min && hi >= lo) {
                return Err(bad(key, format!("[{lo}, {hi}] is not a range ≥ {min}")));
            }
        }
        if t.open_range[1] > 1.0 {
            return Err(bad("task.open_range", "fractions of a joint's range must be ≤ 1"));
        }
        if !(t.goal_lateral.is_finite() && t.goal_lateral >= 0.0) {
            return Err(bad("task.goal_lateral", format!("{} is not ≥ 0", t.goal_lateral)));
        }
        positive("task.reach_tolerance", t.reach_tolerance)?;
        if !(t.closed_tolerance.is_finite() && t.closed_tolerance > 0.0 && t.closed_tolerance < 1.0) {
            return Err(bad(
                "task.closed_tolerance",
                format!("{} is not a fraction in (0, 1)", t.closed_tolerance),
            ));
        }
        let articulated = matches!(t.name.as_str(), "push_drawer" | "push_cabinet" | "room_rearrangement");
        if articulated && t.closed_tolerance >= t.open_range[0] {
            return Err(bad(
                "task.closed_tolerance",
                format!(
                    "{} would count joints opened to {} of their range as closed",
                    t.closed_tolerance, t.open_range[0]
                ),
            ));
        }
        Ok(())
    }
}

/// Parses `category/variant` (e.g. `chair/1`) into a category and a variant it has.
pub(crate) fn parse_asset(text: &str) -> Result<(Category, usize), String> {
    let (c, v) = text
        .split_once('/')
        .ok_or_else(|| format!("`{text}` is not `category/variant` (e.g. `chair/0`)"))?;
    let category = Category::from_name(c).ok_or_else(|| format!("`{c}` in `{text}` is not an asset category"))?;
    let variant: usize = v
        .parse()
        .map_err(|_| format!("`{v}` in `{text}` is not a variant number"))?;
    if variant >= category.variants() {
        return Err(format!("`{text}`: {c} has variants 0 to {}", category.variants() - 1));
    }
    Ok((category, variant))
}
