//! Spawning a [`RobotModel`] as a rapier multibody, placing it and resetting its joints.

use std::sync::Arc;

use std::fmt;

use ::nalgebra::{Isometry3, UnitQuaternion, Vector3};
use hearth_kinematics::{JointKind, RobotModel, to_pose};
use parry3d::mass_properties::MassProperties;
use parry3d::math::Matrix;
use rapier3d::prelude::*;

use super::contact_filter::BodyOwner;
use super::control::{
    BaseDrive, DiffDrive, DiffDriveConfig, FINGER_PAD_FRICTION, Gripper, GripperConfig, JointCommand, JointGains,
    default_gains,
};
use super::error::{WorldError, WorldResult, check_len};
use super::physics::{BodyId, World, check_pose};
use super::readout::Twist;

/// A model (robot or object) spawned in a [`World`].
///
/// ```
/// use hearth_sim::world::ModelHandle;
/// assert_eq!(ModelHandle::from_index(2).index(), 2);
/// assert_eq!(ModelHandle::from_index(2).to_string(), "#2");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ModelHandle(pub(crate) u32);

impl ModelHandle {
    /// The handle's index (models are numbered in spawn order).
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use hearth_sim::kinematics::RobotModel;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), Default::default()).unwrap();
    /// assert_eq!(arm.index(), 0); // the first model spawned
    /// ```
    pub fn index(self) -> usize {
        self.0 as usize
    }

    /// A handle from an index (it may not name a live model).
    ///
    /// ```
    /// # use hearth_sim::world::{ModelHandle, World, WorldConfig};
    /// let world = World::new(WorldConfig::default()).unwrap();
    /// assert!(world.model(ModelHandle::from_index(5)).is_err()); // names no live model
    /// ```
    pub fn from_index(index: usize) -> Self {
        Self(index as u32)
    }
}

impl fmt::Display for ModelHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// How the root link of a model moves.
///
/// ```
/// use hearth_sim::world::{BaseMode, SpawnOptions};
/// assert_eq!(BaseMode::default(), BaseMode::Free);
/// assert_eq!(SpawnOptions::fixed().base, BaseMode::Fixed);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BaseMode {
    /// Welded to the world (arms on a table, furniture, buildings).
    Fixed,
    /// A free dynamic body (mobile robots on wheels, loose objects).
    #[default]
    Free,
    /// A velocity-driven kinematic body following (vx, vy, ω) commands
    /// ([`World::drive_holonomic`]); it pushes objects but is not pushed back.
    Holonomic,
}

/// Options of [`World::spawn_model`].
///
/// ```
/// use hearth_sim::world::{BaseMode, SpawnOptions};
/// let opts = SpawnOptions::fixed();
/// assert_eq!(opts.base, BaseMode::Fixed);
/// assert!(!opts.self_collision);
/// ```
#[derive(Clone, Debug, Default)]
pub struct SpawnOptions {
    /// Instance name used in messages and body names (default: the model's name).
    pub name: Option<String>,
    /// How the root moves.
    pub base: BaseMode,
    /// Initial configuration (default: the model's neutral configuration).
    pub configuration: Option<Vec<f64>>,
    /// Collisions between non-adjacent links of the model (adjacent links never collide).
    pub self_collision: bool,
    /// Density (kg/m³) for links without a URDF inertial (default: the world's).
    pub density: Option<f64>,
    /// Friction coefficient of the model's colliders (default 0.8).
    pub friction: Option<f64>,
    /// Differential drive (default: the built-in table for Fetch, LoCoBot and TurtleBot).
    pub diff_drive: Option<DiffDriveConfig>,
    /// Parallel gripper (default: the built-in table for Panda, Fetch and LoCoBot).
    pub gripper: Option<GripperConfig>,
}

impl SpawnOptions {
    /// Options for a fixed-base model.
    ///
    /// ```
    /// # use hearth_sim::world::{BaseMode, SpawnOptions};
    /// let opts = SpawnOptions::fixed();
    /// assert_eq!(opts.base, BaseMode::Fixed);
    /// assert!(opts.configuration.is_none());
    /// ```
    pub fn fixed() -> Self {
        Self {
            base: BaseMode::Fixed,
            ..Self::default()
        }
    }

    /// Options for a free-floating model.
    ///
    /// ```
    /// # use hearth_sim::world::{BaseMode, SpawnOptions};
    /// assert_eq!(SpawnOptions::free().base, BaseMode::Free);
    /// ```
    pub fn free() -> Self {
        Self::default()
    }
}

/// Where one model joint lives in the multibody.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointSlot {
    /// The rigid body of the joint's child link.
    pub(crate) body: RigidBodyHandle,
    /// The rigid body of the joint's parent link.
    pub(crate) parent_body: RigidBodyHandle,
    /// Multibody link id of `body`.
    pub(crate) link_id: usize,
    /// Spatial axis of the single DoF (0 = LinX for prismatic, 3 = AngX for revolute).
    pub(crate) axis: usize,
    /// The joint axis in the child body frame.
    pub(crate) local_axis: Vector,
}

impl JointSlot {
    pub(crate) fn joint_axis(&self) -> JointAxis {
        if self.axis == 0 {
            JointAxis::LinX
        } else {
            JointAxis::AngX
        }
    }
}

/// A spawned model and its controller state.
#[derive(Clone, Debug)]
pub(crate) struct ModelEntry {
    pub(crate) model: RobotModel,
    pub(crate) name: String,
    pub(crate) base: BaseMode,
    pub(crate) root: RigidBodyHandle,
    /// The body at the root of the model's multibody: `root`, or for a split root, the
    /// collider-less mount welded to it (see [`World::spawn_model`]).
    pub(crate) mb_root: RigidBodyHandle,
    /// Per model link: its body and its pose in that body's frame.
    pub(crate) link_bodies: Vec<(RigidBodyHandle, Pose)>,
    /// Every body of the model, sorted.
    pub(crate) bodies: Vec<RigidBodyHandle>,
    /// Per model joint: its multibody slot (movable joints only).
    pub(crate) joints: Vec<Option<JointSlot>>,
    /// Per configuration variable: the active command.
    pub(crate) commands: Vec<JointCommand>,
    /// Per configuration variable: controller gains.
    pub(crate) gains: Vec<JointGains>,
    pub(crate) drive: Option<BaseDrive>,
    /// The world twist a holonomic base was moved with in the last physics step (zero until
    /// it is first driven, and after its velocities are zeroed); see [`World::base_twist`].
    pub(crate) holonomic_twist: Twist,
    pub(crate) diff_drive: Option<DiffDrive>,
    pub(crate) gripper: Option<Gripper>,
    /// Whether any variable is in effort mode (forces must be re-applied every step).
    pub(crate) has_effort: bool,

    /// Whether position targets are offset by the joints' gravity load each physics step.
    pub(crate) gravity_compensation: bool,
}

impl ModelEntry {
    pub(crate) fn slot(&self, var: usize) -> Option<JointSlot> {
        self.joints[self.model.variables()[var]]
    }

    pub(crate) fn variable_by_name(&self, joint: &str) -> WorldResult<usize> {
        let j = self.model.joint_index(joint).map_err(|_| WorldError::UnknownJoint {
            model: self.name.clone(),
            joint: joint.to_owned(),
        })?;
        let jt = &self.model.joints()[j];
        match jt.variable {
            Some(v) => Ok(v),
            None => Err(WorldError::JointNotCommandable {
                model: self.name.clone(),
                joint: joint.to_owned(),
                reason: if jt.kind == JointKind::Fixed {
                    "it is fixed"
                } else {
                    "it mimics another joint; command its leader"
                },
            }),
        }
    }
}

/// Rotation taking +x onto `axis`.
fn x_to_axis(axis: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::x(), axis)
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI))
}

/// Mass properties of a link's URDF inertial, in the body frame (`offset` = link in body).
fn inertial_mass_properties(inertial: &hearth_kinematics::Inertial, offset: &Isometry3<f64>) -> MassProperties {
    let frame = offset * inertial.origin;
    let r = frame.rotation.to_rotation_matrix();
    let i = r.matrix() * inertial.inertia * r.matrix().transpose();
    let col = |c: usize| parry3d::math::Vector::new(i[(0, c)] as f32, i[(1, c)] as f32, i[(2, c)] as f32);
    let t = frame.translation.vector;
    MassProperties::with_inertia_matrix(
        parry3d::math::Vector::new(t.x as f32, t.y as f32, t.z as f32),
        inertial.mass.max(0.0) as f32,
        Matrix::from_cols(col(0), col(1), col(2)),
    )
}

impl World {
    /// Spawns `model` as a rapier multibody with its root at `pose`.
    ///
    /// One rigid body per group of links welded by fixed joints (fixed joints are merged into
    /// their parent body); one collider per link from its collision shapes (merged into a
    /// compound by the kinematics crate, each element at its `shape_origin`);
    /// masses and inertias from the URDF inertials (density-derived for links without one);
    /// revolute and prismatic joints with their limits, continuous joints without; URDF
    /// damping and friction as joint damping and dry friction; mimic joints coupled to their
    /// leader. Every joint starts under position control holding the initial configuration.
    ///
    /// The root of an object whose links move (a model without a drive or a gripper: a
    /// dresser, a bookcase, a laptop, a cabinet, a fridge) is split in two: the root's
    /// colliders stay on a plain body outside the multibody, and the multibody hangs from a
    /// second, collider-less body (the mount) at the same pose. On a free base both bodies are
    /// dynamic, welded together by a fixed joint, and share the root's mass properties half and
    /// half; on a fixed base both are fixed. Contacts between the root body and the links that
    /// hang on it (all the model's links when self-collisions are off) are dropped, as the
    /// multibody would drop them. Objects resting on such a model's root (books on a
    /// bookcase's shelves, a mug in a counter's sink) then touch a plain body, which rapier
    /// solves on its fast two-body contact path instead of its multibody path. Robots keep
    /// their root in the multibody, and so does every model when
    /// [`WorldConfig::split_roots`](super::WorldConfig::split_roots) is off.
    ///
    /// # Errors
    /// [`WorldError::InvalidModel`] when rapier refuses the articulation, and the usual
    /// input errors for a bad pose or configuration.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// use nalgebra::Isometry3;
    ///
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())?;
    /// assert_eq!(world.joint_positions(arm)?.len(), panda.dof());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn spawn_model(
        &mut self,
        model: &RobotModel,
        pose: &Isometry3<f64>,
        options: SpawnOptions,
    ) -> WorldResult<ModelHandle> {
        let name = options.name.clone().unwrap_or_else(|| model.name().to_owned());
        check_pose("spawn pose", &name, pose)?;
        let q0 = match &options.configuration {
            Some(q) => {
                check_configuration(model, q)?;
                q.clone()
            }
            None => model.neutral_configuration(),
        };
        let density = options.density.unwrap_or(self.config.default_density);
        super::error::check_range("density", &name, density, 1e-6, 1e6)?;
        let friction = options.friction.unwrap_or(0.8);
        super::error::check_range("friction", &name, friction, 0.0, 1e3)?;
        let diff_drive = match options.diff_drive.clone() {
            Some(d) => Some(d.validate(model, &name)?),
            None => DiffDriveConfig::builtin(model),
        };
        let gripper = match options.gripper.clone() {
            Some(g) => Some(g.validate(model, &name)?),
            None => GripperConfig::builtin(model),
        };

        let mut link_poses = model.pose_buffer();
        model.fk(&q0, &mut link_poses).map_err(|e| WorldError::InvalidModel {
            model: name.clone(),
            reason: e.to_string(),
        })?;

        // Group links into bodies: a link behind a fixed joint joins its parent's body.
        let links = model.links();
        let mut group: Vec<(usize, Isometry3<f64>)> = vec![(usize::MAX, Isometry3::identity()); links.len()];
        let mut group_heads: Vec<usize> = Vec::new();
        for (l, link) in links.iter().enumerate() {
            match link.parent_joint.map(|j| &model.joints()[j]) {
                Some(j) if j.kind == JointKind::Fixed => {
                    let (g, off) = group[j.parent];
                    group[l] = (g, off * j.origin);
                }
                _ => {
                    group[l] = (group_heads.len(), Isometry3::identity());
                    group_heads.push(l);
                }
            }
        }

        // Finger links: children of the gripper's joints and of the joints that mimic them.
        let finger_links: Vec<usize> = gripper.as_ref().map_or_else(Vec::new, |g| {
            let leaders: Vec<usize> = model
                .joints()
                .iter()
                .enumerate()
                .filter(|(_, j)| j.variable.is_some_and(|v| g.vars.contains(&v)))
                .map(|(i, _)| i)
                .collect();
            model
                .joints()
                .iter()
                .enumerate()
                .filter(|(i, j)| leaders.contains(i) || j.mimic.as_ref().is_some_and(|m| leaders.contains(&m.joint)))
                .map(|(_, j)| j.child)
                .collect()
        });
        let sleeping = self.config.sleeping;
        let root_group = group[model.root()].0;
        let split =
            self.config.split_roots && split_root(model, options.base, diff_drive.is_some() || gripper.is_some());
        // A free split root's mount is dynamic, welded to the root body, and shares its mass.
        let free_split = split && options.base == BaseMode::Free;
        // Half of a free split root's mass properties: the root body's and the mount's.
        let mut mount_mprops = MassProperties::default();
        let mut body_handles = Vec::with_capacity(group_heads.len());
        for (g, &head) in group_heads.iter().enumerate() {
            let mut mprops = MassProperties::default();
            let mut colliders = Vec::new();
            for (l, link) in links.iter().enumerate().filter(|(l, _)| group[*l].0 == g) {
                let offset = group[l].1;
                let link_density = if link.inertial.is_some() { 0.0 } else { density };
                if let Some(inertial) = &link.inertial {
                    mprops += inertial_mass_properties(inertial, &offset);
                }
                // One collider per link: the model's merged link shape (a compound when the link
                // has several collision elements), which keeps the broad phase small.
                if let Some(shape) = model.link_shape(l) {
                    let builder = ColliderBuilder::new(shape.shape.clone())
                        .position(to_pose(&(offset * shape.origin)))
                        .density(link_density as Real);
                    let is_caster = diff_drive.as_ref().is_some_and(|d| d.casters.contains(&l));
                    colliders.push(if is_caster {
                        // A swivel caster rolls whichever way the base moves: no friction.
                        builder.friction(0.0).friction_combine_rule(CoefficientCombineRule::Min)
                    } else if finger_links.contains(&l) {
                        builder
                            .friction(FINGER_PAD_FRICTION as Real)
                            .friction_combine_rule(CoefficientCombineRule::Max)
                    } else {
                        builder.friction(friction as Real)
                    });
                }
            }
            if mprops.mass() <= 0.0 && colliders.is_empty() {
                // A frame-only body: give it a token mass so the articulation stays regular.
                mprops = MassProperties::new(parry3d::math::Vector::ZERO, 1e-3, parry3d::math::Vector::splat(1e-6));
            }
            let is_root = head == model.root();
            if is_root && free_split {
                // The root's mass is shared with its mount, half each, so that the two bodies
                // welded together weigh what the root weighs.
                let mut total = mprops;
                for c in &colliders {
                    total += c.mass_properties.mass_properties(&*c.shape).transform_by(&c.position);
                }
                if total.mass() > 0.0 {
                    total.set_mass(total.mass() / 2.0, true);
                    mprops = total;
                    mount_mprops = total;
                    colliders = colliders.into_iter().map(|c| c.density(0.0)).collect();
                }
            }
            let builder = if !is_root {
                RigidBodyBuilder::dynamic()
            } else {
                match options.base {
                    BaseMode::Fixed => RigidBodyBuilder::fixed(),
                    BaseMode::Free => RigidBodyBuilder::dynamic(),
                    BaseMode::Holonomic => RigidBodyBuilder::kinematic_velocity_based(),
                }
            }
            .pose(to_pose(&(pose * link_poses[head])))
            .additional_mass_properties(mprops)
            .can_sleep(sleeping);
            let body_name = format!("{name}/{}", links[head].name);
            body_handles.push(self.insert_body(&body_name, builder, colliders));
        }

        // A split root: the multibody hangs from a collider-less mount at the root's pose,
        // welded to the root body by a fixed joint on a free base, fixed like it otherwise.
        let mount = split.then(|| {
            let builder = if free_split {
                RigidBodyBuilder::dynamic().additional_mass_properties(mount_mprops)
            } else {
                RigidBodyBuilder::fixed()
            }
            .can_sleep(sleeping)
            .pose(to_pose(&(pose * link_poses[model.root()])));
            let mount_name = format!("{name}/{}/mount", links[model.root()].name);
            let mount = self.insert_body(&mount_name, builder, []);
            if free_split {
                let weld = FixedJointBuilder::new().contacts_enabled(false);
                self.state
                    .impulse_joints
                    .insert(body_handles[root_group], mount, weld, true);
            }
            mount
        });
        let all_bodies = || body_handles.iter().copied().chain(mount).collect::<Vec<_>>();

        // Articulate: one multibody joint per movable joint.
        let mut joints: Vec<Option<JointSlot>> = vec![None; model.joints().len()];
        for (j, joint) in model.joints().iter().enumerate() {
            if joint.kind == JointKind::Fixed {
                continue;
            }
            let (pg, poff) = group[joint.parent];
            let cg = group[joint.child].0;
            let axis = joint.axis.into_inner();
            let r = x_to_axis(&axis);
            let frame1 = poff * joint.origin * Isometry3::from_parts(Default::default(), r);
            let frame2 = Isometry3::from_parts(Default::default(), r);
            let (locked, dof_axis, spatial) = if joint.kind == JointKind::Prismatic {
                (JointAxesMask::LOCKED_PRISMATIC_AXES, JointAxis::LinX, 0)
            } else {
                (JointAxesMask::LOCKED_REVOLUTE_AXES, JointAxis::AngX, 3)
            };
            let mut builder = GenericJointBuilder::new(locked)
                .local_frame1(to_pose(&frame1))
                .local_frame2(to_pose(&frame2))
                .contacts_enabled(false);
            if joint.kind != JointKind::Continuous && joint.limits.lower.is_finite() && joint.limits.upper.is_finite() {
                builder = builder.limits(dof_axis, [joint.limits.lower as Real, joint.limits.upper as Real]);
            }
            let b1 = match mount {
                Some(m) if pg == root_group => m,
                _ => body_handles[pg],
            };
            let b2 = body_handles[cg];
            let inserted = self.state.multibody_joints.insert(b1, b2, builder.build(), true);
            if inserted.is_none() {
                self.remove_bodies(&all_bodies());
                return Err(WorldError::InvalidModel {
                    model: name,
                    reason: format!("rapier refused the multibody joint `{}`", joint.name),
                });
            }
            let link_id = self.state.multibody_joints.rigid_body_link(b2).map_or(0, |l| l.id);
            joints[j] = Some(JointSlot {
                body: b2,
                parent_body: b1,
                link_id,
                axis: spatial,
                local_axis: parry3d::math::Vector::new(axis.x as f32, axis.y as f32, axis.z as f32),
            });
        }

        let root = body_handles[root_group];
        let mut bodies = all_bodies();
        bodies.sort_by_key(|h| h.into_raw_parts());
        let link_bodies = group.iter().map(|&(g, off)| (body_handles[g], to_pose(&off))).collect();
        let dof = model.dof();
        let handle = ModelHandle(self.state.models.len() as u32);
        if mount.is_some() {
            // The root body's contacts with the links the multibody would keep apart are dropped.
            let hanging: Vec<RigidBodyHandle> = joints
                .iter()
                .flatten()
                .filter(|slot| Some(slot.parent_body) == mount)
                .map(|slot| slot.body)
                .collect();
            let model_index = handle.0;
            for &h in &body_handles {
                let owner = if h == root {
                    BodyOwner::Root { model: model_index }
                } else {
                    BodyOwner::Link {
                        model: model_index,
                        skip_root: !options.self_collision || hanging.contains(&h),
                    }
                };
                self.set_body_owner(h, owner);
            }
        }
        self.state.models.push(ModelEntry {
            model: model.clone(),
            name,
            base: options.base,
            root,
            mb_root: mount.unwrap_or(root),
            link_bodies,
            bodies,
            joints,
            commands: vec![JointCommand::Off; dof],
            gains: Vec::new(),
            drive: None,
            holonomic_twist: Twist::default(),
            diff_drive,
            gripper,
            has_effort: false,
            gravity_compensation: true,
        });
        self.configure_multibody(handle, options.self_collision);
        self.write_configuration(handle, &q0);
        let gains = self.compute_default_gains(handle);
        let entry = &mut self.state.models[handle.index()];
        entry.gains = gains;
        for (v, &q) in q0.iter().enumerate() {
            entry.commands[v] = JointCommand::Position { target: q };
        }
        for v in 0..dof {
            self.write_motor(handle, v);
        }
        Ok(handle)
    }

    /// Self-contacts, URDF damping/friction and mimic couplings of a fresh multibody.
    fn configure_multibody(&mut self, handle: ModelHandle, self_collision: bool) {
        let entry = &self.state.models[handle.index()];
        let model = entry.model.clone();
        let joints = entry.joints.clone();
        let Some(mb) = self.multibody_of_mut(handle) else {
            return;
        };
        mb.set_self_contacts_enabled(self_collision);
        for (j, joint) in model.joints().iter().enumerate() {
            let Some(slot) = joints[j] else { continue };
            let Some(dof) = mb.link(slot.link_id).map(|l| l.assembly_id()) else {
                continue;
            };
            if let Some(d) = joint.dynamics
                && dof < mb.damping().len()
            {
                mb.damping_mut()[dof] = d.damping.max(0.0) as Real;
                mb.frictions_mut()[dof] = d.friction.max(0.0) as Real;
            }
            if let (Some(m), Some(leader)) = (joint.mimic, joint.mimic.and_then(|m| joints[m.joint])) {
                mb.add_dof_coupling(MultibodyDofCoupling {
                    link1: leader.link_id,
                    dof1: 0,
                    axis1: leader.axis,
                    link2: slot.link_id,
                    dof2: 0,
                    axis2: slot.axis,
                    coeff: m.multiplier as Real,
                    offset: m.offset as Real,
                });
            }
        }
    }

    fn compute_default_gains(&mut self, handle: ModelHandle) -> Vec<JointGains> {
        let entry = &self.state.models[handle.index()];
        let model = entry.model.clone();
        let slots: Vec<Option<JointSlot>> = (0..model.dof()).map(|v| entry.slot(v)).collect();
        let root = entry.mb_root;
        let s = &mut self.state;
        let link = s.multibody_joints.rigid_body_link(root).copied();
        let (inv, ids): (Vec<Real>, Vec<Option<usize>>) =
            match link.and_then(|l| s.multibody_joints.get_multibody_mut(l.multibody)) {
                Some(mb) => {
                    let inv = mb.dof_inverse_inertia(&s.bodies);
                    let ids = slots
                        .iter()
                        .map(|sl| sl.and_then(|sl| mb.link(sl.link_id).map(|l| l.assembly_id())))
                        .collect();
                    (inv.iter().copied().collect(), ids)
                }
                None => (Vec::new(), vec![None; slots.len()]),
            };
        (0..model.dof())
            .map(|v| {
                let inv_m = ids[v].and_then(|d| inv.get(d).copied()).unwrap_or(1.0) as f64;
                let m_eff = if inv_m.is_finite() && inv_m > 1e-12 {
                    1.0 / inv_m
                } else {
                    1.0
                };
                default_gains(m_eff, model.effort_limits()[v])
            })
            .collect()
    }

    fn remove_bodies(&mut self, handles: &[RigidBodyHandle]) {
        let s = &mut self.state;
        for &h in handles {
            Arc::make_mut(&mut s.bodies).remove(
                h,
                &mut s.islands,
                Arc::make_mut(&mut s.colliders),
                &mut s.impulse_joints,
                &mut s.multibody_joints,
                &mut s.soft_bodies,
                true,
            );
        }
    }

    pub(crate) fn entry(&self, handle: ModelHandle) -> WorldResult<&ModelEntry> {
        self.state
            .models
            .get(handle.index())
            .ok_or(WorldError::UnknownModel { handle })
    }

    /// The dynamic mount that shares the mass of `body` when `body` is the root body of a model
    /// whose free root is split off its multibody (a fixed root's mount is fixed and massless).
    pub(crate) fn split_mount(&self, handle: ModelHandle, body: BodyId) -> Option<BodyId> {
        let entry = self.state.models.get(handle.index())?;
        let dynamic = self.state.bodies.get(entry.mb_root).is_some_and(|rb| rb.is_dynamic());
        (entry.root == body.0 && entry.mb_root != entry.root && dynamic).then_some(BodyId(entry.mb_root))
    }

    pub(crate) fn multibody_of(&self, handle: ModelHandle) -> Option<&Multibody> {
        let root = self.state.models.get(handle.index())?.mb_root;
        let link = self.state.multibody_joints.rigid_body_link(root)?;
        self.state.multibody_joints.get_multibody(link.multibody)
    }

    pub(crate) fn multibody_of_mut(&mut self, handle: ModelHandle) -> Option<&mut Multibody> {
        let root = self.state.models.get(handle.index())?.mb_root;
        let link = *self.state.multibody_joints.rigid_body_link(root)?;
        self.state.multibody_joints.get_multibody_mut(link.multibody)
    }

    /// The model a spawned handle refers to.
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
    /// assert_eq!(world.model(arm)?.dof(), panda.dof());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn model(&self, handle: ModelHandle) -> WorldResult<&RobotModel> {
        self.entry(handle).map(|e| &e.model)
    }

    /// The instance name of a model.
    ///
    /// # Errors
    /// [`WorldError::UnknownModel`].
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let opts = SpawnOptions { name: Some("left_arm".into()), ..SpawnOptions::fixed() };
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), opts)?;
    /// assert_eq!(world.model_name(arm)?, "left_arm");
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn model_name(&self, handle: ModelHandle) -> WorldResult<&str> {
        self.entry(handle).map(|e| e.name.as_str())
    }

    /// Handles of every spawned model, in spawn order.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// assert_eq!(world.models().collect::<Vec<_>>(), [arm]);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn models(&self) -> impl Iterator<Item = ModelHandle> + '_ {
        (0..self.state.models.len()).map(ModelHandle::from_index)
    }

    /// The first spawned model with instance name `name`, if any.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let robot = world.spawn_model(&fetch, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// assert_eq!(world.model_named(world.model_name(robot)?), Some(robot));
    /// assert_eq!(world.model_named("no such model"), None);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn model_named(&self, name: &str) -> Option<ModelHandle> {
        self.state
            .models
            .iter()
            .position(|e| e.name == name)
            .map(ModelHandle::from_index)
    }

    /// The bodies of a model (one per group of welded links).
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
    /// let bodies = world.model_bodies(arm)?;
    /// assert!(bodies.len() > 1 && bodies.len() <= panda.links().len());
    /// assert!(bodies.contains(&world.link_body(arm, "panda_link0")?));
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn model_bodies(&self, handle: ModelHandle) -> WorldResult<Vec<BodyId>> {
        Ok(self.entry(handle)?.bodies.iter().map(|&h| BodyId(h)).collect())
    }

    /// The body carrying a link.
    ///
    /// # Errors
    /// Unknown model or link.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let hand = world.link_body(arm, "panda_hand")?;
    /// assert_eq!(hand, world.link_body(arm, "panda_link7")?); // welded links share a body
    /// assert!(world.link_body(arm, "no_such_link").is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn link_body(&self, handle: ModelHandle, link: &str) -> WorldResult<BodyId> {
        let entry = self.entry(handle)?;
        let l = link_index(entry, link)?;
        Ok(BodyId(entry.link_bodies[l].0))
    }

    /// Moves a model's root to `pose`, keeping its joint positions, and zeroes its velocities.
    ///
    /// # Errors
    /// Unknown model, non-finite pose.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.place(arm, &Isometry3::translation(0.0, 1.0, 0.0))?;
    /// assert!((world.base_pose(arm)?.translation.y - 1.0).abs() < 1e-6);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn place(&mut self, handle: ModelHandle, pose: &Isometry3<f64>) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        check_pose("place pose", &entry.name, pose)?;
        let roots = [entry.root, entry.mb_root];
        for root in roots {
            if let Some(rb) = Arc::make_mut(&mut self.state.bodies).get_mut(root) {
                rb.set_position(to_pose(pose), true);
            }
        }
        let q = self.joint_positions(handle)?;
        self.write_configuration(handle, &q);
        Ok(())
    }

    /// Resets a model to configuration `q` (joint positions set directly, velocities zeroed)
    /// and makes `q` the position target of every actuated joint. Joints under
    /// [`JointCommand::Off`] (the passive joints of loaded furniture, or joints switched off)
    /// take their new positions and stay free.
    ///
    /// # Errors
    /// Unknown model; wrong length, non-finite or out-of-limit values.
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// let mut q = panda.neutral_configuration();
    /// q[3] = -1.5;
    /// world.reset_configuration(arm, &q)?;
    /// assert!((world.joint_positions(arm)?[3] + 1.5).abs() < 1e-5);
    /// assert!(world.reset_configuration(arm, &[0.0]).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn reset_configuration(&mut self, handle: ModelHandle, q: &[f64]) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        check_configuration(&entry.model, q)?;
        self.write_configuration(handle, q);
        let entry = &mut self.state.models[handle.index()];
        for (v, &x) in q.iter().enumerate() {
            // Unactuated joints (passive furniture joints, joints switched off) stay free.
            if entry.commands[v] != JointCommand::Off {
                entry.commands[v] = JointCommand::Position { target: x };
            }
        }
        // Ramped finger targets start from the new positions.
        if let Some(g) = entry.gripper.as_mut() {
            for (i, &v) in g.vars.iter().enumerate() {
                if let Some(r) = g.ramp[i].as_mut() {
                    *r = q[v];
                }
            }
        }
        for v in 0..q.len() {
            self.write_motor(handle, v);
        }
        self.refresh_effort_flag(handle);
        Ok(())
    }

    /// Sets the joints named in a built-in named configuration (`"tuck"`, `"ready"`, …) and
    /// holds them there; other joints keep their positions.
    ///
    /// # Errors
    /// [`WorldError::UnknownConfiguration`] when the model has no such configuration.
    ///
    /// ```
    /// # use hearth_sim::kinematics::RobotModel;
    /// # use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let arm = world.spawn_model(&panda, &nalgebra::Isometry3::identity(), SpawnOptions::fixed())?;
    /// world.set_named_configuration(arm, "ready")?;
    /// assert!((world.joint_positions(arm)?[3] + 2.356).abs() < 1e-3);
    /// assert!(world.set_named_configuration(arm, "dance").is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn set_named_configuration(&mut self, handle: ModelHandle, name: &str) -> WorldResult<()> {
        let entry = self.entry(handle)?;
        let values = named_configuration(entry.model.name(), name).ok_or_else(|| WorldError::UnknownConfiguration {
            model: entry.name.clone(),
            name: name.to_owned(),
        })?;
        let mut q = self.joint_positions(handle)?;
        let entry = self.entry(handle)?;
        for (joint, value) in values {
            let v = entry.variable_by_name(joint)?;
            q[v] = value.clamp(entry.model.lower()[v], entry.model.upper()[v]);
        }
        self.reset_configuration(handle, &q)
    }

    /// Tucks the arm: [`World::set_named_configuration`] with `"tuck"`.
    ///
    /// # Errors
    /// As [`World::set_named_configuration`].
    ///
    /// ```
    /// use hearth_sim::kinematics::RobotModel;
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default())?;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let robot = world.spawn_model(&fetch, &nalgebra::Isometry3::identity(), SpawnOptions::free())?;
    /// world.tuck(robot)?;
    /// let elbow = fetch.variable_names().iter().position(|n| n == "elbow_flex_joint").unwrap();
    /// assert!((world.joint_positions(robot)?[elbow] - 1.72).abs() < 1e-5);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn tuck(&mut self, handle: ModelHandle) -> WorldResult<()> {
        self.set_named_configuration(handle, "tuck")
    }

    /// Writes joint coordinates (and mimic followers), zeroes velocities, runs forward
    /// kinematics and syncs the colliders. `q` must be valid.
    pub(crate) fn write_configuration(&mut self, handle: ModelHandle, q: &[f64]) {
        let entry = &self.state.models[handle.index()];
        let model = entry.model.clone();
        let joints = entry.joints.clone();
        let bodies = entry.bodies.clone();
        let root = entry.mb_root;
        if let Some(rb) = Arc::make_mut(&mut self.state.bodies).get_mut(root) {
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
        self.state.models[handle.index()].holonomic_twist = Twist::default();
        let s = &mut self.state;
        if let Some(link) = s.multibody_joints.rigid_body_link(root).copied()
            && let Some(mb) = s.multibody_joints.get_multibody_mut(link.multibody)
        {
            // Root type first, so that the generalized vectors have their final size.
            mb.forward_kinematics(&s.bodies, true);
            let mut disp = vec![0.0; mb.ndofs()];
            for (j, slot) in joints.iter().enumerate() {
                let Some(slot) = slot else { continue };
                let Some(l) = mb.link(slot.link_id) else { continue };
                let target = model.joint_position(q, j) as Real;
                let current = l.joint().coords()[slot.axis];
                if let Some(d) = disp.get_mut(l.assembly_id()) {
                    *d = target - current;
                }
            }
            mb.apply_displacements(&disp);
            mb.generalized_velocity_mut().fill(0.0);
            mb.forward_kinematics(&s.bodies, true);
            mb.update_rigid_bodies(Arc::make_mut(&mut s.bodies), true);
        }
        for &h in &bodies {
            if let Some(rb) = Arc::make_mut(&mut s.bodies).get_mut(h)
                && rb.is_dynamic()
            {
                rb.set_linvel(Vector::ZERO, true);
                rb.set_angvel(Vector::ZERO, true);
            }
        }
        self.sync_bodies(&bodies);
        for h in bodies {
            self.wake(h);
        }
    }
}

/// Whether a model's root is split off its multibody (see [`World::spawn_model`]): objects (no
/// drive, no gripper) on a free or fixed base whose links move. Robots, whose bases are
/// driven through the multibody, keep their root in it.
fn split_root(model: &RobotModel, base: BaseMode, is_robot: bool) -> bool {
    let moves = model.joints().iter().any(|j| j.kind != JointKind::Fixed);
    moves && !is_robot && matches!(base, BaseMode::Free | BaseMode::Fixed)
}

/// Checks a configuration's length, finiteness and limits.
fn check_configuration(model: &RobotModel, q: &[f64]) -> WorldResult<()> {
    check_len("configuration", model.dof(), q.len())?;
    for (v, &x) in q.iter().enumerate() {
        let joint = &model.variable_names()[v];
        super::error::check_range("configuration", joint, x, model.lower()[v], model.upper()[v])?;
    }
    Ok(())
}

/// Index of a link by name, as a world error.
pub(crate) fn link_index(entry: &ModelEntry, link: &str) -> WorldResult<usize> {
    entry.model.link_index(link).map_err(|_| WorldError::UnknownLink {
        model: entry.name.clone(),
        link: link.to_owned(),
    })
}

/// Built-in named configurations: `(robot, name)` → joint values (`fetch`/`tuck`,
/// `panda`/`ready` (= `tuck`), `locobot`/`tuck`).
///
/// ```
/// let tuck = hearth_sim::world::named_configuration("fetch", "tuck").unwrap();
/// assert!(tuck.contains(&("elbow_flex_joint", 1.72)));
/// assert!(hearth_sim::world::named_configuration("fetch", "dance").is_none());
/// ```
pub fn named_configuration(robot: &str, name: &str) -> Option<Vec<(&'static str, f64)>> {
    const FETCH_TUCK: &[(&str, f64)] = &[
        ("torso_lift_joint", 0.0),
        ("shoulder_pan_joint", 1.32),
        ("shoulder_lift_joint", 1.40),
        ("upperarm_roll_joint", -0.2),
        ("elbow_flex_joint", 1.72),
        ("forearm_roll_joint", 0.0),
        ("wrist_flex_joint", 1.66),
        ("wrist_roll_joint", 0.0),
    ];
    const PANDA_READY: &[(&str, f64)] = &[
        ("panda_joint1", 0.0),
        ("panda_joint2", -0.785),
        ("panda_joint3", 0.0),
        ("panda_joint4", -2.356),
        ("panda_joint5", 0.0),
        ("panda_joint6", 1.571),
        ("panda_joint7", 0.785),
    ];
    const LOCOBOT_TUCK: &[(&str, f64)] = &[
        ("joint_1", 0.0),
        ("joint_2", -1.3),
        ("joint_3", 1.5),
        ("joint_4", 0.5),
        ("joint_5", 0.0),
    ];
    let table: &[(&str, f64)] = match (robot, name) {
        ("fetch", "tuck") => FETCH_TUCK,
        ("panda", "ready" | "tuck") => PANDA_READY,
        ("locobot", "tuck") => LOCOBOT_TUCK,
        _ => return None,
    };
    Some(table.to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn x_maps_onto_any_axis() {
        for axis in [
            Vector3::x(),
            -Vector3::x(),
            Vector3::y(),
            -Vector3::z(),
            Vector3::new(1.0, 2.0, -3.0).normalize(),
        ] {
            let r = x_to_axis(&axis);
            assert!((r * Vector3::x() - axis).norm() < 1e-12, "{axis:?}");
        }
    }

    #[test]
    fn inertials_are_rotated_into_the_body_frame() {
        let inertial = hearth_kinematics::Inertial {
            origin: Isometry3::new(
                Vector3::new(0.1, 0.0, 0.0),
                Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
            ),
            mass: 2.0,
            inertia: ::nalgebra::Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0)),
        };
        let m = inertial_mass_properties(&inertial, &Isometry3::translation(0.0, 0.5, 0.0));
        assert!((m.mass() - 2.0).abs() < 1e-6);
        assert!((m.local_com - parry3d::math::Vector::new(0.1, 0.5, 0.0)).length() < 1e-6);
        let i = m.reconstruct_inertia_matrix();
        // A quarter turn about z swaps the x and y moments.
        assert!((i.x_axis.x - 2.0).abs() < 1e-5 && (i.y_axis.y - 1.0).abs() < 1e-5 && (i.z_axis.z - 3.0).abs() < 1e-5);
    }
}
