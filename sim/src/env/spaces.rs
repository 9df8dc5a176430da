//! Observation and action space descriptions, and observation values.

use serde::Serialize;

/// Element type of an array.
///
/// ```
/// use hearth_sim::env::{DType, Space};
/// let rgb = Space::boxed("rgb", &[64, 64, 3], DType::U8, 0.0, 255.0);
/// assert_eq!(rgb.dtype, DType::U8);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DType {
    /// 32-bit float.
    F32,
    /// 8-bit unsigned.
    U8,
    /// 32-bit unsigned.
    U32,
}

/// One named array: shape, dtype and value range (Gymnasium's `Box`), or a discrete choice.
///
/// ```
/// use hearth_sim::env::{DType, Space};
/// let s = Space::boxed("depth", &[128, 128, 1], DType::F32, 0.0, 5.0);
/// assert_eq!(s.size(), 128 * 128);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Space {
    /// Name (`depth`, `scan`, `action`, …).
    pub name: String,
    /// Shape.
    pub shape: Vec<usize>,
    /// Element type.
    pub dtype: DType,
    /// Smallest value.
    pub low: f64,
    /// Largest value.
    pub high: f64,
}

impl Space {
    /// A box space.
    ///
    /// ```
    /// # use hearth_sim::env::{DType, Space};
    /// let s = Space::boxed("scan", &[228, 1], DType::F32, 0.0, 1.0);
    /// assert_eq!((s.name.as_str(), s.shape.as_slice(), s.high), ("scan", &[228, 1][..], 1.0));
    /// ```
    pub fn boxed(name: &str, shape: &[usize], dtype: DType, low: f64, high: f64) -> Self {
        Self {
            name: name.to_owned(),
            shape: shape.to_vec(),
            dtype,
            low,
            high,
        }
    }

    /// Number of elements.
    ///
    /// ```
    /// # use hearth_sim::env::{DType, Space};
    /// assert_eq!(Space::boxed("rgb", &[4, 3, 3], DType::U8, 0.0, 255.0).size(), 36);
    /// assert_eq!(Space::boxed("none", &[], DType::F32, 0.0, 1.0).size(), 1); // a scalar
    /// ```
    pub fn size(&self) -> usize {
        self.shape.iter().product()
    }
}

/// Values of one observation.
///
/// ```
/// use hearth_sim::env::ObsData;
/// let ids = ObsData::U32(vec![3, 3, 7]);
/// assert_eq!(ids.len(), 3);
/// assert!(ids.as_f32().is_none());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum ObsData {
    /// Floats.
    F32(Vec<f32>),
    /// Bytes.
    U8(Vec<u8>),
    /// Ids.
    U32(Vec<u32>),
}

impl ObsData {
    /// Number of elements.
    ///
    /// ```
    /// # use hearth_sim::env::ObsData;
    /// assert_eq!(ObsData::U8(vec![0; 12]).len(), 12);
    /// ```
    pub fn len(&self) -> usize {
        match self {
            ObsData::F32(v) => v.len(),
            ObsData::U8(v) => v.len(),
            ObsData::U32(v) => v.len(),
        }
    }

    /// Whether empty.
    ///
    /// ```
    /// # use hearth_sim::env::ObsData;
    /// assert!(ObsData::F32(Vec::new()).is_empty());
    /// assert!(!ObsData::U8(vec![1]).is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The floats, if this is an f32 array.
    ///
    /// ```
    /// # use hearth_sim::env::ObsData;
    /// assert_eq!(ObsData::F32(vec![0.5]).as_f32(), Some(&[0.5f32][..]));
    /// assert_eq!(ObsData::U8(vec![1]).as_f32(), None);
    /// ```
    pub fn as_f32(&self) -> Option<&[f32]> {
        match self {
            ObsData::F32(v) => Some(v),
            _ => None,
        }
    }

    /// Appends `other` (same type) to `self`, for batching.
    pub(crate) fn extend_from(&mut self, other: &ObsData) {
        match (self, other) {
            (ObsData::F32(a), ObsData::F32(b)) => a.extend_from_slice(b),
            (ObsData::U8(a), ObsData::U8(b)) => a.extend_from_slice(b),
            (ObsData::U32(a), ObsData::U32(b)) => a.extend_from_slice(b),
            _ => {}
        }
    }

    pub(crate) fn empty_like(&self, capacity: usize) -> ObsData {
        match self {
            ObsData::F32(_) => ObsData::F32(Vec::with_capacity(capacity)),
            ObsData::U8(_) => ObsData::U8(Vec::with_capacity(capacity)),
            ObsData::U32(_) => ObsData::U32(Vec::with_capacity(capacity)),
        }
    }
}

/// A named set of observations, in the order of the env's observation spaces.
///
/// ```
/// use hearth_sim::env::{Obs, ObsData};
/// let obs = Obs { entries: vec![("task_obs".into(), ObsData::F32(vec![1.0, 2.0]))] };
/// assert_eq!(obs.get("task_obs").unwrap().len(), 2);
/// assert!(obs.get("rgb").is_none());
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Obs {
    /// (name, values) pairs.
    pub entries: Vec<(String, ObsData)>,
}

impl Obs {
    /// The observation called `name`.
    ///
    /// ```
    /// # use hearth_sim::env::{Obs, ObsData};
    /// let obs = Obs { entries: vec![("bump".into(), ObsData::U8(vec![0]))] };
    /// assert_eq!(obs.get("bump"), Some(&ObsData::U8(vec![0])));
    /// assert_eq!(obs.get("scan"), None);
    /// ```
    pub fn get(&self, name: &str) -> Option<&ObsData> {
        self.entries.iter().find(|(n, _)| n == name).map(|(_, d)| d)
    }
}
