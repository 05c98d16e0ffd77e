//! Observers that the run attaches to a solve: [`Recorder`] keeps every iteration record (the
//! convergence figures are drawn from them), [`Tee`] hands each record to several observers so
//! that one solve feeds both the history file and the figures.

use crate::solvers::{IterationRecord, Observer};

/// Keeps every record it is shown, in order.
#[derive(Debug, Default, Clone)]
pub struct Recorder {
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
