//! The one driver of every solver: it owns the loop, the iteration cap, the timing and the
//! calls to the observer.
//!
//! ```text
//! state ← init(load), or warm_init(load, previous answer)
//! loop:
//!     report the iterate (with e when a reference is given) to the observer
//!     stop when the solver says so (converged or stalled), or at max_iterations
//!     at iterations 16, 32, 64, …: stop when the iterate has run away (no equilibrium)
//!     next_iter(state)
//! answer ← iterate(state)
//! ```
//!
//! The clock runs only while the solver works (`init`, `next_iter`, the final `iterate`):
//! measuring e and the observers' own work are not charged to the solve.

use super::{
    Equilibrium, IterationRecord, Measure, Observer, Reference, Solution, SolveInfo, Solver, Status,
};
use std::time::{Duration, Instant};

/// The first iteration at which the driver checks an iterate for no equilibrium (then at every
/// power of two).
const RUNAWAY_FIRST_CHECK: usize = 16;

/// Solver time, accumulated over the calls it times.
#[derive(Default)]
struct Stopwatch(Duration);

impl Stopwatch {
    fn time<T>(&mut self, work: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = work();
        self.0 += start.elapsed();
        out
    }

    fn seconds(&self) -> f64 {
        self.0.as_secs_f64()
    }
}

/// Drive `solver` from `init` to its stop for `load` (free dofs, N). With `reference`, every
/// iterate's energy error e is measured and reported.
pub fn drive<S: Solver + ?Sized>(
    solver: &mut S,
    load: &[f64],
    reference: Option<&Reference>,
    observer: &mut dyn Observer,
) -> Solution {
    drive_from(solver, load, None, reference, observer)
}

/// [`drive`], started from `warm` (a previous answer of the same solver on the same
/// structure, [`Solver::warm_init`]) when given.
pub fn drive_from<S: Solver + ?Sized>(
    solver: &mut S,
    load: &[f64],
    warm: Option<&Equilibrium>,
    reference: Option<&Reference>,
    observer: &mut dyn Observer,
) -> Solution {
    let mut clock = Stopwatch::default();
    let mut state = clock.time(|| match warm {
        Some(previous) => solver.warm_init(load, previous),
        None => solver.init(load),
    });
    let mut last_checked: Option<Vec<f64>> = None;
    let mut runaway = None;
    let (status, progress) = loop {
        let progress = solver.progress(&state);
        // A start guess that is no iterate of the method is reported only when the solve ends
        // on it (converged at iteration 0): a history is never a header alone (issue 42, M11).
        if progress.iteration > 0 || S::INIT_IS_ITERATE || progress.stop.is_some() {
            observer.iteration(&IterationRecord {
                iteration: progress.iteration,
                stopping_value: progress.stopping_value,
                equilibrium_residual: progress.equilibrium_residual,
                rebuilds: progress.rebuilds,
                error: reference.map(|r| r.error(&solver.elongations(&state))),
                slack_cables: progress.slack_cables,
                elapsed_seconds: clock.seconds(),
            });
        }
        if let Some(status) = progress.stop {
            break (status, progress);
        }
        if progress.iteration >= solver.max_iterations() {
            break (Status::MaxIterations, progress);
        }
        if let Some(found) = solver.runaway(&state) {
            runaway = Some(found);
            break (Status::NoEquilibrium, progress);
        }
        // No equilibrium: the iterates run away along a mechanism the load works on. Asked
        // at iterations 16, 32, 64, … of the change since the last check (the runaway
        // direction, free of the part that converges): a solver never spins to its cap, at the
        // cost of a few iterates.
        if progress.iteration >= RUNAWAY_FIRST_CHECK && progress.iteration.is_power_of_two() {
            let mut iterate = clock.time(|| solver.iterate(&state));
            let displacements = iterate.displacements.clone();
            if let Some(last) = &last_checked {
                iterate
                    .displacements
                    .iter_mut()
                    .zip(last)
                    .for_each(|(u, v)| *u -= v);
            }
            if let Some(found) = solver.no_equilibrium_along(&iterate.displacements, load) {
                runaway = Some(found);
                break (Status::NoEquilibrium, progress);
            }
            last_checked = Some(displacements);
        }
        clock.time(|| solver.next_iter(&mut state));
    };
    let equilibrium: Equilibrium = clock.time(|| solver.iterate(&state));
    let load_path = solver.load_path(&state);
    Solution {
        equilibrium,
        info: SolveInfo {
            status,
            iterations: progress.iteration,
            measure: solver.measure(),
            stopping_value: progress.stopping_value,
            rebuilds: progress.rebuilds,
            krylov_iterations: progress.krylov_iterations,
            solve_seconds: clock.seconds(),
            at_roundoff: status == Status::Converged && progress.at_roundoff,
            no_equilibrium: runaway,
            load_path,
        },
    }
}

/// A solver of any kind behind one object-safe interface: what the application holds in a
/// list. Every [`Solver`] is one, solved through [`drive`].
pub trait AnySolver {
    /// Solve for `load` through the driver from a cold start (see [`drive`]).
    fn solve(
        &mut self,
        load: &[f64],
        reference: Option<&Reference>,
        observer: &mut dyn Observer,
    ) -> Solution {
        self.solve_from(load, None, reference, observer)
    }

    /// [`AnySolver::solve`] warm-started from `warm` when given (see [`drive_from`]).
    fn solve_from(
        &mut self,
        load: &[f64],
        warm: Option<&Equilibrium>,
        reference: Option<&Reference>,
        observer: &mut dyn Observer,
    ) -> Solution;

    /// What the solver's stopping measure measures.
    fn stopping_measure(&self) -> Measure;

    /// The no-equilibrium certificate along `u` ([`Solver::no_equilibrium_along`]).
    fn no_equilibrium_along(&self, u: &[f64], load: &[f64]) -> Option<super::NoEquilibrium>;
}

impl<S: Solver> AnySolver for S {
    fn solve_from(
        &mut self,
        load: &[f64],
        warm: Option<&Equilibrium>,
        reference: Option<&Reference>,
        observer: &mut dyn Observer,
    ) -> Solution {
        drive_from(self, load, warm, reference, observer)
    }

    fn stopping_measure(&self) -> Measure {
        self.measure()
    }

    fn no_equilibrium_along(&self, u: &[f64], load: &[f64]) -> Option<super::NoEquilibrium> {
        Solver::no_equilibrium_along(self, u, load)
    }
}
