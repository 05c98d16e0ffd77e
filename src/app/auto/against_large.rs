//! What a model on the initial geometry (`linear`, `prestress`) is off by at one row: the same
//! case solved at that α with `large` (newton along its load path), its largest deflection,
//! largest cable tension and slack count, to set beside the row's.

use crate::app::setup::{set_up, Prepared};
use crate::model::GeometricModel;
use crate::output::SummaryRow;
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

/// What a run's rows on a model of the initial geometry leave out, past `model.tolerance`.
#[derive(Debug, Clone)]
pub struct ModelOffBy {
    /// Rows whose left-out geometric term is above `model.tolerance`.
    pub count: usize,
    /// The row of the largest (a term not measured counts as the largest).
    pub worst: SummaryRow,
    /// `large` at the worst row's α, where it was solved ([`large_answer`]).
    pub measured: Option<LargeAnswer>,
}

impl ModelOffBy {
    /// The rows of `rows` that need `large` (converged, on a model the case pinned: `auto`
    /// measured its own choice, and a refused row has no answer whose geometric term means
    /// anything), with `large` solved at the worst one's α on `prepared`'s structure when
    /// `measures` (a single process: the ranks of an MPI run keep shares of the links); `None`
    /// when no row needs `large`.
    pub fn of(rows: &[SummaryRow], prepared: &Prepared, measures: bool) -> Option<ModelOffBy> {
        let term = |r: &SummaryRow| r.geometric_term().unwrap_or(f64::INFINITY);
        let off: Vec<&SummaryRow> = rows
            .iter()
            .filter(|r| r.needs_large() && r.converged && r.model_pinned)
            .collect();
        // The first of the largest, as the rows came.
        let worst = off
            .iter()
            .copied()
            .reduce(|a, b| if term(b) > term(a) { b } else { a })?;
        Some(ModelOffBy {
            count: off.len(),
            worst: worst.clone(),
            measured: measures
                .then(|| large_answer(prepared, worst.alpha))
                .flatten(),
        })
    }
}

/// `prepared`'s structure solved at `alpha` under `large` by newton, when its model is on the
/// initial geometry, it has at most [`MEASURED_UP_TO_DOFS`] free dofs, and the solve converges.
pub fn large_answer(prepared: &Prepared, alpha: f64) -> Option<LargeAnswer> {
    if prepared.model.updates_geometry()
        || prepared.share.is_some()
        || prepared.model.structure.n_free > MEASURED_UP_TO_DOFS
    {
        return None;
    }
    let large = prepared.under(GeometricModel::Large).ok()?;
    let mut newton = set_up(Method::Newton, &Default::default(), &large).ok()?;
    let load = large.model.load(alpha);
    let solution = newton.solver.solve(&load, None, &mut Silent);
    if !solution.info.status.converged() {
        return None;
    }
    let eq = &solution.equilibrium;
    let measures = AnswerMeasures::of(&large.model, eq, &load);
    Some(LargeAnswer {
        max_deflection: measures.max_deflection,
        max_tension: measures.max_tension,
        slack_cables: eq.slack_count(),
    })
}
