//! Parts of the building that are assets: doors in a wall frame and windows.
//!
//! Both sit in an opening of a wall: the opening spans y, the wall thickness spans x, and +x is
//! the side the door or sash opens towards. A door's origin is the bottom centre of the opening;
//! a window's origin is the centre of its sill.

use super::Material;
use super::parts::{Hinge, side_door};
use super::writer::{JointFeel, Motion, Part, UrdfWriter};

/// Depth of door and window frames (fits walls up to this thick), metres.
pub(crate) const FRAME_DEPTH: f64 = 0.14;
/// Height of a door opening, metres.
pub(crate) const DOOR_HEIGHT: f64 = 2.1;
/// Height of a window opening, metres.
pub(crate) const WINDOW_HEIGHT: f64 = 1.2;

/// Width of the opening a door or window variant fills.
pub(crate) fn opening_width(door: bool, v: usize) -> f64 {
    if door {
        [0.8, 0.9, 1.0][v.min(2)]
    } else {
        [1.0, 1.2, 1.4][v.min(2)]
    }
}

/// A rectangular frame of profile `p` around an opening `wd` × `h` whose bottom is at z = 0.
fn frame(w: &mut UrdfWriter, wd: f64, h: f64, p: f64, sill: bool, m: Material) {
    let b = w.base();
    let d = FRAME_DEPTH;
    w.add_all(
        b,
        [
            Part::cuboid([d, p, h], [0.0, -wd / 2.0 + p / 2.0, h / 2.0], m),
            Part::cuboid([d, p, h], [0.0, wd / 2.0 - p / 2.0, h / 2.0], m),
            Part::cuboid([d, wd - 2.0 * p, p], [0.0, 0.0, h - p / 2.0], m),
        ],
    );
    if sill {
        w.add(b, Part::cuboid([d, wd - 2.0 * p, p], [0.0, 0.0, p / 2.0], m));
    }
}

/// A room door in its frame: 80, 90 or 100 cm; the last variant is hinged on the other side.
pub(crate) fn door(w: &mut UrdfWriter, v: usize, m: Material) {
    let wd = opening_width(true, v);
    let p = 0.04;
    frame(w, wd, DOOR_HEIGHT, p, false, m);
    let b = w.base();
    let lw = wd - 2.0 * p - 0.01;
    let lh = DOOR_HEIGHT - p - 0.015;
    let (y, hinge) = if v == 2 {
        (wd / 2.0 - p - 0.005, Hinge::Left)
    } else {
        (-wd / 2.0 + p + 0.005, Hinge::Right)
    };
    side_door(
        w,
        b,
        "leaf",
        [0.0, y, 0.005 + lh / 2.0],
        lw,
        lh,
        0.04,
        hinge,
        1.6,
        JointFeel::ROOM_DOOR,
        m,
    );
}

/// A window in its frame: fixed pane, casement sash, sliding sash.
pub(crate) fn window(w: &mut UrdfWriter, v: usize, m: Material) {
    let wd = opening_width(false, v);
    let p = 0.05;
    let h = WINDOW_HEIGHT;
    frame(w, wd, h, p, true, m);
    let b = w.base();
    let (gw, gh) = (wd - 2.0 * p, h - 2.0 * p);
    let glass = Material::Glass;
    match v {
        0 => w.add(b, Part::cuboid([0.01, gw, gh], [0.0, 0.0, h / 2.0], glass)),
        1 => {
            side_door(
                w,
                b,
                "sash",
                [0.0, -gw / 2.0, h / 2.0],
                gw - 0.005,
                gh - 0.005,
                0.03,
                Hinge::Right,
                1.5,
                JointFeel::HINGE,
                glass,
            );
        }
        _ => {
            let half = gw / 2.0;
            w.add(b, Part::cuboid([0.01, half, gh], [-0.02, gw / 4.0, h / 2.0], glass));
            let slide = Motion::Prismatic {
                axis: [0.0, 1.0, 0.0],
                lower: 0.0,
                upper: half - 0.05,
            };
            let sash = w.child(b, "sash", [0.02, -gw / 4.0, h / 2.0], slide, JointFeel::DRAWER);
            w.add(sash, Part::cuboid([0.01, half, gh], [0.0, 0.0, 0.0], glass));
        }
    }
}
