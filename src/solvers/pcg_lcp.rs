//! The paper's reference solver (§2.3, docs/method.md §3): the LCP on the unilateral cables,
//! `τ = Wλ + q ≥ 0, λ ≥ 0, λ ⊥ τ`, with `W = k_c − k_c B_c K⁻¹ B_cᵀ k_c` and
//! `q = k_c B_c K⁻¹ F + t0_c`, solved as `min ½λᵀWλ + qᵀλ, λ ≥ 0` by a projected conjugate
//! gradient (Dostál's MPRGP). W is never formed: `W v` is one solve with the factor of K.
//! The variables are scaled, `x = k^{1/2} λ`, so that the scaled W has spectrum in [0, 1]
//! (a Jacobi preconditioning that also fixes the step length of the expansion steps).
//!
//! Stopping measure: [`Measure::ComplementarityResidual`], `‖min(k λ, τ)‖ / ‖k_c B_c K⁻¹ F‖` —
//! the method's complementarity residual with the slack gap λ expressed as the force k λ so
//! that both arguments are in N, relative to the tensions the load brings into play (the
//! prestress left out, as newton's stop: relative to the prestress, λ = 0 passed at α = 1e-10
//! 46 % off, issue 42 T3); relative to `‖t0_c‖` at zero load.
//!
//! No equilibrium: a descent direction of zero curvature that keeps λ ≥ 0 (`dᵀW̃d = 0`,
//! `d ≥ 0`) is a mechanism left by the cables it opens, along which the energy decreases
//! without bound; the solver stops there with its certificate ([`Solver::runaway`]) rather
//! than divide by `dᵀW̃d`.

use super::{stop_when, Equilibrium, Measure, NoEquilibrium, Progress, Solver, TautStiffness};
use crate::linalg::{dot, norm, SparseCholesky};
use crate::model::material::trial_tension;
use crate::model::Model;
use crate::structure::Structure;

/// Settings, each default written once, at its field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcgLcpSettings {
    /// Relative complementarity residual to reach. Default 1e-10.
    pub tolerance: f64,
    /// Iteration cap. Default 50 000.
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
/// A direction d with `dᵀW̃d` at most this fraction of `dᵀd` has no curvature: W̃'s spectrum is
/// in [0, 1], and round-off leaves about 1e-16 of a null direction.
const NULL_CURVATURE: f64 = 1e-12;

/// The pcg-lcp solver, set up for one structure.
pub struct PcgLcp<'s> {
    model: &'s Model,
    structure: &'s Structure,
    settings: PcgLcpSettings,
    /// Factor of K, shared with the other solvers.
    factor: &'s SparseCholesky,
    /// Indices of the unilateral cables (the LCP's unknowns).
    cables: Vec<usize>,
    /// `k^{1/2}` of each of them.
    sqrt_k: Vec<f64>,
    /// `‖t0_c‖`, the complementarity residual's scale at zero load.
    prestress_norm: f64,
    /// Scratch on the free dofs.
    nodal: Vec<f64>,
}

/// The MPRGP iterate: the scaled slack gaps x = k^{1/2} λ and what goes with them.
pub struct PcgLcpState {
    load: Vec<f64>,
    /// `q̃ = k^{-1/2}(k_c B_c K⁻¹ F + t0_c)`.
    q: Vec<f64>,
    x: Vec<f64>,
    /// Scaled gradient `g = W̃ x + q̃`.
    g: Vec<f64>,
    /// Search direction.
    p: Vec<f64>,
    /// Scratch `W̃ p`.
    wp: Vec<f64>,
    since_refresh: usize,
    /// `‖k_c B_c K⁻¹ F‖` (`‖t0_c‖` at zero load): the scale of the complementarity residual,
    /// the tensions the load brings into play, so that it is homogeneous in α however large
    /// the prestress.
    scale: f64,
    residual: f64,
    iteration: usize,
    /// A descent direction of no curvature that the certificate does not confirm: no further
    /// progress is possible.
    stalled: bool,
    /// The no-equilibrium certificate of a descent direction of no curvature (see the module
    /// text).
    runaway: Option<NoEquilibrium>,
}

impl<'s> PcgLcp<'s> {
    /// Set up on a model whose taut stiffness is already factorized.
    pub fn new(model: &'s Model, taut: &'s TautStiffness, settings: PcgLcpSettings) -> Self {
        let structure = &model.structure;
        let cables: Vec<usize> = (0..structure.links.len())
            .filter(|&i| structure.links[i].unilateral)
            .collect();
        let sqrt_k = cables
            .iter()
            .map(|&i| structure.links[i].stiffness.sqrt())
            .collect();
        let prestress: Vec<f64> = cables
            .iter()
            .map(|&i| structure.links[i].prestress)
            .collect();
        PcgLcp {
            model,
            structure,
            settings,
            factor: &taut.factor,
            cables,
            sqrt_k,
            prestress_norm: norm(&prestress),
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

    /// Scaled gradient `g = W̃ x + q̃`, from scratch.
    fn refresh_gradient(&mut self, state: &mut PcgLcpState) {
        let mut g = std::mem::take(&mut state.g);
        self.apply_w(&state.x, &mut g);
        g.iter_mut().zip(&state.q).for_each(|(gi, qi)| *gi += qi);
        state.g = g;
        state.since_refresh = 0;
    }

    /// `‖min(k λ, τ)‖ / scale`, with `k λ = k^{1/2} x` and `τ = k^{1/2} g` (absolute only
    /// when both prestress and load vanish, where λ = 0 is exact).
    fn residual_of(&self, x: &[f64], g: &[f64], scale: f64) -> f64 {
        // Through `norm`, which scales what would underflow (a load factor of 1e-165).
        let products: Vec<f64> = x
            .iter()
            .zip(g)
            .zip(&self.sqrt_k)
            .map(|((xi, gi), sk)| sk * xi.min(*gi))
            .collect();
        let r = norm(&products);
        if scale > 0.0 {
            r / scale
        } else {
            r
        }
    }

    /// The residual of `state`; when it meets the tolerance, confirmed on an exact gradient
    /// (the updated one drifts by round-off), the search direction restarting if it does not.
    fn measure_state(&mut self, state: &mut PcgLcpState) {
        state.residual = self.residual_of(&state.x, &state.g, state.scale);
        if state.residual <= self.settings.tolerance {
            self.refresh_gradient(state);
            state.residual = self.residual_of(&state.x, &state.g, state.scale);
            if state.residual > self.settings.tolerance {
                state.p = free_part(&state.x, &state.g);
            }
        }
    }

    /// `U = K⁻¹(F − B_cᵀ k_c λ)`, `k_c λ = k^{1/2} x`.
    fn displacements(&self, state: &PcgLcpState) -> Vec<f64> {
        let s = self.structure;
        let mut u = state.load.clone();
        for (j, &i) in self.cables.iter().enumerate() {
            s.link_dofs[i].scatter(-self.sqrt_k[j] * state.x[j], &mut u);
        }
        self.factor.solve_in_place(&mut u);
        u
    }

    /// A descent direction `d ≥ 0` of the scaled slack gaps with no curvature (`W̃d ≈ 0`):
    /// the displacements change by `ΔU = −K⁻¹ B_cᵀ k^{1/2} d` per unit step, every cable d
    /// opens shortens by its gap and the others keep their length; the certificate is tested
    /// along ΔU. `None` when ΔU is no runaway (round-off of a tiny but real curvature).
    fn runaway_along(&mut self, d: &[f64], load: &[f64]) -> Option<NoEquilibrium> {
        let s = self.structure;
        let mut change = vec![0.0; s.n_free];
        for (j, &i) in self.cables.iter().enumerate() {
            s.link_dofs[i].scatter(-self.sqrt_k[j] * d[j], &mut change);
        }
        self.factor.solve_in_place(&mut change);
        super::no_equilibrium_along(self.model, &change, load)
    }

    /// Whether the step along `−direction` (a descent direction, `gᵀdirection > 0`) has no
    /// curvature (`curvature = directionᵀW̃direction`): then, when it never reaches a bound,
    /// the energy is unbounded below along it (a certificate, `state.runaway`) or, where the
    /// certificate does not hold and the curvature is not positive, the solve stalls.
    /// `false`: the step can be taken.
    fn unbounded(&mut self, st: &mut PcgLcpState, direction: &[f64], curvature: f64) -> bool {
        if curvature > NULL_CURVATURE * dot(direction, direction) {
            return false;
        }
        // x moves by −t·direction: it reaches a bound where a component of direction is > 0.
        if direction.iter().all(|&di| di <= 0.0) {
            let opening: Vec<f64> = direction.iter().map(|d| -d).collect();
            st.runaway = self.runaway_along(&opening, &st.load);
            if st.runaway.is_some() {
                return true;
            }
        }
        st.stalled = curvature <= 0.0;
        st.stalled
    }

    /// The first MPRGP state for `load` at the scaled slack gaps `x` (`None`: λ = 0).
    fn state_from(&mut self, load: &[f64], x: Option<Vec<f64>>) -> PcgLcpState {
        let s = self.structure;
        let m = self.cables.len();
        // The split τ = t0 + t assumes B_fᵀ t0 = 0; prescribed displacements break it by
        // B_fᵀ (k e_p), which moves to the load: F ← F − B_fᵀ (k e_p) (docs/method.md §7).
        let load: Vec<f64> = load
            .iter()
            .zip(&s.settlement_force)
            .map(|(f, p)| f - p)
            .collect();
        // U_F = K⁻¹ F; q̃ = k^{-1/2}(k_c B_c U_F + t0_c) = k^{1/2} B_c U_F + k^{-1/2} t0_c.
        let mut u_load = load.clone();
        self.factor.solve_in_place(&mut u_load);
        let q: Vec<f64> = self
            .cables
            .iter()
            .zip(&self.sqrt_k)
            .map(|(&i, &sk)| sk * s.link_dofs[i].elongation(&u_load) + s.links[i].prestress / sk)
            .collect();
        // The residual's scale: the load's tensions k_c B_c K⁻¹ F (homogeneous in α, as
        // newton's load-relative stop), the prestress at zero load.
        let load_tensions: Vec<f64> = self
            .cables
            .iter()
            .zip(&self.sqrt_k)
            .map(|(&i, &sk)| sk * sk * s.link_dofs[i].elongation(&u_load))
            .collect();
        let load_scale = norm(&load_tensions);
        let scale = if load_scale > 0.0 {
            load_scale
        } else {
            self.prestress_norm
        };
        let cold = x.is_none();
        let x = x.unwrap_or_else(|| vec![0.0; m]);
        let g = q.clone();
        let p = free_part(&x, &g);
        let mut state = PcgLcpState {
            load,
            scale,
            q,
            x,
            g,
            p,
            wp: vec![0.0; m],
            since_refresh: 0,
            residual: f64::INFINITY,
            iteration: 0,
            stalled: false,
            runaway: None,
        };
        if !cold {
            // g = W̃ x + q̃, p on its free face.
            self.refresh_gradient(&mut state);
            state.p = free_part(&state.x, &state.g);
        }
        self.measure_state(&mut state);
        state
    }
}

impl Solver for PcgLcp<'_> {
    type State = PcgLcpState;
    const INIT_IS_ITERATE: bool = false;

    fn measure(&self) -> Measure {
        Measure::ComplementarityResidual
    }

    fn model(&self) -> &Model {
        self.model
    }

    fn max_iterations(&self) -> usize {
        self.settings.max_iterations
    }

    /// λ = 0: every cable taut.
    fn init(&mut self, load: &[f64]) -> PcgLcpState {
        self.state_from(load, None)
    }

    /// λ = the previous answer's slack gaps: on each cable it says is slack,
    /// `λ = −(t0 + k B U)/k ≥ 0` at its displacements U (0 elsewhere). A previous answer of
    /// another size, or not finite, is ignored (λ = 0).
    fn warm_init(&mut self, load: &[f64], previous: &Equilibrium) -> PcgLcpState {
        let s = self.structure;
        let usable = previous.displacements.len() == s.n_free
            && previous.slack.len() == s.links.len()
            && previous.displacements.iter().all(|x| x.is_finite());
        if !usable {
            return self.init(load);
        }
        // x = k^{1/2} λ = ⟨−(t0 + k e)⟩₊ / k^{1/2}.
        let x: Vec<f64> = self
            .cables
            .iter()
            .zip(&self.sqrt_k)
            .map(|(&i, &sk)| {
                if previous.slack[i] {
                    let trial = trial_tension(
                        &s.links[i],
                        s.link_dofs[i].elongation(&previous.displacements),
                    );
                    (-trial).max(0.0) / sk
                } else {
                    0.0
                }
            })
            .collect();
        self.state_from(load, Some(x))
    }

    /// One MPRGP step: conjugate gradient on the free face, expansion, or proportioning.
    fn next_iter(&mut self, st: &mut PcgLcpState) {
        st.iteration += 1;
        let phi = free_part(&st.x, &st.g);
        let beta: Vec<f64> =
            st.x.iter()
                .zip(&st.g)
                .map(|(&xi, &gi)| if xi == 0.0 { gi.min(0.0) } else { 0.0 })
                .collect();
        let reduced: f64 =
            st.x.iter()
                .zip(&phi)
                .map(|(&xi, &fi)| {
                    if xi > 0.0 {
                        fi * (xi / EXPANSION_STEP).min(fi)
                    } else {
                        0.0
                    }
                })
                .sum();
        let mut wp = std::mem::take(&mut st.wp);
        if dot(&beta, &beta) <= PROPORTIONING * PROPORTIONING * reduced {
            self.apply_w(&st.p, &mut wp);
            let pwp = dot(&st.p, &wp);
            let p = st.p.clone();
            if self.unbounded(st, &p, pwp) {
                st.wp = wp;
                return;
            }
            let cg_step = dot(&st.g, &st.p) / pwp;
            let feasible_step =
                st.x.iter()
                    .zip(&st.p)
                    .filter(|(_, &pi)| pi > 0.0)
                    .map(|(&xi, &pi)| xi / pi)
                    .fold(f64::INFINITY, f64::min);
            if cg_step <= feasible_step {
                // Conjugate gradient step on the current face.
                axpy(-cg_step, &st.p, &mut st.x);
                axpy(-cg_step, &wp, &mut st.g);
                let phi = free_part(&st.x, &st.g);
                let gamma = dot(&phi, &wp) / pwp;
                st.p.iter_mut()
                    .zip(&phi)
                    .for_each(|(pi, fi)| *pi = fi - gamma * *pi);
            } else {
                // Expansion: to the boundary, then a projected gradient step.
                axpy(-feasible_step, &st.p, &mut st.x);
                axpy(-feasible_step, &wp, &mut st.g);
                let phi = free_part(&st.x, &st.g);
                st.x.iter_mut()
                    .zip(&phi)
                    .for_each(|(xi, fi)| *xi = (*xi - EXPANSION_STEP * fi).max(0.0));
                self.refresh_gradient(st);
                st.p = free_part(&st.x, &st.g);
            }
        } else {
            // Proportioning: release bound variables whose gradient pulls them free (β ≤ 0,
            // x moves by −step β ≥ 0; with βᵀW̃β = 0 it would move without bound).
            self.apply_w(&beta, &mut wp);
            let curvature = dot(&beta, &wp);
            if self.unbounded(st, &beta, curvature) {
                st.wp = wp;
                return;
            }
            let step = dot(&st.g, &beta) / curvature;
            axpy(-step, &beta, &mut st.x);
            axpy(-step, &wp, &mut st.g);
            st.p = free_part(&st.x, &st.g);
        }
        st.wp = wp;
        st.since_refresh += 1;
        if st.since_refresh >= REFRESH_EVERY {
            self.refresh_gradient(st);
            st.p = free_part(&st.x, &st.g);
        }
        self.measure_state(st);
    }

    fn progress(&self, state: &PcgLcpState) -> Progress {
        let stop = stop_when(state.residual <= self.settings.tolerance, state.stalled);
        Progress {
            iteration: state.iteration,
            stopping_value: state.residual,
            // r(U) would cost a solve with K per iteration.
            equilibrium_residual: None,
            rebuilds: 0,
            krylov_iterations: None,
            slack_cables: state.x.iter().filter(|&&xi| xi > 0.0).count(),
            at_roundoff: false,
            stop,
        }
    }

    fn runaway(&self, state: &PcgLcpState) -> Option<NoEquilibrium> {
        state.runaway.clone()
    }

    fn elongations(&self, state: &PcgLcpState) -> Vec<f64> {
        let mut e = vec![0.0; self.structure.links.len()];
        self.structure
            .elongations(&self.displacements(state), &mut e);
        e
    }

    fn iterate(&self, state: &PcgLcpState) -> Equilibrium {
        let u = self.displacements(state);
        let mut tensions = self.model.trial_tensions(&u);
        for (j, &i) in self.cables.iter().enumerate() {
            // τ = t0 + k(e + λ) = 0 up to the tolerance: an open gap carries nothing, nor does
            // a cable at the switch point (λ = 0, τ = t0 + k e ≤ 0).
            if state.x[j] > 0.0 || tensions[i] <= 0.0 {
                tensions[i] = 0.0;
            }
        }
        Equilibrium::classified(self.model, u, tensions)
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
