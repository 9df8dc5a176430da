//! The immutable robot description: links, joints, limits, geometry.

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::{Isometry3, Matrix3, Unit, Vector3};
use parry3d::shape::SharedShape;
use rand::{Rng, RngExt};

use crate::error::{KinematicsError, Result};
use crate::fk::FkProgram;

/// How a joint moves its child link relative to its parent.
///
/// ```
/// use hearth_kinematics::{JointKind, RobotModel};
/// let panda = RobotModel::builtin("panda").unwrap();
/// let j = panda.joint_index("panda_finger_joint1").unwrap();
/// assert_eq!(panda.joints()[j].kind, JointKind::Prismatic);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// Rotation about the axis, within position limits.
    Revolute,
    /// Rotation about the axis without position limits.
    Continuous,
    /// Translation along the axis, within position limits.
    Prismatic,
    /// No motion.
    Fixed,
}

impl JointKind {
    /// The URDF spelling of this kind.
    ///
    /// ```
    /// use hearth_kinematics::JointKind;
    /// assert_eq!(JointKind::Continuous.as_str(), "continuous");
    /// assert_eq!(JointKind::Fixed.as_str(), "fixed");
    /// ```
    pub fn as_str(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
            JointKind::Fixed => "fixed",
        }
    }

    /// Whether the joint moves at all.
    ///
    /// ```
    /// use hearth_kinematics::JointKind;
    /// assert!(JointKind::Prismatic.is_movable());
    /// assert!(!JointKind::Fixed.is_movable());
    /// ```
    pub fn is_movable(self) -> bool {
        self != JointKind::Fixed
    }
}

/// Position, velocity and effort limits of one joint.
///
/// Continuous joints have `lower = -∞`, `upper = +∞`. A velocity or effort written as 0 (or
/// absent) in the URDF means "unspecified" and is stored as `+∞`.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let j4 = &panda.joints()[panda.joint_index("panda_joint4").unwrap()];
/// assert!(j4.limits.lower < j4.limits.upper && j4.limits.upper < 0.0);
/// assert!(j4.limits.velocity > 0.0 && j4.limits.effort > 0.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointLimits {
    /// Lower position limit (rad or m).
    pub lower: f64,
    /// Upper position limit (rad or m).
    pub upper: f64,
    /// Velocity limit (rad/s or m/s).
    pub velocity: f64,
    /// Effort limit (N·m or N).
    pub effort: f64,
}

/// `q_this = multiplier · q_target + offset`.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let f2 = &panda.joints()[panda.joint_index("panda_finger_joint2").unwrap()];
/// let mimic = f2.mimic.expect("the second finger follows the first");
/// assert_eq!(panda.joints()[mimic.joint].name, "panda_finger_joint1");
/// assert_eq!(mimic.multiplier, 1.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mimic {
    /// Index of the joint followed (always an independent variable, chains resolved at load).
    pub joint: usize,
    /// Multiplier.
    pub multiplier: f64,
    /// Offset.
    pub offset: f64,
}

/// Joint damping and friction (used by the simulator).
///
/// ```
/// use hearth_kinematics::Dynamics;
/// let d = Dynamics::default();
/// assert_eq!((d.damping, d.friction), (0.0, 0.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Dynamics {
    /// Viscous damping.
    pub damping: f64,
    /// Coulomb friction.
    pub friction: f64,
}

/// One joint of the tree.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let j1 = &panda.joints()[panda.joint_index("panda_joint1").unwrap()];
/// assert_eq!(panda.links()[j1.parent].name, "panda_link0");
/// assert_eq!(panda.links()[j1.child].name, "panda_link1");
/// assert_eq!(j1.variable, Some(0));
/// ```
#[derive(Clone, Debug)]
pub struct Joint {
    /// Joint name.
    pub name: String,
    /// How it moves.
    pub kind: JointKind,
    /// Parent link index.
    pub parent: usize,
    /// Child link index.
    pub child: usize,
    /// Pose of the joint frame (= child link frame at zero) in the parent link frame.
    pub origin: Isometry3<f64>,
    /// Unit axis in the joint frame.
    pub axis: Unit<Vector3<f64>>,
    /// Limits (meaningless for fixed joints).
    pub limits: JointLimits,
    /// Set when this joint follows another one.
    pub mimic: Option<Mimic>,
    /// Damping and friction, if the URDF gives them.
    pub dynamics: Option<Dynamics>,
    /// Index into the configuration vector, for movable joints that do not mimic.
    pub variable: Option<usize>,
}

/// Mass properties of a link.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let link1 = &panda.links()[panda.link_index("panda_link1").unwrap()];
/// let inertial = link1.inertial.as_ref().expect("panda links have mass");
/// assert!(inertial.mass > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Inertial {
    /// Centre-of-mass frame in the link frame.
    pub origin: Isometry3<f64>,
    /// Mass in kg.
    pub mass: f64,
    /// Inertia tensor about the centre of mass, in the `origin` frame (kg·m²).
    pub inertia: Matrix3<f64>,
}

/// A triangle mesh, already scaled, in the geometry's frame.
///
/// ```
/// use hearth_kinematics::TriangleMesh;
/// let tri = TriangleMesh {
///     vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
///     triangles: vec![[0, 1, 2]],
/// };
/// assert!(tri.triangles.iter().flatten().all(|&i| (i as usize) < tri.vertices.len()));
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// A geometric primitive or mesh as the URDF describes it.
///
/// ```
/// use hearth_kinematics::{Geometry, RobotModel};
/// let panda = RobotModel::builtin("panda").unwrap();
/// let link0 = &panda.links()[panda.root()];
/// assert!(!link0.collisions.is_empty());
/// // The built-in Panda is made of primitives only (no mesh files).
/// assert!(link0.visuals.iter().all(|v| !matches!(v.geometry, Geometry::Mesh { .. })));
/// ```
#[derive(Clone, Debug)]
pub enum Geometry {
    /// A box with these half extents.
    Box {
        /// Half extents along x, y, z.
        half_extents: Vector3<f64>,
    },
    /// A cylinder along the local z axis.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Full length.
        length: f64,
    },
    /// A capsule along the local z axis (cylinder length, without caps).
    Capsule {
        /// Radius.
        radius: f64,
        /// Length of the cylindrical part.
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A mesh file.
    Mesh {
        /// The `filename` attribute as written.
        uri: String,
        /// The scale applied.
        scale: Vector3<f64>,
        /// The loaded, scaled triangles.
        mesh: Arc<TriangleMesh>,
    },
}

/// A visual element of a link.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let hand = &panda.links()[panda.link_index("panda_hand").unwrap()];
/// assert!(!hand.visuals.is_empty());
/// ```
#[derive(Clone, Debug)]
pub struct Visual {
    /// Optional name.
    pub name: Option<String>,
    /// Pose in the link frame.
    pub origin: Isometry3<f64>,
    /// Shape.
    pub geometry: Geometry,
    /// Material name (e.g. `metal_white`), if any.
    pub material: Option<String>,
    /// RGBA colour, if given.
    pub rgba: Option<[f64; 4]>,
}

/// A collision element of a link, with its parry shape.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let hand = &panda.links()[panda.link_index("panda_hand").unwrap()];
/// let c = &hand.collisions[0];
/// assert!(c.shape.compute_local_aabb().volume() > 0.0);
/// ```
#[derive(Clone)]
pub struct Collision {
    /// Optional name.
    pub name: Option<String>,
    /// Pose in the link frame, as the URDF writes it.
    pub origin: Isometry3<f64>,
    /// The shape as described.
    pub geometry: Geometry,
    /// The parry shape (meshes become convex hulls or decompositions).
    pub shape: SharedShape,
    /// Pose of `shape` in the link frame (differs from `origin` for cylinders and capsules,
    /// whose parry axis is y while URDF's is z).
    pub shape_origin: Isometry3<f64>,
}

impl std::fmt::Debug for Collision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Collision")
            .field("name", &self.name)
            .field("origin", &self.origin)
            .field("geometry", &self.geometry)
            .finish_non_exhaustive()
    }
}

/// One link of the tree.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let root = &panda.links()[panda.root()];
/// assert_eq!(root.name, "panda_link0");
/// assert!(root.parent_joint.is_none());
/// ```
#[derive(Clone, Debug)]
pub struct Link {
    /// Link name.
    pub name: String,
    /// The joint whose child this link is (`None` for the root).
    pub parent_joint: Option<usize>,
    /// Mass properties, if given.
    pub inertial: Option<Inertial>,
    /// Visual elements.
    pub visuals: Vec<Visual>,
    /// Collision elements.
    pub collisions: Vec<Collision>,
}

/// A link's collision geometry as one parry shape, in the link frame.
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let shape = panda.link_shape(panda.link_index("panda_link3").unwrap()).unwrap();
/// assert!(shape.shape.compute_local_aabb().volume() > 0.0);
/// ```
#[derive(Clone)]
pub struct LinkShape {
    /// The shape (a compound when the link has several collision elements).
    pub shape: SharedShape,
    /// Pose of the shape in the link frame.
    pub origin: Isometry3<f64>,
}

/// A named ordered subset of joints defined with a model (e.g. Fetch's `arm`).
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let arm = &panda.chains()[0];
/// assert_eq!((arm.name.as_str(), arm.tip.as_str()), ("arm", "panda_hand_tcp"));
/// assert_eq!(arm.joints.len(), 7);
/// ```
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ChainSpec {
    /// Chain name.
    pub name: String,
    /// Joint names in order.
    pub joints: Vec<String>,
    /// The end-effector link the chain is usually solved for.
    pub tip: String,
}

/// Clearance tables by (smaller, larger) link index; `None`: the pair has none.
pub(crate) type PairTables = HashMap<(usize, usize), Option<Arc<crate::pair_table::PairTable>>>;

pub(crate) struct ModelData {
    pub(crate) name: String,
    pub(crate) source_name: String,
    pub(crate) links: Vec<Link>,
    pub(crate) joints: Vec<Joint>,
    pub(crate) root: usize,
    pub(crate) variables: Vec<usize>,
    pub(crate) variable_names: Vec<String>,
    pub(crate) lower: Vec<f64>,
    pub(crate) upper: Vec<f64>,
    pub(crate) velocity: Vec<f64>,
    pub(crate) effort: Vec<f64>,
    pub(crate) link_by_name: HashMap<String, usize>,
    pub(crate) joint_by_name: HashMap<String, usize>,
    pub(crate) link_shapes: Vec<Option<LinkShape>>,
    pub(crate) chains: Vec<ChainSpec>,
    pub(crate) fk: FkProgram,
    pub(crate) fingerprint: u64,
    /// Clearance tables of link pairs, built on first request (`None`: the pair has none).
    pub(crate) pair_tables: std::sync::Mutex<PairTables>,
    /// Per link: a conservative sphere cover of its collision shape, built on first use.
    pub(crate) sphere_covers: std::sync::OnceLock<Arc<Vec<Vec<crate::spheres::Sphere>>>>,
    /// Per link: the distance field of a compound link's shape, built on first use.
    pub(crate) distance_fields: std::sync::OnceLock<Arc<Vec<Option<crate::distance_field::DistanceField>>>>,
}

/// An immutable robot description: a tree of links connected by joints, with limits and
/// collision geometry.
///
/// Cloning is cheap (one reference count); a model can be shared across threads.
/// The configuration vector `q` lists the **movable joints that do not mimic another**, in the
/// order they appear in the URDF ([`RobotModel::variable_names`]).
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// assert_eq!(panda.dof(), 8); // 7 arm joints + 1 finger (the second finger mimics)
/// let mut poses = panda.pose_buffer();
/// panda.fk(&panda.neutral_configuration(), &mut poses).unwrap();
/// let hand = panda.link_index("panda_hand").unwrap();
/// assert!(poses[hand].translation.z > 0.5);
/// ```
#[derive(Clone)]
pub struct RobotModel(pub(crate) Arc<ModelData>);

impl std::fmt::Debug for RobotModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotModel")
            .field("name", &self.0.name)
            .field("links", &self.0.links.len())
            .field("dof", &self.0.variables.len())
            .finish()
    }
}

impl RobotModel {
    /// Robot name (the URDF's `<robot name>`).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.name(), "panda");
    /// ```
    pub fn name(&self) -> &str {
        &self.0.name
    }

    /// Where the model came from (file path, `builtin:NAME` or `<string>`).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.source_name(), "builtin:panda");
    /// ```
    pub fn source_name(&self) -> &str {
        &self.0.source_name
    }

    /// All links, parents before children (index 0 is the root).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.links()[0].name, "panda_link0");
    /// assert!(panda.links().iter().any(|l| l.name == "panda_hand"));
    /// ```
    pub fn links(&self) -> &[Link] {
        &self.0.links
    }

    /// All joints, in URDF order.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.joints()[0].name, "panda_joint1");
    /// assert_eq!(panda.joints().len(), panda.links().len() - 1); // a tree
    /// ```
    pub fn joints(&self) -> &[Joint] {
        &self.0.joints
    }

    /// Index of the root link.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.links()[panda.root()].name, "panda_link0");
    /// ```
    pub fn root(&self) -> usize {
        self.0.root
    }

    /// Number of configuration variables.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.dof(), panda.variable_names().len());
    /// assert_eq!(panda.dof(), 8);
    /// ```
    pub fn dof(&self) -> usize {
        self.0.variables.len()
    }

    /// Joint index of each configuration variable.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// for (v, &j) in panda.variables().iter().enumerate() {
    ///     assert_eq!(panda.joints()[j].variable, Some(v));
    /// }
    /// ```
    pub fn variables(&self) -> &[usize] {
        &self.0.variables
    }

    /// Joint name of each configuration variable, in `q` order.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.variable_names()[0], "panda_joint1");
    /// assert_eq!(panda.variable_names().last().unwrap(), "panda_finger_joint1");
    /// ```
    pub fn variable_names(&self) -> &[String] {
        &self.0.variable_names
    }

    /// Lower position limit per variable (`-∞` for continuous joints).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert!(panda.lower().iter().zip(panda.upper()).all(|(lo, hi)| lo < hi));
    /// ```
    pub fn lower(&self) -> &[f64] {
        &self.0.lower
    }

    /// Upper position limit per variable (`+∞` for continuous joints).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let j4 = panda.variable_names().iter().position(|n| n == "panda_joint4").unwrap();
    /// assert!(panda.upper()[j4] < 0.0); // the elbow cannot straighten fully
    /// ```
    pub fn upper(&self) -> &[f64] {
        &self.0.upper
    }

    /// Velocity limit per variable.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert!(panda.velocity_limits().iter().all(|&v| v > 0.0));
    /// ```
    pub fn velocity_limits(&self) -> &[f64] {
        &self.0.velocity
    }

    /// Effort limit per variable.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.effort_limits().len(), panda.dof());
    /// assert!(panda.effort_limits().iter().all(|&e| e > 0.0));
    /// ```
    pub fn effort_limits(&self) -> &[f64] {
        &self.0.effort
    }

    /// Named chains that come with the model (built-in robots define them).
    ///
    /// ```
    /// let fetch = hearth_kinematics::RobotModel::builtin("fetch").unwrap();
    /// assert!(fetch.chains().iter().any(|c| c.name == "head"));
    /// ```
    pub fn chains(&self) -> &[ChainSpec] {
        &self.0.chains
    }

    /// A hash of everything that affects kinematics and collision geometry.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let a = RobotModel::builtin("panda").unwrap();
    /// let b = RobotModel::builtin("panda").unwrap();
    /// assert_eq!(a.fingerprint(), b.fingerprint());
    /// assert_ne!(a.fingerprint(), RobotModel::builtin("locobot").unwrap().fingerprint());
    /// ```
    pub fn fingerprint(&self) -> u64 {
        self.0.fingerprint
    }

    /// Index of a link by name.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let hand = panda.link_index("panda_hand").unwrap();
    /// assert_eq!(panda.links()[hand].name, "panda_hand");
    /// assert!(panda.link_index("no_such_link").is_err());
    /// ```
    pub fn link_index(&self, name: &str) -> Result<usize> {
        self.0
            .link_by_name
            .get(name)
            .copied()
            .ok_or_else(|| KinematicsError::UnknownLink {
                robot: self.0.name.clone(),
                name: name.to_owned(),
            })
    }

    /// Index of a joint by name.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.joint_index("panda_joint1").unwrap(), 0);
    /// assert!(panda.joint_index("no_such_joint").is_err());
    /// ```
    pub fn joint_index(&self, name: &str) -> Result<usize> {
        self.0
            .joint_by_name
            .get(name)
            .copied()
            .ok_or_else(|| KinematicsError::UnknownJoint {
                robot: self.0.name.clone(),
                name: name.to_owned(),
            })
    }

    /// The link's collision geometry merged into one shape, or `None` if it has none.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert!(panda.link_shape(panda.link_index("panda_link1").unwrap()).is_some());
    /// assert!(panda.link_shape(panda.link_index("panda_hand_tcp").unwrap()).is_none());
    /// ```
    pub fn link_shape(&self, link: usize) -> Option<&LinkShape> {
        self.0.link_shapes.get(link).and_then(Option::as_ref)
    }

    /// A few balls (in the link frame) whose union contains the link's whole collision shape,
    /// or an empty slice for a link without one. Built once per model on first use (about a
    /// second of CPU time for every link of the Fetch, spread over the cores; a built-in
    /// robot's covers once per process); see [`crate::spheres`] for how.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let l = panda.link_index("panda_link4").unwrap();
    /// let balls = panda.link_spheres(l);
    /// assert!(balls.len() > 1 && balls.iter().all(|b| b.radius > 0.0));
    /// ```
    pub fn link_spheres(&self, link: usize) -> &[crate::spheres::Sphere] {
        let covers = self.0.sphere_covers.get_or_init(|| crate::spheres::covers(self));
        covers.get(link).map_or(&[], Vec::as_slice)
    }

    /// The distance field of link `link`'s collision shape, in the link frame, for links
    /// with at least [`MIN_PARTS`](crate::distance_field::MIN_PARTS) collision elements
    /// (`None` for the others). Built once per model on first use, for every such link at
    /// once (a built-in robot's once per process); see [`crate::distance_field`].
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// assert!(fetch.link_field(fetch.link_index("base_link").unwrap()).is_some()); // 15 boxes
    /// assert!(fetch.link_field(fetch.link_index("wrist_roll_link").unwrap()).is_none()); // one cylinder
    /// ```
    pub fn link_field(&self, link: usize) -> Option<&crate::distance_field::DistanceField> {
        let fields = self
            .0
            .distance_fields
            .get_or_init(|| crate::distance_field::fields(self));
        fields.get(link).and_then(Option::as_ref)
    }

    /// The clearance table of links `a` and `b` (see [`PairTable`](crate::PairTable)), built
    /// on the first request for the pair; `None` when their relative pose depends on more than
    /// two joints (or on joints without finite limits). The same table is returned for
    /// `(a, b)` and `(b, a)`.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let (l5, l7) = (panda.link_index("panda_link5").unwrap(), panda.link_index("panda_link7").unwrap());
    /// assert!(panda.pair_table(l5, l7).is_some());
    /// ```
    pub fn pair_table(&self, a: usize, b: usize) -> Option<Arc<crate::pair_table::PairTable>> {
        let key = (a.min(b), a.max(b));
        let mut tables = self
            .0
            .pair_tables
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        tables
            .entry(key)
            .or_insert_with(|| crate::pair_table::PairTable::build(self, key.0, key.1).map(Arc::new))
            .clone()
    }

    /// A buffer with one identity pose per link, for [`RobotModel::fk`].
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let poses = panda.pose_buffer();
    /// assert_eq!(poses.len(), panda.links().len());
    /// ```
    pub fn pose_buffer(&self) -> Vec<Isometry3<f64>> {
        vec![Isometry3::identity(); self.0.links.len()]
    }

    /// A configuration at zero, moved inside the limits where zero is outside them.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let q = panda.neutral_configuration();
    /// assert_eq!(q[0], 0.0);
    /// assert_eq!(q[3], panda.upper()[3]); // zero lies above joint 4's range
    /// ```
    pub fn neutral_configuration(&self) -> Vec<f64> {
        self.0
            .lower
            .iter()
            .zip(&self.0.upper)
            .map(|(&lo, &hi)| 0.0f64.clamp(lo, hi))
            .collect()
    }

    /// Fills `q` with a configuration drawn uniformly inside the limits (continuous joints
    /// in `[-π, π)`).
    ///
    /// ```
    /// use rand::SeedableRng;
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
    /// let mut q = vec![0.0; panda.dof()];
    /// panda.random_configuration(&mut rng, &mut q);
    /// assert!(panda.within_limits(&q, 0.0));
    /// ```
    pub fn random_configuration<R: Rng + ?Sized>(&self, rng: &mut R, q: &mut [f64]) {
        for ((qi, &lo), &hi) in q.iter_mut().zip(&self.0.lower).zip(&self.0.upper) {
            *qi = sample_interval(rng, lo, hi);
        }
    }

    /// Checks that `q` has the right length and only finite values.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// assert!(panda.check_configuration(&panda.neutral_configuration()).is_ok());
    /// assert!(panda.check_configuration(&[0.0; 3]).is_err());
    /// assert!(panda.check_configuration(&[f64::NAN; 8]).is_err());
    /// ```
    pub fn check_configuration(&self, q: &[f64]) -> Result<()> {
        check_values("configuration", q, &self.0.variable_names)
    }

    /// Whether every value of `q` lies within its limits (plus `tolerance`).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let mut q = panda.neutral_configuration();
    /// assert!(panda.within_limits(&q, 0.0));
    /// q[0] = panda.upper()[0] + 0.01;
    /// assert!(!panda.within_limits(&q, 0.0));
    /// assert!(panda.within_limits(&q, 0.02));
    /// ```
    pub fn within_limits(&self, q: &[f64], tolerance: f64) -> bool {
        q.len() == self.dof()
            && q.iter()
                .zip(&self.0.lower)
                .zip(&self.0.upper)
                .all(|((&v, &lo), &hi)| v >= lo - tolerance && v <= hi + tolerance)
    }

    /// Position of joint `j` for configuration `q` (mimic joints follow their target).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let mut q = panda.neutral_configuration();
    /// q[7] = 0.03; // panda_finger_joint1
    /// let f2 = panda.joint_index("panda_finger_joint2").unwrap();
    /// assert_eq!(panda.joint_position(&q, f2), 0.03);
    /// ```
    pub fn joint_position(&self, q: &[f64], j: usize) -> f64 {
        let joint = &self.0.joints[j];
        match (joint.variable, joint.mimic) {
            (Some(v), _) => q[v],
            (None, Some(m)) => {
                let v = self.0.joints[m.joint].variable.unwrap_or(0);
                m.multiplier * q[v] + m.offset
            }
            _ => 0.0,
        }
    }

    /// The joints from the root down to `link`, root first.
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let path = panda.joints_to(panda.link_index("panda_link2").unwrap());
    /// let names: Vec<_> = path.iter().map(|&j| panda.joints()[j].name.as_str()).collect();
    /// assert_eq!(names, ["panda_joint1", "panda_joint2"]);
    /// ```
    pub fn joints_to(&self, link: usize) -> Vec<usize> {
        let mut path = Vec::new();
        let mut cur = link;
        while let Some(j) = self.0.links[cur].parent_joint {
            path.push(j);
            cur = self.0.joints[j].parent;
        }
        path.reverse();
        path
    }

    /// Whether link `ancestor` lies on the path from the root to `link` (or is `link`).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::builtin("panda").unwrap();
    /// let (l1, hand) = (panda.link_index("panda_link1").unwrap(), panda.link_index("panda_hand").unwrap());
    /// assert!(panda.is_ancestor(l1, hand));
    /// assert!(!panda.is_ancestor(hand, l1));
    /// assert!(panda.is_ancestor(hand, hand));
    /// ```
    pub fn is_ancestor(&self, ancestor: usize, link: usize) -> bool {
        let mut cur = link;
        loop {
            if cur == ancestor {
                return true;
            }
            match self.0.links[cur].parent_joint {
                Some(j) => cur = self.0.joints[j].parent,
                None => return false,
            }
        }
    }
}

/// Uniform sample in `[lo, hi]`; `[-π, π)` when the interval is unbounded.
pub(crate) fn sample_interval<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (-std::f64::consts::PI, std::f64::consts::PI)
    };
    if hi > lo {
        lo + (hi - lo) * rng.random::<f64>()
    } else {
        lo
    }
}

pub(crate) fn check_values(what: &'static str, q: &[f64], names: &[String]) -> Result<()> {
    if q.len() != names.len() {
        return Err(KinematicsError::DimensionMismatch {
            what,
            expected: names.len(),
            got: q.len(),
        });
    }
    // Every value at once first (a fold without an early exit, which the compiler vectorises:
    // this runs on every forward kinematics call); the loop below names the first bad one.
    if q.iter().fold(true, |finite, v| finite & v.is_finite()) {
        return Ok(());
    }
    for (index, (&value, name)) in q.iter().zip(names).enumerate() {
        if !value.is_finite() {
            return Err(KinematicsError::NonFinite {
                what,
                index,
                name: name.clone(),
                value,
            });
        }
    }
    Ok(())
}
