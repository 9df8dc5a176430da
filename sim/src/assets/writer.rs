//! A small URDF writer for assets made of primitive parts: links hold boxes, cylinders and
//! spheres (each both visual and collision), joints are fixed, revolute or prismatic. Masses and
//! inertia tensors follow from the part volumes and material densities; the bounding box and the
//! support surfaces are tracked in the asset frame at the zero configuration.

use std::fmt::Write as _;

use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};

use super::Material;

/// Index of a link in a [`UrdfWriter`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct LinkId(usize);

/// A primitive shape with its full dimensions.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Shape {
    /// Full size along x, y, z.
    Cuboid([f64; 3]),
    /// Radius and full length along the local z axis.
    Cylinder(f64, f64),
    /// Radius.
    Ball(f64),
}

/// One primitive part of a link: its shape, pose in the link frame, material and the fraction
/// of its volume that is solid (hollow shells and furniture bodies are far from solid).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Part {
    shape: Shape,
    pos: [f64; 3],
    rpy: [f64; 3],
    material: Material,
    fill: f64,
}

impl Part {
    /// A box of full `size` centred at `pos`.
    pub(crate) fn cuboid(size: [f64; 3], pos: [f64; 3], material: Material) -> Self {
        Part {
            shape: Shape::Cuboid(size),
            pos,
            rpy: [0.0; 3],
            material,
            fill: 1.0,
        }
    }

    /// A vertical cylinder centred at `pos`.
    pub(crate) fn cylinder(radius: f64, length: f64, pos: [f64; 3], material: Material) -> Self {
        Part {
            shape: Shape::Cylinder(radius, length),
            ..Part::cuboid([0.0; 3], pos, material)
        }
    }

    /// A sphere centred at `pos`.
    pub(crate) fn ball(radius: f64, pos: [f64; 3], material: Material) -> Self {
        Part {
            shape: Shape::Ball(radius),
            ..Part::cuboid([0.0; 3], pos, material)
        }
    }

    /// Lays a cylinder along the x axis.
    pub(crate) fn along_x(mut self) -> Self {
        self.rpy = [0.0, std::f64::consts::FRAC_PI_2, 0.0];
        self
    }

    /// Turns the part about the vertical axis.
    pub(crate) fn yawed(mut self, yaw: f64) -> Self {
        self.rpy = [0.0, 0.0, yaw];
        self
    }

    /// Sets the solid fraction of the part's volume (mass = density × volume × fill).
    pub(crate) fn fill(mut self, fill: f64) -> Self {
        self.fill = fill;
        self
    }

    fn scaled(mut self, s: f64) -> Self {
        self.pos = self.pos.map(|v| v * s);
        self.shape = match self.shape {
            Shape::Cuboid(d) => Shape::Cuboid(d.map(|v| v * s)),
            Shape::Cylinder(r, l) => Shape::Cylinder(r * s, l * s),
            Shape::Ball(r) => Shape::Ball(r * s),
        };
        self
    }

    fn rotation(&self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(self.rpy[0], self.rpy[1], self.rpy[2])
    }

    fn volume(&self) -> f64 {
        match self.shape {
            Shape::Cuboid([x, y, z]) => x * y * z,
            Shape::Cylinder(r, l) => std::f64::consts::PI * r * r * l,
            Shape::Ball(r) => 4.0 / 3.0 * std::f64::consts::PI * r * r * r,
        }
    }

    fn mass(&self) -> f64 {
        self.volume() * self.fill * self.material.props().density
    }

    /// Inertia tensor about the part's centre in its own frame.
    fn local_inertia(&self, m: f64) -> Matrix3<f64> {
        match self.shape {
            Shape::Cuboid([x, y, z]) => {
                Matrix3::from_diagonal(&Vector3::new(y * y + z * z, x * x + z * z, x * x + y * y)) * (m / 12.0)
            }
            Shape::Cylinder(r, l) => {
                let side = m * (3.0 * r * r + l * l) / 12.0;
                Matrix3::from_diagonal(&Vector3::new(side, side, m * r * r / 2.0))
            }
            Shape::Ball(r) => Matrix3::identity() * (0.4 * m * r * r),
        }
    }

    /// Half extents of the part's bounding box in its own frame.
    fn local_half(&self) -> Vector3<f64> {
        match self.shape {
            Shape::Cuboid([x, y, z]) => Vector3::new(x, y, z) / 2.0,
            Shape::Cylinder(r, l) => Vector3::new(r, r, l / 2.0),
            Shape::Ball(r) => Vector3::repeat(r),
        }
    }

    fn geometry_xml(&self) -> String {
        match self.shape {
            Shape::Cuboid([x, y, z]) => format!("<box size=\"{} {} {}\"/>", num(x), num(y), num(z)),
            Shape::Cylinder(r, l) => format!("<cylinder radius=\"{}\" length=\"{}\"/>", num(r), num(l)),
            Shape::Ball(r) => format!("<sphere radius=\"{}\"/>", num(r)),
        }
    }
}

/// The kind of a joint and its motion range.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Motion {
    /// Rotation about `axis` within `[lower, upper]` radians.
    Revolute { axis: [f64; 3], lower: f64, upper: f64 },
    /// Translation along `axis` within `[lower, upper]` metres (before scaling).
    Prismatic { axis: [f64; 3], lower: f64, upper: f64 },
}

/// Damping and friction of a moving joint; typical furniture values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointFeel {
    pub(crate) damping: f64,
    pub(crate) friction: f64,
}

impl JointFeel {
    /// A drawer on ball-bearing runners.
    pub(crate) const DRAWER: JointFeel = JointFeel {
        damping: 5.0,
        friction: 0.5,
    };
    /// A cabinet or appliance door on hinges.
    pub(crate) const HINGE: JointFeel = JointFeel {
        damping: 0.5,
        friction: 0.3,
    };
    /// A room door: heavier, with a latch-free hinge.
    pub(crate) const ROOM_DOOR: JointFeel = JointFeel {
        damping: 2.0,
        friction: 1.0,
    };
    /// A small lid (laptop, toilet).
    pub(crate) const LID: JointFeel = JointFeel {
        damping: 0.05,
        friction: 0.05,
    };
}

struct LinkDraft {
    name: String,
    parts: Vec<Part>,
    /// Origin of the link frame in the asset frame at the zero configuration.
    origin: Vector3<f64>,
}

struct JointDraft {
    name: String,
    motion: Motion,
    feel: JointFeel,
    parent: usize,
    child: usize,
    origin: Vector3<f64>,
}

/// A horizontal area objects can rest on, in the asset frame.
///
/// ```
/// use hearth_sim::assets::{Asset, Category};
/// let table = Asset::build(Category::Table, 0, 1.0).unwrap();
/// let top = &table.surfaces[0];
/// assert!(top.z > 0.7 && top.max[0] > top.min[0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Surface {
    /// Height of the surface above the asset origin.
    pub z: f64,
    /// Corner with the smallest x and y.
    pub min: [f64; 2],
    /// Corner with the largest x and y.
    pub max: [f64; 2],
    /// Free height above the surface (shelf spacing, or a generous limit for open tops).
    pub clearance: f64,
}

/// What a writer produces: the URDF text and the derived figures.
pub(crate) struct Written {
    pub(crate) urdf: String,
    pub(crate) aabb_min: Vector3<f64>,
    pub(crate) aabb_max: Vector3<f64>,
    pub(crate) mass: f64,
    pub(crate) surfaces: Vec<Surface>,
    pub(crate) moving_joints: usize,
}

/// Builds the URDF of one asset; lengths given to it are multiplied by `scale`.
pub(crate) struct UrdfWriter {
    name: String,
    scale: f64,
    links: Vec<LinkDraft>,
    joints: Vec<JointDraft>,
    surfaces: Vec<Surface>,
}

/// Formats a number compactly and deterministically (at most 6 decimals, no trailing zeros).
pub(crate) fn num(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}

fn vec3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", num(v.x), num(v.y), num(v.z))
}

impl UrdfWriter {
    /// A writer for a robot named `name` with a root link called `base`.
    pub(crate) fn new(name: &str, scale: f64) -> Self {
        UrdfWriter {
            name: name.to_owned(),
            scale,
            links: vec![LinkDraft {
                name: "base".into(),
                parts: Vec::new(),
                origin: Vector3::zeros(),
            }],
            joints: Vec::new(),
            surfaces: Vec::new(),
        }
    }

    /// The root link.
    pub(crate) fn base(&self) -> LinkId {
        LinkId(0)
    }

    /// Adds a part to a link.
    pub(crate) fn add(&mut self, link: LinkId, part: Part) {
        let part = part.scaled(self.scale);
        self.links[link.0].parts.push(part);
    }

    /// Adds several parts to a link.
    pub(crate) fn add_all(&mut self, link: LinkId, parts: impl IntoIterator<Item = Part>) {
        for p in parts {
            self.add(link, p);
        }
    }

    /// Adds a child link attached by a joint at `origin` (in the parent link frame).
    pub(crate) fn child(
        &mut self,
        parent: LinkId,
        name: &str,
        origin: [f64; 3],
        motion: Motion,
        feel: JointFeel,
    ) -> LinkId {
        let s = self.scale;
        let origin = Vector3::from(origin) * s;
        let motion = match motion {
            Motion::Prismatic { axis, lower, upper } => Motion::Prismatic {
                axis,
                lower: lower * s,
                upper: upper * s,
            },
            m => m,
        };
        let child = self.links.len();
        self.links.push(LinkDraft {
            name: name.to_owned(),
            parts: Vec::new(),
            origin: self.links[parent.0].origin + origin,
        });
        let joint_name = match motion {
            Motion::Revolute { .. } => format!("{name}_hinge"),
            Motion::Prismatic { .. } => format!("{name}_slide"),
        };
        self.joints.push(JointDraft {
            name: joint_name,
            motion,
            feel,
            parent: parent.0,
            child,
            origin,
        });
        LinkId(child)
    }

    /// Declares a support surface (unscaled coordinates in the asset frame).
    pub(crate) fn surface(&mut self, z: f64, min: [f64; 2], max: [f64; 2], clearance: f64) {
        let s = self.scale;
        self.surfaces.push(Surface {
            z: z * s,
            min: min.map(|v| v * s),
            max: max.map(|v| v * s),
            clearance: clearance * s,
        });
    }

    /// Writes the URDF text and derives mass, bounding box and surfaces.
    pub(crate) fn finish(self) -> Written {
        let mut out = String::new();
        let _ = writeln!(out, "<?xml version=\"1.0\"?>\n<robot name=\"{}\">", self.name);
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        let mut total = 0.0;
        for link in &self.links {
            let _ = writeln!(out, "  <link name=\"{}\">", link.name);
            let (mass, com, inertia) = link_inertial(&link.parts);
            total += mass;
            if mass > 0.0 {
                let _ = writeln!(
                    out,
                    "    <inertial><origin xyz=\"{}\" rpy=\"0 0 0\"/><mass value=\"{}\"/>\
                     <inertia ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"/></inertial>",
                    vec3(&com),
                    num(mass),
                    num(inertia[(0, 0)]),
                    num(inertia[(0, 1)]),
                    num(inertia[(0, 2)]),
                    num(inertia[(1, 1)]),
                    num(inertia[(1, 2)]),
                    num(inertia[(2, 2)]),
                );
            }
            for (k, p) in link.parts.iter().enumerate() {
                let origin = format!(
                    "<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
                    num(p.pos[0]),
                    num(p.pos[1]),
                    num(p.pos[2]),
                    num(p.rpy[0]),
                    num(p.rpy[1]),
                    num(p.rpy[2])
                );
                let geometry = p.geometry_xml();
                let m = p.material;
                let c = m.props().rgba;
                let _ = writeln!(
                    out,
                    "    <visual name=\"{}_{k}\">{origin}<geometry>{geometry}</geometry>\
                     <material name=\"{}\"><color rgba=\"{} {} {} {}\"/></material></visual>",
                    link.name,
                    m.name(),
                    num(c[0]),
                    num(c[1]),
                    num(c[2]),
                    num(c[3])
                );
                let _ = writeln!(
                    out,
                    "    <collision name=\"{}_{k}\">{origin}<geometry>{geometry}</geometry></collision>",
                    link.name
                );
                let rot = p.rotation().to_rotation_matrix();
                let half = rot.matrix().abs() * p.local_half();
                let centre = link.origin + Vector3::from(p.pos);
                lo = lo.inf(&(centre - half));
                hi = hi.sup(&(centre + half));
            }
            let _ = writeln!(out, "  </link>");
        }
        let mut moving = 0;
        for j in &self.joints {
            let (kind, axis, limits) = match j.motion {
                Motion::Revolute { axis, lower, upper } => ("revolute", Some(axis), Some((lower, upper, 20.0, 1.5))),
                Motion::Prismatic { axis, lower, upper } => ("prismatic", Some(axis), Some((lower, upper, 100.0, 0.5))),
            };
            let _ = write!(
                out,
                "  <joint name=\"{}\" type=\"{kind}\"><parent link=\"{}\"/><child link=\"{}\"/>\
                 <origin xyz=\"{}\" rpy=\"0 0 0\"/>",
                j.name,
                self.links[j.parent].name,
                self.links[j.child].name,
                vec3(&j.origin)
            );
            if let (Some(a), Some((lower, upper, effort, velocity))) = (axis, limits) {
                moving += 1;
                let _ = write!(
                    out,
                    "<axis xyz=\"{} {} {}\"/><limit lower=\"{}\" upper=\"{}\" effort=\"{}\" velocity=\"{}\"/>\
                     <dynamics damping=\"{}\" friction=\"{}\"/>",
                    num(a[0]),
                    num(a[1]),
                    num(a[2]),
                    num(lower),
                    num(upper),
                    num(effort),
                    num(velocity),
                    num(j.feel.damping),
                    num(j.feel.friction)
                );
            }
            let _ = writeln!(out, "</joint>");
        }
        out.push_str("</robot>\n");
        if lo.x > hi.x {
            lo = Vector3::zeros();
            hi = Vector3::zeros();
        }
        Written {
            urdf: out,
            aabb_min: lo,
            aabb_max: hi,
            mass: total,
            surfaces: self.surfaces,
            moving_joints: moving,
        }
    }
}

/// Mass, centre of mass and inertia about the centre of mass of a set of parts.
fn link_inertial(parts: &[Part]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let mass: f64 = parts.iter().map(Part::mass).sum();
    if mass <= 0.0 {
        return (0.0, Vector3::zeros(), Matrix3::zeros());
    }
    let com = parts
        .iter()
        .fold(Vector3::zeros(), |acc, p| acc + Vector3::from(p.pos) * p.mass())
        / mass;
    let mut inertia = Matrix3::zeros();
    for p in parts {
        let m = p.mass();
        let r = p.rotation().to_rotation_matrix();
        let d = Point3::from(p.pos) - Point3::from(com);
        let shift = Matrix3::identity() * d.dot(&d) - d * d.transpose();
        inertia += r.matrix() * p.local_inertia(m) * r.matrix().transpose() + shift * m;
    }
    (mass, com, inertia)
}
