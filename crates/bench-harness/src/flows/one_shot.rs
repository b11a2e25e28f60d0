//! One-shot motions: the whole deformation in the first step, then stillness.
//!
//! The 2024 paper's inversion test (Fig. 15) deforms a double bubble with strong noise in
//! a single step, and its copies test (Fig. 16) teleports rotated copies of a mesh onto
//! each other; the tracker must repair everything at once. Later steps propose the
//! current positions (no motion), so a longer run shows the repaired mesh settling under
//! the tracker's own improvement.

use glam::DVec3;
use mesh_core::LabeledMesh;

use super::{Flow, VelocityField};

/// True for the first step of a run (started at `t = 0`), whatever `dt` is.
fn is_first_step(t: f64, dt: f64) -> bool {
    t < 0.5 * dt.abs()
}

/// The current position of every vertex slot: "stay where you are".
fn still(mesh: &LabeledMesh) -> Vec<DVec3> {
    mesh.positions().to_vec()
}

/// Applies `inner` for the first step only (at `t = 0`), then proposes no motion.
pub struct OneShot {
    name: &'static str,
    inner: Box<dyn Flow>,
}

impl OneShot {
    /// Wraps a flow; `name` goes into run records.
    pub fn new(name: &'static str, inner: Box<dyn Flow>) -> Self {
        OneShot { name, inner }
    }
}

impl Flow for OneShot {
    fn name(&self) -> &str {
        self.name
    }

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3> {
        if is_first_step(t, dt) {
            self.inner.propose(mesh, t, dt)
        } else {
            still(mesh)
        }
    }

    fn velocity_field(&self, t: f64) -> Option<&dyn VelocityField> {
        self.inner.velocity_field(t)
    }
}

/// Moves every vertex to a fixed target position in the first step, then stays: the
/// initial mesh and the targets must share vertex numbering (one target per vertex slot
/// of the initial mesh). If the mesh no longer has that many slots at `t = 0` (a tracker
/// that renumbered on construction), nothing moves rather than moving the wrong vertices.
pub struct TargetPositions {
    targets: Vec<DVec3>,
}

impl TargetPositions {
    /// Targets indexed like the initial mesh's vertex slots.
    pub fn new(targets: Vec<DVec3>) -> Self {
        TargetPositions { targets }
    }
}

impl Flow for TargetPositions {
    fn name(&self) -> &str {
        "teleport"
    }

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3> {
        if is_first_step(t, dt) && mesh.vertex_capacity() == self.targets.len() {
            self.targets.clone()
        } else {
            still(mesh)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::test_meshes::icosphere;
    use mesh_core::Label;

    struct Shift;
    impl Flow for Shift {
        fn name(&self) -> &str {
            "shift"
        }
        fn propose(&self, mesh: &LabeledMesh, _t: f64, dt: f64) -> Vec<DVec3> {
            mesh.positions()
                .iter()
                .map(|p| *p + DVec3::X * dt)
                .collect()
        }
    }

    #[test]
    fn one_shot_moves_in_the_first_step_only() {
        let mesh = icosphere(1, 1.0, [Label::new(0), Label::new(1)]);
        let flow = OneShot::new("test", Box::new(Shift));
        let first = flow.propose(&mesh, 0.0, 0.5);
        let later = flow.propose(&mesh, 0.5, 0.5);
        for v in mesh.vertices() {
            assert_eq!(first[v.idx()], mesh.position(v) + DVec3::X * 0.5);
            assert_eq!(later[v.idx()], mesh.position(v));
        }
    }

    #[test]
    fn targets_apply_once_and_only_to_matching_meshes() {
        let mesh = icosphere(1, 1.0, [Label::new(0), Label::new(1)]);
        let targets: Vec<_> = mesh.positions().iter().map(|p| *p * 2.0).collect();
        let flow = TargetPositions::new(targets.clone());
        assert_eq!(flow.propose(&mesh, 0.0, 1.0), targets);
        assert_eq!(flow.propose(&mesh, 1.0, 1.0), mesh.positions());
        let other = icosphere(2, 1.0, [Label::new(0), Label::new(1)]);
        assert_eq!(flow.propose(&other, 0.0, 1.0), other.positions());
    }
}
