//! State readout: joint positions, velocities and efforts; base, link and end-effector poses;
//! contacts per link.

use ::nalgebra::{Isometry3, Vector3};
use hearth_kinematics::from_pose;
use rapier3d::prelude::*;

use super::control::JointCommand;
use super::error::{WorldResult, check_len};
use super::physics::{BodyId, World};
use super::spawn::{BaseMode, ModelEntry, ModelHandle, link_index};

/// Linear and angular velocity of a body, in the world frame.
///
/// ```
/// let t = hearth_sim::world::Twist::default();
/// assert_eq!(t.linear.norm(), 0.0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist {
    /// Linear velocity of the body frame's origin (m/s).
    pub linear: Vector3<f64>,
    /// Angular velocity (rad/s).
    pub angular: Vector3<f64>,
}

/// One contact between a model link and another body.
///
/// ```
/// use hearth_sim::kinematics::RobotModel;
/// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
/// let mut world = World::new(WorldConfig::default())?;
/// let bot = RobotModel::builtin("turtlebot").unwrap();
/// let h = world.spawn_model(&bot, &nalgebra::Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::free())?;
/// for _ in 0..30 { world.step(); }
/// let contacts = world.contacts(h)?;
/// assert!(contacts.iter().any(|c| c.other_name == "ground"));
/// let total: f64 = contacts.iter().map(|c| c.force.z).sum();
/// assert!(total > 0.0, "the ground pushes the robot up");
/// # Ok::<(), hearth_sim::world::WorldError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ContactInfo {
    /// Name of the model link in contact (the main link of its body).
    pub link: String,
    /// The other body.
    pub other: BodyId,
    /// Name of the other body.
    pub other_name: String,
    /// Estimated contact force on the link (N, world frame): the last step's contact impulse
    /// divided by the timestep.
    pub force: Vector3<f64>,
    /// A world point of the contact (the deepest one).
    pub point: Vector3<f64>,
    /// Moment of `force` applied at `point` about the origin of the link's body frame (N·m,
    /// world frame): with `force`, the contact wrench on the link.
    pub torque: Vector3<f64>,
}

/// One contact as [`World::for_each_contact`] hands it over: [`ContactInfo`] with borrowed
/// names.
///
/// ```no_run
/// # fn f(world: &hearth_sim::world::World, robot: hearth_sim::world::ModelHandle) {
/// world.for_each_contact(robot, |c| println!("{} touches {} ({:.1} N)", c.link, c.other_name, c.force.norm())).unwrap();
/// # }
/// ```
#[derive(Clone, Copy, Debug)]
pub struct ContactRef<'a> {
    /// Name of the model link in contact (the main link of its body).
    pub link: &'a str,
    /// The other body.
    pub other: BodyId,
    /// Name of the other body.
    pub other_name: &'a str,
    /// Estimated contact force on the link (N, world frame).
    pub force: Vector3<f64>,
    /// A world point of the contact (the deepest one).
    pub point: Vector3<f64>,
    /// Moment of `force` at `point` about the origin of the link's body frame (N·m, world).
    pub torque: Vector3<f64>,
}

impl World {
    /// Joint positions in `q` order.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let q = world.joint_positions(arm)?;
    /// assert_eq!(q.len(), panda.dof());
    /// assert!(q.iter().zip(panda.neutral_configuration()).all(|(a, b)| (a - b).abs() < 1e-5));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_positions(&self, handle: ModelHandle) -> WorldResult<Vec<f64>> {
        let mut q = vec![0.0; self.entry(handle)?.model.dof()];
        self.joint_positions_into(handle, &mut q)?;
        Ok(q)
    }

    /// Joint positions written into `out` (no allocation).
    ///
    /// # Errors
    /// Unknown model; `out` of the wrong length.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let mut q = vec![0.0; panda.dof()];
    /// world.joint_positions_into(arm, &mut q)?;
    /// assert_eq!(q, world.joint_positions(arm)?);
    /// assert!(world.joint_positions_into(arm, &mut [0.0; 2]).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_positions_into(&self, handle: ModelHandle, out: &mut [f64]) -> WorldResult<()> {
        self.read_joints(handle, out, |_, link, axis| f64::from(link.joint().coords()[axis]))
    }

    /// Joint velocities in `q` order.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// assert!(world.joint_velocities(arm)?.iter().all(|v| *v == 0.0));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_velocities(&self, handle: ModelHandle) -> WorldResult<Vec<f64>> {
        let mut v = vec![0.0; self.entry(handle)?.model.dof()];
        self.joint_velocities_into(handle, &mut v)?;
        Ok(v)
    }

    /// Joint velocities written into `out` (no allocation).
    ///
    /// # Errors
    /// Unknown model; `out` of the wrong length.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let mut v = vec![f64::NAN; panda.dof()];
    /// world.joint_velocities_into(arm, &mut v)?;
    /// assert!(v.iter().all(|x| x.is_finite()));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_velocities_into(&self, handle: ModelHandle, out: &mut [f64]) -> WorldResult<()> {
        self.read_joints(handle, out, |mb, link, _| {
            mb.generalized_velocity()
                .get(link.assembly_id())
                .map_or(0.0, |v| f64::from(*v))
        })
    }

    /// Joint efforts in `q` order: the commanded effort for effort control, otherwise the
    /// motor's force law `clamp(kp·(q* − q) − kd·q̇)` (position) or `clamp(kv·(q̇* − q̇))`
    /// (velocity) evaluated at the current state; 0 for joints without a command.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{JointCommand, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.set_joint_command(arm, "panda_joint1", JointCommand::Effort { value: 2.0 })?;
    /// world.set_joint_command(arm, "panda_joint2", JointCommand::Off)?;
    /// let tau = world.joint_efforts(arm)?;
    /// assert_eq!((tau[0], tau[1]), (2.0, 0.0));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_efforts(&self, handle: ModelHandle) -> WorldResult<Vec<f64>> {
        let entry = self.entry(handle)?;
        let q = self.joint_positions(handle)?;
        let qd = self.joint_velocities(handle)?;
        Ok(entry
            .commands
            .iter()
            .enumerate()
            .map(|(v, c)| {
                let g = entry.gains[v];
                let raw = match *c {
                    JointCommand::Off => 0.0,
                    JointCommand::Effort { value } => value,
                    JointCommand::Position { target } => g.stiffness * (target - q[v]) - g.damping * qd[v],
                    JointCommand::Velocity { target } => g.velocity_gain * (target - qd[v]),
                };
                raw.clamp(-g.max_effort, g.max_effort)
            })
            .collect())
    }

    fn read_joints(
        &self,
        handle: ModelHandle,
        out: &mut [f64],
        read: impl Fn(&Multibody, &MultibodyLink, usize) -> f64,
    ) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        check_len("joint readout buffer", entry.model.dof(), out.len())?;
        let mb = self.multibody_of(handle);
        for (v, o) in out.iter_mut().enumerate() {
            *o = match (mb, entry.slot(v)) {
                (Some(mb), Some(slot)) => mb.link(slot.link_id).map_or(0.0, |l| read(mb, l, slot.axis)),
                _ => 0.0,
            };
        }
        Ok(())
    }

    /// World pose of the model's root link.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &Isometry3::translation(1.0, 0.5, 0.0), SpawnOptions::fixed())?;
    /// let t = world.base_pose(arm)?.translation;
    /// assert!((t.x - 1.0).abs() < 1e-6 && (t.y - 0.5).abs() < 1e-6);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn base_pose(&self, handle: ModelHandle) -> WorldResult<Isometry3<f64>> {
        let entry = self.entry(handle)?;
        let root = entry.model.root();
        Ok(link_world_pose(self, entry, root))
    }

    /// Velocity of the model's root body.
    ///
    /// A [`BaseMode::Holonomic`] base is moved by setting its pose each physics step, so its
    /// body holds no velocity between steps: for it this is the twist it was moved with in
    /// the last physics step, i.e. the [`World::drive_holonomic`] command in the world frame
    /// (its pose change over that step divided by the timestep). It is zero before the first
    /// driven step and after [`World::place`] or a configuration reset, until the next step.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{BaseMode, SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let bot = RobotModel::builtin("turtlebot").unwrap();
    /// let h = world.spawn_model(&bot, &nalgebra::Isometry3::translation(0.0, 0.0, 1.0), SpawnOptions::free())?;
    /// world.step(); // 1/30 s of free fall
    /// let v = world.base_twist(h)?.linear.z;
    /// assert!((v + 9.81 / 30.0).abs() < 0.05, "{v}");
    ///
    /// // A holonomic base reads the twist it is driven with.
    /// let opts = SpawnOptions { base: BaseMode::Holonomic, ..SpawnOptions::default() };
    /// let hb = world.spawn_model(&bot, &nalgebra::Isometry3::translation(2.0, 0.0, 0.01), opts)?;
    /// world.drive_holonomic(hb, 0.4, 0.0, 0.2)?;
    /// world.step();
    /// let t = world.base_twist(hb)?;
    /// assert!((t.linear.norm() - 0.4).abs() < 1e-4 && (t.angular.z - 0.2).abs() < 1e-6, "{t:?}");
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn base_twist(&self, handle: ModelHandle) -> WorldResult<Twist> {
        let entry = self.entry(handle)?;
        if entry.base == BaseMode::Holonomic {
            return Ok(entry.holonomic_twist);
        }
        let Some(rb) = self.state.bodies.get(entry.root) else {
            return Ok(Twist::default());
        };
        let origin = rb.translation();
        let lin = rb.velocity_at_point(origin);
        let ang = rb.angvel();
        Ok(Twist {
            linear: Vector3::new(lin.x.into(), lin.y.into(), lin.z.into()),
            angular: Vector3::new(ang.x.into(), ang.y.into(), ang.z.into()),
        })
    }

    /// World pose of a link by name (e.g. the end effector `panda_hand_tcp`).
    ///
    /// # Errors
    /// Unknown model or link.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let base = nalgebra::Isometry3::translation(1.0, 0.0, 0.0);
    /// let arm = world.spawn_model(&panda, &base, SpawnOptions::fixed())?;
    /// let q = panda.neutral_configuration();
    /// let mut poses = panda.pose_buffer();
    /// panda.fk(&q, &mut poses).unwrap();
    /// let tcp = panda.link_index("panda_hand_tcp").unwrap();
    /// let sim = world.link_pose(arm, "panda_hand_tcp")?;
    /// assert!(((base * poses[tcp]).translation.vector - sim.translation.vector).norm() < 1e-4);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn link_pose(&self, handle: ModelHandle, link: &str) -> WorldResult<Isometry3<f64>> {
        let entry = self.entry(handle)?;
        let l = link_index(entry, link)?;
        Ok(link_world_pose(self, entry, l))
    }

    /// Contacts of the model's links with other bodies (not with its own links), from the last
    /// physics step.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let robot = world.spawn_model(&fetch, &nalgebra::Isometry3::identity(), SpawnOptions::free())?;
    /// for _ in 0..10 { world.step(); }
    /// let on_ground: Vec<_> = world.contacts(robot)?.into_iter().filter(|c| c.link.contains("wheel")).collect();
    /// assert!(!on_ground.is_empty());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn contacts(&self, handle: ModelHandle) -> WorldResult<Vec<ContactInfo>> {
        let mut out = Vec::new();
        self.for_each_contact(handle, |c| {
            out.push(ContactInfo {
                link: c.link.to_owned(),
                other: c.other,
                other_name: c.other_name.to_owned(),
                force: c.force,
                point: c.point,
                torque: c.torque,
            });
        })?;
        Ok(out)
    }

    /// Calls `f` on each contact [`World::contacts`] would list, borrowing the names instead
    /// of copying them: for per-step checks that should not allocate.
    ///
    /// # Errors
    /// [`super::WorldError::UnknownModel`].
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let robot = world.spawn_model(&fetch, &nalgebra::Isometry3::identity(), SpawnOptions::free())?;
    /// for _ in 0..10 { world.step(); }
    /// let mut load = 0.0;
    /// world.for_each_contact(robot, |c| load += c.force.z)?;
    /// assert!(load > 0.0, "the floor carries the robot");
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn for_each_contact(&self, handle: ModelHandle, mut f: impl FnMut(&ContactRef<'_>)) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        let s = &self.state;
        let inv_dt = 1.0 / self.config.timestep;
        for &body in &entry.bodies {
            let Some(rb) = s.bodies.get(body) else { continue };
            let link = self.state.names.get(rb.user_data as usize).map_or("", String::as_str);
            let link = link.rsplit('/').next().unwrap_or(link);
            for &ch in rb.colliders() {
                for pair in s.narrow_phase.contact_pairs_with(ch) {
                    if !pair.has_any_active_contact() {
                        continue;
                    }
                    let (other_collider, sign) = if pair.collider1 == ch {
                        (pair.collider2, -1.0)
                    } else {
                        (pair.collider1, 1.0)
                    };
                    let Some(other_body) = s.colliders.get(other_collider).and_then(|c| c.parent()) else {
                        continue;
                    };
                    if entry
                        .bodies
                        .binary_search_by_key(&other_body.into_raw_parts(), |h| h.into_raw_parts())
                        .is_ok()
                    {
                        continue;
                    }
                    let impulse = pair.total_impulse();
                    let point = pair
                        .find_deepest_contact()
                        .and_then(|(manifold, c)| {
                            // The point on this link's collider; points of a compound's part are
                            // in that part's frame.
                            let (local, part) = if pair.collider1 == ch {
                                (c.local_p1, manifold.subshape_pos1())
                            } else {
                                (c.local_p2, manifold.subshape_pos2())
                            };
                            let local = part.map_or(local, |p| p.transform_point(local));
                            Some(s.colliders.get(ch)?.position().transform_point(local))
                        })
                        .unwrap_or(Vector::ZERO);
                    let force = Vector3::new(impulse.x.into(), impulse.y.into(), impulse.z.into()) * (sign * inv_dt);
                    let point = Vector3::new(point.x.into(), point.y.into(), point.z.into());
                    let origin = rb.translation();
                    let arm = point - Vector3::new(origin.x.into(), origin.y.into(), origin.z.into());
                    f(&ContactRef {
                        link,
                        other: BodyId(other_body),
                        other_name: self.body_name(BodyId(other_body)).unwrap_or(""),
                        force,
                        point,
                        torque: arm.cross(&force),
                    });
                }
            }
        }
        Ok(())
    }
}

fn link_world_pose(world: &World, entry: &ModelEntry, link: usize) -> Isometry3<f64> {
    let (body, offset) = entry.link_bodies[link];
    world
        .state
        .bodies
        .get(body)
        .map_or_else(Isometry3::identity, |rb| from_pose(&(*rb.position() * offset)))
}
