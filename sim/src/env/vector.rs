//! [`VecEnv`]: N environments stepped in one process across threads, with auto-reset and
//! batched observations.

use rayon::prelude::*;

use super::config::EnvConfig;
use super::environment::{Env, Info, Step};
use super::error::{EnvError, EnvResult};
use super::spaces::{Obs, ObsData};

/// Observations of all envs, batched per name (env-major: env 0's values first).
///
/// ```
/// use hearth_sim::env::{BatchedObs, Obs, ObsData};
/// let obs = Obs { entries: vec![("bump".into(), ObsData::U8(vec![1]))] };
/// let batch = BatchedObs::stack(&[obs.clone(), obs]);
/// assert_eq!(batch.entries.len(), 1);
/// assert_eq!(batch.get("bump").unwrap().len(), 2);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BatchedObs {
    /// (name, values of every env concatenated) pairs.
    pub entries: Vec<(String, ObsData)>,
}

impl BatchedObs {
    /// Stacks the observations of several envs (same spaces, env-major), as [`VecEnv`] returns
    /// them; other vectorised envs use it too.
    ///
    /// ```
    /// use hearth_sim::env::{BatchedObs, Obs, ObsData};
    /// let one = |x: f32| Obs { entries: vec![("task_obs".into(), ObsData::F32(vec![x, x]))] };
    /// let b = BatchedObs::stack(&[one(1.0), one(2.0)]);
    /// assert_eq!(b.get("task_obs"), Some(&ObsData::F32(vec![1.0, 1.0, 2.0, 2.0])));
    /// ```
    pub fn stack(obs: &[Obs]) -> Self {
        let Some(first) = obs.first() else {
            return Self::default();
        };
        let entries = first
            .entries
            .iter()
            .enumerate()
            .map(|(k, (name, data))| {
                let mut all = data.empty_like(data.len() * obs.len());
                for o in obs {
                    all.extend_from(&o.entries[k].1);
                }
                (name.clone(), all)
            })
            .collect();
        Self { entries }
    }

    /// The batch of observation `name`.
    ///
    /// ```
    /// # use hearth_sim::env::{BatchedObs, ObsData};
    /// let batch = BatchedObs { entries: vec![("task_obs".into(), ObsData::F32(vec![0.0; 8]))] };
    /// assert_eq!(batch.get("task_obs").map(ObsData::len), Some(8));
    /// assert!(batch.get("rgb").is_none());
    /// ```
    pub fn get(&self, name: &str) -> Option<&ObsData> {
        self.entries.iter().find(|(n, _)| n == name).map(|(_, d)| d)
    }
}

/// The result of [`VecEnv::step`].
///
/// ```
/// # use hearth_sim::env::{EnvConfig, VecEnv};
/// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
/// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
/// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
/// # let path = std::env::temp_dir().join("hearth_sim_doc_vecstep.json");
/// # let written_file = path.clone();
/// # std::fs::write(&path, hall).unwrap();
/// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
///     "[sensors]\nmodalities = [\"task_obs\"]\n");
/// let mut config = EnvConfig::from_toml(toml)?;
/// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
/// let mut envs = VecEnv::new(&config, 2)?;
/// envs.reset(0)?;
/// let step = envs.step(&[1.0, 0.0, 0.0, 0.0])?;
/// assert_eq!(step.rewards.len(), 2);
/// assert!(step.infos[0].metrics.path_length > step.infos[1].metrics.path_length, "only env 0 drove");
/// assert_eq!(step.infos.len(), 2);
/// # std::fs::remove_file(&written_file).ok();
/// # Ok::<(), hearth_sim::env::EnvError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct VecStep {
    /// Observations (after auto-reset for envs whose episode ended).
    pub obs: BatchedObs,
    /// Rewards.
    pub rewards: Vec<f64>,
    /// Terminated flags.
    pub terminated: Vec<bool>,
    /// Truncated flags.
    pub truncated: Vec<bool>,
    /// Per env: the step's info (for an env that ended, the final metrics of its episode).
    pub infos: Vec<Info>,
}

/// N envs of one configuration, stepped in parallel (rayon); an env whose episode ends is reset
/// at once with the next seed of its sequence, and its returned observation is the new
/// episode's first (Gymnasium's same-step auto-reset).
///
/// ```no_run
/// use hearth_sim::env::{EnvConfig, VecEnv};
/// let config = EnvConfig::from_toml("[task]\nname = \"point_nav_random\"\n")?;
/// let mut envs = VecEnv::new(&config, 4)?;
/// envs.reset(0)?;
/// let step = envs.step(&[[0.5, 0.0]; 4].concat())?;
/// assert_eq!(step.rewards.len(), 4);
/// # Ok::<(), hearth_sim::env::EnvError>(())
/// ```
pub struct VecEnv {
    envs: Vec<Env>,
    episodes: Vec<u64>,
    base_seed: u64,
}

impl VecEnv {
    /// Builds `n` envs (in parallel).
    ///
    /// # Errors
    /// As [`Env::new`]; [`EnvError::Config`] for `n == 0`.
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, VecEnv};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_vec_new.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let envs = VecEnv::new(&config, 2)?;
    /// assert_eq!(envs.len(), 2);
    /// assert!(VecEnv::new(&config, 0).is_err());
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn new(config: &EnvConfig, n: usize) -> EnvResult<Self> {
        if n == 0 {
            return Err(EnvError::Config {
                key: "envs".into(),
                reason: "must be at least 1".into(),
            });
        }
        let envs = (0..n)
            .into_par_iter()
            .map(|i| {
                // Each env draws its own randomisation sequence.
                let mut config = config.clone();
                config.randomization.seed = config.randomization.seed.wrapping_add(i as u64);
                Env::new(config)
            })
            .collect::<EnvResult<Vec<_>>>()?;
        Ok(Self {
            envs,
            episodes: vec![0; n],
            base_seed: 0,
        })
    }

    /// Number of envs.
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, VecEnv};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_vec_len.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// assert_eq!(VecEnv::new(&config, 1)?.len(), 1);
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn len(&self) -> usize {
        self.envs.len()
    }

    /// Whether there are no envs (never: `new` refuses 0).
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, VecEnv};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_vec_empty.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// assert!(!VecEnv::new(&config, 1)?.is_empty());
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn is_empty(&self) -> bool {
        self.envs.is_empty()
    }

    /// The envs.
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, VecEnv};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_vec_envs.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let envs = VecEnv::new(&config, 2)?;
    /// assert!(envs.envs().iter().all(|e| e.config().task.name == "point_nav_fixed"));
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn envs(&self) -> &[Env] {
        &self.envs
    }

    fn seed_of(&self, env: usize) -> u64 {
        // Distinct, reproducible seeds per env and episode.
        self.base_seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add((env as u64) << 32)
            .wrapping_add(self.episodes[env])
    }

    /// Resets every env (env `i`'s episodes get seeds derived from `seed`, `i` and the episode
    /// count).
    ///
    /// # Errors
    /// The first env error.
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, VecEnv};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_vec_reset.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// let mut envs = VecEnv::new(&config, 2)?;
    /// let obs = envs.reset(3)?;
    /// assert_eq!(obs.get("task_obs").unwrap().len(), 2 * envs.envs()[0].observation_spaces()[0].size());
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn reset(&mut self, seed: u64) -> EnvResult<BatchedObs> {
        self.base_seed = seed;
        self.episodes.iter_mut().for_each(|e| *e = 0);
        let seeds: Vec<u64> = (0..self.envs.len()).map(|i| self.seed_of(i)).collect();
        let obs = self
            .envs
            .par_iter_mut()
            .zip(seeds)
            .map(|(env, s)| env.reset(s).map(|(o, _)| o))
            .collect::<EnvResult<Vec<_>>>()?;
        Ok(BatchedObs::stack(&obs))
    }

    /// Steps every env with its slice of `actions` (the action space's size per env,
    /// env-major).
    ///
    /// # Errors
    /// [`EnvError::BadAction`] for a wrong total length (nothing is stepped), or the first env
    /// error.
    ///
    /// ```
    /// # use hearth_sim::env::{EnvConfig, VecEnv};
    /// # let hall = r#"{"name": "hall", "building": {"rooms": [{"name": "hall", "room_type": "corridor",
    /// #     "polygon": [[0, 0], [6, 0], [6, 2], [0, 2]]}]},
    /// #   "robot": {"name": "turtlebot", "position": [1, 1, 0], "yaw": 0}}"#;
    /// # let path = std::env::temp_dir().join("hearth_sim_doc_vec_step.json");
    /// # let written_file = path.clone();
    /// # std::fs::write(&path, hall).unwrap();
    /// let toml = concat!("[task]\nname = \"point_nav_fixed\"\nstart = [1, 1, 0]\ngoal = [4, 1]\n",
    ///     "[sensors]\nmodalities = [\"task_obs\"]\n");
    /// let mut config = EnvConfig::from_toml(toml)?;
    /// config.scene.file = Some(path); // a bare 6 m × 2 m hall with a turtlebot
    /// config.episode.max_steps = 1;
    /// let mut envs = VecEnv::new(&config, 1)?;
    /// envs.reset(0)?;
    /// assert!(envs.step(&[0.0]).is_err(), "2 values per env");
    /// let step = envs.step(&[0.0, 0.0])?;
    /// assert_eq!(step.truncated, [true]); // and env 0 was reset at once
    /// assert_eq!(step.infos[0].metrics.episode_length, 1);
    /// # std::fs::remove_file(&written_file).ok();
    /// # Ok::<(), hearth_sim::env::EnvError>(())
    /// ```
    pub fn step(&mut self, actions: &[f32]) -> EnvResult<VecStep> {
        let n = self.envs.len();
        let per = self.envs[0].action_space().size();
        if actions.len() != per * n {
            return Err(EnvError::BadAction(format!(
                "expected {} values ({per} per env), got {}",
                per * n,
                actions.len()
            )));
        }
        if let Some(bad) = actions.iter().find(|a| !a.is_finite()) {
            return Err(EnvError::BadAction(format!("non-finite entry {bad}")));
        }
        let next_seeds: Vec<u64> = (0..n)
            .map(|i| {
                self.episodes[i] += 1;
                let s = self.seed_of(i);
                self.episodes[i] -= 1;
                s
            })
            .collect();
        let results = self
            .envs
            .par_iter_mut()
            .zip(actions.par_chunks(per))
            .zip(next_seeds)
            .map(|((env, a), next)| -> EnvResult<(Step, bool)> {
                let mut step = env.step(a)?;
                let done = step.terminated || step.truncated;
                if done {
                    step.obs = env.reset(next)?.0;
                }
                Ok((step, done))
            })
            .collect::<EnvResult<Vec<_>>>()?;
        let mut out = VecStep {
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
