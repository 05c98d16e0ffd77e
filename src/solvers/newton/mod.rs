//! Exact active-set (semismooth Newton) solver on the energy (docs/method.md §1, §3), beyond the paper.
//!
//! Minimises `Π(U) = Σ_bars (½ k e² + t0 e) + Σ_cables ½ k ⟨e + t0/k⟩₊² − Fᵀ U`. Each iteration
//! solves `(K_bars + B_Aᵀ k_A B_A + μ I) ΔU = −∇Π` on the taut set A, then takes the exact
//! minimiser of the 1-D piecewise quadratic `Π(U + sΔU)` (`line_search`). The
//! regularisation μ vanishes with the residual; the symbolic factorization is the one of the
//! taut stiffness, reused.
//!
//! Factor reuse: the solver keeps the last factor of a Hessian it computed (and the taut
//! stiffness's). When the new taut set differs from a factored one by few links, the Newton
//! equations are solved by conjugate gradients preconditioned with that factor corrected for
//! the changed links ([`LowRankUpdate`], Woodbury: exact but for the regularisations' small
//! difference, so CG usually stops after one or two iterations); when CG needs more than a few
//! iterations, the Hessian is refactorised. The factor survives from one solve to the next,
//! so a warm start ([`Solver::warm_init`], from the previous α's answer) begins on the factor
//! of its own active set.
//!
//! Stopping measure: [`Measure::EquilibriumResidual`], `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)`.

mod krylov;
mod line_search;
mod nearby;

use super::{
    residual_stop, BalanceTolerances, Equilibrium, Measure, Progress, SetupError, Solver,
    TautStiffness,
};
use crate::linalg::{dot, LowRankUpdate, SparseCholesky, StiffnessPattern, CHUNK};
use crate::model::material::{self, SlackRule};
use crate::model::{unbalances_on, Model};
pub use crate::solvers::arc_length::PathFollowing;
use crate::structure::Structure;
use krylov::KrylovSolve;
pub use krylov::LinearSolve;
pub(crate) use line_search::{exact_line_search, EnergyAlongStep};
use nearby::{Base, Factored};
use rayon::prelude::*;

/// Settings, each default written once, at its field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Relative equilibrium residual to reach. Default 1e-10.
    pub tolerance: f64,
    /// Iteration cap. Default 100.
    pub max_iterations: usize,
    /// Reuse a factor of a nearby Hessian as a CG preconditioner (see the module doc);
    /// `false` refactorises at every step whose taut set is not all links. Default true.
    pub reuse_factor: bool,
    /// How each Newton system is solved (`solver.linear`). Default [`LinearSolve::Direct`].
    pub linear: LinearSolve,
    /// The partition a substructured solve works on (`solver.subdomains`, or the structure's
    /// default partition). Default `[4, 4]`.
    pub subdomains: [usize; 2],
    /// How the `large` model's load path is followed (`load.path`). Default
    /// [`PathFollowing::LoadControl`].
    pub path: PathFollowing,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 100,
            reuse_factor: true,
            linear: LinearSolve::Direct,
            subdomains: [4, 4],
            path: PathFollowing::LoadControl,
        }
    }
}

/// What newton's linear algebra cost since it was set up, summed over its solves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NewtonWork {
    /// Newton steps taken.
    pub steps: usize,
    /// Numeric factorizations of a Hessian (attempts that failed and were regularised more
    /// included).
    pub factorizations: usize,
    /// Steps solved with the taut stiffness's own factor (every cable taut).
    pub taut_steps: usize,
    /// Steps solved by CG preconditioned with an earlier factor (corrected for the links that
    /// changed state).
    pub reused_steps: usize,
    /// CG iterations, over all steps (successful or not); each applies the preconditioner
    /// once (a solve with a factor).
    pub cg_iterations: usize,
    /// Columns of the low-rank correction computed (kept columns are not recomputed): one
    /// right-hand side of a forward substitution each.
    pub correction_columns: usize,
    /// PCG iterations of the substructured solves (`solver.linear = "krylov"`).
    pub krylov_iterations: usize,
    /// Subdomains refactorised by the substructured solves.
    pub preconditioner_updates: usize,
    /// Of those, the subdomains whose GenEO vectors were found anew.
    pub geneo_solves: usize,
}

/// Regularisation μ = `REGULARISATION · min(1, residual)² · mean diagonal`: enough to step
/// through a taut set that is a mechanism on the way, vanishing quadratically so that the step
/// on the final active set is exact to round-off; a factorization that fails raises μ (see
/// `newton_step`). Why quadratic and why 1e-8: docs/method.md, "Tuning log".
const REGULARISATION: f64 = 1e-8;

/// Stall: for this many iterations the residual has not fallen below half its best value and
/// the slack set has not changed. Newton converges quadratically on a fixed taut set, so ten
/// such steps mean it sits at round-off (issue 13, C7: `tolerance = 1e-15` ran all
/// iterations).
const STALL_ITERATIONS: usize = 10;

/// The Hessian is factored in two halves side by side from this many free dofs, with a second
/// thread: on 256 × 256 modules (590 k dofs, a separator of 2 301) measured in
/// docs/performance.md ("newton at scale, and on two threads"); below, the separator's dense work weighs more.
pub const SPLIT_MIN_DOFS: usize = 100_000;

/// The newton solver, set up for one structure.
pub struct Newton<'s> {
    model: &'s Model,
    structure: &'s Structure,
    taut: Taut<'s>,
    settings: NewtonSettings,
    chol: SparseCholesky,
    /// What `chol` holds a factor of, if anything.
    factored: Option<Factored>,
    /// The change, from the factored Hessian `correction.0` names, to the last Hessian solved
    /// by CG; its columns are reused while the links and the factor stay the same.
    correction: (Base, LowRankUpdate),
    hessian: Vec<f64>,
    mean_stiffness: f64,
    work: NewtonWork,
    /// The substructured solve, with `solver.linear = "krylov"`.
    krylov: Option<KrylovSolve>,
}

/// The taut stiffness newton solves with: the run's, factorised; or, for a substructured solve
/// in a run that never factorises K whole, its own pattern and analysis, never factorised.
enum Taut<'s> {
    Factorised(&'s TautStiffness),
    Unfactorised(Box<TautStiffness>),
}

impl Taut<'_> {
    fn get(&self) -> &TautStiffness {
        match self {
            Taut::Factorised(taut) => taut,
            Taut::Unfactorised(taut) => taut,
        }
    }

    /// K's factor, where there is one.
    fn factor(&self) -> Option<&SparseCholesky> {
        match self {
            Taut::Factorised(taut) => Some(&taut.factor),
            Taut::Unfactorised(_) => None,
        }
    }
}

/// The iterate.
pub struct NewtonState {
    load: Vec<f64>,
    u: Vec<f64>,
    /// `t0 + k e` of every link, before a unilateral cable's clipping at 0.
    trial: Vec<f64>,
    /// Total tensions τ (docs/method.md §1): the trial tension, clipped at 0 for unilateral cables.
    tensions: Vec<f64>,
    /// `Bᵀτ − F`, the energy's gradient.
    gradient: Vec<f64>,
    /// r(U), the relative equilibrium residual every solver reports.
    residual: f64,
    /// The unbalance relative to `‖F‖ + ‖|B|ᵀ|τ − t0|‖`: the stop needs it ≤ tol too.
    load_residual: f64,
    iteration: usize,
    /// The smallest load-relative residual so far that halved the one before it, and its iteration.
    best: (f64, usize),
    /// The last step was not a descent direction, or the residual stopped falling for
    /// [`STALL_ITERATIONS`] iterations: no further progress is possible.
    stalled: bool,
}

impl<'s> Newton<'s> {
    /// Set up on a model whose taut stiffness is already known to be regular.
    pub fn new(
        model: &'s Model,
        taut: &'s TautStiffness,
        settings: NewtonSettings,
    ) -> Result<Self, SetupError> {
        Ok(Self::with(model, Taut::Factorised(taut), settings))
    }

    /// Set up with `solver.linear = "krylov"` without K's factor, on a model whose mechanism
    /// check was made substructure by substructure: K's pattern and analysis of its own, for
    /// the steps a subdomain factor cannot solve (factorised only then).
    pub fn substructured(model: &'s Model, settings: NewtonSettings) -> Self {
        debug_assert_eq!(settings.linear, LinearSolve::Krylov);
        let taut = Taut::Unfactorised(Box::new(TautStiffness::unfactorised(model)));
        Self::with(model, taut, settings)
    }

    fn with(model: &'s Model, taut: Taut<'s>, settings: NewtonSettings) -> Self {
        let structure = &model.structure;
        let k = taut.get();
        Newton {
            model,
            structure,
            // Substructured without K's factor, a direct step is a rare fallback: a workspace
            // on K's analysis alone (its values allocated, never touched until then), not the
            // halves' patterns and analyses a split would build at set-up.
            chol: match &taut {
                Taut::Unfactorised(_) => k.factor.share_symbolic(),
                Taut::Factorised(_) => hessian_factor(k, structure.n_free),
            },
            factored: None,
            correction: (Base::Taut, LowRankUpdate::none(structure.n_free)),
            hessian: vec![0.0; k.values.len()],
            mean_stiffness: k.pattern.mean_diagonal(&k.values),
            work: NewtonWork::default(),
            krylov: (settings.linear == LinearSolve::Krylov)
                .then(|| KrylovSolve::new(model, settings.subdomains)),
            taut,
            settings,
        }
    }

    /// Whether the Hessian is factored in two halves side by side (a second thread and at
    /// least `SPLIT_MIN_DOFS` free dofs).
    pub fn factors_in_halves(&self) -> bool {
        self.chol.is_split()
    }

    /// What the linear algebra cost so far.
    pub fn work(&self) -> NewtonWork {
        self.work
    }

    /// Trial tensions, tensions, gradient and residual of `state.u` (with the prestress's
    /// geometric force `K_G U` when the model has it: docs/method.md §8).
    fn evaluate(&self, state: &mut NewtonState) {
        let s = self.structure;
        let u = &state.u;
        (
            &mut state.trial,
            &mut state.tensions,
            &s.links,
            &s.link_dofs,
        )
            .into_par_iter()
            .with_min_len(CHUNK)
            .for_each(|(trial, tension, l, ld)| {
                *trial = material::trial_tension(l, ld.elongation(u));
                *tension = material::tension(l, *trial);
            });
        let geometric_force = self.model.prestress_force(&state.u);
        let sizes = unbalances_on(
            s,
            &s.link_dofs,
            &state.tensions,
            geometric_force.as_deref(),
            &state.load,
            &mut state.gradient,
        );
        state.residual = sizes.relative;
        state.load_residual = sizes.load_relative;
    }

    /// `step ← H⁻¹ step` with H the Hessian on the taut set of `state` (docs/method.md §3) plus the
    /// vanishing regularisation. With every link taut H is K, whose factor is reused; with a
    /// taut set close to a factored one, by CG preconditioned with that factor; otherwise H is
    /// factorized.
    fn newton_step(&mut self, state: &NewtonState, step: &mut [f64]) {
        let s = self.structure;
        self.work.steps += 1;
        let taut_links: Vec<bool> = s
            .links
            .iter()
            .zip(&state.trial)
            .map(|(l, &trial)| material::is_taut(l, trial))
            .collect();
        // H = Σ_taut k Bᵢᵀ Bᵢ + μ I, μ = REGULARISATION · min(1, r)² · mean diagonal.
        let mut mu = REGULARISATION * state.residual.min(1.0).powi(2) * self.mean_stiffness;
        if let Some(krylov) = &mut self.krylov {
            let unbalance = state.residual.max(state.load_residual);
            let stop = (unbalance, self.settings.tolerance);
            let mu = (mu, self.mean_stiffness);
            if krylov.solve(self.model, &taut_links, mu, stop, step, &mut self.work) {
                return;
            }
        }
        if let Some(factor) = self.taut.factor().filter(|_| taut_links.iter().all(|&t| t)) {
            self.work.taut_steps += 1;
            factor.solve_in_place(step);
            return;
        }
        if self.settings.reuse_factor
            && self.solve_with_nearby_factor(&taut_links, mu, step, state.residual)
        {
            return;
        }
        let pattern = &self.taut.get().pattern;
        assemble_hessian(self.model, pattern, &taut_links, mu, &mut self.hessian);
        let mut added = mu;
        loop {
            self.work.factorizations += 1;
            if self.chol.factorize(pattern, &self.hessian).is_ok() {
                break;
            }
            mu = raised_regularisation(mu, self.mean_stiffness);
            for &d in &pattern.diag_slot {
                self.hessian[d] += mu - added;
            }
            added = mu;
        }
        self.factored = Some(Factored { taut: taut_links });
        if self.correction.0 == Base::Last {
            self.correction.1 = LowRankUpdate::none(self.structure.n_free);
        }
        self.chol.solve_in_place(step);
    }

    /// A state at displacements `u` for `load`, evaluated.
    fn state_at(&self, load: &[f64], u: Vec<f64>) -> NewtonState {
        let m = self.structure.links.len();
        let mut state = NewtonState {
            load: load.to_vec(),
            gradient: vec![0.0; u.len()],
            u,
            trial: vec![0.0; m],
            tensions: vec![0.0; m],
            residual: f64::INFINITY,
            load_residual: f64::INFINITY,
            iteration: 0,
            best: (f64::INFINITY, 0),
            stalled: false,
        };
        self.evaluate(&mut state);
        state.best = (state.load_residual, 0);
        state
    }
}

impl Solver for Newton<'_> {
    type State = NewtonState;
    const INIT_IS_ITERATE: bool = false;

    fn measure(&self) -> Measure {
        Measure::EquilibriumResidual
    }

    fn model(&self) -> &Model {
        self.model
    }

    fn max_iterations(&self) -> usize {
        self.settings.max_iterations
    }

    /// U = 0.
    fn init(&mut self, load: &[f64]) -> NewtonState {
        if let Some(krylov) = &mut self.krylov {
            krylov.begin(&self.work);
        }
        self.state_at(load, vec![0.0; self.structure.n_free])
    }

    /// U = the previous answer's displacements: its active set is the first step's, and the
    /// factor kept from the previous solve is usually that of its Hessian. A previous answer of
    /// another size, or not finite, is ignored (U = 0).
    fn warm_init(&mut self, load: &[f64], previous: &Equilibrium) -> NewtonState {
        let u = &previous.displacements;
        if u.len() == self.structure.n_free && u.iter().all(|x| x.is_finite()) {
            if let Some(krylov) = &mut self.krylov {
                krylov.begin(&self.work);
            }
            self.state_at(load, u.clone())
        } else {
            self.init(load)
        }
    }

    /// `ΔU = −H⁻¹ ∇Π`, then `U ← U + s ΔU` with s the exact minimiser along ΔU.
    fn next_iter(&mut self, state: &mut NewtonState) {
        let s = self.structure;
        state.iteration += 1;
        let slack_before: Vec<bool> = state.tensions.iter().map(|&t| t == 0.0).collect();
        let mut step: Vec<f64> = state.gradient.iter().map(|g| -g).collect();
        self.newton_step(state, &mut step);
        let mut step_elongation = vec![0.0; s.links.len()];
        s.elongations(&step, &mut step_elongation);
        let load_work = dot(&state.load, &step);
        // φ(s) = Π(U + sΔU) gains ½ s² ΔUᵀK_GΔU + s ΔUᵀK_G U with the prestress's geometric
        // stiffness (docs/method.md §8).
        let geometric = self.model.prestress_energy_along(&state.u, &step);
        let Some(length) = exact_line_search(
            &s.links,
            &state.trial,
            &step_elongation,
            load_work,
            geometric,
        ) else {
            state.stalled = true;
            return;
        };
        state
            .u
            .iter_mut()
            .zip(&step)
            .for_each(|(u, d)| *u += length * d);
        self.evaluate(state);
        let slack_changed = state
            .tensions
            .iter()
            .zip(&slack_before)
            .any(|(&t, &was)| (t == 0.0) != was);
        if state.load_residual <= 0.5 * state.best.0 || slack_changed {
            state.best = (state.load_residual.min(state.best.0), state.iteration);
        } else if state.iteration - state.best.1 >= STALL_ITERATIONS {
            state.stalled = true;
        }
    }

    fn progress(&self, state: &NewtonState) -> Progress {
        // r(U) ≤ tol, and the same unbalance relative to the forces the load brings into play
        // (the prestress left out): the second is the stricter, and keeps U = 0 from passing
        // at a huge prestress (issue 13, D5a).
        let balance = BalanceTolerances::both(self.settings.tolerance)
            .balance(state.residual, state.load_residual);
        let (stop, at_roundoff) = residual_stop(balance, state.stalled);
        Progress {
            iteration: state.iteration,
            stopping_value: state.residual,
            // newton's own measure is r(U).
            equilibrium_residual: Some(state.residual),
            rebuilds: 0,
            krylov_iterations: self.krylov.as_ref().map(|k| k.iterations(&self.work)),
            slack_cables: material::slack_flags(self.structure, &state.trial, SlackRule::Clipped)
                .iter()
                .filter(|&&x| x)
                .count(),
            at_roundoff,
            stop,
        }
    }

    fn elongations(&self, state: &NewtonState) -> Vec<f64> {
        let mut e = vec![0.0; self.structure.links.len()];
        self.structure.elongations(&state.u, &mut e);
        e
    }

    fn iterate(&self, state: &NewtonState) -> Equilibrium {
        Equilibrium::classified(self.model, state.u.clone(), state.tensions.clone())
    }
}

/// μ after a factorization that failed: ×100, and at least 1e-12 of the mean diagonal (the
/// direct and the substructured solves alike).
fn raised_regularisation(mu: f64, mean_diagonal: f64) -> f64 {
    (mu * 100.0).max(1e-12 * mean_diagonal)
}

/// The Hessian's factor: in two halves side by side (`SparseCholesky::share_symbolic_split`)
/// when there is a second thread and the problem is large enough for the halves to outweigh
/// the separator's dense work, else on K's analysis as it is.
fn hessian_factor(taut: &TautStiffness, n_free: usize) -> SparseCholesky {
    let split = (rayon::current_num_threads() >= 2 && n_free >= SPLIT_MIN_DOFS)
        .then(|| taut.factor.share_symbolic_split(&taut.pattern, 1))
        .flatten();
    split.unwrap_or_else(|| taut.factor.share_symbolic())
}

/// `values = H = Σ_taut k Bᵢᵀ Bᵢ + K_G + μ I` (docs/method.md §3, §8), lower triangle on
/// `pattern`.
fn assemble_hessian(
    model: &Model,
    pattern: &StiffnessPattern,
    taut_links: &[bool],
    mu: f64,
    values: &mut [f64],
) {
    model.assemble_tangent(pattern, |i| taut_links[i], values);
    for &d in &pattern.diag_slot {
        values[d] += mu;
    }
}

#[cfg(test)]
mod tests;
