//! Status-following search directions (docs/method.md §6): when the cables' status asks for
//! it, l becomes ε·l on the slack cables and the operators of the substructures where l
//! changed are rebuilt (each rank those it holds), then the macro problem.

use super::operators::share_homogenised;
use super::{
    Latin, LatinState, SubState, Substructure, SLACK_SEARCH_FACTOR, STATUS_BAND, STATUS_PERSISTENCE,
};
use crate::structure::law;
use nalgebra::DMatrix;
use rayon::prelude::*;

impl Latin<'_> {
    /// Status-following l (docs/method.md §6): l for bars and taut cables, ε·l for slack ones, when at
    /// least `update_threshold` cables changed status since the operators were built; then
    /// the operators are rebuilt for it. A cable's status is read from the linear stage's
    /// trial tension `τ = t0 + k e` (newton's active set; the slack set of ŝ would keep a
    /// taut cable held at ε·l slack, since with l ≪ k its local stage barely moves), with a
    /// band: it goes slack below −δ and taut above +δ, δ = `STATUS_BAND` × the RMS trial
    /// tension of the cables, so that cables near zero tension do not flip back and forth
    /// (l is a search direction: any choice converges, only the rate changes). A cable's l
    /// changes only once its status has differed for [`STATUS_PERSISTENCE`] linear stages in a
    /// row. `true` when rebuilt.
    pub(super) fn follow_status(&mut self, state: &mut LatinState) -> bool {
        let links = &self.structure.links;
        let (trial, rms) = self.trial_tensions(&state.subs);
        let band = STATUS_BAND * rms;
        let mut slack = self.search_slack.clone();
        for (i, (l, &tau)) in links.iter().zip(&trial).enumerate() {
            let was_slack = self.search_slack[i];
            let is_slack = l.unilateral && if was_slack { tau <= band } else { tau < -band };
            let streak = &mut state.status_streak[i];
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
            .zip(&self.search_slack)
            .filter(|(a, b)| a != b)
            .count();
        if changed < self.settings.update_threshold.max(1) {
            return false;
        }
        let rebuilt = self.set_search(slack);
        if rebuilt {
            // The cables whose l just changed start counting afresh.
            for streak in &mut state.status_streak {
                if *streak >= STATUS_PERSISTENCE {
                    *streak = 0;
                }
            }
        }
        rebuilt
    }

    /// Every link's trial tension `t0 + k e` from the linear stage's e, and the RMS of the
    /// cables' (the scale of the status bands).
    pub(super) fn trial_tensions(&self, subs: &[SubState]) -> (Vec<f64>, f64) {
        let links = &self.structure.links;
        let mut trial = vec![0.0; links.len()];
        for (sub, st) in self.substructures.iter().zip(subs) {
            for (j, &i) in sub.links.iter().enumerate() {
                trial[i] = law::trial_tension(&links[i], st.e[j]);
            }
        }
        let (sum2, cables) = links
            .iter()
            .zip(&trial)
            .filter(|(l, _)| l.unilateral)
            .fold((0.0, 0usize), |(s, n), (_, t)| (s + t * t, n + 1));
        (trial, (sum2 / cables.max(1) as f64).sqrt())
    }

    /// New operators with ε·l on the cables of `slack`: the substructures where l changed,
    /// then the macro problem. On failure (a substructure left without stiffness) the previous
    /// ones are kept. `true` when rebuilt.
    pub(super) fn set_search(&mut self, slack: Vec<bool>) -> bool {
        let mut search = self.base_search.clone();
        for (l, &is_slack) in search.iter_mut().zip(&slack) {
            if is_slack {
                *l *= SLACK_SEARCH_FACTOR;
            }
        }
        let changed: Vec<usize> = (0..self.substructures.len())
            .filter(|&e| {
                self.substructures[e]
                    .links
                    .iter()
                    .any(|&i| search[i] != self.search[i])
            })
            .collect();
        // Only l changed: each substructure keeps its pattern, symbolic analysis and kernel.
        // Each rank rebuilds those it holds; the rebuild stands only if it succeeded on all.
        let (dm, dense) = (self.dm, self.dense);
        let held: Vec<usize> = changed
            .iter()
            .copied()
            .filter(|e| self.held.contains(e))
            .collect();
        let rebuilt = held
            .par_iter()
            .map(|&e| self.substructures[e].with_search(&search, dm, dense))
            .collect::<Result<Vec<Substructure>, _>>();
        if !self.exchange.all(rebuilt.is_ok()) {
            return false;
        }
        let Ok(rebuilt) = rebuilt else {
            return false;
        };
        let mut substructures = std::mem::take(&mut self.substructures);
        let previous: Vec<(usize, Substructure)> = held
            .iter()
            .zip(rebuilt)
            .map(|(&e, sub)| (e, std::mem::replace(&mut substructures[e], sub)))
            .collect();
        // L_E and Q_E of the others' rebuilt substructures (the previous ones kept to undo).
        let remote: Vec<(usize, DMatrix<f64>, DMatrix<f64>)> = changed
            .iter()
            .filter(|e| !self.held.contains(e))
            .map(|&e| {
                let sub = &substructures[e];
                (e, sub.flexibility.clone(), sub.kernel.clone())
            })
            .collect();
        share_homogenised(&mut substructures, &changed, self.exchange, &self.held);
        match self
            .macro_problem
            .refactor(&substructures, &self.interfaces)
        {
            Ok(macro_problem) => {
                self.substructures = substructures;
                self.macro_problem = macro_problem;
                self.search = search;
                self.search_slack = slack;
                true
            }
            Err(_) => {
                for (e, sub) in previous {
                    substructures[e] = sub;
                }
                for (e, flexibility, kernel) in remote {
                    substructures[e].flexibility = flexibility;
                    substructures[e].kernel = kernel;
                }
                self.substructures = substructures;
                false
            }
        }
    }
}
