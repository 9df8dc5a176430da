//! How far a robot's links can move when its chain's joints move: the bound behind the free
//! region of a checked state ([`crate::validity::RobotValidity`]'s
//! [`first_invalid_along`](crate::validity::StateValidator::first_invalid_along)).
//!
//! Turning a revolute joint by `Δ` moves a point `p` of a link below it by at most
//! `|Δ|·|p − o|`, with `o` the joint's origin (on its axis); sliding a prismatic joint by `Δ`
//! moves it by `|Δ|`. Summed over the joints along a straight joint-space motion, a link's
//! point moves at most `Σⱼ Rⱼ·|Δⱼ|`, where `Rⱼ` bounds `|p − oⱼ|` over every configuration:
//! the lengths of the fixed offsets from joint `j` down to the link, plus the travel of any
//! prismatic joint between, plus the point's distance from the link's origin. Joints that two
//! links share turn both rigidly, so the distance between a point of each changes only with the
//! joints that one of them has and the other has not.
//!
//! Each link, pair and pair table keeps its own row of `Rⱼ`. One weighted distance
//! `Σⱼ wⱼ·|Δⱼ|` (with `wⱼ` the largest `Rⱼ` of any row) bounds them all up to each row's scale:
//! a checked state uses it to leave out the constraints that no state of its stretch can break.

use std::collections::HashMap;

use hearth_kinematics::{Chain, JointKind, RobotModel};

/// Displacement bounds per chain joint, one row per geometric link (its motion in the world)
/// and one per checked self-collision pair (the change of distance between its two links), and
/// the weights of a distance in which they are all at most their scale.
#[derive(Clone, Debug)]
pub(crate) struct Reach {
    dof: usize,
    /// Rows of `dof` bounds: the geometric links (the order of `RobotValidity::geometric`),
    /// then the checked pairs, then the pairs' clearance tables (zero rows for pairs without
    /// one).
    rows: Vec<f64>,
    links: usize,
    pairs: usize,
    /// Per chain column: the largest bound of any row (0 when the joint moves nothing that
    /// is checked).
    pub(crate) weights: Vec<f64>,
    /// Per row: the largest ratio of a bound to its joint's weight (0 for a row of zeros,
    /// infinite when a bound is).
    scale: Vec<f64>,
}

/// One row of [`Reach`]: a geometric link, a checked pair, or a pair's clearance table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Row {
    Link(usize),
    Pair(usize),
    Table(usize),
}

impl Reach {
    /// `extent(l)`: the largest distance from link `l`'s origin of any point whose motion the
    /// bounds must cover (the centres of its covering and bounding balls). `tables`: per
    /// checked pair, the (model variable, bound) of its clearance table's joints.
    pub(crate) fn new(
        model: &RobotModel,
        chain: &Chain,
        geometric: &[usize],
        pairs: &[(usize, usize)],
        tables: &[Vec<(usize, f64)>],
        extent: impl Fn(usize) -> f64,
    ) -> Self {
        let dof = chain.dof();
        let column: HashMap<usize, usize> = chain.variables().iter().enumerate().map(|(c, &v)| (v, c)).collect();
        let joints = model.joints();
        // The chain column that drives joint `j`, and by how much.
        let driven = |j: usize| -> Option<(usize, f64)> {
            let joint = &joints[j];
            if !joint.kind.is_movable() {
                return None;
            }
            match (joint.variable, joint.mimic) {
                (Some(v), _) => column.get(&v).map(|&c| (c, 1.0)),
                (None, Some(m)) => joints[m.joint]
                    .variable
                    .and_then(|v| column.get(&v))
                    .map(|&c| (c, m.multiplier.abs())),
                _ => None,
            }
        };
        let travel = |j: usize| {
            let l = &joints[j].limits;
            if joints[j].kind == JointKind::Prismatic {
                l.lower.abs().max(l.upper.abs())
            } else {
                0.0
            }
        };
        // Per link: its joints from the root, and each one's bound.
        let bounds = |l: usize| -> Vec<(usize, f64)> {
            let path = model.joints_to(l);
            let mut below = extent(l);
            let mut out = Vec::new();
            for &j in path.iter().rev() {
                let r = if joints[j].kind == JointKind::Prismatic {
                    1.0
                } else {
                    below
                };
                out.push((j, r));
                below += joints[j].origin.translation.vector.norm() + travel(j);
            }
            out
        };
        let add = |into: &mut [f64], bounds: &[(usize, f64)], skip: &[(usize, f64)]| {
            for &(j, r) in bounds {
                if skip.iter().any(|&(k, _)| k == j) {
                    continue;
                }
                if let Some((c, f)) = driven(j) {
                    into[c] += f * r;
                }
            }
        };
        let mut per_link: HashMap<usize, Vec<(usize, f64)>> = HashMap::new();
        let mut of = |l: usize| per_link.entry(l).or_insert_with(|| bounds(l)).clone();
        let mut rows = vec![0.0; (geometric.len() + 2 * pairs.len()) * dof];
        let mut chunks = rows.chunks_exact_mut(dof.max(1));
        for (&l, row) in geometric.iter().zip(&mut chunks) {
            add(row, &of(l), &[]);
        }
        for (&(a, b), row) in pairs.iter().zip(&mut chunks) {
            let (ba, bb) = (of(a), of(b));
            add(row, &ba, &bb);
            add(row, &bb, &ba);
        }
        for (table, row) in tables.iter().zip(&mut chunks) {
            for &(var, r) in table {
                if let Some(&c) = column.get(&var) {
                    row[c] += r;
                }
            }
        }
        let mut weights = vec![0.0f64; dof];
        for row in rows.chunks_exact(dof.max(1)) {
            for (w, &r) in weights.iter_mut().zip(row) {
                *w = w.max(r);
            }
        }
        let scale = rows
            .chunks_exact(dof.max(1))
            .map(|row| {
                row.iter()
                    .zip(&weights)
                    .map(|(&r, &w)| if r > 0.0 { r / w } else { 0.0 })
                    .fold(0.0f64, |a, b| if b.is_nan() { f64::INFINITY } else { a.max(b) })
            })
            .collect();
        Self {
            dof,
            rows,
            links: geometric.len(),
            pairs: pairs.len(),
            weights,
            scale,
        }
    }

    fn index(&self, row: Row) -> usize {
        match row {
            Row::Link(i) => i,
            Row::Pair(p) => self.links + p,
            Row::Table(p) => self.links + self.pairs + p,
        }
    }

    /// The row's largest ratio of a bound to its joint's weight: a clearance `c` certifies
    /// every state within `c / scale` in [`Reach::distance`].
    pub(crate) fn scale(&self, row: Row) -> f64 {
        self.scale[self.index(row)]
    }

    /// How far the row's points can move (or its pair's distance change) along the straight
    /// motion that changes the chain's joints by `delta` (absolute values).
    #[inline]
    pub(crate) fn motion(&self, row: Row, delta: &[f64]) -> f64 {
        let i = self.index(row) * self.dof;
        self.rows[i..i + self.dof].iter().zip(delta).map(|(r, d)| r * d).sum()
    }

    /// The weighted distance `Σⱼ wⱼ·|aⱼ − bⱼ|` between two chain configurations.
    #[inline]
    pub(crate) fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.weights
            .iter()
            .zip(a.iter().zip(b))
            .map(|(w, (x, y))| w * (x - y).abs())
            .sum()
    }
}
