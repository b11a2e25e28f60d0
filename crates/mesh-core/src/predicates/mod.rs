//! Exact geometric predicates: orientation tests, axis-aligned ray crossings with
//! Simulation of Simplicity, and closed triangle–triangle intersection.
//!
//! Every function here returns a decision that is exact for finite `f64` input (products
//! of coordinate differences must neither overflow nor underflow, as for Shewchuk's
//! predicates; [`range`] gives the coordinate range where that holds, which validation
//! checks), does not allocate, and does not panic. Floating-point filters make the
//! common case cheap; the exact path runs only when the filter cannot certify the answer.
//!
//! # Sign convention
//!
//! [`orient3d`]`(a, b, c, d)` is the sign of `((b − a) × (c − a)) · (d − a)`: `Positive`
//! when `d` is in front of triangle `a, b, c`, i.e. on the side its right-hand normal
//! points into — the side of the `front` label of a mesh triangle. (`robust`'s raw
//! `orient3d` has the opposite sign; never call it directly.) [`orient2d`]`(a, b, c)` is
//! `Positive` when `a, b, c` turn counter-clockwise. Projections along an [`Axis`] keep
//! the other two coordinates in cyclic order, so a triangle whose normal has a positive
//! `axis` component projects counter-clockwise.
//!
//! # Glossary
//!
//! - **closed** test: touching (sharing a single boundary point) counts as intersecting.
//! - **degenerate** triangle: collinear (or coincident) vertices, zero normal; treated as
//!   the segment or point it spans.
//! - **SoS**, Simulation of Simplicity (Edelsbrunner & Mücke 1990): every ray-query point
//!   `p` stands for `p + (ε, ε², ε³)` with infinitesimal `ε > 0`, so no query is ever
//!   degenerate; see [`crossing`] for what this buys the grid tracker.
//! - **filter**: a floating-point evaluation with a proven error bound that settles easy
//!   cases before the exact (adaptive-precision) evaluation.
//!
//! # Entry points
//!
//! - [`orient2d`], [`orient3d`], [`orient2d_axis`], with [`Sign`] and [`Axis`];
//! - [`cross_axis_line_triangle`], [`cross_axis_segment_triangle`],
//!   [`compare_crossing_with_point`], [`compare_crossings`] for material-vector ray
//!   casting;
//! - [`intersect_triangle_triangle`], [`intersect_segment_triangle`], and for mesh
//!   validation [`intersect_sharing_vertex`] and [`intersect_sharing_edge`], both behind
//!   [`intersect_keyed_triangle_triangle`] (two triangles of one mesh, shared vertices
//!   recognised by key).

pub mod crossing;
pub mod order;
pub mod orient;
mod planar;
pub mod range;
pub mod tri_tri;

#[cfg(test)]
mod exact_ref;

pub use crossing::{
    AxisCrossing, compare_crossing_with_point, cross_axis_line_triangle,
    cross_axis_segment_triangle, orient2d_sos,
};
pub use order::compare_crossings;
pub use orient::{Axis, Sign, collinear, orient2d, orient2d_axis, orient3d};
pub use range::{MAX_COORDINATE, MIN_EXTENT, below_min_extent, within_max_coordinate};
pub use tri_tri::{
    intersect_keyed_triangle_triangle, intersect_segment_triangle, intersect_sharing_edge,
    intersect_sharing_vertex, intersect_triangle_triangle,
};
