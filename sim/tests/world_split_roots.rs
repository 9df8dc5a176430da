//! Furniture whose root is split off its multibody (`World::spawn_model`): a free root body
//! and its mount move as one, the model keeps its mass, its own links never touch its root, its
//! drawers still slide, and snapshots replay it exactly; a fixed root hangs its multibody from
//! a fixed mount, and its drawers and doors still move.

use hearth_sim::kinematics::JointKind;
use hearth_sim::scene::{SceneFile, SceneObject};
use hearth_sim::world::{BodyId, JointCommand, LoadedScene, ModelHandle, World, WorldConfig};
use nalgebra::{Isometry3, Vector3};

/// A free dresser and a fixed bottom cabinet side by side, a crate on the dresser's top.
fn furniture() -> (World, LoadedScene, BodyId) {
    furniture_with(WorldConfig::default())
}

fn furniture_with(config: WorldConfig) -> (World, LoadedScene, BodyId) {
    let mut scene = SceneFile::empty("split roots");
    scene
        .objects
        .push(SceneObject::new("dresser", "dresser", 0, [0.0, 0.0, 0.0]));
    let mut cabinet = SceneObject::new("cabinet", "bottom_cabinet", 1, [2.0, 0.0, 0.0]);
    cabinet.fixed = true;
    scene.objects.push(cabinet);
    let mut world = World::new(config).unwrap();
    let loaded = world.load_scene(&scene).unwrap();
    let dresser = loaded.object("dresser").unwrap();
    let root = world.model(dresser).unwrap().links()[0].name.clone();
    let top = world.link_pose(dresser, &root).unwrap().translation.z;
    let height = top + dresser_height(&world, dresser);
    let crate_box = world
        .add_box(
            "crate",
            [0.05, 0.05, 0.05],
            &Isometry3::translation(0.0, 0.0, height + 0.1),
            true,
        )
        .unwrap();
    (world, loaded, crate_box)
}

/// Height of the dresser's collision boxes above its root frame.
fn dresser_height(world: &World, dresser: ModelHandle) -> f64 {
    let model = world.model(dresser).unwrap();
    let root = &model.links()[0].name;
    let body = world.link_body(dresser, root).unwrap();
    let rb = &world.bodies()[body.handle()];
    let pose = rb.position();
    rb.colliders()
        .iter()
        .map(|&c| f64::from(world.colliders()[c].compute_aabb().maxs.z - pose.translation.z))
        .fold(0.0, f64::max)
}

fn prismatic_variables(world: &World, h: ModelHandle) -> Vec<usize> {
    let model = world.model(h).unwrap();
    model
        .joints()
        .iter()
        .filter(|j| j.kind == JointKind::Prismatic)
        .filter_map(|j| j.variable)
        .collect()
}

/// Whether any collider of `a` has active contacts with a collider of `b`.
/// Drives variable `v` of `h` with 20 N (or N·m) of effort for 30 steps; its new position.
fn push_joint(world: &mut World, h: ModelHandle, v: usize) -> f64 {
    let name = world.model(h).unwrap().variable_names()[v].clone();
    world
        .set_joint_command(h, &name, JointCommand::Effort { value: 20.0 })
        .unwrap();
    for _ in 0..30 {
        world.step();
    }
    world.joint_positions(h).unwrap()[v]
}

/// The body holding a model's root link.
fn root_body(world: &World, h: ModelHandle) -> BodyId {
    let root = world.model(h).unwrap().links()[0].name.clone();
    world.link_body(h, &root).unwrap()
}

fn touching(world: &World, a: BodyId, b: BodyId) -> bool {
    world.narrow_phase().contact_pairs().any(|pair| {
        let parent = |c| world.colliders().get(c).and_then(|co| co.parent());
        let (p1, p2) = (parent(pair.collider1), parent(pair.collider2));
        pair.has_any_active_contact()
            && ((p1 == Some(a.handle()) && p2 == Some(b.handle()))
                || (p1 == Some(b.handle()) && p2 == Some(a.handle())))
    })
}

#[test]
fn a_split_model_keeps_its_mass_and_never_touches_itself() {
    let (mut world, loaded, crate_box) = furniture();
    for _ in 0..60 {
        world.step();
    }
    for name in ["dresser", "cabinet"] {
        let h = loaded.object(name).unwrap();
        let model = world.model(h).unwrap().clone();
        let urdf_mass: f64 = model
            .links()
            .iter()
            .filter_map(|l| l.inertial.as_ref())
            .map(|i| i.mass)
            .sum();
        let bodies = world.model_bodies(h).unwrap();
        // Root, one body per moving joint, and the mount.
        let moving = model.joints().iter().filter(|j| j.kind != JointKind::Fixed).count();
        assert_eq!(bodies.len(), moving + 2, "{name}");
        if name == "dresser" {
            let sim_mass: f64 = bodies
                .iter()
                .map(|b| f64::from(world.bodies()[b.handle()].mass()))
                .sum();
            assert!(
                (sim_mass - urdf_mass).abs() < 1e-3 * urdf_mass,
                "{name}: {sim_mass} kg simulated, {urdf_mass} kg in the URDF"
            );
        }
        let root = root_body(&world, h);
        for &b in &bodies {
            assert!(
                !touching(&world, root, b),
                "{name}: the root touches its own body {b:?}"
            );
        }
    }
    // The crate rests on the dresser's root: a contact the filter keeps.
    let dresser = loaded.object("dresser").unwrap();
    let root = root_body(&world, dresser);
    assert!(touching(&world, root, crate_box), "the crate rests on the dresser");
}

#[test]
fn free_furniture_moves_as_one_and_its_drawers_still_slide() {
    let (mut world, loaded, _) = furniture();
    let dresser = loaded.object("dresser").unwrap();
    for _ in 0..30 {
        world.step();
    }
    let start = world.base_pose(dresser).unwrap();
    let drawers = prismatic_variables(&world, dresser);
    assert!(!drawers.is_empty());
    let v = drawers[0];
    let model = world.model(dresser).unwrap().clone();
    let joint = model.joints().iter().find(|j| j.variable == Some(v)).unwrap().clone();
    let drawer_link = model.links()[joint.child].name.clone();
    let name = model.variable_names()[v].clone();
    let q = push_joint(&mut world, dresser, v);
    assert!(
        q > 0.5 * model.upper()[v],
        "the drawer slid open to {q} (upper limit {})",
        model.upper()[v]
    );
    world.set_joint_command(dresser, &name, JointCommand::Off).unwrap();
    // The drawer's pose agrees with the root body's pose and the joint position.
    let check_drawer = |world: &World| {
        let q = world.joint_positions(dresser).unwrap()[v];
        let mut qs = world.model(dresser).unwrap().neutral_configuration();
        qs[v] = q;
        let base = world.base_pose(dresser).unwrap();
        let link = world.link_pose(dresser, &drawer_link).unwrap();
        let mut poses = model.pose_buffer();
        let mut q_all = world.joint_positions(dresser).unwrap();
        q_all[v] = q;
        model.fk(&q_all, &mut poses).unwrap();
        let expected = base * poses[joint.child];
        let err = (expected.translation.vector - link.translation.vector).norm();
        assert!(err < 5e-3, "drawer {err} m away from where its joint puts it");
    };
    check_drawer(&world);
    // Move the whole dresser: the root body, its mount and its links go together.
    let moved = Isometry3::translation(0.5, 0.3, 0.0) * start;
    world.place(dresser, &moved).unwrap();
    for _ in 0..30 {
        world.step();
    }
    let now = world.base_pose(dresser).unwrap();
    let shift: Vector3<f64> = now.translation.vector - start.translation.vector;
    assert!(
        (shift.x - 0.5).abs() < 0.02 && (shift.y - 0.3).abs() < 0.02,
        "moved by {shift:?}"
    );
    check_drawer(&world);
}

#[test]
fn fixed_furniture_hangs_from_a_fixed_mount_and_its_joints_still_move() {
    let (mut world, loaded, _) = furniture();
    let cabinet = loaded.object("cabinet").unwrap();
    let model = world.model(cabinet).unwrap().clone();
    let root = root_body(&world, cabinet);
    let bodies = world.model_bodies(cabinet).unwrap();
    // The root (with colliders) and the collider-less mount are both fixed.
    let fixed: Vec<_> = bodies
        .iter()
        .filter(|b| world.bodies()[b.handle()].is_fixed())
        .collect();
    assert_eq!(fixed.len(), 2, "root and mount are fixed");
    assert!(!world.bodies()[root.handle()].colliders().is_empty());
    let joint = model
        .joints()
        .iter()
        .find(|j| j.kind != JointKind::Fixed)
        .unwrap()
        .clone();
    let v = joint.variable.unwrap();
    let name = model.variable_names()[v].clone();
    let before = world.joint_positions(cabinet).unwrap()[v];
    let q = push_joint(&mut world, cabinet, v);
    assert!(q > before + 0.05, "`{name}` moved from {before} to {q}");
    // The link sits where the joint puts it, relative to the fixed root.
    let base = world.base_pose(cabinet).unwrap();
    let mut poses = model.pose_buffer();
    model.fk(&world.joint_positions(cabinet).unwrap(), &mut poses).unwrap();
    let link = world.link_pose(cabinet, &model.links()[joint.child].name).unwrap();
    let err = ((base * poses[joint.child]).translation.vector - link.translation.vector).norm();
    assert!(err < 5e-3, "`{name}`'s link is {err} m from where its joint puts it");
    // The root never touches its own links, and did not move.
    for &b in &bodies {
        assert!(!touching(&world, root, b), "the root touches its own body {b:?}");
    }
    assert!((base.translation.vector - Vector3::new(2.0, 0.0, 0.0)).norm() < 1e-6);
}

#[test]
fn snapshots_replay_split_furniture_exactly() {
    let (mut world, loaded, _) = furniture();
    let dresser = loaded.object("dresser").unwrap();
    let v = prismatic_variables(&world, dresser)[0];
    let name = world.model(dresser).unwrap().variable_names()[v].clone();
    world
        .set_joint_command(dresser, &name, JointCommand::Effort { value: 15.0 })
        .unwrap();
    let snap = world.snapshot();
    for _ in 0..20 {
        world.step();
    }
    let first = world.state_hash();
    world.restore(&snap).unwrap();
    for _ in 0..20 {
        world.step();
    }
    assert_eq!(world.state_hash(), first);
}

#[test]
fn mass_randomization_keeps_a_split_root_shared_half_and_half() {
    use hearth_sim::randomize::{PhysicsRandomization, randomize_physics};
    use rand::SeedableRng;
    let (mut world, loaded, _) = furniture();
    let dresser = loaded.object("dresser").unwrap();
    let root = root_body(&world, dresser);
    // The mount is the one body of the model without colliders.
    let mount = world
        .model_bodies(dresser)
        .unwrap()
        .into_iter()
        .find(|b| world.bodies()[b.handle()].colliders().is_empty())
        .expect("a free dresser has a mount");
    let half0 = world.body_mass(root).unwrap();
    assert!((world.body_mass(mount).unwrap() - half0).abs() < 1e-4 * half0);
    let cfg = PhysicsRandomization {
        enabled: true,
        mass: true,
        ..Default::default()
    };
    randomize_physics(&mut world, &loaded, &cfg, &mut rand_pcg::Pcg64Mcg::seed_from_u64(4)).unwrap();
    let half = world.body_mass(root).unwrap();
    assert!((half - half0).abs() > 1e-6 * half0, "the mass was drawn anew");
    assert!((world.body_mass(mount).unwrap() - half).abs() < 1e-4 * half);
}

#[test]
fn without_the_split_furniture_is_one_multibody() {
    let config = WorldConfig {
        split_roots: false,
        ..WorldConfig::default()
    };
    let (mut world, loaded, _) = furniture_with(config);
    let dresser = loaded.object("dresser").unwrap();
    let model = world.model(dresser).unwrap().clone();
    let moving = model.joints().iter().filter(|j| j.kind != JointKind::Fixed).count();
    let bodies = world.model_bodies(dresser).unwrap();
    assert_eq!(bodies.len(), moving + 1, "no mount");
    assert!(
        bodies
            .iter()
            .all(|b| !world.bodies()[b.handle()].colliders().is_empty())
    );
    for _ in 0..10 {
        world.step();
    }
    assert!(world.base_pose(dresser).unwrap().translation.z.abs() < 0.01);
}
