//! `model.geometry = "auto"` (the default): each row solved with the cheapest model whose answer
//! is within `model.tolerance` of the large-displacement one (docs/method.md §8, "auto").
//!
//! - A structure whose stiffness with every cable taut is regular starts `linear`; a mechanism
//!   its prestress stiffens (a tensegrity) starts `large`: `linear` cannot carry it, and
//!   `prestress` is chosen only when a case pins it.
//! - While `linear`, newton's linear answer at each α (the probe) is taken by Newton steps of
//!   the large model to the large answer near it ([`distance_to_large`]); the first α where
//!   that distance passes the tolerance, or cannot be measured, and every α after it, are
//!   solved with `large`: the geometric effect grows with the load, and the α are in
//!   increasing order. So is an α where the steps settle on an equilibrium whose tangent is not
//!   positive definite (a column past its Euler load): however close, linear's answer there
//!   sits next to a saddle of the energy, which only `large` can say (it reports `unstable`).

pub mod against_large;

use super::setup::{prepare_keeping, set_up, Prepared, SetUpSolver};
use crate::case::Case;
use crate::labels::alpha_label;
use crate::model::GeometricModel;
use crate::results::{distance_to_large, LargeDistance, DISTANCE_STEPS};
use crate::solvers::{Equilibrium, Method, SetupError, Silent};

/// The model of a row and why it is that one (the solve line says it).
#[derive(Debug, Clone, PartialEq)]
pub struct RowModel {
    /// The model the row was solved with.
    pub model: GeometricModel,
    /// Why, in a few words.
    pub reason: String,
    /// The case pins it (else `auto` chose it).
    pub pinned: bool,
}

impl RowModel {
    /// The model a case pins.
    pub fn pinned(model: GeometricModel) -> RowModel {
        RowModel {
            model,
            reason: "pinned".to_string(),
            pinned: true,
        }
    }
}

/// The structure of `case` prepared for its first model, and why that one: the case's own, or
/// under `auto` `linear` when K with every cable taut is regular, else `large` (a mechanism
/// its prestress stiffens; one it does not is refused as `large` refuses it), which `case`
/// then says.
pub fn prepare_start(
    case: &mut Case,
    keeps_taut: bool,
) -> Result<(Prepared, RowModel), SetupError> {
    if !case.model_auto {
        let prepared = prepare_keeping(case, keeps_taut)?;
        return Ok((prepared, RowModel::pinned(case.model)));
    }
    match prepare_keeping(case, keeps_taut) {
        Ok(prepared) => Ok((prepared, linear_start(case.model_tolerance))),
        // A mechanism its prestress does not stiffen keeps linear's refusal: it says where
        // the modes are, and whether any model solves it.
        Err(refused @ SetupError::Mechanism { .. }) => {
            case.model = GeometricModel::Large;
            match prepare_keeping(case, keeps_taut) {
                Ok(prepared) => Ok((prepared, mechanism_start())),
                Err(_) => {
                    case.model = GeometricModel::Linear;
                    Err(refused)
                }
            }
        }
        Err(other) => Err(other),
    }
}

/// The model of `case` under `large` (what `auto` moves to), its structure built anew.
pub fn large_model(case: &Case) -> crate::model::Model {
    case.model_with(GeometricModel::Large)
}

/// `case` under `large` (what `auto` moves to).
pub fn large_case(case: &Case) -> Case {
    let mut large = case.clone();
    large.model = GeometricModel::Large;
    large
}

/// Why `auto` starts `linear` (with `model.tolerance` = `tolerance`), as `check` says it.
pub fn linear_start(tolerance: f64) -> RowModel {
    RowModel {
        model: GeometricModel::Linear,
        reason: format!(
            "auto: the structure is stiff with every cable taut; newton's linear answer at each \
             alpha is taken to large's by at most {DISTANCE_STEPS} Newton steps, and large \
             solves from the first alpha where they differ by more than model.tolerance = {}",
            percent_label(tolerance)
        ),
        pinned: false,
    }
}

/// `0.01` as `1 %`.
fn percent_label(fraction: f64) -> String {
    format!("{} %", (100.0 * fraction * 1e6).round() / 1e6)
}

/// Why `auto` starts `large` on a mechanism its prestress stiffens.
pub fn mechanism_start() -> RowModel {
    RowModel {
        model: GeometricModel::Large,
        reason: "auto: a mechanism its prestress stiffens".to_string(),
        pinned: false,
    }
}

/// What [`AutoModel::choose`] chose at one α.
#[derive(Debug, Clone, PartialEq)]
pub struct Chosen {
    /// The model of the α's rows, and why.
    pub row: RowModel,
    /// What was measured, in a few words (`linear 6.4 % from large`), for the rows after.
    pub measured: String,
}

impl Chosen {
    /// Whether `auto` moves to `large` here (for this α and every later one).
    pub fn moves_to_large(&self) -> bool {
        self.row.model == GeometricModel::Large
    }
}

/// The choice along a sweep under `auto` while it is `linear`: newton's linear answer at each α
/// and its distance to `large`.
pub struct AutoModel<'s> {
    /// newton on the linear model, at its default settings: the answer measured.
    probe: SetUpSolver<'s>,
    /// Its answer at the previous α: its warm start.
    previous: Option<Equilibrium>,
    prepared: &'s Prepared,
    tolerance: f64,
}

impl<'s> AutoModel<'s> {
    /// The choice along a sweep of `case` that starts with `start` on `prepared`: under `auto`
    /// when it starts `linear`; `None` for a pinned model and for `auto` started `large`.
    pub fn starting(
        case: &Case,
        start: &RowModel,
        prepared: &'s Prepared,
    ) -> Result<Option<AutoModel<'s>>, SetupError> {
        match case.model_auto && start.model == GeometricModel::Linear {
            true => AutoModel::new(case, prepared).map(Some),
            false => Ok(None),
        }
    }

    /// The choice for a sweep of `case` on `prepared` (`linear`, K's factor kept).
    pub fn new(case: &Case, prepared: &'s Prepared) -> Result<AutoModel<'s>, SetupError> {
        Ok(AutoModel {
            probe: set_up(Method::Newton, &Default::default(), prepared)?,
            previous: None,
            prepared,
            tolerance: case.model_tolerance,
        })
    }

    /// The model of the rows at `alpha` (load `load`): `linear` while its answer is within
    /// the tolerance of `large`'s, else `large`, with why.
    pub fn choose(&mut self, alpha: f64, load: &[f64]) -> Chosen {
        let solution =
            self.probe
                .solver
                .solve_from(load, self.previous.as_ref(), None, &mut Silent);
        let percent = |d: f64| format!("{:.3} %", 100.0 * d);
        let tolerance = percent_label(self.tolerance);
        let large = |reason: String, measured: String| Chosen {
            row: RowModel {
                model: GeometricModel::Large,
                reason,
                pinned: false,
            },
            measured,
        };
        let taut = self.prepared.taut.as_ref();
        let Some(taut) = taut.filter(|_| solution.info.status.converged()) else {
            // The status the linear row would have: a runaway the run's own test certifies is
            // no equilibrium, not the solver's stall on it (issue 57, A1).
            let model = &self.prepared.model;
            let eq = &solution.equilibrium;
            let status = match crate::solvers::no_equilibrium(model, eq, load)
                .or_else(|| crate::solvers::no_equilibrium_of_answer(model, eq, load))
            {
                Some(_) => crate::solvers::Status::NoEquilibrium,
                None => solution.info.status,
            };
            return large(
                format!(
                    "auto: newton found no linear answer at alpha = {} to measure ({})",
                    alpha_label(alpha),
                    status.code()
                ),
                "no linear answer there".to_string(),
            );
        };
        let model = &self.prepared.model;
        let eq = solution.equilibrium;
        let distance = distance_to_large(model, &eq, load, taut, self.tolerance);
        self.previous = Some(eq);
        match distance {
            LargeDistance::Within(d) => Chosen {
                row: RowModel {
                    model: GeometricModel::Linear,
                    reason: format!(
                        "auto: {} from large, within model.tolerance {tolerance}",
                        percent(d)
                    ),
                    pinned: false,
                },
                measured: format!("linear {} from large", percent(d)),
            },
            LargeDistance::Beyond(d) => large(
                format!(
                    "auto: linear would be {} from large, beyond model.tolerance {tolerance}",
                    percent(d)
                ),
                format!("linear {} from large there", percent(d)),
            ),
            LargeDistance::Far(d) => large(
                format!(
                    "auto: large's Newton steps move linear's answer by {} and on, beyond \
                     model.tolerance {tolerance}",
                    percent(d)
                ),
                format!("linear {} and more from large there", percent(d)),
            ),
            LargeDistance::Unstable { eigenvalue, .. } => large(
                format!(
                    "auto: the large-displacement equilibrium next to linear's answer is unstable \
                     (large's tangent there has the eigenvalue {eigenvalue:.3e} N/m): large \
                     decides"
                ),
                "an unstable large equilibrium next to linear's answer there".to_string(),
            ),
            LargeDistance::Unsettled => large(
                format!(
                    "auto: linear's distance to large did not settle in {DISTANCE_STEPS} Newton \
                     steps"
                ),
                "linear's distance to large unsettled there".to_string(),
            ),
        }
    }
}
