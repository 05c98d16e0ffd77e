//! What an answer is beyond its solver's own stop (docs/method.md §8): no equilibrium, an
//! unstable one, or beyond the model; and the failure line of a row that did not converge.

use crate::app::setup::{AnswerChecks, Prepared};
use crate::output::{alpha_label, SummaryRow};
use crate::results;
use crate::results::uniqueness::{self, Uniqueness};
use crate::solvers::{Equilibrium, NoEquilibrium, Solution, Status};

/// What the sweep found of an answer beyond its solver's stop.
pub(super) struct Verdict {
    /// The smallest tangent eigenvalue at the answer, when computed.
    pub min_tangent_eigenvalue: Option<f64>,
    /// The relative change the geometric term the model leaves out would make.
    pub geometric_term: Option<f64>,
    /// Why the answer is no equilibrium, when it is none.
    pub no_equilibrium: Option<crate::solvers::NoEquilibrium>,
    /// Whether a converged answer is the only equilibrium, when checked ([`checked_uniqueness`]).
    pub uniqueness: Option<Uniqueness>,
}

/// Judge `solution` (docs/method.md §8): its displacements may be a direction along which the
/// energy decreases without bound (no equilibrium exists: [`Status::NoEquilibrium`]); with
/// `checks.eigenvalue`, the smallest tangent eigenvalue at the answer, and a converged answer
/// where it is negative is an unstable equilibrium ([`Status::Unstable`]).
///
/// `certificate` tests a direction for no equilibrium ([`crate::solvers::no_equilibrium`] on
/// the whole structure, or the solver's own test over the shares of the links the ranks keep).
pub(super) fn assess(
    solution: &mut Solution,
    prepared: &Prepared,
    checks: AnswerChecks,
    load: &[f64],
    certificate: impl FnOnce(&Equilibrium) -> Option<NoEquilibrium>,
) -> Verdict {
    let s = &prepared.structure;
    if !results::is_finite(solution) {
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: None,
            uniqueness: None,
        };
    }
    // A converged answer is an equilibrium (r(U) within its tolerance): only the others are
    // asked for a runaway.
    let found = solution.info.no_equilibrium.clone().or_else(|| {
        (!solution.info.status.converged())
            .then(|| certificate(&solution.equilibrium))
            .flatten()
    });
    if let Some(none) = found {
        solution.info.status = Status::NoEquilibrium;
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: Some(none),
            uniqueness: None,
        };
    }
    // The run keeps K's factor whenever a check is asked (`Workload::keeps_taut`).
    let taut = prepared.taut.as_ref();
    let min_tangent_eigenvalue = taut
        .filter(|_| checks.eigenvalue && !solution.info.status.no_answer())
        .map(|taut| results::smallest_tangent_eigenvalue(s, &solution.equilibrium, taut));
    if solution.info.status.converged() && min_tangent_eigenvalue.is_some_and(|v| v < 0.0) {
        solution.info.status = Status::Unstable;
    }
    // A model on the initial geometry whose answer moves a node by more than the structure's
    // own size has left its domain: converged or not, no answer of it.
    if results::beyond_model(s, &solution.equilibrium) {
        solution.info.status = Status::BeyondModel;
    }
    Verdict {
        min_tangent_eigenvalue,
        geometric_term: taut
            .filter(|_| checks.geometric_term)
            .and_then(|taut| results::geometric_term(s, &solution.equilibrium, taut)),
        no_equilibrium: None,
        uniqueness: solution
            .info
            .status
            .converged()
            .then(|| checked_uniqueness(prepared, checks, &solution.equilibrium, load))
            .flatten(),
    }
}

/// Whether the converged answer `eq` is the only equilibrium ([`uniqueness::uniqueness`]), on
/// K's pattern and analysis when the run keeps them (up to [`uniqueness::CHECKED_UP_TO_DOFS`]
/// free dofs, or at any size where the run factorizes a tangent per row anyway:
/// `checks.eigenvalue`), else on its own analysis (up to
/// [`uniqueness::OWN_ANALYSIS_UP_TO_DOFS`]); `None` (not checked) beyond, and where the ranks
/// keep shares of the links.
fn checked_uniqueness(
    prepared: &Prepared,
    checks: AnswerChecks,
    eq: &Equilibrium,
    load: &[f64],
) -> Option<Uniqueness> {
    let s = &prepared.structure;
    match &prepared.taut {
        _ if prepared.share.is_some() => None,
        Some(taut) if s.n_free <= uniqueness::CHECKED_UP_TO_DOFS || checks.eigenvalue => Some(
            uniqueness::uniqueness(s, eq, load, &taut.pattern, &taut.factor),
        ),
        None if s.n_free <= uniqueness::OWN_ANALYSIS_UP_TO_DOFS => {
            let (pattern, analysed) = crate::solvers::TautStiffness::analyse(s);
            Some(uniqueness::uniqueness(s, eq, load, &pattern, &analysed))
        }
        _ => None,
    }
}

/// The failure line of a row that did not converge: how it ended, and for no equilibrium the
/// cables that went slack and the nodes of the mode.
pub(super) fn not_converged_message(
    row: &SummaryRow,
    solution: &Solution,
    verdict: &Verdict,
) -> String {
    let head = format!("{} at alpha = {}", row.solver, alpha_label(row.alpha));
    let ids = |ids: &[u64]| {
        ids.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match (&verdict.no_equilibrium, row.status) {
        (Some(none), _) => format!(
            "{head}: no equilibrium: with cable(s) {} slack, a mechanism is left that the load \
             works on (it moves nodes {}), so the energy decreases without bound; no \
             displacement or tension file is written, and its row says converged = false, \
             status = no_equilibrium. Add members or supports, prestress those cables, or model \
             the geometric stiffness (`model.geometry`)",
            ids(&none.slack_cables),
            none.mode_nodes
                .iter()
                .map(|(id, u)| format!("{id} ({:.2}, {:.2}, {:.2})", u[0], u[1], u[2]))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        (None, Status::LimitPoint) => format!(
            "{head}: limit point: the load path could not be followed to this load (load \
             increments halved below {} of the path from the last equilibrium); no \
             displacement or tension file is written, and its row says converged = false, \
             status = limit_point",
            crate::solvers::newton::MIN_INCREMENT
        ),
        (None, Status::BeyondModel) => format!(
            "{head}: beyond the model: the answer moves a node by {:.3e} m, more than the \
             structure's own size; a model on the initial geometry does not describe that (a \
             unit slip, such as E in GPa or coordinates in mm? `tensolve check` prints the \
             magnitudes); no displacement or tension file is written, and its row says \
             converged = false, status = beyond_model",
            row.max_deflection
        ),
        (None, Status::Unstable) => format!(
            "{head}: an unstable equilibrium: the residual criterion holds, but the tangent \
             stiffness has a negative eigenvalue ({:.3e} N/m): a saddle of the energy, which a \
             load path would not stay on; its row says converged = false, status = unstable",
            row.min_tangent_eigenvalue.unwrap_or(f64::NAN)
        ),
        _ => format!(
            "{head}: not converged after {} iterations ({:?}), {} = {:e}; its row says \
             converged = false",
            row.iterations,
            solution.info.status,
            solution.info.measure.short_name(),
            row.stopping_value
        ),
    }
}
