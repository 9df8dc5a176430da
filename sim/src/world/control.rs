//! Controllers: joint position (PD through rapier's multibody motors), velocity and effort;
//! mimic joints follow their leader through rapier DoF couplings; differential-drive and
//! holonomic bases; a parallel gripper.

use std::sync::Arc;

use hearth_kinematics::RobotModel;
use rapier3d::prelude::*;

use super::error::{WorldError, WorldResult, check_finite, check_len, check_range};
use super::physics::World;
use super::readout::Twist;
use super::spawn::{BaseMode, ModelEntry, ModelHandle};

/// What drives one joint.
///
/// ```
/// use hearth_sim::world::JointCommand;
/// assert_eq!(JointCommand::Position { target: 0.5 }.target(), Some(0.5));
/// assert_eq!(JointCommand::Off.target(), None);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum JointCommand {
    /// No actuation: the joint moves freely (with its URDF damping and friction).
    #[default]
    Off,
    /// PD control towards a position (rad or m).
    Position {
        /// Target position.
        target: f64,
    },
    /// Velocity control (rad/s or m/s).
    Velocity {
        /// Target velocity.
        target: f64,
    },
    /// A constant effort (N·m or N).
    Effort {
        /// Applied effort.
        value: f64,
    },
}

impl JointCommand {
    /// The commanded value, if any.
    ///
    /// ```
    /// # use hearth_sim::world::JointCommand;
    /// assert_eq!(JointCommand::Effort { value: -2.0 }.target(), Some(-2.0));
    /// assert_eq!(JointCommand::default().target(), None);
    /// ```
    pub fn target(self) -> Option<f64> {
        match self {
            JointCommand::Off => None,
            JointCommand::Position { target } | JointCommand::Velocity { target } => Some(target),
            JointCommand::Effort { value } => Some(value),
        }
    }
}

/// Gains of one joint's controllers (force-based: N·m/rad, N·m·s/rad, or N/m, N·s/m).
///
/// Defaults from the joint's effort limit and effective inertia: the position controller
/// reaches its effort limit at 5 mrad (or 5 mm) of error and is critically damped.
///
/// ```
/// use hearth_sim::world::JointGains;
/// let g = JointGains { stiffness: 100.0, damping: 20.0, velocity_gain: 10.0, max_effort: 5.0 };
/// assert!(g.validate("j").is_ok());
/// assert!(JointGains { stiffness: f64::NAN, ..g }.validate("j").is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointGains {
    /// Position stiffness (proportional gain).
    pub stiffness: f64,
    /// Position damping (derivative gain).
    pub damping: f64,
    /// Velocity-controller gain (effort per unit of velocity error).
    pub velocity_gain: f64,
    /// Largest effort the motor applies (`+∞` for none).
    pub max_effort: f64,
}

impl JointGains {
    /// Checks that every gain is finite and non-negative (`max_effort` may be `+∞`) and that
    /// `max_effort` is positive.
    ///
    /// # Errors
    /// [`WorldError::NonFinite`] or [`WorldError::OutOfRange`] naming the joint.
    ///
    /// ```
    /// # use hearth_sim::world::JointGains;
    /// let g = JointGains { stiffness: 100.0, damping: 20.0, velocity_gain: 10.0, max_effort: f64::INFINITY };
    /// assert!(g.validate("j").is_ok());
    /// assert!(JointGains { max_effort: 0.0, ..g }.validate("j").is_err());
    /// assert!(JointGains { damping: -1.0, ..g }.validate("j").is_err());
    /// ```
    pub fn validate(&self, joint: &str) -> WorldResult<()> {
        check_range("stiffness", joint, self.stiffness, 0.0, f64::MAX)?;
        check_range("damping", joint, self.damping, 0.0, f64::MAX)?;
        check_range("velocity gain", joint, self.velocity_gain, 0.0, f64::MAX)?;
        if self.max_effort.is_nan() || self.max_effort <= 0.0 {
            return Err(WorldError::OutOfRange {
                what: "max effort",
                name: joint.to_owned(),
                value: self.max_effort,
                lower: f64::MIN_POSITIVE,
                upper: f64::INFINITY,
            });
        }
        Ok(())
    }
}

/// Finger speed of a gripper, m/s: the finger joint's velocity limit, or 0.1 m/s where the
/// model gives none.
fn gripper_speed(velocity_limit: f64) -> f64 {
    if velocity_limit.is_finite() && velocity_limit > 0.0 {
        velocity_limit
    } else {
        0.1
    }
}

/// Default gains for a joint with effective inertia `m_eff` and effort limit `effort`.
pub(crate) fn default_gains(m_eff: f64, effort: f64) -> JointGains {
    let (stiffness, velocity_gain) = if effort.is_finite() {
        (effort / 0.005, effort / 0.05)
    } else {
        (m_eff * 4.0e3, (m_eff * 200.0).max(10.0))
    };
    JointGains {
        stiffness,
        damping: 2.0 * (stiffness * m_eff).sqrt(),
        velocity_gain,
        max_effort: effort,
    }
}

/// A differential-drive base: two wheel joints, wheel radius and axle width.
///
/// ```
/// use hearth_sim::kinematics::RobotModel;
/// use hearth_sim::world::DiffDriveConfig;
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// let d = DiffDriveConfig::for_builtin("fetch").unwrap();
/// assert_eq!(d.left_joint, "l_wheel_joint");
/// assert!(d.wheel_radius > 0.05 && d.axle_width > 0.3);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct DiffDriveConfig {
    /// Left wheel joint.
    pub left_joint: String,
    /// Right wheel joint.
    pub right_joint: String,
    /// Wheel radius in m.
    pub wheel_radius: f64,
    /// Distance between the wheel contact points in m.
    pub axle_width: f64,
    /// Links that stand for free-swivelling casters: their contacts carry no friction, so they
    /// hold the base level without resisting its motion in any direction.
    pub casters: Vec<String>,
}

impl DiffDriveConfig {
    /// The parameters of a built-in robot (`fetch`, `locobot`, `turtlebot`).
    ///
    /// ```
    /// # use hearth_sim::world::DiffDriveConfig;
    /// let d = DiffDriveConfig::for_builtin("turtlebot").unwrap();
    /// assert_eq!(d.casters.len(), 2);
    /// assert!(DiffDriveConfig::for_builtin("panda").is_none());
    /// ```
    pub fn for_builtin(robot: &str) -> Option<Self> {
        let (l, r, radius, width, casters): (_, _, _, _, &[&str]) = match robot {
            "fetch" => (
                "l_wheel_joint",
                "r_wheel_joint",
                0.06433,
                0.37476,
                &["fl_caster_link", "fr_caster_link", "bl_caster_link", "br_caster_link"],
            ),
            "locobot" | "turtlebot" => (
                "wheel_left_joint",
                "wheel_right_joint",
                0.0392,
                0.23,
                &["caster_front_link", "caster_back_link"],
            ),
            _ => return None,
        };
        Some(Self {
            left_joint: l.to_owned(),
            right_joint: r.to_owned(),
            wheel_radius: radius,
            axle_width: width,
            casters: casters.iter().map(|c| (*c).to_owned()).collect(),
        })
    }

    pub(crate) fn builtin(model: &RobotModel) -> Option<DiffDrive> {
        Self::for_builtin(model.name())?.validate(model, model.name()).ok()
    }

    /// Resolves the joints against `model`.
    pub(crate) fn validate(self, model: &RobotModel, name: &str) -> WorldResult<DiffDrive> {
        check_range("wheel radius", name, self.wheel_radius, 1e-4, 10.0)?;
        check_range("axle width", name, self.axle_width, 1e-4, 100.0)?;
        let mut poses = model.pose_buffer();
        let _ = model.fk(&model.neutral_configuration(), &mut poses);
        let resolve = |joint: &str| -> WorldResult<(usize, f64)> {
            let j = model.joint_index(joint).map_err(|_| WorldError::UnknownJoint {
                model: name.to_owned(),
                joint: joint.to_owned(),
            })?;
            let jt = &model.joints()[j];
            let v = jt.variable.ok_or_else(|| WorldError::JointNotCommandable {
                model: name.to_owned(),
                joint: joint.to_owned(),
                reason: "a wheel must be an independent movable joint",
            })?;
            // Positive wheel speed must roll the base forward (+x): the axis must point left.
            let axis_in_root = poses[model.root()].rotation.inverse() * poses[jt.child].rotation * jt.axis.into_inner();
            Ok((v, if axis_in_root.y >= 0.0 { 1.0 } else { -1.0 }))
        };
        let (left, left_sign) = resolve(&self.left_joint)?;
        let (right, right_sign) = resolve(&self.right_joint)?;
        let mut casters = Vec::with_capacity(self.casters.len());
        for link in &self.casters {
            casters.push(model.link_index(link).map_err(|_| WorldError::UnknownLink {
                model: name.to_owned(),
                link: link.clone(),
            })?);
        }
        Ok(DiffDrive {
            config: self,
            casters,
            left,
            right,
            left_sign,
            right_sign,
        })
    }
}

/// A differential drive resolved against its model.
#[derive(Clone, Debug)]
pub(crate) struct DiffDrive {
    pub(crate) config: DiffDriveConfig,
    /// Link indices of the casters.
    pub(crate) casters: Vec<usize>,
    pub(crate) left: usize,
    pub(crate) right: usize,
    pub(crate) left_sign: f64,
    pub(crate) right_sign: f64,
}

/// The latest base command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum BaseDrive {
    Holonomic { vx: f64, vy: f64, omega: f64 },
}

/// A parallel gripper: finger joints with their open and closed positions.
///
/// The colliders of the finger links (the leaders' and their mimics') are rubber pads:
/// friction [`FINGER_PAD_FRICTION`] against whatever they touch.
///
/// ```
/// let g = hearth_sim::world::GripperConfig::for_builtin("panda").unwrap();
/// assert_eq!(g.joints, ["panda_finger_joint1"]);
/// assert_eq!(g.open, [0.04]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GripperConfig {
    /// Finger joints (leaders only; mimic joints follow).
    pub joints: Vec<String>,
    /// Open position per joint.
    pub open: Vec<f64>,
    /// Closed position per joint.
    pub closed: Vec<f64>,
}

/// Friction coefficient of gripper finger pads: soft silicone rubber, whose static friction
/// on wood, metal or ceramic is about 1–2 (hard rubber 0.8–1.2); it wins over the other
/// surface's coefficient in a contact. With 1.0 a pinched drawer handle slid out of the
/// fingers during the pull once contacts were recomputed every 2 mm.
///
/// ```
/// assert!(hearth_sim::world::FINGER_PAD_FRICTION >= 1.0);
/// ```
pub const FINGER_PAD_FRICTION: f64 = 1.5;

impl GripperConfig {
    /// The gripper of a built-in robot (`panda`, `fetch`, `locobot`).
    ///
    /// ```
    /// # use hearth_sim::world::GripperConfig;
    /// let g = GripperConfig::for_builtin("locobot").unwrap();
    /// assert_eq!(g.joints.len(), g.closed.len());
    /// assert!(GripperConfig::for_builtin("turtlebot").is_none());
    /// ```
    pub fn for_builtin(robot: &str) -> Option<Self> {
        let (joints, open, closed): (&[&str], &[f64], &[f64]) = match robot {
            "panda" => (&["panda_finger_joint1"], &[0.04], &[0.0]),
            "fetch" => (&["r_gripper_finger_joint"], &[0.05], &[0.0]),
            "locobot" => (&["joint_6", "joint_7"], &[-0.025, 0.025], &[0.0, 0.0]),
            _ => return None,
        };
        Some(Self {
            joints: joints.iter().map(|s| (*s).to_owned()).collect(),
            open: open.to_vec(),
            closed: closed.to_vec(),
        })
    }

    pub(crate) fn builtin(model: &RobotModel) -> Option<Gripper> {
        Self::for_builtin(model.name())?.validate(model, model.name()).ok()
    }

    pub(crate) fn validate(self, model: &RobotModel, name: &str) -> WorldResult<Gripper> {
        check_len("gripper open positions", self.joints.len(), self.open.len())?;
        check_len("gripper closed positions", self.joints.len(), self.closed.len())?;
        let mut vars = Vec::with_capacity(self.joints.len());
        for (i, joint) in self.joints.iter().enumerate() {
            let j = model.joint_index(joint).map_err(|_| WorldError::UnknownJoint {
                model: name.to_owned(),
                joint: joint.clone(),
            })?;
            let v = model.joints()[j]
                .variable
                .ok_or_else(|| WorldError::JointNotCommandable {
                    model: name.to_owned(),
                    joint: joint.clone(),
                    reason: "a finger must be an independent movable joint",
                })?;
            let (lo, hi) = (model.lower()[v], model.upper()[v]);
            check_range("gripper open position", joint, self.open[i], lo, hi)?;
            check_range("gripper closed position", joint, self.closed[i], lo, hi)?;
            vars.push(v);
        }
        let speed = vars
            .iter()
            .map(|&v| gripper_speed(model.velocity_limits()[v]))
            .collect();
        let ramp = vec![None; vars.len()];
        Ok(Gripper {
            config: self,
            vars,
            speed,
            ramp,
        })
    }
}

/// A gripper resolved against its model.
///
/// A real parallel gripper moves its fingers at a set speed and squeezes with at most the set
/// force once they stall on something. Its finger joints are position controlled with the
/// force as effort limit, and their motor targets move towards the commanded position at the
/// finger's speed (`ramp`, once the gripper has been commanded) instead of jumping there: a
/// target at the far end would slam the fingers shut at the effort limit and push them
/// through thin walls.
#[derive(Clone, Debug)]
pub(crate) struct Gripper {
    pub(crate) config: GripperConfig,
    pub(crate) vars: Vec<usize>,
    /// Finger speed per var, m/s or rad/s.
    pub(crate) speed: Vec<f64>,
    /// Motor target per var on its way to the commanded position; `None` until the gripper
    /// is first commanded (the command is then the target).
    pub(crate) ramp: Vec<Option<f64>>,
}

impl Gripper {
    /// The motor target of variable `v` for a position command `target`.
    pub(crate) fn motor_target(&self, v: usize, target: f64) -> f64 {
        match self.vars.iter().position(|&x| x == v) {
            Some(i) => self.ramp[i].unwrap_or(target),
            None => target,
        }
    }

    /// Moves the ramped targets towards the position commands by one physics step `dt`.
    fn advance(&mut self, commands: &[JointCommand], dt: f64) {
        for (i, &v) in self.vars.iter().enumerate() {
            if let (Some(r), JointCommand::Position { target }) = (self.ramp[i].as_mut(), commands[v]) {
                let step = self.speed[i] * dt;
                *r += (target - *r).clamp(-step, step);
            }
        }
    }
}

impl World {
    /// Whether the position controllers of a model add a gravity feed-forward: each physics
    /// step, every position target is offset by the joint's gravity load (from the links
    /// beyond it) divided by its stiffness, so the joint settles on the target instead of
    /// sagging below it. On for spawned models; off for the objects of a loaded scene.
    ///
    /// # Errors
    /// [`WorldError::UnknownModel`].
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// assert!(world.gravity_compensation(arm)?);
    /// world.set_gravity_compensation(arm, false)?;
    /// assert!(!world.gravity_compensation(arm)?);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn gravity_compensation(&self, handle: ModelHandle) -> WorldResult<bool> {
        Ok(self.entry(handle)?.gravity_compensation)
    }

    /// Turns the gravity feed-forward of a model's position controllers on or off (see
    /// [`World::gravity_compensation`]). Turning it off restores the plain targets.
    ///
    /// # Errors
    /// [`WorldError::UnknownModel`].
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let robot = world.spawn_model(&fetch, &nalgebra::Isometry3::identity(), SpawnOptions::free())?;
    /// world.set_gravity_compensation(robot, false)?;
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn set_gravity_compensation(&mut self, handle: ModelHandle, on: bool) -> WorldResult<()> {
        self.entry(handle)?;
        self.state.models[handle.index()].gravity_compensation = on;
        if !on {
            for v in 0..self.state.models[handle.index()].commands.len() {
                self.write_motor(handle, v);
            }
        }
        Ok(())
    }

    /// Position targets for every joint (`q` order), held by PD motors.
    ///
    /// # Errors
    /// Unknown model; wrong length; NaN or out-of-limit targets. Nothing changes on error.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig, WorldError};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let mut q = panda.neutral_configuration();
    /// q[0] = 0.3;
    /// world.set_position_targets(arm, &q)?;
    /// for _ in 0..30 { world.step(); }
    /// assert!((world.joint_positions(arm)?[0] - 0.3).abs() < 1e-2);
    /// q[0] = f64::NAN;
    /// assert!(matches!(world.set_position_targets(arm, &q), Err(WorldError::NonFinite { .. })));
    /// # Ok::<(), WorldError>(())
    /// ```
    pub fn set_position_targets(&mut self, handle: ModelHandle, q: &[f64]) -> WorldResult<()> {
        self.set_all(handle, "position targets", q, check_position, |target| {
            JointCommand::Position { target }
        })
    }

    /// Velocity targets for every joint (`q` order).
    ///
    /// # Errors
    /// Unknown model; wrong length; NaN or beyond the velocity limit.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let mut v = vec![0.0; panda.dof()];
    /// v[0] = 0.5;
    /// world.set_velocity_targets(arm, &v)?;
    /// for _ in 0..5 { world.step(); }
    /// assert!(world.joint_positions(arm)?[0] > 0.02);
    /// assert!(world.set_velocity_targets(arm, &[0.0]).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn set_velocity_targets(&mut self, handle: ModelHandle, v: &[f64]) -> WorldResult<()> {
        self.set_all(handle, "velocity targets", v, check_velocity, |target| {
            JointCommand::Velocity { target }
        })
    }

    /// Efforts for every joint (`q` order), applied every physics step until changed.
    ///
    /// # Errors
    /// Unknown model; wrong length; NaN or beyond the effort limit.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{JointCommand, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let mut tau = vec![0.0; panda.dof()];
    /// tau[0] = 1.0;
    /// world.set_efforts(arm, &tau)?;
    /// assert_eq!(world.joint_commands(arm)?[0], JointCommand::Effort { value: 1.0 });
    /// assert_eq!(world.joint_efforts(arm)?[0], 1.0);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn set_efforts(&mut self, handle: ModelHandle, tau: &[f64]) -> WorldResult<()> {
        self.set_all(handle, "efforts", tau, check_effort, |value| JointCommand::Effort {
            value,
        })
    }

    /// Validates every value, then installs one command per joint.
    fn set_all(
        &mut self,
        handle: ModelHandle,
        what: &'static str,
        values: &[f64],
        check: fn(&ModelEntry, usize, f64) -> WorldResult<()>,
        make: fn(f64) -> JointCommand,
    ) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        check_len(what, entry.model.dof(), values.len())?;
        for (v, &x) in values.iter().enumerate() {
            check(entry, v, x)?;
        }
        let entry = &mut self.state.models[handle.index()];
        for (slot, &x) in entry.commands.iter_mut().zip(values) {
            *slot = make(x);
        }
        for v in 0..values.len() {
            self.write_motor(handle, v);
        }
        self.refresh_effort_flag(handle);
        Ok(())
    }

    /// Sets the command of one joint by name.
    ///
    /// # Errors
    /// Unknown model or joint; a fixed or mimic joint; NaN or out-of-range value.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{JointCommand, SpawnOptions, World, WorldConfig, WorldError};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.set_joint_command(arm, "panda_joint1", JointCommand::Velocity { target: 0.2 })?;
    /// let err = world.set_joint_command(arm, "elbow", JointCommand::Off).unwrap_err();
    /// assert!(matches!(err, WorldError::UnknownJoint { .. }));
    /// # Ok::<(), WorldError>(())
    /// ```
    pub fn set_joint_command(&mut self, handle: ModelHandle, joint: &str, command: JointCommand) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        let v = entry.variable_by_name(joint)?;
        match command {
            JointCommand::Off => {}
            JointCommand::Position { target } => check_position(entry, v, target)?,
            JointCommand::Velocity { target } => check_velocity(entry, v, target)?,
            JointCommand::Effort { value } => check_effort(entry, v, value)?,
        }
        self.state.models[handle.index()].commands[v] = command;
        self.write_motor(handle, v);
        self.refresh_effort_flag(handle);
        Ok(())
    }

    /// The active command of every joint (`q` order).
    ///
    /// # Errors
    /// [`WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{JointCommand, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.set_joint_command(arm, "panda_joint2", JointCommand::Off)?;
    /// assert_eq!(world.joint_commands(arm)?.len(), panda.dof());
    /// assert_eq!(world.joint_commands(arm)?[1], JointCommand::Off);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_commands(&self, handle: ModelHandle) -> WorldResult<&[JointCommand]> {
        Ok(&self.entry(handle)?.commands)
    }

    /// The gains of every joint (`q` order).
    ///
    /// # Errors
    /// [`WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let gains = world.joint_gains(arm)?;
    /// assert_eq!(gains.len(), panda.dof());
    /// assert!(gains.iter().all(|g| g.validate("joint").is_ok()));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_gains(&self, handle: ModelHandle) -> WorldResult<&[JointGains]> {
        Ok(&self.entry(handle)?.gains)
    }

    /// Replaces the gains of one joint.
    ///
    /// # Errors
    /// Unknown model or joint; invalid gains.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{JointGains, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let soft = JointGains { stiffness: 50.0, damping: 5.0, velocity_gain: 5.0, max_effort: 10.0 };
    /// world.set_joint_gains(arm, "panda_joint1", soft)?;
    /// assert_eq!(world.joint_gains(arm)?[0], soft);
    /// assert!(world.set_joint_gains(arm, "panda_joint1", JointGains { stiffness: -1.0, ..soft }).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn set_joint_gains(&mut self, handle: ModelHandle, joint: &str, gains: JointGains) -> WorldResult<()> {
        let v = self.entry(handle)?.variable_by_name(joint)?;
        gains.validate(joint)?;
        self.state.models[handle.index()].gains[v] = gains;
        self.write_motor(handle, v);
        Ok(())
    }

    /// Drives a differential-drive base at forward speed `v` (m/s) and yaw rate `omega`
    /// (rad/s) through left/right wheel velocity targets `(v ∓ ω·w/2) / r`.
    ///
    /// # Errors
    /// [`WorldError::NoController`] without wheels; NaN; wheel speeds beyond their limit.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{JointCommand, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let bot = RobotModel::builtin("turtlebot").unwrap();
    /// let base = world.spawn_model(&bot, &nalgebra::Isometry3::identity(), SpawnOptions::free())?;
    /// world.drive(base, 0.1, 0.0)?;
    /// let commands = world.joint_commands(base)?;
    /// assert_eq!(commands.iter().filter(|c| matches!(c, JointCommand::Velocity { .. })).count(), 2);
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::translation(2.0, 0.0, 0.0), SpawnOptions::fixed())?;
    /// assert!(world.drive(arm, 0.1, 0.0).is_err()); // no wheels
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn drive(&mut self, handle: ModelHandle, v: f64, omega: f64) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        check_finite("base speed", "v", v)?;
        check_finite("base yaw rate", "omega", omega)?;
        let dd = entry.diff_drive.as_ref().ok_or_else(|| WorldError::NoController {
            model: entry.name.clone(),
            controller: "differential-drive base",
        })?;
        let c = &dd.config;
        let left = dd.left_sign * (v - omega * c.axle_width / 2.0) / c.wheel_radius;
        let right = dd.right_sign * (v + omega * c.axle_width / 2.0) / c.wheel_radius;
        check_velocity(entry, dd.left, left)?;
        check_velocity(entry, dd.right, right)?;
        let (l, r) = (dd.left, dd.right);
        let entry = &mut self.state.models[handle.index()];
        entry.commands[l] = JointCommand::Velocity { target: left };
        entry.commands[r] = JointCommand::Velocity { target: right };
        self.write_motor(handle, l);
        self.write_motor(handle, r);
        self.refresh_effort_flag(handle);
        Ok(())
    }

    /// Drives a holonomic base (spawned with [`BaseMode::Holonomic`]) at `(vx, vy)` m/s in
    /// its own frame and yaw rate `omega` rad/s.
    ///
    /// # Errors
    /// [`WorldError::NoController`] for other bases; NaN values.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{BaseMode, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let bot = RobotModel::builtin("turtlebot").unwrap();
    /// let opts = SpawnOptions { base: BaseMode::Holonomic, ..SpawnOptions::default() };
    /// let h = world.spawn_model(&bot, &nalgebra::Isometry3::translation(0.0, 0.0, 0.01), opts)?;
    /// world.drive_holonomic(h, 0.0, 0.5, 0.0)?;
    /// for _ in 0..30 { world.step(); }
    /// assert!((world.base_pose(h)?.translation.y - 0.5).abs() < 0.02);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn drive_holonomic(&mut self, handle: ModelHandle, vx: f64, vy: f64, omega: f64) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        check_finite("base speed", "vx", vx)?;
        check_finite("base speed", "vy", vy)?;
        check_finite("base yaw rate", "omega", omega)?;
        if entry.base != BaseMode::Holonomic {
            return Err(WorldError::NoController {
                model: entry.name.clone(),
                controller: "holonomic base (spawn with BaseMode::Holonomic)",
            });
        }
        let root = entry.root;
        self.state.models[handle.index()].drive = Some(BaseDrive::Holonomic { vx, vy, omega });
        self.wake(root);
        if let Some(bodies) = self.state.models.get(handle.index()).map(|e| e.bodies.clone()) {
            for h in bodies {
                self.wake(h);
            }
        }
        Ok(())
    }

    /// Opens the gripper: the fingers move apart at their velocity limit (their position
    /// targets move at that speed), with full effort, until they reach the open positions.
    ///
    /// # Errors
    /// [`WorldError::NoController`] without a gripper.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.gripper_open(arm)?;
    /// for _ in 0..15 { world.step(); }
    /// assert!(world.joint_positions(arm)?[7] > 0.035);
    /// let bot = RobotModel::builtin("turtlebot").unwrap();
    /// let base = world.spawn_model(&bot, &nalgebra::Isometry3::translation(2.0, 0.0, 0.0), SpawnOptions::free())?;
    /// assert!(world.gripper_open(base).is_err()); // no gripper
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn gripper_open(&mut self, handle: ModelHandle) -> WorldResult<()> {
        let effort = f64::INFINITY;
        self.gripper_command(handle, true, effort)
    }

    /// Closes the gripper: the fingers move together at their velocity limit (their position
    /// targets move at that speed towards the closed positions) and, once they stall on an
    /// object, squeeze it with at most `force` (N) per finger joint.
    ///
    /// # Errors
    /// [`WorldError::NoController`] without a gripper; a force that is NaN, not positive or
    /// beyond the finger's effort limit.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.gripper_open(arm)?;
    /// for _ in 0..15 { world.step(); }
    /// assert!(world.joint_positions(arm)?[7] > 0.035);
    /// world.gripper_close(arm, 10.0)?;
    /// for _ in 0..15 { world.step(); }
    /// assert!(world.joint_positions(arm)?[7] < 0.005);
    /// assert!(world.gripper_close(arm, -1.0).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn gripper_close(&mut self, handle: ModelHandle, force: f64) -> WorldResult<()> {
        self.gripper_command(handle, false, force)
    }

    fn gripper_command(&mut self, handle: ModelHandle, open: bool, force: f64) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        let gripper = entry.gripper.as_ref().ok_or_else(|| WorldError::NoController {
            model: entry.name.clone(),
            controller: "gripper",
        })?;
        for &v in &gripper.vars {
            let limit = entry.model.effort_limits()[v];
            if !open {
                check_range(
                    "gripper force",
                    &entry.model.variable_names()[v],
                    force,
                    f64::MIN_POSITIVE,
                    limit,
                )?;
            }
        }
        let gripper = gripper.clone();
        let entry = &mut self.state.models[handle.index()];
        for (i, &v) in gripper.vars.iter().enumerate() {
            let limit = entry.model.effort_limits()[v];
            let target = if open {
                gripper.config.open[i]
            } else {
                gripper.config.closed[i]
            };
            entry.commands[v] = JointCommand::Position { target };
            entry.gains[v].max_effort = force.min(limit);
        }
        // The fingers' targets move from where the fingers are now (see `Gripper::ramp`).
        let q = self.joint_positions(handle)?;
        if let Some(g) = self.state.models[handle.index()].gripper.as_mut() {
            for (i, &v) in g.vars.iter().enumerate() {
                g.ramp[i] = Some(q[v]);
            }
        }
        for &v in &gripper.vars {
            self.write_motor(handle, v);
        }
        self.refresh_effort_flag(handle);
        Ok(())
    }

    pub(crate) fn refresh_effort_flag(&mut self, handle: ModelHandle) {
        let entry = &mut self.state.models[handle.index()];
        let had = entry.has_effort;
        entry.has_effort = entry.commands.iter().any(|c| matches!(c, JointCommand::Effort { .. }));
        if had && !entry.has_effort {
            let bodies = entry.bodies.clone();
            for h in bodies {
                if let Some(rb) = Arc::make_mut(&mut self.state.bodies).get_mut(h) {
                    rb.reset_forces(true);
                    rb.reset_torques(true);
                }
            }
        }
    }

    /// Writes the motor of variable `v` from its command and gains.
    pub(crate) fn write_motor(&mut self, handle: ModelHandle, v: usize) {
        let entry = &self.state.models[handle.index()];
        let Some(slot) = entry.slot(v) else { return };
        let command = match entry.commands[v] {
            JointCommand::Position { target } => JointCommand::Position {
                target: entry.gripper.as_ref().map_or(target, |gr| gr.motor_target(v, target)),
            },
            c => c,
        };
        let g = entry.gains[v];
        let max = if g.max_effort.is_finite() {
            g.max_effort as Real
        } else {
            Real::MAX
        };
        let Some(mb) = self.multibody_of_mut(handle) else {
            return;
        };
        let Some(link) = mb.link_mut(slot.link_id) else { return };
        let axis = slot.joint_axis();
        let data = &mut link.joint.data;
        match command {
            JointCommand::Position { target } => {
                data.set_motor(axis, target as Real, 0.0, g.stiffness as Real, g.damping as Real);
            }
            JointCommand::Velocity { target } => {
                data.set_motor(axis, 0.0, target as Real, 0.0, g.velocity_gain as Real);
            }
            JointCommand::Effort { .. } | JointCommand::Off => {
                data.motor_axes.remove(axis.into());
                self.wake(slot.body);
                return;
            }
        }
        data.set_motor_max_force(axis, max);
        data.set_motor_model(axis, MotorModel::ForceBased);
        self.wake(slot.body);
    }

    /// Sets the target of variable `v`'s position motor of model `i` (gains unchanged).
    fn write_motor_target(&mut self, i: usize, v: usize, target: f64) {
        let entry = &self.state.models[i];
        let Some(slot) = entry.slot(v) else { return };
        let g = entry.gains[v];
        let Some(mb) = self.multibody_of_mut(ModelHandle::from_index(i)) else {
            return;
        };
        if let Some(link) = mb.link_mut(slot.link_id) {
            link.joint.data.set_motor(
                slot.joint_axis(),
                target as Real,
                0.0,
                g.stiffness as Real,
                g.damping as Real,
            );
        }
    }

    /// Per physics step: gravity compensation, effort joints and holonomic bases.
    pub(crate) fn apply_controllers(&mut self) {
        for i in 0..self.state.models.len() {
            self.advance_gripper(i);
            self.compensate_gravity(i);
            self.keep_driven_joints_awake(i);
        }
        let s = &mut self.state;
        for entry in &mut s.models {
            if entry.has_effort {
                apply_efforts(entry, Arc::make_mut(&mut s.bodies));
            }
            if let Some(BaseDrive::Holonomic { vx, vy, omega }) = entry.drive
                && let Some(rb) = Arc::make_mut(&mut s.bodies).get_mut(entry.root)
            {
                // The multibody takes its root pose from the body at the start of each step,
                // so the kinematic root is advanced here; its velocity is set too so that
                // contacts see the motion.
                let dt = self.params.dt;
                let pose = *rb.position();
                let world_v = pose.rotation * Vector::new(vx as Real, vy as Real, 0.0);
                let world_w = Vector::new(0.0, 0.0, omega as Real);
                let turn = Rotation::from_rotation_z(omega as Real * dt);
                let next = Pose::from_parts(pose.translation + world_v * dt, (turn * pose.rotation).normalize());
                rb.set_position(next, true);
                rb.set_linvel(world_v, true);
                rb.set_angvel(world_w, true);
                // The body reads zero velocity again after the step: keep the twist the base
                // moves with this step (its origin moves by `world_v * dt`) for `base_twist`.
                entry.holonomic_twist = Twist {
                    linear: ::nalgebra::Vector3::new(world_v.x.into(), world_v.y.into(), world_v.z.into()),
                    angular: ::nalgebra::Vector3::new(0.0, 0.0, world_w.z.into()),
                };
            }
        }
    }
}

impl World {
    /// Wakes the links of model `i` whose joints have a non-zero velocity command: a motor
    /// that moves its joint slowly (a gripper closing at 5 cm/s) or pushes against a stall
    /// (a gripper squeezing) must not be put to sleep with its body.
    fn keep_driven_joints_awake(&mut self, i: usize) {
        let entry = &self.state.models[i];
        for v in 0..entry.commands.len() {
            let entry = &self.state.models[i];
            if let JointCommand::Velocity { target } = entry.commands[v]
                && target != 0.0
                && let Some(slot) = entry.slot(v)
            {
                self.wake(slot.body);
            }
        }
    }

    /// Moves the gripper's ramped finger targets of model `i` one physics step on and writes
    /// them to the motors (gravity compensation, if on, rewrites them with its offset).
    fn advance_gripper(&mut self, i: usize) {
        let dt = f64::from(self.params.dt);
        let entry = &mut self.state.models[i];
        let Some(g) = entry.gripper.as_mut() else { return };
        if g.ramp.iter().all(Option::is_none) {
            return;
        }
        g.advance(&entry.commands, dt);
        for k in 0..g.vars.len() {
            let entry = &self.state.models[i];
            let Some(g) = entry.gripper.as_ref() else { return };
            let v = g.vars[k];
            if let (Some(r), JointCommand::Position { target }) = (g.ramp[k], entry.commands[v]) {
                let body = entry.slot(v).map(|s| s.body);
                self.write_motor_target(i, v, r);
                // A finger moving at a few cm/s must not be put to sleep with its body.
                if r != target
                    && let Some(b) = body
                {
                    self.wake(b);
                }
            }
        }
    }

    /// Shifts the position targets of model `i` by the gravity load on each joint divided by
    /// its stiffness, so that a position-controlled joint settles on its target instead of
    /// sagging below it (real arm controllers add the same feed-forward term). The load is
    /// that of the links beyond the joint, from the bodies' masses and centres of mass now.
    fn compensate_gravity(&mut self, i: usize) {
        let entry = &self.state.models[i];
        if !entry.gravity_compensation
            || !entry
                .commands
                .iter()
                .any(|c| matches!(c, JointCommand::Position { .. }))
        {
            return;
        }
        let g = self.gravity;
        let Some(link) = self.state.multibody_joints.rigid_body_link(entry.mb_root).copied() else {
            return;
        };
        let Some(mb) = self.state.multibody_joints.get_multibody(link.multibody) else {
            return;
        };
        // Mass and first moment of each link's subtree: links come parents first.
        let scratch = &mut self.gravity_scratch;
        scratch.clear();
        for l in mb.links() {
            let (m, mc) = self
                .state
                .bodies
                .get(l.rigid_body_handle())
                .map_or((0.0, Vector::ZERO), |rb| (rb.mass(), rb.center_of_mass() * rb.mass()));
            scratch.push((m, mc));
        }
        for l in (0..mb.num_links()).rev() {
            if let Some(p) = mb.link(l).and_then(|k| k.parent_id()) {
                let (m, mc) = scratch[l];
                scratch[p].0 += m;
                scratch[p].1 += mc;
            }
        }
        let entry = &self.state.models[i];
        let offsets = &mut self.gravity_offsets;
        offsets.clear();
        for (v, command) in entry.commands.iter().enumerate() {
            let (&JointCommand::Position { target }, Some(slot)) = (command, entry.slot(v)) else {
                continue;
            };
            let target = entry.gripper.as_ref().map_or(target, |gr| gr.motor_target(v, target));
            let (Some(child), Some(mlink)) = (self.state.bodies.get(slot.body), mb.link(slot.link_id)) else {
                continue;
            };
            let stiffness = entry.gains[v].stiffness;
            if stiffness.is_nan() || stiffness <= 0.0 {
                continue;
            }
            let axis = *child.rotation() * slot.local_axis;
            let (m, mc) = scratch[slot.link_id];
            let load = if slot.axis == 0 {
                m * g.dot(axis)
            } else {
                let anchor = child
                    .position()
                    .transform_point(mlink.joint.data.local_frame2.translation);
                axis.dot((mc - anchor * m).cross(g))
            };
            // A target beyond a limit would only press the joint into its stop.
            let (lo, hi) = (entry.model.lower()[v], entry.model.upper()[v]);
            offsets.push((v, (target - f64::from(load) / stiffness).clamp(lo, hi)));
        }
        let offsets = std::mem::take(&mut self.gravity_offsets);
        for &(v, target) in &offsets {
            self.write_motor_target(i, v, target);
        }
        self.gravity_offsets = offsets;
    }
}

/// Applies the model's joint efforts as equal and opposite body forces/torques.
fn apply_efforts(entry: &ModelEntry, bodies: &mut RigidBodySet) {
    for &h in &entry.bodies {
        if let Some(rb) = bodies.get_mut(h) {
            rb.reset_forces(false);
            rb.reset_torques(false);
        }
    }
    for (v, command) in entry.commands.iter().enumerate() {
        let (JointCommand::Effort { value }, Some(slot)) = (command, entry.slot(v)) else {
            continue;
        };
        let Some(child) = bodies.get(slot.body) else { continue };
        let axis = *child.rotation() * slot.local_axis;
        let point = child.center_of_mass();
        let value = *value as Real;
        if slot.axis == 0 {
            if let Some(rb) = bodies.get_mut(slot.body) {
                rb.add_force(axis * value, true);
            }
            if let Some(rb) = bodies.get_mut(slot.parent_body) {
                rb.add_force_at_point(-axis * value, point, true);
            }
        } else {
            if let Some(rb) = bodies.get_mut(slot.body) {
                rb.add_torque(axis * value, true);
            }
            if let Some(rb) = bodies.get_mut(slot.parent_body) {
                rb.add_torque(-axis * value, true);
            }
        }
    }
}

fn check_position(entry: &ModelEntry, v: usize, x: f64) -> WorldResult<()> {
    let m = &entry.model;
    check_range("position target", &m.variable_names()[v], x, m.lower()[v], m.upper()[v])
}

fn check_velocity(entry: &ModelEntry, v: usize, x: f64) -> WorldResult<()> {
    let m = &entry.model;
    let limit = m.velocity_limits()[v];
    check_range("velocity target", &m.variable_names()[v], x, -limit, limit)
}

fn check_effort(entry: &ModelEntry, v: usize, x: f64) -> WorldResult<()> {
    let m = &entry.model;
    let limit = m.effort_limits()[v];
    check_range("effort", &m.variable_names()[v], x, -limit, limit)
}
