//! What a rank sends to each neighbouring rank after a linear stage, and what it reads back
//! (issue 25): point to point, in place of an all-gather of s. Between two status steps a
//! rank reads, of the substructures other ranks hold, only
//! - the far side's U and F of each interface between them (the interface's local stage
//!   reads both sides),
//! - their U at the dofs its own substructures share with them (r(U) averages U there), and
//! - their pieces of r(U) at those dofs (a shared dof's forces are summed over the
//!   substructures holding it, in their order).
//!
//! A status step needs no more: each rank classifies its own links, and the line search adds
//! the substructures' parts (`status_step.rs`). Only the answer is gathered whole
//! (`Latin::share_whole_state`). Both ranks of a pair build the same lists from the partition,
//! which every rank knows: what one packs, the other unpacks in the same order.

use super::dof_ownership::DofOwnership;
use super::state::SubState;
use super::{block, Exchange, Interface, Substructure};
use std::ops::Range;

/// r(U)'s pieces per shared dof: `Bᵀτ`, `|B|ᵀ|τ|` and `Bᵀ(τ_frozen − τ)`.
pub(super) const PIECES_PER_DOF: usize = 4;

/// One substructure's values for a neighbouring rank.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Item {
    /// The substructure.
    sub: usize,
    /// Its local dofs the other rank's substructures hold too (positions in its shared dofs'
    /// list, [`DofOwnership::shared_local`], and the local dofs themselves).
    shared: Vec<(u32, u32)>,
    /// Its sides (slots in `sides`) whose interface's other substructure the other rank holds.
    sides: Vec<usize>,
}

/// What passes between this rank and one neighbouring rank.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Neighbour {
    rank: usize,
    /// Of this rank's substructures, what the neighbour reads.
    send: Vec<Item>,
    /// Of the neighbour's substructures, what this rank reads.
    receive: Vec<Item>,
}

/// A rank's point-to-point exchanges, with each neighbouring rank in increasing order.
#[derive(Debug, Clone, Default)]
pub(super) struct NeighbourPlan {
    neighbours: Vec<Neighbour>,
}

impl NeighbourPlan {
    /// The plan of rank `rank` of `ranks`, each holding its [`block`] of `substructures`.
    pub(super) fn new(
        substructures: &[Substructure],
        interfaces: &[Interface],
        ownership: &DofOwnership,
        rank: usize,
        ranks: usize,
    ) -> NeighbourPlan {
        let n = substructures.len();
        let blocks: Vec<Range<usize>> = (0..ranks).map(|r| block(r, ranks, n)).collect();
        let rank_of = |e: usize| blocks.iter().position(|b| b.contains(&e)).unwrap_or(0);
        // Per shared dof (by slot), the ranks holding it.
        let mut holder_ranks: Vec<Vec<usize>> = vec![Vec::new(); ownership.n_shared];
        for (e, sub) in substructures.iter().enumerate() {
            let r = rank_of(e);
            for &k in &ownership.shared_local[e] {
                let ranks = &mut holder_ranks[ownership.slot(sub.dof_global[k as usize])];
                if !ranks.contains(&r) {
                    ranks.push(r);
                }
            }
        }
        // What rank `from` sends rank `to`.
        let items = |from: usize, to: usize| -> Vec<Item> {
            blocks[from]
                .clone()
                .filter_map(|e| {
                    let sub = &substructures[e];
                    let shared: Vec<(u32, u32)> = ownership.shared_local[e]
                        .iter()
                        .enumerate()
                        .filter(|(_, &k)| {
                            holder_ranks[ownership.slot(sub.dof_global[k as usize])].contains(&to)
                        })
                        .map(|(position, &k)| (position as u32, k))
                        .collect();
                    let sides: Vec<usize> = sub
                        .sides
                        .iter()
                        .enumerate()
                        .filter(|(_, side)| {
                            let other = interfaces[side.interface].topology.sides[1 - side.which];
                            blocks[to].contains(&other)
                        })
                        .map(|(slot, _)| slot)
                        .collect();
                    (!shared.is_empty() || !sides.is_empty()).then_some(Item {
                        sub: e,
                        shared,
                        sides,
                    })
                })
                .collect()
        };
        let neighbours = (0..ranks)
            .filter(|&q| q != rank)
            .map(|q| Neighbour {
                rank: q,
                send: items(rank, q),
                receive: items(q, rank),
            })
            .filter(|nb| !nb.send.is_empty() || !nb.receive.is_empty())
            .collect();
        NeighbourPlan { neighbours }
    }

    /// The neighbouring ranks, increasing.
    #[cfg(test)]
    pub(super) fn ranks(&self) -> Vec<usize> {
        self.neighbours.iter().map(|nb| nb.rank).collect()
    }

    /// Values sent per iteration, all neighbours together: U and r(U)'s pieces per shared
    /// dof, U and F per side row (what `RankLayout` counts from the partition alone).
    #[cfg(test)]
    pub(super) fn values_sent(&self, substructures: &[Substructure]) -> usize {
        self.neighbours
            .iter()
            .flat_map(|nb| &nb.send)
            .map(|item| {
                (1 + PIECES_PER_DOF) * item.shared.len()
                    + item
                        .sides
                        .iter()
                        .map(|&slot| 2 * substructures[item.sub].sides[slot].rows)
                        .sum::<usize>()
            })
            .sum()
    }

    /// To each neighbour, the values `pack` gives of each item it reads (in order); from
    /// each, in the same order as `neighbours`, what it sent.
    fn send_items(
        &self,
        exchange: &dyn Exchange,
        pack: impl Fn(&Item, &mut Vec<f64>),
    ) -> Vec<Vec<f64>> {
        let sends = self.neighbours.iter().map(|nb| {
            let mut values = Vec::new();
            nb.send.iter().for_each(|item| pack(item, &mut values));
            (nb.rank, values)
        });
        exchange.exchange_with(sends.collect())
    }

    /// After a linear stage: to each neighbour, this rank's U at the dofs it shares with it
    /// and its sides' U and F on the interfaces between them; from each, the same of its
    /// substructures, written into `state`.
    pub(super) fn share_s(&self, exchange: &dyn Exchange, state: &mut [SubState]) {
        let received = self.send_items(exchange, |item, values| {
            let st = &state[item.sub];
            values.extend(item.shared.iter().map(|&(_, k)| st.u[k as usize]));
            for &slot in &item.sides {
                values.extend_from_slice(&st.sides[slot].u);
                values.extend_from_slice(&st.sides[slot].f);
            }
        });
        for (nb, values) in self.neighbours.iter().zip(received) {
            let mut rest = values.as_slice();
            let mut take = |into: &mut [f64]| {
                let (values, tail) = rest.split_at(into.len().min(rest.len()));
                into[..values.len()].copy_from_slice(values);
                rest = tail;
            };
            for item in &nb.receive {
                let st = &mut state[item.sub];
                for &(_, k) in &item.shared {
                    take(std::slice::from_mut(&mut st.u[k as usize]));
                }
                for &slot in &item.sides {
                    take(&mut st.sides[slot].u);
                    take(&mut st.sides[slot].f);
                }
            }
        }
    }

    /// r(U)'s pieces at shared dofs ([`PIECES_PER_DOF`] per dof; of a held substructure
    /// `mine(e)` gives them in its shared dofs' order): to each neighbour those at the dofs
    /// it shares, from each its own, as `(substructure, position in its shared dofs, pieces)`.
    pub(super) fn share_pieces<'a>(
        &self,
        exchange: &dyn Exchange,
        mine: impl Fn(usize) -> &'a [f64],
    ) -> Vec<(usize, u32, [f64; PIECES_PER_DOF])> {
        let received = self.send_items(exchange, |item, values| {
            let pieces = mine(item.sub);
            for &(position, _) in &item.shared {
                let at = position as usize * PIECES_PER_DOF;
                values.extend_from_slice(&pieces[at..at + PIECES_PER_DOF]);
            }
        });
        let mut out = Vec::new();
        for (nb, values) in self.neighbours.iter().zip(received) {
            let mut chunks = values.chunks_exact(PIECES_PER_DOF);
            for item in &nb.receive {
                for &(position, _) in &item.shared {
                    let mut v = [0.0; PIECES_PER_DOF];
                    if let Some(chunk) = chunks.next() {
                        v.copy_from_slice(chunk);
                    }
                    out.push((item.sub, position, v));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests;
