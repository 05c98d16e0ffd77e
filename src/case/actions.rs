//! `[load]`'s actions beyond loads, each a change Δℓ0 of some members' rest lengths (never
//! scaled by α): `[[load.rest_length_change]]` (actuation: `change` = Δℓ0, m) and
//! `[[load.temperature]]` (`change` = ΔT, K, and `expansion` = α_T, 1/K: Δℓ0 = α_T ΔT L). A
//! member's law becomes `τ = t0 − k Δℓ0 + k e` in every model: a cable shortened by δ gains
//! `k δ` of tension before anything moves (docs/method.md §7).

use super::numbers::{bounded, number, PHYSICAL_MAX};
use super::raw::LoadParts;
use super::CaseError;
use crate::structure::Geometry;
use std::collections::HashMap;

/// The largest |ΔT| accepted, K.
const TEMPERATURE_MAX: f64 = 1e4;

/// The largest α_T accepted, 1/K (steel's is 1.2e-5).
const EXPANSION_MAX: f64 = 1e-2;

/// Every member's rest-length change, summed over the entries of both keys under `prefix`
/// (`load`, `load.cases[k]`), by member index (members with no change left out).
pub(super) fn rest_length_changes(
    prefix: &str,
    raw: &LoadParts<'_>,
    geometry: &Geometry,
) -> Result<Vec<(usize, f64)>, CaseError> {
    let mut change = vec![0.0; geometry.members.len()];
    let length = |j: usize| geometry.member_length(j);
    for (i, entry) in raw.rest_length_change.iter().flatten().enumerate() {
        let key = format!("{prefix}.rest_length_change[{i}]");
        bounded(
            &format!("{key}.change"),
            entry.change,
            PHYSICAL_MAX,
            "the change of the rest length in m (negative shortens)",
        )?;
        let by = Selection {
            members: &entry.members,
            group: &entry.group,
            kind: &entry.kind,
        };
        let members = selected(&key, geometry, by, false)?;
        members.into_iter().for_each(|j| change[j] += entry.change);
    }
    for (i, entry) in raw.temperature.iter().flatten().enumerate() {
        let key = format!("{prefix}.temperature[{i}]");
        bounded(
            &format!("{key}.change"),
            entry.change,
            TEMPERATURE_MAX,
            "the temperature change ΔT in K",
        )?;
        let expansion = entry.expansion;
        if !(expansion.is_finite() && (0.0..=EXPANSION_MAX).contains(&expansion)) {
            return Err(CaseError::invalid(
                format!("{key}.expansion"),
                number(expansion),
                format!(
                    "give the coefficient of thermal expansion α_T in 1/K, ≥ 0 and at most \
                     {EXPANSION_MAX:e} (steel 1.2e-5)"
                ),
            ));
        }
        let by = Selection {
            members: &entry.members,
            group: &entry.group,
            kind: &entry.kind,
        };
        for j in selected(&key, geometry, by, true)? {
            // Δℓ0 = α_T ΔT L.
            change[j] += expansion * entry.change * length(j);
        }
    }
    let changes = change.iter().copied().enumerate();
    if let Some((j, c, l)) = first_non_positive_rest_length(changes, geometry) {
        return Err(CaseError::invalid(
            format!("{prefix}.rest_length_change"),
            number(c),
            format!(
                "member {} ({} m long) would have a rest length of {} m: give a change above \
                 −{} m",
                geometry.members[j].id,
                number(l),
                number(l + c),
                number(l)
            ),
        ));
    }
    Ok(change
        .into_iter()
        .enumerate()
        .filter(|&(_, c)| c != 0.0)
        .collect())
}

/// The first member of `changes` (index, Δℓ0) whose rest length `L + Δℓ0` is not positive,
/// with its change and its length L.
pub(super) fn first_non_positive_rest_length(
    changes: impl IntoIterator<Item = (usize, f64)>,
    geometry: &Geometry,
) -> Option<(usize, f64, f64)> {
    changes
        .into_iter()
        .map(|(j, c)| (j, c, geometry.member_length(j)))
        .find(|&(_, c, l)| l + c <= 0.0)
}

/// How an entry names its members: exactly one of `members` (ids), `group` (a members
/// table's group, or a grid's member kind) and `kind` (`"bar"` or `"cable"`).
struct Selection<'a> {
    members: &'a Option<Vec<u64>>,
    group: &'a Option<String>,
    kind: &'a Option<String>,
}

/// The members an entry `key` names by `by`; none named selects every member where
/// `all_by_default`.
fn selected(
    key: &str,
    geometry: &Geometry,
    by: Selection<'_>,
    all_by_default: bool,
) -> Result<Vec<usize>, CaseError> {
    let given = [by.members.is_some(), by.group.is_some(), by.kind.is_some()];
    if given.iter().filter(|&&g| g).count() > 1 {
        return Err(CaseError::invalid(
            key,
            "more than one of `members`, `group`, `kind`",
            "name the members one way: `members = [ids]`, `group = \"name\"` or `kind = \"cable\"`",
        ));
    }
    if let Some(kind) = by.kind {
        let cables = match kind.as_str() {
            "cable" => true,
            "bar" => false,
            other => {
                return Err(CaseError::invalid(
                    format!("{key}.kind"),
                    format!("\"{other}\""),
                    "give `\"bar\"` or `\"cable\"`",
                ))
            }
        };
        return Ok((0..geometry.members.len())
            .filter(|&j| geometry.members[j].kind.is_cable() == cables)
            .collect());
    }
    match (by.members, by.group) {
        (None, None) if all_by_default => Ok((0..geometry.members.len()).collect()),
        (None, None) => Err(CaseError::invalid(
            key,
            "no members",
            "name the members it changes: `members = [ids]`, `group = \"name\"` or `kind = \"cable\"`",
        )),
        (Some(ids), _) => {
            let index: HashMap<u64, usize> = geometry
                .members
                .iter()
                .enumerate()
                .map(|(j, m)| (m.id, j))
                .collect();
            if ids.is_empty() {
                return Err(CaseError::invalid(
                    format!("{key}.members"),
                    "[]",
                    "name at least one member id",
                ));
            }
            ids.iter()
                .map(|id| {
                    index.get(id).copied().ok_or_else(|| {
                        CaseError::invalid(
                            format!("{key}.members"),
                            id,
                            "no member has this id: name members of the structure (a members \
                             table's `member` column; a grid's member ids are those of \
                             `forces/`)",
                        )
                    })
                })
                .collect()
        }
        (None, Some(name)) => {
            let groups = geometry.member_groups();
            let chosen: Vec<usize> = (0..groups.len()).filter(|&j| &groups[j] == name).collect();
            if chosen.is_empty() {
                let mut known: Vec<&str> = groups.iter().map(String::as_str).collect();
                known.sort_unstable();
                known.dedup();
                known.truncate(12);
                return Err(CaseError::invalid(
                    format!("{key}.group"),
                    format!("\"{name}\""),
                    format!(
                        "no member is in this group: name one of {}",
                        known.join(", ")
                    ),
                ));
            }
            Ok(chosen)
        }
    }
}
