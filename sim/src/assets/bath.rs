//! Bathroom categories: toilet and bathtub.

use super::Material;
use super::writer::{JointFeel, Motion, Part, UrdfWriter};

/// Toilet: round bowl, elongated bowl, compact; the lid is hinged at the back.
pub(crate) fn toilet(w: &mut UrdfWriter, v: usize, m: Material) {
    let (r, tank_h, reach) = [(0.18, 0.38, 0.0), (0.19, 0.4, 0.06), (0.17, 0.3, -0.03)][v];
    let b = w.base();
    let seat_z = 0.4;
    w.add_all(
        b,
        [
            Part::cylinder(r, seat_z, [0.08 + reach, 0.0, seat_z / 2.0], m).fill(0.15),
            Part::cuboid([0.2, 0.22, seat_z], [-0.1, 0.0, seat_z / 2.0], m).fill(0.2),
            Part::cuboid([0.18, 0.42, tank_h], [-0.2, 0.0, seat_z + tank_h / 2.0], m).fill(0.2),
        ],
    );
    let hinge = Motion::Revolute {
        axis: [0.0, -1.0, 0.0],
        lower: 0.0,
        upper: 1.7,
    };
    let lid = w.child(b, "lid", [-0.1, 0.0, seat_z], hinge, JointFeel::LID);
    w.add(
        lid,
        Part::cylinder(r, 0.02, [0.18 + reach, 0.0, 0.01], Material::Plastic),
    );
}

/// Bathtub: 1.5 m, 1.7 m, 1.8 m long; a tub of panels with a faucet.
pub(crate) fn bathtub(w: &mut UrdfWriter, v: usize, m: Material) {
    let (len, wd, h) = [(1.5, 0.7, 0.55), (1.7, 0.75, 0.57), (1.8, 0.8, 0.6)][v];
    let t = 0.06;
    let b = w.base();
    let zc = h / 2.0;
    w.add_all(
        b,
        [
            Part::cuboid([wd, len, t], [0.0, 0.0, t / 2.0], m).fill(0.15),
            Part::cuboid([t, len, h], [-wd / 2.0 + t / 2.0, 0.0, zc], m).fill(0.15),
            Part::cuboid([t, len, h], [wd / 2.0 - t / 2.0, 0.0, zc], m).fill(0.15),
            Part::cuboid([wd - 2.0 * t, t, h], [0.0, -len / 2.0 + t / 2.0, zc], m).fill(0.15),
            Part::cuboid([wd - 2.0 * t, t, h], [0.0, len / 2.0 - t / 2.0, zc], m).fill(0.15),
            Part::cylinder(
                0.015,
                0.2,
                [-wd / 2.0 + 0.03, len / 2.0 - 0.15, h + 0.1],
                Material::Metal,
            ),
        ],
    );
}
