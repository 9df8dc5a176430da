//! `object_nav` measures SPL against the nearest *view* of the target: the estimated viewpoint
//! region agrees with what the camera's semantic image shows, and SPL stays in [0, 1].

use hearth_sim::env::{Ending, Env, EnvConfig, ObsData};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// `examples/configs/object_nav.toml` (a fridge, 5 %, 4:3 camera at 60°) with a small
/// ray-cast camera of the same aspect.
fn config() -> EnvConfig {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/configs/object_nav.toml");
    let mut c = EnvConfig::load(&path).unwrap();
    c.sensors.modalities = vec!["task_obs".into()];
    c.sensors.camera.backend = "raycast".into();
    c.sensors.camera.width = 48;
    c.sensors.camera.height = 36;
    c
}

/// Puts the robot on `xy` facing `target`, steps once with a zero action: (the `task_obs`
/// geodesic distance to a view after the step, the ending, the step's SPL).
fn probe(env: &mut Env, xy: [f64; 2], target: [f64; 2]) -> (f32, Option<Ending>, f64) {
    env.reset(0).unwrap();
    let robot = env.robot();
    let z = env.world().base_pose(robot).unwrap().translation.z;
    let yaw = (target[1] - xy[1]).atan2(target[0] - xy[0]);
    let pose = Isometry3::from_parts(
        Translation3::new(xy[0], xy[1], z),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    );
    env.world_mut().place(robot, &pose).unwrap();
    let step = env.step(&[0.0, 0.0]).unwrap();
    let obs = step.obs.get("task_obs").and_then(ObsData::as_f32).unwrap().to_vec();
    (obs[2], step.info.ending, step.info.metrics.spl)
}

#[test]
fn viewpoints_match_the_rendered_view_and_spl_stays_in_range() {
    let mut env = Env::new(config()).unwrap();
    let (_, info) = env.reset(0).unwrap();
    let (start, goal) = env.start_and_goal();
    let shortest = info.metrics.geodesic_distance;
    assert!((1.0..=8.0).contains(&shortest), "{info:?}");

    // Free cells within 5 m of the fridge, every 7th.
    let maps = env.maps().clone();
    let cells: Vec<[f64; 2]> = (0..maps.traversable.len())
        .filter(|&i| maps.traversable[i])
        .map(|i| maps.cell_center(i % maps.width, i / maps.width))
        .filter(|p| (p[0] - goal[0]).hypot(p[1] - goal[1]) < 5.0)
        .step_by(7)
        .collect();
    assert!(cells.len() > 100, "{}", cells.len());
    // (predicted view, seen) counts.
    let mut table = [[0usize; 2]; 2];
    let mut spls = Vec::new();
    for &p in &cells {
        let (distance, ending, spl) = probe(&mut env, p, goal);
        // Within 1 cm of a view: the distance is interpolated between cell centres, and the
        // robot settles a little off the centre it was put on.
        let predicted = distance < 0.01;
        let seen = ending == Some(Ending::Success);
        table[usize::from(predicted)][usize::from(seen)] += 1;
        if seen {
            // The step's path is the teleport from the start: SPL = shortest / max(path, shortest).
            let path = (p[0] - start[0]).hypot(p[1] - start[1]);
            let want = shortest / path.max(shortest);
            assert!((0.0..=1.0).contains(&spl), "{spl}");
            assert!((spl - want).abs() < 0.05, "SPL {spl} vs {want} at {p:?}");
            spls.push(spl);
        }
    }
    let [[neither, missed], [wrong, right]] = table;
    eprintln!(
        "{} probes: predicted and seen {right}, predicted not seen {wrong}, seen not predicted {missed}, neither {neither}",
        cells.len()
    );
    let agree = (right + neither) as f64 / cells.len() as f64;
    assert!(agree >= 0.9, "agreement {agree:.2}");
    assert!(right >= 10, "{right}");
    // Most predicted viewpoints do show the fridge; most views are predicted.
    assert!(
        right as f64 >= 0.85 * (right + wrong) as f64,
        "precision {right}/{}",
        right + wrong
    );
    assert!(
        right as f64 >= 0.9 * (right + missed) as f64,
        "recall {right}/{}",
        right + missed
    );
    assert!(!spls.is_empty());

    // A view no farther (straight) from the start than the shortest path: teleporting there
    // scores 1. The nearest view lies within the shortest path's length of the start, and the
    // grid's path is longer than the straight line, so such cells exist.
    let mut near: Vec<[f64; 2]> = (0..maps.traversable.len())
        .filter(|&i| maps.traversable[i])
        .map(|i| maps.cell_center(i % maps.width, i / maps.width))
        .filter(|p| (p[0] - start[0]).hypot(p[1] - start[1]) <= shortest - 0.02)
        .collect();
    near.sort_by(|a, b| {
        let d = |p: &[f64; 2]| (p[0] - goal[0]).hypot(p[1] - goal[1]);
        d(a).total_cmp(&d(b))
    });
    let full = near.iter().take(40).find_map(|&p| {
        let (distance, ending, spl) = probe(&mut env, p, goal);
        (distance == 0.0 && ending == Some(Ending::Success)).then_some((p, spl))
    });
    let (p, spl) = full.expect("a view within the shortest path's length of the start");
    eprintln!("start {start:?}, shortest {shortest:.2} m; view at {p:?} scores SPL {spl}");
    assert_eq!(spl, 1.0);
}
