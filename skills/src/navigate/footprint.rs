//! The robot base's footprint and the SE(2) state validator built on it.

use std::f32::consts::FRAC_PI_2;

use hearth_planning::obstacles::Obstacles;
use hearth_planning::validity::StateValidator;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::Cylinder;

/// The volume a mobile base sweeps: a vertical cylinder of `radius` around the base origin,
/// from `z_min` to `z_max` above the floor (world z). Things entirely below `z_min` (rugs,
/// thresholds, the floor) never block it.
///
/// ```
/// use hearth_skills::navigate::BaseFootprint;
/// let fetch = BaseFootprint::for_builtin("fetch").unwrap();
/// assert!(fetch.radius >= 0.32 && fetch.z_max > 1.1);
/// assert!(BaseFootprint::for_builtin("panda").is_none());
/// assert!(fetch.validate().is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BaseFootprint {
    /// Radius of the base, metres.
    pub radius: f64,
    /// Lowest height the base occupies (its floor clearance), metres.
    pub z_min: f64,
    /// Highest height the robot occupies while driving, metres.
    pub z_max: f64,
}

impl BaseFootprint {
    /// The footprint of a built-in wheeled robot, from ray casts against its collision
    /// geometry at rest (arm tucked) around the base origin, rounded up: `fetch` radius
    /// 0.32 m (the torso's back corners reach 0.321 m, the base 0.30 m), 3 cm clearance,
    /// 1.12 m tall; `locobot` 0.25 m (the gripper reaches 0.243 m), 8 mm, 0.64 m;
    /// `turtlebot` 0.245 m (the plates, set back, reach 0.240 m), 8 mm, 0.44 m.
    ///
    /// ```
    /// use hearth_skills::navigate::BaseFootprint;
    /// let locobot = BaseFootprint::for_builtin("locobot").unwrap();
    /// assert_eq!(locobot.radius, 0.25);
    /// assert!(locobot.z_max < BaseFootprint::for_builtin("fetch").unwrap().z_max);
    /// assert!(BaseFootprint::for_builtin("panda").is_none()); // not a wheeled robot
    /// ```
    pub fn for_builtin(robot: &str) -> Option<Self> {
        let (radius, z_min, z_max) = match robot {
            "fetch" => (0.32, 0.03, 1.12),
            "locobot" => (0.25, 0.008, 0.64),
            "turtlebot" => (0.245, 0.008, 0.44),
            _ => return None,
        };
        Some(Self { radius, z_min, z_max })
    }

    /// Checks that the numbers are finite, the radius positive and `0 ≤ z_min < z_max`.
    ///
    /// ```
    /// use hearth_skills::navigate::BaseFootprint;
    /// let bad = BaseFootprint { radius: f64::NAN, z_min: 0.0, z_max: 1.0 };
    /// assert!(bad.validate().unwrap_err().contains("radius"));
    /// ```
    pub fn validate(&self) -> Result<(), String> {
        if !(self.radius.is_finite() && self.radius > 0.0 && self.radius <= 5.0) {
            return Err(format!("footprint radius {} is not in (0, 5] m", self.radius));
        }
        if !(self.z_min.is_finite() && self.z_max.is_finite() && self.z_min >= 0.0 && self.z_min < self.z_max) {
            return Err(format!(
                "footprint heights [{}, {}] are not 0 ≤ z_min < z_max",
                self.z_min, self.z_max
            ));
        }
        Ok(())
    }
}

/// SE(2) state validity for a mobile base: the [`BaseFootprint`] cylinder at `(x, y)` against
/// an [`Obstacles`] view (the yaw does not matter for a round base). Checking does not
/// allocate.
///
/// States within [`FootprintValidity::set_free_near`] of a point count as valid whatever they
/// touch: a robot pressed against something can still plan its way out from where it stands.
///
/// ```
/// use hearth_planning::obstacles::{Obstacle, ParryScene};
/// use hearth_planning::validity::StateValidator;
/// use hearth_skills::navigate::{BaseFootprint, FootprintValidity};
/// use parry3d::math::{Pose, Vector};
///
/// let wall = Obstacle::cuboid("wall", Pose::translation(1.0, 0.0, 1.0), Vector::new(0.05, 2.0, 1.0));
/// let fp = BaseFootprint::for_builtin("fetch").unwrap();
/// let mut v = FootprintValidity::new(ParryScene::new(vec![wall]), fp);
/// assert!(v.is_valid(&[0.0, 0.0, 0.0]));
/// assert!(!v.is_valid(&[0.8, 0.0, 1.0]));
/// assert_eq!(v.checks(), 2);
/// assert_eq!(v.touching(&[0.8, 0.0, 0.0]).as_deref(), Some("wall"));
/// assert!((v.clearance(&[0.0, 0.0, 0.0], 2.0) - (0.95 - fp.radius)).abs() < 1e-4);
/// ```
pub struct FootprintValidity<O: Obstacles> {
    obstacles: O,
    shape: Cylinder,
    z_center: f32,
    rotation: Rotation,
    free_near: Option<([f64; 2], f64)>,
    checks: u64,
}

impl<O: Obstacles> FootprintValidity<O> {
    /// A validator of `footprint` against `obstacles` (apply any margin on the view).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::StateValidator;
    /// use hearth_skills::navigate::{BaseFootprint, FootprintValidity};
    /// use parry3d::math::{Pose, Vector};
    /// // A 2 cm rug lies below the footprint's floor clearance: it never blocks the base.
    /// let rug = Obstacle::cuboid("rug", Pose::translation(0.0, 0.0, 0.01), Vector::new(1.0, 1.0, 0.01));
    /// let mut v = FootprintValidity::new(ParryScene::new(vec![rug]), BaseFootprint::for_builtin("fetch").unwrap());
    /// assert!(v.is_valid(&[0.0, 0.0, 0.0]));
    /// ```
    pub fn new(obstacles: O, footprint: BaseFootprint) -> Self {
        let half = ((footprint.z_max - footprint.z_min) / 2.0) as f32;
        Self {
            obstacles,
            shape: Cylinder::new(half, footprint.radius as f32),
            z_center: ((footprint.z_max + footprint.z_min) / 2.0) as f32,
            // parry's cylinders stand along their y axis: turn it upright.
            rotation: Rotation::from_rotation_x(FRAC_PI_2),
            free_near: None,
            checks: 0,
        }
    }

    /// Treats states within `radius` of `point` as valid (`None` turns this off).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_planning::validity::StateValidator;
    /// use hearth_skills::navigate::{BaseFootprint, FootprintValidity};
    /// use parry3d::math::{Pose, Vector};
    /// let chair = Obstacle::cuboid("chair", Pose::translation(0.4, 0.0, 0.4), Vector::new(0.2, 0.2, 0.4));
    /// let mut v = FootprintValidity::new(ParryScene::new(vec![chair]), BaseFootprint::for_builtin("fetch").unwrap());
    /// assert!(!v.is_valid(&[0.0, 0.0, 0.0])); // the base stands against the chair
    /// v.set_free_near(Some(([0.0, 0.0], 0.1)));
    /// assert!(v.is_valid(&[0.05, 0.0, 0.0]) && !v.is_valid(&[0.2, 0.0, 0.0]));
    /// v.set_free_near(None);
    /// assert!(!v.is_valid(&[0.0, 0.0, 0.0]));
    /// ```
    pub fn set_free_near(&mut self, near: Option<([f64; 2], f64)>) {
        self.free_near = near;
    }

    /// The obstacle view.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_skills::navigate::{BaseFootprint, FootprintValidity};
    /// use parry3d::math::{Pose, Vector};
    /// let box_ = Obstacle::cuboid("box", Pose::translation(2.0, 0.0, 0.2), Vector::new(0.2, 0.2, 0.2));
    /// let v = FootprintValidity::new(ParryScene::new(vec![box_]), BaseFootprint::for_builtin("locobot").unwrap());
    /// assert_eq!(v.obstacles().len(), 1);
    /// ```
    pub fn obstacles(&self) -> &O {
        &self.obstacles
    }

    fn pose(&self, q: &[f64]) -> Pose {
        Pose::from_parts(Vector::new(q[0] as f32, q[1] as f32, self.z_center), self.rotation)
    }

    /// The distance from the footprint at `q` to the nearest obstacle (beyond the view's
    /// margin), or `max` when nothing is that close.
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_skills::navigate::{BaseFootprint, FootprintValidity};
    /// use parry3d::math::{Pose, Vector};
    /// let wall = Obstacle::cuboid("wall", Pose::translation(2.0, 0.0, 1.0), Vector::new(0.05, 3.0, 1.0));
    /// let fp = BaseFootprint::for_builtin("locobot").unwrap();
    /// let v = FootprintValidity::new(ParryScene::new(vec![wall]), fp);
    /// assert!((v.clearance(&[1.0, 0.0, 0.0], 5.0) - (0.95 - fp.radius)).abs() < 1e-4);
    /// assert_eq!(v.clearance(&[-3.0, 0.0, 0.0], 1.0), 1.0); // nothing within 1 m
    /// ```
    pub fn clearance(&self, q: &[f64], max: f64) -> f64 {
        self.obstacles
            .distance(&self.shape, &self.pose(q), max as f32)
            .map_or(max, |(d, _)| f64::from(d))
    }

    /// The name of an obstacle the footprint touches at `q`, `None` when it is clear (the
    /// free-near exception does not apply here).
    ///
    /// ```
    /// use hearth_planning::obstacles::{Obstacle, ParryScene};
    /// use hearth_skills::navigate::{BaseFootprint, FootprintValidity};
    /// use parry3d::math::{Pose, Vector};
    /// let table = Obstacle::cuboid("table", Pose::translation(1.0, 0.0, 0.4), Vector::new(0.5, 0.5, 0.4));
    /// let v = FootprintValidity::new(ParryScene::new(vec![table]), BaseFootprint::for_builtin("fetch").unwrap());
    /// assert_eq!(v.touching(&[0.3, 0.0, 0.0]).as_deref(), Some("table"));
    /// assert_eq!(v.touching(&[-1.0, 0.0, 0.0]), None);
    /// ```
    pub fn touching(&self, q: &[f64]) -> Option<String> {
        let id = self.obstacles.first_hit(&self.shape, &self.pose(q))?;
        Some(self.obstacles.name(id).unwrap_or("an unnamed obstacle").to_owned())
    }
}

impl<O: Obstacles> StateValidator for FootprintValidity<O> {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        if !(q[0].is_finite() && q[1].is_finite()) {
            return false;
        }
        if let Some((p, r)) = self.free_near
            && (q[0] - p[0]).hypot(q[1] - p[1]) <= r
        {
            return true;
        }
        !self.obstacles.intersects(&self.shape, &self.pose(q))
    }

    fn checks(&self) -> u64 {
        self.checks
    }
}
