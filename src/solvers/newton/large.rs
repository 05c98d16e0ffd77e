//! newton on the exact-length law (docs/method.md §8, `model.geometry = "large"`): large
//! displacements under dead loads. It solves one load from given displacements; `large`
//! drives it along the load path ([`crate::solvers::LoadPath`], which says where each solve
//! starts, and halves the increments that do not converge).
//!
//! Minimises `Π(U) = Σ_bars (t0 e + ½ k e²) + Σ_cables ½ k ⟨e + t0/k⟩₊² − Fᵀ U` with
//! `e = ℓ(U) − L` on the current geometry. A Newton step solves `H ΔU = −∇Π` with the Hessian
//! `Σ [[G, −G], [−G, G]]`, `G = k_t n nᵀ + (τ/ℓ)(I − n nᵀ)`, factorized; while steps with the
//! last factor (chord steps) shrink the residual enough, it is reused; where H is not positive definite
//! it is shifted, `H + σ diag(H)` with σ raised until the Cholesky factorisation succeeds. The
//! line search follows the sign of `Π'(s) = ∇Π(U + sΔU)·ΔU` (a search on Π's value stalls at
//! r ≈ 4e-8: Π is dominated by the prestress energy).
//!
//! Stopping measure: [`Measure::EquilibriumResidual`] with the current unit vectors, the
//! stricter load-relative form ≤ tolerance, as for the linear newton.

use super::NewtonSettings;
use crate::linalg::{dot, SparseCholesky, StiffnessPattern};
use crate::model::material::{self, SlackRule};
use crate::model::{CurrentGeometry, Model};
use crate::solvers::{
    stop_when, Equilibrium, Measure, PathPoint, PathSolver, Progress, Solver, TautStiffness,
};
use crate::structure::Structure;

/// The first shift σ of a Hessian that is not positive definite (× its diagonal), raised ×10
/// until the factorisation succeeds, up to [`MAX_SHIFT`].
const FIRST_SHIFT: f64 = 1e-8;
const MAX_SHIFT: f64 = 1e4;
/// Bisections of the line search at most.
const LINE_SEARCH_BISECTIONS: usize = 40;
/// A chord step (the last factor's Hessian for the new one: the geometry changes little from
/// one step, or one α, to the next) must shrink the load-relative residual to this fraction,
/// else the next step assembles and factorizes the Hessian. Paper case, 41-α sweep, one
/// process: 0.03 183 ms, 0.1 195 ms, 0.3 217 ms, 0.5 260 ms, 0.01 213 ms; CG on the new Hessian
/// preconditioned with the last factor (4 iterations to r²) instead: 234 ms; a factorization
/// at every step: 241 ms.
const CHORD_CONTRACTION: f64 = 0.03;

/// What the large-displacement solver's steps cost, over its solves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LargeWork {
    /// Newton steps.
    pub steps: usize,
    /// Steps whose Hessian was not positive definite and was shifted.
    pub shifted_steps: usize,
    /// Numeric factorizations of a Hessian (shifted attempts included).
    pub factorizations: usize,
    /// Chord steps: solved with an earlier step's factor, the Hessian not assembled.
    pub reused_steps: usize,
}

/// newton on the exact-length law, set up for one model.
pub struct LargeNewton<'s> {
    model: &'s Model,
    structure: &'s Structure,
    pattern: &'s StiffnessPattern,
    chol: SparseCholesky,
    settings: NewtonSettings,
    hessian: Vec<f64>,
    /// `chol` holds the factor of an earlier Hessian, and chord steps with it still contract
    /// the residual enough.
    chord: bool,
    /// The last step was a chord step.
    last_was_chord: bool,
    work: LargeWork,
}

/// The law's values at one iterate.
struct Evaluation {
    current: CurrentGeometry,
    trial: Vec<f64>,
    gradient: Vec<f64>,
    residual: f64,
    load_residual: f64,
    /// r(U)'s scale, `‖F‖ + ‖|B|ᵀ|τ|‖`, N.
    scale: f64,
}

/// The iterate of a solve for one load.
pub struct LargeState {
    load: Vec<f64>,
    u: Vec<f64>,
    eval: Evaluation,
    iteration: usize,
    /// The last step was no descent, or no shift made its Hessian factorisable: the state is
    /// the one before it.
    failed: bool,
}

impl<'s> LargeNewton<'s> {
    /// Set up on a model whose `K + K_G(t0)` (the tangent at the prestressed state) is
    /// known to be positive definite: its pattern and symbolic analysis serve every tangent.
    pub fn new(model: &'s Model, taut: &'s TautStiffness, settings: NewtonSettings) -> Self {
        LargeNewton {
            model,
            structure: &model.structure,
            pattern: &taut.pattern,
            chol: taut.factor.share_symbolic(),
            settings,
            hessian: vec![0.0; taut.values.len()],
            chord: false,
            last_was_chord: false,
            work: LargeWork::default(),
        }
    }

    /// What the steps cost so far.
    pub fn work(&self) -> LargeWork {
        self.work
    }

    fn evaluate(&self, load: &[f64], u: &[f64]) -> Evaluation {
        let s = self.structure;
        let current = CurrentGeometry::of(s, u);
        let mut gradient = vec![0.0; s.n_free];
        // ∇Π = Σ τ ∇ℓ − F.
        let (trial, sizes) = current.unbalances(s, load, &mut gradient);
        let finite = gradient.iter().all(|g| g.is_finite());
        Evaluation {
            current,
            trial,
            gradient,
            residual: if finite {
                sizes.relative
            } else {
                f64::INFINITY
            },
            load_residual: if finite {
                sizes.load_relative
            } else {
                f64::INFINITY
            },
            scale: sizes.scale,
        }
    }

    /// `ΔU = −H⁻¹ ∇Π`: a chord step with the last factor while chord steps contract the
    /// residual ([`CHORD_CONTRACTION`]), else with H assembled and factorized, shifted where it
    /// is not positive definite; `None` when no shift up to [`MAX_SHIFT`] makes it factorisable.
    fn newton_step(&mut self, state: &LargeState) -> Option<Vec<f64>> {
        let s = self.structure;
        self.work.steps += 1;
        let rhs: Vec<f64> = state.eval.gradient.iter().map(|g| -g).collect();
        if self.chord {
            // A chord step: the last factor's Hessian for this one.
            let mut step = rhs;
            self.chol.solve_in_place(&mut step);
            self.work.reused_steps += 1;
            self.last_was_chord = true;
            return step.iter().all(|x| x.is_finite()).then_some(step);
        }
        self.last_was_chord = false;
        state
            .eval
            .current
            .assemble_tangent(s, &state.eval.trial, self.pattern, &mut self.hessian);
        let diagonal: Vec<f64> = self
            .pattern
            .diag_slot
            .iter()
            .map(|&d| self.hessian[d].abs().max(f64::MIN_POSITIVE))
            .collect();
        let mut shift = 0.0;
        loop {
            self.work.factorizations += 1;
            if self.chol.factorize(self.pattern, &self.hessian).is_ok() {
                break;
            }
            // H + σ D, σ raised tenfold: D = |diag H|.
            let next = if shift == 0.0 {
                FIRST_SHIFT
            } else {
                shift * 10.0
            };
            if next > MAX_SHIFT {
                return None;
            }
            for (&d, &w) in self.pattern.diag_slot.iter().zip(&diagonal) {
                self.hessian[d] += (next - shift) * w;
            }
            shift = next;
        }
        self.chord = true;
        if shift > 0.0 {
            self.work.shifted_steps += 1;
        }
        let mut step = rhs;
        self.chol.solve_in_place(&mut step);
        step.iter().all(|x| x.is_finite()).then_some(step)
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
            (
                if slope.is_finite() {
                    slope
                } else {
                    f64::INFINITY
                },
                eval,
            )
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

    /// r(U) and its load-relative form both at or below the tolerance (with every cable slack
    /// the load-relative scale holds the released prestress and alone could pass a state far
    /// from equilibrium).
    fn converged(&self, eval: &Evaluation) -> bool {
        eval.load_residual.max(eval.residual) <= self.settings.tolerance
    }
}

impl Solver for LargeNewton<'_> {
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
        self.settings.max_iterations
    }

    /// U = 0, the prestressed state.
    fn init(&mut self, load: &[f64]) -> LargeState {
        self.state_at(load, vec![0.0; self.structure.n_free])
    }

    /// U = the previous answer's displacements.
    fn warm_init(&mut self, load: &[f64], previous: &Equilibrium) -> LargeState {
        self.state_at(load, previous.displacements.clone())
    }

    /// One Newton step with its line search; a step that is no descent (or whose Hessian no
    /// shift makes factorisable) fails, the state unchanged.
    fn next_iter(&mut self, state: &mut LargeState) {
        state.iteration += 1;
        let stepped = self
            .newton_step(state)
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
        // A chord step that contracted the residual by less than CHORD_CONTRACTION: the next
        // step refactorizes.
        if self.last_was_chord && eval.load_residual > CHORD_CONTRACTION * state.eval.load_residual
        {
            self.chord = false;
        }
        state.eval = eval;
    }

    fn progress(&self, state: &LargeState) -> Progress {
        Progress {
            iteration: state.iteration,
            stopping_value: state.eval.residual,
            equilibrium_residual: Some(state.eval.residual),
            rebuilds: 0,
            slack_cables: material::slack_flags(
                self.structure,
                &state.eval.trial,
                SlackRule::Clipped,
            )
            .iter()
            .filter(|&&x| x)
            .count(),
            at_roundoff: false,
            stop: stop_when(self.converged(&state.eval), state.failed),
        }
    }

    /// `e = ℓ(U) − L`.
    fn elongations(&self, state: &LargeState) -> Vec<f64> {
        state.eval.current.elongations.clone()
    }

    fn iterate(&self, state: &LargeState) -> Equilibrium {
        let tensions = self
            .structure
            .links
            .iter()
            .zip(&state.eval.trial)
            .map(|(l, &t)| material::tension(l, t))
            .collect();
        Equilibrium::classified(self.model, state.u.clone(), tensions)
    }
}

impl PathSolver for LargeNewton<'_> {
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

    /// The next step assembles and factorizes its Hessian.
    fn forget_tangent(&mut self) {
        self.chord = false;
    }

    fn tolerance(&self) -> f64 {
        self.settings.tolerance
    }

    fn point<'a>(&self, state: &'a LargeState) -> PathPoint<'a> {
        PathPoint {
            displacements: &state.u,
            gradient: &state.eval.gradient,
            trial: &state.eval.trial,
            residual: state.eval.residual,
            scale: state.eval.scale,
            converged: self.converged(&state.eval),
            failed: state.failed,
        }
    }
}
