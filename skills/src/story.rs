//! The scripted mobile-manipulation story: in a generated home, the Fetch drives to the
//! kitchen, pulls a drawer of a bottom cabinet open, drives to the sink counter, picks up the
//! bowl standing on the worktop beside the sink and puts it into the sink's basin.
//!
//! [`run_story`] generates the home ([`generate`]) and runs the stages in order; the first
//! stage that fails ends the story, and the [`StoryReport`] names it with the
//! [`SkillError::reason`] and message. Each stage is timed (simulated and wall-clock), the
//! robot's head camera can write an RGB image after each stage, and the base pose and joint
//! positions are sampled after every skill call (the trajectory, written as JSON).
//!
//! Set-up (part of the scenario, done on the scene before it is loaded): the bottom cabinet
//! with drawers nearest the sink counter is the one opened (its highest drawer), and a bowl
//! (the library's small one, 14 cm across: wider than the Fetch's 94 mm gripper opening, so
//! it is taken by its rim) is stood on the worktop next to the sink, the worktop cleared of
//! the generator's small objects; the kitchen's dining table and chairs are cleared away (they
//! often stand where the robot has to stand). A home without a kitchen counter or without a
//! cabinet with drawers in its kitchen fails the `setup` stage.
//!
//! ```no_run
//! use hearth_skills::story::{StoryOptions, run_story};
//! let report = run_story(&StoryOptions { seed: 1, ..Default::default() });
//! for s in &report.stages {
//!     println!("{:<20} {:>5.1} s  {}", s.name, s.wall_time, s.detail);
//! }
//! if let Some(f) = &report.failure {
//!     println!("failed at {}: {} ({})", f.stage, f.reason, f.message);
//! }
//! ```

use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::time::Instant;

use hearth_sim::assets::{Asset, Category, RoomType};
use hearth_sim::scene::{GenerateOptions, MapOptions, SceneFile, SceneMaps, SceneObject, generate};
use hearth_sim::sensors::{Camera, CameraConfig, Modality, ModalitySet, Preset};
use hearth_sim::world::{ModelHandle, World, WorldConfig};
use nalgebra::{Isometry3, Point3};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

use crate::arm::{Arm, ArmSettings, ArmTarget, LinearMove};
use crate::articulated::{ArticulatedSettings, open};
use crate::error::{SkillError, SkillResult};
use crate::execution::Execution;
use crate::grasp::{GraspSettings, grasp};
use crate::navigate::{NavigateSettings, Navigator};
use crate::place::{PlaceSettings, PlaceTarget, place};

/// What [`run_story`] runs.
///
/// ```
/// let o = hearth_skills::story::StoryOptions::default();
/// assert_eq!(o.execution, hearth_skills::Execution::Physics);
/// assert!(o.out_dir.is_none());
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct StoryOptions {
    /// Seed of the generated home and of every planner.
    pub seed: u64,
    /// Rooms of the generated home besides the corridor (the kitchen is always the first).
    pub rooms: usize,
    /// Physics (the default) or kinematic execution of every skill.
    pub execution: Execution,
    /// Where to write the camera images, `report.json` and `trajectory.json`; `None` writes
    /// nothing (and renders nothing).
    pub out_dir: Option<PathBuf>,
    /// How far the drawer is pulled, metres.
    pub drawer_opening: f64,
}

impl Default for StoryOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            rooms: 2,
            execution: Execution::Physics,
            out_dir: None,
            drawer_opening: 0.25,
        }
    }
}

/// One stage of the story.
///
/// ```
/// let s = hearth_skills::story::StageReport::default();
/// assert!(!s.success);
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StageReport {
    /// `setup`, `navigate_to_cabinet`, `open_drawer`, `navigate_to_sink`, `grasp_dish`,
    /// `place_in_sink`.
    pub name: String,
    /// Whether it succeeded.
    pub success: bool,
    /// Simulated seconds it took.
    pub sim_time: f64,
    /// Wall-clock seconds it took.
    pub wall_time: f64,
    /// A line about what it did (or why it failed).
    pub detail: String,
    /// The camera image written after it, if any.
    pub image: Option<PathBuf>,
}

/// Why the story stopped.
///
/// ```
/// let f = hearth_skills::story::StoryFailure { stage: "grasp_dish".into(), reason: "slipped".into(), message: "…".into() };
/// assert_eq!(f.reason, "slipped");
/// ```
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct StoryFailure {
    /// The first stage that failed.
    pub stage: String,
    /// [`SkillError::reason`] of its error.
    pub reason: String,
    /// The error's message.
    pub message: String,
}

/// The robot's state at one moment.
///
/// ```
/// let s = hearth_skills::story::TrajectorySample::default();
/// assert!(s.joints.is_empty());
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrajectorySample {
    /// Simulated time, seconds.
    pub time: f64,
    /// The stage running.
    pub stage: String,
    /// Base pose `[x, y, yaw]`.
    pub base: [f64; 3],
    /// Joint positions, in the order of [`StoryReport::joint_names`].
    pub joints: Vec<f64>,
}

/// What [`run_story`] did.
///
/// ```
/// let r = hearth_skills::story::StoryReport::default();
/// assert!(!r.success && r.stages.is_empty());
/// ```
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StoryReport {
    /// The home's seed.
    pub seed: u64,
    /// How the skills were executed.
    pub execution: Execution,
    /// Whether every stage succeeded (the dish rests in the sink).
    pub success: bool,
    /// The stages run, in order.
    pub stages: Vec<StageReport>,
    /// The first failure, if any.
    pub failure: Option<StoryFailure>,
    /// The cabinet opened, its drawer joint, the dish and the sink counter (scene names).
    pub cabinet: String,
    /// The drawer's joint.
    pub drawer: String,
    /// The dish carried.
    pub dish: String,
    /// The counter with the sink.
    pub counter: String,
    /// The dish's final position.
    pub dish_position: [f64; 3],
    /// Names of the robot's joint variables.
    pub joint_names: Vec<String>,
    /// The robot's state after every skill call.
    pub trajectory: Vec<TrajectorySample>,
    /// A hash of the trajectory's exact numbers (equal for equal runs).
    pub trajectory_hash: u64,
    /// Wall-clock seconds of the whole story.
    pub wall_time: f64,
}

impl StoryReport {
    /// A hash of the trajectory's exact numbers (bit patterns), used for
    /// [`StoryReport::trajectory_hash`].
    ///
    /// ```
    /// let r = hearth_skills::story::StoryReport::default();
    /// assert_eq!(r.hash_trajectory(), r.clone().hash_trajectory());
    /// ```
    pub fn hash_trajectory(&self) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for s in &self.trajectory {
            s.time.to_bits().hash(&mut h);
            s.stage.hash(&mut h);
            for v in s.base.iter().chain(&s.joints) {
                v.to_bits().hash(&mut h);
            }
        }
        h.finish()
    }
}

/// The objects the story works with, chosen at set-up.
struct Cast {
    /// Cabinets with drawers and their highest drawer's joint, nearest the counter first.
    cabinets: Vec<(SceneObject, String)>,
    /// Sideways offset (counter frame) of the spot between the dish and the basin, metres.
    stand_side: f64,
    counter: SceneObject,
    dish: String,
}

/// Picks the sink counter and the cabinet, clears the counter's worktop and stands the dish
/// next to the sink.
fn cast(scene: &mut SceneFile) -> SkillResult<Cast> {
    let kitchens: Vec<String> = scene
        .building
        .rooms
        .iter()
        .filter(|r| r.room_type == RoomType::Kitchen)
        .map(|r| r.name.clone())
        .collect();
    if kitchens.is_empty() {
        return Err(SkillError::Unreachable("the home has no kitchen".into()));
    }
    let in_kitchen = |o: &SceneObject| o.room.as_ref().is_some_and(|r| kitchens.contains(r));
    let counter = scene
        .objects
        .iter()
        .find(|o| o.category == "counter" && in_kitchen(o))
        .cloned()
        .ok_or_else(|| SkillError::Unreachable("the kitchen has no counter with a sink".into()))?;
    let c = [counter.position[0], counter.position[1]];
    let mut cabinets: Vec<(f64, SceneObject, String)> = Vec::new();
    for o in scene
        .objects
        .iter()
        .filter(|o| o.category == "bottom_cabinet" && in_kitchen(o))
    {
        let asset = Asset::build(Category::BottomCabinet, o.variant, o.scale)
            .map_err(|e| SkillError::BadInput(format!("cabinet `{}`: {e}", o.name)))?;
        // The highest drawer has the highest index (drawer columns count from the bottom).
        let drawer = asset
            .model
            .joints()
            .iter()
            .filter(|j| j.name.starts_with("drawer_"))
            .map(|j| j.name.clone())
            .max();
        if let Some(drawer) = drawer {
            let d = (o.position[0] - c[0]).hypot(o.position[1] - c[1]);
            cabinets.push((d, o.clone(), drawer));
        }
    }
    cabinets.sort_by(|a, b| a.0.total_cmp(&b.0));
    if cabinets.is_empty() {
        return Err(SkillError::Unreachable("no cabinet with drawers in the kitchen".into()));
    }
    let cabinets = cabinets.into_iter().map(|(_, o, d)| (o, d)).collect();
    // The dish: on the worktop piece next to the sink, towards the front.
    let asset = Asset::build(Category::Counter, counter.variant, counter.scale)
        .map_err(|e| SkillError::BadInput(format!("counter `{}`: {e}", counter.name)))?;
    let worktop = asset.surfaces.iter().map(|s| s.z).fold(f64::NEG_INFINITY, f64::max);
    // The worktop piece beside the basin: the hole is on the side of the piece where the
    // counter goes on without worktop.
    let (piece, edge, towards) = asset
        .surfaces
        .iter()
        .filter(|s| (s.z - worktop).abs() < 0.01 && s.max[1] - s.min[1] > 0.2)
        .map(|s| {
            if s.max[1] < asset.aabb_max.y - 0.1 {
                (s, s.max[1], 1.0)
            } else {
                (s, s.min[1], -1.0)
            }
        })
        .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .ok_or_else(|| SkillError::Unreachable(format!("no worktop beside the sink of `{}`", counter.name)))?;
    // The bowl (14 cm across) towards the front, its rim 2 cm from the hole's edge; the robot
    // stands between it and the basin's middle (about 28 cm beyond the edge).
    let x = piece.max[0] - 0.1;
    let y = edge - towards * 0.09;
    let stand_side = edge + towards * 0.1;
    let p = counter.pose() * Point3::new(x, y, piece.z);
    scene.objects.retain(|o| o.on.as_deref() != Some(counter.name.as_str()));
    // The kitchen's dining set (table, chairs and what stands on them) is cleared away: it
    // often stands where the robot has to stand in front of the kitchen run.
    let dining: Vec<String> = scene
        .objects
        .iter()
        .filter(|o| in_kitchen(o) && matches!(o.category.as_str(), "table" | "chair"))
        .map(|o| o.name.clone())
        .collect();
    scene
        .objects
        .retain(|o| !dining.contains(&o.name) && !o.on.as_ref().is_some_and(|s| dining.contains(s)));
    let dish = "story_dish".to_owned();
    let mut bowl = SceneObject::new(&dish, "bowl", 0, [p.x, p.y, p.z]);
    bowl.orientation = counter.orientation;
    bowl.on = Some(counter.name.clone());
    bowl.room = counter.room.clone();
    scene.objects.push(bowl);
    Ok(Cast {
        cabinets,
        stand_side,
        counter,
        dish,
    })
}

/// A base pose `distance` in front of a wall-standing object (its front faces its +x) and
/// `side` to its left, facing the wall.
fn in_front_of(o: &SceneObject, distance: f64, side: f64) -> [f64; 3] {
    let yaw = o.orientation.yaw();
    let (c, s) = (yaw.cos(), yaw.sin());
    [
        o.position[0] + distance * c - side * s,
        o.position[1] + distance * s + side * c,
        hearth_kinematics::wrap_angle(yaw + std::f64::consts::PI),
    ]
}

/// The running story: world, robot, clocks, records.
struct Run {
    objects: std::collections::BTreeMap<String, ModelHandle>,
    world: World,
    robot: ModelHandle,
    camera: Option<Camera>,
    out_dir: Option<PathBuf>,
    report: StoryReport,
}

impl Run {
    fn loaded_object(&self, name: &str) -> SkillResult<ModelHandle> {
        self.objects
            .get(name)
            .copied()
            .ok_or_else(|| SkillError::BadInput(format!("`{name}` was not loaded")))
    }

    /// Holds the wheels still until the base has stopped (at most 2 s): arm plans are made
    /// against the base's pose and go wrong if it still turns.
    fn come_to_rest(&mut self, execution: Execution) -> SkillResult<()> {
        if execution == Execution::Kinematic {
            return Ok(());
        }
        self.world.drive(self.robot, 0.0, 0.0)?;
        let dt = self.world.config().control_dt();
        let mut last = self.world.base_pose(self.robot)?;
        for _ in 0..(2.0 / dt).ceil() as usize {
            self.world.step();
            let now = self.world.base_pose(self.robot)?;
            let moved =
                (now.translation.vector - last.translation.vector).norm() + 0.5 * now.rotation.angle_to(&last.rotation);
            last = now;
            if moved < 1e-5 * dt / 0.01 {
                break;
            }
        }
        Ok(())
    }

    fn sample(&mut self, stage: &str) -> SkillResult<()> {
        let pose = self.world.base_pose(self.robot)?;
        let yaw = pose.rotation.euler_angles().2;
        self.report.trajectory.push(TrajectorySample {
            time: self.world.time(),
            stage: stage.to_owned(),
            base: [pose.translation.x, pose.translation.y, yaw],
            joints: self.world.joint_positions(self.robot)?,
        });
        Ok(())
    }

    fn snap(&mut self, index: usize, stage: &str) -> Option<PathBuf> {
        let (camera, dir) = (self.camera.as_mut()?, self.out_dir.as_ref()?);
        let rgb = ModalitySet::EMPTY.with(Modality::Rgb);
        camera.render(&self.world, rgb).ok()?;
        let written = camera.frame().save(dir, &format!("{index}_{stage}_")).ok()?;
        written.into_iter().next()
    }

    /// Runs one stage; a failure is recorded and returned.
    fn stage<T>(&mut self, name: &str, f: impl FnOnce(&mut Self) -> SkillResult<(T, String)>) -> Result<T, ()> {
        let (t0, clock) = (self.world.time(), Instant::now());
        let out = f(self);
        let _ = self.sample(name);
        let index = self.report.stages.len();
        let image = self.snap(index, name);
        let mut stage = StageReport {
            name: name.to_owned(),
            success: out.is_ok(),
            sim_time: self.world.time() - t0,
            wall_time: clock.elapsed().as_secs_f64(),
            detail: String::new(),
            image,
        };
        match out {
            Ok((v, detail)) => {
                stage.detail = detail;
                self.report.stages.push(stage);
                Ok(v)
            }
            Err(e) => {
                stage.detail = e.to_string();
                self.report.stages.push(stage);
                self.report.failure = Some(StoryFailure {
                    stage: name.to_owned(),
                    reason: e.reason().to_owned(),
                    message: e.to_string(),
                });
                Err(())
            }
        }
    }
}

/// Generates the home of `options.seed` and runs the story in it (see the [module
/// docs](self)). Never panics on a failing stage: the report names it.
///
/// ```no_run
/// use hearth_skills::{Execution, story::{StoryOptions, run_story}};
/// let r = run_story(&StoryOptions { seed: 3, execution: Execution::Kinematic, ..Default::default() });
/// println!("success: {} in {:.1} s", r.success, r.wall_time);
/// ```
pub fn run_story(options: &StoryOptions) -> StoryReport {
    let home = generate(&GenerateOptions {
        seed: options.seed,
        rooms: options.rooms,
        robot: Some("fetch".into()),
        small_objects: true,
    });
    match home {
        Ok(scene) => run_story_in(scene, options),
        Err(e) => failed_setup(options, e.into(), Instant::now()),
    }
}

fn failed_setup(options: &StoryOptions, e: SkillError, clock: Instant) -> StoryReport {
    StoryReport {
        seed: options.seed,
        execution: options.execution,
        stages: vec![StageReport {
            name: "setup".into(),
            detail: e.to_string(),
            wall_time: clock.elapsed().as_secs_f64(),
            ..Default::default()
        }],
        failure: Some(StoryFailure {
            stage: "setup".into(),
            reason: e.reason().into(),
            message: e.to_string(),
        }),
        wall_time: clock.elapsed().as_secs_f64(),
        ..Default::default()
    }
}

/// Runs the story in `scene` (a home with a Fetch placed; [`run_story`] generates one).
///
/// ```no_run
/// use hearth_skills::story::{StoryOptions, run_story_in};
/// let mut home = hearth_sim::scene::generate(&Default::default()).unwrap();
/// home.objects.retain(|o| o.category != "counter");
/// let r = run_story_in(home, &StoryOptions::default());
/// assert_eq!(r.failure.unwrap().stage, "setup");
/// ```
pub fn run_story_in(mut scene: SceneFile, options: &StoryOptions) -> StoryReport {
    let clock = Instant::now();
    let set_up = (|| -> SkillResult<_> {
        if !(options.drawer_opening.is_finite() && options.drawer_opening > 0.0) {
            return Err(SkillError::BadInput(format!(
                "drawer_opening is {}; it must be positive",
                options.drawer_opening
            )));
        }
        if scene.robot.as_ref().is_none_or(|r| r.name != "fetch") {
            return Err(SkillError::BadInput(
                "the story needs a Fetch placed in the scene".into(),
            ));
        }
        let cast = cast(&mut scene)?;
        let maps = SceneMaps::build(
            &scene,
            &MapOptions {
                robot_radius: 0.38,
                ..Default::default()
            },
        )?;
        let mut world = World::new(WorldConfig::default())?;
        let loaded = world
            .load_scene(&scene)
            .map_err(|e| SkillError::BadInput(format!("loading the home: {e}")))?;
        let robot = loaded
            .robot
            .ok_or_else(|| SkillError::BadInput("the scene places no robot".into()))?;
        world.tuck(robot)?;
        world.settle(120);
        let handle = |name: &str| {
            loaded
                .object(name)
                .ok_or_else(|| SkillError::BadInput(format!("`{name}` was not loaded")))
        };
        let handles = (handle(&cast.counter.name)?, handle(&cast.dish)?);
        let arm = Arm::new(&world, robot, story_arm_settings())?;
        Ok((cast, maps, world, robot, handles, loaded.objects.clone(), arm))
    })();
    let (cast, maps, world, robot, (counter, dish), objects, arm) = match set_up {
        Ok(v) => v,
        Err(e) => return failed_setup(options, e, clock),
    };
    let camera = match &options.out_dir {
        Some(_) => CameraConfig::preset(Preset::VisualRl)
            .and_then(|c| Camera::new(&world, Some(robot), c))
            .ok(),
        None => None,
    };
    let joint_names = world
        .model(robot)
        .map(|m| m.variable_names().to_vec())
        .unwrap_or_default();
    let mut run = Run {
        objects,
        world,
        robot,
        camera,
        out_dir: options.out_dir.clone(),
        report: StoryReport {
            seed: options.seed,
            execution: options.execution,
            dish: cast.dish.clone(),
            counter: cast.counter.name.clone(),
            joint_names,
            ..Default::default()
        },
    };
    let detail = format!(
        "{} cabinets with drawers, sink counter `{}`, dish `{}`",
        cast.cabinets.len(),
        cast.counter.name,
        cast.dish
    );
    let _ = run.stage("setup", |_| Ok(((), detail)));
    let _ = story_stages(&mut run, arm, &cast, &maps, options, counter, dish);
    run.report.success = run.report.failure.is_none();
    if let Ok(p) = run.world.base_pose(dish) {
        run.report.dish_position = [p.translation.x, p.translation.y, p.translation.z];
    }
    run.report.trajectory_hash = run.report.hash_trajectory();
    run.report.wall_time = clock.elapsed().as_secs_f64();
    if let Some(dir) = &options.out_dir {
        let _ = std::fs::create_dir_all(dir);
        let trajectory = serde_json::json!({
            "joint_names": run.report.joint_names,
            "samples": run.report.trajectory,
        });
        let _ = std::fs::write(dir.join("trajectory.json"), trajectory.to_string());
        let mut summary = run.report.clone();
        summary.trajectory.clear();
        if let Ok(text) = serde_json::to_string_pretty(&summary) {
            let _ = std::fs::write(dir.join("report.json"), text);
        }
    }
    run.report
}

#[allow(clippy::too_many_arguments)]
fn story_stages(
    run: &mut Run,
    mut arm: Arm,
    cast: &Cast,
    maps: &SceneMaps,
    options: &StoryOptions,
    counter: ModelHandle,
    dish: ModelHandle,
) -> Result<(), ()> {
    let exec = options.execution;
    let mut rng = Pcg64Mcg::seed_from_u64(options.seed ^ 0x0570_71e5);
    let nav = Navigator::new(NavigateSettings {
        execution: exec,
        plan_iterations: 60_000,
        ..Default::default()
    })
    .map_err(|_| ())?;
    let robot = run.robot;

    let (cabinet, drawer, cabinet_object, first_stand) = run.stage("navigate_to_cabinet", |r| {
        // The first cabinet with a free spot in front of it that a path reaches.
        let mut last = None;
        for (o, drawer) in &cast.cabinets {
            let spots = CABINET_STANDS.iter().map(|&(d, side)| in_front_of(o, d, side));
            match reachable(&nav, r, maps, spots, &mut rng) {
                Ok(goal) => {
                    let n = nav.navigate(&mut r.world, robot, maps, goal, &mut rng)?;
                    r.come_to_rest(exec)?;
                    let handle = r.loaded_object(&o.name)?;
                    r.report.cabinet = o.name.clone();
                    r.report.drawer = drawer.clone();
                    return Ok((
                        (handle, drawer.clone(), o, goal),
                        format!(
                            "to `{}`: {:.2} m, {} replans, {:.2} m from the goal",
                            o.name, n.distance, n.replans, n.position_error
                        ),
                    ));
                }
                Err(e) => last = Some(e),
            }
        }
        Err(last.unwrap_or_else(|| SkillError::Unreachable("no cabinet".into())))
    })?;
    run.stage("open_drawer", |r| {
        let settings = ArticulatedSettings {
            // Open far enough to reach in: 40 % of the asked pull (10 cm of 25).
            min_fraction: 0.4,
            ..Default::default()
        };
        // A second try (new IK seeds and plans) after a miss of the handle or a pull that
        // did not take, the arm brought in first; after two misses from one spot, or a
        // collision, the same from another spot in front of the cabinet.
        let mut tries = 0;
        let mut stands = vec![first_stand];
        let o = loop {
            tries += 1;
            let opened = open(
                &mut r.world,
                &mut arm,
                cabinet,
                &drawer,
                options.drawer_opening,
                &settings,
                exec,
                &mut rng,
            );
            match opened {
                Ok(o) => break o,
                Err(e) if !retryable(&e) && !matches!(e, SkillError::Collision(_)) => return Err(e),
                Err(e) => {
                    let _ = r.world.gripper_open(robot);
                    if tries % 2 == 1 && retryable(&e) {
                        let recovered =
                            clear_of(r, &mut arm, exec).and_then(|_| tuck_arm(r, &mut arm, exec, cabinet, &mut rng));
                        if recovered.is_ok() {
                            continue;
                        }
                    }
                    if stands.len() >= MAX_STANDS {
                        return Err(e);
                    }
                    let spots = CABINET_STANDS
                        .iter()
                        .map(|&(d, side)| in_front_of(cabinet_object, d, side));
                    let goal =
                        restand(r, &nav, &mut arm, exec, maps, spots, &stands, cabinet, &mut rng).map_err(|_| e)?;
                    stands.push(goal);
                    tries = 0;
                }
            }
        };
        r.sample("open_drawer")?;
        stow(r, &nav, &mut arm, exec, cabinet, &mut rng)?;
        Ok((
            (),
            format!(
                "`{}` from {:.2} to {:.2} m (from spot {} of the cabinet)",
                o.joint,
                o.start,
                o.end,
                stands.len()
            ),
        ))
    })?;
    let counter_spots = || {
        COUNTER_STANDS
            .iter()
            .map(|&(d, side)| in_front_of(&cast.counter, d, cast.stand_side + side))
    };
    let sink_stand = run.stage("navigate_to_sink", |r| {
        let goal = reachable(&nav, r, maps, counter_spots(), &mut rng)?;
        let n = nav.navigate(&mut r.world, robot, maps, goal, &mut rng)?;
        Ok((
            goal,
            format!(
                "{:.2} m, {} replans, {:.2} m from the goal",
                n.distance, n.replans, n.position_error
            ),
        ))
    })?;
    run.stage("grasp_dish", |r| {
        // The bowl is wider than the gripper opens: it is taken by its rim, from above.
        let top = GraspSettings {
            side: false,
            ..Default::default()
        };
        ready_arm(r, &mut arm, exec, &mut rng)?;
        let g = grasp(&mut r.world, &mut arm, dish, &top, exec, &mut rng)?;
        Ok(((), format!("{:?} grasp, lifted {:.2} m", g.candidate.kind, g.lifted)))
    })?;
    run.stage("place_in_sink", |r| {
        let tops = PlaceTarget::surfaces_of(&r.world, counter, 0.02)?;
        let worktop = tops.iter().map(|t| t.z).fold(f64::NEG_INFINITY, f64::max);
        let basin = tops
            .into_iter()
            .filter(|t| t.z > 0.3 && t.z < worktop - 0.1)
            .min_by(|a, b| a.z.total_cmp(&b.z))
            .ok_or_else(|| SkillError::Unreachable(format!("no sink basin in `{}`", cast.counter.name)))?;
        // Set down on the basin's floor, or failing that let go 8 cm above it (the bowl drops
        // into the basin); no placement within reach from here, or the arm brushed the
        // counter on the way: the same from another spot.
        let mut stands = vec![sink_stand];
        let mut drop = false;
        let p = loop {
            let settings = PlaceSettings {
                clearance: if drop { 0.08 } else { 0.01 },
                ..PlaceSettings::default()
            };
            match place(&mut r.world, &mut arm, &basin, &settings, exec, &mut rng) {
                Ok(p) => break p,
                Err(SkillError::Unreachable(_) | SkillError::IkFailed(_) | SkillError::PlanningFailed(_)) if !drop => {
                    drop = true;
                }
                // A brush against the counter on the way: the same from another spot.
                Err(
                    e @ (SkillError::Unreachable(_)
                    | SkillError::IkFailed(_)
                    | SkillError::PlanningFailed(_)
                    | SkillError::Collision(_)),
                ) if stands.len() < MAX_STANDS && arm.held().is_some() => {
                    let goal = restand(
                        r,
                        &nav,
                        &mut arm,
                        exec,
                        maps,
                        counter_spots(),
                        &stands,
                        counter,
                        &mut rng,
                    )
                    .map_err(|_| e)?;
                    stands.push(goal);
                    drop = false;
                }
                Err(e) => return Err(e),
            }
        };
        r.sample("place_in_sink")?;
        let rest = r.world.base_pose(dish)?.translation;
        let inside = rest.x >= basin.min[0] - 0.02
            && rest.x <= basin.max[0] + 0.02
            && rest.y >= basin.min[1] - 0.02
            && rest.y <= basin.max[1] + 0.02
            && (rest.z - basin.z).abs() < 0.05;
        if !inside {
            return Err(SkillError::NotFinished(format!(
                "the dish rests at [{:.2}, {:.2}, {:.2}], not in the basin at height {:.2}",
                rest.x, rest.y, rest.z, basin.z
            )));
        }
        // Back off and bring the arm in, with the stow's retries (the arm may brush the
        // counter's front on its way in).
        stow(r, &nav, &mut arm, exec, counter, &mut rng)?;
        Ok((
            (),
            format!(
                "dish in the basin at [{:.2}, {:.2}, {:.2}] ({:.1} s)",
                rest.x, rest.y, rest.z, p.approach.duration
            ),
        ))
    })?;
    Ok(())
}

/// The Fetch's arm settings for the story: slower motions and a wider margin (the base tilts
/// by up to 0.006 rad on its casters under the moving arm, so the arm ends up millimetres off
/// its plan until the final correction), and a brush of up to 20 N against furniture tolerated.
fn story_arm_settings() -> ArmSettings {
    ArmSettings {
        velocity_scale: 0.3,
        margin: 0.03,
        contact_force: 20.0,
        ..ArmSettings::fetch()
    }
}

/// Spots of the base in front of a cabinet when opening its drawer, in order of preference:
/// distance from the cabinet's origin and sideways offset, metres.
const CABINET_STANDS: [(f64, f64); 10] = [
    (1.2, 0.0),
    (1.3, 0.0),
    (1.1, 0.0),
    (1.2, 0.15),
    (1.2, -0.15),
    (1.0, 0.0),
    (1.1, 0.25),
    (1.1, -0.25),
    (1.0, 0.3),
    (1.0, -0.3),
];
/// Spots of the base in front of the sink counter when grasping and placing (sideways from
/// the spot between the dish and the basin).
const COUNTER_STANDS: [(f64, f64); 10] = [
    (0.85, 0.0),
    (0.9, 0.0),
    (0.8, 0.0),
    (0.85, 0.12),
    (0.85, -0.12),
    (0.85, 0.24),
    (0.85, -0.24),
    (0.8, 0.36),
    (0.8, -0.36),
    (0.95, 0.0),
];

/// Spots a manipulation is tried from before the story gives up on it.
const MAX_STANDS: usize = 2;

/// Brings the arm in (backing the base off 10 cm first when the arm is caught on something)
/// and drives to the first of `spots` a path reaches that is not near one of `tried`.
#[allow(clippy::too_many_arguments)]
fn restand(
    run: &mut Run,
    nav: &Navigator,
    arm: &mut Arm,
    exec: Execution,
    maps: &SceneMaps,
    spots: impl Iterator<Item = [f64; 3]>,
    tried: &[[f64; 3]],
    near: ModelHandle,
    rng: &mut Pcg64Mcg,
) -> SkillResult<[f64; 3]> {
    // What the gripper holds travels with the base: no obstacle to it.
    let nav = Navigator::new(NavigateSettings {
        carried: arm.held().map(|h| h.bodies.clone()).unwrap_or_default(),
        ..nav.settings().clone()
    })?;
    stow(run, &nav, arm, exec, near, rng)?;
    let fresh = spots.filter(|g| tried.iter().all(|t| (t[0] - g[0]).hypot(t[1] - g[1]) > 0.1));
    let goal = reachable(&nav, run, maps, fresh, rng)?;
    nav.navigate(&mut run.world, run.robot, maps, goal, rng)?;
    run.come_to_rest(exec)?;
    Ok(goal)
}

/// Backs the gripper off what it touched and brings the arm in; when the arm is caught (a
/// brush against furniture, a plan that cannot start), once more, then once more after
/// backing the base off 10 cm where that is free.
fn stow(
    run: &mut Run,
    nav: &Navigator,
    arm: &mut Arm,
    exec: Execution,
    near: ModelHandle,
    rng: &mut Pcg64Mcg,
) -> SkillResult<()> {
    let mut last = None;
    for attempt in 0..3 {
        if attempt == 2 {
            nav.back_off(&mut run.world, run.robot, 0.1)?;
            run.come_to_rest(exec)?;
        }
        match clear_of(run, arm, exec).and_then(|_| tuck_arm(run, arm, exec, near, rng)) {
            Ok(()) => return Ok(()),
            Err(e) => last = Some(e),
        }
    }
    Err(last.unwrap_or_else(|| SkillError::NotFinished("the arm could not be brought in".into())))
}

/// The first of `spots` a path reaches (planned, not driven).
fn reachable(
    nav: &Navigator,
    run: &Run,
    maps: &SceneMaps,
    spots: impl Iterator<Item = [f64; 3]>,
    rng: &mut Pcg64Mcg,
) -> SkillResult<[f64; 3]> {
    let mut last = None;
    for goal in spots {
        match nav.plan(&run.world, run.robot, maps, goal, rng) {
            Ok(_) => return Ok(goal),
            Err(e) => last = Some(e),
        }
    }
    Err(last.unwrap_or_else(|| SkillError::Unreachable("no spot to stand on".into())))
}

/// Reaches forward before planning a manipulation: the base tilts on its casters by a few
/// thousandths of a radian as the arm's weight moves forward, which would throw a plan made
/// with the arm tucked off by millimetres at the gripper. With the arm already forward (and
/// the base come to rest), the plans start from the tilt they will keep.
fn ready_arm(run: &mut Run, arm: &mut Arm, exec: Execution, rng: &mut Pcg64Mcg) -> SkillResult<()> {
    let base = run.world.base_pose(run.robot)?;
    let yaw = base.rotation.euler_angles().2;
    let level = nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
    let mut last = None;
    for (x, z) in [(0.55, 1.1), (0.5, 1.2), (0.6, 1.0)] {
        let at = base * Point3::new(x, 0.0, z);
        let pose = Isometry3::from_parts(at.coords.into(), level);
        match arm.move_to(&mut run.world, &ArmTarget::Pose(pose), exec, rng) {
            Ok(_) => {
                run.sample("ready")?;
                return run.come_to_rest(exec);
            }
            Err(e @ (SkillError::IkFailed(_) | SkillError::PlanningFailed(_) | SkillError::PlanningTimeout(_))) => {
                last = Some(e)
            }
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| SkillError::IkFailed("no ready pose".into())))
}

/// Brings the arm back close to the body for driving: above the base, a little ahead, the
/// gripper keeping its orientation (a held object stays upright).
fn tuck_arm(run: &mut Run, arm: &mut Arm, exec: Execution, near: ModelHandle, rng: &mut Pcg64Mcg) -> SkillResult<()> {
    let base = run.world.base_pose(run.robot)?;
    let tip = arm.tip_pose(&run.world)?;
    let mut last = None;
    // The fingers may still graze the furniture they worked on: if no plan starts clear of
    // it, the way out may touch it.
    let near = run.world.model_bodies(near)?;
    for ignore in [&[][..], &near[..]] {
        for (x, z) in [(0.45, 1.05), (0.5, 1.15), (0.55, 0.95)] {
            let at = base * Point3::new(x, 0.0, z);
            let pose = Isometry3::from_parts(at.coords.into(), tip.rotation);
            let moved = arm
                .plan(&run.world, &ArmTarget::Pose(pose), ignore, rng)
                .and_then(|plan| arm.execute(&mut run.world, &plan, exec));
            match moved {
                Ok(_) => {
                    run.sample("carry")?;
                    return Ok(());
                }
                Err(e) if retryable(&e) => last = Some(e),
                Err(e) => return Err(e),
            }
        }
    }
    Err(last.unwrap_or_else(|| SkillError::IkFailed("no carrying pose".into())))
}

/// Failures another plan may avoid.
fn retryable(e: &SkillError) -> bool {
    matches!(
        e,
        SkillError::IkFailed(_)
            | SkillError::PlanningFailed(_)
            | SkillError::PlanningTimeout(_)
            | SkillError::Unreachable(_)
            | SkillError::NotHeld(_)
            | SkillError::NoEffect(_)
    )
}

/// Backs the gripper a little away from what it let go of and lifts it (where a straight step
/// is possible).
fn clear_of(run: &mut Run, arm: &mut Arm, exec: Execution) -> SkillResult<()> {
    let back = arm.tip_pose(&run.world)?.rotation * -nalgebra::Vector3::x();
    for (direction, distance) in [(back, 0.06), (nalgebra::Vector3::z(), 0.06)] {
        let m = LinearMove {
            check_world: false,
            ..LinearMove::new(direction, distance)
        };
        match arm.move_linear(&mut run.world, &m, exec) {
            Ok(_) | Err(SkillError::Unreachable(_)) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
