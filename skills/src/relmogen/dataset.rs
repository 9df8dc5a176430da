//! A push dataset for learning where pushes succeed (ReLMoGen's arm score map): for random
//! robot poses on the traversability map, push at random pixels of the head camera, the world
//! restored to the location's snapshot before every push, and record which pixels pushed
//! something.
//!
//! Layout of a dataset folder:
//! - `loc_NNNNN/rgb.png`: the head camera's colour image at the location (H × W RGB8);
//! - `loc_NNNNN/mask.npy`: (H, W) u8 — 1: a push there moved the touched point more than
//!   `min_motion` (0.10 m by default), 0: it failed, 255: untried (a pixel drawn twice keeps
//!   its last result);
//! - `loc_NNNNN/mask_rgb.png`: the mask as a picture (green 1, red 0, black untried);
//! - `loc_NNNNN/pushes.json`: the location's index — robot pose, image size, execution mode,
//!   and per push the pixel, success, failure reason ([`SkillError::reason`]), how far the
//!   touched point moved and the body seen. It is written last (through a temporary file),
//!   so a location with it is complete: [`PushDataset::write`] skips those (resume).
//! - `dataset.json`: the settings of the run.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use hearth_sim::scene::{MapOptions, SceneFile, SceneMaps};
use hearth_sim::sensors::{
    Backend, Camera, CameraConfig, CameraIntrinsics, Frame, Modality, ModalitySet, RenderOptions,
};
use hearth_sim::world::{JointCommand, LoadedScene, ModelHandle, Snapshot, World, WorldConfig};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};

use super::config::{ReLMoGenError, ReLMoGenResult, bad, io_error};
use crate::arm::{Arm, ArmSettings};
use crate::error::SkillError;
use crate::execution::Execution;
use crate::push::{PushSettings, push_at_point, surface_at_pixel};

/// Mask value of a pixel never tried.
///
/// ```
/// assert_eq!(hearth_skills::relmogen::UNTRIED, 255);
/// ```
pub const UNTRIED: u8 = 255;

/// Settings of a push dataset.
///
/// ```
/// let s = hearth_skills::relmogen::DatasetSettings::default();
/// assert_eq!((s.width, s.height, s.pushes_per_location), (128, 128, 20));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetSettings {
    /// Robot poses (camera views).
    pub locations: usize,
    /// Pushes at each.
    pub pushes_per_location: usize,
    /// How pushes execute.
    pub execution: Execution,
    /// Seed: location `i` draws its pose and pixels from (`seed`, `i`).
    pub seed: u64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Vertical field of view, degrees.
    pub vfov_deg: f64,
    /// Rendering backend.
    pub backend: Backend,
    /// The push.
    pub push: PushSettings,
    /// Fraction of locations that face a piece of articulated furniture (a cabinet, a
    /// dresser, a fridge, a door) from about arm's length, with each of its drawers and doors
    /// opened to a random part of its range with probability ½; the rest are uniform on the
    /// traversability map. Uniform views rarely have anything within reach that a push can
    /// move, so they give almost only failures.
    pub furniture_views: f64,
}

impl Default for DatasetSettings {
    fn default() -> Self {
        Self {
            locations: 10,
            pushes_per_location: 20,
            execution: Execution::Physics,
            seed: 0,
            width: 128,
            height: 128,
            vfov_deg: 90.0,
            backend: Backend::Auto,
            push: PushSettings::default(),
            furniture_views: 0.75,
        }
    }
}

/// One push of the dataset.
///
/// ```
/// let r = hearth_skills::relmogen::PushRecord { pixel: [3, 4], success: false, reason: Some("no_effect".into()), moved: 0.02, body: None };
/// assert!(serde_json::to_string(&r).unwrap().contains("no_effect"));
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PushRecord {
    /// (u, v).
    pub pixel: [u32; 2],
    /// Whether the touched point moved more than `min_motion`.
    pub success: bool,
    /// Failure reason ([`SkillError::reason`]).
    pub reason: Option<String>,
    /// How far the touched point moved, m (0 when nothing was touched).
    pub moved: f64,
    /// Name of the body the pixel saw.
    pub body: Option<String>,
}

/// The index of one location (`pushes.json`).
///
/// ```no_run
/// let text = std::fs::read_to_string("out/loc_00000/pushes.json").unwrap();
/// let index: hearth_skills::relmogen::LocationIndex = serde_json::from_str(&text).unwrap();
/// println!("{} pushes from {:?}", index.pushes.len(), index.pose);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocationIndex {
    /// Location number.
    pub location: usize,
    /// Robot base pose (x, y, yaw).
    pub pose: [f64; 3],
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// `physics` or `kinematic`.
    pub execution: Execution,
    /// The pushes, in order.
    pub pushes: Vec<PushRecord>,
}

/// A location with its image and mask.
///
/// ```no_run
/// # fn f(loc: hearth_skills::relmogen::Location) {
/// assert_eq!(loc.mask.len() * 3, loc.rgb.len());
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    /// Index (pose, pushes).
    pub index: LocationIndex,
    /// RGB8 image.
    pub rgb: Vec<u8>,
    /// Per pixel: 1 success, 0 failure, [`UNTRIED`].
    pub mask: Vec<u8>,
}

/// Progress of [`PushDataset::write`].
///
/// ```no_run
/// # fn f(p: &hearth_skills::relmogen::Progress) {
/// eprint!("\r{}/{} {:.1} pushes/s", p.locations_done, p.locations, p.pushes_per_second);
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Locations finished or skipped.
    pub locations_done: usize,
    /// All locations.
    pub locations: usize,
    /// Pushes run so far in this run.
    pub pushes: usize,
    /// Their rate, per wall-clock second.
    pub pushes_per_second: f64,
}

/// What [`PushDataset::write`] did.
///
/// ```
/// let s = hearth_skills::relmogen::DatasetSummary::default();
/// assert_eq!((s.written, s.skipped, s.pushes_per_second), (0, 0, 0.0));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct DatasetSummary {
    /// Locations written now.
    pub written: usize,
    /// Locations found complete and skipped.
    pub skipped: usize,
    /// Pushes run now.
    pub pushes: usize,
    /// Of which succeeded.
    pub successes: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Pushes per second (0 when none ran).
    pub pushes_per_second: f64,
}

/// A world with a Fetch, ready to sample locations and push (`docs/relmogen.md` has the
/// dataset format).
///
/// ```no_run
/// use hearth_sim::scene::{GenerateOptions, generate};
/// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
/// let home = generate(&GenerateOptions { seed: 2, rooms: 2, robot: Some("fetch".into()), small_objects: false })?;
/// let settings = DatasetSettings { locations: 2, pushes_per_location: 5, ..Default::default() };
/// let mut data = PushDataset::new(&home, settings)?;
/// let summary = data.write("pushes-out".as_ref(), |_| {})?;
/// println!("{:.2} pushes/s", summary.pushes_per_second);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct PushDataset {
    world: World,
    robot: ModelHandle,
    home: Snapshot,
    cells: Vec<[f64; 2]>,
    /// Articulated furniture with free joints, for furniture views.
    furniture: Vec<Furniture>,
    /// The traversability map (furniture views stand on it).
    maps: SceneMaps,
    camera: Camera,
    arm: Arm,
    settings: DatasetSettings,
}

/// A piece of articulated furniture a location can face.
#[derive(Clone, Debug)]
struct Furniture {
    model: ModelHandle,
    /// Footprint centre and yaw of the object (its front faces +x of that yaw).
    xy: [f64; 2],
    yaw: f64,
    /// Half its depth along its front axis.
    half_depth: f64,
    /// Its unactuated joints (variables) with their ranges.
    joints: Vec<(usize, f64, f64)>,
}

/// Articulated objects of `scene` whose joints move freely in `world`.
fn articulated_furniture(world: &World, scene: &SceneFile, loaded: &LoadedScene) -> Vec<Furniture> {
    let mut out = Vec::new();
    for object in &scene.objects {
        let Some(model) = loaded.object(&object.name) else {
            continue;
        };
        let (Ok(m), Ok(commands)) = (world.model(model), world.joint_commands(model)) else {
            continue;
        };
        let joints: Vec<(usize, f64, f64)> = (0..m.dof())
            .filter(|&v| commands[v] == JointCommand::Off && m.upper()[v] - m.lower()[v] > 1e-3)
            .map(|v| (v, m.lower()[v], m.upper()[v]))
            .collect();
        if joints.is_empty() {
            continue;
        }
        let (centre, half_depth) = object.bbox.as_ref().map_or(([0.0, 0.0], 0.3), |b| {
            (
                [(b.min[0] + b.max[0]) / 2.0, (b.min[1] + b.max[1]) / 2.0],
                ((b.max[0] - b.min[0]) / 2.0).abs(),
            )
        });
        let pose = object.pose();
        let c = pose * nalgebra::Point3::new(centre[0], centre[1], 0.0);
        out.push(Furniture {
            model,
            xy: [c.x, c.y],
            yaw: object.orientation.yaw(),
            half_depth,
            joints,
        });
    }
    out
}

impl std::fmt::Debug for PushDataset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PushDataset")
            .field("settings", &self.settings)
            .field("cells", &self.cells.len())
            .finish_non_exhaustive()
    }
}

impl PushDataset {
    /// Loads `scene` with a Fetch at its robot placement (the scene's robot is replaced by
    /// the Fetch), settles it, and builds the traversability map and the camera.
    ///
    /// # Errors
    /// [`ReLMoGenError::Config`] for bad settings or a scene without a robot placement or
    /// free floor; scene, world and sensor errors.
    /// ```no_run
    /// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
    /// let home = hearth_sim::scene::SceneFile::load("home.json")?;
    /// let mut data = PushDataset::new(&home, DatasetSettings::default())?;
    /// println!("{:?}", data);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(scene: &SceneFile, settings: DatasetSettings) -> ReLMoGenResult<Self> {
        if settings.locations == 0 {
            return Err(bad("locations", "must be at least 1"));
        }
        if settings.pushes_per_location == 0 {
            return Err(bad("pushes_per_location", "must be at least 1"));
        }
        let intrinsics = CameraIntrinsics {
            width: settings.width,
            height: settings.height,
            vfov_deg: settings.vfov_deg,
            near: 0.05,
            far: 5.0,
        };
        intrinsics.validate().map_err(|e| bad("camera", e.to_string()))?;
        let mut scene = scene.clone();
        match scene.robot.as_mut() {
            Some(r) => r.name = "fetch".into(),
            None => return Err(bad("scene", "places no robot")),
        }
        let mut world = World::new(WorldConfig::default()).map_err(SkillError::from)?;
        let loaded = world.load_scene(&scene).map_err(|e| bad("scene", e.to_string()))?;
        let robot = loaded.robot.ok_or_else(|| bad("scene", "places no robot"))?;
        // Tucked once here: every location starts from this snapshot with the arm tucked.
        world.tuck(robot).map_err(SkillError::from)?;
        world.settle(120);
        let maps = SceneMaps::build(
            &scene,
            &MapOptions {
                resolution: 0.05,
                robot_radius: 0.37,
                floor_clearance: 0.03,
                ..MapOptions::default()
            },
        )
        .map_err(SkillError::from)?;
        let mut cells = Vec::new();
        for iy in 0..maps.height {
            for ix in 0..maps.width {
                if maps.traversable[iy * maps.width + ix] {
                    cells.push(maps.cell_center(ix, iy));
                }
            }
        }
        if cells.is_empty() {
            return Err(bad("scene", "has no floor the Fetch fits on"));
        }
        let furniture = articulated_furniture(&world, &scene, &loaded);
        let camera = Camera::new(
            &world,
            Some(robot),
            CameraConfig {
                intrinsics,
                options: RenderOptions::default(),
                backend: settings.backend,
                mount: None,
            },
        )
        .map_err(SkillError::from)?;
        let arm = Arm::new(&world, robot, ArmSettings::fetch())?;
        Ok(Self {
            home: world.snapshot(),
            world,
            robot,
            cells,
            furniture,
            maps,
            camera,
            arm,
            settings,
        })
    }

    /// How many pieces of articulated furniture (with free drawers or doors) furniture views
    /// can face.
    /// ```no_run
    /// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
    /// let home = hearth_sim::scene::SceneFile::load("home.json")?;
    /// let data = PushDataset::new(&home, DatasetSettings::default())?;
    /// println!("{} pieces of furniture to face", data.furniture_count());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn furniture_count(&self) -> usize {
        self.furniture.len()
    }

    /// The settings.
    /// ```no_run
    /// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
    /// let home = hearth_sim::scene::SceneFile::load("home.json")?;
    /// let mut data = PushDataset::new(&home, DatasetSettings::default())?;
    /// assert_eq!(data.settings().pushes_per_location, 20);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn settings(&self) -> &DatasetSettings {
        &self.settings
    }

    /// The physics world (as the last push left it).
    /// ```no_run
    /// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
    /// let home = hearth_sim::scene::SceneFile::load("home.json")?;
    /// let mut data = PushDataset::new(&home, DatasetSettings::default())?;
    /// println!("{} models", data.world().models().count());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Runs location `index`: a pose drawn from (`seed`, `index`) on the traversability map
    /// (arm tucked since loading), its image, then `pushes_per_location` pushes at random pixels, each from
    /// the location's snapshot. The same seed and index give the same location.
    ///
    /// # Errors
    /// World and sensor errors (a push that fails is a record, not an error).
    /// ```no_run
    /// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
    /// let home = hearth_sim::scene::SceneFile::load("home.json")?;
    /// let mut data = PushDataset::new(&home, DatasetSettings::default())?;
    /// let loc = data.location(3)?;
    /// assert_eq!(loc.index.pushes.len(), 20);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn location(&mut self, index: usize) -> ReLMoGenResult<Location> {
        let s = self.settings.clone();
        let mut rng = Pcg64Mcg::seed_from_u64(s.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(index as u64));
        self.world.restore(&self.home).map_err(SkillError::from)?;
        let facing = if !self.furniture.is_empty() && rng.random::<f64>() < s.furniture_views {
            self.face_furniture(&mut rng)?
        } else {
            None
        };
        let [x, y, yaw] = match facing {
            Some(pose) => pose,
            None => {
                let [x, y] = self.cells[rng.random_range(0..self.cells.len())];
                [x, y, rng.random_range(-std::f64::consts::PI..std::f64::consts::PI)]
            }
        };
        let z = self
            .world
            .base_pose(self.robot)
            .map_err(SkillError::from)?
            .translation
            .z;
        let pose = Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        );
        self.world.place(self.robot, &pose).map_err(SkillError::from)?;
        self.world.drive(self.robot, 0.0, 0.0).map_err(SkillError::from)?;
        for _ in 0..10 {
            self.world.step();
        }
        let start = self.world.snapshot();
        let (w, h) = (s.width, s.height);
        let rgb = self
            .camera
            .render(&self.world, ModalitySet::EMPTY.with(Modality::Rgb))
            .map_err(SkillError::from)?
            .rgb
            .clone();
        let mut mask = vec![UNTRIED; (w * h) as usize];
        let mut pushes = Vec::with_capacity(s.pushes_per_location);
        let push = s.push.clone();
        let execution = s.execution;
        for _ in 0..s.pushes_per_location {
            let (u, v) = (rng.random_range(0..w), rng.random_range(0..h));
            self.world.restore(&start).map_err(SkillError::from)?;
            let record = self.push_at(u, v, &push, execution, &mut rng)?;
            mask[(v * w + u) as usize] = u8::from(record.success);
            pushes.push(record);
        }
        Ok(Location {
            index: LocationIndex {
                location: index,
                pose: [x, y, yaw],
                width: w,
                height: h,
                execution,
                pushes,
            },
            rgb,
            mask,
        })
    }

    /// A base pose about arm's length in front of a random piece of articulated furniture,
    /// facing it, on the traversability map; opens each of its joints to a random part of its
    /// range with probability ½. `None` when no traversable cell is near its front.
    fn face_furniture(&mut self, rng: &mut Pcg64Mcg) -> ReLMoGenResult<Option<[f64; 3]>> {
        let f = self.furniture[rng.random_range(0..self.furniture.len())].clone();
        let (sin, cos) = f.yaw.sin_cos();
        let reach = f.half_depth + rng.random_range(0.8..1.1);
        let lateral = rng.random_range(-0.2..0.2);
        let xy = [
            f.xy[0] + cos * reach - sin * lateral,
            f.xy[1] + sin * reach + cos * lateral,
        ];
        // The nearest traversable cell within 0.3 m of the wanted spot.
        let mut best: Option<([f64; 2], f64)> = None;
        for dy in -6i32..=6 {
            for dx in -6i32..=6 {
                let p = [xy[0] + 0.05 * f64::from(dx), xy[1] + 0.05 * f64::from(dy)];
                let d = (p[0] - xy[0]).hypot(p[1] - xy[1]);
                if d <= 0.3 && self.maps.is_traversable(p) && best.is_none_or(|(_, b)| d < b) {
                    best = Some((p, d));
                }
            }
        }
        let Some((p, _)) = best else { return Ok(None) };
        let face = (f.xy[1] - p[1]).atan2(f.xy[0] - p[0]) + rng.random_range(-0.15..0.15);
        let mut q = self.world.joint_positions(f.model).map_err(SkillError::from)?;
        let model = self.world.model(f.model).map_err(SkillError::from)?;
        // Solver drift can leave a joint a hair past its limit; the reset wants it inside.
        for (v, x) in q.iter_mut().enumerate() {
            *x = x.clamp(model.lower()[v], model.upper()[v]);
        }
        for &(v, lo, hi) in &f.joints {
            if rng.random::<bool>() {
                q[v] = lo + (hi - lo) * rng.random_range(0.3..1.0);
            }
        }
        self.world.reset_configuration(f.model, &q).map_err(SkillError::from)?;
        Ok(Some([p[0], p[1], face]))
    }

    fn push_at(
        &mut self,
        u: u32,
        v: u32,
        push: &PushSettings,
        execution: Execution,
        rng: &mut Pcg64Mcg,
    ) -> ReLMoGenResult<PushRecord> {
        let mut record = PushRecord {
            pixel: [u, v],
            success: false,
            reason: None,
            moved: 0.0,
            body: None,
        };
        let (p, n, body) = match surface_at_pixel(&self.world, &mut self.camera, Some(self.robot), u.into(), v.into()) {
            Ok(hit) => hit,
            Err(e @ SkillError::Sensor(_)) => return Err(e.into()),
            Err(e) => {
                record.reason = Some(e.reason().into());
                return Ok(record);
            }
        };
        record.body = self.world.body_name(body).map(str::to_owned);
        let before = self.world.body_pose(body).map_err(SkillError::from)?;
        let local = before.inverse() * p;
        let outcome = push_at_point(&mut self.world, &mut self.arm, p, n, body, push, execution, rng);
        record.moved = (self.world.body_pose(body).map_err(SkillError::from)? * local - p).norm();
        match outcome {
            Ok(_) => record.success = true,
            Err(e) => record.reason = Some(e.reason().into()),
        }
        Ok(record)
    }

    /// Writes every location not yet complete in `dir` (format in `docs/relmogen.md`),
    /// calling `progress` after each location.
    ///
    /// # Errors
    /// [`ReLMoGenError::Io`] for files that cannot be written; as [`PushDataset::location`].
    /// ```no_run
    /// use hearth_skills::relmogen::{DatasetSettings, PushDataset};
    /// let home = hearth_sim::scene::SceneFile::load("home.json")?;
    /// let mut data = PushDataset::new(&home, DatasetSettings::default())?;
    /// let summary = data.write("out".as_ref(), |p| eprint!("\\r{}/{}", p.locations_done, p.locations))?;
    /// println!("{} written, {} skipped", summary.written, summary.skipped);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn write(&mut self, dir: &Path, mut progress: impl FnMut(&Progress)) -> ReLMoGenResult<DatasetSummary> {
        std::fs::create_dir_all(dir).map_err(|e| io_error(dir, e))?;
        let meta = serde_json::json!({
            "locations": self.settings.locations,
            "pushes_per_location": self.settings.pushes_per_location,
            "seed": self.settings.seed,
            "execution": self.settings.execution,
            "width": self.settings.width,
            "height": self.settings.height,
            "vfov_deg": self.settings.vfov_deg,
            "push_distance": self.settings.push.distance,
            "min_motion": self.settings.push.min_motion,
        });
        write_atomic(
            &dir.join("dataset.json"),
            serde_json::to_string_pretty(&meta).unwrap_or_default().as_bytes(),
        )?;
        let clock = Instant::now();
        let mut summary = DatasetSummary::default();
        for i in 0..self.settings.locations {
            let folder = location_dir(dir, i);
            if is_complete(&folder, self.settings.pushes_per_location) {
                summary.skipped += 1;
            } else {
                let loc = self.location(i)?;
                write_location(&folder, &loc)?;
                summary.written += 1;
                summary.pushes += loc.index.pushes.len();
                summary.successes += loc.index.pushes.iter().filter(|p| p.success).count();
            }
            summary.seconds = clock.elapsed().as_secs_f64();
            summary.pushes_per_second = if summary.pushes > 0 {
                summary.pushes as f64 / summary.seconds.max(1e-9)
            } else {
                0.0
            };
            progress(&Progress {
                locations_done: i + 1,
                locations: self.settings.locations,
                pushes: summary.pushes,
                pushes_per_second: summary.pushes_per_second,
            });
        }
        Ok(summary)
    }
}

/// The folder of location `i` in `dir`.
///
/// ```
/// let p = hearth_skills::relmogen::location_dir("out".as_ref(), 7);
/// assert!(p.ends_with("loc_00007"));
/// ```
pub fn location_dir(dir: &Path, i: usize) -> PathBuf {
    dir.join(format!("loc_{i:05}"))
}

/// Whether `folder` holds a complete location of `pushes` pushes (its index parses and its
/// image and mask exist).
fn is_complete(folder: &Path, pushes: usize) -> bool {
    let Ok(text) = std::fs::read_to_string(folder.join("pushes.json")) else {
        return false;
    };
    let Ok(index) = serde_json::from_str::<LocationIndex>(&text) else {
        return false;
    };
    index.pushes.len() == pushes && folder.join("rgb.png").is_file() && folder.join("mask.npy").is_file()
}

fn write_location(folder: &Path, loc: &Location) -> ReLMoGenResult<()> {
    std::fs::create_dir_all(folder).map_err(|e| io_error(folder, e))?;
    let (w, h) = (loc.index.width, loc.index.height);
    let rgb_set = ModalitySet::EMPTY.with(Modality::Rgb);
    let mut frame = Frame::default();
    frame.prepare(w, h, rgb_set);
    frame.rgb.copy_from_slice(&loc.rgb);
    frame.save(folder, "").map_err(|e| io_error(folder, e))?;
    for (k, &m) in loc.mask.iter().enumerate() {
        let c = match m {
            1 => [40, 200, 60],
            0 => [220, 40, 40],
            _ => [0, 0, 0],
        };
        frame.rgb[3 * k..3 * k + 3].copy_from_slice(&c);
    }
    frame.save(folder, "mask_").map_err(|e| io_error(folder, e))?;
    write_atomic(&folder.join("mask.npy"), &npy_u8(&loc.mask, h as usize, w as usize))?;
    let json = serde_json::to_string_pretty(&loc.index).map_err(|e| ReLMoGenError::Io {
        path: folder.display().to_string(),
        reason: e.to_string(),
    })?;
    write_atomic(&folder.join("pushes.json"), json.as_bytes())
}

/// Writes through a temporary file and a rename, so a file that exists is whole.
fn write_atomic(path: &Path, bytes: &[u8]) -> ReLMoGenResult<()> {
    let tmp = path.with_extension("tmp");
    std::fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(bytes))
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| io_error(path, e))
}

/// A (h, w) u8 array in NumPy's `.npy` format (version 1.0).
fn npy_u8(data: &[u8], h: usize, w: usize) -> Vec<u8> {
    let mut header = format!("{{'descr': '|u1', 'fortran_order': False, 'shape': ({h}, {w}), }}");
    // Magic (6) + version (2) + length (2) + header + '\n' must be a multiple of 64.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + data.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

/// Reads a mask written by [`PushDataset::write`]: (height, width, values).
///
/// # Errors
/// [`ReLMoGenError::Io`] for a missing file or one that is not a u8 `.npy`.
///
/// ```no_run
/// let (h, w, mask) = hearth_skills::relmogen::read_mask("out/loc_00000/mask.npy".as_ref())?;
/// assert_eq!(mask.len(), h * w);
/// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
/// ```
pub fn read_mask(path: &Path) -> ReLMoGenResult<(usize, usize, Vec<u8>)> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, e))?;
    let not = |why: &str| io_error(path, format!("not a u8 mask .npy: {why}"));
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(not("no magic"));
    }
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(bytes.get(10..10 + len).ok_or_else(|| not("short header"))?)
        .map_err(|_| not("header is not text"))?;
    if !header.contains("'|u1'") {
        return Err(not("dtype is not u1"));
    }
    let shape = header
        .split("'shape': (")
        .nth(1)
        .and_then(|r| r.split(')').next())
        .ok_or_else(|| not("no shape"))?;
    let dims: Vec<usize> = shape
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| not("bad shape"))?;
    let [h, w] = dims[..] else {
        return Err(not("shape is not 2-D"));
    };
    let data = bytes[10 + len..].to_vec();
    if data.len() != h * w {
        return Err(not("size does not match its shape"));
    }
    Ok((h, w, data))
}
