//! The keys of EN 1993's member checks: a grid's `bars.buckling_curve` (EN 1993-1-1 §6.3.1,
//! the bars' `strength` read as f_y) and `cables.breaking_load` (EN 1993-1-11 §6.3, F_uk), the
//! members table's cells of the same names (read in `tables`), and `[checks]`' partial factors
//! `gamma_m1` (default 1.0, EN 1993-1-1 §6.1's recommended value) and `gamma_r` (no default:
//! EN 1993-1-11 leaves it to the national annex and the terminations), put on every member that
//! asks for the check.

use super::numbers::{number, positive};
use super::raw::RawCase;
use super::CaseError;
use crate::structure::{Buckling, BucklingCurve, CableBreaking, MemberChecks};

/// γ_M1 where `checks.gamma_m1` is not given (EN 1993-1-1 §6.1, note 2B).
const GAMMA_M1: f64 = 1.0;

/// The curve named `text` under `key`, or an error listing the curves.
pub(super) fn curve(key: &str, text: &str) -> Result<BucklingCurve, CaseError> {
    BucklingCurve::from_name(text).ok_or_else(|| {
        CaseError::invalid(
            key,
            format!("\"{text}\""),
            "give one of EN 1993-1-1 Table 6.1's buckling curves: \"a0\", \"a\", \"b\", \"c\" \
             or \"d\" (Table 6.2 gives the curve of a section)",
        )
    })
}

/// A grid's `bars.buckling_curve`, which needs `bars.strength` (f_y) and `bars.inertia`; γ_M1
/// put on later.
pub(super) fn grid_buckling(
    raw: &RawCase,
    strength: Option<f64>,
    inertia: Option<f64>,
) -> Result<Option<Buckling>, CaseError> {
    let Some(text) = raw.bars.buckling_curve.as_deref() else {
        return Ok(None);
    };
    let curve = curve("bars.buckling_curve", text)?;
    if strength.is_none() || inertia.is_none() {
        return Err(CaseError::invalid(
            "bars.buckling_curve",
            format!("\"{text}\""),
            "EN 1993-1-1's buckling resistance χ A f_y / γ_M1 needs the bars' yield strength \
             and second moment of area: give `bars.strength` (f_y, Pa) and `bars.inertia` (m⁴), \
             or remove this key",
        ));
    }
    // γ_M1 is put on by `apply_factors`.
    Ok(Some(Buckling {
        curve,
        gamma_m1: f64::NAN,
    }))
}

/// A grid's `cables.breaking_load` (F_uk, N, > 0); γ_R put on later.
pub(super) fn grid_breaking(raw: &RawCase) -> Result<Option<CableBreaking>, CaseError> {
    let Some(load) = raw.cables.breaking_load else {
        return Ok(None);
    };
    positive(
        "cables.breaking_load",
        load,
        "the cables' characteristic breaking load F_uk in N",
    )?;
    Ok(Some(CableBreaking {
        load,
        gamma_r: f64::NAN,
    }))
}

/// `[checks]`' partial factors put on every member check that uses them: γ_M1 on every
/// buckling curve, γ_R on every breaking load. A breaking load without γ_R, or γ_R without a
/// breaking load, is refused.
pub(super) fn apply_factors(
    raw: &RawCase,
    checks: &mut Option<MemberChecks>,
) -> Result<(), CaseError> {
    let factor = |key: &str, value: Option<f64>| -> Result<Option<f64>, CaseError> {
        let Some(v) = value else { return Ok(None) };
        if !(v.is_finite() && (0.5..=5.0).contains(&v)) {
            return Err(CaseError::invalid(
                key,
                number(v),
                "give the partial factor as a number between 0.5 and 5 (EN 1993 recommends 1.0 \
                 for γ_M1; γ_R is the national annex's)",
            ));
        }
        Ok(Some(v))
    };
    let gamma_m1 = factor("checks.gamma_m1", raw.checks.gamma_m1)?;
    let gamma_r = factor("checks.gamma_r", raw.checks.gamma_r)?;
    let members = match checks {
        Some(MemberChecks::Kinds { bars, cables }) => vec![bars, cables],
        Some(MemberChecks::Each(each)) => each.iter_mut().collect(),
        None => Vec::new(),
    };
    let mut breaking = false;
    for member in members {
        if let Some(b) = member.buckling.as_mut() {
            b.gamma_m1 = gamma_m1.unwrap_or(GAMMA_M1);
        }
        if let Some(c) = member.breaking.as_mut() {
            c.gamma_r = gamma_r.ok_or_else(|| {
                CaseError::invalid(
                    "checks.gamma_r",
                    "missing",
                    "a cable has a breaking load (EN 1993-1-11 §6.3: F_Rd = F_uk / (1.5 γ_R)): \
                     give `checks.gamma_r`, the partial factor of its terminations",
                )
            })?;
            breaking = true;
        }
    }
    // γ_R has no default: given where no cable has a breaking load, it asks for a check the
    // case does not make. γ_M1 has one, and may be written as it is whatever the bars.
    match gamma_r {
        Some(v) if !breaking => Err(CaseError::invalid(
            "checks.gamma_r",
            number(v),
            "no cable has a breaking load, so γ_R divides nothing: give `cables.breaking_load` \
             (or a members table's `breaking_load` column), or remove this key",
        )),
        _ => Ok(()),
    }
}
