//! Forward kinematics against computations that share no code with the crate:
//! the Panda's published (modified) Denavit–Hartenberg parameters, and, for every built-in
//! robot, homogeneous 4×4 transforms chained straight from the URDF XML.

use std::collections::HashMap;

use hearth_kinematics::{BUILTIN_ROBOTS, RobotModel};
use nalgebra::{Isometry3, Matrix3, Matrix4, Vector3};
use rand::{RngExt, SeedableRng};

fn rot_x(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(1.0, 0.0, 0.0, 0.0, 0.0, c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0)
}
fn rot_y(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(c, 0.0, s, 0.0, 0.0, 1.0, 0.0, 0.0, -s, 0.0, c, 0.0, 0.0, 0.0, 0.0, 1.0)
}
fn rot_z(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)
}
fn trans(x: f64, y: f64, z: f64) -> Matrix4<f64> {
    Matrix4::new(1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0)
}
/// Rotation by `a` about the unit axis `k` (Rodrigues).
fn rot_axis(k: Vector3<f64>, a: f64) -> Matrix4<f64> {
    let k = k.normalize();
    let kx = Matrix3::new(0.0, -k.z, k.y, k.z, 0.0, -k.x, -k.y, k.x, 0.0);
    let r = Matrix3::identity() + kx * a.sin() + kx * kx * (1.0 - a.cos());
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    m
}

fn assert_pose_eq(label: &str, iso: &Isometry3<f64>, m: &Matrix4<f64>, tol: f64) {
    let h = iso.to_homogeneous();
    let diff = (h - m).abs().max();
    assert!(
        diff < tol,
        "{label}: pose differs by {diff}\nmodel:\n{h}\nreference:\n{m}"
    );
}

/// Craig-convention DH: `RotX(α_{i-1}) · TransX(a_{i-1}) · RotZ(θ_i) · TransZ(d_i)`.
fn panda_dh(q: &[f64]) -> Vec<Matrix4<f64>> {
    // (a_{i-1}, d_i, α_{i-1}) for joints 1..7 and the flange, from Franka's documentation.
    let dh = [
        (0.0, 0.333, 0.0),
        (0.0, 0.0, -std::f64::consts::FRAC_PI_2),
        (0.0, 0.316, std::f64::consts::FRAC_PI_2),
        (0.0825, 0.0, std::f64::consts::FRAC_PI_2),
        (-0.0825, 0.384, -std::f64::consts::FRAC_PI_2),
        (0.0, 0.0, std::f64::consts::FRAC_PI_2),
        (0.088, 0.0, std::f64::consts::FRAC_PI_2),
        (0.0, 0.107, 0.0),
    ];
    let mut t = Matrix4::identity();
    let mut out = Vec::new();
    for (i, &(a, d, alpha)) in dh.iter().enumerate() {
        let theta = if i < 7 { q[i] } else { 0.0 };
        t = t * rot_x(alpha) * trans(a, 0.0, 0.0) * rot_z(theta) * trans(0.0, 0.0, d);
        out.push(t);
    }
    out
}

#[test]
fn panda_matches_denavit_hartenberg() {
    let panda = RobotModel::builtin("panda").unwrap();
    let mut poses = panda.pose_buffer();
    let known: Vec<[f64; 7]> = vec![
        [0.0; 7],
        [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785], // the "ready" pose
        [1.0, 0.5, -0.7, -1.2, 2.0, 3.0, -2.5],
        [-2.8, 1.7, 2.8, -3.0, -2.8, -0.01, 2.8],
    ];
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
    let mut configs = known;
    for _ in 0..200 {
        let mut q = [0.0; 7];
        for (i, v) in q.iter_mut().enumerate() {
            *v = rng.random_range(panda.lower()[i]..panda.upper()[i]);
        }
        configs.push(q);
    }
    for q7 in configs {
        let mut q = panda.neutral_configuration();
        q[..7].copy_from_slice(&q7);
        panda.fk(&q, &mut poses).unwrap();
        let reference = panda_dh(&q7);
        for (i, m) in reference.iter().enumerate() {
            let link = panda.link_index(&format!("panda_link{}", i + 1)).unwrap();
            assert_pose_eq(&format!("panda_link{} at {q7:?}", i + 1), &poses[link], m, 1e-9);
        }
        // The hand is the flange turned by -45° about z.
        let hand = panda.link_index("panda_hand").unwrap();
        assert_pose_eq(
            "panda_hand",
            &poses[hand],
            &(reference[7] * rot_z(-std::f64::consts::FRAC_PI_4)),
            1e-9,
        );
    }
}

#[test]
fn panda_known_positions() {
    // Flange position at q = 0: x = a4 + a5 + a7 = 0.088, z = 0.333 + 0.316 + 0.384 - 0.107.
    let panda = RobotModel::builtin("panda").unwrap();
    let p = panda
        .link_pose(&vec![0.0; panda.dof()], panda.link_index("panda_link8").unwrap())
        .unwrap();
    assert!(
        (p.translation.vector - Vector3::new(0.088, 0.0, 0.926)).norm() < 1e-9,
        "{p}"
    );
}

/// Independent FK straight from the URDF XML.
struct XmlRobot {
    joints: Vec<XmlJoint>,
    root: String,
}
struct XmlJoint {
    name: String,
    kind: String,
    parent: String,
    child: String,
    origin: Matrix4<f64>,
    axis: Vector3<f64>,
    mimic: Option<(String, f64, f64)>,
}

fn numbers(s: Option<&str>, default: [f64; 3]) -> [f64; 3] {
    match s {
        None => default,
        Some(s) => {
            let v: Vec<f64> = s.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        }
    }
}

fn parse(text: &str) -> XmlRobot {
    let doc = roxmltree::Document::parse(text).unwrap();
    let mut joints = Vec::new();
    let mut children = std::collections::HashSet::new();
    let mut links = Vec::new();
    for n in doc.root_element().children().filter(|n| n.is_element()) {
        match n.tag_name().name() {
            "link" => links.push(n.attribute("name").unwrap().to_owned()),
            "joint" => {
                let child_el = |tag: &str| n.children().find(|c| c.has_tag_name(tag));
                let origin = child_el("origin");
                let xyz = numbers(origin.and_then(|o| o.attribute("xyz")), [0.0; 3]);
                let rpy = numbers(origin.and_then(|o| o.attribute("rpy")), [0.0; 3]);
                let axis = numbers(child_el("axis").and_then(|a| a.attribute("xyz")), [1.0, 0.0, 0.0]);
                let mimic = child_el("mimic").map(|m| {
                    (
                        m.attribute("joint").unwrap().to_owned(),
                        m.attribute("multiplier").map_or(1.0, |v| v.parse().unwrap()),
                        m.attribute("offset").map_or(0.0, |v| v.parse().unwrap()),
                    )
                });
                let child = child_el("child").unwrap().attribute("link").unwrap().to_owned();
                children.insert(child.clone());
                joints.push(XmlJoint {
                    name: n.attribute("name").unwrap().to_owned(),
                    kind: n.attribute("type").unwrap().to_owned(),
                    parent: child_el("parent").unwrap().attribute("link").unwrap().to_owned(),
                    child,
                    // URDF rpy: fixed-axis roll about x, then pitch about y, then yaw about z.
                    origin: trans(xyz[0], xyz[1], xyz[2]) * rot_z(rpy[2]) * rot_y(rpy[1]) * rot_x(rpy[0]),
                    axis: Vector3::from(axis),
                    mimic,
                });
            }
            _ => {}
        }
    }
    let root = links.into_iter().find(|l| !children.contains(l)).unwrap();
    XmlRobot { joints, root }
}

fn xml_fk(robot: &XmlRobot, values: &HashMap<String, f64>) -> HashMap<String, Matrix4<f64>> {
    let mut out = HashMap::new();
    out.insert(robot.root.clone(), Matrix4::identity());
    let mut changed = true;
    while changed {
        changed = false;
        for j in &robot.joints {
            if out.contains_key(&j.child) || !out.contains_key(&j.parent) {
                continue;
            }
            let v = match &j.mimic {
                Some((target, m, o)) => m * values[target] + o,
                None => values.get(&j.name).copied().unwrap_or(0.0),
            };
            let motion = match j.kind.as_str() {
                "revolute" | "continuous" => rot_axis(j.axis, v),
                "prismatic" => {
                    let d = j.axis.normalize() * v;
                    trans(d.x, d.y, d.z)
                }
                _ => Matrix4::identity(),
            };
            let t = out[&j.parent] * j.origin * motion;
            out.insert(j.child.clone(), t);
            changed = true;
        }
    }
    out
}

#[test]
fn every_builtin_robot_matches_chained_transforms() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    for robot in BUILTIN_ROBOTS {
        let model = RobotModel::builtin(robot.name).unwrap();
        let xml = parse(robot.urdf);
        let mut poses = model.pose_buffer();
        let mut q = vec![0.0; model.dof()];
        for trial in 0..100 {
            if trial > 0 {
                model.random_configuration(&mut rng, &mut q);
            }
            model.fk(&q, &mut poses).unwrap();
            let values: HashMap<String, f64> = model.variable_names().iter().cloned().zip(q.iter().copied()).collect();
            let reference = xml_fk(&xml, &values);
            assert_eq!(
                reference.len(),
                model.links().len(),
                "{}: every link reached",
                robot.name
            );
            for (link, pose) in model.links().iter().zip(&poses) {
                assert_pose_eq(
                    &format!("{} {} at {q:?}", robot.name, link.name),
                    pose,
                    &reference[&link.name],
                    1e-9,
                );
            }
        }
    }
}

#[test]
fn link_pose_equals_full_fk() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
    for robot in BUILTIN_ROBOTS {
        let model = RobotModel::builtin(robot.name).unwrap();
        let mut poses = model.pose_buffer();
        let mut q = vec![0.0; model.dof()];
        model.random_configuration(&mut rng, &mut q);
        model.fk(&q, &mut poses).unwrap();
        for (l, full) in poses.iter().enumerate() {
            let p = model.link_pose(&q, l).unwrap();
            assert!((p.to_homogeneous() - full.to_homogeneous()).abs().max() < 1e-12);
        }
    }
}

#[test]
fn fk_from_places_the_root() {
    let fetch = RobotModel::builtin("fetch").unwrap();
    let base = Isometry3::new(Vector3::new(1.0, -2.0, 0.0), Vector3::new(0.0, 0.0, 0.7));
    let q = fetch.neutral_configuration();
    let mut at_origin = fetch.pose_buffer();
    let mut moved = fetch.pose_buffer();
    fetch.fk(&q, &mut at_origin).unwrap();
    fetch.fk_from(&base, &q, &mut moved).unwrap();
    for (a, b) in at_origin.iter().zip(&moved) {
        assert!(((base * a).to_homogeneous() - b.to_homogeneous()).abs().max() < 1e-12);
    }
}

/// Four configurations at a time give, bit for bit, the poses each gives alone: on every
/// built-in robot (revolute, continuous, prismatic and mimic joints), for the whole model and
/// for the links below one joint, with lanes that repeat a configuration.
#[test]
fn four_lanes_equal_one_at_a_time() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(17);
    for robot in BUILTIN_ROBOTS {
        let (name, model) = (robot.name, RobotModel::builtin(robot.name).unwrap());
        let n = model.links().len();
        let subsets = [
            model.fk_subset(|_| true),
            model.fk_subset(|l| l >= n / 3 && model.joints_to(l).len() > 1),
        ];
        let root = Isometry3::new(Vector3::new(0.3, -0.2, 0.1), Vector3::new(0.0, 0.0, 0.7));
        for (which, subset) in subsets.iter().enumerate() {
            for round in 0..50 {
                let qs: Vec<Vec<f64>> = (0..4)
                    .map(|_| {
                        let mut q = vec![0.0; model.dof()];
                        model.random_configuration(&mut rng, &mut q);
                        q
                    })
                    .collect();
                let lane_q: [&[f64]; 4] = std::array::from_fn(|k| qs[if round % 5 == 0 { 0 } else { k }].as_slice());
                // Links outside the subset hold the poses of a full pass from `root`.
                let mut base = model.pose_buffer();
                model.fk_from(&root, lane_q[0], &mut base).unwrap();
                let mut four: [Vec<Isometry3<f64>>; 4] = std::array::from_fn(|_| base.clone());
                model.fk_update4(subset, lane_q, &mut four).unwrap();
                for k in 0..4 {
                    let mut one = base.clone();
                    model.fk_update(subset, lane_q[k], &mut one).unwrap();
                    assert_eq!(one, four[k], "{name}, lane {k}");
                    // A subset's joint sines and cosines come four at a time; a full pass
                    // computes each as its joint comes: the same bits (for the whole model:
                    // the other subset's links hang from poses of the first lane).
                    if which == 0 {
                        let mut full = model.pose_buffer();
                        model.fk_from(&root, lane_q[k], &mut full).unwrap();
                        assert_eq!(one, full, "{name}, lane {k}");
                    }
                }
            }
        }
        // Continuous joints far from zero, their half angles in every quadrant and past the
        // inlined sine's range (where it hands the angle to libm): still the bits of a full
        // pass.
        for angle in [5.0, -5.0, 8.0, -11.0, 3.0e5] {
            let mut far = vec![0.0; model.dof()];
            model.random_configuration(&mut rng, &mut far);
            for v in (0..model.dof()).filter(|&v| model.upper()[v].is_infinite()) {
                far[v] = angle + 0.1 * v as f64;
            }
            let (mut one, mut full) = (model.pose_buffer(), model.pose_buffer());
            model.fk(&far, &mut one).unwrap();
            model.fk_update(&subsets[0], &far, &mut one).unwrap();
            model.fk(&far, &mut full).unwrap();
            assert_eq!(one, full, "{name}: continuous joints at {angle}");
        }
        let bad = vec![f64::NAN; model.dof()];
        let ok = vec![0.0; model.dof()];
        let mut four: [Vec<Isometry3<f64>>; 4] = std::array::from_fn(|_| model.pose_buffer());
        assert!(model.fk_update4(&subsets[0], [&ok, &ok, &bad, &ok], &mut four).is_err());
        let mut short: [Vec<Isometry3<f64>>; 4] = std::array::from_fn(|_| vec![Isometry3::identity(); 1]);
        assert!(model.fk_update4(&subsets[0], [&ok; 4], &mut short).is_err());
    }
}

/// A subset that holds the variables outside a set gives, bit for bit, the poses of the plain
/// subset for every configuration that agrees with the held values, one lane and four lanes at
/// a time, on every built-in robot; holding again at another configuration follows it, and a
/// failed hold leaves the subset plain.
#[test]
fn held_subsets_equal_plain_ones() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(23);
    for robot in BUILTIN_ROBOTS {
        let (name, model) = (robot.name, RobotModel::builtin(robot.name).unwrap());
        let plain = model.fk_subset(|_| true);
        // Every other variable moves; the rest are held.
        let varies = |v: usize| v.is_multiple_of(2);
        let mut held = plain.clone();
        for round in 0..20 {
            let mut reference = vec![0.0; model.dof()];
            model.random_configuration(&mut rng, &mut reference);
            model.fk_subset_hold(&mut held, &reference, varies).unwrap();
            let qs: Vec<Vec<f64>> = (0..4)
                .map(|_| {
                    let mut q = vec![0.0; model.dof()];
                    model.random_configuration(&mut rng, &mut q);
                    for (v, x) in q.iter_mut().enumerate() {
                        if !varies(v) {
                            *x = reference[v];
                        }
                    }
                    q
                })
                .collect();
            let lane_q: [&[f64]; 4] = std::array::from_fn(|k| qs[k].as_slice());
            let mut base = model.pose_buffer();
            model.fk(&reference, &mut base).unwrap();
            let mut four: [Vec<Isometry3<f64>>; 4] = std::array::from_fn(|_| base.clone());
            model.fk_update4(&held, lane_q, &mut four).unwrap();
            for k in 0..4 {
                let (mut a, mut b) = (base.clone(), base.clone());
                model.fk_update(&plain, lane_q[k], &mut a).unwrap();
                model.fk_update(&held, lane_q[k], &mut b).unwrap();
                assert_eq!(a, b, "{name}, round {round}, one lane {k}");
                assert_eq!(a, four[k], "{name}, round {round}, four lanes, lane {k}");
            }
        }
        assert_ne!(held, plain, "{name}: something is held");
        let bad = vec![f64::NAN; model.dof()];
        assert!(model.fk_subset_hold(&mut held, &bad, varies).is_err());
        assert_eq!(held, plain, "{name}: a failed hold leaves the subset plain");
    }
}
