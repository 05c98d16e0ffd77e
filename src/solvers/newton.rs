//! Exact active-set (semismooth Newton) solver on the energy (SPEC §1, §3), beyond the paper.
//!
//! Minimises `Π(U) = Σ_bars (½ k e² + t0 e) + Σ_cables ½ k ⟨e + t0/k⟩₊² − Fᵀ U`. Each iteration
//! solves `(K_bars + B_Aᵀ k_A B_A + μ I) ΔU = −∇Π` on the taut set A, then takes the exact
//! minimiser of the 1-D piecewise quadratic `Π(U + sΔU)`. The regularisation μ vanishes with
//! the residual; the symbolic factorization is the one of the taut stiffness, reused.
//!
//! Stopping measure (`residual`): `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)` on the free dofs.

use super::{
    Equilibrium, IterationRecord, Observer, SetupError, Solution, SolveInfo, Status, TautStiffness,
};
use crate::linalg::SparseCholesky;
use crate::results::relative_unbalance;
use crate::structure::Structure;
use std::time::Instant;

/// Settings with their defaults.
#[derive(Debug, Clone, Copy)]
pub struct NewtonSettings {
    /// Relative equilibrium residual to reach. Default 1e-10.
    pub tolerance: f64,
    /// Default 100.
    pub max_iterations: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 100,
        }
    }
}

/// Regularisation μ = `REGULARISATION · min(1, residual)² · mean diagonal`: enough to step
/// through a taut set that is a mechanism on the way, and vanishing quadratically so that the
/// step on the final active set is exact to round-off (with a linear decay the paper case
/// needed one more factorization; measured on the paper case at α = 1 and 3, a 32 × 32 grid at
/// α = 0.3 and the 64 × 64 case).
const REGULARISATION: f64 = 1e-6;

pub struct Newton<'s> {
    structure: &'s Structure,
    taut: &'s TautStiffness,
    settings: NewtonSettings,
    chol: SparseCholesky,
    hessian: Vec<f64>,
    mean_stiffness: f64,
}

/// The iterate.
struct State {
    u: Vec<f64>,
    /// `t0 + k e` of every link, before a unilateral cable's clipping at 0.
    trial: Vec<f64>,
    /// Total tensions τ (SPEC §1): the trial tension, clipped at 0 for unilateral cables.
    tensions: Vec<f64>,
    gradient: Vec<f64>,
    residual: f64,
}

impl<'s> Newton<'s> {
    /// Set up on a structure whose taut stiffness is already known to be regular.
    pub fn new(
        structure: &'s Structure,
        taut: &'s TautStiffness,
        settings: NewtonSettings,
    ) -> Result<Self, SetupError> {
        Ok(Newton {
            structure,
            taut,
            settings,
            chol: taut.factor.share_symbolic(),
            hessian: vec![0.0; taut.values.len()],
            mean_stiffness: taut.pattern.mean_diagonal(&taut.values),
        })
    }

    fn evaluate(&self, load: &[f64], state: &mut State) {
        let s = self.structure;
        for (i, (l, ld)) in s.links.iter().zip(&s.link_dofs).enumerate() {
            let trial = l.prestress + l.stiffness * ld.elongation(&state.u);
            state.trial[i] = trial;
            state.tensions[i] = if l.unilateral { trial.max(0.0) } else { trial };
        }
        state.residual = relative_unbalance(s, &state.tensions, load, &mut state.gradient);
    }

    /// `step ← H⁻¹ step` with H the Hessian on the taut set of `state` (SPEC §3) plus the
    /// vanishing regularisation. With every link taut H is K, whose factor is reused.
    fn newton_step(&mut self, state: &State, step: &mut [f64]) {
        let s = self.structure;
        let pattern = &self.taut.pattern;
        let taut_links: Vec<bool> = s
            .links
            .iter()
            .zip(&state.trial)
            .map(|(l, &trial)| !l.unilateral || trial >= 0.0)
            .collect();
        if taut_links.iter().all(|&t| t) {
            self.taut.factor.solve_in_place(step);
            return;
        }
        pattern.assemble(
            &s.link_dofs,
            |i| {
                if taut_links[i] {
                    s.links[i].stiffness
                } else {
                    0.0
                }
            },
            &mut self.hessian,
        );
        let mut mu = REGULARISATION * state.residual.min(1.0).powi(2) * self.mean_stiffness;
        let mut added = 0.0;
        loop {
            for &d in &pattern.diag_slot {
                self.hessian[d] += mu - added;
            }
            added = mu;
            if self.chol.factorize(pattern, &self.hessian).is_ok() {
                break;
            }
            mu = (mu * 100.0).max(1e-12 * self.mean_stiffness);
        }
        self.chol.solve_in_place(step);
    }

    /// Solve for the load `load` (on the free dofs) from `start` (zero if `None`).
    pub fn solve(
        &mut self,
        load: &[f64],
        start: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let clock = Instant::now();
        let s = self.structure;
        let n = s.n_free;
        let mut state = State {
            u: start.map(|u| u.to_vec()).unwrap_or_else(|| vec![0.0; n]),
            trial: vec![0.0; s.links.len()],
            tensions: vec![0.0; s.links.len()],
            gradient: vec![0.0; n],
            residual: f64::INFINITY,
        };
        self.evaluate(load, &mut state);
        let mut status = Status::MaxIterations;
        let mut iterations = 0;
        let mut step = vec![0.0; n];
        let mut step_elongation = vec![0.0; s.links.len()];
        while iterations < self.settings.max_iterations {
            if state.residual <= self.settings.tolerance {
                status = Status::Converged;
                break;
            }
            iterations += 1;
            step.iter_mut()
                .zip(&state.gradient)
                .for_each(|(d, g)| *d = -g);
            self.newton_step(&state, &mut step);
            s.elongations(&step, &mut step_elongation);
            let Some(length) = exact_line_search(s, load, &state, &step, &step_elongation) else {
                status = Status::Stalled;
                break;
            };
            state
                .u
                .iter_mut()
                .zip(&step)
                .for_each(|(u, d)| *u += length * d);
            self.evaluate(load, &mut state);
            observer.iteration(&IterationRecord {
                iteration: iterations,
                residual: state.residual,
                error: None,
                slack_cables: slack_flags(s, &state.tensions)
                    .iter()
                    .filter(|&&x| x)
                    .count(),
                elapsed_seconds: clock.elapsed().as_secs_f64(),
            });
        }
        if status == Status::MaxIterations && state.residual <= self.settings.tolerance {
            status = Status::Converged;
        }
        let slack = slack_flags(s, &state.tensions);
        Solution {
            equilibrium: Equilibrium {
                displacements: state.u,
                tensions: state.tensions,
                slack,
            },
            info: SolveInfo {
                status,
                iterations,
                residual: state.residual,
                solve_seconds: clock.elapsed().as_secs_f64(),
            },
        }
    }
}

/// Slack cables of the energy's law: unilateral cables whose tension was clipped to 0.
fn slack_flags(s: &Structure, tensions: &[f64]) -> Vec<bool> {
    s.links
        .iter()
        .zip(tensions)
        .map(|(l, &t)| l.unilateral && t == 0.0)
        .collect()
}

/// Exact minimiser `s > 0` of `φ(s) = Π(U + s ΔU)`: φ' is piecewise linear and non-decreasing
/// in s, with a breakpoint wherever a unilateral cable changes state; walk the breakpoints in
/// order. `None` when ΔU is not a descent direction (φ'(0) ≥ 0).
fn exact_line_search(
    s: &Structure,
    load: &[f64],
    state: &State,
    step: &[f64],
    step_elongation: &[f64],
) -> Option<f64> {
    let mut slope_value = -load.iter().zip(step).map(|(f, d)| f * d).sum::<f64>();
    let mut curvature = 0.0;
    let mut events: Vec<(f64, f64)> = Vec::new();
    for ((l, &a), &de) in s.links.iter().zip(&state.trial).zip(step_elongation) {
        let b = l.stiffness * de;
        let c = l.stiffness * de * de;
        if !l.unilateral {
            slope_value += a * de;
            curvature += c;
            continue;
        }
        let active = a > 0.0 || (a == 0.0 && b > 0.0);
        if active {
            slope_value += a * de;
            curvature += c;
            if b < 0.0 {
                events.push((-a / b, -c));
            }
        } else if b > 0.0 {
            events.push((-a / b, c));
        }
    }
    if slope_value >= 0.0 {
        return None;
    }
    events.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut at = 0.0;
    for (position, change) in events {
        let reached = slope_value + curvature * (position - at);
        if curvature > 0.0 && reached >= 0.0 {
            return Some(at - slope_value / curvature);
        }
        slope_value = reached;
        at = position;
        curvature += change;
    }
    if curvature > 0.0 {
        Some(at - slope_value / curvature)
    } else {
        None
    }
}
