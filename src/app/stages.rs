//! `tensolve run` on a case with construction stages (`[[stages]]`): each stage is its own
//! case ([`Case::stage`]: the members installed so far, the supports and the stage's props,
//! its loads), solved under `large` as a whole run into `DIR/stages/<name>/`, its load path
//! starting where the last stage left the structure (its displacements, under its load). A
//! stage that releases a prop still carrying a reaction is refused: the reaction would be
//! let go at once. `DIR/summary.csv` gathers the stages' rows with a `stage` column.

use super::sweep::{output_dir, run_on, RunError, RunEvent, RunOptions};
use crate::case::{Case, CaseError, StageStart};
use crate::decomposition::Exchange;
use crate::model::material;
use crate::model::Model;
use crate::output::{write_combined_summary, Combined, SummaryRow, WriteError};
use crate::solvers::Equilibrium;
use std::path::Path;

/// A released prop whose reaction at the last stage is above this fraction of the largest
/// member force there still carries load.
const RELEASED_REACTION: f64 = 1e-6;

/// Every stage of `case` run in order, each from the last; the first that does not converge
/// ends the sequence (the stages after it would start from no answer). Returns every row,
/// with its stage's name.
pub fn run_stages(
    case: &Case,
    options: &RunOptions,
    exchange: &dyn Exchange,
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<Vec<(String, SummaryRow)>, RunError> {
    if exchange.size() > 1 {
        // Each stage starts from the last one's displacements, which rank 0 alone writes.
        return Err(CaseError::invalid(
            "stages",
            format!("on {} MPI ranks", exchange.size()),
            "construction stages run on one process: run the case without mpirun",
        )
        .into());
    }
    if let Some(methods) = &options.methods {
        case.newton_only(methods)?;
    }
    let dir = output_dir(case, options);
    let mut rows = Vec::new();
    let mut combined: Vec<Combined> = Vec::new();
    // The last stage's model (its structure under `large`) and where the next one starts.
    let mut last: Option<(Model, StageStart)> = None;
    let mut outcome = Ok(());
    for k in 0..case.stages.len() {
        let name = case.stages[k].name.clone();
        let mut stage = case.stage(k, last.as_ref().map(|(_, start)| start));
        // The stage reads its answer back from its displacements.
        stage.output.displacements = true;
        if let Some((before, start)) = &last {
            if let Err(e) = released_props_carry_nothing(case, k, before, &stage, start) {
                outcome = Err(e);
                break;
            }
        }
        let sub = dir.join("stages").join(&name);
        let sub_options = RunOptions {
            out_dir: Some(sub.clone()),
            methods: options.methods.clone(),
        };
        events(RunEvent::Construction(&name));
        let ran = run_on(stage.clone(), &sub_options, exchange, events);
        if sub.join("summary.csv").exists() {
            combined.push((name.clone(), sub.clone()));
        }
        let read = ran.and_then(|r| Ok((r, displacements(&sub, &stage)?)));
        match read {
            Ok((r, displacements)) => {
                rows.extend(r.into_iter().map(|r| (name.clone(), r)));
                let model = stage.model();
                let load = node_loads(&model);
                last = Some((
                    model,
                    StageStart {
                        displacements,
                        load,
                    },
                ));
            }
            Err(e) => {
                outcome = Err(e);
                break;
            }
        }
    }
    // The summary of the stages solved, also when one ended the sequence.
    let path = dir.join("summary.csv");
    let written = match combined.is_empty() {
        true => Ok(()),
        false => write_combined_summary(&dir, &combined, "stage"),
    };
    outcome?;
    written.map_err(|source| WriteError { path, source })?;
    Ok(rows)
}

/// Per node, the displacements of a stage's answer (`displacements/newton_alpha1.csv`).
fn displacements(sub: &Path, stage: &Case) -> Result<Vec<[f64; 3]>, RunError> {
    let path = sub.join("displacements").join("newton_alpha1.csv");
    let unreadable = |reason: String| {
        let path = path.clone();
        RunError::Write(WriteError {
            path,
            source: std::io::Error::other(reason),
        })
    };
    let mut reader = csv::Reader::from_path(&path).map_err(|e| unreadable(e.to_string()))?;
    let index: std::collections::HashMap<u64, usize> = (stage.geometry.node_ids.iter())
        .enumerate()
        .map(|(i, &id)| (id, i))
        .collect();
    let mut u = vec![[0.0; 3]; stage.geometry.nodes.len()];
    for record in reader.records() {
        let record = record.map_err(|e| unreadable(e.to_string()))?;
        let field = |k: usize| record.get(k).and_then(|x| x.parse::<f64>().ok());
        let node = record.get(0).and_then(|x| x.parse::<u64>().ok());
        match (
            node.and_then(|n| index.get(&n)),
            field(4),
            field(5),
            field(6),
        ) {
            (Some(&i), Some(x), Some(y), Some(z)) => u[i] = [x, y, z],
            _ => return Err(unreadable(format!("a row it cannot read: {record:?}"))),
        }
    }
    Ok(u)
}

/// Per node, the load of `model`'s structure at α = 1 (on free and held components).
fn node_loads(model: &Model) -> Vec<[f64; 3]> {
    let s = &model.structure;
    let mut load = vec![[0.0; 3]; s.nodes.len()];
    for (global, &d) in s.dof_of.iter().enumerate() {
        if d != crate::structure::CLAMPED {
            load[global / 3][global % 3] = s.unit_load[d];
        }
    }
    for &(global, f) in &s.held_load {
        load[global / 3][global % 3] += f;
    }
    load
}

/// Stage `k` frees no component the last stage held with a reaction above
/// [`RELEASED_REACTION`] of its largest member force (a prop taken away under load).
fn released_props_carry_nothing(
    case: &Case,
    k: usize,
    model: &Model,
    stage: &Case,
    start: &StageStart,
) -> Result<(), RunError> {
    let s = &model.structure;
    let mut u = vec![0.0; s.n_free];
    for (global, &d) in s.dof_of.iter().enumerate() {
        if d != crate::structure::CLAMPED {
            u[d] = start.displacements[global / 3][global % 3];
        }
    }
    let trial = model.trial_tensions(&u);
    let tensions: Vec<f64> = (s.links.iter().zip(&trial))
        .map(|(l, &t)| material::tension(l, t))
        .collect();
    let scale = tensions.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let states = model.member_states(&u);
    let eq = Equilibrium::classified(model, u.clone(), tensions);
    let held_now = stage.structure().dof_of;
    for r in crate::results::reactions(model, &eq, 1.0, &states) {
        let global = 3 * r.node + r.component;
        if held_now[global] != crate::structure::CLAMPED
            && r.force.abs() > RELEASED_REACTION * scale
        {
            let id = case.geometry.node_ids[r.node];
            let (this, last) = (&case.stages[k].name, &case.stages[k - 1].name);
            let component = ["x", "y", "z"][r.component];
            let propped = case.stages[k - 1].props.contains(&r.node);
            let (key, value, fix) = match propped {
                true => (
                    format!("stages[{k}].props"),
                    format!("node {id} released"),
                    format!(
                        "stage `{this}` lets go of node {id}'s {component} component, which \
                         carries a reaction of {:.6e} N at stage `{last}`: a support removed \
                         under load drops that load at once; hold it at this stage too \
                         (`props`), or unload it first (a stage whose prestress or rest-length \
                         change lifts the structure off it)",
                        r.force
                    ),
                ),
                false => (
                    format!("stages[{k}].members"),
                    format!("node {id} built"),
                    format!(
                        "stage `{this}` builds node {id}, which no member reached at stage \
                         `{last}`, where a load on it ({component}: {:.6e} N) went to the \
                         ground: apply that load from the stage that builds the node",
                        r.force
                    ),
                ),
            };
            return Err(CaseError::invalid(key, value, fix).into());
        }
    }
    Ok(())
}
