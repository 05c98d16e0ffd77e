//! Status-following search directions (docs/method.md §6): when the cables' status asks for
//! it, l becomes ε·l on the slack cables (how small ε is: `slack_direction`) and the operators
//! of the substructures where l changed are rebuilt (each rank those it holds), then the
//! macro problem.

use super::operators::share_homogenised;
use super::{Latin, LatinState, SearchPolicy, SubState, STATUS_BAND, STATUS_PERSISTENCE};
use crate::model::material;
use rayon::prelude::*;

impl Latin<'_> {
    /// Status-following l, when the policy asks for it: the cables to make slack in new search
    /// directions, for which the operators are to be rebuilt.
    pub(super) fn status_to_follow(&self, state: &mut LatinState) -> Option<Vec<bool>> {
        (self.settings.policy == SearchPolicy::Status)
            .then(|| self.follow_status(state))
            .flatten()
    }

    /// The one change an iteration makes to the solver: its operators rebuilt for the search
    /// directions that make `slack` slack (status-following l). `true` when rebuilt, which
    /// restarts relaxation and acceleration (the old s was computed with another l).
    pub(super) fn rebuild_for(&mut self, slack: Option<Vec<bool>>, state: &mut LatinState) -> bool {
        let Some(slack) = slack else {
            return false;
        };
        let rebuilt = self.set_search(slack);
        if rebuilt {
            Self::followed(state);
            state.rebuilds += 1;
            state.acceleration.relax = false;
        }
        rebuilt
    }

    /// Status-following l (docs/method.md §6): l for bars and taut cables, ε·l for slack ones, when at
    /// least `update_threshold` cables changed status since the operators were built: the
    /// cables to make slack, for which the caller rebuilds the operators. A cable's status is read from the linear stage's
    /// trial tension `τ = t0 + k e` (newton's active set; the slack set of ŝ would keep a
    /// taut cable held at ε·l slack, since with l ≪ k its local stage barely moves), with a
    /// band: it goes slack below −δ and taut above +δ, δ = `STATUS_BAND` × the RMS trial
    /// tension of the cables, so that cables near zero tension do not flip back and forth
    /// (l is a search direction: any choice converges, only the rate changes). A cable's l
    /// changes only once its status has differed for [`STATUS_PERSISTENCE`] linear stages in a
    /// row.
    pub(super) fn follow_status(&self, state: &mut LatinState) -> Option<Vec<bool>> {
        let links = &self.structure.links;
        let (trial, rms) = self.trial_tensions(&state.subs);
        let band = STATUS_BAND * rms;
        let mut slack = self.search.slack.clone();
        for (i, (l, &tau)) in links.iter().zip(&trial).enumerate() {
            let was_slack = self.search.slack[i];
            let is_slack = l.unilateral && if was_slack { tau <= band } else { tau < -band };
            let streak = &mut state.following.status_streak[i];
            *streak = if is_slack == was_slack {
                0
            } else {
                streak.saturating_add(1)
            };
            if *streak >= STATUS_PERSISTENCE {
                slack[i] = is_slack;
            }
        }
        let changed = slack
            .iter()
            .zip(&self.search.slack)
            .filter(|(a, b)| a != b)
            .count();
        (changed >= self.settings.update_threshold.max(1)).then_some(slack)
    }

    /// After the rebuild [`Latin::follow_status`] asked for: the cables whose l just changed
    /// start counting afresh.
    pub(super) fn followed(state: &mut LatinState) {
        for streak in &mut state.following.status_streak {
            if *streak >= STATUS_PERSISTENCE {
                *streak = 0;
            }
        }
    }

    /// Every link's trial tension `t0 + k e` from the linear stage's e, and the RMS of the
    /// cables' (the scale of the status bands).
    pub(super) fn trial_tensions(&self, subs: &[SubState]) -> (Vec<f64>, f64) {
        let links = &self.structure.links;
        let mut trial = vec![0.0; links.len()];
        for (sub, st) in self.operators.substructures.iter().zip(subs) {
            for (j, &i) in sub.links.iter().enumerate() {
                trial[i] = material::trial_tension(&links[i], st.e[j]);
            }
        }
        let (sum2, cables) = links
            .iter()
            .zip(&trial)
            .filter(|(l, _)| l.unilateral)
            .fold((0.0, 0usize), |(s, n), (_, t)| (s + t * t, n + 1));
        (trial, (sum2 / cables.max(1) as f64).sqrt())
    }

    /// Whether any cable has its search direction at ε·l, on any process (each knows its own
    /// substructures' cables).
    pub(super) fn any_search_slack(&self) -> bool {
        let held = &self.operators.substructures[self.ranks.held()];
        let mine = held
            .iter()
            .any(|sub| sub.links.iter().any(|&i| self.search.slack[i]));
        !self.ranks.all(!mine)
    }

    /// New operators with ε·l on the cables of `slack`: the substructures where l changed,
    /// then the macro problem. On failure (a substructure left without stiffness, or a
    /// singular macro problem) the operators of the current directions are rebuilt and kept.
    /// `true` when rebuilt.
    pub(super) fn set_search(&mut self, slack: Vec<bool>) -> bool {
        let mut search = self.search.base.clone();
        for (l, factor) in search.iter_mut().zip(self.slack_factors(&slack)) {
            *l *= factor;
        }
        // Each process knows the status of its own substructures' links: the changed ones
        // are gathered from the ranks that hold them.
        let held_changed: Vec<usize> = self
            .ranks
            .held()
            .filter(|&e| {
                self.operators.substructures[e]
                    .links
                    .iter()
                    .any(|&i| search[i] != self.search.now[i])
            })
            .collect();
        let changed: Vec<usize> = match self.ranks.size() {
            1 => held_changed,
            _ => {
                let mine: Vec<f64> = held_changed.iter().map(|&e| e as f64).collect();
                let all = self.ranks.gather(&mine);
                all.into_iter().map(|e| e as usize).collect()
            }
        };
        if self.rebuild(&changed, &search) {
            self.search.now = search;
            self.search.slack = slack;
            return true;
        }
        // Back to the current directions: the inputs the operators were last built from, so
        // the same operators, bit for bit. Should that fail all the same, the solve cannot go
        // on (`operators_lost`: it stops as stalled).
        let current = std::mem::take(&mut self.search.now);
        self.operators.lost |= !self.rebuild(&changed, &current);
        self.search.now = current;
        false
    }

    /// The operators of the substructures `changed` rebuilt in place for the directions
    /// `search` (each rank those it holds; the rebuild stands only if it succeeded on all),
    /// their L_E shared, and the macro problem refactorised; with soft interface modes, the
    /// modes retaken where stale and the substructures on their interfaces condensed on the
    /// new bases (those only refactorized here). `false` on failure, when the changed
    /// substructures' operators are left unusable.
    fn rebuild(&mut self, changed: &[usize], search: &[f64]) -> bool {
        let (dm, storage, held) = (self.world.dm, self.operators.storage, self.ranks.held());
        let plan = self.plan_enrichment(changed, search);
        let condensed_later: &[usize] = plan.as_ref().map_or(&[], |p| &p.affected);
        let rebuilt = self
            .operators
            .substructures
            .par_iter_mut()
            .enumerate()
            .filter(|(e, _)| held.contains(e) && changed.binary_search(e).is_ok())
            .map(|(e, sub)| match condensed_later.binary_search(&e) {
                Ok(_) => sub.refactor(search, dm, storage),
                Err(_) => sub.set_search(search, dm, storage),
            })
            .collect::<Result<Vec<()>, _>>()
            .is_ok();
        if !self.ranks.all(rebuilt) {
            return false;
        }
        let condensed_now: Vec<usize> = changed
            .iter()
            .filter(|e| condensed_later.binary_search(e).is_err())
            .copied()
            .collect();
        share_homogenised(
            &mut self.operators.substructures,
            &condensed_now,
            self.ranks.exchange(),
            &held,
        );
        if let Some(plan) = plan {
            // The soft modes of the stale substructures, and the macro problem anew.
            return self.enrich(plan).is_ok();
        }
        match self
            .operators
            .macro_problem
            .refactor(&self.operators.substructures, &self.interfaces.list)
        {
            Ok(macro_problem) => {
                self.operators.macro_problem = macro_problem;
                true
            }
            Err(_) => false,
        }
    }
}
