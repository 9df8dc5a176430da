//! Building blocks shared by the categories: cabinet carcasses, drawers, hinged doors, legs.
//!
//! Conventions of every asset frame: x points out of the front, y to the left, z up; the origin
//! is the centre of the footprint at the bottom. Fronts (drawer fronts, doors) overlay the
//! carcass, so they start at the carcass front plane and move away from it when opened.

use super::Material;
use super::writer::{JointFeel, LinkId, Motion, Part, UrdfWriter};

/// Thickness of board panels (carcass sides, shelves), metres.
pub(crate) const PANEL: f64 = 0.018;
/// Thickness of drawer fronts and cabinet doors, metres.
pub(crate) const FRONT: f64 = 0.02;

/// An open-front box of outer depth `d`, width `wd` and height `h` whose bottom is at `z0`;
/// returns the inner width.
pub(crate) fn carcass(w: &mut UrdfWriter, link: LinkId, d: f64, wd: f64, h: f64, z0: f64, m: Material) -> f64 {
    let t = PANEL;
    let inner = wd - 2.0 * t;
    w.add_all(
        link,
        [
            Part::cuboid([d, t, h], [0.0, -wd / 2.0 + t / 2.0, z0 + h / 2.0], m),
            Part::cuboid([d, t, h], [0.0, wd / 2.0 - t / 2.0, z0 + h / 2.0], m),
            Part::cuboid([d, inner, t], [0.0, 0.0, z0 + t / 2.0], m),
            Part::cuboid([d, inner, t], [0.0, 0.0, z0 + h - t / 2.0], m),
            Part::cuboid([t, inner, h - 2.0 * t], [-d / 2.0 + t / 2.0, 0.0, z0 + h / 2.0], m),
        ],
    );
    inner
}

/// A horizontal board spanning a carcass of depth `d` and inner width `inner` at height `z`
/// (its top face), and the surface on it with `clearance` of free height above.
pub(crate) fn shelf_board(w: &mut UrdfWriter, link: LinkId, d: f64, inner: f64, z: f64, clearance: f64, m: Material) {
    w.add(
        link,
        Part::cuboid([d - PANEL, inner, PANEL], [PANEL / 2.0, 0.0, z - PANEL / 2.0], m),
    );
    surface_in_carcass(w, d, inner, z, clearance);
}

/// The usable surface of a shelf inside a carcass (kept clear of the back panel and the fronts).
pub(crate) fn surface_in_carcass(w: &mut UrdfWriter, d: f64, inner: f64, z: f64, clearance: f64) {
    let x0 = -d / 2.0 + PANEL + 0.01;
    let x1 = d / 2.0 - 0.02;
    w.surface(z, [x0, -inner / 2.0 + 0.01], [x1, inner / 2.0 - 0.01], clearance - 0.01);
}

/// A small bar handle centred at `pos` on a front, `len` long along y (or z when `vertical`).
pub(crate) fn handle(w: &mut UrdfWriter, link: LinkId, pos: [f64; 3], len: f64, vertical: bool) {
    let size = if vertical {
        [0.025, 0.015, len]
    } else {
        [0.025, len, 0.015]
    };
    w.add(link, Part::cuboid(size, pos, Material::Metal));
}

/// A drawer in an opening of a carcass whose front plane is `x_front`: the opening is centred
/// at (`y`, `z`) with width `ow` and height `oh`; the tray reaches `depth` inwards and the drawer
/// slides out 80 % of it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn drawer(
    w: &mut UrdfWriter,
    parent: LinkId,
    name: &str,
    x_front: f64,
    y: f64,
    z: f64,
    ow: f64,
    oh: f64,
    depth: f64,
    m: Material,
) -> LinkId {
    let slide = Motion::Prismatic {
        axis: [1.0, 0.0, 0.0],
        lower: 0.0,
        upper: 0.8 * depth,
    };
    let d = w.child(parent, name, [x_front, y, z], slide, JointFeel::DRAWER);
    let tw = ow - 0.012;
    let th = (oh * 0.7).max(0.05);
    let tz = -oh / 2.0 + 0.01 + th / 2.0;
    let cx = -depth / 2.0 - 0.003;
    let t = 0.012;
    w.add_all(
        d,
        [
            Part::cuboid([FRONT, ow - 0.004, oh - 0.004], [FRONT / 2.0, 0.0, 0.0], m),
            Part::cuboid([depth - 0.006, tw, t], [cx, 0.0, tz - th / 2.0 + t / 2.0], m),
            Part::cuboid([depth - 0.006, t, th], [cx, -tw / 2.0 + t / 2.0, tz], m),
            Part::cuboid([depth - 0.006, t, th], [cx, tw / 2.0 - t / 2.0, tz], m),
            Part::cuboid([t, tw - 2.0 * t, th], [-depth + t / 2.0, 0.0, tz], m),
        ]
        .map(|p| p.fill(leaf_fill(0.0, m))),
    );
    handle(w, d, [FRONT + 0.0125, 0.0, oh * 0.2], (ow * 0.4).min(0.16), false);
    d
}

/// Which side of an opening a door's hinge is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Hinge {
    /// Hinge on the −y side.
    Right,
    /// Hinge on the +y side.
    Left,
}

/// A door hinged on a vertical axis at (`x_front`, `y_hinge`, `z`) (z is the leaf's centre
/// height), `lw` wide and `lh` high, opening outwards up to `max_angle` radians.
#[allow(clippy::too_many_arguments)]
pub(crate) fn side_door(
    w: &mut UrdfWriter,
    parent: LinkId,
    name: &str,
    at: [f64; 3],
    lw: f64,
    lh: f64,
    thickness: f64,
    hinge: Hinge,
    max_angle: f64,
    feel: JointFeel,
    m: Material,
) -> LinkId {
    let (dir, axis) = match hinge {
        Hinge::Right => (1.0, [0.0, 0.0, -1.0]),
        Hinge::Left => (-1.0, [0.0, 0.0, 1.0]),
    };
    let swing = Motion::Revolute {
        axis,
        lower: 0.0,
        upper: max_angle,
    };
    let d = w.child(parent, name, at, swing, feel);
    let leaf = Part::cuboid([thickness, lw, lh], [thickness / 2.0, dir * lw / 2.0, 0.0], m);
    w.add(d, leaf.fill(leaf_fill(thickness, m)));
    let handle_y = dir * (lw - 0.05);
    handle(w, d, [thickness + 0.0125, handle_y, 0.0], (lh * 0.25).min(0.2), true);
    d
}

/// Solid fraction of a door leaf: steel appliance doors are insulated shells, glass leaves are
/// framed panes, thick wooden leaves are hollow-core; thin board doors are solid.
fn leaf_fill(thickness: f64, m: Material) -> f64 {
    match m {
        Material::Metal => 0.04,
        Material::Glass => 0.25,
        _ if thickness > 0.03 => 0.5,
        _ => 1.0,
    }
}

/// A door hinged at its bottom edge (ovens, dishwashers): the leaf rises from `at` and opens
/// outwards and down by up to 1.5 rad.
pub(crate) fn drop_door(
    w: &mut UrdfWriter,
    parent: LinkId,
    name: &str,
    at: [f64; 3],
    lw: f64,
    lh: f64,
    m: Material,
) -> LinkId {
    let swing = Motion::Revolute {
        axis: [0.0, 1.0, 0.0],
        lower: 0.0,
        upper: 1.5,
    };
    let d = w.child(parent, name, at, swing, JointFeel::HINGE);
    w.add(d, Part::cuboid([0.03, lw, lh], [0.015, 0.0, lh / 2.0], m).fill(0.1));
    handle(w, d, [0.0425, 0.0, lh - 0.05], lw * 0.7, false);
    d
}

/// Leg style of tables, chairs and cabinets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Legs {
    /// Square section.
    Square,
    /// Round section.
    Round,
}

/// Four legs of height `h` under a top of depth `d` and width `wd`, inset by `inset`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn four_legs(
    w: &mut UrdfWriter,
    link: LinkId,
    d: f64,
    wd: f64,
    h: f64,
    inset: f64,
    style: Legs,
    m: Material,
) {
    let s = 0.045;
    for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
        let pos = [sx * (d / 2.0 - inset), sy * (wd / 2.0 - inset), h / 2.0];
        let part = match style {
            Legs::Square => Part::cuboid([s, s, h], pos, m),
            Legs::Round => Part::cylinder(s / 2.0, h, pos, m),
        };
        w.add(link, part);
    }
}

/// A slab of depth `d`, width `wd`, thickness `t` whose top is at `z`, with an open surface.
pub(crate) fn top_slab(w: &mut UrdfWriter, link: LinkId, d: f64, wd: f64, t: f64, z: f64, m: Material) {
    w.add(link, Part::cuboid([d, wd, t], [0.0, 0.0, z - t / 2.0], m));
    open_top(w, d, wd, z, 0.6);
}

/// Declares the open top of a piece `d` deep and `wd` wide at height `z` as a surface with
/// `clearance` of free height above it.
pub(crate) fn open_top(w: &mut UrdfWriter, d: f64, wd: f64, z: f64, clearance: f64) {
    let (x, y) = (d / 2.0 - 0.03, wd / 2.0 - 0.03);
    w.surface(z, [-x, -y], [x, y], clearance);
}

/// A stack of `n` equal drawers filling an opening column centred at `y`, from `z0` to `z1`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn drawer_column(
    w: &mut UrdfWriter,
    parent: LinkId,
    prefix: &str,
    first: usize,
    x_front: f64,
    y: f64,
    ow: f64,
    z0: f64,
    z1: f64,
    n: usize,
    depth: f64,
    m: Material,
) {
    let oh = (z1 - z0) / n as f64;
    for k in 0..n {
        let z = z0 + oh * (k as f64 + 0.5);
        drawer(
            w,
            parent,
            &format!("{prefix}{}", first + k),
            x_front,
            y,
            z,
            ow,
            oh,
            depth,
            m,
        );
    }
}

/// A pair (or single) of doors covering an opening centred at `y` of width `ow`, bottom `z0`
/// and height `oh`, hinged at the outer edges.
#[allow(clippy::too_many_arguments)]
pub(crate) fn door_pair(
    w: &mut UrdfWriter,
    parent: LinkId,
    prefix: &str,
    x_front: f64,
    y: f64,
    ow: f64,
    z0: f64,
    oh: f64,
    count: usize,
    m: Material,
) {
    let zc = z0 + oh / 2.0;
    if count <= 1 {
        let at = [x_front, y - ow / 2.0, zc];
        side_door(
            w,
            parent,
            &format!("{prefix}0"),
            at,
            ow - 0.004,
            oh - 0.004,
            FRONT,
            Hinge::Right,
            1.9,
            JointFeel::HINGE,
            m,
        );
        return;
    }
    let lw = ow / 2.0 - 0.003;
    let right = [x_front, y - ow / 2.0, zc];
    let left = [x_front, y + ow / 2.0, zc];
    side_door(
        w,
        parent,
        &format!("{prefix}0"),
        right,
        lw,
        oh - 0.004,
        FRONT,
        Hinge::Right,
        1.9,
        JointFeel::HINGE,
        m,
    );
    side_door(
        w,
        parent,
        &format!("{prefix}1"),
        left,
        lw,
        oh - 0.004,
        FRONT,
        Hinge::Left,
        1.9,
        JointFeel::HINGE,
        m,
    );
}
