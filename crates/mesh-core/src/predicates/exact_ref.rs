//! Test-only exact references in `BigRational` arithmetic, and closed test meshes with
//! integer coordinates. Deliberately written differently from the code under test (no
//! orientation predicates in the intersection reference) so that one cannot share the
//! other's mistake.

use glam::{DVec2, DVec3};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{Signed, Zero};

use super::orient::Sign;

/// An exact rational.
pub type Q = BigRational;

/// The exact value of a finite float.
pub fn q(x: f64) -> Q {
    BigRational::from_float(x).expect("finite test input")
}

/// The exact value of an integer.
pub fn qi(x: i64) -> Q {
    BigRational::from_integer(BigInt::from(x))
}

/// The sign of an exact rational.
pub fn sign_q(x: &Q) -> Sign {
    if x.is_positive() {
        Sign::Positive
    } else if x.is_negative() {
        Sign::Negative
    } else {
        Sign::Zero
    }
}

/// A point with exact coordinates.
pub type Q3 = [Q; 3];

/// The exact coordinates of a point.
pub fn q3(p: DVec3) -> Q3 {
    [q(p.x), q(p.y), q(p.z)]
}

fn sub(a: &Q3, b: &Q3) -> Q3 {
    [&a[0] - &b[0], &a[1] - &b[1], &a[2] - &b[2]]
}

fn cross(a: &Q3, b: &Q3) -> Q3 {
    [
        &a[1] * &b[2] - &a[2] * &b[1],
        &a[2] * &b[0] - &a[0] * &b[2],
        &a[0] * &b[1] - &a[1] * &b[0],
    ]
}

fn dot(a: &Q3, b: &Q3) -> Q {
    &a[0] * &b[0] + &a[1] * &b[1] + &a[2] * &b[2]
}

/// The exact normal `(b − a) × (c − a)`.
pub fn normal_ref(a: DVec3, b: DVec3, c: DVec3) -> Q3 {
    let a = q3(a);
    cross(&sub(&q3(b), &a), &sub(&q3(c), &a))
}

/// The exact sign of `(b − a) × (c − a) · (d − a)`.
pub fn orient3d_ref(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Sign {
    sign_q(&dot(&normal_ref(a, b, c), &sub(&q3(d), &q3(a))))
}

/// The exact sign of `(b − a) × (c − a)` in the plane.
pub fn orient2d_ref(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    let (ax, ay) = (q(a.x), q(a.y));
    let det = (q(b.x) - &ax) * (q(c.y) - &ay) - (q(b.y) - &ay) * (q(c.x) - &ax);
    sign_q(&det)
}

/// The unique solution of the linear system with the given columns and right-hand side,
/// or `None` when the columns are dependent or the system inconsistent (Gauss–Jordan).
fn solve_unique(cols: &[Vec<Q>], rhs: &[Q]) -> Option<Vec<Q>> {
    let (m, k) = (rhs.len(), cols.len());
    let mut a: Vec<Vec<Q>> = (0..m)
        .map(|r| {
            cols.iter()
                .map(|c| c[r].clone())
                .chain([rhs[r].clone()])
                .collect()
        })
        .collect();
    for col in 0..k {
        let p = (col..m).find(|&r| !a[r][col].is_zero())?;
        a.swap(col, p);
        let pivot = a[col][col].clone();
        for x in &mut a[col][col..] {
            *x = &*x / &pivot;
        }
        let pivot_row = a[col].clone();
        for (r, row) in a.iter_mut().enumerate() {
            if r != col && !row[col].is_zero() {
                let f = row[col].clone();
                for (x, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                    *x = &*x - &f * p;
                }
            }
        }
    }
    if (k..m).any(|r| !a[r][k].is_zero()) {
        return None;
    }
    Some((0..k).map(|r| a[r][k].clone()).collect())
}

/// The vertices of `hull(pa) ∩ hull(pb)` — or rather a superset of them, all inside it:
/// the images of the basic feasible solutions of `Σ λᵢ paᵢ = Σ μⱼ pbⱼ`,
/// `Σ λ = Σ μ = 1`, `λ, μ ≥ 0`. Empty iff the hulls are disjoint: a non-empty polytope
/// has a vertex, and every vertex of the image is the image of some vertex of the
/// solution polytope.
pub fn hull_intersection_vertices(pa: &[DVec3], pb: &[DVec3]) -> Vec<Q3> {
    let n = pa.len() + pb.len();
    let column = |i: usize| -> Vec<Q> {
        if i < pa.len() {
            let p = q3(pa[i]);
            vec![p[0].clone(), p[1].clone(), p[2].clone(), qi(1), qi(0)]
        } else {
            let p = q3(pb[i - pa.len()]);
            vec![-&p[0], -&p[1], -&p[2], qi(0), qi(1)]
        }
    };
    let rhs = [qi(0), qi(0), qi(0), qi(1), qi(1)];
    let mut out = Vec::new();
    for mask in 1u32..(1 << n) {
        let support: Vec<usize> = (0..n).filter(|i| mask & (1 << i) != 0).collect();
        if support.len() > rhs.len() {
            continue;
        }
        let cols: Vec<Vec<Q>> = support.iter().map(|&i| column(i)).collect();
        let Some(x) = solve_unique(&cols, &rhs) else {
            continue;
        };
        if x.iter().any(|v| v.is_negative()) {
            continue;
        }
        let mut point = [qi(0), qi(0), qi(0)];
        for (&i, w) in support.iter().zip(&x) {
            if i < pa.len() {
                let p = q3(pa[i]);
                for c in 0..3 {
                    point[c] = &point[c] + w * &p[c];
                }
            }
        }
        out.push(point);
    }
    out
}

/// The convex hulls of `pa` and `pb` share a point.
pub fn hulls_intersect(pa: &[DVec3], pb: &[DVec3]) -> bool {
    !hull_intersection_vertices(pa, pb).is_empty()
}

/// `x` lies on the closed segment `vw` (`v ≠ w`).
pub fn on_segment(x: &Q3, v: DVec3, w: DVec3) -> bool {
    let (v, w) = (q3(v), q3(w));
    let d = sub(&w, &v);
    let e = sub(x, &v);
    if cross(&d, &e).iter().any(|c| !c.is_zero()) {
        return false;
    }
    let t = dot(&d, &e);
    !t.is_negative() && t <= dot(&d, &d)
}

/// A closed, consistently and outward oriented triangle mesh.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Vertex positions.
    pub verts: Vec<DVec3>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub tris: Vec<[usize; 3]>,
}

impl Mesh {
    /// The triangles' corner positions.
    pub fn triangles(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.tris.iter().map(|t| t.map(|i| self.verts[i]))
    }

    /// Six times the enclosed volume, exactly (positive for outward orientation).
    pub fn volume6(&self) -> Q {
        self.triangles()
            .map(|[a, b, c]| dot(&q3(a), &cross(&q3(b), &q3(c))))
            .fold(qi(0), |s, x| s + x)
    }
}

fn v(x: i32, y: i32, z: i32) -> DVec3 {
    DVec3::new(f64::from(x), f64::from(y), f64::from(z))
}

/// A tetrahedron with a right-angled corner at the origin.
pub fn tetrahedron() -> Mesh {
    Mesh {
        verts: vec![v(0, 0, 0), v(2, 0, 0), v(0, 2, 0), v(0, 0, 2)],
        tris: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

/// The cube [0, 2]³ split into 12 triangles.
pub fn cube() -> Mesh {
    let verts = (0..8).map(|i| v(2 * (i & 1), i & 2, (i & 4) / 2)).collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let tris = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh { verts, tris }
}

/// An octahedron with vertices at ±r on the axes.
pub fn octahedron(r: i32) -> Mesh {
    let verts = vec![
        v(r, 0, 0),
        v(-r, 0, 0),
        v(0, r, 0),
        v(0, -r, 0),
        v(0, 0, r),
        v(0, 0, -r),
    ];
    let mut tris = Vec::new();
    for sx in [0, 1] {
        for sy in [0, 1] {
            for sz in [0, 1] {
                let t = [sx, 2 + sy, 4 + sz];
                // (+x, +y, +z) is counter-clockwise from outside; each mirror flips it.
                tris.push(if (sx + sy + sz) % 2 == 0 {
                    t
                } else {
                    [t[0], t[2], t[1]]
                });
            }
        }
    }
    Mesh { verts, tris }
}

/// An octahedron of radius 4 with each face split in four, the edge midpoints pushed out
/// to (3, 3, 0)-like positions: 18 vertices, 32 triangles, integer coordinates.
pub fn icosphere_like() -> Mesh {
    let base = octahedron(4);
    let mut verts = base.verts.clone();
    let mut midpoint = |a: usize, b: usize| -> usize {
        let m = (base.verts[a] + base.verts[b]) * 0.75;
        match verts.iter().position(|&p| p == m) {
            Some(i) => i,
            None => {
                verts.push(m);
                verts.len() - 1
            }
        }
    };
    let mut tris = Vec::new();
    for &[a, b, c] in &base.tris {
        let (ab, bc, ca) = (midpoint(a, b), midpoint(b, c), midpoint(c, a));
        tris.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Mesh { verts, tris }
}

/// The test meshes, by index.
pub fn mesh(i: usize) -> Mesh {
    match i % 4 {
        0 => tetrahedron(),
        1 => cube(),
        2 => octahedron(3),
        _ => icosphere_like(),
    }
}

#[test]
fn meshes_are_closed_and_outward() {
    for i in 0..4 {
        let m = mesh(i);
        assert!(m.volume6().is_positive(), "mesh {i}");
        // Every directed edge appears once, and its reverse once: a closed oriented surface.
        let mut edges: Vec<(usize, usize)> = m
            .tris
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        edges.sort_unstable();
        assert!(edges.windows(2).all(|w| w[0] != w[1]), "mesh {i}");
        assert!(
            edges
                .iter()
                .all(|&(a, b)| edges.binary_search(&(b, a)).is_ok()),
            "mesh {i}"
        );
    }
    assert_eq!(icosphere_like().verts.len(), 18);
}

#[test]
fn reference_sanity() {
    let t = [v(0, 0, 0), v(2, 0, 0), v(0, 2, 0)];
    assert!(hulls_intersect(&t, &[v(1, 1, 0)]));
    assert!(hulls_intersect(&t, &[v(1, 1, -1), v(1, 1, 1)]));
    assert!(!hulls_intersect(&t, &[v(2, 2, -1), v(2, 2, 1)]));
    assert!(!hulls_intersect(&t, &[v(0, 0, 1), v(2, 0, 1), v(0, 2, 1)]));
    // Touching along an edge: the intersection's vertices are that edge's ends.
    let other = [v(0, 0, 0), v(2, 0, 0), v(0, 0, 2)];
    let verts = hull_intersection_vertices(&t, &other);
    assert!(verts.iter().all(|x| on_segment(x, v(0, 0, 0), v(2, 0, 0))));
    assert!(verts.contains(&q3(v(2, 0, 0))));
    assert!(on_segment(&q3(v(1, 0, 0)), v(0, 0, 0), v(2, 0, 0)));
    assert!(!on_segment(&q3(v(3, 0, 0)), v(0, 0, 0), v(2, 0, 0)));
}
