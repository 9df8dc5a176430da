//! Procedurally generated homes: validity, density, determinism, reachability.

use std::time::Instant;

use hearth_sim::assets::{Category, Placement};
use hearth_sim::scene::{GenerateOptions, SceneInfo, generate};

fn home(seed: u64) -> hearth_sim::scene::SceneFile {
    generate(&GenerateOptions {
        seed,
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("seed {seed}: {e}"))
}

#[test]
fn homes_reach_forty_objects_per_room() {
    let mut total = 0.0;
    for seed in 0..10 {
        let t = Instant::now();
        let scene = home(seed);
        let dt = t.elapsed();
        let info = SceneInfo::of(&scene);
        println!(
            "seed {seed}: {} rooms, {} objects, {:.1} per room, {} articulated, {:.0} ms",
            info.rooms.len(),
            info.objects,
            info.objects_per_room,
            info.articulated.len(),
            dt.as_secs_f64() * 1e3
        );
        for r in &info.rooms {
            println!("    {} {:.1} m² {}", r.name, r.area, r.objects);
        }
        let missing: Vec<&str> = Category::ALL
            .iter()
            .map(|c| c.name())
            .filter(|c| !info.categories.contains_key(*c))
            .collect();
        println!("    categories missing: {missing:?}");
        assert!(
            info.objects_per_room >= 40.0,
            "seed {seed}: {:.1} objects per room",
            info.objects_per_room
        );
        assert_eq!(info.unassigned, 0);
        total += info.objects_per_room;
    }
    println!("average over seeds 0..10: {:.1} objects per room", total / 10.0);
}

#[test]
fn objects_rest_on_supports_floor_or_walls() {
    for seed in [0, 1, 2] {
        let scene = home(seed);
        let assets = scene.assets().unwrap();
        let mut small = 0;
        for (o, a) in scene.objects.iter().zip(&assets) {
            match (&o.on, a.category.placement()) {
                (Some(s), Placement::OnSurface) => {
                    small += 1;
                    let support = scene.objects.iter().position(|p| &p.name == s).unwrap();
                    let sa = &assets[support];
                    let sz = scene.objects[support].position[2];
                    let on_a_surface = sa.surfaces.iter().any(|f| (sz + f.z - o.position[2]).abs() < 1e-6);
                    assert!(on_a_surface, "seed {seed}: {} floats above {s}", o.name);
                }
                (None, Placement::WallMounted { z }) => assert_eq!(o.position[2], z, "{}", o.name),
                (None, Placement::InWall) => assert!(o.position[2] >= 0.0),
                (None, p) => {
                    assert_ne!(p, Placement::OnSurface, "{} has no support", o.name);
                    assert_eq!(o.position[2], 0.0, "{} is not on the floor", o.name);
                }
                (Some(_), p) => panic!("{} of placement {p:?} rests on another object", o.name),
            }
        }
        assert!(
            small * 2 > scene.objects.len(),
            "seed {seed}: only {small} small objects"
        );
        // Doors stand in doorways: one per room besides the corridor.
        let doors = assets.iter().filter(|a| a.category == Category::Door).count();
        assert_eq!(doors, scene.building.rooms.len() - 1);
    }
}

#[test]
fn rooms_hold_the_furniture_of_their_type() {
    use hearth_sim::assets::RoomType;
    for seed in 0..12 {
        let scene = home(seed);
        for room in &scene.building.rooms {
            let has = |c: &str| {
                scene
                    .objects
                    .iter()
                    .any(|o| o.room.as_deref() == Some(&room.name) && o.category == c)
            };
            let needed: &[&str] = match room.room_type {
                RoomType::Kitchen => &[
                    "fridge",
                    "stove",
                    "counter",
                    "bottom_cabinet",
                    "top_cabinet",
                    "bowl",
                    "mug",
                ],
                RoomType::LivingRoom => &["sofa", "tv_stand", "tv", "book"],
                RoomType::Bedroom => &["bed", "nightstand", "door", "window"],
                RoomType::Bathroom => &["toilet", "bottle"],
                _ => &[],
            };
            for c in needed {
                assert!(has(c), "seed {seed}: {} has no {c}", room.name);
            }
        }
    }
}
