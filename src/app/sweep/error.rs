//! Why a run failed, and the exit status each reason maps to.

use crate::case::CaseError;
use crate::output::{OpenError, WriteError};
use crate::solvers::SetupError;
use thiserror::Error;

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
    /// Another MPI rank failed where this one did not (that rank says why): every rank stops
    /// at the same step, so that none waits alone in a collective.
    #[error("another MPI rank failed")]
    OnAnotherRank,
}

impl RunError {
    /// 2 for bad input (the case, the structure it describes, the output directory); 3 when
    /// another run holds the output directory; 1 when the run could not produce what was
    /// asked.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_) | RunError::Setup(_) | RunError::OutputDir { .. } => 2,
            RunError::Busy(_) => 3,
            RunError::Write { .. } | RunError::NotConverged { .. } | RunError::OnAnotherRank => 1,
        }
    }
}

/// `result` where it holds on every rank of `exchange`; otherwise an error on every rank: its
/// own where it failed, [`RunError::OnAnotherRank`] where it did not. A step that can fail on
/// some ranks only (rank 0's files, each rank's memory) goes through it before the next
/// collective operation.
pub fn on_every_rank<T>(
    exchange: &dyn crate::decomposition::Exchange,
    result: Result<T, RunError>,
) -> Result<T, RunError> {
    if exchange.all(result.is_ok()) {
        return result;
    }
    Err(result.err().unwrap_or(RunError::OnAnotherRank))
}

impl RunError {
    /// The failure of a run some of whose solves (`failures`) failed.
    pub(super) fn not_converged(failures: &Failures) -> Self {
        RunError::NotConverged {
            count: failures.count,
            list: failures.text(),
        }
    }
}

/// The solves of a run that failed, each said once: the rows of one solver whose failure reads
/// the same (a limit point located once and met by every later α, L1) share one line,
/// `newton at alpha = 3, 4, 5: limit point: …`.
#[derive(Debug, Default)]
pub(super) struct Failures {
    /// Solves failed.
    count: usize,
    /// Per line: the solver, its α labels, and what the line says after them.
    lines: Vec<(String, Vec<String>, String)>,
}

impl Failures {
    /// A failed solve of `solver` at α `alpha` (its label), `what` saying how after the head
    /// `{solver} at alpha = {alpha}: `.
    pub(super) fn push(&mut self, solver: &str, alpha: String, what: String) {
        self.count += 1;
        match self
            .lines
            .iter_mut()
            .find(|(s, _, w)| s == solver && *w == what)
        {
            Some((_, alphas, _)) => alphas.push(alpha),
            None => self.lines.push((solver.to_string(), vec![alpha], what)),
        }
    }

    /// Whether no solve failed.
    pub(super) fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The first [`LISTED_FAILURES`] lines in full, each with at most [`LISTED_FAILURES`] of
    /// its α, and the solves of the rest counted.
    fn text(&self) -> String {
        let line = |(solver, alphas, what): &(String, Vec<String>, String)| {
            let mut listed = alphas[..alphas.len().min(LISTED_FAILURES)].join(", ");
            if alphas.len() > LISTED_FAILURES {
                listed.push_str(&format!(" and {} more", alphas.len() - LISTED_FAILURES));
            }
            format!("{solver} at alpha = {listed}: {what}")
        };
        let shown = &self.lines[..self.lines.len().min(LISTED_FAILURES)];
        let mut text = shown.iter().map(line).collect::<Vec<_>>().join("; ");
        let said: usize = shown.iter().map(|(_, alphas, _)| alphas.len()).sum();
        if said < self.count {
            text.push_str(&format!("; and {} more solve(s)", self.count - said));
        }
        text
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
            OpenError::LockIsLink { ref lock } => RunError::OutputDir {
                dir: lock
                    .parent()
                    .unwrap_or(lock.as_path())
                    .display()
                    .to_string(),
                reason: e.to_string(),
            },
        }
    }
}

/// At most this many lines of failed solves, and α on one line, are listed in a message; the
/// rest are counted.
const LISTED_FAILURES: usize = 10;
