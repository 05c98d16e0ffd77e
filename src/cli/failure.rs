//! How a command's error ends the process: its exit status, from the library's typed error in
//! its chain (2 bad input, 3 output directory in use, 1 a run that could not produce what was
//! asked), and its message, the step and file first.

use tensolve::app::bench::BenchError;
use tensolve::app::design::DesignError;
use tensolve::app::sweep::RunError;

/// A refusal of the command line's own (bad tolerances, bench under mpirun, runs that differ),
/// and the exit status it maps to; the library's errors carry theirs.
#[derive(Debug)]
pub struct Refusal {
    pub message: String,
    pub exit_code: u8,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Refusal {}

/// The exit status of `error`: that of the first error of its chain that has one (2 bad input,
/// 3 output directory in use, 1 a run that could not produce what was asked), else 1.
pub fn exit_code_of(error: &anyhow::Error) -> u8 {
    error
        .chain()
        .find_map(|cause| {
            let code = if let Some(e) = cause.downcast_ref::<RunError>() {
                e.exit_code()
            } else if let Some(e) = cause.downcast_ref::<BenchError>() {
                e.exit_code()
            } else if let Some(e) = cause.downcast_ref::<DesignError>() {
                e.exit_code()
            } else {
                return cause.downcast_ref::<Refusal>().map(|r| r.exit_code);
            };
            Some(code as u8)
        })
        .unwrap_or(1)
}

/// What `error` says, the step and file first (`run `case.toml`: …`); nothing for a failure on
/// another MPI rank, which that rank says.
pub fn message_of(error: &anyhow::Error) -> String {
    match error.root_cause().downcast_ref::<RunError>() {
        Some(RunError::OnAnotherRank) => String::new(),
        _ => format!("{error:#}"),
    }
}
