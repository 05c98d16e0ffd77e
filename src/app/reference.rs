//! Where the energy error e of the LATIN solvers is measured from (`solver.reference`): a
//! solver of the case at its default settings when there is one (its own solves serve), else
//! a solver of its own at its default (tight) settings.

use super::setup::{set_up, Prepared, SetUpSolver};
use crate::case::Case;
use crate::solvers::{Equilibrium, SetupError, Silent, Solution};

/// Where the reference of the LATIN error comes from.
pub enum ReferenceSource<'s> {
    /// No solver reports e (none stops on η), or `solver.reference = "none"`.
    Unneeded,
    /// A solver of the case at its default settings: its own solution serves.
    Shared(usize),
    /// A solver of its own, with the solver's default (tight) settings.
    Own(SetUpSolver<'s>),
}

impl<'s> ReferenceSource<'s> {
    /// The reference policy of `case` (`solver.reference`) for `solvers`: none when no solver
    /// reports e; the case's own solver when it runs at its default settings; else one of its own.
    pub fn new(
        case: &Case,
        solvers: &[SetUpSolver<'_>],
        prepared: &'s Prepared,
    ) -> Result<Self, SetupError> {
        let reports_error = solvers.iter().any(|s| s.method.reports_error());
        let Some(method) = case.solver.reference.method().filter(|_| reports_error) else {
            return Ok(ReferenceSource::Unneeded);
        };
        let shared = solvers
            .iter()
            .position(|s| s.method == method && case.solver.is_default(method));
        Ok(match shared {
            Some(i) => ReferenceSource::Shared(i),
            None => ReferenceSource::Own(set_up(method, &Default::default(), prepared)?),
        })
    }

    /// The reference solution at `load`, if one is needed; a shared solver starts from its
    /// `previous` answer.
    pub fn solve(
        &mut self,
        load: &[f64],
        solvers: &mut [SetUpSolver<'_>],
        previous: &[Option<Equilibrium>],
    ) -> Option<Solution> {
        match self {
            ReferenceSource::Unneeded => None,
            ReferenceSource::Shared(i) => Some(solvers[*i].solver.solve_from(
                load,
                previous[*i].as_ref(),
                None,
                &mut Silent,
            )),
            ReferenceSource::Own(own) => Some(own.solver.solve(load, None, &mut Silent)),
        }
    }

    /// Whether a reference solve runs at each α.
    pub fn needed(&self) -> bool {
        !matches!(self, ReferenceSource::Unneeded)
    }

    /// The solver whose own solve is the reference.
    pub fn shared_index(&self) -> Option<usize> {
        match self {
            ReferenceSource::Shared(i) => Some(*i),
            _ => None,
        }
    }
}
