//! # implicit-surface
//!
//! Animated implicit surfaces after Nesme & Bouthors 2006 ("Dynamic Triangulation of
//! Implicit Surfaces: towards the handling of topology changes"): a triangle mesh that
//! *follows* `F(x, t) = 0` from frame to frame instead of being rebuilt, with one of our
//! tracker backends doing the blending and splitting. Modules, in the paper's order:
//!
//! | stage | module | paper |
//! |---|---|---|
//! | the field `F`, `∇F` | [`field`]: [`ImplicitField`], skeletons with L2/Lₚ norms, sampled grids | §1, §5 |
//! | projection | [`project`]: Newton along the gradient, quasi-critical points | §2.2, eq. 2 |
//! | following + topology | [`follow`]: [`Follower`], [`propose`] | §2, §4 |
//! | geometric mesh | [`mod@refine`]: crack-free red–green refinement by normal angle α_r | §3 |
//! | from-scratch baseline | [`mod@polygonize`]: marching tetrahedra | §1.1, §2 |
//! | comparison | [`compare`]: ours vs marching tetrahedra every frame | §5 |
//!
//! Convention: the surface is `F = 0`, the inside `F > 0` (the paper's); meshes carry
//! labels `[front, back] = [0, 1]` (outside, inside), normals pointing out.
//!
//! ```no_run
//! use implicit_surface::{Follower, FollowParams, scenes};
//! let anim = scenes::crossing(1.1, 0.12, 40)?;
//! let mut follower = Follower::new(anim.field.clone(), anim.t0, None, FollowParams::new(anim.edge_length))?;
//! for k in 1..=anim.frames {
//!     let report = follower.advance_to(anim.time(k, anim.frames))?;
//!     println!("t = {:.3}: {} components", report.t, report.components);
//! }
//! # Ok::<(), implicit_surface::ImplicitError>(())
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod compare;
pub mod error;
pub mod field;
pub mod follow;
pub mod polygonize;
pub mod project;
pub mod refine;
pub mod scenes;

pub use error::ImplicitError;
pub use field::{
    Falloff, GridField, ImplicitField, Norm, Path, Skeleton, SkeletonElement, SkeletonField,
    SphereField, finite_difference_gradient,
};
pub use follow::{
    FollowParams, Follower, FrameReport, Proposal, QuasiCritical, QuasiCriticalKind, initial_mesh,
    outward_vertex_normals, propose, reproject,
};
pub use polygonize::{Polygonization, polygonize, polygonize_mesh};
pub use project::{
    ProjectParams, Projection, ProjectionOutcome, project_point, project_point_oriented,
};
pub use refine::{RefineParams, Refinement, refine};
