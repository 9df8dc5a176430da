//! The action of the ReLMoGen env: its [`ActionSpec`] (space and decoding) and the [`Subgoal`]
//! an action asks for.
//!
//! **Continuous** (ReLMoGen-R), 8 entries in [−1, 1]:
//!
//! | entry | meaning | scaling |
//! |---|---|---|
//! | 0 | selector | > 0: arm subgoal, else base subgoal |
//! | 1 | base bearing | × π rad, robot frame (0 ahead, + left) |
//! | 2 | base distance | (x + 1) / 2 × `max_base_distance` |
//! | 3 | base final yaw | × π rad, relative to the current heading |
//! | 4 | arm u | (x + 1) / 2 × (W − 1), rounded |
//! | 5 | arm v | (x + 1) / 2 × (H − 1), rounded |
//! | 6 | push direction | × π rad: horizontal direction in the robot frame |
//! | 7 | push mode | > 0: along −normal (straight into the surface; entry 6 unused), else entry 6 |
//!
//! **Discrete** (ReLMoGen-D), 1 entry: an index into two score maps at quarter resolution,
//! each `H/4 × W/4 × D` (D = `direction_bins`). With `m = (H/4)·(W/4)·D`:
//! `index = map·m + (row·(W/4) + col)·D + bin`, `map` 0 = base, 1 = arm. The cell (`row`,
//! `col`) stands for pixel (`u`, `v`) = (4·col + 2, 4·row + 2).
//! - base map: drive to the floor point seen at that pixel (a pixel that does not see floor
//!   is a failed subgoal), final yaw `2π·bin/D` relative to the current heading;
//! - arm map: push the surface seen at that pixel; bin 0 pushes along −normal (straight into
//!   the surface), bin k ≥ 1 pushes horizontally at `2π(k − 1)/(D − 1)` in the robot frame.

use std::f64::consts::{PI, TAU};

use hearth_kinematics::{Num, wrap_angle};
use hearth_sim::env::{DType, Space};

use super::config::{ActionForm, ReLMoGenError, ReLMoGenResult};

/// Entries of the continuous action.
const CONTINUOUS_LEN: usize = 8;

/// The direction of an arm subgoal's push.
///
/// ```
/// use hearth_skills::relmogen::PushDirection;
/// assert_ne!(PushDirection::AgainstNormal, PushDirection::Horizontal(0.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PushDirection {
    /// Along the surface's inward normal.
    AgainstNormal,
    /// Horizontally at this angle in the robot frame (rad; 0 ahead, + to the left).
    Horizontal(f64),
}

/// What an action asks for, before it is resolved against the world.
///
/// ```
/// use hearth_skills::relmogen::Subgoal;
/// let s = Subgoal::Base { bearing: 0.0, distance: 1.0, yaw: 0.0 };
/// assert!(!s.is_arm());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Subgoal {
    /// Drive `distance` m at `bearing` rad (robot frame), then turn to `yaw` rad relative to
    /// the heading at the start.
    Base {
        /// Bearing, robot frame.
        bearing: f64,
        /// Distance, m.
        distance: f64,
        /// Final yaw relative to the current heading.
        yaw: f64,
    },
    /// Drive to the floor point seen at pixel (`u`, `v`), final yaw `yaw` relative to the
    /// current heading.
    BaseAtPixel {
        /// Column.
        u: u32,
        /// Row.
        v: u32,
        /// Final yaw relative to the current heading.
        yaw: f64,
    },
    /// Push what pixel (`u`, `v`) sees.
    Arm {
        /// Column.
        u: u32,
        /// Row.
        v: u32,
        /// Push direction.
        direction: PushDirection,
    },
}

impl Subgoal {
    /// Whether this is an arm subgoal.
    ///
    /// ```
    /// use hearth_skills::relmogen::{PushDirection, Subgoal};
    /// assert!(Subgoal::Arm { u: 1, v: 2, direction: PushDirection::AgainstNormal }.is_arm());
    /// ```
    pub fn is_arm(&self) -> bool {
        matches!(self, Subgoal::Arm { .. })
    }
}

/// The action space of a ReLMoGen env and how its actions decode (`docs/relmogen.md` has the
/// layouts).
///
/// ```
/// use hearth_skills::relmogen::{ActionForm, ActionSpec, PushDirection, Subgoal};
/// let spec = ActionSpec { form: ActionForm::Discrete, width: 128, height: 128, bins: 8, max_base_distance: 2.0 };
/// assert_eq!(spec.space().high, (2 * 32 * 32 * 8 - 1) as f64);
/// let i = spec.arm_index(10, 20, 0).unwrap();
/// assert_eq!(spec.decode(&[i as f32]).unwrap(),
///            Subgoal::Arm { u: 82, v: 42, direction: PushDirection::AgainstNormal });
/// assert!(spec.decode(&[-1.0]).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActionSpec {
    /// Continuous or discrete.
    pub form: ActionForm,
    /// Camera width, pixels (a multiple of 4).
    pub width: u32,
    /// Camera height, pixels (a multiple of 4).
    pub height: u32,
    /// D.
    pub bins: usize,
    /// Longest continuous base subgoal, m.
    pub max_base_distance: f64,
}

impl ActionSpec {
    /// Cells of one discrete map: (H/4)·(W/4)·D.
    ///
    /// ```
    /// use hearth_skills::relmogen::{ActionForm, ActionSpec};
    /// let spec = ActionSpec { form: ActionForm::Discrete, width: 64, height: 48, bins: 4, max_base_distance: 2.0 };
    /// assert_eq!(spec.map_size(), 12 * 16 * 4);
    /// ```
    pub fn map_size(&self) -> usize {
        (self.width / 4) as usize * (self.height / 4) as usize * self.bins
    }

    /// The action space: a box of 8 entries in [−1, 1], or 1 integer entry in
    /// [0, 2·[`ActionSpec::map_size`] − 1].
    ///
    /// ```
    /// use hearth_skills::relmogen::{ActionForm, ActionSpec};
    /// let spec = ActionSpec { form: ActionForm::Discrete, width: 64, height: 48, bins: 4, max_base_distance: 2.0 };
    /// assert_eq!(spec.space().shape, vec![1]);
    /// let c = ActionSpec { form: ActionForm::Continuous, ..spec };
    /// assert_eq!(c.space().shape, vec![8]);
    /// ```
    pub fn space(&self) -> Space {
        match self.form {
            ActionForm::Continuous => Space::boxed("action", &[CONTINUOUS_LEN], DType::F32, -1.0, 1.0),
            ActionForm::Discrete => Space::boxed("action", &[1], DType::U32, 0.0, (2 * self.map_size() - 1) as f64),
        }
    }

    /// The discrete index of base cell (`row`, `col`), yaw bin `bin`; `None` out of range.
    ///
    /// ```
    /// use hearth_skills::relmogen::{ActionForm, ActionSpec};
    /// let spec = ActionSpec { form: ActionForm::Discrete, width: 64, height: 48, bins: 4, max_base_distance: 2.0 };
    /// assert_eq!(spec.base_index(0, 1, 2), Some(6));
    /// assert_eq!(spec.base_index(12, 0, 0), None);
    /// ```
    pub fn base_index(&self, row: u32, col: u32, bin: usize) -> Option<usize> {
        self.cell_index(row, col, bin)
    }

    /// The discrete index of arm cell (`row`, `col`), direction bin `bin`; `None` out of
    /// range.
    ///
    /// ```
    /// use hearth_skills::relmogen::{ActionForm, ActionSpec};
    /// let spec = ActionSpec { form: ActionForm::Discrete, width: 64, height: 48, bins: 4, max_base_distance: 2.0 };
    /// assert_eq!(spec.arm_index(0, 0, 0), Some(spec.map_size()));
    /// ```
    pub fn arm_index(&self, row: u32, col: u32, bin: usize) -> Option<usize> {
        self.cell_index(row, col, bin).map(|i| i + self.map_size())
    }

    fn cell_index(&self, row: u32, col: u32, bin: usize) -> Option<usize> {
        let (mw, mh) = (self.width / 4, self.height / 4);
        (row < mh && col < mw && bin < self.bins).then(|| (row as usize * mw as usize + col as usize) * self.bins + bin)
    }

    /// Decodes an action.
    ///
    /// # Errors
    /// [`ReLMoGenError::BadAction`] for a wrong length, a non-finite entry, an entry outside
    /// [−1, 1] (continuous), or an index that is not an integer in range (discrete).
    ///
    /// ```
    /// use hearth_skills::relmogen::{ActionForm, ActionSpec};
    /// let spec = ActionSpec { form: ActionForm::Discrete, width: 64, height: 48, bins: 4, max_base_distance: 2.0 };
    /// use hearth_skills::relmogen::Subgoal;
    /// let Subgoal::BaseAtPixel { u, v, yaw } = spec.decode(&[5.0]).unwrap() else { panic!() };
    /// assert_eq!((u, v), (6, 2));
    /// assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    /// assert!(spec.decode(&[0.5]).is_err());
    /// // A continuous entry out of range is named, its value printed short.
    /// let spec = ActionSpec { form: ActionForm::Continuous, ..spec };
    /// let mut action = vec![0.0_f32; spec.space().size()];
    /// action[1] = 1e30;
    /// let e = spec.decode(&action).unwrap_err();
    /// assert!(e.to_string().contains("entry 1 = 1e30 is outside [-1, 1]"), "{e}");
    /// ```
    pub fn decode(&self, action: &[f32]) -> ReLMoGenResult<Subgoal> {
        let want = self.space().size();
        if action.len() != want {
            return Err(ReLMoGenError::BadAction(format!(
                "expected {want} values, got {}",
                action.len()
            )));
        }
        if let Some(bad) = action.iter().find(|a| !a.is_finite()) {
            return Err(ReLMoGenError::BadAction(format!("non-finite entry {bad}")));
        }
        match self.form {
            ActionForm::Continuous => {
                if let Some((k, x)) = action.iter().enumerate().find(|(_, x)| x.abs() > 1.0) {
                    return Err(ReLMoGenError::BadAction(format!(
                        "entry {k} = {} is outside [-1, 1]",
                        Num(*x)
                    )));
                }
                let a: [f64; CONTINUOUS_LEN] = std::array::from_fn(|k| f64::from(action[k]));
                let unit = |x: f64| (x + 1.0) * 0.5;
                if a[0] > 0.0 {
                    Ok(Subgoal::Arm {
                        u: (unit(a[4]) * f64::from(self.width - 1)).round() as u32,
                        v: (unit(a[5]) * f64::from(self.height - 1)).round() as u32,
                        direction: if a[7] > 0.0 {
                            PushDirection::AgainstNormal
                        } else {
                            PushDirection::Horizontal(a[6] * PI)
                        },
                    })
                } else {
                    Ok(Subgoal::Base {
                        bearing: a[1] * PI,
                        distance: unit(a[2]) * self.max_base_distance,
                        yaw: a[3] * PI,
                    })
                }
            }
            ActionForm::Discrete => {
                let x = f64::from(action[0]);
                let top = 2 * self.map_size();
                if x.fract() != 0.0 || x < 0.0 || x >= top as f64 {
                    return Err(ReLMoGenError::BadAction(format!(
                        "index {x} is not an integer in [0, {})",
                        top
                    )));
                }
                let i = x as usize;
                let (map, cell) = (i / self.map_size(), i % self.map_size());
                let bin = cell % self.bins;
                let pixel = cell / self.bins;
                let mw = (self.width / 4) as usize;
                let (row, col) = ((pixel / mw) as u32, (pixel % mw) as u32);
                let (u, v) = (4 * col + 2, 4 * row + 2);
                if map == 0 {
                    Ok(Subgoal::BaseAtPixel {
                        u,
                        v,
                        yaw: wrap_angle(TAU * bin as f64 / self.bins as f64),
                    })
                } else {
                    let direction = if bin == 0 {
                        PushDirection::AgainstNormal
                    } else {
                        PushDirection::Horizontal(wrap_angle(TAU * (bin - 1) as f64 / (self.bins - 1) as f64))
                    };
                    Ok(Subgoal::Arm { u, v, direction })
                }
            }
        }
    }
}
