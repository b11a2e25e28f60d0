//! Breaking points (§8.1, Fig. 10): where the material vector along a grid edge turns
//! from physical to non-physical.
//!
//! Walking edge `a → b` visits a sequence of states, each holding on a stretch:
//!
//! ```text
//!   status(a) │ v₀ ─ c₁ ─ v₁ ─ c₂ ─ … ─ c_k ─ v_k │ status(b)
//!   at a        a … c₁     c₁ … c₂        c_k … b    at b
//! ```
//!
//! `status` is the node's physical label ([`Materials::physical_label`]: one-hot and all
//! three ray axes agreeing; `None` otherwise), `v₀` the vector the ray along the edge's
//! axis gave `a`, and `vᵢ` the vector after crossing `cᵢ` ([`Materials::edge_vectors`]).
//! Wherever two consecutive states differ in being physical, the transition point — `a`,
//! a crossing, or `b` — is a breaking point carrying the physical state's label: the last
//! point with a well-defined label before (or after) an ill-defined stretch. Transitions
//! at a node arise only at flawed nodes, whose own status is non-physical although the
//! ray along the edge may be physical there; the breaking point then lies on the node and
//! the node takes that label at distance zero.
//!
//! The same walk records the first and last crossing of the edge and the breaking points
//! nearest each end ([`EdgeTransitions`]), the data §8.3 places edge vertices with.

use glam::DVec3;
use mesh_core::predicates::Axis;
use mesh_core::{Label, LabeledMesh};

use crate::stages::grid::primitives::GridEdge;
use crate::stages::grid::{Grid, NodeId};
use crate::stages::materials::{MaterialVector, Materials};

/// A point on a grid edge where the material vector turns from physical to non-physical,
/// with the physical side's label (§8.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BreakingPoint {
    /// Where it lies (on its grid edge).
    pub position: DVec3,
    /// The last well-defined label before the non-physical stretch.
    pub label: Label,
}

/// What §8.3 needs to know about a region edge the mesh crosses: positions are axis
/// coordinates along the edge (absolute, clamped to the edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeTransitions {
    /// The first crossing from the lower end (`None` when only breaking points at nodes
    /// lie on the edge).
    pub first_crossing: Option<f64>,
    /// The last crossing (nearest the upper end).
    pub last_crossing: Option<f64>,
    /// The breaking point nearest the lower end.
    pub lower_breaking: Option<f64>,
    /// The breaking point nearest the upper end.
    pub upper_breaking: Option<f64>,
}

/// Per-worker output of [`scan_edge`].
#[derive(Clone, Debug, Default)]
pub(crate) struct EdgeScans {
    /// Edges walked.
    pub(crate) scanned: usize,
    /// Edges with crossings or breaking points, by their lower end's region node index
    /// and axis.
    pub(crate) transitions: Vec<(u32, Axis, EdgeTransitions)>,
    /// Every breaking point, with its edge.
    pub(crate) points: Vec<(GridEdge, BreakingPoint)>,
}

/// The walk's running state.
struct Walk {
    prev: Option<Label>,
    t: EdgeTransitions,
    any: bool,
}

impl Walk {
    /// Enters state `next` at axis coordinate `coord` (`crossing`: whether a crossing is
    /// there), recording a breaking point if physicality changes.
    fn step(
        &mut self,
        edge: GridEdge,
        base: DVec3,
        coord: f64,
        next: Option<Label>,
        crossing: bool,
        out: &mut Vec<(GridEdge, BreakingPoint)>,
    ) {
        if crossing {
            self.t.first_crossing.get_or_insert(coord);
            self.t.last_crossing = Some(coord);
            self.any = true;
        }
        let label = match (self.prev, next) {
            (Some(l), None) | (None, Some(l)) => Some(l),
            _ => None,
        };
        if let Some(label) = label {
            let mut position = base;
            position[edge.axis.index()] = coord;
            out.push((edge, BreakingPoint { position, label }));
            self.t.lower_breaking.get_or_insert(coord);
            self.t.upper_breaking = Some(coord);
            self.any = true;
        }
        self.prev = next;
    }
}

/// Whether walking `edge`, whose end nodes have allocated ids `ends`, can find anything:
/// only an edge with crossings or a flawed end changes state along its length (the vector
/// is the same all along otherwise: an end's own vector equals its vector along every
/// axis), so every other edge is skipped without walking.
#[inline]
pub(crate) fn needs_walk(materials: &Materials, edge: GridEdge, ends: [Option<NodeId>; 2]) -> bool {
    let crossings = ends[0].map_or(0, |n| materials.edge_crossing_count(n, edge.axis));
    crossings > 0 || ends.iter().flatten().any(|&n| materials.is_flawed(n))
}

/// Walks `edge` (whose end nodes have physical labels `status`), appends its breaking
/// points to `out` and returns its transitions, if it has crossings or breaking points. The caller walks only edges for which [`needs_walk`]
/// holds.
pub(crate) fn scan_edge(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    edge: GridEdge,
    status: [Option<Label>; 2],
    buf: &mut MaterialVector,
    out: &mut EdgeScans,
) -> Option<EdgeTransitions> {
    let a = edge.node;
    let axis = edge.axis.index();
    let id = grid.node_id(a);
    out.scanned += 1;
    let lattice = grid.lattice();
    let base = lattice.node_position(a);
    let (lo, hi) = (
        lattice.plane(axis, a[axis]),
        lattice.plane(axis, a[axis] + 1),
    );
    let mut walk = Walk {
        prev: status[0],
        t: EdgeTransitions {
            first_crossing: None,
            last_crossing: None,
            lower_breaking: None,
            upper_breaking: None,
        },
        any: false,
    };
    let points = &mut out.points;
    match id {
        Some(n) => materials.edge_vectors(mesh, n, edge.axis, buf, |x, v| {
            let coord = x.map_or(lo, |x| x.coordinate.clamp(lo, hi));
            walk.step(edge, base, coord, v.physical_label(), x.is_some(), points);
        }),
        None => {
            let v = materials.material_at(grid, a).label();
            walk.step(edge, base, lo, v, false, points);
        }
    }
    walk.step(edge, base, hi, status[1], false, points);
    walk.any.then_some(walk.t)
}
