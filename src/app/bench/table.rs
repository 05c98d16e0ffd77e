//! The table `bench` prints: per solver and α, the wall time (set-up included) of the first
//! iterate below each error level.

use super::Series;
use crate::output::alpha_label;
use std::fmt;

/// The error levels of the table.
pub const THRESHOLDS: [f64; 5] = [1e-2, 1e-3, 1e-4, 1e-6, 1e-8];

/// One row of the table: a solver at one α.
#[derive(Debug, Clone)]
pub struct TableRow {
    /// Solver name.
    pub solver: &'static str,
    /// Load factor.
    pub alpha: f64,
    /// Per [`THRESHOLDS`] entry: the wall time to reach it, set-up included.
    pub seconds_to_reach: [Option<f64>; THRESHOLDS.len()],
    /// e of the last iterate.
    pub final_error: Option<f64>,
    /// The solver met its stopping criterion.
    pub converged: bool,
}

/// Time to reach each error level, per solver and α.
#[derive(Debug, Clone)]
pub struct Table {
    /// One row per solver and α.
    pub rows: Vec<TableRow>,
}

impl Table {
    /// The table of `series`.
    pub fn new(series: &[Series]) -> Table {
        let rows = series
            .iter()
            .map(|s| TableRow {
                solver: s.method.name(),
                alpha: s.alpha,
                seconds_to_reach: THRESHOLDS.map(|t| s.seconds_to_reach(t)),
                final_error: s.final_error(),
                converged: s.status.converged(),
            })
            .collect();
        Table { rows }
    }
}

/// `12.3 ms`, `1.23 s`.
fn format_seconds(seconds: f64) -> String {
    let ms = 1e3 * seconds;
    if ms < 10.0 {
        format!("{ms:.2} ms")
    } else if ms < 1e3 {
        format!("{ms:.1} ms")
    } else {
        format!("{seconds:.2} s")
    }
}

impl fmt::Display for Table {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "wall time to reach e <= threshold, set-up included (— never reached)"
        )?;
        write!(f, "{:<12} {:>6}", "solver", "alpha")?;
        for t in THRESHOLDS {
            write!(f, " {:>10}", format!("e<={t:e}"))?;
        }
        writeln!(f, " {:>9}", "final e")?;
        for row in &self.rows {
            write!(f, "{:<12} {:>6}", row.solver, alpha_label(row.alpha))?;
            for seconds in row.seconds_to_reach {
                let cell = seconds.map(format_seconds).unwrap_or_else(|| "—".into());
                write!(f, " {cell:>10}")?;
            }
            let last = row.final_error.map(|e| format!("{e:.1e}"));
            write!(f, " {:>9}", last.unwrap_or_else(|| "—".into()))?;
            writeln!(
                f,
                "{}",
                if row.converged {
                    ""
                } else {
                    "  (not converged)"
                }
            )?;
        }
        Ok(())
    }
}
