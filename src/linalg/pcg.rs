//! Preconditioned conjugate gradients for `A x = b`, A symmetric positive (semi)definite, with
//! the preconditioner applied as a solve (typically the Cholesky factor of a nearby matrix:
//! when A differs from the factored matrix by a rank-r change, CG converges in at most r + 1
//! iterations in exact arithmetic).

use super::{norm, par_dot, par_update};

/// `‖v‖` by [`par_dot`] (the same bits on any number of threads), [`norm`] where `vᵀv` under-
/// or overflows.
fn par_norm(v: &[f64]) -> f64 {
    let sum = par_dot(v, v);
    if sum.is_normal() {
        sum.sqrt()
    } else {
        norm(v)
    }
}

/// How a [`preconditioned_cg`] run ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgOutcome {
    /// Iterations done (each one product with A and one preconditioner solve).
    pub iterations: usize,
    /// `‖b − A x‖ ≤ tolerance · ‖b‖` holds for the returned x.
    pub converged: bool,
}

/// Solve `A x = b` from `x = 0` by conjugate gradients preconditioned with `precondition`
/// (`z ← M⁻¹ z`), stopping when `‖b − A x‖ ≤ tolerance · ‖b‖` or after `max_iterations`
/// (`x` then holds the last iterate, which still decreases `½xᵀAx − bᵀx` against 0, so it is a
/// descent direction for that quadratic). `apply(v, out)`: `out = A v`.
pub fn preconditioned_cg(
    mut apply: impl FnMut(&[f64], &mut [f64]),
    precondition: impl Fn(&mut [f64]),
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> CgOutcome {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    let b_norm = par_norm(b);
    if b_norm == 0.0 {
        return CgOutcome {
            iterations: 0,
            converged: true,
        };
    }
    // r = b − A x, z = M⁻¹ r, p = z.
    let mut r = b.to_vec();
    let mut z = r.clone();
    precondition(&mut z);
    let mut p = z.clone();
    let mut rz = par_dot(&r, &z);
    let mut ap = vec![0.0; n];
    for iteration in 1..=max_iterations {
        apply(&p, &mut ap);
        let curvature = par_dot(&p, &ap);
        // Stop on a non-positive (or NaN) curvature or preconditioned residual.
        let positive = |v: f64| v > 0.0;
        if !positive(curvature) || !positive(rz) {
            return CgOutcome {
                iterations: iteration,
                converged: false,
            };
        }
        // α = rᵀz / pᵀAp; x ← x + α p; r ← r − α A p.
        let step = rz / curvature;
        par_update(x, &p, |xi, pi| xi + step * pi);
        par_update(&mut r, &ap, |ri, api| ri - step * api);
        if par_norm(&r) <= tolerance * b_norm {
            return CgOutcome {
                iterations: iteration,
                converged: true,
            };
        }
        z.copy_from_slice(&r);
        precondition(&mut z);
        // β = r₊ᵀz₊ / rᵀz; p ← z + β p.
        let rz_next = par_dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        par_update(&mut p, &z, |pi, zi| zi + beta * pi);
    }
    CgOutcome {
        iterations: max_iterations,
        converged: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::dot;

    /// A = D + u uᵀ + w wᵀ (rank-2 change of a diagonal D), preconditioned by D⁻¹: CG
    /// converges in at most 3 iterations, to the solution of the dense system.
    #[test]
    fn rank_two_change_of_the_preconditioner_converges_in_three_iterations() {
        let n = 40;
        let d: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let u: Vec<f64> = (0..n).map(|i| ((i * 7 % 11) as f64 - 5.0) * 0.3).collect();
        let w: Vec<f64> = (0..n).map(|i| ((i * 3 % 5) as f64 - 2.0) * 0.7).collect();
        let apply = |v: &[f64], out: &mut [f64]| {
            let (uv, wv) = (dot(&u, v), dot(&w, v));
            for i in 0..n {
                out[i] = d[i] * v[i] + u[i] * uv + w[i] * wv;
            }
        };
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin() + 0.5).collect();
        let mut x = vec![f64::NAN; n];
        let outcome = preconditioned_cg(
            apply,
            |z: &mut [f64]| z.iter_mut().zip(&d).for_each(|(zi, di)| *zi /= di),
            &b,
            &mut x,
            1e-12,
            50,
        );
        assert!(outcome.converged, "{outcome:?}");
        assert!(outcome.iterations <= 3, "{outcome:?}");
        let mut ax = vec![0.0; n];
        apply(&x, &mut ax);
        let err: f64 = ax
            .iter()
            .zip(&b)
            .map(|(a, bi)| (a - bi).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(err <= 1e-10 * norm(&b), "residual {err}");
        // Capped before convergence: reported as not converged, after exactly the cap.
        let capped = preconditioned_cg(apply, |_: &mut [f64]| {}, &b, &mut x, 1e-14, 2);
        assert_eq!(
            capped,
            CgOutcome {
                iterations: 2,
                converged: false
            }
        );
    }
}
