//! `[[load.cases]]` and `[[load.combinations]]`: named load cases, each with `[load]`'s loads
//! (`nodal`, `point`, `self_weight`, `rest_length_change`, `temperature`), and combinations of
//! them with factors (`factors = { G = 1.35, Q = 1.5, prestress = 1.0 }`). Because cables go
//! slack the response is not linear in the load: a combination is one load `Σ f_c · case_c`,
//! solved on its own and never superposed; `load.alpha` then scales the combination's forces
//! (its actions, as settlements, are not scaled by α).

use super::loads::case_loads;
use super::numbers::number;
use super::raw::{LoadParts, RawLoad};
use super::{Case, CaseError, Combination, LoadCase};
use crate::structure::{Geometry, NodeFix};
use std::collections::HashMap;

/// The factor key that scales the prestress rather than a load case.
pub const PRESTRESS_FACTOR: &str = "prestress";

/// The largest |factor| accepted.
const FACTOR_MAX: f64 = 1e3;

/// The load cases and combinations of `raw` (`own`: `[load]`'s own loads, which must be
/// absent when load cases are given); both empty without `[[load.cases]]`.
pub(super) fn cases_and_combinations(
    raw: &RawLoad,
    own: &LoadParts<'_>,
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
    fixes: &[NodeFix],
) -> Result<(Vec<LoadCase>, Vec<Combination>), CaseError> {
    let Some(raw_cases) = &raw.cases else {
        if let Some(first) = raw.combinations.iter().flatten().next() {
            return Err(CaseError::invalid(
                "load.combinations[0]",
                format!("\"{}\"", first.name),
                "a combination combines named load cases: give them as [[load.cases]]",
            ));
        }
        return Ok((Vec::new(), Vec::new()));
    };
    if own.any() {
        return Err(CaseError::invalid(
            "load",
            "loads beside [[load.cases]]",
            "with load cases, every load belongs to one: move `load.nodal`, `load.point`, \
             `load.self_weight`, `load.rest_length_change` and `load.temperature` into a \
             [[load.cases]] entry",
        ));
    }
    if raw_cases.is_empty() {
        return Err(CaseError::invalid(
            "load.cases",
            "[]",
            "give at least one load case, or remove the key",
        ));
    }
    let mut cases: Vec<LoadCase> = Vec::new();
    for (k, c) in raw_cases.iter().enumerate() {
        let prefix = format!("load.cases[{k}]");
        name(
            &format!("{prefix}.name"),
            &c.name,
            cases.iter().map(|c| &c.name),
        )?;
        if c.name == PRESTRESS_FACTOR {
            return Err(CaseError::invalid(
                format!("{prefix}.name"),
                "\"prestress\"",
                "`prestress` names the prestress's factor in a combination: name the case \
                 otherwise",
            ));
        }
        let mut loads = case_loads(&prefix, &c.parts(), [0.0; 3], geometry, index_of)?;
        loads.name = c.name.clone();
        loads.settlements = settlements(&prefix, c, geometry, index_of, fixes)?;
        cases.push(loads);
    }
    let combinations = match &raw.combinations {
        None => (0..cases.len())
            .map(|k| Combination {
                name: cases[k].name.clone(),
                factors: vec![(k, 1.0)],
                prestress: 1.0,
            })
            .collect(),
        Some(raw_combinations) => combinations(raw_combinations, &cases)?,
    };
    for (k, c) in combinations.iter().enumerate() {
        rest_lengths_stay_positive(k, c, &cases, geometry)?;
    }
    Ok((cases, combinations))
}

/// A load case's `[[load.cases.settlement]]`: each moves the components [[supports.fix]] holds
/// of the nodes it selects (a component it moves must be held).
fn settlements(
    prefix: &str,
    case: &super::raw::RawLoadCase,
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
    fixes: &[NodeFix],
) -> Result<Vec<(usize, [f64; 3])>, CaseError> {
    let mut held = vec![[false; 3]; geometry.nodes.len()];
    for f in fixes {
        (0..3).for_each(|c| held[f.node][c] |= f.dofs[c]);
    }
    let mut out = Vec::new();
    for (i, entry) in case.settlement.iter().flatten().enumerate() {
        let key = format!("{prefix}.settlement[{i}]");
        let nodes = super::nodes::select(&key, geometry, index_of, &entry.nodes, &entry.in_box)?;
        let d = super::numbers::vector(
            &format!("{key}.displacement"),
            entry.displacement,
            SETTLEMENT_MAX,
            "each settlement component in m",
        )?;
        for n in nodes {
            if let Some(c) = (0..3).find(|&c| d[c] != 0.0 && !held[n][c]) {
                return Err(CaseError::invalid(
                    format!("{key}.displacement"),
                    format!("{:?}", entry.displacement),
                    format!(
                        "node {}'s {} component is not held: a settlement moves a support; \
                         hold it in [[supports.fix]], or give 0 there",
                        geometry.node_ids[n],
                        ["x", "y", "z"][c]
                    ),
                ));
            }
            out.push((n, d));
        }
    }
    Ok(out)
}

/// The largest settlement component accepted, m.
const SETTLEMENT_MAX: f64 = 1e3;

/// `[[load.combinations]]` over `cases`: unique names, factors naming cases (or
/// `prestress`), finite and at most [`FACTOR_MAX`] in magnitude.
fn combinations(
    raw: &[super::raw::RawCombination],
    cases: &[LoadCase],
) -> Result<Vec<Combination>, CaseError> {
    if raw.is_empty() {
        return Err(CaseError::invalid(
            "load.combinations",
            "[]",
            "give at least one combination, or remove the key (each case is then solved alone)",
        ));
    }
    let mut out: Vec<Combination> = Vec::new();
    for (k, c) in raw.iter().enumerate() {
        let prefix = format!("load.combinations[{k}]");
        name(
            &format!("{prefix}.name"),
            &c.name,
            out.iter().map(|c| &c.name),
        )?;
        out.push(factors(&prefix, &c.name, &c.factors, cases)?);
    }
    Ok(out)
}

/// The combination `name` of `raw` (`<prefix>.factors`): factors naming `cases` (or
/// `prestress`), finite and at most [`FACTOR_MAX`] in magnitude.
pub(super) fn factors(
    prefix: &str,
    name: &str,
    raw: &std::collections::BTreeMap<String, f64>,
    cases: &[LoadCase],
) -> Result<Combination, CaseError> {
    let mut combination = Combination {
        name: name.to_string(),
        factors: Vec::new(),
        prestress: 1.0,
    };
    for (case, &factor) in raw {
        let key = format!("{prefix}.factors.{case}");
        if !(factor.is_finite() && factor.abs() <= FACTOR_MAX) {
            return Err(CaseError::invalid(
                key,
                number(factor),
                format!("give a finite factor, at most {FACTOR_MAX:e} in magnitude"),
            ));
        }
        if case == PRESTRESS_FACTOR {
            if factor < 0.0 {
                return Err(CaseError::invalid(
                    key,
                    number(factor),
                    "the prestress's factor scales t0: give it ≥ 0 (1 keeps it as designed)",
                ));
            }
            combination.prestress = factor;
            continue;
        }
        let Some(index) = cases.iter().position(|l| &l.name == case) else {
            let names: Vec<&str> = cases.iter().map(|l| l.name.as_str()).collect();
            return Err(CaseError::invalid(
                key,
                number(factor),
                format!(
                    "no load case is named `{case}`: name one of [{}], or `prestress`",
                    names.join(", ")
                ),
            ));
        };
        combination.factors.push((index, factor));
    }
    Ok(combination)
}

/// Combination `k`'s rest-length changes `Σ f Δℓ0` leave every member a positive rest length.
fn rest_lengths_stay_positive(
    k: usize,
    combination: &Combination,
    cases: &[LoadCase],
    geometry: &Geometry,
) -> Result<(), CaseError> {
    let mut change: HashMap<usize, f64> = HashMap::new();
    for &(c, f) in &combination.factors {
        for &(j, d) in &cases[c].rest_length_changes {
            *change.entry(j).or_default() += f * d;
        }
    }
    let mut members: Vec<(usize, f64)> = change.into_iter().collect();
    members.sort_by_key(|&(j, _)| j);
    match super::actions::first_non_positive_rest_length(members, geometry) {
        None => Ok(()),
        Some((j, d, length)) => Err(CaseError::invalid(
            format!("load.combinations[{k}].factors"),
            format!("\"{}\"", combination.name),
            format!(
                "its factors change member {}'s rest length by {} m, {} m long: it would be ≤ \
                 0; lower the factors of its rest-length changes",
                geometry.members[j].id,
                number(d),
                number(length)
            ),
        )),
    }
}

/// A case's or combination's name under `key`: 1 to 64 letters, digits, `-`, `_` or `.` (a
/// directory name and a TOML bare key), not among `taken`.
pub(super) fn name<'a>(
    key: &str,
    text: &str,
    mut taken: impl Iterator<Item = &'a String>,
) -> Result<(), CaseError> {
    let bare = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.';
    if text.is_empty() || text.len() > 64 || !text.chars().all(bare) || text.starts_with('.') {
        return Err(CaseError::invalid(
            key,
            format!("\"{text}\""),
            "give a name of 1 to 64 letters, digits, `-`, `_` or `.` (not first), e.g. `G`, `ULS-1`",
        ));
    }
    if taken.any(|t| t == text) {
        return Err(CaseError::invalid(
            key,
            format!("\"{text}\""),
            "another entry has this name: give each its own",
        ));
    }
    Ok(())
}

impl Case {
    /// The case of combination `k` alone: `Σ f_c · case_c` as its one load (nodal forces,
    /// point loads and gravity summed with their factors, rest-length changes likewise), the
    /// members' prestress scaled by the combination's prestress factor; no load cases left.
    pub fn combination(&self, k: usize) -> Case {
        self.with_combination(&self.load.combinations[k])
    }

    /// The case of `combination` (over this case's load cases) alone, as
    /// [`Case::combination`].
    pub(super) fn with_combination(&self, combination: &Combination) -> Case {
        let mut case = self.clone();
        let load = &mut case.load;
        load.pattern.nodal = [0.0; 3];
        load.points.clear();
        load.gravity = None;
        load.rest_length_changes.clear();
        for &(c, f) in &combination.factors {
            let part = &self.load.cases[c];
            (0..3).for_each(|i| load.pattern.nodal[i] += f * part.nodal[i]);
            load.points
                .extend(part.points.iter().map(|&(n, p)| (n, p.map(|x| f * x))));
            if let Some(g) = part.gravity {
                let sum = load.gravity.get_or_insert([0.0; 3]);
                (0..3).for_each(|i| sum[i] += f * g[i]);
            }
            let scaled = part.rest_length_changes.iter().map(|&(j, d)| (j, f * d));
            load.rest_length_changes.extend(scaled);
        }
        // Settlements: a fix after the others (the last one of a component holds), moving
        // each held component by Σ f d from where [[supports.fix]] holds it.
        let mut moved: HashMap<usize, [f64; 3]> = HashMap::new();
        for &(c, f) in &combination.factors {
            for &(n, d) in &self.load.cases[c].settlements {
                let sum = moved.entry(n).or_default();
                (0..3).for_each(|k| sum[k] += f * d[k]);
            }
        }
        let mut nodes: Vec<usize> = moved.keys().copied().collect();
        nodes.sort_unstable();
        for n in nodes {
            let mut fix = NodeFix {
                node: n,
                dofs: [false; 3],
                displacement: [0.0; 3],
            };
            for f in self.fixes.iter().filter(|f| f.node == n) {
                for k in (0..3).filter(|&k| f.dofs[k]) {
                    fix.dofs[k] = true;
                    fix.displacement[k] = f.displacement[k];
                }
            }
            (0..3).for_each(|k| fix.displacement[k] += moved[&n][k]);
            case.fixes.push(fix);
        }
        let load = &mut case.load;
        load.cases.clear();
        load.combinations.clear();
        if combination.prestress != 1.0 {
            for m in &mut case.geometry.members {
                m.prestress *= combination.prestress;
            }
        }
        case
    }
}
