//! Solvers. Each one is set up once per structure and then solves for any load; it reports what
//! happened in a [`SolveInfo`] and never prints. Observers (CSV writers, progress bars) are
//! attached from outside through [`Observer`].

pub mod latin;
pub mod newton;
pub mod pcg_lcp;
mod taut;

pub use taut::TautStiffness;

use thiserror::Error;

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The stopping criterion was met.
    Converged,
    /// `max_iterations` reached before the criterion.
    MaxIterations,
    /// No further progress is possible in floating point (descent lost) before the criterion.
    Stalled,
}

impl Status {
    pub fn converged(self) -> bool {
        self == Status::Converged
    }
}

/// What a solver did for one load.
#[derive(Debug, Clone)]
pub struct SolveInfo {
    pub status: Status,
    pub iterations: usize,
    /// The solver's own stopping measure at the end (see each solver's docs).
    pub residual: f64,
    pub solve_seconds: f64,
}

/// An equilibrium state (from the prestressed configuration).
#[derive(Debug, Clone)]
pub struct Equilibrium {
    /// Displacements on the free dofs, m.
    pub displacements: Vec<f64>,
    /// Total tension τ = t0 + t of every link, N (exactly 0 for a slack cable).
    pub tensions: Vec<f64>,
    /// Per link: a unilateral cable that is slack.
    pub slack: Vec<bool>,
}

impl Equilibrium {
    pub fn slack_count(&self) -> usize {
        self.slack.iter().filter(|&&s| s).count()
    }
}

/// A solver's answer for one load.
#[derive(Debug, Clone)]
pub struct Solution {
    pub equilibrium: Equilibrium,
    pub info: SolveInfo,
}

/// Why a solver cannot be set up for a structure.
#[derive(Debug, Error)]
pub enum SetupError {
    #[error(
        "the structure is a mechanism: its stiffness with every cable taut has {zero_modes} \
         zero-stiffness mode(s), so no load that works on them can be carried; clamp more \
         nodes (`supports.clamp`) or use a stiffer module (`grid.module = \"braced\"`)"
    )]
    Mechanism { zero_modes: usize },
    #[error(
        "substructure {index} has a singular operator (K_E or K*_E + QQᵀ): change \
         `solver.subdomains` or `solver.dm`"
    )]
    SingularSubstructure { index: usize },
    #[error(
        "the macro problem is singular: an interface or a rigid mode is left undetermined; \
         try `solver.weak_interfaces = \"macro\"` or another `solver.subdomains`"
    )]
    SingularMacroProblem,
}

/// One iteration as seen from outside the solver.
#[derive(Debug, Clone, Copy)]
pub struct IterationRecord {
    pub iteration: usize,
    /// The solver's stopping measure (η for the LATIN solvers).
    pub residual: f64,
    /// Energy error e against a reference solution, when one was given.
    pub error: Option<f64>,
    pub slack_cables: usize,
    pub elapsed_seconds: f64,
}

/// Attached to a solve from outside; the solver calls it after every iteration.
pub trait Observer {
    fn iteration(&mut self, record: &IterationRecord);
}

/// An observer that does nothing.
pub struct Silent;

impl Observer for Silent {
    fn iteration(&mut self, _: &IterationRecord) {}
}
