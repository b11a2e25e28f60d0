//! Scenes and checks shared by the integration tests.
#![allow(dead_code)]

use glam::DVec3;
use grid_tracker::{FlawOptions, FlawedRegion, Grid, GridOptions, MaterialOptions, Materials};
use mesh_core::generators::icosphere;
use mesh_core::{Label, LabeledMesh};

pub fn sphere(sub: u32, centre: DVec3, radius: f64, outside: u32, inside: u32) -> LabeledMesh {
    icosphere(
        sub,
        centre,
        radius,
        [Label::new(outside), Label::new(inside)],
    )
    .expect("valid sphere")
}

pub fn union(meshes: &[LabeledMesh]) -> LabeledMesh {
    let (mut pos, mut tris, mut labels) = (Vec::new(), Vec::new(), Vec::new());
    for m in meshes {
        let (p, t, l) = m.to_raw();
        let off = pos.len() as u32;
        pos.extend(p);
        tris.extend(t.iter().map(|t| t.map(|v| v + off)));
        labels.extend(l);
    }
    LabeledMesh::from_raw(pos, &tris, &labels).expect("valid union")
}

pub fn inverted(m: &LabeledMesh) -> LabeledMesh {
    let (p, t, l) = m.to_raw();
    let t: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
    LabeledMesh::from_raw(p, &t, &l).expect("valid inverted mesh")
}

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
