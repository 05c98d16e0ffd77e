//! One sink per file family. A sweep hands every solve to the sinks the case asks for: each
//! sees the solve start, its iterations, its end, and the end of the sweep, and writes its own
//! files. Nothing here solves.
//!
//! | sink | files |
//! |---|---|
//! | [`HistorySink`] | `history/{solver}_alpha{α}.csv`, as the iterations go |
//! | [`PerSolveSink`] | `tensions/{solver}_alpha{α}.csv`, `displacements/…`, `forces/…`, `reactions/…`, `vtk/…vtu` |
//! | [`super::ModesSink`] | `modes/{solver}_alpha{α}.csv`, `modes/…_shapes.csv` (`output.modes`) |
//! | [`PlotsSink`] | `plots/*.svg`, at the end of the sweep |
//! | [`PublishSink`] | publishes what the sinks above staged: the solve's commit point |
//! | [`StabilitySink`] | `stability.csv`, one row appended after every solve |
//! | [`ReactionTotalsSink`] | `reaction_totals.csv`, one row appended after every solve with an answer |
//! | [`super::ChecksSink`] | `checks.csv`, a row per member above a utilisation of 1, after every solve |
//! | [`SummarySink`] | `summary.csv`, one row appended after every solve |
//!
//! The sinks above [`PublishSink`] write into the run's private staging directory; nothing of
//! a solve is visible before it publishes, and a solve without a finite answer is discarded.
//! A ledger row that cannot be written (a full disk, a file-size limit) withdraws the solve's
//! published files and the rows it had appended: no file is left without its `summary.csv` row.

use super::{
    history_column, reaction_totals, reaction_totals_line, result_path, stability_line,
    summary_check_cells, summary_line, vtu_path, write_displacements, write_forces,
    write_reactions, write_tensions, write_vtu, FigureData, FigureSettings, HistoryWriter,
    OutputDir, StabilityRow, SummaryRow, REACTION_TOTALS_HEADER, STABILITY_HEADER,
    SUMMARY_CHECK_COLUMNS, SUMMARY_HEADER,
};
use crate::model::Model;
use crate::results;
use crate::solvers::{Equilibrium, IterationRecord, Measure, Method, Solution, TautStiffness};
use crate::structure::Structure;
use std::cell::RefCell;
use std::io;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A file that could not be written.
#[derive(Debug, Error)]
#[error("could not write `{}`: {source}{}", path.display(), advice(source))]
pub struct WriteError {
    /// The file (or, for the figures, their directory), under its final name.
    pub path: PathBuf,
    /// Why.
    pub source: io::Error,
}

/// What to do about a write that failed for want of room: a full disk or a file-size limit.
fn advice(source: &io::Error) -> &'static str {
    match source.kind() {
        io::ErrorKind::StorageFull => {
            " (the disk is full: free some space, or pass `--out` with a directory on another disk)"
        }
        io::ErrorKind::FileTooLarge => {
            " (a file-size limit, `ulimit -f`, is below this file's size: raise it)"
        }
        _ => "",
    }
}

impl WriteError {
    pub(super) fn at(path: impl Into<PathBuf>) -> impl FnOnce(io::Error) -> WriteError {
        let path = path.into();
        move |source| WriteError { path, source }
    }
}

/// Which solve is starting.
#[derive(Debug, Clone, Copy)]
pub struct SolveKey {
    /// The solver.
    pub method: Method,
    /// The load factor.
    pub alpha: f64,
    /// What the solver's stopping measure measures.
    pub measure: Measure,
}

/// How a solve ended, as the sinks see it.
#[derive(Debug, Clone, Copy)]
pub enum SolveEnd<'a> {
    /// A finite answer and its summary row.
    Solved {
        /// The solver's answer.
        solution: &'a Solution,
        /// Its row of `summary.csv`.
        row: &'a SummaryRow,
        /// The model it was solved with (under `model.geometry = "auto"`, the row's).
        model: &'a Model,
        /// Its natural modes (`output.modes`; empty when not asked for).
        modes: &'a [crate::analysis::modes::NaturalMode],
    },
    /// The answer has a non-finite value: no file of it is written.
    NonFinite,
    /// The solve ended with no answer (no equilibrium, a limit point): its summary row only.
    NoAnswer {
        /// Its row of `summary.csv`.
        row: &'a SummaryRow,
    },
}

/// A family of output files.
pub trait Sink {
    /// A solve starts.
    fn start(&mut self, _key: &SolveKey) -> Result<(), WriteError> {
        Ok(())
    }

    /// An iterate of the current solve.
    fn iteration(&mut self, _record: &IterationRecord) {}

    /// The current solve ended.
    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError>;

    /// The sweep ended.
    fn close(&mut self) -> Result<(), WriteError> {
        Ok(())
    }
}

/// `history/{solver}_alpha{α}.csv` of the solvers whose stopping measure is the indicator η.
pub struct HistorySink {
    root: PathBuf,
    dir: PathBuf,
    cables: usize,
    writer: Option<HistoryWriter>,
}

impl HistorySink {
    /// Histories written under `dir/history` (the staging directory) of a structure of
    /// `cables` cables; errors name the file under `root/history`.
    pub fn new(root: &Path, dir: &Path, cables: usize) -> Self {
        HistorySink {
            root: root.to_path_buf(),
            dir: dir.to_path_buf(),
            cables,
            writer: None,
        }
    }
}

impl Sink for HistorySink {
    fn start(&mut self, key: &SolveKey) -> Result<(), WriteError> {
        if let Some(column) = history_column(key.measure) {
            let writer =
                HistoryWriter::create(&self.dir, key.method.name(), key.alpha, column, self.cables)
                    .map_err(WriteError::at(result_path(
                        &self.root,
                        "history",
                        key.method.name(),
                        key.alpha,
                    )))?;
            self.writer = Some(writer);
        }
        Ok(())
    }

    fn iteration(&mut self, record: &IterationRecord) {
        if let Some(writer) = self.writer.as_mut() {
            crate::solvers::Observer::iteration(writer, record);
        }
    }

    fn end(&mut self, key: &SolveKey, _end: SolveEnd) -> Result<(), WriteError> {
        match self.writer.take() {
            Some(writer) => writer
                .finish()
                .map(|_| ())
                .map_err(WriteError::at(result_path(
                    &self.root,
                    "history",
                    key.method.name(),
                    key.alpha,
                ))),
            None => Ok(()),
        }
    }
}

/// Writes one file of a solve: `(dir, solver, α, model, equilibrium) → its path`.
type WriteSolve = fn(&Path, &str, f64, &Model, &Equilibrium) -> io::Result<PathBuf>;

/// One file per solve, written when the solve ends with a finite answer:
/// `tensions/…`, `displacements/…`, `forces/…`, `reactions/…`, `vtk/…`.
pub struct PerSolveSink {
    root: PathBuf,
    dir: PathBuf,
    write: WriteSolve,
    /// The file a write error names, under `root`.
    error_path: fn(&Path, &str, f64) -> PathBuf,
}

impl PerSolveSink {
    /// `tensions/{solver}_alpha{α}.csv` of `model`'s structure, written under `dir` (the
    /// staging directory); errors name the file under `root`.
    pub fn tensions(root: &Path, dir: &Path) -> Self {
        Self::new(
            root,
            dir,
            |dir, solver, alpha, m, eq| write_tensions(dir, solver, alpha, &m.structure, eq),
            |dir, solver, alpha| result_path(dir, "tensions", solver, alpha),
        )
    }

    /// `displacements/{solver}_alpha{α}.csv` of `model`'s structure, written under `dir`;
    /// errors name the file under `root`.
    pub fn displacements(root: &Path, dir: &Path) -> Self {
        Self::new(
            root,
            dir,
            |dir, solver, alpha, m, eq| write_displacements(dir, solver, alpha, &m.structure, eq),
            |dir, solver, alpha| result_path(dir, "displacements", solver, alpha),
        )
    }

    /// `forces/{solver}_alpha{α}.csv` of `model`, written under `dir`; errors name the file
    /// under `root`.
    pub fn forces(root: &Path, dir: &Path) -> Self {
        Self::new(root, dir, write_forces, |dir, solver, alpha| {
            result_path(dir, "forces", solver, alpha)
        })
    }

    /// `reactions/{solver}_alpha{α}.csv` of `model`, written under `dir`; errors name the
    /// file under `root`.
    pub fn reactions(root: &Path, dir: &Path) -> Self {
        Self::new(root, dir, write_reactions, |dir, solver, alpha| {
            result_path(dir, "reactions", solver, alpha)
        })
    }

    /// `vtk/{solver}_alpha{α}.vtu` of `model`'s structure, written under `dir`; errors name
    /// the file under `root`.
    pub fn vtk(root: &Path, dir: &Path) -> Self {
        Self::new(
            root,
            dir,
            |dir, solver, alpha, m, eq| write_vtu(dir, solver, alpha, &m.structure, eq),
            vtu_path,
        )
    }

    fn new(
        root: &Path,
        dir: &Path,
        write: WriteSolve,
        error_path: fn(&Path, &str, f64) -> PathBuf,
    ) -> Self {
        PerSolveSink {
            root: root.to_path_buf(),
            dir: dir.to_path_buf(),
            write,
            error_path,
        }
    }
}

impl Sink for PerSolveSink {
    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let SolveEnd::Solved {
            solution, model, ..
        } = end
        else {
            return Ok(());
        };
        (self.write)(
            &self.dir,
            key.method.name(),
            key.alpha,
            model,
            &solution.equilibrium,
        )
        .map(|_| ())
        .map_err(WriteError::at((self.error_path)(
            &self.root,
            key.method.name(),
            key.alpha,
        )))
    }
}

/// `plots/*.svg`: gathers what the figures need along the sweep (the convergence figures from
/// the iteration records of the solvers whose stopping measure is η) and draws them at its end.
pub struct PlotsSink<'s> {
    root: PathBuf,
    dir: PathBuf,
    structure: &'s Structure,
    figures: FigureData,
    /// Records of the current solve, when its convergence is drawn.
    records: Option<Vec<IterationRecord>>,
}

impl<'s> PlotsSink<'s> {
    /// Figures of `structure` written under `dir/plots` (the staging directory); Figures 6
    /// and 8 show `first_solver`; errors name `root/plots`.
    pub fn new(
        root: &Path,
        dir: &Path,
        structure: &'s Structure,
        first_solver: Method,
        settings: FigureSettings,
    ) -> Self {
        PlotsSink {
            root: root.to_path_buf(),
            dir: dir.to_path_buf(),
            structure,
            figures: FigureData::new(first_solver, settings),
            records: None,
        }
    }
}

impl Sink for PlotsSink<'_> {
    fn start(&mut self, key: &SolveKey) -> Result<(), WriteError> {
        self.records = key.method.reports_error().then(Vec::new);
        Ok(())
    }

    fn iteration(&mut self, record: &IterationRecord) {
        if let Some(records) = self.records.as_mut() {
            records.push(*record);
        }
    }

    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let records = self.records.take();
        if let SolveEnd::Solved { solution, .. } = end {
            self.figures
                .add_solve(key.method, key.alpha, self.structure, &solution.equilibrium);
            if let Some(records) = records {
                self.figures.add_history(key.method, key.alpha, records);
            }
        }
        Ok(())
    }

    fn close(&mut self) -> Result<(), WriteError> {
        self.figures
            .write(&self.dir, self.structure)
            .map(|_| ())
            .map_err(WriteError::at(self.root.join("plots")))
    }
}

/// The commit point of a solve: publishes every file the sinks before it staged (and, at the
/// end of the sweep, the figures); a solve without a finite answer is discarded unseen.
pub struct PublishSink<'s> {
    out: &'s RefCell<OutputDir>,
}

impl<'s> PublishSink<'s> {
    /// Publishes into `out`.
    pub fn new(out: &'s RefCell<OutputDir>) -> Self {
        PublishSink { out }
    }

    fn publish(&self) -> Result<(), WriteError> {
        let mut out = self.out.borrow_mut();
        out.commit()
    }
}

impl Sink for PublishSink<'_> {
    fn end(&mut self, _key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        match end {
            SolveEnd::Solved { .. } | SolveEnd::NoAnswer { .. } => self.publish(),
            SolveEnd::NonFinite => {
                let mut out = self.out.borrow_mut();
                let root = out.root().to_path_buf();
                out.discard().map_err(WriteError::at(root))
            }
        }
    }

    fn close(&mut self) -> Result<(), WriteError> {
        self.publish()
    }
}

/// `stability.csv`: the smallest tangent eigenvalue of every solution, one row appended per
/// solve.
pub struct StabilitySink<'s> {
    out: &'s RefCell<OutputDir>,
    taut: &'s TautStiffness,
}

impl<'s> StabilitySink<'s> {
    /// `stability.csv` in `out`; the eigenvalues reuse the symbolic factorization of `taut`.
    pub fn new(out: &'s RefCell<OutputDir>, taut: &'s TautStiffness) -> Self {
        StabilitySink { out, taut }
    }
}

impl Sink for StabilitySink<'_> {
    fn end(&mut self, _key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let SolveEnd::Solved {
            solution,
            row,
            model,
            ..
        } = end
        else {
            return Ok(());
        };
        let row = StabilityRow {
            solver: row.solver.clone(),
            alpha: row.alpha,
            slack_cables: row.slack_cables,
            min_tangent_eigenvalue: row.min_tangent_eigenvalue.unwrap_or_else(|| {
                results::smallest_tangent_eigenvalue(model, &solution.equilibrium, self.taut)
            }),
        };
        append(
            self.out,
            "stability.csv",
            STABILITY_HEADER,
            &stability_line(&row),
        )
    }
}

/// `reaction_totals.csv`: the sums of a solve's reactions per axis, one row appended per solve
/// with an answer (the reactions' own table, `reactions/…`, holds one row per held component).
pub struct ReactionTotalsSink<'s> {
    out: &'s RefCell<OutputDir>,
}

impl<'s> ReactionTotalsSink<'s> {
    /// `reaction_totals.csv` in `out`, of each solve's reactions under its model.
    pub fn new(out: &'s RefCell<OutputDir>) -> Self {
        ReactionTotalsSink { out }
    }
}

impl Sink for ReactionTotalsSink<'_> {
    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let SolveEnd::Solved {
            solution, model, ..
        } = end
        else {
            return Ok(());
        };
        let name = "reaction_totals.csv";
        let totals = reaction_totals(model, &solution.equilibrium, key.alpha)
            .map_err(|e| withdrawn(self.out, name, e))?;
        let line = reaction_totals_line(key.method.name(), key.alpha, totals);
        append(self.out, name, REACTION_TOTALS_HEADER, &line)
    }
}

/// `summary.csv`, one row appended after every solve, once its files are published: the row
/// says the solve is complete. A row is one write, so the file always ends with a whole row.
pub struct SummarySink<'s> {
    out: &'s RefCell<OutputDir>,
    /// The case checks members: the rows end with [`SUMMARY_CHECK_COLUMNS`].
    checks: bool,
}

impl<'s> SummarySink<'s> {
    /// `summary.csv` in `out`, with the member checks' columns when `checks`.
    pub fn new(out: &'s RefCell<OutputDir>, checks: bool) -> Self {
        SummarySink { out, checks }
    }
}

impl Sink for SummarySink<'_> {
    fn end(&mut self, _key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let (SolveEnd::Solved { row, .. } | SolveEnd::NoAnswer { row }) = end else {
            return Ok(());
        };
        match self.checks {
            false => append(self.out, "summary.csv", SUMMARY_HEADER, &summary_line(row)),
            true => append(
                self.out,
                "summary.csv",
                &format!("{SUMMARY_HEADER}{SUMMARY_CHECK_COLUMNS}"),
                &format!("{}{}", summary_line(row), summary_check_cells(row)),
            ),
        }
    }
}

/// Append `line` (one or more rows, one write) to the ledger `name` of `out`. When it cannot
/// be written, the solve's files and rows are withdrawn ([`OutputDir::withdraw`]).
pub(super) fn append(
    out: &RefCell<OutputDir>,
    name: &str,
    header: &str,
    line: &str,
) -> Result<(), WriteError> {
    let appended = out.borrow_mut().append(name, header, line);
    appended.map_err(|e| withdrawn(out, name, e))
}

/// Withdraw the current solve from `out` after `source` kept its ledger `name` from being
/// written; the error names that ledger.
fn withdrawn(out: &RefCell<OutputDir>, name: &str, source: io::Error) -> WriteError {
    let mut out = out.borrow_mut();
    out.withdraw();
    WriteError {
        path: out.root().join(name),
        source,
    }
}

/// Every sink of a sweep behind one: the solve's observer and its ending, in order.
#[derive(Default)]
pub struct Sinks<'s> {
    sinks: Vec<Box<dyn Sink + 's>>,
}

impl<'s> Sinks<'s> {
    /// Add `sink` when `wanted`.
    pub fn add(&mut self, wanted: bool, sink: impl Sink + 's) {
        if wanted {
            self.sinks.push(Box::new(sink));
        }
    }

    /// Whether any file is written.
    pub fn is_empty(&self) -> bool {
        self.sinks.is_empty()
    }
}

impl Sink for Sinks<'_> {
    fn start(&mut self, key: &SolveKey) -> Result<(), WriteError> {
        self.sinks.iter_mut().try_for_each(|s| s.start(key))
    }

    fn iteration(&mut self, record: &IterationRecord) {
        self.sinks.iter_mut().for_each(|s| s.iteration(record));
    }

    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        self.sinks.iter_mut().try_for_each(|s| s.end(key, end))
    }

    fn close(&mut self) -> Result<(), WriteError> {
        self.sinks.iter_mut().try_for_each(|s| s.close())
    }
}

/// The sinks as the observer of a solve.
impl crate::solvers::Observer for Sinks<'_> {
    fn iteration(&mut self, record: &IterationRecord) {
        Sink::iteration(self, record);
    }
}
