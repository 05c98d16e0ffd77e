//! newton on the exact-length law (docs/method.md §8, `model.geometry = "large"`): large
//! displacements under dead loads, along the load path.
//!
//! Minimises `Π(U) = Σ_bars (t0 e + ½ k e²) + Σ_cables ½ k ⟨e + t0/k⟩₊² − Fᵀ U` with
//! `e = ℓ(U) − L` on the current geometry. A Newton step solves `H ΔU = −∇Π` with the Hessian
//! `Σ [[G, −G], [−G, G]]`, `G = k_t n nᵀ + (τ/ℓ)(I − n nᵀ)`, factorized; while steps with the
//! last factor (chord steps) shrink the residual enough, it is reused; where H is not positive definite
//! it is shifted, `H + σ diag(H)` with σ raised until the Cholesky factorisation succeeds. The
//! line search follows the sign of `Π'(s) = ∇Π(U + sΔU)·ΔU` (a search on Π's value stalls at
//! r ≈ 4e-8: Π is dominated by the prestress energy).
//!
//! The load path: a solve starts from the last equilibrium this solver reached (the prestressed
//! state, U = 0 under no load, at first) and walks to its load in increments, first the whole
//! way; an increment that does not converge within [`INCREMENT_MAX_STEPS`] steps is halved and
//! retried from the last equilibrium, down to [`MIN_INCREMENT`] of the path, below which the
//! solve ends at a limit point ([`Status::LimitPoint`]), never as converged. A retry
//! assembles and factorizes its Hessian afresh: the failed attempt's factor (nearly singular
//! near a limit point) is no chord for it. An increment's equilibrium is accepted only when
//! it lies on the path: the energy at the increment's load is convex along the segment from
//! the last equilibrium to it (`LargeNewton::on_the_path`); one reached across a region where it is not
//! (past a limit point, on a snapped-through branch) is rejected and the increment halved, so
//! that a solve's verdict depends on its load alone, not on the α before it. Loads beyond a
//! limit point of the path end `LimitPoint`, whatever the α list.
//!
//! Stopping measure: [`Measure::EquilibriumResidual`] with the current unit vectors, the
//! stricter load-relative form ≤ tolerance, as for the linear newton.

use super::NewtonSettings;
use crate::linalg::{dot, norm, SparseCholesky, StiffnessPattern};
use crate::model::material::{self, SlackRule};
use crate::model::{CurrentGeometry, Model};
use crate::solvers::{Equilibrium, LoadPathEnd, Measure, Progress, Solver, Status, TautStiffness};
use crate::structure::Structure;

/// Newton steps one load increment may take before it is halved (fewer when
/// `solver.max_iterations` is smaller: under `large` the cap is per increment).
pub const INCREMENT_MAX_STEPS: usize = 30;
/// Points (besides the last equilibrium) at which the slope of the energy along an
/// increment's segment is sampled for `LargeNewton::on_the_path`.
const SEGMENT_SAMPLES: usize = 4;
/// An increment whose r(U) is at or below this after [`INCREMENT_MAX_STEPS`] steps without
/// meeting the tolerance sits at round-off: the solve ends `Stalled` rather than halving.
const ROUNDOFF_RESIDUAL: f64 = 1e-12;
/// The smallest load increment tried, as a fraction of the path from the last equilibrium to
/// the solve's load: below it the solve stops at a limit point.
pub const MIN_INCREMENT: f64 = 1.0 / 1024.0;
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

/// What the large-displacement solver's work cost, over its solves.
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
    /// Load increments halved.
    pub halvings: usize,
    /// Solves started from the prediction extrapolated from the last equilibria.
    pub predicted_starts: usize,
    /// Increments whose equilibrium lay on another branch (rejected, the increment halved).
    pub branch_jumps: usize,
}

/// newton on the exact-length law, set up for one structure.
pub struct LargeNewton<'s> {
    model: &'s Model,
    structure: &'s Structure,
    pattern: &'s StiffnessPattern,
    chol: SparseCholesky,
    settings: NewtonSettings,
    hessian: Vec<f64>,
    /// `chol` holds the factor of an earlier Hessian.
    factored: bool,
    /// Chord steps with that factor still contract the residual enough.
    chord: bool,
    /// The last step was a chord step.
    last_was_chord: bool,
    /// The last equilibrium reached (its load and displacements): where a solve's path starts.
    reached: (Vec<f64>, Vec<f64>),
    /// The equilibria reached before it (the latest last, at most two), for the predictor of
    /// the next solve.
    before: Vec<(Vec<f64>, Vec<f64>)>,
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

/// The iterate of a solve along its load path.
pub struct LargeState {
    /// The path: from `start` (the last equilibrium's load) to `target`.
    start: Vec<f64>,
    target: Vec<f64>,
    /// Fraction of the path at which an equilibrium was reached, and its displacements.
    done: f64,
    u_done: Vec<f64>,
    /// The increment being solved: the path fraction `done + increment`.
    increment: f64,
    load: Vec<f64>,
    u: Vec<f64>,
    eval: Evaluation,
    iteration: usize,
    increment_steps: usize,
    stop: Option<Status>,
    /// Increments of this solve whose equilibrium lay on another branch.
    branch_jumps: usize,
    /// At a limit point: the cables taut at the last equilibrium that went slack in the last
    /// increment tried, when it did not converge (ids).
    slackened: Vec<u64>,
    /// The cables slack at some iterate of the increment being tried.
    slack_on_the_way: Vec<bool>,
    /// The last increment halved was halved for an equilibrium on another branch.
    jumped: bool,
}

impl<'s> LargeNewton<'s> {
    /// Set up on a structure whose `K + K_G(t0)` (the tangent at the prestressed state) is
    /// known to be positive definite: its pattern and symbolic analysis serve every tangent.
    pub fn new(model: &'s Model, taut: &'s TautStiffness, settings: NewtonSettings) -> Self {
        let structure = &model.structure;
        LargeNewton {
            model,
            structure,
            pattern: &taut.pattern,
            chol: taut.factor.share_symbolic(),
            settings,
            hessian: vec![0.0; taut.values.len()],
            factored: false,
            chord: false,
            last_was_chord: false,
            reached: (vec![0.0; structure.n_free], vec![0.0; structure.n_free]),
            before: Vec::new(),
            work: LargeWork::default(),
        }
    }

    /// What the work cost so far.
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

    /// Whether the equilibrium `state.u` at the increment's load lies on the path from the
    /// last one, `state.u_done`: the energy Π at that load is convex along the segment
    /// between them, its slope `ψ(s) = ∇Π(U_done + s d)·d` (`d = U − U_done`) never
    /// decreasing, sampled at [`SEGMENT_SAMPLES`] points. An equilibrium reached across a
    /// region where Π is concave along d (a snap-through past a limit point: a von Mises arch
    /// passing flat) is not on the path. Near an equilibrium of the path Π is convex (its
    /// tangent is positive definite), so a short enough increment along the path passes.
    fn on_the_path(&self, state: &LargeState) -> bool {
        let d: Vec<f64> = state
            .u
            .iter()
            .zip(&state.u_done)
            .map(|(u, v)| u - v)
            .collect();
        let size = norm(&d);
        if size == 0.0 || !size.is_finite() {
            return size == 0.0;
        }
        let load_work = dot(&state.load, &d);
        // ψ(s) = Σ τ ∇ℓ·d − F·d at U_done + s d.
        let slope_at = |fraction: f64| {
            let u: Vec<f64> = state
                .u_done
                .iter()
                .zip(&d)
                .map(|(v, d)| v + fraction * d)
                .collect();
            self.model.internal_slope(&u, &d) - load_work
        };
        let mut previous = slope_at(0.0);
        // Round-off of ψ: each end is an equilibrium to the tolerance only (|∇Π| up to
        // tolerance × scale there), and ψ(0) is −ΔF·d up to that.
        let noise = 10.0 * (self.settings.tolerance + 1e-12) * state.eval.scale * size
            + 1e-6 * previous.abs();
        for k in 1..=SEGMENT_SAMPLES {
            let slope = match k {
                SEGMENT_SAMPLES => dot(&state.eval.gradient, &d),
                _ => slope_at(k as f64 / SEGMENT_SAMPLES as f64),
            };
            if !slope.is_finite() || slope < previous - noise {
                return false;
            }
            previous = slope;
        }
        true
    }

    /// The Newton steps one increment may take: [`INCREMENT_MAX_STEPS`], or the cap when lower.
    fn increment_max_steps(&self) -> usize {
        INCREMENT_MAX_STEPS.min(self.settings.max_iterations).max(1)
    }

    /// `ΔU = −H⁻¹ ∇Π`: a chord step with the last factor while chord steps contract the
    /// residual ([`CHORD_CONTRACTION`]), else with H assembled and factorized, shifted where it
    /// is not positive definite; `None` when no shift up to [`MAX_SHIFT`] makes it factorisable.
    fn newton_step(&mut self, state: &LargeState) -> Option<Vec<f64>> {
        let s = self.structure;
        self.work.steps += 1;
        let rhs: Vec<f64> = state.eval.gradient.iter().map(|g| -g).collect();
        if self.factored && self.chord {
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
            self.factored = false;
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
        self.factored = true;
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

    /// Go on from the equilibrium reached on the path: the next increment, the same size (or
    /// what is left of the path).
    fn advance(&self, state: &mut LargeState) {
        state.done = (state.done + state.increment).min(1.0);
        state.u_done = state.u.clone();
        state.increment = state.increment.min(1.0 - state.done);
        self.begin_increment(state);
    }

    /// Halve the increment and retry it from the last equilibrium, or stop at a limit point.
    fn halve(&mut self, state: &mut LargeState) {
        self.work.halvings += 1;
        // The retry assembles its Hessian: the failed attempt's factor, nearly singular near a
        // limit point, would steer every retry off the path as a chord.
        self.chord = false;
        state.increment *= 0.5;
        if state.increment < MIN_INCREMENT {
            state.stop = Some(Status::LimitPoint);
            let s = self.structure;
            state.u = state.u_done.clone();
            // The answer is the last equilibrium; its stopping value is measured at the
            // solve's load, the α of its row, not at the load where it is an equilibrium.
            state.load = state.target.clone();
            state.eval = self.evaluate(&state.load, &state.u);
            // Cables that went slack on the way of an increment that found no equilibrium (one
            // that found it on another branch says so itself).
            if !state.jumped {
                let done = material::slack_flags(s, &state.eval.trial, SlackRule::Gap);
                state.slackened = s
                    .links
                    .iter()
                    .zip(state.slack_on_the_way.iter().zip(&done))
                    .filter(|(_, (&tried, &done))| tried && !done)
                    .map(|(link, _)| link.id)
                    .collect();
            }
            return;
        }
        state.u = state.u_done.clone();
        self.begin_increment(state);
    }

    /// The load of `done + increment`, evaluated at the current displacements.
    fn begin_increment(&self, state: &mut LargeState) {
        state.increment_steps = 0;
        state.slack_on_the_way.iter_mut().for_each(|x| *x = false);
        state.load = path_load(&state.start, &state.target, state.done + state.increment);
        state.eval = self.evaluate(&state.load, &state.u);
    }

    /// The prediction of the answer at `load` by extrapolating the last equilibria along the
    /// load path (Lagrange, through the last three when there are three, else the secant of the
    /// last two), when their loads and `load` are collinear and `load` lies ahead by at most
    /// four of the last steps.
    fn predict(&self, load: &[f64]) -> Option<Vec<f64>> {
        let (l2, u2) = &self.reached;
        let (l1, u1) = self.before.last()?;
        let step: Vec<f64> = l2.iter().zip(l1).map(|(a, b)| a - b).collect();
        let squared = dot(&step, &step);
        if squared.is_nan() || squared <= 0.0 {
            return None;
        }
        // The path parameter of a load: 0 at the last equilibrium, −1 at the one before.
        let parameter = |l: &[f64]| -> Option<f64> {
            let ahead: Vec<f64> = l.iter().zip(l2).map(|(a, b)| a - b).collect();
            let t = dot(&ahead, &step) / squared;
            let off: f64 = ahead
                .iter()
                .zip(&step)
                .map(|(a, b)| (a - t * b).powi(2))
                .sum();
            (off <= 1e-12 * dot(&ahead, &ahead).max(squared)).then_some(t)
        };
        let t = parameter(load).filter(|&t| t > 0.0 && t <= 4.0)?;
        let mut points: Vec<(f64, &Vec<f64>)> = vec![(-1.0, u1), (0.0, u2)];
        if self.before.len() == 2 {
            let (l0, u0) = &self.before[0];
            if let Some(t0) = parameter(l0).filter(|&t0| t0 < -1.0) {
                points.insert(0, (t0, u0));
            }
        }
        // Lagrange weights at t.
        let weights: Vec<f64> = (0..points.len())
            .map(|i| {
                (0..points.len())
                    .filter(|&j| j != i)
                    .map(|j| (t - points[j].0) / (points[i].0 - points[j].0))
                    .product()
            })
            .collect();
        Some(
            (0..u2.len())
                .map(|k| {
                    points
                        .iter()
                        .zip(&weights)
                        .map(|((_, u), w)| w * u[k])
                        .sum()
                })
                .collect(),
        )
    }

    /// r(U) and its load-relative form both at or below the tolerance (with every cable slack
    /// the load-relative scale holds the released prestress and alone could pass a state far
    /// from equilibrium).
    fn converged(&self, eval: &Evaluation) -> bool {
        eval.load_residual.max(eval.residual) <= self.settings.tolerance
    }

    /// After a step or a new increment: an equilibrium at the increment's load either ends the
    /// solve (at the target) or moves the path on.
    fn settle(&mut self, state: &mut LargeState) {
        while state.stop.is_none() && self.converged(&state.eval) {
            if !self.on_the_path(state) {
                // An equilibrium on another branch: the path is not followed across.
                state.branch_jumps += 1;
                self.work.branch_jumps += 1;
                state.jumped = true;
                self.halve(state);
                continue;
            }
            if state.done + state.increment >= 1.0 {
                state.stop = Some(Status::Converged);
                let reached = (state.target.clone(), state.u.clone());
                let previous = std::mem::replace(&mut self.reached, reached);
                if self.before.len() == 2 {
                    self.before.remove(0);
                }
                self.before.push(previous);
            } else {
                self.advance(state);
            }
        }
    }
}

/// The load at fraction θ of the path from `start` to `target`.
fn path_load(start: &[f64], target: &[f64], theta: f64) -> Vec<f64> {
    start
        .iter()
        .zip(target)
        .map(|(a, b)| a + theta * (b - a))
        .collect()
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

    /// The path's own limits end every solve first (at most [`INCREMENT_MAX_STEPS`] steps
    /// for each of at most `1 / MIN_INCREMENT` increments and their halvings): the cap
    /// `solver.max_iterations` bounds each increment instead
    /// (`LargeNewton::increment_max_steps`), so a limit point is never reported as a cap.
    fn max_iterations(&self) -> usize {
        let halvings = MIN_INCREMENT.recip().log2() as usize + 1;
        (MIN_INCREMENT.recip() as usize + halvings + 1) * INCREMENT_MAX_STEPS
    }

    /// From the last equilibrium reached, the whole path in one increment first, started from
    /// the extrapolation of the last equilibria (`LargeNewton::predict`; paper case, 41-α
    /// sweep with Newton steps: 2.63 steps per α with the secant instead of 3.39 from the last
    /// answer, though the secant's residual is often the larger; with chord steps, 3.41 steps
    /// per α through three points against 3.95 with the secant).
    fn init(&mut self, load: &[f64]) -> LargeState {
        let (start, u_done) = self.reached.clone();
        // The prediction when it evaluates to finite numbers, else the last equilibrium.
        let predicted = self
            .predict(load)
            .map(|u| {
                let eval = self.evaluate(load, &u);
                (u, eval)
            })
            .filter(|(_, eval)| eval.load_residual.is_finite());
        let (u, eval) = match predicted {
            Some(start) => {
                self.work.predicted_starts += 1;
                start
            }
            None => {
                let eval = self.evaluate(load, &u_done);
                (u_done.clone(), eval)
            }
        };
        let mut state = LargeState {
            start,
            target: load.to_vec(),
            done: 0.0,
            u_done,
            increment: 1.0,
            load: load.to_vec(),
            u,
            eval,
            iteration: 0,
            increment_steps: 0,
            stop: None,
            branch_jumps: 0,
            slackened: Vec::new(),
            slack_on_the_way: vec![false; self.structure.links.len()],
            jumped: false,
        };
        self.settle(&mut state);
        state
    }

    /// The path always starts from this solver's own last equilibrium (the previous α's answer
    /// when the sweep's α increase): `previous` is not needed.
    fn warm_init(&mut self, load: &[f64], _previous: &Equilibrium) -> LargeState {
        self.init(load)
    }

    /// One Newton step at the increment's load; an increment that does not converge within
    /// [`INCREMENT_MAX_STEPS`] steps (or whose step is no descent) is halved.
    fn next_iter(&mut self, state: &mut LargeState) {
        state.iteration += 1;
        state.increment_steps += 1;
        let stepped = self
            .newton_step(state)
            .and_then(|step| self.line_search(state, &step).map(|found| (step, found)));
        match stepped {
            Some((step, (length, eval))) => {
                state
                    .u
                    .iter_mut()
                    .zip(&step)
                    .for_each(|(u, d)| *u += length * d);
                // A chord step that contracted the residual by less than CHORD_CONTRACTION:
                // the next step refactorizes.
                if self.last_was_chord
                    && eval.load_residual > CHORD_CONTRACTION * state.eval.load_residual
                {
                    self.chord = false;
                }
                state.eval = eval;
                // Slack with its gap open: a cable at τ = 0 with a closed gap is not.
                let slack =
                    material::slack_flags(self.structure, &state.eval.trial, SlackRule::Gap);
                state
                    .slack_on_the_way
                    .iter_mut()
                    .zip(slack)
                    .for_each(|(seen, now)| *seen |= now);
                self.settle(state);
                if state.stop.is_none() && state.increment_steps >= self.increment_max_steps() {
                    if state.eval.residual <= ROUNDOFF_RESIDUAL {
                        // At round-off (a load tiny against the prestress, or a tolerance f64
                        // does not resolve): no smaller increment would do better. On the way,
                        // the path goes on from here; at the load, the solve has stalled.
                        if state.done + state.increment >= 1.0 {
                            state.stop = Some(Status::Stalled);
                        } else {
                            self.advance(state);
                        }
                    } else {
                        state.jumped = false;
                        self.halve(state);
                        self.settle(state);
                    }
                }
            }
            None => {
                state.jumped = false;
                self.halve(state);
                self.settle(state);
            }
        }
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
            stop: state.stop,
        }
    }

    fn load_path(&self, state: &LargeState) -> Option<LoadPathEnd> {
        Some(LoadPathEnd {
            reached: match state.stop {
                Some(Status::Converged) => 1.0,
                _ => state.done,
            },
            branch_jumps: state.branch_jumps,
            slackened: state.slackened.clone(),
            increment_steps: self.increment_max_steps(),
        })
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
