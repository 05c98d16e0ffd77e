//! A two-level overlapping Schwarz preconditioner with a GenEO coarse space, for `H x = b` with
//! `H = Σ_i w_i b_i b_iᵀ + μ I` (newton's Hessian on a taut set: docs/method.md, "Newton–Krylov
//! on the substructures"):
//!
//! `M⁻¹ = Σ_j R_jᵀ A_j⁻¹ R_j + Z E⁻¹ Zᵀ`, `A_j = R_j H R_jᵀ`, `E = Zᵀ H Z`,
//!
//! Z the subdomains' GenEO vectors (`A_j^Neu v = λ D_j A_j D_j v`, λ < τ), so that the
//! condition number of `M⁻¹ H` is bounded by a function of τ and of the number of subdomains
//! sharing a dof alone, whatever the number of subdomains and whichever cables are slack (the
//! kernel of a subdomain whose cables went slack is among its vectors). Measured first in
//! docs/performance.md ("Toward the exact answer at any size").
//!
//! | file | what |
//! |---|---|
//! | `overlap` | the overlapping subdomains of a partition, the partition of unity |
//! | `local` | a subdomain's Dirichlet factor and its GenEO vectors |
//! | `coarse` | `E = Zᵀ H Z`, assembled block by block and factorised |

mod coarse;
mod local;
mod overlap;

use super::substructure::SubstructureSolves;
use super::Partition;
use crate::linalg::{gemv, gemv_transposed, NotPositiveDefinite};
use crate::structure::Structure;
use coarse::Coarse;
use local::LocalProblem;
pub use overlap::Overlap;
use rayon::prelude::*;

/// Settings, each default written once, at its field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SchwarzSettings {
    /// Layers of nodes each substructure is grown by. Default 1.
    pub layers: usize,
    /// GenEO's threshold τ: a subdomain keeps the vectors with λ < τ. The condition number is
    /// bounded by about `(1 + k₀)(2 + k₀(2k₀ + 1)/τ)`, k₀ the most subdomains sharing a dof.
    /// Default 0.1 (κ ≈ 9–10 measured with 0.25 on 16 to 256 substructures, taut and
    /// softened; 0.1 keeps about 40 vectors a subdomain against 77, for 1.5–1.9× the PCG
    /// iterations, and a count that doubles from 256 to 1024 substructures: docs/performance.md,
    /// "Toward the exact answer at any size").
    pub tau: f64,
    /// How the GenEO vectors are found. Default a subspace iteration of 64 vectors, 4 sweeps
    /// from a random block and 2 from the last vectors: with τ 0.1, on 128 × 128 modules 3.7×
    /// faster than the exact pairs at τ 0.25, for 145 PCG iterations against 75
    /// (docs/performance.md).
    pub geneo: GeneoSolve,
    /// The most GenEO vectors a subdomain keeps. Default 400.
    pub max_modes: usize,
    /// A subdomain keeps its GenEO vectors while at most this fraction of its links changed
    /// weight (state) since they were found; its Dirichlet factor and E are made anew on the
    /// current H all the same. 0: found anew at every change. Default 0.02: on 128 × 128
    /// modules newton's PCG iterations go from 70 to 75 and its solve from 63 s to 37 s
    /// (docs/performance.md, "Toward the exact answer at any size"). newton's substructured
    /// solve sets 1 (kept) until a step is slow (`src/solvers/newton/krylov.rs`).
    pub keep_vectors: f64,
}

impl Default for SchwarzSettings {
    fn default() -> Self {
        SchwarzSettings {
            layers: 1,
            tau: 0.1,
            geneo: GeneoSolve::Subspace {
                width: 64,
                sweeps: 4,
                warm_sweeps: 2,
            },
            max_modes: 400,
            keep_vectors: 0.02,
        }
    }
}

/// How a subdomain's GenEO vectors are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeneoSolve {
    /// Every pair below τ, each converged (block Lanczos: [`crate::linalg::modes_below`]).
    Exact,
    /// The pairs below τ of a block subspace iteration of `width` vectors
    /// ([`crate::linalg::modes_below_by_subspace`]), approximate: `sweeps` from a random
    /// block, `warm_sweeps` from the subdomain's last vectors.
    Subspace {
        /// Vectors in the block (doubled where all lie below τ).
        width: usize,
        /// Sweeps from a random block.
        sweeps: usize,
        /// Sweeps from the last vectors.
        warm_sweeps: usize,
    },
}

/// Why the preconditioner could not be made: the Dirichlet matrix of a subdomain (or the
/// coarse matrix) is not positive definite, so H is not.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotDefinite {
    /// The subdomain, or `None` for the coarse matrix.
    pub subdomain: Option<usize>,
}

/// What a [`TwoLevelSchwarz::update`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Refresh {
    /// Subdomains refactorised (their links' weights changed).
    pub subdomains: usize,
    /// Of those, the subdomains whose GenEO vectors were found anew.
    pub eigensolves: usize,
    /// The coarse space's size after it.
    pub coarse: usize,
    /// Subdomains whose GenEO vectors stopped at `max_modes` or did not all converge.
    pub incomplete: usize,
    /// E was updated by the links whose weight changed, not made anew (no subdomain found
    /// new vectors).
    pub coarse_updated: bool,
}

/// The preconditioner: the subdomains (made once), their factors and the coarse factor (made
/// anew by [`TwoLevelSchwarz::update`]).
pub struct TwoLevelSchwarz {
    settings: SchwarzSettings,
    overlap: Overlap,
    locals: Vec<LocalProblem>,
    coarse: Coarse,
    /// The coarse factor is that of the subdomains' current vectors.
    coarse_ready: bool,
    n: usize,
}

impl TwoLevelSchwarz {
    /// The subdomains of `partition` on `structure`, grown by `settings.layers`, with their
    /// patterns and symbolic analyses; nothing factorised yet.
    pub fn new(
        structure: &Structure,
        partition: &Partition,
        settings: SchwarzSettings,
    ) -> TwoLevelSchwarz {
        let overlap = Overlap::new(structure, partition, settings.layers);
        let locals = (0..overlap.len())
            .into_par_iter()
            .map(|j| LocalProblem::new(structure, &overlap.dofs[j], &overlap.links[j]))
            .collect();
        TwoLevelSchwarz {
            settings,
            coarse: Coarse::none(overlap.len()),
            coarse_ready: false,
            overlap,
            locals,
            n: structure.n_free,
        }
    }

    /// The preconditioner of `H = Σ w_i b_i b_iᵀ + μ I` (`weights` per link of `structure`):
    /// the subdomains whose links' weights changed since their last factorisation are
    /// refactorised with `mu` and get new GenEO vectors (the others keep theirs, made with an
    /// earlier μ: a preconditioner need not be exact), then the coarse matrix is updated by the
    /// links whose weight changed where no subdomain found new vectors, and made anew
    /// otherwise.
    pub fn update(
        &mut self,
        structure: &Structure,
        weights: &[f64],
        mu: f64,
    ) -> Result<Refresh, NotDefinite> {
        let settings = self.settings;
        let unity = &self.overlap.unity;
        let refreshed: Vec<Result<(bool, bool), usize>> = self
            .locals
            .par_iter_mut()
            .enumerate()
            .map(|(j, local)| {
                if !local.changed(weights) {
                    return Ok((false, false));
                }
                local
                    .refresh(weights, mu, &unity[j], &settings)
                    .map(|found| (true, found))
                    .map_err(|_: NotPositiveDefinite| j)
            })
            .collect();
        let mut refresh = Refresh::default();
        for r in refreshed {
            match r {
                Ok((refactorised, found)) => {
                    refresh.subdomains += usize::from(refactorised);
                    refresh.eigensolves += usize::from(found);
                }
                Err(j) => return Err(NotDefinite { subdomain: Some(j) }),
            }
        }
        refresh.incomplete = self.locals.iter().filter(|l| !l.complete).count();
        if refresh.subdomains == 0 && self.coarse_ready {
            // The same taut set: the coarse factor kept (made with an earlier μ).
            refresh.coarse = self.coarse.len();
            return Ok(refresh);
        }
        // The coarse vectors the same: E updated by the changed links alone.
        let only_weights = refresh.eigensolves == 0 && self.coarse_ready;
        self.coarse_ready = false;
        if only_weights
            && self
                .coarse
                .update_weights(structure, &self.overlap, &self.locals, weights)
        {
            self.coarse_ready = true;
            refresh.coarse = self.coarse.len();
            refresh.coarse_updated = true;
            return Ok(refresh);
        }
        self.coarse = Coarse::new(structure, &self.overlap, &self.locals, (weights, mu))
            .map_err(|_| NotDefinite { subdomain: None })?;
        self.coarse_ready = true;
        refresh.coarse = self.coarse.len();
        Ok(refresh)
    }

    /// [`SchwarzSettings::keep_vectors`] from the next [`TwoLevelSchwarz::update`] on.
    pub fn set_keep_vectors(&mut self, fraction: f64) {
        self.settings.keep_vectors = fraction;
    }

    /// Every subdomain and the coarse matrix made anew at the next [`TwoLevelSchwarz::update`]
    /// (after a change of μ that the kept factors must not miss).
    pub fn forget_factors(&mut self) {
        self.locals.iter_mut().for_each(LocalProblem::forget);
        self.coarse_ready = false;
    }

    /// The number of subdomains.
    pub fn subdomains(&self) -> usize {
        self.locals.len()
    }

    /// The coarse space's size.
    pub fn coarse_size(&self) -> usize {
        self.coarse.len()
    }

    /// `r ← M⁻¹ r = Σ_j R_jᵀ A_j⁻¹ R_j r + Z E⁻¹ Zᵀ r` (additive, both levels).
    pub fn apply(&self, r: &mut [f64]) {
        debug_assert_eq!(r.len(), self.n);
        let overlap = &self.overlap;
        // Per subdomain: A_j⁻¹ R_j r and Z_jᵀ R_j r.
        let parts: Vec<(Vec<f64>, Vec<f64>)> = self
            .locals
            .par_iter()
            .enumerate()
            .map(|(j, local)| {
                let mut x: Vec<f64> = overlap.dofs[j].iter().map(|&d| r[d]).collect();
                let mut c = vec![0.0; local.coarse.ncols()];
                // Z_jᵀ x.
                gemv_transposed(&mut c, &local.coarse, &x, false);
                local.solve(&mut x);
                (x, c)
            })
            .collect();
        // E⁻¹ Zᵀ r.
        let mut c = vec![0.0; self.coarse.len()];
        for (j, (_, cj)) in parts.iter().enumerate() {
            c[self.coarse.offsets[j]..self.coarse.offsets[j + 1]].copy_from_slice(cj);
        }
        self.coarse.solve(&mut c);
        // Per subdomain: A_j⁻¹ R_j r + Z_j (E⁻¹ Zᵀ r)_j.
        let lifted: Vec<Vec<f64>> = parts
            .into_par_iter()
            .zip(&self.locals)
            .enumerate()
            .map(|(j, ((mut x, _), local))| {
                let cj = &c[self.coarse.offsets[j]..self.coarse.offsets[j + 1]];
                // x += Z_j c_j.
                gemv(&mut x, &local.coarse, cj, true);
                x
            })
            .collect();
        // Σ_j R_jᵀ (…)_j, per dof in subdomain order.
        overlap.sum_into(&lifted, r);
    }
}

impl SubstructureSolves for TwoLevelSchwarz {
    fn substructures(&self) -> usize {
        self.locals.len()
    }

    /// `rhs[j] ← A_j⁻¹ rhs[j]`, the subdomains' Dirichlet solves (on Ω_j's dofs).
    fn solve_each(&self, rhs: &mut [Vec<f64>]) {
        rhs.par_iter_mut()
            .zip(&self.locals)
            .for_each(|(b, local)| local.solve(b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::WeakInterfaces;
    use crate::linalg::preconditioned_cg;
    use crate::structure::{GridSpec, LoadPattern};

    /// An 8 × 8 grid on a 2 × 2 partition.
    fn eight_by_eight_on_four() -> (Structure, Partition) {
        let spec = GridSpec {
            modules: [8, 8],
            ..GridSpec::default()
        };
        let s = Structure::grid(&spec, &LoadPattern::default());
        let partition = Partition::new(&s, [2, 2], WeakInterfaces::Macro);
        (s, partition)
    }

    /// A link that changes state refactorises the subdomains holding it; their GenEO vectors
    /// are found anew only past `keep_vectors`; either way PCG solves `H x = b` to 1e-10 in
    /// far fewer iterations than the dofs.
    #[test]
    fn changed_links_refresh_their_subdomains_and_pcg_converges() {
        let (s, partition) = eight_by_eight_on_four();
        let mut weights: Vec<f64> = s.links.iter().map(|l| l.stiffness).collect();
        let mu = 1e-8 * weights.iter().sum::<f64>() / weights.len() as f64;
        let cable = s.links.iter().position(|l| l.unilateral).unwrap();
        for (keep, anew) in [(0.0, true), (0.5, false)] {
            let settings = SchwarzSettings {
                keep_vectors: keep,
                ..SchwarzSettings::default()
            };
            let mut schwarz = TwoLevelSchwarz::new(&s, &partition, settings);
            let first = schwarz.update(&s, &weights, mu).unwrap();
            assert_eq!((first.subdomains, first.eigensolves), (4, 4));
            assert!(schwarz.coarse_size() > 0);
            weights[cable] = 0.0;
            let holding = (0..schwarz.subdomains())
                .filter(|&j| schwarz.overlap.links[j].iter().any(|&(i, _)| i == cable))
                .count();
            let second = schwarz.update(&s, &weights, mu).unwrap();
            assert!(holding >= 1);
            assert_eq!(second.subdomains, holding);
            assert_eq!(second.eigensolves, if anew { holding } else { 0 });
            // PCG on H = Σ w b bᵀ + μ I.
            let apply = |v: &[f64], out: &mut [f64]| {
                out.iter_mut().zip(v).for_each(|(o, x)| *o = mu * x);
                for (row, &w) in s.link_dofs.iter().zip(&weights) {
                    row.scatter(w * row.elongation(v), out);
                }
            };
            let b: Vec<f64> = (0..s.n_free)
                .map(|d| ((d * 31) % 17) as f64 - 8.0)
                .collect();
            let mut x = vec![0.0; s.n_free];
            let outcome = preconditioned_cg(apply, |z| schwarz.apply(z), &b, &mut x, 1e-10, 500);
            assert!(outcome.converged, "{outcome:?}");
            assert!(outcome.iterations < 60, "{outcome:?}");
            weights[cable] = s.links[cable].stiffness;
        }
    }

    /// Where no subdomain finds new vectors, E is updated by the links whose weight changed
    /// (`E += Σ Δw g gᵀ`): entry by entry it equals E made anew from the same vectors and
    /// weights, to 1e-12 of its largest entry, after cables go slack and after they come back.
    #[test]
    fn the_updated_coarse_matrix_equals_one_made_anew() {
        let (s, partition) = eight_by_eight_on_four();
        let settings = SchwarzSettings {
            keep_vectors: 1.0,
            ..SchwarzSettings::default()
        };
        let mut schwarz = TwoLevelSchwarz::new(&s, &partition, settings);
        let mut weights: Vec<f64> = s.links.iter().map(|l| l.stiffness).collect();
        let mu = 1e-8 * weights.iter().sum::<f64>() / weights.len() as f64;
        assert!(!schwarz.update(&s, &weights, mu).unwrap().coarse_updated);
        let cables: Vec<usize> = (0..s.links.len())
            .filter(|&i| s.links[i].unilateral)
            .step_by(7)
            .collect();
        assert!(cables.len() > 10);
        for slack in [true, false] {
            for &i in &cables {
                weights[i] = if slack { 0.0 } else { s.links[i].stiffness };
            }
            let refresh = schwarz.update(&s, &weights, mu).unwrap();
            assert!(refresh.coarse_updated && refresh.eigensolves == 0);
            let anew = Coarse::new(&s, &schwarz.overlap, &schwarz.locals, (&weights, mu)).unwrap();
            let (updated, anew) = (schwarz.coarse.entries(), anew.entries());
            assert_eq!(updated.len(), anew.len());
            let largest = anew.iter().map(|e| e.2.abs()).fold(0.0, f64::max);
            for (u, a) in updated.iter().zip(&anew) {
                assert_eq!((u.0, u.1), (a.0, a.1));
                assert!((u.2 - a.2).abs() <= 1e-12 * largest, "{u:?} against {a:?}");
            }
        }
    }

    /// E factored in the subtrees of its dissection side by side (each subdomain's coarse
    /// unknowns one block; 1 and 2 levels) solves as E factored whole, to 1e-10, on a 16 × 16
    /// grid of 4 × 4 subdomains, taut and with one cable in five slack.
    #[test]
    fn the_coarse_matrix_in_subtrees_solves_as_whole() {
        let spec = GridSpec {
            modules: [16, 16],
            ..GridSpec::default()
        };
        let s = Structure::grid(&spec, &LoadPattern::default());
        let partition = Partition::new(&s, [4, 4], WeakInterfaces::Macro);
        let mut schwarz = TwoLevelSchwarz::new(&s, &partition, SchwarzSettings::default());
        let mut weights: Vec<f64> = s.links.iter().map(|l| l.stiffness).collect();
        let mu = 1e-8 * weights.iter().sum::<f64>() / weights.len() as f64;
        for slack in [false, true] {
            if slack {
                for (i, l) in s.links.iter().enumerate() {
                    if l.unilateral && i % 5 == 0 {
                        weights[i] = 0.0;
                    }
                }
            }
            schwarz.update(&s, &weights, mu).unwrap();
            let n = schwarz.coarse_size();
            assert!(n > 16, "{n} coarse unknowns");
            let b: Vec<f64> = (0..n).map(|k| ((k * 13) % 7) as f64 - 3.0).collect();
            let mut whole = b.clone();
            schwarz.coarse.solve(&mut whole);
            let largest = whole.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for levels in [1, 2] {
                let mut split = b.clone();
                let made = schwarz
                    .coarse
                    .solve_split(&s, &schwarz.overlap, levels, &mut split);
                assert_eq!(made, levels);
                for (x, y) in split.iter().zip(&whole) {
                    assert!(
                        (x - y).abs() <= 1e-10 * largest,
                        "{levels}: {x} against {y}"
                    );
                }
            }
        }
    }

    /// `Σ_j R_jᵀ x_j` gathered per dof in parallel equals the scatter subdomain by subdomain,
    /// bit for bit (the same sums in the same order), on one thread or two.
    #[test]
    fn the_parallel_sum_over_subdomains_is_the_scatter() {
        let (s, partition) = eight_by_eight_on_four();
        let overlap = Overlap::new(&s, &partition, 1);
        let parts: Vec<Vec<f64>> = (0..overlap.len())
            .map(|j| {
                (0..overlap.dofs[j].len())
                    .map(|k| ((k * 7 + j * 3) % 11) as f64 / 3.0 - 1.7)
                    .collect()
            })
            .collect();
        let mut scattered = vec![0.0; s.n_free];
        for (j, x) in parts.iter().enumerate() {
            for (&d, v) in overlap.dofs[j].iter().zip(x) {
                scattered[d] += v;
            }
        }
        assert!(overlap.dofs.iter().map(Vec::len).sum::<usize>() > s.n_free);
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut gathered = vec![f64::NAN; s.n_free];
            pool.install(|| overlap.sum_into(&parts, &mut gathered));
            assert_eq!(gathered, scattered);
        }
    }
}
