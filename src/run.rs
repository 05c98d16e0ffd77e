//! One case, end to end: build the structure, set the asked solvers up once, solve every α,
//! write the asked files. Only what the case asks for is computed and written.

use crate::case::{Case, CaseError, Method, Reference};
use crate::output::{self, HistoryWriter, SummaryRow};
use crate::results;
use crate::solvers::latin::{Latin, LatinSettings, SearchDirection};
use crate::solvers::newton::{Newton, NewtonSettings};
use crate::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use crate::solvers::{Observer, SetupError, Silent, Solution, TautStiffness};
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

/// A solver set up for the structure.
enum Runner<'s> {
    Newton(Newton<'s>),
    PcgLcp(PcgLcp<'s>),
    Latin(Latin<'s>),
}

impl<'s> Runner<'s> {
    /// Set `method` up with the case's settings (`tuned`) or with the solver's own defaults.
    fn new(
        method: Method,
        case: &Case,
        structure: &'s Structure,
        taut: &'s TautStiffness,
        tuned: bool,
    ) -> Result<Runner<'s>, SetupError> {
        let tolerance = case.solver.tolerance.filter(|_| tuned);
        let max_iterations = case.solver.max_iterations.filter(|_| tuned);
        Ok(match method {
            Method::Newton => {
                let mut settings = NewtonSettings::default();
                settings.tolerance = tolerance.unwrap_or(settings.tolerance);
                settings.max_iterations = max_iterations.unwrap_or(settings.max_iterations);
                Runner::Newton(Newton::new(structure, taut, settings)?)
            }
            Method::PcgLcp => {
                let mut settings = PcgLcpSettings::default();
                settings.tolerance = tolerance.unwrap_or(settings.tolerance);
                settings.max_iterations = max_iterations.unwrap_or(settings.max_iterations);
                Runner::PcgLcp(PcgLcp::new(structure, taut, settings))
            }
            Method::MonoLatin | Method::MicroMacro => {
                let mut settings = LatinSettings {
                    subdomains: if method == Method::MonoLatin {
                        [1, 1]
                    } else {
                        case.solver.partition()
                    },
                    dm: case.solver.dm,
                    search: case.solver.search.unwrap_or(SearchDirection::Stiffness),
                    weak: case.solver.weak_interfaces,
                    ..LatinSettings::default()
                };
                settings.tolerance = tolerance.unwrap_or(settings.tolerance);
                settings.max_iterations = max_iterations.unwrap_or(settings.max_iterations);
                Runner::Latin(Latin::new(structure, settings)?)
            }
        })
    }

    fn solve(
        &mut self,
        load: &[f64],
        reference: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Solution {
        match self {
            Runner::Newton(s) => s.solve(load, None, observer),
            Runner::PcgLcp(s) => s.solve(load, observer),
            Runner::Latin(s) => s.solve(load, reference, observer),
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
    Own(Box<Runner<'s>>),
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
    let fail = |e: std::io::Error| RunError::OutputDir {
        dir: dir.display().to_string(),
        reason: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(format!(".tensolve-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)?;
    Ok(())
}

fn write_error(path: &Path, e: std::io::Error) -> RunError {
    RunError::Write {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
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
        || (case.output.history && methods.iter().any(|m| m.is_latin()));

    let clock = Instant::now();
    let structure = Structure::from_case(case);
    let structure_seconds = clock.elapsed().as_secs_f64();
    // The mechanism check of every run: K with every cable taut, factorized. newton and
    // pcg-lcp solve with it, so it is part of their set-up; the LATIN solvers never use it.
    let taut = TautStiffness::new(&structure)?;
    let taut_seconds = clock.elapsed().as_secs_f64() - structure_seconds;
    // After the structure is known to be solvable: a refused case leaves no directory behind.
    if wants_files {
        check_writable(&dir)?;
    }

    let tuned = case.solver.tolerance.is_some() || case.solver.max_iterations.is_some();
    let mut runners = Vec::with_capacity(methods.len());
    for &method in &methods {
        let clock = Instant::now();
        let runner = Runner::new(method, case, &structure, &taut, true)?;
        let shared = if method.is_latin() {
            structure_seconds
        } else {
            structure_seconds + taut_seconds
        };
        runners.push((method, runner, shared + clock.elapsed().as_secs_f64()));
    }
    let reference_method = match case.solver.reference {
        Reference::Newton => Some(Method::Newton),
        Reference::PcgLcp => Some(Method::PcgLcp),
        Reference::None => None,
    }
    .filter(|_| methods.iter().any(|m| m.is_latin()));
    let mut reference_source = match reference_method {
        None => ReferenceSource::Unneeded,
        Some(m) => match runners.iter().position(|(rm, _, _)| *rm == m && !tuned) {
            Some(i) => ReferenceSource::Shared(i),
            None => ReferenceSource::Own(Box::new(Runner::new(m, case, &structure, &taut, false)?)),
        },
    };

    let summary_path = dir.join("summary.csv");
    let mut rows = Vec::new();
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
            let solution = match (&reference_source, &reference) {
                (ReferenceSource::Shared(i), Some(r)) if *i == index => r.clone(),
                _ if method.is_latin() && case.output.history => {
                    let mut history =
                        HistoryWriter::create(&dir, method.name(), alpha, structure.n_cables())
                            .map_err(|e| write_error(&dir.join("history"), e))?;
                    let solution = runner.solve(&load, reference_u, &mut history);
                    history
                        .finish()
                        .map_err(|e| write_error(&dir.join("history"), e))?;
                    solution
                }
                _ => runner.solve(&load, reference_u, &mut Silent),
            };
            let eq = &solution.equilibrium;
            let row = SummaryRow {
                solver: method.name().to_string(),
                alpha,
                converged: solution.info.status.converged(),
                iterations: solution.info.iterations,
                slack_cables: eq.slack_count(),
                cables: structure.n_cables(),
                max_tension: results::max_cable_tension(&structure, eq),
                max_deflection: results::max_deflection(&structure, eq),
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
            if case.output.tensions {
                output::write_tensions(&dir, method.name(), alpha, &structure, eq)
                    .map_err(|e| write_error(&dir.join("tensions"), e))?;
            }
            if case.output.displacements {
                output::write_displacements(&dir, method.name(), alpha, &structure, eq)
                    .map_err(|e| write_error(&dir.join("displacements"), e))?;
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
    if failures.is_empty() {
        Ok(rows)
    } else {
        Err(RunError::NotConverged {
            count: failures.len(),
            list: failures.join("; "),
        })
    }
}
