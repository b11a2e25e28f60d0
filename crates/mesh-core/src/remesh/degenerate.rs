//! Degenerate removal (T2 processes, Los Topos §6; El Topo §3.6): regions that collapsed to
//! zero volume, and triangles that collapsed to a segment or a point.
//!
//! An edge collapse or flip can flatten a small closed region — typically a tetrahedron —
//! into two triangles on the same three vertices. Their labels are still consistent: the
//! zero-volume region "between" them carries one label `X` on both inner sides. If the
//! materials outside the pair differ (`L1 ≠ L2`), one triangle is deleted and the other
//! relabelled `[L1 | L2]`, keeping the interface between them; if they agree, both are
//! deleted and the two outer regions merge. Which sides are inner is decided from labels
//! alone — the corner table cannot tell coincident sheets apart — by the rule that the
//! two facing sides must carry the same label (when both readings are consistent, both
//! say "delete both", so the outcome does not depend on the choice; see `classify`).
//!
//! Triangles with a repeated vertex are deleted outright. Every removal is one [`Edit`]
//! through [`apply_edit`], so a guard may veto it; vertices left without triangles are
//! removed by the same edit.
//!
//! **Thin regions** ([`remove_thin_regions`]) are the same process one step earlier: a
//! bounded region whose volume is at most Ω and whose mean thickness is a small fraction
//! of an edge has not collapsed to coincident triangles, but it is no region either. Snap
//! merging makes them: it joins two sheets pair by pair, and the last gaps between the
//! joined pairs are closed pockets of the surrounding material, a few thousandths of an
//! edge thick, whose sides are neighbours along the mesh (so the merge takes them for
//! one sheet) and whose tiny edges block every collapse. Such a region is absorbed into
//! the neighbour it shares most of its boundary with, `Y`: its sides facing `Y` are
//! deleted (the two regions become one) and its other sides relabelled to face `Y` — what
//! the coincident-pair rule does when the pair's volume is exactly zero.

use rayon::prelude::*;

use crate::corner::Side;
use crate::ids::{CornerId, Label, TriId, VertexId};
use crate::mesh::LabeledMesh;

use crate::broadphase::Aabb;

use super::attributes::VertexAttributes;
use super::edit::{Edit, EditError, VertexRef, apply_edit};
use super::guard::EditGuard;

/// Bound on the duplicate-finding passes: one pass resolves every pair; more are needed
/// only where three or more triangles share a vertex set.
const MAX_PASSES: usize = 8;

/// What [`remove_degenerate`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct DegenerateReport {
    /// Triangles with a repeated vertex deleted.
    pub collapsed_removed: usize,
    /// Coincident pairs between different materials: one deleted, one relabelled.
    pub pairs_relabelled: usize,
    /// Coincident pairs between the same material: both deleted.
    pub pairs_removed: usize,
    /// Isolated vertices removed with them.
    pub vertices_removed: usize,
    /// Edits the guard refused (counted per attempt).
    pub vetoed: usize,
    /// Groups of coincident triangles whose labels describe no zero-volume region (left
    /// for validation to report).
    pub unresolved: usize,
}

/// How a coincident pair resolves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Resolution {
    /// Delete both: the outer materials agree.
    DeleteBoth,
    /// Delete the second and give the first these labels.
    Relabel([Label; 2]),
}

/// Removes collapsed triangles and zero-volume regions (see the module doc).
pub fn remove_degenerate(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
) -> DegenerateReport {
    remove_degenerate_in(mesh, attrs, guard, None)
}

/// The live triangles to examine: every one, or those at the `only` vertices (increasing,
/// each once). Coincident triangles share their vertices, so a duplicate of a triangle at
/// `only` is there too.
fn triangles_at(mesh: &LabeledMesh, only: Option<&[VertexId]>) -> Vec<TriId> {
    match only {
        None => mesh.triangles().collect(),
        Some(vertices) => {
            let mut tris: Vec<TriId> = vertices
                .iter()
                .filter(|&&v| mesh.is_vertex_alive(v))
                .flat_map(|&v| mesh.vertex_triangles(v))
                .collect();
            tris.par_sort_unstable();
            tris.dedup();
            tris
        }
    }
}

/// [`remove_degenerate`] restricted to the triangles at the `only` vertices (`None`: the
/// whole mesh), the work list of [`super::improve_in`].
pub fn remove_degenerate_in(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    only: Option<&[VertexId]>,
) -> DegenerateReport {
    let mut report = DegenerateReport::default();
    let mut edit = Edit::default();

    let collapsed: Vec<TriId> = triangles_at(mesh, only)
        .into_iter()
        .filter(|&t| is_collapsed(mesh.tri(t)))
        .collect();
    for t in collapsed {
        edit.clear();
        edit.remove_tris.push(t);
        remove_orphans(mesh, &mut edit);
        if commit(mesh, attrs, guard, &edit, &mut report) {
            report.collapsed_removed += 1;
        }
    }

    let mut keyed: Vec<([VertexId; 3], TriId)> = Vec::new();
    for _ in 0..MAX_PASSES {
        keyed.clear();
        let tris = triangles_at(mesh, only);
        keyed.par_extend(tris.par_iter().filter_map(|&t| {
            (mesh.is_triangle_alive(t) && may_have_duplicate(mesh, t)).then(|| {
                let mut key = mesh.tri(t);
                key.sort_unstable();
                (key, t)
            })
        }));
        keyed.par_sort_unstable();
        let mut changed = false;
        report.unresolved = 0;
        for group in keyed.chunk_by(|x, y| x.0 == y.0) {
            if group.len() < 2 {
                continue;
            }
            let pair = (0..group.len())
                .flat_map(|i| (i + 1..group.len()).map(move |j| (group[i].1, group[j].1)))
                .find_map(|(t1, t2)| classify(mesh, t1, t2).map(|r| (t1, t2, r)));
            let Some((t1, t2, resolution)) = pair else {
                report.unresolved += 1;
                continue;
            };
            edit.clear();
            edit.remove_tris.extend([t1, t2]);
            if let Resolution::Relabel(labels) = resolution {
                edit.add_tris
                    .push((mesh.tri(t1).map(VertexRef::Old), labels));
            }
            remove_orphans(mesh, &mut edit);
            if commit(mesh, attrs, guard, &edit, &mut report) {
                changed = true;
                match resolution {
                    Resolution::DeleteBoth => report.pairs_removed += 1,
                    Resolution::Relabel(_) => report.pairs_relabelled += 1,
                }
            }
        }
        if !changed {
            break;
        }
    }
    report
}

/// Which regions [`remove_thin_regions`] absorbs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ThinRegionParams {
    /// Largest volume of a region absorbed (Ω: the volume one edit may move between
    /// labels, as for collapses).
    pub max_volume: f64,
    /// Largest mean thickness, `volume / area` of the region's boundary (half the gap of a
    /// pocket between two sheets).
    pub max_mean_thickness: f64,
}

/// What [`remove_thin_regions`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ThinRegionReport {
    /// Regions absorbed into a neighbour.
    pub absorbed: usize,
    /// Their summed volume (moved from their label to the neighbour's).
    pub volume: f64,
    /// Thin regions left alone: it is the last region of its label (absorbing it would
    /// make a material vanish), a region of the same label may lie inside (a cavity the
    /// shell alone cannot tell from the region's own), or the edit was refused or vetoed.
    pub refused: usize,
}

/// Bound on the passes of [`remove_thin_regions`]: a pass absorbs every thin region whose
/// triangles the earlier absorptions of the pass left alone; neighbours of an absorbed
/// region are looked at again in the next pass, with their new shape.
const MAX_THIN_PASSES: usize = 4;

/// Absorbs every thin bounded region into its main neighbour (see the module doc); with
/// `only_at`, only the regions with a corner at one of those vertices (a merge closes the
/// pockets at its own snaps and leaves shrinking regions elsewhere to T2).
pub fn remove_thin_regions(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &ThinRegionParams,
    only_at: Option<&[VertexId]>,
) -> ThinRegionReport {
    let mut report = ThinRegionReport::default();
    let marked = only_at.map(|vertices| {
        let mut flags = vec![false; mesh.vertex_capacity()];
        for v in vertices {
            if let Some(f) = flags.get_mut(v.idx()) {
                *f = true;
            }
        }
        flags
    });
    let at_marked = |mesh: &LabeledMesh, t: TriId| match &marked {
        None => true,
        Some(flags) => mesh
            .tri(t)
            .iter()
            .any(|v| flags.get(v.idx()).copied().unwrap_or(false)),
    };
    let mut edit = Edit::default();
    for _ in 0..MAX_THIN_PASSES {
        let regions = mesh.regions();
        let thin: Vec<usize> = (0..regions.shells.len())
            .filter(|&s| {
                let shell = &regions.shells[s];
                shell.closed
                    && shell.consistent
                    && shell.volume > 0.0
                    && shell.volume <= params.max_volume
                    && shell.volume <= params.max_mean_thickness * shell.area
            })
            .collect();
        if thin.is_empty() {
            break;
        }
        // Sides of each shell, and the box of every shell (for the cavity test).
        let mut sides: Vec<Vec<(TriId, Side)>> = vec![Vec::new(); regions.shells.len()];
        let mut boxes = vec![Aabb::EMPTY; regions.shells.len()];
        let mut is_thin = vec![false; regions.shells.len()];
        for &s in &thin {
            is_thin[s] = true;
        }
        for t in mesh.triangles() {
            for side in [Side::Front, Side::Back] {
                let Some(s) = regions.shell_of(t, side) else {
                    continue;
                };
                for p in mesh.tri_positions(t) {
                    boxes[s] = boxes[s].including(p);
                }
                if is_thin[s] {
                    sides[s].push((t, side));
                }
            }
        }
        // Shells per label: the last one of a label is never absorbed, so no material
        // disappears here (a droplet below resolution is T2's to remove, and the caller's
        // to be told about).
        let mut per_label: Vec<(Label, usize)> = Vec::new();
        for shell in &regions.shells {
            match per_label.iter_mut().find(|(l, _)| *l == shell.label) {
                Some(entry) => entry.1 += 1,
                None => per_label.push((shell.label, 1)),
            }
        }
        let mut touched = vec![false; mesh.triangle_capacity()];
        let mut changed = false;
        for &s in &thin {
            let shell = &regions.shells[s];
            let own = &sides[s];
            if own.iter().any(|&(t, _)| touched[t.idx()]) {
                continue; // a neighbour was absorbed: next pass
            }
            if !own.iter().any(|&(t, _)| at_marked(mesh, t)) {
                continue;
            }
            // A shell of the same label facing inward (negative volume) inside this one's
            // box may be a cavity of this very region: relabelling the outer shell alone
            // would leave the cavity's sides with the old label.
            let cavity = regions.shells.iter().zip(&boxes).any(|(other, b)| {
                other.label == shell.label
                    && other.volume < 0.0
                    && b.min.cmpge(boxes[s].min).all()
                    && b.max.cmple(boxes[s].max).all()
            });
            let Some(count) = per_label
                .iter_mut()
                .find(|(l, _)| *l == shell.label)
                .map(|entry| &mut entry.1)
            else {
                continue;
            };
            let last = *count <= 1;
            let Some(into) = main_neighbour(mesh, own).filter(|_| !cavity && !last) else {
                report.refused += 1;
                continue;
            };
            edit.clear();
            for &(t, side) in own {
                let mut labels = mesh.labels(t);
                edit.remove_tris.push(t);
                if labels[side.flip().index()] != into {
                    labels[side.index()] = into;
                    edit.add_tris
                        .push((mesh.tri(t).map(VertexRef::Old), labels));
                }
            }
            remove_orphans(mesh, &mut edit);
            match apply_edit(mesh, attrs, guard, &edit) {
                Ok(_) => {
                    *count -= 1;
                    for &(t, _) in own {
                        touched[t.idx()] = true;
                    }
                    touched.resize(mesh.triangle_capacity(), false);
                    report.absorbed += 1;
                    report.volume += shell.volume;
                    changed = true;
                }
                Err(_) => report.refused += 1,
            }
        }
        if !changed {
            break;
        }
    }
    report
}

/// The label across the given sides that covers the most area (ties: the smaller
/// label); `None` for a shell whose triangles have it on both sides.
fn main_neighbour(mesh: &LabeledMesh, sides: &[(TriId, Side)]) -> Option<Label> {
    let mut areas: Vec<(Label, f64)> = Vec::new();
    for &(t, side) in sides {
        let labels = mesh.labels(t);
        if labels[0] == labels[1] {
            return None;
        }
        let [a, b, c] = mesh.tri_positions(t);
        let area = 0.5 * (b - a).cross(c - a).length();
        let across = labels[side.flip().index()];
        match areas.iter_mut().find(|(l, _)| *l == across) {
            Some(entry) => entry.1 += area,
            None => areas.push((across, area)),
        }
    }
    areas
        .into_iter()
        .max_by(|x, y| x.1.total_cmp(&y.1).then(y.0.cmp(&x.0)))
        .map(|(l, _)| l)
}

/// True when another triangle on `t`'s edge `v0 v1` has `t`'s third vertex — necessary
/// for a duplicate, since coincident triangles share all three edges. Walking the radial
/// cycle of one edge (two corners on a manifold edge) is much cheaper than sorting every
/// triangle's vertex set; an open cycle falls back to the vertex ring, which lists every
/// triangle at `v0` whatever the corner table says.
fn may_have_duplicate(mesh: &LabeledMesh, t: TriId) -> bool {
    let [a, b, c] = mesh.tri(t);
    if is_collapsed([a, b, c]) {
        return false;
    }
    let start = CornerId::of(t, Side::Front, 2);
    let mut last = start;
    for r in mesh.radial_corners(start) {
        if r.tri() != t && mesh.corner_vertex(r) == c {
            return true;
        }
        last = r;
    }
    if mesh.opposite(last).map(CornerId::dual) == Some(start) {
        return false;
    }
    mesh.edge_triangles(a, b)
        .any(|u| u != t && mesh.tri(u).contains(&c))
}

fn is_collapsed([a, b, c]: [VertexId; 3]) -> bool {
    a == b || b == c || c == a
}

/// Applies `edit`, counting vetoes and removed vertices; true when applied.
fn commit(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    edit: &Edit,
    report: &mut DegenerateReport,
) -> bool {
    match apply_edit(mesh, attrs, guard, edit) {
        Ok(_) => {
            report.vertices_removed += edit.remove_vertices.len();
            true
        }
        Err(EditError::Vetoed(_)) => {
            report.vetoed += 1;
            false
        }
        // Malformed cannot happen (ids are live and distinct); nothing changed either way.
        Err(_) => false,
    }
}

/// Adds to `edit.remove_vertices` every vertex of a removed triangle that no kept or added
/// triangle uses.
pub(crate) fn remove_orphans(mesh: &LabeledMesh, edit: &mut Edit) {
    for i in 0..edit.remove_tris.len() {
        for v in mesh.tri(edit.remove_tris[i]) {
            let used_by_kept = mesh
                .vertex_triangles(v)
                .any(|t| !edit.remove_tris.contains(&t));
            let used_by_added = edit
                .add_tris
                .iter()
                .any(|(verts, _)| verts.contains(&VertexRef::Old(v)));
            if !used_by_kept && !used_by_added && !edit.remove_vertices.contains(&v) {
                edit.remove_vertices.push(v);
            }
        }
    }
}

/// How the coincident triangles `t1`, `t2` resolve, or `None` if their labels describe no
/// zero-volume region.
///
/// With equal orientations the facing sides are (front₁, back₂) or (back₁, front₂); with
/// opposite orientations (front₁, front₂) or (back₁, back₂). A reading is consistent when
/// the facing sides share a label `X`. If both readings are consistent, then reading one's
/// outer labels are reading two's inner ones (and vice versa), so both readings see equal
/// outer labels and both delete the pair.
fn classify(mesh: &LabeledMesh, t1: TriId, t2: TriId) -> Option<Resolution> {
    let (p, q) = (mesh.tri(t1), mesh.tri(t2));
    if is_collapsed(p) {
        return None;
    }
    let same_orientation = (0..3).any(|r| [q[r], q[(r + 1) % 3], q[(r + 2) % 3]] == p);
    let (l1, l2) = (mesh.labels(t1), mesh.labels(t2));
    let readings = if same_orientation {
        [(Side::Front, Side::Back), (Side::Back, Side::Front)]
    } else {
        [(Side::Front, Side::Front), (Side::Back, Side::Back)]
    };
    let (s1, s2) = readings
        .into_iter()
        .find(|&(s1, s2)| l1[s1.index()] == l2[s2.index()])?;
    let outer1 = l1[s1.flip().index()];
    let outer2 = l2[s2.flip().index()];
    if outer1 == outer2 {
        return Some(Resolution::DeleteBoth);
    }
    // t1's inner side now faces what t2's outer side faced.
    let mut labels = l1;
    labels[s1.index()] = outer2;
    Some(Resolution::Relabel(labels))
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::remesh::NoGuard;

    fn mesh_of(tris: &[[u32; 3]], labels: &[[u32; 2]]) -> LabeledMesh {
        let p = (0..5)
            .map(|i| DVec3::new(i as f64, (i * i) as f64, 0.5 * i as f64))
            .collect();
        LabeledMesh::from_raw(p, tris, labels).unwrap()
    }

    #[test]
    fn classify_relabels_with_the_outer_labels_on_the_right_sides() {
        // Same orientation: t1 = [1 | 3] above, t2 = [3 | 2] below; region 3 between.
        let m = mesh_of(&[[0, 1, 2], [0, 1, 2]], &[[1, 3], [3, 2]]);
        let r = classify(&m, TriId::new(0), TriId::new(1));
        assert_eq!(r, Some(Resolution::Relabel([Label::new(1), Label::new(2)])));
        // Opposite orientation: t2 reversed carries [2 | 3].
        let m = mesh_of(&[[0, 1, 2], [0, 2, 1]], &[[1, 3], [2, 3]]);
        let r = classify(&m, TriId::new(0), TriId::new(1));
        assert_eq!(r, Some(Resolution::Relabel([Label::new(1), Label::new(2)])));
        // The inner region on t1's front: t1 = [3 | 1], t2 reversed = [3 | 2] → keep [2 | 1].
        let m = mesh_of(&[[0, 1, 2], [1, 0, 2]], &[[3, 1], [3, 2]]);
        let r = classify(&m, TriId::new(0), TriId::new(1));
        assert_eq!(r, Some(Resolution::Relabel([Label::new(2), Label::new(1)])));
    }

    #[test]
    fn classify_deletes_pairs_between_one_material_and_refuses_nonsense() {
        let m = mesh_of(&[[0, 1, 2], [0, 1, 2]], &[[1, 3], [3, 1]]);
        assert_eq!(
            classify(&m, TriId::new(0), TriId::new(1)),
            Some(Resolution::DeleteBoth)
        );
        // Both readings consistent ([3|1] and [1|3] with equal orientation): delete both.
        let m = mesh_of(&[[0, 1, 2], [1, 2, 0]], &[[3, 1], [1, 3]]);
        assert_eq!(
            classify(&m, TriId::new(0), TriId::new(1)),
            Some(Resolution::DeleteBoth)
        );
        // No shared label on facing sides: not a collapsed region.
        let m = mesh_of(&[[0, 1, 2], [0, 1, 2]], &[[1, 2], [3, 4]]);
        assert_eq!(classify(&m, TriId::new(0), TriId::new(1)), None);
    }

    /// Tetrahedron 0123 (label 1 inside, 0 outside) with, glued on its face 012, a second
    /// tetrahedron 0124 of label 2 whose apex lies `height` below the face's centre; with
    /// `spare`, a separate tetrahedron 5678 of label 2 far away (so that label 2 survives
    /// the thin one's absorption).
    fn glued_tetrahedra(height: f64, spare: bool) -> LabeledMesh {
        let mut p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0 / 3.0, 1.0 / 3.0, -height),
        ];
        let far = DVec3::new(10.0, 0.0, 0.0);
        p.extend([p[0], p[1], p[2], p[3]].map(|q| q + far));
        // The shared face 012 first (its normal points to −z, into label 2), then the
        // outer faces of each tetrahedron: front faces away from the tetrahedron's centre.
        let mut tris = vec![[0u32, 2, 1]];
        let mut labels = vec![[2u32, 1]];
        let spare_faces = [[5, 7, 6], [5, 6, 8], [6, 7, 8], [5, 8, 7]];
        let tetrahedra = [
            (&[[0, 1, 3], [1, 2, 3], [0, 3, 2]][..], 1, [0usize, 1, 2, 3]),
            (&[[0, 1, 4], [1, 2, 4], [2, 0, 4]][..], 2, [0, 1, 2, 4]),
            (&spare_faces[..], 2, [5, 6, 7, 8]),
        ];
        for &(faces, inside, corners) in &tetrahedra[..2 + usize::from(spare)] {
            let centre = corners.iter().map(|&i| p[i]).sum::<DVec3>() / 4.0;
            for &f in faces {
                let [a, b, c] = f.map(|i: u32| p[i as usize]);
                let outward = (b - a).cross(c - a).dot(a - centre) > 0.0;
                tris.push(f);
                labels.push(if outward { [0, inside] } else { [inside, 0] });
            }
        }
        if !spare {
            p.truncate(5);
        }
        LabeledMesh::from_raw(p, &tris, &labels).unwrap()
    }

    fn label_volume(m: &LabeledMesh, label: u32) -> f64 {
        m.regions()
            .bounded()
            .filter(|s| s.label == Label::new(label))
            .map(|s| s.volume)
            .sum()
    }

    fn absorb(
        m: &mut LabeledMesh,
        params: &ThinRegionParams,
        only: Option<&[VertexId]>,
    ) -> ThinRegionReport {
        remove_thin_regions(m, &mut VertexAttributes::none(), &mut NoGuard, params, only)
    }

    /// The volume of the regular tetrahedron 0123 (the spare one).
    const SPARE: f64 = 1.0 / 6.0;

    #[test]
    fn a_thin_region_is_absorbed_into_its_main_neighbour() {
        let params = ThinRegionParams {
            max_volume: 0.01,
            max_mean_thickness: 0.01,
        };
        let mut m = glued_tetrahedra(1e-4, true);
        assert!(crate::validate::validate(&m, &Default::default()).is_valid());
        let thin = label_volume(&m, 2) - SPARE;
        assert!(thin > 0.0 && thin < 1e-4, "{thin}");
        let before_1 = label_volume(&m, 1);
        let r = absorb(&mut m, &params, None);
        assert_eq!(r.absorbed, 1, "{r:?}");
        assert!((r.volume - thin).abs() < 1e-15);
        // Label 2 faced the outside on most of its area: its outer faces go, the face it
        // shared with label 1 now faces the outside, and the apex vertex is gone.
        assert_eq!(m.num_triangles(), 4 + 4);
        assert_eq!(m.num_vertices(), 4 + 4);
        assert!(crate::validate::validate(&m, &Default::default()).is_valid());
        assert!((label_volume(&m, 2) - SPARE).abs() < 1e-15);
        assert!((label_volume(&m, 1) - before_1).abs() < 1e-15);

        // Without the spare, the thin tetrahedron is all of label 2: absorbing it would
        // make a material vanish, so it stays.
        let mut m = glued_tetrahedra(1e-4, false);
        let r = absorb(&mut m, &params, None);
        assert_eq!((r.absorbed, r.refused), (0, 1), "{r:?}");
        assert_eq!(m.num_triangles(), 7);
    }

    #[test]
    fn regions_thicker_or_larger_than_the_bounds_stay() {
        let mut m = glued_tetrahedra(1e-4, true);
        let thin = label_volume(&m, 2) - SPARE;
        for params in [
            // Thin, but more volume than one edit may move.
            ThinRegionParams {
                max_volume: 0.5 * thin,
                max_mean_thickness: 1.0,
            },
            // Small, but thicker than asked.
            ThinRegionParams {
                max_volume: 1.0,
                max_mean_thickness: 1e-6,
            },
        ] {
            let r = absorb(&mut m, &params, None);
            assert_eq!(r, ThinRegionReport::default());
            assert_eq!(m.num_triangles(), 7 + 4);
        }
        // Thin and small, but no corner at the given vertices (vertex 3 is only on the
        // thick tetrahedron, which these bounds keep).
        let params = ThinRegionParams {
            max_volume: 2.0 * thin,
            max_mean_thickness: 0.01,
        };
        let only = [VertexId::new(3)];
        let r = absorb(&mut m, &params, Some(&only));
        assert_eq!(r, ThinRegionReport::default());
        let only = [VertexId::new(4)];
        let r = absorb(&mut m, &params, Some(&only));
        assert_eq!(r.absorbed, 1);
    }

    #[test]
    fn collapsed_triangles_and_their_orphan_vertices_go() {
        // A lone collapsed triangle [3, 3, 4]: removed, and its vertices with it.
        let mut m = mesh_of(
            &[[0, 1, 2], [0, 2, 1], [3, 3, 4]],
            &[[1, 3], [1, 3], [0, 1]],
        );
        let r = remove_degenerate(&mut m, &mut VertexAttributes::none(), &mut NoGuard);
        assert_eq!(r.collapsed_removed, 1);
        assert_eq!(r.vertices_removed, 5, "{r:?}");
        assert_eq!(r.pairs_removed, 1);
        assert_eq!(m.num_triangles(), 0);
        assert_eq!(m.num_vertices(), 0);
    }
}
