//! What an answer is beyond its solver's own stop (docs/method.md §8): no equilibrium, an
//! unstable one, or beyond the model; and the failure line of a row that did not converge.

use crate::app::setup::{AnswerChecks, Prepared};
use crate::output::{alpha_label, SummaryRow};
use crate::results;
use crate::solvers::{Equilibrium, Measure, NoEquilibrium, Solution, Status};

/// What the sweep found of an answer beyond its solver's stop.
pub(super) struct Verdict {
    /// The smallest tangent eigenvalue at the answer, when computed.
    pub min_tangent_eigenvalue: Option<f64>,
    /// The relative change the geometric term the model leaves out would make.
    pub geometric_term: Option<f64>,
    /// Why the answer is no equilibrium, when it is none.
    pub no_equilibrium: Option<crate::solvers::NoEquilibrium>,
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
    certificate: impl FnOnce(&Equilibrium) -> Option<NoEquilibrium>,
) -> Verdict {
    let s = &prepared.structure;
    // The solver's own certificate holds whatever its last iterate (issue 42, D2); a
    // non-finite answer has no direction to test, and nothing else to judge.
    let finite = results::is_finite(solution);
    // A converged answer is an equilibrium (r(U) within its tolerance): only the others are
    // asked for a runaway.
    let found = solution.info.no_equilibrium.clone().or_else(|| {
        (finite && !solution.info.status.converged())
            .then(|| certificate(&solution.equilibrium))
            .flatten()
    });
    if let Some(none) = found {
        solution.info.status = Status::NoEquilibrium;
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: Some(none),
        };
    }
    if !finite {
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: None,
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
            "{head}: not converged after {} iterations ({:?}), {}; its row says \
             converged = false{}",
            row.iterations,
            solution.info.status,
            stopping_values(row, solution.info.measure),
            off_equilibrium(row, solution.info.measure)
        ),
    }
}

/// The stopping measure's value and, where it is not r(U), r(U) beside it: either may be the
/// criterion that failed (issue 42, M7).
fn stopping_values(row: &SummaryRow, measure: Measure) -> String {
    let own = format!("{} = {:e}", measure.short_name(), row.stopping_value);
    match measure {
        Measure::EquilibriumResidual => own,
        _ => format!("{own}, r(U) = {:e}", row.equilibrium_residual),
    }
}

/// LATIN's η far below r(U): what that says (issue 42, T5), or nothing.
fn off_equilibrium(row: &SummaryRow, measure: Measure) -> &'static str {
    let far_below = row.stopping_value * 100.0 < row.equilibrium_residual;
    match measure == Measure::Indicator && far_below {
        true => {
            ". eta is far below r(U): the iteration may have settled on a fixed point that is \
             not the equilibrium, which more iterations do not change: try another \
             `solver.subdomains`, or mono-latin"
        }
        false => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::SolveInfo;

    /// A solver's own no-equilibrium certificate holds even when its last iterate is not
    /// finite (issue 42, D2): the row says no equilibrium, not "non-finite values".
    #[test]
    fn a_solvers_certificate_holds_on_a_non_finite_answer() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/simplex.toml");
        let case = crate::case::load_with(&path, &[]).unwrap();
        let prepared = crate::app::setup::prepare(&case).unwrap();
        let s = &prepared.structure;
        let none = NoEquilibrium {
            slack_cables: vec![90],
            mode_nodes: vec![(3, [1.0, 0.0, 0.0])],
        };
        let mut solution = Solution {
            equilibrium: Equilibrium {
                displacements: vec![f64::NAN; s.n_free],
                tensions: vec![0.0; s.links.len()],
                slack: vec![false; s.links.len()],
            },
            info: SolveInfo {
                status: Status::MaxIterations,
                iterations: 2,
                measure: Measure::ComplementarityResidual,
                stopping_value: f64::NAN,
                rebuilds: 0,
                solve_seconds: 0.0,
                at_roundoff: false,
                no_equilibrium: Some(none),
            },
        };
        let checks = AnswerChecks {
            eigenvalue: false,
            geometric_term: false,
        };
        let verdict = assess(&mut solution, &prepared, checks, |_| None);
        assert_eq!(solution.info.status, Status::NoEquilibrium);
        assert_eq!(
            verdict.no_equilibrium.map(|n| n.slack_cables),
            Some(vec![90])
        );
    }
}
