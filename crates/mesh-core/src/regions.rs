//! Regions: the connected pieces of space the mesh bounds, found by flood fill over sides.
//!
//! Each triangle side faces one material. Two sides are in the same *region shell* when
//! they are joined by opposite pointers, i.e. they bound the same wedge of space across an
//! edge. With a valid corner table every shell is a closed 2-manifold of sides (2024 paper
//! §4), and all its sides carry the same label. A volume with cavities has one shell per
//! boundary component (its outer skin and one per cavity): telling which shells bound the
//! same connected volume needs point location, which is the grid tracker's job.

use crate::corner::Side;
use crate::ids::{CornerId, Label, TriId};
use crate::mesh::LabeledMesh;

/// One connected component of sides.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionShell {
    /// The label of the first side found; `consistent` says whether all sides agree.
    pub label: Label,
    /// Number of triangle sides in the shell.
    pub sides: usize,
    /// True when every side of the shell faces `label`.
    pub consistent: bool,
    /// True when no side of the shell lies across a boundary edge (missing opposite).
    pub closed: bool,
    /// Signed volume enclosed by the shell's sides (divergence theorem; each side oriented
    /// to face into the region, so a bounded region has positive volume and the unbounded
    /// outside region a negative one).
    pub volume: f64,
}

/// All region shells of a mesh and the shell of every side.
#[derive(Clone, Debug, Default)]
pub struct Regions {
    /// Shells in order of discovery (by lowest triangle id).
    pub shells: Vec<RegionShell>,
    /// `side_shell[2·t + side]` = index into `shells`, or `u32::MAX` for dead triangles.
    pub side_shell: Vec<u32>,
}

impl Regions {
    /// The shell of triangle `t`'s side `side`.
    pub fn shell_of(&self, t: TriId, side: Side) -> Option<usize> {
        let s = *self.side_shell.get(t.idx() * 2 + side.index())?;
        (s != u32::MAX).then_some(s as usize)
    }

    /// Shells that enclose a bounded volume (positive enclosed volume), with their labels.
    pub fn bounded(&self) -> impl Iterator<Item = &RegionShell> + '_ {
        self.shells.iter().filter(|s| s.volume > 0.0)
    }
}

impl LabeledMesh {
    /// Flood-fills sides over opposite pointers into [`Regions`]. Linear time, no recursion.
    pub fn regions(&self) -> Regions {
        let n_sides = self.triangle_capacity() * 2;
        let mut side_shell = vec![u32::MAX; n_sides];
        let mut shells = Vec::new();
        let mut stack: Vec<u32> = Vec::new();
        for t in self.triangles() {
            for side in [Side::Front, Side::Back] {
                let start = t.idx() * 2 + side.index();
                if side_shell[start] != u32::MAX {
                    continue;
                }
                let id = shells.len() as u32;
                let label = self.labels(t)[side.index()];
                let mut shell = RegionShell {
                    label,
                    sides: 0,
                    consistent: true,
                    closed: true,
                    volume: 0.0,
                };
                side_shell[start] = id;
                stack.push(start as u32);
                while let Some(s) = stack.pop() {
                    let c0 = CornerId::new(s * 3);
                    shell.sides += 1;
                    shell.consistent &= self.corner_label(c0) == label;
                    // Signed volume of the cone from the origin, with the side's own
                    // orientation (its normal points into the region it faces).
                    let [a, b, c] =
                        [c0, c0.next(), c0.prev()].map(|c| self.position(self.corner_vertex(c)));
                    shell.volume -= a.dot(b.cross(c)) / 6.0;
                    for c in [c0, c0.next(), c0.prev()] {
                        match self.opposite(c) {
                            Some(o) => {
                                let os = o.side_index();
                                if side_shell[os] == u32::MAX {
                                    side_shell[os] = id;
                                    stack.push(os as u32);
                                }
                            }
                            None => shell.closed = false,
                        }
                    }
                }
                shells.push(shell);
            }
        }
        Regions { shells, side_shell }
    }
}
