//! Planning a base path: the shortest path on the traversability grid, checked against the
//! live world with the robot's footprint, SE(2) BiRRT where it is not free, then shortcutting.

use hearth_kinematics::wrap_angle;
use hearth_planning::motion::MotionValidator;
use hearth_planning::planner::{Budget, Goal, Path, PlanRequest, Planner};
use hearth_planning::shortcut::{ShortcutSettings, random as shortcut_random};
use hearth_planning::space::Se2Space;
use hearth_planning::validity::StateValidator;
use hearth_planning::{BiRrt, PlanError};
use hearth_sim::scene::{SceneError, SceneMaps};
use hearth_sim::world::{BodyId, ModelHandle, World, WorldObstacles};
use rand::Rng;

use super::NavigateSettings;
use super::footprint::{BaseFootprint, FootprintValidity};
use crate::error::{SkillError, SkillResult};

/// How far (metres) a start or goal off the grid's traversable cells may be snapped to the
/// nearest traversable cell (the live-world check decides whether the gap is really free).
const SNAP_RADIUS: f64 = 0.6;

/// Distance (metres) around a start in contact within which states count as free, so the
/// base can plan its way out of the contact (or out of the margin).
pub(crate) const FREE_NEAR: f64 = 0.12;

/// Room (metres) around a blocked stretch of the grid path that its SE(2) planner may use.
const LOCAL_PAD: f64 = 1.0;

/// A planned base path.
///
/// ```
/// let plan = hearth_skills::navigate::NavPlan::default();
/// assert!(plan.poses.is_empty() && plan.length == 0.0);
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NavPlan {
    /// `[x, y, yaw]` poses from the start to the goal; the robot drives straight between
    /// them (intermediate yaws are the heading of the next stretch).
    pub poses: Vec<[f64; 3]>,
    /// Waypoints of the grid path (after merging collinear cells).
    pub grid_waypoints: usize,
    /// Stretches of the grid path that collided with the live world and were replanned by
    /// SE(2) BiRRT.
    pub refined_segments: usize,
    /// Refined stretches that needed the minimum margin
    /// ([`NavigateSettings::min_margin`](super::NavigateSettings::min_margin)) to get through.
    pub narrow_segments: usize,
    /// Length of the path in the plane, metres.
    pub length: f64,
}

/// Bodies entirely below the footprint's clearance (floors, rugs, thresholds), the ground
/// and what the robot carries, sorted: nothing the base can bump into.
pub(crate) fn low_bodies(world: &World, footprint: &BaseFootprint, carried: &[BodyId]) -> Vec<BodyId> {
    let mut tops: Vec<((u32, u32), f64, BodyId)> = Vec::new();
    for (_, co) in world.colliders().iter() {
        if let Some(parent) = co.parent() {
            let top = f64::from(co.compute_aabb().maxs.z);
            tops.push((parent.into_raw_parts(), top, BodyId::from_handle(parent)));
        }
    }
    tops.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut low: Vec<BodyId> = Vec::new();
    for (k, t) in tops.iter().enumerate() {
        // The last entry of each body holds its highest top.
        let last = tops.get(k + 1).is_none_or(|n| n.0 != t.0);
        if last && t.1 <= footprint.z_min {
            low.push(t.2);
        }
    }
    low.extend(world.ground());
    low.extend_from_slice(carried);
    low.sort_by_key(|b| b.handle().into_raw_parts());
    low.dedup();
    low
}

/// The live world as the base planner sees it: everything but the robot and the
/// [`low_bodies`], with the margin applied.
pub(crate) fn live_view(
    world: &World,
    robot: ModelHandle,
    footprint: &BaseFootprint,
    margin: f64,
    carried: &[BodyId],
) -> SkillResult<WorldObstacles> {
    let low = low_bodies(world, footprint, carried);
    Ok(world
        .obstacles_view(&[robot])?
        .excluding_bodies(&low)
        .with_margin(margin as f32))
}

/// The nearest traversable cell centre within [`SNAP_RADIUS`] of `p`.
fn snap(maps: &SceneMaps, p: [f64; 2]) -> Option<[f64; 2]> {
    if maps.is_traversable(p) {
        return Some(p);
    }
    let r = (SNAP_RADIUS / maps.resolution).ceil() as i64;
    let fx = ((p[0] - maps.origin[0]) / maps.resolution).floor() as i64;
    let fy = ((p[1] - maps.origin[1]) / maps.resolution).floor() as i64;
    let mut best: Option<(f64, [f64; 2])> = None;
    for iy in (fy - r)..=(fy + r) {
        for ix in (fx - r)..=(fx + r) {
            if ix < 0 || iy < 0 || ix >= maps.width as i64 || iy >= maps.height as i64 {
                continue;
            }
            if !maps.traversable[iy as usize * maps.width + ix as usize] {
                continue;
            }
            let c = maps.cell_center(ix as usize, iy as usize);
            let d = (c[0] - p[0]).hypot(c[1] - p[1]);
            if d <= SNAP_RADIUS && best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, c));
            }
        }
    }
    best.map(|(_, c)| c)
}

fn map_error(e: SceneError, goal: [f64; 3]) -> SkillError {
    match e {
        SceneError::NoPath { .. } => SkillError::Unreachable(format!(
            "no free path on the traversability map to ({:.2}, {:.2})",
            goal[0], goal[1]
        )),
        other => SkillError::Unreachable(other.to_string()),
    }
}

/// Plans from `start` to `goal` (both `[x, y, yaw]`) through the live world.
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_path<R: Rng + ?Sized>(
    world: &World,
    robot: ModelHandle,
    maps: &SceneMaps,
    start: [f64; 3],
    goal: [f64; 3],
    footprint: &BaseFootprint,
    settings: &NavigateSettings,
    rng: &mut R,
) -> SkillResult<NavPlan> {
    let view = live_view(world, robot, footprint, settings.margin, &settings.carried)?;
    let mut validity = FootprintValidity::new(view.clone(), *footprint);
    // Where the margin leaves no way through (a narrow doorway), the plan may come as close
    // as the minimum margin.
    let mut narrow = FootprintValidity::new(
        view.with_margin(settings.min_margin.min(settings.margin) as f32),
        *footprint,
    );
    if let Some(what) = narrow.touching(&goal) {
        return Err(SkillError::Unreachable(format!(
            "the goal ({:.2}, {:.2}) puts the base in collision with `{what}`",
            goal[0], goal[1]
        )));
    }
    if validity.touching(&start).is_some() {
        // The base is where it is: let it plan its way out of a contact (or out of the margin).
        let near = Some(([start[0], start[1]], footprint.radius.min(FREE_NEAR)));
        validity.set_free_near(near);
        narrow.set_free_near(near);
    }
    let goal_xy = [goal[0], goal[1]];
    if maps.cell_of(goal_xy).is_none() {
        return Err(SkillError::Unreachable(format!(
            "the goal ({:.2}, {:.2}) is off the map",
            goal[0], goal[1]
        )));
    }
    let s_map = snap(maps, [start[0], start[1]]).ok_or_else(|| {
        SkillError::Unreachable(format!(
            "no traversable map cell within {SNAP_RADIUS} m of the start ({:.2}, {:.2})",
            start[0], start[1]
        ))
    })?;
    let g_map = snap(maps, goal_xy).ok_or_else(|| {
        SkillError::Unreachable(format!(
            "no traversable map cell within {SNAP_RADIUS} m of the goal ({:.2}, {:.2})",
            goal[0], goal[1]
        ))
    })?;
    let grid = maps.shortest_path(s_map, g_map).map_err(|e| map_error(e, goal))?;

    // The grid path as SE(2) states, yaws along the direction of travel.
    let mut xy: Vec<[f64; 2]> = Vec::with_capacity(grid.len() + 2);
    xy.push([start[0], start[1]]);
    for &p in grid.iter().chain(std::iter::once(&goal_xy)) {
        let last = xy[xy.len() - 1];
        if (p[0] - last[0]).hypot(p[1] - last[1]) > 1e-6 {
            xy.push(p);
        }
    }
    let mut states: Vec<Vec<f64>> = Vec::with_capacity(xy.len().max(2));
    states.push(start.to_vec());
    for k in 1..xy.len() {
        let yaw = if k + 1 < xy.len() {
            heading(xy[k], xy[k + 1])
        } else {
            goal[2]
        };
        states.push(vec![xy[k][0], xy[k][1], yaw]);
    }
    if states.len() == 1 {
        states.push(goal.to_vec());
    }

    let lo = maps.origin;
    let hi = [
        maps.origin[0] + maps.width as f64 * maps.resolution,
        maps.origin[1] + maps.height as f64 * maps.resolution,
    ];
    let space = Se2Space::new(lo, hi).map_err(|e| SkillError::BadInput(e.to_string()))?;
    for s in &states {
        if !(lo[0]..=hi[0]).contains(&s[0]) || !(lo[1]..=hi[1]).contains(&s[1]) {
            return Err(SkillError::Unreachable(format!(
                "({:.2}, {:.2}) is off the map",
                s[0], s[1]
            )));
        }
    }
    let mut motion = MotionValidator::new(space.clone(), settings.check_resolution);
    let mut out: Vec<Vec<f64>> = vec![states[0].clone()];
    let mut refined = 0;
    let mut narrow_segments = 0;
    let mut i = 0;
    let n = states.len();
    while i + 1 < n {
        if validity.is_valid(&states[i + 1]) && motion.check_motion(&mut validity, &states[i], &states[i + 1]) {
            out.push(states[i + 1].clone());
            i += 1;
            continue;
        }
        // The search ends at the goal at the latest (it is valid at the minimum margin).
        let mut j = i + 1;
        while j + 1 < n && !validity.is_valid(&states[j]) {
            j += 1;
        }
        let mut a = [f64::INFINITY; 2];
        let mut b = [f64::NEG_INFINITY; 2];
        for s in &states[i..=j] {
            for k in 0..2 {
                a[k] = a[k].min(s[k] - LOCAL_PAD);
                b[k] = b[k].max(s[k] + LOCAL_PAD);
            }
        }
        let local = Se2Space::new([a[0].max(lo[0]), a[1].max(lo[1])], [b[0].min(hi[0]), b[1].min(hi[1])])
            .map_err(|e| SkillError::BadInput(e.to_string()))?;
        let mut local_motion = MotionValidator::new(local, settings.check_resolution);
        let request = PlanRequest::new(states[i].clone(), Goal::Config(states[j].clone()));
        let budget = Budget::iterations(settings.plan_iterations).with_time(settings.plan_time);
        let mut planner = BiRrt::with_range(Some(0.2));
        let local_shortcut = ShortcutSettings {
            attempts: settings.shortcut_attempts,
            time_limit: None,
            fine_resolution: None,
            verify_resolution: None,
        };
        // Each stretch is shortcut with the validator it was planned with, so a narrow
        // passage comes out straight too (the whole-path pass below keeps the full margin).
        let solution = match planner.plan(&mut local_motion, &mut validity, &request, &budget, rng) {
            Ok(found) => Ok(shortcut_random(&mut local_motion, &mut validity, &found.path, &local_shortcut, rng).0),
            Err(_) => {
                narrow_segments += 1;
                planner
                    .plan(&mut local_motion, &mut narrow, &request, &budget, rng)
                    .map(|found| shortcut_random(&mut local_motion, &mut narrow, &found.path, &local_shortcut, rng).0)
            }
        };
        let solution = solution.map_err(|e| match e {
            PlanError::Timeout { .. } => SkillError::PlanningTimeout(format!(
                "no SE(2) path around the obstacles between ({:.2}, {:.2}) and ({:.2}, {:.2}): {e}",
                states[i][0], states[i][1], states[j][0], states[j][1]
            )),
            other => SkillError::PlanningFailed(other.to_string()),
        })?;
        out.extend(solution.states.into_iter().skip(1));
        refined += 1;
        i = j;
    }

    let shortcut = ShortcutSettings {
        attempts: settings.shortcut_attempts,
        time_limit: None,
        fine_resolution: None,
        verify_resolution: None,
    };
    let (path, _) = shortcut_random(&mut motion, &mut validity, &Path { states: out }, &shortcut, rng);
    let mut poses: Vec<[f64; 3]> = Vec::with_capacity(path.states.len());
    for s in &path.states {
        let p = [s[0], s[1], s[2]];
        // Drop repeated points (a shortcut can leave two equal states).
        if poses
            .last()
            .is_none_or(|q: &[f64; 3]| (q[0] - p[0]).hypot(q[1] - p[1]) > 1e-6)
        {
            poses.push(p);
        }
    }
    poses[0] = start;
    if poses.len() == 1 {
        poses.push(goal);
    }
    let last = poses.len() - 1;
    poses[last] = goal;
    for k in 1..last {
        poses[k][2] = heading([poses[k][0], poses[k][1]], [poses[k + 1][0], poses[k + 1][1]]);
    }
    let length = poses
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    Ok(NavPlan {
        poses,
        grid_waypoints: grid.len(),
        refined_segments: refined,
        narrow_segments,
        length,
    })
}

/// Direction from `a` to `b`.
pub(crate) fn heading(a: [f64; 2], b: [f64; 2]) -> f64 {
    wrap_angle((b[1] - a[1]).atan2(b[0] - a[0]))
}
