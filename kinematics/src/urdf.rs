//! Building a [`RobotModel`] from URDF text, with validation that names every fault.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};
use parry3d::math::Vector;
use parry3d::shape::SharedShape;

use crate::convert::to_pose;
use crate::error::{KinematicsError, Result};
use crate::fk::{Axis, FkOp, FkProgram, Motion};
use crate::mesh::{MeshCollision, load_mesh, mesh_shape};
use crate::model::{
    ChainSpec, Collision, Dynamics, Geometry, Inertial, Joint, JointKind, JointLimits, Link, LinkShape, Mimic,
    ModelData, RobotModel, Visual,
};
use crate::resolve::PackageResolver;

/// Options for loading a URDF.
///
/// ```
/// use hearth_kinematics::{LoadOptions, MeshCollision};
/// let opts = LoadOptions { mesh_collision: MeshCollision::ConvexDecomposition, ..Default::default() };
/// assert!(opts.package_paths.is_empty());
/// ```
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// How meshes become collision shapes.
    pub mesh_collision: MeshCollision,
    /// Extra `package://` roots (after `HEARTH_PACKAGE_PATH` and `ROS_PACKAGE_PATH`).
    pub package_paths: Vec<PathBuf>,
}

impl RobotModel {
    /// Loads a URDF file (meshes resolved against its folder; see [`PackageResolver`]).
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let path = std::env::temp_dir().join("hearth_doc_from_urdf_file.urdf");
    /// std::fs::write(&path, r#"<robot name="slider"><link name="rail"/><link name="cart"/>
    ///   <joint name="slide" type="prismatic"><parent link="rail"/><child link="cart"/>
    ///   <axis xyz="1 0 0"/><limit lower="0" upper="0.5" effort="5" velocity="1"/></joint></robot>"#).unwrap();
    /// let model = RobotModel::from_urdf_file(&path).unwrap();
    /// assert_eq!((model.name(), model.dof(), model.upper()[0]), ("slider", 1, 0.5));
    /// assert!(RobotModel::from_urdf_file("/no/such/robot.urdf").is_err());
    /// ```
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_urdf_file_with(path, &LoadOptions::default())
    }

    /// Loads a URDF file with options.
    ///
    /// ```
    /// use hearth_kinematics::{LoadOptions, MeshCollision, RobotModel};
    /// let dir = std::env::temp_dir().join("hearth_doc_urdf_with");
    /// std::fs::create_dir_all(&dir).unwrap();
    /// std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    /// let urdf = r#"<robot name="plate"><link name="base">
    ///   <collision><geometry><mesh filename="tri.obj"/></geometry></collision></link></robot>"#;
    /// std::fs::write(dir.join("plate.urdf"), urdf).unwrap();
    /// let options = LoadOptions { mesh_collision: MeshCollision::TriMesh, ..Default::default() };
    /// let m = RobotModel::from_urdf_file_with(dir.join("plate.urdf"), &options).unwrap();
    /// assert!(m.link_shape(0).unwrap().shape.as_trimesh().is_some());
    /// ```
    pub fn from_urdf_file_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|error| KinematicsError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        let dir = path
            .parent()
            .map(|p| if p.as_os_str().is_empty() { Path::new(".") } else { p });
        build(&text, &path.display().to_string(), dir, options, Vec::new())
    }

    /// Loads URDF text; relative and `package://` mesh paths are resolved against `base_dir`.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let urdf = r#"<robot name="pendulum">
    ///   <link name="base"/>
    ///   <link name="arm"><collision><geometry><box size="0.1 0.1 1"/></geometry></collision></link>
    ///   <joint name="hinge" type="revolute">
    ///     <parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>
    ///     <limit lower="-1" upper="1" effort="10" velocity="2"/>
    ///   </joint>
    /// </robot>"#;
    /// let m = RobotModel::from_urdf_str(urdf, None).unwrap();
    /// assert_eq!(m.variable_names(), ["hinge"]);
    /// ```
    pub fn from_urdf_str(text: &str, base_dir: Option<&Path>) -> Result<Self> {
        build(text, "<string>", base_dir, &LoadOptions::default(), Vec::new())
    }

    /// Loads URDF text with options and a name used in error messages.
    ///
    /// ```
    /// use hearth_kinematics::{LoadOptions, RobotModel};
    /// let bad = r#"<robot name="broken"><link name="a"/><joint name="j" type="fixed">
    ///   <parent link="a"/><child link="nowhere"/></joint></robot>"#;
    /// let err = RobotModel::from_urdf_str_with(bad, "broken.urdf", None, &LoadOptions::default()).unwrap_err();
    /// assert!(err.to_string().contains("broken.urdf"));
    /// let one_link = r#"<robot name="r"><link name="a"/></robot>"#;
    /// let ok = RobotModel::from_urdf_str_with(one_link, "r.urdf", None, &LoadOptions::default()).unwrap();
    /// assert_eq!(ok.source_name(), "r.urdf");
    /// ```
    pub fn from_urdf_str_with(
        text: &str,
        source_name: &str,
        base_dir: Option<&Path>,
        options: &LoadOptions,
    ) -> Result<Self> {
        build(text, source_name, base_dir, options, Vec::new())
    }
}

pub(crate) fn build(
    text: &str,
    source_name: &str,
    base_dir: Option<&Path>,
    options: &LoadOptions,
    chains: Vec<ChainSpec>,
) -> Result<RobotModel> {
    let src = || source_name.to_owned();
    // urdf-rs and its XML parsers are third-party code fed untrusted text: contain any panic.
    let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text));
    let robot = match parsed {
        Ok(Ok(r)) => r,
        Ok(Err(e)) => {
            return Err(KinematicsError::Xml {
                source_name: src(),
                message: e.to_string(),
            });
        }
        Err(_) => {
            return Err(KinematicsError::Xml {
                source_name: src(),
                message: "the XML parser failed on this text".into(),
            });
        }
    };
    if robot.links.is_empty() {
        return Err(KinematicsError::NoLinks { source_name: src() });
    }

    // Names.
    let mut urdf_link: HashMap<&str, usize> = HashMap::new();
    for (i, l) in robot.links.iter().enumerate() {
        if urdf_link.insert(l.name.as_str(), i).is_some() {
            return Err(KinematicsError::DuplicateName {
                source_name: src(),
                element: "link",
                name: l.name.clone(),
            });
        }
    }
    let mut joint_by_name = HashMap::new();
    for (i, j) in robot.joints.iter().enumerate() {
        if joint_by_name.insert(j.name.clone(), i).is_some() {
            return Err(KinematicsError::DuplicateName {
                source_name: src(),
                element: "joint",
                name: j.name.clone(),
            });
        }
    }

    // Tree structure.
    let mut parent_of: Vec<Option<usize>> = vec![None; robot.links.len()];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    let mut ends = Vec::with_capacity(robot.joints.len());
    for (ji, j) in robot.joints.iter().enumerate() {
        let find = |name: &str, role| {
            urdf_link
                .get(name)
                .copied()
                .ok_or_else(|| KinematicsError::MissingLink {
                    source_name: src(),
                    joint: j.name.clone(),
                    role,
                    link: name.to_owned(),
                })
        };
        let p = find(&j.parent.link, "parent")?;
        let c = find(&j.child.link, "child")?;
        if let Some(prev) = parent_of[c] {
            return Err(KinematicsError::MultipleParents {
                source_name: src(),
                link: j.child.link.clone(),
                first: robot.joints[prev].name.clone(),
                second: j.name.clone(),
            });
        }
        parent_of[c] = Some(ji);
        children[p].push(ji);
        ends.push((p, c));
    }
    let roots: Vec<usize> = (0..robot.links.len()).filter(|&l| parent_of[l].is_none()).collect();
    if roots.is_empty() {
        return Err(KinematicsError::JointCycle {
            source_name: src(),
            link: robot.links[0].name.clone(),
        });
    }
    // Depth-first order from the roots; links never reached lie on a cycle.
    let mut order = Vec::with_capacity(robot.links.len());
    let mut stack: Vec<usize> = roots.iter().rev().copied().collect();
    while let Some(l) = stack.pop() {
        order.push(l);
        for &ji in children[l].iter().rev() {
            stack.push(ends[ji].1);
        }
    }
    if order.len() != robot.links.len() {
        let mut reached = vec![false; robot.links.len()];
        for &l in &order {
            reached[l] = true;
        }
        let stray = reached.iter().position(|r| !r).unwrap_or(0);
        return Err(KinematicsError::JointCycle {
            source_name: src(),
            link: robot.links[stray].name.clone(),
        });
    }
    if roots.len() > 1 {
        return Err(KinematicsError::MultipleRoots {
            source_name: src(),
            roots: roots
                .iter()
                .map(|&r| robot.links[r].name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    let mut new_index = vec![0usize; robot.links.len()];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }

    // Joints.
    let mut joints = Vec::with_capacity(robot.joints.len());
    for (ji, j) in robot.joints.iter().enumerate() {
        let element = || format!("joint `{}`", j.name);
        let kind = match j.joint_type {
            urdf_rs::JointType::Revolute => JointKind::Revolute,
            urdf_rs::JointType::Continuous => JointKind::Continuous,
            urdf_rs::JointType::Prismatic => JointKind::Prismatic,
            urdf_rs::JointType::Fixed => JointKind::Fixed,
            ref other => {
                return Err(KinematicsError::UnsupportedJoint {
                    source_name: src(),
                    joint: j.name.clone(),
                    kind: format!("{other:?}").to_ascii_lowercase(),
                });
            }
        };
        let origin = pose(&j.origin, source_name, &element())?;
        let axis_v = Vector3::from(j.axis.xyz.0);
        finite3(&j.axis.xyz.0, source_name, &element(), "axis")?;
        let axis = if kind == JointKind::Fixed {
            Unit::new_normalize(if axis_v.norm() > 0.0 { axis_v } else { Vector3::x() })
        } else {
            Unit::try_new(axis_v, 1e-12).ok_or_else(|| KinematicsError::ZeroAxis {
                source_name: src(),
                joint: j.name.clone(),
            })?
        };
        let lim = &j.limit;
        for (what, v) in [("limit lower", lim.lower), ("limit upper", lim.upper)] {
            if !v.is_finite() && matches!(kind, JointKind::Revolute | JointKind::Prismatic) {
                return Err(invalid(source_name, element(), what, v, "expected a finite number"));
            }
        }
        // Velocity and effort may be omitted (URDF 1.2 reads that as "no limit", +∞).
        for (what, v) in [("limit velocity", lim.velocity), ("limit effort", lim.effort)] {
            if v.is_nan() || v < 0.0 {
                return Err(invalid(source_name, element(), what, v, "expected a number ≥ 0"));
            }
        }
        let unspecified = |v: f64| if v > 0.0 { v } else { f64::INFINITY };
        let limits = match kind {
            JointKind::Revolute | JointKind::Prismatic => {
                if lim.lower == 0.0 && lim.upper == 0.0 && lim.velocity == 0.0 && lim.effort == 0.0 {
                    return Err(KinematicsError::MissingLimit {
                        source_name: src(),
                        joint: j.name.clone(),
                        kind: kind.as_str(),
                    });
                }
                if lim.lower > lim.upper {
                    return Err(KinematicsError::InvertedLimits {
                        source_name: src(),
                        joint: j.name.clone(),
                        lower: lim.lower,
                        upper: lim.upper,
                    });
                }
                JointLimits {
                    lower: lim.lower,
                    upper: lim.upper,
                    velocity: unspecified(lim.velocity),
                    effort: unspecified(lim.effort),
                }
            }
            JointKind::Continuous => JointLimits {
                lower: f64::NEG_INFINITY,
                upper: f64::INFINITY,
                velocity: unspecified(lim.velocity),
                effort: unspecified(lim.effort),
            },
            JointKind::Fixed => JointLimits {
                lower: 0.0,
                upper: 0.0,
                velocity: 0.0,
                effort: 0.0,
            },
        };
        let dynamics = match &j.dynamics {
            Some(d) => {
                for (what, v) in [("dynamics damping", d.damping), ("dynamics friction", d.friction)] {
                    if !v.is_finite() || v < 0.0 {
                        return Err(invalid(source_name, element(), what, v, "expected a finite number ≥ 0"));
                    }
                }
                Some(Dynamics {
                    damping: d.damping,
                    friction: d.friction,
                })
            }
            None => None,
        };
        joints.push(Joint {
            name: j.name.clone(),
            kind,
            parent: new_index[ends[ji].0],
            child: new_index[ends[ji].1],
            origin,
            axis,
            limits,
            mimic: None,
            dynamics,
            variable: None,
        });
    }

    // Mimic joints: resolve chains of mimics to an independent joint.
    for (ji, j) in robot.joints.iter().enumerate() {
        let Some(m) = &j.mimic else { continue };
        let bad = |reason| KinematicsError::BadMimic {
            source_name: src(),
            joint: j.name.clone(),
            target: m.joint.clone(),
            reason,
        };
        // A target that does not exist is an error (likely a typo), on any joint.
        let mut target = *joint_by_name
            .get(&m.joint)
            .ok_or_else(|| bad("no joint has that name"))?;
        // A fixed joint has no position to follow: its `<mimic>` is left out (VAMP's sphere
        // model of the Panda fixes its fingers and keeps the tag).
        if joints[ji].kind == JointKind::Fixed {
            continue;
        }
        let mut multiplier = m.multiplier.unwrap_or(1.0);
        let mut offset = m.offset.unwrap_or(0.0);
        if !multiplier.is_finite() || !offset.is_finite() {
            return Err(bad("multiplier and offset must be finite"));
        }
        if target == ji {
            return Err(bad("a joint cannot mimic itself"));
        }
        let mut hops = 0;
        while let Some(next) = &robot.joints[target].mimic {
            hops += 1;
            if hops > robot.joints.len() || target == ji {
                return Err(bad("the mimic relations form a loop"));
            }
            let t2 = *joint_by_name
                .get(&next.joint)
                .ok_or_else(|| bad("its target mimics a missing joint"))?;
            let m2 = next.multiplier.unwrap_or(1.0);
            offset += multiplier * next.offset.unwrap_or(0.0);
            multiplier *= m2;
            target = t2;
        }
        if !multiplier.is_finite() || !offset.is_finite() {
            return Err(bad(
                "the combined multiplier or offset of the mimic chain is not finite",
            ));
        }
        if joints[target].kind == JointKind::Fixed {
            return Err(bad("the target is a fixed joint"));
        }
        joints[ji].mimic = Some(Mimic {
            joint: target,
            multiplier,
            offset,
        });
    }

    // Configuration variables: movable, non-mimic joints in URDF order.
    let mut variables = Vec::new();
    for (ji, j) in joints.iter_mut().enumerate() {
        if j.kind.is_movable() && j.mimic.is_none() {
            j.variable = Some(variables.len());
            variables.push(ji);
        }
    }

    // Links, in tree order.
    let resolver = PackageResolver::new(options.package_paths.clone());
    let mut links = Vec::with_capacity(order.len());
    for &old in &order {
        let l = &robot.links[old];
        links.push(build_link(
            l,
            parent_of[old],
            source_name,
            base_dir,
            &resolver,
            options,
            &robot.materials,
        )?);
    }

    // FK program: op i computes link i + 1.
    let mut ops = Vec::with_capacity(links.len().saturating_sub(1));
    for link in links.iter().skip(1) {
        let j = &joints[link.parent_joint.expect("non-root links have a parent joint")];
        let (var, multiplier, offset) = match (j.variable, j.mimic) {
            (Some(v), _) => (v as u32, 1.0, 0.0),
            (None, Some(m)) => (joints[m.joint].variable.unwrap_or(0) as u32, m.multiplier, m.offset),
            _ => (0, 0.0, 0.0),
        };
        let motion = match j.kind {
            JointKind::Fixed => Motion::Fixed,
            JointKind::Revolute | JointKind::Continuous => match Axis::classify(&j.axis) {
                (Axis::General, _) => Motion::Revolute {
                    axis: j.axis,
                    var,
                    multiplier,
                    offset,
                },
                (axis, sign) => Motion::RevoluteAxis {
                    axis,
                    var,
                    multiplier: sign * multiplier,
                    offset: sign * offset,
                    plain: j.origin.rotation.quaternion().coords == nalgebra::Vector4::new(0.0, 0.0, 0.0, 1.0),
                },
            },
            JointKind::Prismatic => Motion::Prismatic {
                axis: j.axis,
                var,
                multiplier,
                offset,
            },
        };
        ops.push(FkOp {
            parent: j.parent as u32,
            child: j.child as u32,
            origin: j.origin,
            motion,
        });
    }

    let link_shapes = links.iter().map(link_shape).collect();
    let var_joints: Vec<&Joint> = variables.iter().map(|&v| &joints[v]).collect();
    let data = ModelData {
        name: robot.name.clone(),
        source_name: source_name.to_owned(),
        variable_names: var_joints.iter().map(|j| j.name.clone()).collect(),
        lower: var_joints.iter().map(|j| j.limits.lower).collect(),
        upper: var_joints.iter().map(|j| j.limits.upper).collect(),
        velocity: var_joints.iter().map(|j| j.limits.velocity).collect(),
        effort: var_joints.iter().map(|j| j.limits.effort).collect(),
        link_by_name: links.iter().enumerate().map(|(i, l)| (l.name.clone(), i)).collect(),
        joint_by_name,
        fingerprint: fingerprint(&links, &joints),
        links,
        joints,
        root: 0,
        variables,
        link_shapes,
        chains,
        fk: FkProgram { ops },
        sphere_covers: std::sync::OnceLock::new(),
        distance_fields: std::sync::OnceLock::new(),
        pair_tables: std::sync::Mutex::default(),
    };
    Ok(RobotModel(Arc::new(data)))
}

fn build_link(
    l: &urdf_rs::Link,
    parent_urdf_joint: Option<usize>,
    source_name: &str,
    base_dir: Option<&Path>,
    resolver: &PackageResolver,
    options: &LoadOptions,
    named_materials: &[urdf_rs::Material],
) -> Result<Link> {
    let element = format!("link `{}`", l.name);
    let inertial = {
        let i = &l.inertial;
        let m = i.mass.value;
        if !m.is_finite() || m < 0.0 {
            return Err(invalid(
                source_name,
                element.clone(),
                "inertial mass",
                m,
                "expected a finite number ≥ 0",
            ));
        }
        let t = &i.inertia;
        for v in [t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz] {
            if !v.is_finite() {
                return Err(invalid(
                    source_name,
                    element.clone(),
                    "inertia",
                    v,
                    "expected a finite number",
                ));
            }
        }
        if m > 0.0 {
            Some(Inertial {
                origin: pose(&i.origin, source_name, &element)?,
                mass: m,
                inertia: Matrix3::new(t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz),
            })
        } else {
            None
        }
    };
    let mut visuals = Vec::new();
    for v in &l.visual {
        let (material, rgba) = match &v.material {
            Some(m) => (
                (!m.name.is_empty()).then(|| m.name.clone()),
                // A visual may refer to a material defined once at the robot level.
                m.color
                    .as_ref()
                    .or_else(|| {
                        named_materials
                            .iter()
                            .find(|n| n.name == m.name)
                            .and_then(|n| n.color.as_ref())
                    })
                    .map(|c| c.rgba.0),
            ),
            None => (None, None),
        };
        visuals.push(Visual {
            name: v.name.clone(),
            origin: pose(&v.origin, source_name, &element)?,
            geometry: geometry(&v.geometry, source_name, &l.name, base_dir, resolver)?,
            material,
            rgba,
        });
    }
    let mut collisions = Vec::new();
    for c in &l.collision {
        let origin = pose(&c.origin, source_name, &element)?;
        let geometry = geometry(&c.geometry, source_name, &l.name, base_dir, resolver)?;
        let (shape, correction) = shape_of(&geometry, options.mesh_collision)?;
        collisions.push(Collision {
            name: c.name.clone(),
            origin,
            shape_origin: origin * correction,
            geometry,
            shape,
        });
    }
    Ok(Link {
        name: l.name.clone(),
        parent_joint: parent_urdf_joint,
        inertial,
        visuals,
        collisions,
    })
}

fn geometry(
    g: &urdf_rs::Geometry,
    source_name: &str,
    link: &str,
    base_dir: Option<&Path>,
    resolver: &PackageResolver,
) -> Result<Geometry> {
    let element = || format!("link `{link}` geometry");
    let positive = |what: &'static str, v: f64| {
        if v > 0.0 && v <= MAX_LENGTH {
            Ok(v)
        } else {
            Err(invalid(
                source_name,
                element(),
                what,
                v,
                "expected a number > 0 and ≤ 1e4 m",
            ))
        }
    };
    Ok(match g {
        urdf_rs::Geometry::Box { size } => Geometry::Box {
            half_extents: Vector3::new(
                positive("box size x", size[0])? / 2.0,
                positive("box size y", size[1])? / 2.0,
                positive("box size z", size[2])? / 2.0,
            ),
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
            radius: positive("cylinder radius", *radius)?,
            length: positive("cylinder length", *length)?,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Geometry::Capsule {
            radius: positive("capsule radius", *radius)?,
            length: if *length >= 0.0 && *length <= MAX_LENGTH {
                *length
            } else {
                return Err(invalid(
                    source_name,
                    element(),
                    "capsule length",
                    *length,
                    "expected ≥ 0",
                ));
            },
        },
        urdf_rs::Geometry::Sphere { radius } => Geometry::Sphere {
            radius: positive("sphere radius", *radius)?,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let scale = scale
                .map(|s| Vector3::from(s.0))
                .unwrap_or_else(|| Vector3::repeat(1.0));
            for (what, v) in [
                ("mesh scale x", scale.x),
                ("mesh scale y", scale.y),
                ("mesh scale z", scale.z),
            ] {
                if v.is_nan() || v.abs() > MAX_LENGTH || v == 0.0 {
                    return Err(invalid(
                        source_name,
                        element(),
                        what,
                        v,
                        "expected a non-zero number within ±1e4",
                    ));
                }
            }
            let path = resolver
                .resolve(filename, base_dir)
                .map_err(|tried| KinematicsError::MeshNotFound {
                    source_name: source_name.to_owned(),
                    link: link.to_owned(),
                    uri: filename.clone(),
                    searched: tried
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", "),
                })?;
            Geometry::Mesh {
                uri: filename.clone(),
                scale,
                mesh: Arc::new(load_mesh(&path, &scale)?),
            }
        }
    })
}

/// The parry shape of a geometry, and the pose correction from the URDF frame to parry's
/// (parry's cylinders and capsules run along y, URDF's along z).
pub(crate) fn shape_of(g: &Geometry, mode: MeshCollision) -> Result<(SharedShape, Isometry3<f64>)> {
    let z_to_y = Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
    );
    Ok(match g {
        Geometry::Box { half_extents: h } => (
            SharedShape::cuboid(h.x as f32, h.y as f32, h.z as f32),
            Isometry3::identity(),
        ),
        Geometry::Cylinder { radius, length } => (SharedShape::cylinder((length / 2.0) as f32, *radius as f32), z_to_y),
        Geometry::Capsule { radius, length } => (SharedShape::capsule_y((length / 2.0) as f32, *radius as f32), z_to_y),
        Geometry::Sphere { radius } => (SharedShape::ball(*radius as f32), Isometry3::identity()),
        Geometry::Mesh { uri, mesh, .. } => (mesh_shape(mesh, mode, uri)?, Isometry3::identity()),
    })
}

fn link_shape(link: &Link) -> Option<LinkShape> {
    match link.collisions.as_slice() {
        [] => None,
        [one] => Some(LinkShape {
            shape: one.shape.clone(),
            origin: one.shape_origin,
        }),
        many => Some(LinkShape {
            shape: SharedShape::compound(many.iter().flat_map(compound_parts).collect()),
            origin: Isometry3::identity(),
        }),
    }
}

/// The parts that collision element `c` adds to its link's compound shape. A compound cannot
/// hold composite shapes (parry panics on them), so a convex decomposition gives its convex
/// parts and a triangle mesh its triangles, each placed where the element puts it.
fn compound_parts(c: &Collision) -> Vec<(parry3d::math::Pose, SharedShape)> {
    let at = to_pose(&c.shape_origin);
    if let Some(compound) = c.shape.as_compound() {
        compound.shapes().iter().map(|(p, s)| (at * *p, s.clone())).collect()
    } else if let Some(mesh) = c.shape.as_trimesh() {
        mesh.triangles().map(|t| (at, SharedShape::new(t))).collect()
    } else {
        vec![(at, c.shape.clone())]
    }
}

fn pose(p: &urdf_rs::Pose, source_name: &str, element: &str) -> Result<Isometry3<f64>> {
    finite3(&p.xyz.0, source_name, element, "origin xyz")?;
    finite3(&p.rpy.0, source_name, element, "origin rpy")?;
    let [x, y, z] = p.xyz.0;
    let [r, pi, ya] = p.rpy.0;
    Ok(Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(r, pi, ya),
    ))
}

/// Largest length (m) or coordinate accepted: far beyond any robot, and well inside the f32
/// range that parry and rapier compute in.
pub(crate) const MAX_LENGTH: f64 = 1e4;

fn finite3(v: &[f64; 3], source_name: &str, element: &str, what: &'static str) -> Result<()> {
    match v.iter().find(|x| x.is_nan() || x.abs() > MAX_LENGTH) {
        Some(&bad) => Err(invalid(
            source_name,
            element.to_owned(),
            what,
            bad,
            "expected numbers within ±1e4",
        )),
        None => Ok(()),
    }
}

fn invalid(
    source_name: &str,
    element: String,
    what: &'static str,
    value: f64,
    expected: &'static str,
) -> KinematicsError {
    KinematicsError::InvalidValue {
        source_name: source_name.to_owned(),
        element,
        what,
        value,
        expected,
    }
}

/// FNV-1a over everything that affects kinematics and collision geometry (stable across runs
/// and platforms, unlike `std`'s hasher).
fn fingerprint(links: &[Link], joints: &[Joint]) -> u64 {
    struct Fnv(u64);
    impl Fnv {
        fn bytes(&mut self, b: &[u8]) {
            for &x in b {
                self.0 ^= x as u64;
                self.0 = self.0.wrapping_mul(0x100_0000_01b3);
            }
        }
        fn f(&mut self, v: f64) {
            self.bytes(&v.to_le_bytes());
        }
        fn iso(&mut self, i: &Isometry3<f64>) {
            for v in i.translation.vector.iter().chain(i.rotation.coords.iter()) {
                self.f(*v);
            }
        }
    }
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    for l in links {
        h.bytes(l.name.as_bytes());
        for c in &l.collisions {
            h.iso(&c.shape_origin);
            let aabb = c.shape.compute_local_aabb();
            for v in [aabb.mins, aabb.maxs] {
                let v: Vector = v;
                h.f(v.x as f64);
                h.f(v.y as f64);
                h.f(v.z as f64);
            }
        }
    }
    for j in joints {
        h.bytes(j.name.as_bytes());
        h.bytes(j.kind.as_str().as_bytes());
        h.iso(&j.origin);
        for v in j.axis.iter() {
            h.f(*v);
        }
        h.f(j.limits.lower);
        h.f(j.limits.upper);
    }
    h.0
}
