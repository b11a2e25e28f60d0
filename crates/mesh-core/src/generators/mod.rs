//! Seeded, deterministic scene generators.
//!
//! Every generator returns a [`LabeledMesh`](crate::LabeledMesh) that is watertight (every edge has at least
//! two triangles), consistently labelled (every region shell closed and facing one
//! material) and free of self-intersections — except [`copies`], whose copies overlap on
//! purpose to exercise a tracker's intersection handling. Bad parameters (non-positive
//! sizes, zero counts, NaN) are a typed [`GeneratorError`], never a panic. Randomised
//! generators take a `seed` and use `ChaCha8Rng`, so a seed names the same scene on every
//! platform.
//!
//! Label convention: 0 is the outside; closed objects get labels from 1.
//!
//! | generator | scene | labels |
//! |---|---|---|
//! | [`icosphere`] | one sphere, `20·4^s` triangles | `[outside, inside]` as given |
//! | [`random_spheres`] | `n` separated spheres in a box ([`place_random_spheres`], [`spheres_mesh`]) | `1..=n` |
//! | [`double_bubble`] | two equal bubbles meeting at 120° along a triple circle | 1, 2 |
//! | [`zalesak`] | Zalesak's notched sphere ([`NotchedSphere`]) | 1 |
//! | [`mesh_implicit`] | the zero set of any function, by marching tetrahedra | as given |
//! | [`voronoi_foam`] | the Voronoi cells of random seeds clipped to a cube | `1..=n` |
//! | [`copies`] | `k` rotated, overlapping copies of a mesh ([`copies_with_rotations`]) | offset per copy |
//! | [`subdivide`] | any mesh with every triangle split in four, `levels` times (same surface) | as given |

mod bubble;
mod copies;
mod cuboid;
mod error;
mod icosphere;
mod implicit;
mod spheres;
mod subdivide;
mod voronoi;
mod zalesak;

#[cfg(test)]
mod checks;

pub use bubble::double_bubble;
pub use copies::{copies, copies_with_rotations};
pub use cuboid::cuboid;
pub use error::GeneratorError;
pub use icosphere::{MAX_SUBDIVISIONS, icosphere};
pub use implicit::{EDGE_MARGIN, MAX_CELLS_PER_AXIS, mesh_implicit};
pub use spheres::{
    ATTEMPTS_PER_SPHERE, MIN_GAP_FRACTION, PlacedSphere, place_random_spheres, random_spheres,
    spheres_mesh,
};
pub use subdivide::subdivide;
pub use voronoi::{MAX_CELLS, MAX_SITE_ATTEMPTS, voronoi_foam};
pub use zalesak::{NotchedSphere, zalesak};
