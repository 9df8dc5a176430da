//! Time-optimal state-to-state motions and motions through waypoints, computed locally by
//! `rsruckig` (the pure-Rust Ruckig).

use rsruckig::prelude::*;

use super::{Limits, TrajectoryError};

/// A ruckig trajectory of any number of coordinates.
pub(crate) type Generated = rsruckig::prelude::Trajectory<0>;

/// How the coordinates are synchronised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sync {
    /// All coordinates finish together (free shape).
    Time,
    /// Proportional profiles: from rest to rest the motion stays on the straight line.
    Phase,
}

/// Fills a ruckig input with the limits and optional position bounds.
fn input(limits: &Limits, bounds: Option<(&[f64], &[f64])>) -> InputParameter<0> {
    let n = limits.dim();
    let mut input = InputParameter::<0>::new(Some(n));
    for i in 0..n {
        input.max_velocity[i] = limits.velocity()[i];
        input.max_acceleration[i] = limits.acceleration()[i];
        input.max_jerk[i] = limits.jerk()[i];
    }
    if let Some((lower, upper)) = bounds {
        let mut lo = DataArrayOrVec::<f64, 0>::new(Some(n), f64::NEG_INFINITY);
        let mut hi = DataArrayOrVec::<f64, 0>::new(Some(n), f64::INFINITY);
        for i in 0..n {
            lo[i] = lower[i];
            hi[i] = upper[i];
        }
        input.min_position = Some(lo);
        input.max_position = Some(hi);
    }
    input
}

fn run(input: &InputParameter<0>, n: usize, sweeps: usize) -> Result<Generated, TrajectoryError> {
    let mut otg = Ruckig::<0, ThrowErrorHandler>::new(Some(n), 0.001);
    otg.waypoint_refinement_sweeps = sweeps;
    let mut trajectory = Generated::new(Some(n));
    calculate(&mut otg, input, &mut trajectory)?;
    Ok(trajectory)
}

/// The generator's error message without the dump of its whole input that follows `input:`
/// (every limit and state printed with 16 decimals: kilobytes for a limit of 10³⁰⁰).
fn without_input_dump(message: &str) -> String {
    let head = message.split_once("input:").map_or(message, |(head, _)| head);
    head.trim_end_matches(|c: char| c.is_whitespace() || c == ',')
        .to_owned()
}

/// The time-optimal motion from `(q0, v0)` to `(q1, v1)` (accelerations zero at both ends)
/// within `limits` and, where given, position `bounds` (`±∞` for unbounded coordinates).
pub(crate) fn between(
    q0: &[f64],
    v0: &[f64],
    q1: &[f64],
    v1: &[f64],
    limits: &Limits,
    sync: Sync,
) -> Result<Generated, TrajectoryError> {
    let mut ramps = RampGenerator::new(limits, sync);
    let mut out = Generated::new(Some(limits.dim()));
    ramps.between(q0, v0, q1, v1, &mut out)?;
    Ok(out)
}

/// Time-optimal state-to-state motions within fixed limits, one after another, in the same
/// generator and input: after the first, computing one allocates nothing (as Ruckig is used
/// in a control loop). The generator of the shortcutter's ramps (`trajectory::Ramps`).
pub(crate) struct RampGenerator {
    otg: Ruckig<0, ThrowErrorHandler>,
    input: InputParameter<0>,
}

impl RampGenerator {
    /// A generator of motions within `limits` (and their position bounds), synchronised by
    /// `sync`.
    pub(crate) fn new(limits: &Limits, sync: Sync) -> Self {
        let mut input = input(limits, limits.position_bounds());
        input.synchronization = match sync {
            Sync::Time => Synchronization::Time,
            Sync::Phase => Synchronization::Phase,
        };
        Self {
            otg: Ruckig::<0, ThrowErrorHandler>::new(Some(limits.dim()), 0.001),
            input,
        }
    }

    /// The motion from `(q0, v0)` to `(q1, v1)` (accelerations zero at both ends), written
    /// into `out` (a trajectory of the limits' dimension, whatever it held before).
    pub(crate) fn between(
        &mut self,
        q0: &[f64],
        v0: &[f64],
        q1: &[f64],
        v1: &[f64],
        out: &mut Generated,
    ) -> Result<(), TrajectoryError> {
        self.set(q0, v0, q1, v1);
        calculate(&mut self.otg, &self.input, out)
    }

    /// As [`RampGenerator::between`], but `false` instead of an error, and without calling the
    /// generator for a target state it refuses before computing anything
    /// ([`target_refused`]): the generator formats the text of every refusal, and the
    /// shortcutter, which tries ramps in a loop, has no use for it.
    pub(crate) fn try_between(&mut self, q0: &[f64], v0: &[f64], q1: &[f64], v1: &[f64], out: &mut Generated) -> bool {
        self.set(q0, v0, q1, v1);
        if target_refused(&self.input) {
            return false;
        }
        matches!(
            self.otg.calculate(&self.input, out),
            Ok(RuckigResult::Working | RuckigResult::Finished)
        )
    }

    fn set(&mut self, q0: &[f64], v0: &[f64], q1: &[f64], v1: &[f64]) {
        let input = &mut self.input;
        for i in 0..q0.len() {
            input.current_position[i] = q0[i];
            input.current_velocity[i] = v0[i];
            input.current_acceleration[i] = 0.0;
            input.target_position[i] = q1[i];
            input.target_velocity[i] = v1[i];
            input.target_acceleration[i] = 0.0;
        }
    }
}

/// Whether the generator's validation refuses `input`'s target state, for an input whose limits
/// are valid (as [`Limits`] makes them), without minimum velocities or accelerations, in
/// position control, with every state finite and the target at rest in acceleration: the
/// target velocity beyond its limit, or, with position bounds, the target position beyond them
/// or a stop from the target state (at full deceleration, jerk-limited when the jerk is finite)
/// that would overrun them. The same tests, in the same arithmetic, as `rsruckig`'s
/// `InputParameter::validate` makes of the target state; the generator checks no other
/// state before it computes (`calculate` leaves the current state unchecked).
fn target_refused(input: &InputParameter<0>) -> bool {
    use rsruckig::brake::{stop_distance_second_order, stop_distance_third_order};
    for dof in 0..input.degrees_of_freedom {
        let (v_max, a_max, j_max) = (
            input.max_velocity[dof],
            input.max_acceleration[dof],
            input.max_jerk[dof],
        );
        let (pf, vf, af) = (
            input.target_position[dof],
            input.target_velocity[dof],
            input.target_acceleration[dof],
        );
        if vf > v_max || vf < -v_max {
            return true;
        }
        if input.max_position.is_none() && input.min_position.is_none() {
            continue;
        }
        let max_pos = input.max_position.as_ref().map_or(f64::INFINITY, |p| p[dof]);
        let min_pos = input.min_position.as_ref().map_or(f64::NEG_INFINITY, |p| p[dof]);
        if pf > max_pos || pf < min_pos {
            return true;
        }
        let a_min = -a_max;
        let (up, down) = if j_max > 0.0 && j_max.is_finite() {
            (
                stop_distance_third_order(vf, af, a_min, j_max),
                stop_distance_third_order(-vf, -af, a_max, j_max),
            )
        } else if a_max.is_finite() || a_min.is_finite() {
            (
                stop_distance_second_order(vf, a_min),
                stop_distance_second_order(-vf, a_max),
            )
        } else {
            (0.0, 0.0)
        };
        if up > max_pos - pf || down > pf - min_pos {
            return true;
        }
    }
    false
}

/// Runs the generator, its errors as [`TrajectoryError::Generator`].
fn calculate(
    otg: &mut Ruckig<0, ThrowErrorHandler>,
    input: &InputParameter<0>,
    out: &mut Generated,
) -> Result<(), TrajectoryError> {
    match otg.calculate(input, out) {
        Ok(RuckigResult::Working) | Ok(RuckigResult::Finished) => Ok(()),
        Ok(other) => Err(TrajectoryError::Generator(format!("{other:?}"))),
        Err(e) => Err(TrajectoryError::Generator(without_input_dump(&e.to_string()))),
    }
}

/// A motion from rest at `waypoints[0]` to rest at the last waypoint that passes through the
/// ones between without stopping, its pass-through states refined by up to `sweeps` sweeps of
/// the waypoint solver's local search.
pub(crate) fn through(waypoints: &[Vec<f64>], limits: &Limits, sweeps: usize) -> Result<Generated, TrajectoryError> {
    let n = limits.dim();
    let (Some(first), Some(last)) = (waypoints.first(), waypoints.last()) else {
        return Err(TrajectoryError::EmptyPath);
    };
    let mut input = input(limits, None);
    for i in 0..n {
        input.current_position[i] = first[i];
        input.target_position[i] = last[i];
    }
    if waypoints.len() > 2 {
        input.intermediate_positions = waypoints[1..waypoints.len() - 1]
            .iter()
            .map(|w| {
                let mut p = DataArrayOrVec::<f64, 0>::new(Some(n), 0.0);
                for i in 0..n {
                    p[i] = w[i];
                }
                p
            })
            .collect();
    }
    run(&input, n, sweeps)
}

/// Position and velocity of a ruckig trajectory at time `t` (clamped to its duration),
/// without allocating.
pub(crate) fn eval(trajectory: &Generated, t: f64, q: &mut [f64], mut v: Option<&mut [f64]>) {
    let mut section = 0;
    trajectory.state_to_integrate_from(t, &mut section, |dof, dt, p, vel, a, j| {
        let (pp, vv, _) = rsruckig::util::integrate(dt, p, vel, a, j);
        q[dof] = pp;
        if let Some(v) = v.as_deref_mut() {
            v[dof] = vv;
        }
    });
}

/// Appends the times where a ruckig trajectory's phases change (every coordinate's, every
/// section's), as [`Generated::state_to_integrate_from`] walks them.
pub(crate) fn knots(trajectory: &Generated, out: &mut Vec<f64>) {
    for (section, profiles) in trajectory.profiles.iter().enumerate() {
        let start = if section == 0 {
            0.0
        } else {
            trajectory.cumulative_times[section - 1]
        };
        out.push(start);
        for dof in 0..profiles.len() {
            let p = &profiles[dof];
            let mut from = start;
            if section == 0 && p.brake.duration > 0.0 {
                out.push(start + p.brake.t[0]);
                from += p.brake.duration;
                out.push(from);
            }
            out.extend(p.t_sum.iter().map(|t| from + t));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Zero limits (below the generator's precision) fail with the generator's reason and
    /// without the dump of its input.
    #[test]
    fn generator_errors_leave_out_the_input_dump() {
        let limits = Limits::new(vec![1e-300; 2], vec![1.0; 2], vec![10.0; 2]).unwrap();
        let err = between(&[0.0; 2], &[0.0; 2], &[1.0, -1.0], &[0.0; 2], &limits, Sync::Time).unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with("the trajectory generator failed: "), "{text}");
        assert!(
            !text.contains("inp.") && !text.contains("input") && text.len() < 200,
            "{text}"
        );
        assert_eq!(without_input_dump("a, b, input: \n x"), "a, b");
        assert_eq!(without_input_dump("no dump"), "no dump");
    }

    /// Three coordinates, the first two bounded to [-1, 1] and [0, 2], the third unbounded.
    fn bounded(jerk: f64) -> RampGenerator {
        let limits = Limits::new(vec![1.0, 2.0, 0.5], vec![2.0, 4.0, 1.0], vec![jerk; 3])
            .unwrap()
            .with_position_bounds(vec![-1.0, 0.0, f64::NEG_INFINITY], vec![1.0, 2.0, f64::INFINITY])
            .unwrap();
        RampGenerator::new(&limits, Sync::Time)
    }

    /// The shortcutter's pre-test refuses what the generator's own validation refuses, no
    /// more and no less, with and without a jerk limit: a stop from 1 rad/s at 2 rad/s² takes
    /// 0.25 rad, so 0.8 rad moving up in [-1, 1] overruns the bound and 0.7 does not.
    #[test]
    fn target_refused_marks_what_the_generator_refuses() {
        let mut ramps = bounded(f64::INFINITY);
        let mut out = Generated::new(Some(3));
        let rest = [0.0; 3];
        assert!(ramps.try_between(&rest, &rest, &[0.7, 1.0, 0.0], &[1.0, 0.0, 0.0], &mut out));
        assert!(!ramps.try_between(&rest, &rest, &[0.8, 1.0, 0.0], &[1.0, 0.0, 0.0], &mut out));
        assert!(!ramps.try_between(&rest, &rest, &[0.0, 1.0, 0.0], &[0.0, 0.0, -0.5000001], &mut out));
        assert!(!ramps.try_between(&rest, &rest, &[0.0, 2.1, 0.0], &rest, &mut out));
        assert!(
            ramps
                .between(&rest, &rest, &[0.8, 1.0, 0.0], &[1.0, 0.0, 0.0], &mut out)
                .is_err()
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(3000))]

        /// Targets near the bounds and the velocity limits: [`target_refused`] is exactly the
        /// generator's validation of the target state.
        #[test]
        fn target_refused_is_the_generators_validation(
            p in proptest::collection::vec(-1.2f64..2.2, 3),
            v in proptest::collection::vec(-2.1f64..2.1, 3),
            jerk in proptest::sample::select(vec![f64::INFINITY, 5.0, 50.0]),
        ) {
            let mut ramps = bounded(jerk);
            ramps.set(&[0.0, 1.0, 0.0], &[0.0; 3], &p, &v);
            let refused = ramps.input.validate::<ThrowErrorHandler>(false, true).is_err();
            proptest::prop_assert_eq!(target_refused(&ramps.input), refused);
        }
    }
}
