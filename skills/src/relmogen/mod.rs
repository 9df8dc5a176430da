//! ReLMoGen (Xia et al., 2021): reinforcement learning over motion-generator subgoals. A
//! policy picks, at each step, the base or the arm and a subgoal — a base pose to navigate to,
//! or a pixel of the head camera to push — and the skills plan and execute it
//! ([`crate::navigate()`], [`crate::push`]). [`ReLMoGenEnv`] wraps a
//! [`hearth_sim::env::Env`] (`push_drawer`, `push_cabinet`, `interactive_nav` with the Fetch)
//! this way; [`ReLMoGenVecEnv`] steps many on rayon's threads; [`PushDataset`] records where
//! pushes succeed, for supervised score maps. `docs/relmogen.md` has the action layouts, info
//! fields, config keys and dataset format.
//!
//! ```
//! use hearth_skills::relmogen::{ActionForm, ActionSpec, PushDirection, Subgoal};
//! let spec = ActionSpec { form: ActionForm::Continuous, width: 64, height: 64, bins: 8, max_base_distance: 2.0 };
//! let s = spec.decode(&[-1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
//! assert_eq!(s, Subgoal::Base { bearing: 0.0, distance: 2.0, yaw: 0.0 });
//! // An arm subgoal at the image centre, pushing straight into the surface seen there.
//! let s = spec.decode(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]).unwrap();
//! assert_eq!(s, Subgoal::Arm { u: 32, v: 32, direction: PushDirection::AgainstNormal });
//! let s = spec.decode(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, -1.0]).unwrap();
//! assert_eq!(s, Subgoal::Arm { u: 32, v: 32, direction: PushDirection::Horizontal(std::f64::consts::FRAC_PI_2) });
//! ```

mod action;
mod config;
mod dataset;
mod env;
mod vector;

pub use action::{ActionSpec, PushDirection, Subgoal};
pub use config::{ActionForm, PushSection, ReLMoGenConfig, ReLMoGenError, ReLMoGenResult};
pub use dataset::{
    DatasetSettings, DatasetSummary, Location, LocationIndex, Progress, PushDataset, PushRecord, UNTRIED, location_dir,
    read_mask,
};
pub use env::{ReLMoGenEnv, ReLMoGenInfo, ReLMoGenStep};
pub use vector::{ReLMoGenVecEnv, ReLMoGenVecStep};
