//! Hand-built scenes shared by the unit tests of the remesh operations and by
//! `tests/remesh_topology.rs`, which includes this file by path so each scene is written
//! once. Only `glam` is named, so the file compiles inside both crates.

use glam::DVec3;

/// One step of Knuth's 64-bit linear congruential generator, the deterministic noise of
/// the remesh unit tests (jittered spheres, random quadrics, random edit sequences); each
/// test derives its own sample from the returned state. `tests/remesh_topology.rs`, which
/// includes this file, has no use for it.
#[allow(dead_code)]
pub(crate) fn lcg(state: &mut u64) -> u64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    *state
}

/// Raw arrays (positions, triangles, `[front, back]` labels) of the bowtie: two
/// tetrahedra of label 1 in label 0 touching only at vertex 0, the second the first
/// mirrored through it. Mirroring reverses orientation, so the mirrored triangles are
/// listed reversed and every front still faces outwards. Vertex 0 is the smallest
/// singular (irregular) vertex, the case that pinching and separation exist for.
pub(crate) fn bowtie_raw() -> (Vec<DVec3>, [[u32; 3]; 8], [[u32; 2]; 8]) {
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        -DVec3::X,
        -DVec3::Y,
        -DVec3::Z,
    ];
    let tris = [
        [0, 2, 1],
        [0, 1, 3],
        [0, 3, 2],
        [1, 2, 3],
        [0, 4, 5],
        [0, 6, 4],
        [0, 5, 6],
        [4, 6, 5],
    ];
    (p, tris, [[0, 1]; 8])
}
