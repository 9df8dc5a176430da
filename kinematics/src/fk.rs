//! Forward kinematics: a flat program of joint transforms evaluated in link order.
//!
//! The model's links are sorted parents-first, so one pass over [`FkOp`]s fills every link pose.
//! Each op stores its joint origin and axis by value; evaluating it is one `sin_cos`, two
//! quaternion products and one rotated vector. A subset of the links
//! ([`RobotModel::fk_update`]) computes its revolute joints' sines and cosines four at a time
//! before it composes the ops. Nothing allocates.

use std::ops::{Add, Mul, Sub};

use nalgebra::{Isometry3, Quaternion, Translation3, Unit, UnitQuaternion, Vector3};
use wide::f64x4;

use crate::error::Result;
use crate::model::RobotModel;

/// A revolute axis: one of the frame axes (the common case, with a cheaper product) or
/// any unit vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Axis {
    X,
    Y,
    Z,
    General,
}

impl Axis {
    pub(crate) fn classify(axis: &Unit<Vector3<f64>>) -> (Axis, f64) {
        let a = axis.into_inner();
        for (kind, i) in [(Axis::X, 0), (Axis::Y, 1), (Axis::Z, 2)] {
            let others = (0..3).filter(|&k| k != i).all(|k| a[k] == 0.0);
            if others && a[i].abs() == 1.0 {
                return (kind, a[i]);
            }
        }
        (Axis::General, 1.0)
    }
}

/// How an op moves its child.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Motion {
    Fixed,
    /// Rotation about a frame axis; `multiplier` already carries the axis sign. `plain`: the
    /// joint's origin does not rotate (its quaternion is exactly the identity), as for most
    /// of the Fetch's joints, which [`FkOp::after`] composes with fewer products.
    RevoluteAxis {
        axis: Axis,
        var: u32,
        multiplier: f64,
        offset: f64,
        plain: bool,
    },
    Revolute {
        axis: Unit<Vector3<f64>>,
        var: u32,
        multiplier: f64,
        offset: f64,
    },
    Prismatic {
        axis: Unit<Vector3<f64>>,
        var: u32,
        multiplier: f64,
        offset: f64,
    },
}

/// One step of the program: `pose[child] = pose[parent] · origin · motion(q)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FkOp {
    pub(crate) parent: u32,
    pub(crate) child: u32,
    pub(crate) origin: Isometry3<f64>,
    pub(crate) motion: Motion,
}

impl FkOp {
    /// The child's pose relative to its parent link for configuration `q`.
    #[inline(always)]
    pub(crate) fn local(&self, q: &[f64]) -> Isometry3<f64> {
        self.local_at::<f64>(self.var().map_or(0.0, |v| q[v]), sin_cos)
            .to_isometry()
    }

    /// The child's pose for configuration value `v`, composed after its parent's pose
    /// `parent`: `parent.then(&self.local_at(v, sin_cos))`, bit for bit (up to the sign of a
    /// zero). A plain rotation about a frame axis keeps only the nonzero products of that
    /// composition, in the same order: the local rotation `c + s·e` has two nonzero
    /// coordinates, so 8 products replace the 8 of `local_at` and the 16 of the quaternion
    /// product.
    #[inline(always)]
    fn after<L: Lanes>(&self, parent: &PoseLanes<L>, v: L, sin_cos: impl FnOnce(L) -> (L, L)) -> PoseLanes<L> {
        let Motion::RevoluteAxis {
            axis,
            multiplier,
            offset,
            plain: true,
            ..
        } = self.motion
        else {
            return parent.then(&self.local_at(v, sin_cos));
        };
        let half = L::splat(0.5) * (L::splat(multiplier) * v + L::splat(offset));
        let (s, c) = sin_cos(half);
        let o = &self.origin.translation.vector;
        let r = rotate(&parent.q, &[L::splat(o.x), L::splat(o.y), L::splat(o.z)]);
        PoseLanes {
            q: turn_about(&parent.q, axis, s, c),
            t: [parent.t[0] + r[0], parent.t[1] + r[1], parent.t[2] + r[2]],
        }
    }

    /// The configuration variable the joint reads (`None` for a fixed joint).
    #[inline(always)]
    fn var(&self) -> Option<usize> {
        match self.motion {
            Motion::Fixed => None,
            Motion::RevoluteAxis { var, .. } | Motion::Revolute { var, .. } | Motion::Prismatic { var, .. } => {
                Some(var as usize)
            }
        }
    }

    /// The child's pose relative to its parent for joint value `v` (ignored by fixed joints),
    /// one lane per configuration. `sin_cos` evaluates the half angle of a revolute joint.
    #[inline(always)]
    fn local_at<L: Lanes>(&self, v: L, sin_cos: impl FnOnce(L) -> (L, L)) -> PoseLanes<L> {
        let origin = PoseLanes::<L>::splat(&self.origin);
        match self.motion {
            Motion::Fixed => origin,
            Motion::RevoluteAxis {
                axis,
                multiplier,
                offset,
                ..
            } => {
                let half = L::splat(0.5) * (L::splat(multiplier) * v + L::splat(offset));
                let (s, c) = sin_cos(half);
                PoseLanes {
                    q: turn_about(&origin.q, axis, s, c),
                    t: origin.t,
                }
            }
            Motion::Revolute {
                axis,
                multiplier,
                offset,
                ..
            } => {
                let half = L::splat(0.5) * (L::splat(multiplier) * v + L::splat(offset));
                let (s, c) = sin_cos(half);
                let rot = [c, L::splat(axis.x) * s, L::splat(axis.y) * s, L::splat(axis.z) * s];
                PoseLanes {
                    q: quat_mul(&origin.q, &rot),
                    t: origin.t,
                }
            }
            Motion::Prismatic {
                axis,
                multiplier,
                offset,
                ..
            } => {
                let d = L::splat(multiplier) * v + L::splat(offset);
                let moved = rotate(
                    &origin.q,
                    &[L::splat(axis.x) * d, L::splat(axis.y) * d, L::splat(axis.z) * d],
                );
                PoseLanes {
                    q: origin.q,
                    t: [origin.t[0] + moved[0], origin.t[1] + moved[1], origin.t[2] + moved[2]],
                }
            }
        }
    }
}

/// Arithmetic that forward kinematics needs, for one configuration (`f64`) or four at once
/// (`f64x4`). Both run the same operations in the same order, so a pose computed four at a
/// time equals, bit for bit, the pose computed alone.
pub(crate) trait Lanes: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    fn splat(v: f64) -> Self;
}

impl Lanes for f64 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
}

impl Lanes for f64x4 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        f64x4::splat(v)
    }
}

/// A rigid pose as a unit quaternion `q = [w, x, y, z]` and a translation `t`, per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PoseLanes<L> {
    q: [L; 4],
    t: [L; 3],
}

impl<L: Lanes> PoseLanes<L> {
    #[inline(always)]
    fn splat(p: &Isometry3<f64>) -> Self {
        let (q, t) = (p.rotation.quaternion(), &p.translation.vector);
        Self {
            q: [L::splat(q.w), L::splat(q.i), L::splat(q.j), L::splat(q.k)],
            t: [L::splat(t.x), L::splat(t.y), L::splat(t.z)],
        }
    }

    /// `self · other`.
    #[inline(always)]
    fn then(&self, other: &Self) -> Self {
        let r = rotate(&self.q, &other.t);
        Self {
            q: quat_mul(&self.q, &other.q),
            t: [self.t[0] + r[0], self.t[1] + r[1], self.t[2] + r[2]],
        }
    }
}

impl PoseLanes<f64> {
    #[inline(always)]
    fn to_isometry(self) -> Isometry3<f64> {
        let [w, x, y, z] = self.q;
        Isometry3::from_parts(
            Translation3::new(self.t[0], self.t[1], self.t[2]),
            UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z)),
        )
    }
}

impl PoseLanes<f64x4> {
    /// Lane `k`.
    #[inline(always)]
    fn lane(&self, k: usize) -> PoseLanes<f64> {
        PoseLanes {
            q: self.q.map(|v| v.as_array()[k]),
            t: self.t.map(|v| v.as_array()[k]),
        }
    }

    /// Lane `k` from `poses[k]`.
    #[inline(always)]
    fn gather(poses: [&Isometry3<f64>; 4]) -> Self {
        let q = poses.map(|p| p.rotation.quaternion());
        let t = poses.map(|p| p.translation.vector);
        Self {
            q: [
                f64x4::new(q.map(|q| q.w)),
                f64x4::new(q.map(|q| q.i)),
                f64x4::new(q.map(|q| q.j)),
                f64x4::new(q.map(|q| q.k)),
            ],
            t: [
                f64x4::new(t.map(|t| t.x)),
                f64x4::new(t.map(|t| t.y)),
                f64x4::new(t.map(|t| t.z)),
            ],
        }
    }
}

/// Hamilton product `a · b` of quaternions `[w, x, y, z]`.
#[inline(always)]
fn quat_mul<L: Lanes>(a: &[L; 4], b: &[L; 4]) -> [L; 4] {
    let [aw, ax, ay, az] = *a;
    let [bw, bx, by, bz] = *b;
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

/// `q · (c + s·e)`, `e` the unit quaternion of a frame axis (`Axis::General` is never
/// classified as one, and counts as z): 8 products instead of the 16 of [`quat_mul`], and
/// the same value, as the terms the 16 would add are exact zeros.
#[inline(always)]
fn turn_about<L: Lanes>(q: &[L; 4], axis: Axis, s: L, c: L) -> [L; 4] {
    let [w, x, y, z] = *q;
    match axis {
        Axis::X => [w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s],
        Axis::Y => [w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s],
        _ => [w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s],
    }
}

/// `v` rotated by the unit quaternion `q`: `v + w·t + u × t` with `t = 2 u × v`.
#[inline(always)]
fn rotate<L: Lanes>(q: &[L; 4], v: &[L; 3]) -> [L; 3] {
    let [w, x, y, z] = *q;
    let cross = |a: [L; 3], b: [L; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let u = [x, y, z];
    let two = L::splat(2.0);
    let c = cross(u, *v);
    let t = [c[0] * two, c[1] * two, c[2] * two];
    let ut = cross(u, t);
    [
        v[0] + w * t[0] + ut[0],
        v[1] + w * t[1] + ut[1],
        v[2] + w * t[2] + ut[2],
    ]
}

/// [`sin_cos`] of four values: the same reduction and polynomials per lane, and the quadrant
/// placed with lane masks (so the same bits), with libm for lanes outside its range.
#[inline(always)]
fn sin_cos4(x: f64x4) -> (f64x4, f64x4) {
    let xs = x.to_array();
    if xs.iter().any(|v| v.abs() >= 1e5 || v.is_nan()) {
        let sc = xs.map(sin_cos);
        return (f64x4::new(sc.map(|p| p.0)), f64x4::new(sc.map(|p| p.1)));
    }
    let (k, s, c) = sin_cos_reduced(x);
    quadrant4(k, s, c)
}

/// [`quadrant`] in four lanes: `k` mod 4 as a float (`k − 4·⌊k/4⌋`, exact for the quadrants
/// of |x| < 1e5), then a lane select for the swap and a sign-bit flip for each output.
#[inline(always)]
fn quadrant4(k: f64x4, s: f64x4, c: f64x4) -> (f64x4, f64x4) {
    let m = k - (k * f64x4::splat(0.25)).floor() * f64x4::splat(4.0);
    let (one, two, three) = (f64x4::splat(1.0), f64x4::splat(2.0), f64x4::splat(3.0));
    let swap = m.simd_eq(one) | m.simd_eq(three);
    let sign = f64x4::splat(-0.0);
    let flip_first = m.simd_ge(two) & sign;
    let flip_second = (m.simd_eq(one) | m.simd_eq(two)) & sign;
    (swap.select(c, s) ^ flip_first, swap.select(s, c) ^ flip_second)
}

/// The revolute joints of a subset's ops in evaluation order, four to a chunk, so that one
/// pass computes their sines and cosines four at a time before the ops are composed. A short
/// last chunk repeats its first variable with a zero angle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct TurnChunk {
    vars: [u32; 4],
    multiplier: [f64; 4],
    offset: [f64; 4],
}

/// Chunks of [`TurnChunk`] computed ahead; a subset with more revolute joints computes each
/// one as its op comes.
const TURN_CHUNKS: usize = 4;

/// Fills `turns` with the chunks of `ops`' revolute joints (it is cleared first).
fn fill_turns<'a>(ops: impl Iterator<Item = &'a FkOp>, turns: &mut Vec<TurnChunk>) {
    turns.clear();
    let mut lane = 0;
    for op in ops {
        let (var, multiplier, offset) = match op.motion {
            Motion::RevoluteAxis {
                var,
                multiplier,
                offset,
                ..
            }
            | Motion::Revolute {
                var,
                multiplier,
                offset,
                ..
            } => (var, multiplier, offset),
            Motion::Fixed | Motion::Prismatic { .. } => continue,
        };
        if lane == 0 {
            turns.push(TurnChunk {
                vars: [var; 4],
                ..TurnChunk::default()
            });
        }
        let chunk = turns.last_mut().expect("pushed above");
        chunk.vars[lane] = var;
        chunk.multiplier[lane] = multiplier;
        chunk.offset[lane] = offset;
        lane = (lane + 1) % 4;
    }
}

/// The compiled forward-kinematics program of a model: `ops[i]` computes link `i + 1`.
#[derive(Clone, Debug, Default)]
pub(crate) struct FkProgram {
    pub(crate) ops: Vec<FkOp>,
}

impl FkProgram {
    /// Runs every op: `poses[0]` must hold the root pose.
    #[inline]
    pub(crate) fn run(&self, q: &[f64], poses: &mut [Isometry3<f64>]) {
        Self::eval(self.ops.iter(), &[], q, poses);
    }

    /// Runs only the ops listed (each op's parent must already be computed).
    #[inline]
    pub(crate) fn run_subset(&self, subset: &[u32], q: &[f64], poses: &mut [Isometry3<f64>]) {
        Self::eval(subset.iter().map(|&i| &self.ops[i as usize]), &[], q, poses);
    }

    /// Runs `subset`'s ops, its held copies when it has them.
    #[inline]
    fn run_fk_subset(&self, subset: &FkSubset, q: &[f64], poses: &mut [Isometry3<f64>]) {
        if subset.held.is_empty() {
            let ops = subset.ops.iter().map(|&i| &self.ops[i as usize]);
            Self::eval(ops, &subset.turns, q, poses);
        } else {
            Self::eval(subset.held.iter(), &subset.turns, q, poses);
        }
    }

    /// Evaluates `ops` in order. `turns` are their revolute joints ([`fill_turns`]), whose
    /// sines and cosines are then computed four at a time before the ops are composed (with
    /// the same bits as one at a time); empty or too many, each op computes its own.
    #[inline(always)]
    fn eval<'a>(ops: impl Iterator<Item = &'a FkOp>, turns: &[TurnChunk], q: &[f64], poses: &mut [Isometry3<f64>]) {
        if turns.is_empty() || turns.len() > TURN_CHUNKS {
            return Self::compose(ops, q, poses, |_, half| sin_cos(half));
        }
        let mut sines = [0.0; 4 * TURN_CHUNKS];
        let mut cosines = [0.0; 4 * TURN_CHUNKS];
        for (k, t) in turns.iter().enumerate() {
            let v = f64x4::new(t.vars.map(|v| q[v as usize]));
            let half = f64x4::splat(0.5) * (f64x4::new(t.multiplier) * v + f64x4::new(t.offset));
            let (s, c) = sin_cos4(half);
            sines[4 * k..4 * k + 4].copy_from_slice(&s.to_array());
            cosines[4 * k..4 * k + 4].copy_from_slice(&c.to_array());
        }
        Self::compose(ops, q, poses, |turn, _| (sines[turn], cosines[turn]))
    }

    /// Composes `ops` in order; `sin_cos(turn, half)` gives the sine and cosine of the half
    /// angle `half` of the `turn`-th revolute joint among them. Serial chains dominate: the
    /// last pose stays in registers instead of being reloaded when the next op hangs from it.
    #[inline(always)]
    fn compose<'a>(
        ops: impl Iterator<Item = &'a FkOp>,
        q: &[f64],
        poses: &mut [Isometry3<f64>],
        sin_cos: impl Fn(usize, f64) -> (f64, f64),
    ) {
        let mut prev_child = 0u32;
        let mut prev = PoseLanes::<f64>::splat(&poses[0]);
        let mut turn = 0;
        for op in ops {
            let parent = if op.parent == prev_child {
                prev
            } else {
                PoseLanes::splat(&poses[op.parent as usize])
            };
            let v = op.var().map_or(0.0, |v| q[v]);
            let pose = op.after(&parent, v, |half| {
                turn += 1;
                sin_cos(turn - 1, half)
            });
            poses[op.child as usize] = pose.to_isometry();
            prev = pose;
            prev_child = op.child;
        }
    }

    /// [`FkProgram::run_fk_subset`] for four configurations at once, bit for bit the same poses.
    #[inline]
    fn run_fk_subset4(&self, subset: &FkSubset, q: [&[f64]; 4], poses: &mut [Vec<Isometry3<f64>>; 4]) {
        if subset.held.is_empty() {
            Self::eval4(subset.ops.iter().map(|&i| &self.ops[i as usize]), q, poses);
        } else {
            Self::eval4(subset.held.iter(), q, poses);
        }
    }

    /// Evaluates `ops` in order for four configurations at once.
    #[inline(always)]
    fn eval4<'a>(ops: impl Iterator<Item = &'a FkOp>, q: [&[f64]; 4], poses: &mut [Vec<Isometry3<f64>>; 4]) {
        let mut prev_child = u32::MAX;
        let mut prev = PoseLanes::<f64x4>::splat(&Isometry3::identity());
        for op in ops {
            let p = op.parent as usize;
            let parent = if op.parent == prev_child {
                prev
            } else {
                PoseLanes::gather([&poses[0][p], &poses[1][p], &poses[2][p], &poses[3][p]])
            };
            let v = op.var().map_or(f64x4::splat(0.0), |v| f64x4::new(q.map(|q| q[v])));
            let pose = op.after(&parent, v, sin_cos4);
            for (k, buf) in poses.iter_mut().enumerate() {
                buf[op.child as usize] = pose.lane(k).to_isometry();
            }
            prev = pose;
            prev_child = op.child;
        }
    }
}

/// Some links of a model, for [`RobotModel::fk_update`]: recomputing only the links a planned
/// chain moves (the base, wheels and head of a mobile manipulator keep their poses).
///
/// ```
/// use hearth_kinematics::{Chain, RobotModel};
/// let fetch = RobotModel::builtin("fetch").unwrap();
/// let arm = Chain::named(&fetch, "arm").unwrap();
/// let wrist = fetch.link_index("wrist_roll_link").unwrap();
/// let below = fetch.fk_subset(|l| fetch.joints_to(l).iter().any(|&j| arm.joints().contains(&j)));
/// assert!(below.contains(wrist) && below.len() < fetch.links().len());
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FkSubset {
    /// Op indices in evaluation order (op `i` computes link `i + 1`).
    ops: Vec<u32>,
    /// Links of the model it was made for.
    links: usize,
    /// When not empty, evaluated instead of `ops`: copies of them in which the joints held at
    /// a configuration are fixed joints ([`RobotModel::fk_subset_hold`]).
    held: Vec<FkOp>,
    /// The revolute joints of the ops evaluated (`held` when not empty, else `ops`).
    turns: Vec<TurnChunk>,
}

impl FkSubset {
    /// Number of links in the subset.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// assert_eq!(panda.fk_subset(|_| true).len(), panda.links().len() - 1); // never the root
    /// assert_eq!(panda.fk_subset(|l| l == 3).len(), 1);
    /// ```
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Whether the subset has no link.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// assert!(panda.fk_subset(|_| false).is_empty());
    /// assert!(panda.fk_subset(|l| l == panda.root()).is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Whether link `link` is in the subset.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let hand = panda.link_index("panda_hand").unwrap();
    /// let subset = panda.fk_subset(|l| l == hand);
    /// assert!(subset.contains(hand) && !subset.contains(panda.root()));
    /// ```
    pub fn contains(&self, link: usize) -> bool {
        link > 0 && self.ops.binary_search(&((link - 1) as u32)).is_ok()
    }
}

impl RobotModel {
    /// The links for which `select(link)` holds (the root is never part of a subset: it is
    /// where [`RobotModel::fk_from`] places the robot).
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let l4 = panda.link_index("panda_link4").unwrap();
    /// let after_l4 = panda.fk_subset(|l| panda.is_ancestor(l4, l));
    /// assert!(after_l4.contains(panda.link_index("panda_hand").unwrap()));
    /// assert!(!after_l4.contains(panda.link_index("panda_link3").unwrap()));
    /// ```
    pub fn fk_subset(&self, mut select: impl FnMut(usize) -> bool) -> FkSubset {
        let mut subset = FkSubset {
            ops: (1..self.0.links.len())
                .filter(|&l| select(l))
                .map(|l| (l - 1) as u32)
                .collect(),
            links: self.0.links.len(),
            held: Vec::new(),
            turns: Vec::new(),
        };
        let ops = &self.0.fk.ops;
        fill_turns(subset.ops.iter().map(|&i| &ops[i as usize]), &mut subset.turns);
        subset
    }

    /// Holds every joint of `subset` whose configuration variable `varies` rejects at its value
    /// in `q`: such a joint's transform is composed once, here, instead of in every
    /// [`RobotModel::fk_update`]. Mimic joints read their leader's variable. Updates with the
    /// held subset give, bit for bit, the poses the plain subset gives for any configuration
    /// that agrees with `q` on the held variables, and cost less when the subset has joints
    /// that never move (a mobile manipulator's head and fingers while its arm is planned).
    /// Holding again replaces what was held; the buffers are reused, so it does not allocate
    /// after the first time.
    ///
    /// # Errors
    /// `q` of the wrong length or with a value that is not finite, or a subset made for another
    /// model; the subset is then plain again (it holds nothing).
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// let moving = fetch.fk_subset(|l| fetch.joints_to(l).iter().any(|&j| arm.joints().contains(&j)));
    /// let mut q = fetch.neutral_configuration();
    /// let mut held = moving.clone();
    /// fetch.fk_subset_hold(&mut held, &q, |v| arm.variables().contains(&v)).unwrap();
    /// let (mut plain, mut fast) = (fetch.pose_buffer(), fetch.pose_buffer());
    /// fetch.fk(&q, &mut plain).unwrap();
    /// fast.copy_from_slice(&plain);
    /// arm.scatter(&[0.3, -0.5, 0.2, 1.0, 0.1, 0.4, -0.2], &mut q);
    /// fetch.fk_update(&moving, &q, &mut plain).unwrap();
    /// fetch.fk_update(&held, &q, &mut fast).unwrap();
    /// assert_eq!(plain, fast);
    /// assert!(fetch.fk_subset_hold(&mut held, &[0.0; 2], |_| true).is_err());
    /// ```
    pub fn fk_subset_hold(&self, subset: &mut FkSubset, q: &[f64], varies: impl Fn(usize) -> bool) -> Result<()> {
        subset.held.clear();
        // Without turns each op computes its own sine and cosine, right for any ops.
        subset.turns.clear();
        self.check_link_counts([("link subset's model", subset.links)])?;
        let ops = &self.0.fk.ops;
        fill_turns(subset.ops.iter().map(|&i| &ops[i as usize]), &mut subset.turns);
        self.check_configuration(q)?;
        subset.held.extend(subset.ops.iter().map(|&i| {
            let op = ops[i as usize];
            match op.var() {
                Some(v) if !varies(v) => FkOp {
                    origin: op.local(q),
                    motion: Motion::Fixed,
                    ..op
                },
                _ => op,
            }
        }));
        fill_turns(subset.held.iter(), &mut subset.turns);
        Ok(())
    }

    /// Recomputes the poses of `subset`'s links for configuration `q`, keeping every other
    /// pose in `poses` as it is: those must be current (from an earlier
    /// [`RobotModel::fk_from`] with the same base and the same values of the joints that move
    /// them). Cheaper than a full pass when few links move. Does not allocate.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel};
    /// let fetch = RobotModel::builtin("fetch").unwrap();
    /// let arm = Chain::named(&fetch, "arm").unwrap();
    /// let moving = fetch.fk_subset(|l| fetch.joints_to(l).iter().any(|&j| arm.joints().contains(&j)));
    /// let mut q = fetch.neutral_configuration();
    /// let (mut full, mut partial) = (fetch.pose_buffer(), fetch.pose_buffer());
    /// fetch.fk(&q, &mut partial).unwrap();
    /// arm.scatter(&[0.3, -0.5, 0.2, 1.0, 0.1, 0.4, -0.2], &mut q);
    /// fetch.fk_update(&moving, &q, &mut partial).unwrap();
    /// fetch.fk(&q, &mut full).unwrap();
    /// assert!(full.iter().zip(&partial).all(|(a, b)| (a.translation.vector - b.translation.vector).norm() < 1e-12));
    /// ```
    pub fn fk_update(&self, subset: &FkSubset, q: &[f64], poses: &mut [Isometry3<f64>]) -> Result<()> {
        self.check_configuration(q)?;
        self.check_link_counts([("pose buffer", poses.len()), ("link subset's model", subset.links)])?;
        self.0.fk.run_fk_subset(subset, q, poses);
        Ok(())
    }

    /// [`RobotModel::fk_update`] for four configurations at once: `poses[k]` gets the poses
    /// of `subset`'s links for `q[k]`, bit for bit what `fk_update` writes, computed four
    /// lanes at a time. Links outside `subset` must already hold their poses in every buffer.
    /// (Repeat a configuration to fill unused lanes.)
    ///
    /// Does not allocate. Errors on a wrong length or a non-finite value in any lane.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let all = panda.fk_subset(|_| true);
    /// let mut one = panda.pose_buffer();
    /// let mut four = std::array::from_fn(|_| panda.pose_buffer());
    /// let qs: Vec<Vec<f64>> = (0..4).map(|k| vec![0.1 * k as f64, -0.5, 0.2, -2.0, 0.0, 1.5, 0.7, 0.03]).collect();
    /// panda.fk_update4(&all, std::array::from_fn(|k| qs[k].as_slice()), &mut four).unwrap();
    /// for k in 0..4 {
    ///     panda.fk_update(&all, &qs[k], &mut one).unwrap();
    ///     assert_eq!(one, four[k]);
    /// }
    /// ```
    pub fn fk_update4(&self, subset: &FkSubset, q: [&[f64]; 4], poses: &mut [Vec<Isometry3<f64>>; 4]) -> Result<()> {
        for q in q {
            self.check_configuration(q)?;
        }
        self.check_link_counts(
            poses
                .iter()
                .map(|p| ("pose buffer", p.len()))
                .chain([("link subset's model", subset.links)]),
        )?;
        self.0.fk.run_fk_subset4(subset, q, poses);
        Ok(())
    }

    /// Errors when one of `sizes` (what, length) is not this model's number of links.
    fn check_link_counts(&self, sizes: impl IntoIterator<Item = (&'static str, usize)>) -> Result<()> {
        let expected = self.0.links.len();
        match sizes.into_iter().find(|&(_, got)| got != expected) {
            Some((what, got)) => Err(crate::KinematicsError::DimensionMismatch { what, expected, got }),
            None => Ok(()),
        }
    }

    /// Forward kinematics: writes the world pose of every link into `poses`, with the root at
    /// the origin. `poses` must have one entry per link ([`RobotModel::pose_buffer`]).
    ///
    /// Does not allocate. Errors on a wrong length or a non-finite value.
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let mut poses = panda.pose_buffer();
    /// let half_pi = std::f64::consts::FRAC_PI_2;
    /// let q = vec![0.0, 0.0, 0.0, -half_pi, 0.0, half_pi, 0.0, 0.0];
    /// panda.fk(&q, &mut poses).unwrap();
    /// let flange = &poses[panda.link_index("panda_link8").unwrap()];
    /// assert!((flange.translation.x - (0.0825 + 0.384 + 0.088)).abs() < 1e-9);
    /// assert!((flange.translation.z - (0.333 + 0.316 + 0.0825 - 0.107)).abs() < 1e-9);
    /// ```
    pub fn fk(&self, q: &[f64], poses: &mut [Isometry3<f64>]) -> Result<()> {
        self.fk_from(&Isometry3::identity(), q, poses)
    }

    /// Like [`RobotModel::fk`] with the root link placed at `base` (e.g. a mobile base pose).
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// use nalgebra::Isometry3;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let q = panda.neutral_configuration();
    /// let (mut at_origin, mut moved) = (panda.pose_buffer(), panda.pose_buffer());
    /// panda.fk(&q, &mut at_origin).unwrap();
    /// panda.fk_from(&Isometry3::translation(1.0, 0.0, 0.0), &q, &mut moved).unwrap();
    /// let hand = panda.link_index("panda_hand").unwrap();
    /// assert!((moved[hand].translation.x - at_origin[hand].translation.x - 1.0).abs() < 1e-12);
    /// ```
    pub fn fk_from(&self, base: &Isometry3<f64>, q: &[f64], poses: &mut [Isometry3<f64>]) -> Result<()> {
        self.check_configuration(q)?;
        self.check_link_counts([("pose buffer", poses.len())])?;
        poses[0] = *base;
        self.0.fk.run(q, poses);
        Ok(())
    }

    /// Forward kinematics to one link: its world pose (root at the origin).
    ///
    /// ```
    /// use hearth_kinematics::RobotModel;
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let link0 = panda.link_index("panda_link1").unwrap();
    /// let pose = panda.link_pose(&panda.neutral_configuration(), link0).unwrap();
    /// assert!((pose.translation.z - 0.333).abs() < 1e-9);
    /// ```
    pub fn link_pose(&self, q: &[f64], link: usize) -> Result<Isometry3<f64>> {
        self.check_configuration(q)?;
        if link >= self.0.links.len() {
            return Err(crate::KinematicsError::DimensionMismatch {
                what: "link index",
                expected: self.0.links.len(),
                got: link,
            });
        }
        let mut pose = Isometry3::identity();
        let mut path = [0u32; 64];
        let mut n = 0;
        let mut cur = link;
        while cur != 0 && n < path.len() {
            path[n] = (cur - 1) as u32;
            n += 1;
            cur = self.0.fk.ops[cur - 1].parent as usize;
        }
        if cur != 0 {
            // Deeper than 64 links: fall back to a full pass.
            let mut poses = self.pose_buffer();
            self.0.fk.run(q, &mut poses);
            return Ok(poses[link]);
        }
        for &i in path[..n].iter().rev() {
            pose *= self.0.fk.ops[i as usize].local(q);
        }
        Ok(pose)
    }

    /// The op indices that compute the links from the root to `link`, in evaluation order.
    pub(crate) fn fk_path(&self, link: usize) -> Vec<u32> {
        let mut path = Vec::new();
        let mut cur = link;
        while cur != 0 {
            path.push((cur - 1) as u32);
            cur = self.0.fk.ops[cur - 1].parent as usize;
        }
        path.reverse();
        path
    }
}

/// `(sin x, cos x)` to within a few ulps for |x| ≲ 1e5: Cody–Waite reduction to
/// [−π/4, π/4] and Taylor polynomials (error < 1e-17 there). Inlined, unlike libm's `sincos`,
/// so the FK loop overlaps it with the previous link's products.
#[inline(always)]
pub(crate) fn sin_cos(x: f64) -> (f64, f64) {
    if x.abs() >= 1e5 || x.is_nan() {
        return x.sin_cos();
    }
    let (k, s, c) = sin_cos_reduced(x);
    quadrant(k, s, c)
}

/// The quadrant `k` (an integer, as a float) of `x` and the sine and cosine of `x − k·π/2`.
#[inline(always)]
fn sin_cos_reduced<L: Lanes>(x: L) -> (L, L, L) {
    // π/2 split so that k·PIO2_HI is exact for |k| < 2^20 (PIO2_HI has 33 significant bits).
    const PIO2_HI: f64 = 1.570_796_326_734_125_6;
    const PIO2_LO: f64 = 6.077_100_506_506_192e-11;
    // Round to nearest without a libm call: adding 1.5·2^52 drops the fraction bits.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    let k = (x * L::splat(std::f64::consts::FRAC_2_PI) + L::splat(SHIFT)) - L::splat(SHIFT);
    let r = (x - k * L::splat(PIO2_HI)) - k * L::splat(PIO2_LO);
    let r2 = r * r;
    let p = |c: f64| L::splat(c);
    let s = r
        * (p(1.0)
            + r2 * (p(-1.0 / 6.0)
                + r2 * (p(1.0 / 120.0)
                    + r2 * (p(-1.0 / 5040.0)
                        + r2 * (p(1.0 / 362_880.0)
                            + r2 * (p(-1.0 / 39_916_800.0)
                                + r2 * (p(1.0 / 6_227_020_800.0) + r2 * p(-1.0 / 1_307_674_368_000.0))))))));
    let c = p(1.0)
        + r2 * (p(-0.5)
            + r2 * (p(1.0 / 24.0)
                + r2 * (p(-1.0 / 720.0)
                    + r2 * (p(1.0 / 40_320.0)
                        + r2 * (p(-1.0 / 3_628_800.0)
                            + r2 * (p(1.0 / 479_001_600.0)
                                + r2 * (p(-1.0 / 87_178_291_200.0) + r2 * p(1.0 / 20_922_789_888_000.0))))))));
    (k, s, c)
}

/// `(sin x, cos x)` from the reduced pair of quadrant `k` (signs and a swap: exact):
/// `(s, c)`, `(c, −s)`, `(−s, −c)`, `(−c, s)` for `k` mod 4 = 0, 1, 2, 3. Computed with bit
/// masks, not a branch on `k`: the quadrants of random configurations' joints are random, and
/// a mispredicted branch per joint cost more than the few integer operations.
#[inline(always)]
fn quadrant(k: f64, s: f64, c: f64) -> (f64, f64) {
    let k = k as i64;
    // All ones for an odd quadrant (swap), else zero.
    let swap = ((k & 1) as u64).wrapping_neg();
    let (s, c) = (s.to_bits(), c.to_bits());
    let first = (s & !swap) | (c & swap);
    let second = (c & !swap) | (s & swap);
    // The sign bit of the sine flips in quadrants 2 and 3, the cosine's in 1 and 2.
    let flip_first = ((k & 2) as u64) << 62;
    let flip_second = (((k + 1) & 2) as u64) << 62;
    (f64::from_bits(first ^ flip_first), f64::from_bits(second ^ flip_second))
}

#[cfg(test)]
mod tests {
    use super::{Axis, FkOp, Motion, PoseLanes, sin_cos};
    use nalgebra::{Isometry3, Vector3};

    /// A plain rotation about each frame axis, either sign, composed after random parent
    /// poses: the shortened composition equals the general one exactly (`==` on every
    /// coordinate, so up to the sign of a zero).
    #[test]
    fn plain_axis_rotation_composes_as_the_general_product() {
        let mut x = 0.37_f64;
        let mut next = || {
            x = (x * 3.7 + 0.123).fract();
            x * 6.0 - 3.0
        };
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            for multiplier in [1.0, -1.0, 0.5] {
                let origin = Isometry3::translation(next(), next(), next());
                let op = |plain| FkOp {
                    parent: 0,
                    child: 1,
                    origin,
                    motion: Motion::RevoluteAxis {
                        axis,
                        var: 0,
                        multiplier,
                        offset: 0.25,
                        plain,
                    },
                };
                for _ in 0..200 {
                    let parent = PoseLanes::<f64>::splat(&Isometry3::new(
                        Vector3::new(next(), next(), next()),
                        Vector3::new(next(), next(), next()),
                    ));
                    let v = next();
                    let short = op(true).after(&parent, v, sin_cos);
                    let general = parent.then(&op(false).local_at(v, sin_cos));
                    assert!(
                        short.q == general.q && short.t == general.t,
                        "{axis:?} {multiplier} {v}"
                    );
                }
            }
        }
    }

    #[test]
    fn sin_cos_matches_libm() {
        let mut x = -50.0;
        while x < 50.0 {
            let (s, c) = sin_cos(x);
            assert!(
                (s - x.sin()).abs() < 1e-15 && (c - x.cos()).abs() < 1e-15,
                "{x}: {} {}",
                s - x.sin(),
                c - x.cos()
            );
            x += 0.000_731;
        }
        for x in [0.0, 1e-300, -0.0, 1e5 - 1.0, 1e6, f64::NAN, f64::INFINITY] {
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 1e-12 || (s.is_nan() && x.sin().is_nan()), "{x}");
            assert!((c - x.cos()).abs() < 1e-12 || (c.is_nan() && x.cos().is_nan()), "{x}");
        }
    }

    /// The masked quadrant selection gives exactly the signs and swap of the textbook table,
    /// bit for bit (zeros keep or flip their sign as negation does), for negative quadrants too.
    #[test]
    fn quadrant_matches_the_table_bit_for_bit() {
        for k in -9_i64..=9 {
            for (s, c) in [(0.3, 0.9), (-0.7, 0.1), (0.0, 1.0), (-0.0, -1.0), (1e-300, -0.0)] {
                let expected = match k & 3 {
                    0 => (s, c),
                    1 => (c, -s),
                    2 => (-s, -c),
                    _ => (-c, s),
                };
                let got = super::quadrant(k as f64, s, c);
                assert_eq!(
                    (got.0.to_bits(), got.1.to_bits()),
                    (expected.0.to_bits(), expected.1.to_bits()),
                    "k = {k}, s = {s}, c = {c}"
                );
                // The four-lane selection, with the other lanes on other quadrants.
                let ks = wide::f64x4::new([k as f64, (k + 1) as f64, (k - 2) as f64, (k * 3) as f64]);
                let (s4, c4) = super::quadrant4(ks, wide::f64x4::splat(s), wide::f64x4::splat(c));
                for (lane, kk) in ks.to_array().into_iter().enumerate() {
                    let one = super::quadrant(kk, s, c);
                    assert_eq!(
                        (s4.to_array()[lane].to_bits(), c4.to_array()[lane].to_bits()),
                        (one.0.to_bits(), one.1.to_bits()),
                        "k = {kk}, s = {s}, c = {c}"
                    );
                }
            }
        }
    }
}
