//! Cyclical normal flow (Los Topos §8.2, Fig. 16, after Saye and Sethian 2012).
//!
//! Three materials chase each other: `a` advances into `b`, `b` into `c`, `c` into `a`,
//! all at the same speed. No per-material speeds can say that (it would need
//! `s_a > s_b > s_c > s_a`), hence per-pair speeds. Started from two overlapping spheres
//! `a` and `b` in `c` sharing a flat disk bounded by a triple curve, the sheets curl
//! around the triple curve, which the exact solution keeps still; as in Los Topos the
//! triple curve is a zero-velocity boundary ([`JunctionRule::Pinned`]) and the sheets move
//! by face offsetting, the scheme Los Topos used there.

use mesh_core::Label;

use super::error::check_finite;
use super::{FlowError, InterfaceSpeeds, JunctionRule, NormalFlow, NormalScheme};

/// The cyclical flow `a → b → c → a` at `speed`, by face offsetting with pinned
/// junctions. Any material other than the three is stationary against all. Fails on a
/// non-finite speed or labels that are not three distinct materials.
pub fn cyclic_normal_flow(
    a: Label,
    b: Label,
    c: Label,
    speed: f64,
) -> Result<NormalFlow, FlowError> {
    const NAME: &str = "cyclic-normal";
    check_finite(NAME, "speed", speed)?;
    if a == b || b == c || c == a {
        return Err(super::error::invalid(
            NAME,
            "labels",
            [a, b, c],
            "three distinct labels",
        ));
    }
    let speeds = InterfaceSpeeds::per_material(0.0)
        .with_pair(a, b, speed)
        .with_pair(b, c, speed)
        .with_pair(c, a, speed);
    Ok(NormalFlow::new(speeds, NormalScheme::FaceOffsetting)?
        .with_junctions(JunctionRule::Pinned)
        .named(NAME))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::Flow;
    use crate::flows::test_meshes::triple_fan;
    use glam::DVec3;
    use mesh_core::VertexId;

    fn l(i: u32) -> Label {
        Label::new(i)
    }

    #[test]
    fn sheets_move_cyclically_and_the_triple_curve_stays() {
        let (a, b, c) = (l(1), l(2), l(0));
        let flow = cyclic_normal_flow(a, b, c, 0.5).unwrap();
        assert_eq!(flow.name(), "cyclic-normal");
        let mesh = triple_fan(a, b, c);
        let v = flow.velocities(&mesh);
        assert_eq!(v[VertexId::new(0)], DVec3::ZERO);
        // Sheet k separates (behind → front) a|b, b|c, c|a: its normal points into the
        // front wedge, and in every case the material behind advances into the one in
        // front (a into b, b into c, c into a): speed +0.5 along the normal.
        for k in 0..3 {
            let angle = (90.0 + 120.0 * k as f64).to_radians();
            let d = DVec3::new(angle.cos(), angle.sin(), 0.0);
            let n = DVec3::Z.cross(d);
            let got = v[VertexId::new(3 + k)];
            assert!((got - 0.5 * n).length() < 1e-12, "sheet {k}: {got}");
        }
    }

    #[test]
    fn unpinned_symmetric_junction_also_stays_by_least_squares() {
        let (a, b, c) = (l(1), l(2), l(0));
        let flow = cyclic_normal_flow(a, b, c, 0.5)
            .unwrap()
            .with_junctions(JunctionRule::LeastSquares);
        let v = flow.velocities(&triple_fan(a, b, c));
        assert!(v[VertexId::new(0)].length() < 1e-12);
    }

    #[test]
    fn rejects_repeated_labels_and_bad_speed() {
        assert!(cyclic_normal_flow(l(1), l(1), l(0), 1.0).is_err());
        assert!(cyclic_normal_flow(l(1), l(2), l(0), f64::INFINITY).is_err());
    }
}
