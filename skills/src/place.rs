//! Placing the held object: a stable placement sampled on a support surface, a planned motion
//! above it, a straight descent, release and retreat.
//!
//! A placement keeps the object upright (the orientation it rested in before the grasp, turned
//! about the vertical by a sampled yaw) with its bottom `clearance` above the surface and its
//! footprint inside the surface, clear of everything else on it. Surfaces are rectangles in the world frame: the top
//! of a model ([`PlaceTarget::on_top_of`]), every free top face of its collision parts (a
//! worktop, a shelf, the floor of a sink's basin: [`PlaceTarget::surfaces_of`]), an asset's
//! [`Surface`] posed in the world ([`PlaceTarget::from_surface`]),
//! or any rectangle.

use hearth_kinematics::to_pose;
use hearth_planning::Obstacles;
use hearth_sim::assets::Surface;
use hearth_sim::world::{ModelHandle, World};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, RngExt};

use crate::arm::{Arm, ArmTarget, LinearMove, MotionReport};
use crate::error::{SkillError, SkillResult, require_positive};
use crate::execution::Execution;
use crate::grasp::release;

/// Where to put the held object: a horizontal rectangle in the world.
///
/// ```
/// let t = hearth_skills::place::PlaceTarget { z: 0.75, min: [0.6, -0.3], max: [0.9, 0.3], support: None };
/// assert!(t.validate().is_ok());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PlaceTarget {
    /// Height of the surface, metres.
    pub z: f64,
    /// Corner with the smallest x and y.
    pub min: [f64; 2],
    /// Corner with the largest x and y.
    pub max: [f64; 2],
    /// The model the surface belongs to (the object may touch it).
    pub support: Option<ModelHandle>,
}

impl PlaceTarget {
    /// The top of `model`'s root collision shape: its bounding box's top face, shrunk by 2 cm
    /// (for tables and boxes; furniture with parts above its top, such as a counter's tap,
    /// should use [`PlaceTarget::from_surface`]).
    ///
    /// ```no_run
    /// # fn f(world: &hearth_sim::world::World, table: hearth_sim::world::ModelHandle) {
    /// let t = hearth_skills::place::PlaceTarget::on_top_of(world, table).unwrap();
    /// assert!(t.z > 0.5);
    /// # }
    /// ```
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a model without collision geometry.
    pub fn on_top_of(world: &World, model: ModelHandle) -> SkillResult<Self> {
        let m = world.model(model)?;
        let shape = m
            .link_shape(m.root())
            .ok_or_else(|| SkillError::BadInput(format!("`{}` has no collision shape", m.name())))?;
        let aabb = shape
            .shape
            .compute_aabb(&to_pose(&(world.base_pose(model)? * shape.origin)));
        Ok(Self {
            z: aabb.maxs.z as f64,
            min: [aabb.mins.x as f64 + 0.02, aabb.mins.y as f64 + 0.02],
            max: [aabb.maxs.x as f64 - 0.02, aabb.maxs.y as f64 - 0.02],
            support: Some(model),
        })
    }

    /// An asset surface of `model` (asset frame) in the world, as the bounding rectangle of its
    /// corners under the model's pose.
    ///
    /// ```no_run
    /// # fn f(world: &hearth_sim::world::World, counter: hearth_sim::world::ModelHandle) {
    /// use hearth_sim::assets::{Asset, Category};
    /// let asset = Asset::build(Category::Counter, 0, 1.0).unwrap();
    /// let t = hearth_skills::place::PlaceTarget::from_surface(world, counter, &asset.surfaces[0]).unwrap();
    /// assert!(t.validate().is_ok());
    /// # }
    /// ```
    ///
    /// # Errors
    /// [`SkillError::World`] for an unknown model.
    pub fn from_surface(world: &World, model: ModelHandle, surface: &Surface) -> SkillResult<Self> {
        let pose = world.base_pose(model)?;
        let corners = [
            [surface.min[0], surface.min[1]],
            [surface.min[0], surface.max[1]],
            [surface.max[0], surface.min[1]],
            [surface.max[0], surface.max[1]],
        ]
        .map(|[x, y]| pose * Point3::new(x, y, surface.z));
        let fold = |f: fn(f64, f64) -> f64, i: usize, init: f64| corners.iter().map(|c| c[i]).fold(init, f);
        Ok(Self {
            z: corners[0].z,
            min: [fold(f64::min, 0, f64::INFINITY), fold(f64::min, 1, f64::INFINITY)],
            max: [
                fold(f64::max, 0, f64::NEG_INFINITY),
                fold(f64::max, 1, f64::NEG_INFINITY),
            ],
            support: Some(model),
        })
    }

    /// Every free horizontal top face of `model`'s root collision parts of at least `min_area`
    /// square metres, shrunk by 2 cm: tops of tables and worktops, shelves, the floor of a
    /// sink's basin. A face with other parts of the model over most of it within 20 cm (a
    /// panel under a worktop, a shelf board under the next) is covered and left out.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a model without collision geometry or a bad area.
    ///
    /// ```no_run
    /// # fn f(world: &hearth_sim::world::World, counter: hearth_sim::world::ModelHandle) {
    /// let tops = hearth_skills::place::PlaceTarget::surfaces_of(world, counter, 0.02).unwrap();
    /// assert!(tops.iter().all(|t| t.validate().is_ok()));
    /// # }
    /// ```
    pub fn surfaces_of(world: &World, model: ModelHandle, min_area: f64) -> SkillResult<Vec<Self>> {
        require_positive("", &[("minimum area", min_area)])?;
        let m = world.model(model)?;
        let shape = m
            .link_shape(m.root())
            .ok_or_else(|| SkillError::BadInput(format!("`{}` has no collision shape", m.name())))?;
        let pose = world.base_pose(model)? * shape.origin;
        let parts: Vec<(Isometry3<f64>, hearth_kinematics::parry3d::shape::SharedShape)> =
            match shape.shape.as_compound() {
                Some(c) => c
                    .shapes()
                    .iter()
                    .map(|(p, s)| (pose * hearth_kinematics::from_pose(p), s.clone()))
                    .collect(),
                None => vec![(pose, shape.shape.clone())],
            };
        let boxes: Vec<_> = parts.iter().map(|(p, s)| s.compute_aabb(&to_pose(p))).collect();
        let mut out = Vec::new();
        for (i, (p, s)) in parts.iter().enumerate() {
            // Boxes standing upright (their z axis vertical) have a horizontal top face.
            if s.as_cuboid().is_none() || (p.rotation * Vector3::z()).z.abs() < 0.999 {
                continue;
            }
            let b = &boxes[i];
            let (x0, y0, x1, y1) = (b.mins.x as f64, b.mins.y as f64, b.maxs.x as f64, b.maxs.y as f64);
            let z = b.maxs.z as f64;
            let area = (x1 - x0) * (y1 - y0);
            if area < min_area {
                continue;
            }
            let covered: f64 = boxes
                .iter()
                .enumerate()
                .filter(|&(k, o)| k != i && (o.mins.z as f64) > z + 0.002 && (o.mins.z as f64) < z + 0.20)
                .map(|(_, o)| {
                    let w = (x1.min(o.maxs.x as f64) - x0.max(o.mins.x as f64)).max(0.0);
                    let h = (y1.min(o.maxs.y as f64) - y0.max(o.mins.y as f64)).max(0.0);
                    w * h
                })
                .sum();
            if covered > 0.5 * area || x1 - x0 < 0.05 || y1 - y0 < 0.05 {
                continue;
            }
            out.push(Self {
                z,
                min: [x0 + 0.02, y0 + 0.02],
                max: [x1 - 0.02, y1 - 0.02],
                support: Some(model),
            });
        }
        Ok(out)
    }

    /// Checks that the rectangle is finite and not empty.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] naming the problem.
    ///
    /// ```
    /// use hearth_skills::PlaceTarget;
    /// let shelf = PlaceTarget { z: 0.8, min: [1.0, -0.2], max: [1.4, 0.2], support: None };
    /// assert!(shelf.validate().is_ok());
    /// let empty = PlaceTarget { min: [1.5, -0.2], ..shelf.clone() };
    /// assert_eq!(empty.validate().unwrap_err().reason(), "bad_input");
    /// assert!(PlaceTarget { z: f64::NAN, ..shelf }.validate().is_err());
    /// ```
    pub fn validate(&self) -> SkillResult<()> {
        let finite = self.z.is_finite() && self.min.iter().chain(&self.max).all(|x| x.is_finite());
        if !finite || self.min[0] > self.max[0] || self.min[1] > self.max[1] {
            return Err(SkillError::BadInput(format!(
                "placement region {self:?} is empty or not finite"
            )));
        }
        Ok(())
    }
}

/// Placement parameters.
///
/// ```
/// let s = hearth_skills::place::PlaceSettings::default();
/// assert!(s.samples > 0 && s.clearance > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PlaceSettings {
    /// Gap between the object's bottom and the surface at release, metres.
    pub clearance: f64,
    /// Straight descent onto the placement, metres.
    pub approach: f64,
    /// Straight retreat upwards after release, metres.
    pub retreat: f64,
    /// Placements sampled at most.
    pub samples: usize,
    /// Free space kept around the object's footprint, metres.
    pub spacing: f32,
    /// Speed of the straight moves, m/s.
    pub speed: f64,
    /// How far (metres) the object may rest outside the region or off the surface height and
    /// still count as placed.
    pub tolerance: f64,
    /// Plan only, execute nothing.
    pub dry_run: bool,
}

impl Default for PlaceSettings {
    fn default() -> Self {
        Self {
            clearance: 0.01,
            approach: 0.10,
            retreat: 0.10,
            samples: 40,
            spacing: 0.01,
            speed: 0.08,
            tolerance: 0.02,
            dry_run: false,
        }
    }
}

/// What a placement did.
///
/// ```no_run
/// # fn f(r: hearth_skills::place::PlaceReport) {
/// let off = (r.rest.translation.vector - r.planned.translation.vector).norm();
/// assert!(off < 0.05);
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PlaceReport {
    /// The planned pose of the object at release.
    pub planned: Isometry3<f64>,
    /// Placements sampled before this one.
    pub rejected: usize,
    /// The motion above the placement.
    pub approach: MotionReport,
    /// Where the object came to rest (the planned pose for a dry run).
    pub rest: Isometry3<f64>,
}

/// Placements sampled before the whole region is in play: the `k`-th sample lies within
/// `k / CENTRED_SAMPLES` of the region's half-extent around its middle.
const CENTRED_SAMPLES: usize = 10;

/// Places the held object on `target` (see the [module docs](self)).
///
/// "Upright" is the orientation the object rested in before the grasp, turned about the
/// vertical by a sampled yaw; the tip goes where the hold recorded after the lift puts the
/// object so. Placements are sampled around the region's middle first and over the whole
/// region after 10 samples: an object held by its edge (a bowl by its
/// rim) can turn in the fingers while the arm moves, and lands with the most room around it.
///
/// # Errors
/// [`SkillError::NotHeld`] without a held object; [`SkillError::BadInput`] for a bad target or
/// settings; [`SkillError::Unreachable`] when no sampled placement is free and reachable;
/// [`SkillError::NotFinished`] when the object did not come to rest upright on the region; planning and
/// execution errors of [`Arm`].
///
/// ```no_run
/// # fn f(world: &mut hearth_sim::world::World, arm: &mut hearth_skills::Arm, table: hearth_sim::world::ModelHandle) {
/// use hearth_skills::place::{place, PlaceSettings, PlaceTarget};
/// use rand::SeedableRng;
/// let target = PlaceTarget::on_top_of(world, table).unwrap();
/// let r = place(world, arm, &target, &PlaceSettings::default(), hearth_skills::Execution::Physics,
///               &mut rand_pcg::Pcg64Mcg::seed_from_u64(0)).unwrap();
/// assert!(arm.held().is_none());
/// # }
/// ```
pub fn place<R: Rng + ?Sized>(
    world: &mut World,
    arm: &mut Arm,
    target: &PlaceTarget,
    settings: &PlaceSettings,
    execution: Execution,
    rng: &mut R,
) -> SkillResult<PlaceReport> {
    target.validate()?;
    check_settings(settings)?;
    let held = arm
        .held()
        .cloned()
        .ok_or_else(|| SkillError::NotHeld("placing needs a held object".into()))?;
    // The object's shape relative to its root.
    let shape_in_object = held.shape_in_object();
    let support_bodies = match target.support {
        Some(m) => world.model_bodies(m)?,
        None => Vec::new(),
    };
    let mut skip = support_bodies.clone();
    skip.extend_from_slice(&held.bodies);
    skip.extend(world.model_bodies(arm.robot())?);
    let view = world
        .obstacles_view(&[])?
        .excluding_bodies(&skip)
        .with_margin(settings.spacing);
    let mut check = arm.validity(world, &support_bodies, 0.0)?;
    let mut last = String::from("no placement sampled");
    let mut chosen = None;
    for i in 0..settings.samples {
        let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * held.rest;
        let upright = Isometry3::from_parts(Translation3::identity(), rotation);
        let aabb = held.shape.compute_aabb(&to_pose(&(upright * shape_in_object)));
        let (lo, hi) = (aabb.mins, aabb.maxs);
        let (x0, x1) = (target.min[0] - lo.x as f64, target.max[0] - hi.x as f64);
        let (y0, y1) = (target.min[1] - lo.y as f64, target.max[1] - hi.y as f64);
        if x0 > x1 || y0 > y1 {
            last = format!("`{}` does not fit on the placement region", held.name);
            continue;
        }
        // The middle of the region first, then wider: the most room around the object for
        // one that turned in the fingers on the way and lands off its planned footprint.
        let spread = ((i + 1) as f64 / CENTRED_SAMPLES as f64).min(1.0);
        let around = |lo: f64, hi: f64, u: f64| 0.5 * (lo + hi) + 0.5 * (hi - lo) * spread * u;
        let x = around(x0, x1, rng.random_range(-1.0..=1.0));
        let y = around(y0, y1, rng.random_range(-1.0..=1.0));
        let z = target.z + settings.clearance - lo.z as f64;
        let planned = Isometry3::from_parts(Translation3::new(x, y, z), rotation);
        if view.intersects(held.shape.as_ref(), &to_pose(&(planned * shape_in_object))) {
            last = format!("placement ({x:.2}, {y:.2}) overlaps something");
            continue;
        }
        let tip = planned * held.offset.inverse();
        if let Err(e) = arm.goal_configurations(world, &ArmTarget::Pose(tip), &mut check, rng) {
            last = e.to_string();
            continue;
        }
        let above = Isometry3::from_parts(
            Translation3::from(tip.translation.vector + Vector3::z() * settings.approach),
            tip.rotation,
        );
        match arm.plan(world, &ArmTarget::Pose(above), &[], rng) {
            Ok(plan) => {
                chosen = Some((i, planned, plan));
                break;
            }
            Err(e @ (SkillError::IkFailed(_) | SkillError::PlanningFailed(_) | SkillError::PlanningTimeout(_))) => {
                last = e.to_string()
            }
            Err(e) => return Err(e),
        }
    }
    let (rejected, planned, plan) = chosen.ok_or_else(|| {
        SkillError::Unreachable(format!(
            "no free, reachable placement for `{}` in {} samples: {last}",
            held.name, settings.samples
        ))
    })?;
    let mut report = PlaceReport {
        planned,
        rejected,
        approach: plan.report.clone(),
        rest: planned,
    };
    if settings.dry_run {
        return Ok(report);
    }
    report.approach = arm.execute(world, &plan, execution)?;
    let down = LinearMove {
        speed: settings.speed,
        force_limit: 30.0,
        ignore: support_bodies.clone(),
        ..LinearMove::new(-Vector3::z(), settings.approach)
    };
    arm.move_linear(world, &down, execution)?;
    release(world, arm)?;
    let up = LinearMove {
        speed: settings.speed,
        ignore: held.bodies.clone(),
        ..LinearMove::new(Vector3::z(), settings.retreat)
    };
    arm.move_linear(world, &up, execution)?;
    for _ in 0..15 {
        world.step();
    }
    report.rest = world.base_pose(held.object)?;
    // Placed: upright, on the surface, inside the region (the object may have swung in the
    // fingers on the way, so it need not be on the sampled spot).
    let rest = report.rest.translation.vector;
    let tilt = (report.rest.rotation * Vector3::z()).dot(&(planned.rotation * Vector3::z()));
    let bottom = held
        .shape
        .compute_aabb(&to_pose(&(report.rest * shape_in_object)))
        .mins
        .z as f64;
    let t = settings.tolerance;
    let inside = rest.x > target.min[0] - t
        && rest.x < target.max[0] + t
        && rest.y > target.min[1] - t
        && rest.y < target.max[1] + t;
    if tilt < 0.9 || (bottom - target.z).abs() > t || !inside {
        return Err(SkillError::NotFinished(format!(
            "`{}` came to rest at ({:.2}, {:.2}, {:.2}), bottom {bottom:.3} m (surface {:.3} m), tilt cos {tilt:.2}: not on the region",
            held.name, rest.x, rest.y, rest.z, target.z
        )));
    }
    Ok(report)
}

fn check_settings(s: &PlaceSettings) -> SkillResult<()> {
    require_positive(
        "place ",
        &[
            ("approach", s.approach),
            ("speed", s.speed),
            ("tolerance", s.tolerance),
            ("retreat", s.retreat),
        ],
    )?;
    if !s.clearance.is_finite() || s.clearance < 0.0 || !s.spacing.is_finite() || s.spacing < 0.0 || s.samples == 0 {
        return Err(SkillError::BadInput(format!("place settings out of range: {s:?}")));
    }
    Ok(())
}
