//! `tensolve`: the command line. Parses arguments, loads the case, hands it to the library and
//! turns errors into messages and exit codes (0 success, 2 bad input, 3 output directory in
//! use by another run, 1 run could not produce what was asked).

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};
use tensolve::app::bench::{self, BenchError, Progress};
use tensolve::app::check::check;
use tensolve::app::compare::{compare, CompareSettings};
use tensolve::app::sweep::{output_dir, run, RunError, RunEvent, RunOptions};
use tensolve::case;
use tensolve::case::memory::{self, MemoryEstimate, Size, Workload};
use tensolve::output::{alpha_label, SummaryRow};
use tensolve::solvers::{IterationRecord, Measure, Method};

/// Static equilibrium of tensegrity grids whose cables can go slack.
///
/// A TOML case file says what structure to build, which solvers to run over which load factors
/// α, and which files to write (see the README for every key).
#[derive(Parser)]
#[command(name = "tensolve", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve every load factor α of a case with every solver asked for, and write the results.
    ///
    /// Exit status: 0 when every solve converged and every file was written; 2 on bad input
    /// (invalid case, a structure that is a mechanism, an unwritable output directory); 3 when
    /// another run holds the output directory; 1 when a solve did not converge (its row says
    /// converged = false) or a file could not be written.
    Run {
        /// The case file (TOML).
        case: PathBuf,
        /// Output directory; overrides `output.dir` (default `out/<case file stem>`).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Solver(s) to run instead of `solver.methods`: newton, pcg-lcp, mono-latin,
        /// micro-macro. Repeat or separate with commas.
        #[arg(long = "solver", value_name = "NAME", value_delimiter = ',', value_parser = parse_method)]
        solvers: Vec<Method>,
        /// Print nothing but errors.
        #[arg(long)]
        quiet: bool,
        /// Override a case key, in TOML syntax: `--set solver.dm=2e6`, `--set
        /// 'load.alpha=[0.5, 1.0]'`. Repeatable; validated like the file.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Validate a case and print the model it describes: nodes, dofs, links, self-stress
    /// balance and whether the stiffness with every cable taut is regular.
    Check {
        /// The case file (TOML).
        case: PathBuf,
        /// Override a case key, in TOML syntax: `--set solver.dm=2e6`, `--set
        /// 'load.alpha=[0.5, 1.0]'`. Repeatable; validated like the file.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Time every solver of a case at every α against a newton reference: the energy error e
    /// of every iterate against wall time (set-up included).
    ///
    /// Writes `bench.csv` (solver, alpha, iteration, seconds, error_e) and `bench.svg` (e
    /// against wall time, log-log) and prints, per solver and α, the wall time to reach
    /// e <= 1e-2, 1e-3, 1e-4, 1e-6 and 1e-8. Exit status as for `run`: 2 on bad input, 1 when a
    /// solver or the reference did not converge or a file could not be written.
    Bench {
        /// The case file (TOML).
        case: PathBuf,
        /// Output directory (default `out/<case file stem>-bench`).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// No progress on stderr (the table still goes to stdout).
        #[arg(long)]
        quiet: bool,
        /// Override a case key, in TOML syntax: `--set solver.dm=2e6`, `--set
        /// 'load.alpha=[0.5, 1.0]'`. Repeatable; validated like the file.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Compare a run's output directory with a stored (golden) one, for CI regression.
    ///
    /// Every CSV of GOLDEN (summary, tensions, displacements, histories) must be in RUN with
    /// the same columns; numbers must agree within `atol + rtol · max(|a|, |b|)`, other values
    /// exactly; timing columns (`*seconds`) are left out; slack counts and slack sets must
    /// match exactly unless `--slack-tolerance` says otherwise. Prints what differs and by how
    /// much. Exit status: 0 when the runs agree, 1 when they differ, 2 on bad input (a
    /// directory or a golden file missing, different columns).
    Compare {
        /// The run's output directory.
        run: PathBuf,
        /// The stored run to compare against.
        golden: PathBuf,
        /// Relative tolerance on numbers.
        #[arg(long, default_value_t = CompareSettings::default().rtol)]
        rtol: f64,
        /// Absolute tolerance on numbers.
        #[arg(long, default_value_t = CompareSettings::default().atol)]
        atol: f64,
        /// How many cables a slack count or a slack set may differ by.
        #[arg(long, default_value_t = CompareSettings::default().slack_tolerance)]
        slack_tolerance: u64,
    },
}

fn parse_method(name: &str) -> Result<Method, String> {
    Method::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("unknown solver `{name}`; use one of: {}", names.join(", "))
    })
}

/// A command's error message and the exit status it maps to.
struct Failure {
    message: String,
    exit_code: i32,
}

impl From<RunError> for Failure {
    fn from(e: RunError) -> Self {
        Failure {
            message: e.to_string(),
            exit_code: e.exit_code(),
        }
    }
}

impl From<BenchError> for Failure {
    fn from(e: BenchError) -> Self {
        Failure {
            message: e.to_string(),
            exit_code: e.exit_code(),
        }
    }
}

fn main() -> ExitCode {
    tensolve::app::allocator::retain_freed_memory();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            case,
            out,
            solvers,
            quiet,
            set,
        } => run_command(case, out, solvers, quiet, &set).map_err(Failure::from),
        Command::Check { case, set } => check_command(case, &set).map_err(Failure::from),
        Command::Bench {
            case,
            out,
            quiet,
            set,
        } => bench_command(&case, out, quiet, &set).map_err(Failure::from),
        Command::Compare {
            run,
            golden,
            rtol,
            atol,
            slack_tolerance,
        } => compare_command(
            &run,
            &golden,
            CompareSettings {
                rtol,
                atol,
                slack_tolerance,
            },
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.message);
            ExitCode::from(e.exit_code as u8)
        }
    }
}

/// Progress on stderr: a bar on a terminal (lines printed above it, a spinner and what is
/// running beside it), plain lines when stderr is not a terminal, nothing with `--quiet`.
enum Display {
    Quiet,
    Lines,
    Bar(ProgressBar),
}

/// The bar's message is redrawn at most this often.
const BAR_REFRESH: Duration = Duration::from_millis(100);
/// Without a terminal, a running solve prints its iterate at most this often.
const LINE_REFRESH: Duration = Duration::from_secs(10);
/// Without a terminal, a set-up step longer than this prints what it did and how long it took.
const LONG_STAGE: Duration = Duration::from_secs(1);

/// What the progress display knows of the run: the set-up step or solve in progress.
struct Reporter {
    display: Display,
    /// The set-up step in progress and when it began.
    stage: Option<(String, Instant)>,
    /// When the display last showed an iterate.
    shown: Instant,
    /// The last e reported in the solve in progress (LATIN against its reference).
    last_error: Option<f64>,
    /// Rows whose left-out geometric term is above its limit: how many, and the largest (value,
    /// solver and α).
    geometric: (usize, Option<(f64, String)>),
}

impl Reporter {
    fn new(quiet: bool, ticks: usize) -> Reporter {
        let display = if quiet {
            Display::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(ticks as u64);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner:.green} {bar:30.cyan/blue} {pos}/{len} solves [{elapsed}] {msg}",
                )
                .expect("valid template"),
            );
            // Redrawn on a timer too: a long set-up or solve sends nothing for seconds.
            bar.enable_steady_tick(Duration::from_millis(120));
            Display::Bar(bar)
        } else {
            Display::Lines
        };
        Reporter {
            display,
            stage: None,
            shown: Instant::now(),
            last_error: None,
            geometric: (0, None),
        }
    }

    fn line(&self, text: &str) {
        match &self.display {
            Display::Quiet => {}
            Display::Lines => eprintln!("{text}"),
            Display::Bar(bar) => bar.println(text),
        }
    }

    /// What is running now (shown on the bar only).
    fn status(&self, text: String) {
        if let Display::Bar(bar) = &self.display {
            bar.set_message(text);
        }
    }

    fn tick(&self) {
        if let Display::Bar(bar) = &self.display {
            bar.inc(1);
        }
    }

    fn finish(&mut self) {
        self.end_stage();
        if let Display::Bar(bar) = &self.display {
            bar.finish_and_clear();
        }
    }

    /// A set-up step began.
    fn begin_stage(&mut self, text: &str) {
        self.end_stage();
        self.status(format!("{text} ..."));
        self.stage = Some((text.to_string(), Instant::now()));
    }

    /// The step in progress ended: without a terminal, a long one is reported with its time.
    fn end_stage(&mut self) {
        if let Some((text, start)) = self.stage.take() {
            let took = start.elapsed();
            if matches!(self.display, Display::Lines) && took > LONG_STAGE {
                self.line(&format!("{text}: {:.1} s", took.as_secs_f64()));
            }
        }
    }

    /// One event of `tensolve run`.
    fn run_event(&mut self, event: RunEvent<'_>) {
        match event {
            RunEvent::Stage(text) => self.begin_stage(text),
            RunEvent::SolveStart { solver, alpha } => {
                self.end_stage();
                self.last_error = None;
                self.shown = Instant::now();
                self.status(format!("{solver} alpha = {}: starting", alpha_label(alpha)));
            }
            RunEvent::Iteration {
                solver,
                alpha,
                measure,
                record,
            } => {
                self.last_error = record.error.or(self.last_error);
                let refresh = match self.display {
                    Display::Quiet => return,
                    Display::Lines => LINE_REFRESH,
                    Display::Bar(_) => BAR_REFRESH,
                };
                if self.shown.elapsed() < refresh {
                    return;
                }
                self.shown = Instant::now();
                let text = iterate_message(solver, alpha, measure, record);
                match self.display {
                    Display::Lines => self.line(&format!("  {text}")),
                    _ => self.status(text),
                }
            }
            RunEvent::Row(row) => {
                if row.needs_large() {
                    let value = row.geometric_term.unwrap_or(0.0);
                    self.geometric.0 += 1;
                    if self.geometric.1.as_ref().is_none_or(|(v, _)| value > *v) {
                        let at = format!("{}, alpha {}", row.solver, alpha_label(row.alpha));
                        self.geometric.1 = Some((value, at));
                    }
                }
                let mut text = format_row(row);
                if let Some(e) = self.last_error.take() {
                    text.push_str(&format!(", e = {e:.1e}"));
                }
                self.line(&text);
                self.tick();
            }
        }
    }
}

/// `micro-macro alpha = 0.5: iteration 37, eta = 3.2e-4, e = 1.1e-3, 12 slack, 0.84 s`: a
/// solve in progress, e when the solve is measured against a reference.
fn iterate_message(solver: &str, alpha: f64, measure: Measure, record: &IterationRecord) -> String {
    let mut text = format!(
        "{solver} alpha = {}: iteration {}, {} = {:.1e}",
        alpha_label(alpha),
        record.iteration,
        measure.short_name(),
        record.residual
    );
    if let Some(e) = record.error {
        text.push_str(&format!(", e = {e:.1e}"));
    }
    text.push_str(&format!(
        ", {} slack, {:.2} s",
        record.slack_cables, record.elapsed_seconds
    ));
    text
}

fn format_row(r: &SummaryRow) -> String {
    let mut line = format!(
        "{:>11} alpha = {:<6} {} in {} it, {} / {} slack, {}r(U) {:.1e}, {:.1} ms",
        r.solver,
        alpha_label(r.alpha),
        match (r.converged, r.at_roundoff) {
            // A LATIN stop on Δη at round-off of the prestress: η is then a ratio of round-off
            // to round-off (no load), not a measure of anything.
            (true, true) if r.alpha == 0.0 => {
                "converged (no load: Δη at round-off of the prestress)".to_string()
            }
            (true, true) => "converged (Δη at round-off of the prestress)".to_string(),
            (true, false) => "converged".to_string(),
            (false, _) => format!("NOT converged ({})", r.status),
        },
        r.iterations,
        r.slack_cables,
        r.cables,
        // The stopping measure beside r(U), when it is another measure (and means something).
        match r.measure {
            _ if r.converged && r.at_roundoff => String::new(),
            Measure::EquilibriumResidual => String::new(),
            Measure::ComplementarityResidual => format!("complementarity {:.1e}, ", r.residual),
            Measure::Indicator => format!("eta {:.1e}, ", r.residual),
        },
        r.equilibrium_residual,
        1e3 * r.solve_seconds
    );
    if !r.status.no_answer() && r.max_member_rotation > tensolve::results::SMALL_DISPLACEMENT_LIMIT
    {
        line.push_str(&format!(
            "\n  warning: {} at alpha = {}: a member's ends moved apart by {:.0} % of its length \
             (max deflection {:.3} m); the small-perturbation model (geometry not updated) is \
             not valid beyond {:.0} %: read this row with care (summary.csv: \
             small_displacement_ok = false)",
            r.solver,
            alpha_label(r.alpha),
            100.0 * r.max_member_rotation,
            r.max_deflection,
            100.0 * tensolve::results::SMALL_DISPLACEMENT_LIMIT
        ));
    }
    line
}

fn run_command(
    path: PathBuf,
    out: Option<PathBuf>,
    solvers: Vec<Method>,
    quiet: bool,
    set: &[String],
) -> Result<(), RunError> {
    let case = case::load_with(&path, set)?;
    let options = RunOptions {
        out_dir: out,
        methods: (!solvers.is_empty()).then_some(solvers),
    };
    let dir = output_dir(&case, &options);
    let solves = options
        .methods
        .as_ref()
        .unwrap_or(&case.solver.methods)
        .len()
        * case.load.alphas.len();
    let mut reporter = Reporter::new(quiet, solves);
    let result = run(&case, &options, &mut |event| reporter.run_event(event));
    reporter.finish();
    if let (count, Some((largest, at))) = &reporter.geometric {
        reporter.line(&format!(
            "warning: {count} row(s) leave out a geometric term (the members' rotation under \
             their tension) that changes the answer by more than {:.0} % (up to {:.1} %: {at}): \
             `model.geometry = \"large\"` computes the large-displacement answer (summary.csv: \
             geometric_term, small_displacement_ok = false)",
            100.0 * tensolve::results::GEOMETRIC_TERM_LIMIT,
            100.0 * largest
        ));
    }
    if !matches!(
        result,
        Err(RunError::Case(_)
            | RunError::Setup(_)
            | RunError::OutputDir { .. }
            | RunError::Busy(_))
    ) {
        reporter.line(&format!("results in {}", dir.display()));
    }
    result.map(|_| ())
}

fn bench_command(
    path: &Path,
    out: Option<PathBuf>,
    quiet: bool,
    set: &[String],
) -> Result<(), BenchError> {
    let case = case::load_with(path, set)?;
    let estimate = MemoryEstimate::new(Size::of(&case), &Workload::bench(&case));
    memory::ensure_fits(&estimate, "bench").map_err(BenchError::Case)?;
    let dir = out.unwrap_or_else(|| bench::default_dir(path));
    let mut reporter = Reporter::new(quiet, case.solver.methods.len() * case.load.alphas.len());
    reporter.begin_stage("building the structure and factorising its taut stiffness");
    let prepared = tensolve::app::setup::prepare(&case);
    reporter.end_stage();
    if prepared.is_err() {
        reporter.finish();
    }
    let prepared = prepared?;
    bench::ensure_writable(&dir)?;
    let measured = bench::measure(&case, &prepared, &mut |p| report_bench(&reporter, p));
    reporter.finish();
    let measured = measured?;
    let title = bench_title(path, &case.load.alphas);
    bench::write_files(&dir, &measured, &title)?;
    print_ignoring_closed_pipe(&measured.table.to_string());
    reporter.line(&format!("results in {}", dir.display()));
    measured.check_converged()
}

/// `paper-bench: e against wall time, α = 1`.
fn bench_title(path: &Path, alphas: &[f64]) -> String {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let alphas: Vec<String> = alphas.iter().map(|&a| alpha_label(a)).collect();
    format!("{stem}: e against wall time, α = {}", alphas.join(", "))
}

fn report_bench(reporter: &Reporter, progress: Progress) {
    match progress {
        Progress::Reference { alpha } => reporter.status(format!(
            "reference (newton) at alpha = {}",
            alpha_label(alpha)
        )),
        Progress::Solve { method, alpha } => reporter.status(format!(
            "{} at alpha = {}",
            method.name(),
            alpha_label(alpha)
        )),
        Progress::Done(series) => {
            let last = series.samples.last();
            reporter.line(&format!(
                "{:>11} alpha = {:<6} {:?} after {} it, e = {:.1e}, {:.1} ms (set-up {:.1} ms)",
                series.method.name(),
                alpha_label(series.alpha),
                series.status,
                last.map_or(0, |s| s.iteration),
                last.map_or(f64::NAN, |s| s.error),
                1e3 * last.map_or(0.0, |s| s.seconds),
                1e3 * series.setup_seconds
            ));
            reporter.tick();
        }
    }
}

fn check_command(path: PathBuf, set: &[String]) -> Result<(), RunError> {
    let case = case::load_with(&path, set)?;
    // What check itself allocates (a rank factorization, the LATIN set-ups) must fit first.
    let own = MemoryEstimate::new(Size::of(&case), &Workload::check(&case));
    memory::ensure_fits(&own, "check")?;
    let report = check(&case, path);
    print_ignoring_closed_pipe(&report.to_string());
    match report.error {
        Some(e) => Err(e.into()),
        // A case `run` would refuse for its memory is not valid here either.
        None => memory::ensure_fits(&report.memory, "run").map_err(RunError::from),
    }
}

/// Print to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn print_ignoring_closed_pipe(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// `compare`: the report on stdout; exit 1 when the runs differ, 2 when they cannot be compared.
fn compare_command(run: &Path, golden: &Path, settings: CompareSettings) -> Result<(), Failure> {
    let bad = |message: String| Failure {
        message,
        exit_code: 2,
    };
    if !(settings.rtol.is_finite() && settings.rtol >= 0.0) {
        return Err(bad(format!(
            "--rtol {}: give a relative tolerance >= 0, e.g. 1e-6",
            settings.rtol
        )));
    }
    if !(settings.atol.is_finite() && settings.atol >= 0.0) {
        return Err(bad(format!(
            "--atol {}: give an absolute tolerance >= 0, e.g. 1e-12",
            settings.atol
        )));
    }
    let report = compare(run, golden, &settings).map_err(|e| bad(e.to_string()))?;
    // `compare … | head`: a reader that stops early ends the report, not the command.
    print_ignoring_closed_pipe(&report.to_string());
    if report.agree() {
        Ok(())
    } else {
        Err(Failure {
            message: format!(
                "{} file(s) and {} column(s) differ between {} and {}",
                report.files_differ.len(),
                report.differences.len(),
                run.display(),
                golden.display()
            ),
            exit_code: 1,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_iterate_shows_solver_alpha_iteration_measure_error_and_time() {
        let record = IterationRecord {
            iteration: 37,
            residual: 3.2e-4,
            equilibrium_residual: Some(1e-6),
            setups: 0,
            error: Some(1.1e-3),
            slack_cables: 12,
            elapsed_seconds: 0.84,
        };
        assert_eq!(
            iterate_message("micro-macro", 0.5, Measure::Indicator, &record),
            "micro-macro alpha = 0.5: iteration 37, eta = 3.2e-4, e = 1.1e-3, 12 slack, 0.84 s"
        );
        let record = IterationRecord {
            error: None,
            ..record
        };
        assert_eq!(
            iterate_message("pcg-lcp", 1.0, Measure::ComplementarityResidual, &record),
            "pcg-lcp alpha = 1: iteration 37, residual = 3.2e-4, 12 slack, 0.84 s"
        );
    }
}
