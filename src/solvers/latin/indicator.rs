//! The LATIN indicator η (docs/method.md §4 "Indicator", paper §5.3) between s (a linear stage) and the
//! ŝ that fed it, and what the state reports after each linear stage.

use super::local_stage::link_local_stage;
use super::{Latin, LatinState, SubState};
use rayon::prelude::*;

/// Δη below this fraction of the prestress scale is round-off (a load-induced Δη on the
/// paper's case is 1e-4 of it at η = 1e-4).
const ROUNDOFF: f64 = 1e-12;

/// Under a load, Δη below this fraction of the prestress scale is a stall: the stages'
/// round-off on prestress-sized terms is ≈ 1e-16 of it, so a tiny load (α = 1e-9 on the paper
/// grid) still iterates to its tolerance above it.
const LOADED_ROUNDOFF: f64 = 1e-15;

/// r(U) and r_F(U) of the exact law, and with inexact Newton status steps the residual under
/// the law linearised at the status.
#[derive(Debug, Clone, Copy)]
pub(super) struct Residuals {
    /// r(U), relative to all the forces meeting at the nodes.
    pub exact: f64,
    /// r_F(U), relative to the forces the load brings into play.
    pub load_relative: f64,
    /// With status steps: the residual under the law linearised at the status.
    pub frozen: Option<f64>,
}

impl Latin<'_> {
    /// `(Δη, η̃)`: η = Δη/η̃ between s and ŝ (docs/method.md §4 "Indicator", §5.3). The distance is
    /// measured along the search direction that does not relate them: E⁺ (`t − t̂ = −l(e − ê)`)
    /// when ŝ fed s (the relaxed iteration), E⁻ when ŝ = local(s) (the accelerated one).
    ///
    /// With inexact Newton status steps ŝ lies on the law linearised at the status; η is
    /// measured against the exact law all the same (the links' ŝ recomputed on it), so that
    /// it says how far s is from the solution, not from the inner problem's.
    fn indicator(&self, state: &[SubState]) -> (f64, f64) {
        let dm = self.world.dm;
        let sign = if self.accelerated() { -1.0 } else { 1.0 };
        let exact = self.newton_steps();
        let links = &self.structure.links;
        // Per held substructure in parallel, gathered from every rank, then added in the
        // substructures' order (the same sums on any number of threads and of ranks).
        let held = self.ranks.held();
        let parts: Vec<(f64, f64)> = self.operators.substructures[held.clone()]
            .par_iter()
            .zip(state[held].par_iter())
            .with_min_len(self.ranks.chunk())
            .map(|(sub, st)| {
                let mut delta = 0.0;
                let mut size = 0.0;
                for (j, &i) in sub.links.iter().enumerate() {
                    let l = self.search.now[i];
                    let (e_hat, t_hat) = if exact {
                        let (e_hat, t_hat, _) = link_local_stage(&links[i], l, st.e[j], st.t[j]);
                        (e_hat, t_hat)
                    } else {
                        (st.e_hat[j], st.t_hat[j])
                    };
                    let d = (st.t[j] - t_hat) + sign * l * (st.e[j] - e_hat);
                    delta += d * d / l;
                    let e_mid = 0.5 * (st.e[j] + e_hat);
                    let t_mid = 0.5 * (st.t[j] + t_hat);
                    size += l * e_mid * e_mid + t_mid * t_mid / l;
                }
                for ss in &st.sides {
                    for r in 0..ss.u.len() {
                        let df = (ss.f[r] - ss.f_hat[r]) - sign * dm * (ss.u[r] - ss.u_hat[r]);
                        delta += df * df / dm;
                        let u_mid = 0.5 * (ss.u[r] + ss.u_hat[r]);
                        let f_mid = 0.5 * (ss.f[r] + ss.f_hat[r]);
                        size += dm * u_mid * u_mid + f_mid * f_mid / dm;
                    }
                }
                (delta, size)
            })
            .collect();
        let mine: Vec<f64> = parts.iter().flat_map(|&(d, s)| [d, s]).collect();
        let (delta, size) = self
            .ranks
            .gather(&mine)
            .chunks(2)
            .fold((0.0, 0.0), |(d, s), p| (d + p[0], s + p[1]));
        ((0.5 * delta).sqrt(), (0.5 * size).sqrt())
    }

    /// r(U) of the linear stage's U (`u`, [`Latin::displacements`]) under the exact law, and
    /// with inexact Newton status steps the residual under the law linearised at `law_slack`.
    /// It reads only U, so it may run beside the local stage.
    pub(super) fn residuals(&self, u: &[f64], load: &[f64], law_slack: &[bool]) -> Residuals {
        if self.model.prestress_stiffness().is_none() {
            let (exact, load_relative, frozen) = self.residuals_by_substructure(u, load, law_slack);
            Residuals {
                exact,
                load_relative,
                frozen: self.newton_steps().then_some(frozen),
            }
        } else if self.newton_steps() {
            let (exact, frozen) = self.model.exact_and_frozen_residuals(u, load, law_slack);
            Residuals {
                exact: exact.relative,
                load_relative: exact.load_relative,
                frozen: Some(frozen),
            }
        } else {
            let exact = self.model.unbalance_sizes(u, load);
            Residuals {
                exact: exact.relative,
                load_relative: exact.load_relative,
                frozen: None,
            }
        }
    }

    /// η, the equilibrium residual r(U), the round-off stop and the slack count of `state`
    /// after a linear stage; the residuals are `measured` when the iteration computed them
    /// beside its local stage.
    pub(super) fn measure_state(&self, state: &mut LatinState, measured: Option<Residuals>) {
        let (distance, size) = self.indicator(&state.subs);
        state.eta = if size > 0.0 { distance / size } else { 0.0 };
        // η is scale-free: when s and ŝ are both round-off (no load: the exact answer is
        // zero), it is a ratio of noise. Δη at round-off against the prestress is convergence.
        let floor = if state.unloaded {
            ROUNDOFF
        } else {
            LOADED_ROUNDOFF
        };
        state.at_roundoff = distance <= floor * self.world.prestress_scale;
        // r(U) of the linear stage's U under the exact law (docs/method.md §6), unless the
        // iteration measured it beside its local stage.
        let residuals = measured.unwrap_or_else(|| {
            let u = self.displacements(&state.subs);
            self.residuals(&u, &state.load, &state.steps.law_slack)
        });
        state.residual = residuals.exact;
        state.load_residual = residuals.load_relative;
        if let Some(frozen) = residuals.frozen {
            state.steps.frozen_residual = frozen;
        }

        // The slack cables of ŝ, counted per held substructure and gathered from every rank.
        let held: Vec<f64> = state.subs[self.ranks.held()]
            .iter()
            .map(|st| st.slack_hat.iter().filter(|&&x| x).count() as f64)
            .collect();
        state.slack_cables = self.ranks.gather(&held).iter().sum::<f64>() as usize;
    }
}
