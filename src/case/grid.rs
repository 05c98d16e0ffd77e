//! `[grid]`, `[cables]`, `[bars]` and `prestress.lower_cable` of a module grid: its
//! description, checked.

use super::numbers::{number, positive, PHYSICAL_MAX};
use super::raw::{RawCase, RawGrid};
use super::CaseError;
use crate::structure::{CableSpec, CheckedMember, Geometry, GridSpec, Material, MemberChecks};

/// `[grid]` of a raw case: the grid's description, checked.
pub(super) fn grid_spec(raw: &RawCase, g: &RawGrid) -> Result<GridSpec, CaseError> {
    let paper = GridSpec::default();
    let [nx, ny] = g.modules.0;
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
    let length = g.length.unwrap_or(paper.length);
    positive("grid.length", length, "the module side L in m")?;
    let height = g.height.unwrap_or(paper.height);
    positive("grid.height", height, "the module height H in m")?;
    let cables = Material {
        young: raw.cables.young.unwrap_or(paper.cables.material.young),
        section: raw.cables.section.unwrap_or(paper.cables.material.section),
    };
    positive(
        "cables.young",
        cables.young,
        "the cables' Young's modulus in Pa",
    )?;
    positive(
        "cables.section",
        cables.section,
        "the cables' cross-section in m²",
    )?;
    let bars = Material {
        young: raw.bars.young.unwrap_or(paper.bars.young),
        section: raw.bars.section.unwrap_or(paper.bars.section),
    };
    positive("bars.young", bars.young, "the bars' Young's modulus in Pa")?;
    positive(
        "bars.section",
        bars.section,
        "the bars' cross-section in m²",
    )?;
    let p = raw.prestress.lower_cable.unwrap_or(paper.prestress);
    if !(p.is_finite() && (0.0..=PHYSICAL_MAX).contains(&p)) {
        return Err(CaseError::invalid(
            "prestress.lower_cable",
            number(p),
            format!("give the lower cables' prestress in N as a number ≥ 0 and ≤ {PHYSICAL_MAX:e}"),
        ));
    }
    Ok(GridSpec {
        modules: [nx, ny],
        length,
        height,
        module: g.module.unwrap_or(paper.module),
        cables: CableSpec {
            material: cables,
            unilateral: raw.cables.unilateral.unwrap_or(paper.cables.unilateral),
        },
        bars,
        prestress: p,
        clamp: raw.supports.clamp.unwrap_or(paper.clamp),
    })
}

/// The densities of a grid's members (`bars.density`, `cables.density`, kg/m³, ≥ 0; absent:
/// 0, no mass), set on `geometry`'s members by kind: their mass for the natural modes and
/// `load.self_weight`.
pub(super) fn grid_densities(raw: &RawCase, geometry: &mut Geometry) -> Result<(), CaseError> {
    let density = |key: &str, value: Option<f64>, what: &str| -> Result<f64, CaseError> {
        match value {
            None => Ok(0.0),
            Some(v) if v.is_finite() && (0.0..=PHYSICAL_MAX).contains(&v) => Ok(v),
            Some(v) => Err(CaseError::invalid(
                key,
                number(v),
                format!("give {what} in kg/m³ as a number ≥ 0 and ≤ {PHYSICAL_MAX:e}"),
            )),
        }
    };
    let bars = density("bars.density", raw.bars.density, "the bars' density")?;
    let cables = density("cables.density", raw.cables.density, "the cables' density")?;
    for m in &mut geometry.members {
        m.density = if m.kind.is_cable() { cables } else { bars };
    }
    Ok(())
}

/// The member checks of a grid (`bars.strength`, `bars.inertia`, `bars.buckling_curve`,
/// `cables.strength`, `cables.breaking_load`), when any is given, for the materials of `spec`;
/// each a physical quantity (> 0). The partial factors are put on by
/// [`super::code_checks::apply_factors`].
pub(super) fn grid_checks(
    raw: &RawCase,
    spec: &GridSpec,
) -> Result<Option<MemberChecks>, CaseError> {
    let given = |key: &str, value: Option<f64>, what: &str| -> Result<Option<f64>, CaseError> {
        value.map(|v| positive(key, v, what).map(|_| v)).transpose()
    };
    let bar_strength = given(
        "bars.strength",
        raw.bars.strength,
        "the bars' design strength in Pa",
    )?;
    let inertia = given(
        "bars.inertia",
        raw.bars.inertia,
        "the bars' second moment of area in m⁴ (about the weaker axis)",
    )?;
    let cable_strength = given(
        "cables.strength",
        raw.cables.strength,
        "the cables' design strength in Pa",
    )?;
    let buckling = super::code_checks::grid_buckling(raw, bar_strength, inertia)?;
    let breaking = super::code_checks::grid_breaking(raw)?;
    let bars = CheckedMember {
        strength: bar_strength,
        inertia,
        buckling,
        ..CheckedMember::unchecked(spec.bars.young, spec.bars.section)
    };
    let cables = CheckedMember {
        strength: cable_strength,
        breaking,
        ..CheckedMember::unchecked(spec.cables.material.young, spec.cables.material.section)
    };
    if !bars.is_checked() && !cables.is_checked() {
        return Ok(None);
    }
    Ok(Some(MemberChecks::Kinds { bars, cables }))
}
