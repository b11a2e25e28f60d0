//! Normal speeds per pair of materials.
//!
//! **Convention.** `speed(grower, into)` is the rate at which material `grower` advances
//! into material `into` across their interface, along the interface normal that points
//! into `into`. It is antisymmetric: `speed(b, a) = −speed(a, b)` (`b` advancing into `a`
//! at `−s` is `a` advancing into `b` at `s`), and `speed(a, a) = 0`.
//!
//! Two ways to set it, combinable:
//! - **per material**: material `L` grows at `s_L`, and an interface between `a` and `b`
//!   moves at `s_a − s_b`. Two spheres of speed 1 in an outside of speed 0 expand at 1
//!   and their shared interface, once created, stays put (`1 − 1 = 0`) — the merging
//!   bubbles of the Los Topos paper (§8.2) and the 2024 paper (§9.6, Fig. 18);
//! - **per pair**, overriding the above: needed for cyclical flow (A into B into C into
//!   A, Los Topos Fig. 16), which no per-material speeds can express.

use mesh_core::Label;

use super::FlowError;
use super::error::check_finite;

/// Antisymmetric per-material-pair normal speeds (see the module doc for the convention).
#[derive(Clone, Debug, PartialEq)]
pub struct InterfaceSpeeds {
    /// Growth speed of materials not listed in `materials`.
    default: f64,
    /// Per-material growth speeds, sorted by label.
    materials: Vec<(Label, f64)>,
    /// Per-pair overrides `(lo, hi, speed(lo, hi))` with `lo < hi`, sorted.
    pairs: Vec<(Label, Label, f64)>,
}

impl InterfaceSpeeds {
    /// Every material grows at `default` until told otherwise; with nothing else set,
    /// every interface is stationary (`s − s = 0`).
    pub fn per_material(default: f64) -> Self {
        InterfaceSpeeds {
            default,
            materials: Vec::new(),
            pairs: Vec::new(),
        }
    }

    /// Every material except `ambient` grows at `speed` into `ambient` (and into each
    /// other at 0): the expanding-spheres benchmark of the 2024 paper (§9.6); negative
    /// `speed` shrinks them.
    pub fn grow_into(ambient: Label, speed: f64) -> Self {
        Self::per_material(speed).with_material(ambient, 0.0)
    }

    /// Sets the growth speed of one material.
    pub fn with_material(mut self, label: Label, speed: f64) -> Self {
        match self.materials.binary_search_by_key(&label, |e| e.0) {
            Ok(i) => self.materials[i].1 = speed,
            Err(i) => self.materials.insert(i, (label, speed)),
        }
        self
    }

    /// Sets the speed at which `grower` advances into `into`, overriding the
    /// per-material difference for that pair. `grower == into` is ignored (a material has
    /// no interface with itself).
    pub fn with_pair(mut self, grower: Label, into: Label, speed: f64) -> Self {
        if grower == into {
            return self;
        }
        let (lo, hi, s) = if grower < into {
            (grower, into, speed)
        } else {
            (into, grower, -speed)
        };
        match self.pairs.binary_search_by_key(&(lo, hi), |e| (e.0, e.1)) {
            Ok(i) => self.pairs[i].2 = s,
            Err(i) => self.pairs.insert(i, (lo, hi, s)),
        }
        self
    }

    /// Growth speed of one material (the default if not listed).
    pub fn material(&self, label: Label) -> f64 {
        match self.materials.binary_search_by_key(&label, |e| e.0) {
            Ok(i) => self.materials[i].1,
            Err(_) => self.default,
        }
    }

    /// Speed at which `grower` advances into `into` (see the module doc).
    pub fn speed(&self, grower: Label, into: Label) -> f64 {
        if grower == into {
            return 0.0;
        }
        let (lo, hi, sign) = if grower < into {
            (grower, into, 1.0)
        } else {
            (into, grower, -1.0)
        };
        match self.pairs.binary_search_by_key(&(lo, hi), |e| (e.0, e.1)) {
            Ok(i) => sign * self.pairs[i].2,
            Err(_) => self.material(grower) - self.material(into),
        }
    }

    /// Checks every speed is finite; `flow` names the flow being built.
    pub(crate) fn check(&self, flow: &'static str) -> Result<(), FlowError> {
        check_finite(flow, "default material speed", self.default)?;
        for &(_, s) in &self.materials {
            check_finite(flow, "material speed", s)?;
        }
        for &(_, _, s) in &self.pairs {
            check_finite(flow, "pair speed", s)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(i: u32) -> Label {
        Label::new(i)
    }

    #[test]
    fn per_material_speeds_are_differences() {
        let s = InterfaceSpeeds::grow_into(l(0), 2.0).with_material(l(3), -1.0);
        assert_eq!(s.speed(l(1), l(0)), 2.0);
        assert_eq!(s.speed(l(0), l(1)), -2.0);
        assert_eq!(s.speed(l(1), l(2)), 0.0);
        assert_eq!(s.speed(l(1), l(3)), 3.0);
        assert_eq!(s.speed(l(3), l(0)), -1.0);
        assert_eq!(s.speed(l(4), l(4)), 0.0);
    }

    #[test]
    fn pairs_override_and_stay_antisymmetric() {
        let s = InterfaceSpeeds::per_material(0.0)
            .with_pair(l(1), l(2), 0.5)
            .with_pair(l(3), l(2), 0.25)
            .with_pair(l(2), l(3), 0.75);
        assert_eq!(s.speed(l(1), l(2)), 0.5);
        assert_eq!(s.speed(l(2), l(1)), -0.5);
        // The later setting of the pair {2, 3} wins, whichever way round it was given.
        assert_eq!(s.speed(l(2), l(3)), 0.75);
        assert_eq!(s.speed(l(3), l(2)), -0.75);
        assert_eq!(s.speed(l(1), l(3)), 0.0);
    }

    #[test]
    fn check_rejects_non_finite() {
        assert!(InterfaceSpeeds::grow_into(l(0), 1.0).check("t").is_ok());
        assert!(
            InterfaceSpeeds::grow_into(l(0), f64::NAN)
                .check("t")
                .is_err()
        );
        assert!(
            InterfaceSpeeds::per_material(0.0)
                .with_pair(l(0), l(1), f64::INFINITY)
                .check("t")
                .is_err()
        );
    }
}
