//! # hearth-planning
//!
//! Configuration spaces, collision checking and sampling-based planners (RRT, BiRRT,
//! LazyPRM) with shortcutting, on top of [`hearth_kinematics`].
//!
//! - [`space`]: the [`Space`] trait (sample, distance, interpolate, bounds) for joint spaces
//!   with bounded and continuous joints, SE(2) bases, and compound base + arm spaces.
//! - [`obstacles`]: the [`Obstacles`] seam ("does this shape at this pose touch anything?",
//!   distance, ray cast) and [`ParryScene`], its static implementation over a parry BVH.
//! - [`validity`]: [`StateValidator`] and the exact [`RobotValidity`] (FK + links vs obstacles
//!   + self-collision + attached objects); [`motion`]: edges checked midpoint-first.
//! - [`planner`]: the [`Planner`] trait, [`PlanRequest`], [`Budget`], [`Solution`]; planners
//!   [`Rrt`], [`BiRrt`] (RRT-Connect) and [`LazyPrm`], failing with a typed [`PlanError`];
//!   [`nn`]: exact nearest-neighbour search under any space's metric.
//! - [`goal`]: end-effector pose goals, sampled by collision-aware IK.
//! - [`shortcut`]: repair at a fine resolution, random and acceleration-bounded (parabolic)
//!   shortcutting; [`trajectory`]: timed motions (trapezoids, Ruckig ramps, jerk-limited
//!   motions through waypoints) within per-joint [`trajectory::Limits`].
//! - [`pipeline`]: [`MotionPlanner`], all of the above in one call with the benchmarks'
//!   settings: a start and a goal in, a timed, checked motion out.
//! - [`problem`]: benchmark problem files (MotionBenchMaker JSON).
//!
//! A Panda arm swinging around a post: the straight motion is blocked, [`BiRrt`] finds a way
//! round, and random shortcutting straightens it.
//!
//! ```
//! use std::sync::Arc;
//! use hearth_planning::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
//! use hearth_planning::obstacles::Obstacle;
//! use hearth_planning::shortcut::{self, ShortcutSettings};
//! use hearth_planning::space::JointSpace;
//! use hearth_planning::{BiRrt, Budget, Goal, MotionValidator, ParryScene, PlanRequest, Planner, RobotValidity};
//! use parry3d::math::{Pose, Vector};
//! use rand::SeedableRng;
//!
//! let panda = RobotModel::builtin("panda")?;
//! let arm = Chain::named(&panda, "arm")?;
//! let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
//! let post = Obstacle::cuboid("post", Pose::translation(0.5, 0.0, 0.3), Vector::new(0.05, 0.05, 0.3));
//! let mut validity = RobotValidity::new(arm.clone(), acm, Arc::new(ParryScene::new(vec![post])));
//! let space = JointSpace::from_chain(&arm)?;
//! let mut motion = MotionValidator::new(space.clone(), 0.02);
//!
//! let start = vec![-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
//! let goal = vec![0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785];
//! assert!(!motion.check_motion(&mut validity, &start, &goal)); // through the post
//! let request = PlanRequest::new(start.clone(), Goal::Config(goal.clone()));
//! let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(0);
//! let solution = BiRrt::default().plan(&mut motion, &mut validity, &request, &Budget::iterations(2_000), &mut rng)?;
//! assert_eq!(solution.path.states.first(), Some(&start));
//! assert_eq!(solution.path.states.last(), Some(&goal));
//!
//! let settings = ShortcutSettings { attempts: 20, ..Default::default() };
//! let (short, _) = shortcut::random(&mut motion, &mut validity, &solution.path, &settings, &mut rng);
//! assert!(short.length(&space) < solution.path.length(&space));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

/// The kinematics crate this one builds on (robot models, chains, FK, IK, self-collision).
///
/// ```
/// let panda = hearth_planning::kinematics::RobotModel::builtin("panda").unwrap();
/// assert_eq!(panda.dof(), 8); // seven arm joints and the finger joint
/// ```
pub use hearth_kinematics as kinematics;

pub mod birrt;
pub mod error;
pub mod escape;
pub mod goal;
pub mod lazy_prm;
pub mod motion;
pub mod nn;
pub mod obstacles;
mod pair_lanes;
pub mod pipeline;
pub mod planner;
pub mod problem;
pub mod race;
mod reach;
pub mod rrt;
pub mod shortcut;
pub mod space;
pub mod trajectory;
mod twins;
pub mod validity;

pub use birrt::{BiRrt, Connect, DynamicDomain, Retraction, ShortSteps};
pub use error::PlanError;
pub use escape::Escape;
pub use lazy_prm::{LazyPrm, LazyPrmSettings};
pub use motion::MotionValidator;
pub use nn::NearestNeighbors;
pub use obstacles::{Obstacles, ParryScene};
pub use pipeline::{MotionPlanner, MotionSettings, PlannedMotion};
pub use planner::{Budget, Goal, Path, PlanRequest, PlanStats, Planner, Solution};
pub use race::Race;
pub use rrt::Rrt;
pub use space::Space;
pub use validity::{RobotValidity, StateValidator};
