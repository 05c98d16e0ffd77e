//! `[load]`: the load pattern, point loads, self weight, rest-length changes (`actions`), the
//! load cases and combinations (`combinations`), and the load factors α.

use super::loads::case_loads;
use super::numbers::{bounded, shown};
use super::raw::RawLoad;
use super::{CaseError, Load, SolverChoice};
use crate::model::GeometricModel;
use crate::solvers::arc_length::PathFollowing;
use crate::solvers::Method;
use crate::structure::{Geometry, LoadPattern};
use std::collections::HashMap;

/// Largest load factor accepted.
const ALPHA_MAX: f64 = 1e6;

/// `[load]` of a structure of `geometry` (`grid`: a module grid, whose nodal load defaults to
/// the paper's; a general structure's to none, as does a load case's): its loads, or its named
/// load cases and their combinations (`super::combinations`), and the load factors α.
pub(super) fn load(
    raw: &RawLoad,
    grid: bool,
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
    fixes: &[crate::structure::NodeFix],
) -> Result<Load, CaseError> {
    let default_nodal = if grid {
        LoadPattern::default().nodal
    } else {
        [0.0; 3]
    };
    let own = raw.parts();
    let (cases, combinations) =
        super::combinations::cases_and_combinations(raw, &own, geometry, index_of, fixes)?;
    let loads = case_loads("load", &own, default_nodal, geometry, index_of)?;
    Ok(Load {
        pattern: LoadPattern { nodal: loads.nodal },
        points: loads.points,
        gravity: loads.gravity,
        rest_length_changes: loads.rest_length_changes,
        cases,
        combinations,
        alphas: alpha_values(&raw.alpha)?,
    })
}

/// The load factors of `load.alpha`: a non-empty list of finite numbers, or a range
/// `{ from, to, steps }` with `steps ≥ 1` values spaced evenly, both ends included.
fn alpha_values(value: &toml::Value) -> Result<Vec<f64>, CaseError> {
    const KEY: &str = "load.alpha";
    let as_number = |v: &toml::Value| match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let alphas = match value {
        toml::Value::Array(items) => {
            if items.is_empty() {
                return Err(CaseError::invalid(
                    KEY,
                    "[]",
                    "give at least one load factor, e.g. [0.5, 1.0]",
                ));
            }
            items
                .iter()
                .map(|v| {
                    as_number(v).ok_or_else(|| {
                        CaseError::invalid(KEY, shown(v), "every load factor must be a number")
                    })
                })
                .collect::<Result<Vec<_>, _>>()?
        }
        toml::Value::Table(t) => {
            for key in t.keys() {
                if !matches!(key.as_str(), "from" | "to" | "steps") {
                    return Err(CaseError::invalid(
                        KEY,
                        value,
                        format!("unknown key `{key}` in the range: use {{ from, to, steps }}"),
                    ));
                }
            }
            let get = |k: &str| t.get(k).and_then(as_number);
            let (Some(from), Some(to)) = (get("from"), get("to")) else {
                return Err(CaseError::invalid(
                    KEY,
                    value,
                    "a range needs numbers `from` and `to`, e.g. { from = 0.0, to = 1.0, steps = 41 }",
                ));
            };
            let steps = match t.get("steps") {
                Some(toml::Value::Integer(s)) if *s >= 1 && *s <= 1_000_000 => *s as usize,
                _ => {
                    return Err(CaseError::invalid(
                        KEY,
                        value,
                        "a range needs an integer `steps` between 1 and 1000000 (the number of values)",
                    ))
                }
            };
            if steps == 1 {
                vec![from]
            } else {
                // Rounded to 12 significant digits: 0.1 stays 0.1 (not 0.09999999999999999) in
                // file names and tables.
                (0..steps)
                    .map(|i| from + (to - from) * i as f64 / (steps - 1) as f64)
                    .map(|a| format!("{a:.11e}").parse().unwrap_or(a))
                    .collect()
            }
        }
        other => {
            return Err(CaseError::invalid(
                KEY,
                shown(other),
                "give a list such as [0.5, 1.0] or a range such as { from = 0.0, to = 1.0, steps = 41 }",
            ))
        }
    };
    for &a in &alphas {
        bounded(KEY, a, ALPHA_MAX, "every load factor")?;
    }
    // −0 is the load factor 0 (one label, one file name: `alpha0`).
    let alphas: Vec<f64> = alphas.into_iter().map(|a| a + 0.0).collect();
    // Two load factors with one label would write to the same files and repeat a row.
    let mut labels = std::collections::HashMap::new();
    for (i, &a) in alphas.iter().enumerate() {
        if let Some(j) = labels.insert(crate::labels::alpha_label(a), i) {
            return Err(CaseError::invalid(
                KEY,
                format!(
                    "a list whose values {j} and {i} are both {}",
                    crate::labels::alpha_label(a)
                ),
                "give distinct load factors (a range needs `to` - `from` large enough for its \
                 steps to differ in 12 significant digits)",
            ));
        }
    }
    Ok(alphas)
}

/// `load.path`: load control by default; arc length only for newton on the `large` model
/// (the path it follows is that model's), from α = 0 up, under a load.
pub(super) fn path_following(
    path: Option<PathFollowing>,
    choice: &SolverChoice,
    model: GeometricModel,
    model_auto: bool,
    load: &Load,
) -> Result<PathFollowing, CaseError> {
    const KEY: &str = "load.path";
    let Some(PathFollowing::ArcLength) = path else {
        return Ok(PathFollowing::LoadControl);
    };
    let value = "\"arc-length\"";
    if model != GeometricModel::Large || model_auto {
        return Err(CaseError::invalid(
            KEY,
            value,
            "the arc length follows the equilibrium path of the large-displacement model: set \
             `model.geometry = \"large\"`, or use `load.path = \"load-control\"`",
        ));
    }
    if let Some(other) = choice.methods.iter().find(|m| **m != Method::Newton) {
        return Err(CaseError::invalid(
            KEY,
            value,
            format!(
                "the arc-length path is newton's, and `solver.methods` names {}: set \
                 `solver.methods = [\"newton\"]`",
                other.name()
            ),
        ));
    }
    if let Some(&alpha) = load.alphas.iter().find(|&&a| a < 0.0) {
        return Err(CaseError::invalid(
            "load.alpha",
            super::numbers::number(alpha),
            "the arc-length path starts at α = 0 and is followed toward larger α: give α ≥ 0",
        ));
    }
    // A force: the pattern's, or a load case's (settlements and rest-length changes are not
    // scaled by α, and a path along a zero force has no direction).
    let forces = |nodal: [f64; 3], points: &[(usize, [f64; 3])], gravity: Option<[f64; 3]>| {
        nodal != [0.0; 3]
            || points.iter().any(|(_, f)| *f != [0.0; 3])
            || gravity.is_some_and(|g| g != [0.0; 3])
    };
    let loaded = forces(load.pattern.nodal, &load.points, load.gravity)
        || (load.cases.iter()).any(|c| forces(c.nodal, &c.points, c.gravity));
    if !loaded {
        return Err(CaseError::invalid(
            KEY,
            value,
            "the arc-length path follows the force α F, and this case has none: give \
             `load.nodal`, `load.point` or `load.self_weight` a non-zero force (in a load case \
             with load cases)",
        ));
    }
    Ok(PathFollowing::ArcLength)
}
