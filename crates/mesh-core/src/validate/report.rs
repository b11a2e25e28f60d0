//! What [`super::validate`] found: counts and capped lists of offenders per category,
//! each naming the ids involved.

use std::fmt;

use serde::Serialize;

use crate::ids::{CornerId, Label, TriId, VertexId};
use crate::placement::MisplacedShell;

/// Offenders of one category: the exact `count`, and the first `items` (up to
/// [`super::ValidateOptions::max_listed`], in increasing id order).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Listed<T> {
    /// How many offenders there are (exact, never capped).
    pub count: usize,
    /// The first offenders, at most `max_listed` of them.
    pub items: Vec<T>,
}

impl<T> Default for Listed<T> {
    fn default() -> Self {
        Listed {
            count: 0,
            items: Vec::new(),
        }
    }
}

impl<T> Listed<T> {
    /// True when there is no offender.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Counts an offender and lists it if fewer than `cap` are listed.
    pub(crate) fn push(&mut self, item: T, cap: usize) {
        self.count += 1;
        if self.items.len() < cap {
            self.items.push(item);
        }
    }

    /// Appends `other` (whose offenders come after ours in id order).
    pub(crate) fn append(&mut self, other: Listed<T>, cap: usize) {
        self.count += other.count;
        let room = cap.saturating_sub(self.items.len());
        self.items.extend(other.items.into_iter().take(room));
    }
}

/// A live triangle refers to a vertex that is dead or outside the vertex array.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct DanglingReference {
    /// The triangle.
    pub tri: TriId,
    /// The vertex it names.
    pub vertex: VertexId,
}

/// An edge with a single incident triangle (every edge of a closed mesh has ≥ 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct BoundaryEdge {
    /// The edge, lower vertex id first.
    pub edge: [VertexId; 2],
    /// Its only triangle.
    pub tri: TriId,
}

/// A triangle whose two sides carry the same label: it separates nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct SameLabel {
    /// The triangle.
    pub tri: TriId,
    /// The label on both sides.
    pub label: Label,
}

/// An edge around which some wedge of space is bounded by two sides with different
/// labels: the wedge would have to be two materials at once.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct InconsistentEdge {
    /// The edge, lower vertex id first.
    pub edge: [VertexId; 2],
    /// The incident triangles in radial order about `edge[0] → edge[1]`.
    pub tris: Vec<TriId>,
    /// The two triangles bounding the first inconsistent wedge (counter-clockwise).
    pub wedge: [TriId; 2],
    /// The labels their sides give that wedge.
    pub labels: [Label; 2],
}

/// A broken link of the corner table or of a vertex ring. Not constructible through the
/// public editing API; seeing one means a bug in mesh editing code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum CornerTableError {
    /// `opposite(corner)` names a corner of a dead or non-existent triangle.
    OppositeDead {
        /// The corner.
        corner: CornerId,
        /// Its opposite.
        opposite: CornerId,
    },
    /// `opposite(opposite(corner)) != corner`.
    OppositeNotSymmetric {
        /// The corner.
        corner: CornerId,
        /// Its opposite, which points elsewhere.
        opposite: CornerId,
    },
    /// The opposite corner's edge is not this corner's edge traversed in reverse.
    OppositeWrongEdge {
        /// The corner.
        corner: CornerId,
        /// Its opposite.
        opposite: CornerId,
    },
    /// The stored opposite differs from the pairing recomputed from the current radial
    /// order of the edge (`expected` is `None` on a boundary or degenerate edge).
    PairingMismatch {
        /// The corner.
        corner: CornerId,
        /// The recomputed opposite.
        expected: Option<CornerId>,
        /// The stored opposite.
        found: Option<CornerId>,
    },
    /// A vertex ring holds a corner that is not a live front corner at that vertex.
    RingForeignCorner {
        /// The vertex whose ring was walked.
        vertex: VertexId,
        /// The foreign corner.
        corner: CornerId,
    },
    /// A vertex ring visits a corner twice (it is cyclic).
    RingRepeatedCorner {
        /// The vertex whose ring was walked.
        vertex: VertexId,
        /// The repeated corner.
        corner: CornerId,
    },
    /// A live triangle's front corner is missing from its vertex's ring.
    MissingFromRing {
        /// The vertex.
        vertex: VertexId,
        /// The missing corner.
        corner: CornerId,
    },
}

/// The result of [`super::validate`]: every category of defect, each with an exact count
/// and a capped list naming the ids involved. Volumes are not part of it (see
/// [`crate::geometry::label_volumes`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ValidationReport {
    /// Live vertices.
    pub vertices: usize,
    /// Live triangles.
    pub triangles: usize,
    /// Distinct undirected edges of the live triangles.
    pub edges: usize,
    /// Edges with more than two triangles: legal (multi-material junctions), for context.
    pub non_manifold_edges: usize,
    /// Layer 1: live triangles naming dead or out-of-range vertices.
    pub dangling_references: Listed<DanglingReference>,
    /// Layer 1: triangles with a repeated vertex.
    pub degenerate: Listed<TriId>,
    /// Layer 1: triangles with the same vertex set as an earlier one: `[earlier, later]`.
    pub duplicates: Listed<[TriId; 2]>,
    /// Layer 1: edges with a single triangle.
    pub boundary_edges: Listed<BoundaryEdge>,
    /// Layer 1: corner-table and vertex-ring integrity errors.
    pub corner_table: Listed<CornerTableError>,
    /// Layer 2: triangles with `front == back`.
    pub same_label_triangles: Listed<SameLabel>,
    /// Layer 2: edges with a wedge bounded by two different labels.
    pub inconsistent_edges: Listed<InconsistentEdge>,
    /// Layer 3: live vertices with a NaN or infinite coordinate.
    pub non_finite: Listed<VertexId>,
    /// Layer 3: live vertices with a coordinate outside the supported range
    /// ([`crate::predicates::range`]): above 2¹⁰⁰ in magnitude, or every vertex of a mesh
    /// smaller than 2⁻¹⁰⁰.
    pub out_of_range: Listed<VertexId>,
    /// Layer 3: triangles with three distinct vertices at exactly collinear positions.
    pub zero_area: Listed<TriId>,
    /// Layer 4: surface components whose outside is labelled with another material than
    /// the one they lie in (a part drawn inside another, both labelled against 0), by
    /// [`crate::placement::misplaced_shells`]; `None` when not checked (layers 1–3 failed,
    /// or [`super::ValidateOptions::placement`] is off).
    pub misplaced_shells: Option<Listed<MisplacedShell>>,
    /// Layer 5: pairs of triangles that intersect other than along what they share,
    /// `[lower id, higher id]`; `None` when not checked.
    pub self_intersecting_pairs: Option<Listed<[TriId; 2]>>,
}

impl ValidationReport {
    /// True when no category has an offender. Placement and self-intersections count only
    /// if they were checked.
    pub fn is_valid(&self) -> bool {
        self.dangling_references.is_empty()
            && self.degenerate.is_empty()
            && self.duplicates.is_empty()
            && self.boundary_edges.is_empty()
            && self.corner_table.is_empty()
            && self.same_label_triangles.is_empty()
            && self.inconsistent_edges.is_empty()
            && self.non_finite.is_empty()
            && self.out_of_range.is_empty()
            && self.zero_area.is_empty()
            && self.misplaced_shells.as_ref().is_none_or(Listed::is_empty)
            && self
                .self_intersecting_pairs
                .as_ref()
                .is_none_or(Listed::is_empty)
    }
}

/// How many offenders per category the summary names.
const SHOWN: usize = 3;

fn category<T>(
    f: &mut fmt::Formatter<'_>,
    name: &str,
    list: &Listed<T>,
    show: impl Fn(&T) -> String,
) -> fmt::Result {
    if list.is_empty() {
        return Ok(());
    }
    write!(f, "\n  {} {}:", list.count, name)?;
    for (k, item) in list.items.iter().take(SHOWN).enumerate() {
        let sep = if k == 0 { " " } else { "; " };
        write!(f, "{sep}{}", show(item))?;
    }
    let shown = SHOWN.min(list.items.len());
    if list.count > shown {
        write!(f, "{}…", if shown == 0 { " " } else { "; " })?;
    }
    Ok(())
}

impl fmt::Display for ValidationReport {
    /// A short summary: the verdict, the sizes, and per failing category its count and
    /// first few offenders.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verdict = if self.is_valid() { "valid" } else { "INVALID" };
        write!(
            f,
            "mesh {verdict}: {} vertices, {} triangles, {} edges ({} non-manifold)",
            self.vertices, self.triangles, self.edges, self.non_manifold_edges
        )?;
        if self.self_intersecting_pairs.is_none() {
            write!(f, "; self-intersections not checked")?;
        }
        category(
            f,
            "dangling vertex references",
            &self.dangling_references,
            |d| format!("{} → {}", d.tri, d.vertex),
        )?;
        category(f, "degenerate triangles", &self.degenerate, |t| {
            t.to_string()
        })?;
        category(f, "duplicate triangles", &self.duplicates, |[a, b]| {
            format!("{b} = {a}")
        })?;
        category(f, "boundary edges", &self.boundary_edges, |e| {
            format!("{}–{} ({})", e.edge[0], e.edge[1], e.tri)
        })?;
        category(f, "corner-table errors", &self.corner_table, |e| {
            format!("{e:?}")
        })?;
        category(
            f,
            "triangles with one label on both sides",
            &self.same_label_triangles,
            |s| format!("{} ({})", s.tri, s.label),
        )?;
        category(
            f,
            "inconsistently labelled edges",
            &self.inconsistent_edges,
            |e| {
                format!(
                    "{}–{}: wedge {}/{} sees {} and {}",
                    e.edge[0], e.edge[1], e.wedge[0], e.wedge[1], e.labels[0], e.labels[1]
                )
            },
        )?;
        category(f, "non-finite vertices", &self.non_finite, |v| {
            v.to_string()
        })?;
        category(
            f,
            "vertices out of range (|coordinate| ≤ 2^100 ≈ 1.3e30, mesh not smaller than 2^-100 ≈ 7.9e-31; rescale the mesh)",
            &self.out_of_range,
            |v| v.to_string(),
        )?;
        category(f, "zero-area triangles", &self.zero_area, |t| t.to_string())?;
        if let Some(shells) = &self.misplaced_shells {
            category(f, "misplaced shells", shells, |m| m.to_string())?;
        }
        if let Some(pairs) = &self.self_intersecting_pairs {
            category(f, "self-intersecting triangle pairs", pairs, |[a, b]| {
                format!("{a} × {b}")
            })?;
        }
        Ok(())
    }
}
