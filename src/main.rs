//! `tensolve`: the command line. Parses arguments, loads the case, hands it to the library and
//! turns errors into messages and exit codes (0 success, 2 bad input, 1 run could not produce
//! what was asked).

use clap::{Parser, Subcommand};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use tensolve::case::{self, Method};
use tensolve::output::alpha_label;
use tensolve::run::{run, RunError, RunOptions};
use tensolve::solvers::latin::{Latin, LatinSettings, SearchDirection};
use tensolve::solvers::TautStiffness;
use tensolve::structure::Structure;

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
    /// (invalid case, a structure that is a mechanism, an unwritable output directory); 1 when
    /// a solve did not converge (its row says converged = false) or a file could not be written.
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
    },
    /// Validate a case and print the model it describes: nodes, dofs, links, self-stress
    /// balance and whether the stiffness with every cable taut is regular.
    Check {
        /// The case file (TOML).
        case: PathBuf,
    },
}

fn parse_method(name: &str) -> Result<Method, String> {
    Method::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        format!("unknown solver `{name}`; use one of: {}", names.join(", "))
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            case,
            out,
            solvers,
            quiet,
        } => run_command(case, out, solvers, quiet),
        Command::Check { case } => check_command(case),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn run_command(
    path: PathBuf,
    out: Option<PathBuf>,
    solvers: Vec<Method>,
    quiet: bool,
) -> Result<(), RunError> {
    let case = case::load(&path)?;
    let options = RunOptions {
        out_dir: out,
        methods: (!solvers.is_empty()).then_some(solvers),
    };
    let dir = tensolve::run::output_dir(&case, &options);
    let mut print_row = |r: &tensolve::output::SummaryRow| {
        if !quiet {
            eprintln!(
                "{:>8} alpha = {:<6} {} in {} it, {} / {} slack, residual {:.1e}, {:.1} ms",
                r.solver,
                alpha_label(r.alpha),
                if r.converged {
                    "converged"
                } else {
                    "NOT converged"
                },
                r.iterations,
                r.slack_cables,
                r.cables,
                r.residual,
                1e3 * r.solve_seconds
            );
        }
    };
    let result = run(&case, &options, &mut print_row);
    if !quiet
        && !matches!(
            result,
            Err(RunError::Case(_) | RunError::Setup(_) | RunError::OutputDir { .. })
        )
    {
        eprintln!("results in {}", dir.display());
    }
    result.map(|_| ())
}

fn check_command(path: PathBuf) -> Result<(), RunError> {
    let case = case::load(&path)?;
    let s = Structure::from_case(&case);
    let mut out = String::new();
    let n_nodes = s.n_nodes();
    let _ = writeln!(out, "case            {}", path.display());
    let _ = writeln!(
        out,
        "grid            {} x {} modules ({:?})",
        s.layout.nx, s.layout.ny, case.grid.module
    );
    let _ = writeln!(out, "nodes           {n_nodes}");
    let _ = writeln!(out, "dofs            {}", 3 * n_nodes);
    let _ = writeln!(out, "free dofs       {}", s.n_free);
    let _ = writeln!(
        out,
        "clamped nodes   {}",
        s.clamped.iter().filter(|&&c| c).count()
    );
    let _ = writeln!(
        out,
        "cables          {} ({})",
        s.n_cables(),
        if case.cables.unilateral {
            "unilateral"
        } else {
            "bilateral"
        }
    );
    let _ = writeln!(out, "bars            {}", s.n_bars());
    let _ = writeln!(
        out,
        "max |B^T t0|    {:.3e} N ({:.1e} of the lower cable prestress)",
        s.prestress_imbalance(),
        if s.prestress_scale > 0.0 {
            s.prestress_imbalance() / s.prestress_scale
        } else {
            0.0
        }
    );
    let alphas: Vec<String> = case.load.alphas.iter().map(|&a| alpha_label(a)).collect();
    let _ = writeln!(out, "load factors    {}", alphas.join(", "));
    let methods: Vec<&str> = case.solver.methods.iter().map(|m| m.name()).collect();
    let _ = writeln!(out, "solvers         {}", methods.join(", "));
    let result = check_solvers(&case, &s, &mut out);
    print_ignoring_closed_pipe(&out);
    result
}

/// The taut stiffness, and the partition of every LATIN solver the case asks for.
fn check_solvers(case: &case::Case, s: &Structure, out: &mut String) -> Result<(), RunError> {
    TautStiffness::new(s)?;
    let _ = writeln!(
        out,
        "stiffness       positive definite with every cable taut"
    );
    for &method in case.solver.methods.iter().filter(|m| m.is_latin()) {
        let subdomains = if method == Method::MonoLatin {
            [1, 1]
        } else {
            case.solver.partition()
        };
        let settings = LatinSettings {
            subdomains,
            dm: case.solver.dm,
            search: case.solver.search.unwrap_or(SearchDirection::Stiffness),
            weak: case.solver.weak_interfaces,
            ..LatinSettings::default()
        };
        let r = Latin::new(s, settings)?.report();
        let _ = writeln!(out, "{}:", method.name());
        let _ = writeln!(
            out,
            "  substructures {} ({} x {}), largest {} free dofs",
            r.substructures, subdomains[0], subdomains[1], r.max_substructure_dofs
        );
        let _ = writeln!(
            out,
            "  interfaces    {} ({} strong, {} weak, {} dropped; weak = {:?})",
            r.interfaces,
            r.strong_interfaces,
            r.weak_interfaces,
            r.dropped_interfaces,
            settings.weak
        );
        let _ = writeln!(out, "  macro dofs    {}", r.macro_dofs);
        let _ = writeln!(out, "  kernel cols   {}", r.kernel_columns);
    }
    Ok(())
}

/// Print to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn print_ignoring_closed_pipe(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}
