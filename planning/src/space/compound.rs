//! [`CompoundSpace`]: two spaces side by side, such as a mobile base and an arm.

use rand::Rng;

use super::{EuclideanBound, Space, SpaceError, valid_weight};

/// Two spaces concatenated: a state is the first space's coordinates followed by the second's
/// (e.g. an [`Se2Space`](super::Se2Space) base then a [`JointSpace`](super::JointSpace) arm).
///
/// The distance is the weighted sum `w₁·d₁ + w₂·d₂` of the parts' distances (weights default
/// to 1), a metric whenever both parts' are. Everything else acts on each part's slice, so the
/// pair costs nothing over calling the parts directly; nest pairs for more than two parts
/// (`CompoundSpace<A, CompoundSpace<B, C>>`).
///
/// ```
/// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space, Space};
///
/// let base = Se2Space::new([-5.0, -5.0], [5.0, 5.0])?;
/// let arm = JointSpace::new(&[-1.0, 0.0], &[1.0, 0.0], &[false, true])?;
/// let space = CompoundSpace::new(base, arm).with_weights(1.0, 0.5)?;
/// assert_eq!(space.dim(), 5);
/// assert_eq!(space.coordinate_name(3), Some("q0"));
/// let (a, b) = ([0.0, 0.0, 0.0, 0.0, 0.0], [3.0, 4.0, 0.0, 1.0, 0.0]);
/// assert_eq!(space.distance(&a, &b), 5.0 + 0.5 * 1.0);
/// // Errors name coordinates of the whole state.
/// assert!(matches!(
///     space.check(&[0.0, 0.0, 0.0, 2.0, 0.0]),
///     Err(hearth_planning::space::SpaceError::OutOfBounds { index: 3, .. })
/// ));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CompoundSpace<A, B> {
    first: A,
    second: B,
    weights: [f64; 2],
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// The parts' Euclidean bounds side by side ([`Space::euclidean_bound`]); `None` when a
    /// part has none.
    bound: Option<JointBound>,
}

impl<A: Space, B: Space> CompoundSpace<A, B> {
    /// The concatenation of `first` and `second`, with both distance weights 1.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space, Space};
    ///
    /// let (base, arm) = (Se2Space::new([0.0, 0.0], [4.0, 4.0])?, JointSpace::new(&[-1.0], &[1.0], &[false])?);
    /// let space = CompoundSpace::new(base, arm);
    /// assert_eq!(space.dim(), 4);
    /// assert_eq!(space.lower(), &[0.0, 0.0, -std::f64::consts::PI, -1.0]);
    /// assert_eq!(space.weights(), [1.0, 1.0]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn new(first: A, second: B) -> Self {
        let lower = first.lower().iter().chain(second.lower()).copied().collect();
        let upper = first.upper().iter().chain(second.upper()).copied().collect();
        let bound = joint_bound(&first, &second, [1.0, 1.0]);
        Self {
            first,
            second,
            weights: [1.0, 1.0],
            lower,
            upper,
            bound,
        }
    }

    /// The same space with distance weights for the two parts (finite, non-negative).
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Space};
    ///
    /// let joint = || JointSpace::new(&[-1.0], &[1.0], &[false]);
    /// let space = CompoundSpace::new(joint()?, joint()?).with_weights(2.0, 0.0)?;
    /// // The second part does not count.
    /// assert_eq!(space.distance(&[0.0, 0.0], &[0.5, 1.0]), 1.0);
    /// assert!(CompoundSpace::new(joint()?, joint()?).with_weights(-1.0, 1.0).is_err());
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn with_weights(mut self, first: f64, second: f64) -> Result<Self, SpaceError> {
        for (what, value) in [("first space", first), ("second space", second)] {
            if !valid_weight(value) {
                return Err(SpaceError::InvalidWeight {
                    what: what.to_owned(),
                    value,
                });
            }
        }
        self.weights = [first, second];
        self.bound = joint_bound(&self.first, &self.second, self.weights);
        Ok(self)
    }

    /// The first part.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space, Space};
    ///
    /// let (base, arm) = (Se2Space::new([0.0; 2], [1.0; 2])?, JointSpace::new(&[0.0], &[1.0], &[false])?);
    /// let space = CompoundSpace::new(base, arm);
    /// assert_eq!(space.first().dim(), 3);
    /// assert_eq!(space.first().yaw_weight(), Se2Space::DEFAULT_YAW_WEIGHT);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn first(&self) -> &A {
        &self.first
    }

    /// The second part.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space};
    ///
    /// let arm = JointSpace::new(&[0.0; 2], &[1.0; 2], &[false; 2])?.with_names(["lift", "pan"])?;
    /// let space = CompoundSpace::new(Se2Space::new([0.0; 2], [1.0; 2])?, arm);
    /// assert_eq!(space.second().names(), ["lift", "pan"]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn second(&self) -> &B {
        &self.second
    }

    /// Distance weights of the two parts.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace};
    ///
    /// let joint = || JointSpace::new(&[0.0], &[1.0], &[false]);
    /// assert_eq!(CompoundSpace::new(joint()?, joint()?).weights(), [1.0, 1.0]);
    /// assert_eq!(CompoundSpace::new(joint()?, joint()?).with_weights(1.0, 0.25)?.weights(), [1.0, 0.25]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    pub fn weights(&self) -> [f64; 2] {
        self.weights
    }

    /// Splits a state into the parts' coordinates.
    ///
    /// Panics if `q` is shorter than the first part's dimension.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space};
    ///
    /// let (base, arm) = (Se2Space::new([0.0; 2], [1.0; 2])?, JointSpace::new(&[0.0], &[1.0], &[false])?);
    /// let space = CompoundSpace::new(base, arm);
    /// let (base, arm) = space.split(&[0.1, 0.2, 0.3, 0.4]);
    /// assert_eq!((base, arm), (&[0.1, 0.2, 0.3][..], &[0.4][..]));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    #[inline]
    pub fn split<'q>(&self, q: &'q [f64]) -> (&'q [f64], &'q [f64]) {
        q.split_at(self.first.dim())
    }

    /// Splits a mutable state into the parts' coordinates.
    ///
    /// Panics if `q` is shorter than the first part's dimension.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space};
    ///
    /// let (base, arm) = (Se2Space::new([0.0; 2], [1.0; 2])?, JointSpace::new(&[0.0], &[1.0], &[false])?);
    /// let space = CompoundSpace::new(base, arm);
    /// let mut q = [0.1, 0.2, 0.3, 0.4];
    /// let (_, arm) = space.split_mut(&mut q);
    /// arm[0] = 0.9;
    /// assert_eq!(q, [0.1, 0.2, 0.3, 0.9]);
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    #[inline]
    pub fn split_mut<'q>(&self, q: &'q mut [f64]) -> (&'q mut [f64], &'q mut [f64]) {
        q.split_at_mut(self.first.dim())
    }
}

impl<A: Space, B: Space> Space for CompoundSpace<A, B> {
    #[inline]
    fn dim(&self) -> usize {
        self.lower.len()
    }

    #[inline]
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.dim());
        let (o1, o2) = self.split_mut(out);
        self.first.sample(rng, o1);
        self.second.sample(rng, o2);
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        let ((a1, a2), (b1, b2)) = (self.split(a), self.split(b));
        self.weights[0] * self.first.distance(a1, b1) + self.weights[1] * self.second.distance(a2, b2)
    }

    #[inline]
    fn interpolate(&self, a: &[f64], b: &[f64], t: f64, out: &mut [f64]) {
        let ((a1, a2), (b1, b2)) = (self.split(a), self.split(b));
        let (o1, o2) = self.split_mut(out);
        self.first.interpolate(a1, b1, t, o1);
        self.second.interpolate(a2, b2, t, o2);
    }

    #[inline]
    fn lower(&self) -> &[f64] {
        &self.lower
    }

    #[inline]
    fn upper(&self) -> &[f64] {
        &self.upper
    }

    #[inline]
    fn enforce_bounds(&self, q: &mut [f64]) {
        let (q1, q2) = self.split_mut(q);
        self.first.enforce_bounds(q1);
        self.second.enforce_bounds(q2);
    }

    #[inline]
    fn satisfies_bounds(&self, q: &[f64]) -> bool {
        if q.len() != self.dim() {
            return false;
        }
        let (q1, q2) = self.split(q);
        self.first.satisfies_bounds(q1) && self.second.satisfies_bounds(q2)
    }

    #[inline]
    fn difference(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        let ((a1, a2), (b1, b2)) = (self.split(a), self.split(b));
        let (o1, o2) = self.split_mut(out);
        self.first.difference(a1, b1, o1);
        self.second.difference(a2, b2, o2);
    }

    fn check(&self, q: &[f64]) -> Result<(), SpaceError> {
        if q.len() != self.dim() {
            return Err(SpaceError::DimensionMismatch {
                what: "state",
                expected: self.dim(),
                got: q.len(),
            });
        }
        let (q1, q2) = self.split(q);
        self.first.check(q1)?;
        self.second.check(q2).map_err(|e| e.offset(q1.len()))
    }

    fn coordinate_name(&self, i: usize) -> Option<&str> {
        let n = self.first.dim();
        if i < n {
            self.first.coordinate_name(i)
        } else {
            self.second.coordinate_name(i - n)
        }
    }

    /// The parts' bounds side by side, each part's weights times its distance weight. With
    /// `Eₖ ≤ dₖ ≤ cₖ·Eₖ` for the parts, the bound `E = √((w₁E₁)² + (w₂E₂)²)` is at most
    /// `w₁E₁ + w₂E₂ ≤ w₁d₁ + w₂d₂`, the distance, which is at most `max(c₁, c₂)·√2·E`. A sum of
    /// two Euclidean parts is no Euclidean metric, so even two joint spaces have stretch √2.
    /// The parts' groups stay apart (the second part's numbered after the first's), so `L`
    /// adds up the parts' own `L`s, each at most the part's distance.
    ///
    /// ```
    /// use hearth_planning::space::{CompoundSpace, JointSpace, Se2Space, Space};
    ///
    /// let base = Se2Space::new([-5.0, -5.0], [5.0, 5.0])?;
    /// let arm = JointSpace::new(&[-1.0], &[1.0], &[false])?;
    /// let space = CompoundSpace::new(base, arm).with_weights(1.0, 0.5)?;
    /// let bound = space.euclidean_bound().unwrap();
    /// assert_eq!(bound.weights, &[1.0, 1.0, 0.5, 0.5][..]);
    /// assert_eq!(bound.wraps, &[false, false, true, false][..]);
    /// assert_eq!(bound.groups, &[0, 0, 1, 2][..]);
    /// assert!((bound.stretch - 2.0).abs() < 1e-12); // √2 for the base, √2 for the sum
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    fn euclidean_bound(&self) -> Option<EuclideanBound<'_>> {
        self.bound.as_ref().map(|b| EuclideanBound {
            weights: &b.weights,
            wraps: &b.wraps,
            groups: &b.groups,
            stretch: b.stretch,
        })
    }
}

/// The owned values of [`CompoundSpace::euclidean_bound`].
#[derive(Clone, Debug, PartialEq)]
struct JointBound {
    weights: Vec<f64>,
    wraps: Vec<bool>,
    groups: Vec<u8>,
    stretch: f64,
}

/// [`CompoundSpace::euclidean_bound`]'s values, from the parts' bounds and distance weights
/// (`None` when a part has no usable bound, or the groups would not fit in `u8`).
fn joint_bound<A: Space, B: Space>(first: &A, second: &B, weights: [f64; 2]) -> Option<JointBound> {
    let parts = [
        (first.euclidean_bound()?, first.dim()),
        (second.euclidean_bound()?, second.dim()),
    ];
    let mut joint = JointBound {
        weights: Vec::new(),
        wraps: Vec::new(),
        groups: Vec::new(),
        stretch: 1.0,
    };
    let mut next_group = 0u8;
    for ((bound, dim), scale) in parts.iter().zip(weights) {
        if !bound.usable(*dim) {
            return None;
        }
        joint.weights.extend(bound.weights.iter().map(|x| x * scale));
        if bound.wraps.is_empty() {
            joint.wraps.extend(std::iter::repeat_n(false, *dim));
        } else {
            joint.wraps.extend_from_slice(bound.wraps);
        }
        let first_group = next_group;
        for i in 0..*dim {
            let g = first_group.checked_add(bound.groups.get(i).copied().unwrap_or(0))?;
            next_group = next_group.max(g.checked_add(1)?);
            joint.groups.push(g);
        }
        joint.stretch = joint.stretch.max(bound.stretch);
    }
    joint.stretch *= std::f64::consts::SQRT_2;
    Some(joint)
}
