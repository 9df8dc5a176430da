//! Small objects that rest on surfaces: dishes, bottles, books, laptops, vases, pots, TVs.

use super::Material;
use super::writer::{JointFeel, Motion, Part, UrdfWriter};

/// Bowl: small, medium, large. A hollow shell: a 4 mm bottom and a 5 mm wall of 16 staves
/// (a 16-sided solid of revolution), so that its inside is empty for the physics and a
/// gripper narrower than the bowl can pinch its rim.
pub(crate) fn bowl(w: &mut UrdfWriter, v: usize, m: Material) {
    let (r, h) = [(0.07, 0.05), (0.09, 0.06), (0.11, 0.07)][v];
    let (wall, bottom) = (0.005, 0.004);
    let b = w.base();
    w.add(b, Part::cylinder(r - wall, bottom, [0.0, 0.0, bottom / 2.0], m));
    const STAVES: usize = 16;
    let half_angle = std::f64::consts::PI / STAVES as f64;
    // Each stave touches the circle of radius r with its outer face and meets its
    // neighbours at the inner face.
    let chord = 2.0 * r * half_angle.tan();
    for k in 0..STAVES {
        let a = 2.0 * half_angle * k as f64;
        let c = r - wall / 2.0;
        w.add(
            b,
            Part::cuboid([wall, chord, h], [c * a.cos(), c * a.sin(), h / 2.0], m).yawed(a),
        );
    }
}

/// Mug: espresso cup, mug, large mug; with a handle on +y.
pub(crate) fn mug(w: &mut UrdfWriter, v: usize, m: Material) {
    let (r, h) = [(0.03, 0.06), (0.04, 0.095), (0.045, 0.11)][v];
    let b = w.base();
    w.add(b, Part::cylinder(r, h, [0.0, 0.0, h / 2.0], m).fill(0.25));
    w.add(b, Part::cuboid([0.012, 0.02, h * 0.6], [0.0, r + 0.01, h / 2.0], m));
}

/// Plate: side plate, dinner plate, charger.
pub(crate) fn plate(w: &mut UrdfWriter, v: usize, m: Material) {
    let r = [0.1, 0.125, 0.14][v];
    let b = w.base();
    w.add(b, Part::cylinder(r, 0.02, [0.0, 0.0, 0.01], m).fill(0.25));
}

/// Bottle: wine bottle (glass), water bottle (plastic), jar (glass).
pub(crate) fn bottle(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    let (r, h, neck, mat) = [
        (0.037, 0.22, 0.08, m),
        (0.035, 0.2, 0.04, Material::Plastic),
        (0.05, 0.12, 0.0, m),
    ][v];
    w.add(b, Part::cylinder(r, h, [0.0, 0.0, h / 2.0], mat).fill(0.3));
    if neck > 0.0 {
        w.add(
            b,
            Part::cylinder(0.014, neck, [0.0, 0.0, h + neck / 2.0], mat).fill(0.5),
        );
        w.add(
            b,
            Part::cylinder(0.016, 0.015, [0.0, 0.0, h + neck + 0.0075], Material::Plastic),
        );
    } else {
        w.add(
            b,
            Part::cylinder(r, 0.02, [0.0, 0.0, h + 0.01], Material::Metal).fill(0.1),
        );
    }
}

/// Book standing upright, spine towards +x: paperback, novel, textbook, art book.
pub(crate) fn book(w: &mut UrdfWriter, v: usize, m: Material) {
    let [d, t, h] = [
        [0.11, 0.025, 0.18],
        [0.15, 0.03, 0.23],
        [0.19, 0.04, 0.26],
        [0.23, 0.025, 0.3],
    ][v];
    let b = w.base();
    w.add(b, Part::cuboid([d, t, h], [0.0, 0.0, h / 2.0], m));
}

/// Laptop of 13, 15 or 17 inches; the lid is hinged at the back (0 = closed, ~1.9 = open).
pub(crate) fn laptop(w: &mut UrdfWriter, v: usize, m: Material) {
    let (d, wd) = [(0.21, 0.3), (0.24, 0.35), (0.27, 0.4)][v];
    let b = w.base();
    let t = 0.018;
    w.add(b, Part::cuboid([d, wd, t], [0.0, 0.0, t / 2.0], m).fill(0.8));
    let hinge = Motion::Revolute {
        axis: [0.0, -1.0, 0.0],
        lower: 0.0,
        upper: 2.2,
    };
    let lid = w.child(b, "lid", [-d / 2.0, 0.0, t], hinge, JointFeel::LID);
    w.add(lid, Part::cuboid([d, wd, 0.008], [d / 2.0, 0.0, 0.004], m).fill(0.8));
}

/// Vase: slim, wide, round.
pub(crate) fn vase(w: &mut UrdfWriter, v: usize, m: Material) {
    let b = w.base();
    match v {
        0 => w.add(b, Part::cylinder(0.05, 0.3, [0.0, 0.0, 0.15], m).fill(0.2)),
        1 => w.add(b, Part::cylinder(0.08, 0.22, [0.0, 0.0, 0.11], m).fill(0.2)),
        _ => {
            w.add(b, Part::ball(0.09, [0.0, 0.0, 0.09], m).fill(0.2));
            w.add(b, Part::cylinder(0.03, 0.08, [0.0, 0.0, 0.2], m).fill(0.4));
        }
    }
}

/// Cooking pot: saucepan, stock pot, casserole; handles on ±y.
pub(crate) fn pot(w: &mut UrdfWriter, v: usize, m: Material) {
    let (r, h) = [(0.09, 0.09), (0.12, 0.16), (0.14, 0.1)][v];
    let b = w.base();
    w.add_all(
        b,
        [
            Part::cylinder(r, h, [0.0, 0.0, h / 2.0], m).fill(0.06),
            Part::cuboid([0.03, 0.04, 0.015], [0.0, r + 0.02, h - 0.02], m),
            Part::cuboid([0.03, 0.04, 0.015], [0.0, -r - 0.02, h - 0.02], m),
        ],
    );
}

/// Flat-panel TV on a foot: 32, 43 and 55 inches.
pub(crate) fn tv(w: &mut UrdfWriter, v: usize, m: Material) {
    let (wd, h) = [(0.73, 0.43), (0.96, 0.56), (1.23, 0.71)][v];
    let b = w.base();
    let lift = 0.08;
    w.add_all(
        b,
        [
            Part::cuboid([0.2, 0.3, 0.02], [0.0, 0.0, 0.01], m),
            Part::cuboid([0.04, 0.06, lift], [-0.02, 0.0, 0.02 + lift / 2.0], m),
            Part::cuboid([0.05, wd, h], [-0.02, 0.0, 0.02 + lift + h / 2.0], m).fill(0.3),
            Part::cuboid(
                [0.002, wd - 0.02, h - 0.02],
                [0.006, 0.0, 0.02 + lift + h / 2.0],
                Material::Glass,
            ),
        ],
    );
}
