//! Everything that changes along the LATIN iterations: per substructure its links' s = (e, t)
//! and ŝ = (ê, t̂), its interface sides' (U, F) and (Û, F̂), and its displacements.

use super::anderson::Anderson;
use super::substructure::Substructure;

/// One side of an interface as E holds it: s (U, F) and ŝ (Û, F̂), full nodal vectors in the
/// interface's node order, and the load the micro search direction puts on E,
/// `F̂^m + d_m Û^m`. F is the force of the interface on E.
#[derive(Debug, Clone)]
pub struct SideState {
    /// U of s.
    pub u: Vec<f64>,
    /// F of s.
    pub f: Vec<f64>,
    /// Û of ŝ.
    pub u_hat: Vec<f64>,
    /// F̂ of ŝ.
    pub f_hat: Vec<f64>,
    /// `F̂^m + d_m Û^m`.
    pub hat_load: Vec<f64>,
}

/// Everything that changes along the iterations for one substructure. Per-link arrays follow
/// `Substructure::links`; `sides` follows `Substructure::sides`; `u` is U_E on E's dofs.
#[derive(Debug, Clone)]
pub struct SubState {
    /// Elongations e of s, m.
    pub e: Vec<f64>,
    /// Additional tensions t of s (τ = t0 + t), N.
    pub t: Vec<f64>,
    /// Elongations ê of ŝ, m.
    pub e_hat: Vec<f64>,
    /// Additional tensions t̂ of ŝ, N.
    pub t_hat: Vec<f64>,
    /// Cables slack in ŝ.
    pub slack_hat: Vec<bool>,
    /// Its interface sides.
    pub sides: Vec<SideState>,
    /// U_E of the linear stage, on E's dofs.
    pub u: Vec<f64>,
}

impl SubState {
    /// ŝ = 0 and s = 0 on `sub`.
    pub(super) fn zero(sub: &Substructure) -> SubState {
        let m = sub.links.len();
        SubState {
            e: vec![0.0; m],
            t: vec![0.0; m],
            e_hat: vec![0.0; m],
            t_hat: vec![0.0; m],
            slack_hat: vec![false; m],
            sides: sub
                .sides
                .iter()
                .map(|side| SideState {
                    u: vec![0.0; side.rows],
                    f: vec![0.0; side.rows],
                    u_hat: vec![0.0; side.rows],
                    f_hat: vec![0.0; side.rows],
                    hat_load: vec![0.0; side.rows],
                })
                .collect(),
            u: vec![0.0; sub.n_dofs()],
        }
    }

    /// The state a process keeps of a substructure another process holds, when the
    /// iterations exchange s point to point: U_E (its shared dofs kept current) and the
    /// sides (the interfaces' local stage reads and writes both), no per-link field.
    pub(super) fn of_another_rank(sub: &Substructure) -> SubState {
        let mut st = SubState::zero(sub);
        (st.e, st.t, st.e_hat, st.t_hat) = Default::default();
        st.slack_hat = Vec::new();
        st
    }

    /// The per-link fields back at E's size, zero, where they were left out.
    pub(super) fn widen(&mut self, sub: &Substructure) {
        let m = sub.links.len();
        if self.e.len() != m {
            (self.e, self.t) = (vec![0.0; m], vec![0.0; m]);
            (self.e_hat, self.t_hat) = (vec![0.0; m], vec![0.0; m]);
            self.slack_hat = vec![false; m];
        }
    }
}

/// The iterate of the LATIN state machine: after `init` or `next_iter` it holds s (the last
/// linear stage) and the ŝ that fed it.
#[derive(Debug, Clone)]
pub struct LatinState {
    /// Per substructure.
    pub subs: Vec<SubState>,
    /// Iterations done (0 after the first linear stage).
    pub iteration: usize,
    /// η between s and ŝ.
    pub eta: f64,
    /// r(U): the equilibrium residual of the linear stage's U under the exact law.
    pub residual: f64,
    /// r_F(U): the same unbalance relative to the forces the load brings into play.
    pub load_residual: f64,
    /// Slack cables of ŝ.
    pub slack_cables: usize,
    /// Operator rebuilds (status-following l) so far in this solve.
    pub rebuilds: usize,
    /// The relaxed or Anderson-accelerated fixed point's state (every iteration order).
    pub(super) acceleration: Acceleration,
    /// Status-following l's state (`solver.policy = "status"`).
    pub(super) following: Following,
    /// Inexact Newton status steps' state (`solver.policy = "newton"`, the default).
    pub steps: StatusSteps,

    /// Δη is at round-off level against the prestress: nothing is left to iterate on.
    pub at_roundoff: bool,
    /// r(U) has been within 100 times its tolerance: every macro solve from then on is refined
    /// to the end ([`super::Latin::macro_accuracy`]).
    pub(super) macro_to_the_end: bool,
    /// No force and no settlement: the exact answer is U = 0 (η is then a ratio of round-off,
    /// and Δη at round-off is convergence; under a load it is a stall).
    pub(super) unloaded: bool,
    /// The load on the free dofs, N.
    pub(super) load: Vec<f64>,
}

/// What the next linear stage is relaxed against or extrapolated from.
#[derive(Debug, Clone)]
pub(crate) struct Acceleration {
    /// Whether s was computed with the current operators, so that the next linear stage may
    /// be relaxed (or extrapolated) against it: not after a re-set-up.
    pub(super) relax: bool,
    /// With Anderson acceleration: the linear stage's input that gave s (see
    /// [`super::anderson`]), and the history it extrapolates from.
    pub(super) input: Vec<f64>,
    pub(super) anderson: Anderson,
}

/// What status-following l counts between rebuilds.
#[derive(Debug, Clone)]
pub(crate) struct Following {
    /// Per link: for how many linear stages in a row its status has differed from the one its
    /// search direction was built for.
    pub(super) status_streak: Vec<u8>,
}

/// What inexact Newton status steps keep between iterations.
#[derive(Debug, Clone)]
pub struct StatusSteps {
    /// r(U) under the law linearised at the status.
    pub frozen_residual: f64,
    /// The slack status the local stage's law is linearised at (per link).
    pub law_slack: Vec<bool>,
    /// A step along which the exact energy decreases without bound, as its certificate
    /// (docs/method.md §8).
    pub(super) runaway: Option<crate::solvers::NoEquilibrium>,
    /// Where the current step started.
    pub(super) start: Option<super::status_step::StepStart>,
}
