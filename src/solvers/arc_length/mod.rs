//! `load.path = "arc-length"` (docs/method.md §8, "Past a limit point"): newton on the `large`
//! model along the equilibrium path (U, λ), parametrised by its arc length in the metric
//! `‖(ΔU, Δλ)‖² = ΔU·ΔU + ψ² Δλ²` with ψ = 0 (Crisfield's cylindrical arc: `PSI`), instead
//! of by the load. Load control stops at a limit point; this follows the
//! path through it, down the unstable branch and on to where the load rises again
//! (snap-through), with cables slackening and retightening on the way.
//!
//! Each step (Riks, normal plane): the predictor `P0 + Δs t0` along the unit tangent
//! `t ∝ (K⁻¹F, 1)`, then Newton on `R(U, λ) = ∇Π(U; λF) = 0` and `t0·(P − P0) = Δs`
//! (`corrector`). A step is halved when its corrector fails or the tangent turns by more
//! than `MAX_TURN`; it grows after an easy one. The tangent's λ-component changing from
//! positive to negative marks a limit point, located by bisection of the step
//! (`LIMIT_BISECTIONS`); a step whose λ passes the row's α is landed on it by load control.
//!
//! A solve at α starts from the path's last point and walks on to the first point where
//! λ = α: the sweep's α increase, and past a limit point the answer is on the branch the path
//! reaches, stable or not (the row says which, by the tangent's smallest eigenvalue).

mod corrector;

use super::{
    BalanceTolerances, Equilibrium, LoadPathEnd, Measure, Progress, Solver, Status, TautStiffness,
};
use crate::linalg::{SparseLdlt, StiffnessPattern};
use crate::model::Model;
use corrector::{Constraint, Direction, Point};

/// Arc steps (accepted or halved) one solve may take before it stops as
/// [`Status::MaxIterations`].
pub const MAX_ARC_STEPS: usize = 2000;
/// The largest turn of the tangent over an accepted step, as the cosine of its angle: a step
/// that turns more is halved (it may have jumped to another branch), unless already the
/// smallest.
const MAX_TURN: f64 = 0.8;
/// A step that turned less than this (cosine) and took at most [`EASY_STEPS`] corrector steps
/// is followed by one [`GROWTH`] times longer, up to [`LARGEST_STEP`] times the first.
const SMOOTH_TURN: f64 = 0.995;
const EASY_STEPS: usize = 4;
const GROWTH: f64 = 1.5;
const LARGEST_STEP: f64 = 64.0;
/// The smallest step, as a fraction of the first: a corrector that fails below it stops the
/// solve as [`Status::Stalled`].
const SMALLEST_STEP: f64 = 1e-8;
/// The step, as a fraction of the first, below which a turn of the tangent is taken as a kink
/// of the path (the simplex under 1 MN per top node: its kinks each halved to `SMALLEST_STEP`
/// without it, 171 + 323 Newton steps for α = 0.5 and 0.7, against 68 + 190 with it).
const KINK_STEP: f64 = 1e-4;
/// The first step's load increment, as a fraction of the first α asked.
const FIRST_STEP: f64 = 0.25;
/// Bisections of a step that passed a limit point: the limit is located within
/// `2^-LIMIT_BISECTIONS` of the step, its load (quadratic in the arc length there) to far less.
const LIMIT_BISECTIONS: usize = 30;

/// How newton follows the load path of the `large` model (`load.path`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PathFollowing {
    /// Load control (`"load-control"`, the default): the load raised in increments, halved
    /// near a limit point, where the path ends (`limit_point`).
    #[default]
    LoadControl,
    /// Arc length (`"arc-length"`): the path followed through limit points, by [`ArcLength`].
    ArcLength,
}

/// ψ of the path's metric `‖(ΔU, Δλ)‖² = ΔU·ΔU + ψ² Δλ²`: 0, Crisfield's cylindrical arc,
/// the step measured on the displacements alone. ψ = ‖K₀⁻¹F‖ (load and displacement alike at
/// the start) let the simplex's path jump its limit point: from its prestress-stiffened
/// mechanism the structure stiffens a hundredfold, the metric became the load's, and a 2.7 m
/// snap-through counted less than its 0.1 in λ.
const PSI: f64 = 0.0;

/// What the path's steps cost, over its solves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ArcWork {
    /// Arc steps accepted.
    pub steps: usize,
    /// Arc steps halved (the corrector failed, or the tangent turned too far).
    pub halvings: usize,
    /// Newton steps of every corrector (arc steps, landings, limit bisections).
    pub corrector_steps: usize,
    /// Numeric `L D Lᵀ` factorizations of a tangent.
    pub factorizations: usize,
    /// Limit points located.
    pub limits: usize,
}

/// The path followed so far: it persists from one solve to the next.
struct Path {
    /// The last point reached, with its unit tangent (`None` before the first solve found the
    /// equilibrium at λ = 0).
    last: Option<(Point, Direction)>,
    /// ψ of the metric ([`PSI`]), m per unit λ.
    psi: f64,
    /// The next step's length Δs, the first's, and the largest a step may grow to
    /// ([`LARGEST_STEP`] times the first, or times a quarter of what is left to the α asked
    /// when that is longer).
    step: f64,
    first_step: f64,
    largest: f64,
    /// The loads of the limit points passed (local maxima of λ along the path).
    limits: Vec<f64>,
}

/// newton on the `large` model along the arc length of its equilibrium path.
pub struct ArcLength<'s> {
    model: &'s Model,
    pattern: &'s StiffnessPattern,
    ldlt: SparseLdlt,
    hessian: Vec<f64>,
    tolerances: BalanceTolerances,
    /// F, the load at λ = 1 less the load at 0, on the free dofs.
    unit: Vec<f64>,
    path: Path,
    work: ArcWork,
}

/// A solve to one α along the path.
pub struct ArcState {
    /// The α asked.
    target: f64,
    /// The λ of the path's last point when the solve started.
    from: f64,
    /// The iterate: the last point reached, and the law there under the load at `target`.
    point: Point,
    eval: crate::solvers::large::Evaluation,
    iterations: usize,
    arc_steps: usize,
    stop: Option<Status>,
}

impl<'s> ArcLength<'s> {
    /// On a `large` model with a load (F ≠ 0); the tangents on the pattern and ordering of the
    /// taut stiffness.
    pub fn new(model: &'s Model, taut: &'s TautStiffness, tolerance: f64) -> Self {
        let unit: Vec<f64> = (model.load(1.0).iter().zip(model.load(0.0)))
            .map(|(a, b)| a - b)
            .collect();
        ArcLength {
            model,
            pattern: &taut.pattern,
            ldlt: SparseLdlt::sharing(&taut.factor),
            hessian: vec![0.0; taut.values.len()],
            tolerances: crate::solvers::large::on_the_path(BalanceTolerances::both(tolerance)),
            unit,
            path: Path {
                last: None,
                psi: PSI,
                step: 0.0,
                first_step: 0.0,
                largest: 0.0,
                limits: Vec::new(),
            },
            work: ArcWork::default(),
        }
    }

    /// What the steps cost so far.
    pub fn work(&self) -> ArcWork {
        self.work
    }

    /// The loads of the limit points passed so far.
    pub fn limits(&self) -> &[f64] {
        &self.path.limits
    }

    /// The start: the equilibrium at λ = 0 (U = 0 for a prestress in self-equilibrium), and
    /// the first step from its tangent. `None` when none is found there.
    fn start(&mut self, target: f64) -> Option<()> {
        let n = self.model.structure.n_free;
        let origin = Point {
            u: vec![0.0; n],
            lambda: 0.0,
        };
        let eval = self.evaluate_at(&origin);
        let (point, eval) = match self.balanced(&eval) {
            true => (origin, eval),
            false => {
                let found = self.correct(origin, &Constraint::Load(0.0))?;
                (found.point, found.eval)
            }
        };
        let tangent = self.tangent(&eval, (&vec![0.0; n], 1.0))?;
        // Δλ of the first step = FIRST_STEP of the first α (or of the unit load).
        let first_load = FIRST_STEP * if target > 0.0 { target } else { 1.0 };
        self.path.first_step = first_load / tangent.lambda;
        self.path.step = self.path.first_step;
        self.path.largest = LARGEST_STEP * self.path.first_step;
        self.path.last = Some((point, tangent));
        Some(())
    }

    /// One arc step from the path's last point: a point accepted (the path moves on), landed
    /// at the target (the solve ends), or the step halved.
    fn arc_step(&mut self, state: &mut ArcState) {
        let (from, tangent) = self.path.last.clone().expect("a started path");
        let step = self.path.step;
        let predicted = Point {
            u: (from.u.iter().zip(&tangent.u))
                .map(|(u, t)| u + step * t)
                .collect(),
            lambda: from.lambda + step * tangent.lambda,
        };
        let plane = Constraint::Plane {
            from: &from,
            tangent: &tangent,
            step,
        };
        let smallest = self.path.step <= SMALLEST_STEP * self.path.first_step;
        // A cable that slackens or retightens turns the path at a kink, however short the
        // step: below KINK_STEP the turn is taken (the chord check still guards a jump).
        let at_kink = self.path.step <= KINK_STEP * self.path.first_step;
        let Some(found) = self.correct(predicted, &plane) else {
            return self.halve(state, smallest);
        };
        state.iterations += found.steps;
        let secant = secant(&from, &found.point);
        let Some(next) = self.tangent(&found.eval, (&secant.u, secant.lambda)) else {
            return self.halve(state, smallest);
        };
        let turn = self.inner((&tangent.u, tangent.lambda), (&next.u, next.lambda));
        // The chord's length against the step: `t0·(P − P0) = Δs` holds exactly, so a chord
        // much longer than Δs left the tangent's direction (a jump to another branch).
        let chord = self.length(&secant);
        if ((turn < MAX_TURN && !at_kink) || step < MAX_TURN * chord) && !smallest {
            return self.halve(state, false);
        }
        // A limit point: λ rose along the tangent at the start and falls at the end. The
        // path passes it unless the α asked lies before it (then it lands there first).
        let mut reach = (found.point.clone(), next.clone());
        if tangent.lambda > 0.0 && next.lambda < 0.0 {
            let Some((limit, before)) = self.locate_limit(&from, &tangent, step, &found.point)
            else {
                return self.halve(state, smallest);
            };
            if limit >= state.target && before.lambda >= state.target {
                reach = (before, tangent.clone());
            } else {
                self.path.limits.push(limit);
                self.work.limits += 1;
            }
        }
        // The target passed between `from` and the point reached: land on it.
        if reach.0.lambda >= state.target {
            return self.land(state, &from, &tangent, &reach.0);
        }
        self.work.steps += 1;
        state.point = found.point;
        self.path.last = Some((state.point.clone(), next));
        if found.steps <= EASY_STEPS && turn >= SMOOTH_TURN {
            self.path.step = (self.path.step * GROWTH).min(self.path.largest);
        }
    }

    /// The step failed: halved, or the solve stalls when it was already the smallest.
    fn halve(&mut self, state: &mut ArcState, smallest: bool) {
        self.work.halvings += 1;
        if smallest {
            state.stop = Some(Status::Stalled);
        }
        self.path.step *= 0.5;
    }

    /// The limit point between `from` (λ rising along `tangent`) and `beyond` (falling), at
    /// most `step` along the path: bisection of the step on the sign of the tangent's λ. Its
    /// load (the largest λ met), and the last point found before it; `None` when a bisection's
    /// corrector fails (the step is then halved).
    fn locate_limit(
        &mut self,
        from: &Point,
        tangent: &Direction,
        step: f64,
        beyond: &Point,
    ) -> Option<(f64, Point)> {
        let (mut rising, mut falling) = (0.0, step);
        let mut limit = from.lambda.max(beyond.lambda);
        let mut before = from.clone();
        for _ in 0..LIMIT_BISECTIONS {
            let mid = 0.5 * (rising + falling);
            let predicted = Point {
                u: (from.u.iter().zip(&tangent.u))
                    .map(|(u, t)| u + mid * t)
                    .collect(),
                lambda: from.lambda + mid * tangent.lambda,
            };
            let plane = Constraint::Plane {
                from,
                tangent,
                step: mid,
            };
            let found = self.correct(predicted, &plane)?;
            let secant = secant(from, &found.point);
            let t = self.tangent(&found.eval, (&secant.u, secant.lambda))?;
            limit = limit.max(found.point.lambda);
            if t.lambda > 0.0 {
                rising = mid;
                before = found.point;
            } else {
                falling = mid;
            }
        }
        Some((limit, before))
    }

    /// Land on λ = α between `from` and `reached` (λ below and at or above α): load control
    /// from their interpolation. The path moves to the landing, the solve converges; a landing
    /// that fails, or lies off the step, halves the step instead.
    fn land(&mut self, state: &mut ArcState, from: &Point, tangent: &Direction, reached: &Point) {
        let target = state.target;
        let share = (target - from.lambda) / (reached.lambda - from.lambda);
        let start = Point {
            u: (from.u.iter().zip(&reached.u))
                .map(|(a, b)| a + share * (b - a))
                .collect(),
            lambda: target,
        };
        let span = self.inner(
            (&secant(from, reached).u, reached.lambda - from.lambda),
            (&tangent.u, tangent.lambda),
        );
        let reached_chord = self.length(&secant(from, reached));
        // On the step: ahead of `from` along its tangent, and no farther from it than the
        // point reached (a landing on another branch is not).
        let landed = self
            .correct(start, &Constraint::Load(target))
            .filter(|found| {
                let s = secant(from, &found.point);
                let along = self.inner((&s.u, s.lambda), (&tangent.u, tangent.lambda));
                along >= -0.05 * span && self.length(&s) <= reached_chord / MAX_TURN
            });
        let Some(found) = landed else {
            let smallest = self.path.step <= SMALLEST_STEP * self.path.first_step;
            return self.halve(state, smallest);
        };
        state.iterations += found.steps;
        let secant = secant(from, &found.point);
        let next = self
            .tangent(&found.eval, (&secant.u, secant.lambda))
            .unwrap_or_else(|| tangent.clone());
        self.work.steps += 1;
        state.point = found.point;
        state.eval = found.eval;
        self.path.last = Some((state.point.clone(), next));
        state.stop = Some(Status::Converged);
    }
}

impl ArcLength<'_> {
    /// The length of `d` in the path's metric.
    fn length(&self, d: &Direction) -> f64 {
        self.inner((&d.u, d.lambda), (&d.u, d.lambda)).sqrt()
    }
}

/// `b − a` as a direction (not normalised).
fn secant(a: &Point, b: &Point) -> Direction {
    Direction {
        u: b.u.iter().zip(&a.u).map(|(b, a)| b - a).collect(),
        lambda: b.lambda - a.lambda,
    }
}

impl Solver for ArcLength<'_> {
    type State = ArcState;
    const INIT_IS_ITERATE: bool = false;

    fn measure(&self) -> Measure {
        Measure::EquilibriumResidual
    }

    fn model(&self) -> &Model {
        self.model
    }

    /// The path's own caps end every solve first ([`MAX_ARC_STEPS`]).
    fn max_iterations(&self) -> usize {
        usize::MAX
    }

    /// From the path's last point (the equilibrium at λ = 0 at first), toward λ = α.
    fn init(&mut self, load: &[f64]) -> ArcState {
        // α of `load = α F`; no force F: no path to follow (the row stalls at α = 0).
        let unit = crate::linalg::dot(&self.unit, &self.unit);
        let target = match unit > 0.0 {
            true => crate::linalg::dot(load, &self.unit) / unit,
            false => 0.0,
        };
        if unit == 0.0 || (self.path.last.is_none() && self.start(target).is_none()) {
            let n = self.model.structure.n_free;
            let point = Point {
                u: vec![0.0; n],
                lambda: 0.0,
            };
            let eval = crate::solvers::large::evaluate(&self.model.structure, load, &point.u);
            return ArcState {
                target,
                from: 0.0,
                point,
                eval,
                iterations: 0,
                arc_steps: 0,
                stop: Some(Status::Stalled),
            };
        }
        let (point, tangent) = self.path.last.clone().expect("a started path");
        // Steps may grow to LARGEST_STEP times a quarter of what is left to α along the
        // tangent (a first α far below the next left them tiny).
        if tangent.lambda > 0.0 && target > point.lambda {
            let wanted = FIRST_STEP * (target - point.lambda) / tangent.lambda;
            self.path.largest = self.path.largest.max(LARGEST_STEP * wanted);
        }
        let eval = crate::solvers::large::evaluate(&self.model.structure, load, &point.u);
        // At the path's point already (α = 0 at the start, or α asked twice).
        let stop = (point.lambda == target
            || (target - point.lambda).abs() <= f64::EPSILON * target.abs())
        .then_some(Status::Converged);
        ArcState {
            target,
            from: point.lambda,
            point,
            eval,
            iterations: 0,
            arc_steps: 0,
            stop,
        }
    }

    /// The path starts from its own last point: `previous` is not needed.
    fn warm_init(&mut self, load: &[f64], _previous: &Equilibrium) -> ArcState {
        self.init(load)
    }

    /// One arc step; the solve ends at the target, or stops at [`MAX_ARC_STEPS`].
    fn next_iter(&mut self, state: &mut ArcState) {
        if state.stop.is_some() {
            return;
        }
        state.arc_steps += 1;
        self.arc_step(state);
        if state.stop.is_none() && state.arc_steps >= MAX_ARC_STEPS {
            state.stop = Some(Status::MaxIterations);
        }
        if state.stop != Some(Status::Converged) {
            // The stopping value of a row that did not reach α is measured at α.
            let load = self.model.load(state.target);
            state.eval =
                crate::solvers::large::evaluate(&self.model.structure, &load, &state.point.u);
        }
    }

    fn progress(&self, state: &ArcState) -> Progress {
        Progress {
            iteration: state.iterations,
            stopping_value: state.eval.residual,
            equilibrium_residual: Some(state.eval.residual),
            rebuilds: 0,
            krylov_iterations: None,
            slack_cables: state.eval.slack_cables(&self.model.structure),
            // Converged where only round-off is left of the load's balance: the row says so.
            at_roundoff: state.stop == Some(Status::Converged)
                && (self.tolerances).balance(state.eval.residual, state.eval.load_residual)
                    == crate::solvers::Balance::AtRoundOff,
            stop: state.stop,
        }
    }

    fn elongations(&self, state: &ArcState) -> Vec<f64> {
        state.eval.current.elongations.clone()
    }

    fn iterate(&self, state: &ArcState) -> Equilibrium {
        state.eval.equilibrium(self.model, &state.point.u)
    }

    /// How far the path went: the fraction of `from → α` its last point reached in load,
    /// and the largest limit load passed so far.
    fn load_path(&self, state: &ArcState) -> Option<LoadPathEnd> {
        let span = state.target - state.from;
        Some(LoadPathEnd {
            reached: match state.stop {
                Some(Status::Converged) => 1.0,
                _ if span != 0.0 => (state.point.lambda - state.from) / span,
                _ => 0.0,
            },
            branch_jumps: 0,
            slackened: Vec::new(),
            increment_steps: corrector::MAX_CORRECTOR_STEPS,
            limit_bracket: None,
            limit_alpha: self.path.limits.iter().copied().reduce(f64::max),
        })
    }
}
