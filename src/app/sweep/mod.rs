//! `tensolve run`: one case, end to end. Build the structure, set the asked solvers up once,
//! solve every α, hand every solve to the sinks the case asks for; nothing else.

mod error;
mod figure12;
mod files;
mod models;
mod path;
mod sharing;
mod verdict;

pub use error::RunError;
use error::{on_every_rank, Failures};
use files::{open_output, sinks, write_homogenised, write_mechanisms};
use models::Models;
use path::PathStart;
pub use sharing::Sharing;

use super::auto::against_large::ModelOffBy;
use super::auto::{prepare_start, RowModel};
use super::memory::{self, MemoryEstimate, Workload};
use super::reference::ReferenceSource;
use super::setup::{set_up_on, AnswerChecks, Prepared, SetUpSolver};
use crate::analysis::modes::ModalAnalysis;
use crate::case::Case;
use crate::decomposition::{Exchange, OneProcess};
use crate::output::{alpha_label, Sink, Sinks, SolveEnd, SolveKey, SummaryRow, WriteError};
use crate::results::{self, AnswerMeasures};
use crate::solvers::{
    Equilibrium, IterationRecord, Measure, Method, Observer, Reference, Solution, Tee,
};
use crate::structure::StructureSize;
use std::path::{Path, PathBuf};
use verdict::{assess, not_converged_message};

/// What the command line adds to a case.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Overrides `output.dir`.
    pub out_dir: Option<PathBuf>,
    /// Overrides `solver.methods`.
    pub methods: Option<Vec<Method>>,
}

/// The output directory: `--out`, else `output.dir`, else `out/case`.
pub fn output_dir(case: &Case, options: &RunOptions) -> PathBuf {
    options
        .out_dir
        .clone()
        .or_else(|| case.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out/case"))
}

/// What a run is doing, for a progress display: the run reports each as it happens and never
/// prints.
#[derive(Debug, Clone, Copy)]
pub enum RunEvent<'a> {
    /// A set-up step began (the structure, a solver's factorisations, a reference solve);
    /// it lasts until the next event.
    Stage(&'a str),
    /// A solve began.
    SolveStart {
        /// The solver's name.
        solver: &'a str,
        /// The load factor.
        alpha: f64,
    },
    /// An iterate of the solve in progress.
    Iteration {
        /// The solver's name.
        solver: &'a str,
        /// The load factor.
        alpha: f64,
        /// What `record.stopping_value` measures.
        measure: Measure,
        /// The iterate.
        record: &'a IterationRecord,
    },
    /// A solve ended and its summary row was written.
    Row(&'a SummaryRow),
    /// The rows on a model of the initial geometry off by more than `model.tolerance`: how
    /// many, the worst, and `large` measured at its α (sent once, after the last row).
    ModelOffBy(&'a ModelOffBy),
    /// A combination's (`combinations/<name>/`) own run begins.
    Combination(&'a str),
    /// A construction stage's (`stages/<name>/`) own run begins.
    Construction(&'a str),
    /// Set-up kept `kept` of the structure's `whole` links on this process (fewer on an MPI
    /// rank keeping only its micro-macro substructures' links).
    LinksKept {
        /// Links kept.
        kept: usize,
        /// Links of the whole structure.
        whole: usize,
    },
}

/// Passes every iterate of one solve to the run's events as [`RunEvent::Iteration`].
struct IterationEvents<'e> {
    events: &'e mut dyn FnMut(RunEvent<'_>),
    key: SolveKey,
}

impl Observer for IterationEvents<'_> {
    fn iteration(&mut self, record: &IterationRecord) {
        (self.events)(RunEvent::Iteration {
            solver: self.key.method.name(),
            alpha: self.key.alpha,
            measure: self.key.measure,
            record,
        });
    }
}

/// Run a validated case; `events` sees what it does ([`RunEvent`]), each row as written.
pub fn run(
    case: &Case,
    options: &RunOptions,
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<Vec<SummaryRow>, RunError> {
    run_on(case.clone(), options, &OneProcess, events)
}

/// [`run`] on the processes of `exchange` (MPI ranks: every one calls it alike): micro-macro's
/// substructures are shared among them ([`crate::decomposition::Exchange`]), the other
/// solvers run alike on each, and rank 0 alone writes files. It takes the case, whose members
/// it releases once the structure is built of them.
pub fn run_on(
    mut case: Case,
    options: &RunOptions,
    exchange: &dyn Exchange,
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<Vec<SummaryRow>, RunError> {
    let writes = exchange.rank() == 0;
    let described = &case;
    let dir = output_dir(described, options);
    let methods = methods(described, options)?;
    // 0. The memory the run needs, estimated before anything large is allocated.
    let work = Workload::run(described, &methods);
    let estimate = MemoryEstimate::new(StructureSize::of(&described.geometry), &work);
    on_every_rank(
        exchange,
        memory::ensure_fits(&estimate, "run").map_err(RunError::from),
    )?;
    // 1. The structure and its mechanism check (K with every cable taut, factorized; or, on a
    //    grid when nothing of the run solves with K, substructure by substructure); the
    //    factor released when nothing of the run solves with it. Such a run on MPI ranks has
    //    rank 0 alone make the check, and the others take its verdict: they never hold a
    //    factor of the whole structure.
    events(RunEvent::Stage(match work.taut_by_substructures {
        true => "building the structure and checking it for mechanisms by substructures",
        false => "building the structure and factorising its taut stiffness",
    }));
    //    Under `auto`, the model it starts with: `linear`, or `large` for a mechanism its
    //    prestress stiffens (which the case then says).
    let started = match writes || work.keeps_taut {
        true => prepare_or_locate_mechanisms(&mut case, &dir, writes, work.keeps_taut),
        false => Ok((Prepared::unchecked(&case), RowModel::pinned(case.model))),
    };
    let (mut prepared, start) = on_every_rank(exchange, started)?;
    if !work.keeps_taut {
        prepared.release_taut();
    }
    // The members are in the structure now: the case's own copy goes (1.2 GB of a 1024 × 1024
    // grid, on every rank).
    case.geometry.release_members();
    let case = &case;
    // 1b. On MPI ranks, only the links of the rank's own micro-macro substructures, when
    //     nothing else of the run needs the whole structure there ([`Sharing`]).
    let sharing = Sharing::of(case, &methods, work.keeps_taut, exchange.size());
    let keeps_share = match sharing {
        Sharing::Whole => false,
        Sharing::AllButRank0 => exchange.rank() > 0,
        Sharing::EveryRank => true,
    };
    let kept = match case.solver.latin_settings(Method::MicroMacro) {
        Some(settings) if keeps_share => prepared
            .keep_links_of(&settings, exchange.rank(), exchange.size())
            .map_err(RunError::from),
        _ => Ok(false),
    };
    on_every_rank(exchange, kept)?;
    events(RunEvent::LinksKept {
        kept: prepared.model.structure.links.len(),
        whole: prepared
            .share
            .as_ref()
            .map_or(prepared.model.structure.links.len(), |s| s.world_links()),
    });
    let prepared = prepared;
    // 2. Every solver asked for, set up once.
    let mut solvers = set_up_all(case, &methods, &prepared, exchange, events)?;
    // 3. Where LATIN's error e is measured from.
    events(RunEvent::Stage("setting up the reference solver"));
    let reference = ReferenceSource::new(case, &solvers, &prepared)?;
    // 4. The output directory, once the case is known solvable: locked for this run, with a
    //    private staging directory; then the sinks of the files asked for.
    let out = on_every_rank(exchange, open_output(case, &dir, writes))?;
    let sinks = sinks(case, &dir, out.as_ref(), &prepared, &solvers);
    // 5. The homogenised substructure operators, when asked (set-up products, written once).
    let homogenised = match out.as_ref().filter(|_| case.output.homogenised) {
        Some(out) => write_homogenised(&dir, out, &mut solvers, events),
        None => Ok(()),
    };
    on_every_rank(exchange, homogenised)?;
    // 6. Every α, every solver (steps 7–9 in `Sweep`); 10. the files of the whole sweep.
    // 6a. The model of each α's rows: the case's, or under `auto` chosen per α.
    let large = std::cell::OnceCell::new();
    let models = Models::new(case, &methods, start, &prepared, &large)?;
    let mut sweep = Sweep::new(
        models, &prepared, solvers, reference, sinks, exchange, sharing,
    );
    for &alpha in &case.load.alphas {
        sweep.solve_alpha(alpha, events)?;
    }
    let (rows, failures) = sweep.close()?;
    // 10b. What a pinned model on the initial geometry is off by at its worst row, measured
    //      with `large` there (small structures, one process), the run's solvers released.
    if let Some(off) = ModelOffBy::of(&rows, &prepared, exchange.size() == 1) {
        events(RunEvent::ModelOffBy(&off));
    }
    // 11. Figure 12: the LATIN solvers at the largest α on the grid of each module kind asked.
    let compare = case.output.plots && !case.output.compare_modules.is_empty();
    if let Some(out) = out.as_ref().filter(|_| compare) {
        events(RunEvent::Stage(
            "Figure 12: the LATIN solvers on each module of output.compare_modules",
        ));
        figure12::write(case, &methods, out, &dir)?;
    }
    // 12. The directory released; the run fails when a solve did.
    if let Some(out) = out {
        out.into_inner().finish().map_err(|source| WriteError {
            path: dir.clone(),
            source,
        })?;
    }
    match failures.is_empty() {
        true => Ok(rows),
        false => Err(RunError::not_converged(&failures)),
    }
}

/// The solvers of the run: `--solver`, else `solver.methods`, each named once.
fn methods(case: &Case, options: &RunOptions) -> Result<Vec<Method>, RunError> {
    let methods = (options.methods.clone()).unwrap_or_else(|| case.solver.methods.clone());
    crate::case::check_distinct_methods("--solver", &methods)?;
    outputs_have_their_solvers(case, &methods)?;
    case.newton_only(&methods)?;
    Ok(methods)
}

/// Refuse an output that a solver of `methods` must write and none does: `output.homogenised`
/// without micro-macro (`run` and `check` alike).
pub fn outputs_have_their_solvers(
    case: &Case,
    methods: &[Method],
) -> Result<(), crate::case::CaseError> {
    if case.output.homogenised && !methods.contains(&Method::MicroMacro) {
        let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
        return Err(crate::case::CaseError::Invalid {
            key: "output.homogenised".into(),
            value: "true".into(),
            fix: format!(
                "it writes micro-macro's homogenised operators, and this run solves with {} \
                 only: add \"micro-macro\" to `solver.methods` (or `--solver`), or drop the key",
                names.join(", ")
            ),
        });
    }
    Ok(())
}

/// Every solver of `methods` set up for `prepared` with the settings of `case`, in order.
fn set_up_all<'s>(
    case: &Case,
    methods: &[Method],
    prepared: &'s Prepared,
    exchange: &'s dyn Exchange,
    events: &mut dyn FnMut(RunEvent<'_>),
) -> Result<Vec<SetUpSolver<'s>>, RunError> {
    let mut solvers = Vec::with_capacity(methods.len());
    for &method in methods {
        events(RunEvent::Stage(&format!("setting up {}", method.name())));
        solvers.push(set_up_on(method, &case.solver, prepared, exchange)?);
    }
    Ok(solvers)
}

/// The structure of `case` and its taut stiffness, under the model it starts with
/// ([`prepare_start`]); a refused mechanism's modes, node by node,
/// are written to `mechanisms.csv` under `dir` before the refusal is returned (by the process
/// that `writes`).
fn prepare_or_locate_mechanisms(
    case: &mut Case,
    dir: &Path,
    writes: bool,
    keeps_taut: bool,
) -> Result<(Prepared, RowModel), RunError> {
    prepare_start(case, keeps_taut).or_else(|refused| {
        if writes && !refused.modes().is_empty() {
            write_mechanisms(dir, refused.modes())?;
        }
        Err(refused.into())
    })
}

/// The sweep over α: the solvers, where their e is measured from, the sinks, and what the
/// solves have given so far.
struct Sweep<'s> {
    prepared: &'s Prepared,
    solvers: Vec<SetUpSolver<'s>>,
    reference: ReferenceSource<'s>,
    sinks: Sinks<'s>,
    /// Each solver's converged answer at the previous α: its warm start (newton and pcg-lcp
    /// use it; they stop on the same criterion as from a cold start).
    previous: Vec<Option<Equilibrium>>,
    /// Each solver's load path (`large`): the α of its last equilibrium reached, where its
    /// next solve's path starts (0: the prestressed state), and the α of its previous row.
    paths: Vec<PathStart>,
    /// The checks made of every answer with K's factor.
    checks: AnswerChecks,
    /// The natural modes of every answer (`output.modes`).
    modal: Option<ModalAnalysis>,
    rows: Vec<SummaryRow>,
    failures: Failures,
    /// The processes of the run: a solve's files, written by rank 0 alone, are agreed on
    /// before the next solve's collectives.
    exchange: &'s dyn Exchange,
    /// Which ranks keep only their substructures' links.
    sharing: Sharing,
    /// The model of each α's rows.
    models: Models<'s>,
}

impl<'s> Sweep<'s> {
    fn new(
        models: Models<'s>,
        prepared: &'s Prepared,
        solvers: Vec<SetUpSolver<'s>>,
        reference: ReferenceSource<'s>,
        sinks: Sinks<'s>,
        exchange: &'s dyn Exchange,
        sharing: Sharing,
    ) -> Self {
        Sweep {
            exchange,
            sharing,
            prepared,
            previous: vec![None; solvers.len()],
            paths: vec![PathStart::default(); solvers.len()],
            solvers,
            reference,
            sinks,
            checks: AnswerChecks::of(models.case),
            modal: (models.case.output.modes > 0)
                .then(|| ModalAnalysis::new(models.case.output.modes, models.case.modal_mass)),
            models,
            rows: Vec::new(),
            failures: Failures::default(),
        }
    }

    /// Step 6: every solver at `alpha`, after the reference solve (shared with a solver of the
    /// case at its default settings, whose solve it then is).
    fn solve_alpha(
        &mut self,
        alpha: f64,
        events: &mut dyn FnMut(RunEvent<'_>),
    ) -> Result<(), RunError> {
        self.choose_model(alpha, events)?;
        let model = &self.prepared.model;
        let load = model.load(alpha);
        if self.reference.needed() {
            events(RunEvent::Stage(&format!(
                "reference solve at alpha = {}",
                alpha_label(alpha)
            )));
        }
        let reference_solution = self
            .reference
            .solve(&load, &mut self.solvers, &self.previous);
        let reference_errors = reference_solution
            .as_ref()
            .map(|r| Reference::new(model, &r.equilibrium.displacements));
        for index in 0..self.solvers.len() {
            let set_up = &mut self.solvers[index];
            let key = SolveKey {
                method: set_up.method,
                alpha,
                measure: set_up.solver.stopping_measure(),
            };
            on_every_rank(
                self.exchange,
                self.sinks.start(&key).map_err(RunError::from),
            )?;
            events(RunEvent::SolveStart {
                solver: key.method.name(),
                alpha,
            });
            let solution = match (self.reference.shared_index(), &reference_solution) {
                (Some(i), Some(r)) if i == index => r.clone(),
                _ => {
                    let mut progress = IterationEvents {
                        events: &mut *events,
                        key,
                    };
                    let mut observers = Tee::default()
                        .with(Some(&mut self.sinks))
                        .with(Some(&mut progress));
                    set_up.solver.solve_from(
                        &load,
                        self.previous[index].as_ref(),
                        reference_errors.as_ref(),
                        &mut observers,
                    )
                }
            };
            let recorded = self.record(index, &key, &load, solution, events);
            on_every_rank(self.exchange, recorded)?;
        }
        Ok(())
    }

    /// Steps 7–9: what the answer of solver `index` is, its row and its files.
    fn record(
        &mut self,
        index: usize,
        key: &SolveKey,
        load: &[f64],
        mut solution: Solution,
        events: &mut dyn FnMut(RunEvent<'_>),
    ) -> Result<(), RunError> {
        // Where the ranks keep shares of the links: with every rank keeping its own alone,
        //    the answer is judged and measured by all of them together; with rank 0 keeping
        //    the whole structure, the others leave the answer to it (it judges it, writes it
        //    and fails the run for it).
        let together = match &self.prepared.share {
            Some(share) if self.sharing == Sharing::EveryRank => Some(share),
            Some(_) => return Ok(()),
            None => None,
        };
        let (model, alpha) = (&self.prepared.model, key.alpha);
        // 6b. Where the solve's load path started and how far it went, before the verdict
        //     below may judge the answer otherwise (the solver's path moved on all the same).
        let path = self.paths[index].follow(alpha, &solution);
        // 7. What the answer is beyond the solver's own stop: no equilibrium, or an unstable
        //    one (docs/method.md §8).
        let solver = &self.solvers[index].solver;
        let verdict = assess(
            &mut solution,
            self.prepared,
            self.checks,
            load,
            |eq| match together {
                Some(_) => solver.no_equilibrium_along(&eq.displacements, load),
                None => crate::solvers::no_equilibrium(model, eq, load)
                    .or_else(|| crate::solvers::no_equilibrium_of_answer(model, eq, load)),
            },
        );
        self.previous[index] = (solution.info.status.converged() && results::is_finite(&solution))
            .then(|| solution.equilibrium.clone());
        // 8. A non-finite answer (or a row it would give) is reported, never written.
        let row = results::is_finite(&solution).then(|| {
            let path = path.as_ref();
            let eq = &solution.equilibrium;
            let measures = match together {
                Some(share) => AnswerMeasures::over_shares(
                    model,
                    &share.kept_world_links(),
                    share.world_cables(),
                    eq,
                    load,
                    self.exchange,
                ),
                None => AnswerMeasures::of(model, eq, load),
            };
            let mut row = SummaryRow::new(
                key.method.name(),
                alpha,
                &measures,
                &solution,
                (verdict.min_tangent_eigenvalue, verdict.geometric_term),
                self.solvers[index].setup_seconds,
            )
            .on_path(path);
            row.model_tolerance = self.checks.model_tolerance;
            row.model = self.models.row.model;
            row.model_reason = self.models.row.reason.clone();
            row.model_pinned = self.models.row.pinned;
            row.uniqueness = verdict.uniqueness.clone();
            // The member checks, on the answer of a row that has one (rank 0 holds every link).
            row.governing = (together.is_none() && !row.status.no_answer())
                .then(|| results::checks::governing(model, eq))
                .flatten();
            row
        });
        let Some(row) = row.filter(SummaryRow::is_finite) else {
            self.sinks.end(key, SolveEnd::NonFinite)?;
            // The solver's certificate said no equilibrium before its iterate overflowed.
            let found = match verdict.no_equilibrium {
                Some(_) => "no equilibrium (the solver's certificate holds), and its iterate ",
                None => "",
            };
            self.failures.push(
                key.method.name(),
                alpha_label(alpha),
                format!(
                    "{found}produced non-finite values after {} iterations; no row and no \
                     files written for it",
                    solution.info.iterations,
                ),
            );
            return Ok(());
        };
        if !row.converged {
            self.failures.push(
                key.method.name(),
                alpha_label(row.alpha),
                not_converged_message(&row, &solution, &verdict),
            );
        }
        // 9. The files of this solve; with no answer, its row and no file that would look
        //    like one.
        let modes = match (&mut self.modal, row.status.no_answer()) {
            (Some(modal), false) => modal.of(&self.prepared.model, &solution.equilibrium),
            _ => Vec::new(),
        };
        let end = match row.status.no_answer() {
            true => SolveEnd::NoAnswer { row: &row },
            false => SolveEnd::Solved {
                solution: &solution,
                row: &row,
                model: &self.prepared.model,
                modes: &modes,
            },
        };
        self.sinks.end(key, end)?;
        events(RunEvent::Row(&row));
        self.rows.push(row);
        Ok(())
    }

    /// Step 10: the files of the whole sweep; the rows and the failures.
    fn close(mut self) -> Result<(Vec<SummaryRow>, Failures), RunError> {
        self.sinks.close()?;
        Ok((self.rows, self.failures))
    }
}
