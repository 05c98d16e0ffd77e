//! Validation of a parsed case: every number finite, physical quantities positive, the α list
//! non-empty. Each error names the key, the value and the fix.

use super::schema::Case;
use crate::solvers::latin::SearchDirection;
use thiserror::Error;

/// Why a case cannot be used. Displayed messages are meant for the user as they are.
#[derive(Debug, Error)]
pub enum CaseError {
    #[error("cannot read case file `{path}`: {reason}")]
    Io { path: String, reason: String },
    #[error("case file is not valid: {0}")]
    Syntax(String),
    #[error("`{key}` = {value} is not valid: {fix}")]
    Invalid {
        key: &'static str,
        value: String,
        fix: String,
    },
}

impl CaseError {
    pub(crate) fn from_toml(e: toml::de::Error) -> Self {
        // toml's message already has the line, the column, the offending text and, for
        // unknown keys or variants, the allowed names; keep it on one line per fact.
        CaseError::Syntax(e.to_string().trim_end().to_string())
    }

    fn invalid(key: &'static str, value: impl ToString, fix: impl Into<String>) -> Self {
        CaseError::Invalid {
            key,
            value: value.to_string(),
            fix: fix.into(),
        }
    }
}

/// Substructures per axis when `solver.subdomains` is left out (the paper's 4 × 4).
const DEFAULT_SUBDOMAINS: usize = 4;

/// A number as a user would write it: exponent form when very large or very small.
pub(crate) fn number(x: f64) -> String {
    if x != 0.0 && x.is_finite() && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Largest magnitude accepted for any physical number: far beyond any structure, far enough
/// from f64's range (1e308) that stiffnesses, loads and their products cannot overflow.
const PHYSICAL_MAX: f64 = 1e15;

/// A physical quantity: finite, strictly positive, at most [`PHYSICAL_MAX`].
fn positive(key: &'static str, value: f64, what: &str) -> Result<(), CaseError> {
    if value.is_finite() && value > 0.0 && value <= PHYSICAL_MAX {
        Ok(())
    } else {
        Err(CaseError::invalid(
            key,
            number(value),
            format!("give {what} as a number > 0 and ≤ {PHYSICAL_MAX:e}"),
        ))
    }
}

/// A finite number of magnitude at most `max`.
fn bounded(key: &'static str, value: f64, max: f64, what: &str) -> Result<(), CaseError> {
    if value.is_finite() && value.abs() <= max {
        Ok(())
    } else {
        Err(CaseError::invalid(
            key,
            number(value),
            format!("give {what} as a finite number of magnitude ≤ {max:e}"),
        ))
    }
}

/// Largest load factor accepted.
const ALPHA_MAX: f64 = 1e6;

pub(crate) fn validate(case: &mut Case) -> Result<(), CaseError> {
    let [nx, ny] = case.grid.modules;
    if nx == 0 || ny == 0 {
        return Err(CaseError::invalid(
            "grid.modules",
            format!("[{nx}, {ny}]"),
            "give at least one module along each axis, e.g. [16, 16]",
        ));
    }
    const MAX_MODULES: usize = 4_000_000;
    if nx.saturating_mul(ny) > MAX_MODULES {
        return Err(CaseError::invalid(
            "grid.modules",
            format!("[{nx}, {ny}]"),
            format!("at most {MAX_MODULES} modules in all"),
        ));
    }
    positive("grid.length", case.grid.length, "the module side L in m")?;
    positive("grid.height", case.grid.height, "the module height H in m")?;
    positive(
        "cables.young",
        case.cables.young,
        "the cables' Young's modulus in Pa",
    )?;
    positive(
        "cables.section",
        case.cables.section,
        "the cables' cross-section in m²",
    )?;
    positive(
        "bars.young",
        case.bars.young,
        "the bars' Young's modulus in Pa",
    )?;
    positive(
        "bars.section",
        case.bars.section,
        "the bars' cross-section in m²",
    )?;
    let p = case.prestress.lower_cable;
    if !(p.is_finite() && (0.0..=PHYSICAL_MAX).contains(&p)) {
        return Err(CaseError::invalid(
            "prestress.lower_cable",
            number(p),
            format!("give the lower cables' prestress in N as a number ≥ 0 and ≤ {PHYSICAL_MAX:e}"),
        ));
    }
    for (c, &f) in case.load.nodal.iter().enumerate() {
        let key = ["load.nodal[0]", "load.nodal[1]", "load.nodal[2]"][c];
        bounded(key, f, PHYSICAL_MAX, "each nodal force component in N")?;
    }
    case.load.alphas = alpha_values(&case.load.alpha)?;

    if case.solver.methods.is_empty() {
        return Err(CaseError::invalid(
            "solver.methods",
            "[]",
            "name at least one solver, e.g. [\"newton\"]",
        ));
    }
    if let Some(tol) = case.solver.tolerance {
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(CaseError::invalid(
                "solver.tolerance",
                number(tol),
                "give a relative tolerance between 0 and 1 (exclusive), e.g. 1e-8",
            ));
        }
    }
    let [sx, sy] = *case
        .solver
        .subdomains
        .get_or_insert([DEFAULT_SUBDOMAINS.min(nx), DEFAULT_SUBDOMAINS.min(ny)]);
    if sx == 0 || sy == 0 || sx > nx || sy > ny {
        return Err(CaseError::invalid(
            "solver.subdomains",
            format!("[{sx}, {sy}]"),
            format!("give 1 ≤ sx ≤ {nx} and 1 ≤ sy ≤ {ny} (at most one substructure per module)"),
        ));
    }
    positive(
        "solver.dm",
        case.solver.dm,
        "the interface search direction d_m in N/m",
    )?;
    case.solver.search = Some(match &case.solver.l {
        toml::Value::String(s) if s == "stiffness" => SearchDirection::Stiffness,
        toml::Value::Float(v) => {
            positive("solver.l", *v, "the link search direction l in N/m")?;
            SearchDirection::Uniform(*v)
        }
        toml::Value::Integer(v) => {
            positive("solver.l", *v as f64, "the link search direction l in N/m")?;
            SearchDirection::Uniform(*v as f64)
        }
        other => {
            return Err(CaseError::invalid(
                "solver.l",
                other,
                "give \"stiffness\" (l = k on every link) or a number of N/m",
            ))
        }
    });
    if case.solver.max_iterations == Some(0) {
        return Err(CaseError::invalid(
            "solver.max_iterations",
            0,
            "give at least 1 iteration",
        ));
    }
    Ok(())
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
                        CaseError::invalid(KEY, v, "every load factor must be a number")
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
                other,
                "give a list such as [0.5, 1.0] or a range such as { from = 0.0, to = 1.0, steps = 41 }",
            ))
        }
    };
    for &a in &alphas {
        bounded(KEY, a, ALPHA_MAX, "every load factor")?;
    }
    Ok(alphas)
}
