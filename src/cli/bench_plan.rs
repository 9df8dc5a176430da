//! `hearth bench plan`: planners on benchmark problem files (MotionBenchMaker JSON), every
//! returned path re-validated at `--fine-resolution` (0.002 rad by default, at most a tenth of
//! the planning resolution) before it counts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use hearth_kinematics::{Chain, DisabledReason, RobotModel, SelfCollisionMatrix, SelfCollisionSettings, wrap_angle};
use hearth_planning::motion::{MAX_SEGMENTS, finest_resolution};
use hearth_planning::pipeline::{FETCH_WEIGHT_SCHEDULE, reach_step, schedule_spaces};
use hearth_planning::problem::{JointsInfo, ProblemSet, load_dir};
use hearth_planning::shortcut::{ShortcutSettings, Smoothing, smooth};
use hearth_planning::space::{JointSpace, Space};
use hearth_planning::trajectory::{Limits, Trajectory};
use hearth_planning::{
    BiRrt, Budget, Connect, DynamicDomain, Escape, Goal, LazyPrm, LazyPrmSettings, MotionValidator, ParryScene,
    PlanRequest, Race, Retraction, RobotValidity, Rrt, ShortSteps, StateValidator,
};
use hearth_sim::randomize::mix;
use hearth_skills::arm::WAYPOINT_SPACING;
use rand::SeedableRng;
use serde_json::{Value, json};

use super::bench::percentile;
use super::weight_schedule::WeightSchedule;

/// Which planner to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PlannerKind {
    /// RRT with goal bias.
    Rrt,
    /// RRT-Connect.
    Birrt,
    /// Lazy PRM (the roadmap is rebuilt for every problem: each has its own obstacles).
    Lazyprm,
}

/// `--weights`: the planning space's distance weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum WeightsArg {
    /// Every joint weighs 1: radians (and metres) as they are, the metric of OMPL and VAMP.
    None,
    /// Each joint weighs how far it can carry the robot's geometry, the largest 1
    /// (`RobotValidity::joint_weights`).
    Reach,
}

/// `--connect`: which tree BiRRT grows along the joining line ([`Connect`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ConnectArg {
    /// The tree that just grew (VAMP's RRT-Connect).
    Onward,
    /// The other tree (OMPL's RRTConnect).
    Other,
}

impl From<ConnectArg> for Connect {
    fn from(c: ConnectArg) -> Self {
        match c {
            ConnectArg::Onward => Connect::Onward,
            ConnectArg::Other => Connect::Other,
        }
    }
}

/// Post-processing of each path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShortcutKind {
    /// None (the path is still repaired at the fine resolution where needed).
    None,
    /// Random shortcutting.
    Random,
    /// Random, then acceleration-bounded (parabolic) shortcutting.
    Parabolic,
}

/// A jerk-limited pass over each smoothed motion, timed and checked at the fine resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum JerkKind {
    /// None (the default).
    None,
    /// The motion's moving average (`Trajectory::with_jerk_limits`).
    Average,
    /// Ruckig's waypoint solver through states of the motion `hearth_skills::arm::WAYPOINT_SPACING`
    /// (0.2 rad) apart, as the arm skills' waypoint pass takes them (`Trajectory::jerk_limited`).
    Waypoints,
}

#[derive(Args, Debug)]
pub struct BenchPlanArgs {
    /// Problem files or folders of them (`joints.json` in a folder is read for limits and
    /// fixed finger positions).
    #[arg(long, num_args = 1.., required = true)]
    problems: Vec<PathBuf>,
    /// Planner.
    #[arg(long, value_enum, default_value_t = PlannerKind::Birrt)]
    planner: PlannerKind,
    /// Plans a robot with the model of a URDF file instead of the built-in one, as
    /// `ROBOT=PATH` (repeatable; ROBOT is the name the problem files give). The file must
    /// have the joints the problems plan; its collision geometry, limits and fixed joints are
    /// used as they are, and the problem set's finger position is applied only where the file
    /// makes that joint movable. For side-by-side runs on another planner's robot model, e.g.
    /// VAMP's sphere model of the Panda (`docs/benchmarks.md`).
    #[arg(long = "urdf", value_name = "ROBOT=PATH")]
    urdf: Vec<String>,
    /// Time limit per plan, in seconds.
    #[arg(long, default_value_t = 1.0)]
    time_limit: f64,
    /// Iteration limit per plan as well (whichever limit comes first). With a time limit
    /// long enough never to end a plan first, every plan is the same on any machine, so two
    /// builds or two machines can be timed on the same plans.
    #[arg(long)]
    iterations: Option<u64>,
    /// Edge-check resolution while planning (joint-space distance between checked states,
    /// rad, in the planning space's metric: see `--weights`). The default, 1/32 rad, is
    /// VAMP's: unweighted, both check edges equally densely; weighted, a joint of weight `w`
    /// is checked every 1/(32·w) rad, no further apart in the workspace.
    #[arg(long, default_value_t = 1.0 / 32.0)]
    resolution: f64,
    /// Resolution of the repair and the final re-check of every path (rad): at most a tenth of
    /// `--resolution` (a larger value is lowered to that). Neither may be finer than the
    /// planning space's diameter over 2²⁰ (`hearth_planning::motion::finest_resolution`: about
    /// 1.2e-5 rad for the Panda's arm), so that no edge takes more than 2²⁰ checks.
    #[arg(long, default_value_t = 0.002)]
    fine_resolution: f64,
    /// Longest planner step (rad, in the planning space's metric: see `--weights`). When
    /// absent: BiRRT takes 0.4 rad for the Fetch and 0.5 rad for the Panda with the joints'
    /// reach as weights (1.2 and 0.65 rad without) and its own default otherwise (0.02 × the
    /// space's extent); RRT takes 6 rad for the Panda and the Fetch and its default otherwise;
    /// LazyPRM 2 rad for the Fetch with the weights (4 rad without) and its default otherwise
    /// (0.2 × the extent, as OMPL). See `docs/planning-log.md`. No shorter than the finest
    /// resolution (`--fine-resolution`).
    #[arg(long)]
    range: Option<f64>,
    /// The planning space's distance weights, its metric for nearest neighbours, steps and
    /// the spacing of edge checks: `none` or `reach` (`RobotValidity::joint_weights`: a wrist
    /// weighs less than a shoulder, so a step moves the robot about equally far whichever
    /// joints it turns). `--range` and the planner's edge checks at `--resolution` are in
    /// that metric; smoothing, the re-check at `--fine-resolution` and the reported path
    /// lengths are not weighted. When absent: `reach`, with which every planner solved more
    /// of the Fetch's problems, and faster. See `docs/planning-log.md`.
    #[arg(long, value_enum)]
    weights: Option<WeightsArg>,
    /// BiRRT only: change the distance weights part-way through each plan
    /// (`BiRrt::plan_with_metrics`; the trees are kept): powers of the joints' reach weights,
    /// each from an iteration on, e.g. `2,1@160000,0.5@360000` (the squared weights first, the
    /// weights themselves from iteration 160,000, their square roots from 360,000). A single
    /// power plans with it throughout; `1` is `--weights reach`. Needs the reach weights and
    /// one thread. When absent: `2,1@160000,0.5@360000` for the Fetch (the squared weights
    /// plan its open and cage problems fastest, milder ones its wedged bookshelf goals), none
    /// for the Panda (the squared weights planned its cage more slowly). See
    /// `docs/planning-log.md`.
    #[arg(long, value_name = "POWER[@ITERATION],...")]
    weight_schedule: Option<WeightSchedule>,
    /// BiRRT only: dynamic-domain sampling with this radius, in multiples of the step (the
    /// minimum radius is a quarter of it). Off by default: see `docs/planning-log.md`.
    #[arg(long)]
    dynamic_domain: Option<f64>,
    /// BiRRT and LazyPRM: turn off the pocket escape (`Escape`: a tree, or a LazyPRM query
    /// end's part of the roadmap, that almost never grows gets a helper tree of short steps),
    /// for comparisons with plain balanced RRT-Connect.
    #[arg(long)]
    no_escape: bool,
    /// BiRRT and LazyPRM: share of the escape helper's turns spent probing short steps to
    /// learn the pocket's free directions (`Escape::probe`; 0 steers every helper step
    /// straight at its sample). When absent: the planner's default.
    #[arg(long)]
    escape_probe: Option<f64>,
    /// BiRRT and LazyPRM: share of a stuck tree's turns given to its escape helper
    /// (`Escape::share`). When absent: the planner's default.
    #[arg(long)]
    escape_share: Option<f64>,
    /// BiRRT and LazyPRM: helper turns without growth after which an escape helper is replaced
    /// by a fresh one (`Escape::reset`; 0 keeps every helper for the whole plan). When absent:
    /// the planner's default.
    #[arg(long)]
    escape_reset: Option<u64>,
    /// BiRRT only: which tree grows along the line joining the trees after an extension:
    /// `other` (the other tree, as OMPL's RRTConnect) or `onward` (the tree that just grew, as
    /// VAMP's). When absent: `other`, which solved more of the Fetch's hardest problems and
    /// planned the Panda's open ones faster. See `docs/planning-log.md`.
    #[arg(long, value_enum)]
    connect: Option<ConnectArg>,
    /// BiRRT only: the step of a wedged tree (one that has grown by fewer than one state per
    /// 500 attempts after 100), as a fraction of the step (`ShortSteps::scale`), in (0, 1];
    /// 1 keeps every step full. When absent: 0.4, the planner's default. See
    /// `docs/planning-log.md`.
    #[arg(long, value_name = "FRACTION")]
    short_steps: Option<f64>,
    /// BiRRT and RRT: retraction out of the obstacles along the contact normals
    /// (`Retraction::every`), 0 off. BiRRT: one blocked step of a wedged tree in this many is
    /// pushed out (when absent: 30, the planner's default). RRT: one in this many goal-zone
    /// samples that land in an obstacle (`Rrt::zone_retraction`; when absent: 4, the
    /// planner's default, for the Panda and other robots, and off for the Fetch, whose tables
    /// and box it slowed 1.5–1.8× without solving more of bookshelf_small). See
    /// `docs/planning-log.md`.
    #[arg(long, value_name = "EVERY")]
    retraction: Option<u64>,
    /// LazyPRM only: whether a wedged start or goal grows greedily, each free growth step going
    /// on towards its sample until blocked (`LazyPrmSettings::tree_connect`): `true` or
    /// `false`. When absent: on for the Fetch, where it solved more of the bookshelf and cage
    /// plans and planned cage's faster, off for the Panda, whose plans it slowed 1.5×, and for
    /// other robots (the planner's default). See `docs/planning-log.md`.
    #[arg(long, value_name = "BOOL")]
    tree_connect: Option<bool>,
    /// RRT only: probability of steering towards a point near a goal (`Rrt::goal_zone`); 0 is
    /// OMPL's RRT. When absent: 0.8 for the Panda and the Fetch, the planner's default (0.1)
    /// otherwise.
    #[arg(long)]
    goal_zone: Option<f64>,
    /// Random configurations per robot whose self-collision certificates are computed before
    /// any plan is timed (`RobotValidity::warm_pair_tables`): plans then run as they do in a
    /// process that has planned before. 0 times every plan from a cold process, as the first
    /// plans of a program run. See `docs/planning-log.md`.
    #[arg(long, default_value_t = 1_000_000)]
    warm_up: usize,
    /// Copies of the planner racing on their own threads per plan (`hearth_planning::Race`:
    /// the path found in the fewest iterations wins, so runs stay reproducible). 1, the
    /// default, plans on one thread, as the peers in `docs/benchmarks.md` do.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    threads: u16,
    /// Path post-processing.
    #[arg(long, value_enum, default_value_t = ShortcutKind::Parabolic)]
    shortcut: ShortcutKind,
    /// Shortcut attempts per stage.
    #[arg(long, default_value_t = 100)]
    shortcut_attempts: usize,
    /// A jerk-limited pass over each smoothed motion that passes the re-check, within the
    /// robot's jerk limits: its time, its duration against the smoothed motion's, and whether
    /// it passes the same re-check (reported apart; a plan's success does not depend on it).
    #[arg(long, value_enum, default_value_t = JerkKind::None)]
    jerk: JerkKind,
    /// RNG seed. Each plan draws from its own stream, mixed from the seed, the problem id and
    /// the repeat: different seeds give unrelated streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Plans per problem (at least 1).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
    /// Only these problems: `FAMILY` (a whole family) or `FAMILY:ID` (one problem), e.g.
    /// `--only table_under_pick:13 cage`.
    #[arg(long, num_args = 1..)]
    only: Vec<String>,
    /// Include every path's waypoints in the JSON.
    #[arg(long)]
    emit_paths: bool,
    /// Write results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// `--urdf` arguments: each robot named, its file and its model, loaded before anything is
/// planned or written. A malformed argument, a robot that no problem file plans or that is
/// named twice, a file that does not load, or a model without the joints a problem set plans
/// is an error.
fn load_urdfs<'a>(
    urdf: &'a [String],
    sets: &[(ProblemSet, Option<PathBuf>)],
) -> anyhow::Result<BTreeMap<&'a str, (&'a Path, RobotModel)>> {
    let mut out = BTreeMap::new();
    for arg in urdf {
        let Some((robot, path)) = arg.split_once('=').filter(|(r, p)| !r.is_empty() && !p.is_empty()) else {
            bail!("--urdf `{arg}`: expected ROBOT=PATH, e.g. panda=panda_spherized.urdf");
        };
        if !sets.iter().any(|(s, _)| s.robot == robot) {
            bail!("--urdf {arg}: no problem file given plans robot `{robot}`");
        }
        if out.contains_key(robot) {
            bail!("--urdf names robot `{robot}` twice");
        }
        let path = Path::new(path);
        let model = RobotModel::from_urdf_file(path).with_context(|| format!("--urdf {arg}"))?;
        for (set, _) in sets.iter().filter(|(s, _)| s.robot == robot) {
            Chain::new(&model, &set.joint_names)
                .with_context(|| format!("--urdf {arg}: the {} problems' joints", set.family))?;
        }
        out.insert(robot, (path, model));
    }
    Ok(out)
}

/// `--only` selectors: (family, optional problem id).
fn parse_selectors(only: &[String]) -> anyhow::Result<Vec<(String, Option<u32>)>> {
    only.iter()
        .map(|s| match s.split_once(':') {
            None if !s.is_empty() => Ok((s.clone(), None)),
            Some((family, id)) if !family.is_empty() => id
                .parse::<u32>()
                .map(|id| (family.to_owned(), Some(id)))
                .map_err(|_| anyhow::anyhow!("--only {s}: `{id}` is not a problem id (expected FAMILY or FAMILY:ID)")),
            _ => bail!("--only `{s}`: expected FAMILY or FAMILY:ID"),
        })
        .collect()
}

/// BiRRT for a robot as the command's arguments set it up. `--range` and `--connect` where
/// given, else this benchmark's settings, measured on MotionBenchMaker (`docs/planning-log.md`):
/// without weights, the Fetch's torso + arm problems are solved more often with a 1.2 rad step
/// than with the planner's 0.26 rad default (94.0 % against 82.8 % in 1 s) and the Panda's
/// fastest with 0.65 rad; with the joints' reach as weights (the default), 0.4 and 0.5 rad
/// (fiftieth round; [`reach_step`] of their eight and seven joints). Both take the planner's
/// connection, [`Connect::Other`]: with [`Connect::Onward`] the Fetch's hardest problems were
/// solved in 54 of 176 plans against 74, and the Panda's open ones were slower. Other robots
/// take the planner's defaults.
fn birrt_for(robot: &str, dof: usize, a: &BenchPlanArgs) -> BiRrt {
    let default_range = match (robot, weighted(a)) {
        ("fetch", false) => Some(1.2),
        ("panda", false) => Some(0.65),
        ("fetch" | "panda", true) => Some(reach_step(dof)),
        _ => None,
    };
    BiRrt {
        range: a.range.or(default_range),
        connect: a.connect.map_or_else(Connect::default, Connect::from),
        dynamic_domain: a.dynamic_domain.map(|radius| DynamicDomain {
            radius,
            min_radius: radius / 4.0,
            ..DynamicDomain::default()
        }),
        escape: escape_for(a),
        short_steps: match a.short_steps {
            Some(scale) if scale >= 1.0 => None,
            Some(scale) => Some(ShortSteps {
                scale,
                ..ShortSteps::default()
            }),
            None => Some(ShortSteps::default()),
        },
        retraction: match a.retraction {
            Some(0) => None,
            Some(every) => Some(Retraction {
                every,
                ..Retraction::default()
            }),
            None => Some(Retraction::default()),
        },
        ..BiRrt::default()
    }
}

/// Whether the planning space takes [`RobotValidity::joint_weights`] (`--weights`; by default
/// it does).
fn weighted(a: &BenchPlanArgs) -> bool {
    a.weights != Some(WeightsArg::None)
}

/// BiRRT's weight schedule (`--weight-schedule`; by default [`FETCH_WEIGHT_SCHEDULE`], the
/// reach weights squared, as they are from iteration 160,000 and their square roots from
/// 360,000, for the Fetch and none for other robots), or `None` to plan in one metric
/// throughout. Only BiRRT with the reach weights on one thread takes one.
fn schedule_for(robot: &str, a: &BenchPlanArgs) -> Option<WeightSchedule> {
    if a.planner != PlannerKind::Birrt || !weighted(a) || a.threads > 1 {
        return None;
    }
    match (&a.weight_schedule, robot) {
        (Some(s), _) => Some(s.clone()),
        (None, "fetch") => Some(WeightSchedule(FETCH_WEIGHT_SCHEDULE.to_vec())),
        (None, _) => None,
    }
}

/// The pocket escape the arguments ask for (BiRRT's and LazyPRM's): `None` with `--no-escape`.
fn escape_for(a: &BenchPlanArgs) -> Option<Escape> {
    (!a.no_escape).then(|| {
        let e = Escape::default();
        Escape {
            probe: a.escape_probe.unwrap_or(e.probe),
            share: a.escape_share.unwrap_or(e.share),
            reset: match a.escape_reset {
                Some(0) => u64::MAX,
                Some(n) => n,
                None => e.reset,
            },
            ..e
        }
    })
}

/// RRT for a robot: `range` and `goal_zone` where given, else this benchmark's settings,
/// measured on MotionBenchMaker (`docs/planning-log.md`): for the Panda and the Fetch a step
/// bounded only by the edge check (6 rad) and four samples in five drawn near a goal solve more
/// problems than the planner's defaults (OMPL's step of 0.2 × the extent, a goal zone of 0.1),
/// which other robots take. (Over six seeds of the Fetch's tables and box, a zone of 0.8
/// solved 1,301 of 1,344 plans within 1 s against 1,287 with 0.5.) The Fetch's zone reaches
/// 0.45 of the step from a goal instead of the planner's 0.3: 1,064 against 1,043 of 1,120
/// plans over five paired seeds, more in each (twenty-third round), and on a 16-core host over
/// nine seeds 1,977 against 1,947 of 2,016 (twenty-fourth round). So does the Panda's: on its
/// bookshelves over seeds 0–5, 1,055 against 1,038 of 1,122 plans, no fewer with any seed
/// (bookshelf_tall 95.8 % or more with every seed, against 94.8 % with two), and on its other
/// five families 735 against 730 of 744 over seeds 0 and 1 (forty-seventh round).
/// `retraction` retracts one colliding goal-zone sample in that many (0: none); when absent,
/// the planner's default, except for the Fetch: none (fifty-seventh round).
fn rrt_for(robot: &str, range: Option<f64>, goal_zone: Option<f64>, retraction: Option<u64>) -> Rrt {
    let planner = Rrt::default();
    let (default_range, default_zone, goal_zone_radius) = match robot {
        "fetch" | "panda" => (Some(6.0), 0.8, 0.45),
        _ => (None, planner.goal_zone, planner.goal_zone_radius),
    };
    Rrt {
        range: range.or(default_range),
        goal_zone: goal_zone.unwrap_or(default_zone),
        goal_zone_radius,
        zone_retraction: match (retraction, robot) {
            (Some(0), _) | (None, "fetch") => None,
            (Some(every), _) => planner.zone_retraction.map(|r| Retraction { every, ..r }),
            (None, _) => planner.zone_retraction,
        },
        ..planner
    }
}

/// LazyPRM's roadmap step for a robot: `range` where given, else this benchmark's setting,
/// measured on MotionBenchMaker (`docs/planning-log.md`, seventeenth round): the Fetch's
/// torso and arm problems are solved more often with 4 rad than with the planner's default of
/// 0.2 × the extent (848 against 807 of 1,068 plans over seeds 0 and 1; bookshelf_small,
/// bookshelf_tall and cage gain, bookshelf_thin loses 3 %); with the joints' reach as weights
/// (the default since the fiftieth round), 2 rad. Other robots, the Panda included, take the
/// default.
fn lazyprm_range(robot: &str, a: &BenchPlanArgs) -> Option<f64> {
    a.range.or(match (robot, weighted(a)) {
        ("fetch", false) => Some(4.0),
        ("fetch", true) => Some(2.0),
        _ => None,
    })
}

/// Whether LazyPRM's wedged query ends grow greedily ([`LazyPrmSettings::tree_connect`]) for a
/// robot: `tree_connect` where given, else as measured on MotionBenchMaker
/// (`docs/planning-log.md`, forty-fifth round): on the Fetch, seeds 0–5, 1,815 of the 1,866
/// bookshelf and cage plans solved against 1,810 and cage plans 0.84× as long (geometric
/// mean); the Panda's plans, short and seldom wedged, take 1.5× as long with it, so it and
/// other robots keep the default (off).
fn lazyprm_connect(robot: &str, tree_connect: Option<bool>) -> bool {
    tree_connect.unwrap_or(robot == "fetch")
}

/// A planner step for the setup line: `4 rad`, or the planner's default when unset.
fn step_text(range: Option<f64>) -> String {
    range.map_or("the planner's default".into(), |r| format!("{r} rad"))
}

/// Whether problem `id` of `family` passes the selectors (all pass when there are none).
fn selected(selectors: &[(String, Option<u32>)], family: &str, id: u32) -> bool {
    selectors.is_empty() || selectors.iter().any(|(f, i)| f == family && i.is_none_or(|i| i == id))
}

struct RobotSetup {
    chain: Chain,
    /// The planning space (weighted or not, see [`weighted`]).
    space: JointSpace,
    /// The joints' reach weights when the planning space takes them.
    reach: Option<Vec<f64>>,
    /// The same space without weights: smoothing, the re-check and the reported path lengths
    /// run in it (radians, and metres for prismatic joints) whatever the planner's metric.
    plain: JointSpace,
    limits: Limits,
    matrix: SelfCollisionMatrix,
    reference: Vec<f64>,
    note: String,
}

/// The robot's chain, self-collision matrix, reference and limits as the problem set describes
/// them, and its planning space: with [`RobotValidity::joint_weights`] as distance weights when
/// `weighted`.
fn setup(
    robot: &str,
    urdf: Option<&(&Path, RobotModel)>,
    joint_names: &[String],
    joints_file: Option<&Path>,
    weighted: bool,
) -> anyhow::Result<RobotSetup> {
    let mut note = String::new();
    let model = match urdf {
        None => RobotModel::builtin(robot)?,
        Some((path, model)) => {
            note.push_str(&format!("model from {}; ", path.display()));
            model.clone()
        }
    };
    let chain = Chain::new(&model, joint_names)?;
    let mut matrix = SelfCollisionMatrix::compute(
        &model,
        &SelfCollisionSettings {
            samples: 2000,
            ..Default::default()
        },
    );
    let mut reference = model.neutral_configuration();
    let info = joints_file
        .map(|path| JointsInfo::load(path).map(|i| (path, i)))
        .transpose()?;
    if let Some((path, info)) = &info
        && info.robot != robot
    {
        note.push_str(&format!(
            "{} describes robot `{}`, not used",
            path.display(),
            info.robot
        ));
    } else if let Some((_, info)) = info {
        for [a, b] in &info.notes.self_collision_allowed_pairs {
            if let (Ok(a), Ok(b)) = (model.link_index(a), model.link_index(b)) {
                matrix.disable(a, b, DisabledReason::Never);
            }
        }
        let fingers: &[&str] = match robot {
            "panda" => &["panda_finger_joint1"],
            "fetch" => &["r_gripper_finger_joint"],
            _ => &[],
        };
        if let Some(values) = info.finger_positions() {
            for (name, &v) in fingers.iter().zip(values) {
                // A model from `--urdf` may fix the fingers or leave them out.
                let var = model.joint_index(name).ok().and_then(|j| model.joints()[j].variable);
                if let Some(var) = var {
                    let clamped = v.clamp(model.lower()[var], model.upper()[var]);
                    reference[var] = clamped;
                    note.push_str(&format!("{name} = {clamped} (problem set: {v}); "));
                }
            }
        }
        note.push_str(&format!(
            "{} allowed pairs from joints.json",
            info.notes.self_collision_allowed_pairs.len()
        ));
    }
    let plain = JointSpace::from_chain(&chain).map_err(|e| anyhow::anyhow!("{e}"))?;
    let reach = weighted.then(|| {
        RobotValidity::new(chain.clone(), matrix.clone(), Arc::new(ParryScene::new(Vec::new()))).joint_weights()
    });
    let space = if let Some(w) = &reach {
        let shown: Vec<String> = w.iter().map(|x| format!("{x:.2}")).collect();
        let sep = if note.is_empty() { "" } else { "; " };
        note.push_str(&format!(
            "{sep}distance weights {} (the joints' reach)",
            shown.join(", ")
        ));
        plain.clone().with_weights(w).map_err(|e| anyhow::anyhow!("{e}"))?
    } else {
        plain.clone()
    };
    Ok(RobotSetup {
        limits: Limits::for_chain(&chain),
        space,
        reach,
        plain,
        chain,
        matrix,
        reference,
        note,
    })
}

/// A plan's statistics in its JSON row, for solved plans and plans stopped by the budget.
fn put_stats(row: &mut Value, stats: &hearth_planning::PlanStats) {
    row["plan_time_s"] = json!(stats.time.as_secs_f64());
    row["plan_checks"] = json!(stats.states_checked);
    row["iterations"] = json!(stats.iterations);
    row["tree_sizes"] = json!(stats.tree_sizes);
}

/// The seed of one plan's random stream: the bench's seed, the problem id and the repeat,
/// mixed ([`mix`], SplitMix64's finaliser, after each) so that no two of them share a stream.
/// (XOR-ing them gave seed 1's repeats 0 and 1 the streams of seed 0's repeats 1 and 0.)
fn plan_seed(seed: u64, id: u32, repeat: u32) -> u64 {
    mix(mix(mix(seed) ^ u64::from(id)) ^ u64::from(repeat))
}

/// Wraps continuous joints into (-π, π] (MBM writes some at ±π plus rounding).
fn wrap_continuous(chain: &Chain, q: &[f64]) -> Vec<f64> {
    q.iter()
        .zip(chain.continuous())
        .map(|(&v, &c)| if c { wrap_angle(v) } else { v })
        .collect()
}

pub fn run(a: BenchPlanArgs) -> anyhow::Result<()> {
    if a.time_limit.is_nan() || a.time_limit <= 0.0 {
        bail!("--time-limit must be positive");
    }
    if [a.resolution, a.fine_resolution]
        .iter()
        .any(|v| !v.is_finite() || *v <= 0.0)
    {
        bail!("--resolution and --fine-resolution must be positive and finite");
    }
    // Paths are repaired and re-checked at least ten times finer than they were planned.
    let fine_resolution = a.fine_resolution.min(a.resolution / 10.0);
    if a.iterations == Some(0) {
        bail!("--iterations must be positive");
    }
    if a.range.is_some_and(|r| r.is_nan() || r <= 0.0) {
        bail!("--range must be positive");
    }
    if a.goal_zone.is_some_and(|z| !(0.0..=0.95).contains(&z)) {
        bail!("--goal-zone must be in [0, 0.95] (RRT's goal bias is 0.05)");
    }
    if a.dynamic_domain.is_some_and(|r| !r.is_finite() || r <= 0.0) {
        bail!("--dynamic-domain must be positive and finite");
    }
    if a.dynamic_domain.is_some() && a.planner != PlannerKind::Birrt {
        bail!("--dynamic-domain applies to --planner birrt only");
    }
    let tunes_escape = a.escape_probe.is_some() || a.escape_share.is_some() || a.escape_reset.is_some();
    if (a.no_escape || tunes_escape) && a.planner == PlannerKind::Rrt {
        bail!(
            "--no-escape, --escape-probe, --escape-share and --escape-reset apply to --planner birrt and lazyprm only"
        );
    }
    if a.escape_probe.is_some_and(|p| !(0.0..1.0).contains(&p)) {
        bail!("--escape-probe must be in [0, 1)");
    }
    if a.escape_share.is_some_and(|s| !(s > 0.0 && s < 1.0)) {
        bail!("--escape-share must be in (0, 1)");
    }
    if a.no_escape && tunes_escape {
        bail!("--escape-probe, --escape-share and --escape-reset set the escape that --no-escape turns off");
    }
    if a.weight_schedule.is_some() {
        if a.planner != PlannerKind::Birrt {
            bail!("--weight-schedule applies to --planner birrt only");
        }
        if !weighted(&a) {
            bail!("--weight-schedule takes powers of the reach weights, which --weights none turns off");
        }
        if a.threads > 1 {
            bail!("--weight-schedule plans on one thread: racing copies (--threads) keep one metric");
        }
    }
    if a.connect.is_some() && a.planner != PlannerKind::Birrt {
        bail!("--connect applies to --planner birrt only");
    }
    if a.short_steps.is_some() && a.planner != PlannerKind::Birrt {
        bail!("--short-steps applies to --planner birrt only");
    }
    if a.short_steps.is_some_and(|s| !(s > 0.0 && s <= 1.0)) {
        bail!("--short-steps must be in (0, 1]");
    }
    if a.retraction.is_some() && a.planner == PlannerKind::Lazyprm {
        bail!("--retraction applies to --planner birrt and rrt only");
    }
    if a.tree_connect.is_some() && a.planner != PlannerKind::Lazyprm {
        bail!("--tree-connect applies to --planner lazyprm only");
    }
    let mut sets: Vec<(ProblemSet, Option<PathBuf>)> = Vec::new();
    for p in &a.problems {
        if p.is_dir() {
            let joints = p.join("joints.json");
            let joints = joints.is_file().then_some(joints);
            for s in load_dir(p)? {
                sets.push((s, joints.clone()));
            }
        } else {
            let s = ProblemSet::load(p)?;
            let joints = p.parent().map(|d| d.join("joints.json")).filter(|j| j.is_file());
            sets.push((s, joints));
        }
    }
    let urdfs = load_urdfs(&a.urdf, &sets)?;
    let selectors = parse_selectors(&a.only)?;
    for (set, _) in &mut sets {
        set.problems.retain(|p| selected(&selectors, &set.family, p.id));
    }
    for (family, id) in &selectors {
        let found = sets
            .iter()
            .any(|(s, _)| &s.family == family && s.problems.iter().any(|p| id.is_none_or(|i| p.id == i)));
        if !found {
            bail!(
                "--only {family}{}: no such problem among the files given",
                id.map(|i| format!(":{i}")).unwrap_or_default()
            );
        }
    }
    if sets.iter().all(|(s, _)| s.problems.is_empty()) {
        let given: Vec<String> = a.problems.iter().map(|p| p.display().to_string()).collect();
        bail!("no problems to plan in {}", given.join(", "));
    }
    // A results file that cannot be written is reported before any plan is run (and after
    // every other input was checked, so that bad input leaves no file behind).
    super::bench::create_json(a.json.as_deref())?;
    let total: usize = sets.iter().map(|(s, _)| s.problems.len()).sum::<usize>() * a.repeat as usize;
    let mut setups: BTreeMap<String, RobotSetup> = BTreeMap::new();
    // Each robot's setup line (fingers, weights, step, schedule), for the JSON file as well.
    let mut setup_lines: BTreeMap<String, String> = BTreeMap::new();
    let mut results = Vec::new();
    let mut done = 0usize;
    let progress = Progress::new(total);
    for (set, joints) in &sets {
        if !setups.contains_key(&set.robot) {
            let s = setup(
                &set.robot,
                urdfs.get(set.robot.as_str()),
                &set.joint_names,
                joints.as_deref(),
                weighted(&a),
            )
            .with_context(|| format!("setting up robot `{}`", set.robot))?;
            // The unweighted space's finest spacing is the coarser of the two (weights are at
            // most 1): the re-check runs in it, the planner in the weighted one.
            let finest = finest_resolution(&s.plain);
            let too_fine = if a.resolution < finest {
                Some(format!("--resolution {:e}", a.resolution))
            } else if let Some(r) = a.range.filter(|&r| r < finest) {
                Some(format!("--range {r:e}"))
            } else {
                (fine_resolution < finest).then(|| {
                    format!(
                        "the re-check spacing {fine_resolution:e} (the finer of --fine-resolution and a tenth of --resolution)"
                    )
                })
            };
            if let Some(what) = too_fine {
                bail!(
                    "{what} is finer than the {} planning space allows: {finest:.3e} at the finest (its diameter over {MAX_SEGMENTS}), so that no edge or straight connection takes more than that many steps",
                    set.robot
                );
            }
            let step = match a.planner {
                PlannerKind::Birrt => {
                    let birrt = birrt_for(&set.robot, set.joint_names.len(), &a);
                    let range = step_text(birrt.range);
                    let connect = match birrt.connect {
                        Connect::Other => "other",
                        Connect::Onward => "onward",
                    };
                    let schedule = schedule_for(&set.robot, &a)
                        .map(|w| format!(", the reach weights to the power {w}"))
                        .unwrap_or_default();
                    format!("BiRRT step {range}, {connect} connection{schedule}")
                }
                PlannerKind::Rrt => {
                    let rrt = rrt_for(&set.robot, a.range, a.goal_zone, a.retraction);
                    let range = step_text(rrt.range);
                    format!(
                        "RRT step {range}, goal zone {} within {} of the step, {}",
                        rrt.goal_zone,
                        rrt.goal_zone_radius,
                        rrt.zone_retraction.map_or_else(
                            || "no zone retraction".to_owned(),
                            |r| format!("one colliding zone sample in {} retracted", r.every)
                        )
                    )
                }
                PlannerKind::Lazyprm => {
                    let range = step_text(lazyprm_range(&set.robot, &a));
                    let greedy = if lazyprm_connect(&set.robot, a.tree_connect) {
                        ", wedged ends grown greedily"
                    } else {
                        ""
                    };
                    format!("LazyPRM step {range}{greedy}")
                }
            };
            let racing = (a.threads > 1).then(|| format!("{} copies racing per plan", a.threads));
            // (Without a joints file next to the problems there is no note.)
            let about: Vec<&str> = [Some(s.note.as_str()), Some(step.as_str()), racing.as_deref()]
                .into_iter()
                .flatten()
                .filter(|part| !part.is_empty())
                .collect();
            let line = about.join("; ");
            eprintln!("{}: {line}", set.robot);
            setup_lines.insert(set.robot.clone(), line);
            if a.warm_up > 0 {
                let mut v =
                    RobotValidity::new(s.chain.clone(), s.matrix.clone(), Arc::new(ParryScene::new(Vec::new())));
                v.set_reference(&s.reference)?;
                let took = v.warm_pair_tables(a.warm_up, a.seed);
                eprintln!(
                    "{}: self-collision certificates warmed with {} random configurations in {:.2} s (not timed)",
                    set.robot,
                    a.warm_up,
                    took.as_secs_f64()
                );
            }
            setups.insert(set.robot.clone(), s);
        }
        let rs = &setups[&set.robot];
        // The planning space, and the spaces a weight schedule switches to (BiRRT only).
        let (space, mut later) = match (&rs.reach, schedule_for(&set.robot, &a)) {
            (Some(reach), Some(schedule)) => schedule_spaces(&rs.plain, reach, &schedule.0)?,
            _ => (rs.space.clone(), Vec::new()),
        };
        let (birrt, rrt) = (
            birrt_for(&set.robot, set.joint_names.len(), &a),
            rrt_for(&set.robot, a.range, a.goal_zone, a.retraction),
        );
        for problem in &set.problems {
            for rep in 0..a.repeat {
                done += 1;
                progress.show(done);
                let mut row = json!({"robot": set.robot, "family": set.family, "id": problem.id, "planner": format!("{:?}", a.planner).to_lowercase(), "repeat": rep});
                if !problem.valid {
                    row["skipped"] = json!("marked invalid in the problem set");
                    results.push(row);
                    continue;
                }
                let mut v = RobotValidity::new(rs.chain.clone(), rs.matrix.clone(), Arc::new(problem.scene()));
                v.set_reference(&rs.reference)?;
                let start = wrap_continuous(&rs.chain, &problem.start);
                // Limits before collisions: a start far outside them would otherwise be
                // reported as whatever its links happen to touch there.
                if let Err(e) = space.check(&start) {
                    row["skipped"] = json!(format!("outside our model's limits: start: {e}"));
                    results.push(row);
                    continue;
                }
                if let Some(c) = v.explain(&start) {
                    row["skipped"] = json!(format!("start collides in our model: {c}"));
                    results.push(row);
                    continue;
                }
                let goals: Vec<Vec<f64>> = problem.goals.iter().map(|g| wrap_continuous(&rs.chain, g)).collect();
                let mut motion = MotionValidator::new(space.clone(), a.resolution);
                let request = PlanRequest::new(start, Goal::AnyOf(goals));
                let budget = match a.iterations {
                    Some(n) => Budget::time(a.time_limit).with_iterations(n),
                    None => Budget::time(a.time_limit),
                };
                let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(plan_seed(a.seed, problem.id, rep));
                let before = v.checks();
                let threads = usize::from(a.threads);
                let outcome = match a.planner {
                    PlannerKind::Rrt => {
                        Race::new(rrt.clone(), threads).plan(&mut motion, &mut v, &request, &budget, &mut rng)
                    }
                    PlannerKind::Birrt if !later.is_empty() => {
                        birrt
                            .clone()
                            .plan_with_metrics(&mut motion, &mut v, &request, &budget, &mut rng, &mut later)
                    }
                    PlannerKind::Birrt => {
                        Race::new(birrt.clone(), threads).plan(&mut motion, &mut v, &request, &budget, &mut rng)
                    }
                    PlannerKind::Lazyprm => Race::new(
                        LazyPrm::new(LazyPrmSettings {
                            range: lazyprm_range(&set.robot, &a),
                            tree_connect: lazyprm_connect(&set.robot, a.tree_connect),
                            escape: escape_for(&a),
                            ..LazyPrmSettings::default()
                        }),
                        threads,
                    )
                    .plan(&mut motion, &mut v, &request, &budget, &mut rng),
                };
                match outcome {
                    Err(hearth_planning::PlanError::InvalidGoals { .. }) => {
                        row["skipped"] = json!("every goal collides in our model");
                    }
                    Err(hearth_planning::PlanError::BadInput(msg)) => {
                        row["skipped"] = json!(format!("outside our model's limits: {msg}"));
                    }
                    Err(e) => {
                        row["success"] = json!(false);
                        row["error"] = json!(e.to_string());
                        row["checks"] = json!(v.checks() - before);
                        // A plan cut off by its budget reports what it did, in the fields a
                        // solved plan has (the summary's medians read solved plans only).
                        if let hearth_planning::PlanError::Timeout { stats } = &e {
                            put_stats(&mut row, stats);
                        }
                    }
                    Ok(sol) => {
                        put_stats(&mut row, &sol.stats);
                        let settings = ShortcutSettings {
                            attempts: a.shortcut_attempts,
                            time_limit: None,
                            // Ramps are checked at the re-check's spacing; a graze between
                            // the two sample sets is caught by the final verification, so
                            // the returned motion passes the very re-check below.
                            fine_resolution: Some(fine_resolution),
                            verify_resolution: Some(fine_resolution),
                        };
                        let smoothing = match a.shortcut {
                            ShortcutKind::None => Smoothing::None,
                            ShortcutKind::Random => Smoothing::Random,
                            ShortcutKind::Parabolic => Smoothing::Parabolic,
                        };
                        let left = (a.time_limit - sol.stats.time.as_secs_f64()).max(0.05);
                        let t0 = Instant::now();
                        // Smoothing, repairs and the re-check run unweighted, whatever the
                        // planner's metric: every state of the motion at most
                        // `fine_resolution` rad from the next, whichever joints move.
                        let mut unweighted = MotionValidator::new(rs.plain.clone(), a.resolution);
                        let smoothed = smooth(
                            smoothing,
                            &mut unweighted,
                            &mut v,
                            &sol.path,
                            &rs.limits,
                            &settings,
                            Duration::try_from_secs_f64(left).unwrap_or(Duration::MAX),
                            &mut rng,
                        );
                        row["shortcut_time_s"] = json!(t0.elapsed().as_secs_f64());
                        row["checks"] = json!(v.checks() - before);
                        match smoothed {
                            Err(e) => {
                                row["success"] = json!(false);
                                row["error"] = json!(match e {
                                    hearth_planning::PlanError::InvalidMotion { .. } => e.to_string(),
                                    _ => format!("repair at the fine resolution failed: {e}"),
                                });
                            }
                            Ok(out) => {
                                // Re-validate the whole timed motion at the fine resolution.
                                let check = out.trajectory.check(&rs.plain, &mut v, fine_resolution);
                                row["success"] = json!(check.is_ok());
                                if let Err(e) = &check {
                                    row["error"] = json!(format!(
                                        "path fails re-validation at the fine resolution: {e} of {:.4} s",
                                        out.trajectory.duration()
                                    ));
                                }
                                row["repaired_edges"] = json!(out.repaired);
                                row["smoothing_fell_back"] = json!(out.fell_back);
                                // (`--resolution` was checked to be positive and finite.)
                                row["path_length"] = json!(out.trajectory.length(&rs.plain, a.resolution)?);
                                row["duration_s"] = json!(out.trajectory.duration());
                                if check.is_ok() && a.jerk != JerkKind::None {
                                    let t0 = Instant::now();
                                    let jerk = match a.jerk {
                                        JerkKind::Average => out.trajectory.with_jerk_limits(&rs.limits),
                                        JerkKind::Waypoints | JerkKind::None => out
                                            .trajectory
                                            .to_path(&rs.plain, WAYPOINT_SPACING)
                                            .and_then(|waypoints| {
                                                Trajectory::jerk_limited(&rs.plain, &waypoints, &rs.limits)
                                            }),
                                    };
                                    row["jerk_time_s"] = json!(t0.elapsed().as_secs_f64());
                                    if let Ok(j) = jerk {
                                        row["jerk_duration_s"] = json!(j.duration());
                                        row["jerk_valid"] = json!(j.check(&rs.plain, &mut v, fine_resolution).is_ok());
                                    } else {
                                        row["jerk_valid"] = json!(false);
                                    }
                                }
                                if a.emit_paths {
                                    row["path"] = json!(out.path.states);
                                }
                            }
                        }
                    }
                }
                results.push(row);
            }
        }
    }
    progress.finish();
    // Summary per family, then over all families; labelled `robot/family` (and `robot/all`)
    // when the run covers several robots, as two robots' families can share a name.
    let robots: std::collections::BTreeSet<&str> = results.iter().filter_map(|r| r["robot"].as_str()).collect();
    let label = |robot: &str, family: &str| {
        if robots.len() > 1 {
            format!("{robot}/{family}")
        } else {
            family.to_owned()
        }
    };
    let mut groups: BTreeMap<(String, String), Vec<&Value>> = BTreeMap::new();
    for r in &results {
        let robot = r["robot"].as_str().unwrap_or("?").to_owned();
        let family = r["family"].as_str().unwrap_or("?").to_owned();
        groups.entry((robot, family)).or_default().push(r);
    }
    println!(
        "{:<22} {:>6} {:>7} {:>9} {:>8} {:>11} {:>11} {:>9} {:>11} {:>9} {:>9}",
        "family",
        "plans",
        "skipped",
        "solved",
        "success",
        "median ms",
        "p95 ms",
        "length",
        "shortcut ms",
        "motion s",
        "checks"
    );
    let mut summary = serde_json::Map::new();
    for ((robot, family), rows) in &groups {
        let name = label(robot, family);
        summary.insert(name.clone(), summarize(&name, rows));
    }
    for robot in &robots {
        let rows: Vec<&Value> = results.iter().filter(|r| r["robot"].as_str() == Some(*robot)).collect();
        let name = label(robot, "all");
        summary.insert(name.clone(), summarize(&name, &rows));
    }
    if a.jerk != JerkKind::None {
        println!(
            "\n{:<22} {:>15} {:>11} {:>11} {:>16}",
            "jerk pass", "collision-free", "median ms", "p90 ms", "duration ratio"
        );
        for (name, s) in &summary {
            let j = &s["jerk_pass"];
            if let (Some(n), Some(free)) = (j["motions"].as_u64(), j["collision_free"].as_u64()) {
                let f = |key: &str, digits: usize| j[key].as_f64().map_or("-".to_owned(), |v| format!("{v:.digits$}"));
                println!(
                    "{:<22} {:>15} {:>11} {:>11} {:>16}",
                    name,
                    format!("{free}/{n}"),
                    f("time_ms_median", 3),
                    f("time_ms_p90", 3),
                    f("duration_ratio_median", 3)
                );
            }
        }
    }
    if let Some(path) = a.json {
        let out = json!({"results": results, "summary": summary, "setup": setup_lines});
        std::fs::write(&path, serde_json::to_string(&out)?).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// One summary row (printed) and its JSON entry, for the plans `rows` of one group.
fn summarize(name: &str, rows: &[&Value]) -> Value {
    let attempted: Vec<&Value> = rows.iter().copied().filter(|r| r.get("skipped").is_none()).collect();
    let ok: Vec<&Value> = attempted
        .iter()
        .copied()
        .filter(|r| r["success"] == json!(true))
        .collect();
    // One numeric field of the successful rows, scaled.
    let column =
        |key: &str, scale: f64| -> Vec<f64> { ok.iter().filter_map(|r| r[key].as_f64()).map(|v| v * scale).collect() };
    let times = column("plan_time_s", 1e3);
    let (time_median, time_p95) = (percentile(&times, 0.5), percentile(&times, 0.95));
    let length = percentile(&column("path_length", 1.0), 0.5);
    let checks = percentile(&column("checks", 1.0), 0.5);
    let shortcut = percentile(&column("shortcut_time_s", 1e3), 0.5);
    let duration = percentile(&column("duration_s", 1.0), 0.5);
    // No rate when nothing was attempted (every plan skipped).
    let rate = (!attempted.is_empty()).then(|| ok.len() as f64 / attempted.len() as f64);
    let fell_back = ok.iter().filter(|r| r["smoothing_fell_back"] == json!(true)).count();
    let jerk_rows: Vec<&Value> = ok.iter().copied().filter(|r| r.get("jerk_valid").is_some()).collect();
    let jerk = (!jerk_rows.is_empty()).then(|| {
        let valid = jerk_rows.iter().filter(|r| r["jerk_valid"] == json!(true)).count();
        let ms: Vec<f64> = jerk_rows
            .iter()
            .filter_map(|r| r["jerk_time_s"].as_f64())
            .map(|t| t * 1e3)
            .collect();
        let ratio: Vec<f64> = jerk_rows
            .iter()
            .filter_map(|r| Some(r["jerk_duration_s"].as_f64()? / r["duration_s"].as_f64()?))
            .collect();
        json!({"motions": jerk_rows.len(), "collision_free": valid,
               "time_ms_median": percentile(&ms, 0.5), "time_ms_p90": percentile(&ms, 0.9),
               "duration_ratio_median": percentile(&ratio, 0.5)})
    });
    // A column without successful plans (NaN) prints as "-".
    let cell = |v: f64, digits: usize| {
        if v.is_nan() {
            "-".to_owned()
        } else {
            format!("{v:.digits$}")
        }
    };
    println!(
        "{:<22} {:>6} {:>7} {:>9} {:>8} {:>11} {:>11} {:>9} {:>11} {:>9} {:>9}",
        name,
        rows.len(),
        rows.len() - attempted.len(),
        format!("{}/{}", ok.len(), attempted.len()),
        rate.map_or("-".to_owned(), |r| format!("{:.1}%", 100.0 * r)),
        cell(time_median, 3),
        cell(time_p95, 3),
        cell(length, 3),
        cell(shortcut, 3),
        cell(duration, 3),
        cell(checks, 0)
    );
    json!({"plans": rows.len(), "skipped": rows.len() - attempted.len(), "solved": ok.len(), "attempted": attempted.len(),
           "success_rate": rate,
           "plan_time_ms_median": time_median, "plan_time_ms_p95": time_p95,
           "path_length_median": length, "checks_median": checks,
           "shortcut_time_ms_median": shortcut, "motion_duration_s_median": duration,
           "smoothing_fell_back": fell_back, "jerk_pass": jerk})
}

/// Progress on stderr: one line rewritten in place on a terminal; otherwise (a log file, a
/// pipe) a line at every tenth of the run, so logs stay readable.
struct Progress {
    total: usize,
    terminal: bool,
}

impl Progress {
    fn new(total: usize) -> Self {
        use std::io::IsTerminal;
        Self {
            total,
            terminal: std::io::stderr().is_terminal(),
        }
    }

    fn show(&self, done: usize) {
        if self.terminal {
            if done.is_multiple_of(10) || done == self.total {
                eprint!("\r{done}/{} plans", self.total);
            }
        } else if done * 10 / self.total.max(1) > (done - 1) * 10 / self.total.max(1) {
            eprintln!("{done}/{} plans", self.total);
        }
    }

    fn finish(&self) {
        if self.terminal {
            eprintln!();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::plan_seed;

    #[test]
    fn every_plan_draws_its_own_stream() {
        let mut seen = std::collections::HashSet::new();
        for seed in 0..8 {
            for id in [1, 2, 100] {
                for repeat in 0..8 {
                    assert!(seen.insert(plan_seed(seed, id, repeat)), "{seed} {id} {repeat}");
                }
            }
        }
        assert_eq!(plan_seed(3, 7, 1), plan_seed(3, 7, 1));
    }
}
