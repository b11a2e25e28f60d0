//! Scenes and checks shared by the integration tests.
#![allow(dead_code)]

use grid_tracker::{FlawOptions, FlawedRegion, Grid, GridOptions, MaterialOptions, Materials};
use mesh_core::LabeledMesh;

// The scene builders are the unit tests' own (they need nothing crate-internal).
#[path = "../../src/test_util.rs"]
mod scenes;
// Each test binary uses a subset (hence also `allow(dead_code)` above).
#[allow(unused_imports)]
pub use scenes::{cube, inverted, sphere, union};

/// Mean edge length (each triangle's three edges; shared edges count twice, which does
/// not change the mean of a uniform mesh much).
pub fn mean_edge(m: &LabeledMesh) -> f64 {
    let (sum, n) = m.triangles().fold((0.0, 0usize), |(s, n), t| {
        let [a, b, c] = m.tri_positions(t);
        (
            s + (b - a).length() + (c - b).length() + (a - c).length(),
            n + 3,
        )
    });
    sum / n as f64
}

pub struct Stages {
    pub grid: Grid,
    pub materials: Materials,
    pub flaws: FlawedRegion,
}

pub fn stages(mesh: &LabeledMesh, ell: f64, grid: &GridOptions) -> Stages {
    let g = grid_tracker::build_grid(mesh, ell, grid).expect("grid");
    let m =
        grid_tracker::assign_materials(mesh, &g, &MaterialOptions::default()).expect("materials");
    let f = grid_tracker::detect_flaws(mesh, &g, &m, &FlawOptions::default()).expect("flaws");
    Stages {
        grid: g,
        materials: m,
        flaws: f,
    }
}

/// The material vector of a node as plain `(label, count)` pairs.
pub fn vector(s: &Stages, n: grid_tracker::NodeId) -> Vec<(u32, i32)> {
    s.materials
        .node_vector(n)
        .to_vector()
        .entries()
        .iter()
        .map(|&(l, c)| (l.raw(), c))
        .collect()
}
