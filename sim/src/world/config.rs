//! [`WorldConfig`]: timestep, substeps, gravity, solver and sleeping settings.

use super::error::{WorldError, WorldResult};

/// Settings of a [`super::World`]. z is up; gravity points along −z by default.
///
/// One control step ([`super::World::step`]) runs `substeps` physics steps of `timestep`
/// seconds each: the defaults (1/120 s × 4) give 30 Hz control, as iGibson.
///
/// ```
/// use hearth_sim::world::WorldConfig;
/// let config = WorldConfig { substeps: 2, ..WorldConfig::default() };
/// assert!((config.control_dt() - 2.0 / 120.0).abs() < 1e-12);
/// assert!(config.validate().is_ok());
/// assert!(WorldConfig { timestep: 0.0, ..config }.validate().is_err());
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct WorldConfig {
    /// Physics timestep in seconds (default 1/120).
    pub timestep: f64,
    /// Physics steps per control step (default 4).
    pub substeps: u32,
    /// Gravity vector in m/s² (default `[0, 0, -9.81]`).
    pub gravity: [f64; 3],
    /// Velocity solver iterations per physics step (default 4).
    pub solver_iterations: u32,
    /// Whether resting bodies may fall asleep (default true).
    pub sleeping: bool,
    /// Add a fixed ground box whose top face is the plane z = 0 (default true).
    pub ground_plane: bool,
    /// Friction coefficient of the ground (default 0.8).
    pub ground_friction: f64,
    /// Density (kg/m³) given to collision shapes of links that have no URDF inertial
    /// (default 500).
    pub default_density: f64,
    /// Split the root of objects whose links move (dressers, bookcases, laptops, cabinets,
    /// counters, fridges) off their multibody, so that what rests on them takes rapier's fast
    /// two-body contact path (default true; see [`super::World::spawn_model`]). Off, every
    /// model is one multibody.
    pub split_roots: bool,
}

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            timestep: 1.0 / 120.0,
            substeps: 4,
            gravity: [0.0, 0.0, -9.81],
            solver_iterations: 4,
            sleeping: true,
            ground_plane: true,
            ground_friction: 0.8,
            default_density: 500.0,
            split_roots: true,
        }
    }
}

impl WorldConfig {
    /// Seconds of simulated time per control step (`timestep × substeps`).
    ///
    /// ```
    /// # use hearth_sim::world::WorldConfig;
    /// assert!((WorldConfig::default().control_dt() - 4.0 / 120.0).abs() < 1e-12);
    /// ```
    pub fn control_dt(&self) -> f64 {
        self.timestep * f64::from(self.substeps)
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`WorldError::InvalidConfig`] naming the first bad field.
    ///
    /// ```
    /// # use hearth_sim::world::WorldConfig;
    /// assert!(WorldConfig::default().validate().is_ok());
    /// assert!(WorldConfig { gravity: [0.0, 0.0, f64::NAN], ..WorldConfig::default() }.validate().is_err());
    /// ```
    pub fn validate(&self) -> WorldResult<()> {
        let bad = |field: &'static str, reason: &str| {
            Err(WorldError::InvalidConfig {
                field,
                reason: reason.to_owned(),
            })
        };
        if !(self.timestep.is_finite() && self.timestep > 0.0 && self.timestep <= 1.0) {
            return bad("timestep", "must be in (0, 1] seconds");
        }
        if self.substeps == 0 || self.substeps > 1000 {
            return bad("substeps", "must be in 1..=1000");
        }
        if self.gravity.iter().any(|g| !g.is_finite()) {
            return bad("gravity", "must be finite");
        }
        if self.solver_iterations == 0 || self.solver_iterations > 1000 {
            return bad("solver_iterations", "must be in 1..=1000");
        }
        if !(self.ground_friction.is_finite() && self.ground_friction >= 0.0) {
            return bad("ground_friction", "must be finite and non-negative");
        }
        if !(self.default_density.is_finite() && self.default_density > 0.0) {
            return bad("default_density", "must be finite and positive");
        }
        Ok(())
    }
}
