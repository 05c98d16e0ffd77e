//! Figure 12 (`plots/error_modules.svg`): the LATIN solvers at the case's largest α on the
//! case's grid made of each module kind of `output.compare_modules`.

use super::RunError;
use crate::app::reference::ReferenceSource;
use crate::app::setup::{prepare, set_up};
use crate::case::Case;
use crate::output::plots::{self, History};
use crate::output::OutputDir;
use crate::output::{FigureSettings, WriteError};
use crate::solvers::{Method, Recorder, Reference};
use std::cell::RefCell;
use std::path::Path;

/// Figure 12 drawn into the staging directory of `out` (`root`: its path, for errors), then
/// committed.
pub(super) fn write(
    case: &Case,
    methods: &[Method],
    out: &RefCell<OutputDir>,
    root: &Path,
) -> Result<(), RunError> {
    let staging = out.borrow().staging().to_path_buf();
    write_module_comparison(case, methods, &staging, root)?;
    out.borrow_mut().commit()?;
    Ok(())
}

/// `plots/error_modules.svg`: every LATIN solver of `methods` at the case's largest α, on the
/// case's grid made of each module kind of `output.compare_modules` (the paper's Figure 12).
fn write_module_comparison(
    case: &Case,
    methods: &[Method],
    staging: &Path,
    root: &Path,
) -> Result<(), RunError> {
    let alpha = case
        .load
        .alphas
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let mut histories = Vec::new();
    for &module in &case.output.compare_modules {
        // Case validation refuses compare_modules without a [grid].
        let Some(grid_case) = case.with_module(module) else {
            return Ok(());
        };
        let prepared = prepare(&grid_case)?;
        let mut solvers = Vec::new();
        for &method in methods {
            let set_up = set_up(method, &case.solver, &prepared)?;
            if method.reports_error() {
                solvers.push(set_up);
            }
        }
        let model = &prepared.model;
        let load = model.load(alpha);
        let mut reference = ReferenceSource::new(&grid_case, &solvers, &prepared)?;
        let cold = vec![None; solvers.len()];
        let reference_solution = reference.solve(&load, &mut solvers, &cold);
        let errors = reference_solution
            .as_ref()
            .map(|r| Reference::new(model, &r.equilibrium.displacements));
        for set_up in &mut solvers {
            let mut recorder = Recorder::default();
            set_up.solver.solve(&load, errors.as_ref(), &mut recorder);
            histories.push((
                module.name(),
                History {
                    solver: set_up.method,
                    alpha,
                    records: recorder.records,
                },
            ));
        }
    }
    let settings = FigureSettings {
        amplification: case.output.amplification,
        figure_alpha: case.output.figure_alpha,
        max_plot_iterations: case.output.max_plot_iterations,
    };
    let path = staging.join("plots").join("error_modules.svg");
    let written = plots::write_module_comparison(&path, &histories, &settings);
    written.map_err(|source| {
        RunError::Write(WriteError {
            path: root.join("plots").join("error_modules.svg"),
            source,
        })
    })
}
