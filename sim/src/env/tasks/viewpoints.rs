//! Viewpoints of `object_nav`: the traversable cells from which the robot's camera would see a
//! target instance covering at least `visible_fraction` of its image.
//!
//! The estimate, per cell within range of an instance:
//!
//! 1. **Pose.** The robot stands on the cell centre turned towards the instance's box centre
//!    (it can turn in place, so the heading is free); the camera sits where the robot's
//!    default camera mount puts it relative to the base (height, forward offset and pitch
//!    measured on the spawned robot).
//! 2. **Coverage.** The instance's bounding box (asset AABB, posed) is clipped to the camera's
//!    depth range `[near, far]` and projected through the pinhole model (vertical field of view,
//!    square pixels, the image's aspect ratio); the convex hull of the projection, clipped to
//!    the image rectangle, divided by the image's area is the fraction of the image the box
//!    would fill. A box over-states a non-box shape (a sofa's seat, a table's legs), so this
//!    is an upper estimate of what the semantic image shows.
//! 3. **Line of sight.** Each box face turned towards the camera gets a 3 × 3 grid of sight
//!    rays, cast against the world's colliders (the robot excluded); a ray is clear when
//!    nothing but the instance itself lies before its point. The estimate sums the faces'
//!    projected areas (clipped like the box) times the clear share of their rays: a counter
//!    beside a fridge hides the lower half of its side, a table in front the lower part of its
//!    front.
//!
//! A cell is a viewpoint when the scaled coverage reaches the fraction. Each instance is
//! judged alone (the semantic image counts every instance of the category, so two instances
//! seen together can succeed where neither would), and dynamic objects are where the home
//! snapshot left them. Cells farther than the camera's far plane plus the box's half diagonal,
//! or than the distance at which even the box's bounding sphere would fill too little of the
//! image, are not examined.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d::math::{Real, Vector};

use super::field::cell_center;
use crate::scene::SceneMaps;
use crate::world::WorldObstacles;
use hearth_planning::obstacles::Obstacles;

/// What the viewpoint estimate knows of the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CameraView {
    /// Vertical field of view, degrees.
    pub(crate) vfov_deg: f64,
    /// Image width / height.
    pub(crate) aspect: f64,
    /// Near and far clipping (m).
    pub(crate) near: f64,
    pub(crate) far: f64,
}

impl CameraView {
    /// The view of a `[sensors.camera]` section.
    pub(crate) fn of(c: &crate::env::config::CameraSection) -> Self {
        Self {
            vfov_deg: c.vfov,
            aspect: c.width as f64 / c.height.max(1) as f64,
            near: c.near,
            far: c.far,
        }
    }
}

/// The camera on the robot: its optical frame (z forward, y down) in the base frame, and the
/// base's height.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rig {
    pub(crate) view: CameraView,
    pub(crate) camera_in_base: Isometry3<f64>,
    pub(crate) base_z: f64,
}

/// One instance: its scene object name (its colliders are `NAME` or `NAME/LINK`), pose and
/// local box.
#[derive(Clone, Debug)]
pub(crate) struct Instance {
    pub(crate) name: String,
    pub(crate) pose: Isometry3<f64>,
    pub(crate) min: Vector3<f64>,
    pub(crate) max: Vector3<f64>,
}

impl Instance {
    fn corner(&self, k: usize) -> Point3<f64> {
        let pick = |bit: usize, lo: f64, hi: f64| if k & bit == 0 { lo } else { hi };
        self.pose
            * Point3::new(
                pick(1, self.min.x, self.max.x),
                pick(2, self.min.y, self.max.y),
                pick(4, self.min.z, self.max.z),
            )
    }

    fn centre(&self) -> Point3<f64> {
        self.pose * Point3::from((self.min + self.max) / 2.0)
    }

    /// The box's faces that turn towards `eye`: for each, its corners (going round) and the
    /// two edge vectors from the first corner.
    fn faces_towards(&self, eye: &Point3<f64>, out: &mut [[Point3<f64>; 4]; 3]) -> usize {
        let local_eye = self.pose.inverse_transform_point(eye);
        let (lo, hi) = (self.min, self.max);
        let mut n = 0;
        for axis in 0..3 {
            for (side, outward) in [
                (lo[axis], local_eye[axis] < lo[axis]),
                (hi[axis], local_eye[axis] > hi[axis]),
            ] {
                if !outward || n >= out.len() {
                    continue;
                }
                let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |u: f64, v: f64| {
                    let mut p = Vector3::zeros();
                    p[axis] = side;
                    p[b] = u;
                    p[c] = v;
                    self.pose * Point3::from(p)
                };
                out[n] = [
                    corner(lo[b], lo[c]),
                    corner(hi[b], lo[c]),
                    corner(hi[b], hi[c]),
                    corner(lo[b], hi[c]),
                ];
                n += 1;
            }
        }
        n
    }

    fn owns(&self, collider: &str) -> bool {
        collider
            .strip_prefix(self.name.as_str())
            .is_some_and(|rest| rest.is_empty() || rest.starts_with('/'))
    }
}

/// Room for the projected points: 8 corners and 2 plane crossings on each of 12 edges.
const MAX_POINTS: usize = 32;
/// Room for a hull clipped by the image's four sides.
const MAX_POLY: usize = MAX_POINTS + 8;

/// The 12 edges of a box, as pairs of corner indices (bit 1: x, 2: y, 4: z).
const BOX_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// The 4 edges of a quad whose corners go round.
const QUAD_EDGES: [(usize, usize); 4] = [(0, 1), (1, 2), (2, 3), (3, 0)];

/// Half the image's extent on the normalised image plane (z = 1): (x, y).
fn half_image(view: &CameraView) -> (f64, f64) {
    let t = (view.vfov_deg.to_radians() / 2.0).tan();
    (view.aspect * t, t)
}

/// The area, on the normalised image plane, of the convex solid (or planar polygon) with
/// camera-frame vertices `local` and edges `edges`, clipped to the depth range and the image.
fn projected_area(view: &CameraView, local: &[Point3<f64>], edges: &[(usize, usize)]) -> f64 {
    let (hx, hy) = half_image(view);
    let mut pts = [[0.0f64; 2]; MAX_POINTS];
    let mut n = 0;
    let mut push = |p: &Point3<f64>, pts: &mut [[f64; 2]; MAX_POINTS]| {
        if n < MAX_POINTS {
            pts[n] = [p.x / p.z, p.y / p.z];
            n += 1;
        }
    };
    for c in local {
        if c.z >= view.near && c.z <= view.far {
            push(c, &mut pts);
        }
    }
    // The solid clipped to the depth slab has, besides the corners inside, the crossings of
    // its edges with the two planes as vertices.
    for &(a, b) in edges {
        let (pa, pb) = (local[a], local[b]);
        for plane in [view.near, view.far] {
            if (pa.z - plane) * (pb.z - plane) < 0.0 {
                let s = (plane - pa.z) / (pb.z - pa.z);
                push(&(pa + (pb - pa) * s), &mut pts);
            }
        }
    }
    if n < 3 {
        return 0.0;
    }
    let mut hull = [[0.0f64; 2]; MAX_POLY];
    let h = convex_hull(&mut pts[..n], &mut hull);
    clipped_area(&hull[..h], hx, hy)
}

/// The fraction of the image the box of `inst` fills, seen from the optical frame `camera`
/// (occlusion ignored).
pub(crate) fn box_coverage(view: &CameraView, camera: &Isometry3<f64>, inst: &Instance) -> f64 {
    let mut local = [Point3::origin(); 8];
    for (k, c) in local.iter_mut().enumerate() {
        *c = camera.inverse_transform_point(&inst.corner(k));
    }
    let (hx, hy) = half_image(view);
    projected_area(view, &local, &BOX_EDGES) / (4.0 * hx * hy)
}

/// Andrew's monotone chain: the hull of `pts` (sorted in place) counter-clockwise into `out`;
/// returns its vertex count.
fn convex_hull(pts: &mut [[f64; 2]], out: &mut [[f64; 2]; MAX_POLY]) -> usize {
    pts.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut k = 0;
    for &p in pts.iter() {
        while k >= 2 && cross(out[k - 2], out[k - 1], p) <= 0.0 {
            k -= 1;
        }
        out[k] = p;
        k += 1;
    }
    let lower = k + 1;
    for &p in pts.iter().rev().skip(1) {
        while k >= lower && cross(out[k - 2], out[k - 1], p) <= 0.0 {
            k -= 1;
        }
        out[k] = p;
        k += 1;
    }
    k.saturating_sub(1)
}

/// Area of the convex polygon `poly` clipped to the rectangle [−hx, hx] × [−hy, hy]
/// (Sutherland–Hodgman, one side at a time).
fn clipped_area(poly: &[[f64; 2]], hx: f64, hy: f64) -> f64 {
    let mut a = [[0.0f64; 2]; MAX_POLY];
    let mut b = [[0.0f64; 2]; MAX_POLY];
    let mut n = poly.len().min(MAX_POLY);
    a[..n].copy_from_slice(&poly[..n]);
    // Each side as (axis, sign, limit): keep points with sign × p[axis] ≤ limit.
    for (axis, sign, limit) in [(0, 1.0, hx), (0, -1.0, hx), (1, 1.0, hy), (1, -1.0, hy)] {
        let inside = |p: [f64; 2]| sign * p[axis] <= limit;
        let mut m = 0;
        for i in 0..n {
            let (p, q) = (a[i], a[(i + 1) % n]);
            let (pi, qi) = (inside(p), inside(q));
            if pi && m < MAX_POLY {
                b[m] = p;
                m += 1;
            }
            if pi != qi && m < MAX_POLY {
                let s = (limit - sign * p[axis]) / (sign * (q[axis] - p[axis]));
                b[m] = [p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])];
                m += 1;
            }
        }
        n = m;
        a[..n].copy_from_slice(&b[..n]);
        if n < 3 {
            return 0.0;
        }
    }
    let mut twice = 0.0;
    for i in 0..n {
        let (p, q) = (a[i], a[(i + 1) % n]);
        twice += p[0] * q[1] - q[0] * p[1];
    }
    twice.abs() / 2.0
}

/// The optical frame of the camera with the robot on `xy` facing `target`.
pub(crate) fn camera_at(rig: &Rig, xy: [f64; 2], target: Point3<f64>) -> Isometry3<f64> {
    let yaw = (target.y - xy[1]).atan2(target.x - xy[0]);
    let base = Isometry3::from_parts(
        Translation3::new(xy[0], xy[1], rig.base_z),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    );
    base * rig.camera_in_base
}

/// Sight-ray samples per face side: a 3 × 3 grid at the centres of its ninths.
const GRID: usize = 3;

/// How many of the sight rays from `eye` to the grid points of the face `quad` nothing but
/// the instance blocks.
fn clear_rays(view: &WorldObstacles, eye: &Point3<f64>, quad: &[Point3<f64>; 4], inst: &Instance) -> usize {
    let origin = Vector::new(eye.x as Real, eye.y as Real, eye.z as Real);
    let (u, v) = (quad[1] - quad[0], quad[3] - quad[0]);
    let mut clear = 0;
    for i in 0..GRID {
        for j in 0..GRID {
            let (a, b) = ((i as f64 + 0.5) / GRID as f64, (j as f64 + 0.5) / GRID as f64);
            let d = quad[0] + u * a + v * b - eye;
            let dir = Vector::new(d.x as Real, d.y as Real, d.z as Real);
            let blocked = view
                .cast_ray(origin, dir, 1.0)
                .is_some_and(|(t, id)| t < 0.999 && !view.name(id).is_some_and(|n| inst.owns(n)));
            clear += usize::from(!blocked);
        }
    }
    clear
}

/// The estimated fraction of the image `inst` fills from a camera on cell `xy`: over the box
/// faces turned towards the camera, each face's projected area (clipped to the image) times
/// the clear share of its sight rays. The rays are cast only when the whole box could fill
/// `fraction`; below that the box's coverage is returned.
pub(crate) fn estimate(rig: &Rig, view: &WorldObstacles, inst: &Instance, xy: [f64; 2], fraction: f64) -> f64 {
    let camera = camera_at(rig, xy, inst.centre());
    let cover = box_coverage(&rig.view, &camera, inst);
    if cover < fraction {
        return cover;
    }
    let eye = Point3::from(camera.translation.vector);
    let mut faces = [[Point3::origin(); 4]; 3];
    let n = inst.faces_towards(&eye, &mut faces);
    let (hx, hy) = half_image(&rig.view);
    let mut seen = 0.0;
    for quad in &faces[..n] {
        let local = quad.map(|p| camera.inverse_transform_point(&p));
        let area = projected_area(&rig.view, &local, &QUAD_EDGES);
        if area > 0.0 {
            seen += area * clear_rays(view, &eye, quad, inst) as f64 / (GRID * GRID) as f64;
        }
    }
    seen / (4.0 * hx * hy)
}

/// The viewpoint cells of a category with instances `insts` (sorted, deduplicated).
pub(crate) fn viewpoints(
    maps: &SceneMaps,
    rig: &Rig,
    view: &WorldObstacles,
    insts: &[Instance],
    fraction: f64,
) -> Vec<usize> {
    let t = (rig.view.vfov_deg.to_radians() / 2.0).tan();
    let image = 4.0 * rig.view.aspect * t * t;
    let mut cells = Vec::new();
    for inst in insts {
        let c = inst.centre();
        let radius = ((inst.max - inst.min) / 2.0).norm();
        // Beyond this the bounding sphere's image (radius r / (d − r)) fills less than the
        // fraction; beyond far + r nothing of the box is rendered.
        let reach = (radius + radius * (std::f64::consts::PI / (image * fraction)).sqrt()).min(rig.view.far + radius);
        let r = (reach / maps.resolution).ceil() as i64;
        let cx = ((c.x - maps.origin[0]) / maps.resolution).floor() as i64;
        let cy = ((c.y - maps.origin[1]) / maps.resolution).floor() as i64;
        for y in (cy - r).max(0)..=(cy + r).min(maps.height as i64 - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(maps.width as i64 - 1) {
                let i = y as usize * maps.width + x as usize;
                if !maps.traversable[i] {
                    continue;
                }
                let p = cell_center(maps, i);
                if (p[0] - c.x).hypot(p[1] - c.y) > reach {
                    continue;
                }
                if estimate(rig, view, inst, p, fraction) >= fraction {
                    cells.push(i);
                }
            }
        }
    }
    cells.sort_unstable();
    cells.dedup();
    cells
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_view() -> CameraView {
        CameraView {
            vfov_deg: 90.0,
            aspect: 1.0,
            near: 0.05,
            far: 10.0,
        }
    }

    /// A camera at the origin looking along world +x (optical z), image y down.
    fn looking_along_x() -> Isometry3<f64> {
        let r = nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
            0.0, 0.0, 1.0, //
            -1.0, 0.0, 0.0, //
            0.0, -1.0, 0.0,
        ));
        Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_rotation_matrix(&r))
    }

    fn plate(x: f64, half: f64) -> Instance {
        Instance {
            name: "plate".into(),
            pose: Isometry3::translation(x, 0.0, 0.0),
            min: Vector3::new(0.0, -half, -half),
            max: Vector3::new(0.001, half, half),
        }
    }

    #[test]
    fn a_square_facing_the_camera_covers_its_share_of_the_image() {
        // 90° field: the image at 2 m is 4 m × 4 m; a 1 m square fills 1/16 of it.
        let c = box_coverage(&square_view(), &looking_along_x(), &plate(2.0, 0.5));
        assert!((c - 1.0 / 16.0).abs() < 1e-3, "{c}");
        // A square larger than the view fills all of it.
        let c = box_coverage(&square_view(), &looking_along_x(), &plate(1.0, 5.0));
        assert!((c - 1.0).abs() < 1e-9, "{c}");
        // Behind the camera, or beyond far: nothing.
        assert_eq!(box_coverage(&square_view(), &looking_along_x(), &plate(-2.0, 0.5)), 0.0);
        assert_eq!(box_coverage(&square_view(), &looking_along_x(), &plate(11.0, 0.5)), 0.0);
    }

    #[test]
    fn a_box_straddling_the_near_plane_is_clipped_not_dropped() {
        let inst = Instance {
            name: "slab".into(),
            pose: Isometry3::identity(),
            min: Vector3::new(-1.0, -0.2, -0.2),
            max: Vector3::new(1.0, 0.2, 0.2),
        };
        let c = box_coverage(&square_view(), &looking_along_x(), &inst);
        assert!(c > 0.5, "{c}");
    }

    #[test]
    fn colliders_of_an_instance_are_matched_by_model_name() {
        let i = plate(1.0, 0.1);
        assert!(i.owns("plate") && i.owns("plate/door_0"));
        assert!(!i.owns("plates/base") && !i.owns("building/wall_0"));
    }
}
