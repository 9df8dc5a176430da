//! Snapshots of the full world state and a bit-exact state hash.

use super::error::{WorldError, WorldResult};
use super::physics::{State, World};

/// A copy of the whole simulation state: rapier's body, collider and joint sets, island
/// manager, broad and narrow phases, and every model's controller targets and gains.
///
/// Taking one clones the sets (cost proportional to the world's size); restoring puts them
/// back. Restoring into the world the snapshot came from (or an identically built one) and
/// stepping with the same commands reproduces the original run bit for bit.
///
/// ```
/// use hearth_sim::world::{World, WorldConfig};
/// use nalgebra::Isometry3;
/// let mut world = World::new(WorldConfig::default())?;
/// world.add_box("crate", [0.1, 0.1, 0.1], &Isometry3::translation(0.0, 0.0, 1.0), true)?;
/// let snap = world.snapshot();
/// for _ in 0..10 { world.step(); }
/// let after = world.state_hash();
/// world.restore(&snap)?;
/// assert_eq!(world.time(), 0.0);
/// for _ in 0..10 { world.step(); }
/// assert_eq!(world.state_hash(), after);
/// # Ok::<(), hearth_sim::world::WorldError>(())
/// ```
#[derive(Clone)]
pub struct Snapshot {
    state: State,
    timestep_bits: u64,
}

impl std::fmt::Debug for Snapshot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Snapshot")
            .field("time", &self.state.time)
            .field("bodies", &self.state.bodies.len())
            .finish_non_exhaustive()
    }
}

impl Snapshot {
    /// Simulated time at which the snapshot was taken.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.step();
    /// assert_eq!(world.snapshot().time(), world.time());
    /// ```
    pub fn time(&self) -> f64 {
        self.state.time
    }
}

impl World {
    /// Copies the full state.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let snap = world.snapshot();
    /// world.step();
    /// world.restore(&snap).unwrap();
    /// assert_eq!(world.physics_steps(), 0);
    /// ```
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            state: self.state.clone(),
            timestep_bits: self.config.timestep.to_bits(),
        }
    }

    /// Puts a snapshot's state back (bodies, joints, contacts, controllers, time).
    ///
    /// # Errors
    /// [`WorldError::SnapshotMismatch`] when the snapshot comes from a world with a different
    /// timestep; the world is unchanged.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// let snap = world.snapshot();
    /// let mut other = World::new(WorldConfig { timestep: 1.0 / 240.0, ..WorldConfig::default() }).unwrap();
    /// assert!(other.restore(&snap).is_err());
    /// world.step();
    /// world.restore(&snap).unwrap();
    /// assert_eq!(world.time(), 0.0);
    /// ```
    pub fn restore(&mut self, snapshot: &Snapshot) -> WorldResult<()> {
        if snapshot.timestep_bits != self.config.timestep.to_bits() {
            return Err(WorldError::SnapshotMismatch {
                reason: "the timestep differs",
            });
        }
        self.state = snapshot.state.clone();
        // The pipeline holds only scratch memory, but it memoizes joint selections against
        // the sets it last stepped: start from a fresh one.
        self.pipeline = rapier3d::prelude::PhysicsPipeline::new();
        Ok(())
    }

    /// A 64-bit hash of the exact state: every body's pose and velocity, every multibody
    /// joint's coordinates and velocities (f32 bit patterns), and the step count.
    ///
    /// Equal hashes mean (up to hash collisions) bit-identical states.
    ///
    /// ```
    /// # use hearth_sim::world::{World, WorldConfig};
    /// # use nalgebra::Isometry3;
    /// let mut world = World::new(WorldConfig::default()).unwrap();
    /// world.add_box("crate", [0.1; 3], &Isometry3::translation(0.0, 0.0, 0.5), true).unwrap();
    /// let before = world.state_hash();
    /// world.step();
    /// assert_ne!(world.state_hash(), before);
    /// ```
    pub fn state_hash(&self) -> u64 {
        let mut h = StateHasher::new();
        let s = &self.state;
        h.u64(s.physics_steps);
        for (handle, rb) in s.bodies.iter() {
            let (i, g) = handle.into_raw_parts();
            h.u64((u64::from(i) << 32) | u64::from(g));
            let p = rb.position();
            h.f32s(&[p.translation.x, p.translation.y, p.translation.z]);
            h.f32s(&[p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w]);
            let (v, w) = (rb.linvel(), rb.angvel());
            h.f32s(&[v.x, v.y, v.z, w.x, w.y, w.z]);
        }
        for mb in s.multibody_joints.multibodies() {
            for link in mb.links() {
                h.f32s(&link.joint().coords());
            }
            h.f32s(mb.generalized_velocity().as_slice());
        }
        h.finish()
    }
}

/// FNV-1a over bytes, finished with a 64-bit mixer.
struct StateHasher(u64);

impl StateHasher {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn u64(&mut self, x: u64) {
        for b in x.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn f32s(&mut self, xs: &[f32]) {
        for x in xs {
            self.u64(u64::from(x.to_bits()));
        }
    }

    fn finish(&self) -> u64 {
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

#[cfg(test)]
mod tests {
    use super::StateHasher;

    #[test]
    fn hash_sees_every_bit() {
        let hash = |x: f32| {
            let mut h = StateHasher::new();
            h.f32s(&[1.0, x]);
            h.finish()
        };
        assert_eq!(hash(0.5), hash(0.5));
        assert_ne!(hash(0.5), hash(f32::from_bits(0.5f32.to_bits() + 1)));
        assert_ne!(hash(0.0), hash(-0.0));
    }
}
