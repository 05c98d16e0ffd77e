//! newton's direction on the `large` model (docs/method.md §8): `H ΔU = −∇Π` with the Hessian
//! `Σ [[G, −G], [−G, G]]`, `G = k_t n nᵀ + (τ/ℓ)(I − n nᵀ)`, factorized; while steps with the
//! last factor (chord steps) shrink the residual enough, it is reused; where H is not positive
//! definite it is shifted, `H + σ diag(H)` with σ raised until the Cholesky factorisation
//! succeeds.

use super::{LargeState, TangentStep};
use crate::linalg::{SparseCholesky, StiffnessPattern};
use crate::model::Model;
use crate::solvers::TautStiffness;

/// The first shift σ of a Hessian that is not positive definite (× its diagonal), raised ×10
/// until the factorisation succeeds, up to [`MAX_SHIFT`].
const FIRST_SHIFT: f64 = 1e-8;
const MAX_SHIFT: f64 = 1e4;
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

/// newton's direction: the factorized Hessian, or the last factor while chord steps contract.
pub struct HessianStep<'s> {
    pattern: &'s StiffnessPattern,
    chol: SparseCholesky,
    hessian: Vec<f64>,
    /// `chol` holds the factor of an earlier Hessian, and chord steps with it still contract
    /// the residual enough.
    chord: bool,
    /// The last step was a chord step.
    last_was_chord: bool,
    work: LargeWork,
}

impl<'s> HessianStep<'s> {
    /// On the pattern and symbolic analysis of the taut stiffness, which serve every tangent.
    pub fn new(taut: &'s TautStiffness) -> Self {
        HessianStep {
            pattern: &taut.pattern,
            chol: taut.factor.share_symbolic(),
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
}

impl TangentStep for HessianStep<'_> {
    /// `ΔU = −H⁻¹ ∇Π`: a chord step with the last factor while chord steps contract the
    /// residual (`CHORD_CONTRACTION`), else with H assembled and factorized, shifted where it
    /// is not positive definite; `None` when no shift up to `MAX_SHIFT` makes it factorisable.
    fn direction(&mut self, model: &Model, state: &LargeState) -> Option<Vec<f64>> {
        self.work.steps += 1;
        let mut step: Vec<f64> = state.eval.gradient.iter().map(|g| -g).collect();
        if self.chord {
            // A chord step: the last factor's Hessian for this one.
            self.chol.solve_in_place(&mut step);
            self.work.reused_steps += 1;
            self.last_was_chord = true;
            return Some(step);
        }
        self.last_was_chord = false;
        let eval = &state.eval;
        eval.current.assemble_tangent(
            &model.structure,
            &eval.trial,
            self.pattern,
            &mut self.hessian,
        );
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
        self.chol.solve_in_place(&mut step);
        Some(step)
    }

    /// A chord step that contracted the residual by less than `CHORD_CONTRACTION`: the next
    /// step refactorizes.
    fn taken(&mut self, before: f64, after: f64) {
        if self.last_was_chord && after > CHORD_CONTRACTION * before {
            self.chord = false;
        }
    }

    /// The next step assembles and factorizes its Hessian.
    fn forget(&mut self) {
        self.chord = false;
    }
}
