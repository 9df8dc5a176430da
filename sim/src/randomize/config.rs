//! [`RandomizationConfig`]: the `[randomization]` section (serde, TOML-friendly). Every field
//! has a default, and every default is off.

use serde::{Deserialize, Serialize};

use super::error::RandomizeError;
use crate::assets::{Category, Placement};

fn one_u64() -> u64 {
    1
}
fn one() -> f64 {
    1.0
}
fn unit_range() -> [f64; 2] {
    [1.0, 1.0]
}
fn default_min_fill() -> f64 {
    0.25
}

/// What to randomise and how much. Parsed from the body of a `[randomization]` TOML section
/// ([`RandomizationConfig::from_toml_str`]) or embedded in a larger serde configuration;
/// unknown keys are errors. See `docs/randomization.md` for every key.
///
/// ```
/// use hearth_sim::randomize::RandomizationConfig;
/// let c = RandomizationConfig::from_toml_str(r#"
/// every_k_episodes = 5
/// [objects]
/// enabled = true
/// [physics]
/// enabled = true
/// friction = true
/// joint_damping = [0.5, 2.0]
/// "#).unwrap();
/// assert!(c.objects.enabled && c.physics.friction && !c.visual.enabled);
/// assert!(!RandomizationConfig::default().any());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomizationConfig {
    /// Run seed of the draws: the same seed gives the same sequence of randomised episodes.
    /// A vectorised env offsets it by the env's index.
    #[serde(default)]
    pub seed: u64,
    /// Draw a new randomisation every this many episodes (1 = every episode); the episodes in
    /// between reuse the last draw. Applies to objects, visual and physical materials; pose
    /// perturbations are drawn every episode.
    #[serde(default = "one_u64")]
    pub every_k_episodes: u64,
    /// Object model swaps (scene level).
    #[serde(default)]
    pub objects: ObjectRandomization,
    /// Visual materials (camera level).
    #[serde(default)]
    pub visual: VisualRandomizationConfig,
    /// Friction, restitution, mass and joint damping (world level).
    #[serde(default)]
    pub physics: PhysicsRandomization,
    /// Robot start pose and camera mount perturbations.
    #[serde(default)]
    pub pose: PoseRandomization,
    /// Sensor noise levels.
    #[serde(default)]
    pub noise: SensorNoiseConfig,
}

impl Default for RandomizationConfig {
    fn default() -> Self {
        RandomizationConfig {
            seed: 0,
            every_k_episodes: 1,
            objects: ObjectRandomization::default(),
            visual: VisualRandomizationConfig::default(),
            physics: PhysicsRandomization::default(),
            pose: PoseRandomization::default(),
            noise: SensorNoiseConfig::default(),
        }
    }
}

/// Swapping objects for other variants of their category (`[randomization.objects]`).
///
/// ```
/// let o = hearth_sim::randomize::ObjectRandomization::default();
/// assert!(!o.enabled && o.probability == 1.0 && o.categories.is_empty());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectRandomization {
    /// Whether objects are swapped.
    #[serde(default)]
    pub enabled: bool,
    /// Probability that an eligible object is swapped, `[0, 1]`.
    #[serde(default = "one")]
    pub probability: f64,
    /// Category names to swap (empty: every category except doors and windows, which fill
    /// their wall openings).
    #[serde(default)]
    pub categories: Vec<String>,
    /// Smallest accepted ratio of the new model's bounding-box volume to the original box's,
    /// `(0, 1]`: a variant that would shrink below it to fit is not used.
    #[serde(default = "default_min_fill")]
    pub min_fill: f64,
}

impl Default for ObjectRandomization {
    fn default() -> Self {
        ObjectRandomization {
            enabled: false,
            probability: 1.0,
            categories: Vec::new(),
            min_fill: default_min_fill(),
        }
    }
}

/// Visual material randomisation (`[randomization.visual]`).
///
/// ```
/// let v = hearth_sim::randomize::VisualRandomizationConfig::default();
/// assert!(!v.enabled && v.objects && !v.building && !v.robot);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisualRandomizationConfig {
    /// Whether materials are drawn anew.
    #[serde(default)]
    pub enabled: bool,
    /// Objects' materials (true by default once enabled).
    #[serde(default = "yes")]
    pub objects: bool,
    /// Walls, floors and ceilings.
    #[serde(default)]
    pub building: bool,
    /// The robot's links (their colours are jittered, their class kept).
    #[serde(default)]
    pub robot: bool,
}

fn yes() -> bool {
    true
}

impl Default for VisualRandomizationConfig {
    fn default() -> Self {
        VisualRandomizationConfig {
            enabled: false,
            objects: true,
            building: false,
            robot: false,
        }
    }
}

/// Physical material randomisation (`[randomization.physics]`).
///
/// ```
/// let p = hearth_sim::randomize::PhysicsRandomization::default();
/// assert!(!p.enabled && !p.friction && p.joint_damping == [1.0, 1.0]);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhysicsRandomization {
    /// Whether physical properties are drawn anew.
    #[serde(default)]
    pub enabled: bool,
    /// Friction from each material's span ([`crate::assets::Material::ranges`]).
    #[serde(default)]
    pub friction: bool,
    /// Restitution from each material's span.
    #[serde(default)]
    pub restitution: bool,
    /// Mass: density drawn from each material's span, mass scaled by density / typical
    /// density.
    #[serde(default)]
    pub mass: bool,
    /// Factor range on the URDF damping of object joints (drawers, doors); `[1, 1]` = off.
    #[serde(default = "unit_range")]
    pub joint_damping: [f64; 2],
    /// Fraction of each material span used, centred on the typical value: 1 = the whole span,
    /// 0 = the typical value, `[0, 1]`.
    #[serde(default = "one")]
    pub spread: f64,
    /// Also floors (the ground included), walls and ceilings.
    #[serde(default)]
    pub building: bool,
}

impl Default for PhysicsRandomization {
    fn default() -> Self {
        PhysicsRandomization {
            enabled: false,
            friction: false,
            restitution: false,
            mass: false,
            joint_damping: unit_range(),
            spread: 1.0,
            building: false,
        }
    }
}

/// Pose perturbations, zero-mean Gaussian (`[randomization.pose]`); 0 = off.
///
/// ```
/// let p = hearth_sim::randomize::PoseRandomization::default();
/// assert_eq!(p.robot_xy_std, 0.0);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseRandomization {
    /// Standard deviation of the robot's start position along x and y, m (`[0, 2]`).
    #[serde(default)]
    pub robot_xy_std: f64,
    /// Standard deviation of the robot's start heading, rad (`[0, π]`).
    #[serde(default)]
    pub robot_yaw_std: f64,
    /// Standard deviation of the camera mount's offset along each axis, m (`[0, 0.2]`).
    #[serde(default)]
    pub camera_xyz_std: f64,
    /// Standard deviation of the camera mount's roll, pitch and yaw offsets, rad (`[0, 0.5]`).
    #[serde(default)]
    pub camera_rpy_std: f64,
}

/// Sensor noise levels (`[randomization.noise]`); 0 = off.
///
/// ```
/// let n = hearth_sim::randomize::SensorNoiseConfig::default();
/// assert_eq!(n.depth_std, 0.0);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorNoiseConfig {
    /// Depth noise standard deviation at any distance, m (`[0, 1]`).
    #[serde(default)]
    pub depth_std: f64,
    /// Depth noise growth with the square of the distance, m per m² (`[0, 1]`).
    #[serde(default)]
    pub depth_quadratic: f64,
    /// Probability that a depth pixel reads 0 (no return), `[0, 1]`.
    #[serde(default)]
    pub depth_dropout: f64,
    /// LiDAR range noise standard deviation, m (`[0, 10]`).
    #[serde(default)]
    pub lidar_std: f64,
    /// Probability that a LiDAR ray returns nothing, `[0, 1]`.
    #[serde(default)]
    pub lidar_dropout: f64,
}

fn check(key: &str, value: f64, lo: f64, hi: f64, reason: &str) -> Result<(), RandomizeError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(RandomizeError::invalid(key, value, reason))
    }
}

impl RandomizationConfig {
    /// Parses the body of a `[randomization]` section (keys relative to it) and validates it.
    ///
    /// # Errors
    /// [`RandomizeError::UnknownKey`], [`RandomizeError::Parse`] or
    /// [`RandomizeError::InvalidValue`], each naming the key.
    ///
    /// ```
    /// use hearth_sim::randomize::{RandomizationConfig, RandomizeError};
    /// let err = RandomizationConfig::from_toml_str("[pose]\nrobot_xy_std = -1.0").unwrap_err();
    /// assert!(err.to_string().contains("pose.robot_xy_std"));
    /// ```
    pub fn from_toml_str(text: &str) -> Result<Self, RandomizeError> {
        let config: RandomizationConfig =
            toml::from_str(text).map_err(|e| RandomizeError::from_parser(e.to_string()))?;
        config.validate()?;
        Ok(config)
    }

    /// Whether anything at all is randomised.
    ///
    /// ```
    /// let mut c = hearth_sim::randomize::RandomizationConfig::default();
    /// assert!(!c.any());
    /// c.noise.lidar_std = 0.01;
    /// assert!(c.any());
    /// ```
    pub fn any(&self) -> bool {
        let p = &self.pose;
        let n = &self.noise;
        self.objects.enabled
            || self.visual.enabled
            || self.physics_active()
            || [p.robot_xy_std, p.robot_yaw_std, p.camera_xyz_std, p.camera_rpy_std]
                .iter()
                .any(|&x| x > 0.0)
            || [
                n.depth_std,
                n.depth_quadratic,
                n.depth_dropout,
                n.lidar_std,
                n.lidar_dropout,
            ]
            .iter()
            .any(|&x| x > 0.0)
    }

    /// Whether the physics section changes anything.
    pub(crate) fn physics_active(&self) -> bool {
        let p = &self.physics;
        p.enabled && (p.friction || p.restitution || p.mass || p.joint_damping != [1.0, 1.0])
    }

    /// Checks every value; the error names the first bad key.
    ///
    /// # Errors
    /// [`RandomizeError::InvalidValue`].
    ///
    /// ```
    /// let mut c = hearth_sim::randomize::RandomizationConfig::default();
    /// c.physics.joint_damping = [2.0, 0.5];
    /// let err = c.validate().unwrap_err();
    /// assert!(err.to_string().contains("physics.joint_damping"));
    /// ```
    pub fn validate(&self) -> Result<(), RandomizeError> {
        if self.every_k_episodes == 0 {
            return Err(RandomizeError::invalid("every_k_episodes", 0, "must be at least 1"));
        }
        let o = &self.objects;
        check(
            "objects.probability",
            o.probability,
            0.0,
            1.0,
            "must be a probability in [0, 1]",
        )?;
        check("objects.min_fill", o.min_fill, 1e-6, 1.0, "must be in (0, 1]")?;
        for name in &o.categories {
            match Category::from_name(name) {
                None => {
                    return Err(RandomizeError::invalid(
                        "objects.categories",
                        name,
                        "is not a category of the asset library",
                    ));
                }
                Some(c) if c.placement() == Placement::InWall => {
                    return Err(RandomizeError::invalid(
                        "objects.categories",
                        name,
                        "doors and windows fill their wall openings and are not swapped",
                    ));
                }
                Some(_) => {}
            }
        }
        let p = &self.physics;
        let [lo, hi] = p.joint_damping;
        check("physics.joint_damping", lo, 0.0, 100.0, "factors must be in [0, 100]")?;
        check("physics.joint_damping", hi, 0.0, 100.0, "factors must be in [0, 100]")?;
        if lo > hi {
            return Err(RandomizeError::invalid(
                "physics.joint_damping",
                format!("[{lo}, {hi}]"),
                "the low end exceeds the high end",
            ));
        }
        check("physics.spread", p.spread, 0.0, 1.0, "must be in [0, 1]")?;
        let q = &self.pose;
        check("pose.robot_xy_std", q.robot_xy_std, 0.0, 2.0, "must be in [0, 2] m")?;
        check(
            "pose.robot_yaw_std",
            q.robot_yaw_std,
            0.0,
            std::f64::consts::PI,
            "must be in [0, π] rad",
        )?;
        check(
            "pose.camera_xyz_std",
            q.camera_xyz_std,
            0.0,
            0.2,
            "must be in [0, 0.2] m",
        )?;
        check(
            "pose.camera_rpy_std",
            q.camera_rpy_std,
            0.0,
            0.5,
            "must be in [0, 0.5] rad",
        )?;
        let n = &self.noise;
        check("noise.depth_std", n.depth_std, 0.0, 1.0, "must be in [0, 1] m")?;
        check(
            "noise.depth_quadratic",
            n.depth_quadratic,
            0.0,
            1.0,
            "must be in [0, 1] m/m²",
        )?;
        check(
            "noise.depth_dropout",
            n.depth_dropout,
            0.0,
            1.0,
            "must be a probability in [0, 1]",
        )?;
        check("noise.lidar_std", n.lidar_std, 0.0, 10.0, "must be in [0, 10] m")?;
        check(
            "noise.lidar_dropout",
            n.lidar_dropout,
            0.0,
            1.0,
            "must be a probability in [0, 1]",
        )?;
        Ok(())
    }
}
