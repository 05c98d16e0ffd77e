//! Solvers. Each one is set up once per structure ([`SetupError`] when it cannot be) and is a
//! state machine (`Solver`) that the one `driver` runs for any load; it reports what
//! happened in a [`SolveInfo`] and never prints. Observers (CSV writers, progress bars, the
//! bench recorder) are attached from outside through [`Observer`].

pub mod arc_length;
mod driver;
pub mod large;
pub mod latin;
mod load_path;
mod method;
pub mod newton;
mod observer;
pub mod pcg_lcp;
mod solution;
mod solver;
mod status;

pub use driver::{drive, drive_from, AnySolver};
pub use load_path::{
    LoadPath, PathPoint, PathSolver, PathState, PathWork, GROWTH_STEPS, INCREMENT_MAX_STEPS,
    LIMIT_TOLERANCE, SMALLEST_INCREMENT,
};
pub use method::{Method, Settings};
pub use observer::{IterationRecord, Observer, Recorder, Silent, Tee};
pub use solution::Solution;
pub use solver::{
    residual_stop, stop_when, Balance, BalanceTolerances, Progress, Solver, PRESTRESS_ROUND_OFF,
};
pub use status::{LoadPathEnd, Measure, SolveInfo, Status};
// The analyses the solvers set up on and answer with, where their users have found them.
pub use crate::analysis::{
    check_shape, mechanism_by_substructures, no_equilibrium, no_equilibrium_along,
    no_equilibrium_of_answer, no_equilibrium_of_slack_set, unit_direction, Equilibrium, LinksAlong,
    ModeRow, NoEquilibrium, Reference, SetupError, SubstructuredVerdict, TautStiffness,
    UnitDirection, CHECK_MODULES,
};
