//! The one trait both tracker backends implement, and what a step reports.
//!
//! A simulator owns a `Box<dyn SurfaceTracker>`, proposes new vertex positions each time
//! step and reads back a clean mesh. The contract that makes it safe to call inside a long
//! run: a failed [`SurfaceTracker::advance`] returns an error and leaves the previous,
//! valid mesh exactly as it was.

use std::time::Duration;

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::geometry::label_volumes;
use crate::ids::{Label, VertexId};
use crate::mesh::LabeledMesh;
use crate::remesh::VertexAttributes;

/// A surface tracker backend.
pub trait SurfaceTracker: Send {
    /// Short backend name (`"grid"`, `"collision"`).
    fn name(&self) -> &str;

    /// The current mesh. Between successful steps it always passes `validate()`.
    fn mesh(&self) -> &LabeledMesh;

    /// Moves towards `proposed` (one position per vertex slot of [`Self::mesh`], indexed by
    /// `VertexId`; positions of dead slots are ignored), resolves the topology the motion
    /// implies, improves the mesh, and reports what it did. On error the mesh is unchanged.
    fn advance(&mut self, proposed: &[DVec3]) -> Result<StepReport, TrackError>;

    /// The per-vertex attributes (velocities, temperatures, …) the backend itself carries
    /// through its steps, indexed like [`Self::mesh`]'s vertex slots; `None` (the
    /// default) when it carries none. A backend that implements this keeps them on
    /// surviving vertices, blends them through its edits and transfers them to the
    /// vertices it rebuilds, which only it can do well (the grid backend by PIC, §8.4).
    fn attributes(&self) -> Option<&VertexAttributes> {
        None
    }

    /// Hands the backend attributes to carry (`dim` values per vertex slot of
    /// [`Self::mesh`], e.g. from `VertexAttributes::zeros`). A backend that carries none
    /// gives them back as `Err`, and the caller must carry them itself (the facade's
    /// `surftrack::Tracker` does, by nearest-vertex transfer after each step).
    fn set_attributes(&mut self, attrs: VertexAttributes) -> Result<(), VertexAttributes> {
        Err(attrs)
    }
}

/// Wall time of one pipeline stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageTiming {
    /// Stage name, as in the paper (`"materials"`, `"ccd"`, …).
    pub stage: &'static str,
    /// Seconds spent.
    pub seconds: f64,
}

/// Counts of the topology changes and mesh edits a step performed.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TopologyEvents {
    /// Regions joined (merges / snaps).
    pub merges: u64,
    /// Regions pulled apart (splits / pinches).
    pub splits: u64,
    /// T1 events: vertex separations.
    pub t1: u64,
    /// T2 events: degenerate tetrahedra removed.
    pub t2: u64,
    /// Edge splits, flips, collapses and smoothing moves of mesh improvement.
    pub remeshing_edits: u64,
    /// Materials present before the step and gone after it (no triangle side faces them
    /// any more), in increasing order: a material a step deletes is never silent.
    pub vanished: Vec<Label>,
}

/// What one successful step did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StepReport {
    /// Time per stage, in pipeline order.
    pub stages: Vec<StageTiming>,
    /// Topology changes and edits.
    pub events: TopologyEvents,
    /// Live vertices after the step.
    pub vertices: usize,
    /// Live triangles after the step.
    pub triangles: usize,
    /// Sub-steps taken (time-step halving in the collision backend; 1 otherwise).
    pub substeps: u32,
    /// Enclosed volume of every bounded material (label ≠ 0) before and after the step,
    /// by label; empty when the backend does not measure it.
    pub volumes: Vec<LabelVolume>,
}

/// The enclosed volume of one material before and after a step or a repair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LabelVolume {
    /// The material.
    pub label: Label,
    /// Volume before (0 when the material was absent).
    pub before: f64,
    /// Volume after (0 when the material is gone).
    pub after: f64,
}

/// Per-material volume, presence and contacts of a mesh: what [`LabelVolume`]s,
/// [`TopologyEvents::vanished`] and neighbour changes ([`MaterialCensus::contact_changes`])
/// are computed from, linear passes per mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialCensus {
    /// Enclosed volume per label that some live triangle side faces (label 0, the outside,
    /// included: minus the sum of the others on a closed mesh).
    pub volumes: std::collections::BTreeMap<Label, f64>,
    /// Every pair of materials that share an interface (some live triangle carries the two
    /// labels), as `[lower, higher]`, sorted, each once.
    pub contacts: Vec<[Label; 2]>,
}

/// Pairs of materials that started or stopped sharing an interface between two meshes
/// ([`MaterialCensus::contact_changes`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ContactChanges {
    /// Pairs in contact after, not before.
    pub gained: u64,
    /// Pairs in contact before, not after.
    pub lost: u64,
}

impl MaterialCensus {
    /// The census of `mesh`: [`label_volumes`], whose keys are exactly the labels some
    /// live triangle side carries, and the contacts of its live triangles.
    pub fn of(mesh: &LabeledMesh) -> Self {
        let alive = mesh.tri_alive_flags();
        let mut contacts: Vec<[Label; 2]> = mesh
            .label_pairs()
            .iter()
            .zip(alive)
            .filter(|(_, a)| **a)
            .map(|(&[f, b], _)| [f.min(b), f.max(b)])
            .collect();
        contacts.par_sort_unstable();
        contacts.dedup();
        Self {
            volumes: label_volumes(mesh),
            contacts,
        }
    }

    /// Contacts gained and lost from `self` (before) to `after`, among materials present
    /// in both: a pair with a material that vanished or appeared is that material's
    /// event, not a change of neighbours.
    ///
    /// Why this counts T1 processes: in a 3D foam a T1 is a neighbour swap (Weaire and
    /// Hutzler 2001; Los Topos §4.4: "two materials that originally share a border
    /// separate from one another while two different neighbouring materials become
    /// connected"). In 3D the two halves are separate elementary events — a face shrinks
    /// to an edge and its two cells lose contact, or an edge shrinks to a point and the
    /// cells at its ends gain a new face — and each changes exactly one pair, so
    /// `gained + lost` is the number of elementary T1 events between the two meshes, up to
    /// events undone within the interval.
    pub fn contact_changes(&self, after: &MaterialCensus) -> ContactChanges {
        let present = |l: &Label| self.volumes.contains_key(l) && after.volumes.contains_key(l);
        let counted = |c: &&[Label; 2]| present(&c[0]) && present(&c[1]);
        let (mut gained, mut lost) = (0, 0);
        let (mut a, mut b) = (
            self.contacts.iter().filter(counted).peekable(),
            after.contacts.iter().filter(counted).peekable(),
        );
        loop {
            match (a.peek(), b.peek()) {
                (Some(x), Some(y)) if x == y => {
                    a.next();
                    b.next();
                }
                (Some(x), Some(y)) if x < y => {
                    lost += 1;
                    a.next();
                }
                (Some(_), Some(_)) | (None, Some(_)) => {
                    gained += 1;
                    b.next();
                }
                (Some(_), None) => {
                    lost += 1;
                    a.next();
                }
                (None, None) => break,
            }
        }
        ContactChanges { gained, lost }
    }

    /// Bounded materials (label ≠ 0) of `self` (before) and `after`, with both volumes.
    pub fn volumes_to(&self, after: &MaterialCensus) -> Vec<LabelVolume> {
        let mut labels: Vec<Label> = self
            .volumes
            .keys()
            .chain(after.volumes.keys())
            .copied()
            .filter(|&l| l != Label::OUTSIDE)
            .collect();
        labels.sort_unstable();
        labels.dedup();
        labels
            .into_iter()
            .map(|label| LabelVolume {
                label,
                before: self.volumes.get(&label).copied().unwrap_or(0.0),
                after: after.volumes.get(&label).copied().unwrap_or(0.0),
            })
            .collect()
    }

    /// Labels present in `self` (before) and absent from `after`, in increasing order.
    pub fn vanished_in(&self, after: &MaterialCensus) -> Vec<Label> {
        self.volumes
            .keys()
            .filter(|l| !after.volumes.contains_key(l))
            .copied()
            .collect()
    }
}

impl StepReport {
    /// Appends a stage timing.
    pub fn time_stage(&mut self, stage: &'static str, elapsed: Duration) {
        self.stages.push(StageTiming {
            stage,
            seconds: elapsed.as_secs_f64(),
        });
    }

    /// Total seconds over all stages.
    pub fn total_seconds(&self) -> f64 {
        self.stages.iter().map(|s| s.seconds).sum()
    }
}

/// Why a step failed. The tracker's mesh is the one from before the step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrackError {
    /// `proposed` must have one entry per vertex slot.
    #[error("proposed positions: expected {expected} (one per vertex slot), got {got}")]
    ProposalLength {
        /// `mesh().vertex_capacity()`.
        expected: usize,
        /// The length passed in.
        got: usize,
    },
    /// A proposed position is NaN or infinite.
    #[error("proposed position of vertex {vertex} is not finite: {position:?}")]
    NonFiniteProposal {
        /// The vertex.
        vertex: VertexId,
        /// The offending position.
        position: [f64; 3],
    },
    /// A proposed position has a coordinate above [`crate::predicates::MAX_COORDINATE`]
    /// (2¹⁰⁰) in magnitude, where the exact predicates are no longer exact.
    #[error(
        "proposed position of vertex {vertex} is out of the supported range (|coordinate| ≤ 2^100 ≈ 1.3e30): {position:?}"
    )]
    ProposalOutOfRange {
        /// The vertex.
        vertex: VertexId,
        /// The offending position.
        position: [f64; 3],
    },
    /// The mesh handed to the tracker does not satisfy its preconditions.
    #[error("invalid input mesh: {0}")]
    InvalidInput(String),
    /// A stage could not complete within its bounds.
    #[error("stage `{stage}` failed: {reason}")]
    StageFailed {
        /// The stage.
        stage: &'static str,
        /// What happened.
        reason: String,
    },
    /// The optional per-step time budget ran out.
    #[error("time budget of {budget:?} exceeded in stage `{stage}`")]
    TimeBudgetExceeded {
        /// The stage running when the budget ran out.
        stage: &'static str,
        /// The budget.
        budget: Duration,
    },
}

/// Checks a proposal's length, finiteness and range against a mesh: the common first
/// stage of every backend's `advance`.
pub fn check_proposal(mesh: &LabeledMesh, proposed: &[DVec3]) -> Result<(), TrackError> {
    if proposed.len() != mesh.vertex_capacity() {
        return Err(TrackError::ProposalLength {
            expected: mesh.vertex_capacity(),
            got: proposed.len(),
        });
    }
    for v in mesh.vertices() {
        let p = proposed[v.idx()];
        if !p.is_finite() {
            return Err(TrackError::NonFiniteProposal {
                vertex: v,
                position: p.to_array(),
            });
        }
        if !crate::predicates::within_max_coordinate(p) {
            return Err(TrackError::ProposalOutOfRange {
                vertex: v,
                position: p.to_array(),
            });
        }
    }
    Ok(())
}

/// Serde for `Option<Duration>` as seconds (a number, or `null`), for the backends' time
/// budgets: records and scenario files say `time_budget = 2.5`. Use with
/// `#[serde(with = "mesh_core::tracker::optional_seconds")]`.
pub mod optional_seconds {
    use std::time::Duration;

    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Writes the duration as seconds, or `null`.
    pub fn serialize<S: Serializer>(value: &Option<Duration>, s: S) -> Result<S::Ok, S::Error> {
        value.map(|d| d.as_secs_f64()).serialize(s)
    }

    /// Reads seconds (or `null`); a negative, non-finite or too large number is an error
    /// naming the value.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Duration>, D::Error> {
        match Option::<f64>::deserialize(d)? {
            None => Ok(None),
            Some(x) => Duration::try_from_secs_f64(x)
                .map(Some)
                .map_err(|e| serde::de::Error::custom(format!("time_budget = {x}: {e}"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn census(labels: &[u32], contacts: &[[u32; 2]]) -> MaterialCensus {
        MaterialCensus {
            volumes: labels.iter().map(|&l| (Label::new(l), 1.0)).collect(),
            contacts: contacts
                .iter()
                .map(|&[a, b]| [Label::new(a), Label::new(b)])
                .collect(),
        }
    }

    #[test]
    fn contacts_of_a_double_bubble() {
        let mesh = crate::generators::double_bubble(1.0, 8).unwrap();
        let c = MaterialCensus::of(&mesh);
        let expect: Vec<[Label; 2]> = [[0, 1], [0, 2], [1, 2]]
            .iter()
            .map(|&[a, b]| [Label::new(a), Label::new(b)])
            .collect();
        assert_eq!(c.contacts, expect);
        assert_eq!(c.contact_changes(&c), ContactChanges::default());
    }

    #[test]
    fn contact_changes_count_neighbour_swaps_not_vanished_materials() {
        // Cells 1..4 around a face 1|2 that shrinks away while 3|4 appears (one T1 made
        // of its two elementary halves); cell 5 vanishes, taking 5|1 with it.
        let before = census(
            &[0, 1, 2, 3, 4, 5],
            &[[0, 1], [1, 2], [1, 3], [1, 5], [2, 3]],
        );
        let after = census(&[0, 1, 2, 3, 4], &[[0, 1], [1, 3], [2, 3], [3, 4]]);
        assert_eq!(
            before.contact_changes(&after),
            ContactChanges { gained: 1, lost: 1 }
        );
        assert_eq!(
            after.contact_changes(&before),
            ContactChanges { gained: 1, lost: 1 }
        );
    }
}
