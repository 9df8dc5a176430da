//! The self-collision matrix: which link pairs need checking at all.
//!
//! As MoveIt's setup assistant does, a pair is disabled when the links are adjacent in the
//! tree (or joined only through links without geometry), collide in the neutral
//! configuration, collide in nearly every sampled configuration (`always`), or never collide
//! in any of N sampled configurations (`never`). Computed once and cacheable to a JSON file
//! that records the model's fingerprint, so a stale cache is refused.

use std::path::Path;

use nalgebra::Isometry3;
use rand::SeedableRng;

use crate::convert::to_pose;
use crate::error::{KinematicsError, Result};
use crate::model::RobotModel;

/// Why a pair is not checked.
///
/// ```
/// use hearth_kinematics::{DisabledReason, RobotModel, SelfCollisionMatrix};
/// let panda = RobotModel::builtin("panda").unwrap();
/// let m = SelfCollisionMatrix::adjacent_only(&panda);
/// let (l3, l4) = (panda.link_index("panda_link3").unwrap(), panda.link_index("panda_link4").unwrap());
/// assert_eq!(m.reason(l3, l4), Some(DisabledReason::Adjacent));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DisabledReason {
    /// Joined by a joint (or through links without geometry).
    Adjacent,
    /// In collision in the neutral configuration.
    Default,
    /// In collision in (nearly) every sample.
    Always,
    /// Never in collision in any sample.
    Never,
}

/// Settings for [`SelfCollisionMatrix::compute`].
///
/// ```
/// use hearth_kinematics::SelfCollisionSettings;
/// let quick = SelfCollisionSettings { samples: 100, ..Default::default() };
/// assert_eq!((quick.samples, quick.seed), (100, 0));
/// assert_eq!(SelfCollisionSettings::default().samples, 10_000);
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SelfCollisionSettings {
    /// Random configurations sampled. With 0, only adjacent pairs and pairs touching in the
    /// neutral configuration are disabled: no pair is called `never` without a sample.
    pub samples: usize,
    /// A pair colliding in at least this fraction of samples is `always` disabled.
    pub always_fraction: f64,
    /// RNG seed (the matrix is a pure function of model, settings and seed).
    pub seed: u64,
}

impl Default for SelfCollisionSettings {
    fn default() -> Self {
        Self {
            samples: 10_000,
            always_fraction: 0.95,
            seed: 0,
        }
    }
}

/// Link pairs to check for self-collision, and why the others are skipped.
///
/// ```
/// use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
/// let panda = RobotModel::builtin("panda").unwrap();
/// let m = SelfCollisionMatrix::compute(&panda, &SelfCollisionSettings { samples: 200, ..Default::default() });
/// let l0 = panda.link_index("panda_link0").unwrap();
/// let l1 = panda.link_index("panda_link1").unwrap();
/// assert!(m.is_disabled(l0, l1)); // adjacent
/// let mut poses = panda.pose_buffer();
/// panda.fk(&panda.neutral_configuration(), &mut poses).unwrap();
/// assert_eq!(m.first_collision(&panda, &poses), None);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SelfCollisionMatrix {
    fingerprint: u64,
    n: usize,
    disabled: Vec<Option<DisabledReason>>,
    checked: Vec<(usize, usize)>,
    names: Vec<String>,
}

#[derive(serde::Serialize, serde::Deserialize)]
struct CacheFile {
    robot: String,
    fingerprint: String,
    settings: SelfCollisionSettings,
    disabled: Vec<(String, String, DisabledReason)>,
}

impl SelfCollisionMatrix {
    /// Only adjacent pairs disabled (no sampling).
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let (l1, l5) = (panda.link_index("panda_link1").unwrap(), panda.link_index("panda_link5").unwrap());
    /// assert!(m.is_disabled(l1, l1 + 1) && !m.is_disabled(l1, l5));
    /// ```
    pub fn adjacent_only(model: &RobotModel) -> Self {
        let mut m = Self::empty(model);
        m.mark_adjacent(model);
        m.finish();
        m
    }

    /// Computes the matrix by sampling (deterministic for given settings).
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let settings = SelfCollisionSettings { samples: 50, ..Default::default() };
    /// let m = SelfCollisionMatrix::compute(&panda, &settings);
    /// assert_eq!(m, SelfCollisionMatrix::compute(&panda, &settings)); // deterministic
    /// assert!(m.checked_pairs().len() < SelfCollisionMatrix::adjacent_only(&panda).checked_pairs().len());
    /// ```
    pub fn compute(model: &RobotModel, settings: &SelfCollisionSettings) -> Self {
        let mut m = Self::empty(model);
        m.mark_adjacent(model);
        let geo: Vec<usize> = (0..m.n).filter(|&l| model.link_shape(l).is_some()).collect();
        let mut poses = model.pose_buffer();
        let pairs: Vec<(usize, usize)> = geo
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| geo[i + 1..].iter().map(move |&b| (a, b)))
            .filter(|&(a, b)| m.disabled[a * m.n + b].is_none())
            .collect();
        // Neutral configuration.
        let q0 = model.neutral_configuration();
        if model.fk(&q0, &mut poses).is_ok() {
            for &(a, b) in &pairs {
                if links_touch(model, &poses, a, b) {
                    m.set(a, b, DisabledReason::Default);
                }
            }
        }
        let pairs: Vec<(usize, usize)> = pairs
            .into_iter()
            .filter(|&(a, b)| m.disabled[a * m.n + b].is_none())
            .collect();
        let mut hits = vec![0usize; pairs.len()];
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(settings.seed);
        let mut q = q0;
        // Samples whose forward kinematics succeeded: the evidence for `Never` and `Always`.
        let mut sampled = 0usize;
        for _ in 0..settings.samples {
            model.random_configuration(&mut rng, &mut q);
            if model.fk(&q, &mut poses).is_err() {
                continue;
            }
            sampled += 1;
            for (k, &(a, b)) in pairs.iter().enumerate() {
                if links_touch(model, &poses, a, b) {
                    hits[k] += 1;
                }
            }
        }
        // Without a single sample, no pair has been seen apart (or together): none is `Never`.
        for (k, &(a, b)) in pairs.iter().enumerate().filter(|_| sampled > 0) {
            if hits[k] == 0 {
                m.set(a, b, DisabledReason::Never);
            } else if hits[k] as f64 >= settings.always_fraction * sampled as f64 {
                m.set(a, b, DisabledReason::Always);
            }
        }
        m.finish();
        m
    }

    fn empty(model: &RobotModel) -> Self {
        let n = model.links().len();
        Self {
            fingerprint: model.fingerprint(),
            n,
            disabled: vec![None; n * n],
            checked: Vec::new(),
            names: model.links().iter().map(|l| l.name.clone()).collect(),
        }
    }

    fn set(&mut self, a: usize, b: usize, why: DisabledReason) {
        self.disabled[a * self.n + b] = Some(why);
        self.disabled[b * self.n + a] = Some(why);
    }

    fn mark_adjacent(&mut self, model: &RobotModel) {
        // Nearest ancestor that has geometry, for every link.
        for l in 0..self.n {
            let mut cur = l;
            while let Some(j) = model.links()[cur].parent_joint {
                let p = model.joints()[j].parent;
                if cur == l || model.link_shape(cur).is_none() {
                    self.set(l, p, DisabledReason::Adjacent);
                }
                if model.link_shape(p).is_some() {
                    break;
                }
                cur = p;
            }
        }
        // Links whose only connection runs through geometry-free links are adjacent, too:
        // siblings hanging off the same geometry-free parent.
        for j in model.joints() {
            if model.link_shape(j.parent).is_none() {
                for k in model.joints() {
                    if k.parent == j.parent && k.child != j.child {
                        self.set(j.child, k.child, DisabledReason::Adjacent);
                    }
                }
            }
        }
    }

    fn finish(&mut self) {
        self.checked.clear();
        for a in 0..self.n {
            for b in a + 1..self.n {
                if self.disabled[a * self.n + b].is_none() {
                    self.checked.push((a, b));
                }
            }
        }
    }

    /// Whether the pair is skipped.
    ///
    /// An index that is not a link of the matrix's model (`>= links().len()`) is never part of
    /// a disabled pair: the answer is then `false`, even for `a == b`.
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let (l0, l1) = (panda.link_index("panda_link0").unwrap(), panda.link_index("panda_link1").unwrap());
    /// assert!(m.is_disabled(l0, l1) && m.is_disabled(l1, l0));
    /// assert!(m.is_disabled(l0, l0)); // a link never collides with itself
    /// let n = panda.links().len();
    /// assert!(!m.is_disabled(l0, n) && !m.is_disabled(n, n)); // not a link
    /// ```
    pub fn is_disabled(&self, a: usize, b: usize) -> bool {
        // One comparison bounds both indices, so `a * n + b` cannot reach another pair's entry.
        a.max(b) < self.n && (a == b || self.disabled.get(a * self.n + b).is_some_and(Option::is_some))
    }

    /// Why the pair is skipped, if it is; `None` when either index is not a link of the
    /// matrix's model.
    ///
    /// ```
    /// use hearth_kinematics::{DisabledReason, RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let mut m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let (l0, l6) = (panda.link_index("panda_link0").unwrap(), panda.link_index("panda_link6").unwrap());
    /// assert_eq!(m.reason(l0, l6), None);
    /// m.disable(l0, l6, DisabledReason::Never);
    /// assert_eq!(m.reason(l6, l0), Some(DisabledReason::Never));
    /// assert_eq!(m.reason(l0, panda.links().len()), None); // not a link
    /// ```
    pub fn reason(&self, a: usize, b: usize) -> Option<DisabledReason> {
        if a.max(b) >= self.n {
            return None;
        }
        self.disabled.get(a * self.n + b).copied().flatten()
    }

    /// Pairs that are not disabled, `a < b`. Links without collision geometry are not
    /// filtered out here (see [`SelfCollisionMatrix::checked_geometric_pairs`]).
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let pairs = m.checked_pairs();
    /// assert!(pairs.iter().all(|&(a, b)| a < b && !m.is_disabled(a, b)));
    /// ```
    pub fn checked_pairs(&self) -> Vec<(usize, usize)> {
        self.checked.clone()
    }

    /// Pairs that need checking, restricted to links with geometry in `model`.
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let geometric = m.checked_geometric_pairs(&panda);
    /// let tcp = panda.link_index("panda_hand_tcp").unwrap(); // a frame without geometry
    /// assert!(m.checked_pairs().iter().any(|&(a, b)| a == tcp || b == tcp));
    /// assert!(geometric.iter().all(|&(a, b)| a != tcp && b != tcp));
    /// ```
    pub fn checked_geometric_pairs(&self, model: &RobotModel) -> Vec<(usize, usize)> {
        self.checked
            .iter()
            .copied()
            .filter(|&(a, b)| model.link_shape(a).is_some() && model.link_shape(b).is_some())
            .collect()
    }

    /// Marks a pair as never checked (e.g. from a benchmark's allowed-collision list).
    ///
    /// A no-op when `a == b` (a link is never checked against itself) or when either index is
    /// not a link of the matrix's model.
    ///
    /// ```
    /// use hearth_kinematics::{DisabledReason, RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let mut m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let (l0, l6) = (panda.link_index("panda_link0").unwrap(), panda.link_index("panda_link6").unwrap());
    /// let before = m.checked_pairs().len();
    /// m.disable(l0, l6, DisabledReason::Never);
    /// assert!(m.is_disabled(l0, l6));
    /// assert_eq!(m.checked_pairs().len(), before - 1);
    /// let unchanged = m.clone();
    /// m.disable(l0, panda.links().len(), DisabledReason::Never); // not a link: no-op
    /// assert_eq!(m, unchanged);
    /// ```
    pub fn disable(&mut self, a: usize, b: usize, why: DisabledReason) {
        if a < self.n && b < self.n && a != b {
            self.set(a, b, why);
            self.finish();
        }
    }

    /// The first checked pair in collision for these link poses, if any.
    ///
    /// ```
    /// use hearth_kinematics::{Chain, RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let mut q = panda.neutral_configuration();
    /// let mut poses = panda.pose_buffer();
    /// // Fold the elbow and wrist so that the hand comes back against the upper arm.
    /// Chain::named(&panda, "arm").unwrap().scatter(&[0.0, 1.7, 0.0, -3.0, 0.0, 3.7, 0.0], &mut q);
    /// panda.fk(&q, &mut poses).unwrap();
    /// assert!(m.first_collision(&panda, &poses).is_some());
    /// ```
    pub fn first_collision(&self, model: &RobotModel, poses: &[Isometry3<f64>]) -> Option<(usize, usize)> {
        self.checked
            .iter()
            .copied()
            .find(|&(a, b)| links_touch(model, poses, a, b))
    }

    /// Writes the matrix as JSON.
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let json = SelfCollisionMatrix::adjacent_only(&panda).to_json(&panda, &SelfCollisionSettings::default());
    /// assert!(json.contains("\"robot\": \"panda\"") && json.contains("adjacent"));
    /// ```
    pub fn to_json(&self, model: &RobotModel, settings: &SelfCollisionSettings) -> String {
        let mut disabled = Vec::new();
        for a in 0..self.n {
            for b in a + 1..self.n {
                if let Some(why) = self.disabled[a * self.n + b] {
                    disabled.push((self.names[a].clone(), self.names[b].clone(), why));
                }
            }
        }
        let file = CacheFile {
            robot: model.name().to_owned(),
            fingerprint: format!("{:016x}", self.fingerprint),
            settings: settings.clone(),
            disabled,
        };
        serde_json::to_string_pretty(&file).unwrap_or_default()
    }

    /// Reads a matrix written by [`SelfCollisionMatrix::to_json`], refusing one computed for
    /// a different model.
    ///
    /// ```
    /// use hearth_kinematics::{KinematicsError, RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// let json = m.to_json(&panda, &SelfCollisionSettings::default());
    /// assert_eq!(SelfCollisionMatrix::from_json(&json, &panda, "mem").unwrap(), m);
    /// let locobot = RobotModel::builtin("locobot").unwrap();
    /// let stale = SelfCollisionMatrix::from_json(&json, &locobot, "mem");
    /// assert!(matches!(stale, Err(KinematicsError::StaleCache { .. })));
    /// ```
    pub fn from_json(text: &str, model: &RobotModel, source_name: &str) -> Result<Self> {
        let file: CacheFile = serde_json::from_str(text).map_err(|e| KinematicsError::BadCache {
            source_name: source_name.to_owned(),
            message: e.to_string(),
        })?;
        let expected = format!("{:016x}", model.fingerprint());
        if file.fingerprint != expected {
            return Err(KinematicsError::StaleCache {
                source_name: source_name.to_owned(),
                found: file.fingerprint,
                expected,
            });
        }
        let mut m = Self::empty(model);
        for (a, b, why) in file.disabled {
            let a = model.link_index(&a)?;
            let b = model.link_index(&b)?;
            m.set(a, b, why);
        }
        m.finish();
        Ok(m)
    }

    /// Saves to a file.
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let path = std::env::temp_dir().join("hearth_doc_scm_save.json");
    /// let m = SelfCollisionMatrix::adjacent_only(&panda);
    /// m.save(&path, &panda, &SelfCollisionSettings::default()).unwrap();
    /// assert_eq!(SelfCollisionMatrix::load(&path, &panda).unwrap(), m);
    /// ```
    pub fn save(&self, path: &Path, model: &RobotModel, settings: &SelfCollisionSettings) -> Result<()> {
        std::fs::write(path, self.to_json(model, settings)).map_err(|error| KinematicsError::Io {
            path: path.to_path_buf(),
            error,
        })
    }

    /// Loads from a file.
    ///
    /// ```
    /// use hearth_kinematics::{KinematicsError, RobotModel, SelfCollisionMatrix};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let path = std::env::temp_dir().join("hearth_doc_scm_load.json");
    /// std::fs::write(&path, "not json").unwrap();
    /// let err = SelfCollisionMatrix::load(&path, &panda).unwrap_err();
    /// assert!(matches!(err, KinematicsError::BadCache { .. }));
    /// assert!(SelfCollisionMatrix::load(std::path::Path::new("/no/such/file.json"), &panda).is_err());
    /// ```
    pub fn load(path: &Path, model: &RobotModel) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|error| KinematicsError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Self::from_json(&text, model, &path.display().to_string())
    }

    /// Loads from `path` if it holds a matrix for this model, otherwise computes one and
    /// writes it there.
    ///
    /// ```
    /// use hearth_kinematics::{RobotModel, SelfCollisionMatrix, SelfCollisionSettings};
    /// let panda = RobotModel::builtin("panda").unwrap();
    /// let path = std::env::temp_dir().join(format!("hearth_doc_scm_{}.json", std::process::id()));
    /// let settings = SelfCollisionSettings { samples: 20, ..Default::default() };
    /// let computed = SelfCollisionMatrix::load_or_compute(&path, &panda, &settings).unwrap();
    /// assert!(path.is_file()); // written for next time
    /// assert_eq!(SelfCollisionMatrix::load_or_compute(&path, &panda, &settings).unwrap(), computed);
    /// # std::fs::remove_file(&path).unwrap();
    /// ```
    pub fn load_or_compute(path: &Path, model: &RobotModel, settings: &SelfCollisionSettings) -> Result<Self> {
        if let Ok(m) = Self::load(path, model) {
            return Ok(m);
        }
        let m = Self::compute(model, settings);
        m.save(path, model, settings)?;
        Ok(m)
    }
}

/// Whether the collision shapes of links `a` and `b` intersect at these poses.
///
/// ```
/// use hearth_kinematics::{RobotModel, links_touch};
/// let panda = RobotModel::builtin("panda").unwrap();
/// let mut poses = panda.pose_buffer();
/// panda.fk(&panda.neutral_configuration(), &mut poses).unwrap();
/// let link = |name: &str| panda.link_index(name).unwrap();
/// let (l0, l1, l7) = (link("panda_link0"), link("panda_link1"), link("panda_link7"));
/// assert!(links_touch(&panda, &poses, l0, l1)); // joined at the base joint
/// assert!(!links_touch(&panda, &poses, l0, l7));
/// let tcp = panda.link_index("panda_hand_tcp").unwrap();
/// assert!(!links_touch(&panda, &poses, tcp, l7)); // no geometry: never touches
/// ```
pub fn links_touch(model: &RobotModel, poses: &[Isometry3<f64>], a: usize, b: usize) -> bool {
    let (Some(sa), Some(sb)) = (model.link_shape(a), model.link_shape(b)) else {
        return false;
    };
    let pa = to_pose(&(poses[a] * sa.origin));
    let pb = to_pose(&(poses[b] * sb.origin));
    parry3d::query::intersection_test(&pa, sa.shape.as_ref(), &pb, sb.shape.as_ref())
        .map(|r| r.intersecting)
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::{DisabledReason, SelfCollisionMatrix};
    use crate::RobotModel;

    /// An index past the last link reads no other pair's entry: `a * n + b` with `b >= n` used
    /// to land in row `a + 1`.
    #[test]
    fn out_of_range_link_indices_are_never_disabled() {
        let panda = RobotModel::builtin("panda").unwrap();
        let m = SelfCollisionMatrix::adjacent_only(&panda);
        let n = panda.links().len();
        // Some `(a, b)` whose aliased entry `(a + 1, b - n)` is disabled (every link and its
        // parent are adjacent, so there is one).
        let (a, b) = (0..n - 1)
            .flat_map(|a| (n..2 * n).map(move |b| (a, b)))
            .find(|&(a, b)| m.is_disabled(a + 1, b - n) && a + 1 != b - n)
            .expect("an aliased disabled pair");
        assert!(!m.is_disabled(a, b), "({a}, {b}) read another pair's entry");
        assert!(!m.is_disabled(b, a));
        assert_eq!(m.reason(a, b), None);
        assert!(!m.is_disabled(n, n) && !m.is_disabled(usize::MAX, usize::MAX));
        assert!(!m.is_disabled(usize::MAX, 0) && !m.is_disabled(0, usize::MAX));
        assert_eq!(m.reason(usize::MAX, 1), None);
        let mut d = m.clone();
        d.disable(a, b, DisabledReason::Never);
        d.disable(usize::MAX, 0, DisabledReason::Never);
        assert_eq!(d, m);
    }
}
