//! A solver's answer: an equilibrium state and the [`SolveInfo`] of how it was reached.

use super::{Equilibrium, SolveInfo};

/// A solver's answer for one load.
#[derive(Debug, Clone)]
pub struct Solution {
    /// The final iterate.
    pub equilibrium: Equilibrium,
    /// How it was reached.
    pub info: SolveInfo,
}
