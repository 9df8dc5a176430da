//! [`ReLMoGenVecEnv`]: N ReLMoGen envs stepped in parallel with auto-reset.

use hearth_sim::env::BatchedObs;
use rayon::prelude::*;

use super::config::{ReLMoGenConfig, ReLMoGenError, ReLMoGenResult, bad};
use super::env::{ReLMoGenEnv, ReLMoGenInfo, ReLMoGenStep};

/// The result of [`ReLMoGenVecEnv::step`].
///
/// ```no_run
/// # fn f(step: hearth_skills::relmogen::ReLMoGenVecStep) {
/// let failed = step.infos.iter().filter(|i| !i.planner_success).count();
/// println!("{failed} of {} subgoals failed", step.rewards.len());
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ReLMoGenVecStep {
    /// Observations (after auto-reset for envs whose episode ended), batched env-major.
    pub obs: BatchedObs,
    /// Rewards.
    pub rewards: Vec<f64>,
    /// Terminated flags.
    pub terminated: Vec<bool>,
    /// Truncated flags.
    pub truncated: Vec<bool>,
    /// Per env: the step's info (for an env that ended, its finished episode's).
    pub infos: Vec<ReLMoGenInfo>,
}

/// N [`ReLMoGenEnv`]s of one configuration, stepped on rayon's threads; an env whose episode
/// ends is reset at once with the next seed of its sequence (its returned observation is the
/// new episode's first), as [`hearth_sim::env::VecEnv`] does.
///
/// ```no_run
/// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
/// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
/// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
/// envs.reset(0)?;
/// let step = envs.step(&[[-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]; 2].concat())?;
/// assert_eq!(step.rewards.len(), 2);
/// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
/// ```
pub struct ReLMoGenVecEnv {
    envs: Vec<ReLMoGenEnv>,
    episodes: Vec<u64>,
    base_seed: u64,
}

impl ReLMoGenVecEnv {
    /// Builds `n` envs (in parallel).
    ///
    /// # Errors
    /// As [`ReLMoGenEnv::new`]; [`ReLMoGenError::Config`] for `n == 0`.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
    /// assert!(ReLMoGenVecEnv::new(&config, 0).is_err());
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn new(config: &ReLMoGenConfig, n: usize) -> ReLMoGenResult<Self> {
        if n == 0 {
            return Err(bad("envs", "must be at least 1"));
        }
        let envs = (0..n)
            .into_par_iter()
            .map(|_| ReLMoGenEnv::new(config.clone()))
            .collect::<ReLMoGenResult<Vec<_>>>()?;
        Ok(Self {
            envs,
            episodes: vec![0; n],
            base_seed: 0,
        })
    }

    /// Number of envs.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
    /// assert_eq!(envs.len(), 2);
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn len(&self) -> usize {
        self.envs.len()
    }

    /// Whether there are no envs (never: `new` refuses 0).
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
    /// assert!(!envs.is_empty());
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn is_empty(&self) -> bool {
        self.envs.is_empty()
    }

    /// The envs.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
    /// assert_eq!(envs.envs().len(), 2);
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn envs(&self) -> &[ReLMoGenEnv] {
        &self.envs
    }

    fn seed_of(&self, env: usize, episode: u64) -> u64 {
        self.base_seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add((env as u64) << 32)
            .wrapping_add(episode)
    }

    /// Resets every env (env `i`'s episodes get seeds derived from `seed`, `i` and the episode
    /// count).
    ///
    /// # Errors
    /// The first env error.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
    /// let obs = envs.reset(7)?;
    /// assert!(obs.get("task_obs").is_some());
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn reset(&mut self, seed: u64) -> ReLMoGenResult<BatchedObs> {
        self.base_seed = seed;
        self.episodes.iter_mut().for_each(|e| *e = 0);
        let seeds: Vec<u64> = (0..self.envs.len()).map(|i| self.seed_of(i, 0)).collect();
        let obs = self
            .envs
            .par_iter_mut()
            .zip(seeds)
            .map(|(env, s)| env.reset(s).map(|(o, _)| o))
            .collect::<ReLMoGenResult<Vec<_>>>()?;
        Ok(BatchedObs::stack(&obs))
    }

    /// Steps every env with its slice of `actions` (the action space's size per env,
    /// env-major).
    ///
    /// # Errors
    /// [`ReLMoGenError::BadAction`] for a wrong total length or any action an env would
    /// refuse (nothing is stepped), or the first env error.
    /// ```no_run
    /// use hearth_skills::relmogen::{ReLMoGenConfig, ReLMoGenVecEnv};
    /// let config = ReLMoGenConfig::load("examples/configs/relmogen_push_drawer.toml".as_ref())?;
    /// let mut envs = ReLMoGenVecEnv::new(&config, 2)?;
    /// envs.reset(0)?;
    /// let step = envs.step(&[0.0, 100.0])?;
    /// assert_eq!(step.infos.len(), 2);
    /// # Ok::<(), hearth_skills::relmogen::ReLMoGenError>(())
    /// ```
    pub fn step(&mut self, actions: &[f32]) -> ReLMoGenResult<ReLMoGenVecStep> {
        let n = self.envs.len();
        let per = self.envs[0].action_space().size();
        if actions.len() != per * n {
            return Err(ReLMoGenError::BadAction(format!(
                "expected {} values ({per} per env), got {}",
                per * n,
                actions.len()
            )));
        }
        for (i, a) in actions.chunks(per).enumerate() {
            self.envs[i]
                .action_spec()
                .decode(a)
                .map_err(|e| ReLMoGenError::BadAction(format!("env {i}: {e}")))?;
        }
        let next: Vec<u64> = (0..n).map(|i| self.seed_of(i, self.episodes[i] + 1)).collect();
        let results = self
            .envs
            .par_iter_mut()
            .zip(actions.par_chunks(per))
            .zip(next)
            .map(|((env, a), next)| -> ReLMoGenResult<(ReLMoGenStep, bool)> {
                let mut step = env.step(a)?;
                let done = step.terminated || step.truncated;
                if done {
                    step.obs = env.reset(next)?.0;
                }
                Ok((step, done))
            })
            .collect::<ReLMoGenResult<Vec<_>>>()?;
        let mut out = ReLMoGenVecStep {
            obs: BatchedObs::default(),
            rewards: Vec::with_capacity(n),
            terminated: Vec::with_capacity(n),
            truncated: Vec::with_capacity(n),
            infos: Vec::with_capacity(n),
        };
        let mut obs = Vec::with_capacity(n);
        for (i, (step, done)) in results.into_iter().enumerate() {
            if done {
                self.episodes[i] += 1;
            }
            out.rewards.push(step.reward);
            out.terminated.push(step.terminated);
            out.truncated.push(step.truncated);
            out.infos.push(step.info);
            obs.push(step.obs);
        }
        out.obs = BatchedObs::stack(&obs);
        Ok(out)
    }
}
