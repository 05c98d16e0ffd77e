//! The measurement: every solver of a case at every α, each iterate's (wall time, e) from one
//! driven solve against a reference solved by the case's reference solver
//! (`solver.reference`).

use super::BenchError;
use crate::app::setup::{set_up, Prepared};
use crate::case::{Case, SolverChoice};
use crate::output::alpha_label;
use crate::results::uniqueness::Uniqueness;
use crate::solvers::{Equilibrium, Method, Recorder, Reference, SetupError, Silent, Status};

/// One iterate of one solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Iterations done.
    pub iteration: usize,
    /// Wall time since the start of the solver's set-up, s.
    pub seconds: f64,
    /// Energy error e against the reference.
    pub error: f64,
}

/// Every iterate of one solver at one α.
#[derive(Debug, Clone)]
pub struct Series {
    /// The solver.
    pub method: Method,
    /// The load factor.
    pub alpha: f64,
    /// Its set-up time, s.
    pub setup_seconds: f64,
    /// How its solve ended.
    pub status: Status,
    /// In increasing iteration and time.
    pub samples: Vec<Sample>,
}

impl Series {
    /// Wall time (set-up included) of the first iterate with e ≤ `threshold`.
    pub fn seconds_to_reach(&self, threshold: f64) -> Option<f64> {
        self.samples
            .iter()
            .find(|s| s.error <= threshold)
            .map(|s| s.seconds)
    }

    /// e of the last iterate.
    pub fn final_error(&self) -> Option<f64> {
        self.samples.last().map(|s| s.error)
    }
}

/// What `bench` measured.
#[derive(Debug, Clone)]
pub struct Bench {
    /// Per α, per solver in the case's order.
    pub series: Vec<Series>,
    /// Time to reach each error level, per solver and α.
    pub table: super::Table,
}

impl Bench {
    /// `Err(NotConverged)` when a solver stopped before its criterion.
    pub fn check_converged(&self) -> Result<(), BenchError> {
        let failures: Vec<String> = self
            .series
            .iter()
            .filter(|s| !s.status.converged())
            .map(|s| {
                format!(
                    "{} at alpha = {} ({:?})",
                    s.method.name(),
                    alpha_label(s.alpha),
                    s.status
                )
            })
            .collect();
        if failures.is_empty() {
            Ok(())
        } else {
            Err(BenchError::NotConverged {
                count: failures.len(),
                list: failures.join(", "),
            })
        }
    }
}

/// What `measure` is doing, for progress displays.
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// Solving the reference at α.
    Reference {
        /// The reference solver.
        method: Method,
        /// The load factor.
        alpha: f64,
    },
    /// Set-up and timed solve of a solver at α.
    Solve {
        /// The solver.
        method: Method,
        /// The load factor.
        alpha: f64,
    },
    /// A solver at α is measured.
    Done(&'a Series),
    /// The reference at α is one of several equilibria of the same energy (its `unique` would
    /// read `false` in `run`): e against it says how far an answer is from that one.
    ReferenceNotUnique {
        /// The load factor.
        alpha: f64,
        /// The nodes the free motion moves most, as `run`'s warning names them.
        nodes: &'a str,
    },
}

/// As `run` judges it: an answer on the initial geometry moving a node by more than the
/// structure's size is beyond the model, converged or not (review turn 4, R9).
fn mark_beyond_model(prepared: &Prepared, solution: &mut crate::solvers::Solution) {
    if crate::results::beyond_model(&prepared.model, &solution.equilibrium) {
        solution.info.status = Status::BeyondModel;
    }
}

/// The solver bench measures e against: the case's `solver.reference`, as `run` takes it;
/// `"none"` is refused ([`BenchError::NoReference`]), since e is what bench measures.
pub fn reference_method(case: &Case) -> Result<Method, BenchError> {
    case.solver
        .reference
        .method()
        .ok_or(BenchError::NoReference)
}

/// The reference at one α: `method` at its default (tight) settings, and its answer; refused
/// unless it converged.
fn reference(
    prepared: &Prepared,
    method: Method,
    load: &[f64],
    alpha: f64,
) -> Result<(Reference, Equilibrium), BenchError> {
    let mut solver = set_up(method, &SolverChoice::default(), prepared)?;
    let mut solution = solver.solver.solve(load, None, &mut Silent);
    mark_beyond_model(prepared, &mut solution);
    if !solution.info.status.converged() {
        return Err(BenchError::Reference {
            method,
            alpha: alpha_label(alpha),
            status: solution.info.status,
            residual: solution.info.stopping_value,
        });
    }
    Ok((
        Reference::new(&prepared.model, &solution.equilibrium.displacements),
        solution.equilibrium,
    ))
}

/// The free motion's nodes when the converged reference `eq` is not the only equilibrium, as
/// `run` checks it ([`Prepared::checked_uniqueness`]); `None` when it is unique or not checked.
fn reference_not_unique(prepared: &Prepared, eq: &Equilibrium, load: &[f64]) -> Option<String> {
    match prepared.checked_uniqueness(eq, load, false)? {
        u @ Uniqueness::NotUnique { .. } => Some(u.motion_nodes()),
        _ => None,
    }
}

/// Run every solver of the case at every α of it against a reference solved by the case's
/// reference solver ([`reference_method`]; refused before any solve when there is none).
pub fn measure(
    case: &Case,
    prepared: &Prepared,
    on_progress: &mut dyn FnMut(Progress),
) -> Result<Bench, BenchError> {
    let reference_method = reference_method(case)?;
    let mut series = Vec::new();
    for &alpha in &case.load.alphas {
        let load = prepared.model.load(alpha);
        on_progress(Progress::Reference {
            method: reference_method,
            alpha,
        });
        let (reference, answer) = reference(prepared, reference_method, &load, alpha)?;
        if let Some(nodes) = reference_not_unique(prepared, &answer, &load) {
            on_progress(Progress::ReferenceNotUnique {
                alpha,
                nodes: &nodes,
            });
        }
        drop(answer);
        for &method in &case.solver.methods {
            on_progress(Progress::Solve { method, alpha });
            let measured = measure_series(case, prepared, method, alpha, &load, &reference)?;
            on_progress(Progress::Done(&measured));
            series.push(measured);
        }
    }
    let table = super::Table::new(&series);
    Ok(Bench { series, table })
}

/// Set up and solve once, recording every iterate.
fn measure_series(
    case: &Case,
    prepared: &Prepared,
    method: Method,
    alpha: f64,
    load: &[f64],
    reference: &Reference,
) -> Result<Series, SetupError> {
    let mut solver = set_up(method, &case.solver, prepared)?;
    let setup_seconds = solver.setup_seconds;
    let mut recorder = Recorder::default();
    let mut solution = solver.solver.solve(load, Some(reference), &mut recorder);
    mark_beyond_model(prepared, &mut solution);
    let mut samples: Vec<Sample> = recorder
        .records
        .iter()
        .map(|record| Sample {
            iteration: record.iteration,
            seconds: setup_seconds + record.elapsed_seconds,
            error: record.error.unwrap_or(f64::NAN),
        })
        .collect();
    // The last iterate is the answer: timed when the solve returned it. Its e is the one the
    // driver reported, or (when the start was the answer) that of the answer's displacements.
    let last = solution.info.iterations;
    let final_error = match samples.last() {
        Some(s) if s.iteration == last => s.error,
        _ => {
            let s = &prepared.model.structure;
            let mut elongations = vec![0.0; s.links.len()];
            s.elongations(&solution.equilibrium.displacements, &mut elongations);
            reference.error(&elongations)
        }
    };
    samples.retain(|s| s.iteration < last);
    samples.push(Sample {
        iteration: last,
        seconds: setup_seconds + solution.info.solve_seconds,
        error: final_error,
    });
    Ok(Series {
        method,
        alpha,
        setup_seconds,
        status: solution.info.status,
        samples,
    })
}
