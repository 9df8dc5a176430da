//! The single-configuration check (FK + every link against the obstacles + self-collision),
//! the hot loop of every planner, on a MotionBenchMaker Panda problem, and for the Fetch's arm
//! over a table in the simulator, through the live world's view and through its scene copy;
//! and the contacts retraction asks for, against parry's own query.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
use hearth_planning::problem::ProblemSet;
use hearth_planning::validity::{RobotValidity, StateValidator};
use rand::SeedableRng;

fn state_validity(c: &mut Criterion) {
    let set = ProblemSet::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../planning/tests/data/panda_table_pick.json"
    ))
    .expect("problem data");
    let problem = set.valid_problems().next().expect("a valid problem");
    let m = RobotModel::builtin("panda").unwrap();
    let arm = Chain::named(&m, "arm").unwrap();
    let acm = SelfCollisionMatrix::compute(
        &m,
        &SelfCollisionSettings {
            samples: 2000,
            ..Default::default()
        },
    );
    let mut v = RobotValidity::new(arm.clone(), acm, Arc::new(problem.scene()));
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    let qs: Vec<Vec<f64>> = (0..256)
        .map(|_| {
            let mut q = vec![0.0; 7];
            arm.random_configuration(&mut rng, &mut q);
            q
        })
        .collect();
    let mut k = 0;
    c.bench_function("state_validity/panda_table_pick_random", |b| {
        b.iter(|| {
            k = (k + 1) & 255;
            black_box(v.is_valid(black_box(&qs[k])))
        })
    });
    c.bench_function("state_validity/panda_table_pick_random_exact", |b| {
        b.iter(|| {
            k = (k + 1) & 255;
            black_box(v.is_valid_exact(black_box(&qs[k])))
        })
    });
    let start = problem.start.clone();
    c.bench_function("state_validity/panda_table_pick_start", |b| {
        b.iter(|| black_box(v.is_valid(black_box(&start))))
    });
    c.bench_function("state_validity/panda_table_pick_start_exact", |b| {
        b.iter(|| black_box(v.is_valid_exact(black_box(&start))))
    });
}

/// The Fetch's torso and arm over a table in a world: random configurations checked against
/// `World::obstacles_view` (rapier's query pipeline) and against its `to_scene` copy.
fn world_validity(c: &mut Criterion) {
    use hearth_sim::assets::{Asset, Category};
    use hearth_sim::scene::{SceneFile, SceneObject};
    use hearth_sim::world::{SpawnOptions, World, WorldConfig};

    let table = Asset::build(Category::Table, 0, 1.0).expect("a table");
    let mut scene = SceneFile::empty("table in front of a fetch");
    scene
        .objects
        .push(SceneObject::new("table", "table", 0, [1.05, 0.0, 0.0]));
    for (name, y) in [("bowl", -0.25), ("mug", 0.0)] {
        let mut o = SceneObject::new(name, name, 0, [0.85, y, table.aabb_max[2]]);
        o.on = Some("table".into());
        scene.objects.push(o);
    }
    let mut world = World::new(WorldConfig::default()).expect("a world");
    world.load_scene(&scene).expect("the scene loads");
    let fetch = RobotModel::builtin("fetch").unwrap();
    let robot = world
        .spawn_model(
            &fetch,
            &nalgebra::Isometry3::translation(0.0, 0.0, 0.02),
            SpawnOptions::fixed(),
        )
        .expect("the fetch spawns");
    world.tuck(robot).expect("tucked");
    world.settle(60);
    let chain = Chain::named(&fetch, "arm_with_torso").unwrap();
    let acm = SelfCollisionMatrix::compute(
        &fetch,
        &SelfCollisionSettings {
            samples: 500,
            ..Default::default()
        },
    );
    // 1 cm of margin: the base stands 2 cm above the floor, which stays in the view.
    let view = world.obstacles_view(&[robot]).expect("a view").with_margin(0.01);
    let full = world.joint_positions(robot).expect("joint positions");
    let base = world.base_pose(robot).expect("a base pose");
    let make = |obstacles: Arc<dyn hearth_planning::obstacles::Obstacles>| {
        let mut v = RobotValidity::new(chain.clone(), acm.clone(), obstacles);
        v.set_reference(&full).expect("a reference");
        v.set_base(base);
        v
    };
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    let qs: Vec<Vec<f64>> = (0..256)
        .map(|_| {
            let mut q = vec![0.0; chain.dof()];
            chain.random_configuration(&mut rng, &mut q);
            q
        })
        .collect();
    // Neither trivially clear nor trivially blocked (a view that kept the floor within the
    // margin would reject every state at the base).
    let mut through_view = make(Arc::new(view.clone()));
    let valid = qs.iter().filter(|q| through_view.is_valid(q)).count();
    assert!((26..230).contains(&valid), "{valid} of 256 states valid");
    for (name, mut v) in [
        ("state_validity/fetch_table_world_view", through_view),
        ("state_validity/fetch_table_scene_copy", make(Arc::new(view.to_scene()))),
    ] {
        let mut k = 0;
        c.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                black_box(v.is_valid(black_box(&qs[k])))
            })
        });
    }
    c.bench_function("world/to_scene_fetch_table", |b| b.iter(|| black_box(view.to_scene())));
}

/// Contacts of overlapping shapes (`obstacles::shape_contact`, which retraction asks for):
/// boxes by the separating-axis test, a cylinder against a box by GJK and the per-thread EPA,
/// each beside parry's `query::contact` on the same 512 seeded pairs.
fn contacts(c: &mut Criterion) {
    use hearth_planning::obstacles::shape_contact;
    use parry3d::math::{Pose, Rotation, Vector};
    use parry3d::shape::{Cuboid, Cylinder, Shape};
    use rand::RngExt;

    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
    let pose = |rng: &mut rand_pcg::Pcg64Mcg, reach: f32| {
        let mut v = || {
            if reach > 0.0 {
                rng.random_range(-reach..reach)
            } else {
                0.0
            }
        };
        let at = Vector::new(v(), v(), v());
        let rot = Rotation::from_rotation_x(rng.random_range(-3.2..3.2))
            * Rotation::from_rotation_y(rng.random_range(-3.2..3.2));
        Pose::from_parts(at, rot)
    };
    let pairs = |rng: &mut rand_pcg::Pcg64Mcg, first: &dyn Fn(&mut rand_pcg::Pcg64Mcg) -> Box<dyn Shape>| {
        let mut out = Vec::new();
        while out.len() < 512 {
            let a = first(rng);
            let h = Vector::new(
                rng.random_range(0.02..0.2),
                rng.random_range(0.02..0.2),
                rng.random_range(0.01..0.05),
            );
            let b: Box<dyn Shape> = Box::new(Cuboid::new(h));
            let (pa, pb) = (pose(rng, 0.0), pose(rng, 0.15));
            if parry3d::query::intersection_test(&pa, a.as_ref(), &pb, b.as_ref())
                .unwrap()
                .intersecting
            {
                out.push((a, pa, b, pb));
            }
        }
        out
    };
    let boxes = pairs(&mut rng, &|rng| {
        let h = Vector::new(
            rng.random_range(0.05..0.15),
            rng.random_range(0.03..0.08),
            rng.random_range(0.03..0.13),
        );
        Box::new(Cuboid::new(h))
    });
    let cylinders = pairs(&mut rng, &|rng| {
        Box::new(Cylinder::new(
            rng.random_range(0.05..0.15),
            rng.random_range(0.03..0.08),
        ))
    });
    for (name, set) in [("box_box", &boxes), ("cylinder_box", &cylinders)] {
        let mut k = 0;
        c.bench_function(&format!("contact/{name}_overlapping"), |b| {
            b.iter(|| {
                k = (k + 1) & 511;
                let (a, pa, o, po) = &set[k];
                black_box(shape_contact(a.as_ref(), pa, o.as_ref(), po, 0.0))
            })
        });
        c.bench_function(&format!("contact/{name}_overlapping_parry"), |b| {
            b.iter(|| {
                k = (k + 1) & 511;
                let (a, pa, o, po) = &set[k];
                black_box(parry3d::query::contact(pa, a.as_ref(), po, o.as_ref(), 0.0))
            })
        });
    }
}

criterion_group!(benches, state_validity, world_validity, contacts);
criterion_main!(benches);
