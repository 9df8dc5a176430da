//! Clearance certificates for pairs of links whose relative pose depends on one or two joints
//! (a Panda's link 5 and its flange, a Fetch's torso and upper shoulder): the joints' range is
//! cut into cells, and a cell is *certified clear* when the exact distance between the two
//! links at the cell's centre exceeds how far any point of one link can move relative to the
//! other within the cell. A self-collision check that lands in a certified cell needs no
//! geometry at all.
//!
//! Cells are certified lazily, on the first query that lands in them, and the verdicts are
//! shared by every user of the model (lock-free atomics), so a planner pays one closest-points
//! query per visited cell, once per process; the query only looks as far as the cell's level
//! needs, so part pairs farther apart are skipped.
//!
//! The displacement bound: rotating joint `J` by `Δ` moves a point `p` by at most
//! `|Δ|·|p − o|` for any point `o` on `J`'s axis; translating a prismatic joint by `Δ` moves it
//! by `|Δ|`. For joints `J1` (nearer link `a`) and `J2` (nearer `b`), `|p − o2|` does not
//! depend on either joint and `|p − o1| ≤ |p − o2| + |o2 − o1|`, where `|o2 − o1|` is fixed.

use std::sync::atomic::{AtomicU32, Ordering};

use nalgebra::{Isometry3, Point3};
use parry3d::query::ClosestPoints;

use crate::convert::to_pose;
use crate::model::{JointKind, RobotModel};

/// Largest movement (m) one joint's half cell may cause; sets the cell count.
const CELL_MOTION: f64 = 0.001;
/// Most cells along one joint.
const MAX_CELLS: usize = 1024;
/// Extra clearance (m) a certificate demands beyond the motion bound: covers f32 rounding and
/// the distance query.
const SLACK: f64 = 0.0005;

/// A cell whose centre distance is not computed yet (a NaN pattern no distance produces).
const UNKNOWN: u32 = u32::MAX;

/// One joint of the path between the two links.
#[derive(Clone, Debug)]
struct Axis {
    /// Configuration variable it reads.
    var: usize,
    lower: f64,
    /// Joint range (upper − lower).
    range: f64,
    /// Cells at the coarsest level (level `k` has `base << k`).
    base: usize,
    /// Largest motion of a point of the far link per unit of this joint.
    reach: f64,
}

/// Levels of the cell hierarchy: each halves the cells of the one before along every joint.
/// A query descends from the coarsest level until a cell certifies it, so configurations far
/// from contact cost one coarse certificate, and only those near contact need fine cells.
const LEVELS: usize = 6;

/// A lazily filled grid of clearance certificates for one pair of links. Obtain one with
/// [`RobotModel::pair_table`].
///
/// ```
/// use hearth_kinematics::RobotModel;
/// let panda = RobotModel::builtin("panda").unwrap();
/// let (a, b) = (panda.link_index("panda_link5").unwrap(), panda.link_index("panda_link7").unwrap());
/// let table = panda.pair_table(a, b).expect("two revolute joints apart");
/// let mut q = panda.neutral_configuration();
/// q[5] = 1.8; // joint 6 bent well away from the folded pose
/// assert!(table.certainly_clear(&panda, &q));
/// ```
#[derive(Debug)]
pub struct PairTable {
    /// The ancestor link and the descendant.
    a: usize,
    b: usize,
    axes: Vec<Axis>,
    /// Per level, the exact distance between the links at each cell's centre, or a lower
    /// bound on it above the level's largest motion bound (f32 bits, row-major over `axes`;
    /// [`UNKNOWN`] until first needed).
    levels: Vec<Vec<AtomicU32>>,
}

impl PairTable {
    /// A table for links `a` and `b` when one is an ancestor of the other through fixed joints
    /// and one or two revolute or prismatic joints with finite limits that mimic nothing (a
    /// prismatic joint only as the joint nearer the ancestor); `None` otherwise.
    pub(crate) fn build(model: &RobotModel, a: usize, b: usize) -> Option<Self> {
        let (a, b, path) = path_between(model, a, b).or_else(|| path_between(model, b, a))?;
        model.link_shape(a)?;
        model.link_shape(b)?;
        let movable: Vec<usize> = path
            .iter()
            .copied()
            .filter(|&j| model.joints()[j].kind != JointKind::Fixed)
            .collect();
        if movable.is_empty() || movable.len() > 2 {
            return None;
        }
        for &j in &movable {
            let joint = &model.joints()[j];
            let finite = joint.limits.lower.is_finite() && joint.limits.upper.is_finite();
            if joint.mimic.is_some() || joint.variable.is_none() || !finite || joint.kind == JointKind::Continuous {
                return None;
            }
        }
        if movable.len() == 2 && model.joints()[movable[1]].kind == JointKind::Prismatic {
            return None;
        }
        // Geometry at the lower limits, in `a`'s frame: joint origins (on their axes) and
        // the far link's covering balls.
        let mut q = model.neutral_configuration();
        for &j in &movable {
            let joint = &model.joints()[j];
            q[joint.variable?] = joint.limits.lower;
        }
        let poses = relative_poses(model, a, &q)?;
        let origin_of: Vec<Point3<f64>> = movable
            .iter()
            .map(|&j| {
                let joint = &model.joints()[j];
                Point3::from((poses[joint.parent] * joint.origin).translation.vector)
            })
            .collect();
        let pose = poses[b];
        let far: Vec<(Point3<f64>, f64)> = model
            .link_spheres(b)
            .iter()
            .map(|s| (pose * s.center, s.radius))
            .collect();
        if far.is_empty() {
            return None;
        }
        let reach_from = |o: &Point3<f64>| far.iter().map(|(c, r)| (c - o).norm() + r).fold(0.0, f64::max);
        let mut reach = vec![0.0; movable.len()];
        let last = movable.len() - 1;
        reach[last] = match model.joints()[movable[last]].kind {
            JointKind::Prismatic => 1.0,
            _ => reach_from(&origin_of[last]),
        };
        if last == 1 {
            reach[0] = match model.joints()[movable[0]].kind {
                JointKind::Prismatic => 1.0,
                _ => reach[1] + (origin_of[1] - origin_of[0]).norm(),
            };
        }
        let axes: Vec<Axis> = movable
            .iter()
            .zip(reach)
            .map(|(&j, reach)| {
                let l = &model.joints()[j].limits;
                let range = (l.upper - l.lower).max(0.0);
                let cells = ((range * reach / (2.0 * CELL_MOTION)).ceil() as usize).clamp(1, MAX_CELLS);
                Axis {
                    var: model.joints()[j].variable.unwrap_or(0),
                    lower: l.lower,
                    range,
                    base: cells.div_ceil(1 << (LEVELS - 1)),
                    reach,
                }
            })
            .collect();
        let levels = (0..LEVELS)
            .map(|k| {
                let n: usize = axes.iter().map(|a| a.base << k).product();
                (0..n).map(|_| AtomicU32::new(UNKNOWN)).collect()
            })
            .collect();
        Some(Self { a, b, axes, levels })
    }

    /// How many cells, over all levels, hold a certificate computed so far (cells are filled on
    /// first use, or ahead of time by a warm-up such as the planning crate's
    /// `RobotValidity::warm_pair_tables`).
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let (a, b) = (panda.link_index("panda_link5").unwrap(), panda.link_index("panda_link7").unwrap());
    /// let table = panda.pair_table(a, b).unwrap();
    /// assert_eq!(table.filled_cells(), 0);
    /// let mut q = panda.neutral_configuration();
    /// q[5] = 1.8;
    /// table.certainly_clear(&panda, &q);
    /// assert!(table.filled_cells() >= 1);
    /// ```
    pub fn filled_cells(&self) -> usize {
        self.levels
            .iter()
            .flatten()
            .filter(|c| c.load(Ordering::Relaxed) != UNKNOWN)
            .count()
    }

    /// Whether the two links provably do not touch in configuration `q_full` (a full
    /// configuration of `model`, the one this table was built for). `false` means "not
    /// certified", not "touching".
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, links_touch};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let (a, b) = (panda.link_index("panda_link5").unwrap(), panda.link_index("panda_link7").unwrap());
    /// let table = panda.pair_table(a, b).unwrap();
    /// let mut q = panda.neutral_configuration();
    /// q[5] = 1.8;
    /// let mut poses = panda.pose_buffer();
    /// panda.fk(&q, &mut poses).unwrap();
    /// assert!(table.certainly_clear(&panda, &q) && !links_touch(&panda, &poses, a, b));
    /// q[5] = 100.0; // outside the joint's range: never certified
    /// assert!(!table.certainly_clear(&panda, &q));
    /// ```
    pub fn certainly_clear(&self, model: &RobotModel, q_full: &[f64]) -> bool {
        let Some(t) = self.unit(q_full) else { return false };
        for (k, cells) in self.levels.iter().enumerate() {
            let (index, at, moved) = self.cell(&t, k);
            let Some(cell) = cells.get(index) else { return false };
            let mut bits = cell.load(Ordering::Relaxed);
            if bits == UNKNOWN {
                bits = self.clearance_at(model, k, &at).to_bits();
                cell.store(bits, Ordering::Relaxed);
            }
            if f64::from(f32::from_bits(bits)) > moved {
                return true;
            }
        }
        false
    }

    /// Where `q_full` lies along each joint's range, from 0 to 1; `None` outside the ranges
    /// (or when `q_full` is too short).
    fn unit(&self, q_full: &[f64]) -> Option<[f64; 2]> {
        let mut t = [0.0f64; 2];
        for (t, ax) in t.iter_mut().zip(&self.axes) {
            *t = (q_full.get(ax.var)? - ax.lower) / ax.range;
            if !(*t >= 0.0 && *t <= 1.0) {
                return None;
            }
        }
        Some(t)
    }

    /// The cell of `level` holding the configuration at `t` ([`PairTable::unit`]): its index,
    /// its position along each joint, and how far the far link can have moved from its pose at
    /// the cell's centre (plus the slack).
    fn cell(&self, t: &[f64; 2], level: usize) -> (usize, [usize; 2], f64) {
        let mut index = 0usize;
        let mut at = [0usize; 2];
        let mut moved = SLACK;
        for ((at, t), ax) in at.iter_mut().zip(t).zip(&self.axes) {
            let n = ax.base << level;
            *at = ((t * n as f64) as usize).min(n - 1);
            index = index * n + *at;
            moved += ((t * n as f64) - (*at as f64 + 0.5)).abs() * ax.range / n as f64 * ax.reach;
        }
        (index, at, moved)
    }

    /// A lower bound on the distance between the two links in configuration `q_full`, from
    /// the certificates filled so far (the best over the levels of the cell's clearance less
    /// how far the links can have moved from its centre), or `None` when no filled cell holds
    /// `q_full`. Fills nothing. With [`PairTable::reach`] it bounds how far the joints can
    /// move before the links could touch.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let (a, b) = (panda.link_index("panda_link5").unwrap(), panda.link_index("panda_link7").unwrap());
    /// let table = panda.pair_table(a, b).unwrap();
    /// let mut q = panda.neutral_configuration();
    /// q[5] = 1.8;
    /// assert_eq!(table.clearance_bound(&q), None); // nothing filled yet
    /// assert!(table.certainly_clear(&panda, &q));
    /// assert!(table.clearance_bound(&q).unwrap() > 0.0);
    /// ```
    pub fn clearance_bound(&self, q_full: &[f64]) -> Option<f64> {
        let t = self.unit(q_full)?;
        let mut best: Option<f64> = None;
        for (k, cells) in self.levels.iter().enumerate() {
            let (index, _, moved) = self.cell(&t, k);
            let bits = cells.get(index)?.load(Ordering::Relaxed);
            if bits != UNKNOWN {
                let bound = f64::from(f32::from_bits(bits)) - moved;
                best = Some(best.map_or(bound, |b| b.max(bound)));
            }
        }
        best
    }

    /// The joints the two links' relative pose depends on, as (configuration variable, the
    /// largest motion of a point of the far link per unit of that joint).
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let (a, b) = (panda.link_index("panda_link5").unwrap(), panda.link_index("panda_link7").unwrap());
    /// let vars: Vec<usize> = panda.pair_table(a, b).unwrap().reach().map(|(v, _)| v).collect();
    /// assert_eq!(vars, [5, 6]); // joints 6 and 7
    /// ```
    pub fn reach(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.axes.iter().map(|ax| (ax.var, ax.reach))
    }

    /// The largest motion bound a query in a cell of `level` can have: a clearance above it
    /// certifies the whole cell.
    fn cell_motion(&self, level: usize) -> f64 {
        SLACK
            + self
                .axes
                .iter()
                .map(|ax| 0.5 * ax.range / (ax.base << level) as f64 * ax.reach)
                .sum::<f64>()
    }

    /// Distance between the links at the centre of the cell `at` of level `level`, or a
    /// value just above the level's largest motion bound (and below the distance) when the
    /// links are farther apart than that: parry then skips the part pairs that cannot be that
    /// close. 0 when parry cannot compute it.
    fn clearance_at(&self, model: &RobotModel, level: usize, at: &[usize; 2]) -> f32 {
        let mut q = model.neutral_configuration();
        for (ax, &k) in self.axes.iter().zip(at) {
            let step = ax.range / (ax.base << level) as f64;
            q[ax.var] = ax.lower + (k as f64 + 0.5) * step;
        }
        let Some(poses) = relative_poses(model, self.a, &q) else {
            return 0.0;
        };
        let pose = poses[self.b];
        let (Some(sa), Some(sb)) = (model.link_shape(self.a), model.link_shape(self.b)) else {
            return 0.0;
        };
        let pa = to_pose(&sa.origin);
        let pb = to_pose(&(pose * sb.origin));
        let enough = (self.cell_motion(level) * 1.01 + 1e-5) as f32;
        match parry3d::query::closest_points(&pa, sa.shape.as_ref(), &pb, sb.shape.as_ref(), enough) {
            Ok(ClosestPoints::Disjoint) => enough,
            Ok(ClosestPoints::WithinMargin(p1, p2)) => (p2 - p1).length().min(enough),
            Ok(ClosestPoints::Intersecting) | Err(_) => 0.0,
        }
    }
}

/// Every link's pose in link `a`'s frame for the full configuration `q`.
fn relative_poses(model: &RobotModel, a: usize, q: &[f64]) -> Option<Vec<Isometry3<f64>>> {
    let mut poses = model.pose_buffer();
    model.fk(q, &mut poses).ok()?;
    let to_a = poses[a].inverse();
    Some(poses.iter().map(|p| to_a * p).collect())
}

/// The joints from ancestor `a` down to `b`, if `a` is an ancestor of `b`.
fn path_between(model: &RobotModel, a: usize, b: usize) -> Option<(usize, usize, Vec<usize>)> {
    let mut path = Vec::new();
    let mut l = b;
    while l != a {
        let j = model.links().get(l)?.parent_joint?;
        path.push(j);
        l = model.joints()[j].parent;
    }
    path.reverse();
    Some((a, b, path))
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use crate::{RobotModel, links_touch};

    /// Wherever a table certifies a configuration, the exact test agrees that the links are
    /// apart; and certificates cover most configurations.
    #[test]
    fn certified_configurations_are_clear() {
        for (robot, a, b) in [
            ("panda", "panda_link5", "panda_link7"),
            ("panda", "panda_link5", "panda_hand"),
            ("fetch", "torso_lift_link", "shoulder_lift_link"),
        ] {
            let m = RobotModel::builtin(robot).unwrap();
            let (a, b) = (m.link_index(a).unwrap(), m.link_index(b).unwrap());
            let table = m.pair_table(a, b).expect("a table");
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
            let mut poses = m.pose_buffer();
            let (mut certified, mut touching) = (0, 0);
            for _ in 0..3000 {
                let mut q = m.neutral_configuration();
                m.random_configuration(&mut rng, &mut q);
                m.fk(&q, &mut poses).unwrap();
                let touch = links_touch(&m, &poses, a, b);
                touching += usize::from(touch);
                if table.certainly_clear(&m, &q) {
                    certified += 1;
                    assert!(!touch, "{robot}: certified clear but touching at {q:?}");
                }
            }
            assert!(certified > 3000 / 2, "{robot}: only {certified} of 3000 certified");
            assert!(
                touching > 0 || robot == "fetch",
                "{robot}: no touching sample, test too weak"
            );
        }
    }

    #[test]
    fn pairs_far_apart_in_the_tree_have_no_table() {
        let m = RobotModel::builtin("panda").unwrap();
        let (a, b) = (
            m.link_index("panda_link0").unwrap(),
            m.link_index("panda_hand").unwrap(),
        );
        assert!(m.pair_table(a, b).is_none());
    }
}
