//! Grid edges that flaw their cells: non-physical transitions (§6.1) and deep complex
//! edges (§6.2–6.3).

use glam::IVec3;
use mesh_core::predicates::Axis;
use mesh_core::{Label, LabeledMesh};
use rayon::prelude::*;

use crate::stages::grid::primitives::GridEdge;
use crate::stages::grid::{Grid, NodeId};
use crate::stages::materials::{MaterialVector, Materials};

/// Every grid edge with at least `min_crossings` crossings, as `(node, axis)`.
fn edges_with_crossings<'a>(
    grid: &'a Grid,
    materials: &'a Materials,
    min_crossings: usize,
) -> impl ParallelIterator<Item = (NodeId, Axis)> + 'a {
    (0..grid.num_nodes() as u32)
        .into_par_iter()
        .map(NodeId::new)
        .flat_map_iter(move |n| {
            Axis::ALL
                .into_iter()
                .filter(move |&a| materials.edge_crossing_count(n, a) >= min_crossings)
                .map(move |a| (n, a))
        })
}

/// §6.1: edges along which the material vector is non-physical right after some
/// crossing, starting from the lower node's vector along that axis.
pub(crate) fn non_physical_edges(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
) -> Vec<GridEdge> {
    edges_with_crossings(grid, materials, 1)
        .map_init(MaterialVector::default, |v, (n, axis)| {
            let mut bad = false;
            materials.edge_vectors(mesh, n, axis, v, |x, v| {
                bad |= x.is_some() && v.physical_label().is_none()
            });
            bad.then(|| GridEdge {
                node: grid.node_coord(n),
                axis,
            })
        })
        .flatten()
        .collect()
}

/// Offsets `d` (in the edge's frame: `d[0]` along the edge) of the nodes within
/// Manhattan distance `radius` of the unit segment from 0 to `e_0`.
fn near_offsets(radius: i32) -> Vec<[i32; 3]> {
    let mut out = Vec::new();
    for s in -radius..=radius + 1 {
        let along = (-s).max(s - 1).max(0);
        for u in -radius..=radius {
            for w in -radius..=radius {
                if along + u.abs() + w.abs() <= radius {
                    out.push([s, u, w]);
                }
            }
        }
    }
    out
}

/// Result of the deep-edge test.
pub(crate) struct DeepEdges {
    /// Edges crossed by more than one triangle (§6.2).
    pub(crate) complex: usize,
    /// Complex edges tested (not adjacent to a non-physical cell).
    pub(crate) tested: usize,
    /// The deep ones (§6.3).
    pub(crate) deep: Vec<GridEdge>,
}

/// The labels of physical, unflawed allocated nodes, sorted: the materials the grid's
/// implicit surface can rebuild at all.
pub(crate) fn node_labels(grid: &Grid, materials: &Materials) -> Vec<Label> {
    let mut out: Vec<Label> = (0..grid.num_nodes() as u32)
        .into_par_iter()
        .map(NodeId::new)
        .filter(|&n| !materials.is_flawed(n))
        .filter_map(|n| materials.node_material(n).label())
        .fold(Vec::new, |mut acc, l| {
            if !acc.contains(&l) {
                acc.push(l);
            }
            acc
        })
        .reduce(Vec::new, |mut a, b| {
            a.extend(b);
            a
        });
    out.sort_unstable();
    out.dedup();
    out
}

/// §6.3: a complex edge not adjacent to a non-physical cell is *shallow* when every
/// label found along it (the labels of its crossing triangles — with physical vectors
/// all along, these are exactly the materials of its pieces) is the label of a physical,
/// unflawed node within Manhattan distance `radius` cells of it; otherwise *deep*.
/// `test == false` skips the neighbourhood search and calls every tested edge deep (the
/// Fig. 9 ablation).
///
/// Labels absent from `rebuildable` (no physical node anywhere carries them, see
/// [`node_labels`]) never make an edge deep. The paper's test sends an edge to remeshing
/// so that the explicit surface takes the topology of the implicit one at scale ℓ (thin
/// sheets split, close surfaces merge); for a material with no grid node at all the
/// implicit surface has nothing, so remeshing could not change its topology, only delete
/// it — a whole intersection-free material smaller than ℓ (a coarse cube, a thin plate)
/// vanished that way. Such a material's complex cells are kept like the paper's
/// closed-volume cells (small features persist). With a label some node does carry, the
/// paper's test applies unchanged, so thin parts of a material still split.
pub(crate) fn deep_edges(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    radius: i32,
    test: bool,
    non_physical: impl Fn(IVec3) -> bool + Sync,
) -> DeepEdges {
    let offsets = near_offsets(radius);
    let rebuildable = node_labels(grid, materials);
    let labels = mesh.label_pairs();
    let found: Vec<(bool, Option<GridEdge>)> = edges_with_crossings(grid, materials, 2)
        .map_init(Vec::<Label>::new, |wanted, (n, axis)| {
            let edge = GridEdge {
                node: grid.node_coord(n),
                axis,
            };
            if edge.cells().into_iter().any(&non_physical) {
                return (false, None);
            }
            if !test {
                // Ablation (Fig. 9): without the test every complex edge is deep.
                return (true, Some(edge));
            }
            wanted.clear();
            for x in materials.edge_crossings(n, axis) {
                wanted.extend_from_slice(&labels[x.tri.idx()]);
            }
            wanted.sort_unstable();
            wanted.dedup();
            wanted.retain(|w| rebuildable.binary_search(w).is_ok());
            let (a, (b, c)) = (axis.index(), axis.others());
            for d in &offsets {
                if wanted.is_empty() {
                    break;
                }
                let mut q = edge.node;
                q[a] += d[0];
                q[b] += d[1];
                q[c] += d[2];
                if grid.node_id(q).is_some_and(|id| materials.is_flawed(id)) {
                    continue;
                }
                if let Some(l) = materials.material_at(grid, q).label() {
                    wanted.retain(|&w| w != l);
                }
            }
            (true, (!wanted.is_empty()).then_some(edge))
        })
        .collect();
    DeepEdges {
        complex: found.len(),
        tested: found.iter().filter(|f| f.0).count(),
        deep: found.into_iter().filter_map(|f| f.1).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_offsets_are_the_manhattan_ball_of_a_segment() {
        let o = near_offsets(2);
        // 13 + 13 beside the segment, 5 + 5 one step beyond its ends, 1 + 1 two beyond.
        assert_eq!(o.len(), 38);
        assert!(o.contains(&[3, 0, 0]) && o.contains(&[-2, 0, 0]) && o.contains(&[1, 1, 1]));
        assert!(!o.contains(&[2, 1, 1]) && !o.contains(&[-1, 2, 0]));
        assert_eq!(near_offsets(0), vec![[0, 0, 0], [1, 0, 0]]);
    }
}
