//! Mesh validation: layered checks of the invariants every tracker output must satisfy
//! (see `DESIGN.md`, "Invariants"), returning a structured [`ValidationReport`] that names
//! the ids involved. Validation never panics on any mesh the public API can build (NaN
//! coordinates, dangling or degenerate triangles, inconsistent labels and all).
//!
//! The layers, cheapest and most basic first; each one calls the one below (as in
//! spade's sanity checks), so asking for a layer runs everything it relies on:
//! 1. [`check_topology`] — dangling vertex references, repeated-vertex (degenerate)
//!    triangles, duplicate triangles, boundary edges, corner-table and vertex-ring
//!    integrity against a recomputation;
//! 2. [`check_labels`] — `front != back`, and one label per wedge around every edge
//!    (radial order, so non-manifold junctions are checked too);
//! 3. [`check_geometry`] — finite coordinates, no exactly zero-area triangle;
//! 4. placement — every surface component carries on its outside the material it lies
//!    in, by one exact ray per component ([`crate::placement`]; [`validate`] runs it when
//!    [`ValidateOptions::placement`] and layers 1–3 passed: it needs a closed,
//!    consistently labelled mesh);
//! 5. [`check_intersections`] — exact self-intersection test with a parallel broad phase
//!    (the expensive one; [`validate`] runs it when [`ValidateOptions::intersections`]).
//!
//! [`debug_validate!`](crate::debug_validate) runs layers 1–3 at pipeline stage
//! boundaries in debug builds.
//!
//! A note on the corner table: stored pairings are compared with the radial order of the
//! *current* positions. A mesh whose vertices moved (`set_position`) so far that the
//! radial order at a non-manifold edge changed, without relinking that edge, reports
//! `PairingMismatch` there: its wedge pairing no longer matches its geometry.

mod geometry;
mod intersections;
mod labels;
mod report;
mod topology;

#[cfg(test)]
pub(crate) mod testmesh;
#[cfg(test)]
mod tests;

pub use geometry::coordinate_extent;
pub use intersections::{any_intersection, triangles_intersect};
pub use report::{
    BoundaryEdge, CornerTableError, DanglingReference, InconsistentEdge, Listed, SameLabel,
    ValidationReport,
};

use crate::mesh::LabeledMesh;

/// What to check and how much to list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ValidateOptions {
    /// Run the exact self-intersection check (layer 4). Off by default: it costs about
    /// three times as much as layers 1–3 together (on a 1.3M-triangle sphere, ~1.0 vs
    /// ~0.3 CPU-seconds).
    pub intersections: bool,
    /// Run the placement check (layer 4) when layers 1–3 pass. On by default: it costs a
    /// pass over the triangles plus one exact ray per surface component, and catches the
    /// one labelling error the local layers cannot see (a part nested in another with the
    /// wrong material outside it), after which a tracker loses a material.
    pub placement: bool,
    /// Cap on the offenders *listed* per category; the counts stay exact.
    pub max_listed: usize,
}

impl Default for ValidateOptions {
    /// Layers 1–3, listing up to 100 offenders per category.
    fn default() -> Self {
        ValidateOptions {
            intersections: false,
            placement: true,
            max_listed: 100,
        }
    }
}

impl ValidateOptions {
    /// All five layers, listing up to 100 offenders per category.
    pub fn with_intersections() -> Self {
        ValidateOptions {
            intersections: true,
            ..Self::default()
        }
    }
}

/// Validates `mesh`: layers 1–3 always, layer 4 when `opts.placement` and layers 1–3
/// passed, layer 5 when `opts.intersections`.
pub fn validate(mesh: &LabeledMesh, opts: &ValidateOptions) -> ValidationReport {
    let (mut report, ctx, range) = layers_to_geometry(mesh, opts);
    if opts.placement && report.is_valid() {
        let mut listed = Listed::default();
        for m in crate::placement::misplaced_shells(mesh) {
            listed.push(m, opts.max_listed);
        }
        report.misplaced_shells = Some(listed);
    }
    if opts.intersections {
        report.self_intersecting_pairs =
            Some(intersections::check(mesh, range, &ctx, opts.max_listed));
    }
    report
}

/// Layer 1 only: ids, references, duplicates, boundary, corner table and rings.
pub fn check_topology(mesh: &LabeledMesh, opts: &ValidateOptions) -> ValidationReport {
    layers_to_topology(mesh, opts).0
}

/// Layers 1–2: adds label checks.
pub fn check_labels(mesh: &LabeledMesh, opts: &ValidateOptions) -> ValidationReport {
    layers_to_labels(mesh, opts).0
}

/// Layers 1–3: adds finite coordinates and zero-area triangles.
pub fn check_geometry(mesh: &LabeledMesh, opts: &ValidateOptions) -> ValidationReport {
    layers_to_geometry(mesh, opts).0
}

/// Layers 1–3 and 5: adds the exact self-intersection check (not placement).
pub fn check_intersections(mesh: &LabeledMesh, opts: &ValidateOptions) -> ValidationReport {
    let (mut report, ctx, range) = layers_to_geometry(mesh, opts);
    report.self_intersecting_pairs = Some(intersections::check(mesh, range, &ctx, opts.max_listed));
    report
}

fn layers_to_topology(
    mesh: &LabeledMesh,
    opts: &ValidateOptions,
) -> (ValidationReport, topology::EdgeContext) {
    let mut report = ValidationReport::default();
    let ctx = topology::check(mesh, opts.max_listed, &mut report);
    (report, ctx)
}

fn layers_to_labels(
    mesh: &LabeledMesh,
    opts: &ValidateOptions,
) -> (ValidationReport, topology::EdgeContext) {
    let (mut report, ctx) = layers_to_topology(mesh, opts);
    labels::check(mesh, &ctx, opts.max_listed, &mut report);
    (report, ctx)
}

/// Layers 1–3, with what layer 5 reuses: the edge context and the coordinate range.
fn layers_to_geometry(
    mesh: &LabeledMesh,
    opts: &ValidateOptions,
) -> (
    ValidationReport,
    topology::EdgeContext,
    geometry::CoordinateRange,
) {
    let (mut report, ctx) = layers_to_labels(mesh, opts);
    let range = geometry::coordinate_range(mesh);
    geometry::check(mesh, range, &ctx, opts.max_listed, &mut report);
    (report, ctx, range)
}

/// Validates a mesh at a pipeline stage boundary in debug builds, panicking with the
/// report if it is invalid; does nothing in release builds.
///
/// For the backends' tests and debug runs: put `debug_validate!(mesh, "after cut")`
/// between stages so a broken invariant is caught at the stage that broke it, with the
/// stage named. Runs layers 1–3 (no self-intersection check: too slow to run after every
/// stage). The panic is the point — this is an assertion; use `validate` to handle
/// invalid meshes gracefully ([`crate::validate::validate`]). Both arguments are borrowed (evaluated) in every build, so
/// variables used only here do not warn in release.
///
/// ```
/// use mesh_core::{LabeledMesh, DVec3, debug_validate};
/// let mesh = LabeledMesh::from_raw(
///     vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
///     &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
///     &[[0, 1]; 4],
/// ).unwrap();
/// debug_validate!(mesh, "after loading");
/// ```
#[macro_export]
macro_rules! debug_validate {
    ($mesh:expr, $stage:expr) => {{
        let (mesh, stage) = (&$mesh, &$stage);
        #[cfg(debug_assertions)]
        {
            let report =
                $crate::validate::validate(mesh, &$crate::validate::ValidateOptions::default());
            if !report.is_valid() {
                panic!("mesh invalid after stage {}: {}", stage, report);
            }
        }
        let _ = (mesh, stage);
    }};
}
