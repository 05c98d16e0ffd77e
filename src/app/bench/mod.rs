//! `tensolve bench`: how fast each solver of a case gets close to the exact answer.
//!
//! For every α of the case a reference is solved once with the case's reference solver
//! (`solver.reference`, as for `run`: `newton` unless the case says `pcg-lcp`) at its own tight
//! defaults (not timed). `solver.reference = "none"` is refused before anything is solved:
//! bench measures e, which needs a reference. Then every solver of the case (`solver.methods`, with the case's tolerance and
//! iteration cap) solves the same load once, and the driver reports each of its iterates with
//! its energy error e against the reference ([`crate::solvers::Reference`]) and the time the
//! solver had spent to reach it. Each iterate is recorded as (wall time, e), where the wall
//! time is the solver's set-up (as `summary.csv`'s `setup_seconds`) plus that time; the last
//! iterate is timed at the end of the solve, answer assembled.
//!
//! | file | what |
//! |---|---|
//! | `measure` | the measurement: [`Series`] of [`Sample`]s per solver and α |
//! | `table` | wall time to reach each error level, as printed |
//! | `plot` | `bench.svg`, e against wall time |

mod measure;
mod plot;
mod table;

pub use measure::{measure, reference_method, Bench, Progress, Sample, Series};
pub use plot::render_svg;
pub use table::{Table, TableRow, THRESHOLDS};

use crate::case::CaseError;
use crate::output::{alpha_label, write_atomic};
use crate::solvers::{Method, SetupError, Status};
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Header of `bench.csv`.
pub const CSV_HEADER: &str = "solver,alpha,iteration,seconds,error_e";

/// Why `bench` failed, or did not produce all that was asked.
#[derive(Debug, Error)]
pub enum BenchError {
    /// The case is invalid.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// A solver cannot be set up for the structure.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// The output directory cannot be created or written.
    #[error(
        "output directory `{dir}` is not writable ({reason}): pass `--out DIR` with a directory \
         you can write to"
    )]
    OutputDir {
        /// The directory.
        dir: String,
        /// Why.
        reason: String,
    },
    /// Another `run` or `bench` holds the output directory's lock.
    #[error(
        "output directory `{dir}` is in use by another tensolve run: wait for it, or pass \
         `--out DIR` with another directory"
    )]
    Busy {
        /// The directory.
        dir: String,
    },
    /// A file could not be written.
    #[error("could not write `{path}`: {reason}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// `solver.reference = "none"`: bench has nothing to measure e against.
    #[error(
        "`solver.reference` = \"none\" is not valid for `bench`: bench measures each \
         iterate's energy error e against a reference solve at every alpha. Set it to \
         \"newton\" or \"pcg-lcp\" (`--set 'solver.reference=\"newton\"'`), or use `run`, \
         which leaves e empty without a reference"
    )]
    NoReference,
    /// The reference did not converge, so e cannot be measured.
    #[error(
        "the reference ({} at its default settings) did not converge at alpha = {alpha} \
         ({status:?}, residual {residual:e}), so e cannot be measured",
        .method.name()
    )]
    Reference {
        /// The reference solver (`solver.reference`).
        method: Method,
        /// The load factor.
        alpha: String,
        /// How the reference solve ended.
        status: Status,
        /// Its residual.
        residual: f64,
    },
    /// Some solvers stopped before their stopping criterion.
    #[error(
        "{count} solve(s) stopped before their stopping criterion: {list}; bench.csv and the \
         table show how far they got"
    )]
    NotConverged {
        /// How many.
        count: usize,
        /// Which.
        list: String,
    },
}

impl BenchError {
    /// As for `run`: 2 for bad input (the case, `solver.reference = "none"`, the structure,
    /// the output directory); 1 when the bench could not produce what was asked.
    pub fn exit_code(&self) -> i32 {
        match self {
            BenchError::Case(_)
            | BenchError::NoReference
            | BenchError::Setup(_)
            | BenchError::OutputDir { .. } => 2,
            BenchError::Busy { .. } => 3,
            BenchError::Write { .. }
            | BenchError::Reference { .. }
            | BenchError::NotConverged { .. } => 1,
        }
    }
}

/// `out/<case file stem>-bench`.
pub fn default_dir(case_path: &Path) -> PathBuf {
    let stem = case_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "case".into());
    Path::new("out").join(format!("{stem}-bench"))
}

/// Create `dir`, make sure a file can be written in it, and lock it for the bench (as `run`
/// does: two processes never write one directory); the lock lasts as long as the file.
pub fn lock_writable(dir: &Path) -> Result<std::fs::File, BenchError> {
    let lock = crate::output::lock_directory(dir).map_err(|e| match e {
        crate::output::OpenError::Busy { dir } => BenchError::Busy {
            dir: dir.display().to_string(),
        },
        other => BenchError::OutputDir {
            dir: dir.display().to_string(),
            reason: other.to_string(),
        },
    })?;
    crate::output::ensure_writable(dir).map_err(|e| BenchError::OutputDir {
        dir: dir.display().to_string(),
        reason: e.to_string(),
    })?;
    Ok(lock)
}

/// `bench.csv` and `bench.svg` under `dir`, each written atomically.
pub fn write_files(dir: &Path, bench: &Bench, title: &str) -> Result<(), BenchError> {
    let fail = |path: &Path, reason: String| BenchError::Write {
        path: path.display().to_string(),
        reason,
    };
    let csv = dir.join("bench.csv");
    write_atomic(&csv, |w| write_csv(w, &bench.series)).map_err(|e| fail(&csv, e.to_string()))?;
    let svg_path = dir.join("bench.svg");
    let svg = render_svg(&bench.series, title).map_err(|e| fail(&svg_path, e))?;
    write_atomic(&svg_path, |w| w.write_all(svg.as_bytes()))
        .map_err(|e| fail(&svg_path, e.to_string()))
}

/// `solver,alpha,iteration,seconds,error_e`, one row per iterate.
pub fn write_csv(w: &mut dyn Write, series: &[Series]) -> std::io::Result<()> {
    writeln!(w, "{CSV_HEADER}")?;
    for s in series {
        for sample in &s.samples {
            writeln!(
                w,
                "{},{},{},{},{:e}",
                s.method.name(),
                alpha_label(s.alpha),
                sample.iteration,
                sample.seconds,
                sample.error
            )?;
        }
    }
    Ok(())
}
