//! Rest-to-rest motion along a straight line with a trapezoidal speed profile.

use super::Limits;

/// A straight segment `start → start + delta`, travelled from rest to rest as fast as the
/// per-coordinate velocity and acceleration limits allow: every coordinate follows the same
/// scalar profile `s(t) ∈ [0, 1]`, so the motion never leaves the line (the collision check of
/// the geometric edge still holds).
#[derive(Clone, Debug)]
pub(crate) struct LineRamp {
    start: Vec<f64>,
    delta: Vec<f64>,
    accel: f64,
    peak: f64,
    t_acc: f64,
    t_cruise: f64,
    duration: f64,
}

impl LineRamp {
    pub(crate) fn new(start: &[f64], delta: &[f64], limits: &Limits) -> Self {
        let mut vmax = f64::INFINITY;
        let mut amax = f64::INFINITY;
        for ((&d, &v), &a) in delta.iter().zip(limits.velocity()).zip(limits.acceleration()) {
            let d = d.abs();
            if d > 0.0 {
                vmax = vmax.min(v / d);
                amax = amax.min(a / d);
            }
        }
        let (t_acc, t_cruise, peak) = if !vmax.is_finite() {
            (0.0, 0.0, 0.0)
        } else if vmax * vmax / amax >= 1.0 {
            let t = (1.0 / amax).sqrt();
            (t, 0.0, amax * t)
        } else {
            let t = vmax / amax;
            (t, (1.0 - vmax * t) / vmax, vmax)
        };
        Self {
            start: start.to_vec(),
            delta: delta.to_vec(),
            accel: if vmax.is_finite() { amax } else { 0.0 },
            peak,
            t_acc,
            t_cruise,
            duration: 2.0 * t_acc + t_cruise,
        }
    }

    pub(crate) fn duration(&self) -> f64 {
        self.duration
    }

    /// The times where the speed profile changes phase (end of speeding up, end of cruising).
    pub(crate) fn knots(&self) -> [f64; 2] {
        [self.t_acc, self.t_acc + self.t_cruise]
    }

    /// Path parameter and its rate at time `t`.
    fn profile(&self, t: f64) -> (f64, f64) {
        if self.duration <= 0.0 {
            return (1.0, 0.0);
        }
        let t = t.clamp(0.0, self.duration);
        if t < self.t_acc {
            (0.5 * self.accel * t * t, self.accel * t)
        } else if t <= self.t_acc + self.t_cruise {
            (
                0.5 * self.accel * self.t_acc * self.t_acc + self.peak * (t - self.t_acc),
                self.peak,
            )
        } else {
            let r = self.duration - t;
            (1.0 - 0.5 * self.accel * r * r, self.accel * r)
        }
    }

    pub(crate) fn eval(&self, t: f64, q: &mut [f64], v: Option<&mut [f64]>) {
        let (s, ds) = self.profile(t);
        for ((o, &x), &d) in q.iter_mut().zip(&self.start).zip(&self.delta) {
            *o = x + s * d;
        }
        if let Some(v) = v {
            for (o, &d) in v.iter_mut().zip(&self.delta) {
                *o = ds * d;
            }
        }
    }
}
