//! How many MotionBenchMaker start/goal configurations collide with the built-in robots'
//! collision geometry (the configurations are collision-free for the real robot meshes).
//!
//! `cargo run --release --example mbm_check -- panda [BENCH_DIR]` (default `../shared/bench`).
//! Self-collision uses the benchmark's allowed pairs plus adjacent links; fingers are held at
//! the real robots' widest opening.

use hearth::kinematics::*;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::SharedShape;
fn main() {
    let robot = std::env::args().nth(1).unwrap_or("panda".into());
    let bench = std::env::args().nth(2).unwrap_or("../shared/bench".into());
    let dir = format!("{bench}/mbm/{robot}");
    let m = RobotModel::builtin(&robot).unwrap();
    let joints: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{dir}/joints.json")).unwrap()).unwrap();
    let mut sc = SelfCollisionMatrix::adjacent_only(&m);
    for p in joints["notes"]["self_collision_allowed_pairs"].as_array().unwrap() {
        let a = m.link_index(p[0].as_str().unwrap());
        let b = m.link_index(p[1].as_str().unwrap());
        if let (Ok(a), Ok(b)) = (a, b) {
            sc.disable(a, b, DisabledReason::Never);
        }
    }
    let names: Vec<String> = joints["joint_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let chain = Chain::new(&m, &names).unwrap();
    let fingers = if robot == "panda" {
        vec![("panda_finger_joint1", 0.04)]
    } else {
        vec![("r_gripper_finger_joint", 0.05)]
    };
    let mut q_full = m.neutral_configuration();
    for (j, v) in &fingers {
        if let Ok(ji) = m.joint_index(j)
            && let Some(var) = m.joints()[ji].variable
        {
            q_full[var] = *v;
        }
    }
    let mut poses = m.pose_buffer();
    let mut stats: std::collections::BTreeMap<String, usize> = Default::default();
    let (mut total, mut bad) = (0, 0);
    for fam in [
        "table_pick",
        "table_under_pick",
        "box",
        "bookshelf_small",
        "bookshelf_tall",
        "bookshelf_thin",
        "cage",
    ] {
        let f: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(format!("{dir}/{fam}.json")).unwrap()).unwrap();
        for prob in f["problems"].as_array().unwrap() {
            if !prob["valid"].as_bool().unwrap() {
                continue;
            }
            let obs: Vec<(Pose, SharedShape)> = prob["obstacles"]
                .as_array()
                .unwrap()
                .iter()
                .map(|o| {
                    let c: Vec<f32> = o["center"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|v| v.as_f64().unwrap() as f32)
                        .collect();
                    let q: Vec<f32> = o
                        .get("quat_xyzw")
                        .map(|q| {
                            q.as_array()
                                .unwrap()
                                .iter()
                                .map(|v| v.as_f64().unwrap() as f32)
                                .collect()
                        })
                        .unwrap_or(vec![0., 0., 0., 1.]);
                    let mut pose = Pose::from_parts(
                        Vector::new(c[0], c[1], c[2]),
                        Rotation::from_xyzw(q[0], q[1], q[2], q[3]),
                    );
                    let shape = match o["kind"].as_str().unwrap() {
                        "box" => {
                            let h: Vec<f32> = o["half_extents"]
                                .as_array()
                                .unwrap()
                                .iter()
                                .map(|v| v.as_f64().unwrap() as f32)
                                .collect();
                            SharedShape::cuboid(h[0], h[1], h[2])
                        }
                        "sphere" => SharedShape::ball(o["radius"].as_f64().unwrap() as f32),
                        _ => {
                            pose *=
                                Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2));
                            SharedShape::cylinder(
                                o["half_length"].as_f64().unwrap() as f32,
                                o["radius"].as_f64().unwrap() as f32,
                            )
                        }
                    };
                    (pose, shape)
                })
                .collect();
            let mut qs = vec![prob["start"].clone()];
            qs.extend(prob["goals"].as_array().unwrap().iter().cloned());
            for qv in qs {
                let q: Vec<f64> = qv.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
                chain.scatter(&q, &mut q_full);
                m.fk(&q_full, &mut poses).unwrap();
                total += 1;
                let mut hit = None;
                if let Some((a, b)) = sc.first_collision(&m, &poses) {
                    hit = Some(format!("self {}-{}", m.links()[a].name, m.links()[b].name));
                }
                if hit.is_none() {
                    for (l, link) in m.links().iter().enumerate() {
                        let Some(s) = m.link_shape(l) else { continue };
                        let p = to_pose(&(poses[l] * s.origin));
                        for (k, (op, os)) in obs.iter().enumerate() {
                            if parry3d::query::intersection_test(&p, s.shape.as_ref(), op, os.as_ref())
                                .unwrap()
                                .intersecting
                            {
                                hit = Some(format!(
                                    "{} x {}",
                                    link.name,
                                    prob["obstacles"][k]["name"].as_str().unwrap_or("?")
                                ));
                                break;
                            }
                        }
                        if hit.is_some() {
                            break;
                        }
                    }
                }
                if let Some(h) = hit {
                    bad += 1;
                    *stats.entry(format!("{fam}: {h}")).or_default() += 1;
                }
            }
        }
    }
    println!("{robot}: {bad} / {total} valid start/goal configurations collide with our geometry");
    for (k, v) in stats {
        println!("  {v:4}  {k}");
    }
}
