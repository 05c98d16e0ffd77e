//! The `large` model solved (docs/method.md §8, `model.geometry = "large"`): large
//! displacements under dead loads, by Newton's method on the energy of the exact-length law,
//! one load from given displacements. [`crate::solvers::LoadPath`] drives it from load to
//! load (where each solve starts; the increments that do not converge are halved).
//!
//! Minimises `Π(U) = Σ_bars (t0 e + ½ k e²) + Σ_cables ½ k ⟨e + t0/k⟩₊² − Fᵀ U` with
//! `e = ℓ(U) − L` on the current geometry. Each step finds a direction ΔU from the quadratic
//! model of Π at U ([`TangentStep`]), then a length along it by the sign of
//! `Π'(s) = ∇Π(U + sΔU)·ΔU` (a search on Π's value stalls at r ≈ 4e-8: Π is dominated by the
//! prestress energy). Two rules give ΔU:
//! - [`HessianStep`] (`newton`): `H ΔU = −∇Π` with the Hessian factorized, chord steps while
//!   they contract;
//! - [`LinearisedStep`] (`pcg-lcp`, `mono-latin`, `micro-macro`): the solver's own method on
//!   the problem linearised at U — the structure on the current geometry, the trial tensions
//!   as its prestress, `K_G(τ)` as its geometric stiffness, the cables still unilateral — a
//!   sequential LCP.
//!
//! Stopping measure: [`Measure::EquilibriumResidual`] with the current unit vectors, the
//! stricter load-relative form at or below the tolerance too.

mod hessian;
mod linearised;

pub use hessian::{HessianStep, LargeWork};
pub use linearised::{latin_problem_at_rest, LinearisedStep, LinearisedWork};

use super::newton::NewtonSettings;
use crate::linalg::dot;
use crate::model::material::{self, SlackRule};
use crate::model::{CurrentGeometry, Model};
use crate::solvers::{
    residual_stop, Balance, BalanceTolerances, Equilibrium, Measure, PathPoint, PathSolver,
    Progress, Solver, TautStiffness,
};
use crate::structure::Structure;

/// The loosest tolerances a load path's equilibria are held to, whatever the solver's: a looser
/// one passes points near a limit, or on the snapped-through branch, as equilibria of the path
/// (the arch at `solver.tolerance = 1e-2` was converged at α = 3 on its inverted branch, and at
/// 1e-3 its limit was located 2 % off), and the branch check's round-off would swamp it.
pub const PATH_TOLERANCES: BalanceTolerances = BalanceTolerances {
    residual: 1e-8,
    load_residual: 1e-6,
};

/// `tolerances`, at most [`PATH_TOLERANCES`].
pub(super) fn on_the_path(tolerances: BalanceTolerances) -> BalanceTolerances {
    BalanceTolerances {
        residual: tolerances.residual.min(PATH_TOLERANCES.residual),
        load_residual: tolerances.load_residual.min(PATH_TOLERANCES.load_residual),
    }
}

/// Bisections of the line search at most.
const LINE_SEARCH_BISECTIONS: usize = 40;

/// How a step of Newton's method on the large model finds its direction ΔU at an iterate.
pub trait TangentStep {
    /// ΔU at `state` (displacements, load, and the law's values there); `None` when none is
    /// found (no factorisable tangent, no solvable linearised problem).
    fn direction(&mut self, model: &Model, state: &LargeState) -> Option<Vec<f64>>;

    /// The step just taken moved the load-relative residual from `before` to `after`.
    fn taken(&mut self, before: f64, after: f64) {
        let _ = (before, after);
    }

    /// Forget any tangent kept: the next direction is found afresh (an increment is retried).
    fn forget(&mut self) {}

    /// Whether a direction since the last [`TangentStep::forget`] failed for a reason of the
    /// rule's own (an inner solver that did not converge), not the structure's: a path that
    /// ends there has stalled rather than reached a limit point.
    fn failed_on_its_own(&self) -> bool {
        false
    }
}

/// newton on the exact-length law: Newton steps on the factorized Hessian.
pub type LargeNewton<'s> = Large<'s, HessianStep<'s>>;

impl<'s> LargeNewton<'s> {
    /// Set up on a model whose `K + K_G(t0)` (the tangent at the prestressed state) is
    /// known to be positive definite: its pattern and symbolic analysis serve every tangent.
    pub fn new(model: &'s Model, taut: &'s TautStiffness, settings: NewtonSettings) -> Self {
        let tolerances = BalanceTolerances::both(settings.tolerance);
        Large::with_step(
            model,
            HessianStep::new(taut),
            tolerances,
            settings.max_iterations,
        )
    }
}

impl<'s> Large<'s, LinearisedStep<'s>> {
    /// pcg-lcp, mono-latin or micro-macro on the `large` model: Newton steps whose directions
    /// the solver finds on the problem linearised at each step (`step`); the solve stops at
    /// the solver's own tolerances on r(U) and r_F(U) (`LinearisedStep::tolerances`), each
    /// load increment after at most [`crate::solvers::INCREMENT_MAX_STEPS`] steps
    /// (`solver.max_iterations` caps each linearised solve instead).
    pub fn linearised(model: &'s Model, step: LinearisedStep<'s>) -> Self {
        let tolerances = step.tolerances();
        Large::with_step(model, step, tolerances, crate::solvers::INCREMENT_MAX_STEPS)
    }
}

/// Newton's method on the large model, its directions from `R`, set up for one model.
pub struct Large<'s, R> {
    model: &'s Model,
    structure: &'s Structure,
    /// The residuals to reach (the stop every solver shares).
    tolerances: BalanceTolerances,
    /// Steps per solve (per increment along the load path).
    max_iterations: usize,
    step: R,
}

/// The law's values at one iterate.
pub struct Evaluation {
    /// The members on the current geometry.
    pub current: CurrentGeometry,
    /// Trial tensions `t0 + k (ℓ − L)` (before a cable's clipping).
    pub trial: Vec<f64>,
    /// `∇Π(U) = Σ τ ∇ℓ − F`.
    pub gradient: Vec<f64>,
    /// r(U), the relative equilibrium residual.
    pub residual: f64,
    /// The residual relative to the load and the tension changes (the stop needs it too).
    pub load_residual: f64,
    /// r(U)'s scale, `‖F‖ + ‖|B|ᵀ|τ|‖`, N.
    pub scale: f64,
}

impl Evaluation {
    /// The cables slack at this iterate (their trial tension clipped).
    pub fn slack_cables(&self, s: &Structure) -> usize {
        let slack = material::slack_flags(s, &self.trial, SlackRule::Clipped);
        slack.iter().filter(|&&x| x).count()
    }

    /// The iterate at displacements `u` as an equilibrium state: U and the clipped tensions.
    pub fn equilibrium(&self, model: &Model, u: &[f64]) -> Equilibrium {
        let tensions = (model.structure.links.iter().zip(&self.trial))
            .map(|(l, &t)| material::tension(l, t))
            .collect();
        Equilibrium::classified(model, u.to_vec(), tensions)
    }
}

/// The law's values at displacements `u` under `load` (both on the free dofs).
pub fn evaluate(s: &Structure, load: &[f64], u: &[f64]) -> Evaluation {
    let current = CurrentGeometry::of(s, u);
    let mut gradient = vec![0.0; s.n_free];
    // ∇Π = Σ τ ∇ℓ − F.
    let (trial, sizes) = current.unbalances(s, load, &mut gradient);
    let finite = gradient.iter().all(|g| g.is_finite());
    let or_infinite = |x: f64| if finite { x } else { f64::INFINITY };
    Evaluation {
        current,
        trial,
        gradient,
        residual: or_infinite(sizes.relative),
        load_residual: or_infinite(sizes.load_relative),
        scale: sizes.scale,
    }
}

/// The iterate of a solve for one load.
pub struct LargeState {
    /// The load, N, on the free dofs.
    pub load: Vec<f64>,
    /// Displacements U on the free dofs.
    pub u: Vec<f64>,
    /// The law at U.
    pub eval: Evaluation,
    iteration: usize,
    /// The last step was no descent, or no direction was found: the state is the one before it.
    failed: bool,
}

impl<'s, R: TangentStep> Large<'s, R> {
    /// Newton's method on `model` (which must be `large`) with directions from `step`,
    /// stopping at `tolerances` (at most [`PATH_TOLERANCES`]) or after `max_iterations` steps.
    pub fn with_step(
        model: &'s Model,
        step: R,
        tolerances: BalanceTolerances,
        max_iterations: usize,
    ) -> Self {
        Large {
            model,
            structure: &model.structure,
            tolerances: on_the_path(tolerances),
            max_iterations,
            step,
        }
    }

    /// The direction rule (its work counters).
    pub fn step_rule(&self) -> &R {
        &self.step
    }

    fn evaluate(&self, load: &[f64], u: &[f64]) -> Evaluation {
        evaluate(self.structure, load, u)
    }

    /// The step length along ΔU by the sign of `Π'(s) = ∇Π(U + sΔU)·ΔU`: the full step when
    /// `Π'(1) ≤ 0` or `|Π'(1)| ≤ ½ |Π'(0)|`, else bisection of its root on [0, 1]. Returns the
    /// length and the evaluation there; `None` when ΔU is not a descent direction.
    fn line_search(&self, state: &LargeState, step: &[f64]) -> Option<(f64, Evaluation)> {
        let slope0 = dot(&state.eval.gradient, step);
        if slope0.is_nan() || slope0 >= 0.0 {
            return None;
        }
        let at = |length: f64| {
            let u: Vec<f64> = state
                .u
                .iter()
                .zip(step)
                .map(|(u, d)| u + length * d)
                .collect();
            let eval = self.evaluate(&state.load, &u);
            let slope = dot(&eval.gradient, step);
            let slope = if slope.is_finite() {
                slope
            } else {
                f64::INFINITY
            };
            (slope, eval)
        };
        let (slope, eval) = at(1.0);
        if slope <= 0.0 || slope.abs() <= 0.5 * slope0.abs() {
            return Some((1.0, eval));
        }
        let (mut low, mut high) = (0.0, 1.0);
        let mut best = None;
        for _ in 0..LINE_SEARCH_BISECTIONS {
            let mid = 0.5 * (low + high);
            let (slope, eval) = at(mid);
            if slope.abs() <= 0.1 * slope0.abs() {
                return Some((mid, eval));
            }
            if slope < 0.0 {
                low = mid;
                best = Some((mid, eval));
            } else {
                high = mid;
            }
        }
        best
    }

    /// Where `eval` stands against the stop every solver shares: r(U) and r_F(U) within
    /// their tolerances (with every cable slack the load-relative scale holds the released
    /// prestress and alone could pass a state far from equilibrium; r(U) alone passes U = 0
    /// under a small load).
    fn balance(&self, eval: &Evaluation) -> Balance {
        self.tolerances.balance(eval.residual, eval.load_residual)
    }
}

impl<R: TangentStep> Solver for Large<'_, R> {
    type State = LargeState;
    const INIT_IS_ITERATE: bool = false;

    fn measure(&self) -> Measure {
        Measure::EquilibriumResidual
    }

    fn model(&self) -> &Model {
        self.model
    }

    /// `solver.max_iterations` (per increment along the load path).
    fn max_iterations(&self) -> usize {
        self.max_iterations
    }

    /// U = 0, the prestressed state.
    fn init(&mut self, load: &[f64]) -> LargeState {
        self.state_at(load, vec![0.0; self.structure.n_free])
    }

    /// U = the previous answer's displacements.
    fn warm_init(&mut self, load: &[f64], previous: &Equilibrium) -> LargeState {
        self.state_at(load, previous.displacements.clone())
    }

    /// One step: its direction, then its length; a direction that is no descent (or none
    /// found) fails, the state unchanged.
    fn next_iter(&mut self, state: &mut LargeState) {
        state.iteration += 1;
        let stepped = self
            .step
            .direction(self.model, state)
            .filter(|step| step.iter().all(|x| x.is_finite()))
            .and_then(|step| self.line_search(state, &step).map(|found| (step, found)));
        let Some((step, (length, eval))) = stepped else {
            state.failed = true;
            return;
        };
        state.failed = false;
        state
            .u
            .iter_mut()
            .zip(&step)
            .for_each(|(u, d)| *u += length * d);
        self.step
            .taken(state.eval.load_residual, eval.load_residual);
        state.eval = eval;
    }

    fn progress(&self, state: &LargeState) -> Progress {
        let (stop, at_roundoff) = residual_stop(self.balance(&state.eval), state.failed);
        Progress {
            iteration: state.iteration,
            stopping_value: state.eval.residual,
            equilibrium_residual: Some(state.eval.residual),
            rebuilds: 0,
            krylov_iterations: None,
            slack_cables: state.eval.slack_cables(self.structure),
            at_roundoff,
            stop,
        }
    }

    /// `e = ℓ(U) − L`.
    fn elongations(&self, state: &LargeState) -> Vec<f64> {
        state.eval.current.elongations.clone()
    }

    fn iterate(&self, state: &LargeState) -> Equilibrium {
        state.eval.equilibrium(self.model, &state.u)
    }
}

impl<R: TangentStep> PathSolver for Large<'_, R> {
    fn state_at(&mut self, load: &[f64], u: Vec<f64>) -> LargeState {
        let eval = self.evaluate(load, &u);
        LargeState {
            load: load.to_vec(),
            u,
            eval,
            iteration: 0,
            failed: false,
        }
    }

    /// The next step finds its direction afresh.
    fn forget_tangent(&mut self) {
        self.step.forget();
    }

    fn tolerance(&self) -> f64 {
        self.tolerances.residual
    }

    fn failed_on_its_own(&self) -> bool {
        self.step.failed_on_its_own()
    }

    fn point<'a>(&self, state: &'a LargeState) -> PathPoint<'a> {
        PathPoint {
            displacements: &state.u,
            gradient: &state.eval.gradient,
            trial: &state.eval.trial,
            residual: state.eval.residual,
            scale: state.eval.scale,
            balance: self.balance(&state.eval),
            failed: state.failed,
        }
    }
}
