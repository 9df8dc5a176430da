//! Furniture: tables, chairs, sofas, beds, shelves, bookcases, storage, desks, lamps, plants, rugs.

use super::Material;
use super::parts::{
    Legs, PANEL, carcass, door_pair, drawer, drawer_column, four_legs, open_top, shelf_board, surface_in_carcass,
    top_slab,
};
use super::writer::{Part, UrdfWriter};

/// Table: rectangular dining, round pedestal, low coffee table, small square.
pub(crate) fn table(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    if v == 1 {
        let (r, h) = (0.5, 0.75);
        w.add_all(
            b,
            [
                Part::cylinder(r, 0.03, [0.0, 0.0, h - 0.015], m),
                Part::cylinder(0.05, h - 0.06, [0.0, 0.0, (h - 0.03) / 2.0 + 0.015], m),
                Part::cylinder(0.3, 0.03, [0.0, 0.0, 0.015], m),
            ],
        );
        let s = r * std::f64::consts::FRAC_1_SQRT_2 - 0.02;
        w.surface(h, [-s, -s], [s, s], 0.6);
        return;
    }
    let (d, wd, h, legs) = [
        (0.9, 1.6, 0.75, Legs::Square),
        (0.0, 0.0, 0.0, Legs::Round),
        (0.6, 1.1, 0.45, Legs::Round),
        (0.8, 0.8, 0.75, Legs::Square),
    ][v];
    let t = 0.035;
    top_slab(w, b, d, wd, t, h, m);
    four_legs(w, b, d, wd, h - t, 0.05, legs, m);
}

/// Chair: four legs with a back, round stool, upholstered armchair.
pub(crate) fn chair(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    let seat = 0.45;
    match v {
        0 => {
            let s = 0.45;
            four_legs(w, b, s, s, seat - 0.03, 0.03, Legs::Square, m);
            w.add_all(
                b,
                [
                    Part::cuboid([s, s, 0.03], [0.0, 0.0, seat - 0.015], m),
                    Part::cuboid([0.03, s, 0.45], [-s / 2.0 + 0.015, 0.0, seat + 0.225], m),
                ],
            );
        }
        1 => {
            w.add_all(
                b,
                [
                    Part::cylinder(0.18, 0.04, [0.0, 0.0, 0.63], m),
                    Part::cylinder(0.025, 0.6, [0.0, 0.0, 0.31], Material::Metal).fill(0.3),
                    Part::cylinder(0.2, 0.02, [0.0, 0.0, 0.01], Material::Metal).fill(0.25),
                ],
            );
        }
        _ => {
            let f = Material::Fabric;
            w.add_all(
                b,
                [
                    Part::cuboid([0.75, 0.6, 0.3], [0.0, 0.0, 0.25], f),
                    Part::cuboid([0.1, 0.6, 0.45], [-0.325, 0.0, 0.625], f),
                    Part::cuboid([0.65, 0.1, 0.25], [0.05, -0.35, 0.525], f),
                    Part::cuboid([0.65, 0.1, 0.25], [0.05, 0.35, 0.525], f),
                    Part::cuboid([0.75, 0.8, 0.1], [0.0, 0.0, 0.05], m).fill(0.3),
                ],
            );
        }
    }
}

/// Sofa with 2, 3 or 4 seats.
pub(crate) fn sofa(w: &mut UrdfWriter, v: usize, m: Material) {
    let wd = [1.6, 2.1, 2.6][v];
    let d = 0.9;
    let b = w.base();
    w.add_all(
        b,
        [
            Part::cuboid([d, wd, 0.15], [0.0, 0.0, 0.125], Material::Wood).fill(0.15),
            Part::cylinder(0.025, 0.05, [0.35, -wd / 2.0 + 0.1, 0.025], Material::Rubber),
            Part::cylinder(0.025, 0.05, [0.35, wd / 2.0 - 0.1, 0.025], Material::Rubber),
            Part::cylinder(0.025, 0.05, [-0.35, -wd / 2.0 + 0.1, 0.025], Material::Rubber),
            Part::cylinder(0.025, 0.05, [-0.35, wd / 2.0 - 0.1, 0.025], Material::Rubber),
            Part::cuboid([d - 0.2, wd - 0.4, 0.2], [0.1, 0.0, 0.3], m),
            Part::cuboid([0.2, wd, 0.6], [-d / 2.0 + 0.1, 0.0, 0.5], m),
            Part::cuboid([d - 0.2, 0.2, 0.45], [0.1, -wd / 2.0 + 0.1, 0.425], m),
            Part::cuboid([d - 0.2, 0.2, 0.45], [0.1, wd / 2.0 - 0.1, 0.425], m),
        ],
    );
}

/// Bed: single, double or queen, with a headboard, mattress and pillows.
pub(crate) fn bed(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, len) = [(0.9, 2.0), (1.4, 2.0), (1.6, 2.1)][v];
    let b = w.base();
    let frame_h = 0.3;
    w.add_all(
        b,
        [
            Part::cuboid([len, wd, 0.2], [0.0, 0.0, frame_h - 0.1], m).fill(0.12),
            Part::cuboid([0.05, wd, 0.9], [-len / 2.0 + 0.025, 0.0, 0.45], m),
            Part::cuboid(
                [len - 0.05, wd - 0.04, 0.22],
                [0.025, 0.0, frame_h + 0.11],
                Material::Foam,
            ),
        ],
    );
    four_legs(w, b, len, wd, frame_h - 0.2, 0.04, Legs::Square, m);
    let pillows = if v == 0 { 1 } else { 2 };
    for k in 0..pillows {
        let y = -wd / 2.0 + wd * (k as f64 + 0.5) / pillows as f64;
        w.add(
            b,
            Part::cuboid(
                [0.4, 0.6, 0.12],
                [-len / 2.0 + 0.3, y, frame_h + 0.28],
                Material::Fabric,
            ),
        );
    }
}

/// An open shelf unit of `levels` boards; returns nothing, declares a surface per board.
fn open_shelves(w: &mut UrdfWriter, d: f64, wd: f64, h: f64, levels: usize, m: Material) -> f64 {
    let b = w.base();
    let inner = carcass(w, b, d, wd, h, 0.0, m);
    let gap = (h - PANEL) / levels as f64;
    surface_in_carcass(w, d, inner, PANEL, gap - PANEL);
    for k in 1..levels {
        shelf_board(w, b, d, inner, PANEL + gap * k as f64, gap - PANEL, m);
    }
    inner
}

/// Shelf unit: low and wide, medium, tall and narrow.
pub(crate) fn shelf(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h, levels) = [(1.2, 0.9, 2), (0.8, 1.2, 3), (0.6, 1.8, 5)][v];
    open_shelves(w, 0.32, wd, h, levels, m);
}

/// Bookcase: 5 open levels, wide 6 levels, or 4 levels over two doors.
pub(crate) fn bookcase(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h, levels) = [(0.8, 1.8, 5), (1.0, 2.0, 6), (0.9, 1.9, 5)][v];
    let d = 0.3;
    let inner = open_shelves(w, d, wd, h, levels, m);
    if v == 2 {
        let gap = (h - PANEL) / levels as f64;
        let b = w.base();
        door_pair(w, b, "door_", d / 2.0, 0.0, inner, PANEL, gap - PANEL, 2, m);
    }
}

/// Nightstand: one drawer over a shelf, two drawers, three drawers.
pub(crate) fn nightstand(w: &mut UrdfWriter, v: usize, m: Material) {
    let (d, wd, h) = (0.4, 0.45, 0.55);
    let b = w.base();
    let inner = carcass(w, b, d, wd, h - 0.08, 0.08, m);
    four_legs(w, b, d, wd, 0.08, 0.03, Legs::Round, m);
    open_top(w, d, wd, h, 0.6);
    let (z0, z1) = (0.08 + PANEL, h - PANEL);
    let depth = d - PANEL - 0.03;
    match v {
        0 => {
            let split = z1 - 0.14;
            drawer(
                w,
                b,
                "drawer_0",
                d / 2.0,
                0.0,
                (split + z1) / 2.0,
                inner,
                z1 - split,
                depth,
                m,
            );
            surface_in_carcass(w, d, inner, z0, split - z0 - 0.02);
        }
        1 => drawer_column(w, b, "drawer_", 0, d / 2.0, 0.0, inner, z0, z1, 2, depth, m),
        _ => drawer_column(w, b, "drawer_", 0, d / 2.0, 0.0, inner, z0, z1, 3, depth, m),
    }
}

/// Dresser: 3 wide drawers, 2 columns of 3, or 4 tall drawers.
pub(crate) fn dresser(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h, cols, rows) = [(0.9, 0.85, 1, 3), (1.4, 0.8, 2, 3), (0.8, 1.1, 1, 4)][v];
    let d = 0.5;
    let b = w.base();
    let inner = carcass(w, b, d, wd, h - 0.06, 0.06, m);
    four_legs(w, b, d, wd, 0.06, 0.03, Legs::Square, m);
    open_top(w, d, wd, h, 0.6);
    let col_w = inner / cols as f64;
    for c in 0..cols {
        let y = -inner / 2.0 + col_w * (c as f64 + 0.5);
        let first = c * rows;
        drawer_column(
            w,
            b,
            "drawer_",
            first,
            d / 2.0,
            y,
            col_w,
            0.06 + PANEL,
            h - PANEL,
            rows,
            d - PANEL - 0.03,
            m,
        );
    }
}

/// Wardrobe: two doors, three doors, two doors over two drawers.
pub(crate) fn wardrobe(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, doors) = [(1.0, 2), (1.5, 3), (1.2, 2)][v];
    let (d, h) = (0.6, 2.0);
    let b = w.base();
    let inner = carcass(w, b, d, wd, h, 0.0, m);
    let z0 = if v == 2 { 0.5 } else { PANEL };
    if v == 2 {
        drawer_column(
            w,
            b,
            "drawer_",
            0,
            d / 2.0,
            0.0,
            inner,
            PANEL,
            z0,
            2,
            d - PANEL - 0.03,
            m,
        );
        w.add(
            b,
            Part::cuboid([d - PANEL, inner, PANEL], [PANEL / 2.0, 0.0, z0 - PANEL / 2.0], m),
        );
    }
    shelf_board(w, b, d, inner, h - 0.35, 0.3, m);
    surface_in_carcass(w, d, inner, z0, h - 0.35 - z0 - PANEL);
    let bay = inner / doors as f64;
    let mut left = doors;
    let mut y = -inner / 2.0;
    let mut k = 0;
    while left > 0 {
        let n = if left >= 2 { 2 } else { 1 };
        let ow = bay * n as f64;
        door_pair(
            w,
            b,
            &format!("door_{k}_"),
            d / 2.0,
            y + ow / 2.0,
            ow,
            z0,
            h - PANEL - z0,
            n,
            m,
        );
        y += ow;
        left -= n;
        k += 1;
    }
}

/// Desk: plain on four legs, with a three-drawer pedestal, with a centre drawer.
pub(crate) fn desk(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h, d) = ([1.2, 1.5, 1.4][v], 0.75, 0.7);
    let b = w.base();
    top_slab(w, b, d, wd, 0.03, h, m);
    match v {
        0 => four_legs(w, b, d, wd, h - 0.03, 0.04, Legs::Square, m),
        1 => {
            four_legs(w, b, d, wd, h - 0.03, 0.04, Legs::Round, m);
            let pw = 0.42;
            let y = wd / 2.0 - pw / 2.0 - 0.06;
            let pd = d - 0.1;
            let ph = h - 0.03 - 0.05;
            w.add(b, Part::cuboid([pd, pw, PANEL], [0.0, y, 0.05 + PANEL / 2.0], m));
            w.add(
                b,
                Part::cuboid([PANEL, pw, ph], [-pd / 2.0 + PANEL / 2.0, y, 0.05 + ph / 2.0], m),
            );
            drawer_column(
                w,
                b,
                "drawer_",
                0,
                pd / 2.0,
                y,
                pw - 0.01,
                0.05 + PANEL,
                h - 0.04,
                3,
                pd - 0.05,
                m,
            );
        }
        _ => {
            four_legs(w, b, d, wd, h - 0.03, 0.04, Legs::Square, m);
            let ow = 0.6;
            w.add(b, Part::cuboid([d - 0.1, ow + 0.03, PANEL], [0.0, 0.0, h - 0.15], m));
            drawer(w, b, "drawer_0", d / 2.0 - 0.05, 0.0, h - 0.095, ow, 0.09, d - 0.2, m);
        }
    }
}

/// TV stand: open shelves, two doors, two drawers.
pub(crate) fn tv_stand(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h, d) = ([1.6, 1.2, 1.8][v], 0.5, 0.42);
    let b = w.base();
    let inner = carcass(w, b, d, wd, h - 0.05, 0.05, m);
    four_legs(w, b, d, wd, 0.05, 0.03, Legs::Round, m);
    open_top(w, d, wd, h, 1.0);
    let (z0, z1) = (0.05 + PANEL, h - PANEL);
    match v {
        0 => shelf_board(w, b, d, inner, (z0 + z1) / 2.0, (z1 - z0) / 2.0, m),
        1 => {
            surface_in_carcass(w, d, inner, z0, z1 - z0 - 0.01);
            door_pair(w, b, "door_", d / 2.0, 0.0, inner, z0, z1 - z0, 2, m);
        }
        _ => {
            let half = inner / 2.0;
            for k in 0..2 {
                let y = -inner / 4.0 + half * k as f64;
                drawer(
                    w,
                    b,
                    &format!("drawer_{k}"),
                    d / 2.0,
                    y,
                    (z0 + z1) / 2.0,
                    half,
                    z1 - z0,
                    d - 0.06,
                    m,
                );
            }
        }
    }
}

/// Table lamp: drum shade, tall cone-ish shade, small globe.
pub(crate) fn lamp(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    let (base_r, stem, shade_r, shade_h) = [(0.08, 0.3, 0.14, 0.18), (0.07, 0.4, 0.12, 0.22), (0.06, 0.2, 0.0, 0.0)][v];
    w.add(b, Part::cylinder(base_r, 0.03, [0.0, 0.0, 0.015], m).fill(0.3));
    w.add(
        b,
        Part::cylinder(0.012, stem, [0.0, 0.0, 0.03 + stem / 2.0], m).fill(0.3),
    );
    if shade_r > 0.0 {
        w.add(
            b,
            Part::cylinder(
                shade_r,
                shade_h,
                [0.0, 0.0, 0.03 + stem + shade_h / 2.0 - 0.04],
                Material::Fabric,
            )
            .fill(0.1),
        );
    } else {
        w.add(
            b,
            Part::ball(0.1, [0.0, 0.0, 0.03 + stem + 0.08], Material::Glass).fill(0.05),
        );
    }
}

/// Floor lamp: pole with a shade, three heights.
pub(crate) fn floor_lamp(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    let h = [1.5, 1.65, 1.8][v];
    w.add_all(
        b,
        [
            Part::cylinder(0.15, 0.03, [0.0, 0.0, 0.015], m).fill(0.4),
            Part::cylinder(0.015, h - 0.25, [0.0, 0.0, 0.03 + (h - 0.25) / 2.0], m).fill(0.3),
            Part::cylinder(0.2, 0.25, [0.0, 0.0, h - 0.125 + 0.03], Material::Fabric).fill(0.1),
        ],
    );
}

/// Potted plant: small, medium, tall.
pub(crate) fn plant(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    let (pot_r, pot_h, leaves_r) = [(0.12, 0.25, 0.2), (0.16, 0.35, 0.28), (0.2, 0.4, 0.3)][v];
    w.add(b, Part::cylinder(pot_r, pot_h, [0.0, 0.0, pot_h / 2.0], m).fill(0.3));
    if v == 2 {
        w.add(b, Part::cylinder(0.02, 0.8, [0.0, 0.0, pot_h + 0.4], Material::Foliage));
        w.add(
            b,
            Part::ball(leaves_r, [0.0, 0.0, pot_h + 0.8 + leaves_r * 0.8], Material::Foliage),
        );
    } else {
        w.add(
            b,
            Part::ball(leaves_r, [0.0, 0.0, pot_h + leaves_r * 0.8], Material::Foliage),
        );
    }
}

/// Rug: small rectangle, large rectangle, round.
pub(crate) fn rug(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    // A flat-weave rug: thin enough for low robot bases (the TurtleBot clears ~1 cm).
    let t = 0.006;
    let part = match v {
        0 => Part::cuboid([1.2, 1.8, t], [0.0, 0.0, t / 2.0], m),
        1 => Part::cuboid([2.0, 3.0, t], [0.0, 0.0, t / 2.0], m),
        _ => Part::cylinder(0.8, t, [0.0, 0.0, t / 2.0], m),
    };
    w.add(b, part);
}
