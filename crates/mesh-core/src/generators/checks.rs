//! Test-only checks shared by the generator tests: the structural promises every
//! generated scene makes (closed, consistently labelled, no degenerate or repeated
//! elements). Self-intersection is left to [`crate::validate`].

use std::collections::{BTreeMap, HashSet};

use crate::connectivity::EdgeTable;
use crate::ids::Label;
use crate::mesh::LabeledMesh;

/// Asserts the structural promises of a generated mesh:
/// every edge has at least two triangles; no triangle repeats a vertex, has (relatively)
/// zero area or duplicates another; front and back labels differ; every region shell is
/// closed and consistent; no vertex is unused or duplicates another's position.
pub(crate) fn assert_well_formed(m: &LabeledMesh) {
    assert!(m.num_triangles() > 0, "empty mesh");
    let table = EdgeTable::build(m.tris(), m.tri_alive_flags(), m.vertex_capacity());
    for g in table.groups() {
        assert!(
            g.len() >= 2,
            "edge {}–{} has only {} triangle(s)",
            g[0].lo,
            g[0].hi,
            g.len()
        );
    }

    let (lo, hi) = m.vertices().map(|v| m.position(v)).fold(
        (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
        |(a, b), p| (a.min(p), b.max(p)),
    );
    let scale = (hi - lo).length_squared();
    let mut seen = HashSet::new();
    let mut used = vec![false; m.vertex_capacity()];
    for t in m.triangles() {
        let [a, b, c] = m.tri(t);
        assert!(a != b && b != c && c != a, "triangle {t} repeats a vertex");
        let [pa, pb, pc] = m.tri_positions(t);
        let area2 = (pb - pa).cross(pc - pa).length();
        assert!(
            area2 > 1e-12 * scale,
            "triangle {t} has (near) zero area {area2}"
        );
        let mut key = [a, b, c];
        key.sort_unstable();
        assert!(seen.insert(key), "triangle {t} duplicates another");
        let [f, bk] = m.labels(t);
        assert_ne!(f, bk, "triangle {t} has equal labels");
        for v in [a, b, c] {
            used[v.idx()] = true;
        }
    }
    for v in m.vertices() {
        assert!(used[v.idx()], "vertex {v} is unused");
    }
    let mut bits: Vec<[u64; 3]> = m
        .vertices()
        .map(|v| m.position(v).to_array().map(f64::to_bits))
        .collect();
    bits.sort_unstable();
    assert!(
        bits.windows(2).all(|w| w[0] != w[1]),
        "two vertices share a position"
    );

    for (i, s) in m.regions().shells.iter().enumerate() {
        assert!(
            s.consistent && s.closed,
            "shell {i} ({s:?}) is not closed and consistent"
        );
    }
}

/// `(label, volume)` of every bounded region shell (positive enclosed volume).
pub(crate) fn bounded_volumes(m: &LabeledMesh) -> Vec<(Label, f64)> {
    m.regions().bounded().map(|s| (s.label, s.volume)).collect()
}

/// Sum of bounded shell volumes per label.
pub(crate) fn volume_per_label(m: &LabeledMesh) -> BTreeMap<Label, f64> {
    let mut out = BTreeMap::new();
    for (l, v) in bounded_volumes(m) {
        *out.entry(l).or_insert(0.0) += v;
    }
    out
}
