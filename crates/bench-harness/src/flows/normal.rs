//! Constant-speed normal flow of a multi-material mesh, by vertex normals or by face
//! offsetting, with per-material-pair speeds ([`InterfaceSpeeds`]).
//!
//! **Per triangle.** A triangle with labels `[front, back]` lies on the interface between
//! `back` and `front`; its plane should move along its right-hand normal (which points
//! into `front`) at `σ = speeds.speed(back, front)`.
//!
//! **Per vertex, [`NormalScheme::VertexNormals`]** (the "naïve" flow of the 2024 paper,
//! §9.6, and of Los Topos §8.1). Incident triangles are grouped by *interface* (unordered
//! label pair); each interface gets the area-weighted sum of its triangles' normals,
//! oriented into the higher label, and its speed towards that label.
//! - One interface (every manifold vertex): the vertex moves `σ·n̂`, `n̂` the normalised
//!   area-weighted vertex normal — exactly the textbook naïve flow.
//! - Several interfaces (triple curves, quadruple points, touching sheets): no single
//!   normal exists. The vertex takes the velocity `v` that best satisfies `n̂ᵢ·v = σᵢ` for
//!   every interface `i` (weighted by that interface's incident area), in the rank-
//!   truncated least-squares sense described below — so each sheet advances at its own
//!   speed, stationary interfaces included (`n̂·v = 0`). For two bubbles expanding at 1
//!   with a stationary shared wall, the triple curve moves along the wall at `1/cos 30°`,
//!   which keeps both outer sheets on their expanding spheres; for cyclical speeds
//!   around a symmetric junction the equations cancel and the curve stays put.
//! - Except at a convex edge of the growing materials (two sheets grow into one label
//!   whose wedge at the vertex is wider than 180°: the tip of a thin fin of two materials
//!   with their wall inside it). There the least-squares junction would run along the fin
//!   at `σ / sin(α/2)` and every fin would grow; exact normal flow rounds a convex edge,
//!   so the vertex moves at most at the fastest sheet's speed.
//! - A pinch, where two sheets of the *same* interface touch at a vertex, counts as one
//!   interface: their normals are summed and may cancel (the vertex then stays).
//! - More than [`MAX_INTERFACES`] interfaces at one vertex (not seen in valid scenes):
//!   the per-triangle solve of face offsetting is used for that vertex.
//!
//! **Per vertex, [`NormalScheme::FaceOffsetting`]** (Jiao 2007; Los Topos §8.2). Every
//! incident triangle's plane is offset by its own `σ·dt`, and the vertex goes to the
//! weighted (by area) least-squares intersection of the offset planes in the primary
//! space — at a cube corner, to the corner of the offset cube, where vertex normals would
//! cut the corner. Not implemented from Jiao: null-space (tangential) smoothing and the
//! entropy-solution length correction and time-step control, so keep `|σ|·dt` well
//! below the edge length.
//!
//! **Least squares in the primary space.** Both schemes solve `M v = b` with
//! `M = Σ wᵢ nᵢ nᵢᵀ`, `b = Σ wᵢ σᵢ nᵢ` in the eigenbasis of `M`, keeping only directions
//! whose eigenvalue exceeds 0.03 × the largest (El Topo's `G_EIGENVALUE_RANK_RATIO`). On
//! a smooth patch that leaves the normal direction only, so nearly parallel planes asking
//! for slightly different offsets cannot shoot the vertex sideways; along a ridge or a
//! triple curve two directions remain, at a corner three. The dropped directions get no
//! motion (minimum-norm solution).
//!
//! **Junctions.** With [`JunctionRule::Pinned`] any vertex where two or more interfaces
//! meet does not move: Los Topos treats the triple curve of cyclical flow as a
//! zero-velocity boundary (§8.2). Isolated vertices (no triangle) never move.
//!
//! **Sign check.** A single material `L` with speed `s > 0` (and 0 outside) grows: its
//! sphere of radius `r` becomes `r + s·t`.

use glam::DVec3;
use mesh_core::{IdVec, Label, LabeledMesh, TriId, VertexId, geometry};
use rayon::prelude::*;

use super::advect::euler_step;
use super::lsq::{PlaneLsq, RANK_RATIO};
use super::{Flow, FlowError, InterfaceSpeeds};

/// Distinct interfaces accumulated per vertex before falling back to the per-triangle
/// solve; a quadruple point of four materials has six.
pub const MAX_INTERFACES: usize = 8;

/// How vertex velocities are derived from the triangle speeds (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalScheme {
    /// Area-weighted vertex normals; least squares over interfaces at junctions.
    #[default]
    VertexNormals,
    /// Least-squares intersection of the offset planes of every incident triangle.
    FaceOffsetting,
}

/// What vertices on junctions (two or more interfaces) do.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JunctionRule {
    /// Least squares over the interfaces (vertex normals) or triangles (face offsetting).
    #[default]
    LeastSquares,
    /// Junction vertices stay where they are.
    Pinned,
}

/// Constant-speed normal flow (see the module doc), one forward Euler step per proposal.
#[derive(Clone, Debug)]
pub struct NormalFlow {
    name: &'static str,
    speeds: InterfaceSpeeds,
    scheme: NormalScheme,
    junctions: JunctionRule,
}

impl NormalFlow {
    /// Normal flow with the given speeds and scheme, junctions by least squares. Fails if
    /// a speed is not finite.
    pub fn new(speeds: InterfaceSpeeds, scheme: NormalScheme) -> Result<Self, FlowError> {
        let name = match scheme {
            NormalScheme::VertexNormals => "normal",
            NormalScheme::FaceOffsetting => "normal-face-offsetting",
        };
        speeds.check(name)?;
        Ok(NormalFlow {
            name,
            speeds,
            scheme,
            junctions: JunctionRule::LeastSquares,
        })
    }

    /// The same flow with another junction rule.
    pub fn with_junctions(mut self, junctions: JunctionRule) -> Self {
        self.junctions = junctions;
        self
    }

    /// The same flow under another name (for run records).
    pub(crate) fn named(mut self, name: &'static str) -> Self {
        self.name = name;
        self
    }

    /// The speeds.
    pub fn speeds(&self) -> &InterfaceSpeeds {
        &self.speeds
    }

    /// Velocity of every vertex slot (zero for dead and isolated ones).
    pub fn velocities(&self, mesh: &LabeledMesh) -> IdVec<VertexId, DVec3> {
        let area_normals = geometry::area_weighted_face_normals(mesh);
        let sigma = self.triangle_speeds(mesh);
        let (area_normals, sigma) = (area_normals.as_slice(), sigma.as_slice());
        let v = (0..mesh.vertex_capacity())
            .into_par_iter()
            .with_min_len(512)
            .map(|v| self.vertex_velocity(mesh, VertexId::new(v as u32), area_normals, sigma))
            .collect();
        IdVec::from_vec(v)
    }

    /// `σ_t = speed(back, front)`, along the triangle's right-hand normal.
    fn triangle_speeds(&self, mesh: &LabeledMesh) -> IdVec<TriId, f64> {
        let labels = mesh.label_pairs();
        let alive = mesh.tri_alive_flags();
        let s = (0..labels.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|t| {
                if alive[t] {
                    self.speeds.speed(labels[t][1], labels[t][0])
                } else {
                    0.0
                }
            })
            .collect();
        IdVec::from_vec(s)
    }

    fn vertex_velocity(
        &self,
        mesh: &LabeledMesh,
        v: VertexId,
        area_normals: &[DVec3],
        sigma: &[f64],
    ) -> DVec3 {
        if !mesh.is_vertex_alive(v) {
            return DVec3::ZERO;
        }
        let mut faces = PlaneLsq::default();
        let mut ifaces = Interfaces::default();
        let p = mesh.position(v);
        for c in mesh.vertex_corners(v) {
            let t = c.tri();
            let n = area_normals[t.idx()];
            let area = n.length();
            if !(area > 0.0 && area.is_finite()) {
                continue;
            }
            let s = sigma[t.idx()];
            faces.add(n / area, s, area);
            let [front, back] = mesh.labels(t);
            let [x, y, z] = mesh.tri_positions(t);
            let reach = area * ((x + y + z) / 3.0 - p);
            ifaces.add(front, back, n, area, s, reach);
        }
        if ifaces.count == 0 {
            return DVec3::ZERO;
        }
        if ifaces.count >= 2 && self.junctions == JunctionRule::Pinned {
            return DVec3::ZERO;
        }
        match self.scheme {
            NormalScheme::FaceOffsetting => faces.solve(RANK_RATIO),
            NormalScheme::VertexNormals if ifaces.overflow => faces.solve(RANK_RATIO),
            NormalScheme::VertexNormals if ifaces.count == 1 => {
                let i = &ifaces.items[0];
                i.speed * i.normal.normalize_or_zero()
            }
            NormalScheme::VertexNormals => {
                let mut lsq = PlaneLsq::default();
                for i in &ifaces.items[..ifaces.count] {
                    let unit = i.normal.normalize_or_zero();
                    if unit != DVec3::ZERO {
                        lsq.add(unit, i.speed, i.area);
                    }
                }
                let v = lsq.solve(RANK_RATIO);
                let fastest = ifaces.items[..ifaces.count]
                    .iter()
                    .map(|i| i.speed.abs())
                    .fold(0.0, f64::max);
                if v.length() > fastest && ifaces.opens_a_reflex_wedge() {
                    v * (fastest / v.length())
                } else {
                    v
                }
            }
        }
    }
}

/// One interface at a vertex: the label pair `lo < hi`, the sum of its incident area
/// normals oriented into `hi`, their total area, the speed of `lo` into `hi`, and the
/// area-weighted sum of its triangles' centroids relative to the vertex (which way the
/// sheet leaves the vertex).
#[derive(Clone, Copy, Default)]
struct Interface {
    key: (u32, u32),
    normal: DVec3,
    area: f64,
    speed: f64,
    reach: DVec3,
}

impl Interface {
    /// The label this sheet moves into, if it moves.
    fn grows_into(&self) -> Option<u32> {
        if self.speed > 0.0 {
            Some(self.key.1)
        } else if self.speed < 0.0 {
            Some(self.key.0)
        } else {
            None
        }
    }
}

/// Per-vertex interface accumulator in a fixed array, so the hot loop does not allocate.
#[derive(Default)]
struct Interfaces {
    items: [Interface; MAX_INTERFACES],
    count: usize,
    overflow: bool,
}

impl Interfaces {
    /// Adds a triangle with labels `[front, back]`, area normal `n` (into `front`), area
    /// and speed `s` of `back` into `front`.
    fn add(&mut self, front: Label, back: Label, n: DVec3, area: f64, s: f64, reach: DVec3) {
        // Orient into the higher label: flip when `front` is the lower one.
        let (key, n, s) = if front > back {
            ((back.raw(), front.raw()), n, s)
        } else {
            ((front.raw(), back.raw()), -n, -s)
        };
        if let Some(item) = self.items[..self.count].iter_mut().find(|e| e.key == key) {
            item.normal += n;
            item.area += area;
            item.reach += reach;
        } else if self.count < MAX_INTERFACES {
            self.items[self.count] = Interface {
                key,
                normal: n,
                area,
                speed: s,
                reach,
            };
            self.count += 1;
        } else {
            self.overflow = true;
        }
    }

    /// True when two sheets grow into one label whose wedge between them, at this
    /// vertex, is wider than 180°: every other sheet leaves the vertex inside the narrow
    /// angle between the two. That is a convex edge of the growing materials — the tip of
    /// a thin fin of two materials with their wall between them. Offsetting each sheet by
    /// its own distance (the least-squares solve) moves such a tip along the fin at
    /// `σ / sin(α/2)` for a fin of angle `α`, so a fin only grows; exact normal flow
    /// rounds a convex edge instead (the expansion fan of Osher and Sethian's entropy
    /// solution), and its tip advances at `σ`. At a concave edge — the rim where two
    /// growing spheres meet, whose outside wedge is narrower than 180° — the offset
    /// sheets do meet where least squares puts the junction, and that stays.
    fn opens_a_reflex_wedge(&self) -> bool {
        let items = &self.items[..self.count];
        for (i, a) in items.iter().enumerate() {
            for b in &items[i + 1..] {
                let Some(x) = a.grows_into() else { continue };
                if b.grows_into() != Some(x) {
                    continue;
                }
                // The cross-section: the plane across the curve the two sheets share.
                let tangent = a.normal.cross(b.normal).normalize_or_zero();
                if tangent == DVec3::ZERO {
                    continue;
                }
                let across = |d: DVec3| (d - tangent * tangent.dot(d)).normalize_or_zero();
                let (da, db) = (across(a.reach), across(b.reach));
                let inside_narrow = |d: DVec3| {
                    let d = across(d);
                    d != DVec3::ZERO
                        && da.cross(d).dot(da.cross(db)) > 0.0
                        && db.cross(d).dot(db.cross(da)) > 0.0
                };
                let others = items
                    .iter()
                    .filter(|o| o.key != a.key && o.key != b.key)
                    .map(|o| o.reach);
                let mut any = false;
                let mut all = true;
                for d in others {
                    any = true;
                    all &= inside_narrow(d);
                }
                if any && all {
                    return true;
                }
            }
        }
        false
    }
}

impl Flow for NormalFlow {
    fn name(&self) -> &str {
        self.name
    }

    fn propose(&self, mesh: &LabeledMesh, _t: f64, dt: f64) -> Vec<DVec3> {
        euler_step(mesh, self.velocities(mesh).as_slice(), dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::test_meshes::{cube, icosphere, radius_stats, triple_fan};
    use mesh_core::Label;

    fn l(i: u32) -> Label {
        Label::new(i)
    }

    fn run(flow: &NormalFlow, mut mesh: LabeledMesh, dt: f64, steps: usize) -> LabeledMesh {
        for k in 0..steps {
            let p = flow.propose(&mesh, k as f64 * dt, dt);
            mesh.positions_mut().copy_from_slice(&p);
        }
        mesh
    }

    #[test]
    fn sphere_radius_grows_and_shrinks_linearly() {
        for scheme in [NormalScheme::VertexNormals, NormalScheme::FaceOffsetting] {
            for (s, r_end) in [(0.5, 1.2), (-0.5, 0.8)] {
                let flow = NormalFlow::new(InterfaceSpeeds::grow_into(l(0), s), scheme).unwrap();
                let mesh = run(&flow, icosphere(3, 1.0, [l(0), l(1)]), 0.01, 40);
                let (mean, spread) = radius_stats(mesh.positions(), &mesh);
                // Vertex normals move each vertex exactly s·dt when its normal is radial;
                // face offsetting moves it s·dt / cos θ (θ ≈ 4° here).
                assert!(
                    (mean - r_end).abs() < 0.004 * r_end,
                    "{scheme:?} s={s}: r = {mean}"
                );
                assert!(spread < 0.02, "{scheme:?}: spread {spread}");
            }
        }
    }

    #[test]
    fn flipped_orientation_moves_the_same_way() {
        // Labels given the other way round ([inside, outside] with inward normals) must
        // not change the motion: σ flips with the normal.
        let flow = NormalFlow::new(
            InterfaceSpeeds::grow_into(l(0), 1.0),
            NormalScheme::VertexNormals,
        )
        .unwrap();
        let mut mesh = icosphere(1, 1.0, [l(0), l(1)]);
        let a = flow.velocities(&mesh);
        for t in mesh.triangles().collect::<Vec<_>>() {
            mesh.flip_orientation(t).unwrap();
        }
        let b = flow.velocities(&mesh);
        for v in mesh.vertices() {
            assert!((a[v] - b[v]).length() < 1e-14);
            assert!((a[v] - mesh.position(v).normalize()).length() < 0.05);
        }
    }

    #[test]
    fn cube_corner_offsets_faces_exactly_only_with_face_offsetting() {
        let speeds = InterfaceSpeeds::grow_into(l(0), 1.0);
        let fo = NormalFlow::new(speeds.clone(), NormalScheme::FaceOffsetting).unwrap();
        let vn = NormalFlow::new(speeds, NormalScheme::VertexNormals).unwrap();
        let mesh = cube([l(0), l(1)]);
        let (a, b) = (fo.velocities(&mesh), vn.velocities(&mesh));
        for v in mesh.vertices() {
            let corner = mesh.position(v);
            // Offset cube [-1-s, 1+s]³: the corner moves by s along every axis.
            assert!((a[v] - corner).length() < 1e-12, "{v}: {}", a[v]);
            // Vertex normals: unit speed, outward, hence every face lags behind.
            assert!((b[v].length() - 1.0).abs() < 1e-12);
            assert!(b[v].dot(corner) > 0.0);
        }
    }

    #[test]
    fn triple_curve_of_two_growing_bubbles_slides_along_the_wall() {
        // Bubbles a and b grow at 1 into the outside c; the a|b wall is stationary.
        let (a, b, c) = (l(1), l(2), l(0));
        let speeds = InterfaceSpeeds::grow_into(c, 1.0);
        for scheme in [NormalScheme::VertexNormals, NormalScheme::FaceOffsetting] {
            let flow = NormalFlow::new(speeds.clone(), scheme).unwrap();
            let v = flow.velocities(&triple_fan(a, b, c));
            // Wall a|b lies at 90°; c is at 270°: the junction moves towards c at 2/√3.
            let expect = DVec3::new(0.0, -2.0 / 3f64.sqrt(), 0.0);
            assert!(
                (v[VertexId::new(0)] - expect).length() < 1e-12,
                "{scheme:?}: {}",
                v[VertexId::new(0)]
            );
            // A vertex inside the wall does not move; one on the b|c sheet moves into c.
            assert!(v[VertexId::new(3)].length() < 1e-12);
            let d = DVec3::new(210f64.to_radians().cos(), 210f64.to_radians().sin(), 0.0);
            let into_c = DVec3::Z.cross(d);
            assert!(
                (v[VertexId::new(4)] - into_c).length() < 1e-12,
                "{scheme:?}: {}",
                v[VertexId::new(4)]
            );
        }
    }

    /// The tip of a thin fin — bubbles a and b 15° wide each, their wall between them, all
    /// around it the outside c they grow into — advances at the sheets' own speed, not at
    /// the 1/sin 15° of the offset sheets' intersection; a rim whose outside wedge is 60°
    /// (concave) keeps that intersection, at 1/sin 30°.
    #[test]
    fn a_fin_tip_advances_at_the_sheet_speed_a_concave_rim_at_the_miter() {
        use crate::flows::test_meshes::triple_fan_at;
        let (a, b, c) = (l(1), l(2), l(0));
        let flow = NormalFlow::new(
            InterfaceSpeeds::grow_into(c, 1.0),
            NormalScheme::VertexNormals,
        )
        .unwrap();
        // Sheets at: wall a|b, b|c, a|c (a lies from a|c to the wall, counter-clockwise).
        let fin = flow.velocities(&triple_fan_at(a, b, c, [180.0, 195.0, 165.0]))[VertexId::new(0)];
        assert!((fin.length() - 1.0).abs() < 1e-12, "{fin}");
        assert!(fin.x > 0.99, "the tip moves away from the fin: {fin}");
        let rim = flow.velocities(&triple_fan_at(a, b, c, [180.0, 330.0, 30.0]))[VertexId::new(0)];
        assert!((rim - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-12, "{rim}");
    }

    #[test]
    fn pinned_junctions_do_not_move() {
        let flow = NormalFlow::new(
            InterfaceSpeeds::grow_into(l(0), 1.0),
            NormalScheme::VertexNormals,
        )
        .unwrap()
        .with_junctions(JunctionRule::Pinned);
        let mesh = triple_fan(l(1), l(2), l(0));
        let p = flow.propose(&mesh, 0.0, 0.1);
        assert_eq!(p[0], mesh.position(VertexId::new(0)));
        assert!(p[4] != mesh.position(VertexId::new(4)));
    }

    #[test]
    fn dead_and_isolated_vertices_stay() {
        let flow = NormalFlow::new(
            InterfaceSpeeds::grow_into(l(0), 1.0),
            NormalScheme::FaceOffsetting,
        )
        .unwrap();
        let mut mesh = icosphere(1, 1.0, [l(0), l(1)]);
        let isolated = mesh.add_vertex(DVec3::splat(3.0)).unwrap();
        let dead = mesh.add_vertex(DVec3::splat(5.0)).unwrap();
        mesh.remove_vertex(dead).unwrap();
        let p = flow.propose(&mesh, 0.0, 0.1);
        assert_eq!(p.len(), mesh.vertex_capacity());
        assert_eq!(p[isolated.idx()], DVec3::splat(3.0));
        assert_eq!(p[dead.idx()], DVec3::splat(5.0));
    }

    #[test]
    fn non_finite_speed_is_rejected() {
        let err = NormalFlow::new(
            InterfaceSpeeds::grow_into(l(0), f64::NAN),
            NormalScheme::VertexNormals,
        );
        assert!(matches!(err, Err(FlowError::InvalidParameter { .. })));
    }
}
