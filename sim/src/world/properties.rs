//! Physical properties of bodies and joints that can change after spawning: friction,
//! restitution, mass and joint damping (for domain randomisation, see
//! [`crate::randomize`]).
//!
//! All of them live in rapier's body, collider and multibody sets, which [`World::snapshot`]
//! copies whole: restoring a snapshot taken before a change undoes the change. They are not
//! part of [`World::state_hash`] (which covers poses, velocities, joint coordinates and the
//! step count); [`World::properties_hash`] hashes them separately.

use std::sync::Arc;

use rapier3d::prelude::*;

use super::error::{WorldError, WorldResult, check_range};
use super::physics::{BodyId, World};
use super::spawn::ModelHandle;

/// Largest friction coefficient the setters accept.
const MAX_FRICTION: f64 = 10.0;
/// Largest restitution coefficient the setters accept.
const MAX_RESTITUTION: f64 = 1.0;
/// Largest joint damping the setters accept (N·s/m or N·m·s/rad).
const MAX_DAMPING: f64 = 1e6;

impl World {
    /// Friction coefficient of a body's colliders (the first collider's; the setters keep them
    /// equal). `None` for a body without colliders.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`].
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true)?;
    /// world.set_body_friction(b, 0.9)?;
    /// assert!((world.body_friction(b)?.unwrap() - 0.9).abs() < 1e-6);
    /// assert!(world.set_body_friction(b, -1.0).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn body_friction(&self, body: BodyId) -> WorldResult<Option<f64>> {
        let rb = self.rigid_body(body)?;
        Ok(rb
            .colliders()
            .first()
            .and_then(|&c| self.state.colliders.get(c))
            .map(|c| f64::from(c.friction())))
    }

    /// Sets the friction coefficient of every collider of a body.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`]; [`WorldError::OutOfRange`] for a value outside `[0, 10]`
    /// (the world is unchanged then).
    ///
    /// ```
    /// let mut world = hearth_sim::world::World::new(Default::default()).unwrap();
    /// let ground = world.ground().unwrap();
    /// world.set_body_friction(ground, 0.3).unwrap();
    /// assert!((world.body_friction(ground).unwrap().unwrap() - 0.3).abs() < 1e-6);
    /// ```
    pub fn set_body_friction(&mut self, body: BodyId, friction: f64) -> WorldResult<()> {
        check_range("friction", "body", friction, 0.0, MAX_FRICTION)?;
        self.for_colliders(body, |c| c.set_friction(friction as Real))
    }

    /// Restitution coefficient of a body's colliders (the first collider's). `None` for a body
    /// without colliders.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`].
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let b = world.add_box("ball", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true)?;
    /// world.set_body_restitution(b, 0.7)?;
    /// assert!((world.body_restitution(b)?.unwrap() - 0.7).abs() < 1e-6);
    /// assert!(world.set_body_restitution(b, 1.5).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn body_restitution(&self, body: BodyId) -> WorldResult<Option<f64>> {
        let rb = self.rigid_body(body)?;
        Ok(rb
            .colliders()
            .first()
            .and_then(|&c| self.state.colliders.get(c))
            .map(|c| f64::from(c.restitution())))
    }

    /// Sets the restitution coefficient of every collider of a body.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`]; [`WorldError::OutOfRange`] outside `[0, 1]`.
    ///
    /// ```
    /// let mut world = hearth_sim::world::World::new(Default::default()).unwrap();
    /// let ground = world.ground().unwrap();
    /// world.set_body_restitution(ground, 0.5).unwrap();
    /// assert!(world.set_body_restitution(ground, f64::NAN).is_err());
    /// ```
    pub fn set_body_restitution(&mut self, body: BodyId, restitution: f64) -> WorldResult<()> {
        check_range("restitution", "body", restitution, 0.0, MAX_RESTITUTION)?;
        self.for_colliders(body, |c| c.set_restitution(restitution as Real))
    }

    /// Mass of a body, kg (its colliders' and its additional mass properties together).
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`].
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true)?;
    /// let m0 = world.body_mass(b)?;
    /// world.set_body_mass(b, 2.0 * m0)?;
    /// assert!((world.body_mass(b)? - 2.0 * m0).abs() < 1e-3 * m0);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn body_mass(&self, body: BodyId) -> WorldResult<f64> {
        Ok(f64::from(self.total_mass_properties(body)?.mass()))
    }

    /// The body's mass properties from its colliders and additional mass properties as they
    /// are now (rapier refreshes its own copy only at the next step).
    fn total_mass_properties(&self, body: BodyId) -> WorldResult<MassProperties> {
        let mut rb = self.rigid_body(body)?.clone();
        rb.recompute_mass_properties_from_colliders(&self.state.colliders);
        Ok(rb.mass_properties().local_mprops)
    }

    /// Sets the mass of a body, scaling its inertia tensor by the same factor and keeping its
    /// centre of mass (as if its density changed uniformly). Takes effect at once (no step
    /// needed); a sleeping body is woken.
    ///
    /// # Errors
    /// [`WorldError::UnknownBody`]; [`WorldError::OutOfRange`] for a mass outside
    /// `[1e-6, 1e6]` kg; [`WorldError::InvalidModel`] for a body that has no mass to scale.
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true).unwrap();
    /// world.set_body_mass(b, 5.0).unwrap();
    /// assert!((world.body_mass(b).unwrap() - 5.0).abs() < 1e-5);
    /// assert!(world.set_body_mass(b, 0.0).is_err());
    /// ```
    pub fn set_body_mass(&mut self, body: BodyId, mass: f64) -> WorldResult<()> {
        check_range("mass", "body", mass, 1e-6, 1e6)?;
        let current = self.total_mass_properties(body)?;
        if current.mass() <= 0.0 {
            return Err(WorldError::InvalidModel {
                model: self.body_name(body).unwrap_or("body").to_owned(),
                reason: "the body has no mass to scale".to_owned(),
            });
        }
        let mut scaled = current;
        scaled.set_mass(mass as Real, true);
        let s = &mut self.state;
        let colliders = Arc::make_mut(&mut s.colliders);
        let bodies = Arc::make_mut(&mut s.bodies);
        if let Some(rb) = bodies.get_mut(body.0) {
            // The whole mass goes into the body's own mass properties; the colliders keep only
            // their shapes.
            for &c in rb.colliders() {
                if let Some(co) = colliders.get_mut(c) {
                    co.set_density(0.0);
                }
            }
            rb.set_additional_mass_properties(scaled, true);
            rb.recompute_mass_properties_from_colliders(colliders);
        }
        Ok(())
    }

    /// Damping coefficient of a model joint (N·s/m for prismatic joints, N·m·s/rad for
    /// revolute ones).
    ///
    /// # Errors
    /// Unknown model or joint; [`WorldError::JointNotCommandable`] for a fixed joint.
    ///
    /// ```
    /// use hearth_sim::assets::{Asset, Category};
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let cabinet = Asset::build(Category::BottomCabinet, 1, 1.0).unwrap();
    /// let h = world.spawn_model(&cabinet.model, &Isometry3::identity(), SpawnOptions::fixed())?;
    /// let d0 = world.joint_damping(h, "drawer_0_slide")?;
    /// world.set_joint_damping(h, "drawer_0_slide", 3.0 * d0)?;
    /// assert!((world.joint_damping(h, "drawer_0_slide")? - 3.0 * d0).abs() < 1e-5);
    /// assert!(world.set_joint_damping(h, "no_such_joint", 1.0).is_err());
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn joint_damping(&self, model: ModelHandle, joint: &str) -> WorldResult<f64> {
        let dof = self.joint_dof(model, joint)?;
        let mb = self.multibody_of(model);
        Ok(mb.and_then(|mb| mb.damping().get(dof).copied()).map_or(0.0, f64::from))
    }

    /// Sets the damping coefficient of a model joint.
    ///
    /// # Errors
    /// Unknown model or joint, a fixed joint, or a value outside `[0, 1e6]`.
    ///
    /// ```
    /// use hearth_sim::assets::{Asset, Category};
    /// use hearth_sim::world::{SpawnOptions, World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let fridge = Asset::build(Category::Fridge, 0, 1.0).unwrap();
    /// let h = world.spawn_model(&fridge.model, &nalgebra::Isometry3::identity(), SpawnOptions::fixed()).unwrap();
    /// world.set_joint_damping(h, "door_0_hinge", 0.5).unwrap();
    /// assert!(world.set_joint_damping(h, "door_0_hinge", -1.0).is_err());
    /// ```
    pub fn set_joint_damping(&mut self, model: ModelHandle, joint: &str, damping: f64) -> WorldResult<()> {
        check_range("joint damping", joint, damping, 0.0, MAX_DAMPING)?;
        let dof = self.joint_dof(model, joint)?;
        if let Some(mb) = self.multibody_of_mut(model)
            && let Some(d) = mb.damping_mut().get_mut(dof)
        {
            *d = damping as Real;
        }
        let bodies = self.entry(model)?.bodies.clone();
        for h in bodies {
            self.wake(h);
        }
        Ok(())
    }

    /// A 64-bit hash of every body's mass and its colliders' friction and restitution, and of
    /// every multibody's joint damping (f32 bit patterns), in storage order. Two identically
    /// built worlds have equal hashes exactly when these properties are bit-identical.
    ///
    /// ```
    /// use hearth_sim::world::{World, WorldConfig};
    /// use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default())?;
    /// let b = world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.1), true)?;
    /// let before = world.properties_hash();
    /// let snap = world.snapshot();
    /// world.set_body_friction(b, 0.2)?;
    /// assert_ne!(world.properties_hash(), before);
    /// world.restore(&snap)?;
    /// assert_eq!(world.properties_hash(), before);
    /// # Ok::<(), hearth_sim::world::WorldError>(())
    /// ```
    pub fn properties_hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut feed = |x: f32| {
            for b in x.to_bits().to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        let s = &self.state;
        for (handle, rb) in s.bodies.iter() {
            feed(self.total_mass_properties(BodyId(handle)).map_or(0.0, |m| m.mass()));
            for &c in rb.colliders() {
                if let Some(co) = s.colliders.get(c) {
                    feed(co.friction());
                    feed(co.restitution());
                }
            }
        }
        for mb in s.multibody_joints.multibodies() {
            for &d in mb.damping().iter() {
                feed(d);
            }
        }
        h
    }

    /// Index of a joint's degree of freedom in its multibody's generalized coordinates.
    fn joint_dof(&self, model: ModelHandle, joint: &str) -> WorldResult<usize> {
        let entry = self.entry(model)?;
        let j = entry.model.joint_index(joint).map_err(|_| WorldError::UnknownJoint {
            model: entry.name.clone(),
            joint: joint.to_owned(),
        })?;
        let slot = entry.joints[j].ok_or_else(|| WorldError::JointNotCommandable {
            model: entry.name.clone(),
            joint: joint.to_owned(),
            reason: "it is fixed",
        })?;
        let dof = self
            .multibody_of(model)
            .and_then(|mb| mb.link(slot.link_id).map(|l| l.assembly_id()));
        dof.ok_or_else(|| WorldError::InvalidModel {
            model: entry.name.clone(),
            reason: format!("joint `{joint}` has no multibody degree of freedom"),
        })
    }

    /// Runs `f` on every collider of `body`.
    fn for_colliders(&mut self, body: BodyId, mut f: impl FnMut(&mut Collider)) -> WorldResult<()> {
        let handles: Vec<ColliderHandle> = self.rigid_body(body)?.colliders().to_vec();
        let colliders = Arc::make_mut(&mut self.state.colliders);
        for c in handles {
            if let Some(co) = colliders.get_mut(c) {
                f(co);
            }
        }
        Ok(())
    }
}
