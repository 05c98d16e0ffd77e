//! How soft a slack cable's search direction is (docs/method.md §9, "How soft a slack cable's
//! l"): ε_soft·k where both its nodes stay held without it, ε·k where not. The softer l is
//! closer to a slack cable's zero stiffness, so that the end of a run goes at the rate of the
//! structure without its slack cables; but where slack cables are what holds a node, ε_soft
//! leaves K_E nearly singular there.

use super::{Latin, SLACK_SEARCH_FACTOR};
use crate::structure::CLAMPED;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// ε_soft: a slack cable's search direction, relative to its k, where both its nodes stay
/// held without it. 1e-3 took the default partition's 256 × 256 / 512 × 512 cases from 100 /
/// 157 to 92 / 132 iterations (docs/journal/2026-11.md, 2026-11-29).
pub(super) const SOFT_SLACK_SEARCH_FACTOR: f64 = 1e-3;

/// ε_soft only in substructures of at least this many links (2 × 2 modules of the paper's
/// grid): on one-module substructures (16 links) it lifted micro-macro's round-off floor of
/// r(U), 2.5e-8 there with ε, above 1e-7 (a 3 × 3 grid on partial supports, `tests/general.rs`).
pub(super) const SOFT_MIN_LINKS: usize = 64;

/// A node stays held without its slack cables when the stiffness its substructure gives it
/// without them, `A = Σ k n nᵀ` over its bars and taut cables, plus `d_m I` on an interface
/// and the clamped components, is at least this fraction of the slack cable's k in every
/// direction (the smallest eigenvalue of A): then ε_soft·k adds little to what holds it.
pub(super) const HELD_FRACTION: f64 = 0.1;

impl Latin<'_> {
    /// Per link, the factor of its search direction for the slack set `slack`: 1 on bars
    /// and taut cables; on a slack cable [`SOFT_SLACK_SEARCH_FACTOR`] where each of its nodes
    /// stays held without it in its substructure ([`HELD_FRACTION`]), else
    /// [`SLACK_SEARCH_FACTOR`]; ε on substructures of fewer than [`SOFT_MIN_LINKS`] links.
    /// Decided within each substructure, by the rank that holds it (the others' cables keep
    /// ε: a rank builds only its own substructures' operators). With one substructure
    /// (mono-latin), ε everywhere: at ε_soft mono-latin ran away on the skew grid at α = 2
    /// (142 slack cables for 30, 1000 iterations).
    pub(super) fn slack_factors(&self, slack: &[bool]) -> Vec<f64> {
        let links = &self.structure.links;
        let mut factors: Vec<f64> = slack
            .iter()
            .map(|&s| if s { SLACK_SEARCH_FACTOR } else { 1.0 })
            .collect();
        if self.interfaces.list.is_empty() {
            return factors;
        }
        let soft: Vec<Vec<usize>> = self.operators.substructures[self.ranks.held()]
            .par_iter()
            .filter(|sub| sub.links.len() >= SOFT_MIN_LINKS)
            .map(|sub| {
                let interface: HashSet<usize> =
                    sub.gamma_dofs.iter().map(|&d| sub.dof_global[d]).collect();
                let held = self.held_stiffness(&sub.links, slack, &interface);
                let stays_held = |node: usize, k: f64| held[&node] >= HELD_FRACTION * k;
                sub.links
                    .iter()
                    .copied()
                    .filter(|&i| {
                        let l = &links[i];
                        slack[i] && stays_held(l.a, l.stiffness) && stays_held(l.b, l.stiffness)
                    })
                    .collect()
            })
            .collect();
        for i in soft.into_iter().flatten() {
            factors[i] = SOFT_SLACK_SEARCH_FACTOR;
        }
        factors
    }

    /// Per node of a substructure's links `sub_links`: the smallest eigenvalue of the
    /// stiffness that holds it without the cables of `slack`, `A = Σ k n nᵀ` over its bars and
    /// taut cables, plus d_m on the components in `interface` (K_E's `d_m C_Eᵀ C_E`), with its
    /// clamped components removed (held rigidly).
    fn held_stiffness(
        &self,
        sub_links: &[usize],
        slack: &[bool],
        interface: &HashSet<usize>,
    ) -> HashMap<usize, f64> {
        let (links, dof_of) = (&self.structure.links, &self.structure.dof_of);
        let mut stiffness: HashMap<usize, Matrix3<f64>> = HashMap::new();
        for &i in sub_links {
            let l = &links[i];
            let n = Vector3::from(l.direction);
            // A += k n nᵀ for a bar or a taut cable.
            let k = if slack[i] { 0.0 } else { l.stiffness };
            for node in [l.a, l.b] {
                *stiffness.entry(node).or_insert_with(Matrix3::zeros) += k * n * n.transpose();
            }
        }
        stiffness
            .into_iter()
            .map(|(node, mut a)| {
                let dofs: [usize; 3] = std::array::from_fn(|c| dof_of[3 * node + c]);
                let free: Vec<usize> = (0..3).filter(|&c| dofs[c] != CLAMPED).collect();
                for &c in &free {
                    if interface.contains(&dofs[c]) {
                        a[(c, c)] += self.world.dm;
                    }
                }
                // The smallest eigenvalue of A on the free components (∞ when all are held).
                let smallest = match free.len() {
                    0 => f64::INFINITY,
                    _ => {
                        let sub = a.select_rows(&free).select_columns(&free);
                        sub.symmetric_eigenvalues().min()
                    }
                };
                (node, smallest)
            })
            .collect()
    }
}
