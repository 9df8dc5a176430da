//! A motion's moving average over a fixed window: jerk limiting without re-planning.
//!
//! Averaging a motion `q(t)` over the window `[t - w, t]` averages its velocity and its
//! acceleration over the same window, so the result keeps the velocity and acceleration
//! bounds of the source, and its jerk, `(a(t) - a(t - w)) / w`, is at most `2 a_max / w`: a
//! window of `w = 2 a_max / j_max` bounds it by `j_max`. This is the FIR-filter construction of
//! jerk-limited motion (Biagiotti and Melchiorri, "FIR filters for online trajectory planning
//! with time- and frequency-domain specifications", Control Engineering Practice 20(12),
//! 2012). The motion lasts `w` longer, starts and ends at rest with zero acceleration, and
//! stays within `a_max w² / 24` of the source (time-shifted by `w / 2`) when the source's
//! velocity is continuous, as it is for every motion a [`Trajectory`] holds.
//!
//! The source is piecewise polynomial (at most cubic in time between its knots: the phase
//! switches of its ramps), so the average is computed exactly: a prefix integral at every
//! knot, and three-point Gauss–Legendre quadrature (exact to degree five) between knots.

use super::Trajectory;

/// The moving average of `source` over a window of `width` seconds (see the module docs).
#[derive(Debug)]
pub(crate) struct Averaged {
    source: Trajectory,
    width: f64,
    /// Source times where its polynomials change, sorted, from 0 to the source's duration.
    knots: Vec<f64>,
    /// `∫₀^knots[k] q(s) ds`, `dim` values per knot.
    prefix: Vec<f64>,
}

/// Gauss–Legendre nodes on `[-1, 1]` and their weights (three points).
const GAUSS: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// Windows holding at most this many knots are integrated knot by knot; others take the
/// difference of two prefix integrals. That difference rounds at the size of the whole
/// motion's integral, `|q| T ε`: divided by the window, under 10⁻¹¹ rad for a 10 s motion
/// averaged over the Panda's 4 ms. A window holding knots is at least as long as the gaps
/// between them, so only a window far shorter than any robot's would need more.
const DIRECT_KNOTS: usize = 2;

/// Up to this many coordinates, scratch space lives on the stack.
const STACK_DIM: usize = 32;

/// Runs `f` with `dim` values of scratch space, on the stack for most robots.
fn with_scratch<R>(dim: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    if dim <= STACK_DIM {
        let mut stack = [0.0; STACK_DIM];
        f(&mut stack[..dim])
    } else {
        f(&mut vec![0.0; dim])
    }
}

impl Averaged {
    /// The average of `source` over windows of `width` seconds (positive and finite).
    pub(crate) fn new(source: Trajectory, width: f64) -> Self {
        let mut knots = vec![0.0, source.duration()];
        source.knots(&mut knots);
        let end = source.duration();
        knots.retain(|t| t.is_finite() && (0.0..=end).contains(t));
        knots.sort_by(f64::total_cmp);
        knots.dedup_by(|a, b| *a - *b <= 1e-12 * end.max(1.0));
        if let Some(last) = knots.last_mut() {
            *last = end;
        }
        let dim = source.dim();
        let mut prefix = vec![0.0; knots.len() * dim];
        let mut scratch = vec![0.0; dim];
        for k in 1..knots.len() {
            let (done, rest) = prefix.split_at_mut(k * dim);
            let row = &mut rest[..dim];
            row.copy_from_slice(&done[(k - 1) * dim..]);
            gauss(&source, knots[k - 1], knots[k], 1.0, row, &mut scratch);
        }
        Self {
            source,
            width,
            knots,
            prefix,
        }
    }

    /// The source's duration plus the window.
    pub(crate) fn duration(&self) -> f64 {
        self.source.duration() + self.width
    }

    /// The times where the average's polynomials change: the source's knots, and the same
    /// a window later.
    pub(crate) fn knots(&self, out: &mut Vec<f64>) {
        out.extend(self.knots.iter().flat_map(|&k| [k, k + self.width]));
    }

    /// Position (and velocity) at time `t` of the averaged motion: the source's mean over
    /// `[t - width, t]`, holding its first state before 0 and its last after its end.
    pub(crate) fn eval(&self, t: f64, q: &mut [f64], v: Option<&mut [f64]>) {
        let dim = self.source.dim();
        with_scratch(dim, |scratch| {
            let (lo, hi) = (t - self.width, t);
            let end = self.source.duration();
            q.fill(0.0);
            let scale = 1.0 / self.width;
            // Before the start and after the end the source rests.
            let before = (hi.min(0.0) - lo).max(0.0);
            if before > 0.0 {
                self.source.sample(0.0, scratch, None);
                axpy(before * scale, scratch, q);
            }
            let after = (hi - lo.max(end)).max(0.0);
            if after > 0.0 {
                self.source.sample(end, scratch, None);
                axpy(after * scale, scratch, q);
            }
            let (a, b) = (lo.max(0.0), hi.min(end));
            if a < b {
                self.integrate(a, b, scale, q, scratch);
            }
            if let Some(v) = v {
                self.source.sample(hi, v, None);
                self.source.sample(lo, scratch, None);
                for (v, s) in v.iter_mut().zip(scratch.iter()) {
                    *v = (*v - s) * scale;
                }
            }
        });
    }

    /// Adds `scale · ∫_a^b q(s) ds` to `out` (`0 ≤ a < b ≤` the source's duration).
    fn integrate(&self, a: f64, b: f64, scale: f64, out: &mut [f64], scratch: &mut [f64]) {
        let dim = self.source.dim();
        // The knots strictly inside (a, b) are ka..kb.
        let ka = self.knots.partition_point(|&k| k <= a);
        let kb = self.knots.partition_point(|&k| k < b);
        if kb <= ka {
            gauss(&self.source, a, b, scale, out, scratch);
            return;
        }
        gauss(&self.source, a, self.knots[ka], scale, out, scratch);
        gauss(&self.source, self.knots[kb - 1], b, scale, out, scratch);
        if kb - ka <= DIRECT_KNOTS {
            for k in ka..kb - 1 {
                gauss(&self.source, self.knots[k], self.knots[k + 1], scale, out, scratch);
            }
        } else {
            let (first, last) = (
                &self.prefix[ka * dim..(ka + 1) * dim],
                &self.prefix[(kb - 1) * dim..kb * dim],
            );
            for ((o, l), f) in out.iter_mut().zip(last).zip(first) {
                *o += scale * (l - f);
            }
        }
    }
}

/// `out += x · s`.
fn axpy(x: f64, s: &[f64], out: &mut [f64]) {
    for (o, s) in out.iter_mut().zip(s) {
        *o += x * s;
    }
}

/// Adds `scale · ∫_a^b q(s) ds` to `out` by three-point Gauss–Legendre quadrature (exact where
/// the source is one polynomial of degree five or less on `[a, b]`).
fn gauss(source: &Trajectory, a: f64, b: f64, scale: f64, out: &mut [f64], scratch: &mut [f64]) {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    if half <= 0.0 {
        return;
    }
    for (x, w) in GAUSS {
        source.sample(mid + half * x, scratch, None);
        axpy(scale * half * w, scratch, out);
    }
}
