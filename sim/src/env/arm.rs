//! The arm part of the manipulation tasks' action: the Fetch's torso and seven arm joints,
//! each commanded by a velocity in [−1, 1] × its velocity limit. The env integrates the
//! velocities into position targets (held by the joint PD controllers), which keeps the arm
//! steady against gravity where rapier's velocity motors would let it sag.

use super::error::{EnvError, EnvResult};
use crate::world::{JointCommand, ModelHandle, World};

/// The commanded joints, in action order.
pub(crate) const ARM_JOINTS: [&str; 8] = [
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
];

/// Arm joints of one robot: indices, limits, and a scratch buffer.
#[derive(Clone, Debug)]
pub(crate) struct Arm {
    index: Vec<usize>,
    max_velocity: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// Control period (s).
    dt: f64,
    q: Vec<f64>,
}

impl Arm {
    /// The arm of `robot` (a Fetch).
    pub(crate) fn new(world: &World, robot: ModelHandle) -> EnvResult<Self> {
        let model = world.model(robot)?;
        let mut index = Vec::with_capacity(ARM_JOINTS.len());
        for joint in ARM_JOINTS {
            let v = model
                .variable_names()
                .iter()
                .position(|n| n == joint)
                .ok_or_else(|| EnvError::Task(format!("the robot has no arm joint `{joint}`")))?;
            index.push(v);
        }
        Ok(Self {
            max_velocity: index.iter().map(|&v| model.velocity_limits()[v]).collect(),
            lower: index.iter().map(|&v| model.lower()[v]).collect(),
            upper: index.iter().map(|&v| model.upper()[v]).collect(),
            index,
            dt: world.config().control_dt(),
            q: vec![0.0; model.dof()],
        })
    }

    /// Number of action entries.
    pub(crate) fn len(&self) -> usize {
        self.index.len()
    }

    /// Advances every joint's position target by `action[k] × limit × dt` (from its current
    /// target, or its position when it has none), clamped to the joint limits.
    pub(crate) fn apply(&mut self, world: &mut World, robot: ModelHandle, action: &[f32]) -> EnvResult<()> {
        world.joint_positions_into(robot, &mut self.q)?;
        let commands = world.joint_commands(robot)?;
        for (k, &v) in self.index.iter().enumerate() {
            let from = match commands[v] {
                JointCommand::Position { target } => target,
                _ => self.q[v],
            };
            let mut target = from + f64::from(action[k].clamp(-1.0, 1.0)) * self.max_velocity[k] * self.dt;
            if self.lower[k].is_finite() && self.upper[k].is_finite() {
                target = target.clamp(self.lower[k], self.upper[k]);
            }
            self.q[v] = target;
        }
        for (k, &v) in self.index.iter().enumerate() {
            world.set_joint_command(robot, ARM_JOINTS[k], JointCommand::Position { target: self.q[v] })?;
        }
        Ok(())
    }

    /// The arm joints' positions.
    pub(crate) fn positions(&self, world: &World, robot: ModelHandle, out: &mut Vec<f32>) -> EnvResult<()> {
        let q = world.joint_positions(robot)?;
        out.extend(self.index.iter().map(|&v| q[v] as f32));
        Ok(())
    }
}
