//! The solver interface, in the spirit of argmin: a solver is a state machine. [`Solver::init`]
//! gives the first state for a load ([`Solver::warm_init`] from a previous answer), [`Solver::next_iter`] advances it by one iteration, and
//! [`Solver::progress`] and [`Solver::iterate`] let the driver (and, through it, the observers)
//! see where it stands. A solver never loops, times or prints: the driver
//! ([`super::driver::drive`]) does.

use super::{Equilibrium, Measure, Status};
use crate::model::Model;
use crate::structure::Structure;

/// Where a state stands, as the solver sees it.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    /// Iterations done to reach this state (0 after `init`).
    pub iteration: usize,
    /// The stopping measure of this state (see [`Solver::measure`]).
    pub stopping_value: f64,
    /// r(U), the equilibrium residual of the state's displacements under the exact law
    /// ([`crate::model::Model::residual`]), when the solver has it at no extra cost.
    pub equilibrium_residual: Option<f64>,
    /// Operator rebuilds so far in this solve (status-following LATIN; 0 for the others).
    pub rebuilds: usize,
    /// Slack cables of this state.
    pub slack_cables: usize,
    /// PCG iterations of newton's substructured linear solves in this solve so far
    /// (`solver.linear = "krylov"`); `None` for a direct solve and the other solvers.
    pub krylov_iterations: Option<usize>,
    /// `Some` when the solver stops here: [`Status::Converged`] when its stopping criterion
    /// holds, [`Status::Stalled`] when it cannot go on. `None`: it can take another iteration.
    pub stop: Option<Status>,
    /// The solver stops here as converged because its measure is at round-off, not because
    /// its criterion holds (LATIN: Δη at round-off of the prestress, as with no load, where η
    /// is a ratio of round-off to round-off).
    pub at_roundoff: bool,
}

/// r(U) at or below this is the round-off of the prestress's own balance (`‖Bᵀt0‖` of a
/// balanced prestress is 1e-17 to 1e-15 of `‖|B|ᵀ|t0|‖`).
pub const PRESTRESS_ROUND_OFF: f64 = 1e-14;

/// Where an iterate stands against the equilibrium stop every solver shares, under every model
/// (issue 57; docs/method.md §6, "One stop"): r(U) relative to all the forces meeting at the
/// nodes, `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)`, and the same unbalance relative to the forces the
/// load brings into play, `r_F(U) = ‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ − t0|‖)`. The second keeps the
/// prestress, which dominates the first's scale, from passing U = 0 under a small load (R5-6:
/// U = 0 "converged" at α = 1e-9 under `large`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Balance {
    /// r(U) ≤ its tolerance and r_F(U) ≤ its tolerance.
    Met,
    /// Not met, but r(U) is at the round-off of the prestress's balance
    /// ([`PRESTRESS_ROUND_OFF`]) and the load's forces are below `PRESTRESS_ROUND_OFF` / the
    /// r_F tolerance of the prestress's: no iterate in floating point meets r_F's tolerance. A
    /// solver that can go no further there has the answer at round-off, and its row says so.
    AtRoundOff,
    /// Neither: the iterate is not an equilibrium to the tolerances.
    Unmet,
}

/// The two tolerances of [`Balance`]: on r(U) and on r_F(U).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceTolerances {
    /// Tolerance of r(U).
    pub residual: f64,
    /// Tolerance of r_F(U), the unbalance relative to the load's forces.
    pub load_residual: f64,
}

impl BalanceTolerances {
    /// The same tolerance on both (newton, pcg-lcp).
    pub fn both(tolerance: f64) -> Self {
        BalanceTolerances {
            residual: tolerance,
            load_residual: tolerance,
        }
    }

    /// Where r(U) = `residual` and r_F(U) = `load_residual` stand.
    pub fn balance(self, residual: f64, load_residual: f64) -> Balance {
        if residual <= self.residual && load_residual <= self.load_residual {
            return Balance::Met;
        }
        // The load's forces over all of them, `(‖F‖ + ‖|B|ᵀ|τ − t0|‖) / (‖F‖ + ‖|B|ᵀ|τ|‖)`:
        // below PRESTRESS_ROUND_OFF / tolerance, r_F cannot reach its tolerance above the
        // prestress's round-off. A tolerance below that round-off itself (1e-15) is no such
        // load: the row stalls, as it says (issue 13, C7).
        let load_share = residual / load_residual;
        let floor = self.load_residual > PRESTRESS_ROUND_OFF
            && self.residual > PRESTRESS_ROUND_OFF
            && residual <= PRESTRESS_ROUND_OFF
            && load_share <= PRESTRESS_ROUND_OFF / self.load_residual;
        match floor {
            true => Balance::AtRoundOff,
            false => Balance::Unmet,
        }
    }
}

/// The stop of a solver on [`Balance`] alone (newton; every solver under `large`): converged
/// when it is met; converged *at round-off* (the second `true`) when the solver can go no
/// further (`stalled`) at [`Balance::AtRoundOff`] (α = 1e-250 on a grid: the answer is the
/// prestressed state to round-off, which the row says); else stalled when `stalled`.
pub fn residual_stop(balance: Balance, stalled: bool) -> (Option<Status>, bool) {
    let at_roundoff = balance == Balance::AtRoundOff && stalled;
    (
        stop_when(balance == Balance::Met || at_roundoff, stalled),
        at_roundoff,
    )
}

/// The stop of a solver whose criterion is a residual below its tolerance: converged when
/// `converged`, else stalled when `stalled`, else none.
pub fn stop_when(converged: bool, stalled: bool) -> Option<Status> {
    if converged {
        Some(Status::Converged)
    } else if stalled {
        Some(Status::Stalled)
    } else {
        None
    }
}

/// An iterative solver, set up once for a structure, then driven for any load.
pub trait Solver {
    /// Everything that changes along the iterations of one solve.
    type State;

    /// Whether the state `init` returns is an iterate of the method that observers see as
    /// iteration 0 (the LATIN solvers' first linear stage). A start guess that is not a result
    /// of the method (newton's U = 0, pcg-lcp's λ = 0) is reported only when the solve ends on
    /// it.
    const INIT_IS_ITERATE: bool;

    /// What [`Progress::stopping_value`] measures.
    fn measure(&self) -> Measure;

    /// The model the solver is set up for.
    fn model(&self) -> &Model;

    /// The structure of its model.
    fn structure(&self) -> &Structure {
        &self.model().structure
    }

    /// Iteration cap: the driver stops the solve there with [`Status::MaxIterations`].
    fn max_iterations(&self) -> usize;

    /// The first state for `load` (on the free dofs, N).
    fn init(&mut self, load: &[f64]) -> Self::State;

    /// The first state for `load` started from `previous`, an answer of this solver for
    /// another load on the same structure (a sweep's previous α): a warm start. The solve
    /// stops on the same criterion as from [`Solver::init`], so it ends at the same
    /// equilibrium; only the way there may be shorter. By default the warm start is ignored
    /// (the LATIN solvers do so).
    fn warm_init(&mut self, load: &[f64], previous: &Equilibrium) -> Self::State {
        let _ = previous;
        self.init(load)
    }

    /// One iteration.
    fn next_iter(&mut self, state: &mut Self::State);

    /// Where `state` stands.
    fn progress(&self, state: &Self::State) -> Progress;

    /// Elongations `e = B U` of every link of the iterate, m: what the energy error e is
    /// measured on.
    fn elongations(&self, state: &Self::State) -> Vec<f64>;

    /// The iterate as an equilibrium state: displacements U and tensions τ.
    fn iterate(&self, state: &Self::State) -> Equilibrium;

    /// How far the solve followed its load path, for a solver that follows one (`large`);
    /// `None` by default.
    fn load_path(&self, _state: &Self::State) -> Option<super::LoadPathEnd> {
        None
    }

    /// A no-equilibrium certificate the solver found itself (docs/method.md §8), beside the
    /// driver's own check of the iterates. None by default.
    fn runaway(&self, _state: &Self::State) -> Option<super::NoEquilibrium> {
        None
    }

    /// The no-equilibrium certificate along the displacements (or change of displacements)
    /// `u` under `load` (docs/method.md §8); by default tested on [`Solver::model`] whole. A
    /// solver whose ranks each hold a share of the links tests each share and adds the parts.
    fn no_equilibrium_along(&self, u: &[f64], load: &[f64]) -> Option<super::NoEquilibrium> {
        super::no_equilibrium_along(self.model(), u, load)
    }
}
