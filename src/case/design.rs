//! `[prestress] from = "design"` (issue 46, docs/method.md §7 "Designing a prestress"): the
//! members' prestress as the grouped self-stress state nearest to `targets = { group = N }`,
//! cables at least `min_cable`, bars not in tension. Every refusal names the groups at fault.

use super::numbers::{bounded, number, PHYSICAL_MAX};
use super::raw::RawPrestress;
use super::CaseError;
use crate::structure::{
    equilibrium_counts, grouped_states, nearest_state, Bounds, EquilibriumCounts, Fit, Geometry,
    GroupedRefusal, LinkKind, NodeFix, Structure, MET_RELATIVE,
};
use std::collections::BTreeMap;

/// A group's members, kind and designed force.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupForce {
    /// The label (the `group` column; a member's id without it).
    pub name: String,
    /// Its members, by index.
    pub members: Vec<usize>,
    /// Cable or bar (a group is one kind).
    pub kind: LinkKind,
    /// The force of each of its members, N (tension > 0); under `"force-density"`, where
    /// `t = qℓ` varies along a group, the force of largest magnitude.
    pub force: f64,
    /// What the case gave for the group: its target force (N) under `from = "design"` when
    /// `prestress.targets` names it, its force density (N/m) under `"force-density"`.
    pub given: Option<f64>,
}

/// What the design found: the counts it decided on and the force of each group.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// s and m of the members' equilibrium matrix.
    pub counts: EquilibriumCounts,
    /// s₂: the grouped self-stress states.
    pub grouped_states: usize,
    /// The rank decision on `A·G`: the smallest singular value kept and the largest dropped,
    /// relative to the largest.
    pub gap: (Option<f64>, Option<f64>),
    /// How the state was fixed.
    pub fit: Fit,
    /// The groups in order of first appearance, with their forces.
    pub groups: Vec<GroupForce>,
    /// `prestress.min_cable`, N.
    pub min_cable: f64,
    /// Re-balanced (`design --rebalance`): the largest change of a member's prestress, N,
    /// and that member's id.
    pub rebalanced: Option<(f64, u64)>,
    /// Under `"force-density"`: the form found is flat, every node in one plane (the
    /// anchors' plane), and the spread of the nodes off it, relative to the form's size.
    pub flat: Option<f64>,
}

/// Where the design is asked for.
const FROM: &str = "prestress.from";

/// The groups of `geometry`, in order of first appearance: (label, members, kind), refused
/// when one mixes cables and bars.
pub(super) fn groups(
    geometry: &Geometry,
) -> Result<Vec<(String, Vec<usize>, LinkKind)>, CaseError> {
    let labels = geometry.member_groups();
    let mut index: BTreeMap<&str, usize> = BTreeMap::new();
    let mut groups: Vec<(String, Vec<usize>, LinkKind)> = Vec::new();
    for (j, label) in labels.iter().enumerate() {
        let kind = geometry.members[j].kind;
        let k = *index.entry(label).or_insert_with(|| {
            groups.push((label.clone(), Vec::new(), kind));
            groups.len() - 1
        });
        if groups[k].2 != kind {
            return Err(CaseError::invalid(
                "group",
                format!("\"{label}\" (members {} and {})", geometry.members[groups[k].1[0]].id, geometry.members[j].id),
                "a group holds members of one kind: give its cables and its bars different group labels in the members table",
            ));
        }
        groups[k].1.push(j);
    }
    Ok(groups)
}

/// Design `geometry`'s prestress from `raw.targets` and `raw.min_cable` (see the module).
pub(super) fn apply(
    raw: &RawPrestress,
    geometry: &mut Geometry,
    fixes: &[NodeFix],
) -> Result<Design, CaseError> {
    // 1. The intent: the targets on groups that exist, the least cable tension.
    let groups = groups(geometry)?;
    let targets = targets(raw, &groups)?;
    let min_cable = raw.min_cable.unwrap_or(0.0);
    bounded(
        "prestress.min_cable",
        min_cable,
        PHYSICAL_MAX,
        "the least cable tension in N",
    )?;
    if min_cable < 0.0 {
        return Err(CaseError::invalid(
            "prestress.min_cable",
            number(min_cable),
            "give the least cable tension in N, ≥ 0 (a cable carries tension only)",
        ));
    }
    // 2. The grouped self-stress states on the free dofs.
    let structure = Structure::new(geometry, &NodeFix::unsettled(fixes), &Default::default());
    let mut group_of = vec![0; geometry.members.len()];
    for (k, g) in groups.iter().enumerate() {
        g.1.iter().for_each(|&j| group_of[j] = k);
    }
    let states = grouped_states(&structure, &group_of, groups.len()).map_err(refusal)?;
    if states.count() == 0 {
        return Err(CaseError::invalid(
            FROM,
            format!("\"design\" with {} group(s) and no grouped self-stress state (s₂ = 0)", groups.len()),
            "no prestress uniform on each group is in equilibrium: split groups (a `group` label per member type that must carry its own force), or remove the `group` column to let each member be its own group",
        ));
    }
    refuse_unloaded_targets(&states.basis, &targets, &groups)?;
    // 3. The nearest state under the signs.
    let bounds: Vec<Bounds> = groups
        .iter()
        .map(|g| match g.2 {
            LinkKind::Cable => Bounds {
                lower: Some(min_cable),
                upper: None,
            },
            LinkKind::Bar => Bounds {
                lower: None,
                upper: Some(0.0),
            },
        })
        .collect();
    let Some((forces, fit)) = nearest_state(&states.basis, &targets, &bounds) else {
        return Err(CaseError::invalid(
            "prestress.min_cable",
            number(min_cable),
            "no grouped self-stress state has every cable group at least `min_cable` and every bar group in compression: lower `min_cable`, or regroup the members",
        ));
    };
    let forces = cleaned(forces);
    refuse_missed(&forces, &targets, &bounds, &groups, min_cable)?;
    // 4. The members' prestress.
    for (g, &t) in groups.iter().zip(&forces) {
        g.1.iter().for_each(|&j| geometry.members[j].prestress = t);
    }
    let target_of: BTreeMap<usize, f64> = targets.iter().copied().collect();
    Ok(Design {
        flat: None,
        counts: equilibrium_counts(&structure),
        grouped_states: states.count(),
        gap: states.gap,
        fit,
        groups: groups
            .into_iter()
            .zip(&forces)
            .enumerate()
            .map(|(k, ((name, members, kind), &force))| GroupForce {
                name,
                members,
                kind,
                force,
                given: target_of.get(&k).copied(),
            })
            .collect(),
        min_cable,
        rebalanced: None,
    })
}

/// The targets as (group index, force), each on a group that exists, non-zero and bounded.
fn targets(
    raw: &RawPrestress,
    groups: &[(String, Vec<usize>, LinkKind)],
) -> Result<Vec<(usize, f64)>, CaseError> {
    let given = raw.targets.clone().unwrap_or_default();
    if given.is_empty() {
        return Err(CaseError::invalid(
            "prestress.targets",
            "missing",
            "give at least one group's force in N: `targets = { <group> = <force> }` (tension > 0, compression < 0), a group being a label of the members table's `group` column, or a member id without it",
        ));
    }
    let mut out = Vec::new();
    for (name, force) in given {
        let key = format!("prestress.targets.{name}");
        bounded(&key, force, PHYSICAL_MAX, "the group's force in N")?;
        let Some(k) = groups.iter().position(|g| g.0 == name) else {
            let names: Vec<&str> = groups.iter().take(12).map(|g| g.0.as_str()).collect();
            return Err(CaseError::invalid(
                key,
                number(force),
                format!(
                    "there is no group \"{name}\": name one of {}{}",
                    names.join(", "),
                    if groups.len() > 12 { ", …" } else { "" }
                ),
            ));
        };
        if force == 0.0 {
            return Err(CaseError::invalid(
                key,
                "0",
                "give a non-zero force in N (a zero target scales nothing: use `min_cable` for the cables' least tension)",
            ));
        }
        out.push((k, force));
    }
    Ok(out)
}

/// A grouped-state basis component below this (unit basis) is zero: no state loads the group.
const UNLOADED: f64 = 1e-9;

/// Refuse a target on a group that no grouped state loads.
fn refuse_unloaded_targets(
    basis: &[Vec<f64>],
    targets: &[(usize, f64)],
    groups: &[(String, Vec<usize>, LinkKind)],
) -> Result<(), CaseError> {
    for &(k, force) in targets {
        if basis.iter().all(|v| v[k].abs() <= UNLOADED) {
            return Err(CaseError::invalid(
                format!("prestress.targets.{}", groups[k].0),
                number(force),
                format!(
                    "no grouped self-stress state loads group \"{}\" (its force is 0 in every one of the {} state(s)): target another group, or regroup its members",
                    groups[k].0,
                    basis.len()
                ),
            ));
        }
    }
    Ok(())
}

/// Forces at round-off (below 1e-12 of the largest) set to exactly 0.
fn cleaned(mut forces: Vec<f64>) -> Vec<f64> {
    let largest = forces.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for x in &mut forces {
        if x.abs() <= 1e-12 * largest {
            *x = 0.0;
        }
    }
    forces
}

/// A force to 7 significant digits, as a user would write it (−3044.163, not −3044.1634905…).
fn shown(x: f64) -> String {
    number(format!("{x:.6e}").parse().unwrap_or(x))
}

/// Refuse a state that misses a target or a sign, naming the groups.
fn refuse_missed(
    forces: &[f64],
    targets: &[(usize, f64)],
    bounds: &[Bounds],
    groups: &[(String, Vec<usize>, LinkKind)],
    min_cable: f64,
) -> Result<(), CaseError> {
    let scale = targets.iter().map(|t| t.1.abs()).fold(min_cable, f64::max);
    let tol = MET_RELATIVE * scale;
    let missed: Vec<String> = targets
        .iter()
        .filter(|&&(k, t)| (forces[k] - t).abs() > tol)
        .map(|&(k, t)| {
            format!(
                "\"{}\" ({} N for {} N)",
                groups[k].0,
                shown(forces[k]),
                shown(t)
            )
        })
        .collect();
    let signs: Vec<String> = bounds
        .iter()
        .enumerate()
        .filter(|&(k, b)| {
            b.lower.is_some_and(|l| forces[k] < l - tol)
                || b.upper.is_some_and(|u| forces[k] > u + tol)
        })
        .map(|(k, _)| {
            format!(
                "\"{}\" ({}, {} N)",
                groups[k].0,
                groups[k].2.name(),
                shown(forces[k])
            )
        })
        .collect();
    if missed.is_empty() && signs.is_empty() {
        return Ok(());
    }
    let mut what = Vec::new();
    if !missed.is_empty() {
        what.push(format!(
            "the nearest state misses the target of group(s) {}",
            missed.join(", ")
        ));
    }
    if !signs.is_empty() {
        what.push(format!(
            "group(s) {} cannot hold their sign",
            signs.join(", ")
        ));
    }
    Err(CaseError::invalid(
        "prestress.targets",
        "infeasible",
        format!(
            "{}: no grouped self-stress state carries these targets with every cable group ≥ `min_cable` = {} N and every bar group ≤ 0; change the targets (their ratios follow from the states), lower `min_cable`, or regroup the members",
            what.join("; "),
            number(min_cable)
        ),
    ))
}

/// A grouped computation refused, as a case error.
fn refusal(r: GroupedRefusal) -> CaseError {
    match r {
        GroupedRefusal::TooLarge(n, g) => CaseError::invalid(
            FROM,
            format!("\"design\" with {g} groups on {n} free dofs"),
            "the grouped equilibrium matrix would exceed 50 million entries: give the members a `group` column with fewer groups",
        ),
        GroupedRefusal::NoConvergence => CaseError::invalid(
            FROM,
            "\"design\"",
            "the SVD of the grouped equilibrium matrix did not converge (a defect: please report it)",
        ),
    }
}
