//! What a LATIN solve shared by several processes (MPI ranks, issue 25) needs of them, so that
//! the solver itself knows no MPI: the app passes an [`Exchange`] over its ranks, a library
//! caller [`OneProcess`].
//!
//! Each rank holds a contiguous block of the partition's substructures ([`block`]): it builds
//! their operators (K_E's factor, Z_E, K*_E, K⁺_E) and runs their halves of the linear stage.
//! What the others need of them is gathered: L_E and Q_E at set-up and at each rebuild (the
//! macro matrix, factorised on every rank), each substructure's part of the macro right-hand
//! side (summed on every rank in the substructures' order, so that every rank and a run on one
//! process add the same numbers in the same order), and the sums of η, r(U), Anderson's inner
//! products and the slack count. After each linear stage a rank sends its neighbouring ranks
//! what they read of its substructures (`neighbours.rs`, point to point); a status step
//! classifies each rank's own links and adds the substructures' parts of its line search; the
//! answer is gathered whole. A solve whose every iteration reads the whole state
//! (status-following l, or r(U) with the prestress's geometric stiffness) gathers s whole
//! after each linear stage.

use std::ops::Range;

/// The collective operations of the processes that share a solve. Every rank calls each
/// operation in the same order.
pub trait Exchange: Sync {
    /// This process's rank, 0 … size − 1.
    fn rank(&self) -> usize;
    /// How many processes share the solve.
    fn size(&self) -> usize;
    /// Every rank's `mine`, concatenated in rank order, on every rank.
    fn all_gather(&self, mine: &[f64]) -> Vec<f64>;
    /// Whether `value` holds on every rank (every rank learns the answer).
    fn all(&self, value: bool) -> bool;
    /// Point to point: to each rank of `sends` its values, and from each of them (in the same
    /// order) the values it sent this rank. Every rank named must name this one in turn.
    fn exchange_with(&self, sends: Vec<(usize, Vec<f64>)>) -> Vec<Vec<f64>>;
}

/// One process holds every substructure: nothing is exchanged.
#[derive(Debug, Clone, Copy, Default)]
pub struct OneProcess;

impl Exchange for OneProcess {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn all_gather(&self, mine: &[f64]) -> Vec<f64> {
        mine.to_vec()
    }
    fn all(&self, value: bool) -> bool {
        value
    }
    /// One process has no other rank to send to: nothing comes back.
    fn exchange_with(&self, sends: Vec<(usize, Vec<f64>)>) -> Vec<Vec<f64>> {
        sends.iter().map(|_| Vec::new()).collect()
    }
}

/// The substructures rank `rank` of `ranks` holds, of `n`: `[r n / P, (r + 1) n / P)` with
/// P = min(`ranks`, n), row by row of the partition (so that most interfaces stay inside a
/// rank); ranks beyond the P-th hold none.
pub fn block(rank: usize, ranks: usize, n: usize) -> Range<usize> {
    let p = ranks.clamp(1, n.max(1));
    if rank >= p {
        return n..n;
    }
    rank * n / p..(rank + 1) * n / p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocks of every rank cover 0..n once, in rank order.
    #[test]
    fn blocks_tile_the_substructures_in_rank_order() {
        for n in [0, 1, 3, 16, 17, 1024] {
            for ranks in 1..=6 {
                let mut next = 0;
                for r in 0..ranks {
                    let b = block(r, ranks, n);
                    assert_eq!(b.start, next, "n {n} P {ranks} rank {r}");
                    assert!(b.end >= b.start);
                    next = b.end;
                }
                assert_eq!(next, n, "n {n} P {ranks}");
                // No rank is left empty while another holds two, unless ranks > n.
                if ranks <= n {
                    assert!((0..ranks).all(|r| !block(r, ranks, n).is_empty()));
                }
            }
        }
    }
}
