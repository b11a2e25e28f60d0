//! A sphere of four materials: the multi-material Enright test of Los Topos (§8.1,
//! Fig. 14), "a sphere divided into four material regions".
//!
//! The planes `x = 0` and `y = 0` (through the centre) cut the ball into four quadrant
//! wedges, labels 1 (`x > 0, y > 0`), 2 (`x < 0, y > 0`), 3 (`x < 0, y < 0`) and
//! 4 (`x > 0, y < 0`); the outside is 0. The outer sheets meet the inner walls along two
//! great circles (triple curves), and the four walls meet along the `z` axis.
//!
//! **Lattice.** Every vertex has integer coordinates `(a, b, c)` with `|a|+|b|+|c| ≤ N`
//! and sits at `centre + R·(|a|+|b|+|c|)/N · (a, b, c)/‖(a, b, c)‖`: the sphere is the
//! octahedron's faces subdivided `N` times and pushed onto the sphere (`|a|+|b|+|c| = N`),
//! the walls are quarter disks in the planes `a = 0` and `b = 0`, subdivided the same way
//! and mapped to concentric rings. A wall's rim lattice points *are* the sphere's points on
//! that great circle (same integer key), so the pieces share vertices and edges exactly,
//! which welding by key (not by floating-point position) guarantees. Within one octant
//! face or quarter disk the angle of `(i, j)` is monotone in `j/i` along each ring, so no
//! triangle folds over.

use std::collections::HashMap;

use glam::DVec3;
use mesh_core::LabeledMesh;
use mesh_core::generators::GeneratorError;

/// Most subdivisions accepted (the mesh has `16·N²` triangles).
pub const MAX_RESOLUTION: u32 = 256;

/// The material of the quadrant with the given signs of `x` and `y`.
fn quadrant(sx: i32, sy: i32) -> u32 {
    match (sx > 0, sy > 0) {
        (true, true) => 1,
        (false, true) => 2,
        (false, false) => 3,
        (true, false) => 4,
    }
}

/// Welds lattice points into mesh vertices and collects triangles.
struct Builder {
    centre: DVec3,
    radius: f64,
    n: i32,
    ids: HashMap<[i32; 3], u32>,
    positions: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    labels: Vec<[u32; 2]>,
}

impl Builder {
    fn point(&self, key: [i32; 3]) -> DVec3 {
        let d = DVec3::new(key[0] as f64, key[1] as f64, key[2] as f64);
        let l1 = key.iter().map(|k| k.abs()).sum::<i32>();
        if l1 == 0 {
            return self.centre;
        }
        self.centre + self.radius * (l1 as f64 / self.n as f64) * d.normalize()
    }

    fn vertex(&mut self, key: [i32; 3]) -> u32 {
        if let Some(&id) = self.ids.get(&key) {
            return id;
        }
        let id = self.positions.len() as u32;
        self.positions.push(self.point(key));
        self.ids.insert(key, id);
        id
    }

    /// Triangulates the lattice triangle `{key(i, j) : i + j ≤ N}` and labels each
    /// triangle by its normal: `labels(normal) = [front, back]`.
    fn patch(&mut self, key: impl Fn(i32, i32) -> [i32; 3], labels: impl Fn(DVec3) -> [u32; 2]) {
        let n = self.n;
        for i in 0..n {
            for j in 0..n - i {
                let mut cells = vec![[(i, j), (i + 1, j), (i, j + 1)]];
                if i + j + 2 <= n {
                    cells.push([(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
                }
                for cell in cells {
                    let tri = cell.map(|(a, b)| self.vertex(key(a, b)));
                    let [p, q, r] = tri.map(|v| self.positions[v as usize]);
                    let normal = (q - p).cross(r - p);
                    self.tris.push(tri);
                    self.labels.push(labels(normal));
                }
            }
        }
    }
}

/// The four-material sphere of the module doc, `resolution` (`N`, 1 ..=
/// [`MAX_RESOLUTION`]) subdivisions per quarter great circle.
pub fn quadrant_sphere(
    centre: DVec3,
    radius: f64,
    resolution: u32,
) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "quadrant_sphere";
    if !(1..=MAX_RESOLUTION).contains(&resolution) {
        return Err(GeneratorError::InvalidParameter {
            generator: NAME,
            parameter: "resolution",
            value: resolution.to_string(),
            expected: "between 1 and 256",
        });
    }
    if !(radius.is_finite() && radius > 0.0 && centre.is_finite()) {
        return Err(GeneratorError::InvalidParameter {
            generator: NAME,
            parameter: "radius and centre",
            value: format!("{radius}, {centre}"),
            expected: "a finite positive radius and a finite centre",
        });
    }
    let mut b = Builder {
        centre,
        radius,
        n: resolution as i32,
        ids: HashMap::new(),
        positions: Vec::new(),
        tris: Vec::new(),
        labels: Vec::new(),
    };
    let n = b.n;
    let signs = [1, -1];
    let sign_of = |v: f64| if v > 0.0 { 1 } else { -1 };
    for sx in signs {
        for sy in signs {
            for sz in signs {
                // The octant's sphere face, [outside, quadrant]: outward normals are front.
                let inside = quadrant(sx, sy);
                let outward = DVec3::new(sx as f64, sy as f64, sz as f64);
                b.patch(
                    |i, j| [sx * i, sy * j, sz * (n - i - j)],
                    |normal| {
                        if normal.dot(outward) > 0.0 {
                            [0, inside]
                        } else {
                            [inside, 0]
                        }
                    },
                );
            }
        }
    }
    // The walls: a quarter disk per (in-plane sign, z sign) in each plane, between the
    // two quadrants on either side of it.
    for s in signs {
        for sz in signs {
            b.patch(
                |i, j| [0, s * i, sz * j],
                |normal| {
                    let side = sign_of(normal.x);
                    [quadrant(side, s), quadrant(-side, s)]
                },
            );
            b.patch(
                |i, j| [s * i, 0, sz * j],
                |normal| {
                    let side = sign_of(normal.y);
                    [quadrant(s, side), quadrant(s, -side)]
                },
            );
        }
    }
    Ok(LabeledMesh::from_raw(b.positions, &b.tris, &b.labels)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::Label;
    use mesh_core::geometry::label_volumes;
    use mesh_core::validate::{ValidateOptions, validate};

    #[test]
    fn four_quadrants_of_equal_volume_and_a_valid_mesh() {
        let n = 6;
        let mesh = quadrant_sphere(DVec3::new(0.35, 0.35, 0.35), 0.15, n).unwrap();
        assert_eq!(mesh.num_triangles(), 16 * (n * n) as usize);
        let report = validate(&mesh, &ValidateOptions::with_intersections());
        assert!(report.is_valid(), "{report}");
        let labels: Vec<u32> = mesh.label_set().iter().map(|l| l.raw()).collect();
        assert_eq!(labels, vec![0, 1, 2, 3, 4]);
        let volumes = label_volumes(&mesh);
        let quarter: Vec<f64> = (1..=4).map(|l| volumes[&Label::new(l)]).collect();
        // Inscribed polyhedron: a little below a quarter of the ball, all four equal.
        let ball = 4.0 / 3.0 * std::f64::consts::PI * 0.15f64.powi(3);
        for v in &quarter {
            assert!((v - quarter[0]).abs() < 1e-12, "{quarter:?}");
            assert!(
                *v < ball / 4.0 && *v > 0.85 * ball / 4.0,
                "{v} vs {}",
                ball / 4.0
            );
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(quadrant_sphere(DVec3::ZERO, 1.0, 0).is_err());
        assert!(quadrant_sphere(DVec3::ZERO, -1.0, 4).is_err());
        assert!(quadrant_sphere(DVec3::NAN, 1.0, 4).is_err());
    }
}
