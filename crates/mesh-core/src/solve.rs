//! Jacobi-preconditioned conjugate gradients for the symmetric positive semi-definite
//! systems of the flows (the harness's volume-preserving surface tension, matrix-free).
//! (The collision backend's impact zones solve a least-squares problem instead, with
//! CGLS: their constraint systems are too nearly singular for CG on normal equations.)

/// Solves `A x = b` for a symmetric positive semi-definite `A` given by `multiply(x, y)`
/// (`y ← A x`), from `x = 0`.
///
/// `inverse_diagonal[i]` preconditions unknown `i` (0 keeps it out of every search
/// direction). `project` is applied to `b` and to every residual: it removes a component
/// `A` cannot produce (a null space the caller knows), or does nothing. Stops at a
/// residual of `tolerance · ‖project(b)‖`, after `max_iterations`, or when a search
/// direction has zero or NaN curvature (it lies in the null space). Why semi-definite is
/// enough: for `b` in the range of `A`, CG stays in that range and converges there.
pub fn conjugate_gradients(
    b: &[f64],
    inverse_diagonal: &[f64],
    tolerance: f64,
    max_iterations: usize,
    mut multiply: impl FnMut(&[f64], &mut [f64]),
    mut project: impl FnMut(&mut [f64]),
) -> Vec<f64> {
    let n = b.len();
    let dot = |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(p, q)| p * q).sum() };
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    project(&mut r);
    let norm_b = dot(&r, &r).sqrt();
    if norm_b == 0.0 || !norm_b.is_finite() {
        return x;
    }
    let stop = tolerance * norm_b;
    let mut z: Vec<f64> = r.iter().zip(inverse_diagonal).map(|(r, d)| r * d).collect();
    let mut p = z.clone();
    let mut ap = vec![0.0; n];
    let mut rz = dot(&r, &z);
    for _ in 0..max_iterations {
        multiply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        project(&mut r);
        if dot(&r, &r).sqrt() <= stop {
            break;
        }
        for i in 0..n {
            z[i] = r[i] * inverse_diagonal[i];
        }
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_spd_system() {
        // A = [[4, 1], [1, 3]], b = [1, 2]: x = [1/11, 7/11].
        let a = [[4.0, 1.0], [1.0, 3.0]];
        let x = conjugate_gradients(
            &[1.0, 2.0],
            &[0.25, 1.0 / 3.0],
            1e-14,
            10,
            |x, y| {
                for i in 0..2 {
                    y[i] = a[i][0] * x[0] + a[i][1] * x[1];
                }
            },
            |_| {},
        );
        assert!((x[0] - 1.0 / 11.0).abs() < 1e-12 && (x[1] - 7.0 / 11.0).abs() < 1e-12);
    }

    #[test]
    fn a_singular_consistent_system_with_its_null_space_projected_out() {
        // The graph Laplacian of a path of three nodes: null space (1, 1, 1); b sums to 0.
        let lap = |x: &[f64], y: &mut [f64]| {
            y[0] = x[0] - x[1];
            y[1] = 2.0 * x[1] - x[0] - x[2];
            y[2] = x[2] - x[1];
        };
        let mean_free = |r: &mut [f64]| {
            let m = r.iter().sum::<f64>() / 3.0;
            r.iter_mut().for_each(|v| *v -= m);
        };
        let b = [1.0, 0.0, -1.0];
        let x = conjugate_gradients(&b, &[1.0, 0.5, 1.0], 1e-13, 20, lap, mean_free);
        let mut y = [0.0; 3];
        lap(&x, &mut y);
        assert!(y.iter().zip(b).all(|(y, b)| (y - b).abs() < 1e-10));
    }

    #[test]
    fn zero_right_hand_side_gives_zero() {
        let x = conjugate_gradients(&[0.0; 4], &[1.0; 4], 1e-13, 10, |_, _| {}, |_| {});
        assert_eq!(x, vec![0.0; 4]);
    }
}
