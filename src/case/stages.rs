//! `[[stages]]`: a construction sequence under `large`. Each stage installs members
//! (`members`), holds props (`props`: nodes held at that stage alone) and applies loads and a
//! prestress factor (`factors`, as a combination's); each is solved from the last stage's
//! answer (`crate::app::stages`). Members are installed with their designed law (rest length
//! and prestress of the members table) between the nodes where the last stage left them.

use super::combinations::factors;
use super::numbers::number;
use super::raw::RawStage;
use super::{CaseError, Combination, LoadCase, SolverChoice, Stage};
use crate::model::GeometricModel;
use crate::solvers::Method;
use crate::structure::{Geometry, NodeFix};
use std::collections::HashMap;

/// What the stages are read against.
pub(super) struct StageContext<'a> {
    pub geometry: &'a Geometry,
    pub node_index: &'a HashMap<u64, usize>,
    pub cases: &'a [LoadCase],
    pub grid: bool,
    pub model: GeometricModel,
    pub model_auto: bool,
    pub solver: &'a SolverChoice,
    pub alphas: &'a [f64],
    pub combinations_given: bool,
}

/// The stages of `raw`, checked; empty without `[[stages]]`.
pub(super) fn stages(
    raw: Option<&[RawStage]>,
    at: &StageContext<'_>,
) -> Result<Vec<Stage>, CaseError> {
    let Some(raw) = raw else {
        return Ok(Vec::new());
    };
    fits_the_case(raw, at)?;
    let member_index: HashMap<u64, usize> = (at.geometry.members.iter().enumerate())
        .map(|(j, m)| (m.id, j))
        .collect();
    let mut installed_at: Vec<Option<usize>> = vec![None; at.geometry.members.len()];
    let mut out: Vec<Stage> = Vec::new();
    for (k, s) in raw.iter().enumerate() {
        let prefix = format!("stages[{k}]");
        super::combinations::name(
            &format!("{prefix}.name"),
            &s.name,
            out.iter().map(|s| &s.name),
        )?;
        let mut members = Vec::new();
        for &id in s.members.iter().flatten() {
            let Some(&j) = member_index.get(&id) else {
                return Err(CaseError::invalid(
                    format!("{prefix}.members"),
                    id,
                    "no member has this id: name members of the members table",
                ));
            };
            if let Some(earlier) = installed_at[j] {
                return Err(CaseError::invalid(
                    format!("{prefix}.members"),
                    id,
                    format!(
                        "stage `{}` installs this member already: install each member once",
                        raw[earlier].name
                    ),
                ));
            }
            installed_at[j] = Some(k);
            members.push(j);
        }
        let mut props = Vec::new();
        for &id in s.props.iter().flatten() {
            let Some(&n) = at.node_index.get(&id) else {
                return Err(CaseError::invalid(
                    format!("{prefix}.props"),
                    id,
                    "no node has this id: name nodes of the nodes table",
                ));
            };
            props.push(n);
        }
        let empty = Default::default();
        let loads = factors(
            &prefix,
            &s.name,
            s.factors.as_ref().unwrap_or(&empty),
            at.cases,
        )?;
        out.push(Stage {
            name: s.name.clone(),
            members,
            props,
            loads,
        });
    }
    // The first stage installs every member no later stage does.
    let rest = (0..installed_at.len()).filter(|&j| installed_at[j].is_none());
    out[0].members.extend(rest);
    out[0].members.sort_unstable();
    if out[0].members.is_empty() {
        return Err(CaseError::invalid(
            "stages[0].members",
            "[]",
            "the first stage installs no member: leave some members out of the later stages",
        ));
    }
    Ok(out)
}

/// Stages are newton's under `large`, on a members table, each solved at α = 1, their loads
/// their own `factors` (no `[[load.combinations]]` beside them).
fn fits_the_case(raw: &[RawStage], at: &StageContext<'_>) -> Result<(), CaseError> {
    let refuse = |key: &str, value: &str, fix: &str| Err(CaseError::invalid(key, value, fix));
    if raw.is_empty() {
        return refuse("stages", "[]", "give at least one stage, or remove the key");
    }
    if at.grid {
        return refuse(
            "stages",
            "stages of a [grid]",
            "a stage installs members of a members table: write the grid as tables \
             (scripts/grid_csv.py) and give it as [structure]",
        );
    }
    if at.model != GeometricModel::Large || at.model_auto {
        return refuse(
            "stages",
            "construction stages",
            "each stage is solved from where the last left the structure, on its current \
             geometry: set `model.geometry = \"large\"`",
        );
    }
    if let Some(other) = at.solver.methods.iter().find(|m| **m != Method::Newton) {
        return Err(CaseError::invalid(
            "stages",
            "construction stages",
            format!(
                "the stages are solved by newton, and `solver.methods` names {}: set \
                 `solver.methods = [\"newton\"]`",
                other.name()
            ),
        ));
    }
    if at.solver.newton.path == crate::solvers::arc_length::PathFollowing::ArcLength {
        return refuse(
            "load.path",
            "\"arc-length\"",
            "each stage's path starts where the last left the structure, by load control: \
             remove `load.path` from a staged case",
        );
    }
    if at.alphas != [1.0] {
        let shown: Vec<String> = at.alphas.iter().map(|&a| number(a)).collect();
        return Err(CaseError::invalid(
            "load.alpha",
            format!("[{}]", shown.join(", ")),
            "each stage is solved at α = 1, its loads given by its `factors`: give \
             `load.alpha = [1.0]`",
        ));
    }
    if at.combinations_given {
        return refuse(
            "load.combinations",
            "combinations beside stages",
            "each stage's `factors` combine the load cases: remove [[load.combinations]]",
        );
    }
    Ok(())
}

impl super::Case {
    /// The case of construction stage `k` alone: the members installed up to it (their
    /// rest-length changes renumbered), the supports plus the stage's props, every node no
    /// installed member reaches held (not yet built), and the stage's loads and prestress
    /// factor as its one load; no stages left. It starts at `start` (the last stage's answer),
    /// where its props hold their nodes (a component a support prescribes stays where the
    /// support puts it).
    pub fn stage(&self, k: usize, start: Option<&super::StageStart>) -> super::Case {
        let stage = &self.stages[k];
        let mut case = self.with_loads(&stage.loads);
        let mut installed = vec![false; self.geometry.members.len()];
        for s in &self.stages[..=k] {
            s.members.iter().for_each(|&j| installed[j] = true);
        }
        let kept: Vec<usize> = (0..installed.len()).filter(|&j| installed[j]).collect();
        let mut new_index = vec![None; installed.len()];
        kept.iter()
            .enumerate()
            .for_each(|(i, &j)| new_index[j] = Some(i));
        let g = &mut case.geometry;
        g.members = kept.iter().map(|&j| g.members[j].clone()).collect();
        g.groups = g
            .groups
            .take()
            .map(|v| kept.iter().map(|&j| v[j].clone()).collect());
        g.checks = g.checks.take().map(|c| c.keeping(&kept));
        let changes = std::mem::take(&mut case.load.rest_length_changes);
        case.load.rest_length_changes = changes
            .into_iter()
            .filter_map(|(j, d)| new_index[j].map(|i| (i, d)))
            .collect();
        let mut reached = vec![false; g.nodes.len()];
        for m in &g.members {
            reached[m.a] = true;
            reached[m.b] = true;
        }
        // Where each component is: prescribed by a support (the last fix of it), else where
        // the last stage left it.
        let mut at: Vec<[Option<f64>; 3]> = vec![[None; 3]; g.nodes.len()];
        for f in &case.fixes {
            (0..3)
                .filter(|&c| f.dofs[c])
                .for_each(|c| at[f.node][c] = Some(f.displacement[c]));
        }
        let held = |node: usize| NodeFix {
            node,
            dofs: [true; 3],
            displacement: std::array::from_fn(|c| {
                at[node][c].unwrap_or_else(|| start.map_or(0.0, |s| s.displacements[node][c]))
            }),
        };
        let props: Vec<NodeFix> = stage.props.iter().map(|&n| held(n)).collect();
        let unbuilt: Vec<NodeFix> = (0..reached.len())
            .filter(|&n| !reached[n])
            .map(held)
            .collect();
        case.fixes.extend(props);
        case.fixes.extend(unbuilt);
        case.stages.clear();
        case.start = start.cloned();
        case
    }

    /// A stage's loads as the one load of a case: [`Combination`]'s over the load cases, or
    /// without load cases `[load]`'s own loads at every stage, the prestress factored.
    fn with_loads(&self, loads: &Combination) -> super::Case {
        if !self.load.cases.is_empty() {
            return self.with_combination(loads);
        }
        let mut case = self.clone();
        case.load.combinations.clear();
        for m in &mut case.geometry.members {
            m.prestress *= loads.prestress;
        }
        case
    }
}
