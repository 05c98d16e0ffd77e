//! A solver's answer: an equilibrium state and the [`SolveInfo`] of how it was reached.

use super::SolveInfo;

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
    /// Number of slack cables.
    pub fn slack_count(&self) -> usize {
        self.slack.iter().filter(|&&s| s).count()
    }
}

/// A solver's answer for one load.
#[derive(Debug, Clone)]
pub struct Solution {
    /// The final iterate.
    pub equilibrium: Equilibrium,
    /// How it was reached.
    pub info: SolveInfo,
}
