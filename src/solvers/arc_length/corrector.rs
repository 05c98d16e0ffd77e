//! One point of the equilibrium path: Newton's method on `R(U, λ) = ∇Π(U; λF) = 0` with one
//! more equation that fixes where on the path (Riks' normal plane, or the load), and the
//! path's tangent there. The tangent stiffness is factorized `L D Lᵀ`: past a limit point it is
//! indefinite, and Cholesky fails.

use super::ArcLength;
use crate::linalg::dot;
use crate::solvers::large::{evaluate, Evaluation};
use crate::solvers::Balance;

/// Newton steps one corrector may take before the point is given up (the step is halved).
pub(super) const MAX_CORRECTOR_STEPS: usize = 15;

/// A point (U, λ) of the path.
#[derive(Debug, Clone)]
pub(super) struct Point {
    /// Displacements on the free dofs, m.
    pub u: Vec<f64>,
    /// The load factor.
    pub lambda: f64,
}

/// A direction in (U, λ), of unit length in the path's metric `‖(ΔU, Δλ)‖² = ΔU·ΔU + ψ² Δλ²`.
#[derive(Debug, Clone)]
pub(super) struct Direction {
    pub u: Vec<f64>,
    pub lambda: f64,
}

/// The equation that, beside equilibrium, fixes the point.
pub(super) enum Constraint<'a> {
    /// Riks' normal plane: `t·(P − P0) = Δs`, the point at arc length Δs along `t` from `P0`.
    Plane {
        from: &'a Point,
        tangent: &'a Direction,
        step: f64,
    },
    /// The load factor: λ = the given value (load control).
    Load(f64),
}

/// An equilibrium found by the corrector.
pub(super) struct Corrected {
    pub point: Point,
    pub eval: Evaluation,
    /// Newton steps taken.
    pub steps: usize,
}

impl ArcLength<'_> {
    /// `‖(Δu, Δλ)‖`-metric inner product: `a_u·b_u + ψ² a_λ b_λ`.
    pub(super) fn inner(&self, a: (&[f64], f64), b: (&[f64], f64)) -> f64 {
        dot(a.0, b.0) + self.path.psi * self.path.psi * a.1 * b.1
    }

    /// Factorize the tangent at `eval` (`L D Lᵀ`); `false` at a zero pivot.
    fn factorize(&mut self, eval: &Evaluation) -> bool {
        let s = &self.model.structure;
        eval.current
            .assemble_tangent(s, &eval.trial, self.pattern, &mut self.hessian);
        self.work.factorizations += 1;
        self.ldlt.factorize(&self.hessian).is_ok()
    }

    /// `K⁻¹ F` with the last factor: the displacement per unit load factor along the path.
    fn load_direction(&self) -> Vec<f64> {
        let mut a = self.unit.clone();
        self.ldlt.solve_in_place(&mut a);
        a
    }

    /// The law at `point`.
    pub(super) fn evaluate_at(&self, point: &Point) -> Evaluation {
        evaluate(
            &self.model.structure,
            &self.model.load(point.lambda),
            &point.u,
        )
    }

    /// Whether `eval` is an equilibrium to the path's tolerances.
    pub(super) fn balanced(&self, eval: &Evaluation) -> bool {
        matches!(
            self.tolerances.balance(eval.residual, eval.load_residual),
            Balance::Met | Balance::AtRoundOff
        )
    }

    /// Newton's method on R(U, λ) = 0 and `constraint` from `start`: each step
    /// `K δU − F δλ = −R` with the constraint linearised, by bordering:
    /// `δU = b + δλ a`, `K b = −R`, `K a = F`. `None` when it does not converge within
    /// [`MAX_CORRECTOR_STEPS`] steps, or a tangent has a zero pivot.
    pub(super) fn correct(&mut self, start: Point, constraint: &Constraint) -> Option<Corrected> {
        let mut point = start;
        for steps in 0..=MAX_CORRECTOR_STEPS {
            let eval = self.evaluate_at(&point);
            if !eval.residual.is_finite() {
                return None;
            }
            // The plane is linear in (U, λ): met exactly after the first step.
            if steps > 0 && self.balanced(&eval) {
                return Some(Corrected { point, eval, steps });
            }
            if steps == MAX_CORRECTOR_STEPS || !self.factorize(&eval) {
                return None;
            }
            self.work.corrector_steps += 1;
            let a = self.load_direction();
            let mut b: Vec<f64> = eval.gradient.iter().map(|g| -g).collect();
            self.ldlt.solve_in_place(&mut b);
            let delta_lambda = match constraint {
                Constraint::Load(lambda) => lambda - point.lambda,
                Constraint::Plane {
                    from,
                    tangent,
                    step,
                } => {
                    // t·(U + b − U0, λ − λ0) + δλ t·(a, 1) = Δs.
                    let moved: Vec<f64> = (point.u.iter().zip(&from.u).zip(&b))
                        .map(|((u, u0), b)| u + b - u0)
                        .collect();
                    let t = (tangent.u.as_slice(), tangent.lambda);
                    let along = self.inner(t, (&moved, point.lambda - from.lambda));
                    (step - along) / self.inner(t, (&a, 1.0))
                }
            };
            if !delta_lambda.is_finite() {
                return None;
            }
            for ((u, b), a) in point.u.iter_mut().zip(&b).zip(&a) {
                *u += b + delta_lambda * a;
            }
            point.lambda += delta_lambda;
        }
        None
    }

    /// The path's unit tangent at the equilibrium `eval` of `point`, `(K⁻¹F, 1)` normalised,
    /// oriented along `forward` (positive inner product); `None` at a zero pivot.
    pub(super) fn tangent(
        &mut self,
        eval: &Evaluation,
        forward: (&[f64], f64),
    ) -> Option<Direction> {
        if !self.factorize(eval) {
            return None;
        }
        let a = self.load_direction();
        let norm = self.inner((&a, 1.0), (&a, 1.0)).sqrt();
        let sign = match self.inner((&a, 1.0), forward) {
            x if x < 0.0 => -1.0,
            _ => 1.0,
        };
        let scale = sign / norm;
        let direction = Direction {
            u: a.iter().map(|x| x * scale).collect(),
            lambda: scale,
        };
        let finite = direction.lambda.is_finite() && direction.u.iter().all(|x| x.is_finite());
        (norm > 0.0 && finite).then_some(direction)
    }
}
