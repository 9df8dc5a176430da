//! Executing a [`NavPlan`]: pure-pursuit tracking on a differential-drive base at the control
//! rate (stopping and turning in place at sharp corners, a final turn to the goal yaw), with
//! stall and contact detection; or kinematic teleporting along the plan.

use std::fmt::Write as _;

use hearth_kinematics::wrap_angle;
use hearth_planning::obstacles::Obstacles;
use hearth_planning::validity::StateValidator;
use hearth_sim::world::{ModelHandle, World};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use super::NavigateSettings;
use super::footprint::{BaseFootprint, FootprintValidity};
use super::plan::{FREE_NEAR, NavPlan, heading, live_view, low_bodies};
use crate::error::{SkillError, SkillResult};

/// Turns sharper than this (rad) make the tracker stop at the corner and turn in place where
/// the corner is close to an obstacle, so it cuts such corners by a few millimetres at most.
const SHARP_TURN: f64 = 0.1;
/// Clearance (m) at a corner above which pure pursuit may cut it (turns up to
/// [`OPEN_TURN`]).
const CUT_CLEARANCE: f64 = 0.15;
/// Turns sharper than this (rad) always stop at the corner.
const OPEN_TURN: f64 = 0.6;
/// Heading error (rad) to which the base turns in place at a corner before driving on.
const ALIGNED: f64 = 0.05;
/// Heading error (rad) above which the base turns in place instead of driving.
const TURN_IN_PLACE: f64 = 0.5;
/// Distance (m) at which an intermediate corner counts as reached.
const CORNER_CAPTURE: f64 = 0.02;
/// Proportional gain of in-place turns (1/s).
const TURN_GAIN: f64 = 2.0;
/// Slowest forward speed while following (m/s), so the last centimetres do not take forever.
const MIN_SPEED: f64 = 0.04;
/// Control steps between contact checks (the contact list allocates).
const CONTACT_EVERY: usize = 5;
/// Contact force (N) that counts as touching something.
const TOUCH_FORCE: f64 = 2.0;
/// How long (s) a touch may last before the base counts as blocked (when it is also not
/// getting on: [`TOUCH_STALL`]).
const TOUCH_TIME: f64 = 1.0;
/// Seconds without progress that, with a lasting touch, count as blocked.
const TOUCH_STALL: f64 = 0.5;

/// The base pose in the plane: `[x, y, yaw]`.
pub(crate) fn planar_pose(world: &World, robot: ModelHandle) -> SkillResult<[f64; 3]> {
    let p = world.base_pose(robot)?;
    Ok([p.translation.x, p.translation.y, p.rotation.euler_angles().2])
}

/// How one tracking run ended.
pub(crate) enum Outcome {
    /// Within tolerance of the goal, at rest.
    Reached,
    /// No progress or a lasting contact (what happened).
    Blocked(String),
    /// The time limit passed.
    TimeUp,
}

/// Running totals of an execution.
#[derive(Default)]
pub(crate) struct Totals {
    pub(crate) distance: f64,
    pub(crate) steps: usize,
}

/// Where along the plan the robot is and what it aims for.
struct Follower<'a> {
    poses: &'a [[f64; 3]],
    /// Arc length at each vertex.
    cum: Vec<f64>,
    /// Vertices the base must stop at (sharp corners and the goal).
    stop: Vec<bool>,
    seg: usize,
    stop_idx: usize,
}

impl<'a> Follower<'a> {
    fn new<O: Obstacles>(plan: &'a NavPlan, clear: &FootprintValidity<O>) -> Self {
        let poses = &plan.poses[..];
        let n = poses.len();
        let mut cum = Vec::with_capacity(n);
        let mut acc = 0.0;
        cum.push(0.0);
        for w in poses.windows(2) {
            acc += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            cum.push(acc);
        }
        let mut stop = vec![false; n];
        stop[n - 1] = true;
        for k in 1..n - 1 {
            let a = heading(xy(&poses[k - 1]), xy(&poses[k]));
            let b = heading(xy(&poses[k]), xy(&poses[k + 1]));
            let turn = wrap_angle(b - a).abs();
            stop[k] =
                turn > OPEN_TURN || (turn > SHARP_TURN && clear.clearance(&poses[k], CUT_CLEARANCE) < CUT_CLEARANCE);
        }
        let mut f = Self {
            poses,
            cum,
            stop,
            seg: 0,
            stop_idx: 0,
        };
        f.stop_idx = f.next_stop(0);
        f
    }

    fn last(&self) -> usize {
        self.poses.len() - 1
    }

    fn next_stop(&self, after: usize) -> usize {
        (after + 1..self.poses.len())
            .find(|&k| self.stop[k])
            .unwrap_or(self.last())
    }

    /// Projects `p` on the path (searching forward from the current segment) and returns the
    /// arc length there.
    fn project(&mut self, p: [f64; 2]) -> f64 {
        let last_seg = self.last().saturating_sub(1);
        let end = (self.seg + 3)
            .min(last_seg)
            .min(self.stop_idx.saturating_sub(1).max(self.seg));
        let mut best = (f64::INFINITY, self.seg, 0.0);
        for k in self.seg..=end {
            let (a, b) = (xy(&self.poses[k]), xy(&self.poses[k + 1]));
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = (a[0] + t * dx - p[0]).hypot(a[1] + t * dy - p[1]);
            if d < best.0 - 1e-9 {
                best = (d, k, t);
            }
        }
        self.seg = best.1;
        self.cum[best.1] + best.2 * (self.cum[best.1 + 1] - self.cum[best.1])
    }

    /// The point at arc length `s`.
    fn point_at(&self, s: f64) -> [f64; 2] {
        let k = self
            .cum
            .partition_point(|&c| c <= s)
            .saturating_sub(1)
            .min(self.last() - 1);
        let len = self.cum[k + 1] - self.cum[k];
        let t = if len > 0.0 {
            ((s - self.cum[k]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (xy(&self.poses[k]), xy(&self.poses[k + 1]));
        [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
    }
}

fn xy(p: &[f64; 3]) -> [f64; 2] {
    [p[0], p[1]]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Forward speed and yaw rate scaled together so neither exceeds its limit nor a wheel its
/// speed limit.
fn limit(v: f64, w: f64, s: &NavigateSettings) -> (f64, f64) {
    let mut k: f64 = 1.0;
    if v.abs() > s.max_linear_speed {
        k = k.min(s.max_linear_speed / v.abs());
    }
    if w.abs() > s.max_angular_speed {
        k = k.min(s.max_angular_speed / w.abs());
    }
    (v * k, w * k)
}

/// Yaw rate of an in-place turn by `error` radians: proportional, at least 0.15 rad/s.
fn turn_rate(error: f64, s: &NavigateSettings) -> f64 {
    let w = (TURN_GAIN * error).clamp(-s.max_angular_speed, s.max_angular_speed);
    if w.abs() < 0.15 {
        0.15f64.min(s.max_angular_speed) * w.signum()
    } else {
        w
    }
}

/// Drives along `plan` until the goal is reached within tolerance, the base is blocked, or
/// the world's clock passes `deadline`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn track(
    world: &mut World,
    robot: ModelHandle,
    plan: &NavPlan,
    goal: [f64; 3],
    footprint: &BaseFootprint,
    s: &NavigateSettings,
    deadline: f64,
    totals: &mut Totals,
) -> SkillResult<Outcome> {
    let dt = world.config().control_dt();
    let clear = FootprintValidity::new(live_view(world, robot, footprint, 0.0, &s.carried)?, *footprint);
    let mut f = Follower::new(plan, &clear);
    let goal_xy = xy(&goal);
    let (mut v_cmd, mut w_cmd) = (0.0, 0.0);
    let mut final_turn = false;
    let mut best_s = 0.0;
    let mut stall = 0.0;
    let mut touch = 0.0;
    let mut touched = String::new();
    let mut pose = planar_pose(world, robot)?;
    let mut yaw_ref = pose[2];
    let mut settled_steps = 0;
    // Turning in place onto the next stretch (at the start and after each corner).
    let mut aligning = true;
    // What the base stands on is no obstacle.
    let support = low_bodies(world, footprint, &s.carried);
    let key = |b: &hearth_sim::world::BodyId| b.handle().into_raw_parts();
    loop {
        if world.time() > deadline {
            return Ok(Outcome::TimeUp);
        }
        let p = xy(&pose);
        let s_proj = f.project(p);
        // Corners reached (or passed) hand over to the next stretch.
        while f.stop_idx < f.last() && (dist(p, xy(&f.poses[f.stop_idx])) < CORNER_CAPTURE || f.seg >= f.stop_idx) {
            f.seg = f.seg.max(f.stop_idx);
            f.stop_idx = f.next_stop(f.stop_idx);
            aligning = true;
        }
        let goal_dist = dist(p, goal_xy);
        let on_last = f.stop_idx == f.last();
        if on_last && goal_dist < 0.4 * s.position_tolerance {
            final_turn = true;
        } else if goal_dist > 0.8 * s.position_tolerance {
            final_turn = false;
            settled_steps = 0;
        }

        let (v_t, w_t) = if final_turn {
            let e = wrap_angle(goal[2] - pose[2]);
            if e.abs() < 0.4 * s.yaw_tolerance {
                (0.0, 0.0)
            } else {
                (0.0, turn_rate(e, s))
            }
        } else {
            let vertex = xy(&f.poses[f.stop_idx]);
            let target = f.point_at((s_proj + s.lookahead).min(f.cum[f.stop_idx]));
            let mut d_target = dist(p, target);
            let aim = if d_target < 1e-3 {
                d_target = dist(p, vertex).max(1e-3);
                vertex
            } else {
                target
            };
            let alpha = wrap_angle(heading(p, aim) - pose[2]);
            if aligning && alpha.abs() < ALIGNED {
                aligning = false;
            }
            if alpha.abs() > TURN_IN_PLACE || aligning {
                (0.0, turn_rate(alpha, s))
            } else {
                let d_stop = dist(p, vertex);
                let brake = (2.0 * 0.8 * s.linear_acceleration * d_stop).sqrt();
                let v = s.max_linear_speed.min(brake).max(MIN_SPEED);
                let curvature = 2.0 * alpha.sin() / d_target.max(0.05);
                limit(v, v * curvature, s)
            }
        };
        let (av, aw) = (s.linear_acceleration * dt, s.angular_acceleration * dt);
        v_cmd += (v_t - v_cmd).clamp(-av, av);
        w_cmd += (w_t - w_cmd).clamp(-aw, aw);
        world.drive(robot, v_cmd, w_cmd)?;
        world.step();
        totals.steps += 1;
        let next = planar_pose(world, robot)?;
        totals.distance += dist(xy(&next), p);
        pose = next;

        if final_turn && v_t == 0.0 && w_t == 0.0 {
            let twist = world.base_twist(robot)?;
            let still = twist.linear.xy().norm() < 0.01 && twist.angular.z.abs() < 0.02;
            settled_steps = if still { settled_steps + 1 } else { 0 };
            let e_pos = dist(xy(&pose), goal_xy);
            let e_yaw = wrap_angle(goal[2] - pose[2]).abs();
            if settled_steps >= 3 && e_pos <= s.position_tolerance && e_yaw <= s.yaw_tolerance {
                return Ok(Outcome::Reached);
            }
        }

        // Progress: along the path, or turning.
        if s_proj > best_s + 0.05 {
            best_s = s_proj;
            stall = 0.0;
        } else if wrap_angle(pose[2] - yaw_ref).abs() > 0.2 {
            yaw_ref = pose[2];
            stall = 0.0;
        } else if !(final_turn && w_t == 0.0 && v_t == 0.0) {
            stall += dt;
        }
        if stall > s.stall_time {
            return Ok(Outcome::Blocked(format!(
                "no progress for {:.1} s at ({:.2}, {:.2})",
                s.stall_time, pose[0], pose[1]
            )));
        }
        if totals.steps.is_multiple_of(CONTACT_EVERY) {
            let mut hit = false;
            world.for_each_contact(robot, |c| {
                if !hit && c.force.norm() > TOUCH_FORCE && support.binary_search_by_key(&key(&c.other), key).is_err() {
                    hit = true;
                    touched.clear();
                    let _ = write!(touched, "`{}` touches `{}`", c.link, c.other_name);
                }
            })?;
            if hit {
                touch += CONTACT_EVERY as f64 * dt;
            } else {
                touch = 0.0;
            }
            // Grazing something while still getting on is no blockage.
            if touch > TOUCH_TIME && stall > TOUCH_STALL {
                return Ok(Outcome::Blocked(format!(
                    "{touched} for {:.1} s at ({:.2}, {:.2})",
                    touch, pose[0], pose[1]
                )));
            }
        }
    }
}

/// Recovery before a replan: backs the base straight up by `distance` metres (at most 2 s)
/// when the footprint is free there, else drives it forward by that much when that is free;
/// does nothing when neither is. A base snagged while turning in place (a rug edge under it,
/// a corner at its side) usually turns again from a few centimetres away.
pub(crate) fn back_off(
    world: &mut World,
    robot: ModelHandle,
    footprint: &BaseFootprint,
    s: &NavigateSettings,
    distance: f64,
    totals: &mut Totals,
) -> SkillResult<()> {
    let view = live_view(world, robot, footprint, 0.0, &s.carried)?;
    let mut check = FootprintValidity::new(view, *footprint);
    let start = planar_pose(world, robot)?;
    let (sin, cos) = start[2].sin_cos();
    // The base may touch something where it stands: the first centimetres may too.
    let free = |check: &mut FootprintValidity<_>, sign: f64| {
        (3..=5).all(|k| {
            let d = sign * distance * k as f64 / 5.0;
            check.is_valid(&[start[0] + d * cos, start[1] + d * sin, start[2]])
        })
    };
    let sign = if free(&mut check, -1.0) {
        -1.0
    } else if free(&mut check, 1.0) {
        1.0
    } else {
        return Ok(());
    };
    let speed = 0.15f64.min(s.max_linear_speed);
    let dt = world.config().control_dt();
    let max = (2.0 / dt).ceil() as usize;
    world.drive(robot, sign * speed, 0.0)?;
    let mut before = start;
    for _ in 0..max {
        world.step();
        totals.steps += 1;
        let now = planar_pose(world, robot)?;
        totals.distance += dist(xy(&now), xy(&before));
        before = now;
        if dist(xy(&now), xy(&start)) >= distance {
            break;
        }
    }
    stop(world, robot, totals)
}

/// Commands zero speed and steps until the base rests (at most 2 s).
pub(crate) fn stop(world: &mut World, robot: ModelHandle, totals: &mut Totals) -> SkillResult<()> {
    world.drive(robot, 0.0, 0.0)?;
    let max = (2.0 / world.config().control_dt()).ceil() as usize;
    let mut before = planar_pose(world, robot)?;
    for _ in 0..max {
        world.step();
        totals.steps += 1;
        let now = planar_pose(world, robot)?;
        totals.distance += dist(xy(&now), xy(&before));
        before = now;
        let t = world.base_twist(robot)?;
        if t.linear.xy().norm() < 0.005 && t.angular.z.abs() < 0.01 {
            break;
        }
    }
    Ok(())
}

/// The dense poses of a kinematic execution: turn in place to each stretch's heading, then
/// move along it, in steps of at most `step` metres (or 0.05 rad); ends at the goal pose.
fn dense_poses(plan: &NavPlan, step: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    let turn = |out: &mut Vec<[f64; 3]>, at: [f64; 2], from: f64, to: f64| {
        let d = wrap_angle(to - from);
        let n = (d.abs() / 0.05).ceil() as usize;
        for k in 1..=n {
            out.push([at[0], at[1], wrap_angle(from + d * k as f64 / n as f64)]);
        }
    };
    let mut yaw = plan.poses[0][2];
    for w in plan.poses.windows(2) {
        let (a, b) = (xy(&w[0]), xy(&w[1]));
        let len = dist(a, b);
        if len < 1e-6 {
            continue;
        }
        let h = heading(a, b);
        turn(&mut out, a, yaw, h);
        yaw = h;
        let n = (len / step).ceil() as usize;
        for k in 1..=n {
            let t = k as f64 / n as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), h]);
        }
    }
    let goal = plan.poses[plan.poses.len() - 1];
    turn(&mut out, xy(&goal), yaw, goal[2]);
    out.push(goal);
    out
}

/// Teleports the base along `plan` ([`dense_poses`] at `check_resolution`), after checking
/// the footprint at every pose against the live world (without margin), so a failure moves
/// nothing. The world is not stepped.
pub(crate) fn teleport(
    world: &mut World,
    robot: ModelHandle,
    plan: &NavPlan,
    footprint: &BaseFootprint,
    s: &NavigateSettings,
    totals: &mut Totals,
) -> SkillResult<()> {
    let view = live_view(world, robot, footprint, 0.0, &s.carried)?;
    let mut validity = FootprintValidity::new(view, *footprint);
    let start = plan.poses[0];
    // The base may start touching something; it leaves from where it stands.
    if validity.touching(&start).is_some() {
        validity.set_free_near(Some((xy(&start), footprint.radius.min(FREE_NEAR))));
    }
    let poses = dense_poses(plan, s.check_resolution.max(1e-3));
    if let Some(q) = poses.iter().find(|q| !validity.is_valid(&q[..])) {
        let what = validity.touching(q).unwrap_or_default();
        return Err(SkillError::Blocked(format!(
            "the base would touch `{what}` at ({:.2}, {:.2})",
            q[0], q[1]
        )));
    }
    let z = world.base_pose(robot)?.translation.z;
    // Bases without a differential drive have no wheel command to clear.
    let _ = world.drive(robot, 0.0, 0.0);
    for q in &poses {
        let iso = Isometry3::from_parts(
            Translation3::new(q[0], q[1], z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, q[2]),
        );
        world.place(robot, &iso)?;
        totals.steps += 1;
    }
    totals.distance += plan.length;
    Ok(())
}
