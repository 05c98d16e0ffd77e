//! Setting solvers up for a case: the structure and its mechanism check built once and timed,
//! then each solver asked for, with the set-up time it is charged.

use crate::case::{Case, SolverChoice};
use crate::decomposition::{Exchange, Homogenised, OneProcess};
use crate::model::{GeometricModel, Model};
use crate::results::uniqueness;
use crate::solvers::arc_length::{ArcLength, PathFollowing};
use crate::solvers::large::{Large, LargeNewton, LinearisedStep};
use crate::solvers::latin::{Latin, LatinSettings, LinkShare};
use crate::solvers::newton::{LinearSolve, Newton};
use crate::solvers::pcg_lcp::PcgLcp;
use crate::solvers::{
    check_shape, mechanism_by_substructures, AnySolver, LoadPath, Method, PathSolver, Settings,
    SetupError, SubstructuredVerdict, TautStiffness,
};
use crate::structure::Structure;
use std::time::Instant;

/// The structure and its taut stiffness (the mechanism check), built once and timed.
pub struct Prepared {
    /// The model of the case: its structure under its geometric model.
    pub model: Model,
    /// Its stiffness with every cable taut, factorized; `None` once released
    /// ([`Prepared::release_taut`]).
    pub taut: Option<TautStiffness>,
    /// Time to build the structure, s.
    pub structure_seconds: f64,
    /// Time to assemble and factorize the taut stiffness and check for a mechanism, s.
    pub taut_seconds: f64,
    /// On an MPI rank that keeps only its micro-macro substructures' links
    /// ([`Prepared::keep_links_of`]): the rest of its share; `model` then holds those links
    /// alone.
    pub share: Option<LinkShare>,
    /// Where a construction stage's load path starts ([`Case::start`]), on the free dofs: the
    /// load and the displacements.
    pub start: Option<(Vec<f64>, Vec<f64>)>,
}

/// Build the structure of `case` and refuse a mechanism, keeping the factor of K with every
/// cable taut.
pub fn prepare(case: &Case) -> Result<Prepared, SetupError> {
    prepare_keeping(case, true)
}

/// [`prepare`], keeping K's factor only when `keeps_taut`: without it, a grid under the linear
/// model is checked substructure by substructure ([`checks_by_substructures`]) and K is never
/// factorized whole, unless a substructure has a mechanism of its own.
pub fn prepare_keeping(case: &Case, keeps_taut: bool) -> Result<Prepared, SetupError> {
    let mut prepared = Prepared::unchecked(case);
    let clock = Instant::now();
    let model = &prepared.model;
    prepared.taut = match zero_modes_by_substructures(case, &model.structure, keeps_taut) {
        Some(0) => None,
        Some(modes) => return Err(TautStiffness::refusal(model, modes)),
        None => Some(TautStiffness::new(model)?),
    };
    prepared.taut_seconds = clock.elapsed().as_secs_f64();
    Ok(prepared)
}

/// Whether the mechanism check of `case` is made substructure by substructure: a grid under the
/// linear model (K is `Bᵀ k B`) whose run does not keep K's factor
/// ([`crate::app::memory::Workload::keeps_taut`]).
pub fn checks_by_substructures(case: &Case, keeps_taut: bool) -> bool {
    !keeps_taut && case.grid.is_some() && !case.model.has_geometric_stiffness()
}

/// The zero-stiffness modes of K with every cable taut (rigid motions included), counted
/// substructure by substructure when the run of `case` checks that way
/// ([`checks_by_substructures`]); `None` when K must be factorized whole instead (another
/// check, or a substructure with more mechanisms of its own than the check counts).
pub fn zero_modes_by_substructures(
    case: &Case,
    structure: &Structure,
    keeps_taut: bool,
) -> Option<usize> {
    let layout = structure.layout.as_ref()?;
    if !checks_by_substructures(case, keeps_taut) {
        return None;
    }
    match mechanism_by_substructures(structure, check_shape(layout.nx, layout.ny)) {
        SubstructuredVerdict::Regular => Some(0),
        SubstructuredVerdict::Mechanism(modes) => Some(modes),
        SubstructuredVerdict::Undecided(_) => None,
    }
}

/// The checks of every answer that solve with the factor of K with every cable taut, each made
/// only when the case asks for what it gives.
#[derive(Debug, Clone, Copy)]
pub struct AnswerChecks {
    /// The smallest tangent eigenvalue (the models with geometric stiffness, and
    /// `output.stability`).
    pub eigenvalue: bool,
    /// The geometric term a model on the initial geometry leaves out (`output.geometric_term`;
    /// none with `large`, which leaves nothing out).
    pub geometric_term: bool,
    /// Above this geometric term the model is off (`model.tolerance`).
    pub model_tolerance: f64,
}

impl AnswerChecks {
    /// The checks `case` asks for.
    pub fn of(case: &Case) -> AnswerChecks {
        AnswerChecks {
            eigenvalue: case.model.has_geometric_stiffness() || case.output.stability,
            geometric_term: case.output.geometric_term && !case.model.updates_geometry(),
            model_tolerance: case.model_tolerance,
        }
    }

    /// Whether any check is made.
    pub fn any(self) -> bool {
        self.eigenvalue || self.geometric_term
    }
}

impl Prepared {
    /// Whether the converged answer `eq` is the only equilibrium
    /// ([`crate::results::uniqueness::uniqueness`]), on K's pattern and analysis when the run
    /// keeps them (up to [`uniqueness::CHECKED_UP_TO_DOFS`] free dofs, or at any size where
    /// the run factorizes a tangent per row anyway: `factorizes_anyway`), else on its own
    /// analysis (up to [`uniqueness::OWN_ANALYSIS_UP_TO_DOFS`]); `None` (not checked) beyond,
    /// and where the ranks keep shares of the links.
    pub fn checked_uniqueness(
        &self,
        eq: &crate::solvers::Equilibrium,
        load: &[f64],
        factorizes_anyway: bool,
    ) -> Option<uniqueness::Uniqueness> {
        let (model, n_free) = (&self.model, self.model.structure.n_free);
        match &self.taut {
            _ if self.share.is_some() => None,
            Some(taut) if n_free <= uniqueness::CHECKED_UP_TO_DOFS || factorizes_anyway => Some(
                uniqueness::uniqueness(model, eq, load, &taut.pattern, &taut.factor),
            ),
            None if n_free <= uniqueness::OWN_ANALYSIS_UP_TO_DOFS => {
                let (pattern, analysed) = TautStiffness::analyse(&model.structure);
                Some(uniqueness::uniqueness(model, eq, load, &pattern, &analysed))
            }
            _ => None,
        }
    }

    /// The model of `case` without its mechanism check: for an MPI rank whose run never
    /// solves with K's factor, which takes rank 0's check instead of factorizing K itself.
    pub fn unchecked(case: &Case) -> Prepared {
        let clock = Instant::now();
        let model = case.model();
        let start = case.start.as_ref().map(|start| {
            let on_free = |per_node: &[[f64; 3]]| {
                let mut free = vec![0.0; model.structure.n_free];
                for (global, &d) in model.structure.dof_of.iter().enumerate() {
                    if d != crate::structure::CLAMPED {
                        free[d] = per_node[global / 3][global % 3];
                    }
                }
                free
            };
            (on_free(&start.load), on_free(&start.displacements))
        });
        Prepared {
            model,
            taut: None,
            structure_seconds: clock.elapsed().as_secs_f64(),
            taut_seconds: 0.0,
            share: None,
            start,
        }
    }

    /// Keep only the links of the micro-macro substructures rank `rank` of `ranks` holds under
    /// `settings` (issue 25), when the solve can run on such shares
    /// ([`LinkShare::possible`]); the whole model is dropped. Whether it did.
    pub fn keep_links_of(
        &mut self,
        settings: &LatinSettings,
        rank: usize,
        ranks: usize,
    ) -> Result<bool, SetupError> {
        let clock = Instant::now();
        let Some((kept, share)) = LinkShare::new(&self.model, settings, rank, ranks)? else {
            return Ok(false);
        };
        self.model = kept;
        self.share = Some(share);
        self.structure_seconds += clock.elapsed().as_secs_f64();
        Ok(true)
    }

    /// The same structure under `geometry`, its stiffness with every cable taut factorized
    /// anew (`K + K_G(t0)` for the models with geometric stiffness): `auto`'s move to `large`.
    pub fn under(&self, geometry: GeometricModel) -> Result<Prepared, SetupError> {
        let clock = Instant::now();
        let model = Model::new(self.model.structure.clone(), geometry);
        let taut = TautStiffness::new(&model)?;
        Ok(Prepared {
            model,
            taut: Some(taut),
            structure_seconds: self.structure_seconds,
            taut_seconds: clock.elapsed().as_secs_f64(),
            share: None,
            start: self.start.clone(),
        })
    }

    /// Drop the factor of K with every cable taut once the mechanism check is done, for a run
    /// that never solves with it ([`crate::app::memory::Workload::keeps_taut`]): it is as large
    /// as a solver's factor, and the LATIN solvers never use it.
    pub fn release_taut(&mut self) {
        self.taut = None;
    }
}

/// A solver as the application holds it: solved through the driver ([`AnySolver`]), and
/// asked for the set-up products a run writes besides its solves.
pub trait HeldSolver: AnySolver {
    /// The homogenised substructure operators (`output.homogenised`) of the LATIN solvers;
    /// none for the others.
    fn homogenised(&mut self) -> Vec<Homogenised> {
        Vec::new()
    }
}

impl HeldSolver for Newton<'_> {}
impl HeldSolver for ArcLength<'_> {}
impl<S: PathSolver> HeldSolver for LoadPath<S> {}
impl HeldSolver for PcgLcp<'_> {}

impl HeldSolver for Latin<'_> {
    fn homogenised(&mut self) -> Vec<Homogenised> {
        Latin::homogenised(self)
    }
}

/// A solver set up for the prepared model.
pub struct SetUpSolver<'s> {
    /// Which solver.
    pub method: Method,
    /// The solver.
    pub solver: Box<dyn HeldSolver + 's>,
    /// Its set-up time, s: the structure, plus for `newton` and `pcg-lcp` the factorization of
    /// the taut stiffness they solve with (the LATIN solvers never use it), plus its own.
    pub setup_seconds: f64,
}

/// Set `method` up with the settings of `choice`.
pub fn set_up<'s>(
    method: Method,
    choice: &SolverChoice,
    prepared: &'s Prepared,
) -> Result<SetUpSolver<'s>, SetupError> {
    set_up_on(method, choice, prepared, &OneProcess)
}

/// [`set_up`] on the processes of `exchange`: micro-macro shares its substructures among them
/// ([`Latin::on_ranks`]); every other solver is set up whole on each.
pub fn set_up_on<'s>(
    method: Method,
    choice: &SolverChoice,
    prepared: &'s Prepared,
    exchange: &'s dyn Exchange,
) -> Result<SetUpSolver<'s>, SetupError> {
    let model = &prepared.model;
    let taut = || {
        prepared.taut.as_ref().ok_or(SetupError::TautReleased {
            solver: method.name(),
        })
    };
    let clock = Instant::now();
    let (solver, shared): (Box<dyn HeldSolver + 's>, f64) = match choice.settings(method) {
        Settings::Newton(settings)
            if model.updates_geometry() && settings.path == PathFollowing::ArcLength =>
        {
            (
                Box::new(ArcLength::new(model, taut()?, settings.tolerance)),
                prepared.taut_seconds,
            )
        }
        Settings::Newton(settings) if model.updates_geometry() => {
            let newton = LargeNewton::new(model, taut()?, settings);
            let path = match prepared.start.clone() {
                Some((load, u)) => LoadPath::starting_at(newton, load, u),
                None => LoadPath::new(newton),
            };
            (Box::new(path), prepared.taut_seconds)
        }
        Settings::Newton(settings) => match prepared.taut.as_ref() {
            // A run that never factorises K whole (its mechanism check by substructures).
            None if settings.linear == LinearSolve::Krylov => {
                (Box::new(Newton::substructured(model, settings)), 0.0)
            }
            _ => (
                Box::new(Newton::new(model, taut()?, settings)?),
                prepared.taut_seconds,
            ),
        },
        Settings::PcgLcp(settings) if model.updates_geometry() => {
            let step = LinearisedStep::pcg_lcp(settings);
            (large_path(model, step), 0.0)
        }
        Settings::MonoLatin(settings) | Settings::MicroMacro(settings)
            if model.updates_geometry() =>
        {
            (
                large_path(model, LinearisedStep::latin(model, settings, exchange)?),
                0.0,
            )
        }
        Settings::PcgLcp(settings) => (
            Box::new(PcgLcp::new(model, taut()?, settings)),
            prepared.taut_seconds,
        ),
        Settings::MonoLatin(settings) => (Box::new(Latin::new(model, settings)?), 0.0),
        Settings::MicroMacro(settings) => match &prepared.share {
            Some(share) => (
                Box::new(Latin::on_share(model, share, settings, exchange)?),
                0.0,
            ),
            None => (Box::new(Latin::on_ranks(model, settings, exchange)?), 0.0),
        },
    };
    Ok(SetUpSolver {
        method,
        solver,
        setup_seconds: prepared.structure_seconds + shared + clock.elapsed().as_secs_f64(),
    })
}

/// pcg-lcp, mono-latin or micro-macro on the `large` model, along the load path
/// ([`Large::linearised`]).
fn large_path<'s>(model: &'s Model, step: LinearisedStep<'s>) -> Box<dyn HeldSolver + 's> {
    Box::new(LoadPath::new(Large::linearised(model, step)))
}
