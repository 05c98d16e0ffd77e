//! The stability of an answer: the smallest eigenvalue of its tangent stiffness.

use super::{Equilibrium, TautStiffness};
use crate::linalg::smallest_eigenvalues;
use crate::model::Model;

/// Free dofs up to which [`smallest_tangent_eigenvalue`] converges a block of 4 Ritz values to
/// 1e-10; beyond, one to 1e-4 in at most 10 inverse iterations.
pub const EIGENVALUE_FULL_DOFS: usize = 20_000;

/// Smallest eigenvalue (N/m) of the tangent stiffness at an equilibrium, under the model
/// (docs/method.md §3, §8): `Bᵀ k B` over the members that carry load there (bars,
/// bilateral cables, taut unilateral cables), plus with `prestress` the geometric stiffness of
/// the answer's tensions `K_G(τ)` (slack cables none), or the Hessian of the exact-length energy on the current geometry (`large`).
/// 0 when the taut members form a mechanism; negative at an unstable equilibrium (below
/// `−mean diagonal` it is reported as `−mean diagonal`).
pub fn smallest_tangent_eigenvalue(model: &Model, eq: &Equilibrium, taut: &TautStiffness) -> f64 {
    let pattern = &taut.pattern;
    let mut values = vec![0.0; pattern.nnz()];
    // With `prestress`, the geometric stiffness of the answer's own tensions, K_G(τ): a slack
    // cable carries no force, so no geometric stiffness, and a loaded member's changes with
    // its force (docs/method.md §8). K_G(t0) judged a guyed mast whose leeward guys slackened
    // unstable (−340 N/m) where its one-guy mechanism is neutral (0 N/m with `large`; issue
    // 42, D6).
    model.assemble_answer_tangent(
        &eq.displacements,
        &eq.tensions,
        |i| !eq.slack[i],
        pattern,
        &mut values,
    );
    smallest_assembled_eigenvalue(taut, &values)
}

/// The smallest eigenvalue (N/m) of a tangent assembled on K's pattern (`values`), as
/// [`smallest_tangent_eigenvalue`] reports it: 0 within [`TANGENT_ZERO_RELATIVE`] of the mean
/// diagonal, at least `−mean diagonal`.
pub fn smallest_assembled_eigenvalue(taut: &TautStiffness, values: &[f64]) -> f64 {
    let pattern = &taut.pattern;
    let mut factor = taut.factor.share_symbolic();
    // Up to 20 000 free dofs, a block of 4 to 1e-10; beyond, where a solve costs 0.1–0.3 s,
    // a single vector to 1e-4 in at most 10 solves (the sign and two digits).
    let (block, iterations, tolerance) = if pattern.n <= EIGENVALUE_FULL_DOFS {
        (4, 60, 1e-10)
    } else {
        (1, 10, 1e-4)
    };
    let eig = smallest_eigenvalues(pattern, values, &mut factor, block, iterations, tolerance);
    let scale = pattern.mean_diagonal(values);
    // Below TANGENT_ZERO_RELATIVE of the mean diagonal an eigenvalue is zero: the Ritz values
    // carry round-off of about 1e-10 of the scale, which must not decide stable or unstable.
    let zero = TANGENT_ZERO_RELATIVE * scale;
    match eig.values.first() {
        Some(&v) if v.is_finite() && v.abs() > zero => v.max(-scale),
        Some(&v) if v == f64::NEG_INFINITY => -scale,
        _ => 0.0,
    }
}

/// The smallest tangent eigenvalue is reported as exactly 0 within this fraction of the mean
/// diagonal (a singular tangent, neither stable nor unstable by round-off).
pub const TANGENT_ZERO_RELATIVE: f64 = 1e-8;
