//! `tensolve run`: one case, end to end. Build the structure, set the asked solvers up once,
//! solve every α, hand every solve to the sinks the case asks for. Only what the case asks
//! for is computed and written.

use super::setup::{prepare, set_up, Prepared, SetUpSolver};
use crate::case::memory::{self, MemoryEstimate, Size, Workload};
use crate::case::{Case, CaseError};
use crate::output::{
    self, alpha_label,
    plots::{self, History},
    sinks::{HistorySink, PerSolveSink, PlotsSink, PublishSink, StabilitySink, SummarySink},
    FigureSettings, OpenError, OutputDir, Sink, Sinks, SolveEnd, SolveKey, SummaryRow, WriteError,
};
use crate::results;
use crate::solvers::Status;
use crate::solvers::{
    Equilibrium, IterationRecord, Measure, Method, Observer, Recorder, Reference, SetupError,
    Silent, Solution, Tee,
};
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// What the command line adds to a case.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Overrides `output.dir`.
    pub out_dir: Option<PathBuf>,
    /// Overrides `solver.methods`.
    pub methods: Option<Vec<Method>>,
}

/// Why a run failed, or did not produce all that was asked.
#[derive(Debug, Error)]
pub enum RunError {
    /// The case is invalid.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// A solver cannot be set up for the structure (a mechanism, a singular partition).
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// The output directory cannot be created or written.
    #[error(
        "output directory `{dir}` is not writable ({reason}): set `output.dir` in the case or \
         pass `--out DIR` with a directory you can write to"
    )]
    OutputDir {
        /// The directory.
        dir: String,
        /// Why.
        reason: String,
    },
    /// Another run holds the output directory's lock.
    #[error("{0}")]
    Busy(OpenError),
    /// A file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// Some solves did not meet their stopping criterion (their rows say so) or had no finite
    /// answer (no row, no files); each item of the list says which.
    #[error("{count} solve(s) did not converge: {list}")]
    NotConverged {
        /// How many.
        count: usize,
        /// Which, and how they ended.
        list: String,
    },
}

impl RunError {
    /// 2 for bad input (the case, the structure it describes, the output directory); 3 when
    /// another run holds the output directory; 1 when the run could not produce what was
    /// asked.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_) | RunError::Setup(_) | RunError::OutputDir { .. } => 2,
            RunError::Busy(_) => 3,
            RunError::Write { .. } | RunError::NotConverged { .. } => 1,
        }
    }
}

impl From<OpenError> for RunError {
    fn from(e: OpenError) -> Self {
        match e {
            OpenError::Busy { .. } => RunError::Busy(e),
            OpenError::Io { dir, source } => RunError::OutputDir {
                dir: dir.display().to_string(),
                reason: source.to_string(),
            },
        }
    }
}

/// At most this many failed solves are listed in a message; the rest are counted.
const LISTED_FAILURES: usize = 10;

/// `list` joined, its first [`LISTED_FAILURES`] items in full and the rest counted.
fn failure_list(list: &[String]) -> String {
    let mut text = list[..list.len().min(LISTED_FAILURES)].join("; ");
    if list.len() > LISTED_FAILURES {
        text.push_str(&format!("; and {} more", list.len() - LISTED_FAILURES));
    }
    text
}

/// The output directory: `--out`, else `output.dir`, else `out/case`.
pub fn output_dir(case: &Case, options: &RunOptions) -> PathBuf {
    options
        .out_dir
        .clone()
        .or_else(|| case.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out/case"))
}

/// What a run is doing, for a progress display: the run reports each as it happens and never
/// prints.
#[derive(Debug, Clone, Copy)]
pub enum RunEvent<'a> {
    /// A set-up step began (the structure, a solver's factorisations, a reference solve);
    /// it lasts until the next event.
    Stage(&'a str),
    /// A solve began.
    SolveStart {
        /// The solver's name.
        solver: &'a str,
        /// The load factor.
        alpha: f64,
    },
    /// An iterate of the solve in progress.
    Iteration {
        /// The solver's name.
        solver: &'a str,
        /// The load factor.
        alpha: f64,
        /// What `record.residual` measures.
        measure: Measure,
        /// The iterate.
        record: &'a IterationRecord,
    },
    /// A solve ended and its summary row was written.
    Row(&'a SummaryRow),
}

/// Passes every iterate of one solve to the run's events as [`RunEvent::Iteration`].
struct IterationEvents<'e> {
    events: &'e mut dyn FnMut(RunEvent<'_>),
    key: SolveKey,
}

impl Observer for IterationEvents<'_> {
    fn iteration(&mut self, record: &IterationRecord) {
        (self.events)(RunEvent::Iteration {
            solver: self.key.method.name(),
            alpha: self.key.alpha,
            measure: self.key.measure,
            record,
        });
    }
}

/// Run a validated case. `events` sees what the run is doing ([`RunEvent`]), every summary
/// row as soon as it is written among them.
pub fn run(
    case: &Case,
    options: &RunOptions,
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<Vec<SummaryRow>, RunError> {
    let dir = output_dir(case, options);
    let methods = options
        .methods
        .clone()
        .unwrap_or_else(|| case.solver.methods.clone());
    crate::case::check_distinct_methods("--solver", &methods)?;
    // 0. The memory the run needs, estimated before anything large is allocated.
    let estimate = MemoryEstimate::new(Size::of(case), &Workload::run(case, &methods));
    memory::ensure_fits(&estimate, "run")?;

    // 1. The structure and its mechanism check (K with every cable taut, factorized).
    events(RunEvent::Stage(
        "building the structure and factorising its taut stiffness",
    ));
    let prepared = match prepare(case) {
        Ok(prepared) => prepared,
        Err(refused) => {
            // Where a refused mechanism is: its modes, node by node, in mechanisms.csv.
            if !refused.modes().is_empty() {
                write_mechanisms(&dir, refused.modes())?;
            }
            return Err(refused.into());
        }
    };
    let structure = &prepared.structure;
    // 2. Every solver asked for, set up once.
    let mut solvers = Vec::with_capacity(methods.len());
    for &method in &methods {
        events(RunEvent::Stage(&format!("setting up {}", method.name())));
        solvers.push(set_up(method, &case.solver, &prepared)?);
    }
    // 3. Where LATIN's error e is measured from.
    events(RunEvent::Stage("setting up the reference solver"));
    let mut reference = ReferenceSource::new(case, &solvers, &prepared)?;
    // 4. The output directory, once the case is known solvable: locked for this run, with a
    //    private staging directory; then the sinks of the files asked for.
    let out = match writes_files(case) {
        true => Some(RefCell::new(OutputDir::open(&dir)?)),
        false => None,
    };
    let mut sinks = sinks(case, &dir, out.as_ref(), &prepared, &solvers);
    // 5. The homogenised substructure operators, when asked (set-up products, written once).
    if let Some(out) = out.as_ref().filter(|_| case.output.homogenised) {
        events(RunEvent::Stage("writing the homogenised operators"));
        for set_up in &mut solvers {
            let operators = set_up.solver.homogenised_operators();
            let staging = out.borrow().staging().to_path_buf();
            output::write_homogenised(&staging, &operators).map_err(|source| WriteError {
                path: dir.join("homogenised"),
                source,
            })?;
            out.borrow_mut().commit()?;
        }
    }
    // 6. Every α, every solver, each warm-started from its converged answer at the previous α
    //    (newton and pcg-lcp use it; they stop on the same criterion as from a cold start).
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    let wants_eigenvalue = structure.model.has_geometric_stiffness() || case.output.stability;
    let mut previous: Vec<Option<Equilibrium>> = vec![None; solvers.len()];
    for &alpha in &case.load.alphas {
        let load: Vec<f64> = structure.unit_load.iter().map(|f| alpha * f).collect();
        if reference.needed() {
            events(RunEvent::Stage(&format!(
                "reference solve at alpha = {}",
                alpha_label(alpha)
            )));
        }
        let reference_solution = reference.solve(&load, &mut solvers, &previous);
        let reference_errors = reference_solution
            .as_ref()
            .map(|r| Reference::new(structure, &r.equilibrium.displacements));
        for (index, set_up) in solvers.iter_mut().enumerate() {
            let key = SolveKey {
                method: set_up.method,
                alpha,
                measure: set_up.solver.stopping_measure(),
            };
            sinks.start(&key)?;
            events(RunEvent::SolveStart {
                solver: key.method.name(),
                alpha,
            });
            let solution = match (reference.shared_index(), &reference_solution) {
                (Some(i), Some(r)) if i == index => r.clone(),
                _ => {
                    let mut progress = IterationEvents {
                        events: &mut *events,
                        key,
                    };
                    let mut observers = Tee::default()
                        .with(Some(&mut sinks))
                        .with(Some(&mut progress));
                    set_up.solver.solve_from(
                        &load,
                        previous[index].as_ref(),
                        reference_errors.as_ref(),
                        &mut observers,
                    )
                }
            };
            // 7. What the answer is beyond the solver's own stop: no equilibrium, or an
            //    unstable one (docs/method.md §8).
            let mut solution = solution;
            let verdict = assess(&mut solution, &prepared, &load, wants_eigenvalue);
            previous[index] = (solution.info.status.converged() && results::is_finite(&solution))
                .then(|| solution.equilibrium.clone());
            // 8. A non-finite answer (or a row it would give) is reported, never written.
            let row = results::is_finite(&solution).then(|| {
                SummaryRow::new(
                    key.method.name(),
                    alpha,
                    &load,
                    structure,
                    &solution,
                    (verdict.min_tangent_eigenvalue, verdict.geometric_term),
                    set_up.setup_seconds,
                )
            });
            let Some(row) = row.filter(SummaryRow::is_finite) else {
                sinks.end(&key, SolveEnd::NonFinite)?;
                failures.push(format!(
                    "{} at alpha = {}: produced non-finite values after {} iterations; no row \
                     and no files written for it",
                    key.method.name(),
                    alpha_label(alpha),
                    solution.info.iterations,
                ));
                continue;
            };
            if !row.converged {
                failures.push(not_converged_message(&row, &solution, &verdict));
            }
            if row.status.no_answer() {
                // 9. No answer: its row, and no file that would look like one.
                sinks.end(&key, SolveEnd::NoAnswer { row: &row })?;
                events(RunEvent::Row(&row));
                rows.push(row);
                continue;
            }
            // 9. The files of this solve.
            sinks.end(
                &key,
                SolveEnd::Solved {
                    solution: &solution,
                    row: &row,
                },
            )?;
            events(RunEvent::Row(&row));
            rows.push(row);
        }
    }
    // 10. The files of the whole sweep; the directory released.
    sinks.close()?;
    drop(sinks);
    // 11. Figure 12: the LATIN solvers at the largest α on the grid of each module kind asked.
    let compare = case.output.plots && !case.output.compare_modules.is_empty();
    if let Some(out) = out.as_ref().filter(|_| compare) {
        events(RunEvent::Stage(
            "Figure 12: the LATIN solvers on each module of output.compare_modules",
        ));
        let staging = out.borrow().staging().to_path_buf();
        write_module_comparison(case, &methods, &staging, &dir)?;
        out.borrow_mut().commit()?;
    }
    if let Some(out) = out {
        out.into_inner().finish().map_err(|source| WriteError {
            path: dir.clone(),
            source,
        })?;
    }
    if failures.is_empty() {
        Ok(rows)
    } else {
        Err(RunError::NotConverged {
            count: failures.len(),
            list: failure_list(&failures),
        })
    }
}

/// `mechanisms.csv` (`node,mode,ux,uy,uz`) in the output directory, through its lock and
/// staging like every result.
fn write_mechanisms(dir: &Path, modes: &[crate::solvers::ModeRow]) -> Result<(), RunError> {
    let mut out = OutputDir::open(dir)?;
    let staging = out.staging().to_path_buf();
    output::write_mechanisms(&staging, modes).map_err(|source| WriteError {
        path: dir.join("mechanisms.csv"),
        source,
    })?;
    out.commit()?;
    out.finish().map_err(|source| WriteError {
        path: dir.to_path_buf(),
        source,
    })?;
    Ok(())
}

/// What the sweep found of an answer beyond its solver's stop.
struct Verdict {
    /// The smallest tangent eigenvalue at the answer, when computed.
    min_tangent_eigenvalue: Option<f64>,
    /// The relative change the geometric term the model leaves out would make.
    geometric_term: Option<f64>,
    /// Why the answer is no equilibrium, when it is none.
    no_equilibrium: Option<crate::solvers::NoEquilibrium>,
}

/// Judge `solution` (docs/method.md §8): its displacements may be a direction along which the
/// energy decreases without bound (no equilibrium exists: [`Status::NoEquilibrium`]); with
/// `eigenvalue`, the smallest tangent eigenvalue at the answer, and a converged answer where it
/// is negative is an unstable equilibrium ([`Status::Unstable`]).
fn assess(solution: &mut Solution, prepared: &Prepared, load: &[f64], eigenvalue: bool) -> Verdict {
    let s = &prepared.structure;
    if !results::is_finite(solution) {
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: None,
        };
    }
    // A converged answer is an equilibrium (r(U) within its tolerance): only the others are
    // asked for a runaway.
    let found = solution.info.no_equilibrium.clone().or_else(|| {
        (!solution.info.status.converged())
            .then(|| crate::solvers::no_equilibrium(s, &solution.equilibrium, load))
            .flatten()
    });
    if let Some(none) = found {
        solution.info.status = Status::NoEquilibrium;
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: Some(none),
        };
    }
    let min_tangent_eigenvalue = (eigenvalue && !solution.info.status.no_answer())
        .then(|| results::smallest_tangent_eigenvalue(s, &solution.equilibrium, &prepared.taut));
    if solution.info.status.converged() && min_tangent_eigenvalue.is_some_and(|v| v < 0.0) {
        solution.info.status = Status::Unstable;
    }
    // A model on the initial geometry whose answer moves a node by more than the structure's
    // own size has left its domain: converged or not, no answer of it.
    if s.model != crate::structure::GeometricModel::Large
        && results::max_deflection(s, &solution.equilibrium) > s.size()
    {
        solution.info.status = Status::BeyondModel;
    }
    Verdict {
        min_tangent_eigenvalue,
        geometric_term: results::geometric_term(s, &solution.equilibrium, &prepared.taut),
        no_equilibrium: None,
    }
}

/// The failure line of a row that did not converge: how it ended, and for no equilibrium the
/// cables that went slack and the nodes of the mode.
fn not_converged_message(row: &SummaryRow, solution: &Solution, verdict: &Verdict) -> String {
    let head = format!("{} at alpha = {}", row.solver, alpha_label(row.alpha));
    let ids = |ids: &[u64]| {
        ids.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match (&verdict.no_equilibrium, row.status) {
        (Some(none), _) => format!(
            "{head}: no equilibrium: with cable(s) {} slack, a mechanism is left that the load \
             works on (it moves nodes {}), so the energy decreases without bound; no \
             displacement or tension file is written, and its row says converged = false, \
             status = no_equilibrium. Add members or supports, prestress those cables, or model \
             the geometric stiffness (`model.geometry`)",
            ids(&none.slack_cables),
            none.mode_nodes
                .iter()
                .map(|(id, u)| format!("{id} ({:.2}, {:.2}, {:.2})", u[0], u[1], u[2]))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        (None, Status::LimitPoint) => format!(
            "{head}: limit point: the load path could not be followed to this load (load \
             increments halved below {} of the path from the last equilibrium); no \
             displacement or tension file is written, and its row says converged = false, \
             status = limit_point",
            crate::solvers::newton::MIN_INCREMENT
        ),
        (None, Status::BeyondModel) => format!(
            "{head}: beyond the model: the answer moves a node by {:.3e} m, more than the \
             structure's own size; a model on the initial geometry does not describe that (a \
             unit slip, such as E in GPa or coordinates in mm? `tensolve check` prints the \
             magnitudes); no displacement or tension file is written, and its row says \
             converged = false, status = beyond_model",
            row.max_deflection
        ),
        (None, Status::Unstable) => format!(
            "{head}: an unstable equilibrium: the residual criterion holds, but the tangent \
             stiffness has a negative eigenvalue ({:.3e} N/m): a saddle of the energy, which a \
             load path would not stay on; its row says converged = false, status = unstable",
            row.min_tangent_eigenvalue.unwrap_or(f64::NAN)
        ),
        _ => format!(
            "{head}: not converged after {} iterations ({:?}), {} = {:e}; its row says \
             converged = false",
            row.iterations,
            solution.info.status,
            solution.info.measure.short_name(),
            row.residual
        ),
    }
}

/// `plots/error_modules.svg`: every LATIN solver of `methods` at the case's largest α, on the
/// case's grid made of each module kind of `output.compare_modules` (the paper's Figure 12).
fn write_module_comparison(
    case: &Case,
    methods: &[Method],
    staging: &Path,
    root: &Path,
) -> Result<(), RunError> {
    let alpha = case
        .load
        .alphas
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let mut histories = Vec::new();
    for &module in &case.output.compare_modules {
        // Case validation refuses compare_modules without a [grid].
        let Some(grid_case) = case.with_module(module) else {
            return Ok(());
        };
        let prepared = prepare(&grid_case)?;
        let mut solvers = Vec::new();
        for &method in methods {
            let set_up = set_up(method, &case.solver, &prepared)?;
            if method.reports_error() {
                solvers.push(set_up);
            }
        }
        let structure = &prepared.structure;
        let load: Vec<f64> = structure.unit_load.iter().map(|f| alpha * f).collect();
        let mut reference = ReferenceSource::new(&grid_case, &solvers, &prepared)?;
        let cold = vec![None; solvers.len()];
        let reference_solution = reference.solve(&load, &mut solvers, &cold);
        let errors = reference_solution
            .as_ref()
            .map(|r| Reference::new(structure, &r.equilibrium.displacements));
        for set_up in &mut solvers {
            let mut recorder = Recorder::default();
            set_up.solver.solve(&load, errors.as_ref(), &mut recorder);
            histories.push((
                module.name(),
                History {
                    solver: set_up.method,
                    alpha,
                    records: recorder.records,
                },
            ));
        }
    }
    let settings = FigureSettings {
        amplification: case.output.amplification,
        max_plot_iterations: case.output.max_plot_iterations,
    };
    let path = staging.join("plots").join("error_modules.svg");
    let written = plots::write_module_comparison(&path, &histories, &settings);
    written.map_err(|source| {
        RunError::Write(WriteError {
            path: root.join("plots").join("error_modules.svg"),
            source,
        })
    })
}

/// Whether `case` asks for any file.
fn writes_files(case: &Case) -> bool {
    let o = &case.output;
    o.history
        || o.tensions
        || o.displacements
        || o.forces
        || o.reactions
        || o.vtk
        || o.plots
        || o.stability
        || o.summary
        || o.homogenised
}

/// The sinks of the files `case` asks for, in the order they write: the per-solve files into
/// the staging directory of `output`, published together, then the rows of the ledgers.
fn sinks<'s>(
    case: &Case,
    root: &Path,
    output: Option<&'s RefCell<OutputDir>>,
    prepared: &'s Prepared,
    solvers: &[SetUpSolver<'_>],
) -> Sinks<'s> {
    let mut sinks = Sinks::default();
    let Some(output) = output else {
        return sinks;
    };
    let staging = output.borrow().staging().to_path_buf();
    let dir = staging.as_path();
    let (structure, taut) = (&prepared.structure, &prepared.taut);
    let out = &case.output;
    let has_history = solvers
        .iter()
        .any(|s| output::history_column(s.solver.stopping_measure()).is_some());
    sinks.add(
        out.history && has_history,
        HistorySink::new(root, dir, structure.n_cables()),
    );
    sinks.add(out.tensions, PerSolveSink::tensions(root, dir, structure));
    sinks.add(
        out.displacements,
        PerSolveSink::displacements(root, dir, structure),
    );
    sinks.add(out.forces, PerSolveSink::forces(root, dir, structure));
    sinks.add(out.reactions, PerSolveSink::reactions(root, dir, structure));
    sinks.add(out.vtk, PerSolveSink::vtk(root, dir, structure));
    if let Some(first) = solvers.first().filter(|_| out.plots) {
        let settings = FigureSettings {
            amplification: out.amplification,
            max_plot_iterations: out.max_plot_iterations,
        };
        sinks.add(
            true,
            PlotsSink::new(root, dir, structure, first.method, settings),
        );
    }
    sinks.add(true, PublishSink::new(output));
    sinks.add(out.stability, StabilitySink::new(output, structure, taut));
    sinks.add(out.summary, SummarySink::new(output));
    sinks
}

/// Where the reference of the LATIN error comes from.
enum ReferenceSource<'s> {
    /// No solver reports e (none stops on η), or `solver.reference = "none"`.
    Unneeded,
    /// A solver of the case at its default settings: its own solution serves.
    Shared(usize),
    /// A solver of its own, with the solver's default (tight) settings.
    Own(SetUpSolver<'s>),
}

impl<'s> ReferenceSource<'s> {
    fn new(
        case: &Case,
        solvers: &[SetUpSolver<'_>],
        prepared: &'s Prepared,
    ) -> Result<Self, SetupError> {
        let reports_error = solvers.iter().any(|s| s.method.reports_error());
        let Some(method) = case.solver.reference.method().filter(|_| reports_error) else {
            return Ok(ReferenceSource::Unneeded);
        };
        let shared = solvers
            .iter()
            .position(|s| s.method == method && case.solver.is_default(method));
        Ok(match shared {
            Some(i) => ReferenceSource::Shared(i),
            None => ReferenceSource::Own(set_up(method, &Default::default(), prepared)?),
        })
    }

    /// The reference solution at `load`, if one is needed; a shared solver starts from its
    /// `previous` answer.
    fn solve(
        &mut self,
        load: &[f64],
        solvers: &mut [SetUpSolver<'_>],
        previous: &[Option<Equilibrium>],
    ) -> Option<Solution> {
        match self {
            ReferenceSource::Unneeded => None,
            ReferenceSource::Shared(i) => Some(solvers[*i].solver.solve_from(
                load,
                previous[*i].as_ref(),
                None,
                &mut Silent,
            )),
            ReferenceSource::Own(own) => Some(own.solver.solve(load, None, &mut Silent)),
        }
    }

    /// Whether a reference solve runs at each α.
    fn needed(&self) -> bool {
        !matches!(self, ReferenceSource::Unneeded)
    }

    /// The solver whose own solve is the reference.
    fn shared_index(&self) -> Option<usize> {
        match self {
            ReferenceSource::Shared(i) => Some(*i),
            _ => None,
        }
    }
}
