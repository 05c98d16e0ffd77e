//! The prestress of a case. `[prestress] from = "self-stress", member = ID, force = N`
//! (docs/method.md §7): a general structure's prestress as its single self-stress state, scaled
//! so that one member carries a given tension; it replaces the members table's prestress
//! column, which must then be 0. Then every prestress, however given, is checked: no
//! compressed unilateral cable, and in equilibrium at the free dofs.

use super::numbers::{bounded, number, PHYSICAL_MAX};
use super::raw::{RawPrestress, RawPrestressSource};
use super::{CaseError, Design};
use crate::model::GeometricModel;
use crate::structure::{
    self_stress_dense, self_stress_through, DenseSelfStressRefusal, Geometry, NodeFix,
    SelfStressRefusal, Structure,
};

/// Where a `[prestress]` self-stress state's scale is read from.
const FROM: &str = "prestress.from";

/// Set `geometry`'s prestress from `[prestress] from` when it is given (`grid`: the case is a
/// `[grid]`, whose prestress is `lower_cable`), or re-balance the table's prestress
/// (`rebalance`, `design --rebalance`): the design's report when it designed one.
pub(super) fn apply(
    raw: &RawPrestress,
    grid: bool,
    geometry: &mut Geometry,
    fixes: &[NodeFix],
    model: GeometricModel,
    rebalance: bool,
) -> Result<Option<Design>, CaseError> {
    if rebalance && (grid || raw.from.is_some()) {
        return Err(CaseError::invalid(
            "--rebalance",
            "given",
            "it re-balances a [structure]'s members-table prestress: remove `prestress.from` (a designed prestress is balanced already)",
        ));
    }
    refuse_keys_of_other_sources(raw)?;
    let from = match raw.from {
        None if rebalance && !grid => return super::rebalance::apply(geometry, fixes).map(Some),
        None => return Ok(None),
        Some(RawPrestressSource::SelfStress) => {
            self_stress(raw, grid, geometry, fixes, model)?;
            return Ok(None);
        }
        Some(RawPrestressSource::Design) => "\"design\"",
        Some(RawPrestressSource::ForceDensity) => "\"force-density\"",
    };
    refuse_grid_and_table_prestress(grid, geometry, from)?;
    Ok(Some(match raw.from {
        Some(RawPrestressSource::ForceDensity) => {
            super::force_density::apply(raw, geometry, fixes)?
        }
        _ => super::design::apply(raw, geometry, fixes)?,
    }))
}

/// A `[grid]` (its prestress is `lower_cable`), or a members table with a prestress, refused
/// for `from` (`"design"`, `"force-density"`): it replaces the table's prestress.
fn refuse_grid_and_table_prestress(
    grid: bool,
    geometry: &Geometry,
    from: &str,
) -> Result<(), CaseError> {
    if grid {
        return Err(CaseError::invalid(
            FROM,
            from,
            "a [grid]'s prestress is set by `prestress.lower_cable`; `from` needs a [structure] (write the grid as tables with groups: scripts/grid_csv.py --groups)",
        ));
    }
    if let Some(m) = geometry.members.iter().find(|m| m.prestress != 0.0) {
        return Err(CaseError::invalid(
            FROM,
            format!("{from} with a non-zero prestress in the members table (member {} first)", m.id),
            "the designed prestress replaces the members' prestress: set the prestress column to 0, or remove `from`",
        ));
    }
    Ok(())
}

/// The keys of one `from` given with another (or none), refused by name.
fn refuse_keys_of_other_sources(raw: &RawPrestress) -> Result<(), CaseError> {
    use RawPrestressSource::{Design as D, ForceDensity as F, SelfStress as S};
    let keys: [(&str, Option<String>, RawPrestressSource); 5] = [
        ("prestress.member", raw.member.map(|m| m.to_string()), S),
        ("prestress.force", raw.force.map(|f| f.to_string()), S),
        (
            "prestress.targets",
            raw.targets.as_ref().map(|_| "{ … }".into()),
            D,
        ),
        (
            "prestress.min_cable",
            raw.min_cable.map(|f| f.to_string()),
            D,
        ),
        (
            "prestress.force_density",
            raw.force_density.as_ref().map(|_| "{ … }".into()),
            F,
        ),
    ];
    for (key, given, source) in keys {
        if let Some(value) = given {
            let name = match source {
                S => "self-stress",
                D => "design",
                F => "force-density",
            };
            if raw.from != Some(source) {
                return Err(CaseError::invalid(
                    key,
                    value,
                    format!(
                        "it belongs to `from = \"{name}\"`: add that `from`, or remove the key"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The single self-stress state scaled by `member` and `force` (`from = "self-stress"`).
fn self_stress(
    raw: &RawPrestress,
    grid: bool,
    geometry: &mut Geometry,
    fixes: &[NodeFix],
    model: GeometricModel,
) -> Result<(), CaseError> {
    // 1. The scale: member j carries tension `force`.
    let (id, j, force) = scale(raw, grid, geometry)?;
    // 2. The state, on the free dofs of the supports (settlements do not change them).
    let unsettled = NodeFix::unsettled(fixes);
    let structure = Structure::new(geometry, &unsettled, &Default::default());
    let state = self_stress_state(&structure, geometry, id, j, model)?;
    // 3. No cable compressed by the scaled state; then the state is the prestress.
    refuse_compressed_cables(geometry, &state, force)?;
    for (m, t) in geometry.members.iter_mut().zip(&state) {
        m.prestress = force * t;
    }
    Ok(())
}

/// The member (id and index) whose tension `force` scales the state, checked: a general
/// structure, both keys given, a non-zero force, a member of the table, and no prestress given
/// in the members table.
fn scale(
    raw: &RawPrestress,
    grid: bool,
    geometry: &Geometry,
) -> Result<(u64, usize, f64), CaseError> {
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
    Ok((id, j, force))
}

/// The single self-stress state of `structure` through member `j` (id `id`), unit on it;
/// refused with what the structure has instead (mechanisms under the linear model, several
/// states, none loading member `j`).
fn self_stress_state(
    structure: &Structure,
    geometry: &Geometry,
    id: u64,
    j: usize,
    model: GeometricModel,
) -> Result<Vec<f64>, CaseError> {
    Ok(match self_stress_through(structure, j) {
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
        Err(SelfStressRefusal::Counts(c)) => match self_stress_dense(structure, j) {
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
                    if s == 0 {
                        // No self-stress state: no non-zero prestress is in equilibrium, so a
                        // table prestress cannot balance either.
                        "it needs exactly one (s = 1), and with none no non-zero prestress is in equilibrium (a members-table prestress would not balance either): add members so that the structure has a self-stress state, or leave the prestress at 0"
                    } else {
                        "it needs exactly one (s = 1): give each member's prestress in the members table instead"
                    },
                ));
            }
            Err(DenseSelfStressRefusal::TooLarge) => {
                return Err(CaseError::invalid(
                    FROM,
                    format!(
                        "\"self-stress\" on a structure with s = {} self-stress states and m = {} mechanism(s)",
                        c.self_stress_states, c.mechanisms
                    ),
                    if c.self_stress_states == 0 {
                        "it needs exactly one state (s = 1), and with none no non-zero prestress is in equilibrium (a members-table prestress would not balance either): add members so that the structure has a self-stress state, or leave the prestress at 0"
                    } else {
                        "it needs exactly one state (s = 1) and, with mechanisms, a structure of at most 1500 free dofs: give each member's prestress in the members table instead"
                    },
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
    })
}

/// Refuse a scaled state `force × state` that compresses a cable.
fn refuse_compressed_cables(
    geometry: &Geometry,
    state: &[f64],
    force: f64,
) -> Result<(), CaseError> {
    let compressed: Vec<String> = geometry
        .members
        .iter()
        .zip(state)
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
    Ok(())
}

/// Relative prestress imbalance above which a prestress is refused: `|Bᵀt0|` at a node
/// against the `Σ|t0|` of the links meeting there.
const IMBALANCE_RELATIVE: f64 = 1e-9;

/// Refuse a prestress not in equilibrium at the free dofs (docs/method.md §7), naming the worst nodes.
pub(super) fn check_balanced(geometry: &Geometry, fixes: &[NodeFix]) -> Result<(), CaseError> {
    // A unilateral cable carries tension only: a compressed prestress is released at once
    // (every solver would answer with the prestress gone and call it converged).
    if geometry.unilateral {
        let compressed: Vec<&crate::structure::Member> = geometry
            .members
            .iter()
            .filter(|m| m.kind.is_cable() && m.prestress < 0.0)
            .collect();
        if !compressed.is_empty() {
            let ids: Vec<String> = compressed
                .iter()
                .take(10)
                .map(|m| m.id.to_string())
                .collect();
            let most = compressed.iter().fold(0.0f64, |x, m| x.min(m.prestress));
            return Err(CaseError::invalid(
                "prestress",
                format!(
                    "{} unilateral cable(s) in compression, member(s) {}{} (down to {} N)",
                    compressed.len(),
                    ids.join(", "),
                    if compressed.len() > 10 { ", …" } else { "" },
                    number(most)
                ),
                "a cable carries tension only, so its prestress t0 must be ≥ 0 (tension > 0): \
                 check the sign of the members table's prestress column (a self-stress state may \
                 be given with the opposite sign), make those members bars, or set \
                 `cables.unilateral = false`",
            ));
        }
    }
    // Without settlements the effective prestress is t0 itself; with them, the imposed
    // part is carried by the supports on purpose, so check t0 on the same free dofs.
    let s = Structure::new(geometry, &NodeFix::unsettled(fixes), &Default::default());
    let mut worst: Vec<(f64, usize, f64)> = s
        .free_prestress_imbalance()
        .iter()
        .enumerate()
        .filter_map(|(n, (f, scale))| {
            let norm = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            (norm > IMBALANCE_RELATIVE * scale.max(f64::MIN_POSITIVE)).then_some((
                norm / scale,
                n,
                norm,
            ))
        })
        .collect();
    if worst.is_empty() {
        return Ok(());
    }
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    let names: Vec<String> = worst
        .iter()
        .take(3)
        .map(|&(_, n, norm)| {
            format!(
                "node {} (|Bᵀt0| = {} N)",
                geometry.node_ids[n],
                number(norm)
            )
        })
        .collect();
    Err(CaseError::invalid(
        "prestress",
        format!("{} unbalanced node(s): {}", worst.len(), names.join(", ")),
        "give member prestresses t0 in equilibrium at every free node (Bᵀt0 = 0 on the free dofs), or hold those nodes",
    ))
}
