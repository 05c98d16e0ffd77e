//! One case, end to end: build the structure, set the asked solvers up once, solve every α,
//! write the asked files. Only what the case asks for is computed and written.

use crate::case::{Case, CaseError, Method, Reference};
use crate::configure::{prepare, ConfiguredSolver, Limits};
use crate::output::{self, FigureData, HistoryWriter, Recorder, SummaryRow, Tee};
use crate::results;
use crate::solvers::{Equilibrium, Observer, SetupError, Silent, Solution};
use crate::structure::Structure;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

/// What the command line adds to a case.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Overrides `output.dir`.
    pub out_dir: Option<PathBuf>,
    /// Overrides `solver.methods`.
    pub methods: Option<Vec<Method>>,
}

#[derive(Debug, Error)]
pub enum RunError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error(transparent)]
    Setup(#[from] SetupError),
    #[error(
        "output directory `{dir}` is not writable ({reason}): set `output.dir` in the case or \
         pass `--out DIR` with a directory you can write to"
    )]
    OutputDir { dir: String, reason: String },
    #[error("could not write `{path}`: {reason}")]
    Write { path: String, reason: String },
    #[error("{count} solve(s) did not converge: {list}; their rows say converged = false")]
    NotConverged { count: usize, list: String },
}

impl RunError {
    /// 2 for bad input (the case, the structure it describes, the output directory); 1 when
    /// the run could not produce what was asked.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_) | RunError::Setup(_) | RunError::OutputDir { .. } => 2,
            RunError::Write { .. } | RunError::NotConverged { .. } => 1,
        }
    }
}

/// Where the reference of the LATIN error comes from.
enum ReferenceSource<'s> {
    /// No LATIN solver asked, or `solver.reference = "none"`.
    Unneeded,
    /// A runner of the case with default settings: its own solution serves.
    Shared(usize),
    /// A runner of its own, with the solver's default (tight) settings.
    Own(Box<ConfiguredSolver<'s>>),
}

/// The output directory: `--out`, else `output.dir`, else `out/case`.
pub fn output_dir(case: &Case, options: &RunOptions) -> PathBuf {
    options
        .out_dir
        .clone()
        .or_else(|| case.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out/case"))
}

fn check_writable(dir: &Path) -> Result<(), RunError> {
    output::ensure_writable(dir).map_err(|e| RunError::OutputDir {
        dir: dir.display().to_string(),
        reason: e.to_string(),
    })
}

fn write_error(path: &Path, e: std::io::Error) -> RunError {
    RunError::Write {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
}

/// The files of one solve the case asks for: tensions, displacements, VTU.
fn write_solve_files(
    case: &Case,
    dir: &Path,
    solver: &str,
    alpha: f64,
    structure: &Structure,
    eq: &Equilibrium,
) -> Result<(), RunError> {
    if case.output.tensions {
        output::write_tensions(dir, solver, alpha, structure, eq)
            .map_err(|e| write_error(&dir.join("tensions"), e))?;
    }
    if case.output.displacements {
        output::write_displacements(dir, solver, alpha, structure, eq)
            .map_err(|e| write_error(&dir.join("displacements"), e))?;
    }
    if case.output.vtk {
        output::write_vtu(dir, solver, alpha, structure, eq)
            .map_err(|e| write_error(&output::vtu_path(dir, solver, alpha), e))?;
    }
    Ok(())
}

/// Run a validated case. `on_row` sees every summary row as soon as it is written.
pub fn run(
    case: &Case,
    options: &RunOptions,
    on_row: &mut dyn FnMut(&SummaryRow),
) -> Result<Vec<SummaryRow>, RunError> {
    let dir = output_dir(case, options);
    let methods = options
        .methods
        .clone()
        .unwrap_or_else(|| case.solver.methods.clone());
    let wants_files = case.output.summary
        || case.output.tensions
        || case.output.displacements
        || (case.output.history && methods.iter().any(|m| m.is_latin()))
        || case.output.plots
        || case.output.vtk
        || case.output.stability;

    // The mechanism check of every run: K with every cable taut, factorized. newton and
    // pcg-lcp solve with it, so it is part of their set-up; the LATIN solvers never use it.
    let prepared = prepare(case)?;
    let (structure, taut) = (&prepared.structure, &prepared.taut);
    // After the structure is known to be solvable: a refused case leaves no directory behind.
    if wants_files {
        check_writable(&dir)?;
    }

    let limits = Limits::of_case(case);
    let mut runners = Vec::with_capacity(methods.len());
    for &method in &methods {
        let clock = Instant::now();
        let runner = ConfiguredSolver::new(method, case, structure, taut, limits)?;
        let setup_seconds = prepared.shared_setup_seconds(method) + clock.elapsed().as_secs_f64();
        runners.push((method, runner, setup_seconds));
    }
    let reference_method = match case.solver.reference {
        Reference::Newton => Some(Method::Newton),
        Reference::PcgLcp => Some(Method::PcgLcp),
        Reference::None => None,
    }
    .filter(|_| methods.iter().any(|m| m.is_latin()));
    let mut reference_source = match reference_method {
        None => ReferenceSource::Unneeded,
        Some(m) => match runners
            .iter()
            .position(|(rm, _, _)| *rm == m && limits.is_default())
        {
            Some(i) => ReferenceSource::Shared(i),
            None => ReferenceSource::Own(Box::new(ConfiguredSolver::new(
                m,
                case,
                structure,
                taut,
                Limits::default(),
            )?)),
        },
    };

    // Only when figures are asked: what they are drawn from, gathered along the sweep.
    let mut figures = methods
        .first()
        .filter(|_| case.output.plots)
        .map(|first| FigureData::new(first.name()));
    let summary_path = dir.join("summary.csv");
    let stability_path = dir.join("stability.csv");
    let mut rows = Vec::new();
    let mut stability_rows = Vec::new();
    let mut failures = Vec::new();
    for &alpha in &case.load.alphas {
        let load: Vec<f64> = structure.unit_load.iter().map(|f| alpha * f).collect();
        let reference: Option<Solution> = match &mut reference_source {
            ReferenceSource::Unneeded => None,
            ReferenceSource::Shared(i) => Some(runners[*i].1.solve(&load, None, &mut Silent)),
            ReferenceSource::Own(runner) => Some(runner.solve(&load, None, &mut Silent)),
        };
        let reference_u = reference
            .as_ref()
            .map(|r| r.equilibrium.displacements.as_slice());
        for (index, (method, runner, setup_seconds)) in runners.iter_mut().enumerate() {
            // The LATIN iterations go to the history file and, for the figures, to a recorder:
            // one solve feeds both.
            let mut history = if method.is_latin() && case.output.history {
                let writer =
                    HistoryWriter::create(&dir, method.name(), alpha, structure.n_cables())
                        .map_err(|e| write_error(&dir.join("history"), e))?;
                Some(writer)
            } else {
                None
            };
            let mut recorder = (method.is_latin() && figures.is_some()).then(Recorder::default);
            let solution = match (&reference_source, &reference) {
                (ReferenceSource::Shared(i), Some(r)) if *i == index => r.clone(),
                _ => {
                    let mut observers = Tee::new()
                        .with(history.as_mut().map(|h| h as &mut dyn Observer))
                        .with(recorder.as_mut().map(|r| r as &mut dyn Observer));
                    runner.solve(&load, reference_u, &mut observers)
                }
            };
            if let Some(history) = history {
                history
                    .finish()
                    .map_err(|e| write_error(&dir.join("history"), e))?;
            }
            if !results::is_finite(&solution) {
                // Never a NaN or inf in a file: the solve is reported, its files not written.
                failures.push(format!(
                    "{} at alpha = {}: produced non-finite values after {} iterations ({:?}); no files written for it",
                    method.name(),
                    output::alpha_label(alpha),
                    solution.info.iterations,
                    solution.info.status
                ));
                continue;
            }
            let eq = &solution.equilibrium;
            let row = SummaryRow {
                solver: method.name().to_string(),
                alpha,
                converged: solution.info.status.converged(),
                iterations: solution.info.iterations,
                slack_cables: eq.slack_count(),
                cables: structure.n_cables(),
                max_tension: results::max_cable_tension(structure, eq),
                max_deflection: results::max_deflection(structure, eq),
                residual: solution.info.residual,
                setup_seconds: *setup_seconds,
                solve_seconds: solution.info.solve_seconds,
            };
            if !row.converged {
                failures.push(format!(
                    "{} at alpha = {}: not converged after {} iterations ({:?}), {} = {:e}",
                    row.solver,
                    output::alpha_label(alpha),
                    row.iterations,
                    solution.info.status,
                    if method.is_latin() { "eta" } else { "residual" },
                    row.residual
                ));
            }
            write_solve_files(case, &dir, method.name(), alpha, structure, eq)?;
            if let Some(figures) = figures.as_mut() {
                figures.add_solve(method.name(), alpha, structure, eq);
                if let Some(recorder) = recorder {
                    figures.add_history(method.name(), alpha, recorder.records);
                }
            }
            if case.output.stability {
                stability_rows.push(output::StabilityRow {
                    solver: row.solver.clone(),
                    alpha,
                    slack_cables: row.slack_cables,
                    min_tangent_eigenvalue: results::smallest_tangent_eigenvalue(
                        structure,
                        &solution.equilibrium,
                        taut,
                    ),
                });
                output::write_stability(&stability_path, &stability_rows)
                    .map_err(|e| write_error(&stability_path, e))?;
            }
            rows.push(row);
            // Rewritten whole after every solve: an interrupted sweep leaves a complete file.
            if case.output.summary {
                output::write_summary(&summary_path, &rows)
                    .map_err(|e| write_error(&summary_path, e))?;
            }
            on_row(rows.last().expect("row just pushed"));
        }
    }
    if let Some(figures) = &figures {
        figures
            .write(&dir, structure)
            .map_err(|e| write_error(&dir.join("plots"), e))?;
    }
    if failures.is_empty() {
        Ok(rows)
    } else {
        Err(RunError::NotConverged {
            count: failures.len(),
            list: failures.join("; "),
        })
    }
}
