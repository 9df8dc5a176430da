//! Push at a pixel: the action primitive of ReLMoGen (Xia et al., 2021), where a policy picks a
//! pixel of the robot's camera and the robot pushes the surface seen there.
//!
//! The pixel's depth and normal give a world point `p` and outward normal `n`; the gripper goes
//! to a pre-push pose `standoff` in front of `p` (fingertips there, approach axis along `−n`,
//! fingers closed) by a planned, smoothed, jerk-limited motion, then moves straight along `−n`
//! for `distance` with a force limit. The push succeeds when the touched point moved more than
//! `min_motion`. The defaults follow the paper's settings: a 0.30 m push limited to 60 N and a
//! 0.10 m success threshold.

use hearth_kinematics::parry3d::shape::Ball;
use hearth_planning::Obstacles;
use hearth_sim::sensors::{Camera, Modality, ModalitySet};
use hearth_sim::world::{BodyId, World, WorldError};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rand::Rng;

use crate::arm::{Arm, ArmTarget, LinearMove, LinearReport, MotionReport, approach_rotation};
use crate::error::{SkillError, SkillResult, require_non_negative, require_positive};
use crate::execution::Execution;

/// Settings of a push.
///
/// ```
/// let s = hearth_skills::push::PushSettings::default();
/// assert_eq!((s.distance, s.force_limit, s.min_motion), (0.30, 60.0, 0.10));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PushSettings {
    /// Length of the straight push from the pre-push pose, metres.
    pub distance: f64,
    /// Force limit of the push, N.
    pub force_limit: f64,
    /// Gap between the fingertips and the surface at the pre-push pose, metres.
    pub standoff: f64,
    /// Speed of the push, m/s.
    pub speed: f64,
    /// The touched point must move more than this for success, metres.
    pub min_motion: f64,
    /// Squeeze of the closed fingers during the push, N.
    pub grip_force: f64,
    /// Plan only (approach motion found and timed), execute nothing.
    pub dry_run: bool,
}

impl Default for PushSettings {
    fn default() -> Self {
        Self {
            distance: 0.30,
            force_limit: 60.0,
            standoff: 0.05,
            speed: 0.1,
            min_motion: 0.10,
            grip_force: 30.0,
            dry_run: false,
        }
    }
}

/// What a push did.
///
/// ```no_run
/// # fn f(r: hearth_skills::push::PushReport) {
/// println!("pushed `{}` at {:?}: it moved {:.2} m", r.body_name, r.point, r.moved);
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PushReport {
    /// The pushed point, world frame.
    pub point: Point3<f64>,
    /// The surface normal there (towards the camera), world frame.
    pub normal: Vector3<f64>,
    /// The body seen at the pixel.
    pub body: BodyId,
    /// Its name.
    pub body_name: String,
    /// The planned (and, unless a dry run, executed) approach to the pre-push pose.
    pub approach: MotionReport,
    /// The straight push (`None` for a dry run).
    pub push: Option<LinearReport>,
    /// How far the touched point moved, metres (0 for a dry run).
    pub moved: f64,
}

/// The world point, outward normal and body seen at pixel (`u`, `v`) of `camera` now.
///
/// # Errors
/// [`SkillError::BadInput`] for a pixel outside the image, one that sees nothing (sky, beyond
/// the far plane) or sees only the robot itself; [`SkillError::Sensor`] for a failed render.
///
/// ```no_run
/// # fn f(world: &hearth_sim::world::World, camera: &mut hearth_sim::sensors::Camera, robot: hearth_sim::world::ModelHandle) {
/// let (p, n, body) = hearth_skills::push::surface_at_pixel(world, camera, Some(robot), 64, 64).unwrap();
/// assert!((n.norm() - 1.0).abs() < 1e-6);
/// # }
/// ```
pub fn surface_at_pixel(
    world: &World,
    camera: &mut Camera,
    robot: Option<hearth_sim::world::ModelHandle>,
    u: i64,
    v: i64,
) -> SkillResult<(Point3<f64>, Vector3<f64>, BodyId)> {
    let modalities = ModalitySet::EMPTY
        .with(Modality::Depth)
        .with(Modality::Normal)
        .with(Modality::Pc);
    let frame = camera.render(world, modalities)?;
    let (w, h) = (frame.width as i64, frame.height as i64);
    if u < 0 || v < 0 || u >= w || v >= h {
        return Err(SkillError::BadInput(format!(
            "pixel ({u}, {v}) is outside the {w}×{h} image"
        )));
    }
    let i = frame.index(u as u32, v as u32);
    if frame.depth[i] <= 0.0 {
        return Err(SkillError::BadInput(format!(
            "pixel ({u}, {v}) sees nothing within the camera's range"
        )));
    }
    let [px, py, pz] = frame.pc[i];
    let [nx, ny, nz] = frame.normal[i];
    let pose = camera.pose(world)?;
    let p = pose * Point3::new(px as f64, py as f64, pz as f64);
    let n = pose.rotation * Vector3::new(nx as f64, ny as f64, nz as f64);
    let n = n
        .try_normalize(1e-9)
        .ok_or_else(|| SkillError::BadInput(format!("pixel ({u}, {v}) has no surface normal")))?;
    let body = body_at(world, robot, &p)
        .ok_or_else(|| SkillError::BadInput(format!("pixel ({u}, {v}) sees the robot itself, nothing to push")))?;
    Ok((p, n, body))
}

/// The body nearest to `p` within 3 cm, the robot's own excluded.
fn body_at(world: &World, robot: Option<hearth_sim::world::ModelHandle>, p: &Point3<f64>) -> Option<BodyId> {
    let exclude: Vec<_> = robot.into_iter().collect();
    let view = world.obstacles_view(&exclude).ok()?;
    let probe = Ball::new(0.005);
    let pose = hearth_kinematics::to_pose(&Isometry3::translation(p.x, p.y, p.z));
    let (_, id) = view.distance(&probe, &pose, 0.03)?;
    let (co, _) = world.colliders().get_unknown_gen(id.0)?;
    co.parent().map(BodyId::from_handle)
}

/// Pushes what pixel (`u`, `v`) of `camera` sees (see the [module docs](self)).
///
/// # Errors
/// [`SkillError::BadInput`] for a bad pixel or settings; [`SkillError::Unreachable`] when no
/// collision-free pre-push pose is found; planning and execution errors of [`Arm`];
/// [`SkillError::NoEffect`] when the touched point moved no more than `min_motion`.
///
/// ```no_run
/// use hearth_skills::push::{push_at_pixel, PushSettings};
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, camera: &mut hearth_sim::sensors::Camera) {
/// use rand::SeedableRng;
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
/// let report = push_at_pixel(world, arm, camera, 64, 80, &PushSettings::default(),
///                            hearth_skills::Execution::Physics, &mut rng).unwrap();
/// assert!(report.moved > 0.1);
/// # }
/// ```
#[allow(clippy::too_many_arguments)]
pub fn push_at_pixel<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    camera: &mut Camera,
    u: i64,
    v: i64,
    settings: &PushSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<PushReport> {
    check_settings(settings)?;
    let (p, n, body) = surface_at_pixel(world, camera, Some(arm.robot()), u, v)?;
    push_at_point(world, arm, p, n, body, settings, execution, rng)
}

/// Pushes point `p` of `body` along `−n` (`n`: the outward surface normal, world frame).
///
/// # Errors
/// As [`push_at_pixel`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, body: hearth_sim::world::BodyId) {
/// use hearth_skills::push::{push_at_point, PushSettings};
/// use nalgebra::{Point3, Vector3};
/// use rand::SeedableRng;
/// let settings = PushSettings { dry_run: true, ..Default::default() };
/// let r = push_at_point(world, arm, Point3::new(0.8, 0.0, 0.7), -Vector3::x(), body, &settings,
///                       hearth_skills::Execution::Physics, &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert!(r.push.is_none());
/// # }
/// ```
#[allow(clippy::too_many_arguments)]
pub fn push_at_point<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    p: Point3<f64>,
    n: Vector3<f64>,
    body: BodyId,
    settings: &PushSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<PushReport> {
    check_settings(settings)?;
    if !p.coords.iter().all(|x| x.is_finite()) {
        return Err(SkillError::BadInput(format!("push point {p:?} is not finite")));
    }
    let n = n
        .try_normalize(1e-9)
        .filter(|n| n.iter().all(|x| x.is_finite()))
        .ok_or_else(|| SkillError::BadInput(format!("push normal {n:?} is unusable")))?;
    let body_name = world.body_name(body).unwrap_or("").to_owned();
    let local = world.body_pose(body)?.inverse() * p;
    // The pre-push pose: the fingertips `standoff` off the point, the gripper pointing at it
    // along −n, or, where the arm cannot get there, tilted off −n (from above, from the
    // sides, from below): the push itself still runs along −n. The roll about the gripper's
    // axis is free, tried in quarter turns straight on and in half turns tilted.
    let mut last = None;
    let mut plan = None;
    'search: for (pitch, yaw) in APPROACH_TILTS {
        let approach = tilted(&-n, pitch.to_radians(), yaw.to_radians());
        let origin = p - approach * (settings.standoff + arm.settings().tool_reach);
        let rolls: &[f64] = if pitch == 0.0 && yaw == 0.0 {
            &[
                0.0,
                std::f64::consts::FRAC_PI_2,
                -std::f64::consts::FRAC_PI_2,
                std::f64::consts::PI,
            ]
        } else {
            &[0.0, std::f64::consts::FRAC_PI_2]
        };
        for &roll in rolls {
            let pose = Isometry3::from_parts(Translation3::from(origin.coords), approach_rotation(&approach, roll)?);
            match arm.plan(world, &ArmTarget::Pose(pose), &[], rng) {
                Ok(pl) => {
                    plan = Some(pl);
                    break 'search;
                }
                Err(e @ (SkillError::IkFailed(_) | SkillError::PlanningFailed(_) | SkillError::PlanningTimeout(_))) => {
                    last = Some(e)
                }
                Err(e) => return Err(e),
            }
        }
    }
    let plan = plan.ok_or_else(|| {
        SkillError::Unreachable(format!(
            "no pre-push pose in front of ({:.2}, {:.2}, {:.2}) on `{body_name}`: {}",
            p.x,
            p.y,
            p.z,
            last.map(|e| e.to_string()).unwrap_or_default()
        ))
    })?;
    let mut report = PushReport {
        point: p,
        normal: n,
        body,
        body_name,
        approach: plan.report.clone(),
        push: None,
        moved: 0.0,
    };
    if settings.dry_run {
        return Ok(report);
    }
    match world.gripper_close(arm.robot(), settings.grip_force) {
        Ok(()) | Err(WorldError::NoController { .. }) => {}
        Err(e) => return Err(e.into()),
    }
    report.approach = arm.execute(world, &plan, execution)?;
    let push = LinearMove {
        speed: settings.speed,
        force_limit: settings.force_limit,
        ignore: vec![body],
        ..LinearMove::new(-n, settings.distance)
    };
    let done = arm.move_linear(world, &push, execution)?;
    report.push = Some(done);
    report.moved = (world.body_pose(body)? * local - p).norm();
    if report.moved <= settings.min_motion {
        return Err(SkillError::NoEffect(format!(
            "the pushed point on `{}` moved {:.3} m (needs > {:.2} m)",
            report.body_name, report.moved, settings.min_motion
        )));
    }
    Ok(report)
}

/// Tilts of the pre-push approach off −n, degrees: (down from above, sideways).
const APPROACH_TILTS: [(f64, f64); 6] = [
    (0.0, 0.0),
    (30.0, 0.0),
    (0.0, 30.0),
    (0.0, -30.0),
    (50.0, 0.0),
    (-25.0, 0.0),
];

/// `d` (a unit vector) turned `pitch` radians towards world down (about the horizontal axis
/// across it) and `yaw` radians about world up. A vertical `d` is only turned about up.
fn tilted(d: &Vector3<f64>, pitch: f64, yaw: f64) -> Vector3<f64> {
    let across = d.cross(&Vector3::z());
    let pitched = match across.try_normalize(1e-6) {
        // Turning about `across` by +pitch takes a horizontal `d` downwards.
        Some(axis) => nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), -pitch) * d,
        None => *d,
    };
    nalgebra::UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * pitched
}

fn check_settings(s: &PushSettings) -> SkillResult<()> {
    require_positive(
        "push ",
        &[
            ("distance", s.distance),
            ("force limit", s.force_limit),
            ("speed", s.speed),
            ("grip force", s.grip_force),
        ],
    )?;
    require_non_negative("push ", &[("standoff", s.standoff), ("minimum motion", s.min_motion)])
}

#[cfg(test)]
mod tests {
    use super::tilted;
    use nalgebra::Vector3;

    #[test]
    fn tilts_turn_the_approach_down_and_sideways() {
        let d = Vector3::x();
        let down = tilted(&d, 30f64.to_radians(), 0.0);
        assert!((down - Vector3::new(30f64.to_radians().cos(), 0.0, -0.5)).norm() < 1e-12);
        let left = tilted(&d, 0.0, 30f64.to_radians());
        assert!((left - Vector3::new(30f64.to_radians().cos(), 0.5, 0.0)).norm() < 1e-12);
        // A vertical approach has no "down" to turn to.
        assert!((tilted(&-Vector3::z(), 0.5, 0.0) + Vector3::z()).norm() < 1e-12);
    }
}
