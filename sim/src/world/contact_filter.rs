//! The contact filter of split roots: a free object whose links move keeps the colliders of
//! its root on a plain body outside its multibody (see `World::spawn_model`), and this filter
//! stands in for the multibody's own rules between that body and the model's moving links.
//!
//! Why: rapier solves every contact that touches a multibody link with its generic, scalar
//! constraint path, which also pays for the multibody's Jacobians and mass-matrix solves. Books
//! on a bookcase's shelves touch only a plain body once the root is split off, and take the
//! SIMD two-body path.

use rapier3d::prelude::*;

/// What a body is to the contact filter, indexed like the world's body names (the `user_data`
/// of bodies and colliders).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum BodyOwner {
    /// Not part of a split model: never filtered here.
    #[default]
    None,
    /// The collider-carrying root body of model `model`.
    Root {
        /// Model index.
        model: u32,
    },
    /// A moving link body of model `model`.
    Link {
        /// Model index.
        model: u32,
        /// Whether contacts with the model's root body are dropped (the link hangs on the
        /// root, or the model has self-collisions off).
        skip_root: bool,
    },
}

/// The physics hook that drops contacts between a split root and its own moving links.
pub(crate) struct RootContactFilter<'a> {
    /// Per body name index: its owner.
    pub(crate) owners: &'a [BodyOwner],
}

impl RootContactFilter<'_> {
    fn owner(&self, colliders: &ColliderSet, handle: ColliderHandle) -> BodyOwner {
        colliders
            .get(handle)
            .and_then(|co| self.owners.get(co.user_data as usize).copied())
            .unwrap_or_default()
    }
}

/// Whether two owners are a split root and one of its links whose contacts with it are dropped.
pub(crate) fn skips(a: BodyOwner, b: BodyOwner) -> bool {
    match (a, b) {
        (BodyOwner::Root { model }, BodyOwner::Link { model: m, skip_root })
        | (BodyOwner::Link { model: m, skip_root }, BodyOwner::Root { model }) => model == m && skip_root,
        _ => false,
    }
}

impl PhysicsHooks for RootContactFilter<'_> {
    fn filter_contact_pair(&self, context: &PairFilterContext) -> Option<SolverFlags> {
        let a = self.owner(context.colliders, context.collider1);
        let b = self.owner(context.colliders, context.collider2);
        if skips(a, b) {
            None
        } else {
            Some(SolverFlags::default())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_root_and_its_own_skipping_links_are_filtered() {
        let root = BodyOwner::Root { model: 3 };
        let link = BodyOwner::Link {
            model: 3,
            skip_root: true,
        };
        let far_link = BodyOwner::Link {
            model: 3,
            skip_root: false,
        };
        let other = BodyOwner::Link {
            model: 4,
            skip_root: true,
        };
        assert!(skips(root, link) && skips(link, root));
        assert!(!skips(root, far_link));
        assert!(!skips(root, other));
        assert!(!skips(link, link));
        assert!(!skips(root, BodyOwner::None));
        assert!(!skips(BodyOwner::Root { model: 4 }, link));
    }
}
