//! What a model on the initial geometry (`linear`, `prestress`) is off by at one row: the same
//! case solved at that α with `large` (newton along its load path), its largest deflection,
//! largest cable tension and slack count, to set beside the row's.

use super::large_case;
use crate::app::setup::{prepare, set_up};
use crate::case::Case;
use crate::results::{uniqueness::CHECKED_UP_TO_DOFS, AnswerMeasures};
use crate::solvers::{Method, Silent};

/// Structures of at most this many free dofs are solved with `large` to measure what their
/// model is off by: the factor this takes beside the run's (held by then) fits the memory
/// estimate's margin, as the uniqueness check's does.
pub const MEASURED_UP_TO_DOFS: usize = CHECKED_UP_TO_DOFS;

/// The large-displacement answer at one α.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LargeAnswer {
    /// Largest nodal displacement magnitude, m.
    pub max_deflection: f64,
    /// Largest cable tension, N.
    pub max_tension: f64,
    /// Slack unilateral cables.
    pub slack_cables: usize,
}

/// `case` solved at `alpha` under `large` by newton, when its model is on the initial geometry,
/// its structure has at most [`MEASURED_UP_TO_DOFS`] free dofs, and the solve converges.
pub fn large_answer(case: &Case, alpha: f64) -> Option<LargeAnswer> {
    if case.model.updates_geometry() {
        return None;
    }
    let mut large = large_case(case);
    large.load.alphas = vec![alpha];
    if large.structure().n_free > MEASURED_UP_TO_DOFS {
        return None;
    }
    let prepared = prepare(&large).ok()?;
    let mut newton = set_up(Method::Newton, &Default::default(), &prepared).ok()?;
    let load = prepared.model.load(alpha);
    let solution = newton.solver.solve(&load, None, &mut Silent);
    if !solution.info.status.converged() {
        return None;
    }
    let eq = &solution.equilibrium;
    let measures = AnswerMeasures::of(&prepared.model, eq, &load);
    Some(LargeAnswer {
        max_deflection: measures.max_deflection,
        max_tension: measures.max_tension,
        slack_cables: eq.slack_count(),
    })
}
