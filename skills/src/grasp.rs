//! Grasping an object: candidates from its collision geometry, a planned approach, a straight
//! final approach, closing the gripper with a force limit, a lift, and a check that the object
//! came along. The held object is then attached to the [`Arm`] for later planning.
//!
//! Candidates are computed in a grasp frame (x: approach, y: finger axis, z: the rest) from the
//! bounding box of the object's collision shape in that frame, so they fit any upright object
//! (bowls, mugs, bottles, boxes): **side grasps** approach horizontally at the object's middle
//! (no lower than the palm allows above its support), **top grasps** approach from above with
//! the fingers across the object at several yaws. A candidate needs the object to be narrower
//! than the gripper opening across its fingers.
//!
//! An open vessel wider than the opening (a bowl) is taken by its **rim**: rays cast straight
//! down onto the object's shape along a line from its axis outwards find the wall (where the
//! rays hit the top), its thickness, and the depth of the inside next to it. When the wall is
//! thin enough for the fingers and the inside deep enough for the inner finger, the gripper
//! comes down with one finger inside and one outside, the finger axis along the line, and
//! pinches the wall's upper part. Rim grasps are tried nearest the robot first, then around
//! the rim.

use hearth_kinematics::to_pose;
use hearth_sim::world::{BodyId, GripperConfig, ModelHandle, World, WorldError};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rand::Rng;

use crate::arm::{Arm, ArmTarget, Held, LinearMove, LinearReport, MotionReport, approach_rotation};
use crate::error::{SkillError, SkillResult, require_non_negative, require_positive};
use crate::execution::Execution;

/// Which way a grasp approaches.
///
/// ```
/// assert_ne!(hearth_skills::grasp::GraspKind::Top, hearth_skills::grasp::GraspKind::Side);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GraspKind {
    /// Horizontally, fingers closing across the object.
    Side,
    /// From above, gripper pointing down.
    Top,
    /// From above at the rim of an open vessel (a bowl, a pot) too wide for the gripper:
    /// one finger inside, one outside, pinching the wall.
    Rim,
}

/// One way to grasp an object.
///
/// ```no_run
/// # fn f(c: hearth_skills::grasp::GraspCandidate) {
/// // The tip's approach axis (+x) is the candidate's approach direction.
/// assert!((c.pose.rotation * nalgebra::Vector3::x() - c.approach).norm() < 1e-9);
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GraspCandidate {
    /// Side, top or rim.
    pub kind: GraspKind,
    /// The tip link's world pose when grasping.
    pub pose: Isometry3<f64>,
    /// Unit approach direction, world frame.
    pub approach: Vector3<f64>,
    /// The object's width across the fingers, metres.
    pub width: f64,
}

/// Gripper geometry and grasp parameters.
///
/// ```
/// let s = hearth_skills::grasp::GraspSettings::default();
/// assert!(s.max_width < 0.094 && s.force > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GraspSettings {
    /// Most squeeze of the fingers, N (within the finger's effort limit). A grasp squeezes
    /// with what holds the object three times over (its weight by friction, and for a rim
    /// grasp the moment of its weight), at least 10 N, at most this.
    pub force: f64,
    /// Widest object across the fingers, metres (the Fetch opens 94 mm between its pads).
    pub max_width: f64,
    /// Distance from the tip link's origin back to the palm along the approach axis, metres.
    pub palm_offset: f64,
    /// Half the palm's height across the approach (keeps side grasps above the support).
    pub palm_half_height: f64,
    /// Length of the finger pads ahead of the tip origin, metres.
    pub finger_reach: f64,
    /// Half the finger pads' height across the approach and the finger axis, metres.
    pub pad_half_height: f64,
    /// Straight final approach, metres.
    pub approach: f64,
    /// Lift after closing, metres.
    pub lift: f64,
    /// Speed of the straight moves, m/s.
    pub speed: f64,
    /// Consider side grasps.
    pub side: bool,
    /// Consider top grasps.
    pub top: bool,
    /// Consider rim grasps (open vessels whose wall the fingers can pinch).
    pub rim: bool,
    /// Grasps computed again at most this often when the object is nudged on the way.
    pub attempts: usize,
    /// Plan the approach only, execute nothing.
    pub dry_run: bool,
}

impl Default for GraspSettings {
    fn default() -> Self {
        Self {
            force: 40.0,
            max_width: 0.086,
            palm_offset: 0.027,
            palm_half_height: 0.045,
            finger_reach: 0.036,
            pad_half_height: 0.018,
            approach: 0.10,
            lift: 0.10,
            speed: 0.08,
            side: true,
            top: true,
            rim: true,
            attempts: 3,
            dry_run: false,
        }
    }
}

/// What a grasp did.
///
/// ```no_run
/// # fn f(r: hearth_skills::grasp::GraspReport) {
/// println!("{:?} grasp, lifted {:.2} m after {:.1} s of approach", r.candidate.kind, r.lifted, r.approach.duration);
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GraspReport {
    /// The candidate used.
    pub candidate: GraspCandidate,
    /// Candidates tried before it.
    pub rejected: usize,
    /// The planned (and unless a dry run, executed) motion to the pre-grasp pose.
    pub approach: MotionReport,
    /// The lift (`None` for a dry run).
    pub lift: Option<LinearReport>,
    /// How far the object rose, metres.
    pub lifted: f64,
}

/// The object's collision shape and its pose in the world now.
fn object_shape(
    world: &World,
    object: ModelHandle,
) -> SkillResult<(hearth_kinematics::parry3d::shape::SharedShape, Isometry3<f64>)> {
    let model = world.model(object)?;
    let root = model.root();
    let shape = model.link_shape(root).ok_or_else(|| {
        SkillError::BadInput(format!(
            "`{}` has no collision shape",
            world.model_name(object).unwrap_or("?")
        ))
    })?;
    Ok((shape.shape.clone(), world.base_pose(object)? * shape.origin))
}

/// Bounding box of the object's shape in `frame` coordinates: (min, max).
fn extents_in(
    shape: &hearth_kinematics::parry3d::shape::SharedShape,
    pose: &Isometry3<f64>,
    frame: &Isometry3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let aabb = shape.compute_aabb(&to_pose(&(frame.inverse() * pose)));
    let v = |p: hearth_kinematics::parry3d::math::Vector| Vector3::new(p.x as f64, p.y as f64, p.z as f64);
    (v(aabb.mins), v(aabb.maxs))
}

/// Grasp candidates for `object`, best first: level side grasps from the direction of `from`
/// (the robot's base position) and 30° and 60° either side of it, top grasps at four yaws
/// (narrowest first), then the side grasps tilted 45° downwards, then rim grasps (open
/// vessels only) around the rim from the side facing `from`.
///
/// # Errors
/// [`SkillError::BadInput`] for an object without collision geometry or bad settings;
/// [`SkillError::World`] for an unknown object.
///
/// ```no_run
/// # fn f(world: &hearth_sim::world::World, mug: hearth_sim::world::ModelHandle) {
/// use hearth_skills::grasp::{grasp_candidates, GraspSettings};
/// let c = grasp_candidates(world, mug, &nalgebra::Point3::origin(), &GraspSettings::default()).unwrap();
/// assert!(!c.is_empty());
/// # }
/// ```
pub fn grasp_candidates(
    world: &World,
    object: ModelHandle,
    from: &Point3<f64>,
    settings: &GraspSettings,
) -> SkillResult<Vec<GraspCandidate>> {
    check_settings(settings)?;
    let (shape, pose) = object_shape(world, object)?;
    let (lo, hi) = extents_in(&shape, &pose, &Isometry3::identity());
    let centre = (lo + hi) / 2.0;
    let mut out = Vec::new();
    let side = |pitch: f64, out: &mut Vec<GraspCandidate>| -> SkillResult<()> {
        let towards = Vector3::new(centre.x - from.x, centre.y - from.y, 0.0);
        let heading = if towards.norm() > 1e-6 {
            towards.y.atan2(towards.x)
        } else {
            0.0
        };
        for offset in [0.0_f64, 30.0, -30.0, 60.0, -60.0] {
            let yaw = heading + offset.to_radians();
            let approach = Vector3::new(yaw.cos() * pitch.cos(), yaw.sin() * pitch.cos(), -pitch.sin());
            let rotation = approach_rotation(&approach, 0.0)?;
            let frame = Isometry3::from_parts(Translation3::from(centre), rotation);
            let (a, b) = extents_in(&shape, &pose, &frame);
            let width = b.y - a.y;
            if width > settings.max_width {
                continue;
            }
            // Palm 5 mm clear of the near face, but no further in than the middle; level
            // grasps high enough for the palm to clear the support.
            let x = (a.x + settings.palm_offset + 0.005).min((a.x + b.x) / 2.0);
            let mut at = frame * Point3::new(x, (a.y + b.y) / 2.0, (a.z + b.z) / 2.0);
            // Lowest point of the gripper below the tip origin: the pads' front lower edge or
            // the palm's lower edge, whichever is lower for this pitch; 1 cm above the support.
            let (sp, cp) = pitch.sin_cos();
            let pads = settings.finger_reach * sp + settings.pad_half_height * cp;
            let palm = settings.palm_half_height * cp - settings.palm_offset * sp;
            at.z = at.z.max(lo.z + pads.max(palm) + 0.01);
            out.push(GraspCandidate {
                kind: GraspKind::Side,
                pose: Isometry3::from_parts(Translation3::from(at.coords), rotation),
                approach,
                width,
            });
        }
        Ok(())
    };
    if settings.side {
        side(0.0, &mut out)?;
    }
    if settings.top {
        let mut tops = Vec::new();
        for k in 0..4 {
            let roll = k as f64 * std::f64::consts::FRAC_PI_4;
            let approach = -Vector3::z();
            let rotation = approach_rotation(&approach, roll)?;
            let frame = Isometry3::from_parts(Translation3::from(centre), rotation);
            let (a, b) = extents_in(&shape, &pose, &frame);
            let width = b.y - a.y;
            if width > settings.max_width {
                continue;
            }
            // Palm 5 mm above the top, fingertips 1 cm above the support at the lowest.
            let top = hi.z;
            let z = (top - settings.palm_offset - 0.005)
                .max(lo.z + settings.finger_reach + 0.01)
                .min(top);
            let mid = frame * Point3::new(0.0, (a.y + b.y) / 2.0, (a.z + b.z) / 2.0);
            tops.push(GraspCandidate {
                kind: GraspKind::Top,
                pose: Isometry3::from_parts(Translation3::new(mid.x, mid.y, z), rotation),
                approach,
                width,
            });
        }
        // Narrowest first: the most room for the fingers.
        tops.sort_by(|a, b| a.width.total_cmp(&b.width));
        out.extend(tops);
    }
    if settings.side {
        side(std::f64::consts::FRAC_PI_4, &mut out)?;
    }
    if settings.rim {
        rim_candidates(&shape, &pose, (&lo, &hi), from, settings, &mut out)?;
    }
    Ok(out)
}

/// Step of the downward ray probes along a line from the object's axis, metres.
const RIM_PROBE_STEP: f64 = 0.002;
/// Offset of the probes from multiples of the step, in steps.
const RIM_PROBE_OFFSET: f64 = 0.37;
/// Room the open inner finger needs inside the wall beyond its pad: its thickness and a margin.
const INNER_FINGER_ROOM: f64 = 0.02;
/// Least length of wall between the pads, metres.
const RIM_MIN_PINCH: f64 = 0.015;

/// Length of wall between the pads that carries a rim grasp's tipping moment, metres.
const RIM_PINCH: f64 = 0.03;
/// Least squeeze of a grasp, N.
const MIN_SQUEEZE: f64 = 10.0;
/// How many times over the squeeze holds the object's weight (or a rim grasp's moment).
const SQUEEZE_SAFETY: f64 = 3.0;
/// Friction the squeeze counts on between pads and object (the pads have more).
const SQUEEZE_FRICTION: f64 = 1.0;

/// The squeeze of a grasp: what holds the object `SQUEEZE_SAFETY` times over, at least
/// `MIN_SQUEEZE` and at most `max`. Two pads carry the weight by friction; a rim grasp also
/// holds the vessel level against the moment of its weight, whose centre hangs off to the
/// side, over `RIM_PINCH` of wall. No more than that: contacts are soft, so a squeeze far
/// beyond the weight sinks the pads millimetres into a light object (into a bowl's thin wall)
/// and lets it turn in the fingers.
fn squeeze(
    world: &World,
    object: ModelHandle,
    bodies: &[BodyId],
    candidate: &GraspCandidate,
    max: f64,
) -> SkillResult<f64> {
    let mass = bodies.iter().map(|&b| world.body_mass(b)).sum::<Result<f64, _>>()?;
    let weight = mass * 9.81;
    let mut need = weight / (2.0 * SQUEEZE_FRICTION);
    if candidate.kind == GraspKind::Rim {
        let lever = (world.base_pose(object)?.translation.vector - candidate.pose.translation.vector)
            .xy()
            .norm();
        need = need.max(weight * lever / RIM_PINCH);
    }
    Ok((SQUEEZE_SAFETY * need).clamp(MIN_SQUEEZE.min(max), max))
}

/// Rim grasps of an open vessel (see the [module docs](self)), pushed onto `out` in order
/// around the rim starting from the side facing `from`.
fn rim_candidates(
    shape: &hearth_kinematics::parry3d::shape::SharedShape,
    pose: &Isometry3<f64>,
    (lo, hi): (&Vector3<f64>, &Vector3<f64>),
    from: &Point3<f64>,
    settings: &GraspSettings,
    out: &mut Vec<GraspCandidate>,
) -> SkillResult<()> {
    use hearth_kinematics::parry3d::math::Vector as V;
    use hearth_kinematics::parry3d::query::Ray;
    let centre = (lo + hi) / 2.0;
    let top = hi.z;
    let reach = 0.5 * (hi.xy() - lo.xy()).norm() + 0.01;
    let parry_pose = to_pose(pose);
    let above = top + 0.05;
    let max_toi = (above - lo.z + 0.05) as f32;
    // Height of the object's surface below (x, y), if any.
    let surface = |x: f64, y: f64| -> Option<f64> {
        let ray = Ray::new(V::new(x as f32, y as f32, above as f32), V::new(0.0, 0.0, -1.0));
        shape
            .cast_ray(&parry_pose, &ray, max_toi, true)
            .map(|t| above - t as f64)
    };
    let towards = Vector3::new(from.x - centre.x, from.y - centre.y, 0.0);
    let heading = if towards.norm() > 1e-6 {
        towards.y.atan2(towards.x)
    } else {
        0.0
    };
    let steps = (reach / RIM_PROBE_STEP).ceil() as usize;
    for offset in [0.0_f64, 45.0, -45.0, 90.0, -90.0, 135.0, -135.0, 180.0] {
        let phi = heading + offset.to_radians();
        let d = Vector3::new(phi.cos(), phi.sin(), 0.0);
        let at = |s: f64| surface(centre.x + s * d.x, centre.y + s * d.y);
        // Probe i lies at (i + PROBE_OFFSET) steps from the axis: off the round numbers at
        // which a ray could graze a face of the shape.
        let probe = |i: f64| (i + RIM_PROBE_OFFSET) * RIM_PROBE_STEP;
        // From outside inwards: the first surface must be the top (the wall's upper edge).
        let is_top = |z: f64| z >= top - 0.01;
        let Some((outer, z_outer)) = (0..=steps).rev().find_map(|i| at(probe(i as f64)).map(|z| (i, z))) else {
            continue;
        };
        if !is_top(z_outer) {
            continue;
        }
        let mut inner = outer;
        while inner > 0 && at(probe((inner - 1) as f64)).is_some_and(is_top) {
            inner -= 1;
        }
        let (s_out, s_in) = (probe(outer as f64 + 0.5), probe(inner as f64 - 0.5));
        let wall = s_out - s_in;
        if inner == 0 || wall + 0.01 > settings.max_width {
            continue;
        }
        let mid = 0.5 * (s_out + s_in);
        // The inner finger's pad and body, open, lie up to this far in from the wall's middle.
        let room = 0.5 * settings.max_width + INNER_FINGER_ROOM;
        // Highest surface there (past the axis too: the far wall of a narrow vessel counts).
        let floor = (1..)
            .map(|k| probe(inner as f64 - k as f64))
            .take_while(|&s| s > mid - room)
            .map(|s| at(s).unwrap_or(lo.z))
            .fold(lo.z, f64::max);
        // Pads over the wall's upper part, fingertips clear of the inside's floor and of the
        // support outside.
        let z = (top - 0.01)
            .max(floor + settings.finger_reach + 0.008)
            .max(lo.z + settings.finger_reach + 0.005);
        if z - settings.finger_reach > top - RIM_MIN_PINCH || z > top {
            continue;
        }
        let rotation = approach_rotation(&-Vector3::z(), std::f64::consts::FRAC_PI_2 - phi)?;
        let p = centre + d * mid;
        out.push(GraspCandidate {
            kind: GraspKind::Rim,
            pose: Isometry3::from_parts(Translation3::new(p.x, p.y, z), rotation),
            approach: -Vector3::z(),
            width: wall,
        });
    }
    Ok(())
}

/// Grasps `object` with `arm`'s gripper and lifts it (see the [module docs](self)).
///
/// # Errors
/// [`SkillError::BadInput`] for bad settings, an object without geometry or one already held;
/// [`SkillError::Unreachable`] when no candidate fits the gripper or none can be reached;
/// [`SkillError::NotHeld`] when the fingers close on nothing; [`SkillError::Slipped`] when the
/// object stays behind on the lift; planning and execution errors of [`Arm`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, mug: hearth_sim::world::ModelHandle) {
/// use hearth_skills::grasp::{grasp, GraspSettings};
/// use rand::SeedableRng;
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let r = grasp(world, arm, mug, &GraspSettings::default(), hearth_skills::Execution::Physics, &mut rng).unwrap();
/// assert!(r.lifted > 0.05 && arm.held().is_some());
/// # }
/// ```
pub fn grasp<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    object: ModelHandle,
    settings: &GraspSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<GraspReport> {
    check_settings(settings)?;
    if let Some(h) = arm.held() {
        return Err(SkillError::BadInput(format!("the gripper already holds `{}`", h.name)));
    }
    let name = world.model_name(object)?.to_owned();
    let bodies = world.model_bodies(object)?;
    let base = world.base_pose(arm.robot())?;
    let from = Point3::from(base.translation.vector);
    // Plans assume the fingers open, as they will be.
    let model_name = world.model(arm.robot())?.name().to_owned();
    let open: Vec<(String, f64)> = GripperConfig::for_builtin(&model_name)
        .map(|g| g.joints.into_iter().zip(g.open).collect())
        .unwrap_or_default();
    let open: Vec<(&str, f64)> = open.iter().map(|(j, x)| (j.as_str(), *x)).collect();
    let mut report = None;
    let mut disturbed = String::new();
    for _ in 0..settings.attempts {
        let candidates = grasp_candidates(world, object, &from, settings)?;
        if candidates.is_empty() {
            return Err(SkillError::Unreachable(format!(
                "`{name}` is wider than the gripper opens ({:.3} m) every way it was tried",
                settings.max_width
            )));
        }
        arm.assume_joints(&open)?;
        let chosen = choose(world, arm, &candidates, &bodies, settings, rng);
        arm.assume_joints(&[])?;
        let (rejected, candidate, plan) = chosen.map_err(|last| {
            SkillError::Unreachable(format!(
                "none of {} grasps of `{name}` can be reached: {last}",
                candidates.len(),
            ))
        })?;
        let mut r = GraspReport {
            candidate: candidate.clone(),
            rejected,
            approach: plan.report.clone(),
            lift: None,
            lifted: 0.0,
        };
        if settings.dry_run {
            return Ok(r);
        }
        // The object may be nudged on the way (a light object pushes back less than the
        // contact threshold); then the grasp is computed again from where it is.
        let planned_at = world.base_pose(object)?.translation.vector;
        world.gripper_open(arm.robot())?;
        r.approach = arm.execute(world, &plan, execution)?;
        let moved = (world.base_pose(object)?.translation.vector - planned_at).norm();
        if moved > 0.02 {
            disturbed = format!("`{name}` moved {moved:.3} m during the approach");
            // Clear of it again before planning anew.
            let back = LinearMove {
                speed: settings.speed,
                check_world: false,
                ..LinearMove::new(-candidate.approach, 0.05)
            };
            arm.move_linear(world, &back, execution)?;
            continue;
        }
        let approach = LinearMove {
            speed: settings.speed,
            force_limit: 30.0,
            ignore: bodies.clone(),
            ..LinearMove::new(candidate.approach, settings.approach)
        };
        let down = arm.move_linear(world, &approach, execution)?;
        let moved = (world.base_pose(object)?.translation.vector - planned_at).norm();
        // Stopped short by a contact (fingertips on the support in the last millimetres are
        // no reason to give up), or the object was pushed.
        if (down.stopped_by_force && down.travelled < settings.approach - 0.01) || moved > 0.02 {
            disturbed = format!(
                "the final approach to `{name}` was blocked ({:.3} m of {:.3} m, object moved {moved:.3} m)",
                down.travelled, settings.approach
            );
            let back = LinearMove {
                speed: settings.speed,
                check_world: false,
                ..LinearMove::new(-candidate.approach, down.travelled + 0.05)
            };
            arm.move_linear(world, &back, execution)?;
            continue;
        }
        report = Some(r);
        break;
    }
    let mut report = report.ok_or_else(|| {
        SkillError::NotHeld(format!(
            "no grasp of `{name}` in {} attempts: {disturbed}",
            settings.attempts
        ))
    })?;
    let force = squeeze(world, object, &bodies, &report.candidate, settings.force)?;
    world.gripper_close(arm.robot(), force)?;
    let dt = world.config().control_dt();
    for _ in 0..(1.2 / dt).ceil() as usize {
        world.step();
    }
    let fingers = finger_contacts(world, arm.robot(), &bodies)?;
    if fingers < 2 {
        world.gripper_open(arm.robot())?;
        return Err(SkillError::NotHeld(format!(
            "the gripper closed with {fingers} finger(s) on `{name}`"
        )));
    }
    let tip = arm.tip_pose(world)?;
    let object_pose = world.base_pose(object)?;
    let (shape, shape_pose) = object_shape(world, object)?;
    arm.set_held(Some(Held {
        object,
        name: name.clone(),
        bodies: bodies.clone(),
        offset: tip.inverse() * object_pose,
        shape,
        shape_offset: tip.inverse() * shape_pose,
        rest: object_pose.rotation,
    }));
    // Lift; what the object rests on is no obstacle for the first centimetres.
    let support: Vec<BodyId> = world
        .contacts(object)?
        .into_iter()
        .map(|c| c.other)
        .filter(|b| !world.model_bodies(arm.robot()).is_ok_and(|r| r.contains(b)))
        .collect();
    let z0 = object_pose.translation.z;
    let lift = LinearMove {
        speed: settings.speed,
        ignore: support,
        ..LinearMove::new(Vector3::z(), settings.lift)
    };
    let lifted = arm.move_linear(world, &lift, execution);
    let lifted = match lifted {
        Ok(l) => l,
        Err(e) => {
            arm.set_held(None);
            return Err(e);
        }
    };
    for _ in 0..10 {
        world.step();
    }
    report.lifted = world.base_pose(object)?.translation.z - z0;
    report.lift = Some(lifted);
    let fingers = finger_contacts(world, arm.robot(), &bodies)?;
    if report.lifted < 0.5 * settings.lift || fingers < 2 {
        arm.set_held(None);
        return Err(SkillError::Slipped(format!(
            "`{name}` rose {:.3} m of {:.3} m with {fingers} finger(s) on it",
            report.lifted, settings.lift
        )));
    }
    // The object may have turned a little in the fingers while lifted: hold it as it hangs.
    let tip = arm.tip_pose(world)?;
    let (shape, shape_pose) = object_shape(world, object)?;
    arm.set_held(Some(Held {
        object,
        name,
        bodies,
        offset: tip.inverse() * world.base_pose(object)?,
        shape,
        shape_offset: tip.inverse() * shape_pose,
        rest: object_pose.rotation,
    }));
    Ok(report)
}

/// The first candidate whose grasp pose has a collision-free IK solution (the object ignored,
/// no margin) and whose pre-grasp pose can be planned to; else the last error's message.
fn choose<R: Rng + ?Sized>(
    world: &World,
    arm: &Arm,
    candidates: &[GraspCandidate],
    bodies: &[BodyId],
    settings: &GraspSettings,
    rng: &mut R,
) -> Result<(usize, GraspCandidate, crate::arm::ArmPlan), String> {
    let mut check = arm.validity(world, bodies, 0.0).map_err(|e| e.to_string())?;
    let mut last = String::from("no candidate");
    for (i, c) in candidates.iter().enumerate() {
        if let Err(e) = arm.goal_configurations(world, &ArmTarget::Pose(c.pose), &mut check, rng) {
            last = e.to_string();
            continue;
        }
        let pre = Isometry3::from_parts(
            Translation3::from(c.pose.translation.vector - c.approach * settings.approach),
            c.pose.rotation,
        );
        match arm.plan(world, &ArmTarget::Pose(pre), &[], rng) {
            Ok(plan) => return Ok((i, c.clone(), plan)),
            Err(e @ (SkillError::IkFailed(_) | SkillError::PlanningFailed(_) | SkillError::PlanningTimeout(_))) => {
                last = e.to_string()
            }
            Err(e) => return Err(e.to_string()),
        }
    }
    Err(last)
}

/// Opens the gripper and forgets the held object (it falls or rests where it is).
///
/// # Errors
/// [`SkillError::NotHeld`] when nothing is held; [`SkillError::World`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm) {
/// hearth_skills::grasp::release(world, arm).unwrap();
/// assert!(arm.held().is_none());
/// # }
/// ```
pub fn release(world: &mut World, arm: &mut Arm) -> SkillResult<Held> {
    let held = arm
        .held()
        .cloned()
        .ok_or_else(|| SkillError::NotHeld("nothing to release".into()))?;
    world.gripper_open(arm.robot())?;
    let dt = world.config().control_dt();
    for _ in 0..(1.2 / dt).ceil() as usize {
        world.step();
    }
    arm.set_held(None);
    Ok(held)
}

/// How many finger links touch one of `bodies` (links named `*finger*`).
fn finger_contacts(world: &World, robot: ModelHandle, bodies: &[BodyId]) -> Result<usize, WorldError> {
    let mut fingers: Vec<String> = world
        .contacts(robot)?
        .into_iter()
        .filter(|c| bodies.contains(&c.other) && c.link.contains("finger"))
        .map(|c| c.link)
        .collect();
    fingers.sort();
    fingers.dedup();
    Ok(fingers.len())
}

fn check_settings(s: &GraspSettings) -> SkillResult<()> {
    require_positive(
        "grasp ",
        &[
            ("force", s.force),
            ("max width", s.max_width),
            ("approach", s.approach),
            ("lift", s.lift),
            ("speed", s.speed),
        ],
    )?;
    require_non_negative(
        "grasp ",
        &[
            ("palm offset", s.palm_offset),
            ("palm half height", s.palm_half_height),
            ("finger reach", s.finger_reach),
            ("pad half height", s.pad_half_height),
        ],
    )?;
    if s.attempts == 0 {
        return Err(SkillError::BadInput("grasp attempts must be at least 1".into()));
    }
    if !s.side && !s.top {
        return Err(SkillError::BadInput(
            "grasp settings allow neither side nor top grasps".into(),
        ));
    }
    Ok(())
}
