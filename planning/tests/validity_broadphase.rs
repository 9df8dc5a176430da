//! The broad phase inside `RobotValidity::is_valid` (bounding spheres, hint ordering) must never
//! change an answer: compare it with a brute-force exact reference written here.

use std::sync::Arc;

use hearth_kinematics::{
    Chain, LoadOptions, MeshCollision, RobotModel, SelfCollisionMatrix, SelfCollisionSettings, links_touch, to_pose,
};
use hearth_planning::obstacles::{Obstacle, ParryScene};
use hearth_planning::problem::ProblemSet;
use hearth_planning::validity::{RobotValidity, StateValidator};
use nalgebra::Isometry3;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query;
use parry3d::shape::SharedShape;
use rand::{RngExt, SeedableRng};

/// Every geometric link against every obstacle (exact parry test on the link shape), then every
/// checked self-collision pair with `links_touch`.
struct Reference {
    model: RobotModel,
    chain: Chain,
    pairs: Vec<(usize, usize)>,
    scene: ParryScene,
    q_full: Vec<f64>,
    poses: Vec<Isometry3<f64>>,
    /// Where the robot's root stands (identity unless a test moves it).
    base: Isometry3<f64>,
}

impl Reference {
    fn new(chain: &Chain, acm: &SelfCollisionMatrix, scene: ParryScene) -> Self {
        let model = chain.model().clone();
        Self {
            pairs: acm.checked_geometric_pairs(&model),
            q_full: model.neutral_configuration(),
            poses: model.pose_buffer(),
            chain: chain.clone(),
            model,
            scene,
            base: Isometry3::identity(),
        }
    }

    /// Poses every link at `q` (in `poses`).
    fn pose(&mut self, q: &[f64]) {
        self.chain.scatter(q, &mut self.q_full);
        self.model.fk_from(&self.base, &self.q_full, &mut self.poses).unwrap();
    }

    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.pose(q);
        let margin = self.scene.margin();
        for l in 0..self.model.links().len() {
            let Some(s) = self.model.link_shape(l) else { continue };
            let pose = to_pose(&(self.poses[l] * s.origin));
            for o in self.scene.obstacles() {
                let hit = if margin > 0.0 {
                    query::distance(&pose, s.shape.as_ref(), &o.pose, &*o.shape).map_or(true, |d| d.distance <= margin)
                } else {
                    query::intersection_test(&pose, s.shape.as_ref(), &o.pose, &*o.shape)
                        .map_or(true, |r| r.intersecting)
                };
                if hit {
                    return false;
                }
            }
        }
        !self
            .pairs
            .iter()
            .any(|&(a, b)| links_touch(&self.model, &self.poses, a, b))
    }

    /// Whether parry contradicts itself on a part pair of a checked self-collision pair at
    /// `q`: its GJK intersection test and its contact query (GJK, then EPA) disagree about
    /// contact. The checker decides such pairs by its own closed forms and exact search
    /// (checked against alternating projections in the crate's property tests), so the
    /// reference cannot judge them. Parry's intersection test has called a cylinder and a
    /// box touching that its contact query puts 4 mm apart.
    fn self_unsure(&mut self, q: &[f64]) -> bool {
        self.pose(q);
        let parts = |s: &SharedShape| match s.as_compound() {
            Some(c) => c.shapes().to_vec(),
            None => vec![(Pose::IDENTITY, s.clone())],
        };
        self.pairs.iter().any(|&(a, b)| {
            let (sa, sb) = (self.model.link_shape(a).unwrap(), self.model.link_shape(b).unwrap());
            let (pa, pb) = (
                to_pose(&(self.poses[a] * sa.origin)),
                to_pose(&(self.poses[b] * sb.origin)),
            );
            parts(&sa.shape).iter().any(|(qa, xa)| {
                parts(&sb.shape).iter().any(|(qb, xb)| {
                    let (wa, wb) = (pa * *qa, pb * *qb);
                    let touch =
                        query::intersection_test(&wa, xa.as_ref(), &wb, xb.as_ref()).is_ok_and(|t| t.intersecting);
                    // A contact at a positive distance, or a depth, that contradicts the test.
                    query::contact(&wa, xa.as_ref(), &wb, xb.as_ref(), 0.0)
                        .is_ok_and(|c| c.is_some_and(|c| if touch { c.dist > 1e-4 } else { c.dist < -1e-4 }))
                })
            })
        })
    }
}

/// A built-in robot's chain and a self-collision matrix from `samples` random configurations.
fn robot(name: &str, chain: &str, samples: usize) -> (Chain, SelfCollisionMatrix) {
    let m = RobotModel::builtin(name).unwrap();
    let chain = Chain::named(&m, chain).unwrap();
    let settings = SelfCollisionSettings {
        samples,
        ..Default::default()
    };
    (chain, SelfCollisionMatrix::compute(&m, &settings))
}

fn panda() -> (Chain, SelfCollisionMatrix) {
    robot("panda", "arm", 1000)
}

fn cluttered(seed: u64, n: usize) -> Vec<Obstacle> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let c = Vector::new(
                rng.random_range(-0.9..0.9),
                rng.random_range(-0.9..0.9),
                rng.random_range(-0.2..1.2),
            );
            let rot = Rotation::from_scaled_axis(Vector::new(
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
            ));
            let pose = Pose::from_parts(c, rot);
            match i % 3 {
                0 => Obstacle::cuboid(
                    format!("box{i}"),
                    pose,
                    Vector::new(
                        rng.random_range(0.01..0.12),
                        rng.random_range(0.01..0.12),
                        rng.random_range(0.01..0.12),
                    ),
                ),
                1 => Obstacle::ball(format!("ball{i}"), c, rng.random_range(0.01..0.1)),
                _ => Obstacle::cylinder(
                    format!("cyl{i}"),
                    pose,
                    rng.random_range(0.02..0.15),
                    rng.random_range(0.01..0.06),
                ),
            }
        })
        .collect()
}

/// Runs `qs` through both checkers (twice through the fast one, in two orders, so the
/// last-failure hint is exercised) and returns (valid, invalid) counts.
///
/// Configurations where parry contradicts itself on a self-collision pair
/// ([`Reference::self_unsure`]) are left out of the comparison and only checked for the same
/// answer on the checker's three paths.
fn compare(v: &mut RobotValidity, r: &mut Reference, qs: &[Vec<f64>]) -> (usize, usize) {
    let all = qs.len();
    let (unsure, qs): (Vec<Vec<f64>>, Vec<Vec<f64>>) = qs.iter().cloned().partition(|q| r.self_unsure(q));
    // Parry contradicts itself on 0–4 % of random states, 17 % of the Fetch's pocket runs
    // (links folded close together; 13 % before its head's shapes were tightened, which brings
    // the head's boxes closer to the upper arm).
    assert!(
        unsure.len() * 100 <= all * 20,
        "{} of {all} configurations left out",
        unsure.len()
    );
    // Those the checker answers the same way on every path.
    for (i, q) in unsure.iter().enumerate() {
        let fast = v.is_valid(q);
        assert_eq!(v.is_valid_exact(q), fast, "exact path, left-out configuration {i}");
        assert_eq!(v.explain(q).is_none(), fast, "explain, left-out configuration {i}");
    }
    let expected: Vec<bool> = qs.iter().map(|q| r.is_valid(q)).collect();
    for (i, q) in qs.iter().enumerate() {
        assert_eq!(v.is_valid(q), expected[i], "configuration {i}: {q:?}");
        assert_eq!(v.is_valid_exact(q), expected[i], "exact path, configuration {i}");
        assert_eq!(v.explain(q).is_none(), expected[i], "explain, configuration {i}");
    }
    for (i, q) in qs.iter().enumerate().rev() {
        assert_eq!(v.is_valid(q), expected[i], "reverse order, configuration {i}");
    }
    // Batches of 1 to 9 states (four-lane kinematics inside): the first invalid state of each,
    // and one check counted per state up to it.
    let dim = qs[0].len();
    let mut start = 0;
    let mut size = 1;
    while start < qs.len() {
        let end = (start + size).min(qs.len());
        let flat: Vec<f64> = qs[start..end].concat();
        let want = expected[start..end].iter().position(|&ok| !ok);
        let before = v.checks();
        assert_eq!(v.first_invalid(&flat, dim), want, "batch {start}..{end}");
        let counted = want.map_or(end - start, |k| k + 1);
        assert_eq!(
            (v.checks() - before) as usize,
            counted,
            "checks of batch {start}..{end}"
        );
        start = end;
        size = size % 9 + 1;
    }
    let valid = expected.iter().filter(|&&b| b).count();
    (valid, expected.len() - valid)
}

/// [`compare`] with a fresh `RobotValidity` and reference for `chain` among `scene`.
fn compare_in(chain: &Chain, acm: &SelfCollisionMatrix, scene: ParryScene, qs: &[Vec<f64>]) -> (usize, usize) {
    let mut v = RobotValidity::new(chain.clone(), acm.clone(), Arc::new(scene.clone()));
    let mut r = Reference::new(chain, acm, scene);
    compare(&mut v, &mut r, qs)
}

fn random_configurations(chain: &Chain, seed: u64, n: usize) -> Vec<Vec<f64>> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let mut q = vec![0.0; chain.dof()];
            chain.random_configuration(&mut rng, &mut q);
            q
        })
        .collect()
}

#[test]
fn random_clutter_matches_brute_force() {
    let (arm, acm) = panda();
    let qs = random_configurations(&arm, 11, 3000);
    for (seed, n, margin) in [(1u64, 24usize, 0.0f32), (2, 12, 0.0), (3, 24, 0.02)] {
        let obstacles = cluttered(seed, n);
        let scene = ParryScene::new(obstacles.clone()).with_margin(margin);
        let (valid, invalid) = compare_in(&arm, &acm, scene, &qs);
        assert!(
            valid > 100 && invalid > 100,
            "seed {seed}: {valid} valid / {invalid} invalid"
        );
    }
}

/// A link whose collision is a mesh beside a box (one compound of the mesh's convex parts or
/// triangles and the box, see `hearth_kinematics`) is checked like any other: the same
/// answers as the exact reference, with the mesh as a convex decomposition and as a triangle
/// mesh (whose surface alone collides).
#[test]
fn a_link_of_a_mesh_and_a_box_matches_brute_force() {
    let dir = std::env::temp_dir().join(format!("hearth_vb_mesh_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut obj = String::new();
    for (x, y, z) in [
        (-1, -1, -1),
        (1, -1, -1),
        (1, 1, -1),
        (-1, 1, -1),
        (-1, -1, 1),
        (1, -1, 1),
        (1, 1, 1),
        (-1, 1, 1),
    ] {
        obj += &format!("v {} {} {}\n", 0.06 * x as f64, 0.06 * y as f64, 0.06 * z as f64);
    }
    for f in [
        "1 3 2", "1 4 3", "5 6 7", "5 7 8", "1 2 6", "1 6 5", "3 4 8", "3 8 7", "2 3 7", "2 7 6", "1 5 8", "1 8 4",
    ] {
        obj += &format!("f {f}\n");
    }
    std::fs::write(dir.join("block.obj"), obj).unwrap();
    let urdf = r#"<robot name="two">
  <link name="base"/>
  <link name="upper"><collision><origin xyz="0 0 0.25"/><geometry><cylinder radius="0.04" length="0.5"/></geometry></collision></link>
  <link name="fore">
    <collision><origin xyz="0.3 0 0"/><geometry><mesh filename="block.obj"/></geometry></collision>
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.05"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
</robot>"#;
    for mode in [MeshCollision::ConvexDecomposition, MeshCollision::TriMesh] {
        let opts = LoadOptions {
            mesh_collision: mode,
            ..Default::default()
        };
        let m = RobotModel::from_urdf_str_with(urdf, "two.urdf", Some(&dir), &opts).unwrap();
        let chain = Chain::new(&m, &["j1", "j2"]).unwrap();
        let acm = SelfCollisionMatrix::adjacent_only(&m);
        let qs = random_configurations(&chain, 21, 2000);
        let (valid, invalid) = compare_in(&chain, &acm, ParryScene::new(cluttered(5, 16)), &qs);
        assert!(
            valid > 100 && invalid > 100,
            "{mode:?}: {valid} valid / {invalid} invalid"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn self_collision_only_matches_brute_force() {
    let (arm, acm) = panda();
    let qs = random_configurations(&arm, 12, 3000);
    let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(ParryScene::new(vec![])));
    let mut r = Reference::new(&arm, &acm, ParryScene::new(vec![]));
    let (valid, invalid) = compare(&mut v, &mut r, &qs);
    assert!(valid > 100 && invalid > 10, "{valid} valid / {invalid} invalid");
}

/// The self-collision pairs are filtered in f32 from the links' centres less the base's
/// position: a robot standing far from the world's origin gets the same answers as the exact
/// reference standing there too. (States where parry's GJK intersection test reports a pair in
/// contact that its distance query puts apart are left out: the checker's part spheres clear
/// some of those, correctly, and the reference cannot tell.)
#[test]
fn a_robot_far_from_the_origin_gets_the_same_self_collision_answers() {
    let (chain, acm) = robot("fetch", "arm_with_torso", 300);
    let base = Isometry3::new(nalgebra::Vector3::new(250.0, -400.0, 0.0), nalgebra::Vector3::z() * 2.0);
    let mut r = Reference::new(&chain, &acm, ParryScene::new(vec![]));
    r.base = base;
    let qs: Vec<Vec<f64>> = random_configurations(&chain, 13, 1500)
        .into_iter()
        .filter(|q| {
            r.pose(q);
            r.pairs.iter().all(|&(a, b)| {
                let (sa, sb) = (r.model.link_shape(a).unwrap(), r.model.link_shape(b).unwrap());
                let (pa, pb) = (to_pose(&(r.poses[a] * sa.origin)), to_pose(&(r.poses[b] * sb.origin)));
                let apart = query::distance(&pa, sa.shape.as_ref(), &pb, sb.shape.as_ref())
                    .unwrap()
                    .distance
                    > 0.0;
                apart != links_touch(&r.model, &r.poses, a, b)
            })
        })
        .collect();
    assert!(qs.len() > 1400, "{} states kept", qs.len());
    let mut v = RobotValidity::new(chain.clone(), acm.clone(), Arc::new(ParryScene::new(vec![])));
    v.set_base(base);
    let (valid, invalid) = compare(&mut v, &mut r, &qs);
    assert!(valid > 100 && invalid > 100, "{valid} valid / {invalid} invalid");
}

#[test]
fn mbm_table_pick_matches_brute_force() {
    let set = ProblemSet::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/panda_table_pick.json")).unwrap();
    let (arm, acm) = panda();
    let mut total = (0, 0);
    for (k, problem) in set.valid_problems().enumerate() {
        let scene = problem.scene();
        let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(scene.clone()));
        let mut r = Reference::new(&arm, &acm, scene);
        let mut qs = random_configurations(&arm, 100 + k as u64, 300);
        qs.push(problem.start.clone());
        qs.extend(problem.goals.iter().cloned());
        // Straight-line interpolations start → goal: near-contact configurations.
        for g in &problem.goals {
            for t in 1..20 {
                let t = t as f64 / 20.0;
                qs.push(problem.start.iter().zip(g).map(|(a, b)| a + t * (b - a)).collect());
            }
        }
        let (valid, invalid) = compare(&mut v, &mut r, &qs);
        total.0 += valid;
        total.1 += invalid;
    }
    assert!(total.0 > 50 && total.1 > 20, "{total:?}");
}

/// Certified cells of every pair table the model has built.
fn filled_cells(model: &RobotModel) -> usize {
    let n = model.links().len();
    (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
        .filter_map(|(a, b)| model.pair_table(a, b))
        .map(|t| t.filled_cells())
        .sum()
}

#[test]
fn warmed_certificates_change_no_answer() {
    // Warmed: a model whose pair tables were filled ahead by the warm-up.
    let (arm, acm) = panda();
    let scene = ParryScene::new(cluttered(4, 16));
    let warmed = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(scene.clone()));
    assert_eq!(filled_cells(arm.model()), 0);
    warmed.warm_pair_tables(3000, 5);
    let filled = filled_cells(arm.model());
    assert!(filled > 50, "warm-up certified only {filled} cells");
    let mut warmed = warmed;
    // Cold: a fresh model, its cells filled only as the checks below need them.
    let (cold_arm, cold_acm) = panda();
    let mut cold = RobotValidity::new(cold_arm, cold_acm, Arc::new(scene));
    let qs = random_configurations(&arm, 13, 3000);
    let answers = |v: &mut RobotValidity| qs.iter().map(|q| v.is_valid(q)).collect::<Vec<_>>();
    let (w, c) = (answers(&mut warmed), answers(&mut cold));
    assert_eq!(w, c);
    let valid = w.iter().filter(|&&ok| ok).count();
    assert!(valid > 100 && qs.len() - valid > 100, "{valid} valid of {}", qs.len());
    // The warm-up found cells that these checks need: the cold model filled some of the same.
    assert!(filled_cells(cold.chain().model()) > 0);
}

/// Runs of states close to one colliding state, as a tree wedged in a pocket produces: the
/// same part settles check after check, so the checker starts testing that part alone on its
/// ancestors' poses. Runs end with a state that is valid or that another link makes invalid,
/// so the stale poses left by a short-cut check are caught if anything reads them.
fn pocket_runs(chain: &Chain, seed: u64, r: &mut Reference, runs: usize) -> Vec<Vec<f64>> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut qs = Vec::new();
    let mut q = vec![0.0; chain.dof()];
    let mut found = 0;
    while found < runs {
        chain.random_configuration(&mut rng, &mut q);
        if r.is_valid(&q) {
            continue;
        }
        found += 1;
        for _ in 0..12 {
            qs.push(q.iter().map(|v| v + rng.random_range(-0.01..0.01)).collect());
        }
        // Every other run ends with a valid state (when one turns up within 500 draws).
        let mut other = vec![0.0; chain.dof()];
        for _ in 0..500 {
            chain.random_configuration(&mut rng, &mut other);
            if found % 2 == 1 || r.is_valid(&other) {
                break;
            }
        }
        qs.push(other);
    }
    qs
}

#[test]
fn pocket_runs_match_brute_force() {
    let (arm, acm) = panda();
    let scene = ParryScene::new(cluttered(5, 24));
    let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(scene.clone()));
    let mut r = Reference::new(&arm, &acm, scene);
    let qs = pocket_runs(&arm, 21, &mut r, 150);
    let (valid, invalid) = compare(&mut v, &mut r, &qs);
    assert!(valid > 20 && invalid > 1000, "{valid} valid / {invalid} invalid");
}

/// Random clutter in front of a Fetch, clear of its base and body.
fn fetch_clutter(seed: u64) -> ParryScene {
    ParryScene::new(
        cluttered(seed, 40)
            .into_iter()
            .filter(|o| o.pose.translation.x > 0.0 && o.pose.translation.z > 0.4)
            .map(|mut o| {
                o.pose.translation.x += 0.35;
                o
            })
            .collect(),
    )
}

#[test]
fn fetch_pocket_runs_match_brute_force() {
    // The Fetch's torso moves links (the head) that are not ancestors of the arm's links: their
    // poses go stale when a check is settled on the arm's ancestors alone.
    let (chain, acm) = robot("fetch", "arm_with_torso", 300);
    let scene = fetch_clutter(6);
    assert!(scene.len() > 5);
    let mut v = RobotValidity::new(chain.clone(), acm.clone(), Arc::new(scene.clone()));
    let mut r = Reference::new(&chain, &acm, scene);
    let qs = pocket_runs(&chain, 22, &mut r, 100);
    let (valid, invalid) = compare(&mut v, &mut r, &qs);
    assert!(valid > 10 && invalid > 800, "{valid} valid / {invalid} invalid");
}

/// MotionBenchMaker Panda table_pick problem 18 with only its can: near the goal, the straight
/// line from the start brings the left finger's box 7 mm from the can. parry's GJK
/// intersection test (0.31) reports contact there, while its distance query gives the gap;
/// the finger's bounding ball is clear, and with it the state. Checks of these states agree
/// with parry's distances whichever path (hint, batch, exact) settles them.
#[test]
fn states_whose_parts_are_millimetres_clear_are_valid_where_gjk_reports_contact() {
    let json = r#"{"robot": "panda", "family": "table_pick",
        "joint_names": ["panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                        "panda_joint5", "panda_joint6", "panda_joint7"],
        "problems": [{"id": 18, "valid": true,
            "start": [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785],
            "goals": [[-0.8149870054389096, 1.017512444205814, 0.09625714098816579,
                       -1.057071016356038, -2.8973, 2.616988489354312, 0.4897790863599705]],
            "obstacles": [{"kind": "cylinder", "name": "Can1",
                "center": [0.6610046706935239, -0.6352362571097154, 0.20795965600055],
                "radius": 0.03, "half_length": 0.06,
                "quat_xyzw": [0.0, 0.0, -0.429699764930775, 0.9029718223834212]}]}]}"#;
    let set = ProblemSet::from_json_str(json).unwrap();
    let problem = set.problem(18).unwrap();
    let (arm, acm) = panda();
    let scene = problem.scene();
    let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(scene.clone()));
    let model = arm.model().clone();
    let pairs = acm.checked_geometric_pairs(&model);
    let mut q_full = model.neutral_configuration();
    let mut poses = model.pose_buffer();
    let can = &scene.obstacles()[0];
    let goal = &problem.goals[0];
    let (mut gjk_contacts, mut checked) = (0, 0);
    for t in 360..=400 {
        let t = t as f64 / 400.0;
        let q: Vec<f64> = problem.start.iter().zip(goal).map(|(a, b)| a + t * (b - a)).collect();
        arm.scatter(&q, &mut q_full);
        model.fk_from(&Isometry3::identity(), &q_full, &mut poses).unwrap();
        // Ground truth from parry's distance query, part by part.
        let mut gap = f32::INFINITY;
        let mut gjk_contact = false;
        for (l, link_pose) in poses.iter().enumerate() {
            let Some(s) = model.link_shape(l) else { continue };
            let parts: Vec<(Pose, &dyn parry3d::shape::Shape)> = match s.shape.as_compound() {
                Some(c) => c.shapes().iter().map(|(p, sh)| (*p, sh.as_ref())).collect(),
                None => vec![(Pose::IDENTITY, s.shape.as_ref())],
            };
            for (at, part) in parts {
                let pose = to_pose(&(link_pose * s.origin)) * at;
                gap = gap.min(query::distance(&pose, part, &can.pose, &*can.shape).unwrap().distance);
                gjk_contact |= query::intersection_test(&pose, part, &can.pose, &*can.shape)
                    .unwrap()
                    .intersecting;
            }
        }
        let self_clear = !pairs.iter().any(|&(a, b)| links_touch(&model, &poses, a, b));
        if gap > 1e-3 && self_clear {
            checked += 1;
            gjk_contacts += usize::from(gjk_contact);
            assert!(v.is_valid(&q), "t = {t}: {gap} m clear");
            assert!(v.is_valid_exact(&q), "exact path, t = {t}");
            assert!(v.explain(&q).is_none(), "explain, t = {t}");
        } else if gap <= 0.0 {
            assert!(!v.is_valid(&q), "t = {t}: in contact");
        }
    }
    assert!(checked > 5, "{checked} clear states");
    // The case this test is about (if parry stops reporting these contacts, it still passes).
    eprintln!("{gjk_contacts} of {checked} clear states had a GJK contact");
}

/// Straight motions sampled every `step` (max-norm), checked along the motion with
/// `first_invalid_along` (which skips the states inside a checked state's free region): it
/// must find an invalid state exactly when checking every state one by one does, and the state
/// it reports must be invalid. (The one-by-one answers are compared with the brute-force
/// reference by the tests above; parry's GJK reports contact between a cylinder and a box
/// that are a millimetre apart, which the checker sees through, so the reference here is the
/// checker itself.) Returns (clear motions, blocked motions, states of the clear motions,
/// checks spent on them).
fn compare_along(v: &mut RobotValidity, motions: &[(Vec<f64>, Vec<f64>)], step: f64) -> [u64; 4] {
    let mut one_by_one = v.clone();
    let mut out = [0u64; 4];
    for (k, (a, b)) in motions.iter().enumerate() {
        let dim = a.len();
        let span = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        let n = (span / step).ceil() as usize + 1;
        let flat: Vec<f64> = (0..n)
            .flat_map(|i| {
                let t = i as f64 / (n - 1).max(1) as f64;
                a.iter().zip(b).map(move |(x, y)| x + t * (y - x))
            })
            .collect();
        let expected = flat.chunks_exact(dim).position(|q| !one_by_one.is_valid(q));
        let before = v.checks();
        let got = v.first_invalid_along(&flat, dim);
        assert_eq!(
            got.is_some(),
            expected.is_some(),
            "motion {k}: {got:?} against {expected:?}"
        );
        if let Some(i) = got {
            assert!(
                !one_by_one.is_valid(&flat[i * dim..(i + 1) * dim]),
                "motion {k}: state {i} is valid"
            );
            out[1] += 1;
        } else {
            out[0] += 1;
            out[2] += n as u64;
            out[3] += v.checks() - before;
        }
    }
    out
}

/// Motions from random valid configurations to ones up to `reach` away in each joint, where the
/// second is valid too (so blocked motions cross an obstacle between two free ends).
fn short_motions(chain: &Chain, r: &mut Reference, seed: u64, n: usize, reach: f64) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut q = vec![0.0; chain.dof()];
    while out.len() < n {
        chain.random_configuration(&mut rng, &mut q);
        if !r.is_valid(&q) {
            continue;
        }
        let mut to: Vec<f64> = q.iter().map(|x| x + rng.random_range(-reach..reach)).collect();
        chain.clamp(&mut to);
        if r.is_valid(&to) {
            out.push((q.clone(), to));
        }
    }
    out
}

#[test]
fn motions_checked_along_match_brute_force() {
    let (arm, acm) = panda();
    for (seed, n, margin) in [(7u64, 24usize, 0.0f32), (8, 12, 0.02)] {
        let scene = ParryScene::new(cluttered(seed, n)).with_margin(margin);
        let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(scene.clone()));
        let mut r = Reference::new(&arm, &acm, scene);
        let motions = short_motions(&arm, &mut r, seed, 150, 1.5);
        let [clear, blocked, states, checks] = compare_along(&mut v, &motions, 0.005);
        assert!(
            clear > 20 && blocked > 20,
            "seed {seed}: {clear} clear, {blocked} blocked"
        );
        // The free regions spare many of the checks of a clear motion, even in clutter.
        assert!(
            checks * 4 < states * 3,
            "seed {seed}: {checks} checks for {states} states"
        );
    }
}

#[test]
fn fetch_motions_checked_along_match_brute_force() {
    // A prismatic torso, and links (the head) that the torso moves but are not the arm's.
    let (chain, acm) = robot("fetch", "arm_with_torso", 300);
    let scene = fetch_clutter(9);
    let mut v = RobotValidity::new(chain.clone(), acm.clone(), Arc::new(scene.clone()));
    let mut r = Reference::new(&chain, &acm, scene);
    let motions = short_motions(&chain, &mut r, 10, 100, 1.5);
    let [clear, blocked, states, checks] = compare_along(&mut v, &motions, 0.005);
    assert!(clear > 10 && blocked > 10, "{clear} clear, {blocked} blocked");
    assert!(checks * 2 < states, "{checks} checks for {states} states");
}

#[test]
fn mbm_table_pick_motions_checked_along_match_brute_force() {
    // Start to goal in a straight line: grazing the table and the objects near the goal.
    let set = ProblemSet::load(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/panda_table_pick.json")).unwrap();
    let (arm, acm) = panda();
    let mut total = [0u64; 4];
    for problem in set.valid_problems() {
        let scene = problem.scene();
        let mut v = RobotValidity::new(arm.clone(), acm.clone(), Arc::new(scene.clone()));
        let mut r = Reference::new(&arm, &acm, scene);
        let mut motions: Vec<_> = problem
            .goals
            .iter()
            .map(|g| (problem.start.clone(), g.clone()))
            .collect();
        motions.extend(short_motions(&arm, &mut r, 31, 100, 1.5));
        for (t, c) in total.iter_mut().zip(compare_along(&mut v, &motions, 0.002)) {
            *t += c;
        }
    }
    // 96 clear and 5 blocked motions (with 40 random motions a problem, the tightened Panda hand
    // left only 2 blocked).
    assert!(total[0] > 10 && total[1] > 2, "{total:?}");
    assert!(total[3] * 2 < total[2], "{total:?}");
}
