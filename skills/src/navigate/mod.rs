//! The navigate skill: drive a mobile base to an `[x, y, yaw]` goal anywhere in a home.
//!
//! 1. **Global path** on the scene's traversability grid ([`SceneMaps::shortest_path`], the
//!    whole home). Starts and goals just off the traversable cells are snapped to the nearest
//!    one within 0.6 m.
//! 2. **Refinement** against the live world: every stretch of the grid path is checked with
//!    the robot's [`BaseFootprint`] (a cylinder, with a margin) through
//!    [`World::obstacles_view`]; stretches that touch something (a door leaf, a moved chair, a
//!    box that is not on the map) are replanned by SE(2) BiRRT in a box around them (with the
//!    smaller `min_margin` where the margin leaves no way through) and shortcut, and the whole
//!    path is then shortcut again.
//! 3. **Execution.** [`Execution::Physics`]: pure-pursuit tracking on the differential drive
//!    at the control rate, stopping and turning in place at sharp corners, with a final turn
//!    to the goal yaw; a base that makes no progress for `stall_time` or keeps touching
//!    something for a second without progress is stopped, backs off 10 cm where that is
//!    free, and replans from there (at most `max_replans` times). [`Execution::Kinematic`]:
//!    the base is teleported along the plan, densely, after every pose was checked.
//!
//! Failures: a non-finite goal or bad settings → [`SkillError::BadInput`]; a goal off the
//! map, in collision or with no path → [`SkillError::Unreachable`]; the SE(2) planner's
//! budget spent → [`SkillError::PlanningTimeout`]; still blocked after the replans →
//! [`SkillError::Blocked`]; not within tolerance by the time limit →
//! [`SkillError::NotFinished`]. Errors found before the base moves leave the world unchanged.
//!
//! Build the maps with a `robot_radius` a few centimetres larger than the footprint radius
//! plus the margin, so the grid path keeps clear of walls and refinement is only needed where
//! the map and the world differ.
//!
//! ```no_run
//! use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
//! use hearth_sim::world::{World, WorldConfig};
//! use hearth_skills::navigate::{NavigateSettings, navigate};
//! use rand::SeedableRng;
//!
//! let home = generate(&GenerateOptions { seed: 3, rooms: 3, ..Default::default() }).unwrap();
//! let maps = SceneMaps::build(&home, &MapOptions { robot_radius: 0.38, ..Default::default() }).unwrap();
//! let mut world = World::new(WorldConfig::default()).unwrap();
//! let fetch = world.load_scene(&home).unwrap().robot.unwrap();
//! world.settle(300);
//! let room = home.building.rooms[1].center();
//! let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
//! let report = navigate(&mut world, fetch, &maps, [room[0], room[1], 0.0], &NavigateSettings::default(), &mut rng)?;
//! println!("{:.2} m in {:.1} s, {} replans", report.distance, report.sim_time, report.replans);
//! # Ok::<(), hearth_skills::SkillError>(())
//! ```

mod footprint;
mod plan;
mod track;

use std::time::Instant;

use hearth_kinematics::wrap_angle;
use hearth_sim::scene::SceneMaps;
use hearth_sim::world::{ModelHandle, World};
use rand::Rng;

pub use footprint::{BaseFootprint, FootprintValidity};
pub use plan::NavPlan;

use crate::error::{SkillError, SkillResult, require_positive};
use crate::execution::Execution;
use track::{Outcome, Totals, planar_pose};

/// Settings of [`navigate`] / [`Navigator`].
///
/// ```
/// use hearth_skills::navigate::NavigateSettings;
/// let s = NavigateSettings::default();
/// assert_eq!((s.position_tolerance, s.yaw_tolerance), (0.1, 0.1));
/// assert!(s.validate().is_ok());
/// let bad = NavigateSettings { max_linear_speed: -1.0, ..s };
/// assert!(bad.validate().unwrap_err().to_string().contains("max_linear_speed"));
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct NavigateSettings {
    /// Drive with physics (default) or teleport.
    pub execution: Execution,
    /// The base's footprint; `None` takes [`BaseFootprint::for_builtin`] of the robot.
    pub footprint: Option<BaseFootprint>,
    /// Clearance the plan keeps from obstacles, metres.
    pub margin: f64,
    /// Smaller clearance allowed where `margin` leaves no way through (narrow doorways),
    /// metres (capped at `margin`).
    pub min_margin: f64,
    /// Largest final distance from the goal, metres.
    pub position_tolerance: f64,
    /// Largest final yaw error, radians.
    pub yaw_tolerance: f64,
    /// Forward speed limit, m/s.
    pub max_linear_speed: f64,
    /// Yaw-rate limit, rad/s.
    pub max_angular_speed: f64,
    /// Forward acceleration limit, m/s².
    pub linear_acceleration: f64,
    /// Yaw acceleration limit, rad/s².
    pub angular_acceleration: f64,
    /// Pure-pursuit look-ahead distance, metres.
    pub lookahead: f64,
    /// Spacing of footprint checks along motions (SE(2) distance: metres + 0.5 m/rad).
    pub check_resolution: f64,
    /// Iteration budget of each SE(2) BiRRT call (reproducible).
    pub plan_iterations: u64,
    /// Wall-clock cap of each SE(2) BiRRT call, seconds.
    pub plan_time: f64,
    /// Random shortcut attempts on the whole path.
    pub shortcut_attempts: usize,
    /// Replans allowed after being blocked.
    pub max_replans: usize,
    /// Seconds without progress (along the path or turning) that count as blocked.
    pub stall_time: f64,
    /// Simulated seconds allowed; `None` is 20 s + 4 × the path length / `max_linear_speed`.
    pub time_limit: Option<f64>,
    /// Bodies the robot carries (a held object, [`crate::arm::Held::bodies`]): no obstacles
    /// for the base and no blockage when they touch the robot. Not part of a config file.
    #[serde(skip)]
    pub carried: Vec<hearth_sim::world::BodyId>,
}

impl Default for NavigateSettings {
    fn default() -> Self {
        Self {
            execution: Execution::Physics,
            footprint: None,
            margin: 0.04,
            min_margin: 0.015,
            position_tolerance: 0.1,
            yaw_tolerance: 0.1,
            max_linear_speed: 0.4,
            max_angular_speed: 1.0,
            linear_acceleration: 0.6,
            angular_acceleration: 2.0,
            lookahead: 0.3,
            check_resolution: 0.03,
            plan_iterations: 20_000,
            plan_time: 5.0,
            shortcut_attempts: 300,
            max_replans: 3,
            stall_time: 4.0,
            time_limit: None,
            carried: Vec::new(),
        }
    }
}

impl NavigateSettings {
    /// Checks every number; [`SkillError::BadInput`] names the first bad one.
    ///
    /// ```
    /// use hearth_skills::navigate::NavigateSettings;
    /// assert!(NavigateSettings::default().validate().is_ok());
    /// let bad = NavigateSettings { max_linear_speed: 0.0, ..Default::default() };
    /// let err = bad.validate().unwrap_err();
    /// assert_eq!(err.reason(), "bad_input");
    /// assert!(err.to_string().contains("max_linear_speed"));
    /// ```
    pub fn validate(&self) -> SkillResult<()> {
        let positive = [
            ("position_tolerance", self.position_tolerance),
            ("yaw_tolerance", self.yaw_tolerance),
            ("max_linear_speed", self.max_linear_speed),
            ("max_angular_speed", self.max_angular_speed),
            ("linear_acceleration", self.linear_acceleration),
            ("angular_acceleration", self.angular_acceleration),
            ("lookahead", self.lookahead),
            ("check_resolution", self.check_resolution),
            ("plan_time", self.plan_time),
            ("stall_time", self.stall_time),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(SkillError::BadInput(format!(
                    "{name} is {v}; it must be positive and finite"
                )));
            }
        }
        if !(self.margin.is_finite() && (0.0..=1.0).contains(&self.margin)) {
            return Err(SkillError::BadInput(format!(
                "margin is {}; it must be in [0, 1] m",
                self.margin
            )));
        }
        if !(self.min_margin.is_finite() && (0.0..=1.0).contains(&self.min_margin)) {
            return Err(SkillError::BadInput(format!(
                "min_margin is {}; it must be in [0, 1] m",
                self.min_margin
            )));
        }
        if self.plan_iterations == 0 {
            return Err(SkillError::BadInput("plan_iterations is 0".into()));
        }
        if let Some(t) = self.time_limit
            && !(t.is_finite() && t > 0.0)
        {
            return Err(SkillError::BadInput(format!(
                "time_limit is {t}; it must be positive and finite"
            )));
        }
        if let Some(f) = &self.footprint {
            f.validate().map_err(SkillError::BadInput)?;
        }
        Ok(())
    }
}

/// What [`navigate`] did.
///
/// ```
/// let r = hearth_skills::navigate::NavigateReport::default();
/// assert_eq!(r.replans, 0);
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NavigateReport {
    /// How the plan was carried out.
    pub execution: Execution,
    /// The last plan executed.
    pub plan: NavPlan,
    /// Distance the base travelled in the plane, metres.
    pub distance: f64,
    /// Simulated time the execution took, seconds (0 for kinematic execution).
    pub sim_time: f64,
    /// Wall-clock time of the whole call (planning included), seconds.
    pub wall_time: f64,
    /// Control steps run (kinematic: poses set).
    pub steps: usize,
    /// Replans after being blocked.
    pub replans: usize,
    /// Grid-path stretches replanned in SE(2), over all plans.
    pub refined_segments: usize,
    /// Final distance from the goal, metres.
    pub position_error: f64,
    /// Final yaw error, radians.
    pub yaw_error: f64,
    /// Final base pose `[x, y, yaw]`.
    pub final_pose: [f64; 3],
}

/// The navigate skill with its settings; [`navigate`] is the one-call form.
///
/// ```no_run
/// # use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
/// # use hearth_sim::world::{World, WorldConfig};
/// use hearth_skills::Execution;
/// use hearth_skills::navigate::{NavigateSettings, Navigator};
/// use rand::SeedableRng;
/// # let home = generate(&GenerateOptions { seed: 3, rooms: 2, ..Default::default() }).unwrap();
/// # let maps = SceneMaps::build(&home, &MapOptions { robot_radius: 0.38, ..Default::default() }).unwrap();
/// # let mut world = World::new(WorldConfig::default()).unwrap();
/// # let fetch = world.load_scene(&home).unwrap().robot.unwrap();
/// let nav = Navigator::new(NavigateSettings { execution: Execution::Kinematic, ..Default::default() })?;
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
/// let goal = home.building.rooms[0].center();
/// let plan = nav.plan(&world, fetch, &maps, [goal[0], goal[1], 1.57], &mut rng)?;
/// println!("{} poses, {:.2} m", plan.poses.len(), plan.length);
/// let report = nav.navigate(&mut world, fetch, &maps, [goal[0], goal[1], 1.57], &mut rng)?;
/// assert!(report.position_error <= 0.1);
/// # Ok::<(), hearth_skills::SkillError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Navigator {
    settings: NavigateSettings,
}

impl Navigator {
    /// A navigator with checked settings.
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for bad settings.
    ///
    /// ```
    /// use hearth_skills::navigate::{NavigateSettings, Navigator};
    /// assert!(Navigator::new(NavigateSettings::default()).is_ok());
    /// let bad = NavigateSettings { lookahead: f64::NAN, ..Default::default() };
    /// assert_eq!(Navigator::new(bad).unwrap_err().reason(), "bad_input");
    /// ```
    pub fn new(settings: NavigateSettings) -> SkillResult<Self> {
        settings.validate()?;
        Ok(Self { settings })
    }

    /// The settings.
    ///
    /// ```
    /// # use hearth_skills::navigate::{NavigateSettings, Navigator};
    /// let nav = Navigator::new(NavigateSettings::default()).unwrap();
    /// assert_eq!(nav.settings().max_replans, 3);
    /// ```
    pub fn settings(&self) -> &NavigateSettings {
        &self.settings
    }

    fn footprint(&self, world: &World, robot: ModelHandle) -> SkillResult<BaseFootprint> {
        let name = world.model(robot)?.name();
        self.settings
            .footprint
            .or_else(|| BaseFootprint::for_builtin(name))
            .ok_or_else(|| {
                SkillError::BadInput(format!(
                    "no base footprint known for robot `{name}`; set NavigateSettings::footprint"
                ))
            })
    }

    fn check_goal(goal: [f64; 3]) -> SkillResult<[f64; 3]> {
        if goal.iter().any(|v| !v.is_finite()) {
            return Err(SkillError::BadInput(format!(
                "goal [{}, {}, {}] is not finite",
                goal[0], goal[1], goal[2]
            )));
        }
        Ok([goal[0], goal[1], wrap_angle(goal[2])])
    }

    /// Plans a path from the base's current pose to `goal` (`[x, y, yaw]`) without moving
    /// anything (see the [module docs](self) for the steps and errors).
    ///
    /// ```
    /// # use hearth_sim::assets::RoomType;
    /// # use hearth_sim::scene::{MapOptions, RobotPlacement, Room, SceneFile, SceneMaps, Wall};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// use hearth_skills::navigate::{NavigateSettings, Navigator};
    /// use rand::SeedableRng;
    /// # let mut scene = SceneFile::empty("one room");
    /// # let polygon = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]];
    /// # scene.building.rooms.push(Room { name: "office".into(), room_type: RoomType::Office, polygon });
    /// # scene.robot = Some(RobotPlacement { name: "turtlebot".into(), position: [1.0, 1.5, 0.0], yaw: 0.0 });
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let robot = world.load_scene(&scene).unwrap().robot.unwrap();
    /// # let maps = SceneMaps::build(&scene, &MapOptions { robot_radius: 0.25, ..Default::default() }).unwrap();
    /// // A turtlebot at (1, 1.5) in an empty 4 × 3 m room.
    /// let nav = Navigator::new(NavigateSettings::default())?;
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    /// let plan = nav.plan(&world, robot, &maps, [3.0, 1.5, 0.0], &mut rng)?;
    /// assert!(plan.length >= 2.0 - 1e-6 && plan.length < 2.5);
    /// assert!(nav.plan(&world, robot, &maps, [f64::NAN, 0.0, 0.0], &mut rng).is_err());
    /// # Ok::<(), hearth_skills::SkillError>(())
    /// ```
    pub fn plan<R: Rng + ?Sized>(
        &self,
        world: &World,
        robot: ModelHandle,
        maps: &SceneMaps,
        goal: [f64; 3],
        rng: &mut R,
    ) -> SkillResult<NavPlan> {
        let goal = Self::check_goal(goal)?;
        let footprint = self.footprint(world, robot)?;
        let start = planar_pose(world, robot)?;
        plan::plan_path(world, robot, maps, start, goal, &footprint, &self.settings, rng)
    }

    /// Backs the base straight up by `distance` metres where its footprint is free behind it,
    /// else drives it forward by that much where that is free, else leaves it (the recovery
    /// [`Navigator::navigate`] uses before a replan).
    ///
    /// # Errors
    /// [`SkillError::BadInput`] for a robot without a known footprint or a bad distance;
    /// [`SkillError::World`].
    ///
    /// ```no_run
    /// # fn f(world: &mut hearth_sim::world::World, robot: hearth_sim::world::ModelHandle) {
    /// use hearth_skills::navigate::{NavigateSettings, Navigator};
    /// let nav = Navigator::new(NavigateSettings::default()).unwrap();
    /// nav.back_off(world, robot, 0.1).unwrap();
    /// # }
    /// ```
    pub fn back_off(&self, world: &mut World, robot: ModelHandle, distance: f64) -> SkillResult<()> {
        require_positive("", &[("back-off distance", distance)])?;
        let footprint = self.footprint(world, robot)?;
        track::back_off(
            world,
            robot,
            &footprint,
            &self.settings,
            distance,
            &mut Totals::default(),
        )
    }

    /// Plans and executes: drives (or teleports) the base to `goal` (`[x, y, yaw]`).
    ///
    /// # Errors
    /// See the [module docs](self). Errors before the base moves leave the world unchanged;
    /// later ones leave the base where it stopped.
    ///
    /// ```
    /// # use hearth_sim::assets::RoomType;
    /// # use hearth_sim::scene::{MapOptions, RobotPlacement, Room, SceneFile, SceneMaps};
    /// # use hearth_sim::world::{World, WorldConfig};
    /// use hearth_skills::Execution;
    /// use hearth_skills::navigate::{NavigateSettings, Navigator};
    /// use rand::SeedableRng;
    /// # let mut scene = SceneFile::empty("one room");
    /// # let polygon = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]];
    /// # scene.building.rooms.push(Room { name: "office".into(), room_type: RoomType::Office, polygon });
    /// # scene.robot = Some(RobotPlacement { name: "turtlebot".into(), position: [1.0, 1.5, 0.0], yaw: 0.0 });
    /// # let mut world = World::new(WorldConfig::default()).unwrap();
    /// # let robot = world.load_scene(&scene).unwrap().robot.unwrap();
    /// # let maps = SceneMaps::build(&scene, &MapOptions { robot_radius: 0.25, ..Default::default() }).unwrap();
    /// // A turtlebot at (1, 1.5) in an empty 4 × 3 m room, moved kinematically (teleported).
    /// let nav = Navigator::new(NavigateSettings { execution: Execution::Kinematic, ..Default::default() })?;
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    /// let report = nav.navigate(&mut world, robot, &maps, [3.0, 1.5, 1.57], &mut rng)?;
    /// assert!(report.position_error <= nav.settings().position_tolerance);
    /// assert!((report.final_pose[0] - 3.0).abs() < 0.1);
    /// # Ok::<(), hearth_skills::SkillError>(())
    /// ```
    pub fn navigate<R: Rng + ?Sized>(
        &self,
        world: &mut World,
        robot: ModelHandle,
        maps: &SceneMaps,
        goal: [f64; 3],
        rng: &mut R,
    ) -> SkillResult<NavigateReport> {
        let clock = Instant::now();
        let s = &self.settings;
        let goal = Self::check_goal(goal)?;
        let footprint = self.footprint(world, robot)?;
        let start = planar_pose(world, robot)?;
        let mut plan = plan::plan_path(world, robot, maps, start, goal, &footprint, s, rng)?;
        let mut totals = Totals::default();
        let mut replans = 0;
        let mut refined = plan.refined_segments;
        let t0 = world.time();
        match s.execution {
            Execution::Kinematic => track::teleport(world, robot, &plan, &footprint, s, &mut totals)?,
            Execution::Physics => {
                // The only check left that could fail before moving: the base must have a drive.
                world.drive(robot, 0.0, 0.0)?;
                let limit = s.time_limit.unwrap_or(20.0 + 4.0 * plan.length / s.max_linear_speed);
                let deadline = t0 + limit;
                loop {
                    match track::track(world, robot, &plan, goal, &footprint, s, deadline, &mut totals)? {
                        Outcome::Reached => break,
                        Outcome::TimeUp => {
                            track::stop(world, robot, &mut totals)?;
                            let p = planar_pose(world, robot)?;
                            return Err(SkillError::NotFinished(format!(
                                "after {limit:.1} s the base is {:.2} m and {:.2} rad from the goal",
                                (p[0] - goal[0]).hypot(p[1] - goal[1]),
                                wrap_angle(goal[2] - p[2]).abs()
                            )));
                        }
                        Outcome::Blocked(why) => {
                            track::stop(world, robot, &mut totals)?;
                            if replans >= s.max_replans {
                                return Err(SkillError::Blocked(format!("{why} (after {replans} replans)")));
                            }
                            replans += 1;
                            track::back_off(world, robot, &footprint, s, 0.1, &mut totals)?;
                            let here = planar_pose(world, robot)?;
                            plan = plan::plan_path(world, robot, maps, here, goal, &footprint, s, rng)
                                .map_err(|e| SkillError::Blocked(format!("{why}; replanning failed: {e}")))?;
                            refined += plan.refined_segments;
                        }
                    }
                }
                world.drive(robot, 0.0, 0.0)?;
            }
        }
        let p = planar_pose(world, robot)?;
        Ok(NavigateReport {
            execution: s.execution,
            plan,
            distance: totals.distance,
            sim_time: world.time() - t0,
            wall_time: clock.elapsed().as_secs_f64(),
            steps: totals.steps,
            replans,
            refined_segments: refined,
            position_error: (p[0] - goal[0]).hypot(p[1] - goal[1]),
            yaw_error: wrap_angle(goal[2] - p[2]).abs(),
            final_pose: p,
        })
    }
}

/// Drives (or teleports) `robot` to `goal` = `[x, y, yaw]` with [`Navigator`]; see the
/// [module docs](self).
///
/// ```no_run
/// # use hearth_sim::scene::{GenerateOptions, MapOptions, SceneMaps, generate};
/// # use hearth_sim::world::{World, WorldConfig};
/// use hearth_skills::navigate::{NavigateSettings, navigate};
/// use rand::SeedableRng;
/// # let home = generate(&GenerateOptions { seed: 3, rooms: 2, ..Default::default() }).unwrap();
/// # let maps = SceneMaps::build(&home, &MapOptions { robot_radius: 0.38, ..Default::default() }).unwrap();
/// # let mut world = World::new(WorldConfig::default()).unwrap();
/// # let fetch = world.load_scene(&home).unwrap().robot.unwrap();
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
/// let err = navigate(&mut world, fetch, &maps, [f64::NAN, 0.0, 0.0], &NavigateSettings::default(), &mut rng)
///     .unwrap_err();
/// assert_eq!(err.reason(), "bad_input");
/// ```
pub fn navigate<R: Rng + ?Sized>(
    world: &mut World,
    robot: ModelHandle,
    maps: &SceneMaps,
    goal: [f64; 3],
    settings: &NavigateSettings,
    rng: &mut R,
) -> SkillResult<NavigateReport> {
    Navigator::new(settings.clone())?.navigate(world, robot, maps, goal, rng)
}
