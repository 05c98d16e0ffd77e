//! `history/{solver}_alpha{α}.csv`: one row per iteration of an iterative solver (the LATIN
//! solvers and pcg-lcp; newton, the exact reference, writes none), written as the iterations go
//! to a `.partial` file (created exclusively: never through a planted link) that is renamed to
//! its final name only when the solve ends (a file under the final name is complete). The
//! sweep writes it inside its private staging directory and publishes it with the solve.

use super::tables::result_path;
use crate::solvers::{IterationRecord, Measure, Observer};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Header line of a history CSV file: per iteration, energy error e (empty without a
/// reference), the stopping measure under `measure_column` ([`history_column`]), r(U),
/// fraction of cables slack, operator rebuilds (column `search_updates`), solver time (s).
pub fn history_header(measure_column: &str) -> String {
    format!(
        "iteration,error_e,{measure_column},equilibrium_residual,slack_fraction,search_updates,elapsed_seconds"
    )
}

/// The history column of a solver's stopping measure, or `None` for a solver that writes no
/// history (newton: the exact reference, a handful of active-set steps).
pub fn history_column(measure: Measure) -> Option<&'static str> {
    match measure {
        Measure::Indicator => Some("indicator_eta"),
        Measure::ComplementarityResidual => Some("complementarity_residual"),
        Measure::EquilibriumResidual => None,
    }
}

/// An [`Observer`] writing one solve's iteration history CSV, renamed into place by
/// [`HistoryWriter::finish`] (dropped unfinished, it removes its partial file).
pub struct HistoryWriter {
    path: PathBuf,
    partial: PathBuf,
    out: Option<BufWriter<File>>,
    cables: usize,
    error: Option<std::io::Error>,
}

impl HistoryWriter {
    /// Open the `.partial` file of `solver` at `alpha` under `dir/history` and write the header,
    /// whose third column is named `measure_column` ([`history_column`]); `cables` is the
    /// denominator of the slack fraction.
    pub fn create(
        dir: &Path,
        solver: &str,
        alpha: f64,
        measure_column: &str,
        cables: usize,
    ) -> std::io::Result<Self> {
        let path = result_path(dir, "history", solver, alpha);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)?;
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let partial = path.with_file_name(format!(".{name}.partial"));
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&partial)?;
        let mut out = BufWriter::new(file);
        writeln!(out, "{}", history_header(measure_column))?;
        Ok(HistoryWriter {
            path,
            partial,
            out: Some(out),
            cables,
            error: None,
        })
    }

    /// Flush, sync and rename to the final name.
    pub fn finish(mut self) -> std::io::Result<PathBuf> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let out = self.out.take().expect("open until finish");
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&self.partial, &self.path)?;
        Ok(self.path.clone())
    }
}

impl Observer for HistoryWriter {
    fn iteration(&mut self, r: &IterationRecord) {
        if self.error.is_some() {
            return;
        }
        let Some(out) = self.out.as_mut() else { return };
        let fraction = if self.cables > 0 {
            r.slack_cables as f64 / self.cables as f64
        } else {
            0.0
        };
        let error = r.error.map(|e| format!("{e:e}")).unwrap_or_default();
        let residual = r
            .equilibrium_residual
            .map(|x| format!("{x:e}"))
            .unwrap_or_default();
        let result = writeln!(
            out,
            "{},{},{:e},{},{},{},{}",
            r.iteration, error, r.stopping_value, residual, fraction, r.rebuilds, r.elapsed_seconds
        )
        .and_then(|_| out.flush());
        if let Err(e) = result {
            self.error = Some(e);
        }
    }
}

impl Drop for HistoryWriter {
    fn drop(&mut self) {
        // Not finished: leave no partial file behind.
        if self.out.is_some() {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}
