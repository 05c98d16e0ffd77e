//! newton's factor reuse: a Newton system solved by CG, preconditioned by the factor of a
//! nearby Hessian (the last one factored, or K's) corrected for the links whose state changed
//! by a low-rank update ([`LowRankUpdate`]), instead of a new factorisation.

use super::Newton;
use crate::linalg::{norm, preconditioned_cg, LowRankUpdate, SparseCholesky, SparseRow};

/// CG on a new Hessian, preconditioned by the factor of an earlier one corrected for the links
/// whose state changed ([`LowRankUpdate`]), is tried when their taut sets differ by at most
/// this many links (the correction costs one right-hand side per changed link; where it stops
/// paying: docs/method.md, "Tuning log").
const REUSE_MAX_CHANGED_LINKS: usize = 32;
/// CG iterations allowed before giving up and refactorising (the corrected factor is exact but
/// for the regularisations' difference: usually one or two iterations when it works).
const REUSE_MAX_CG_ITERATIONS: usize = 8;
/// Relative residual `‖H ΔU + ∇Π‖ ≤ tol · ‖∇Π‖` of a Newton step solved by CG, an inexact
/// Newton forcing term: `tol = r²` clamped to [`REUSE_CG_TOLERANCE`, `REUSE_CG_LOOSEST`] with r
/// the relative equilibrium residual of the iterate. A step solved to r² keeps Newton's
/// quadratic convergence (the next residual is O(r²) either way), and saves a CG iteration
/// on most steps (with μ = 1e-6 and a fixed 1e-12 before: paper case at α = 1, 4 iterations
/// in its two CG steps instead of 6, the same five Newton steps).
const REUSE_CG_TOLERANCE: f64 = 1e-12;
/// The loosest forcing term (see [`REUSE_CG_TOLERANCE`]): far from the answer (r ≥ 1e-2) a
/// step solved to 1e-4 is as good as an exact one. 1e-4 rather than 1e-8: with the smaller
/// [`super::REGULARISATION`] the first CG iterate often meets it (paper case at α = 1: 2 CG
/// iterations in its two CG steps instead of 4, the same five Newton steps).
const REUSE_CG_LOOSEST: f64 = 1e-4;

/// A factor the CG path can start from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Base {
    /// The taut stiffness's (every link taut).
    Taut,
    /// `chol`'s, the last Hessian factored.
    Last,
}

/// Which Hessian `chol` holds a factor of.
#[derive(Debug, Clone)]
pub(super) struct Factored {
    /// Per link: taut in that Hessian.
    pub(super) taut: Vec<bool>,
}

impl Newton<'_> {
    /// `step ← H⁻¹ step`, `H = Σ_taut k Bᵢᵀ Bᵢ + μ I`, by CG preconditioned by whichever factor
    /// (the last Hessian's, or K's) has the taut set closest to `taut_links`, corrected for the
    /// links that differ, if they are few enough and CG converges within its cap. H is applied
    /// link by link, never assembled (a product costs less than an assembly). `false`: nothing
    /// was solved, `step` is untouched.
    pub(super) fn solve_with_nearby_factor(
        &mut self,
        taut_links: &[bool],
        mu: f64,
        step: &mut [f64],
        residual: f64,
    ) -> bool {
        let (model, s) = (self.model, self.structure);
        let changed = |other: &[bool]| -> usize {
            other.iter().zip(taut_links).filter(|(a, b)| a != b).count()
        };
        let from_taut = taut_links.iter().filter(|&&t| !t).count();
        let from_last = self.factored.as_ref().map(|f| changed(&f.taut));
        let (changed_links, base) = match from_last {
            Some(c) if c <= from_taut => (c, Base::Last),
            _ => (from_taut, Base::Taut),
        };
        if changed_links > REUSE_MAX_CHANGED_LINKS {
            return false;
        }
        let (factor, base_taut): (&SparseCholesky, Option<&[bool]>) = match base {
            Base::Last => (&self.chol, self.factored.as_ref().map(|f| &f.taut[..])),
            Base::Taut => match self.taut.factor() {
                Some(factor) => (factor, None),
                None => return false,
            },
        };
        // H = H_base + Σ ± kᵢ uᵢ uᵢᵀ over the links that changed: + taut now, − slack now.
        let wanted: Vec<(usize, &SparseRow, f64)> = taut_links
            .iter()
            .enumerate()
            .filter(|&(i, &now)| base_taut.is_none_or(|b| b[i]) != now)
            .map(|(i, &now)| {
                let k = s.links[i].stiffness;
                (i, &s.link_dofs[i], if now { k } else { -k })
            })
            .collect();
        if self.correction.0 != base {
            self.correction = (base, LowRankUpdate::none(s.n_free));
        }
        let correction = &mut self.correction.1;
        self.work.correction_columns += correction.update(factor, &wanted);
        if !correction.is_solvable() {
            return false;
        }
        let correction = &self.correction.1;
        let rhs = step.to_vec();
        let mut solution = vec![0.0; rhs.len()];
        let outcome = preconditioned_cg(
            |v, out| model.tangent_product(taut_links, mu, v, out),
            |z| correction.solve_in_place(factor, z),
            &rhs,
            &mut solution,
            (residual * residual).clamp(REUSE_CG_TOLERANCE, REUSE_CG_LOOSEST),
            REUSE_MAX_CG_ITERATIONS,
        );
        self.work.cg_iterations += outcome.iterations;
        if outcome.converged && solution.iter().all(|x| x.is_finite()) && norm(&solution) > 0.0 {
            self.work.reused_steps += 1;
            step.copy_from_slice(&solution);
            true
        } else {
            false
        }
    }
}
