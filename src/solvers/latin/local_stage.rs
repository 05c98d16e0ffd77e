//! Local stage (SPEC §4): given s, find ŝ on the constitutive set Γ along the search
//! direction, independently per link and per interface.

use super::SideState;
use crate::linalg::{gemv, gemv_transposed};
use crate::structure::Link;
use nalgebra::DMatrix;

/// `(ê, t̂, slack)` of one link from its `(e, t)` (additional tension t), search direction l.
pub fn link_local_stage(link: &Link, l: f64, e: f64, t: f64) -> (f64, f64, bool) {
    let k = link.stiffness;
    if !link.unilateral {
        // ê = (l e + t)/(k + l), t̂ = k ê.
        let e_hat = (l * e + t) / (k + l);
        return (e_hat, k * e_hat, false);
    }
    // λ̃ = −(τ/l + e + t0/k), τ = t + t0; slack if λ̃ ≥ 0, else τ̂ = −λ̃ / (1/k + 1/l).
    let t0 = link.prestress;
    let tau = t + t0;
    let lambda = -(tau / l + e + t0 / k);
    let (tau_hat, slack) = if lambda >= 0.0 {
        (0.0, true)
    } else {
        (-lambda / (1.0 / k + 1.0 / l), false)
    };
    let t_hat = tau_hat - t0;
    let e_hat = e - (t_hat - t) / l;
    (e_hat, t_hat, slack)
}

/// The interface's two sides: micro parts by the explicit formulas, macro parts pass through.
pub(super) fn interface_local_stage(
    basis: &DMatrix<f64>,
    dm: f64,
    a: &mut SideState,
    b: &mut SideState,
) {
    // R Rᵀ v, the macro part of an interface field.
    let mut coefficients = vec![0.0; basis.ncols()];
    let mut project = |v: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; v.len()];
        gemv_transposed(&mut coefficients, basis, v, false);
        gemv(&mut out, basis, &coefficients, false);
        out
    };
    let (ua_macro, fa_macro) = (project(&a.u), project(&a.f));
    let (ub_macro, fb_macro) = (project(&b.u), project(&b.f));
    for r in 0..a.u.len() {
        let (ua, fa) = (a.u[r] - ua_macro[r], a.f[r] - fa_macro[r]);
        let (ub, fb) = (b.u[r] - ub_macro[r], b.f[r] - fb_macro[r]);
        // Û^m = ½[(U^m_a + U^m_b) − (F^m_a + F^m_b)/d_m] on both sides;
        // F̂^m_a = ½[(F^m_a − F^m_b) − d_m(U^m_a − U^m_b)] = −F̂^m_b.
        let u_hat = 0.5 * ((ua + ub) - (fa + fb) / dm);
        let f_hat_a = 0.5 * ((fa - fb) - dm * (ua - ub));
        a.u_hat[r] = ua_macro[r] + u_hat;
        b.u_hat[r] = ub_macro[r] + u_hat;
        a.f_hat[r] = fa_macro[r] + f_hat_a;
        b.f_hat[r] = fb_macro[r] - f_hat_a;
        a.hat_load[r] = f_hat_a + dm * u_hat;
        b.hat_load[r] = -f_hat_a + dm * u_hat;
    }
}
