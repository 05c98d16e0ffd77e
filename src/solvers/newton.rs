//! Exact active-set (semismooth Newton) solver on the energy (SPEC §1, §3), beyond the paper.
//!
//! Minimises `Π(U) = Σ_bars (½ k e² + t0 e) + Σ_cables ½ k ⟨e + t0/k⟩₊² − Fᵀ U`. Each iteration
//! solves `(K_bars + B_Aᵀ k_A B_A + μ I) ΔU = −∇Π` on the taut set A, then takes the exact
//! minimiser of the 1-D piecewise quadratic `Π(U + sΔU)`. The regularisation μ vanishes with
//! the residual; the symbolic factorization is the one of the taut stiffness, reused.
//!
//! Stopping measure (`residual`): `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)` on the free dofs.

use super::{
    energy_tensions, Equilibrium, IterationRecord, Observer, SetupError, Solution, SolveInfo,
    Status, TautStiffness,
};
use crate::linalg::{norm, SparseCholesky};
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

/// Regularisation μ = `REGULARISATION · min(1, residual) · mean diagonal`: negligible against
/// any physical stiffness near the solution, enough to step through a taut set that is a
/// mechanism on the way.
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
        energy_tensions(s, &state.u, &mut state.tensions);
        s.nodal_forces(&state.tensions, &mut state.gradient);
        let mut magnitude = vec![0.0; s.n_free];
        for (t, ld) in state.tensions.iter().zip(&s.link_dofs) {
            for (d, c) in ld.iter() {
                magnitude[d] += (c * t).abs();
            }
        }
        state
            .gradient
            .iter_mut()
            .zip(load)
            .for_each(|(g, f)| *g -= f);
        let scale = norm(load) + norm(&magnitude);
        let g = norm(&state.gradient);
        state.residual = if scale > 0.0 { g / scale } else { g };
    }

    /// `step ← H⁻¹ step` with H the Hessian on the taut set of `state` (SPEC §3) plus the
    /// vanishing regularisation. With every link taut H is K, whose factor is reused.
    fn newton_step(&mut self, state: &State, step: &mut [f64]) {
        let s = self.structure;
        let pattern = &self.taut.pattern;
        let taut_links: Vec<bool> = s
            .links
            .iter()
            .zip(&s.link_dofs)
            .map(|(l, ld)| {
                !l.unilateral || l.prestress + l.stiffness * ld.elongation(&state.u) >= 0.0
            })
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
        let mut mu = REGULARISATION * state.residual.min(1.0) * self.mean_stiffness;
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
    for ((l, ld), &de) in s.links.iter().zip(&s.link_dofs).zip(step_elongation) {
        let a = l.prestress + l.stiffness * ld.elongation(&state.u);
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
