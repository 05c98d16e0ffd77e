//! A solver's answer: an equilibrium state and the [`SolveInfo`] of how it was reached.

use super::SolveInfo;
use crate::structure::Structure;

/// Relative tolerance of the one slack classification: a unilateral cable is slack when its gap
/// is open, `λ = −(e + t0/k) > 0`, by more than this fraction of the cables' force scale, i.e.
/// when its trial tension `t0 + k e < −SLACK_GAP_TOLERANCE · max_cables(|t0|, |t0 + k e|)`.
/// A cable at zero tension with a closed gap (an unprestressed cable at rest) is taut. 1e-6 lies
/// well above the round-off of an exact solution (1e-12 of the scale) and well below the trial
/// tension of any cable that is slack on the paper's grids (> 1e-3 of the scale).
pub const SLACK_GAP_TOLERANCE: f64 = 1e-6;

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
    /// The equilibrium of `displacements` with the solver's `tensions`, its slack set by the one
    /// classification every solver shares ([`SLACK_GAP_TOLERANCE`]); a slack cable's tension
    /// is set to exactly 0.
    pub fn classified(s: &Structure, displacements: Vec<f64>, mut tensions: Vec<f64>) -> Self {
        let trial = super::residual::trial_tensions(s, &displacements);
        let scale = s
            .links
            .iter()
            .zip(&trial)
            .filter(|(l, _)| l.unilateral)
            .fold(0.0f64, |m, (l, t)| m.max(l.prestress.abs()).max(t.abs()));
        let slack: Vec<bool> = s
            .links
            .iter()
            .zip(&trial)
            .map(|(l, &t)| l.unilateral && t < -SLACK_GAP_TOLERANCE * scale)
            .collect();
        for (tension, &is_slack) in tensions.iter_mut().zip(&slack) {
            if is_slack {
                *tension = 0.0;
            }
        }
        Equilibrium {
            displacements,
            tensions,
            slack,
        }
    }

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
