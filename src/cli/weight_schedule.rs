//! `--weight-schedule`: BiRRT's distance weights changed part-way through each plan.

use std::fmt;
use std::str::FromStr;

use hearth_planning::pipeline::MAX_WEIGHT_POWER as MAX_POWER;

/// Powers of the joints' reach weights (`RobotValidity::joint_weights`), each with the
/// iteration from which BiRRT plans with it (`BiRrt::plan_with_metrics`): `2,1@160000` plans
/// with the squared weights until iteration 160,000, then with the weights themselves.
///
/// ```text
/// "2,1@160000,0.5@360000" → [(0, 2.0), (160000, 1.0), (360000, 0.5)]
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct WeightSchedule(pub Vec<(u64, f64)>);

impl FromStr for WeightSchedule {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let mut out: Vec<(u64, f64)> = Vec::new();
        for (k, part) in s.split(',').map(str::trim).enumerate() {
            let (power, at) = match part.split_once('@') {
                Some((p, at)) => {
                    let at = at
                        .trim()
                        .parse::<u64>()
                        .map_err(|_| format!("`{part}`: `{}` is not an iteration count", at.trim()))?;
                    (p.trim(), at)
                }
                None if k == 0 => (part, 0),
                None => {
                    return Err(format!(
                        "`{part}`: every power after the first needs `@ITERATION`, the iteration it starts at"
                    ));
                }
            };
            let power: f64 = power
                .parse()
                .map_err(|_| format!("`{part}`: `{power}` is not a number"))?;
            if !(0.0..=MAX_POWER).contains(&power) {
                return Err(format!("`{part}`: a power must be between 0 and {MAX_POWER}"));
            }
            if k == 0 && at != 0 {
                return Err(format!(
                    "`{part}`: the first power applies from the start (iteration 0)"
                ));
            }
            if let Some(&(before, _)) = out.last()
                && at <= before
            {
                return Err(format!("`{part}`: iterations must increase ({at} after {before})"));
            }
            out.push((at, power));
        }
        Ok(Self(out))
    }
}

impl fmt::Display for WeightSchedule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, &(at, power)) in self.0.iter().enumerate() {
            match k {
                0 => write!(f, "{power}")?,
                _ => write!(f, ", {power} from iteration {at}")?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hearth_planning::space::Space;

    #[test]
    fn parses_and_prints() {
        let s: WeightSchedule = "2, 1@160000,0.5@360000".parse().unwrap();
        assert_eq!(s.0, vec![(0, 2.0), (160_000, 1.0), (360_000, 0.5)]);
        // The Fetch's default, as `--help` writes it.
        assert_eq!(s.0, hearth_planning::pipeline::FETCH_WEIGHT_SCHEDULE);
        assert_eq!(s.to_string(), "2, 1 from iteration 160000, 0.5 from iteration 360000");
        let plain = hearth_planning::space::JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2]).unwrap();
        let (first, later) = hearth_planning::pipeline::schedule_spaces(&plain, &[1.0, 0.25], &s.0).unwrap();
        assert_eq!(first.euclidean_weights(), Some(&[1.0, 0.0625][..]));
        assert_eq!(
            (later[1].0, later[1].1.euclidean_weights()),
            (360_000, Some(&[1.0, 0.5][..]))
        );
        assert_eq!("1".parse::<WeightSchedule>().unwrap().0, vec![(0, 1.0)]);
    }

    #[test]
    fn refuses_bad_schedules() {
        for (bad, why) in [
            ("", "not a number"),
            ("two", "not a number"),
            ("NaN", "between 0 and"),
            ("-1", "between 0 and"),
            ("5", "between 0 and"),
            ("2,1", "needs `@ITERATION`"),
            ("2@10", "from the start"),
            ("2,1@x", "not an iteration count"),
            ("2,1@-5", "not an iteration count"),
            ("2,1@100,0.5@100", "must increase"),
            ("2,1@0", "must increase"),
        ] {
            let e = bad.parse::<WeightSchedule>().unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
    }
}
