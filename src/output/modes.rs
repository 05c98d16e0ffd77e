//! `modes/{solver}_alpha{α}.csv` and `modes/{solver}_alpha{α}_shapes.csv`: the lowest natural
//! modes at every answer (`output.modes`, issue 45 item 1), as the sweep's
//! [`crate::analysis::modes::ModalAnalysis`] computed them, written atomically into the
//! staging directory, like the other per-solve files.

use super::modes_vtk::{modal_positions, modes_vtu_path, write_modes_vtu};
use super::plots::write_modes_svg;
use super::sinks::{Sink, SolveEnd, SolveKey, WriteError};
use super::{result_path, write_atomic};
use crate::analysis::modes::NaturalMode;
use crate::labels::alpha_label;
use crate::model::Model;
use crate::structure::CLAMPED;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// `modes/{solver}_alpha{α}_shapes.csv` under `dir`.
pub fn shapes_path(dir: &Path, solver: &str, alpha: f64) -> PathBuf {
    dir.join("modes")
        .join(format!("{solver}_alpha{}_shapes.csv", alpha_label(alpha)))
}

/// The files of the natural modes of every solve with an answer.
pub struct ModesSink {
    root: PathBuf,
    dir: PathBuf,
    /// Whether the modes go to a VTU file (`output.vtk`) and a figure (`output.plots`) too.
    vtk: bool,
    plots: bool,
}

impl ModesSink {
    /// The modes' files under `dir/modes` (the staging directory), with a VTU file of them when
    /// `vtk` and a figure when `plots`; errors name the files under `root`.
    pub fn new(root: &Path, dir: &Path, (vtk, plots): (bool, bool)) -> Self {
        ModesSink {
            root: root.to_path_buf(),
            dir: dir.to_path_buf(),
            vtk,
            plots,
        }
    }
}

impl Sink for ModesSink {
    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let SolveEnd::Solved {
            solution,
            model,
            modes,
            ..
        } = end
        else {
            return Ok(());
        };
        let solver = key.method.name();
        write_atomic(&result_path(&self.dir, "modes", solver, key.alpha), |w| {
            write_frequencies(w, modes)
        })
        .map_err(WriteError::at(result_path(
            &self.root, "modes", solver, key.alpha,
        )))?;
        write_atomic(&shapes_path(&self.dir, solver, key.alpha), |w| {
            write_shapes(w, model, modes)
        })
        .map_err(WriteError::at(shapes_path(&self.root, solver, key.alpha)))?;
        let u = &solution.equilibrium.displacements;
        if self.vtk {
            let path = modes_vtu_path(&self.dir, solver, key.alpha);
            write_modes_vtu(&path, key.alpha, model, u, modes).map_err(WriteError::at(
                modes_vtu_path(&self.root, solver, key.alpha),
            ))?;
        }
        if self.plots {
            let figure =
                |dir: &Path| result_path(dir, "modes", solver, key.alpha).with_extension("svg");
            let at = modal_positions(model, u);
            write_modes_svg(&figure(&self.dir), model, &at, modes)
                .map_err(WriteError::at(figure(&self.root)))?;
        }
        Ok(())
    }
}

/// `mode,frequency_Hz,period_s,prestress_governed,converged`, modes numbered from 1.
fn write_frequencies(w: &mut dyn Write, modes: &[NaturalMode]) -> io::Result<()> {
    writeln!(w, "mode,frequency_Hz,period_s,prestress_governed,converged")?;
    for (i, mode) in modes.iter().enumerate() {
        writeln!(
            w,
            "{},{},{},{},{}",
            i + 1,
            mode.frequency_hz,
            mode.period_s(),
            mode.prestress_governed(),
            mode.converged
        )?;
    }
    Ok(())
}

/// `mode,node,ux,uy,uz`: each mode's shape on every node (node ids; held components 0).
fn write_shapes(w: &mut dyn Write, model: &Model, modes: &[NaturalMode]) -> io::Result<()> {
    let s = &model.structure;
    writeln!(w, "mode,node,ux,uy,uz")?;
    for (i, mode) in modes.iter().enumerate() {
        for (node, id) in s.node_ids.iter().enumerate() {
            let u = |c: usize| match s.dof_of[3 * node + c] {
                CLAMPED => 0.0,
                d => mode.shape[d],
            };
            writeln!(w, "{},{id},{},{},{}", i + 1, u(0), u(1), u(2))?;
        }
    }
    Ok(())
}
