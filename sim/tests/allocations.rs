//! Checks against the live world do not allocate: a counting global allocator (this test
//! binary only) counts each thread's heap allocations, and state and edge checks of the
//! Fetch's arm over a table set with objects, through `World::obstacles_view`, must make none
//! once warm (the planning crate's `tests/allocations.rs` does the same over a static scene).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::Arc;

use hearth_sim::assets::{Asset, Category};
use hearth_sim::kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_sim::planning::space::{JointSpace, Space};
use hearth_sim::planning::{MotionValidator, RobotValidity, StateValidator};
use hearth_sim::scene::{SceneFile, SceneObject};
use hearth_sim::world::{SpawnOptions, World, WorldConfig};
use nalgebra::Isometry3;
use rand::SeedableRng;

/// The system allocator, counting each thread's allocations and reallocations.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: a thread's last deallocations can run after its counter is gone.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is passed on to `System` unchanged; counting touches only a
// thread-local `Cell` with a constant initialiser, which never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract is `System::alloc`'s.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The allocations this thread makes while running `f`, and `f`'s result.
fn allocations<T>(f: impl FnOnce() -> T) -> (u64, T) {
    let before = ALLOCATIONS.with(Cell::get);
    let out = f();
    (ALLOCATIONS.with(Cell::get) - before, out)
}

#[test]
fn checks_against_the_live_world_do_not_allocate() {
    let table = Asset::build(Category::Table, 0, 1.0).unwrap();
    let top = table.aabb_max[2];
    let mut scene = SceneFile::empty("table in front of a fetch");
    scene
        .objects
        .push(SceneObject::new("table", "table", 0, [0.9, 0.0, 0.0]));
    for (name, category, y) in [("bowl", "bowl", -0.25), ("mug", "mug", 0.0), ("bottle", "bottle", 0.25)] {
        let mut o = SceneObject::new(name, category, 0, [0.7, y, top]);
        o.on = Some("table".into());
        scene.objects.push(o);
    }
    let mut world = World::new(WorldConfig::default()).unwrap();
    world.load_scene(&scene).unwrap();
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(&fetch, &Isometry3::translation(0.0, 0.0, 0.02), SpawnOptions::fixed())
        .unwrap();
    world.tuck(robot).unwrap();
    world.settle(60);

    let model = world.model(robot).unwrap().clone();
    let chain = Chain::named(&model, "arm_with_torso").unwrap();
    let mut reference = world.joint_positions(robot).unwrap();
    for (v, q) in reference.iter_mut().enumerate() {
        *q = q.clamp(model.lower()[v], model.upper()[v]);
    }
    let view = world.obstacles_view(&[robot]).unwrap().with_margin(0.005);
    let matrix = SelfCollisionMatrix::compute(
        &model,
        &SelfCollisionSettings {
            samples: 300,
            ..Default::default()
        },
    );
    let mut v = RobotValidity::new(chain.clone(), matrix, Arc::new(view));
    v.set_reference(&reference).unwrap();
    v.set_base(world.base_pose(robot).unwrap());

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
    // The first pass fills the self-collision certificates its checks land in (a one-off per
    // cell); the counted second pass goes over the same states and edges.
    let mut pass = |v: &mut RobotValidity| {
        let valid = qs.iter().filter(|q| v.is_valid(q)).count();
        let free = qs.windows(2).filter(|p| motions.check_motion(v, &p[0], &p[1])).count();
        (valid, free)
    };
    let warm = pass(&mut v);
    let (n, (valid, free)) = allocations(|| pass(&mut v));
    assert_eq!((valid, free), warm, "the same answers in both passes");
    assert!(
        valid > 0 && valid < qs.len(),
        "the states mix free and colliding ({valid})"
    );
    assert!(free > 0, "some random edges are free");
    assert_eq!(
        n,
        0,
        "{} state and edge checks against the live world allocated {n} times",
        2 * qs.len()
    );
}
