//! Stage "t1t2": topological separation (Los Topos §5 T1, §6 T2; El Topo §3.6 pinching).
//!
//! ```text
//! t1t2(mesh, motion):
//!     initiate     collapse short edges between two feature-curve vertices that the flow
//!                  shortens (the collapses that start T1 and T2 processes)
//!     remove_degenerate         T2: zero-volume regions, collapsed triangles
//!     separate_irregular        T1: vertex separation, all irregular vertices globally
//!                               sorted by separation strength
//!     pinch_singular            singular vertices duplicated (optional)
//!     remove_degenerate         what the separations flattened
//! ```
//!
//! **Why `initiate` lives here.** Mesh improvement refuses collapses that join two feature
//! curves or two curve corners (they change topology), so in a foam a shrinking face stops
//! shrinking at its corners and no T1 or T2 process ever starts. Los Topos starts them with
//! exactly those collapses, and keeps them *consistent with vertex separation* (§5,
//! "Consistency with Edge Collapses"): such a collapse happens only when the flow is
//! shortening the edge — with an ambient flow, `e · (∇u e) < 0` at the edge's midpoint;
//! otherwise, when the step's motion of its two ends brings them closer. Separation acts
//! only where the strength is positive, so the two never undo each other. The collapse is
//! mesh-core's [`collapse_edge`] in its [`CollapsePlacement::Midpoint`] mode, through the
//! collision guard (its pseudo-motion: both ends move to the midpoint); it may leave
//! coincident triangles (a flattened tetrahedron), which T2 then removes. If the stage
//! nevertheless ends with a mesh that fails `validate` layers 1–3,
//! it is run again from a snapshot without `initiate`, so the stage never breaks a step.

use glam::{DMat3, DVec3};
use mesh_core::remesh::{
    AreaDecrease, CollapseParams, CollapsePlacement, Edit, EditGuard, FeatureParams,
    SeparationParams, SeparationStrength, VelocityDivergence, VertexAttributes, VertexRef,
    classify_vertex, collapse_edge, pinch_singular_vertices, remove_degenerate,
    separate_irregular_vertices,
};
use mesh_core::validate::{ValidateOptions, check_geometry};
use mesh_core::{LabeledMesh, TopologyEvents, VertexId};
use rayon::prelude::*;

use crate::guard::CollisionGuard;
use crate::params::AmbientFlow;

/// Options of [`separate_regions`], derived from [`crate::CollisionParams`].
#[derive(Clone, Debug)]
pub(crate) struct T1T2Options {
    /// Run T1 (initiating collapses, separation).
    pub t1: bool,
    /// Pinch singular vertices after T1.
    pub pinch: bool,
    /// Run T2 (degenerate removal).
    pub t2: bool,
    /// Edges shorter than this may start a T1/T2 process (the collapse threshold).
    pub min_edge_length: f64,
    /// Ω: the largest label volume change one initiating collapse may cause.
    pub max_volume_change: f64,
    /// Vertex separation options.
    pub separation: SeparationParams,
    /// The flow whose divergence ranks separations (else: area decrease).
    pub ambient_flow: Option<AmbientFlow>,
}

/// Counts of one run of the stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct T1T2Counts {
    /// Initiating collapses committed.
    pub initiated: u64,
    /// T1 vertex separations.
    pub t1: u64,
    /// T2 removals (coincident pairs relabelled or removed).
    pub t2: u64,
    /// Singular vertices pinched.
    pub pinched: u64,
    /// True when the stage was re-run without initiating collapses.
    pub fell_back: bool,
}

/// Runs the stage (see the module doc). `motion` is each vertex's proposed displacement
/// over this step (a 3-vector attribute that followed the mesh through the earlier edits).
/// `protected` are vertices snapped in this step or the previous one: T1 never separates
/// them (Los Topos §5 and §7 agree: a separation does not undo a fresh merge).
pub(crate) fn separate_regions(
    mesh: &mut LabeledMesh,
    motion: &mut VertexAttributes,
    guard: &mut CollisionGuard,
    options: &T1T2Options,
    protected: &[VertexId],
) -> T1T2Counts {
    let candidates = if options.t1 {
        initiating_candidates(mesh, motion, options)
    } else {
        Vec::new()
    };
    if candidates.is_empty() {
        return separate_only(mesh, motion, guard, options, protected);
    }
    let snapshot = mesh.clone();
    let snapshot_motion = motion.clone();
    let mut counts = T1T2Counts::default();
    for &(a, b) in &candidates {
        if initiate_collapse(mesh, motion, guard, options, a, b) {
            counts.initiated += 1;
        }
    }
    let rest = separate_only(mesh, motion, guard, options, protected);
    counts.t1 = rest.t1;
    counts.t2 = rest.t2;
    counts.pinched = rest.pinched;
    if counts.initiated == 0 || check_geometry(mesh, &ValidateOptions::default()).is_valid() {
        return counts;
    }
    // The initiating collapses left something T1/T2 could not resolve: start over.
    *mesh = snapshot;
    *motion = snapshot_motion;
    guard.reset();
    let mut counts = separate_only(mesh, motion, guard, options, protected);
    counts.fell_back = true;
    counts
}

/// T2, T1, pinching, T2 — without initiating collapses.
fn separate_only(
    mesh: &mut LabeledMesh,
    motion: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    options: &T1T2Options,
    protected: &[VertexId],
) -> T1T2Counts {
    let mut counts = T1T2Counts::default();
    let t2 = |mesh: &mut LabeledMesh, motion: &mut VertexAttributes, guard: &mut dyn EditGuard| {
        let d = remove_degenerate(mesh, motion, guard);
        (d.pairs_relabelled + d.pairs_removed) as u64
    };
    if options.t2 {
        counts.t2 += t2(mesh, motion, guard);
    }
    if options.t1 {
        let gate = Displacements::of(mesh, motion);
        let strength = Gated {
            strength: Strength::new(options.ambient_flow.as_ref(), &gate),
            protected: protected_flags(mesh, protected),
        };
        let s = separate_irregular_vertices(mesh, motion, guard, &options.separation, &strength);
        counts.t1 = s.separations as u64;
        if options.pinch {
            counts.pinched = pinch_singular_vertices(mesh, motion, guard) as u64;
        }
        if options.t2 && counts.t1 + counts.pinched > 0 {
            counts.t2 += t2(mesh, motion, guard);
        }
    }
    counts
}

/// Adds the stage's counts to a step's events.
pub(crate) fn add_counts(events: &mut TopologyEvents, counts: &T1T2Counts) {
    events.t1 += counts.t1;
    events.t2 += counts.t2;
    events.remeshing_edits += counts.initiated;
}

/// Short edges between two feature-curve vertices that the flow shortens, shortest first.
fn initiating_candidates(
    mesh: &LabeledMesh,
    motion: &VertexAttributes,
    options: &T1T2Options,
) -> Vec<(VertexId, VertexId)> {
    let features = FeatureParams::default();
    let mut found: Vec<(f64, VertexId, VertexId)> = mesh
        .triangles()
        .collect::<Vec<_>>()
        .par_iter()
        .flat_map_iter(|&t| {
            let tri = mesh.tri(t);
            (0..3).filter_map(move |k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a >= b {
                    return None;
                }
                let length = mesh.position(a).distance(mesh.position(b));
                (length < options.min_edge_length).then_some((length, a, b))
            })
        })
        .collect();
    found.par_sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    found.dedup_by(|x, y| (x.1, x.2) == (y.1, y.2));
    found
        .into_par_iter()
        .filter(|&(_, a, b)| {
            classify_vertex(mesh, a, &features).on_curve()
                && classify_vertex(mesh, b, &features).on_curve()
                && shortening(mesh, motion, options.ambient_flow.as_ref(), a, b)
        })
        .map(|(_, a, b)| (a, b))
        .collect()
}

/// Los Topos' consistency test: is the flow shortening edge `ab`?
fn shortening(
    mesh: &LabeledMesh,
    motion: &VertexAttributes,
    flow: Option<&AmbientFlow>,
    a: VertexId,
    b: VertexId,
) -> bool {
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    let e = pb - pa;
    match flow {
        Some(flow) => e.dot(flow.gradient(0.5 * (pa + pb)) * e) < 0.0,
        None => {
            let d = |v: VertexId| DVec3::from_slice(motion.get(v));
            e.dot(d(b) - d(a)) < 0.0
        }
    }
}

/// Collapses edge `ab` to its midpoint, allowing degenerate results (see the module doc):
/// mesh-core's collapse with [`CollapsePlacement::Midpoint`], refused where a surviving
/// triangle would turn by 90° or more, or a label's volume change by more than Ω. Returns
/// whether it was committed.
fn initiate_collapse(
    mesh: &mut LabeledMesh,
    motion: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    options: &T1T2Options,
    a: VertexId,
    b: VertexId,
) -> bool {
    if !(mesh.is_vertex_alive(a) && mesh.is_vertex_alive(b))
        || mesh.position(a).distance(mesh.position(b)) >= options.min_edge_length
    {
        return false;
    }
    let params = CollapseParams {
        placement: CollapsePlacement::Midpoint,
        allow_degenerate: true,
        min_normal_cos: 0.0,
        max_volume_change: options.max_volume_change,
        ..CollapseParams::default()
    };
    collapse_edge(mesh, motion, guard, a, b, &params).is_ok()
}

/// The T1 separation strength of Los Topos §5: the ambient flow's divergence along the
/// separation direction when the caller gave a flow, else the surface area the separation
/// removes — but only where this step's *proposed* motion pulls the two sides apart ([`side_divergence`] is positive; sides at rest do not separate).
/// Without that gate a flow that pushes two surfaces together (normal flow merging two
/// spheres) would see every fresh snap point separated again because separating it saves
/// area; with it, separation follows the flow, as Los Topos' collapse/separation
/// consistency asks. The proposal, not the resolved motion, is what counts: collision
/// response freezes approaching surfaces and repulsion pushes them apart, so the resolved
/// motion of two surfaces pressed together reads as pulling apart.
enum Strength<'a> {
    Flow(VelocityDivergence<Box<dyn Fn(DVec3) -> DMat3 + Sync + 'a>>),
    Area(&'a Displacements),
}

/// A snapshot of each vertex's proposed displacement, taken before vertex separation (which
/// mutates the attributes the strength would otherwise borrow). Vertices born later (the
/// separation's duplicates) read as at rest.
struct Displacements(Vec<DVec3>);

impl Displacements {
    fn of(mesh: &LabeledMesh, motion: &VertexAttributes) -> Self {
        let mut d = vec![DVec3::ZERO; mesh.vertex_capacity()];
        if motion.dim() == 3 {
            for v in mesh.vertices() {
                d[v.idx()] = DVec3::from_slice(motion.get(v));
            }
        }
        Self(d)
    }

    fn get(&self, v: VertexId) -> DVec3 {
        self.0.get(v.idx()).copied().unwrap_or(DVec3::ZERO)
    }
}

impl<'a> Strength<'a> {
    fn new(flow: Option<&'a AmbientFlow>, motion: &'a Displacements) -> Self {
        match flow {
            Some(flow) => Strength::Flow(VelocityDivergence {
                gradient: Box::new(move |p| flow.gradient(p)),
            }),
            None => Strength::Area(motion),
        }
    }
}

/// How fast the flow pulls the two sides of a proposed separation at `v` apart: the mean
/// proposed displacement of the one-ring corners of the triangles that go to the new vertex
/// `v_a` (the side `A`, which moves along `d`), minus that of the triangles that stay on
/// `v` (the rest), along `d`. The sides are read off the proposal's topology, not off the
/// geometry: near a fresh contact both sheets are nearly flat and a few hundredths of ℓ
/// apart, so "ahead of `v` along `d`" would mix their vertices. Gap triangles (they have
/// both `v_a` and `v`) belong to neither side.
fn side_divergence(motion: &Displacements, v: VertexId, d: DVec3, proposal: &Edit) -> f64 {
    let (mut a_side, mut rest) = ((DVec3::ZERO, 0usize), (DVec3::ZERO, 0usize));
    for (verts, _) in &proposal.add_tris {
        let on_a = verts.iter().any(|r| matches!(r, VertexRef::New(_)));
        let on_v = verts.contains(&VertexRef::Old(v));
        let side = match (on_a, on_v) {
            (true, false) => &mut a_side,
            (false, true) => &mut rest,
            _ => continue,
        };
        for r in verts {
            if let VertexRef::Old(w) = *r
                && w != v
            {
                *side = (side.0 + motion.get(w), side.1 + 1);
            }
        }
    }
    if a_side.1 == 0 || rest.1 == 0 {
        return 0.0;
    }
    (a_side.0 / a_side.1 as f64 - rest.0 / rest.1 as f64).dot(d)
}

impl SeparationStrength for Strength<'_> {
    fn strength(&self, mesh: &LabeledMesh, v: VertexId, d: DVec3, proposal: &Edit) -> f64 {
        match self {
            Strength::Flow(f) => f.strength(mesh, v, d, proposal),
            Strength::Area(motion) => {
                if side_divergence(motion, v, d, proposal) <= 0.0 {
                    0.0
                } else {
                    AreaDecrease.strength(mesh, v, d, proposal)
                }
            }
        }
    }
}

/// Per-vertex flags of the vertices T1 must leave joined.
fn protected_flags(mesh: &LabeledMesh, protected: &[VertexId]) -> Vec<bool> {
    let mut flags = vec![false; mesh.vertex_capacity()];
    for &v in protected {
        if let Some(f) = flags.get_mut(v.idx()) {
            *f = true;
        }
    }
    flags
}

/// A strength that is zero at protected vertices (fresh snaps), the inner one elsewhere.
struct Gated<'a> {
    strength: Strength<'a>,
    protected: Vec<bool>,
}

impl SeparationStrength for Gated<'_> {
    fn strength(&self, mesh: &LabeledMesh, v: VertexId, d: DVec3, proposal: &Edit) -> f64 {
        if self.protected.get(v.idx()).copied().unwrap_or(false) {
            0.0
        } else {
            self.strength.strength(mesh, v, d, proposal)
        }
    }
}
