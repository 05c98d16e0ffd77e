//! From a case to solvers: the structure and its mechanism check built once and timed, the one
//! place where `[solver]` keys become each solver's settings, and a solver of any method set up
//! for a structure, behind one `solve`.

use crate::case::{Case, Method};
use crate::solvers::latin::{Latin, LatinSettings, SearchDirection};
use crate::solvers::newton::{Newton, NewtonSettings};
use crate::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use crate::solvers::{Observer, SetupError, Solution, TautStiffness};
use crate::structure::Structure;
use std::time::Instant;

/// The structure and its taut stiffness (the mechanism check), built once and timed.
pub struct Prepared {
    pub structure: Structure,
    pub taut: TautStiffness,
    pub structure_seconds: f64,
    pub taut_seconds: f64,
}

impl Prepared {
    /// Set-up time a solver shares with the others: the structure, and for newton and pcg-lcp
    /// the factorization of the taut stiffness they solve with (the LATIN solvers never use it).
    pub fn shared_setup_seconds(&self, method: Method) -> f64 {
        if method.is_latin() {
            self.structure_seconds
        } else {
            self.structure_seconds + self.taut_seconds
        }
    }
}

/// Build the structure and refuse a mechanism.
pub fn prepare(case: &Case) -> Result<Prepared, SetupError> {
    let clock = Instant::now();
    let structure = Structure::from_case(case);
    let structure_seconds = clock.elapsed().as_secs_f64();
    let taut = TautStiffness::new(&structure)?;
    Ok(Prepared {
        structure,
        taut,
        structure_seconds,
        taut_seconds: clock.elapsed().as_secs_f64() - structure_seconds,
    })
}

/// Stopping settings; `None` keeps the solver's own default.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    pub tolerance: Option<f64>,
    pub max_iterations: Option<usize>,
}

impl Limits {
    /// `solver.tolerance` and `solver.max_iterations` of the case.
    pub fn of_case(case: &Case) -> Limits {
        Limits {
            tolerance: case.solver.tolerance,
            max_iterations: case.solver.max_iterations,
        }
    }

    /// Whether the case changes any solver default.
    pub fn is_default(&self) -> bool {
        self.tolerance.is_none() && self.max_iterations.is_none()
    }

    fn apply(self, tolerance: &mut f64, max_iterations: &mut usize) {
        *tolerance = self.tolerance.unwrap_or(*tolerance);
        *max_iterations = self.max_iterations.unwrap_or(*max_iterations);
    }
}

/// The LATIN settings the case asks for: `mono-latin` is the 1 × 1 partition.
pub fn latin_settings(case: &Case, method: Method) -> LatinSettings {
    LatinSettings {
        subdomains: if method == Method::MonoLatin {
            [1, 1]
        } else {
            case.solver.partition()
        },
        dm: case.solver.dm,
        search: case.solver.search.unwrap_or(SearchDirection::Stiffness),
        weak: case.solver.weak_interfaces,
        ..LatinSettings::default()
    }
}

/// A solver of any method, set up for a structure.
pub enum ConfiguredSolver<'s> {
    Newton(Newton<'s>),
    PcgLcp(PcgLcp<'s>),
    Latin(Box<Latin<'s>>),
}

impl<'s> ConfiguredSolver<'s> {
    pub fn new(
        method: Method,
        case: &Case,
        structure: &'s Structure,
        taut: &'s TautStiffness,
        limits: Limits,
    ) -> Result<ConfiguredSolver<'s>, SetupError> {
        Ok(match method {
            Method::Newton => {
                let mut settings = NewtonSettings::default();
                limits.apply(&mut settings.tolerance, &mut settings.max_iterations);
                ConfiguredSolver::Newton(Newton::new(structure, taut, settings)?)
            }
            Method::PcgLcp => {
                let mut settings = PcgLcpSettings::default();
                limits.apply(&mut settings.tolerance, &mut settings.max_iterations);
                ConfiguredSolver::PcgLcp(PcgLcp::new(structure, taut, settings))
            }
            Method::MonoLatin | Method::MicroMacro => {
                let mut settings = latin_settings(case, method);
                limits.apply(&mut settings.tolerance, &mut settings.max_iterations);
                ConfiguredSolver::Latin(Box::new(Latin::new(structure, settings)?))
            }
        })
    }

    /// `reference` (free-dof displacements) is used by the LATIN solvers to report e.
    pub fn solve(
        &mut self,
        load: &[f64],
        reference: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Solution {
        match self {
            ConfiguredSolver::Newton(s) => s.solve(load, None, observer),
            ConfiguredSolver::PcgLcp(s) => s.solve(load, observer),
            ConfiguredSolver::Latin(s) => s.solve(load, reference, observer),
        }
    }
}
