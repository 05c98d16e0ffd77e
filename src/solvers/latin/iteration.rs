//! How the LATIN iterates (docs/method.md §4): the two iteration orders (relaxed on s, or
//! Anderson-accelerated on the linear stage's input), the linear stage's input and its
//! refinement of the macro solve, and the [`Solver`] state machine (`init`, `next_iter`,
//! `progress`) the driver runs.

use super::anderson::{Anderson, Pieces};
use super::indicator::Residuals;
use super::local_stage::LocalLaw;
use super::state::{Acceleration, Following, LatinState, StatusSteps, SubState};
use super::{Latin, SearchPolicy, StopOn};
use crate::model::material;
use crate::model::Model;
use crate::solvers::{
    unit_direction, Balance, Equilibrium, LinksAlong, Measure, NoEquilibrium, Progress, Solver,
    Status,
};
use rayon::prelude::*;

/// A LATIN answer whose η meets the tolerance is converged only with r(U) at most this many
/// times the tolerance (or [`EQUILIBRIUM_CHECK_FLOOR`]): at η = 1e-6 r(U) is 5e-7 to 1.5e-6 on
/// the paper's plain method, up to 5.1e-5 with micro-macro's defaults on the paper case; the
/// one-module-wide strips of issue 42 (T5) sit at 1e-2 and 0.43.
const EQUILIBRIUM_CHECK: f64 = 1000.0;

/// ... and r(U) at most this is an equilibrium whatever the tolerance: micro-macro's own
/// accuracy on the paper case is 1.65e-10.
const EQUILIBRIUM_CHECK_FLOOR: f64 = 1e-8;

/// The two ways to iterate: on s with relaxation (the paper's order: local stage, then linear
/// stage), or on the linear stage's input with Anderson acceleration (linear stage, then local
/// stage, so that G is the whole map ŝ ↦ local(linear(ŝ))).
impl Latin<'_> {
    /// Whether the iteration runs on the linear stage's input (Anderson-accelerated when
    /// `solver.anderson` > 0): always with inexact Newton status steps, whose line search
    /// blends that input.
    pub(super) fn accelerated(&self) -> bool {
        self.settings.anderson > 0 || self.newton_steps()
    }

    /// Whether the status is updated by inexact Newton steps (docs/method.md §9).
    pub(super) fn newton_steps(&self) -> bool {
        self.settings.policy == SearchPolicy::Newton
    }

    /// The law of the local stage while iterating: linearised at the status `law_slack` with
    /// inexact Newton steps, exact otherwise.
    pub(super) fn local_law<'a>(&self, law_slack: &'a [bool]) -> LocalLaw<'a> {
        if self.newton_steps() {
            LocalLaw::Frozen(law_slack)
        } else {
            LocalLaw::Exact
        }
    }

    /// ŝ = local(s) (the iteration's first stage, before any rebuild).
    fn relaxed_local_stage(&self, state: &mut LatinState) {
        self.local_stage(&mut state.subs, LocalLaw::Exact);
    }

    /// s = linear(ŝ), relaxed against the previous s with μ < 1.
    fn relaxed_linear_stage(&self, state: &mut LatinState) {
        let mu = self.settings.relaxation;
        let relaxation = (state.acceleration.relax && mu < 1.0).then_some(mu);
        let accuracy = self.macro_accuracy(state);
        self.linear_stage(&state.load, &mut state.subs, relaxation, accuracy);
        state.acceleration.relax = true;
    }

    /// The state holds s = linear(x) and ŝ = local(s), so G(x) is the input ŝ gives; x⁺ from
    /// Anderson (restarted when the map changed: new operators, or a status step's new law);
    /// then s = linear(x⁺) and ŝ = local(s), with the residuals of s measured beside it
    /// (returned).
    pub(super) fn accelerated_iteration(
        &self,
        state: &mut LatinState,
        restarted: bool,
    ) -> Residuals {
        let g = self.linear_stage_input(&state.subs);
        let next = state.acceleration.anderson.step(
            &state.acceleration.input,
            &g,
            restarted,
            &self.input_pieces(&state.subs),
        );
        self.set_linear_stage_input(&mut state.subs, &next);
        let old = std::mem::replace(&mut state.acceleration.input, next);
        state.acceleration.anderson.recycle(old);
        let accuracy = self.macro_accuracy(state);
        self.linear_stage(&state.load, &mut state.subs, None, accuracy);
        let residuals = self.local_stage_measuring(state);
        state.acceleration.relax = true;
        residuals
    }

    /// ŝ = local(s) on the iteration's law, and beside it (on another thread: the local stage
    /// is parallel over the substructures, r(U) one pass over the links) the residuals of s's
    /// U, for [`Latin::measure_state`]: the same numbers as one after the other.
    pub(super) fn local_stage_measuring(&self, state: &mut LatinState) -> Residuals {
        let u = self.displacements(&state.subs);
        let law = self.local_law(&state.steps.law_slack);
        let (subs, load, law_slack) = (&mut state.subs, &state.load, &state.steps.law_slack);
        let ((), residuals) = rayon::join(
            || self.local_stage(subs, law),
            || self.residuals(&u, load, law_slack),
        );
        residuals
    }

    /// How far the macro solve is refined (a fraction of its right-hand side): 1e-9 while
    /// r(U) is above 100 times its tolerance, to the end after. 1e-9 takes 2 solves where
    /// refining to the end took 3 to 5 (the regularised factor leaves 1e-8 to 1e-6, each step
    /// gains three decades) and leaves the iteration counts unchanged, but on one-module
    /// substructures a macro answer to 1e-10 held r(U) above 1e-7 for 1000 iterations. Once
    /// to the end, always to the end: switching back when r(U) rose again changed the map under
    /// Anderson's history at every crossing (on 1024 × 1024 modules r(U) went from below 1e-6
    /// to 4e-6 at each of 27 crossings in 404 iterations).
    pub(super) fn macro_accuracy(&self, state: &mut LatinState) -> f64 {
        state.macro_to_the_end |= state.residual <= 100.0 * self.settings.residual_tolerance();
        match state.macro_to_the_end {
            true => 0.0,
            false => 1e-9,
        }
    }

    /// What a linear stage reads of ŝ, scaled to the energy norm: per link `(t̂ − l ê)/√l`,
    /// per interface row `(F̂^m + d_m Û^m)/√d_m`; of the substructures this process holds
    /// (whose linear stages it runs).
    pub(super) fn linear_stage_input(&self, subs: &[SubState]) -> Vec<f64> {
        let sqrt_dm = self.world.dm.sqrt();
        let held = self.ranks.held();
        let parts: Vec<Vec<f64>> = self.operators.substructures[held.clone()]
            .par_iter()
            .zip(subs[held].par_iter())
            .with_min_len(self.ranks.chunk())
            .map(|(sub, st)| {
                let mut x = Vec::with_capacity(Self::input_len(st));
                for (j, &i) in sub.links.iter().enumerate() {
                    let l = self.search.now[i];
                    x.push((st.t_hat[j] - l * st.e_hat[j]) / l.sqrt());
                }
                for side in &st.sides {
                    x.extend(side.hat_load.iter().map(|v| v / sqrt_dm));
                }
                x
            })
            .collect();
        parts.concat()
    }

    /// A value per link of the world, from `mine`, the held substructures' values in their
    /// links' order: the others' gathered from the ranks holding them (on one process,
    /// `mine` itself, laid out).
    fn per_link(&self, mine: Vec<f64>) -> Vec<f64> {
        let all = match self.ranks.size() {
            1 => mine,
            _ => self.ranks.gather(&mine),
        };
        let mut out = vec![0.0; self.world.links];
        // Where each substructure's links lie in the whole structure, in its links' order.
        let places: Box<dyn Iterator<Item = &usize>> = match self.ranks.world_links() {
            Some(world_links) => Box::new(world_links.iter().flatten()),
            None => Box::new(
                self.operators
                    .substructures
                    .iter()
                    .flat_map(|sub| &sub.links),
            ),
        };
        places.zip(all).for_each(|(&i, v)| out[i] = v);
        out
    }

    /// How many entries of the linear stage's input a substructure holds.
    pub(super) fn input_len(st: &SubState) -> usize {
        st.t_hat.len() + st.sides.iter().map(|s| s.hat_load.len()).sum::<usize>()
    }

    /// How the linear stage's input is held (each held substructure's part, in order) and
    /// summed, for Anderson's inner products.
    pub(super) fn input_pieces(&self, subs: &[SubState]) -> Pieces<'_> {
        Pieces {
            lengths: subs[self.ranks.held()]
                .iter()
                .map(Self::input_len)
                .collect(),
            exchange: self.ranks.exchange(),
        }
    }

    /// A ŝ that a linear stage reads as `x` (t̂ = √l x, ê = 0 on the links), on the held
    /// substructures (`x` their part of the input).
    pub(super) fn set_linear_stage_input(&self, subs: &mut [SubState], x: &[f64]) {
        let sqrt_dm = self.world.dm.sqrt();
        let held = self.ranks.held();
        let subs = &mut subs[held.clone()];
        let mut pieces = Vec::with_capacity(subs.len());
        let mut rest = x;
        for st in subs.iter() {
            let (piece, tail) = rest.split_at(Self::input_len(st).min(rest.len()));
            pieces.push(piece);
            rest = tail;
        }
        self.operators.substructures[held]
            .par_iter()
            .zip(subs.par_iter_mut().zip(pieces.into_par_iter()))
            .with_min_len(self.ranks.chunk())
            .for_each(|(sub, (st, piece))| {
                let mut x = piece.iter();
                for (j, &i) in sub.links.iter().enumerate() {
                    st.t_hat[j] = x.next().copied().unwrap_or(0.0) * self.search.now[i].sqrt();
                    st.e_hat[j] = 0.0;
                }
                for side in st.sides.iter_mut() {
                    for v in side.hat_load.iter_mut() {
                        *v = x.next().copied().unwrap_or(0.0) * sqrt_dm;
                    }
                }
            });
    }
}

impl Solver for Latin<'_> {
    type State = LatinState;

    /// Iteration 0 is the first linear stage.
    const INIT_IS_ITERATE: bool = true;

    fn measure(&self) -> Measure {
        Measure::Indicator
    }

    fn model(&self) -> &Model {
        self.model
    }

    fn max_iterations(&self) -> usize {
        self.settings.max_iterations
    }

    /// Iteration 0: the linear stage from ŝ = 0, with l as set up (a previous solve's
    /// status-following l is undone, so that every solve starts alike). With Anderson
    /// acceleration it is followed by the local stage on it (ŝ = local(s)).
    fn init(&mut self, load: &[f64]) -> LatinState {
        if self.any_search_slack() {
            self.set_search(vec![false; self.structure.links.len()]);
        }
        let mut state = LatinState {
            // Of the others' substructures, a process exchanging s point to point keeps only
            // what it reads (`SubState::of_another_rank`).
            subs: self
                .operators
                .substructures
                .iter()
                .enumerate()
                .map(|(e, sub)| {
                    let own = self.ranks.holds(e) || self.ranks.neighbours().is_none();
                    match own {
                        true => SubState::zero(sub),
                        false => SubState::of_another_rank(sub),
                    }
                })
                .collect(),
            iteration: 0,
            eta: f64::INFINITY,
            residual: f64::INFINITY,
            load_residual: f64::INFINITY,
            slack_cables: 0,
            rebuilds: 0,
            at_roundoff: false,
            macro_to_the_end: false,
            unloaded: load.iter().all(|&f| f == 0.0)
                && self.structure.prescribed.iter().all(|&d| d == 0.0),
            load: load.to_vec(),
            acceleration: Acceleration {
                relax: false,
                input: Vec::new(),
                anderson: Anderson::new(self.settings.anderson, self.settings.relaxation),
            },
            following: Following {
                status_streak: vec![0; self.structure.links.len()],
            },
            steps: StatusSteps {
                frozen_residual: f64::INFINITY,
                law_slack: vec![false; self.structure.links.len()],
                runaway: None,
                start: None,
            },
        };
        self.linear_stage(&state.load, &mut state.subs, None, 1e-9);
        let mut measured = None;
        if self.accelerated() {
            state.acceleration.input = self.linear_stage_input(&state.subs);
            measured = Some(self.local_stage_measuring(&mut state));
        }
        state.acceleration.relax = true;
        self.measure_state(&mut state, measured);
        if self.newton_steps() {
            state.steps.start = Some(self.step_start(&state));
        }
        state
    }

    /// One iteration (docs/method.md §6): with status-following l, new operators when the cables'
    /// status changed (relaxation and acceleration then restart: the old s was computed with
    /// another l); then the linear stage, relaxed `s ← μ s_new + (1 − μ) s_old`, or with
    /// Anderson acceleration on its input.
    /// With inexact Newton status steps, an inner run that has reached its forcing tolerance
    /// first ends in a status step, and the iteration is the first of the next inner run.
    fn next_iter(&mut self, state: &mut LatinState) {
        let stepped = self.newton_steps() && self.inner_run_done(state);
        let measured = if self.accelerated() {
            // 1. With status steps, the end of an inner run: the blend and its status.
            let step = stepped.then(|| self.status_step(state));
            let rebuild = step.as_ref().and_then(|s| s.rebuild.clone());
            // 2. The explicit rebuild step: new operators for a status step's new directions,
            //    or for status-following l.
            let step_rebuilt = self.rebuild_for(rebuild, state);
            let law_changed = match &step {
                Some(step) => self.finish_status_step(state, step, step_rebuilt),
                None => false,
            };
            let follow = self.status_to_follow(state);
            let restart = self.rebuild_for(follow, state) || law_changed;
            // 3. The iteration itself, the solver unchanged.
            Some(self.accelerated_iteration(state, restart))
        } else {
            self.relaxed_local_stage(state);
            let follow = self.status_to_follow(state);
            self.rebuild_for(follow, state);
            self.relaxed_linear_stage(state);
            None
        };
        state.iteration += 1;
        self.measure_state(state, measured);
        if stepped {
            state.steps.start = Some(self.step_start(state));
        }
    }

    fn progress(&self, state: &LatinState) -> Progress {
        let eta_met = state.eta <= self.settings.tolerance;
        // The stop every solver shares: r(U) and r_F(U) within their tolerances, or at the
        // round-off of the prestress's balance (a load below what the tolerance resolves).
        let balance = self
            .settings
            .balance_tolerances()
            .balance(state.residual, state.load_residual);
        let residual_met = balance == Balance::Met;
        // η ≤ tolerance with r(U) above EQUILIBRIUM_CHECK × tolerance: a fixed point of the
        // iteration that is not the equilibrium (one-module-wide substructures: η 5e-11 at
        // r(U) 1e-2, 44 % off, issue 42 T5). Never converged, even on η alone.
        let off_equilibrium = eta_met
            && state.residual
                > (EQUILIBRIUM_CHECK * self.settings.tolerance).max(EQUILIBRIUM_CHECK_FLOOR);
        let criterion = match self.settings.stop_on {
            StopOn::Eta => eta_met && !off_equilibrium,
            StopOn::Residual => residual_met,
            StopOn::Both => eta_met && residual_met,
        };
        // Δη at round-off: nothing left to gain. Converged with no load (η is then a ratio of
        // round-off to round-off), or where the balance holds or is at round-off (the answer
        // at round-off, said so: α = 1e-12 on a grid stalled at r(U) 3e-17 before, E2; the
        // paper's grid at α = 1e-10 stalled with r(U) 2.5e-17 and η 1.6e-6).
        let at_roundoff_answer = state.at_roundoff && (state.unloaded || balance != Balance::Unmet);
        let stop = if self.operators.lost
            || !(state.eta.is_finite() && state.residual.is_finite())
            || (self.settings.stop_on == StopOn::Eta && off_equilibrium && !state.unloaded)
        {
            Some(Status::Stalled)
        } else if criterion || at_roundoff_answer {
            Some(Status::Converged)
        } else if state.at_roundoff {
            // Under a load, Δη at round-off with the criterion unmet: nothing left to gain.
            Some(Status::Stalled)
        } else {
            None
        };
        Progress {
            iteration: state.iteration,
            stopping_value: state.eta,
            equilibrium_residual: Some(state.residual),
            rebuilds: state.rebuilds,
            krylov_iterations: None,
            slack_cables: state.slack_cables,
            at_roundoff: stop == Some(Status::Converged) && !criterion,
            stop,
        }
    }

    /// e of the linear stage, link by link (each link belongs to one substructure; on
    /// several ranks, gathered from the ranks holding them).
    fn elongations(&self, state: &LatinState) -> Vec<f64> {
        let held = self.ranks.held();
        let mine = state.subs[held].iter().flat_map(|st| st.e.iter().copied());
        self.per_link(mine.collect())
    }

    fn runaway(&self, state: &LatinState) -> Option<NoEquilibrium> {
        state.steps.runaway.clone()
    }

    /// U of the linear stage (interface nodes averaged over the substructures holding them),
    /// tensions of the local stage on it (which satisfy the cable law exactly; slack cables
    /// carry exactly 0), the slack set by the shared classification of U. On several ranks s
    /// is gathered whole for U, and each rank gives its own links' tensions: a rank knows the
    /// search directions of its own substructures' links only.
    fn iterate(&self, state: &LatinState) -> Equilibrium {
        let s = self.structure;
        let mut subs = state.subs.clone();
        self.complete_state(&mut subs);
        let u = self.displacements(&subs);
        let held = self.ranks.held();
        self.local_stage_on(&mut subs, LocalLaw::Exact, held.clone());
        let mine: Vec<f64> = self.operators.substructures[held.clone()]
            .iter()
            .zip(&subs[held])
            .flat_map(|(sub, st)| {
                sub.links
                    .iter()
                    .enumerate()
                    .map(|(j, &i)| match st.slack_hat[j] {
                        true => 0.0,
                        false => st.t_hat[j] + s.links[i].prestress,
                    })
            })
            .collect();
        drop(subs);
        self.classified(u, mine)
    }

    /// The no-equilibrium certificate along `u`, each process testing the links of the
    /// substructures it holds and the parts added in the substructures' order (on one process
    /// too, so that every number of ranks adds the same numbers in the same order).
    fn no_equilibrium_along(&self, u: &[f64], load: &[f64]) -> Option<NoEquilibrium> {
        self.certificate_along(u, load)
    }
}

impl Latin<'_> {
    /// The answer of displacements `u` with the held links' tensions `mine` (in the held
    /// substructures' order), classified by the rule every solver shares
    /// ([`material::SlackRule::Gap`]): a cable is slack where its trial tension `t0 + k B U` lies
    /// below [`material::SLACK_GAP_TOLERANCE`] of the cables' force scale, the largest over every
    /// rank; a slack cable's tension is exactly 0. Tensions and slack flags are gathered whole.
    fn classified(&self, u: Vec<f64>, mut mine: Vec<f64>) -> Equilibrium {
        let s = self.structure;
        let held_links = || {
            self.operators.substructures[self.ranks.held()]
                .iter()
                .flat_map(|sub| &sub.links)
        };
        let trial: Vec<f64> = held_links()
            .map(|&i| material::trial_tension(&s.links[i], s.link_dofs[i].elongation(&u)))
            .collect();
        let scale = material::gap_scale(
            held_links()
                .map(|&i| &s.links[i])
                .zip(trial.iter().copied()),
        );
        let scale = match self.ranks.size() {
            1 => scale,
            _ => self.ranks.gather(&[scale]).into_iter().fold(0.0, f64::max),
        };
        let slack: Vec<f64> = held_links()
            .zip(&trial)
            .zip(&mut mine)
            .map(|((&i, &t), tension)| {
                let is_slack = material::gap_slack(&s.links[i], t, scale);
                if is_slack {
                    *tension = 0.0;
                }
                f64::from(u8::from(is_slack))
            })
            .collect();
        Equilibrium {
            displacements: u,
            tensions: self.per_link(mine),
            slack: self.per_link(slack).into_iter().map(|f| f == 1.0).collect(),
        }
    }

    /// [`Solver::no_equilibrium_along`]: each held substructure's links tested along
    /// `d = u / ‖u‖` ([`LinksAlong`]), a failure anywhere ruling d out on every rank; their
    /// stretch energies added in the substructures' order, and the shortened cables gathered
    /// and put back in the whole structure's link order.
    pub(super) fn certificate_along(&self, u: &[f64], load: &[f64]) -> Option<NoEquilibrium> {
        let s = self.structure;
        // The same on every rank: u is whole.
        let d = unit_direction(self.model, u)?;
        let held = self.ranks.held();
        let parts: Vec<Option<LinksAlong>> = held
            .clone()
            .map(|e| {
                let sub = &self.operators.substructures[e];
                let world = |j: usize| match self.ranks.world_links() {
                    Some(world_links) => world_links[e][j],
                    None => sub.links[j],
                };
                let links = sub.links.iter().enumerate();
                let links = links.map(|(j, &i)| (world(j), &s.links[i], &s.link_dofs[i]));
                LinksAlong::of(links, &d.direction)
            })
            .collect();
        if !self.ranks.all(parts.iter().all(Option::is_some)) {
            return None;
        }
        let parts: Vec<LinksAlong> = parts.into_iter().flatten().collect();
        let stretches: Vec<f64> = parts.iter().map(|p| p.stretch).collect();
        let stretch: f64 = self.ranks.gather(&stretches).iter().sum();
        // (link index, id's upper and lower 32 bits): exact in f64.
        let split = |id: u64| [(id >> 32) as f64, (id & 0xffff_ffff) as f64];
        let mine: Vec<f64> = parts
            .iter()
            .flat_map(|p| &p.slack)
            .flat_map(|&(i, id)| {
                let [high, low] = split(id);
                [i as f64, high, low]
            })
            .collect();
        let mut slack: Vec<(usize, u64)> = self
            .ranks
            .gather(&mine)
            .chunks_exact(3)
            .map(|c| (c[0] as usize, ((c[1] as u64) << 32) | c[2] as u64))
            .collect();
        slack.sort_unstable();
        d.certificate(
            self.model,
            stretch,
            slack.into_iter().map(|(_, id)| id).collect(),
            load,
        )
    }
}
