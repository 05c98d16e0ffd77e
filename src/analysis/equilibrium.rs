//! An equilibrium state: displacements, tensions and the slack set, as every solver answers
//! and every analysis reads it.

use crate::model::material::{slack_flags, SlackRule};
use crate::model::Model;

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
    /// classification every solver shares ([`SlackRule::Gap`]); a slack cable's tension
    /// is set to exactly 0.
    pub fn classified(model: &Model, displacements: Vec<f64>, mut tensions: Vec<f64>) -> Self {
        let trial = model.trial_tensions(&displacements);
        let slack = slack_flags(&model.structure, &trial, SlackRule::Gap);
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
