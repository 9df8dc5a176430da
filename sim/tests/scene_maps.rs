//! Traversability maps, room segmentation and shortest paths on generated homes.

use hearth_sim::scene::{GenerateOptions, MapOptions, SceneError, SceneMaps, generate};

fn maps(seed: u64, rooms: usize) -> (hearth_sim::scene::SceneFile, SceneMaps) {
    let scene = generate(&GenerateOptions {
        seed,
        rooms,
        ..Default::default()
    })
    .unwrap();
    let maps = SceneMaps::build(&scene, &MapOptions::default()).unwrap();
    (scene, maps)
}

/// Asserts that the straight segments between waypoints stay on traversable cells (a cell's
/// neighbours count, as waypoints are cell centres of an 8-connected path).
fn assert_path_free(m: &SceneMaps, path: &[[f64; 2]], what: &str) {
    for w in path.windows(2) {
        let n = ((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) / 0.01).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let p = [w[0][0] + t * (w[1][0] - w[0][0]), w[0][1] + t * (w[1][1] - w[0][1])];
            let near = [-0.03, 0.0, 0.03].iter().any(|dx| {
                [-0.03, 0.0, 0.03]
                    .iter()
                    .any(|dy| m.is_traversable([p[0] + dx, p[1] + dy]))
            });
            assert!(near, "{what}: the path leaves the free space at {p:?}");
        }
    }
}

#[test]
fn every_room_centre_reaches_every_other() {
    for (seed, rooms) in [(0, 5), (1, 5), (2, 3), (3, 7), (4, 12), (5, 2)] {
        let (scene, m) = maps(seed, rooms);
        let centres: Vec<[f64; 2]> = scene.building.rooms.iter().map(|r| r.center()).collect();
        for (i, a) in centres.iter().enumerate() {
            assert!(
                m.is_traversable(*a),
                "seed {seed}: centre of {} is blocked",
                scene.building.rooms[i].name
            );
            for b in &centres[i + 1..] {
                let path = m.shortest_path(*a, *b).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
                assert_path_free(&m, &path, &format!("seed {seed}"));
            }
        }
    }
}

#[test]
fn room_ids_match_room_polygons() {
    let (scene, m) = maps(6, 5);
    for r in &scene.building.rooms {
        assert_eq!(m.room_at(r.center()), Some(r.name.as_str()));
    }
    let free = m.free_fraction();
    assert!(free > 0.2 && free < 0.9, "free fraction {free}");
}

#[test]
fn path_queries_fail_with_typed_errors() {
    let (scene, m) = maps(7, 3);
    let c = scene.building.rooms[0].center();
    assert!(matches!(
        m.shortest_path([-100.0, 0.0], c),
        Err(SceneError::OffMap { what: "start", .. })
    ));
    // A point far off prints short.
    let far = m.shortest_path([1e30, -2.5], c).unwrap_err().to_string();
    assert_eq!(far, "start (1.00e30, -2.50) is outside the map");
    assert!(matches!(
        m.shortest_path(c, [f64::NAN, 0.0]),
        Err(SceneError::NonFinite { .. })
    ));
    // A point inside a wall is not traversable.
    let wall = &scene.building.walls[0];
    let inside = wall.point_at(wall.length() / 2.0);
    assert!(matches!(
        m.shortest_path(c, inside),
        Err(SceneError::Blocked { what: "goal", .. })
    ));
}

#[test]
fn walled_off_goal_is_unreachable() {
    // Two rooms without a doorway between them.
    use hearth_sim::assets::RoomType;
    use hearth_sim::scene::{Room, SceneFile, Wall};
    let mut s = SceneFile::empty("two cells");
    let rect = |x0: f64, x1: f64| vec![[x0, 0.0], [x1, 0.0], [x1, 3.0], [x0, 3.0]];
    s.building.rooms.push(Room {
        name: "a".into(),
        room_type: RoomType::Office,
        polygon: rect(0.0, 3.0),
    });
    s.building.rooms.push(Room {
        name: "b".into(),
        room_type: RoomType::Office,
        polygon: rect(3.0, 6.0),
    });
    s.building
        .walls
        .push(Wall::new("split", [3.0, 0.0], [3.0, 3.0], 2.5, 0.1));
    let m = SceneMaps::build(&s, &MapOptions::default()).unwrap();
    assert!(matches!(
        m.shortest_path([1.5, 1.5], [4.5, 1.5]),
        Err(SceneError::NoPath { .. })
    ));
    assert!(m.shortest_path([1.0, 1.0], [2.0, 2.0]).is_ok());
}

#[test]
fn robot_start_is_traversable_and_reaches_every_room() {
    for seed in [10, 11, 12] {
        let (scene, m) = maps(seed, 5);
        let r = scene.robot.as_ref().unwrap();
        let start = [r.position[0], r.position[1]];
        assert!(m.is_traversable(start), "seed {seed}");
        for room in &scene.building.rooms {
            let path = m.shortest_path(start, room.center()).unwrap();
            assert_path_free(&m, &path, &format!("seed {seed}, {}", room.name));
        }
    }
}

#[test]
fn absurd_map_options_are_refused() {
    let scene = hearth_sim::scene::SceneFile::empty("e");
    for opts in [
        MapOptions {
            resolution: 0.0,
            ..Default::default()
        },
        MapOptions {
            resolution: f64::NAN,
            ..Default::default()
        },
        MapOptions {
            robot_radius: 100.0,
            ..Default::default()
        },
    ] {
        assert!(
            matches!(SceneMaps::build(&scene, &opts), Err(SceneError::Invalid { .. })),
            "{opts:?}"
        );
    }
    // A huge house at fine resolution is refused rather than allocated.
    let (home, _) = maps(0, 2);
    let fine = MapOptions {
        resolution: 0.005,
        ..Default::default()
    };
    let mut big = home.clone();
    big.building.rooms[0].polygon[1][0] = 1e5;
    assert!(matches!(SceneMaps::build(&big, &fine), Err(SceneError::Invalid { .. })));
}
