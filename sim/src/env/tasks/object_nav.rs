//! `object_nav`: reach a view in which a target category (e.g. `fridge`) covers at least
//! `visible_fraction` of the camera's semantic (`seg`) image. The shaping potential is the
//! geodesic distance to the nearest instance: a multi-source distance field from the
//! traversable cells nearest each instance's footprint.

use nalgebra::{Isometry3, Point3};
use rand::RngExt;

use super::field::{DistanceField, cell_center, free_cells};
use super::point_nav::spl;
use super::{BuildContext, Ending, Metrics, Progress, StepContext, failure, in_planar_frame, xy_of};
use crate::assets::Category;
use crate::env::config::TaskConfig;
use crate::env::error::{EnvError, EnvResult};
use crate::scene::SceneMaps;
use crate::sensors::SemanticClass;

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
    /// Built at its first episode.
    field: Option<DistanceField>,
}

/// The object-navigation task state of one episode.
#[derive(Clone, Debug)]
pub(crate) struct ObjectNav {
    config: TaskConfig,
    targets: Vec<Target>,
    current: usize,
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
                        field: None,
                    });
                    targets.last_mut().expect("just pushed")
                }
            };
            entry.centers.push([c.x, c.y]);
            entry.footprints.push((centre_pose, [half.x, half.y]));
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

    /// Draws the category and a start whose geodesic distance to it is in range.
    pub(crate) fn reset(&mut self, maps: &SceneMaps, rng: &mut rand_pcg::Pcg64Mcg) -> EnvResult<[f64; 3]> {
        self.current = rng.random_range(0..self.targets.len());
        let t = &mut self.targets[self.current];
        if t.field.is_none() {
            t.field = Some(view_field(maps, &t.footprints));
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

    fn potential_at(&self, xy: [f64; 2], fallback: f64) -> f64 {
        self.field()
            .and_then(|f| f.at(xy))
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

/// The field of geodesic distances to the traversable cells nearest each footprint (those
/// within one and a half cells of the nearest one).
fn view_field(maps: &SceneMaps, footprints: &[(Isometry3<f64>, [f64; 2])]) -> DistanceField {
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
