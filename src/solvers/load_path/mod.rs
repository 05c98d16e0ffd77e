//! The load path (docs/method.md §8): a solver for one load, driven from the last equilibrium
//! reached to each new load in increments. Any solver that can start from given displacements
//! and say where its iterate stands ([`PathSolver`]) sits in it; `large` is newton on the
//! exact-length law in a [`LoadPath`].
//!
//! A solve starts from the last equilibrium this path reached (the prestressed state, U = 0
//! under no load, at first) and walks to its load in increments, first the whole way, started
//! from the extrapolation of the last equilibria ([`prediction`]). An increment that does not
//! converge within [`INCREMENT_MAX_STEPS`] steps is halved and retried from the last
//! equilibrium; one that converged in at most [`GROWTH_STEPS`] steps is followed by one twice
//! its size. The smallest increment is a load, not a fraction of the path: [`SMALLEST_INCREMENT`]
//! of the structure's unit load, or [`LIMIT_TOLERANCE`] of the load reached when that is
//! larger — the same whatever α a solve is asked for and whatever α came before it (N-D1: a
//! fraction of the path made α = 0.25 asked alone end at a limit point at α = 0 that a sweep of
//! small steps passed). An increment that fails at that size ends the solve at a limit point
//! ([`Status::LimitPoint`]), never as converged: the limit lies between the last equilibrium
//! and that increment's load, located to [`LIMIT_TOLERANCE`] of its load. The limit located is
//! kept: a later solve beyond it from the same equilibrium ends there at once, with the same
//! limit (L1: it was located anew, 2.1289 to 2.1338, for every α past the arch's 2.13409).
//!
//! A retry has the solver forget the tangent it factorized (nearly singular near a limit point,
//! it is no chord for the retry). An increment's equilibrium is accepted only when it lies on
//! the path: the energy at the increment's load is convex along the segment from the last
//! equilibrium to it (`LoadPath::on_the_path`); one reached across a region where it is not
//! (past a limit point, on a snapped-through branch) is rejected and the increment halved, so
//! that a solve's verdict depends on its load alone, not on the α before it. An iterate at the
//! round-off of the prestress's balance ([`Balance::AtRoundOff`]: a load too small for the
//! tolerance to resolve) is accepted once the solver can go no further there: the answer at
//! round-off, said so, never a limit point (R5-5).

mod branch;
mod prediction;

use super::{Balance, Equilibrium, LoadPathEnd, Measure, NoEquilibrium, Progress, Solver, Status};
use crate::linalg::norm;
use crate::model::material::{slack_flags, SlackRule};
use crate::model::Model;
use branch::distance;
use prediction::{ray_parameter, LocatedLimit, Reached};

/// Steps one load increment may take before it is halved (fewer when the solver's own cap,
/// `solver.max_iterations`, is smaller: along a path the cap is per increment).
pub const INCREMENT_MAX_STEPS: usize = 30;
/// An increment that converged in at most this many steps is followed by one twice its size.
pub const GROWTH_STEPS: usize = 6;
/// An increment whose r(U) is at or below this after [`INCREMENT_MAX_STEPS`] steps without
/// meeting the tolerance sits at round-off: the solve ends `Stalled` rather than halving.
const ROUNDOFF_RESIDUAL: f64 = 1e-12;
/// The smallest load increment tried, as a fraction of the structure's unit load (its load
/// at α = 1, `‖F‖`): below it the solve stops at a limit point.
pub const SMALLEST_INCREMENT: f64 = 1e-6;
/// How closely a limit point is located: an increment is not halved below this fraction of the
/// load of the last equilibrium (when larger than [`SMALLEST_INCREMENT`]), so the last
/// equilibrium found and the load where none was are this close.
pub const LIMIT_TOLERANCE: f64 = 1e-4;
/// The smallest increment, as a fraction of the path, after a failure of the solver's own.
const OWN_FAILURE_INCREMENT: f64 = 1.0 / 64.0;
/// Increments (accepted, halved or rejected) one solve may try: a cap that ends a path that
/// does not end otherwise as [`Status::MaxIterations`].
const MAX_INCREMENTS: usize = 4000;

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
    /// Where the state stands against the solver's stop: an equilibrium at its load to the
    /// solver's tolerances, at round-off, or neither.
    pub balance: Balance,
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
    /// Solves ended at once at a limit point located by an earlier solve of the path.
    pub limits_reused: usize,
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
    /// The smallest increment tried that found no equilibrium (path fraction): at a limit
    /// point, the limit lies in `(done, done + failed]`.
    failed: Option<f64>,
    /// Increments tried.
    increments: usize,
    /// The equilibrium at the solve's load is one at round-off ([`Balance::AtRoundOff`]).
    at_roundoff: bool,
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

    /// `solver` on a load path that starts at displacements `u` under `load` (a construction
    /// stage, from where the last one left the structure): the first solve goes from there.
    pub fn starting_at(solver: S, load: Vec<f64>, u: Vec<f64>) -> Self {
        let mut path = LoadPath::new(solver);
        path.reached.last = (load, u);
        path
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

    /// The smallest increment at the last equilibrium, as a fraction of the path:
    /// [`SMALLEST_INCREMENT`] of the unit load, or [`LIMIT_TOLERANCE`] of the load reached when
    /// that is larger (1 when the path has no length).
    fn smallest_increment(&self, state: &PathState<S::State>) -> f64 {
        let span = distance(&state.target, &state.start);
        if span == 0.0 || !span.is_finite() {
            return 1.0;
        }
        let reached: Vec<f64> = (state.start.iter().zip(&state.target))
            .map(|(a, b)| a + state.done * (b - a))
            .collect();
        // The unit load; a structure loaded by settlements alone has none: the path's end.
        let unit = match norm(&self.solver.structure().unit_load) {
            0.0 => norm(&state.start).max(norm(&state.target)),
            unit => unit,
        };
        (SMALLEST_INCREMENT * unit).max(LIMIT_TOLERANCE * norm(&reached)) / span
    }

    /// Go on from the equilibrium reached on the path: the next increment, twice the size when
    /// this one converged in at most [`GROWTH_STEPS`] steps, at most what is left of the path.
    fn advance(&mut self, state: &mut PathState<S::State>) {
        state.done = (state.done + state.increment).min(1.0);
        state.u_done = self.solver.point(&state.step).displacements.to_vec();
        if state.increment_steps <= GROWTH_STEPS {
            state.increment *= 2.0;
        }
        state.increment = state.increment.min(1.0 - state.done);
        let u = state.u_done.clone();
        self.begin_increment(state, u);
    }

    /// Halve the increment and retry it from the last equilibrium, or stop at a limit point
    /// when the increment that failed was already the smallest. An increment that failed for
    /// the solver's own reason (an inner solve short of its forcing term) is not halved below
    /// [`OWN_FAILURE_INCREMENT`] of the path: the solve has stalled, and halving on to the
    /// smallest increment only spent time (the tower of N-D3 under mono-latin: 3 710 steps).
    fn halve(&mut self, state: &mut PathState<S::State>) {
        self.work.halvings += 1;
        // An equilibrium found on another branch is the structure's answer, whoever found it.
        let own_failure = self.solver.failed_on_its_own() && !state.jumped;
        // The retry assembles its tangent: the failed attempt's factor, nearly singular near a
        // limit point, would steer every retry off the path as a chord.
        self.solver.forget_tangent();
        state.failed = Some(state.increment);
        let smallest = self.smallest_increment(state);
        // A path shorter than the smallest increment cannot be halved to locate anything: its
        // failure is no limit point (a grid without prestress at α = 1e-9 under `large`, or
        // a settlement with no load to follow).
        let unresolved = smallest >= 1.0 && state.done == 0.0;
        let smallest = match own_failure {
            true => smallest.max(OWN_FAILURE_INCREMENT),
            false => smallest,
        };
        if state.increment <= smallest || state.increments >= MAX_INCREMENTS {
            // The halvings found no equilibrium: a limit point of the structure, unless the
            // solver's own steps failed on the way (it cannot tell), the path is too short to
            // halve, or it ran out of increments before locating anything.
            state.stop = Some(
                match (
                    own_failure || unresolved,
                    state.increments >= MAX_INCREMENTS,
                ) {
                    (_, true) => Status::MaxIterations,
                    (true, false) => Status::Stalled,
                    (false, false) => Status::LimitPoint,
                },
            );
            // The answer is the last equilibrium; its stopping value is measured at the
            // solve's load, the α of its row, not at the load where it is an equilibrium.
            let beyond = self.fraction_of(state, state.done + state.increment);
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
            if state.stop == Some(Status::LimitPoint) {
                self.reached.limit = Some(LocatedLimit {
                    from: state.start.clone(),
                    equilibrium: self.fraction_of(state, state.done),
                    beyond,
                    u: state.u_done.clone(),
                    branch_jumps: state.branch_jumps,
                    slackened: state.slackened.clone(),
                });
            }
            return;
        }
        state.increment *= 0.5;
        let u = state.u_done.clone();
        self.begin_increment(state, u);
    }

    /// The load at fraction `theta` of the path of `state`: `F_start + θ (F_target − F_start)`.
    fn fraction_of(&self, state: &PathState<S::State>, theta: f64) -> Vec<f64> {
        (state.start.iter().zip(&state.target))
            .map(|(a, b)| a + theta * (b - a))
            .collect()
    }

    /// The load of `done + increment`, the solver's state there at displacements `u`.
    fn begin_increment(&mut self, state: &mut PathState<S::State>, u: Vec<f64>) {
        state.increment_steps = 0;
        state.increments += 1;
        state.slack_on_the_way.iter_mut().for_each(|x| *x = false);
        state.load = self.fraction_of(state, state.done + state.increment);
        state.step = self.solver.state_at(&state.load, u);
    }

    /// After a step or a new increment: an equilibrium at the increment's load either ends the
    /// solve (at the target) or moves the path on. With `can_go_no_further` (the step failed,
    /// or the increment's steps are spent), an iterate at round-off is one.
    fn settle(&mut self, state: &mut PathState<S::State>, can_go_no_further: bool) {
        loop {
            let balance = self.solver.point(&state.step).balance;
            let at_roundoff = balance == Balance::AtRoundOff && can_go_no_further;
            if state.stop.is_some() || !(balance == Balance::Met || at_roundoff) {
                return;
            }
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
                state.at_roundoff = at_roundoff;
                let u = self.solver.point(&state.step).displacements.to_vec();
                self.reached.record(state.target.clone(), u);
                return;
            }
            self.advance(state);
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
        let spent = state.increment_steps >= self.increment_max_steps();
        self.settle(state, spent);
        if state.stop.is_none() && spent {
            if self.solver.point(&state.step).residual <= ROUNDOFF_RESIDUAL {
                // At round-off for a tolerance f64 does not resolve (below the prestress's
                // round-off itself): no smaller increment would do better. On the way, the
                // path goes on from here; at the load, the solve has stalled.
                if state.done + state.increment >= 1.0 {
                    state.stop = Some(Status::Stalled);
                } else {
                    self.advance(state);
                }
            } else {
                state.jumped = false;
                self.halve(state);
                self.settle(state, false);
            }
        }
    }

    /// A solve to `load` that ends at once at the limit point an earlier solve located, when
    /// `load` lies beyond it on the same path from the same last equilibrium.
    fn beyond_located_limit(&mut self, load: &[f64]) -> Option<PathState<S::State>> {
        let limit = self.reached.limit.as_ref()?;
        let (start, _) = &self.reached.last;
        if start != &limit.from || ray_parameter(start, &limit.beyond, load)? < 1.0 {
            return None;
        }
        let span = distance(load, start);
        let done = distance(&limit.equilibrium, start) / span;
        let increment = distance(&limit.beyond, start) / span - done;
        let limit = limit.clone();
        self.work.limits_reused += 1;
        let step = self.solver.state_at(load, limit.u.clone());
        Some(PathState {
            start: start.clone(),
            target: load.to_vec(),
            done,
            u_done: limit.u,
            increment,
            load: load.to_vec(),
            failed: Some(increment),
            increments: 0,
            at_roundoff: false,
            step,
            iteration: 0,
            increment_steps: 0,
            stop: Some(Status::LimitPoint),
            branch_jumps: limit.branch_jumps,
            slackened: limit.slackened,
            slack_on_the_way: Vec::new(),
            jumped: limit.branch_jumps > 0,
        })
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
    /// for each of at most `MAX_INCREMENTS` increments): the solver's cap
    /// (`solver.max_iterations`) bounds each increment instead
    /// (`LoadPath::increment_max_steps`), so a limit point is never reported as a cap.
    fn max_iterations(&self) -> usize {
        (MAX_INCREMENTS + 1) * INCREMENT_MAX_STEPS
    }

    /// From the last equilibrium reached, the whole path in one increment first, started from
    /// the extrapolation of the last equilibria (`Reached::predict`; paper case, 41-α sweep
    /// with Newton steps: 2.63 steps per α with the secant instead of 3.39 from the last
    /// answer, though the secant's residual is often the larger; with chord steps, 3.41 steps
    /// per α through three points against 3.95 with the secant).
    fn init(&mut self, load: &[f64]) -> Self::State {
        if let Some(state) = self.beyond_located_limit(load) {
            return state;
        }
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
            failed: None,
            increments: 1,
            at_roundoff: false,
            step,
            iteration: 0,
            increment_steps: 0,
            stop: None,
            branch_jumps: 0,
            slackened: Vec::new(),
            slack_on_the_way: vec![false; self.solver.structure().links.len()],
            jumped: false,
        };
        self.settle(&mut state, false);
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
        let point = self.solver.point(&state.step);
        if point.failed && point.balance == Balance::AtRoundOff {
            // No step does better than round-off: the answer there, when on the path.
            self.settle(state, true);
        }
        if state.stop.is_none() && self.solver.point(&state.step).failed {
            state.jumped = false;
            self.halve(state);
            self.settle(state, false);
        } else if state.stop.is_none() {
            self.after_step(state);
        }
    }

    /// The solver's view of its iterate, at the path's iteration count and stop.
    fn progress(&self, state: &Self::State) -> Progress {
        Progress {
            iteration: state.iteration,
            stop: state.stop,
            at_roundoff: state.at_roundoff,
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
            limit_bracket: match state.stop {
                Some(Status::LimitPoint) => state.failed,
                _ => None,
            },
            limit_alpha: None,
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
