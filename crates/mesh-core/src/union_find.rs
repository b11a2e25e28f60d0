//! Union–find over `u32` ids stored as parent links, for the flood-like groupings of the
//! workspace (surface components, region shells around a vertex, pinch groups, the
//! implicit-surface follower's debris and the polygonization's components). Start from
//! `parent[i] = i`.

/// Root of `x` in the forest `parent` (path halving).
pub fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

/// Joins the sets of `a` and `b`. The smaller root wins, so every set's root is its
/// smallest member and numbering stays independent of the order of the unions.
pub fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra < rb {
        parent[rb as usize] = ra;
    } else if rb < ra {
        parent[ra as usize] = rb;
    }
}
