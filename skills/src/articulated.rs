//! Opening and closing articulated furniture: a drawer along its prismatic axis, a door along
//! its revolute arc.
//!
//! The handle is found from the moving link's collision geometry: of the link's collision
//! parts, the one reaching furthest out of the front (along the drawer's axis, or along the way
//! a door's leaf swings open) is the handle. The gripper pinches it across its thinnest side
//! (approach into the front, fingertips just clear of the panel), then the tip follows the
//! joint's motion — a straight pull or push for a drawer, an arc about the hinge for a door —
//! in small IK steps with a force limit, lets go and backs off. The joint must end up moved by
//! at least `min_fraction` of what was asked.
//!
//! With [`Execution::Kinematic`] the arm's joints are set along the motion and the furniture
//! joint is set to follow the tip's progress at its end (teleported fingers drag nothing).
//!
//! Furniture loaded with a scene has its drawers and vertical-hinge doors unactuated (free,
//! with their damping and friction). A model spawned on its own holds its joints with position
//! motors until `World::set_joint_command(.., JointCommand::Off)` frees them; a held joint
//! resists the robot and the skill reports [`SkillError::NoEffect`].

use hearth_kinematics::parry3d::shape::SharedShape;
use hearth_kinematics::{JointKind, Num, to_pose};
use hearth_sim::world::{GripperConfig, ModelHandle, World};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};
use rand::Rng;

use crate::arm::{Arm, ArmTarget, LinearMove, MotionReport, PoseMove, PoseReport};
use crate::error::{SkillError, SkillResult, require_positive};
use crate::execution::Execution;

/// Parameters of opening and closing.
///
/// ```
/// let s = hearth_skills::articulated::ArticulatedSettings::default();
/// assert!(s.grip_force <= 60.0 && s.min_fraction > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ArticulatedSettings {
    /// Squeeze on the handle, N (within the finger's effort limit).
    pub grip_force: f64,
    /// Force limit of the pull or push, N.
    pub force_limit: f64,
    /// Speed of the handle, m/s.
    pub speed: f64,
    /// Straight final approach to the handle, metres.
    pub approach: f64,
    /// Straight retreat after letting go, metres.
    pub retreat: f64,
    /// Length of the finger pads ahead of the tip origin, metres.
    pub finger_reach: f64,
    /// Widest handle across the fingers, metres.
    pub max_width: f64,
    /// The joint must move at least this fraction of the asked amount.
    pub min_fraction: f64,
    /// Plan the approach to the handle only, execute nothing.
    pub dry_run: bool,
}

impl Default for ArticulatedSettings {
    fn default() -> Self {
        Self {
            grip_force: 60.0,
            force_limit: 80.0,
            speed: 0.08,
            approach: 0.10,
            retreat: 0.08,
            finger_reach: 0.036,
            max_width: 0.086,
            min_fraction: 0.6,
            dry_run: false,
        }
    }
}

/// What opening or closing did.
///
/// ```no_run
/// # fn f(r: hearth_skills::articulated::ArticulatedReport) {
/// println!("`{}` moved from {:.2} to {:.2} (asked {:.2})", r.joint, r.start, r.end, r.target);
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ArticulatedReport {
    /// The joint moved.
    pub joint: String,
    /// Its position before, m or rad.
    pub start: f64,
    /// The position asked for (clamped to the joint's limits).
    pub target: f64,
    /// Its position after (the start for a dry run).
    pub end: f64,
    /// The tip pose grasping the handle, world frame.
    pub grasp: Isometry3<f64>,
    /// The motion to the pre-grasp pose.
    pub approach: MotionReport,
    /// The pull or push along the joint (`None` for a dry run).
    pub motion: Option<PoseReport>,
}

/// Opens joint `joint` of `object` by `amount` (metres for a drawer, radians for a door;
/// towards the joint's upper limit). See the [module docs](self).
///
/// # Errors
/// As [`move_joint`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, cabinet: hearth_sim::world::ModelHandle) {
/// use hearth_skills::articulated::{open, ArticulatedSettings};
/// use rand::SeedableRng;
/// let r = open(world, arm, cabinet, "drawer_2_slide", 0.25, &ArticulatedSettings::default(),
///              hearth_skills::Execution::Physics, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert!(r.end - r.start > 0.15);
/// # }
/// ```
#[allow(clippy::too_many_arguments)]
pub fn open<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    object: ModelHandle,
    joint: &str,
    amount: f64,
    settings: &ArticulatedSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<ArticulatedReport> {
    check_amount(amount)?;
    move_joint(world, arm, object, joint, amount, settings, execution, rng)
}

/// Closes joint `joint` of `object` by `amount` (towards the lower limit).
///
/// # Errors
/// As [`move_joint`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, cabinet: hearth_sim::world::ModelHandle) {
/// use hearth_skills::articulated::{close, ArticulatedSettings};
/// use rand::SeedableRng;
/// let r = close(world, arm, cabinet, "drawer_2_slide", 0.2, &ArticulatedSettings::default(),
///               hearth_skills::Execution::Physics, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert!(r.end < r.start);
/// # }
/// ```
#[allow(clippy::too_many_arguments)]
pub fn close<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    object: ModelHandle,
    joint: &str,
    amount: f64,
    settings: &ArticulatedSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<ArticulatedReport> {
    check_amount(amount)?;
    move_joint(world, arm, object, joint, -amount, settings, execution, rng)
}

fn check_amount(amount: f64) -> SkillResult<()> {
    require_positive("", &[("amount", amount)])
}

/// The handle of the link moved by a joint: its centre, its outer face's coordinate along the
/// outward direction `n`, the finger axis (across its thinnest side), its depth along `n` and
/// its width across the fingers, all in the world frame.
struct Handle {
    centre: Point3<f64>,
    outer: f64,
    across: Vector3<f64>,
    depth: f64,
    width: f64,
}

/// A rotation whose x axis is `x` (unit).
fn frame_x(x: &Vector3<f64>) -> Rotation3<f64> {
    let up = if x.z.abs() > 0.9 { Vector3::x() } else { Vector3::z() };
    let z = (up - x * up.dot(x)).normalize();
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[*x, z.cross(x), z]))
}

fn find_handle(shape: &SharedShape, link_pose: &Isometry3<f64>, out: &Vector3<f64>) -> Option<Handle> {
    let r = frame_x(out);
    let frame = Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_rotation_matrix(&r));
    let parts: Vec<(Isometry3<f64>, SharedShape)> = match shape.as_compound() {
        Some(c) => c
            .shapes()
            .iter()
            .map(|(p, s)| (hearth_kinematics::from_pose(p), s.clone()))
            .collect(),
        None => vec![(Isometry3::identity(), shape.clone())],
    };
    let mut best: Option<(f64, hearth_kinematics::parry3d::bounding_volume::Aabb)> = None;
    for (pose, part) in &parts {
        let aabb = part.compute_aabb(&to_pose(&(frame.inverse() * link_pose * pose)));
        let reach = aabb.maxs.x as f64;
        if best.as_ref().is_none_or(|(b, _)| reach > *b + 1e-6) {
            best = Some((reach, aabb));
        }
    }
    let (_, aabb) = best?;
    let (lo, hi) = (aabb.mins, aabb.maxs);
    let (dy, dz) = ((hi.y - lo.y) as f64, (hi.z - lo.z) as f64);
    let centre = frame
        * Point3::new(
            (lo.x + hi.x) as f64 / 2.0,
            (lo.y + hi.y) as f64 / 2.0,
            (lo.z + hi.z) as f64 / 2.0,
        );
    let (across, width) = if dz <= dy {
        (r * Vector3::z(), dz)
    } else {
        (r * Vector3::y(), dy)
    };
    Some(Handle {
        centre,
        outer: hi.x as f64,
        across,
        depth: (hi.x - lo.x) as f64,
        width,
    })
}

/// Moves joint `joint` of `object` by `delta` (clamped to its limits): grasps the handle of
/// the link it moves, follows the joint's motion, lets go, backs off.
///
/// # Errors
/// [`SkillError::BadInput`] for an unknown or fixed joint, bad settings or a joint already at
/// the limit; [`SkillError::Unreachable`] when the handle is too wide or cannot be reached;
/// [`SkillError::NotHeld`] when the fingers miss the handle; [`SkillError::NoEffect`] when
/// the joint moved less than `min_fraction` of the way; planning and execution errors of
/// [`Arm`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, fridge: hearth_sim::world::ModelHandle) {
/// use hearth_skills::articulated::{move_joint, ArticulatedSettings};
/// use rand::SeedableRng;
/// let r = move_joint(world, arm, fridge, "door_0_hinge", 0.6, &ArticulatedSettings::default(),
///                    hearth_skills::Execution::Physics, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert!(r.end > r.start);
/// # }
/// ```
#[allow(clippy::too_many_arguments)]
pub fn move_joint<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    object: ModelHandle,
    joint: &str,
    delta: f64,
    settings: &ArticulatedSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<ArticulatedReport> {
    check_settings(settings)?;
    if !delta.is_finite() {
        return Err(SkillError::BadInput(format!(
            "joint motion {} is not finite",
            Num(delta)
        )));
    }
    if let Some(h) = arm.held() {
        return Err(SkillError::BadInput(format!(
            "the gripper holds `{}`; it needs to be free to take a handle",
            h.name
        )));
    }
    let model = world.model(object)?.clone();
    let name = world.model_name(object)?.to_owned();
    let j = model
        .joint_index(joint)
        .map_err(|_| SkillError::BadInput(format!("`{name}` has no joint `{joint}`")))?;
    let spec = &model.joints()[j];
    let v = match (spec.kind, spec.variable) {
        (JointKind::Prismatic | JointKind::Revolute, Some(v)) => v,
        _ => {
            return Err(SkillError::BadInput(format!(
                "joint `{joint}` of `{name}` is not an independent prismatic or revolute joint"
            )));
        }
    };
    let start = world.joint_positions(object)?[v];
    let target = (start + delta).clamp(model.lower()[v], model.upper()[v]);
    if (target - start).abs() < 1e-3 {
        return Err(SkillError::BadInput(format!(
            "joint `{joint}` of `{name}` is at {start:.3}, already at its limit that way"
        )));
    }
    let link_name = model.links()[spec.child].name.clone();
    let link_pose = world.link_pose(object, &link_name)?;
    let body = world.link_body(object, &link_name)?;
    let axis = link_pose.rotation * spec.axis.into_inner();
    let hinge = Point3::from(link_pose.translation.vector);
    let shape = model
        .link_shape(spec.child)
        .ok_or_else(|| SkillError::BadInput(format!("link `{link_name}` of `{name}` has no collision shape")))?;
    let shape_pose = link_pose * shape.origin;
    // Outward: along a drawer's axis; for a door, the way its leaf's middle swings open.
    let out = match spec.kind {
        JointKind::Prismatic => axis,
        _ => {
            let middle = shape.shape.compute_aabb(&to_pose(&shape_pose)).center();
            let middle = Point3::new(middle.x as f64, middle.y as f64, middle.z as f64);
            let swing = axis
                .cross(&(middle - hinge))
                .try_normalize(1e-9)
                .ok_or_else(|| SkillError::BadInput(format!("link `{link_name}` lies on its hinge axis")))?;
            // The middle sits a little in front of the hinge, so its swing leans off the leaf's
            // normal: snap it to the nearest axis of the link frame (leaves are built square).
            let frame = [Vector3::x(), Vector3::y(), Vector3::z()].map(|e| link_pose.rotation * e);
            frame
                .iter()
                .flat_map(|e| [*e, -*e])
                .max_by(|a, b| a.dot(&swing).total_cmp(&b.dot(&swing)))
                .unwrap_or(swing)
        }
    };
    let handle = find_handle(&shape.shape, &shape_pose, &out)
        .ok_or_else(|| SkillError::BadInput(format!("link `{link_name}` has no parts")))?;
    if handle.width > settings.max_width {
        return Err(SkillError::Unreachable(format!(
            "the handle of `{link_name}` is {:.3} m across, wider than the gripper takes",
            handle.width
        )));
    }
    // Fingertips 4 mm clear of the panel behind the handle (or at the handle's back).
    let pad_tip = handle.outer - handle.depth.min(settings.finger_reach * 2.0 - 0.004) + 0.004;
    let along = pad_tip + settings.finger_reach - handle.centre.coords.dot(&out);
    let origin = handle.centre + out * along;
    let approach = -out;
    let y = handle.across;
    let rotation = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[approach, y, approach.cross(&y)]));
    let grasp = Isometry3::from_parts(
        Translation3::from(origin.coords),
        UnitQuaternion::from_rotation_matrix(&rotation),
    );
    let pre = Isometry3::from_parts(
        Translation3::from(origin.coords + out * settings.approach),
        grasp.rotation,
    );
    // Plans assume the fingers open, as they will be.
    let open: Vec<(String, f64)> = GripperConfig::for_builtin(world.model(arm.robot())?.name())
        .map(|g| g.joints.into_iter().zip(g.open).collect())
        .unwrap_or_default();
    let open: Vec<(&str, f64)> = open.iter().map(|(j, x)| (j.as_str(), *x)).collect();
    arm.assume_joints(&open)?;
    let plan = arm.plan(world, &ArmTarget::Pose(pre), &[], rng);
    arm.assume_joints(&[])?;
    let plan = plan.map_err(|e| match e {
        SkillError::IkFailed(m) | SkillError::PlanningFailed(m) | SkillError::PlanningTimeout(m) => {
            SkillError::Unreachable(format!("the handle of `{link_name}` cannot be reached: {m}"))
        }
        other => other,
    })?;
    let mut report = ArticulatedReport {
        joint: joint.to_owned(),
        start,
        target,
        end: start,
        grasp,
        approach: plan.report.clone(),
        motion: None,
    };
    if settings.dry_run {
        return Ok(report);
    }
    world.gripper_open(arm.robot())?;
    report.approach = arm.execute(world, &plan, execution)?;
    let reach = LinearMove {
        speed: settings.speed,
        force_limit: 30.0,
        ignore: vec![body],
        ..LinearMove::new(approach, settings.approach)
    };
    arm.move_linear(world, &reach, execution)?;
    world.gripper_close(arm.robot(), settings.grip_force)?;
    let dt = world.config().control_dt();
    for _ in 0..(1.0 / dt).ceil() as usize {
        world.step();
    }
    let on_handle = world
        .contacts(arm.robot())?
        .into_iter()
        .filter(|c| c.other == body && c.link.contains("finger"))
        .map(|c| c.link)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    if on_handle < 2 {
        world.gripper_open(arm.robot())?;
        return Err(SkillError::NotHeld(format!(
            "{on_handle} finger(s) on the handle of `{link_name}`"
        )));
    }
    // The tip follows the joint: a straight line or an arc about the hinge.
    let tip = arm.tip_pose(world)?;
    let travel = target - start;
    let radius = (handle.centre - hinge).cross(&axis).norm().max(0.05);
    let step = match spec.kind {
        JointKind::Prismatic => 0.01,
        _ => 0.01 / radius,
    };
    let steps = (travel.abs() / step).ceil().max(1.0) as usize;
    let poses: Vec<Isometry3<f64>> = (1..=steps)
        .map(|k| {
            let s = travel * k as f64 / steps as f64;
            match spec.kind {
                JointKind::Prismatic => {
                    Isometry3::from_parts(Translation3::from(axis * s), UnitQuaternion::identity()) * tip
                }
                _ => {
                    let turn = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), s);
                    let about = Isometry3::from_parts(Translation3::from(hinge.coords), turn)
                        * Isometry3::translation(-hinge.x, -hinge.y, -hinge.z);
                    about * tip
                }
            }
        })
        .collect();
    let length = match spec.kind {
        JointKind::Prismatic => travel.abs(),
        _ => travel.abs() * radius,
    };
    // The pinched bar's long axis (across both the approach and the finger axis), through
    // the pads' centre: turning about it keeps the grip.
    let bar = tip.inverse() * handle.centre;
    let free_axis = Some((Point3::new(bar.x, bar.y, 0.0), Vector3::z()));
    let motion = PoseMove {
        free_axis,
        step_time: length / steps as f64 / settings.speed,
        force_limit: settings.force_limit,
        ignore: vec![body],
        ..PoseMove::new(poses)
    };
    let moved = arm.move_through(world, &motion, execution);
    if let (Execution::Kinematic, Ok(m)) = (execution, &moved) {
        // Teleported fingers drag nothing by friction: the joint is set to follow the tip.
        let commands = world.joint_commands(object)?.to_vec();
        let mut q = world.joint_positions(object)?;
        q[v] = start + travel * m.planned as f64 / m.requested.max(1) as f64;
        // Joints resting on a limit read back a hair beyond it (float noise of the solver);
        // such a reading is the limit itself.
        for x in q.iter_mut() {
            if x.abs() < 1e-9 {
                *x = 0.0;
            }
        }
        world.reset_configuration(object, &q)?;
        for (k, c) in commands.into_iter().enumerate() {
            world.set_joint_command(object, &model.variable_names()[k], c)?;
        }
    }
    world.gripper_open(arm.robot())?;
    for _ in 0..(0.8 / dt).ceil() as usize {
        world.step();
    }
    let moved = moved?;
    let back_dir = arm.tip_pose(world)?.rotation * -Vector3::x();
    let back = LinearMove {
        speed: settings.speed,
        check_world: false,
        ..LinearMove::new(back_dir, settings.retreat)
    };
    arm.move_linear(world, &back, execution)?;
    report.motion = Some(moved);
    report.end = world.joint_positions(object)?[v];
    let done = (report.end - start) / (target - start);
    if done < settings.min_fraction {
        let m = report.motion.as_ref();
        return Err(SkillError::NoEffect(format!(
            "joint `{joint}` of `{name}` moved from {start:.3} to {:.3} of the asked {target:.3} \
             (the tip followed {} of {} steps{})",
            report.end,
            m.map_or(0, |m| m.planned),
            m.map_or(0, |m| m.requested),
            if m.is_some_and(|m| m.stopped_by_force) {
                ", stopped by the force limit"
            } else {
                ""
            }
        )));
    }
    Ok(report)
}

fn check_settings(s: &ArticulatedSettings) -> SkillResult<()> {
    require_positive(
        "",
        &[
            ("grip force", s.grip_force),
            ("force limit", s.force_limit),
            ("speed", s.speed),
            ("approach", s.approach),
            ("retreat", s.retreat),
            ("finger reach", s.finger_reach),
            ("max width", s.max_width),
        ],
    )?;
    if !(0.0..=1.0).contains(&s.min_fraction) || s.min_fraction == 0.0 {
        return Err(SkillError::BadInput(format!(
            "minimum fraction {} must be in (0, 1]",
            s.min_fraction
        )));
    }
    Ok(())
}
