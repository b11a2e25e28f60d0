//! # collision-tracker
//!
//! The explicit, collision-safe multi-material tracker in the style of Los Topos (Da et al.
//! 2014) on El Topo (Brochu & Bridson 2009): exact continuous collision detection, impact
//! zones, snap merging, T1/T2 vertex separation — the mesh never tangles.
//!
//! Not implemented yet (issue 5): the crate is wired into the workspace and the facade so
//! that the harness reports it as unavailable instead of failing to build.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

/// Why this backend cannot be constructed yet; the facade reports it to the user.
pub const UNAVAILABLE: Option<&str> = Some("the collision backend is not implemented yet (issue 5)");
