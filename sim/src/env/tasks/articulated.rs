//! The articulated-furniture tasks: `push_drawer` and `push_cabinet` (close the drawers, or the
//! doors, of one bottom cabinet) and `room_rearrangement` (close every drawer and door of the
//! furniture in one room). Reset opens the joints to random positions and releases their
//! controllers (they move freely, with their damping and friction); the robot starts in front
//! of the furniture, facing it.
//!
//! Only joints the Fetch can close are candidates: those whose handle (the centre of the
//! front-most part of the moving link, closed) lies within `handle_height` above the floor.
//! The default band, [0.1, 1.5] m, follows the Fetch's URDF: the shoulder-lift axis sits
//! 0.795 m above the floor with the torso down and 1.181 m with it up (base link 0.009 m up,
//! torso joint 0.377 m above it, lift 0–0.386 m, shoulder pan 0.349 m and lift 0.06 m above
//! that); the upper arm (shoulder lift to elbow) is 0.352 m, the rest to the gripper tip
//! 0.626 m. Pushing a front closed along its normal with the forearm and gripper level puts
//! the hand at most 0.352 × sin 1.221 (the shoulder lift's upward limit) = 0.331 m above the
//! raised shoulder: 1.51 m. Low fronts are pushed with the forearm tilted down; the whole arm
//! (0.978 m) at 45° down from the lowered shoulder reaches 0.795 − 0.69 = 0.10 m. Wall
//! cabinets, whose door handles hang at about 1.8 m above a counter, are out of reach; a
//! piece of furniture none of whose joints is in reach is no candidate, and a room without
//! one is never drawn. The band is a model of the reach, not an inverse-kinematics check.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Point3};
use rand::RngExt;

use super::clearance::{Placed, free_opening, overlaps, shape_pose};
use super::field::{cell_center, nearest_free};
use super::reaching::END_EFFECTOR;
use super::{
    BuildContext, Ending, Metrics, Progress, ResetContext, StepContext, failure, in_base_frame, in_planar_frame,
};
use crate::assets::Category;
use crate::env::config::TaskConfig;
use crate::env::error::{EnvError, EnvResult};
use crate::kinematics::RobotModel;
use crate::world::{JointCommand, ModelHandle, World};

/// `task_obs` entries: front of the most open target (x, y in the base frame), the direction
/// it faces (cos, sin of its yaw in the base frame), total opening, joints still open,
/// end-effector x, y, z in the base frame, forward speed, yaw rate.
pub(crate) const OBS_LEN: usize = 11;

/// One piece of furniture with joints to close.
#[derive(Clone, Debug)]
struct Target {
    name: String,
    room: Option<String>,
    handle: ModelHandle,
    /// Scene pose (the furniture is fixed).
    pose: Isometry3<f64>,
    /// Front face, x in the object frame.
    front: f64,
    /// (variable index, joint name, upper limit) of the joints to close (closed at 0).
    joints: Vec<(usize, String, f64)>,
    /// For each joint: the link it moves and the fraction of its range it opens freely
    /// (see [`clearance`](super::clearance)).
    swings: Vec<(usize, f64)>,
    /// The furniture's model and world base pose, for placing its moving links.
    model: RobotModel,
    base: Isometry3<f64>,
    /// Where the robot starts for this target (x, y, yaw), if it has floor in front.
    start: Option<[f64; 3]>,
}

/// Footprint radius of the Fetch (m).
const ROBOT_RADIUS: f64 = 0.32;

/// The traversable cell nearest to a point `reach + robot radius + 10 cm` out of the front
/// (within 1 m of it), facing the front.
fn start_for(maps: &crate::scene::SceneMaps, pose: &Isometry3<f64>, front: f64, reach: f64) -> Option<[f64; 3]> {
    let want = pose * Point3::new(front + reach + ROBOT_RADIUS + 0.1, 0.0, 0.0);
    let cell = nearest_free(maps, [want.x, want.y], 1.0)?;
    let p = cell_center(maps, cell);
    let f = pose * Point3::new(front, 0.0, 0.0);
    Some([p[0], p[1], (f.y - p[1]).atan2(f.x - p[0])])
}

/// The articulated task state of one episode.
#[derive(Clone, Debug)]
pub(crate) struct Articulated {
    config: TaskConfig,
    /// Every candidate target of the home.
    candidates: Vec<Target>,
    /// Groups of candidates one episode may draw (one cabinet, or one room's furniture).
    groups: Vec<Vec<usize>>,
    /// The current episode's targets (indices into `candidates`).
    active: Vec<usize>,
    /// Their names (contacts with them are not collisions).
    names: Vec<String>,
    /// Opening (position / range) of each active joint, in target order.
    openings: Vec<f64>,
    scratch: Vec<f64>,
    pub(crate) start: [f64; 3],
    /// The target the robot starts in front of.
    focus: usize,
    progress: Progress,
    pub(crate) metrics: Metrics,
}

/// Height above the floor of the handle on `link` (the link a joint moves): the centre of its
/// front-most visual part (along the furniture's +x, its front) in the pose the world holds
/// (closed at build time); the link's origin when it has no visual part.
fn handle_height(
    world: &World,
    handle: ModelHandle,
    model: &RobotModel,
    pose: &Isometry3<f64>,
    link: usize,
) -> EnvResult<f64> {
    let link = &model.links()[link];
    let at = world.link_pose(handle, &link.name)?;
    let front_most = link
        .visuals
        .iter()
        .map(|v| at * Point3::from(v.origin.translation.vector))
        .max_by(|a, b| {
            let x = |p: &Point3<f64>| pose.inverse_transform_point(p).x;
            x(a).total_cmp(&x(b))
        });
    Ok(front_most.map_or(at.translation.z, |p| p.z))
}

/// Which joints of a piece of furniture a task closes.
fn wanted_joints(task: &str, category: Category, joint: &str) -> bool {
    match task {
        "push_drawer" => category == Category::BottomCabinet && joint.starts_with("drawer_"),
        "push_cabinet" => category == Category::BottomCabinet && joint.starts_with("door_"),
        _ => {
            !matches!(category, Category::Door | Category::Window)
                && (joint.starts_with("drawer_") || joint.starts_with("door_") || joint.starts_with("oven_door"))
        }
    }
}

impl Articulated {
    pub(crate) fn new(config: TaskConfig, ctx: &BuildContext<'_>) -> EnvResult<Self> {
        let assets = ctx.home.assets()?;
        let mut candidates = Vec::new();
        for (object, asset) in ctx.home.objects.iter().zip(&assets) {
            let Some(handle) = ctx.loaded.object(&object.name) else {
                continue;
            };
            let model = ctx.world.model(handle)?;
            let pose = object.pose();
            let base = ctx.world.base_pose(handle)?;
            let view = ctx.world.obstacles_view(&[handle, ctx.robot])?;
            let [low, high] = config.handle_height;
            let mut joints: Vec<(usize, String, f64)> = Vec::new();
            let mut swings = Vec::new();
            for (v, n) in model.variable_names().iter().enumerate() {
                if !wanted_joints(&config.name, asset.category, n) || model.upper()[v] <= 0.0 {
                    continue;
                }
                let j = model
                    .joint_index(n)
                    .map_err(|e| EnvError::Task(format!("joint `{n}`: {e}")))?;
                let link = model.joints()[j].child;
                let h = handle_height(ctx.world, handle, model, &pose, link)?;
                if !(low..=high).contains(&h) {
                    continue;
                }
                let cap = free_opening(&view, model, &base, v, link);
                // A joint that cannot open past the tolerance cannot be left open.
                if cap > config.closed_tolerance {
                    joints.push((v, n.clone(), model.upper()[v]));
                    swings.push((link, cap));
                }
            }
            if joints.is_empty() {
                continue;
            }
            let depth = asset.aabb_max[0] - asset.aabb_min[0];
            let width = asset.aabb_max[1] - asset.aabb_min[1];
            let reach = (0.8 * depth).max(0.5 * width);
            candidates.push(Target {
                name: object.name.clone(),
                room: object.room.clone(),
                handle,
                start: start_for(ctx.maps, &pose, asset.aabb_max[0], reach),
                pose,
                front: asset.aabb_max[0],
                joints,
                swings,
                model: model.clone(),
                base,
            });
        }
        let [low, high] = config.handle_height;
        let what = match config.name.as_str() {
            "push_drawer" => format!("a bottom cabinet with drawers in reach (handles {low}–{high} m up)"),
            "push_cabinet" => format!("a bottom cabinet with doors in reach (handles {low}–{high} m up)"),
            _ => format!("articulated furniture in reach (handles {low}–{high} m up)"),
        };
        let groups: Vec<Vec<usize>> = if config.name == "room_rearrangement" {
            let mut rooms: Vec<&str> = candidates.iter().filter_map(|t| t.room.as_deref()).collect();
            rooms.sort_unstable();
            rooms.dedup();
            if let Some(room) = &config.room {
                if !rooms.contains(&room.as_str()) {
                    return Err(EnvError::Config {
                        key: "task.room".into(),
                        reason: format!("room `{room}` has no {what} (rooms with some: {})", rooms.join(", ")),
                    });
                }
                rooms.retain(|r| r == room);
            }
            rooms
                .iter()
                .map(|r| {
                    (0..candidates.len())
                        .filter(|&i| candidates[i].room.as_deref() == Some(r))
                        .collect::<Vec<_>>()
                })
                .filter(|g| g.iter().any(|&i| candidates[i].start.is_some()))
                .collect()
        } else if let Some(name) = &config.target_object {
            let i = candidates
                .iter()
                .position(|t| &t.name == name)
                .ok_or_else(|| EnvError::Config {
                    key: "task.target_object".into(),
                    reason: format!(
                        "`{name}` is not {what} of this home (candidates: {})",
                        candidates
                            .iter()
                            .map(|t| t.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })?;
            if candidates[i].start.is_none() {
                return Err(EnvError::Task(format!("no floor in front of `{name}` for the robot")));
            }
            vec![vec![i]]
        } else {
            (0..candidates.len())
                .filter(|&i| candidates[i].start.is_some())
                .map(|i| vec![i])
                .collect()
        };
        if groups.is_empty() {
            return Err(EnvError::Task(format!(
                "`{}`: the home has no {what} with floor in front of it",
                config.name
            )));
        }
        Ok(Self {
            config,
            candidates,
            groups,
            active: Vec::new(),
            names: Vec::new(),
            openings: Vec::new(),
            scratch: Vec::new(),
            start: [0.0; 3],
            focus: 0,
            progress: Progress::default(),
            metrics: Metrics::default(),
        })
    }

    /// Names of the current episode's furniture.
    pub(crate) fn target_names(&self) -> &[String] {
        &self.names
    }

    /// (object name, joint names) of the current episode's targets.
    pub(crate) fn targets(&self) -> Vec<(String, Vec<String>)> {
        self.active
            .iter()
            .map(|&i| {
                let t = &self.candidates[i];
                (t.name.clone(), t.joints.iter().map(|(_, n, _)| n.clone()).collect())
            })
            .collect()
    }

    /// The front of the target the robot starts at, on the floor.
    pub(crate) fn goal(&self) -> [f64; 3] {
        if self.candidates.is_empty() {
            return [0.0; 3];
        }
        let f = self.front_point(self.focus, 0.0);
        [f[0], f[1], 0.0]
    }

    /// A point `standoff` m out of target `i`'s front, world frame.
    fn front_point(&self, i: usize, standoff: f64) -> [f64; 2] {
        let t = &self.candidates[i];
        let p = t.pose * Point3::new(t.front + standoff, 0.0, 0.0);
        [p.x, p.y]
    }

    /// Draws the targets, opens their joints, and returns a start facing one of them.
    pub(crate) fn reset(&mut self, ctx: ResetContext<'_>) -> EnvResult<[f64; 3]> {
        let group = ctx.rng.random_range(0..self.groups.len());
        self.active = self.groups[group].clone();
        self.names = self.active.iter().map(|&i| self.candidates[i].name.clone()).collect();
        let [lo, hi] = self.config.open_range;
        // Opened links so far: a link that would overlap one is closed halfway, up to four
        // times, then left closed.
        let mut placed: Vec<Placed<'_>> = Vec::new();
        for &i in &self.active {
            let t = &self.candidates[i];
            let mut q = ctx.world.joint_positions(t.handle)?;
            let mut scratch = vec![0.0; t.model.dof()];
            let mut poses = t.model.pose_buffer();
            for ((v, _, upper), &(link, cap)) in t.joints.iter().zip(&t.swings) {
                let mut f = ctx.rng.random_range(lo..=hi).min(cap);
                let mut fits = false;
                for _ in 0..5 {
                    let Some(pose) = shape_pose(&t.model, &t.base, *v, f * upper, link, &mut scratch, &mut poses)
                    else {
                        fits = true;
                        break;
                    };
                    let me = Placed {
                        model: &t.model,
                        link,
                        pose,
                    };
                    if !overlaps(&me, &placed) {
                        placed.push(me);
                        fits = true;
                        break;
                    }
                    f /= 2.0;
                }
                q[*v] = if fits { f * upper } else { 0.0 };
            }
            ctx.world.reset_configuration(t.handle, &q)?;
            for (_, name, _) in &t.joints {
                ctx.world.set_joint_command(t.handle, name, JointCommand::Off)?;
            }
        }
        // In front of one of the targets that has floor in front of it (groups have one).
        let with_floor: Vec<usize> = self
            .active
            .iter()
            .copied()
            .filter(|&i| self.candidates[i].start.is_some())
            .collect();
        if with_floor.is_empty() {
            return Err(EnvError::Task(format!(
                "no floor in front of {} for the robot",
                self.names.join(", ")
            )));
        }
        self.focus = with_floor[ctx.rng.random_range(0..with_floor.len())];
        self.start = self.candidates[self.focus].start.unwrap_or_default();
        Ok(self.start)
    }

    /// Reads the openings and starts the potential.
    pub(crate) fn begin(&mut self, ctx: &StepContext<'_>) -> EnvResult<()> {
        let total = self.read_openings(ctx.world)?;
        self.metrics = Metrics {
            remaining: total,
            ..Metrics::default()
        };
        self.progress = Progress::start(super::xy_of(&ctx.base), total);
        Ok(())
    }

    /// Updates `openings` from the world; returns their sum.
    fn read_openings(&mut self, world: &World) -> EnvResult<f64> {
        self.openings.clear();
        for &i in &self.active {
            let t = &self.candidates[i];
            self.scratch.resize(world.model(t.handle)?.dof(), 0.0);
            world.joint_positions_into(t.handle, &mut self.scratch)?;
            for (v, _, upper) in &t.joints {
                self.openings.push((self.scratch[*v] / upper).max(0.0));
            }
        }
        Ok(self.openings.iter().sum())
    }

    /// Reward and ending of one step.
    pub(crate) fn step(&mut self, ctx: &StepContext<'_>) -> (f64, Option<Ending>) {
        let total = self.read_openings(ctx.world).unwrap_or(self.metrics.remaining);
        let mut reward = self.progress.step(&self.config, &mut self.metrics, ctx, total);
        let closed = self.openings.iter().all(|&o| o <= self.config.closed_tolerance);
        let ending = if closed {
            reward += self.config.success_reward;
            self.metrics.success = true;
            Some(Ending::Success)
        } else {
            failure(&self.config, &self.metrics, ctx.on_map)
        };
        (reward, ending)
    }

    /// The `task_obs` entries (see [`OBS_LEN`]).
    pub(crate) fn task_obs(&self, ctx: &StepContext<'_>, v: f64, omega: f64, out: &mut Vec<f32>) {
        // The target with the most opening left.
        let mut best = (f64::NEG_INFINITY, self.active.first().copied().unwrap_or(0));
        let mut k = 0;
        for &i in &self.active {
            let n = self.candidates[i].joints.len();
            let open: f64 = self.openings.get(k..k + n).map_or(0.0, |s| s.iter().sum());
            if open > best.0 {
                best = (open, i);
            }
            k += n;
        }
        let (front, facing) = if self.candidates.is_empty() {
            ([0.0; 2], 0.0)
        } else {
            let t = &self.candidates[best.1];
            let yaw = t.pose.rotation.euler_angles().2 - super::yaw_of(&ctx.base);
            (in_planar_frame(&ctx.base, self.front_point(best.1, 0.0)), yaw)
        };
        let ee = ctx
            .world
            .link_pose(ctx.robot, END_EFFECTOR)
            .map(|p| in_base_frame(&ctx.base, [p.translation.x, p.translation.y, p.translation.z]))
            .unwrap_or([0.0; 3]);
        let still_open = self
            .openings
            .iter()
            .filter(|&&o| o > self.config.closed_tolerance)
            .count();
        let facing = (facing + PI).rem_euclid(2.0 * PI) - PI;
        out.extend_from_slice(&[
            front[0] as f32,
            front[1] as f32,
            facing.cos() as f32,
            facing.sin() as f32,
            self.openings.iter().sum::<f64>() as f32,
            still_open as f32,
            ee[0] as f32,
            ee[1] as f32,
            ee[2] as f32,
            v as f32,
            omega as f32,
        ]);
    }
}
