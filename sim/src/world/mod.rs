//! The rapier3d world: stepping, snapshots, robots with controllers, and the live-world
//! collision view for planners.
