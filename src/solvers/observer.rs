//! Observers: what sees a solve from outside. The driver hands every iterate's
//! [`IterationRecord`] to an [`Observer`]; CSV writers, figure recorders, progress bars and the
//! bench are observers; [`Recorder`] keeps every record for whoever reads them after the solve.

/// One iterate as seen from outside the solver.
#[derive(Debug, Clone, Copy)]
pub struct IterationRecord {
    /// Iterations done to reach it.
    pub iteration: usize,
    /// The solver's stopping measure (η for the LATIN solvers; see [`super::Measure`]).
    pub stopping_value: f64,
    /// r(U) of the iterate, when the solver has it (see [`super::Progress`]).
    pub equilibrium_residual: Option<f64>,
    /// Operator rebuilds so far in this solve.
    pub rebuilds: usize,
    /// Energy error e against a reference solution, when the solve was given one.
    pub error: Option<f64>,
    /// Slack cables of the iterate.
    pub slack_cables: usize,
    /// Time the solver had spent when it reached the iterate (observers excluded), s.
    pub elapsed_seconds: f64,
}

/// Attached to a solve from outside; the driver calls it once per iterate.
pub trait Observer {
    /// An iterate was reached.
    fn iteration(&mut self, record: &IterationRecord);
}

/// An observer that does nothing.
pub struct Silent;

impl Observer for Silent {
    fn iteration(&mut self, _: &IterationRecord) {}
}

/// Keeps every iterate's record of a solve, in order: what a figure, a bench series or a test
/// reads once the solve is done.
#[derive(Debug, Clone, Default)]
pub struct Recorder {
    /// The records, one per iterate reported.
    pub records: Vec<IterationRecord>,
}

impl Observer for Recorder {
    fn iteration(&mut self, record: &IterationRecord) {
        self.records.push(*record);
    }
}

/// Passes every record to each of its observers, in order.
#[derive(Default)]
pub struct Tee<'a> {
    observers: Vec<&'a mut dyn Observer>,
}

impl<'a> Tee<'a> {
    /// No observer yet.
    pub fn new() -> Self {
        Tee {
            observers: Vec::new(),
        }
    }

    /// Add `observer` when there is one.
    pub fn with(mut self, observer: Option<&'a mut dyn Observer>) -> Self {
        self.observers.extend(observer);
        self
    }
}

impl Observer for Tee<'_> {
    fn iteration(&mut self, record: &IterationRecord) {
        for observer in self.observers.iter_mut() {
            observer.iteration(record);
        }
    }
}
