//! Flows chained in time: the double bubble grows for a while, then shrinks (2024 paper
//! Fig. 18); the curl-noise scene alternates normal flow and curl noise (Los Topos
//! Fig. 15).

use glam::DVec3;
use mesh_core::LabeledMesh;

use super::error::invalid;
use super::{Flow, FlowError, VelocityField};

/// A sequence of `(duration, flow)` phases, played once (the last phase then lasts
/// forever) or repeated cyclically.
///
/// A step belongs to the phase active at its *start* time `t`; a step that straddles a
/// boundary is not split. Times within `1e-9` of a phase end (relative to the cycle
/// length) count as past it, so that `t` accumulated as `k·dt` in floating point does
/// not fall one step short of a boundary.
pub struct Schedule {
    phases: Vec<(f64, Box<dyn Flow>)>,
    cycle: f64,
    repeat: bool,
}

impl Schedule {
    /// Phases in order. Fails if there are none or a duration is not finite and positive.
    pub fn new(phases: Vec<(f64, Box<dyn Flow>)>, repeat: bool) -> Result<Self, FlowError> {
        if phases.is_empty() {
            return Err(invalid("schedule", "phases", 0, "at least one phase"));
        }
        for (d, _) in &phases {
            super::error::check_positive("schedule", "duration", *d)?;
        }
        let cycle = phases.iter().map(|p| p.0).sum();
        Ok(Schedule {
            phases,
            cycle,
            repeat,
        })
    }

    /// Index of the phase active at time `t` (times before 0 use the first phase).
    pub fn phase_at(&self, t: f64) -> usize {
        let last = self.phases.len() - 1;
        let local = if self.repeat {
            t.rem_euclid(self.cycle)
        } else {
            t
        };
        let eps = 1e-9 * self.cycle;
        let mut end = 0.0;
        for (i, (d, _)) in self.phases.iter().enumerate() {
            end += d;
            if local < end - eps {
                return i;
            }
        }
        // Past the end: a one-shot schedule stays in its last phase; in a repeating one
        // `local` is within `eps` of the cycle end, i.e. at the start of the next cycle.
        if self.repeat { 0 } else { last }
    }

    fn active(&self, t: f64) -> &dyn Flow {
        self.phases[self.phase_at(t)].1.as_ref()
    }
}

impl Flow for Schedule {
    fn name(&self) -> &str {
        "schedule"
    }

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3> {
        self.active(t).propose(mesh, t, dt)
    }

    fn velocity_field(&self, t: f64) -> Option<&dyn VelocityField> {
        self.active(t).velocity_field(t)
    }

    fn max_stable_dt(&self, mesh: &LabeledMesh) -> Option<f64> {
        self.phases
            .iter()
            .filter_map(|(_, f)| f.max_stable_dt(mesh))
            .reduce(f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::{
        InterfaceSpeeds, MeanCurvatureFlow, NormalFlow, NormalScheme, RigidRotation,
    };
    use mesh_core::Label;

    fn grow(s: f64) -> Box<dyn Flow> {
        Box::new(
            NormalFlow::new(
                InterfaceSpeeds::grow_into(Label::new(0), s),
                NormalScheme::VertexNormals,
            )
            .unwrap(),
        )
    }

    #[test]
    fn one_shot_phases_and_boundaries() {
        let s = Schedule::new(vec![(1.0, grow(1.0)), (1.0, grow(-1.0))], false).unwrap();
        assert_eq!(s.phase_at(-1.0), 0);
        assert_eq!(s.phase_at(0.5), 0);
        // 10 steps of 0.1 sum to 0.9999999999999999, which must count as the boundary.
        let t: f64 = (0..10).map(|_| 0.1).sum();
        assert!(t < 1.0);
        assert_eq!(s.phase_at(t), 1);
        assert_eq!(s.phase_at(1.5), 1);
        assert_eq!(s.phase_at(100.0), 1);
        assert!(s.velocity_field(0.0).is_none());
    }

    #[test]
    fn repeating_alternation_dispatches_fields_and_bounds() {
        let rot = RigidRotation::new(DVec3::ZERO, DVec3::Z, 1.0).unwrap();
        let s = Schedule::new(vec![(0.1, grow(1.0)), (0.1, Box::new(rot))], true).unwrap();
        let phases: Vec<usize> = (0..6).map(|k| s.phase_at(k as f64 * 0.1)).collect();
        assert_eq!(phases, [0, 1, 0, 1, 0, 1]);
        assert!(s.velocity_field(0.0).is_none());
        assert!(s.velocity_field(0.1).is_some());
        let mesh = crate::flows::test_meshes::icosphere(1, 1.0, [Label::new(0), Label::new(1)]);
        assert_eq!(s.max_stable_dt(&mesh), None);
        let mcf =
            Schedule::new(vec![(1.0, Box::new(MeanCurvatureFlow::default()))], false).unwrap();
        assert!(mcf.max_stable_dt(&mesh).is_some_and(|d| d > 0.0));
    }

    #[test]
    fn rejects_empty_and_bad_durations() {
        assert!(Schedule::new(vec![], false).is_err());
        assert!(Schedule::new(vec![(0.0, grow(1.0))], true).is_err());
        assert!(Schedule::new(vec![(f64::INFINITY, grow(1.0))], false).is_err());
    }
}
