//! The penetration depth of an overlapping cylinder and box, in `f64`, by the least overlap of
//! their projections over the directions where it can be least.
//!
//! Two convex shapes overlap along a unit direction `n` by `h_A(n) + h_B(-n)` less the
//! centres' offset along `n` (`h` a support function), and the penetration depth is the least
//! of that over all directions: the distance from the origin to the boundary of their
//! Minkowski difference. For a cylinder (a disk swept along its axis) and a box that
//! difference is a disk swept over a zonotope whose edges run along the cylinder's axis and
//! the box's three axes, so its boundary has flat faces (normal along the cylinder's axis, a
//! box axis, or the cross product of the cylinder's axis with one) and curved pieces, a rim
//! swept along one of those edges, whose normals are perpendicular to that edge. The least
//! overlap is therefore on the caps' normals, on the great circle perpendicular to the
//! cylinder's axis (where it is the greatest of eight linear functions plus the radius:
//! closed form), or on one of the three great circles perpendicular to a box axis (a smooth
//! function between known kinks: each piece between samples and kinks whose slope turns
//! from falling to rising is refined by Newton steps). Every direction tried is a real one,
//! so the answer is never below the depth (and, where a sampled circle misses a narrow dip,
//! rarely a fraction of a millimetre above it); parry's EPA, which builds a polytope inside
//! the difference, errs the other way and takes longer.

use nalgebra::Vector3;

type V = Vector3<f64>;

/// Samples of each great circle perpendicular to a box axis: the steps between them, cut at
/// the circle's kinks, are the smooth pieces searched for minima.
const CIRCLE_SAMPLES: usize = 64;

/// The most Newton (or bisection) steps that refine a minimum within a piece.
const REFINE_STEPS: usize = 40;

/// The least overlap of a cylinder (at the origin, axis `y`, as parry's `Cylinder`: radius
/// `radius`, half height `half_height`) and a box (centre `t`, unit axes `axes`, half extents
/// `half`), with its unit direction, pointing from the cylinder towards the box: the box
/// moved along it by the overlap clears the cylinder. `None` when a direction tried separates
/// them (the overlap is negative: the caller measures the gap) or the input is not finite.
pub(super) fn cylinder_box_depth(
    radius: f64,
    half_height: f64,
    t: V,
    axes: [V; 3],
    half: [f64; 3],
) -> Option<(f64, V)> {
    let overlap = |n: &V| {
        half_height * n.y.abs()
            + radius * (1.0 - n.y * n.y).max(0.0).sqrt()
            + half[0] * n.dot(&axes[0]).abs()
            + half[1] * n.dot(&axes[1]).abs()
            + half[2] * n.dot(&axes[2]).abs()
            - n.dot(&t)
    };
    let mut best = (f64::INFINITY, V::y());
    let consider = |n: V, best: &mut (f64, V)| {
        let o = overlap(&n);
        if o < best.0 {
            *best = (o, n);
        }
    };
    // The caps and the box's faces.
    for n in [V::y(), axes[0], axes[1], axes[2]] {
        consider(n, &mut best);
        consider(-n, &mut best);
    }
    // The great circle perpendicular to the cylinder's axis: there the overlap is the radius
    // plus the greatest over the box's corners `s` of `(Σ s_k h_k b_k − t)·n`, least either
    // where one corner's term is least on the circle or where two corners tie (`n ⊥ b_k`).
    for b in &axes {
        let m = V::new(b.z, 0.0, -b.x);
        let len = m.norm();
        if len > 1e-12 {
            consider(m / len, &mut best);
            consider(-m / len, &mut best);
        }
    }
    for corner in 0..8 {
        let sign = |k: usize| if corner & (1 << k) == 0 { -1.0 } else { 1.0 };
        let c = axes[0] * (sign(0) * half[0]) + axes[1] * (sign(1) * half[1]) + axes[2] * (sign(2) * half[2]) - t;
        let len = (c.x * c.x + c.z * c.z).sqrt();
        if len > 1e-12 {
            consider(V::new(-c.x / len, 0.0, -c.z / len), &mut best);
        }
    }
    // The great circles perpendicular to each box axis, step by step between samples: every
    // smooth piece whose slope falls at its start and rises at its end holds a minimum.
    for k in 0..3 {
        let circle = Circle::new(radius, half_height, t, axes, half, k);
        // The slope at every sample, and the steps that hold a kink (the box's faces lie on
        // every sixteenth sample; `n_y = 0` at two opposite angles): those steps, and the
        // steps whose slope falls at the start and rises at the end, are searched piece by
        // piece.
        let mut slopes = [0.0; CIRCLE_SAMPLES];
        for (slope, &(c, s)) in slopes.iter_mut().zip(&SAMPLES) {
            *slope = circle.slopes(c, s).0;
        }
        let mut kinked = [false; CIRCLE_SAMPLES];
        let quarter = CIRCLE_SAMPLES / 4;
        for i in (0..CIRCLE_SAMPLES).step_by(quarter) {
            kinked[i] = true;
            kinked[(i + CIRCLE_SAMPLES - 1) % CIRCLE_SAMPLES] = true;
        }
        if let Some((fc, fs)) = circle.flat {
            let flat = fs.atan2(fc).rem_euclid(std::f64::consts::PI);
            for half_turn in [0.0, std::f64::consts::PI] {
                let step = ((flat + half_turn) / STEP) as usize;
                for i in [step + CIRCLE_SAMPLES - 1, step, step + 1] {
                    kinked[i % CIRCLE_SAMPLES] = true;
                }
            }
        }
        for i in 0..CIRCLE_SAMPLES {
            let next = slopes[(i + 1) % CIRCLE_SAMPLES];
            if kinked[i] || (slopes[i] < 0.0 && next > 0.0) {
                let (c, s) = SAMPLES[i];
                circle.refine(c, s, |c, s| consider(circle.u * c + circle.w * s, &mut best));
            }
        }
    }
    let (depth, n) = best;
    (depth.is_finite() && depth >= 0.0).then_some((depth, n))
}

/// The angle between samples of a great circle, and its cosine and sine.
const STEP: f64 = std::f64::consts::TAU / CIRCLE_SAMPLES as f64;
const STEP_COS: f64 = 0.995_184_726_672_196_9; // cos(2π / 64)
const STEP_SIN: f64 = 0.098_017_140_329_560_6; // sin(2π / 64)

/// The samples' directions on a great circle, `(cos θ, sin θ)` one step apart.
const SAMPLES: [(f64, f64); CIRCLE_SAMPLES] = {
    let mut out = [(1.0, 0.0); CIRCLE_SAMPLES];
    let mut i = 1;
    while i < CIRCLE_SAMPLES {
        let (c, s) = out[i - 1];
        out[i] = (c * STEP_COS - s * STEP_SIN, s * STEP_COS + c * STEP_SIN);
        i += 1;
    }
    out
};

/// The overlap on the great circle perpendicular to box axis `k`, `n = cos θ u + sin θ w`
/// with `u`, `w` the other two box axes: `h_u |cos θ| + h_w |sin θ| + l |n_y| + r √(1 − n_y²)
/// − t·n` with `n_y = α cos θ + β sin θ`, smooth between its kinks (the box's faces, and
/// `n_y = 0`), with its first two derivatives in closed form.
struct Circle {
    u: V,
    w: V,
    /// The box's half extents along `u` and `w`.
    hu: f64,
    hw: f64,
    /// The cylinder's axis (`y`) along `u` and `w`.
    alpha: f64,
    beta: f64,
    /// The box's centre along `u` and `w`.
    tu: f64,
    tw: f64,
    radius: f64,
    half_height: f64,
    /// The kink where `n_y = 0`, `(cos θ, sin θ)` (its opposite is one too); `None` when the
    /// box axis lies along the cylinder's and `n_y` is 0 all round.
    flat: Option<(f64, f64)>,
}

impl Circle {
    fn new(radius: f64, half_height: f64, t: V, axes: [V; 3], half: [f64; 3], k: usize) -> Self {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let (u, w) = (axes[i], axes[j]);
        let rho = (u.y * u.y + w.y * w.y).sqrt();
        Self {
            u,
            w,
            hu: half[i],
            hw: half[j],
            alpha: u.y,
            beta: w.y,
            tu: t.dot(&u),
            tw: t.dot(&w),
            radius,
            half_height,
            flat: (rho > 1e-12).then(|| (w.y / rho, -u.y / rho)),
        }
    }

    /// The overlap's first and second derivatives in `θ` at `(cos θ, sin θ)`, on the smooth
    /// piece there.
    fn slopes(&self, c: f64, s: f64) -> (f64, f64) {
        let g = self.alpha * c + self.beta * s;
        let g1 = self.beta * c - self.alpha * s;
        let q = (1.0 - g * g).max(1e-12).sqrt();
        let d1 = -self.hu * s * c.signum() + self.hw * c * s.signum() + self.half_height * g1 * g.signum()
            - self.radius * g * g1 / q
            + self.tu * s
            - self.tw * c;
        let d2 = -self.hu * c.abs()
            - self.hw * s.abs()
            - self.half_height * g.abs()
            - self.radius * ((g1 * g1 - g * g) / q + g * g * g1 * g1 / (q * q * q))
            + self.tu * c
            + self.tw * s;
        (d1, d2)
    }

    /// The directions `(cos θ, sin θ)` where the overlap has a local minimum between the
    /// sample `(c0, s0)` and the next, each passed to `found`. The step is cut at its kinks
    /// (the box's faces, a quarter turn apart, and `n_y = 0`: the caller tries those
    /// directions itself) into smooth pieces; a piece whose slope falls at its start and
    /// rises at its end holds a minimum, found by Newton steps on the slope kept inside the
    /// piece by bisection.
    fn refine(&self, c0: f64, s0: f64, mut found: impl FnMut(f64, f64)) {
        // `(c0, s0)` turned by the angle whose cosine and sine are `ca` and `sa`.
        let turned = |ca: f64, sa: f64| (c0 * ca - s0 * sa, s0 * ca + c0 * sa);
        let slope = |c: f64, s: f64| self.slopes(c, s).0;
        // The pieces' ends, as turns from the sample with their directions: the sample, the
        // kinks after it and the next sample.
        let mut ends = [(0.0, 0.0, 0.0); 8];
        ends[0] = (0.0, c0, s0);
        let mut count = 1;
        let (fc, fs) = self.flat.unwrap_or((1.0, 0.0)); // without one, `(1, 0)` twice
        for (kc, ks) in [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (fc, fs), (-fc, -fs)] {
            let (dot, cross) = (kc * c0 + ks * s0, c0 * ks - s0 * kc);
            if dot > STEP_COS && cross > 0.0 {
                ends[count] = (cross.atan2(dot), kc, ks);
                count += 1;
            }
        }
        let (c, s) = turned(STEP_COS, STEP_SIN);
        ends[count] = (STEP, c, s);
        count += 1;
        let ends = &mut ends[..count];
        ends.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        const NUDGE: f64 = 1e-9;
        for piece in ends.windows(2) {
            let ((lo, lc, ls), (hi, hc, hs)) = (piece[0], piece[1]);
            if hi - lo < 4.0 * NUDGE
                || slope(lc - ls * NUDGE, ls + lc * NUDGE) >= 0.0
                || slope(hc + hs * NUDGE, hs - hc * NUDGE) <= 0.0
            {
                continue; // least at an end: a sample or a kink, tried already
            }
            let x = self.newton(&turned, lo, hi);
            let (sa, ca) = x.sin_cos();
            let (c, s) = turned(ca, sa);
            found(c, s);
        }
    }

    /// Where the slope is zero in `(lo, hi)` (turns from the sample `turned` is given),
    /// falling at `lo` and rising at `hi` on one smooth piece: Newton steps from the middle,
    /// bisection where a step would leave the bracket or the overlap is not convex.
    fn newton(&self, turned: &impl Fn(f64, f64) -> (f64, f64), mut lo: f64, mut hi: f64) -> f64 {
        let mut x = 0.5 * (lo + hi);
        for _ in 0..REFINE_STEPS {
            let (sa, ca) = x.sin_cos();
            let (c, s) = turned(ca, sa);
            let (d1, d2) = self.slopes(c, s);
            if d1 < 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            let newton = x - d1 / d2;
            let next = if d2 > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let done = (next - x).abs() < 1e-10 || hi - lo < 1e-10;
            x = next;
            if done {
                break;
            }
        }
        x
    }
}

/// The cylinder's (as in [`cylinder_box_depth`]) point farthest along the unit `n`, towards a
/// box (centre `t`, unit axes `axes`, half extents `half`). Where a line of the side is
/// farthest, the middle of its part inside the box (the contact's middle), or without one its
/// point level with the box's centre; where a cap is, its point nearest the box's centre.
pub(super) fn cylinder_support(radius: f64, half_height: f64, n: &V, t: &V, axes: &[V; 3], half: &[f64; 3]) -> V {
    let side = (n.x * n.x + n.z * n.z).sqrt();
    let (x, z) = if side > 1e-6 {
        (radius * n.x / side, radius * n.z / side)
    } else {
        let len = (t.x * t.x + t.z * t.z).sqrt();
        let s = if len > radius { radius / len } else { 1.0 };
        (t.x * s, t.z * s)
    };
    let y = if n.y.abs() > 1e-6 {
        half_height.copysign(n.y)
    } else {
        // The line `(x, y, z)` for `y` in `±half_height`, clipped by the box's three slabs.
        let (mut lo, mut hi) = (-half_height, half_height);
        for k in 0..3 {
            let (at, rate) = ((V::new(x, 0.0, z) - t).dot(&axes[k]), axes[k].y);
            if rate.abs() > 1e-12 {
                let (a, b) = ((-half[k] - at) / rate, (half[k] - at) / rate);
                lo = lo.max(a.min(b));
                hi = hi.min(a.max(b));
            } else if at.abs() > half[k] {
                (lo, hi) = (1.0, -1.0);
            }
        }
        if lo <= hi {
            0.5 * (lo + hi)
        } else {
            t.y.max(-half_height).min(half_height)
        }
    };
    V::new(x, y, z)
}

/// The box's (centred at the origin, half extents `half` along its frame's axes) point
/// farthest along the unit `n`; where a face or an edge is farthest, its point nearest
/// `toward`.
pub(super) fn box_support(half: [f64; 3], n: &V, toward: &V) -> V {
    V::from_fn(|k, _| {
        if n[k].abs() > 1e-6 {
            half[k].copysign(n[k])
        } else {
            toward[k].max(-half[k]).min(half[k])
        }
    })
}

#[cfg(test)]
mod tests {
    use super::{V, cylinder_box_depth, cylinder_support};
    use nalgebra::{Rotation3, Unit};
    use proptest::prelude::*;

    /// The overlap along `n` from the shapes' vertices and rim points (the box's eight
    /// corners; the cylinder's caps at 4,096 rim points), written independently of the
    /// search's closed forms.
    fn overlap_by_points(radius: f64, half_height: f64, t: V, axes: [V; 3], half: [f64; 3], n: &V) -> f64 {
        let cylinder_top = (0..4096)
            .flat_map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 4096.0;
                [-half_height, half_height].map(|y| V::new(radius * a.cos(), y, radius * a.sin()).dot(n))
            })
            .fold(f64::MIN, f64::max);
        let box_bottom = (0..8)
            .map(|c| {
                let s = |k: usize| if c & (1 << k) == 0 { -half[k] } else { half[k] };
                (t + axes[0] * s(0) + axes[1] * s(1) + axes[2] * s(2)).dot(n)
            })
            .fold(f64::MAX, f64::min);
        cylinder_top - box_bottom
    }

    /// The least overlap by brute force: 20,000 spread directions, the best 16 refined by a
    /// shrinking pattern search on the sphere. An upper bound of the depth, as the search's.
    fn least_overlap_by_search(radius: f64, half_height: f64, t: V, axes: [V; 3], half: [f64; 3]) -> f64 {
        let f = |n: &V| {
            let n = n.normalize();
            half_height * n.y.abs()
                + radius * (1.0 - n.y * n.y).max(0.0).sqrt()
                + (0..3).map(|k| half[k] * n.dot(&axes[k]).abs()).sum::<f64>()
                - n.dot(&t)
        };
        let count = 20_000;
        let mut spread: Vec<(f64, V)> = (0..count)
            .map(|k| {
                let z = 1.0 - (2 * k + 1) as f64 / count as f64;
                let (r, phi) = ((1.0 - z * z).sqrt(), k as f64 * 2.399_963_229_728_653);
                let n = V::new(r * phi.cos(), r * phi.sin(), z);
                (f(&n), n)
            })
            .collect();
        spread.sort_by(|a, b| a.0.total_cmp(&b.0));
        spread
            .iter()
            .take(16)
            .map(|&(mut value, mut n)| {
                let mut h = 0.02;
                while h > 1e-9 {
                    let (a, b) = (n.cross(&V::x()), n.cross(&V::y()));
                    let e1 = if a.norm() > b.norm() {
                        a.normalize()
                    } else {
                        b.normalize()
                    };
                    let e2 = n.cross(&e1);
                    let mut moved = false;
                    for d in [e1, -e1, e2, -e2, e1 + e2, e1 - e2, -e1 + e2, -e1 - e2] {
                        let m = (n + d * h).normalize();
                        let v = f(&m);
                        if v < value {
                            (value, n, moved) = (v, m, true);
                        }
                    }
                    if !moved {
                        h *= 0.5;
                    }
                }
                value
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn check(radius: f64, half_height: f64, t: V, axes: [V; 3], half: [f64; 3]) -> Option<(f64, V)> {
        let got = cylinder_box_depth(radius, half_height, t, axes, half);
        let searched = least_overlap_by_search(radius, half_height, t, axes, half);
        match got {
            None => assert!(searched < 1e-3, "no depth, where the search finds {searched}"),
            Some((depth, n)) => {
                assert!((n.norm() - 1.0).abs() < 1e-9, "{n}");
                // A real direction's overlap, and no direction the search finds overlaps less.
                let along = overlap_by_points(radius, half_height, t, axes, half, &n);
                assert!((along - depth).abs() < 1e-6, "depth {depth}, overlap along {n} {along}");
                assert!(
                    depth <= searched * 1.01 + 1e-7,
                    "depth {depth}, the search's {searched}"
                );
            }
        }
        got
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        /// Random overlapping pairs: the depth is the overlap along its own direction, by
        /// the shapes' points, and within 1 % of a thorough search's least overlap (the sampled
        /// circles can miss a dip narrower than a step: 0.1 % above it in the worst case seen).
        #[test]
        fn the_depth_is_the_least_overlap(
            radius in 0.02f64..0.2,
            half_height in 0.02f64..0.3,
            half in proptest::array::uniform3(0.01f64..0.4),
            t in proptest::array::uniform3(-0.35f64..0.35),
            axis in proptest::array::uniform3(-1.0f64..1.0),
            angle in -3.2f64..3.2,
        ) {
            let axis = Unit::try_new(V::from(axis), 1e-3).unwrap_or(V::x_axis());
            let r = Rotation3::from_axis_angle(&axis, angle);
            let axes = [r * V::x(), r * V::y(), r * V::z()];
            check(radius, half_height, V::from(t), axes, half);
        }
    }

    /// A box on the cap, a box's face against the side, a box's edge along the axis into
    /// the side, a cylinder lying over a board's edge: the depth and direction each has in
    /// closed form.
    #[test]
    fn plain_cases() {
        let id = [V::x(), V::y(), V::z()];
        // Resting on the cap, 1 cm deep.
        let (d, n) = check(0.1, 0.2, V::new(0.02, 0.24, 0.0), id, [0.1, 0.05, 0.1]).unwrap();
        assert!((d - 0.01).abs() < 1e-12 && (n - V::y()).norm() < 1e-12, "{d} {n}");
        // A face against the side, 2 cm deep.
        let (d, n) = check(0.1, 0.2, V::new(0.13, 0.0, 0.0), id, [0.05, 0.1, 0.1]).unwrap();
        assert!((d - 0.02).abs() < 1e-12 && (n - V::x()).norm() < 1e-12, "{d} {n}");
        // An edge along the axis into the side: the box turned 45° about y, its edge 1.5 cm
        // inside.
        let r = Rotation3::from_axis_angle(&V::y_axis(), std::f64::consts::FRAC_PI_4);
        let axes = id.map(|a| r * a);
        let reach = 0.05 * std::f64::consts::SQRT_2;
        let (d, n) = check(0.1, 0.2, V::new(0.1 - 0.015 + reach, 0.0, 0.0), axes, [0.05, 0.3, 0.05]).unwrap();
        assert!((d - 0.015).abs() < 1e-9 && (n - V::x()).norm() < 1e-6, "{d} {n}");
        // Lying on a board's edge: the contact's middle is the middle of the side line's part
        // over the board.
        let (t, half) = (V::new(0.24, 0.2, 0.0), [0.2, 0.2, 0.2]);
        let (d, n) = check(0.05, 0.3, t, id, half).unwrap();
        assert!((d - 0.01).abs() < 1e-12 && (n - V::x()).norm() < 1e-12, "{d} {n}");
        let p = cylinder_support(0.05, 0.3, &n, &t, &id, &half);
        assert!((p - V::new(0.05, 0.15, 0.0)).norm() < 1e-12, "{p}");
        // Apart, and not finite.
        assert!(cylinder_box_depth(0.1, 0.2, V::new(0.5, 0.0, 0.0), id, [0.1; 3]).is_none());
        assert!(cylinder_box_depth(0.1, 0.2, V::new(f64::NAN, 0.0, 0.0), id, [0.1; 3]).is_none());
    }
}
