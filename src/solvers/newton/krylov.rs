//! newton's Newton systems solved on the substructures (`solver.linear = "krylov"`,
//! docs/method.md, "Newton–Krylov on the substructures"): `H ΔU = −∇Π` by PCG preconditioned
//! with a two-level overlapping Schwarz method whose GenEO coarse space follows the slack
//! cables ([`TwoLevelSchwarz`]), to an Eisenstat–Walker forcing tolerance. The outer Newton
//! iteration, its exact line search, regularisation and stop are newton's, unchanged.

use super::NewtonWork;
use crate::decomposition::schwarz::{SchwarzSettings, TwoLevelSchwarz};
use crate::decomposition::{Partition, WeakInterfaces};
use crate::linalg::{preconditioned_cg, RowChunks};
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

/// The GenEO vectors a subdomain found are kept whatever changed since, while PCG converges no
/// more than this many times slower (iterations per decade of the forcing tolerance) than at
/// the step that found them; a slower step has the next update find them anew on the
/// subdomains where more than [`REFRESH_KEEP`] of the links changed. Always finding them anew
/// past 2 % (2026-12-07, this machine, 2 cores): 64² / 128² / 256² took 106 / 145 / 220 PCG
/// iterations and 2.6 / 13.2 / 63.2 s, keeping them 104 / 143 / 199 and 1.8 / 9.0 / 43.9 s:
/// on these grids the first vectors hold what the slack cables leave loose.
pub(super) const STALE_RATE: f64 = 2.0;

/// [`SchwarzSettings::keep_vectors`] when the vectors are found anew after a slow step.
const REFRESH_KEEP: f64 = 0.02;

/// The Hessian product goes by chunks of links side by side from this many threads on, link by
/// link below. The product is bound by memory: on this 2-core machine the chunked one made a
/// 256² run 7 % slower (38.3 s against 35.9 s, medians of 3 alternated, the same 199 PCG
/// iterations); link by link it is 3.7 % of a 512² run's samples on the driver's thread alone.
/// Not measured on more cores.
const CHUNKED_PRODUCT_THREADS: usize = 4;

/// The substructured solve: the preconditioner and the forcing term's history in this solve.
pub(super) struct KrylovSolve {
    schwarz: TwoLevelSchwarz,
    /// PCG iterations per decade at the step whose update last found GenEO vectors.
    found_rate: Option<f64>,
    /// The next update finds the vectors anew where links changed (a step was slow).
    refresh: bool,
    /// newton's residual and the forcing term at the previous step of this solve.
    last: Option<(f64, f64)>,
    /// PCG iterations when this solve began (the work is counted since set-up).
    at_start: usize,
    /// The Hessian product's links in fixed chunks side by side (`None`: link by link).
    link_chunks: Option<RowChunks>,
}

impl KrylovSolve {
    /// The subdomains of `model`'s structure on a `subdomains` partition, analysed.
    pub(super) fn new(model: &Model, subdomains: [usize; 2]) -> KrylovSolve {
        let structure = &model.structure;
        let partition = Partition::new(structure, subdomains, WeakInterfaces::Macro);
        KrylovSolve {
            schwarz: TwoLevelSchwarz::new(structure, &partition, SchwarzSettings::default()),
            found_rate: None,
            refresh: false,
            last: None,
            at_start: 0,
            link_chunks: (rayon::current_num_threads() >= CHUNKED_PRODUCT_THREADS)
                .then(|| RowChunks::new(&structure.link_dofs, structure.n_free))
                .flatten(),
        }
    }

    /// The found rate set to `rate` (tests: a step made to look slow).
    #[cfg(test)]
    pub(super) fn pretend_found_rate(&mut self, rate: f64) {
        self.found_rate = Some(rate);
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
        // The vectors kept whatever changed, unless the last step was slow (see STALE_RATE).
        let keep = if self.refresh { REFRESH_KEEP } else { 1.0 };
        self.schwarz.set_keep_vectors(keep);
        let found = loop {
            match self.schwarz.update(s, &weights, mu) {
                Ok(refresh) => {
                    work.preconditioner_updates += refresh.subdomains;
                    work.geneo_solves += refresh.eigensolves;
                    break refresh.eigensolves > 0;
                }
                Err(_) if shifts < MAX_SHIFTS => {
                    shifts += 1;
                    mu = super::raised_regularisation(mu, mean_diagonal);
                    // Every subdomain is refactorised with the new μ.
                    self.schwarz.forget_factors();
                }
                Err(_) => return false,
            }
        };
        let eta = self.forcing(residual, tolerance);
        let rhs = step.to_vec();
        let schwarz = &self.schwarz;
        let link_chunks = &mut self.link_chunks;
        let outcome = preconditioned_cg(
            |v, out| match link_chunks {
                Some(chunks) => model.tangent_product_chunked(chunks, taut_links, mu, v, out),
                None => model.tangent_product(taut_links, mu, v, out),
            },
            |z| schwarz.apply(z),
            &rhs,
            step,
            eta,
            MAX_PCG_ITERATIONS,
        );
        work.krylov_iterations += outcome.iterations;
        // Iterations per decade, `its / log₁₀(1/η)`, against the step that found the vectors.
        let rate = outcome.iterations as f64 / (-eta.log10()).max(1.0);
        match (found, self.found_rate) {
            (true, _) | (false, None) => {
                self.found_rate = Some(rate);
                self.refresh = false;
            }
            (false, Some(found_rate)) => self.refresh = rate > STALE_RATE * found_rate,
        }
        if step.iter().all(|x| x.is_finite()) {
            true
        } else {
            step.copy_from_slice(&rhs);
            false
        }
    }
}
