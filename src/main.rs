//! `tensolve`: the command line. Parses arguments, loads the case, hands it to the library and
//! turns errors into messages and exit codes (0 success, 2 bad input, 3 output directory in
//! use by another run, 1 run could not produce what was asked).

/// The command line's own modules.
mod cli {
    pub mod failure;
    pub mod model_warning;
    pub mod progress;
}

use anyhow::Context;
use clap::{Parser, Subcommand};
use cli::failure::{exit_code_of, message_of, Refusal};
use cli::progress::{report_bench, Reporter};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use tensolve::app::bench::{self, BenchError};
use tensolve::app::check::check;
use tensolve::app::combinations::run_combinations;
use tensolve::app::compare::{compare, CompareSettings};
use tensolve::app::design::design;
use tensolve::app::memory::{self, MemoryEstimate, Workload};
use tensolve::app::ranks::{case_digest, load_case, Ranks};
use tensolve::app::stages::run_stages;
use tensolve::app::sweep::{output_dir, run_on, RunError, RunEvent, RunOptions, Sharing};
use tensolve::case;
use tensolve::host;
use tensolve::output::alpha_label;
use tensolve::solvers::latin::RankLayout;
use tensolve::solvers::Method;
use tensolve::structure::StructureSize;

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
    /// Time every solver of a case at every α against a reference: the energy error e of every
    /// iterate against wall time (set-up included).
    ///
    /// The reference is solved by `solver.reference` (newton unless the case says pcg-lcp) at
    /// its default settings; "none" is refused. Writes `bench.csv` (solver, alpha, iteration,
    /// seconds, error_e) and `bench.svg` (e against wall time, log-log) and prints, per solver
    /// and α, the wall time to reach e <= 1e-2, 1e-3, 1e-4, 1e-6 and 1e-8. Exit status as for
    /// `run`: 2 on bad input (solver.reference = "none" included), 1 when a solver or the
    /// reference did not converge or a file could not be written.
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
    /// Design the prestress of a case whose `prestress.from` is "design" or "force-density":
    /// print the counts s, m, s₂, the rank decision, each group's force, force density and rest
    /// length and the prestress-stability verdict; with --out, write DIR/nodes.csv,
    /// DIR/members.csv, DIR/groups.csv and DIR/<case>.toml, a case `run` takes as written.
    ///
    /// Exit status: 2 on bad input (an infeasible design included; nothing is written), 1 when
    /// a file could not be written.
    Design {
        /// The case file (TOML).
        case: PathBuf,
        /// Where to write the designed case (nothing is written without it).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Instead of `prestress.from`: project the members table's nearly balanced prestress
        /// (rounded coordinates) on the self-stress states, least squares, and report the
        /// largest change (never done by `run`).
        #[arg(long)]
        rebalance: bool,
        /// Override a case key, in TOML syntax (repeatable; validated like the file).
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

/// A write past a file-size limit (`ulimit -f`) raises SIGXFSZ, whose default action ends the
/// process with no word (exit 153 in a shell). Ignored, the write fails with EFBIG instead,
/// and the run reports it as an error naming the file (exit 1).
fn report_file_size_limit_as_write_error() {
    #[cfg(unix)]
    // SAFETY: SIG_IGN installs no handler; it is set before any other thread starts.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

fn main() -> ExitCode {
    report_file_size_limit_as_write_error();
    tensolve::app::allocator::retain_freed_memory();
    let cli = Cli::parse();
    let ranks = Ranks::init();
    let result = dispatch(cli.command, &ranks);
    // Every rank exits with the worst status of any. Rank 0 says why; where it has nothing to
    // say (it did not fail, or failed only because another rank did), the rank that failed.
    let (code, message) = match &result {
        Ok(()) => (0u8, String::new()),
        Err(e) => (exit_code_of(e), message_of(e)),
    };
    let root_said = ranks.broadcast(vec![u8::from(!message.is_empty())]).first() == Some(&1);
    let worst = ranks.max(u64::from(code)) as u8;
    if !message.is_empty() {
        if ranks.is_root() {
            eprintln!("error: {message}");
        } else if !root_said {
            eprintln!("error (MPI rank {}): {message}", ranks.rank());
        }
    }
    ExitCode::from(worst)
}

/// The command asked for, with the step and file it was on as the context of its error.
fn dispatch(command: Command, ranks: &Ranks) -> anyhow::Result<()> {
    let step = |verb: &str, path: &Path| format!("{verb} `{}`", path.display());
    match command {
        Command::Bench { case, set, .. } if ranks.size() > 1 => {
            refuse_on_ranks(ranks, "bench", &case, &set).context(step("bench", &case))
        }
        Command::Run {
            case,
            out,
            solvers,
            quiet,
            set,
        } => {
            let context = step("run", &case);
            run_command(ranks, case, out, solvers, quiet, &set).context(context)
        }
        Command::Check { case, set } => {
            let context = step("check", &case);
            check_command(ranks, case, &set).context(context)
        }
        Command::Design {
            case,
            out,
            set,
            rebalance,
        } => root_only(ranks, || {
            let report = design(&case, &set, out.as_deref(), rebalance)
                .with_context(|| step("design", &case))?;
            print_ignoring_closed_pipe(&report.to_string());
            Ok(())
        }),
        Command::Bench {
            case,
            out,
            quiet,
            set,
        } => bench_command(&case, out, quiet, &set).with_context(|| step("bench", &case)),
        Command::Compare {
            run,
            golden,
            rtol,
            atol,
            slack_tolerance,
        } => root_only(ranks, || {
            let settings = CompareSettings {
                rtol,
                atol,
                slack_tolerance,
            };
            compare_command(&run, &golden, settings)
                .with_context(|| format!("compare `{}` with `{}`", run.display(), golden.display()))
        }),
    }
}

/// `command` on rank 0 alone; the other ranks exit with its status (`main` shares the worst
/// status of all ranks).
fn root_only(ranks: &Ranks, command: impl FnOnce() -> anyhow::Result<()>) -> anyhow::Result<()> {
    if ranks.is_root() {
        command()
    } else {
        Ok(())
    }
}

/// `bench` on several MPI ranks: the case is loaded as everywhere (its errors come first, from
/// rank 0), then refused: bench measures one process (`run` on P ranks reports its time).
fn refuse_on_ranks(
    ranks: &Ranks,
    command: &str,
    path: &Path,
    set: &[String],
) -> anyhow::Result<()> {
    load_case(ranks, path, set).map_err(RunError::from)?;
    Err(anyhow::Error::new(Refusal {
        message: format!(
            "`tensolve {command}` on {} MPI ranks: bench measures one process; run it \
             without mpirun (or `mpirun -n 1`), and `tensolve run` under mpirun for the \
             time of a solve shared by ranks",
            ranks.size()
        ),
        exit_code: 2,
    }))
}

fn run_command(
    ranks: &Ranks,
    path: PathBuf,
    out: Option<PathBuf>,
    solvers: Vec<Method>,
    quiet: bool,
    set: &[String],
) -> Result<(), RunError> {
    let case = load_case(ranks, &path, set)?;
    let tolerance = case.model_tolerance;
    let quiet = quiet || !ranks.is_root();
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
        * case.load.alphas.len()
        * case.load.combinations.len().max(1)
        * case.stages.len().max(1);
    let mut reporter = Reporter::new(quiet, solves);
    reporter.forbid_slack = case.forbid_slack;
    let exchange = ranks.exchange();
    let mut events = |event: RunEvent<'_>| reporter.run_event(event);
    let result = match (case.stages.is_empty(), case.load.combinations.is_empty()) {
        (false, _) => run_stages(&case, &options, &exchange, &mut events).map(|_| ()),
        (true, true) => run_on(case, &options, &exchange, &mut events).map(|_| ()),
        (true, false) => run_combinations(&case, &options, &exchange, &mut events).map(|_| ()),
    };
    if ranks.size() > 1 {
        // The most links a rank kept, and a rank other than 0 (every rank asks, whatever the
        // run's end).
        let (kept, whole) = reporter.links_kept.unwrap_or((0, 0));
        let most = ranks.max(kept as u64);
        let others = ranks.max(if ranks.is_root() { 0 } else { kept as u64 });
        let set_up = reporter.links_kept.is_some();
        let kept_line = match (kept < whole, others < whole as u64) {
            (true, _) => format!(
                "MPI: every rank kept only its substructures' links, at most {most} of {whole} \
                 (the answers' rows measured by the ranks together)"
            ),
            (false, true) if ranks.size() == 2 => format!(
                "MPI: rank 1 kept only its substructures' links, {others} of {whole}; rank 0 \
                 kept the whole structure (it writes files that read every link)"
            ),
            (false, true) => format!(
                "MPI: ranks 1 to {} kept only their substructures' links, at most {others} of \
                 {whole}; rank 0 kept the whole structure (it writes files that read every link)",
                ranks.size() - 1
            ),
            (false, false) => format!(
                "MPI: every rank kept the whole structure ({})",
                Sharing::WHEN_SHARED
            ),
        };
        if set_up {
            reporter.line(&kept_line);
        }
        reporter.line(&format!(
            "MPI: {} ranks; rank 0 received {} values ({}) in {} collective and \
             point-to-point calls, {:.3} s in them (waiting for the other ranks included)",
            ranks.size(),
            exchange.values_received(),
            match 8 * exchange.values_received() {
                tiny @ 0..1_000 => format!("{tiny} B"),
                small @ 1_000..1_000_000 => format!("{:.1} kB", small as f64 / 1e3),
                bytes => tensolve::host::bytes_text(bytes),
            },
            exchange.calls(),
            exchange.seconds()
        ));
    }
    reporter.finish();
    if let Some(off) = &reporter.model_off_by {
        reporter.line(&cli::model_warning::off_by_warning(off, tolerance));
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
    result
}

fn bench_command(
    path: &Path,
    out: Option<PathBuf>,
    quiet: bool,
    set: &[String],
) -> Result<(), BenchError> {
    let mut case = case::load_with(path, set)?;
    // Refused before anything else when there is no reference to measure e against.
    let reference = bench::reference_method(&case)?;
    let work = Workload::bench(&case, reference);
    let estimate = MemoryEstimate::new(StructureSize::of(&case.geometry), &work);
    memory::ensure_fits(&estimate, "bench").map_err(BenchError::Case)?;
    let dir = out.unwrap_or_else(|| bench::default_dir(path));
    let mut reporter = Reporter::new(quiet, case.solver.methods.len() * case.load.alphas.len());
    reporter.begin_stage("building the structure and factorising its taut stiffness");
    // Under `auto`, every α is measured on the model it starts with.
    let prepared = tensolve::app::auto::prepare_start(&mut case, true).map(|(p, _)| p);
    reporter.end_stage();
    if prepared.is_err() {
        reporter.finish();
    }
    let prepared = prepared?;
    // Held until the files are written.
    let _lock = bench::lock_writable(&dir)?;
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

fn check_command(ranks: &Ranks, path: PathBuf, set: &[String]) -> anyhow::Result<()> {
    // Every rank loads the same case (rank 0's bytes); rank 0 alone checks and prints.
    let case = load_case(ranks, &path, set).map_err(RunError::from)?;
    if !ranks.same_on_every_rank(case_digest(&case)) {
        return Err(anyhow::Error::new(Refusal {
            message: "the MPI ranks loaded different cases from rank 0's bytes (a defect: \
                      please report it)"
                .into(),
            exit_code: 1,
        }));
    }
    root_only(ranks, || {
        check_case(ranks, case, path).map_err(anyhow::Error::from)
    })
}

fn check_case(ranks: &Ranks, case: case::Case, path: PathBuf) -> Result<(), RunError> {
    // What check itself allocates (a rank factorization, the LATIN set-ups) must fit first.
    // The memory available is read once, before check builds anything: read later, what check
    // itself holds (the structure, the set-ups) would count against the run.
    tensolve::app::sweep::outputs_have_their_solvers(&case, &case.solver.methods)?;
    let available = host::available();
    let own = MemoryEstimate::new(StructureSize::of(&case.geometry), &Workload::check(&case));
    memory::ensure_fits_in(&own, "check", available.clone())?;
    let layout = (ranks.size() > 1)
        .then(|| case.solver.latin_settings(Method::MicroMacro))
        .flatten()
        .filter(|_| case.solver.methods.contains(&Method::MicroMacro))
        .map(|settings| RankLayout::new(&case.structure(), &settings, ranks.size()));
    let report = check(&case, path, available.clone());
    print_ignoring_closed_pipe(&report.to_string());
    if let Some(layout) = layout {
        print_ignoring_closed_pipe(&layout.describe());
        print_ignoring_closed_pipe(&format!(
            "  links: {}\n",
            Sharing::of_run(&case, ranks.size()).describe()
        ));
        print_ignoring_closed_pipe(&format!(
            "  every rank loaded the same case (from rank 0's bytes; digest {:016x} on all {} \
             ranks)\n",
            case_digest(&case),
            ranks.size()
        ));
    } else if ranks.size() > 1 {
        print_ignoring_closed_pipe(&format!(
            "ranks: {} (no micro-macro solver in the case: nothing to distribute)\n",
            ranks.size()
        ));
    }
    match report.error {
        Some(e) => Err(e.into()),
        // A case `run` would refuse for its memory is not valid here either.
        None => memory::ensure_fits_in(&report.memory, "run", available).map_err(RunError::from),
    }
}

/// Print to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn print_ignoring_closed_pipe(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// `compare`: the report on stdout; exit 1 when the runs differ, 2 when they cannot be compared.
fn compare_command(run: &Path, golden: &Path, settings: CompareSettings) -> anyhow::Result<()> {
    let bad = |message: String| {
        anyhow::Error::new(Refusal {
            message,
            exit_code: 2,
        })
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
        Err(anyhow::Error::new(Refusal {
            message: format!(
                "{} file(s) and {} column(s) differ between {} and {}",
                report.files_differ.len(),
                report.differences.len(),
                run.display(),
                golden.display()
            ),
            exit_code: 1,
        }))
    }
}
