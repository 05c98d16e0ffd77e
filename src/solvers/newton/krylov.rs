//! newton's Newton systems solved on the substructures (`solver.linear = "krylov"`,
//! docs/method.md, "Newton–Krylov on the substructures"): `H ΔU = −∇Π` by PCG preconditioned
//! with a two-level overlapping Schwarz method whose GenEO coarse space follows the slack
//! cables ([`TwoLevelSchwarz`]), to an Eisenstat–Walker forcing tolerance. The outer Newton
//! iteration, its exact line search, regularisation and stop are newton's, unchanged.

use super::NewtonWork;
use crate::decomposition::schwarz::{SchwarzSettings, TwoLevelSchwarz};
use crate::decomposition::{Partition, WeakInterfaces};
use crate::linalg::preconditioned_cg;
use crate::model::Model;

/// How newton solves its Newton systems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinearSolve {
    /// A sparse Cholesky factor of each Hessian (reused across steps where few links change,
    /// by a Woodbury correction).
    #[default]
    Direct,
    /// PCG with a two-level Schwarz preconditioner on the substructures (a GenEO coarse space),
    /// to a forcing tolerance: no factor of the whole Hessian.
    Krylov,
}

impl LinearSolve {
    /// The name a case file uses.
    pub fn name(self) -> &'static str {
        match self {
            LinearSolve::Direct => "direct",
            LinearSolve::Krylov => "krylov",
        }
    }
}

/// The forcing term's largest value, η_max of Eisenstat and Walker.
const FORCING_MAX: f64 = 0.1;

/// PCG iterations one Newton system may take; past them its iterate, still a descent direction
/// for the step's quadratic, is the step.
const MAX_PCG_ITERATIONS: usize = 1000;

/// The regularisation is raised this many times, ×100 each, when a subdomain's Dirichlet matrix
/// does not factorise (a taut set that is a mechanism on the way), before the step falls back
/// to a direct factor.
const MAX_SHIFTS: usize = 8;

/// The substructured solve: the preconditioner and the forcing term's history in this solve.
pub(super) struct KrylovSolve {
    schwarz: TwoLevelSchwarz,
    /// newton's residual and the forcing term at the previous step of this solve.
    last: Option<(f64, f64)>,
    /// PCG iterations when this solve began (the work is counted since set-up).
    at_start: usize,
}

impl KrylovSolve {
    /// The subdomains of `model`'s structure on a `subdomains` partition, analysed.
    pub(super) fn new(model: &Model, subdomains: [usize; 2]) -> KrylovSolve {
        let structure = &model.structure;
        let partition = Partition::new(structure, subdomains, WeakInterfaces::Macro);
        KrylovSolve {
            schwarz: TwoLevelSchwarz::new(structure, &partition, SchwarzSettings::default()),
            last: None,
            at_start: 0,
        }
    }

    /// A new solve begins (the forcing history is its own).
    pub(super) fn begin(&mut self, work: &NewtonWork) {
        self.last = None;
        self.at_start = work.krylov_iterations;
    }

    /// PCG iterations in this solve so far.
    pub(super) fn iterations(&self, work: &NewtonWork) -> usize {
        work.krylov_iterations - self.at_start
    }

    /// Eisenstat–Walker's choice 2, `η_k = 0.9 (r_k / r_{k−1})²`, safeguarded by `0.9 η_{k−1}²`
    /// when that exceeds 0.1, at most [`FORCING_MAX`], and never tighter than the stop needs:
    /// a step that cuts the unbalance by η leaves `η r`, so `η ≥ tolerance / (2 r)`.
    fn forcing(&mut self, residual: f64, tolerance: f64) -> f64 {
        let eta = match self.last {
            None => FORCING_MAX,
            Some((previous, eta_previous)) => {
                let eta = 0.9 * (residual / previous).powi(2);
                let safeguard = 0.9 * eta_previous * eta_previous;
                if safeguard > 0.1 {
                    eta.max(safeguard)
                } else {
                    eta
                }
            }
        };
        let eta = eta
            .min(FORCING_MAX)
            .max(0.5 * tolerance / residual)
            .max(1e-14);
        self.last = Some((residual, eta));
        eta
    }

    /// `step ← H⁻¹ step` to the forcing tolerance, `H = Σ_taut k Bᵢᵀ Bᵢ (+ K_G) + μ I`, the
    /// preconditioner refreshed on the subdomains whose links changed state; μ raised as the
    /// direct path raises it (`mean_diagonal`: the taut stiffness's); `residual` is the
    /// larger of r(U) and r_F(U) at this step. `false`: no subdomain factor could be made even
    /// with μ raised (the caller solves directly); `step` is then untouched.
    pub(super) fn solve(
        &mut self,
        model: &Model,
        taut_links: &[bool],
        (mut mu, mean_diagonal): (f64, f64),
        (residual, tolerance): (f64, f64),
        step: &mut [f64],
        work: &mut NewtonWork,
    ) -> bool {
        let s = &model.structure;
        let weights: Vec<f64> = s
            .links
            .iter()
            .zip(taut_links)
            .map(|(l, &taut)| if taut { l.stiffness } else { 0.0 })
            .collect();
        let mut shifts = 0;
        loop {
            match self.schwarz.update(s, &weights, mu) {
                Ok(refresh) => {
                    work.preconditioner_updates += refresh.subdomains;
                    break;
                }
                Err(_) if shifts < MAX_SHIFTS => {
                    shifts += 1;
                    mu = super::raised_regularisation(mu, mean_diagonal);
                    // Every subdomain is refactorised with the new μ.
                    self.schwarz.forget_factors();
                }
                Err(_) => return false,
            }
        }
        let eta = self.forcing(residual, tolerance);
        let rhs = step.to_vec();
        let schwarz = &self.schwarz;
        let outcome = preconditioned_cg(
            |v, out| model.tangent_product(taut_links, mu, v, out),
            |z| schwarz.apply(z),
            &rhs,
            step,
            eta,
            MAX_PCG_ITERATIONS,
        );
        work.krylov_iterations += outcome.iterations;
        if step.iter().all(|x| x.is_finite()) {
            true
        } else {
            step.copy_from_slice(&rhs);
            false
        }
    }
}
