//! The load path (docs/method.md §8): a solver for one load, driven from the last equilibrium
//! reached to each new load in increments. Any solver that can start from given displacements
//! and say where its iterate stands ([`PathSolver`]) sits in it; `large` is newton on the
//! exact-length law in a [`LoadPath`].
//!
//! A solve starts from the last equilibrium this path reached (the prestressed state, U = 0
//! under no load, at first) and walks to its load in increments, first the whole way, started
//! from the extrapolation of the last equilibria ([`prediction`]). An increment that does not
//! converge within [`INCREMENT_MAX_STEPS`] steps is halved and retried from the last
//! equilibrium, down to [`MIN_INCREMENT`] of the path, below which the solve ends at a limit
//! point ([`Status::LimitPoint`]), never as converged. A retry has the solver forget the
//! tangent it factorized (nearly singular near a limit point, it is no chord for the retry). An
//! increment's equilibrium is accepted only when it lies on the path: the energy at the
//! increment's load is convex along the segment from the last equilibrium to it
//! (`LoadPath::on_the_path`); one reached across a region where it is not (past a limit point,
//! on a snapped-through branch) is rejected and the increment halved, so that a solve's verdict
//! depends on its load alone, not on the α before it. Loads beyond a limit point of the path
//! end `LimitPoint`, whatever the α list.

mod prediction;

use super::{Equilibrium, LoadPathEnd, Measure, NoEquilibrium, Progress, Solver, Status};
use crate::linalg::{dot, norm};
use crate::model::material::{slack_flags, SlackRule};
use crate::model::Model;
use prediction::Reached;

/// Steps one load increment may take before it is halved (fewer when the solver's own cap,
/// `solver.max_iterations`, is smaller: along a path the cap is per increment).
pub const INCREMENT_MAX_STEPS: usize = 30;
/// Points (besides the last equilibrium) at which the slope of the energy along an
/// increment's segment is sampled for `LoadPath::on_the_path`.
const SEGMENT_SAMPLES: usize = 4;
/// An increment whose r(U) is at or below this after [`INCREMENT_MAX_STEPS`] steps without
/// meeting the tolerance sits at round-off: the solve ends `Stalled` rather than halving.
const ROUNDOFF_RESIDUAL: f64 = 1e-12;
/// The smallest load increment tried, as a fraction of the path from the last equilibrium to
/// the solve's load: below it the solve stops at a limit point.
pub const MIN_INCREMENT: f64 = 1.0 / 1024.0;

/// A solver that can sit in a [`LoadPath`]: it solves one load from given displacements, and
/// says of its iterate what the path reads.
pub trait PathSolver: Solver {
    /// The state at displacements `u` under `load`, evaluated, no step taken: where an
    /// increment starts.
    fn state_at(&mut self, load: &[f64], u: Vec<f64>) -> Self::State;

    /// Forget the tangent earlier steps factorized: a retried increment assembles its own.
    fn forget_tangent(&mut self);

    /// The relative residual the solver stops on.
    fn tolerance(&self) -> f64;

    /// Whether the solver's last steps failed for a reason of its own (an inner solve that
    /// did not converge), not the structure's: a path that cannot go on then ends
    /// [`Status::Stalled`], not at a limit point. By default never.
    fn failed_on_its_own(&self) -> bool {
        false
    }

    /// What the path reads of `state`.
    fn point<'a>(&self, state: &'a Self::State) -> PathPoint<'a>;
}

/// What a [`LoadPath`] reads of an iterate of the solver in it.
#[derive(Debug, Clone, Copy)]
pub struct PathPoint<'a> {
    /// Displacements U on the free dofs.
    pub displacements: &'a [f64],
    /// The energy's gradient at U under the state's load, `∇Π(U) = Bᵀτ − F` (along the
    /// current `∇ℓ` with `large`).
    pub gradient: &'a [f64],
    /// The trial tensions `t0 + k e` at U (before a cable's clipping).
    pub trial: &'a [f64],
    /// r(U), the relative equilibrium residual.
    pub residual: f64,
    /// r(U)'s scale, `‖F‖ + ‖|B|ᵀ|τ|‖`, N.
    pub scale: f64,
    /// The state is an equilibrium at its load to the solver's tolerance.
    pub converged: bool,
    /// The last step failed (no descent, or no factorisable tangent): the state is the one
    /// before it.
    pub failed: bool,
}

/// What the load path's stepping did, over its solves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PathWork {
    /// Load increments halved.
    pub halvings: usize,
    /// Solves started from the prediction extrapolated from the last equilibria.
    pub predicted_starts: usize,
    /// Increments whose equilibrium lay on another branch (rejected, the increment halved).
    pub branch_jumps: usize,
}

/// The solver `S` driven along the load path from one solve's load to the next.
pub struct LoadPath<S> {
    solver: S,
    reached: Reached,
    work: PathWork,
}

/// The iterate of a solve along its load path.
pub struct PathState<T> {
    /// The path: from `start` (the last equilibrium's load) to `target`.
    start: Vec<f64>,
    target: Vec<f64>,
    /// Fraction of the path at which an equilibrium was reached, and its displacements.
    done: f64,
    u_done: Vec<f64>,
    /// The increment being solved: the path fraction `done + increment`, its load.
    increment: f64,
    load: Vec<f64>,
    /// The solver's state at the increment's load.
    step: T,
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

impl<S: PathSolver> LoadPath<S> {
    /// `solver` on its load path, which starts at the prestressed state (U = 0, no load).
    pub fn new(solver: S) -> Self {
        let n = solver.structure().n_free;
        LoadPath {
            solver,
            reached: Reached::prestressed(n),
            work: PathWork::default(),
        }
    }

    /// The solver in the path.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    /// What the path's stepping did so far.
    pub fn work(&self) -> PathWork {
        self.work
    }

    /// The steps one increment may take: [`INCREMENT_MAX_STEPS`], or the solver's cap when
    /// lower.
    fn increment_max_steps(&self) -> usize {
        INCREMENT_MAX_STEPS.min(self.solver.max_iterations()).max(1)
    }

    /// Whether the equilibrium of `state` at the increment's load lies on the path from the
    /// last one, `state.u_done`: the energy Π at that load is convex along the segment
    /// between them, its slope `ψ(s) = ∇Π(U_done + s d)·d` (`d = U − U_done`) never
    /// decreasing, sampled at [`SEGMENT_SAMPLES`] points. An equilibrium reached across a
    /// region where Π is concave along d (a snap-through past a limit point: a von Mises arch
    /// passing flat) is not on the path. Near an equilibrium of the path Π is convex (its
    /// tangent is positive definite), so a short enough increment along the path passes.
    fn on_the_path(&self, state: &PathState<S::State>) -> bool {
        let point = self.solver.point(&state.step);
        let d: Vec<f64> = point
            .displacements
            .iter()
            .zip(&state.u_done)
            .map(|(u, v)| u - v)
            .collect();
        let size = norm(&d);
        if size == 0.0 || !size.is_finite() {
            return size == 0.0;
        }
        let load_work = dot(&state.load, &d);
        let model: &Model = self.solver.model();
        // ψ(s) = Σ τ ∇ℓ·d − F·d at U_done + s d.
        let slope_at = |fraction: f64| {
            let u: Vec<f64> = state
                .u_done
                .iter()
                .zip(&d)
                .map(|(v, d)| v + fraction * d)
                .collect();
            model.internal_slope(&u, &d) - load_work
        };
        let mut previous = slope_at(0.0);
        // Round-off of ψ: each end is an equilibrium to the tolerance only (|∇Π| up to
        // tolerance × scale there), and ψ(0) is −ΔF·d up to that.
        let noise =
            10.0 * (self.solver.tolerance() + 1e-12) * point.scale * size + 1e-6 * previous.abs();
        for k in 1..=SEGMENT_SAMPLES {
            let slope = match k {
                SEGMENT_SAMPLES => dot(point.gradient, &d),
                _ => slope_at(k as f64 / SEGMENT_SAMPLES as f64),
            };
            if !slope.is_finite() || slope < previous - noise {
                return false;
            }
            previous = slope;
        }
        true
    }

    /// Go on from the equilibrium reached on the path: the next increment, the same size (or
    /// what is left of the path).
    fn advance(&mut self, state: &mut PathState<S::State>) {
        state.done = (state.done + state.increment).min(1.0);
        state.u_done = self.solver.point(&state.step).displacements.to_vec();
        state.increment = state.increment.min(1.0 - state.done);
        let u = state.u_done.clone();
        self.begin_increment(state, u);
    }

    /// Halve the increment and retry it from the last equilibrium, or stop at a limit point.
    fn halve(&mut self, state: &mut PathState<S::State>) {
        self.work.halvings += 1;
        let own_failure = self.solver.failed_on_its_own();
        // The retry assembles its tangent: the failed attempt's factor, nearly singular near a
        // limit point, would steer every retry off the path as a chord.
        self.solver.forget_tangent();
        state.increment *= 0.5;
        if state.increment < MIN_INCREMENT {
            // The halvings found no equilibrium: a limit point of the structure, unless the
            // solver's own steps failed on the way (it cannot tell).
            state.stop = Some(match own_failure {
                true => Status::Stalled,
                false => Status::LimitPoint,
            });
            // The answer is the last equilibrium; its stopping value is measured at the
            // solve's load, the α of its row, not at the load where it is an equilibrium.
            state.load = state.target.clone();
            state.step = self.solver.state_at(&state.load, state.u_done.clone());
            // Cables that went slack on the way of an increment that found no equilibrium (one
            // that found it on another branch says so itself).
            if !state.jumped {
                let s = self.solver.structure();
                let trial = self.solver.point(&state.step).trial;
                let done = slack_flags(s, trial, SlackRule::Gap);
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
        let u = state.u_done.clone();
        self.begin_increment(state, u);
    }

    /// The load of `done + increment`, the solver's state there at displacements `u`.
    fn begin_increment(&mut self, state: &mut PathState<S::State>, u: Vec<f64>) {
        state.increment_steps = 0;
        state.slack_on_the_way.iter_mut().for_each(|x| *x = false);
        // The load at fraction θ of the path: F_start + θ (F_target − F_start).
        let theta = state.done + state.increment;
        state.load = (state.start.iter().zip(&state.target))
            .map(|(a, b)| a + theta * (b - a))
            .collect();
        state.step = self.solver.state_at(&state.load, u);
    }

    /// After a step or a new increment: an equilibrium at the increment's load either ends the
    /// solve (at the target) or moves the path on.
    fn settle(&mut self, state: &mut PathState<S::State>) {
        while state.stop.is_none() && self.solver.point(&state.step).converged {
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
                let u = self.solver.point(&state.step).displacements.to_vec();
                self.reached.record(state.target.clone(), u);
            } else {
                self.advance(state);
            }
        }
    }

    /// After a step that took `state` on: the cables it slackened are remembered, an
    /// equilibrium settled; an increment out of steps ends at round-off, or is halved.
    fn after_step(&mut self, state: &mut PathState<S::State>) {
        let point = self.solver.point(&state.step);
        // Slack with its gap open: a cable at τ = 0 with a closed gap is not.
        let slack = slack_flags(self.solver.structure(), point.trial, SlackRule::Gap);
        state
            .slack_on_the_way
            .iter_mut()
            .zip(slack)
            .for_each(|(seen, now)| *seen |= now);
        self.settle(state);
        if state.stop.is_none() && state.increment_steps >= self.increment_max_steps() {
            if self.solver.point(&state.step).residual <= ROUNDOFF_RESIDUAL {
                // At round-off (a load tiny against the prestress, or a tolerance f64 does
                // not resolve): no smaller increment would do better. On the way, the path
                // goes on from here; at the load, the solve has stalled.
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
}

impl<S: PathSolver> Solver for LoadPath<S> {
    type State = PathState<S::State>;
    const INIT_IS_ITERATE: bool = false;

    fn measure(&self) -> Measure {
        self.solver.measure()
    }

    fn model(&self) -> &Model {
        self.solver.model()
    }

    /// The path's own limits end every solve first (at most [`INCREMENT_MAX_STEPS`] steps
    /// for each of at most `1 / MIN_INCREMENT` increments and their halvings): the solver's
    /// cap (`solver.max_iterations`) bounds each increment instead
    /// (`LoadPath::increment_max_steps`), so a limit point is never reported as a cap.
    fn max_iterations(&self) -> usize {
        let halvings = MIN_INCREMENT.recip().log2() as usize + 1;
        (MIN_INCREMENT.recip() as usize + halvings + 1) * INCREMENT_MAX_STEPS
    }

    /// From the last equilibrium reached, the whole path in one increment first, started from
    /// the extrapolation of the last equilibria (`Reached::predict`; paper case, 41-α sweep
    /// with Newton steps: 2.63 steps per α with the secant instead of 3.39 from the last
    /// answer, though the secant's residual is often the larger; with chord steps, 3.41 steps
    /// per α through three points against 3.95 with the secant).
    fn init(&mut self, load: &[f64]) -> Self::State {
        let (start, u_done) = self.reached.last.clone();
        // The prediction when it evaluates to finite numbers, else the last equilibrium.
        let predicted = self
            .reached
            .predict(load)
            .map(|u| self.solver.state_at(load, u))
            .filter(|step| self.solver.point(step).residual.is_finite());
        let step = match predicted {
            Some(step) => {
                self.work.predicted_starts += 1;
                step
            }
            None => self.solver.state_at(load, u_done.clone()),
        };
        let mut state = PathState {
            start,
            target: load.to_vec(),
            done: 0.0,
            u_done,
            increment: 1.0,
            load: load.to_vec(),
            step,
            iteration: 0,
            increment_steps: 0,
            stop: None,
            branch_jumps: 0,
            slackened: Vec::new(),
            slack_on_the_way: vec![false; self.solver.structure().links.len()],
            jumped: false,
        };
        self.settle(&mut state);
        state
    }

    /// The path always starts from its own last equilibrium (the previous α's answer when the
    /// sweep's α increase): `previous` is not needed.
    fn warm_init(&mut self, load: &[f64], _previous: &Equilibrium) -> Self::State {
        self.init(load)
    }

    /// One step of the solver at the increment's load; an increment that does not converge
    /// within [`INCREMENT_MAX_STEPS`] steps (or whose step fails) is halved.
    fn next_iter(&mut self, state: &mut Self::State) {
        state.iteration += 1;
        state.increment_steps += 1;
        self.solver.next_iter(&mut state.step);
        if self.solver.point(&state.step).failed {
            state.jumped = false;
            self.halve(state);
            self.settle(state);
        } else {
            self.after_step(state);
        }
    }

    /// The solver's view of its iterate, at the path's iteration count and stop.
    fn progress(&self, state: &Self::State) -> Progress {
        Progress {
            iteration: state.iteration,
            stop: state.stop,
            ..self.solver.progress(&state.step)
        }
    }

    fn load_path(&self, state: &Self::State) -> Option<LoadPathEnd> {
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

    fn elongations(&self, state: &Self::State) -> Vec<f64> {
        self.solver.elongations(&state.step)
    }

    fn iterate(&self, state: &Self::State) -> Equilibrium {
        self.solver.iterate(&state.step)
    }

    fn no_equilibrium_along(&self, u: &[f64], load: &[f64]) -> Option<NoEquilibrium> {
        self.solver.no_equilibrium_along(u, load)
    }
}
