//! Scene files, procedural homes, traversability maps and URDF export.
