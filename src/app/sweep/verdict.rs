//! What an answer is beyond its solver's own stop (docs/method.md §8): no equilibrium, an
//! unstable one, or beyond the model; and the failure line of a row that did not converge.

use crate::app::setup::{AnswerChecks, Prepared};
use crate::output::{alpha_label, SummaryRow};
use crate::results;
use crate::results::uniqueness::Uniqueness;
use crate::results::LargeDistance;
use crate::solvers::{Equilibrium, Measure, NoEquilibrium, Solution, Status};

/// What the sweep found of an answer beyond its solver's stop.
pub(super) struct Verdict {
    /// The smallest tangent eigenvalue at the answer, when computed.
    pub min_tangent_eigenvalue: Option<f64>,
    /// How far a model on the initial geometry is from `large` there (column
    /// `geometric_term`), with large's stability next to it.
    pub geometric_term: Option<LargeDistance>,
    /// Why the answer is no equilibrium, when it is none.
    pub no_equilibrium: Option<crate::solvers::NoEquilibrium>,
    /// What the advice of a failure line may name: the structure's self-stress states s (a
    /// no equilibrium's cables can be prestressed only when s > 0), whether the model has
    /// geometric stiffness already, and a unit slip the members table shows.
    pub advice: Advice,
    /// Whether a converged answer is the only equilibrium, when checked ([`checked_uniqueness`]).
    pub uniqueness: Option<Uniqueness>,
}

/// The facts a failure line's advice rests on (issue 42, D11).
#[derive(Default)]
pub(super) struct Advice {
    /// The self-stress states s, counted when no equilibrium was found.
    pub self_stress_states: Option<usize>,
    /// Whether the model has geometric stiffness (`prestress`, `large`).
    pub geometric: bool,
    /// A unit slip the members table shows (a prestress strain no material takes).
    pub unit_slip: Option<String>,
    /// The structure's own size, m.
    pub size: f64,
    /// How the solver itself ended, when it did not converge on an answer found beyond the
    /// model (then the answer is an iterate it stopped on, not something the load did).
    pub stopped: Option<Status>,
}

impl Advice {
    fn of(prepared: &Prepared) -> Advice {
        let (model, s) = (&prepared.model, &prepared.model.structure);
        Advice {
            self_stress_states: None,
            geometric: model.has_geometric_stiffness(),
            unit_slip: crate::model::unit_slip_strain(s)
                .map(|(id, strain)| crate::model::unit_slip_sentence(id, strain)),
            size: s.size(),
            stopped: None,
        }
    }
}

/// Judge `solution` (docs/method.md §8): its displacements may be a direction along which the
/// energy decreases without bound (no equilibrium exists: [`Status::NoEquilibrium`]); with
/// `checks.eigenvalue`, the smallest tangent eigenvalue at the answer, and a converged answer
/// where it is negative is an unstable equilibrium ([`Status::Unstable`]); with
/// `checks.geometric_term`, a model on the initial geometry's distance to `large`, and a
/// converged answer next to which large's equilibrium is a saddle is [`Status::Unstable`] too
/// (a column past its Euler load: a model on the initial geometry cannot see it).
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
    let model = &prepared.model;
    let mut advice = Advice::of(prepared);
    // The solver's own certificate holds whatever its last iterate (issue 42, D2); a
    // non-finite answer has no direction to test, and nothing else to judge.
    let finite = results::is_finite(solution);
    // A converged answer is an equilibrium (r(U) within its tolerance): only the others, and
    // an answer beyond the model (a runaway its solver stopped on), are asked for a runaway.
    let beyond = finite && results::beyond_model(model, &solution.equilibrium);
    let found = solution.info.no_equilibrium.clone().or_else(|| {
        (finite && (!solution.info.status.converged() || beyond))
            .then(|| certificate(&solution.equilibrium))
            .flatten()
    });
    if let Some(none) = found {
        solution.info.status = Status::NoEquilibrium;
        advice.self_stress_states =
            Some(crate::structure::equilibrium_counts(&model.structure).self_stress_states);
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: Some(none),
            advice,
            uniqueness: None,
        };
    }
    if !finite {
        return Verdict {
            min_tangent_eigenvalue: None,
            geometric_term: None,
            no_equilibrium: None,
            advice,
            uniqueness: None,
        };
    }
    // The run keeps K's factor whenever a check is asked (`Workload::keeps_taut`).
    let taut = prepared.taut.as_ref();
    let min_tangent_eigenvalue = taut
        .filter(|_| checks.eigenvalue && !solution.info.status.no_answer())
        .map(|taut| results::smallest_tangent_eigenvalue(model, &solution.equilibrium, taut));
    if solution.info.status.converged() && min_tangent_eigenvalue.is_some_and(|v| v < 0.0) {
        solution.info.status = Status::Unstable;
    }
    // A model on the initial geometry whose answer moves a node by more than the structure's
    // own size has left its domain: converged or not, no answer of it.
    if beyond {
        advice.stopped = (!solution.info.status.converged()).then_some(solution.info.status);
        solution.info.status = Status::BeyondModel;
    }
    let geometric_term = taut
        .filter(|_| checks.geometric_term && !model.updates_geometry())
        .map(|taut| {
            let eq = &solution.equilibrium;
            results::distance_to_large(model, eq, load, taut, checks.model_tolerance)
        });
    // Large's equilibrium next to the answer is a saddle: whatever the model on the initial
    // geometry says, no load path stays there.
    if solution.info.status.converged()
        && matches!(geometric_term, Some(LargeDistance::Unstable { .. }))
    {
        solution.info.status = Status::Unstable;
    }
    let uniqueness = solution
        .info
        .status
        .converged()
        .then(|| prepared.checked_uniqueness(&solution.equilibrium, load, checks.eigenvalue))
        .flatten();
    // A motion the answer's own tangent does not resist and the load works on: no
    // equilibrium of that tangent, so no converged row.
    if matches!(uniqueness, Some(Uniqueness::LoadedFreeMotion { .. })) {
        solution.info.status = Status::Unstable;
    }
    Verdict {
        min_tangent_eigenvalue,
        geometric_term,
        no_equilibrium: None,
        advice,
        uniqueness,
    }
}

/// Why a `limit_point` row stopped: where its load path started and ended, and what stopped
/// it (an equilibrium on another branch, increments that no longer converge, cables going
/// slack).
fn limit_point_reason(row: &SummaryRow, solution: &Solution) -> String {
    let path = solution.info.load_path.as_ref();
    // Ten significant digits: rows that met one located limit read the same (their α differ
    // in the last bits of `reached + bracket`).
    let label = |alpha: f64| alpha_label(format!("{alpha:.9e}").parse().unwrap_or(alpha));
    let mut reason = match (row.path_from, row.path_reached) {
        (Some(from), Some(reached)) => format!(
            "the load path from alpha = {} (the last equilibrium reached) was followed to \
             alpha = {} and no further",
            label(from),
            label(reached)
        ),
        _ => "the load path could not be followed to this load".to_string(),
    };
    // The bracket the limit was located in: from the last equilibrium to the smallest
    // increment that found none.
    let bracket = path.and_then(|p| p.limit_bracket);
    if let (Some(from), Some(reached), Some(width)) = (row.path_from, row.path_reached, bracket) {
        reason.push_str(&format!(
            ": the limit lies between alpha = {} and {} (no equilibrium found by the smallest \
             increment, {} of the load reached or {} of the unit load",
            label(reached),
            label(reached + width * (row.alpha - from)),
            crate::solvers::LIMIT_TOLERANCE,
            crate::solvers::SMALLEST_INCREMENT,
        ));
    } else {
        reason.push_str(" (no equilibrium found by the smallest increment");
    }
    // A cap below the default makes increments fail that more steps would converge.
    match path.map(|p| p.increment_steps) {
        Some(steps) if steps < crate::solvers::INCREMENT_MAX_STEPS => reason.push_str(&format!(
            ", each given {steps} Newton step(s) by solver.max_iterations: raise it to \
                 {} before reading this as a limit point)",
            crate::solvers::INCREMENT_MAX_STEPS
        )),
        _ => reason.push(')'),
    }
    if let Some(path) = path {
        if path.branch_jumps > 0 {
            reason.push_str(
                ": beyond it the equilibria found lie on another branch, reached across a \
                 region where the energy is not convex (a snap-through past the limit point)",
            );
        }
        if !path.slackened.is_empty() {
            reason.push_str(&format!(
                "; a loss of equilibrium where cable(s) {} go slack",
                path.slackened
                    .iter()
                    .map(|i| i.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    reason
}

/// What to do about a no equilibrium: members or supports always; prestressing the slack
/// cables only where a self-stress state exists (s > 0), the geometric stiffness only where the
/// model has none.
fn no_equilibrium_advice(advice: &Advice) -> String {
    let mut ways = vec!["add members or supports".to_string()];
    match advice.self_stress_states {
        Some(0) => {}
        _ => ways.push("prestress those cables".to_string()),
    }
    if !advice.geometric {
        ways.push("model the geometric stiffness (`model.geometry`)".to_string());
    }
    let last = ways.pop().unwrap_or_default();
    let mut text = if ways.is_empty() {
        last
    } else {
        format!("{} or {last}", ways.join(", "))
    };
    if let Some(first) = text.get(0..1) {
        text = first.to_uppercase() + &text[1..];
    }
    if advice.self_stress_states == Some(0) {
        text.push_str(
            " (the structure has no self-stress state, s = 0: no prestress of its cables is in \
             equilibrium)",
        );
    }
    text
}

/// The failure line of a row that did not converge, after its head (`{solver} at alpha = {α}: `):
/// how it ended, and for no equilibrium the cables that went slack and the nodes of the mode.
pub(super) fn not_converged_message(
    row: &SummaryRow,
    solution: &Solution,
    verdict: &Verdict,
) -> String {
    let ids = |ids: &[u64]| {
        ids.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match (&verdict.no_equilibrium, row.status) {
        (Some(none), _) => format!(
            "no equilibrium: with cable(s) {} slack, a mechanism is left that the load \
             works on (it moves nodes {}), so the energy decreases without bound; no \
             displacement or tension file is written, and its row says converged = false, \
             status = no_equilibrium. {}",
            ids(&none.slack_cables),
            none.mode_nodes
                .iter()
                .map(|(id, u)| format!("{id} ({:.2}, {:.2}, {:.2})", u[0], u[1], u[2]))
                .collect::<Vec<_>>()
                .join(", "),
            no_equilibrium_advice(&verdict.advice)
        ),
        (None, Status::LimitPoint) => format!(
            "limit point: {}; no displacement or tension file is written, and its row \
             says converged = false, status = limit_point. Loads up to the limit stay on the \
             path; beyond it the structure snaps through or collapses (no static answer on \
             its path)",
            limit_point_reason(row, solution)
        ),
        (None, Status::BeyondModel) => format!(
            "beyond the model: the answer moves a node by {:.3e} m, more than the \
             structure's own size ({:.3e} m); a model on the initial geometry does not describe \
             that: {}; no displacement or tension file is written, and its row says \
             converged = false, status = beyond_model",
            row.max_deflection,
            verdict.advice.size,
            match (&verdict.advice.unit_slip, verdict.advice.stopped) {
                (Some(slip), _) => slip.clone(),
                (None, Some(stopped)) => format!(
                    "the solver stopped without converging ({stopped:?}) on that iterate, \
                     which is no answer: a runaway no certificate of no equilibrium was found \
                     for, or a solver that lost its way (compare the case's other solvers)"
                ),
                (None, None) =>
                    "the load at this alpha is too large for it: lower alpha, or solve \
                         with model.geometry = \"large\" (newton), which follows the geometry; \
                         the members table's magnitudes show no unit slip (`tensolve check` \
                         prints them)"
                        .to_string(),
            }
        ),
        (None, Status::Unstable)
            if matches!(
                verdict.uniqueness,
                Some(Uniqueness::LoadedFreeMotion { .. })
            ) =>
        {
            format!(
                "an unstable equilibrium: the residual criterion holds, but the load \
                 works on a motion that the tangent with the answer's own tensions, \
                 K + K_G(τ), does not resist (it moves nodes {}): no equilibrium of that tangent \
                 is there (the solve's K + K_G(t0) keeps the slack cables' share of the \
                 geometric stiffness; compare model.geometry = \"large\"); its row says \
                 converged = false, status = unstable",
                verdict
                    .uniqueness
                    .as_ref()
                    .map(Uniqueness::motion_nodes)
                    .unwrap_or_default()
            )
        }
        (None, Status::Unstable)
            if matches!(verdict.geometric_term, Some(LargeDistance::Unstable { .. })) =>
        {
            let eigenvalue = match verdict.geometric_term {
                Some(LargeDistance::Unstable { eigenvalue, .. }) => eigenvalue,
                _ => f64::NAN,
            };
            format!(
                "an unstable equilibrium: the residual criterion of the {} model holds, \
                 but the large-displacement equilibrium next to its answer is a saddle of the \
                 energy (large's tangent there has the eigenvalue {eigenvalue:.3e} N/m: a \
                 compressed member past its buckling load, say), which a load path would not \
                 stay on and which a model on the initial geometry cannot see; solve with \
                 model.geometry = \"large\"; its row says converged = false, status = unstable",
                row.model.name()
            )
        }
        (None, Status::Unstable) => format!(
            "an unstable equilibrium: the residual criterion holds, but the tangent \
             stiffness has a negative eigenvalue ({:.3e} N/m): a saddle of the energy, which a \
             load path would not stay on; its row says converged = false, status = unstable",
            row.min_tangent_eigenvalue.unwrap_or(f64::NAN)
        ),
        _ => format!(
            "not converged after {} iterations ({:?}), {}; no displacement or tension file \
             is written, and its row says converged = false{}",
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
        let set = ["model.geometry = \"large\"".to_string()];
        let case = crate::case::load_with(&path, &set).unwrap();
        let prepared = crate::app::setup::prepare(&case).unwrap();
        let s = &prepared.model.structure;
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
                krylov_iterations: None,
                solve_seconds: 0.0,
                at_roundoff: false,
                no_equilibrium: Some(none),
                load_path: None,
            },
        };
        let checks = AnswerChecks {
            eigenvalue: false,
            geometric_term: false,
            model_tolerance: crate::results::DEFAULT_MODEL_TOLERANCE,
        };
        let load = vec![0.0; s.n_free];
        let verdict = assess(&mut solution, &prepared, checks, &load, |_| None);
        assert_eq!(solution.info.status, Status::NoEquilibrium);
        assert_eq!(
            verdict.no_equilibrium.map(|n| n.slack_cables),
            Some(vec![90])
        );
    }
}
