//! Procedurally generated homes.
//!
//! Layout: a corridor runs along x; rooms line both of its sides, each with a doorway (holding
//! an articulated `door`, left open) into the corridor and windows in its outer wall. Furniture
//! is placed by room type along walls and in clusters (table with chairs, sofa facing a TV
//! stand, bed between nightstands, desk with a chair), then small objects are packed onto the
//! surfaces of the furniture (worktops, shelves, cabinet interiors, tables, nightstands).
//!
//! Every footprint is checked against the placed ones and against keep-out zones: the door
//! swing, and a 1 m wide lane from the door to the room centre, so a robot of radius 0.3 m can
//! reach every room centre. Objects rest on their supports (z from the support height); settling
//! is left to the physics world. The same options give the same scene, byte for byte.

use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::footprint::Footprint;
use super::validate::AssetCache;
use super::{
    BoundingBox, Building, Light, LightKind, Opening, OpeningKind, Orientation, RobotPlacement, Room, SceneError,
    SceneFile, SceneObject, Slab, Wall,
};
use crate::assets::{
    Asset, AssetSpec, Category, Material, RoomType, door_opening_width, opening_heights, window_opening_width,
};

/// Width of the corridor between wall centre lines, metres.
const CORRIDOR: f64 = 1.6;
/// Wall height, metres.
const WALL_HEIGHT: f64 = 2.7;
/// Exterior and interior wall thickness, metres.
const EXTERIOR: f64 = 0.2;
const INTERIOR: f64 = 0.12;
/// Clearance kept between furniture footprints, metres.
const GAP: f64 = 0.03;
/// Width of the lane kept free from each door to its room centre, metres.
const LANE: f64 = 1.0;

/// Options of [`generate`].
///
/// ```
/// let o = hearth_sim::scene::GenerateOptions { seed: 7, ..Default::default() };
/// assert_eq!(o.rooms, 5);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GenerateOptions {
    /// Random seed; the same seed gives the same home.
    pub seed: u64,
    /// Number of rooms besides the corridor, 2 to 12.
    pub rooms: usize,
    /// Built-in robot to place in the corridor, if any.
    pub robot: Option<String>,
    /// Whether to put small objects on surfaces.
    pub small_objects: bool,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            seed: 0,
            rooms: 5,
            robot: Some("fetch".to_owned()),
            small_objects: true,
        }
    }
}

/// Room types in the order homes get them.
const ROOM_ORDER: [RoomType; 12] = [
    RoomType::Kitchen,
    RoomType::LivingRoom,
    RoomType::Bedroom,
    RoomType::Bathroom,
    RoomType::Bedroom,
    RoomType::Office,
    RoomType::DiningRoom,
    RoomType::Bedroom,
    RoomType::Bathroom,
    RoomType::Office,
    RoomType::Bedroom,
    RoomType::LivingRoom,
];

fn width_range(t: RoomType) -> (f64, f64) {
    match t {
        RoomType::Kitchen => (4.0, 5.0),
        RoomType::LivingRoom => (5.0, 6.0),
        RoomType::Bedroom => (4.2, 5.0),
        RoomType::Bathroom => (2.8, 3.4),
        RoomType::Office => (3.4, 4.0),
        RoomType::DiningRoom => (4.0, 4.8),
        RoomType::Corridor => (2.0, 2.0),
    }
}

/// A wall side of a rectangular room, named by where it lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    South,
    North,
    West,
    East,
}

const SIDES: [Side; 4] = [Side::South, Side::North, Side::West, Side::East];

impl Side {
    /// Heading of the inward normal.
    fn yaw(self) -> f64 {
        match self {
            Side::South => FRAC_PI_2,
            Side::North => -FRAC_PI_2,
            Side::West => 0.0,
            Side::East => PI,
        }
    }

    fn opposite(self) -> Side {
        match self {
            Side::South => Side::North,
            Side::North => Side::South,
            Side::West => Side::East,
            Side::East => Side::West,
        }
    }

    fn horizontal(self) -> bool {
        matches!(self, Side::South | Side::North)
    }
}

/// A room being furnished: its interior (inside the wall surfaces) and what is taken.
struct RoomPlan {
    name: String,
    kind: RoomType,
    lo: [f64; 2],
    hi: [f64; 2],
    door_side: Side,
    /// Outline on the wall centre lines: x0, y0, x1, y1.
    outline: [f64; 4],
    taken: Vec<Footprint>,
    furniture: Vec<usize>,
}

impl RoomPlan {
    fn centre(&self) -> [f64; 2] {
        [(self.lo[0] + self.hi[0]) / 2.0, (self.lo[1] + self.hi[1]) / 2.0]
    }

    fn fits(&self, f: &Footprint) -> bool {
        let (a, b) = f.aabb();
        let inside = a[0] >= self.lo[0] - 1e-6
            && a[1] >= self.lo[1] - 1e-6
            && b[0] <= self.hi[0] + 1e-6
            && b[1] <= self.hi[1] + 1e-6;
        inside && self.taken.iter().all(|t| t.overlap(f) < -GAP)
    }

    /// Position and yaw that put an asset's back against `side` at `along` (x for south and
    /// north sides, y for west and east).
    fn against(&self, side: Side, along: f64, a: &Asset) -> ([f64; 2], f64) {
        let back = -a.aabb_min.x + 0.005;
        let p = match side {
            Side::South => [along, self.lo[1] + back],
            Side::North => [along, self.hi[1] - back],
            Side::West => [self.lo[0] + back, along],
            Side::East => [self.hi[0] - back, along],
        };
        (p, side.yaw())
    }

    fn along_range(&self, side: Side) -> (f64, f64) {
        if side.horizontal() {
            (self.lo[0], self.hi[0])
        } else {
            (self.lo[1], self.hi[1])
        }
    }
}

fn pose(p: [f64; 3], yaw: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    )
}

fn print_of(a: &Asset, p: [f64; 2], z: f64, yaw: f64) -> Footprint {
    Footprint::of_box(&pose([p[0], p[1], z], yaw), &a.aabb_min, &a.aabb_max)
}

/// What small objects go on a support, with weights, and how full its surfaces get.
fn menu(support: Category, room: RoomType) -> (&'static [(Category, f64)], f64) {
    use Category as C;
    match (support, room) {
        (C::Bookcase, _) => (&[(C::Book, 12.0), (C::Vase, 1.0)], 0.6),
        (C::Shelf | C::TopCabinet | C::Counter | C::BottomCabinet, RoomType::Bathroom) => {
            (&[(C::Bottle, 4.0), (C::Mug, 1.0), (C::Bowl, 1.0)], 0.6)
        }
        (C::Shelf, RoomType::Kitchen) => (
            &[
                (C::Bowl, 2.0),
                (C::Plate, 1.0),
                (C::Mug, 2.0),
                (C::Bottle, 2.0),
                (C::Pot, 1.0),
            ],
            0.7,
        ),
        (C::Shelf | C::TvStand, _) => (&[(C::Book, 6.0), (C::Vase, 1.0), (C::Bowl, 0.5)], 0.7),
        (C::Stove, _) => (&[(C::Pot, 1.0)], 0.6),
        (C::BottomCabinet | C::Counter | C::Dishwasher | C::TopCabinet, _) => (
            &[
                (C::Bowl, 3.0),
                (C::Plate, 2.0),
                (C::Mug, 3.0),
                (C::Bottle, 2.0),
                (C::Pot, 1.0),
                (C::Microwave, 0.5),
            ],
            0.75,
        ),
        (C::Table, RoomType::LivingRoom) => (&[(C::Book, 2.0), (C::Mug, 1.0), (C::Vase, 1.0), (C::Laptop, 0.5)], 0.5),
        (C::Table, _) => (
            &[
                (C::Plate, 3.0),
                (C::Bowl, 2.0),
                (C::Mug, 2.0),
                (C::Bottle, 1.0),
                (C::Vase, 0.5),
            ],
            0.6,
        ),
        (C::Nightstand, _) => (&[(C::Lamp, 2.0), (C::Book, 2.0), (C::Mug, 1.0)], 0.7),
        (C::Dresser, _) => (&[(C::Vase, 1.0), (C::Book, 2.0), (C::Lamp, 1.0), (C::Bottle, 1.0)], 0.6),
        (C::Desk, _) => (&[(C::Laptop, 2.0), (C::Lamp, 1.0), (C::Book, 3.0), (C::Mug, 1.0)], 0.6),
        _ => (&[], 0.0),
    }
}

struct Builder {
    rng: Pcg64Mcg,
    cache: AssetCache,
    scene: SceneFile,
    counts: BTreeMap<Category, usize>,
    small: bool,
}

impl Builder {
    fn asset(&mut self, c: Category, v: usize) -> Result<Asset, SceneError> {
        self.cache
            .get(&AssetSpec::new(c, v))
            .cloned()
            .map_err(|reason| SceneError::Asset {
                object: c.name().to_owned(),
                reason: Box::new(reason),
            })
    }

    /// A random variant of a category.
    fn any_asset(&mut self, c: Category) -> Result<Asset, SceneError> {
        let v = self.rng.random_range(0..c.variants());
        self.asset(c, v)
    }

    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.rng.random_range(0..items.len())]
    }

    /// Adds an object and returns its index.
    fn add(&mut self, a: &Asset, p: [f64; 3], yaw: f64, room: &str, on: Option<usize>) -> usize {
        let n = self.counts.entry(a.category).or_insert(0);
        let name = format!("{}_{n}", a.category.name());
        *n += 1;
        let mut o = SceneObject::new(&name, a.category.name(), a.variant, p);
        o.orientation = Orientation::Yaw(yaw);
        o.fixed = matches!(
            a.category,
            Category::BottomCabinet
                | Category::TopCabinet
                | Category::Counter
                | Category::Fridge
                | Category::Stove
                | Category::Dishwasher
                | Category::Toilet
                | Category::Bathtub
                | Category::Door
                | Category::Window
                | Category::Wardrobe
        );
        o.room = Some(room.to_owned());
        o.on = on.map(|i| self.scene.objects[i].name.clone());
        o.bbox = Some(BoundingBox {
            min: a.aabb_min.into(),
            max: a.aabb_max.into(),
        });
        match a.category {
            Category::Door => {
                o.joints.insert("leaf_hinge".into(), 1.45);
            }
            Category::Laptop if p[2] > 0.0 => {
                o.joints.insert("lid_hinge".into(), 1.5);
            }
            _ => {}
        }
        self.scene.objects.push(o);
        self.scene.objects.len() - 1
    }

    /// Places an asset on the floor at a footprint that fits; records it.
    fn commit(&mut self, room: &mut RoomPlan, a: &Asset, p: [f64; 2], yaw: f64) -> usize {
        room.taken.push(print_of(a, p, 0.0, yaw));
        let i = self.add(a, [p[0], p[1], 0.0], yaw, &room.name, None);
        room.furniture.push(i);
        i
    }

    /// Tries random spots along the given sides; returns the object index when one fits.
    fn on_wall(&mut self, room: &mut RoomPlan, c: Category, sides: &[Side]) -> Result<Option<usize>, SceneError> {
        let v = self.rng.random_range(0..c.variants());
        let a = self.asset(c, v)?;
        for _ in 0..40 {
            let side = self.pick(sides);
            let (lo, hi) = room.along_range(side);
            let half = (a.aabb_max.y - a.aabb_min.y) / 2.0;
            if hi - lo < 2.0 * half {
                continue;
            }
            let along = self.rng.random_range(lo + half..=hi - half);
            let (p, yaw) = room.against(side, along, &a);
            if room.fits(&print_of(&a, p, 0.0, yaw)) {
                return Ok(Some(self.commit(room, &a, p, yaw)));
            }
        }
        Ok(None)
    }

    /// Places an asset against `side` exactly at `along`, if it fits.
    fn on_wall_at(&mut self, room: &mut RoomPlan, a: &Asset, side: Side, along: f64) -> Option<usize> {
        let (p, yaw) = room.against(side, along, a);
        room.fits(&print_of(a, p, 0.0, yaw))
            .then(|| self.commit(room, a, p, yaw))
    }

    /// Places a group of assets (offsets and yaws relative to the group) somewhere free.
    fn cluster(&mut self, room: &mut RoomPlan, group: &[(Asset, [f64; 2], f64)]) -> Vec<usize> {
        for _ in 0..60 {
            let c = [
                self.rng.random_range(room.lo[0]..room.hi[0]),
                self.rng.random_range(room.lo[1]..room.hi[1]),
            ];
            let yaw = if self.rng.random_bool(0.5) { 0.0 } else { FRAC_PI_2 };
            let (s, co) = yaw.sin_cos();
            let placed: Vec<([f64; 2], f64)> = group
                .iter()
                .map(|(_, o, y)| ([c[0] + co * o[0] - s * o[1], c[1] + s * o[0] + co * o[1]], yaw + y))
                .collect();
            let prints: Vec<Footprint> = group
                .iter()
                .zip(&placed)
                .map(|((a, _, _), (p, y))| print_of(a, *p, 0.0, *y))
                .collect();
            let ok = prints
                .iter()
                .enumerate()
                .all(|(k, f)| room.fits(f) && prints[..k].iter().all(|g| g.overlap(f) < -GAP));
            if ok {
                return group
                    .iter()
                    .zip(placed)
                    .map(|((a, _, _), (p, y))| self.commit(room, a, p, y))
                    .collect();
            }
        }
        Vec::new()
    }

    /// A table with chairs around it.
    fn dining_set(&mut self, room: &mut RoomPlan, table_variants: &[usize]) -> Result<Vec<usize>, SceneError> {
        let tv = self.pick(table_variants);
        let table = self.asset(Category::Table, tv)?;
        let cv = if self.rng.random_bool(0.7) { 0 } else { 1 };
        let chair = self.asset(Category::Chair, cv)?;
        let (hx, hy) = (table.aabb_max.x, table.aabb_max.y);
        let off = 0.3;
        let mut group = vec![(table, [0.0, 0.0], 0.0)];
        let mut seat = |o: [f64; 2], y: f64| group.push((chair.clone(), o, y));
        if tv == 0 {
            for y in [-0.45, 0.45] {
                seat([hx + off, y], PI);
                seat([-hx - off, y], 0.0);
            }
            seat([0.0, hy + off], -FRAC_PI_2);
            seat([0.0, -hy - off], FRAC_PI_2);
        } else {
            seat([hx + off, 0.0], PI);
            seat([-hx - off, 0.0], 0.0);
            seat([0.0, hy + off], -FRAC_PI_2);
            seat([0.0, -hy - off], FRAC_PI_2);
        }
        let mut placed = self.cluster(room, &group);
        if placed.is_empty() {
            // Fewer chairs: the table and the two chairs on its long sides.
            group.truncate(3);
            placed = self.cluster(room, &group);
        }
        Ok(placed)
    }

    /// Packs small objects onto every surface of object `support`.
    fn fill(&mut self, room: &RoomPlan, support: usize) -> Result<(), SceneError> {
        let sup = self.scene.objects[support].clone();
        let Some(cat) = Category::from_name(&sup.category) else {
            return Ok(());
        };
        let (items, fullness) = menu(cat, room.kind);
        if items.is_empty() || !self.small {
            return Ok(());
        }
        let sup_asset = self.asset(cat, sup.variant)?;
        let sup_pose = sup.pose();
        let yaw = sup.orientation.yaw();
        let total: f64 = items.iter().map(|(_, w)| w).sum();
        let mut taken_tv = false;
        for (k, s) in sup_asset.surfaces.iter().enumerate() {
            let mut x = s.min[0];
            let len = s.max[1] - s.min[1];
            while x < s.max[0] {
                let mut y = s.min[1] + self.rng.random_range(0.0..0.08);
                let stop = s.min[1] + len * self.rng.random_range(fullness * 0.6..=fullness);
                let mut depth: f64 = 0.0;
                let mut misses = 0;
                while y < stop && misses < 4 {
                    let mut r = self.rng.random_range(0.0..total);
                    let mut c = items[0].0;
                    for &(cand, w) in items {
                        if r < w {
                            c = cand;
                            break;
                        }
                        r -= w;
                    }
                    if cat == Category::TvStand && k == 0 && !taken_tv {
                        c = Category::Tv;
                    }
                    let a = self.any_asset(c)?;
                    let (dx, dy) = (a.aabb_max.x - a.aabb_min.x, a.aabb_max.y - a.aabb_min.y);
                    let tall = if c == Category::Laptop {
                        dx + 0.03
                    } else {
                        a.aabb_max.z - a.aabb_min.z
                    };
                    if tall > s.clearance || x + dx > s.max[0] || y + dy > s.max[1] {
                        misses += 1;
                        continue;
                    }
                    let local = Point3::new(x - a.aabb_min.x, y - a.aabb_min.y, s.z - a.aabb_min.z);
                    let p = sup_pose * local;
                    self.add(&a, [p.x, p.y, p.z], yaw, &room.name, Some(support));
                    taken_tv |= c == Category::Tv;
                    let gap = if c == Category::Book {
                        0.004
                    } else {
                        self.rng.random_range(0.02..0.1)
                    };
                    y += dy + gap;
                    depth = depth.max(dx);
                }
                if depth == 0.0 {
                    break;
                }
                x += depth + 0.02;
            }
        }
        Ok(())
    }
}

/// The footprint keeping a door's swing and the lane from the door to the room centre free.
fn keep_outs(room: &RoomPlan, door_x: f64, door_w: f64) -> Vec<Footprint> {
    let z = [-1.0, 4.0];
    let c = room.centre();
    let h = LANE / 2.0;
    let (wall_y, into) = match room.door_side {
        Side::South => (room.lo[1], 1.0),
        _ => (room.hi[1], -1.0),
    };
    let swing_far = wall_y + into * (door_w + 0.2);
    let ys = |a: f64, b: f64| (a.min(b), a.max(b));
    let (s0, s1) = ys(wall_y, swing_far);
    // The lane runs along the door's wall to below the centre, then straight to the centre, so
    // the far half of the room stays free for beds and sofas.
    let (b0, b1) = ys(wall_y, wall_y + into * LANE);
    let (l0, l1) = ys(wall_y, c[1] + into * h);
    vec![
        Footprint::rect(
            [door_x - door_w / 2.0 - 0.15, s0],
            [door_x + door_w / 2.0 + 0.15, s1],
            z,
        ),
        Footprint::rect([door_x.min(c[0]) - h, b0], [door_x.max(c[0]) + h, b1], z),
        Footprint::rect([c[0] - h, l0], [c[0] + h, l1], z),
    ]
}

/// Builds a multi-room home.
///
/// ```
/// use hearth_sim::scene::{GenerateOptions, generate};
/// let home = generate(&GenerateOptions { seed: 3, rooms: 3, ..Default::default() }).unwrap();
/// assert_eq!(home.building.rooms.len(), 4); // three rooms and the corridor
/// assert!(home.objects.len() >= 4 * 40);
/// assert!(home.validate().is_ok());
/// ```
pub fn generate(opts: &GenerateOptions) -> Result<SceneFile, SceneError> {
    if !(2..=12).contains(&opts.rooms) {
        return Err(SceneError::invalid("rooms", format!("{} is not in 2..=12", opts.rooms)));
    }
    if let Some(name) = &opts.robot
        && !hearth_kinematics::builtin_names().contains(&name.as_str())
    {
        return Err(SceneError::UnknownRobot {
            name: name.clone(),
            known: hearth_kinematics::builtin_names().join(", "),
        });
    }
    let mut b = Builder {
        rng: Pcg64Mcg::seed_from_u64(opts.seed),
        cache: AssetCache::default(),
        scene: SceneFile::empty(&format!("home_{}", opts.seed)),
        counts: BTreeMap::new(),
        small: opts.small_objects,
    };
    // Rows of rooms north (odd) and south (even) of the corridor.
    let kinds: Vec<RoomType> = ROOM_ORDER[..opts.rooms].to_vec();
    let depth_n = b.rng.random_range(4.2..5.0);
    let depth_s = b.rng.random_range(4.2..5.0);
    let mut widths: Vec<f64> = kinds
        .iter()
        .map(|&k| {
            let (lo, hi) = width_range(k);
            (b.rng.random_range(lo..=hi) * 10.0).round() / 10.0
        })
        .collect();
    let row_len = |widths: &[f64], parity: usize| widths.iter().skip(parity).step_by(2).sum::<f64>();
    let length = row_len(&widths, 0).max(row_len(&widths, 1));
    // The shorter row's rooms (bathrooms excepted) share the difference.
    for parity in 0..2 {
        let short = length - row_len(&widths, parity);
        let row: Vec<usize> = (parity..widths.len()).step_by(2).collect();
        let growing: Vec<usize> = row
            .iter()
            .copied()
            .filter(|&i| kinds[i] != RoomType::Bathroom)
            .collect();
        let growing = if growing.is_empty() { row } else { growing };
        for &i in &growing {
            widths[i] += short / growing.len() as f64;
        }
    }
    let (south, north) = (-depth_s, CORRIDOR + depth_n);
    let wall_half = |coord: f64, lo: f64, hi: f64| {
        if (coord - lo).abs() < 1e-9 || (coord - hi).abs() < 1e-9 {
            EXTERIOR / 2.0
        } else {
            INTERIOR / 2.0
        }
    };

    let mut walls = vec![
        Wall::new("wall_south", [0.0, south], [length, south], WALL_HEIGHT, EXTERIOR),
        Wall::new("wall_north", [0.0, north], [length, north], WALL_HEIGHT, EXTERIOR),
        Wall::new("wall_west", [0.0, south], [0.0, north], WALL_HEIGHT, EXTERIOR),
        Wall::new("wall_east", [length, south], [length, north], WALL_HEIGHT, EXTERIOR),
        Wall::new("wall_corridor_south", [0.0, 0.0], [length, 0.0], WALL_HEIGHT, INTERIOR),
        Wall::new(
            "wall_corridor_north",
            [0.0, CORRIDOR],
            [length, CORRIDOR],
            WALL_HEIGHT,
            INTERIOR,
        ),
    ];
    let mut rooms = Vec::new();
    let mut cursor = [0.0, 0.0];
    let mut names: BTreeMap<RoomType, usize> = BTreeMap::new();
    let (door_h, window_h) = opening_heights();
    let mut doors = Vec::new();
    let mut windows = Vec::new();
    for (i, (&kind, &w)) in kinds.iter().zip(&widths).enumerate() {
        let parity = i % 2;
        let x0 = cursor[parity];
        let x1 = x0 + w;
        cursor[parity] = x1;
        let (y0, y1) = if parity == 0 { (CORRIDOR, north) } else { (south, 0.0) };
        let n = names.entry(kind).or_insert(0);
        let name = format!("{}_{n}", kind.name());
        *n += 1;
        if x1 < length - 1e-9 {
            walls.push(Wall::new(
                &format!("wall_{name}_east"),
                [x1, y0],
                [x1, y1],
                WALL_HEIGHT,
                INTERIOR,
            ));
        }
        let lo = [x0 + wall_half(x0, 0.0, length), y0 + wall_half(y0, south, north)];
        let hi = [x1 - wall_half(x1, 0.0, length), y1 - wall_half(y1, south, north)];
        // Door near one end of the corridor wall.
        let dv = b.rng.random_range(0..3);
        let dw = door_opening_width(dv);
        let door_x = if b.rng.random_bool(0.5) {
            x0 + 0.35 + dw / 2.0
        } else {
            x1 - 0.35 - dw / 2.0
        };
        let corridor_wall = if parity == 0 { 5 } else { 4 };
        walls[corridor_wall].openings.push(Opening {
            kind: OpeningKind::Door,
            center: door_x,
            width: dw,
            bottom: 0.0,
            height: door_h,
        });
        let door_side = if parity == 0 { Side::South } else { Side::North };
        doors.push((
            dv,
            [door_x, if parity == 0 { CORRIDOR } else { 0.0 }],
            if parity == 0 { FRAC_PI_2 } else { -FRAC_PI_2 },
            name.clone(),
        ));
        // Windows in the outer wall.
        let count = if w > 3.6 { 2 } else { 1 };
        let outer = if parity == 0 { 1 } else { 0 };
        for k in 0..count {
            let wv = b.rng.random_range(0..3);
            let cx = x0 + w * (k as f64 + 1.0) / (count as f64 + 1.0);
            walls[outer].openings.push(Opening {
                kind: OpeningKind::Window,
                center: cx,
                width: window_opening_width(wv),
                bottom: 0.9,
                height: window_h,
            });
            let wy = if parity == 0 { north } else { south };
            windows.push((
                wv,
                [cx, wy],
                if parity == 0 { -FRAC_PI_2 } else { FRAC_PI_2 },
                name.clone(),
            ));
        }
        let mut plan = RoomPlan {
            name: name.clone(),
            kind,
            lo,
            hi,
            door_side,
            outline: [x0, y0, x1, y1],
            taken: Vec::new(),
            furniture: Vec::new(),
        };
        plan.taken = keep_outs(&plan, door_x, dw);
        rooms.push(plan);
    }
    // The corridor: its doors are on its walls; keep its middle and the doorways free.
    let mut corridor_keep_outs = vec![Footprint::rect([0.9, 0.0], [length - 0.9, CORRIDOR], [-1.0, 4.0])];
    for (v, p, _, _) in &doors {
        let half = door_opening_width(*v) / 2.0 + 0.15;
        corridor_keep_outs.push(Footprint::rect(
            [p[0] - half, 0.0],
            [p[0] + half, CORRIDOR],
            [-1.0, 4.0],
        ));
    }
    let corridor = RoomPlan {
        name: "corridor_0".into(),
        kind: RoomType::Corridor,
        lo: [EXTERIOR / 2.0, INTERIOR / 2.0],
        hi: [length - EXTERIOR / 2.0, CORRIDOR - INTERIOR / 2.0],
        door_side: Side::South,
        outline: [0.0, 0.0, length, CORRIDOR],
        taken: corridor_keep_outs,
        furniture: Vec::new(),
    };

    // Building elements.
    let all: Vec<&RoomPlan> = rooms.iter().chain(std::iter::once(&corridor)).collect();
    let mut room_list = Vec::new();
    for r in &all {
        let [x0, y0, x1, y1] = r.outline;
        let polygon = vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
        let floor_mat = match r.kind {
            RoomType::Kitchen | RoomType::Bathroom => Material::Stone,
            _ => Material::Wood,
        };
        b.scene.building.floors.push(Slab {
            name: format!("floor_{}", r.name),
            polygon: polygon.clone(),
            z: 0.0,
            thickness: 0.1,
            material: floor_mat,
        });
        b.scene.building.ceilings.push(Slab {
            name: format!("ceiling_{}", r.name),
            polygon: polygon.clone(),
            z: WALL_HEIGHT,
            thickness: 0.1,
            material: Material::Plaster,
        });
        room_list.push(Room {
            name: r.name.clone(),
            room_type: r.kind,
            polygon,
        });
        let c = [(x0 + x1) / 2.0, (y0 + y1) / 2.0];
        b.scene.lights.push(Light {
            name: format!("light_{}", r.name),
            kind: LightKind::Point,
            position: [c[0], c[1], WALL_HEIGHT - 0.2],
            direction: None,
            color: [1.0, 0.95, 0.88],
            intensity: 10.0 * (x1 - x0) * (y1 - y0),
        });
    }
    b.scene.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        position: [length / 2.0, 0.0, 10.0],
        direction: Some([0.3, 0.4, -1.0]),
        color: [1.0, 1.0, 0.95],
        intensity: 3.0,
    });
    b.scene.building = Building {
        walls,
        rooms: room_list,
        ..std::mem::take(&mut b.scene.building)
    };
    for (v, p, yaw, room) in doors {
        let a = b.asset(Category::Door, v)?;
        b.add(&a, [p[0], p[1], 0.0], yaw, &room, None);
    }
    for (v, p, yaw, room) in windows {
        let a = b.asset(Category::Window, v)?;
        b.add(&a, [p[0], p[1], 0.9], yaw, &room, None);
    }

    for mut r in rooms.into_iter().chain(std::iter::once(corridor)) {
        furnish(&mut b, &mut r)?;
        for i in r.furniture.clone() {
            b.fill(&r, i)?;
        }
    }
    if let Some(name) = &opts.robot {
        b.scene.robot = Some(RobotPlacement {
            name: name.clone(),
            position: [length / 2.0, CORRIDOR / 2.0, 0.0],
            yaw: 0.0,
        });
    }
    b.scene.validate()?;
    Ok(b.scene)
}

/// Furniture of one room by its type.
fn furnish(b: &mut Builder, r: &mut RoomPlan) -> Result<(), SceneError> {
    use Category as C;
    let walls_but_door: Vec<Side> = SIDES.iter().copied().filter(|&s| s != r.door_side).collect();
    let back = r.door_side.opposite();
    match r.kind {
        RoomType::Kitchen => {
            kitchen_run(b, r)?;
            for _ in 0..3 {
                b.on_wall(r, C::BottomCabinet, &[back])?;
            }
            b.on_wall(r, C::Shelf, &walls_but_door)?;
            b.dining_set(r, &[1, 3])?;
        }
        RoomType::LivingRoom => {
            living_set(b, r)?;
            for c in [C::Bookcase, C::Shelf, C::Shelf, C::Plant, C::FloorLamp, C::Plant] {
                b.on_wall(r, c, &walls_but_door)?;
            }
            let arm = b.asset(C::Chair, 2)?;
            b.cluster(r, &[(arm, [0.0, 0.0], 0.0)]);
        }
        RoomType::Bedroom => {
            bed_set(b, r, back)?;
            for c in [C::Wardrobe, C::Dresser, C::Bookcase, C::Plant] {
                b.on_wall(r, c, &walls_but_door)?;
            }
            desk_set(b, r, &walls_but_door)?;
            rug(b, r, 0)?;
        }
        RoomType::Bathroom => {
            b.on_wall(r, C::Bathtub, &[back])?;
            b.on_wall(r, C::Toilet, &walls_but_door)?;
            if let Some(i) = b.on_wall(r, C::Counter, &walls_but_door)? {
                let o = b.scene.objects[i].clone();
                let side = side_of(o.orientation.yaw());
                let along = if side.horizontal() {
                    o.position[0]
                } else {
                    o.position[1]
                };
                let top = b.asset(C::TopCabinet, 1)?;
                let (p, yaw) = r.against(side, along, &top);
                let idx = b.add(&top, [p[0], p[1], 1.45], yaw, &r.name.clone(), None);
                r.furniture.push(idx);
            }
            b.on_wall(r, C::Shelf, &walls_but_door)?;
            rug(b, r, 0)?;
        }
        RoomType::Office => {
            desk_set(b, r, &walls_but_door)?;
            for c in [C::Bookcase, C::Bookcase, C::Shelf, C::Plant, C::FloorLamp] {
                b.on_wall(r, c, &walls_but_door)?;
            }
            rug(b, r, 2)?;
        }
        RoomType::DiningRoom => {
            b.dining_set(r, &[0, 1, 3])?;
            for c in [C::BottomCabinet, C::BottomCabinet, C::Shelf, C::Bookcase, C::Plant] {
                b.on_wall(r, c, &walls_but_door)?;
            }
        }
        RoomType::Corridor => {
            for c in [C::Shelf, C::Plant, C::Shelf, C::Plant] {
                b.on_wall(r, c, &[Side::West, Side::East])?;
            }
            let runner = b.asset(C::Rug, 0)?;
            let c = r.centre();
            b.add(&runner, [c[0], c[1], 0.0], 0.0, &r.name.clone(), None);
        }
    }
    Ok(())
}

fn side_of(yaw: f64) -> Side {
    let y = yaw.rem_euclid(2.0 * PI);
    SIDES
        .into_iter()
        .min_by(|a, b| {
            let d = |s: Side| {
                (s.yaw().rem_euclid(2.0 * PI) - y)
                    .abs()
                    .min(2.0 * PI - (s.yaw().rem_euclid(2.0 * PI) - y).abs())
            };
            d(*a).total_cmp(&d(*b))
        })
        .unwrap_or(Side::South)
}

/// A rug of variant `v` in the room centre (rugs may lie under furniture).
fn rug(b: &mut Builder, r: &RoomPlan, v: usize) -> Result<(), SceneError> {
    rug_at(b, r, v, r.centre())
}

/// A rug of variant `v` centred at `p` if it lies inside the room.
fn rug_at(b: &mut Builder, r: &RoomPlan, v: usize, p: [f64; 2]) -> Result<(), SceneError> {
    let a = b.asset(Category::Rug, v)?;
    let (lo, hi) = print_of(&a, p, 0.0, 0.0).aabb();
    if lo[0] >= r.lo[0] && lo[1] >= r.lo[1] && hi[0] <= r.hi[0] && hi[1] <= r.hi[1] {
        b.add(&a, [p[0], p[1], 0.0], 0.0, &r.name.clone(), None);
    }
    Ok(())
}

/// The kitchen's main run along the side wall away from the door: fridge, a cabinet, stove, the
/// sink counter, cabinets, dishwasher, with wall cabinets above the worktop modules.
fn kitchen_run(b: &mut Builder, r: &mut RoomPlan) -> Result<(), SceneError> {
    use Category as C;
    let door_x = r.taken.first().map_or(r.centre()[0], |f| f.c[0]);
    let side = if door_x < r.centre()[0] { Side::East } else { Side::West };
    let modules = [
        C::Fridge,
        C::BottomCabinet,
        C::Stove,
        C::Counter,
        C::BottomCabinet,
        C::Dishwasher,
        C::BottomCabinet,
        C::BottomCabinet,
    ];
    // Start at the corner far from the door (the outer wall).
    let (lo, hi) = r.along_range(side);
    let from_hi = r.door_side == Side::South;
    let mut cursor = if from_hi { hi } else { lo };
    for c in modules {
        let v = b.rng.random_range(0..c.variants());
        // Every kitchen gets its sink: a counter that does not fit is tried again in its other
        // variants (without drawing), before the module is given up.
        let mut variants = vec![v];
        if c == C::Counter {
            variants.extend((0..c.variants()).filter(|&o| o != v));
        }
        let mut placed_at = None;
        for v in variants {
            let a = b.asset(c, v)?;
            // The module's extent along the wall is its own y extent (the walls run along world y).
            let width = a.aabb_max.y - a.aabb_min.y;
            // Modules stand side by side, just over the placement clearance apart; one that does
            // not fit is skipped and the next, maybe narrower, is tried.
            let step = width / 2.0 + GAP + 0.005;
            let along = if from_hi { cursor - step } else { cursor + step };
            if along - width / 2.0 < lo - 1e-9 || along + width / 2.0 > hi + 1e-9 {
                continue;
            }
            if let Some(i) = b.on_wall_at(r, &a, side, along) {
                placed_at = Some((i, a, width));
                break;
            }
        }
        let Some((i, a, width)) = placed_at else {
            continue;
        };
        let placed = print_of(
            &a,
            [b.scene.objects[i].position[0], b.scene.objects[i].position[1]],
            0.0,
            side.yaw(),
        );
        let (plo, phi) = placed.aabb();
        cursor = if from_hi { plo[1] } else { phi[1] };
        if matches!(c, C::BottomCabinet | C::Counter | C::Dishwasher) {
            let tv = [1usize, 0, 2].into_iter().find(|&tv| {
                b.asset(C::TopCabinet, tv)
                    .is_ok_and(|t| t.aabb_max.y - t.aabb_min.y <= width + 0.01)
            });
            if let Some(tv) = tv {
                let top = b.asset(C::TopCabinet, tv)?;
                let centre = (plo[1] + phi[1]) / 2.0;
                let (p, yaw) = r.against(side, centre, &top);
                let idx = b.add(&top, [p[0], p[1], 1.45], yaw, &r.name.clone(), None);
                r.furniture.push(idx);
            }
        }
    }
    Ok(())
}

/// TV stand with a TV, a sofa facing it, a coffee table and a rug between them.
fn living_set(b: &mut Builder, r: &mut RoomPlan) -> Result<(), SceneError> {
    use Category as C;
    let first = if b.rng.random_bool(0.5) { Side::West } else { Side::East };
    let stand = b.any_asset(C::TvStand)?;
    let sofa = b.any_asset(C::Sofa)?;
    for stand_side in [first, first.opposite()] {
        let (lo, hi) = r.along_range(stand_side);
        for _ in 0..15 {
            let along = b.rng.random_range(lo + 1.4..(hi - 1.4).max(lo + 1.41));
            if b.on_wall_at(r, &stand, stand_side, along).is_none() {
                continue;
            }
            let Some(sofa_i) = b.on_wall_at(r, &sofa, stand_side.opposite(), along) else {
                // No sofa opposite: keep the stand, the sofa goes elsewhere.
                let sides: Vec<Side> = SIDES.into_iter().filter(|&s| s != r.door_side).collect();
                b.on_wall(r, C::Sofa, &sides)?;
                return Ok(());
            };
            let o = b.scene.objects[sofa_i].clone();
            let yaw = o.orientation.yaw();
            let table = b.asset(C::Table, 2)?;
            let reach = sofa.aabb_max.x + 0.4 + table.aabb_max.x;
            let p = [o.position[0] + reach * yaw.cos(), o.position[1] + reach * yaw.sin()];
            if r.fits(&print_of(&table, p, 0.0, 0.0)) {
                b.commit(r, &table, p, 0.0);
            }
            return rug_at(b, r, 1, p);
        }
    }
    // No facing pair fits: place both wherever they do.
    let sides: Vec<Side> = SIDES.into_iter().filter(|&s| s != r.door_side).collect();
    b.on_wall(r, C::TvStand, &sides)?;
    b.on_wall(r, C::Sofa, &sides)?;
    Ok(())
}

/// A bed against `side` with a nightstand on each side.
fn bed_set(b: &mut Builder, r: &mut RoomPlan, side: Side) -> Result<(), SceneError> {
    use Category as C;
    let stand = b.any_asset(C::Nightstand)?;
    let sides = [side, Side::West, Side::East];
    // The chosen size first, then smaller beds if it does not fit.
    let first = b.rng.random_range(0..C::Bed.variants());
    for v in (0..=first).rev() {
        let bed = b.asset(C::Bed, v)?;
        for _ in 0..40 {
            let s = b.pick(&sides);
            let (lo, hi) = r.along_range(s);
            let half = bed.aabb_max.y;
            if hi - lo < 2.0 * half {
                continue;
            }
            let along = b.rng.random_range(lo + half..=hi - half);
            if b.on_wall_at(r, &bed, s, along).is_none() {
                continue;
            }
            // A nightstand on each side where there is room.
            let off = bed.aabb_max.y + stand.aabb_max.y + GAP + 0.01;
            b.on_wall_at(r, &stand, s, along - off);
            b.on_wall_at(r, &stand, s, along + off);
            return Ok(());
        }
    }
    Ok(())
}

/// A desk against a wall with a chair in front of it.
fn desk_set(b: &mut Builder, r: &mut RoomPlan, sides: &[Side]) -> Result<(), SceneError> {
    use Category as C;
    let chair = b.asset(C::Chair, 0)?;
    let Some(d) = b.on_wall(r, C::Desk, sides)? else {
        return Ok(());
    };
    let o = b.scene.objects[d].clone();
    let desk = b.asset(C::Desk, o.variant)?;
    let yaw = o.orientation.yaw();
    let reach = desk.aabb_max.x + 0.3;
    let p = [o.position[0] + reach * yaw.cos(), o.position[1] + reach * yaw.sin()];
    if r.fits(&print_of(&chair, p, 0.0, yaw + PI)) {
        b.commit(r, &chair, p, yaw + PI);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn room_count_is_checked() {
        let err = generate(&GenerateOptions {
            rooms: 40,
            ..Default::default()
        })
        .unwrap_err();
        assert!(err.to_string().contains("rooms"));
    }

    #[test]
    fn side_of_yaw_inverts_side_yaw() {
        for s in SIDES {
            assert_eq!(side_of(s.yaw()), s);
        }
    }
}
