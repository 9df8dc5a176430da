//! Planning against the live world: a BiRRT plan for the Fetch arm over a table with objects,
//! checked through `World::obstacles_view`, smoothed and executed by the joint controllers,
//! reaches its goal without touching anything; so does one made by `MotionPlanner` in one call.
//! Checks through the view allocate nothing (the planning crate's counting allocator is this
//! binary's).

use std::sync::Arc;
use std::time::Duration;

use hearth_sim::assets::{Asset, Category};
use hearth_sim::kinematics::{
    Chain, IkSettings, IkSolver, IkTarget, RobotModel, SelfCollisionMatrix, SelfCollisionSettings,
};
use hearth_sim::planning::goal::PoseGoal;
use hearth_sim::planning::pipeline::{FETCH_WEIGHT_SCHEDULE, MotionPlanner, MotionSettings};
use hearth_sim::planning::shortcut::{ShortcutSettings, Smoothing, smooth};
use hearth_sim::planning::space::{JointSpace, Space};
use hearth_sim::planning::trajectory::{Limits, Trajectory};
use hearth_sim::planning::{BiRrt, Budget, MotionValidator, PlanRequest, Planner, RobotValidity, StateValidator};
use hearth_sim::scene::{SceneFile, SceneObject};
use hearth_sim::world::{LoadedScene, ModelHandle, SpawnOptions, World, WorldConfig};
use nalgebra::{Isometry3, Point3};
use rand::SeedableRng;

#[path = "../../planning/tests/support/counting.rs"]
mod counting;

/// Clearance the planner keeps from obstacles, metres.
const MARGIN: f32 = 0.005;

/// Where the table's centre stands, in front of the robot (metres along +x).
const TABLE_X: f64 = 1.05;

/// A table with a bowl, a mug and a bottle on it, in front of a Fetch bolted 2 cm above the
/// floor (a fixed base needs no floor, and so the floor can stay in the planner's view with
/// the wheels clear of it).
fn table_scene() -> (World, ModelHandle, LoadedScene, f64) {
    let table = Asset::build(Category::Table, 0, 1.0).unwrap();
    let top = table.aabb_max[2];
    let mut scene = SceneFile::empty("table in front of a fetch");
    scene
        .objects
        .push(SceneObject::new("table", "table", 0, [TABLE_X, 0.0, 0.0]));
    for (name, category, y) in [("bowl", "bowl", -0.25), ("mug", "mug", 0.0), ("bottle", "bottle", 0.25)] {
        let mut o = SceneObject::new(name, category, 0, [TABLE_X - 0.2, y, top]);
        o.on = Some("table".into());
        scene.objects.push(o);
    }
    let mut world = World::new(WorldConfig::default()).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    world.settle(120);
    (world, robot, loaded, top)
}

/// The Fetch's torso and arm in the live world (obstacles through `World::obstacles_view`,
/// kept `MARGIN` away), with the measured joints as reference and the tucked arm as start:
/// the chain, the reference, the validity and the start.
fn arm_validity(world: &World, robot: ModelHandle) -> (Chain, Vec<f64>, RobotValidity, Vec<f64>) {
    let model = world.model(robot).unwrap().clone();
    let chain = Chain::named(&model, "arm_with_torso").unwrap();
    let base = world.base_pose(robot).unwrap();
    // Measured joints sit a hair outside their limits where gravity presses them there.
    let mut reference = world.joint_positions(robot).unwrap();
    for (v, q) in reference.iter_mut().enumerate() {
        *q = q.clamp(model.lower()[v], model.upper()[v]);
    }

    // Plans keep 5 mm from everything, so execution never brushes what planning only missed.
    let view = world.obstacles_view(&[robot]).unwrap().with_margin(MARGIN);
    let matrix = SelfCollisionMatrix::compute(
        &model,
        &SelfCollisionSettings {
            samples: 500,
            ..Default::default()
        },
    );
    let mut validity = RobotValidity::new(chain.clone(), matrix, Arc::new(view));
    validity.set_reference(&reference).unwrap();
    validity.set_base(base);
    let mut start = vec![0.0; chain.dof()];
    chain.gather(&reference, &mut start);
    assert!(validity.is_valid(&start), "the tucked arm must start collision-free");
    (chain, reference, validity, start)
}

/// Runs `trajectory` through the robot's joint controllers at the control rate, then holds its
/// end for 30 steps; returns the contacts that pushed on the way (wheels on the floor aside).
fn execute(
    world: &mut World,
    robot: ModelHandle,
    chain: &Chain,
    reference: &[f64],
    trajectory: &Trajectory,
) -> Vec<String> {
    let dt = world.config().control_dt();
    let steps = (trajectory.duration() / dt).ceil() as usize + 30;
    let mut q_chain = vec![0.0; chain.dof()];
    let mut q_full = reference.to_vec();
    let mut touched = Vec::new();
    for k in 1..=steps {
        trajectory.sample((k as f64 * dt).min(trajectory.duration()), &mut q_chain, None);
        chain.scatter(&q_chain, &mut q_full);
        world.set_position_targets(robot, &q_full).unwrap();
        world.step();
        // Contacts that pushed: rapier also lists speculative contacts (no impulse) for
        // bodies within its prediction distance.
        for c in world
            .contacts(robot)
            .unwrap()
            .into_iter()
            .filter(|c| c.force.norm() > 0.0)
        {
            let wheel_on_floor = c.other_name == "ground" && c.link.ends_with("wheel_link");
            if !wheel_on_floor {
                touched.push(format!(
                    "{} touched {} at t = {:.2} s",
                    c.link,
                    c.other_name,
                    world.time()
                ));
            }
        }
    }
    touched
}

#[test]
fn birrt_plan_in_the_live_world_executes_without_contact() {
    let (mut world, robot, loaded, top) = table_scene();
    let objects_before: Vec<_> = loaded.models().map(|m| world.base_pose(m).unwrap()).collect();
    let (chain, reference, mut validity, start) = arm_validity(&world, robot);
    let base = world.base_pose(robot).unwrap();

    // Goal: the gripper 30 cm above the table, between the mug and the bowl, in the robot frame.
    let target_world = Point3::new(TABLE_X - 0.25, -0.12, top + 0.3);
    let target = base.inverse() * target_world;
    let mut ik = IkSolver::new(chain.clone(), "gripper_link", IkSettings::default()).unwrap();
    ik.set_reference(&reference).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    let goal = PoseGoal::new(IkTarget::Position(target))
        .sample(&mut ik, &mut validity, &start, &mut rng)
        .unwrap();

    let space = JointSpace::from_chain(&chain).unwrap();
    let mut motion = MotionValidator::new(space.clone(), 0.02);
    let request = PlanRequest::new(start.clone(), goal);
    let solution = BiRrt::default()
        .plan(&mut motion, &mut validity, &request, &Budget::time(5.0), &mut rng)
        .unwrap();
    let limits = Limits::for_chain(&chain);
    let smoothed = smooth(
        Smoothing::Parabolic,
        &mut motion,
        &mut validity,
        &solution.path,
        &limits,
        &ShortcutSettings::default(),
        Duration::from_secs(1),
        &mut rng,
    )
    .unwrap();
    let trajectory = smoothed.trajectory;
    let goal_q = smoothed.path.states.last().unwrap().clone();

    let touched = execute(&mut world, robot, &chain, &reference, &trajectory);
    assert!(touched.is_empty(), "contacts during execution: {touched:?}");

    let mut reached = vec![0.0; chain.dof()];
    chain.gather(&world.joint_positions(robot).unwrap(), &mut reached);
    for (i, (r, g)) in reached.iter().zip(&goal_q).enumerate() {
        assert!(
            (r - g).abs() < 0.05,
            "{}: reached {r:.3}, goal {g:.3}",
            chain.joint_names()[i]
        );
    }
    let tip = world.link_pose(robot, "gripper_link").unwrap().translation.vector;
    assert!(
        (tip - target_world.coords).norm() < 0.05,
        "the gripper is {:.3} m from its target",
        (tip - target_world.coords).norm()
    );
    // Nothing on the table was knocked.
    for (m, before) in loaded.models().zip(&objects_before) {
        let moved = (world.base_pose(m).unwrap().translation.vector - before.translation.vector).norm();
        assert!(moved < 0.01, "`{}` moved {moved:.3} m", world.model_name(m).unwrap());
    }
}

/// `WorldObstacles::to_scene` answers as the live view does: the same probes touch something
/// (compound furniture is split into its parts, each at its world pose), and a Fetch arm
/// validator gives the same verdict on random configurations through either.
#[test]
fn scene_copy_of_the_view_agrees_with_the_live_view() {
    use hearth_sim::planning::obstacles::Obstacles;
    use parry3d::math::{Pose, Vector};
    use parry3d::shape::{Ball, Cuboid, Cylinder, Shape};
    use rand::RngExt;

    let (world, robot, _, top) = table_scene();
    let model = world.model(robot).unwrap().clone();
    let chain = Chain::named(&model, "arm_with_torso").unwrap();
    let matrix = SelfCollisionMatrix::compute(
        &model,
        &SelfCollisionSettings {
            samples: 300,
            ..Default::default()
        },
    );
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
    for margin in [0.0, 0.01] {
        let view = world.obstacles_view(&[robot]).unwrap().with_margin(margin);
        let scene = view.to_scene();
        assert_eq!(scene.margin(), margin);
        // The table's compound comes apart into its parts, each named after the table.
        let table_parts = scene.obstacles().iter().filter(|o| o.name.contains("table")).count();
        assert!(table_parts > 1, "{table_parts} table obstacles");
        let shapes: [Box<dyn Shape>; 3] = [
            Box::new(Ball::new(0.04)),
            Box::new(Cuboid::new(Vector::new(0.05, 0.02, 0.08))),
            Box::new(Cylinder::new(0.06, 0.03)),
        ];
        let (mut hits, mut misses) = (0, 0);
        for i in 0..3000 {
            let shape = &shapes[i % 3];
            let at = Vector::new(
                rng.random_range(0.4..1.6) as f32,
                rng.random_range(-0.6..0.6) as f32,
                rng.random_range(0.0..top + 0.3) as f32,
            );
            let turn = Vector::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            );
            let pose = Pose::new(at, turn);
            let live = view
                .first_hit(shape.as_ref(), &pose)
                .map(|id| view.name(id).unwrap().to_owned());
            let copy = scene
                .first_hit(shape.as_ref(), &pose)
                .map(|id| scene.name(id).unwrap().to_owned());
            assert_eq!(
                live.is_some(),
                copy.is_some(),
                "probe {i} at {at:?}: {live:?} against {copy:?}"
            );
            if live.is_some() {
                hits += 1;
            } else {
                misses += 1;
            }
            assert_eq!(view.ball_hits(at, 0.04), scene.ball_hits(at, 0.04), "ball at {at:?}");
        }
        assert!(hits > 300 && misses > 300, "{hits} hits, {misses} misses");
        let make = |o: Arc<dyn Obstacles>| {
            let mut v = RobotValidity::new(chain.clone(), matrix.clone(), o);
            v.set_reference(&world.joint_positions(robot).unwrap()).unwrap();
            v.set_base(world.base_pose(robot).unwrap());
            v
        };
        let (mut live, mut copy) = (make(Arc::new(view.clone())), make(Arc::new(scene)));
        let mut q = vec![0.0; chain.dof()];
        let (mut valid, mut differ) = (0, 0);
        for _ in 0..2000 {
            chain.random_configuration(&mut rng, &mut q);
            let verdict = live.is_valid(&q);
            if verdict != copy.is_valid(&q) {
                // Only at contact, where parry's tests of the whole compound and of its part
                // may round differently: some link is within a millimetre (past the margin).
                let gap = nearest_gap(&world, robot, &chain, &view, &q);
                assert!(
                    gap < margin + 1e-3,
                    "margin {margin}: {q:?} disagree {gap} m from contact"
                );
                differ += 1;
            }
            valid += verdict as usize;
        }
        assert!(valid > 200 && valid < 1900, "{valid} of 2000 valid");
        assert!(differ <= 5, "{differ} of 2000 verdicts differ");
    }
}

/// The smallest distance from a link of the robot at chain configuration `q` to the
/// obstacles of `view` (up to 5 cm).
fn nearest_gap(
    world: &World,
    robot: ModelHandle,
    chain: &Chain,
    view: &hearth_sim::world::WorldObstacles,
    q: &[f64],
) -> f32 {
    use hearth_sim::planning::obstacles::Obstacles;
    let model = chain.model();
    let mut full = world.joint_positions(robot).unwrap();
    chain.scatter(q, &mut full);
    let mut poses = vec![Isometry3::identity(); model.links().len()];
    model
        .fk_from(&world.base_pose(robot).unwrap(), &full, &mut poses)
        .unwrap();
    (0..model.links().len())
        .filter_map(|l| {
            let shape = model.link_shape(l)?;
            let pose = hearth_sim::kinematics::to_pose(&(poses[l] * shape.origin));
            view.distance(shape.shape.as_ref(), &pose, 0.05).map(|(d, _)| d)
        })
        .fold(f32::INFINITY, f32::min)
}

/// `MotionPlanner` over the live view, set up as the benchmark plans the Fetch (the reach
/// metric and its weight schedule): the motion to a gripper position above the table passes a
/// check at 0.002 rad against a fresh view of the live world, and the joint controllers carry
/// it out without touching anything.
#[test]
fn motion_planner_in_the_live_world_executes_without_contact() {
    let (mut world, robot, _, top) = table_scene();
    let (chain, reference, mut validity, start) = arm_validity(&world, robot);
    let base = world.base_pose(robot).unwrap();
    // The gripper 25 cm above the table, between the mug and the bottle.
    let target_world = Point3::new(TABLE_X - 0.25, 0.12, top + 0.25);
    let mut ik = IkSolver::new(chain.clone(), "gripper_link", IkSettings::default()).unwrap();
    ik.set_reference(&reference).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let goal = PoseGoal::new(IkTarget::Position(base.inverse() * target_world))
        .sample(&mut ik, &mut validity, &start, &mut rng)
        .unwrap();
    let mut planner = MotionPlanner::new(validity, MotionSettings::default())
        .unwrap()
        .with_weight_schedule(&FETCH_WEIGHT_SCHEDULE)
        .unwrap();
    let motion = planner.plan(&start, goal, &Budget::time(5.0), &mut rng).unwrap();
    let (_, _, mut fresh, _) = arm_validity(&world, robot);
    motion
        .trajectory
        .check(&JointSpace::from_chain(&chain).unwrap(), &mut fresh, 0.002)
        .unwrap();

    let touched = execute(&mut world, robot, &chain, &reference, &motion.trajectory);
    assert!(touched.is_empty(), "contacts during execution: {touched:?}");
    let tip = world.link_pose(robot, "gripper_link").unwrap().translation.vector;
    let off = (tip - target_world.coords).norm();
    assert!(off < 0.05, "the gripper is {off:.3} m from its target");
}

/// State and edge checks of the arm through the live world's view allocate nothing once warm:
/// the first pass fills the self-collision certificates its checks land in (a one-off per
/// cell), and the counted second pass goes over the same states and edges.
#[test]
fn checks_through_the_live_view_do_not_allocate() {
    let (world, robot, _, _) = table_scene();
    let (chain, _, mut v, _) = arm_validity(&world, robot);
    let space = JointSpace::from_chain(&chain).unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    let qs: Vec<Vec<f64>> = (0..1_500)
        .map(|_| {
            let mut q = vec![0.0; space.dim()];
            space.sample(&mut rng, &mut q);
            q
        })
        .collect();
    let mut motions = MotionValidator::new(space, 1.0 / 32.0);
    counting::assert_checks_do_not_allocate("the Fetch's arm over the table", &mut v, &mut motions, &qs);
    // Retractions through the view (`StateValidator::retract`, its contacts through
    // `shape_contact`) allocate nothing either, once their states' cells are warm.
    let mut out = vec![0.0; qs[0].len()];
    let mut retract_all = |v: &mut RobotValidity| qs.iter().filter(|q| v.retract(q, 0.01, 3, &mut out)).count();
    let pushed = retract_all(&mut v);
    let (counted, again) = counting::allocations(|| retract_all(&mut v));
    assert_eq!(counted, 0, "retraction through the live view allocated");
    assert_eq!(again, pushed);
}
