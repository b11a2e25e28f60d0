//! The default topological resolution ℓ: a scale that fits every material of the input.
//!
//! The mean edge length, the previous default, says how finely the surface is sampled,
//! not how thick its materials are: a unit cube of 12 triangles has mean edge 1.14, so
//! ℓ = 1.14 puts the whole cube inside one or two cells, no grid node inside it, and any
//! rebuild at that scale has nothing to rebuild it from. A coarse mesh of long edges is an
//! ordinary input (CAD tools and mesh libraries write them), so ℓ also has to follow the
//! geometry.
//!
//! The thickness measure is `3 V / A` per region shell (a closed component of triangle
//! sides facing one material, [`mesh_core::regions`]), with `V` its enclosed volume and
//! `A` its area: `r` for a ball of radius `r`, `a / 2` for a cube of side `a`, `1.5 t` for
//! a plate of thickness `t`, `1.5 r` for a long cylinder of radius `r`. Dividing by
//! [`CELLS_PER_THICKNESS`] puts several grid planes through the thinnest material in every
//! direction, so each material has physical grid nodes and its features (faces, creases)
//! are resolved by several cells. Why 8: the rebuild's volume error is about linear in ℓ;
//! for two unit boxes overlapping in a cube of side 0.6 (tests/loss.rs) each label's
//! volume was 1.6 % off the exact split at ℓ = 1/8 (factor 4) and 0.35 % at ℓ = 1/16
//! (factor 8), and the issue asks for 1 %.

use mesh_core::geometry::{total_area, triangle_area};
use mesh_core::remesh::improve::mean_edge_length;
use mesh_core::{Label, LabeledMesh, Side};
use serde::Serialize;

/// ℓ is at most the thinnest shell's `3 V / A` divided by this.
pub const CELLS_PER_THICKNESS: f64 = 8.0;

/// ℓ is at least `sqrt(area / MAX_SURFACE_CELLS)`: a sliver shell of almost no volume
/// would otherwise ask for a grid far too fine to allocate. When this bound decides,
/// [`CellSizeChoice::reason`] says so and the loss check of [`crate::fix_with`] reports
/// what the coarser grid could not keep.
pub const MAX_SURFACE_CELLS: f64 = 4.0e6;

/// Which rule set ℓ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CellSizeRule {
    /// Given by the caller ([`crate::GridParams::cell_size`]).
    Given,
    /// The mean edge length: every material is at least [`CELLS_PER_THICKNESS`] cells
    /// thick at that scale.
    MeanEdgeLength,
    /// The thinnest material's `3 V / A` over [`CELLS_PER_THICKNESS`].
    ThinnestMaterial,
    /// The lower bound from [`MAX_SURFACE_CELLS`].
    SurfaceCellBound,
    /// Coarsened from the rule's choice until the grid fit its incidence budget
    /// ([`crate::GridOptions`]'s `max_cell_entries`): large triangles at a slant cover
    /// many cells with their boxes, which the surface-cell bound does not foresee.
    GridBudget,
}

impl CellSizeRule {
    /// Whether ℓ sat at a bound rather than at what the geometry asked for: a finer ℓ
    /// would not fit the grid, so it is no remedy for a lost material.
    pub fn is_bound(self) -> bool {
        matches!(
            self,
            CellSizeRule::SurfaceCellBound | CellSizeRule::GridBudget
        )
    }
}

/// The cell size used and why (recorded in [`crate::FixReport`] and by
/// [`crate::GridTracker::cell_size_choice`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellSizeChoice {
    /// ℓ.
    pub cell_size: f64,
    /// The rule that decided.
    pub rule: CellSizeRule,
    /// The thinnest bounded shell's material and its `3 V / A` (None without a bounded
    /// shell, or when ℓ was given).
    pub thinnest: Option<(Label, f64)>,
    /// One sentence for people.
    pub reason: String,
}

impl CellSizeChoice {
    /// ℓ as given by the caller.
    pub fn given(cell_size: f64) -> Self {
        Self {
            cell_size,
            rule: CellSizeRule::Given,
            thinnest: None,
            reason: format!("ℓ = {cell_size} given by the caller"),
        }
    }
}

/// The thinnest bounded region shell of `mesh`: its label and `3 V / A`. Shells with no
/// positive volume (the outside, inside-out parts of a tangled input) are skipped.
pub fn thinnest_shell(mesh: &LabeledMesh) -> Option<(Label, f64)> {
    let regions = mesh.regions();
    let mut area = vec![0.0; regions.shells.len()];
    for t in mesh.triangles() {
        let a = triangle_area(&mesh.tri_positions(t));
        for side in [Side::Front, Side::Back] {
            if let Some(s) = regions.shell_of(t, side) {
                area[s] += a;
            }
        }
    }
    regions
        .shells
        .iter()
        .zip(&area)
        .filter(|(s, a)| s.volume > 0.0 && **a > 0.0 && s.label != Label::OUTSIDE)
        .map(|(s, a)| (s.label, 3.0 * s.volume / a))
        .filter(|(_, t)| t.is_finite() && *t > 0.0)
        .min_by(|x, y| x.1.total_cmp(&y.1))
}

/// ℓ for `mesh` when the caller gives none: the mean edge length, or less where some
/// material is thinner than [`CELLS_PER_THICKNESS`] mean edges (see the module doc),
/// bounded below by [`MAX_SURFACE_CELLS`].
pub fn default_cell_size(mesh: &LabeledMesh) -> CellSizeChoice {
    let mean = mean_edge_length(mesh);
    let thinnest = thinnest_shell(mesh);
    let floor = (total_area(mesh) / MAX_SURFACE_CELLS).sqrt();
    let (mut cell_size, mut rule) = (mean, CellSizeRule::MeanEdgeLength);
    if let Some((_, t)) = thinnest
        && t / CELLS_PER_THICKNESS < cell_size
    {
        cell_size = t / CELLS_PER_THICKNESS;
        rule = CellSizeRule::ThinnestMaterial;
    }
    if cell_size < floor {
        cell_size = floor;
        rule = CellSizeRule::SurfaceCellBound;
    }
    let thin = thinnest.map_or("no bounded material".to_string(), |(l, t)| {
        format!("thinnest material {l}: 3V/A = {t:.4}")
    });
    let reason = match rule {
        CellSizeRule::MeanEdgeLength => {
            format!("ℓ = mean edge length {mean:.4}; {thin}, at least {CELLS_PER_THICKNESS} cells")
        }
        CellSizeRule::ThinnestMaterial => format!(
            "ℓ = {cell_size:.4} = ({thin}) / {CELLS_PER_THICKNESS}, below the mean edge \
             length {mean:.4}, so that every material is resolved"
        ),
        _ => format!(
            "ℓ = {cell_size:.4}, the bound of {MAX_SURFACE_CELLS:e} surface cells; {thin} \
             would need less, so thinner materials may not be represented"
        ),
    };
    CellSizeChoice {
        cell_size,
        rule,
        thinnest,
        reason,
    }
}

/// The tracker's default ℓ: the mean edge length, recorded with the thinnest material for
/// comparison. The tracker does not follow [`default_cell_size`]: ℓ is also its
/// improvement's target edge length (0.5–1.5 ℓ over the whole mesh), so a smaller ℓ would
/// refine every coarse scene's whole surface each step; its flaw stage keeps materials
/// coarser than ℓ instead (see `stages::flaws::edges::deep_edges`).
pub fn tracker_cell_size(mesh: &LabeledMesh) -> CellSizeChoice {
    let mean = mean_edge_length(mesh);
    let thinnest = thinnest_shell(mesh);
    let thin = thinnest.map_or("no bounded material".to_string(), |(l, t)| {
        format!("thinnest material {l}: 3V/A = {t:.4}")
    });
    CellSizeChoice {
        cell_size: mean,
        rule: CellSizeRule::MeanEdgeLength,
        thinnest,
        reason: format!("ℓ = mean edge length {mean:.4} (the tracker's default); {thin}"),
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::test_util::{cube, sphere, union};

    #[test]
    fn a_coarse_cube_gets_a_sixteenth_of_its_side() {
        let c = cube(DVec3::ZERO, DVec3::ONE, 0, 1);
        let choice = default_cell_size(&c);
        assert_eq!(choice.rule, CellSizeRule::ThinnestMaterial);
        assert!((choice.cell_size - 0.0625).abs() < 1e-12, "{choice:?}");
        assert!(mean_edge_length(&c) > 1.0);
    }

    #[test]
    fn a_fine_sphere_keeps_the_mean_edge_length() {
        let s = sphere(4, DVec3::ZERO, 1.0, 0, 1);
        let choice = default_cell_size(&s);
        assert_eq!(choice.rule, CellSizeRule::MeanEdgeLength, "{choice:?}");
        assert_eq!(choice.cell_size, mean_edge_length(&s));
    }

    #[test]
    fn the_smallest_material_decides() {
        let m = union(&[
            sphere(3, DVec3::ZERO, 1.0, 0, 1),
            sphere(1, DVec3::new(2.0, 0.0, 0.0), 0.1, 0, 2),
        ]);
        let choice = default_cell_size(&m);
        let (label, t) = choice.thinnest.expect("bounded shells");
        assert_eq!(label, Label::new(2));
        assert!(t > 0.08 && t < 0.1, "{t}");
        assert!((choice.cell_size - t / CELLS_PER_THICKNESS).abs() < 1e-12);
    }
}
