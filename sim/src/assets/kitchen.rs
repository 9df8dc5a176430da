//! Kitchen categories: cabinets, counters with a sink, fridge, stove, dishwasher, microwave.

use super::Material;
use super::parts::{
    FRONT, Hinge, PANEL, carcass, door_pair, drawer, drawer_column, drop_door, handle, shelf_board, side_door,
    surface_in_carcass, top_slab,
};
use super::writer::{JointFeel, Part, UrdfWriter};

/// Depth of a base-cabinet carcass, its plinth and worktop heights (standard 60 cm units).
const BASE_DEPTH: f64 = 0.56;
const PLINTH: f64 = 0.1;
const WORKTOP: f64 = 0.85;

/// Plinth, carcass and marble worktop of a base unit `wd` wide; returns the inner width and the
/// carcass height (the carcass stands on the plinth).
fn base_unit(w: &mut UrdfWriter, wd: f64, carcass_top: f64, m: Material) -> f64 {
    let b = w.base();
    w.add(
        b,
        Part::cuboid([BASE_DEPTH - 0.06, wd - 0.04, PLINTH], [-0.03, 0.0, PLINTH / 2.0], m),
    );
    carcass(w, b, BASE_DEPTH, wd, carcass_top - PLINTH, PLINTH, m)
}

/// Bottom cabinet: 2 doors, 3 drawers, a drawer over 2 doors, or 4 narrow drawers.
pub(crate) fn bottom_cabinet(w: &mut UrdfWriter, v: usize, m: Material) {
    let wd = [0.8, 0.6, 0.9, 0.45][v];
    let top = WORKTOP - 0.03;
    let inner = base_unit(w, wd, top, m);
    let b = w.base();
    top_slab(w, b, 0.6, wd, 0.03, WORKTOP, Material::Marble);
    let xf = BASE_DEPTH / 2.0;
    let (z0, z1) = (PLINTH + PANEL, top - PANEL);
    let depth = BASE_DEPTH - PANEL - 0.03;
    match v {
        0 => {
            shelf_board(w, b, BASE_DEPTH, inner, (z0 + z1) / 2.0, (z1 - z0) / 2.0, m);
            surface_in_carcass(w, BASE_DEPTH, inner, z0, (z1 - z0) / 2.0 - PANEL);
            door_pair(w, b, "door_", xf, 0.0, inner, z0, z1 - z0, 2, m);
        }
        1 => drawer_column(w, b, "drawer_", 0, xf, 0.0, inner, z0, z1, 3, depth, m),
        2 => {
            let split = z1 - 0.16;
            drawer(
                w,
                b,
                "drawer_0",
                xf,
                0.0,
                (split + z1) / 2.0,
                inner,
                z1 - split,
                depth,
                m,
            );
            surface_in_carcass(w, BASE_DEPTH, inner, z0, split - z0 - 0.02);
            door_pair(w, b, "door_", xf, 0.0, inner, z0, split - z0, 2, m);
        }
        _ => drawer_column(w, b, "drawer_", 0, xf, 0.0, inner, z0, z1, 4, depth, m),
    }
}

/// Wall cabinet: one door, two doors, or two glass doors; two shelves inside.
pub(crate) fn top_cabinet(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, doors, front) = [(0.45, 1, m), (0.8, 2, m), (0.9, 2, Material::Glass)][v];
    let (d, h) = (0.33, 0.7);
    let b = w.base();
    let inner = carcass(w, b, d, wd, h, 0.0, m);
    let level = (h - 2.0 * PANEL) / 3.0;
    surface_in_carcass(w, d, inner, PANEL, level - PANEL);
    for k in 1..3 {
        shelf_board(w, b, d, inner, PANEL + level * k as f64, level - PANEL, m);
    }
    door_pair(w, b, "door_", d / 2.0, 0.0, inner, PANEL, h - 2.0 * PANEL, doors, front);
}

/// Counter with a sink (centre, left or right) over a two-door cabinet.
pub(crate) fn counter(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, ys) = [(1.2, 0.0), (1.5, 0.35), (1.8, -0.5)][v];
    let low = 0.65;
    let inner = base_unit(w, wd, low, m);
    let b = w.base();
    let xf = BASE_DEPTH / 2.0;
    // Rails between the low carcass and the worktop, leaving room for the basin.
    let rail = WORKTOP - 0.03 - low;
    let zr = low + rail / 2.0;
    w.add_all(
        b,
        [
            Part::cuboid([BASE_DEPTH, PANEL, rail], [0.0, -wd / 2.0 + PANEL / 2.0, zr], m),
            Part::cuboid([BASE_DEPTH, PANEL, rail], [0.0, wd / 2.0 - PANEL / 2.0, zr], m),
            Part::cuboid([PANEL, inner, rail], [-xf + PANEL / 2.0, 0.0, zr], m),
            Part::cuboid([FRONT, wd, rail], [xf + FRONT / 2.0, 0.0, zr], m),
        ],
    );
    door_pair(
        w,
        b,
        "door_",
        xf,
        0.0,
        inner,
        PLINTH + PANEL,
        low - PLINTH - 2.0 * PANEL,
        2,
        m,
    );
    // Worktop in four pieces around a 0.4 × 0.5 m hole, and the steel basin below it.
    let (hx, hy) = (0.2, 0.25);
    let (x0, x1) = (-0.29, 0.31);
    let zt = WORKTOP - 0.015;
    let marble = Material::Marble;
    let left_w = ys - hy + wd / 2.0;
    let right_w = wd / 2.0 - ys - hy;
    w.add_all(
        b,
        [
            Part::cuboid([-hx - x0, wd, 0.03], [(x0 - hx) / 2.0, 0.0, zt], marble),
            Part::cuboid([x1 - hx, wd, 0.03], [(x1 + hx) / 2.0, 0.0, zt], marble),
            Part::cuboid([2.0 * hx, left_w, 0.03], [0.0, -wd / 2.0 + left_w / 2.0, zt], marble),
            Part::cuboid([2.0 * hx, right_w, 0.03], [0.0, wd / 2.0 - right_w / 2.0, zt], marble),
        ],
    );
    let depth = 0.18;
    let zb = WORKTOP - 0.03 - depth;
    let steel = Material::Metal;
    let wall = 0.004;
    w.add_all(
        b,
        [
            Part::cuboid([2.0 * hx, 2.0 * hy, wall], [0.0, ys, zb + wall / 2.0], steel),
            Part::cuboid([wall, 2.0 * hy, depth], [-hx + wall / 2.0, ys, zb + depth / 2.0], steel),
            Part::cuboid([wall, 2.0 * hy, depth], [hx - wall / 2.0, ys, zb + depth / 2.0], steel),
            Part::cuboid(
                [2.0 * hx, wall, depth],
                [0.0, ys - hy + wall / 2.0, zb + depth / 2.0],
                steel,
            ),
            Part::cuboid(
                [2.0 * hx, wall, depth],
                [0.0, ys + hy - wall / 2.0, zb + depth / 2.0],
                steel,
            ),
            Part::cylinder(0.015, 0.25, [-0.25, ys, WORKTOP + 0.125], steel),
            Part::cylinder(0.012, 0.15, [-0.18, ys, WORKTOP + 0.24], steel).along_x(),
        ],
    );
    for (lo, hi) in [(-wd / 2.0, ys - hy), (ys + hy, wd / 2.0)] {
        if hi - lo > 0.25 {
            w.surface(WORKTOP, [-0.2, lo + 0.03], [x1 - 0.03, hi - 0.03], 0.6);
        }
    }
}

/// Fridge: one door, top freezer with two doors, or French doors over a freezer drawer.
pub(crate) fn fridge(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h) = [(0.6, 1.5), (0.7, 1.75), (0.9, 1.8)][v];
    let d = 0.65;
    let b = w.base();
    // A thin steel shell around an insulated, mostly empty interior.
    w.add(b, Part::cuboid([d, wd, h], [0.0, 0.0, h / 2.0], m).fill(0.012));
    let xf = d / 2.0;
    let t = 0.05;
    let door = |w: &mut UrdfWriter, name: &str, y: f64, z0: f64, z1: f64, lw: f64, hinge: Hinge| {
        let at = [xf, y, (z0 + z1) / 2.0];
        let leaf = side_door(w, b, name, at, lw, z1 - z0 - 0.01, t, hinge, 2.0, JointFeel::HINGE, m);
        let _ = leaf;
    };
    match v {
        0 => door(w, "door_0", -wd / 2.0, 0.05, h, wd, Hinge::Right),
        1 => {
            let split = h - 0.45;
            door(w, "door_0", -wd / 2.0, 0.05, split, wd, Hinge::Right);
            door(w, "door_1", -wd / 2.0, split, h, wd, Hinge::Right);
        }
        _ => {
            let split = 0.65;
            door(w, "door_0", -wd / 2.0, split, h, wd / 2.0 - 0.003, Hinge::Right);
            door(w, "door_1", wd / 2.0, split, h, wd / 2.0 - 0.003, Hinge::Left);
            let inner = wd - 2.0 * PANEL;
            drawer(
                w,
                b,
                "drawer_0",
                xf - 0.03,
                0.0,
                (0.05 + split) / 2.0,
                inner,
                split - 0.06,
                d - 0.1,
                m,
            );
        }
    }
}

/// Stove with an oven: 4 burners 60 cm, 5 burners 76 cm, or 90 cm with a storage drawer.
pub(crate) fn stove(w: &mut UrdfWriter, v: usize, m: Material) {
    let wd = [0.6, 0.76, 0.9][v];
    let (d, h) = (0.6, WORKTOP);
    let b = w.base();
    w.add(b, Part::cuboid([d, wd, h], [0.0, 0.0, h / 2.0], m).fill(0.02));
    w.add(
        b,
        Part::cuboid([0.04, wd, 0.12], [-d / 2.0 + 0.02, 0.0, h + 0.06], m).fill(0.1),
    );
    let burners: &[(f64, f64)] = match v {
        0 => &[(0.12, 0.14), (0.12, -0.14), (-0.12, 0.14), (-0.12, -0.14)],
        1 => &[(0.12, 0.22), (0.12, -0.22), (-0.12, 0.22), (-0.12, -0.22), (0.0, 0.0)],
        _ => &[(0.12, 0.3), (0.12, -0.3), (-0.12, 0.3), (-0.12, -0.3), (0.0, 0.0)],
    };
    for &(x, y) in burners {
        w.add(b, Part::cylinder(0.07, 0.012, [x, y, h + 0.006], Material::Metal));
    }
    for k in 0..burners.len() {
        let y = -wd / 2.0 + wd * (k as f64 + 0.5) / burners.len() as f64;
        w.add(
            b,
            Part::cylinder(0.02, 0.025, [d / 2.0 + 0.0125, y, h - 0.06], Material::Plastic).along_x(),
        );
    }
    let oven_bottom = if v == 2 { 0.22 } else { 0.08 };
    drop_door(
        w,
        b,
        "oven_door",
        [d / 2.0, 0.0, oven_bottom],
        wd - 0.04,
        0.55,
        Material::Glass,
    );
    if v == 2 {
        drawer(w, b, "drawer_0", d / 2.0, 0.0, 0.12, wd - 0.04, 0.16, d - 0.1, m);
    }
    w.surface(h + 0.012, [-0.2, -wd / 2.0 + 0.05], [0.22, wd / 2.0 - 0.05], 0.5);
}

/// Dishwasher under a worktop: steel 60 cm, slim 45 cm, or 60 cm with a wooden front panel.
pub(crate) fn dishwasher(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, front) = [(0.6, m), (0.45, m), (0.6, Material::Wood)][v];
    let body = WORKTOP - 0.03;
    let b = w.base();
    w.add(
        b,
        Part::cuboid([BASE_DEPTH, wd - 0.01, body], [0.0, 0.0, body / 2.0], m).fill(0.015),
    );
    top_slab(w, b, 0.6, wd, 0.03, WORKTOP, Material::Marble);
    drop_door(
        w,
        b,
        "door",
        [BASE_DEPTH / 2.0, 0.0, PLINTH],
        wd - 0.02,
        body - PLINTH - 0.01,
        front,
    );
}

/// Countertop microwave of three sizes, side-hinged door.
pub(crate) fn microwave(w: &mut UrdfWriter, v: usize, m: Material) {
    let (d, wd, h) = [(0.35, 0.45, 0.26), (0.38, 0.5, 0.29), (0.42, 0.56, 0.32)][v];
    let b = w.base();
    w.add(b, Part::cuboid([d, wd, h], [0.0, 0.0, h / 2.0], m).fill(0.03));
    let lw = wd * 0.72;
    side_door(
        w,
        b,
        "door",
        [d / 2.0, wd / 2.0, h / 2.0],
        lw,
        h - 0.02,
        0.02,
        Hinge::Left,
        1.7,
        JointFeel::LID,
        Material::Glass,
    );
    handle(w, b, [d / 2.0 + 0.0125, -wd / 2.0 + wd * 0.14, h / 2.0], 0.05, false);
    w.surface(
        h,
        [-d / 2.0 + 0.03, -wd / 2.0 + 0.03],
        [d / 2.0 - 0.03, wd / 2.0 - 0.03],
        0.3,
    );
}
