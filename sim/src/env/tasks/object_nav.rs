//! `object_nav`: reach a view in which a target category (e.g. `fridge`) covers at least
//! `visible_fraction` of the camera's semantic (`seg`) image.
//!
//! The success region is estimated once per category, at its first episode: the
//! [viewpoints](super::viewpoints) are the traversable cells from which the robot's camera,
//! turned towards an instance, would see it fill at least the fraction (projected bounding
//! box over the image, scaled by the clear share of sight rays cast against the world). A
//! multi-source distance field from those cells gives the geodesic distance to the nearest
//! view: the shortest path length of SPL, the shaping potential, the `task_obs` distance and
//! the start's `geodesic_range`. When no cell qualifies (or the robot has no default camera)
//! the field falls back to the traversable cells nearest each instance's footprint.

use nalgebra::{Isometry3, Point3};
use rand::RngExt;

use super::field::{DistanceField, cell_center, free_cells};
use super::point_nav::spl;
use super::viewpoints::{Instance, Rig, viewpoints};
use super::{BuildContext, Ending, Metrics, Progress, StepContext, failure, in_planar_frame, xy_of};
use crate::assets::Category;
use crate::env::config::TaskConfig;
use crate::env::error::{EnvError, EnvResult};
use crate::scene::SceneMaps;
use crate::sensors::{Mount, SemanticClass};
use crate::world::{ModelHandle, World};

/// `task_obs` entries: nearest instance x, y in the robot frame, geodesic distance to a view
/// of it, fraction of the image the category covers, its semantic class id, forward speed,
/// yaw rate.
pub(crate) const OBS_LEN: usize = 7;

/// Categories an episode draws from when `target_category` is not set (those present).
const DEFAULT_TARGETS: [Category; 12] = [
    Category::Fridge,
    Category::Stove,
    Category::Sofa,
    Category::Bed,
    Category::Table,
    Category::Toilet,
    Category::Bathtub,
    Category::Bookcase,
    Category::Wardrobe,
    Category::Desk,
    Category::Dresser,
    Category::TvStand,
];

/// One category the task may look for.
#[derive(Clone, Debug)]
struct Target {
    category: Category,
    class: u32,
    /// Footprint centres of its instances (world x, y).
    centers: Vec<[f64; 2]>,
    /// Oriented footprints: (pose, half extents x, y).
    footprints: Vec<(Isometry3<f64>, [f64; 2])>,
    /// Names, poses and boxes of its instances.
    instances: Vec<Instance>,
    /// Built at its first episode: the distance to the nearest viewpoint.
    field: Option<DistanceField>,
    /// The viewpoint cells the field starts from (empty: the footprint fallback).
    views: Vec<usize>,
}

/// The object-navigation task state of one episode.
#[derive(Clone, Debug)]
pub(crate) struct ObjectNav {
    config: TaskConfig,
    targets: Vec<Target>,
    current: usize,
    /// The robot's camera, when it has a default one.
    rig: Option<Rig>,
    robot: ModelHandle,
    pub(crate) start: [f64; 3],
    coverage: f64,
    progress: Progress,
    pub(crate) metrics: Metrics,
}

impl ObjectNav {
    pub(crate) fn new(config: TaskConfig, ctx: &BuildContext<'_>) -> EnvResult<Self> {
        let wanted: Vec<Category> = match &config.target_category {
            Some(name) => Category::from_name(name).into_iter().collect(),
            None => DEFAULT_TARGETS.to_vec(),
        };
        let assets = ctx.home.assets()?;
        let mut targets: Vec<Target> = Vec::new();
        for (object, asset) in ctx.home.objects.iter().zip(&assets) {
            if !wanted.contains(&asset.category) {
                continue;
            }
            let pose = object.pose();
            let mid = (asset.aabb_min + asset.aabb_max) / 2.0;
            let c = pose * Point3::new(mid.x, mid.y, 0.0);
            let half = asset.half_extents();
            let centre_pose = Isometry3::from_parts(nalgebra::Translation3::new(c.x, c.y, 0.0), pose.rotation);
            let entry = match targets.iter_mut().position(|t| t.category == asset.category) {
                Some(i) => &mut targets[i],
                None => {
                    targets.push(Target {
                        category: asset.category,
                        class: SemanticClass::of_category(asset.category),
                        centers: Vec::new(),
                        footprints: Vec::new(),
                        instances: Vec::new(),
                        field: None,
                        views: Vec::new(),
                    });
                    targets.last_mut().expect("just pushed")
                }
            };
            entry.centers.push([c.x, c.y]);
            entry.footprints.push((centre_pose, [half.x, half.y]));
            entry.instances.push(Instance {
                name: object.name.clone(),
                pose,
                min: asset.aabb_min,
                max: asset.aabb_max,
            });
        }
        if targets.is_empty() {
            let (key, what) = match &config.target_category {
                Some(name) => ("task.target_category", format!("the home has no `{name}`")),
                None => (
                    "task.target_category",
                    "the home has none of the default categories".to_owned(),
                ),
            };
            return Err(EnvError::Config {
                key: key.into(),
                reason: what,
            });
        }
        // Categories in a fixed order, so that the same seed draws the same one.
        targets.sort_by_key(|t| t.class);
        Ok(Self {
            config,
            targets,
            current: 0,
            rig: rig_of(ctx),
            robot: ctx.robot,
            start: [0.0; 3],
            coverage: 0.0,
            progress: Progress::default(),
            metrics: Metrics::default(),
        })
    }

    /// The category of the current episode.
    pub(crate) fn category(&self) -> Category {
        self.targets[self.current].category
    }

    /// The nearest instance centre (to the start), on the floor.
    pub(crate) fn goal(&self) -> [f64; 3] {
        let t = &self.targets[self.current];
        let s = [self.start[0], self.start[1]];
        let c = nearest(&t.centers, s);
        [c[0], c[1], 0.0]
    }

    /// The viewpoint cells of the current category (empty before its first episode, or when
    /// the footprint fallback is in use).
    #[cfg(test)]
    pub(crate) fn views(&self) -> &[usize] {
        &self.targets[self.current].views
    }

    /// Draws the category and a start whose geodesic distance to a view of it is in range
    /// (building the category's viewpoints and field at its first episode).
    pub(crate) fn reset(
        &mut self,
        maps: &SceneMaps,
        world: &World,
        rng: &mut rand_pcg::Pcg64Mcg,
    ) -> EnvResult<[f64; 3]> {
        self.current = rng.random_range(0..self.targets.len());
        let t = &mut self.targets[self.current];
        if t.field.is_none() {
            if let Some(rig) = &self.rig {
                let view = world.obstacles_view(&[self.robot])?;
                t.views = viewpoints(maps, rig, &view, &t.instances, self.config.visible_fraction);
            }
            t.field = Some(if t.views.is_empty() {
                footprint_field(maps, &t.footprints)
            } else {
                DistanceField::from_cells(maps, &t.views)
            });
        }
        let field = t.field.as_ref().expect("built above");
        let [lo, hi] = self.config.geodesic_range;
        let starts: Vec<usize> = free_cells(maps)
            .into_iter()
            .filter(|&i| (lo..=hi).contains(&field.cell(i)))
            .collect();
        if starts.is_empty() {
            return Err(EnvError::Task(format!(
                "no start within [{lo}, {hi}] m of a `{}`",
                t.category.name()
            )));
        }
        let s = cell_center(maps, starts[rng.random_range(0..starts.len())]);
        let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        self.start = [s[0], s[1], yaw];
        Ok(self.start)
    }

    fn field(&self) -> Option<&DistanceField> {
        self.targets[self.current].field.as_ref()
    }

    /// The geodesic distance to a view at `xy`, interpolated between cell centres (so the
    /// shaping reward follows the robot's motion rather than jumping at cell borders), or
    /// `fallback` off the field.
    fn potential_at(&self, xy: [f64; 2], fallback: f64) -> f64 {
        self.field()
            .and_then(|f| f.interpolated(xy))
            .filter(|d| d.is_finite())
            .unwrap_or(fallback)
    }

    fn coverage_of(&self, seg: Option<&[u32]>) -> f64 {
        let class = self.targets[self.current].class;
        match seg {
            Some(s) if !s.is_empty() => s.iter().filter(|&&c| c == class).count() as f64 / s.len() as f64,
            _ => 0.0,
        }
    }

    /// Starts the potential at the placed robot.
    pub(crate) fn begin(&mut self, ctx: &StepContext<'_>) {
        let xy = xy_of(&ctx.base);
        let d0 = self.potential_at(xy, 0.0);
        self.coverage = self.coverage_of(ctx.seg);
        self.metrics = Metrics {
            geodesic_distance: d0,
            remaining: d0,
            ..Metrics::default()
        };
        self.progress = Progress::start(xy, d0);
    }

    /// Reward and ending of one step.
    pub(crate) fn step(&mut self, ctx: &StepContext<'_>) -> (f64, Option<Ending>) {
        let potential = self.potential_at(xy_of(&ctx.base), self.metrics.remaining);
        let mut reward = self.progress.step(&self.config, &mut self.metrics, ctx, potential);
        self.coverage = self.coverage_of(ctx.seg);
        let ending = if self.coverage >= self.config.visible_fraction {
            reward += self.config.success_reward;
            self.metrics.success = true;
            self.metrics.spl = spl(&self.metrics);
            Some(Ending::Success)
        } else {
            failure(&self.config, &self.metrics, ctx.on_map)
        };
        (reward, ending)
    }

    /// The `task_obs` entries (see [`OBS_LEN`]).
    pub(crate) fn task_obs(&self, ctx: &StepContext<'_>, v: f64, omega: f64, out: &mut Vec<f32>) {
        let t = &self.targets[self.current];
        let xy = xy_of(&ctx.base);
        let local = in_planar_frame(&ctx.base, nearest(&t.centers, xy));
        out.extend_from_slice(&[
            local[0] as f32,
            local[1] as f32,
            self.potential_at(xy, self.metrics.remaining) as f32,
            self.coverage as f32,
            t.class as f32,
            v as f32,
            omega as f32,
        ]);
    }
}

/// The centre in `centers` nearest to `p`.
fn nearest(centers: &[[f64; 2]], p: [f64; 2]) -> [f64; 2] {
    centers
        .iter()
        .copied()
        .min_by(|a, b| {
            let da = (a[0] - p[0]).hypot(a[1] - p[1]);
            let db = (b[0] - p[0]).hypot(b[1] - p[1]);
            da.total_cmp(&db)
        })
        .unwrap_or(p)
}

/// Distance from `p` to an oriented rectangle (0 inside).
fn rect_distance(pose: &Isometry3<f64>, half: [f64; 2], p: [f64; 2]) -> f64 {
    let local = pose.inverse_transform_point(&Point3::new(p[0], p[1], 0.0));
    let dx = (local.x.abs() - half[0]).max(0.0);
    let dy = (local.y.abs() - half[1]).max(0.0);
    dx.hypot(dy)
}

/// The robot's camera as the viewpoint estimate needs it: the default mount's optical frame in
/// the base frame (measured on the robot as spawned) and the configured intrinsics. `None`
/// when the robot has no default camera.
fn rig_of(ctx: &BuildContext<'_>) -> Option<Rig> {
    let name = ctx.world.model(ctx.robot).ok()?.name().to_owned();
    let camera = Mount::default_camera(&name)?.pose(ctx.world, Some(ctx.robot)).ok()?;
    let base = ctx.world.base_pose(ctx.robot).ok()?;
    Some(Rig {
        view: ctx.camera,
        camera_in_base: base.inverse() * camera,
        base_z: base.translation.z,
    })
}

/// The fallback field: geodesic distances to the traversable cells nearest each footprint
/// (those within one and a half cells of the nearest one).
fn footprint_field(maps: &SceneMaps, footprints: &[(Isometry3<f64>, [f64; 2])]) -> DistanceField {
    let free = free_cells(maps);
    let mut sources = Vec::new();
    for (pose, half) in footprints {
        let d: Vec<f64> = free
            .iter()
            .map(|&i| rect_distance(pose, *half, cell_center(maps, i)))
            .collect();
        let min = d.iter().copied().fold(f64::INFINITY, f64::min);
        if !min.is_finite() {
            continue;
        }
        sources.extend(
            free.iter()
                .zip(&d)
                .filter(|&(_, &di)| di <= min + 1.5 * maps.resolution)
                .map(|(&i, _)| i),
        );
    }
    DistanceField::from_cells(maps, &sources)
}

#[cfg(test)]
mod tests {
    use super::super::viewpoints::{CameraView, box_coverage, camera_at, viewpoints};
    use super::*;
    use crate::scene::{GenerateOptions, MapOptions, SceneFile, generate};
    use crate::world::{LoadedScene, WorldConfig};
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    /// The home, world and maps of `examples/configs/object_nav.toml` (home seed 1, two rooms,
    /// the TurtleBot), built as the env builds them.
    fn home() -> (SceneFile, World, LoadedScene, SceneMaps) {
        let home = generate(&GenerateOptions {
            seed: 1,
            rooms: 2,
            robot: Some("turtlebot".into()),
            small_objects: false,
        })
        .unwrap();
        let mut world = World::new(WorldConfig::default()).unwrap();
        let loaded = world.load_scene(&home).unwrap();
        world.settle(120);
        let maps = SceneMaps::build(
            &home,
            &MapOptions {
                robot_radius: 0.23,
                floor_clearance: 0.008,
                ..MapOptions::default()
            },
        )
        .unwrap();
        (home, world, loaded, maps)
    }

    const CAMERA: CameraView = CameraView {
        vfov_deg: 60.0,
        aspect: 64.0 / 48.0,
        near: 0.05,
        far: 5.0,
    };

    fn fridge_nav(home: &SceneFile, world: &mut World, loaded: &LoadedScene, maps: &SceneMaps) -> ObjectNav {
        let mut config = TaskConfig::named("object_nav");
        config.target_category = Some("fridge".into());
        config.geodesic_range = [1.0, 8.0];
        let robot = loaded.robot.unwrap();
        ObjectNav::new(
            config,
            &BuildContext {
                home,
                loaded,
                world,
                maps,
                robot,
                camera: CAMERA,
            },
        )
        .unwrap()
    }

    /// The potential changes by about as much as the robot moves: creeping 1 mm at a time
    /// from the start, across cell borders, it never jumps by a cell's width.
    #[test]
    fn the_potential_follows_small_moves_across_cell_borders() {
        let (home, mut world, loaded, maps) = home();
        let mut nav = fridge_nav(&home, &mut world, &loaded, &maps);
        let start = nav.reset(&maps, &world, &mut Pcg64Mcg::seed_from_u64(0)).unwrap();
        let field = nav.field().unwrap();
        let (mut worst, mut steps, mut crossed) = (0.0f64, 0, 0);
        for (dx, dy) in [(1.0, 0.0), (0.0, 1.0), (-0.6, 0.8)] {
            let at = |k: f64| [start[0] + dx * k * 1e-3, start[1] + dy * k * 1e-3];
            for k in 0..300 {
                let (a, b) = (at(k as f64), at(k as f64 + 1.0));
                // Only where every cell around both points is reachable: elsewhere the
                // interpolation leaves cells out and may step.
                let reachable = |p: [f64; 2]| {
                    [[-0.5, -0.5], [0.5, -0.5], [-0.5, 0.5], [0.5, 0.5]].iter().all(|o| {
                        let q = [p[0] + o[0] * maps.resolution, p[1] + o[1] * maps.resolution];
                        field.at(q).is_some_and(f64::is_finite)
                    })
                };
                if !(reachable(a) && reachable(b)) {
                    continue;
                }
                if field.at(a) != field.at(b) {
                    crossed += 1;
                }
                let jump = (nav.potential_at(a, f64::NAN) - nav.potential_at(b, f64::NAN)).abs();
                worst = worst.max(jump);
                steps += 1;
            }
        }
        assert!(
            steps > 300 && crossed > 3,
            "{steps} steps, {crossed} cell borders crossed"
        );
        // A 1 mm move changes a distance field whose neighbours differ by at most a diagonal
        // step by at most √2 mm.
        assert!(worst <= 1.5e-3, "a 1 mm move changed the potential by {worst} m");
    }

    #[test]
    fn the_nearest_view_is_closer_than_the_object_and_found_through_walls_only_where_seen() {
        let (home, mut world, loaded, maps) = home();
        let mut nav = fridge_nav(&home, &mut world, &loaded, &maps);
        let start = nav.reset(&maps, &world, &mut Pcg64Mcg::seed_from_u64(0)).unwrap();
        let views = nav.views().to_vec();
        assert!(!views.is_empty(), "the fridge has viewpoints");
        let t = &nav.targets[nav.current];
        let to_view = t.field.as_ref().unwrap().at([start[0], start[1]]).unwrap();
        let to_object = footprint_field(&maps, &t.footprints).at([start[0], start[1]]).unwrap();
        eprintln!(
            "{} viewpoints; from the start {start:?}: {to_view:.2} m to a view, {to_object:.2} m to the fridge",
            views.len()
        );
        assert!(to_view.is_finite() && to_view >= 1.0 && to_view < to_object);
        // The field is 0 exactly on the viewpoints.
        assert!(views.iter().all(|&i| t.field.as_ref().unwrap().cell(i) == 0.0));

        // 1.5 m straight out of the fridge's front, facing it: a viewpoint.
        let fridge = &t.instances[0];
        let front = fridge.pose * Point3::new(fridge.max.x + 1.5, 0.0, 0.0);
        let cell = super::super::field::nearest_free(&maps, [front.x, front.y], 0.4).expect("floor in front");
        assert!(views.contains(&cell), "1.5 m in front of the fridge");

        // At 2 % the corridor next to the kitchen comes within range of the fridge (at 5 % it
        // is too far): there the walls hide it, but for cells seeing it through the doorway.
        let rig = nav.rig.unwrap();
        let view = world.obstacles_view(&[loaded.robot.unwrap()]).unwrap();
        let wide = viewpoints(&maps, &rig, &view, &t.instances, 0.02);
        let room = maps.room_at([front.x, front.y]).unwrap().to_owned();
        let centre = fridge.pose * Point3::from((fridge.min + fridge.max) / 2.0);
        let (mut near_elsewhere, mut seen_elsewhere) = (0, 0);
        for i in free_cells(&maps) {
            let p = cell_center(&maps, i);
            if maps.room_at(p).is_none_or(|r| r == room) {
                continue;
            }
            if box_coverage(&CAMERA, &camera_at(&rig, p, centre), fridge) >= 0.02 {
                near_elsewhere += 1;
                seen_elsewhere += usize::from(wide.binary_search(&i).is_ok());
            }
        }
        eprintln!(
            "at 2 %: {} viewpoints; outside the kitchen {near_elsewhere} cells near enough, {seen_elsewhere} of them viewpoints",
            wide.len()
        );
        assert!(wide.len() > views.len(), "a smaller fraction, a larger region");
        assert!(near_elsewhere > 0, "the corridor comes within range of the fridge");
        assert!(seen_elsewhere * 2 < near_elsewhere, "walls hide the fridge");

        // Same seed, same viewpoints.
        let mut again = fridge_nav(&home, &mut world, &loaded, &maps);
        again.reset(&maps, &world, &mut Pcg64Mcg::seed_from_u64(0)).unwrap();
        assert_eq!(again.views(), views.as_slice());
    }
}
