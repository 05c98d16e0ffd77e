//! `[prestress] from = "self-stress", member = ID, force = N` (docs/method.md §7): a general
//! structure's prestress as its single self-stress state, scaled so that one member carries a
//! given tension. It replaces the members table's prestress column, which must then be 0.

use super::convert::{bounded, number, PHYSICAL_MAX};
use super::raw::{RawPrestress, RawPrestressSource};
use super::CaseError;
use crate::structure::{
    self_stress_dense, self_stress_through, DenseSelfStressRefusal, GeometricModel, Geometry,
    NodeFix, SelfStressRefusal, Structure,
};

/// Set `geometry`'s prestress from its self-stress state when `[prestress]` asks for it
/// (`grid`: the case is a `[grid]`, whose prestress is `lower_cable`).
pub(super) fn apply(
    raw: &RawPrestress,
    grid: bool,
    geometry: &mut Geometry,
    fixes: &[NodeFix],
    model: GeometricModel,
) -> Result<(), CaseError> {
    let Some(RawPrestressSource::SelfStress) = raw.from else {
        for (key, given) in [
            ("prestress.member", raw.member.is_some()),
            ("prestress.force", raw.force.is_some()),
        ] {
            if given {
                return Err(CaseError::invalid(
                    key,
                    "given",
                    "it scales the self-stress state: add `from = \"self-stress\"`, or remove it",
                ));
            }
        }
        return Ok(());
    };
    const FROM: &str = "prestress.from";
    if grid {
        return Err(CaseError::invalid(
            FROM,
            "\"self-stress\"",
            "a [grid]'s prestress is set by `prestress.lower_cable`; `from` needs a [structure]: remove it",
        ));
    }
    let Some(id) = raw.member else {
        return Err(CaseError::invalid(
            "prestress.member",
            "missing",
            "name the member (an id of the members table) whose tension `force` sets the scale",
        ));
    };
    let Some(force) = raw.force else {
        return Err(CaseError::invalid(
            "prestress.force",
            "missing",
            "give the tension of member `prestress.member` in N (tension > 0, compression < 0)",
        ));
    };
    bounded(
        "prestress.force",
        force,
        PHYSICAL_MAX,
        "the member's tension in N",
    )?;
    if force == 0.0 {
        return Err(CaseError::invalid(
            "prestress.force",
            "0",
            "give a non-zero tension in N (a zero scale is no prestress: remove [prestress] instead)",
        ));
    }
    let Some(j) = geometry.members.iter().position(|m| m.id == id) else {
        return Err(CaseError::invalid(
            "prestress.member",
            id,
            "name a member id of the members table",
        ));
    };
    let given: Vec<u64> = geometry
        .members
        .iter()
        .filter(|m| m.prestress != 0.0)
        .map(|m| m.id)
        .collect();
    if let Some(first) = given.first() {
        return Err(CaseError::invalid(
            FROM,
            format!(
                "\"self-stress\" with {} member(s) of non-zero prestress in the members table (member {first} first)",
                given.len()
            ),
            "the self-stress state replaces the members' prestress: set the prestress column to 0, or remove `from`",
        ));
    }
    // The free dofs are those of the supports; settlements do not change them.
    let unsettled = NodeFix::unsettled(fixes);
    let structure = Structure::new(geometry, &unsettled, &Default::default());
    let state = match self_stress_through(&structure, j) {
        Ok(state) => state,
        Err(SelfStressRefusal::Counts(c))
            if c.mechanisms > 0 && !model.has_geometric_stiffness() =>
        {
            return Err(CaseError::invalid(
                FROM,
                format!(
                    "\"self-stress\" on a structure with m = {} mechanism(s) and model.geometry = \"linear\"",
                    c.mechanisms
                ),
                "the linear model refuses mechanisms: hold more components, or, for a tensegrity its prestress stiffens, set `model.geometry = \"prestress\"` or `\"large\"` (the state is then computed with its mechanisms)",
            ))
        }
        // Mechanisms (with geometric stiffness), or trivial states among the s counted: the
        // dense computation counts the members between two held nodes apart.
        Err(SelfStressRefusal::Counts(c)) => match self_stress_dense(&structure, j) {
            Ok(dense) => dense.state,
            Err(DenseSelfStressRefusal::Count(s, trivial)) => {
                let ids: Vec<String> = trivial
                    .iter()
                    .take(5)
                    .map(|&i| geometry.members[i].id.to_string())
                    .collect();
                let trivial_text = if trivial.is_empty() {
                    "no trivial state".to_string()
                } else {
                    format!(
                        "besides {} trivial one(s), member(s) {} between two held nodes, not counted",
                        trivial.len(),
                        ids.join(", ")
                    )
                };
                return Err(CaseError::invalid(
                    FROM,
                    format!(
                        "\"self-stress\" on a structure with s = {s} non-trivial self-stress state(s) ({trivial_text})"
                    ),
                    "it needs exactly one (s = 1): give each member's prestress in the members table instead",
                ));
            }
            Err(DenseSelfStressRefusal::TooLarge) => {
                return Err(CaseError::invalid(
                    FROM,
                    format!(
                        "\"self-stress\" on a structure with s = {} self-stress states and m = {} mechanism(s)",
                        c.self_stress_states, c.mechanisms
                    ),
                    "it needs exactly one state (s = 1) and, with mechanisms, a structure of at most 1500 free dofs: give each member's prestress in the members table instead",
                ));
            }
            Err(DenseSelfStressRefusal::ZeroComponent) => {
                return Err(CaseError::invalid(
                    "prestress.member",
                    id,
                    "the self-stress state is zero on this member, so its tension cannot set the scale: name a member the state loads",
                ))
            }
        },
        Err(SelfStressRefusal::ZeroComponent(_)) => {
            return Err(CaseError::invalid(
                "prestress.member",
                id,
                "the self-stress state is zero on this member, so its tension cannot set the scale: name a member the state loads",
            ))
        }
    };
    let compressed: Vec<String> = geometry
        .members
        .iter()
        .zip(&state)
        .filter(|(m, &t)| m.kind.is_cable() && force * t < 0.0)
        .map(|(m, &t)| {
            // Shown to 12 significant digits: −1000, not −999.9999999999998.
            let tension = force * t;
            let shown = format!("{tension:.11e}").parse().unwrap_or(tension);
            format!("member {} ({} N)", m.id, number(shown))
        })
        .collect();
    if !compressed.is_empty() {
        return Err(CaseError::invalid(
            "prestress.force",
            number(force),
            format!(
                "the scaled self-stress state compresses {} cable(s): {}; a cable's prestress must be ≥ 0: change the sign of `force`, or turn those members into bars",
                compressed.len(),
                compressed.iter().take(5).cloned().collect::<Vec<_>>().join(", ")
            ),
        ));
    }
    for (m, t) in geometry.members.iter_mut().zip(&state) {
        m.prestress = force * t;
    }
    Ok(())
}
