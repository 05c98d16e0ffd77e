//! Why a solver cannot be set up for a structure ([`SetupError`]): about the input (the
//! structure, the partition, the search directions), never about a solve.

use thiserror::Error;

/// Why a solver cannot be set up for a structure. A set-up error is about the input (the
/// structure, the partition, the search directions), never about a solve.
#[derive(Debug, Error)]
pub enum SetupError {
    /// The stiffness with every cable taut is singular.
    #[error(
        "the structure is a mechanism: its stiffness with every cable taut has {} \
         zero-stiffness mode(s), so no load that works on them can be carried{where_}; {advice}",
        mode_count(*zero_modes)
    )]
    Mechanism {
        /// Number of zero-stiffness modes.
        zero_modes: usize,
        /// Where the modes are (the nodes they move most), when known; empty otherwise.
        where_: String,
        /// What to do: for grids, hold more nodes or brace the modules; for general structures,
        /// hold more nodes, or model the geometric stiffness when the prestress stiffens them.
        advice: String,
        /// The modes' nodal motions, for `mechanisms.csv` (empty when not computed).
        modes: Vec<ModeRow>,
    },
    /// With geometric stiffness, `K + K_G(t0)` is not positive definite: the prestress does not
    /// stiffen every mechanism (docs/method.md §8).
    #[error(
        "the prestress does not stiffen the structure (model.geometry = \"{model}\"): {detail}"
    )]
    NotPrestressStable {
        /// The model asked for.
        model: &'static str,
        /// The modes not stiffened, their nodes, and the fix.
        detail: String,
        /// The modes' nodal motions, for `mechanisms.csv` (empty when not computed).
        modes: Vec<ModeRow>,
    },
    /// A solver that solves with the factor of K with every cable taut, set up after the run
    /// released it (a library caller's order of calls; `run` keeps it for such solvers).
    #[error(
        "{solver} solves with the factor of K with every cable taut, which was released \
         (`Prepared::release_taut`) before it was set up: set it up before releasing, or keep it"
    )]
    TautReleased {
        /// The solver.
        solver: &'static str,
    },
    /// A LATIN substructure operator could not be factorized or pseudo-inverted.
    #[error(
        "substructure {index} has a singular operator (K_E or K*_E + QQᵀ): change \
         `solver.subdomains`, `solver.dm` or `solver.l`{}",
        if *prestress {
            "; with the prestress's geometric stiffness (`model.geometry = \"prestress\"`, or the \
             problems `large` linearises), a floating substructure's rotations get a small \
             stiffness its kernel test cannot classify: fewer subdomains, or mono-latin (one \
             substructure)"
        } else {
            ""
        }
    )]
    SingularSubstructure {
        /// The substructure, numbered row by row of the partition.
        index: usize,
        /// Whether K_E holds the prestress's geometric stiffness.
        prestress: bool,
    },
    /// A uniform LATIN search direction `solver.l` too far from the links' stiffness for the
    /// stages to be resolved in f64.
    #[error(
        "`solver.l` = {l:e} N/m is out of range for this structure: its links' stiffness k is \
         between {k_min:e} and {k_max:e} N/m; give l between {min:e} and {max:e} N/m, or \
         \"stiffness\" (l = k on every link)"
    )]
    SearchDirectionOutOfRange {
        /// The value given.
        l: f64,
        /// The smallest link stiffness, N/m.
        k_min: f64,
        /// The largest link stiffness, N/m.
        k_max: f64,
        /// The smallest l accepted.
        min: f64,
        /// The largest l accepted.
        max: f64,
    },
    /// The LATIN macro problem is singular.
    #[error(
        "the macro problem is singular: an interface or a rigid mode is left undetermined; \
         {advice}"
    )]
    SingularMacroProblem {
        /// What to change: the largest macro degree the partition takes, or the partition
        /// (never a setting already in force, issue 42 M10).
        advice: String,
    },
}

/// One row of `mechanisms.csv`: a node (its id), the mode (from 1), its motion (unit mode).
pub type ModeRow = (u64, usize, [f64; 3]);

impl SetupError {
    /// The modes a mechanism refusal found, for `mechanisms.csv` (empty otherwise).
    pub fn modes(&self) -> &[ModeRow] {
        match self {
            SetupError::Mechanism { modes, .. } | SetupError::NotPrestressStable { modes, .. } => {
                modes
            }
            _ => &[],
        }
    }
}

/// `N`, or `at least N` when N is the most [`crate::linalg::zero_mode_count`] counts.
fn mode_count(zero_modes: usize) -> String {
    // The sparse count stops at ZERO_MODES_COUNTED; a larger count is the dense test's, exact.
    if zero_modes == crate::linalg::ZERO_MODES_COUNTED {
        format!("at least {zero_modes}")
    } else {
        zero_modes.to_string()
    }
}
