//! The direction of pcg-lcp, mono-latin and micro-macro on the `large` model (docs/method.md
//! §8): at each Newton step the solver's own method solves the problem linearised at U
//! ([`crate::model::CurrentGeometry::linearised`]: the structure on the current geometry, the
//! trial tensions as its prestress, `K_G(τ)`, the cables unilateral), and its displacements
//! are the step ΔU. With the cables' status free in the linearised problem, each step solves
//! an LCP (a sequential LCP); its energy is convex wherever the tangent is positive definite
//! on the taut set, so ΔU is a descent direction of Π.
//!
//! The linearised problems are solved inexactly (an inexact Newton method): to the forcing
//! term `r(U)²`, clamped to [`FORCING_LOOSEST`] and to [`FORCING_FLOOR`] × the tolerance, so
//! the steps far from the answer are cheap and the last ones accurate. The solver is set up
//! afresh at each step, on the geometry of that step (its operators depend on it).

use super::{on_the_path, LargeState, TangentStep};
use crate::decomposition::{Exchange, Partition};
use crate::model::{CurrentGeometry, Model};
use crate::solvers::latin::{Latin, LatinSettings, StopOn};
use crate::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use crate::solvers::{
    drive, no_equilibrium_along, no_equilibrium_of_slack_set, BalanceTolerances, SetupError,
    Silent, Solution, Status, TautStiffness, PRESTRESS_ROUND_OFF,
};
use std::time::Instant;

/// The loosest tolerance a linearised problem is solved to (far from the answer).
const FORCING_LOOSEST: f64 = 1e-4;
/// The tightest, as a fraction of the large solve's own tolerance: the residual after a
/// step is the linearised problem's plus a term quadratic in the step, so the inner solve
/// must do better than the outer tolerance for the outer one to be met.
const FORCING_FLOOR: f64 = 0.3;
/// The loosest η a LATIN linearised problem is asked for, whatever the forcing.
const LATIN_INDICATOR_LOOSEST: f64 = 1e-2;

/// The solver that solves the linearised problems.
enum LinearisedSolver<'s> {
    /// pcg-lcp with these settings (its tolerance set by the forcing term).
    PcgLcp(PcgLcpSettings),
    /// A LATIN solver (mono-latin on a 1 × 1 partition, micro-macro) on `partition` of the
    /// initial geometry, on the processes of `exchange`.
    Latin {
        /// Its settings (its tolerances set by the forcing term).
        settings: LatinSettings,
        /// The partition, kept from the initial geometry (boxed: it is large beside pcg-lcp's
        /// settings).
        partition: Box<Partition>,
        /// The processes the substructures are shared among.
        exchange: &'s dyn Exchange,
    },
}

/// What the linearised solves cost, over the large solve's steps.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LinearisedWork {
    /// Linearised problems solved (one per Newton step).
    pub steps: usize,
    /// The inner solver's iterations, over all steps.
    pub inner_iterations: usize,
    /// Linearised solves that did not reach their forcing term (their answer still served
    /// as a direction when it was a descent one).
    pub inner_unconverged: usize,
    /// Seconds setting the inner solver up (the operators of each step's geometry).
    pub setup_seconds: f64,
}

/// The direction from the solver's own method on the linearised problem.
pub struct LinearisedStep<'s> {
    solver: LinearisedSolver<'s>,
    /// The large solve's tolerances on r(U) and r_F(U).
    tolerances: BalanceTolerances,
    /// The linearised problems keep `K_G(τ)` (see [`LinearisedStep::latin`]).
    geometric_stiffness: bool,
    /// A linearised problem since the last [`TangentStep::forget`] was not solved.
    failed: bool,
    /// A linearised problem since the last [`TangentStep::forget`] had no equilibrium.
    no_equilibrium: bool,
    work: LinearisedWork,
}

impl<'s> LinearisedStep<'s> {
    /// pcg-lcp on the linearised problems; the large solve stops at its tolerance.
    pub fn pcg_lcp(settings: PcgLcpSettings) -> Self {
        LinearisedStep {
            solver: LinearisedSolver::PcgLcp(settings),
            tolerances: on_the_path(BalanceTolerances::both(settings.tolerance)),
            geometric_stiffness: true,
            failed: false,
            no_equilibrium: false,
            work: LinearisedWork::default(),
        }
    }

    /// A LATIN solver on the linearised problems of `model`, on the partition `settings`
    /// ask for (of the initial geometry); the large solve stops where r(U) is within its
    /// tolerance and r_F(U) within η's, as the LATIN solvers do under the other models.
    ///
    /// On a structure that is rigid without geometric stiffness the linearised problems
    /// leave `K_G(τ)` out (modified Newton steps): with it, a floating substructure's rigid
    /// rotations get a small stiffness of either sign, which its kernel test cannot classify
    /// (its operator is refused as singular once the load has moved the tensions off the
    /// prestress), and on the paper's grid at α = 1 mono-latin took 34 steps and 5.5 s with it
    /// against 30 steps and 0.86 s without. A prestress-stable mechanism keeps it (without it
    /// the linearised problem has no answer).
    ///
    /// The LATIN solver is set up once here on the first problem, the one linearised at the
    /// prestressed state ([`latin_problem_at_rest`], what `check` reports): a partition whose
    /// operators that problem refuses is refused at set-up, as `check` refuses it, instead of
    /// failing at the first step and ending every row stalled (N-D2).
    pub fn latin(
        model: &Model,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        let partition = Partition::new(&model.structure, settings.subdomains, settings.weak);
        let geometric_stiffness = !rigid_without_geometric_stiffness(model);
        let at_rest = problem_at_rest(model, geometric_stiffness);
        Latin::on_partition(&at_rest, &partition, settings, exchange)?;
        Ok(LinearisedStep {
            tolerances: on_the_path(settings.balance_tolerances()),
            geometric_stiffness,
            failed: false,
            no_equilibrium: false,
            solver: LinearisedSolver::Latin {
                settings,
                partition: Box::new(partition),
                exchange,
            },
            work: LinearisedWork::default(),
        })
    }

    /// The tolerances the large solve stops at: the inner solver's own.
    pub(super) fn tolerances(&self) -> BalanceTolerances {
        self.tolerances
    }

    /// What the linearised solves cost so far.
    pub fn work(&self) -> LinearisedWork {
        self.work
    }

    /// The linearised problem `linearised` solved under `load` to `forcing`; `None` when
    /// its solver cannot be set up on it: pcg-lcp's `K + K_G(τ)` with every cable taut not
    /// positive definite (the structure's own tangent, as newton's Hessian that no shift
    /// makes factorisable: a limit point may be near), or a LATIN operator refused (the
    /// solver's own failure, [`TangentStep::failed_on_its_own`]).
    fn solve(&mut self, linearised: &Model, load: &[f64], forcing: f64) -> Option<Solution> {
        let clock = Instant::now();
        match &self.solver {
            LinearisedSolver::PcgLcp(settings) => {
                let taut = TautStiffness::new(linearised).ok()?;
                let settings = PcgLcpSettings {
                    tolerance: forcing,
                    ..*settings
                };
                let mut solver = PcgLcp::new(linearised, &taut, settings);
                self.work.setup_seconds += clock.elapsed().as_secs_f64();
                Some(drive(&mut solver, load, None, &mut Silent))
            }
            LinearisedSolver::Latin {
                settings,
                partition,
                exchange,
            } => {
                // η's tolerance loosened as r(U)'s is (docs/method.md §4: both must hold), and
                // both held whatever the case's `stop_on`: the direction must be the
                // linearised problem's answer to the forcing term (a LATIN fixed point off
                // equilibrium, which η alone can pass on one-module strips, made the path
                // halve to a false limit point: R5-7).
                let loosened = forcing / self.tolerances.residual;
                let settings = LatinSettings {
                    stop_on: StopOn::Both,
                    residual_tolerance: Some(forcing),
                    tolerance: (settings.tolerance * loosened)
                        .min(LATIN_INDICATOR_LOOSEST)
                        .max(settings.tolerance),
                    ..*settings
                };
                let Ok(mut solver) =
                    Latin::on_partition(linearised, partition, settings, *exchange)
                else {
                    self.failed = true;
                    return None;
                };
                self.work.setup_seconds += clock.elapsed().as_secs_f64();
                Some(drive(&mut solver, load, None, &mut Silent))
            }
        }
    }
}

impl TangentStep for LinearisedStep<'_> {
    /// ΔU: the displacements of the linearised problem at U, solved to the forcing term
    /// `r(U)²`, clamped to `FORCING_LOOSEST` and to `FORCING_FLOOR` × the r(U) that meets
    /// the stop (r_F's tolerance times the load's share of r(U)'s scale, `r / r_F`), never
    /// below the prestress's round-off.
    fn direction(&mut self, model: &Model, state: &LargeState) -> Option<Vec<f64>> {
        let eval = &state.eval;
        let linearised = eval.current.linearised(
            &model.structure,
            &state.u,
            &eval.trial,
            self.geometric_stiffness,
        );
        let load_share = match eval.load_residual > 0.0 {
            true => (eval.residual / eval.load_residual).min(1.0),
            false => 1.0,
        };
        let needed = self
            .tolerances
            .residual
            .min(self.tolerances.load_residual * load_share);
        let forcing = (eval.residual * eval.residual)
            .min(FORCING_LOOSEST)
            .max(FORCING_FLOOR * needed)
            .max(PRESTRESS_ROUND_OFF);
        let solution = self.solve(&linearised, &state.load, forcing)?;
        self.work.steps += 1;
        self.work.inner_iterations += solution.info.iterations;
        let eq = &solution.equilibrium;
        match solution.info.status {
            Status::Converged => {}
            // The linearised problem has no equilibrium (its slack cables leave a mechanism
            // the load works on): no direction, and the structure's verdict, not the inner
            // solver's failure, as newton's Hessian that no shift makes a descent finds it
            // (the bracket under uplift: a limit point for every solver, D10). An inner
            // solve that stalled is asked too: a LATIN iteration on such a problem stalls at
            // a fixed point off equilibrium (η 1e-16, r(U) 0.9) before its runaway shows.
            Status::NoEquilibrium => {
                self.no_equilibrium = true;
                return None;
            }
            _ if no_equilibrium_along(&linearised, &eq.displacements, &state.load)
                .or_else(|| no_equilibrium_of_slack_set(&linearised, &eq.slack, &state.load))
                .is_some() =>
            {
                self.no_equilibrium = true;
                return None;
            }
            _ => {
                self.work.inner_unconverged += 1;
                self.failed = true;
            }
        }
        Some(solution.equilibrium.displacements)
    }

    /// The increment is retried from its start: its linearised solves are forgotten.
    fn forget(&mut self) {
        self.failed = false;
        self.no_equilibrium = false;
    }

    /// Some linearised problem of the increment was not solved to its forcing term; with a
    /// LATIN solver, too, an increment that failed while every linearised problem had an
    /// equilibrium: its inexact directions (a fixed point off the linearised answer passes its
    /// forcing term) cannot tell a limit point from their own stall. On the arch at
    /// α = 2.125, 0.4 % below its limit, mono-latin's steps gave out and the path said
    /// "limit point at 2.1194"; newton and pcg-lcp converge there.
    fn failed_on_its_own(&self) -> bool {
        let latin = matches!(self.solver, LinearisedSolver::Latin { .. });
        self.failed || (latin && !self.no_equilibrium)
    }
}

/// Whether the structure's stiffness with every cable taut, without geometric stiffness, is
/// regular: grids are (their supports are checked when the case is read); a general
/// structure's is factorized once to tell.
fn rigid_without_geometric_stiffness(model: &Model) -> bool {
    let s = &model.structure;
    s.layout.is_some() || TautStiffness::new(&Model::linear(s.clone())).is_ok()
}

/// The first problem a LATIN solver solves on the `large` model `model`: the one linearised at
/// the prestressed state (U = 0), with or without `K_G(t0)` as [`LinearisedStep::latin`]
/// takes it. `check` sets the solver up on it to report its partition.
pub fn latin_problem_at_rest(model: &Model) -> Model {
    problem_at_rest(model, !rigid_without_geometric_stiffness(model))
}

/// The problem linearised at the prestressed state, with `K_G(t0)` when `geometric_stiffness`.
fn problem_at_rest(model: &Model, geometric_stiffness: bool) -> Model {
    let s = &model.structure;
    let zero = vec![0.0; s.n_free];
    let current = CurrentGeometry::of(s, &zero);
    let trial = current.trial_tensions(s);
    current.linearised(s, &zero, &trial, geometric_stiffness)
}
