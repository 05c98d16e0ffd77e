//! Status updates as inexact Newton steps (docs/method.md §9): the slack status is frozen
//! during an inner LATIN run on the law linearised at it; once the residual under that law is
//! below ρ times the exact r(U) at the step's start (a Newton forcing term), a line search on
//! the exact energy between the step's start and end blends the two states, the status of the
//! blend (`t0 + k e > 0`) is taken by the law, and the operators are rebuilt only when enough
//! cables' search directions disagree with it. A semismooth Newton method whose linear solves
//! are inexact LATIN runs.
//!
//! On several processes each classifies the links of its own substructures, and the sums the
//! step needs (the line search's parts, the step's norms, the RMS trial tension) are made per
//! substructure and added in the substructures' order: the same numbers on any number of
//! processes.

use super::{Latin, LatinState, SubState};
use crate::linalg::dot;
use crate::model::material;
use crate::solvers::newton::{exact_line_search, EnergyAlongStep};
use rayon::prelude::*;

/// An inner run that has not reached its forcing tolerance after this many iterations takes
/// its step anyway (the linearised problem may have no equilibrium, e.g. a loaded node held
/// by cables slack in the status alone).
const INNER_MAX_ITERATIONS: usize = 60;

/// The state at the start of a status step.
#[derive(Debug, Clone)]
pub(crate) struct StepStart {
    /// s and ŝ per substructure.
    subs: Vec<SubState>,
    /// The linear stage's input that gave s.
    input: Vec<f64>,
    /// U of the linear stage.
    displacements: Vec<f64>,
    /// The exact r(U) there.
    residual: f64,
    /// The iteration it was taken at.
    iteration: usize,
}

/// The operators are rebuilt for a new status only when the search directions of more than
/// this fraction of the cables disagree with it (a taut cable at 0.01 k, a slack one at k):
/// the law follows every new status at no cost, l is only a search direction. But a taut
/// cable left at 0.01 k contracts by about 0.98 an iteration: 5e-4 (98 cables of 196 608 on a
/// 128 × 128 grid) left the tail of a run slower than the structure without its slack cables.
/// 2e-5 (4 cables there, 63 on 512 × 512) took 128 × 128 / 256 × 256 modules from 77 / 117 to
/// 68 / 100 iterations with 5 / 7 rebuilds (docs/method.md §9).
const REBUILD_FRACTION: f64 = 2e-5;

/// A cable keeps its status while its trial tension is within this fraction of the r(U)
/// tolerance times the RMS trial tension of the cables: its force is then below what r(U)
/// can see.
const STATUS_BAND: f64 = 0.1;

/// Sums over the free dofs a status step needs.
struct StepSums {
    /// ‖ΔU‖².
    step_squared: f64,
    /// ‖U0‖² at the step's start.
    start_squared: f64,
    /// Fᵀ ΔU.
    load_work: f64,
}

/// What a status step changed.
pub(super) struct StatusStep {
    /// Whether the law linearised at the status changed.
    pub law_changed: bool,
    /// The cables to make slack in the search directions, when the operators are to be rebuilt
    /// for the new status.
    pub rebuild: Option<Vec<bool>>,
}

impl Latin<'_> {
    /// Snapshot of `state` as the start of a status step.
    pub(super) fn step_start(&self, state: &LatinState) -> StepStart {
        StepStart {
            subs: state.subs.clone(),
            input: state.acceleration.input.clone(),
            displacements: self.displacements(&state.subs),
            residual: state.residual,
            iteration: state.iteration,
        }
    }

    /// Whether the inner run has done its work: the linearised residual is below
    /// `forcing × r(U)` at the step's start (or the run reached [`INNER_MAX_ITERATIONS`]).
    pub(super) fn inner_run_done(&self, state: &LatinState) -> bool {
        let Some(start) = &state.steps.start else {
            return false;
        };
        state.steps.frozen_residual <= self.settings.forcing * start.residual
            || state.iteration - start.iteration >= INNER_MAX_ITERATIONS
    }

    /// The end of an inner run: `θ` from the line search on the exact energy between the
    /// step's start and `state`, `state ← start + θ (state − start)`, and the blend's status
    /// (`state.steps.law_slack`); the search directions to rebuild the operators for when
    /// enough cables' directions disagree with it. The caller rebuilds them
    /// ([`Latin::set_search`]), then finishes the step ([`Latin::finish_status_step`]).
    pub(super) fn status_step(&self, state: &mut LatinState) -> StatusStep {
        let start = state.steps.start.take().expect("a status step has a start");
        let end = self.displacements(&state.subs);
        // An inner run on a law whose status leaves a mechanism runs away along it, driven by
        // the load or by the prestress the slack cables released: the step or its opposite
        // is then a no-equilibrium certificate of the exact problem (docs/method.md §8; any
        // direction that passes the test proves the energy unbounded below, however found).
        let step: Vec<f64> = end
            .iter()
            .zip(&start.displacements)
            .map(|(b, a)| b - a)
            .collect();
        let sums = self.step_sums(&step, &start.displacements, &state.load);
        // A runaway outgrows the answer it started from: a step smaller than that is the
        // iteration's own correction, whose size says nothing of the energy far along it (the
        // certificate's energy test compares the stretch, quadratic in the step, with the
        // load's work, linear in it: any small enough step passes it).
        let runs_away = sums.step_squared >= sums.start_squared;
        state.steps.runaway = runs_away
            .then(|| {
                let step = self.whole_step(step.clone());
                self.certificate_along(&step, &state.load).or_else(|| {
                    let opposite: Vec<f64> = step.iter().map(|x| -x).collect();
                    self.certificate_along(&opposite, &state.load)
                })
            })
            .flatten();
        // Near the answer (r(U) within 100 times its tolerance) the full step when it lowered
        // r(U): there the energy along it is flat to round-off and its minimiser is noise
        // (seen: θ ≈ 0.3–0.7 at r(U) ≈ 1e-8 blending the inner run's work away). Farther, the
        // line search (taking the full step whenever r(U) fell cost 13 more iterations on
        // 1024 substructures).
        let near = state.residual <= 100.0 * self.settings.residual_tolerance();
        let theta = if near && state.residual < start.residual {
            1.0
        } else if self.model.prestress_stiffness().is_some() {
            self.line_search(&start.displacements, &step, &state.load)
        } else {
            self.line_search_by_substructure(&start.displacements, &step, sums.load_work)
        };
        if theta < 1.0 {
            for (st, st0) in state.subs.iter_mut().zip(&start.subs) {
                st.blend_from(st0, theta);
            }
            blend(&mut state.acceleration.input, &start.input, theta);
        }
        // The blend's status: slack where τ = t0 + k e ≤ 0, a cable keeping its status while
        // |τ| is within a band far below what r(U) is stopped on (a cable at zero tension in
        // the answer would otherwise be free to flip at every step). Each process classifies
        // the links of the substructures it holds (all of them when every process holds the
        // whole state, whose r(U) reads every link's status).
        let links = &self.structure.links;
        let rms = self.trial_tension_rms(&state.subs);
        let band = STATUS_BAND * self.settings.residual_tolerance() * rms;
        let cables = self.world.cables;
        let whole = self.reads_whole_state();
        let classified = match whole {
            true => 0..self.operators.substructures.len(),
            false => self.ranks.held(),
        };
        let mut slack = state.steps.law_slack.clone();
        let (mut law_changed, mut disagree) = (false, 0usize);
        for (sub, st) in self.operators.substructures[classified.clone()]
            .iter()
            .zip(&state.subs[classified])
        {
            for (&i, &e) in sub.links.iter().zip(&st.e) {
                let (l, was) = (&links[i], state.steps.law_slack[i]);
                let tau = material::trial_tension(l, e);
                slack[i] = l.unilateral && if was { tau <= band } else { tau < -band };
                law_changed |= slack[i] != was;
                disagree += usize::from(slack[i] != self.search.slack[i]);
            }
        }
        if !whole {
            law_changed = !self.ranks.all(!law_changed);
            disagree = self.ranks.gather(&[disagree as f64]).iter().sum::<f64>() as usize;
        }
        let rebuild = (disagree as f64 > REBUILD_FRACTION * cables as f64).then(|| slack.clone());
        state.steps.law_slack = slack;
        StatusStep {
            law_changed,
            rebuild,
        }
    }

    /// After a status step and the rebuild it asked for (`rebuilt`): ŝ of the blend on the law
    /// linearised at its status; whether the iteration's map changed.
    pub(super) fn finish_status_step(
        &self,
        state: &mut LatinState,
        step: &StatusStep,
        rebuilt: bool,
    ) -> bool {
        self.local_stage(&mut state.subs, self.local_law(&state.steps.law_slack));
        rebuilt || step.law_changed
    }

    /// ‖ΔU‖², ‖U0‖² and Fᵀ ΔU, each dof counted by the substructure that owns it, summed per
    /// held substructure and then over the substructures in their order (on every rank).
    fn step_sums(&self, step: &[f64], start: &[f64], load: &[f64]) -> StepSums {
        let own = self.ranks.dof_ownership();
        let held = self.ranks.held();
        let parts: Vec<f64> = self.operators.substructures[held.clone()]
            .iter()
            .zip(held)
            .flat_map(|(sub, e)| {
                let mut sums = [0.0; 3];
                for &d in sub.dof_global.iter().filter(|&&d| own.owns(e, d)) {
                    sums[0] += step[d] * step[d];
                    sums[1] += start[d] * start[d];
                    sums[2] += load[d] * step[d];
                }
                sums
            })
            .collect();
        let all = self.ranks.gather(&parts);
        let total = all
            .chunks_exact(3)
            .fold([0.0; 3], |t, p| [t[0] + p[0], t[1] + p[1], t[2] + p[2]]);
        StepSums {
            step_squared: total[0],
            start_squared: total[1],
            load_work: total[2],
        }
    }

    /// `step` on every free dof (on several ranks each holds it at its substructures' dofs
    /// only): each dof's value from the rank of the substructure that owns it.
    fn whole_step(&self, mut step: Vec<f64>) -> Vec<f64> {
        if self.ranks.size() == 1 {
            return step;
        }
        let own = self.ranks.dof_ownership();
        let owned = |e: usize| {
            let sub = &self.operators.substructures[e];
            sub.dof_global
                .iter()
                .copied()
                .filter(move |&d| own.owns(e, d))
        };
        let mine: Vec<f64> = self
            .ranks
            .held()
            .flat_map(|e| owned(e).map(|d| step[d]))
            .collect();
        let mut all = self.ranks.gather(&mine).into_iter();
        for e in 0..self.operators.substructures.len() {
            for d in owned(e) {
                step[d] = all.next().unwrap_or(0.0);
            }
        }
        step
    }

    /// The RMS trial tension `t0 + k e` of the cables (the scale of the status bands), the
    /// squares summed per held substructure and then in the substructures' order.
    fn trial_tension_rms(&self, subs: &[SubState]) -> f64 {
        let links = &self.structure.links;
        let held = self.ranks.held();
        let parts: Vec<f64> = self.operators.substructures[held.clone()]
            .iter()
            .zip(&subs[held])
            .map(|(sub, st)| {
                let cables = sub
                    .links
                    .iter()
                    .zip(&st.e)
                    .filter(|(&i, _)| links[i].unilateral);
                cables
                    .map(|(&i, &e)| material::trial_tension(&links[i], e).powi(2))
                    .sum::<f64>()
            })
            .collect();
        let sum: f64 = self.ranks.gather(&parts).iter().sum();
        let cables = self.world.cables;
        (sum / cables.max(1) as f64).sqrt()
    }

    /// θ ∈ (0, 1] as [`Latin::line_search`] finds it, from each held substructure's links
    /// (trial tensions at U0 and elongations along ΔU through its dof map) and their parts
    /// added in the substructures' order, on any number of processes alike. For models
    /// without the prestress's geometric stiffness.
    fn line_search_by_substructure(&self, u0: &[f64], step: &[f64], load_work: f64) -> f64 {
        let s = self.structure;
        let held = self.ranks.held();
        let parts: Vec<EnergyAlongStep> = self.operators.substructures[held]
            .par_iter()
            .with_min_len(self.ranks.chunk())
            .map(|sub| {
                let at = |v: &[f64], row: &crate::structure::LinkDofs| -> f64 {
                    row.iter().map(|(d, c)| c * v[sub.dof_global[d]]).sum()
                };
                EnergyAlongStep::of_links(sub.links.iter().zip(&sub.link_dofs).map(|(&i, row)| {
                    let link = &s.links[i];
                    (
                        link,
                        material::trial_tension(link, at(u0, row)),
                        at(step, row),
                    )
                }))
            })
            .collect();
        let mut total = EnergyAlongStep::default();
        for part in self.gather_parts(parts) {
            total.add(&part);
        }
        total
            .minimiser(load_work)
            .map_or(1.0, |theta| theta.min(1.0))
    }

    /// Every substructure's part, in order, from the held ones' on each rank.
    fn gather_parts(&self, held: Vec<EnergyAlongStep>) -> Vec<EnergyAlongStep> {
        if self.ranks.size() == 1 {
            return held;
        }
        let mut mine = Vec::new();
        for part in &held {
            mine.extend([part.slope, part.curvature, part.breakpoints.len() as f64]);
            mine.extend(part.breakpoints.iter().flat_map(|&(p, c)| [p, c]));
        }
        let all = self.ranks.gather(&mine);
        let mut rest = all.as_slice();
        let mut parts = Vec::with_capacity(self.operators.substructures.len());
        while let [slope, curvature, n, tail @ ..] = rest {
            let n = *n as usize;
            let breakpoints = tail[..2 * n]
                .chunks_exact(2)
                .map(|p| (p[0], p[1]))
                .collect();
            parts.push(EnergyAlongStep {
                slope: *slope,
                curvature: *curvature,
                breakpoints,
            });
            rest = &tail[2 * n..];
        }
        parts
    }

    /// θ ∈ (0, 1]: the minimiser of the exact energy `Π(U0 + θ ΔU)` (docs/method.md §3,
    /// newton's exact line search), 1 when it lies beyond or the step is not a descent (a
    /// step along which the energy is unbounded below has been caught as no equilibrium).
    /// With the prestress's geometric stiffness, whose term is one pass over the whole
    /// structure (such a solve holds the whole state on every process).
    fn line_search(&self, u0: &[f64], step: &[f64], load: &[f64]) -> f64 {
        let s = self.structure;
        let trial = self.model.trial_tensions(u0);
        let step_elongation: Vec<f64> = s.link_dofs.iter().map(|r| r.elongation(step)).collect();
        // (ΔUᵀ K_G U0, ΔUᵀ K_G ΔU) with the prestress's geometric stiffness.
        let geometric = self.model.prestress_energy_along(u0, step);
        exact_line_search(
            &s.links,
            &trial,
            &step_elongation,
            dot(load, step),
            geometric,
        )
        .map_or(1.0, |theta| theta.min(1.0))
    }
}

/// `x ← x0 + θ (x − x0)`.
fn blend(x: &mut [f64], x0: &[f64], theta: f64) {
    x.iter_mut()
        .zip(x0)
        .for_each(|(x, x0)| *x = x0 + theta * (*x - x0));
}

impl SubState {
    /// `self ← start + θ (self − start)` on every field of s and ŝ.
    fn blend_from(&mut self, start: &SubState, theta: f64) {
        blend(&mut self.e, &start.e, theta);
        blend(&mut self.t, &start.t, theta);
        blend(&mut self.e_hat, &start.e_hat, theta);
        blend(&mut self.t_hat, &start.t_hat, theta);
        blend(&mut self.u, &start.u, theta);
        for (side, side0) in self.sides.iter_mut().zip(&start.sides) {
            blend(&mut side.u, &side0.u, theta);
            blend(&mut side.f, &side0.f, theta);
            blend(&mut side.u_hat, &side0.u_hat, theta);
            blend(&mut side.f_hat, &side0.f_hat, theta);
            blend(&mut side.hat_load, &side0.hat_load, theta);
        }
    }
}
