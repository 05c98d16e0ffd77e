//! The run's files: the output directory, the sinks of the files the case asks for, and what
//! set-up writes once (mechanisms, homogenised operators).

use super::{RunError, RunEvent};
use crate::app::setup::{Prepared, SetUpSolver};
use crate::case::Case;
use crate::output::{
    self,
    sinks::{
        HistorySink, PerSolveSink, PlotsSink, PublishSink, ReactionTotalsSink, StabilitySink,
        SummarySink,
    },
    ChecksSink, FigureSettings, ModesSink, OutputDir, Sinks, WriteError,
};
use std::cell::RefCell;
use std::path::Path;

/// The output directory `dir`, locked for this run with a private staging directory, when
/// this process `writes` and the case asks for files.
pub(super) fn open_output(
    case: &Case,
    dir: &Path,
    writes: bool,
) -> Result<Option<RefCell<OutputDir>>, RunError> {
    (writes && writes_files(case))
        .then(|| OutputDir::open(dir).map(RefCell::new))
        .transpose()
        .map_err(RunError::from)
}

/// Every LATIN solver's homogenised substructure operators under `homogenised/`, committed
/// to the output directory `out` (`root`: its path, for errors).
pub(super) fn write_homogenised(
    root: &Path,
    out: &RefCell<OutputDir>,
    solvers: &mut [SetUpSolver<'_>],
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<(), RunError> {
    events(RunEvent::Stage("writing the homogenised operators"));
    for set_up in solvers {
        let operators = set_up.solver.homogenised();
        let staging = out.borrow().staging().to_path_buf();
        output::write_homogenised(&staging, &operators).map_err(|source| WriteError {
            path: root.join("homogenised"),
            source,
        })?;
        out.borrow_mut().commit()?;
    }
    Ok(())
}

/// `mechanisms.csv` (`node,mode,ux,uy,uz`) in the output directory, through its lock and
/// staging like every result.
pub(super) fn write_mechanisms(
    dir: &Path,
    modes: &[crate::solvers::ModeRow],
) -> Result<(), RunError> {
    let mut out = OutputDir::open(dir)?;
    let staging = out.staging().to_path_buf();
    output::write_mechanisms(&staging, modes).map_err(|source| WriteError {
        path: dir.join("mechanisms.csv"),
        source,
    })?;
    out.commit()?;
    out.finish().map_err(|source| WriteError {
        path: dir.to_path_buf(),
        source,
    })?;
    Ok(())
}

/// Whether `case` asks for any file.
fn writes_files(case: &Case) -> bool {
    let o = &case.output;
    o.history
        || o.tensions
        || o.displacements
        || o.forces
        || o.reactions
        || o.vtk
        || o.plots
        || o.stability
        || o.summary
        || o.homogenised
        || o.modes > 0
}

/// The sinks of the files `case` asks for, in the order they write: the per-solve files into
/// the staging directory of `output`, published together, then the rows of the ledgers.
pub(super) fn sinks<'s>(
    case: &Case,
    root: &Path,
    output: Option<&'s RefCell<OutputDir>>,
    prepared: &'s Prepared,
    solvers: &[SetUpSolver<'_>],
) -> Sinks<'s> {
    let mut sinks = Sinks::default();
    let Some(output) = output else {
        return sinks;
    };
    let staging = output.borrow().staging().to_path_buf();
    let dir = staging.as_path();
    let (model, taut) = (&prepared.model, prepared.taut.as_ref());
    let structure = &model.structure;
    let out = &case.output;
    let has_history = solvers
        .iter()
        .any(|s| output::history_column(s.solver.stopping_measure()).is_some());
    sinks.add(
        out.history && has_history,
        HistorySink::new(
            root,
            dir,
            prepared
                .share
                .as_ref()
                .map_or(structure.n_cables(), |share| share.world_cables()),
        ),
    );
    sinks.add(out.tensions, PerSolveSink::tensions(root, dir));
    sinks.add(out.displacements, PerSolveSink::displacements(root, dir));
    sinks.add(out.forces, PerSolveSink::forces(root, dir));
    sinks.add(out.reactions, PerSolveSink::reactions(root, dir));
    sinks.add(out.vtk, PerSolveSink::vtk(root, dir));
    sinks.add(
        out.modes > 0,
        ModesSink::new(root, dir, (out.vtk, out.plots)),
    );
    if let Some(first) = solvers.first().filter(|_| out.plots) {
        let settings = FigureSettings {
            amplification: out.amplification,
            figure_alpha: out.figure_alpha,
            max_plot_iterations: out.max_plot_iterations,
        };
        sinks.add(
            true,
            PlotsSink::new(root, dir, structure, first.method, settings),
        );
    }
    sinks.add(true, PublishSink::new(output));
    if let Some(taut) = taut {
        sinks.add(out.stability, StabilitySink::new(output, taut));
    }
    sinks.add(out.reactions, ReactionTotalsSink::new(output));
    let checks = model.structure.checks.is_some();
    sinks.add(
        checks || case.forbid_slack,
        ChecksSink::new(output, case.forbid_slack),
    );
    sinks.add(out.summary, SummarySink::new(output, checks));
    sinks
}
