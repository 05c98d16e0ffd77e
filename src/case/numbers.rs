//! The checks every number of a case goes through (finite; positive where physical; bounded so
//! that nothing can overflow), and how a number is shown in an error. Every other part of
//! `case` uses these; they use nothing of it but [`CaseError`].

use super::CaseError;

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
pub(super) const PHYSICAL_MAX: f64 = 1e15;

/// Smallest magnitude accepted for a positive physical number: products of a few of them
/// (k = EA/L, k², the stiffness's pivots) stay far from f64's underflow (1e-308), so a tiny
/// modulus is refused here by name rather than as a "mechanism" (issue 13, E4).
pub(super) const PHYSICAL_MIN: f64 = 1e-15;

/// A physical quantity: finite, between [`PHYSICAL_MIN`] and [`PHYSICAL_MAX`].
pub(super) fn positive(key: &str, value: f64, what: &str) -> Result<(), CaseError> {
    if value.is_finite() && (PHYSICAL_MIN..=PHYSICAL_MAX).contains(&value) {
        Ok(())
    } else {
        Err(CaseError::invalid(
            key,
            number(value),
            format!(
                "give {what} as a number > 0, at least {PHYSICAL_MIN:e} and ≤ {PHYSICAL_MAX:e}"
            ),
        ))
    }
}

/// A finite number of magnitude at most `max`.
pub(super) fn bounded(key: &str, value: f64, max: f64, what: &str) -> Result<(), CaseError> {
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

/// A force or displacement vector: finite components.
pub(super) fn vector(key: &str, v: [f64; 3], max: f64, what: &str) -> Result<[f64; 3], CaseError> {
    for (k, &x) in v.iter().enumerate() {
        bounded(&format!("{key}[{k}]"), x, max, what)?;
    }
    Ok(v)
}

/// A TOML value as the user wrote it (a date as a date, not toml's internal form).
pub(super) fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::Datetime(d) => d.to_string(),
        other => other.to_string(),
    }
}
