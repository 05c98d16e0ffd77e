//! The paper's reference solver (§2.3, SPEC §3): the LCP on the unilateral cables,
//! `τ = Wλ + q ≥ 0, λ ≥ 0, λ ⊥ τ`, with `W = k_c − k_c B_c K⁻¹ B_cᵀ k_c` and
//! `q = k_c B_c K⁻¹ F + t0_c`, solved as `min ½λᵀWλ + qᵀλ, λ ≥ 0` by a projected conjugate
//! gradient (Dostál's MPRGP). W is never formed: `W v` is one solve with the factor of K.
//! The variables are scaled, `x = k^{1/2} λ`, so that the scaled W has spectrum in [0, 1]
//! (a Jacobi preconditioning that also fixes the step length of the expansion steps).
//!
//! Stopping measure (`residual`): `‖min(k λ, τ)‖ / ‖t0_c‖` — SPEC's complementarity residual
//! with the slack gap λ expressed as the force k λ so that both arguments are in N.

use super::{Equilibrium, IterationRecord, Observer, Solution, SolveInfo, Status, TautStiffness};
use crate::linalg::{dot, norm, SparseCholesky};
use crate::structure::Structure;
use std::time::Instant;

/// Settings with their defaults.
#[derive(Debug, Clone, Copy)]
pub struct PcgLcpSettings {
    /// Relative complementarity residual to reach. Default 1e-10.
    pub tolerance: f64,
    /// Default 50 000.
    pub max_iterations: usize,
}

impl Default for PcgLcpSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 50_000,
        }
    }
}

/// Expansion step length ᾱ ∈ (0, 2/‖W̃‖], ‖W̃‖ ≤ 1.
const EXPANSION_STEP: f64 = 1.9;
/// Proportioning constant Γ.
const PROPORTIONING: f64 = 1.0;
/// The gradient is recomputed from scratch this often, to stop round-off drift.
const REFRESH_EVERY: usize = 50;

pub struct PcgLcp<'s> {
    structure: &'s Structure,
    settings: PcgLcpSettings,
    /// Factor of K, shared with the other solvers.
    factor: &'s SparseCholesky,
    /// Indices of the unilateral cables (the LCP's unknowns).
    cables: Vec<usize>,
    /// `k^{1/2}` of each of them.
    sqrt_k: Vec<f64>,
    /// Scratch on the free dofs.
    nodal: Vec<f64>,
}

impl<'s> PcgLcp<'s> {
    pub fn new(
        structure: &'s Structure,
        taut: &'s TautStiffness,
        settings: PcgLcpSettings,
    ) -> Self {
        let cables: Vec<usize> = (0..structure.links.len())
            .filter(|&i| structure.links[i].unilateral)
            .collect();
        let sqrt_k = cables
            .iter()
            .map(|&i| structure.links[i].stiffness.sqrt())
            .collect();
        PcgLcp {
            structure,
            settings,
            factor: &taut.factor,
            cables,
            sqrt_k,
            nodal: vec![0.0; structure.n_free],
        }
    }

    /// `out = W̃ v = v − k^{1/2} B_c K⁻¹ B_cᵀ k^{1/2} v`.
    fn apply_w(&mut self, v: &[f64], out: &mut [f64]) {
        let s = self.structure;
        self.nodal.iter_mut().for_each(|x| *x = 0.0);
        for (j, &i) in self.cables.iter().enumerate() {
            s.link_dofs[i].scatter(self.sqrt_k[j] * v[j], &mut self.nodal);
        }
        self.factor.solve_in_place(&mut self.nodal);
        for (j, &i) in self.cables.iter().enumerate() {
            out[j] = v[j] - self.sqrt_k[j] * s.link_dofs[i].elongation(&self.nodal);
        }
    }

    /// Scaled gradient `g = W̃ x + q̃`.
    fn gradient(&mut self, x: &[f64], q: &[f64], g: &mut [f64]) {
        self.apply_w(x, g);
        g.iter_mut().zip(q).for_each(|(gi, qi)| *gi += qi);
    }

    pub fn solve(&mut self, load: &[f64], observer: &mut dyn Observer) -> Solution {
        let clock = Instant::now();
        let s = self.structure;
        let m = self.cables.len();
        // U_F = K⁻¹ F; q̃ = k^{-1/2}(k_c B_c U_F + t0_c) = k^{1/2} B_c U_F + k^{-1/2} t0_c.
        let mut u_load = load.to_vec();
        self.factor.solve_in_place(&mut u_load);
        let q: Vec<f64> = self
            .cables
            .iter()
            .zip(&self.sqrt_k)
            .map(|(&i, &sk)| sk * s.link_dofs[i].elongation(&u_load) + s.links[i].prestress / sk)
            .collect();
        let prestress_norm = norm(
            &self
                .cables
                .iter()
                .map(|&i| s.links[i].prestress)
                .collect::<Vec<_>>(),
        );
        let residual_of = |x: &[f64], g: &[f64], sqrt_k: &[f64]| -> f64 {
            let r: f64 = x
                .iter()
                .zip(g)
                .zip(sqrt_k)
                .map(|((xi, gi), sk)| (sk * xi.min(*gi)).powi(2))
                .sum::<f64>()
                .sqrt();
            if prestress_norm > 0.0 {
                r / prestress_norm
            } else {
                r
            }
        };

        let mut x = vec![0.0; m];
        let mut g = q.clone();
        let mut p = free_part(&x, &g);
        let mut wp = vec![0.0; m];
        let mut iterations = 0;
        let mut since_refresh = 0;
        let mut residual = residual_of(&x, &g, &self.sqrt_k);
        let mut status = Status::MaxIterations;
        loop {
            if residual <= self.settings.tolerance {
                // Confirm on an exact gradient before stopping.
                self.gradient(&x, &q, &mut g);
                since_refresh = 0;
                residual = residual_of(&x, &g, &self.sqrt_k);
                if residual <= self.settings.tolerance {
                    status = Status::Converged;
                    break;
                }
                p = free_part(&x, &g);
            }
            if iterations >= self.settings.max_iterations {
                break;
            }
            iterations += 1;
            let phi = free_part(&x, &g);
            let beta: Vec<f64> = x
                .iter()
                .zip(&g)
                .map(|(&xi, &gi)| if xi == 0.0 { gi.min(0.0) } else { 0.0 })
                .collect();
            let reduced: f64 = x
                .iter()
                .zip(&phi)
                .map(|(&xi, &fi)| {
                    if xi > 0.0 {
                        fi * (xi / EXPANSION_STEP).min(fi)
                    } else {
                        0.0
                    }
                })
                .sum();
            if dot(&beta, &beta) <= PROPORTIONING * PROPORTIONING * reduced {
                self.apply_w(&p.clone(), &mut wp);
                let pwp = dot(&p, &wp);
                if pwp <= 0.0 {
                    status = Status::Stalled;
                    break;
                }
                let cg_step = dot(&g, &p) / pwp;
                let feasible_step = x
                    .iter()
                    .zip(&p)
                    .filter(|(_, &pi)| pi > 0.0)
                    .map(|(&xi, &pi)| xi / pi)
                    .fold(f64::INFINITY, f64::min);
                if cg_step <= feasible_step {
                    // Conjugate gradient step on the current face.
                    axpy(-cg_step, &p, &mut x);
                    axpy(-cg_step, &wp, &mut g);
                    let phi = free_part(&x, &g);
                    let gamma = dot(&phi, &wp) / pwp;
                    p.iter_mut()
                        .zip(&phi)
                        .for_each(|(pi, fi)| *pi = fi - gamma * *pi);
                } else {
                    // Expansion: to the boundary, then a projected gradient step.
                    axpy(-feasible_step, &p, &mut x);
                    axpy(-feasible_step, &wp, &mut g);
                    let phi = free_part(&x, &g);
                    x.iter_mut()
                        .zip(&phi)
                        .for_each(|(xi, fi)| *xi = (*xi - EXPANSION_STEP * fi).max(0.0));
                    self.gradient(&x, &q, &mut g);
                    since_refresh = 0;
                    p = free_part(&x, &g);
                }
            } else {
                // Proportioning: release bound variables whose gradient pulls them free.
                self.apply_w(&beta, &mut wp);
                let step = dot(&g, &beta) / dot(&beta, &wp);
                axpy(-step, &beta, &mut x);
                axpy(-step, &wp, &mut g);
                p = free_part(&x, &g);
            }
            since_refresh += 1;
            if since_refresh >= REFRESH_EVERY {
                self.gradient(&x, &q, &mut g);
                since_refresh = 0;
                p = free_part(&x, &g);
            }
            residual = residual_of(&x, &g, &self.sqrt_k);
            observer.iteration(&IterationRecord {
                iteration: iterations,
                residual,
                error: None,
                slack_cables: x.iter().filter(|&&xi| xi > 0.0).count(),
                elapsed_seconds: clock.elapsed().as_secs_f64(),
            });
        }

        // U = K⁻¹(F − B_cᵀ k_c λ), k_c λ = k^{1/2} x.
        let mut u = load.to_vec();
        for (j, &i) in self.cables.iter().enumerate() {
            s.link_dofs[i].scatter(-self.sqrt_k[j] * x[j], &mut u);
        }
        self.factor.solve_in_place(&mut u);
        let mut slack = vec![false; s.links.len()];
        let mut tensions: Vec<f64> = s
            .links
            .iter()
            .zip(&s.link_dofs)
            .map(|(l, ld)| l.prestress + l.stiffness * ld.elongation(&u))
            .collect();
        for (j, &i) in self.cables.iter().enumerate() {
            if x[j] > 0.0 {
                // τ = t0 + k(e + λ) = 0 up to the tolerance: a slack cable carries nothing.
                slack[i] = true;
                tensions[i] = 0.0;
            }
        }
        Solution {
            equilibrium: Equilibrium {
                displacements: u,
                tensions,
                slack,
            },
            info: SolveInfo {
                status,
                iterations,
                residual,
                solve_seconds: clock.elapsed().as_secs_f64(),
            },
        }
    }
}

/// Free gradient φ: the gradient on the variables off their bound.
fn free_part(x: &[f64], g: &[f64]) -> Vec<f64> {
    x.iter()
        .zip(g)
        .map(|(&xi, &gi)| if xi > 0.0 { gi } else { 0.0 })
        .collect()
}

fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(yi, xi)| *yi += a * xi);
}
