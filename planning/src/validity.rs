//! State validity: robot model + chain + obstacles + self-collision + attached objects.

use std::sync::Arc;

use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, links_touch, to_pose};
use nalgebra::Isometry3;
use parry3d::shape::SharedShape;

use crate::obstacles::{ObstacleId, Obstacles};

/// Decides whether one configuration is collision-free. Planners only see this trait, so a
/// vectorised or approximate checker can slot in without touching them.
pub trait StateValidator {
    /// Whether `q` (a configuration of the planned space) is valid.
    fn is_valid(&mut self, q: &[f64]) -> bool;
    /// How many configurations have been checked so far.
    fn checks(&self) -> u64;
}

/// What makes a configuration invalid, with names for messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Two robot links (or an attached object, named `attached:NAME`) touch.
    SelfCollision {
        /// First link.
        a: String,
        /// Second link.
        b: String,
    },
    /// A robot link (or attached object) touches an obstacle.
    Obstacle {
        /// The link.
        link: String,
        /// The obstacle's name.
        obstacle: String,
    },
}

impl std::fmt::Display for Contact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Contact::SelfCollision { a, b } => write!(f, "link `{a}` touches link `{b}`"),
            Contact::Obstacle { link, obstacle } => write!(f, "link `{link}` touches obstacle `{obstacle}`"),
        }
    }
}

/// An object held by the robot: it moves rigidly with `link` and is checked like a link.
#[derive(Clone)]
pub struct Attached {
    /// Name used in messages.
    pub name: String,
    /// The link it is fixed to.
    pub link: usize,
    /// Its pose in the link frame.
    pub offset: Isometry3<f64>,
    /// Its shape.
    pub shape: SharedShape,
}

/// The exact checker: forward kinematics of the whole robot, every link with geometry against
/// the obstacles, the self-collision matrix's pairs against each other, and attached objects
/// against both. Buffers are allocated once; checking does not allocate.
///
/// ```
/// use std::sync::Arc;
/// use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
/// use hearth_planning::obstacles::{Obstacle, ParryScene};
/// use hearth_planning::validity::{RobotValidity, StateValidator};
/// use parry3d::math::{Pose, Vector};
///
/// let panda = RobotModel::builtin("panda").unwrap();
/// let arm = Chain::named(&panda, "arm").unwrap();
/// let acm = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 300, ..Default::default() });
/// let wall = Obstacle::cuboid("wall", Pose::translation(0.45, 0.0, 0.5), Vector::new(0.02, 1.0, 1.0));
/// let mut v = RobotValidity::new(arm, acm, Arc::new(ParryScene::new(vec![wall])));
/// let folded = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
/// assert!(v.is_valid(&folded));
/// let reaching = [0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.785]; // stretched forward into the wall
/// assert!(!v.is_valid(&reaching));
/// assert!(v.explain(&reaching).unwrap().to_string().contains("wall"));
/// ```
pub struct RobotValidity {
    model: RobotModel,
    chain: Chain,
    matrix: SelfCollisionMatrix,
    obstacles: Arc<dyn Obstacles>,
    geometric: Vec<usize>,
    pairs: Vec<(usize, usize)>,
    attached: Vec<Attached>,
    base: Isometry3<f64>,
    q_full: Vec<f64>,
    poses: Vec<Isometry3<f64>>,
    checks: u64,
}

impl RobotValidity {
    /// A checker for `chain`'s configurations. Joints outside the chain keep the model's
    /// neutral configuration (see [`RobotValidity::set_reference`]); the robot root sits at
    /// the world origin (see [`RobotValidity::set_base`]).
    pub fn new(chain: Chain, matrix: SelfCollisionMatrix, obstacles: Arc<dyn Obstacles>) -> Self {
        let model = chain.model().clone();
        let geometric = (0..model.links().len())
            .filter(|&l| model.link_shape(l).is_some())
            .collect();
        let pairs = matrix.checked_geometric_pairs(&model);
        Self {
            q_full: model.neutral_configuration(),
            poses: model.pose_buffer(),
            model,
            chain,
            matrix,
            obstacles,
            geometric,
            pairs,
            attached: Vec::new(),
            base: Isometry3::identity(),
            checks: 0,
        }
    }

    /// The chain being planned.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Sets the full configuration that joints outside the chain keep (fingers, head, …).
    pub fn set_reference(&mut self, q_full: &[f64]) -> Result<(), hearth_kinematics::KinematicsError> {
        self.model.check_configuration(q_full)?;
        self.q_full.copy_from_slice(q_full);
        Ok(())
    }

    /// Places the robot root in the world (e.g. a mobile base pose).
    pub fn set_base(&mut self, base: Isometry3<f64>) {
        self.base = base;
    }

    /// Attaches an object (a held object moves with the gripper). It is checked against the
    /// obstacles and against every link except `link` and links adjacent to it.
    pub fn attach(&mut self, object: Attached) {
        self.attached.push(object);
    }

    /// Removes every attached object.
    pub fn detach_all(&mut self) {
        self.attached.clear();
    }

    fn update_poses(&mut self, q: &[f64]) -> bool {
        if q.len() != self.chain.dof() {
            return false;
        }
        self.chain.scatter(q, &mut self.q_full);
        self.model.fk_from(&self.base, &self.q_full, &mut self.poses).is_ok()
    }

    fn link_hits(&self, l: usize) -> Option<ObstacleId> {
        let s = self.model.link_shape(l)?;
        let pose = to_pose(&(self.poses[l] * s.origin));
        self.obstacles.first_hit(s.shape.as_ref(), &pose)
    }

    fn attached_touches_link(&self, a: &Attached, l: usize) -> bool {
        if l == a.link || self.matrix.is_disabled(l, a.link) {
            return false;
        }
        let Some(s) = self.model.link_shape(l) else {
            return false;
        };
        let pa = to_pose(&(self.poses[a.link] * a.offset));
        let pl = to_pose(&(self.poses[l] * s.origin));
        parry3d::query::intersection_test(&pa, a.shape.as_ref(), &pl, s.shape.as_ref())
            .map(|r| r.intersecting)
            .unwrap_or(true)
    }

    /// Why `q` is invalid (the first contact found), or `None` if it is valid. Wrong-length or
    /// non-finite input reports no contact; check it with [`Chain::check`] first.
    pub fn explain(&mut self, q: &[f64]) -> Option<Contact> {
        if !self.update_poses(q) {
            return None;
        }
        let names = |l: usize| self.model.links()[l].name.clone();
        for &l in &self.geometric {
            if let Some(id) = self.link_hits(l) {
                return Some(Contact::Obstacle {
                    link: names(l),
                    obstacle: self.obstacles.name(id).unwrap_or("?").to_owned(),
                });
            }
        }
        if let Some((a, b)) = self.matrix.first_collision(&self.model, &self.poses) {
            return Some(Contact::SelfCollision {
                a: names(a),
                b: names(b),
            });
        }
        for a in &self.attached {
            let pose = to_pose(&(self.poses[a.link] * a.offset));
            if let Some(id) = self.obstacles.first_hit(a.shape.as_ref(), &pose) {
                return Some(Contact::Obstacle {
                    link: format!("attached:{}", a.name),
                    obstacle: self.obstacles.name(id).unwrap_or("?").to_owned(),
                });
            }
            if let Some(&l) = self.geometric.iter().find(|&&l| self.attached_touches_link(a, l)) {
                return Some(Contact::SelfCollision {
                    a: format!("attached:{}", a.name),
                    b: names(l),
                });
            }
        }
        None
    }
}

impl StateValidator for RobotValidity {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        if !q.iter().all(|v| v.is_finite()) || !self.update_poses(q) {
            return false;
        }
        if self.geometric.iter().any(|&l| self.link_hits(l).is_some()) {
            return false;
        }
        if self
            .pairs
            .iter()
            .any(|&(a, b)| links_touch(&self.model, &self.poses, a, b))
        {
            return false;
        }
        for a in &self.attached {
            let pose = to_pose(&(self.poses[a.link] * a.offset));
            if self.obstacles.intersects(a.shape.as_ref(), &pose) {
                return false;
            }
            if self.geometric.iter().any(|&l| self.attached_touches_link(a, l)) {
                return false;
            }
        }
        true
    }

    fn checks(&self) -> u64 {
        self.checks
    }
}
