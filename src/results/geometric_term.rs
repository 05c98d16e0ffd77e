//! How far the answer of a model on the initial geometry (`linear`, `prestress`) lies from the
//! large-displacement one: one Newton step of the large model's energy (docs/method.md §8) from
//! that answer, and the change it makes. Near the large answer Newton converges quadratically,
//! so a step of relative size ε changes the answer by ε (1 + O(ε)): the estimate is first-order
//! exact where it says the model is close, and says "far" where it is not.

use super::uniqueness::CHECKED_UP_TO_DOFS;
use crate::model::material::tension;
use crate::model::{CurrentGeometry, Model};
use crate::solvers::{Equilibrium, TautStiffness};

/// A motion below this fraction of the structure's size is round-off, not a deflection.
const ROUND_OFF_MOTION: f64 = 1e-9;

/// The relative change of the answer that the geometry left out makes: with
/// `δ = −H(U)⁻¹ r(U)`, r the large model's unbalance at the answer U and H its tangent there
/// (the exact Hessian of §8's energy; where it is not positive definite, or beyond
/// [`CHECKED_UP_TO_DOFS`] free dofs, K with every cable taut, whose factor is at hand), the
/// larger of `max_node |δ| / max_node |U + δ|` and `max_i |τᵢ(U + δ) − τᵢ| / max_i |τᵢ(U + δ)|`
/// (the members' forces of the large model after the step against the answer's): the change
/// relative to the largest deflection and the largest member force of the large answer. `None` for `large`
/// (nothing is left out), without displacements, and where the step is not finite.
pub fn geometric_term(
    model: &Model,
    eq: &Equilibrium,
    load: &[f64],
    taut: &TautStiffness,
) -> Option<f64> {
    let s = &model.structure;
    let u = &eq.displacements;
    let deflection = super::largest_motion(s, u);
    if model.updates_geometry() || deflection.is_nan() || deflection <= 0.0 {
        return None;
    }
    // r(U) = Σ τ ∇ℓ − F on the current geometry, and H(U).
    let geometry = CurrentGeometry::of(s, u);
    let mut step = vec![0.0; u.len()];
    let (trial, _) = geometry.unbalances(s, load, &mut step);
    let mut hessian_factor = None;
    if s.n_free <= CHECKED_UP_TO_DOFS {
        let mut hessian = vec![0.0; taut.pattern.nnz()];
        geometry.assemble_tangent(s, &trial, &taut.pattern, &mut hessian);
        let mut factor = taut.factor.share_symbolic();
        hessian_factor = factor
            .factorize(&taut.pattern, &hessian)
            .is_ok()
            .then_some(factor);
    }
    // δ = −H⁻¹ r.
    hessian_factor
        .as_ref()
        .unwrap_or(&taut.factor)
        .solve_in_place(&mut step);
    let stepped: Vec<f64> = u.iter().zip(&step).map(|(a, d)| a - d).collect();
    // Both changes relative to the stepped answer, the first-order large one: max_node |δ| /
    // max_node |U + δ| (U with its prescribed displacements), and the forces likewise.
    // Motions below ROUND_OFF_MOTION of the structure's size (an unloaded answer's round-off)
    // are no deflection to be relative to.
    let floor = ROUND_OFF_MOTION * s.size();
    // δ moves free dofs only: a settlement is no part of it.
    let step_motion = s
        .full_change(&step)
        .chunks(3)
        .map(|d| d[0].hypot(d[1]).hypot(d[2]))
        .fold(0.0, f64::max);
    let displacement_change = step_motion / super::largest_motion(s, &stepped).max(floor);
    let after: Vec<f64> = CurrentGeometry::of(s, &stepped)
        .trial_tensions(s)
        .iter()
        .zip(&s.links)
        .map(|(&trial, l)| tension(l, trial))
        .collect();
    let largest_force = after.iter().fold(0.0, |m: f64, t| m.max(t.abs()));
    let force_change = after
        .iter()
        .zip(&eq.tensions)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let term = displacement_change.max(if largest_force > 0.0 {
        force_change / largest_force
    } else {
        0.0
    });
    term.is_finite().then_some(term)
}
