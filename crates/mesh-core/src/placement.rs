//! Placement: does every surface component carry, on its outside, the material it
//! actually lies in?
//!
//! The local invariants (one label per wedge around every edge) cannot see how separate
//! surface components sit in space. A sphere of material 2 drawn inside a sphere of
//! material 1, both labelled against the outside 0 — how separately exported parts of an
//! assembly usually arrive — passes them, yet no point between the two spheres has one
//! material: the outer sphere says 1, the inner says 0. The grid tracker's ray casting
//! (§5 of Heiss-Synak et al. 2024) then finds the mixed vector `e_1 + e_2 − e_0` inside
//! the inner sphere and resolves it as an overlap, and material 2 is gone.
//!
//! **The check.** Ray casting gives every point `p` off the mesh a material vector: `e_0`
//! at −∞ (label 0 is the ambient material), changed at every crossing by the crossed
//! triangle's labels, as in the grid tracker's §5 ([`crate::predicates::crossing`]). For
//! one triangle `t` on the outer shell of each component, the line along `t`'s dominant
//! normal axis through its centroid is cast, every crossing of it ordered exactly against
//! `t`'s ([`compare_crossings`], Simulation of Simplicity throughout), and the vector on
//! `t`'s outer side compared with the label of that side.
//!
//! **Why one ray per component suffices.** Within a component, any side of any triangle
//! is reached from `t`'s by walking along the surface and across its triangles, never
//! crossing another component (they do not intersect: layer 4 of [`crate::validate`]);
//! crossing a triangle changes the vector exactly by its labels, and consistency around
//! every edge (layer 2) makes the walk's labels agree with the vector everywhere. So a
//! mesh whose components each pass is labelled consistently with space as a whole.
//! Intersecting components (an overlap, which `fix` repairs) fail here too, and are
//! reported by layer 4 as well.
//!
//! Cost: a union–find over the corner table for the components, then per component a
//! scan of the triangles a ray may cross — all of them for a few components, a [`Bvh`]
//! query for many. Only a component that fails is measured again, on its outer shell
//! (which takes the region flood).

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::broadphase::{Aabb, Bvh};
use crate::corner::Side;
use crate::ids::{Label, TriId};
use crate::mesh::LabeledMesh;
use crate::predicates::{Axis, Sign, compare_crossings, cross_axis_line_triangle, orient2d_axis};
use crate::regions::Regions;
use crate::union_find::{find, union};

/// Candidate triangles tried per component before giving up on it (a triangle whose
/// projection is degenerate, or whose centroid rounds outside it, is skipped).
const TRIES: usize = 8;

/// Up to this many components, each ray scans every triangle; beyond, a [`Bvh`] serves
/// the rays.
const SCAN_LIMIT: usize = 16;

/// A surface component whose outside label disagrees with where it lies.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MisplacedShell {
    /// The triangle the ray was cast through: of the lowest-numbered triangles on the
    /// component's outer shell, the first whose centroid line crosses it.
    pub tri: TriId,
    /// The side of `tri` on the component's outer shell (the region shell enclosing the
    /// most negative volume: the side facing away from the component), whose material
    /// was measured.
    pub side: Side,
    /// The material that side names: what the component says lies around it.
    pub claimed: Label,
    /// The material vector found there by ray casting, as `(label, count)` with count ≠ 0,
    /// by label: `[(1, 1)]` is material 1, `[(0, -1), (1, 1), (2, 1)]` is `e_1 + e_2 − e_0`
    /// (the inside of an overlap).
    pub found: Vec<(Label, i32)>,
    /// The region shell of `side` ([`Regions::shell_of`]).
    pub shell: u32,
    /// Triangles in the component.
    pub component_triangles: usize,
}

impl std::fmt::Display for MisplacedShell {
    /// "the surface component of t7 (320 triangles) is labelled material 0 outside, but
    /// lies in material 1".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the surface component of {} ({} triangles) is labelled material {} outside, but \
             lies in {}",
            self.tri,
            self.component_triangles,
            self.claimed.raw(),
            self.found_text()
        )
    }
}

impl MisplacedShell {
    /// The one material found, if the vector is one-hot (the component lies inside that
    /// material); `None` for a mixed vector (it lies inside an overlap).
    pub fn found_material(&self) -> Option<Label> {
        match self.found.as_slice() {
            [(l, 1)] => Some(*l),
            _ => None,
        }
    }

    /// The found vector written out: `material 1`, or `e_1 + e_2 − e_0`.
    pub fn found_text(&self) -> String {
        if let Some(l) = self.found_material() {
            return format!("material {}", l.raw());
        }
        let mut s = String::new();
        for (k, (l, n)) in self.found.iter().enumerate() {
            let sign = if *n < 0 {
                " − "
            } else if k > 0 {
                " + "
            } else {
                ""
            };
            let sign = if k == 0 && *n < 0 { "−" } else { sign };
            let m = n.unsigned_abs();
            let coef = if m == 1 { String::new() } else { m.to_string() };
            s += &format!("{sign}{coef}e_{}", l.raw());
        }
        if s.is_empty() {
            "nothing (0)".into()
        } else {
            s
        }
    }
}

/// Every surface component whose measured outside differs from its label, in order of
/// `tri`. Assumes what layers 1–3 of [`crate::validate`] check (closed, consistent
/// wedges, finite coordinates); on other meshes the answer means little but nothing
/// panics. A component none of whose first [`TRIES`] triangles can be cast through (all
/// degenerate) is not judged.
///
/// Two passes, so that a placed mesh costs no region flood: one ray per component through
/// any side of one of its triangles decides (by the walk argument of the module doc, one
/// side agrees exactly when all do); only the components that fail are cast again
/// through their outer shell ([`LabeledMesh::regions`]), which is what the report names
/// and what [`place_nested`] relabels.
pub fn misplaced_shells(mesh: &LabeledMesh) -> Vec<MisplacedShell> {
    locate(mesh).0
}

/// [`misplaced_shells`], with the regions its second pass flooded (`None` when every
/// component passed the first): the shells the findings name.
fn locate(mesh: &LabeledMesh) -> (Vec<MisplacedShell>, Option<Regions>) {
    let (component, count) = surface_components(mesh);
    let mut members: Vec<Vec<(TriId, Option<Side>)>> = vec![Vec::new(); count];
    let mut sizes = vec![0usize; count];
    for t in mesh.triangles() {
        let c = component[t.idx()] as usize;
        sizes[c] += 1;
        if members[c].len() < TRIES {
            members[c].push((t, None));
        }
    }
    let alive = mesh.tri_alive_flags();
    let bvh = (count > SCAN_LIMIT)
        .then(|| {
            Bvh::build_from_fn(mesh.triangle_capacity(), |t| {
                if alive[t as usize] {
                    Aabb::from_points(&mesh.tri_positions(TriId::new(t)))
                } else {
                    Aabb::EMPTY
                }
            })
            .ok()
        })
        .flatten();
    let failing = measure(mesh, &members, bvh.as_ref());
    if failing.is_empty() {
        return (Vec::new(), None);
    }

    // The failing components, again through a triangle side on their outer shell: the one
    // enclosing the most negative volume (the unbounded side; see
    // [`crate::RegionShell::volume`]).
    let regions = mesh.regions();
    let mut failed = vec![false; count];
    for m in &failing {
        failed[component[m.tri.idx()] as usize] = true;
    }
    let mut outer: Vec<Option<usize>> = vec![None; count];
    for t in mesh.triangles() {
        let c = component[t.idx()] as usize;
        if !failed[c] {
            continue;
        }
        for side in [Side::Front, Side::Back] {
            if let Some(s) = regions.shell_of(t, side) {
                let v = regions.shells[s].volume;
                if outer[c].is_none_or(|o| v < regions.shells[o].volume) {
                    outer[c] = Some(s);
                }
            }
        }
    }
    let mut members: Vec<Vec<(TriId, Option<Side>)>> = vec![Vec::new(); count];
    for t in mesh.triangles() {
        let c = component[t.idx()] as usize;
        for side in [Side::Front, Side::Back] {
            if outer[c].is_some()
                && regions.shell_of(t, side) == outer[c]
                && members[c].len() < TRIES
            {
                members[c].push((t, Some(side)));
            }
        }
    }
    let mut out = measure(mesh, &members, bvh.as_ref());
    // A failing component whose outer shell no ray could be cast through (all its first
    // triangles there degenerate) is still reported, as the first pass measured it.
    let mut reported = vec![false; count];
    for m in &out {
        reported[component[m.tri.idx()] as usize] = true;
    }
    out.extend(
        failing
            .into_iter()
            .filter(|m| !reported[component[m.tri.idx()] as usize]),
    );
    out.sort_unstable_by_key(|m| m.tri);
    for m in &mut out {
        m.shell = regions
            .shell_of(m.tri, m.side)
            .map_or(u32::MAX, |s| s as u32);
        m.component_triangles = sizes[component[m.tri.idx()] as usize];
    }
    (out, Some(regions))
}

/// Casts one ray per component through the first of its `members` (a triangle, and the
/// side to measure or `None` for the side the ray arrives from) that can be cast through;
/// returns the components whose measured side disagrees with its label, in order of the
/// triangle (`shell` and `component_triangles` are the caller's to fill).
fn measure(
    mesh: &LabeledMesh,
    members: &[Vec<(TriId, Option<Side>)>],
    bvh: Option<&Bvh>,
) -> Vec<MisplacedShell> {
    let rays: Vec<Ray> = members
        .iter()
        .filter_map(|tris| {
            tris.iter()
                .find_map(|&(t, side)| Ray::through(mesh, t, side))
        })
        .collect();
    let mut out: Vec<MisplacedShell> = rays
        .par_iter()
        .filter_map(|ray| {
            let found = ray.vector_on_side(mesh, bvh);
            let claimed = mesh.labels(ray.tri)[ray.side.index()];
            (found.as_slice() != [(claimed, 1)]).then_some(MisplacedShell {
                tri: ray.tri,
                side: ray.side,
                claimed,
                found,
                shell: u32::MAX,
                component_triangles: 0,
            })
        })
        .collect();
    out.sort_unstable_by_key(|m| m.tri);
    out
}

/// The surface component of every triangle slot (triangles joined across edges, by
/// union–find over the corner table's opposite pointers; dead slots in component 0 —
/// they are never asked), numbered in order of their lowest triangle, and the count.
/// No region flood: cheaper than [`Regions::components`] when shells are not needed.
pub fn surface_components(mesh: &LabeledMesh) -> (Vec<u32>, usize) {
    let n = mesh.triangle_capacity();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for t in mesh.triangles() {
        for side in [Side::Front, Side::Back] {
            for k in 0..3 {
                if let Some(o) = mesh.opposite(crate::ids::CornerId::of(t, side, k)) {
                    union(&mut parent, t.raw(), o.tri().raw());
                }
            }
        }
    }
    let mut id = vec![u32::MAX; n];
    let mut count = 0u32;
    let mut component = vec![0u32; n];
    for t in mesh.triangles() {
        let root = find(&mut parent, t.raw()) as usize;
        if id[root] == u32::MAX {
            id[root] = count;
            count += 1;
        }
        component[t.idx()] = id[root];
    }
    (component, count as usize)
}

/// A line along an axis through a triangle, which it crosses, and the side of the
/// triangle to measure.
struct Ray {
    axis: Axis,
    /// The line's other two coordinates ([`Axis::project`]).
    line: DVec2,
    /// A point of the line (the triangle's centroid).
    point: DVec3,
    tri: TriId,
    /// The side of `tri` whose material is measured.
    side: Side,
    /// The side of `tri` the line arrives from (travelling towards +axis).
    arrives: Side,
}

impl Ray {
    /// The line along `t`'s dominant normal axis through its centroid, to measure `side`
    /// (`None`: the side it arrives from), if the line crosses `t` (exactly, under
    /// Simulation of Simplicity; the centroid of a sliver may round outside it).
    fn through(mesh: &LabeledMesh, t: TriId, side: Option<Side>) -> Option<Ray> {
        let p = mesh.tri_positions(t);
        if !p.iter().all(|q| q.is_finite()) {
            return None;
        }
        let axis = Axis::dominant((p[1] - p[0]).cross(p[2] - p[0]));
        if orient2d_axis(axis, p[0], p[1], p[2]) == Sign::Zero {
            return None;
        }
        let point = (p[0] + p[1] + p[2]) / 3.0;
        let line = axis.project(point);
        let crossing = cross_axis_line_triangle(axis, line, p)?;
        // Travelling towards +axis through a triangle whose normal points that way goes
        // from its back to its front: it arrives from the back.
        let arrives = if crossing.direction > 0 {
            Side::Back
        } else {
            Side::Front
        };
        Some(Ray {
            axis,
            line,
            point,
            tri: t,
            side: side.unwrap_or(arrives),
            arrives,
        })
    }

    /// The material vector on `self.side` of `self.tri`: `e_0`, changed by every crossing
    /// of the line ordered before `tri`'s (coplanar ties, which only overlapping triangles
    /// make, by triangle id), and by `tri`'s own when `side` is the one the line leaves
    /// into.
    fn vector_on_side(&self, mesh: &LabeledMesh, bvh: Option<&Bvh>) -> Vec<(Label, i32)> {
        let mut counts: Vec<(Label, i32)> = vec![(Label::OUTSIDE, 1)];
        let mut add = |l: Label, d: i32| match counts.iter_mut().find(|(m, _)| *m == l) {
            Some((_, n)) => *n += d,
            None => counts.push((l, d)),
        };
        let own = mesh.tri_positions(self.tri);
        let alive = mesh.tri_alive_flags();
        let crossing_of = |c: u32| {
            if c == self.tri.raw() || !alive[c as usize] {
                return None;
            }
            let q = mesh.tri_positions(TriId::new(c));
            cross_axis_line_triangle(self.axis, self.line, q).map(|x| (c, x.direction))
        };
        let crossings: Vec<(u32, i8)> = match bvh {
            Some(bvh) => {
                let (mut lo, mut hi) = (self.point, self.point);
                lo[self.axis.index()] = f64::NEG_INFINITY;
                hi[self.axis.index()] = f64::INFINITY;
                let mut found = Vec::new();
                bvh.query(&Aabb::new(lo, hi), 0.0, |c| found.extend(crossing_of(c)));
                found
            }
            None => (0..alive.len() as u32)
                .into_par_iter()
                .filter_map(crossing_of)
                .collect(),
        };
        for (c, direction) in crossings {
            let q = mesh.tri_positions(TriId::new(c));
            let before = match compare_crossings(self.axis, self.point, q, own) {
                std::cmp::Ordering::Less => true,
                std::cmp::Ordering::Equal => c < self.tri.raw(),
                std::cmp::Ordering::Greater => false,
            };
            if before {
                let [front, back] = mesh.labels(TriId::new(c));
                let (left, entered) = if direction > 0 {
                    (back, front)
                } else {
                    (front, back)
                };
                add(left, -1);
                add(entered, 1);
            }
        }
        if self.side != self.arrives {
            let labels = mesh.labels(self.tri);
            add(labels[self.arrives.index()], -1);
            add(labels[self.side.index()], 1);
        }
        counts.retain(|&(_, n)| n != 0);
        counts.sort_unstable_by_key(|&(l, _)| l);
        counts
    }
}

/// One component's outside relabelled by [`place_nested`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Relabelled {
    /// A triangle of the component (in the input's numbering).
    pub tri: TriId,
    /// Triangles in the component.
    pub component_triangles: usize,
    /// The material its outside was labelled with.
    pub from: Label,
    /// The material it lies in, which its outside now carries.
    pub to: Label,
    /// Triangles whose labels changed (those removed included).
    pub relabelled_triangles: usize,
    /// Triangles removed because both their sides now face `to` (a part of `to` drawn
    /// inside `to`: the faces between them separate nothing).
    pub removed_triangles: usize,
}

impl std::fmt::Display for Relabelled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the surface component of {} ({} triangles) lies inside material {}: its outside \
             was relabelled from material {} to {}",
            self.tri,
            self.component_triangles,
            self.to.raw(),
            self.from.raw(),
            self.to.raw()
        )?;
        if self.removed_triangles > 0 {
            write!(
                f,
                " and {} triangles with material {} on both sides were removed",
                self.removed_triangles,
                self.to.raw()
            )?;
        }
        Ok(())
    }
}

/// Relabels nested parts: every surface component that lies wholly inside one bounded
/// material (its measured outside vector is one-hot, [`MisplacedShell::found_material`],
/// and not 0) but is labelled with another outside gets that material on its outer shell,
/// and triangles left with the same material on both sides are removed. A component
/// lying in the ambient material 0 that claims another outside is not nested: its labels
/// are swapped or its orientation inverted, which relabelling would turn into deleting
/// it, so it is left for the caller to refuse. Components for which
/// `may_relabel(tri)` is false (the caller's: those that intersect another component,
/// whose overlap the grid repair resolves instead) are left alone, and so are components
/// inside an overlap (mixed vector).
///
/// Why this repair: a part exported on its own is labelled against the ambient material
/// 0, and an assembly of such parts (an inclusion inside a body, a core inside a shell)
/// arrives with every inner part's outside saying 0. Read as solids, the inner part
/// overlaps the outer one completely, and an overlap resolution by nearest interface
/// (§8.1) gives all of it to the outer material: the inner material would vanish. Read
/// as an assembly — what the labels of a nested part mean — the inner part displaces the
/// outer material, which is what relabelling its outside says; no volume is lost.
///
/// Rounds run from the outside in: a part nested two deep measures a mixed vector until
/// the part around it has been relabelled. Bounded by the number of components + 1
/// rounds. Returns the mesh (`None` when nothing changed; rebuilt and densely numbered
/// when triangles were removed, otherwise with the input's ids) and what was relabelled
/// (with the input's triangle ids).
pub fn place_nested(
    mesh: &LabeledMesh,
    may_relabel: impl Fn(TriId) -> bool,
) -> Result<(Option<LabeledMesh>, Vec<Relabelled>), crate::MeshError> {
    let mut work: Option<LabeledMesh> = None;
    let mut done: Vec<Relabelled> = Vec::new();
    let mut same: Vec<TriId> = Vec::new();
    let mut rounds = 0;
    loop {
        let current = work.as_ref().unwrap_or(mesh);
        rounds += 1;
        let (misplaced, regions) = locate(current);
        let Some(regions) = regions else {
            break;
        };
        if rounds > regions.shells.len() + 1 {
            break;
        }
        let movable: Vec<(MisplacedShell, Label)> = misplaced
            .into_iter()
            .filter(|m| may_relabel(m.tri))
            .filter_map(|m| {
                m.found_material()
                    .filter(|&to| to != Label::OUTSIDE)
                    .map(|to| (m, to))
            })
            .collect();
        if movable.is_empty() {
            break;
        }
        // The relabelling (index into `movable`) of every shell that changes.
        let mut owner = vec![u32::MAX; regions.shells.len()];
        let first = done.len();
        for (k, (m, to)) in movable.iter().enumerate() {
            owner[m.shell as usize] = k as u32;
            done.push(Relabelled {
                tri: m.tri,
                component_triangles: m.component_triangles,
                from: m.claimed,
                to: *to,
                relabelled_triangles: 0,
                removed_triangles: 0,
            });
        }
        let mut next = current.clone();
        for t in current.triangles() {
            let mut labels = current.labels(t);
            let mut by = None;
            for side in [Side::Front, Side::Back] {
                let k = regions.shell_of(t, side).map_or(u32::MAX, |s| owner[s]);
                if k != u32::MAX {
                    labels[side.index()] = movable[k as usize].1;
                    by = Some(first + k as usize);
                }
            }
            if let Some(r) = by {
                done[r].relabelled_triangles += 1;
                next.set_labels(t, labels);
                if labels[0] == labels[1] {
                    done[r].removed_triangles += 1;
                    same.push(t);
                }
            }
        }
        work = Some(next);
    }
    // Removed at the end, so that triangle ids (which `may_relabel` is asked about) stay
    // those of the input through every round; a triangle with one material on both sides
    // changes no ray's vector meanwhile.
    if !same.is_empty() {
        work = work.map(|w| without_triangles(&w, &same)).transpose()?;
    }
    Ok((work, done))
}

/// `mesh` without `remove`, rebuilt from plain arrays (vertices no triangle uses any
/// more dropped), so that the corner table pairs the sides across the removed faces.
fn without_triangles(
    mesh: &LabeledMesh,
    remove: &[TriId],
) -> Result<LabeledMesh, crate::MeshError> {
    let mut gone = vec![false; mesh.triangle_capacity()];
    for t in remove {
        gone[t.idx()] = true;
    }
    let mut index = vec![u32::MAX; mesh.vertex_capacity()];
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    let mut labels = Vec::new();
    for t in mesh.triangles().filter(|t| !gone[t.idx()]) {
        let tri = mesh.tri(t).map(|v| {
            if index[v.idx()] == u32::MAX {
                index[v.idx()] = positions.len() as u32;
                positions.push(mesh.position(v));
            }
            index[v.idx()]
        });
        tris.push(tri);
        labels.push(mesh.labels(t).map(|l| l.raw()));
    }
    LabeledMesh::from_raw(positions, &tris, &labels)
}

/// Every triangle of the surface components that hold one of `tris`, in id order: what a
/// repair must revisit for a [`MisplacedShell`], which names one triangle of its
/// component.
pub fn component_triangles(mesh: &LabeledMesh, tris: &[TriId]) -> Vec<TriId> {
    let (component, count) = surface_components(mesh);
    let mut wanted = vec![false; count];
    let alive = mesh.tri_alive_flags();
    for &t in tris {
        if alive.get(t.idx()).copied().unwrap_or(false) {
            wanted[component[t.idx()] as usize] = true;
        }
    }
    mesh.triangles()
        .filter(|&t| wanted[component[t.idx()] as usize])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::{cuboid, icosphere};
    use crate::geometry::label_volumes;
    use crate::validate::{ValidateOptions, validate};

    fn l(i: u32) -> Label {
        Label::new(i)
    }

    fn sphere(centre: DVec3, radius: f64, outside: u32, inside: u32) -> LabeledMesh {
        icosphere(2, centre, radius, [l(outside), l(inside)]).expect("sphere")
    }

    fn union(parts: &[LabeledMesh]) -> LabeledMesh {
        LabeledMesh::disjoint_union(parts).expect("union")
    }

    fn volume(m: &LabeledMesh, label: u32) -> f64 {
        label_volumes(m)
            .into_iter()
            .find(|(k, _)| *k == l(label))
            .map_or(0.0, |(_, v)| v)
    }

    fn misplaced(m: &LabeledMesh) -> Vec<MisplacedShell> {
        misplaced_shells(m)
    }

    #[test]
    fn a_part_nested_with_the_outside_label_is_misplaced_and_named() {
        let outer = sphere(DVec3::ZERO, 1.0, 0, 1);
        let wrong = union(&[outer.clone(), sphere(DVec3::ZERO, 0.5, 0, 2)]);
        let report = validate(&wrong, &ValidateOptions::default());
        assert!(!report.is_valid());
        let listed = report.misplaced_shells.as_ref().expect("checked");
        assert_eq!(listed.count, 1);
        let m = &listed.items[0];
        assert!(
            m.tri.idx() >= outer.num_triangles(),
            "the inner sphere is named"
        );
        assert_eq!((m.claimed, m.found_material()), (l(0), Some(l(1))));
        assert_eq!(m.component_triangles, outer.num_triangles());
        assert!(
            report.to_string().contains("lies in material 1"),
            "{report}"
        );

        let right = union(&[outer, sphere(DVec3::ZERO, 0.5, 1, 2)]);
        let report = validate(&right, &ValidateOptions::default());
        assert!(report.is_valid(), "{report}");
        assert_eq!(report.misplaced_shells.map(|m| m.count), Some(0));
    }

    #[test]
    fn separate_and_touching_parts_are_placed() {
        // Side by side, in the ambient material: nothing nested.
        let apart = union(&[
            sphere(DVec3::ZERO, 1.0, 0, 1),
            sphere(DVec3::new(3.0, 0.2, -0.1), 1.0, 0, 2),
            cuboid(
                DVec3::new(-1.0, 3.0, -1.0),
                DVec3::new(1.0, 4.0, 1.0),
                [l(0), l(3)],
            )
            .expect("box"),
        ]);
        assert!(misplaced(&apart).is_empty());
        // Nested boxes share no triangle but their rays cross axis-aligned faces and
        // the diagonals of their squares, where Simulation of Simplicity decides.
        let boxes = union(&[
            cuboid(DVec3::splat(-2.0), DVec3::splat(2.0), [l(0), l(1)]).expect("box"),
            cuboid(DVec3::splat(-1.0), DVec3::splat(1.0), [l(1), l(2)]).expect("box"),
            cuboid(DVec3::splat(-0.5), DVec3::splat(0.5), [l(2), l(3)]).expect("box"),
        ]);
        assert!(misplaced(&boxes).is_empty());
        let wrong = union(&[
            cuboid(DVec3::splat(-2.0), DVec3::splat(2.0), [l(0), l(1)]).expect("box"),
            cuboid(DVec3::splat(-1.0), DVec3::splat(1.0), [l(1), l(2)]).expect("box"),
            cuboid(DVec3::splat(-0.5), DVec3::splat(0.5), [l(1), l(3)]).expect("box"),
        ]);
        let found = misplaced(&wrong);
        assert_eq!(found.len(), 1);
        assert_eq!(
            (found[0].claimed, found[0].found_material()),
            (l(1), Some(l(2)))
        );
    }

    #[test]
    fn an_inside_out_part_lies_in_material_0_and_is_not_relabelled() {
        let inverted = sphere(DVec3::ZERO, 1.0, 1, 0);
        let found = misplaced(&inverted);
        assert_eq!(found.len(), 1);
        assert_eq!(
            (found[0].claimed, found[0].found_material()),
            (l(1), Some(l(0)))
        );
        let (placed, relabelled) = place_nested(&inverted, |_| true).expect("runs");
        assert!(
            placed.is_none() && relabelled.is_empty(),
            "swapped labels are not a nesting"
        );
    }

    #[test]
    fn nested_parts_are_relabelled_from_the_outside_in() {
        let (a, b, c) = (
            sphere(DVec3::ZERO, 1.0, 0, 1),
            sphere(DVec3::new(0.1, 0.0, 0.0), 0.6, 0, 2),
            sphere(DVec3::new(0.2, 0.05, 0.0), 0.3, 0, 3),
        );
        let (va, vb, vc) = (volume(&a, 1), volume(&b, 2), volume(&c, 3));
        let mesh = union(&[a, b.clone(), c]);
        let (placed, relabelled) = place_nested(&mesh, |_| true).expect("runs");
        let placed = placed.expect("relabelled");
        assert_eq!(relabelled.len(), 2);
        assert_eq!((relabelled[0].from, relabelled[0].to), (l(0), l(1)));
        assert_eq!((relabelled[1].from, relabelled[1].to), (l(0), l(2)));
        assert_eq!(relabelled[0].relabelled_triangles, b.num_triangles());
        let report = validate(&placed, &ValidateOptions::with_intersections());
        assert!(report.is_valid(), "{report}");
        let tol = 1e-12;
        assert!((volume(&placed, 1) - (va - vb)).abs() < tol);
        assert!((volume(&placed, 2) - (vb - vc)).abs() < tol);
        assert!((volume(&placed, 3) - vc).abs() < tol);
        assert_eq!(
            placed.num_triangles(),
            mesh.num_triangles(),
            "nothing removed"
        );
    }

    #[test]
    fn a_part_of_the_material_around_it_dissolves_into_it() {
        let outer = sphere(DVec3::ZERO, 1.0, 0, 1);
        let mesh = union(&[outer.clone(), sphere(DVec3::ZERO, 0.5, 0, 1)]);
        let (placed, relabelled) = place_nested(&mesh, |_| true).expect("runs");
        let placed = placed.expect("changed");
        assert_eq!(relabelled.len(), 1);
        assert_eq!(
            relabelled[0].removed_triangles,
            mesh.num_triangles() - outer.num_triangles()
        );
        assert_eq!(placed.num_triangles(), outer.num_triangles());
        assert_eq!(
            placed.num_vertices(),
            outer.num_vertices(),
            "its vertices went too"
        );
        assert!(validate(&placed, &ValidateOptions::default()).is_valid());
        assert!((volume(&placed, 1) - volume(&outer, 1)).abs() < 1e-12);
    }

    #[test]
    fn parts_the_caller_holds_back_are_left_alone() {
        let mesh = union(&[
            sphere(DVec3::ZERO, 1.0, 0, 1),
            sphere(DVec3::ZERO, 0.5, 0, 2),
        ]);
        let (placed, relabelled) = place_nested(&mesh, |_| false).expect("runs");
        assert!(placed.is_none() && relabelled.is_empty());
    }

    /// More components than [`SCAN_LIMIT`]: the rays go through the tree.
    #[test]
    fn many_nested_parts_are_each_located() {
        let mut parts = vec![sphere(DVec3::ZERO, 3.0, 0, 1)];
        for i in 0..27u32 {
            let c = DVec3::new((i % 3) as f64, ((i / 3) % 3) as f64, (i / 9) as f64) - 1.0;
            parts.push(icosphere(1, c * 1.2, 0.3, [l(0), l(2 + i)]).expect("sphere"));
        }
        let mesh = union(&parts);
        let found = misplaced(&mesh);
        assert_eq!(found.len(), 27);
        assert!(
            found
                .iter()
                .all(|m| m.found_material() == Some(l(1)) && m.claimed == l(0))
        );
        let (placed, relabelled) = place_nested(&mesh, |_| true).expect("runs");
        assert_eq!(relabelled.len(), 27);
        assert!(misplaced(&placed.expect("relabelled")).is_empty());
    }

    #[test]
    fn a_mixed_vector_is_written_as_a_sum() {
        let m = MisplacedShell {
            tri: TriId::new(0),
            side: Side::Front,
            claimed: l(2),
            found: vec![(l(0), -1), (l(1), 1), (l(2), 2)],
            shell: 0,
            component_triangles: 4,
        };
        assert_eq!(m.found_material(), None);
        assert_eq!(m.found_text(), "−e_0 + e_1 + 2e_2");
    }
}
