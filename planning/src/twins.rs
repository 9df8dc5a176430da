//! Links whose collision geometry coincides with another link's, so that checking both is
//! checking the same thing twice.
//!
//! The Fetch's `bellows_link` hangs from the torso lift on a prismatic joint that no planned
//! chain moves, and `bellows_link2` hangs from it on a fixed joint with the same box: at the
//! joint's zero, where the MotionBenchMaker problems keep it, the two boxes are one. A link is
//! a twin of another when both have the same collision elements (shapes and origins) and sit at
//! the same pose for the current reference, with the same last chain joint above them, so that
//! no configuration of the chain can part them. Then a twin touches an obstacle exactly when
//! its representative (the twin with the lowest number) does, and a pair with a twin touches
//! exactly when the pair of representatives does: [`RobotValidity`](crate::RobotValidity)
//! tests the representatives alone, and a pair with a twin only when the representatives' pair
//! is not checked itself.

use hearth_kinematics::{Chain, Collision, Geometry, RobotModel};
use nalgebra::Isometry3;

/// How far apart (m, rad) two poses may be and still be one.
const SAME_POSE: f64 = 1e-9;

/// Which links and pairs duplicate others for the current reference.
#[derive(Clone, Debug)]
pub(crate) struct Twins {
    /// Per model link: the last joint above it that the chain drives (`None` for none).
    last_driven: Vec<Option<usize>>,
    /// Per model link: its representative (itself when it has no twin of a lower number).
    representative: Vec<usize>,
    /// Per geometric link number: whether it is a twin of a link of a lower number.
    link: Vec<bool>,
    /// Per checked pair: whether the pair of its links' representatives is checked instead.
    pair: Vec<bool>,
}

impl Twins {
    /// No twins yet (call [`Twins::update`] once poses are known): `links` geometric links and
    /// `pairs` checked pairs of `model` for `chain`.
    pub(crate) fn new(model: &RobotModel, chain: &Chain, links: usize, pairs: usize) -> Self {
        Self {
            last_driven: last_driven_joints(model, chain),
            representative: (0..model.links().len()).collect(),
            link: vec![false; links],
            pair: vec![false; pairs],
        }
    }

    /// Finds the twins among `geometric` (model link numbers) at `poses` (every link's pose
    /// for the current reference), and the checked `pairs` they make redundant. Allocates
    /// nothing.
    pub(crate) fn update(
        &mut self,
        model: &RobotModel,
        geometric: &[usize],
        pairs: &[(usize, usize)],
        poses: &[Isometry3<f64>],
    ) {
        let links = model.links();
        for (i, &b) in geometric.iter().enumerate() {
            let twin = geometric[..i].iter().copied().find(|&a| {
                self.representative[a] == a
                    && self.last_driven[a] == self.last_driven[b]
                    && same_elements(&links[a].collisions, &poses[a], &links[b].collisions, &poses[b])
            });
            self.representative[b] = twin.unwrap_or(b);
            self.link[i] = twin.is_some();
        }
        let checked = |a: usize, b: usize| pairs.iter().any(|&(x, y)| (x, y) == (a, b) || (x, y) == (b, a));
        for (p, &(a, b)) in pairs.iter().enumerate() {
            let (ra, rb) = (self.representative[a], self.representative[b]);
            self.pair[p] = (ra, rb) != (a, b) && ra != rb && checked(ra, rb);
        }
    }

    /// Which links move when the chain's joints move: those below a joint the chain drives,
    /// itself or through a mimic.
    pub(crate) fn moving_links(&self) -> Vec<bool> {
        self.last_driven.iter().map(Option::is_some).collect()
    }

    /// Whether geometric link `i` is a twin of a link of a lower number.
    #[inline]
    pub(crate) fn link(&self, i: usize) -> bool {
        self.link[i]
    }

    /// Whether checked pair `p` is made redundant by its representatives' pair.
    #[inline]
    pub(crate) fn pair(&self, p: usize) -> bool {
        self.pair[p]
    }
}

/// Per link of `model`: the last joint on its way from the root that `chain` drives (itself
/// or through a mimic), `None` for a link that the chain does not move. Two links below the
/// same such joint keep their relative pose whatever the chain's configuration.
fn last_driven_joints(model: &RobotModel, chain: &Chain) -> Vec<Option<usize>> {
    let vars = chain.variables();
    let joints = model.joints();
    let variable = |j: usize| joints[j].variable.is_some_and(|v| vars.contains(&v));
    let driven = |j: usize| variable(j) || joints[j].mimic.as_ref().is_some_and(|m| variable(m.joint));
    (0..model.links().len())
        .map(|l| model.joints_to(l).into_iter().rev().find(|&j| driven(j)))
        .collect()
}

/// Whether two links' collision elements, at link poses `pa` and `pb`, are the same shapes at
/// the same places, element by element.
fn same_elements(a: &[Collision], pa: &Isometry3<f64>, b: &[Collision], pb: &Isometry3<f64>) -> bool {
    !a.is_empty()
        && a.len() == b.len()
        && a.iter().zip(b).all(|(ca, cb)| {
            let (wa, wb) = (pa * ca.origin, pb * cb.origin);
            same_geometry(&ca.geometry, &cb.geometry)
                && (wa.translation.vector - wb.translation.vector).norm() <= SAME_POSE
                && wa.rotation.angle_to(&wb.rotation) <= SAME_POSE
        })
}

/// Whether two described shapes are equal (meshes: the same file at the same scale).
fn same_geometry(a: &Geometry, b: &Geometry) -> bool {
    match (a, b) {
        (Geometry::Box { half_extents: x }, Geometry::Box { half_extents: y }) => x == y,
        (Geometry::Cylinder { radius: r, length: l }, Geometry::Cylinder { radius: s, length: m })
        | (Geometry::Capsule { radius: r, length: l }, Geometry::Capsule { radius: s, length: m }) => r == s && l == m,
        (Geometry::Sphere { radius: r }, Geometry::Sphere { radius: s }) => r == s,
        (Geometry::Mesh { uri: u, scale: x, .. }, Geometry::Mesh { uri: v, scale: y, .. }) => u == v && x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hearth_kinematics::SelfCollisionMatrix;

    fn fetch_twins(bellows: f64) -> (RobotModel, Twins, Vec<usize>, Vec<(usize, usize)>) {
        let fetch = RobotModel::builtin("fetch").unwrap();
        let chain = Chain::named(&fetch, "arm_with_torso").unwrap();
        let geometric: Vec<usize> = (0..fetch.links().len())
            .filter(|&l| fetch.link_shape(l).is_some())
            .collect();
        let pairs = SelfCollisionMatrix::adjacent_only(&fetch).checked_geometric_pairs(&fetch);
        let mut q = fetch.neutral_configuration();
        let joint = fetch.joints().iter().find(|j| j.name == "bellows_joint").unwrap();
        q[joint.variable.unwrap()] = bellows;
        let mut poses = fetch.pose_buffer();
        fetch.fk(&q, &mut poses).unwrap();
        let mut twins = Twins::new(&fetch, &chain, geometric.len(), pairs.len());
        twins.update(&fetch, &geometric, &pairs, &poses);
        (fetch, twins, geometric, pairs)
    }

    /// At the bellows joint's zero the two bellows boxes are one: the second is the twin, and
    /// each checked pair with it whose counterpart with the first is checked is redundant.
    /// Lowered by 5 cm they are two links again.
    #[test]
    fn the_fetchs_bellows_boxes_are_twins_only_where_they_coincide() {
        let (fetch, twins, geometric, pairs) = fetch_twins(0.0);
        let bellows = fetch.link_index("bellows_link").unwrap();
        let bellows2 = fetch.link_index("bellows_link2").unwrap();
        let twin_links: Vec<usize> = (0..geometric.len())
            .filter(|&i| twins.link(i))
            .map(|i| geometric[i])
            .collect();
        assert_eq!(twin_links, [bellows.max(bellows2)]);
        let (first, second) = (bellows.min(bellows2), bellows.max(bellows2));
        let has = |a: usize, b: usize| pairs.iter().any(|&p| p == (a, b) || p == (b, a));
        let mut redundant = 0;
        for (p, &(a, b)) in pairs.iter().enumerate() {
            let other = if a == second {
                b
            } else if b == second {
                a
            } else {
                usize::MAX
            };
            let expected = other != usize::MAX && other != first && has(other, first);
            assert_eq!(
                twins.pair(p),
                expected,
                "{} – {}",
                fetch.links()[a].name,
                fetch.links()[b].name
            );
            redundant += usize::from(expected);
        }
        assert!(redundant > 0);
        let (_, apart, ..) = fetch_twins(0.05);
        assert!((0..geometric.len()).all(|i| !apart.link(i)));
        assert!((0..pairs.len()).all(|p| !apart.pair(p)));
    }

    /// Two equal boxes in different places, or different boxes in one place, are no twins.
    #[test]
    fn shapes_and_places_must_both_agree() {
        let fetch = RobotModel::builtin("fetch").unwrap();
        let bellows = &fetch.links()[fetch.link_index("bellows_link").unwrap()].collisions;
        let estop = &fetch.links()[fetch.link_index("estop_link").unwrap()].collisions;
        let here = Isometry3::identity();
        let there = Isometry3::translation(0.0, 0.0, 1e-6);
        assert!(same_elements(bellows, &here, bellows, &here));
        assert!(!same_elements(bellows, &here, bellows, &there));
        assert!(!same_elements(bellows, &here, estop, &here));
        assert!(!same_elements(&[], &here, &[], &here));
    }
}
