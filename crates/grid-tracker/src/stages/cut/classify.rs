//! Flawed or intact: the flood fill of App. A, with no new numerical test.
//!
//! Inside one triangle's constrained triangulation, two faces sharing an ordinary edge lie
//! on the same side of the flawed boundary, and two faces sharing a constraint edge (a
//! piece of the triangle's trace on a boundary face) lie on opposite sides. The three
//! corners are seeded with the side of the cell containing their vertex (under the
//! symbolic perturbation, [`super::points::vertex_cell`]); the fill then 2-colours every
//! face. A face reached with both colours means the trace does not separate the triangle
//! the way the corners say — a local inconsistency, reported, never guessed.

use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// The per-triangle CDT in the parameter frame.
pub(crate) type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Face colour: not yet reached.
pub(crate) const UNSET: u8 = 0;
/// Face colour: on the intact side (kept).
pub(crate) const INTACT: u8 = 1;
/// Face colour: on the flawed side (deleted).
pub(crate) const FLAWED: u8 = 2;

/// The fill reached a face with both colours, or left a face unreached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ColourConflict;

/// Colours every inner face of `cdt` ([`INTACT`] / [`FLAWED`], indexed by face index) from
/// the corner seeds `(vertex, flawed)`, flipping across constraint edges. `stack` is a
/// reusable buffer. Each face is pushed at most once, so the fill is bounded by the face
/// count.
pub(crate) fn colour_faces(
    cdt: &Cdt,
    seeds: [(FixedVertexHandle, bool); 3],
    colour: &mut Vec<u8>,
    stack: &mut Vec<FixedFaceHandle<InnerTag>>,
) -> Result<(), ColourConflict> {
    colour.clear();
    colour.resize(cdt.num_all_faces(), UNSET);
    stack.clear();
    for (v, flawed) in seeds {
        // A corner carries no constraint (cut points are strictly off the corners), so
        // every face around it has its colour; checking them all costs nothing.
        let c = if flawed { FLAWED } else { INTACT };
        for e in cdt.vertex(v).out_edges() {
            if let Some(f) = e.face().as_inner() {
                paint(colour, stack, f.fix(), c)?;
            }
        }
    }
    while let Some(f) = stack.pop() {
        let c = colour[f.index()];
        for e in cdt.face(f).adjacent_edges() {
            if let Some(g) = e.rev().face().as_inner() {
                let want = if e.is_constraint_edge() {
                    FLAWED + INTACT - c
                } else {
                    c
                };
                paint(colour, stack, g.fix(), want)?;
            }
        }
    }
    if cdt.fixed_inner_faces().any(|f| colour[f.index()] == UNSET) {
        return Err(ColourConflict);
    }
    Ok(())
}

/// Gives face `f` colour `c` (queueing it) unless it has one; a different one conflicts.
fn paint(
    colour: &mut [u8],
    stack: &mut Vec<FixedFaceHandle<InnerTag>>,
    f: FixedFaceHandle<InnerTag>,
    c: u8,
) -> Result<(), ColourConflict> {
    match colour[f.index()] {
        UNSET => {
            colour[f.index()] = c;
            stack.push(f);
            Ok(())
        }
        x if x == c => Ok(()),
        _ => Err(ColourConflict),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit frame triangle with one constraint across it: corner 0 on one side,
    /// corners 1 and 2 on the other.
    fn split_frame() -> (Cdt, [FixedVertexHandle; 5]) {
        let mut cdt = Cdt::new();
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.0], [0.0, 0.5]];
        let h = pts.map(|[x, y]| cdt.insert(Point2::new(x, y)).unwrap());
        assert_eq!(cdt.try_add_constraint(h[3], h[4]).len(), 1);
        (cdt, h)
    }

    #[test]
    fn constraint_flips_the_colour() {
        let (cdt, h) = split_frame();
        let (mut colour, mut stack) = (Vec::new(), Vec::new());
        colour_faces(
            &cdt,
            [(h[0], true), (h[1], false), (h[2], false)],
            &mut colour,
            &mut stack,
        )
        .unwrap();
        let mut flawed_area = 0.0;
        for f in cdt.inner_faces() {
            if colour[f.fix().index()] == FLAWED {
                flawed_area += f.area();
            }
        }
        // The corner triangle (0,0), (0.5,0), (0,0.5) has area 1/8.
        assert_eq!(flawed_area, 0.125);
    }

    #[test]
    fn inconsistent_seeds_conflict() {
        let (cdt, h) = split_frame();
        let (mut colour, mut stack) = (Vec::new(), Vec::new());
        // Corners 1 and 2 share a side of the constraint but are seeded differently.
        let r = colour_faces(
            &cdt,
            [(h[0], true), (h[1], true), (h[2], false)],
            &mut colour,
            &mut stack,
        );
        assert_eq!(r, Err(ColourConflict));
    }
}
