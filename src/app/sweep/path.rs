//! Where each solver's load path stands along the sweep (`large`, whose solves each start from
//! the solver's last equilibrium), and the summary columns that say so.

use crate::output::SummaryRow;
use crate::solvers::{Solution, Status};

/// Where a solver's load path stands in the sweep (`large`, whose solves each start from the
/// solver's last equilibrium).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PathStart {
    /// The α of the solver's last equilibrium reached at a row's load (0: the prestressed
    /// state).
    alpha: f64,
    /// The α of the solver's previous row, when there was one.
    previous_row: Option<f64>,
}

/// A solve's load path in the sweep: where it started, how far it went, and whether it
/// started elsewhere than at the solver's previous row.
#[derive(Debug, Clone, Copy)]
pub(super) struct FollowedPath {
    from: f64,
    reached: f64,
    restarted: bool,
    /// The limit load located: arc length's highest limit point passed, or where load
    /// control stopped at one.
    limit: Option<f64>,
}

impl PathStart {
    /// The path of `solution`, the solve at `alpha`, and the start of the next one; `None`
    /// for a solver that follows no load path.
    pub(super) fn follow(&mut self, alpha: f64, solution: &Solution) -> Option<FollowedPath> {
        let end = solution.info.load_path.as_ref()?;
        let from = self.alpha;
        // The α at fraction `reached` of the path from `from` to `alpha`.
        let reached = from + end.reached * (alpha - from);
        let followed = FollowedPath {
            from,
            reached,
            restarted: self.previous_row.is_some_and(|row| row != from),
            limit: match solution.info.status {
                Status::LimitPoint => end.limit_alpha.or(Some(reached)),
                _ => end.limit_alpha,
            },
        };
        if solution.info.status.converged() {
            self.alpha = alpha;
        }
        self.previous_row = Some(alpha);
        Some(followed)
    }
}

impl SummaryRow {
    /// The row with its load path's columns.
    pub(super) fn on_path(mut self, path: Option<&FollowedPath>) -> SummaryRow {
        if let Some(path) = path {
            self.path_from = Some(path.from);
            self.path_reached = Some(path.reached);
            self.path_restarted = path.restarted;
            self.limit_alpha = path.limit;
        }
        self
    }
}
