//! How micro-macro's substructures lie on P ranks (issue 25): contiguous blocks of the
//! partition, row by row, so that most interfaces stay inside a rank; what each rank holds and
//! what crosses between ranks at each iteration. Topology only: nothing is factorized.
//!
//! After each linear stage a rank sends each neighbouring rank, point to point
//! (`neighbours.rs`), its U at the dofs their substructures share and its sides' U and F on
//! the interfaces between them, then its pieces of r(U) at those dofs. What is still gathered
//! from every rank per iteration is small and per substructure: the macro right-hand side's
//! parts (every rank solves the macro problem), the parts of η, of r(U)'s norms, of the slack
//! count and of Anderson's inner products, and at a status step the parts of its line search.
//! The answer is gathered whole where the driver reads it: at its no-equilibrium checks
//! (iterations 16, 32, 64, …) and at the end.

use super::{LatinSettings, Partition};
use crate::decomposition::interfaces::Interfaces;
use crate::structure::Structure;
use std::ops::Range;

/// Values sent per shared dof and iteration: U and r(U)'s four pieces (`Bᵀτ`, `|B|ᵀ|τ|`,
/// `Bᵀ(τ_frozen − τ)`, `|B|ᵀ|τ − t0|`).
pub const VALUES_PER_SHARED_DOF: usize = 5;

/// Values sent per interface row and iteration: the side's U and F.
pub const VALUES_PER_ROW: usize = 2;

/// One rank's share.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RankShare {
    /// Its substructures (row-by-row indices of the partition).
    pub substructures: Range<usize>,
    /// Links of its substructures.
    pub links: usize,
    /// Ranks it shares an interface with, increasing.
    pub neighbours: Vec<usize>,
    /// Values it sends per iteration to its neighbours, point to point: per dof one of its
    /// substructures shares with a neighbour's, [`VALUES_PER_SHARED_DOF`]; per row of an
    /// interface between them, [`VALUES_PER_ROW`].
    pub values_sent: usize,
    /// Values it receives per iteration in the solve's all-gathers, from every other rank's
    /// substructures: the macro right-hand side's parts (one per macro dof; kernel amplitudes
    /// left out), η's parts, the slack count, r(U)'s sums of squares, and Anderson's inner
    /// products with a full history.
    pub values_gathered: usize,
    /// Values it receives each time the answer is gathered whole (the driver's no-equilibrium
    /// checks at iterations 16, 32, 64, … and the end): U per dof, and the tension and the
    /// slack flag per link, of every other rank's substructures.
    pub values_per_answer: usize,
}

/// The layout of a micro-macro partition over P ranks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RankLayout {
    /// The partition, substructures along x and y.
    pub subdomains: [usize; 2],
    /// Per rank, its share.
    pub ranks: Vec<RankShare>,
    /// Interfaces of the partition.
    pub interfaces: usize,
    /// Interfaces whose two substructures lie on different ranks.
    pub crossing_interfaces: usize,
    /// Macro forces: the macro right-hand side reduced over the ranks at each iteration.
    pub macro_forces: usize,
}

impl RankLayout {
    /// The layout of `settings`' partition of `structure` over `ranks` ranks (at least 1, and
    /// no more than the substructures: the extra ranks would hold nothing).
    pub fn new(structure: &Structure, settings: &LatinSettings, ranks: usize) -> RankLayout {
        let partition = Partition::new(structure, settings.subdomains, settings.weak);
        let degree = settings.macro_degree_on(structure.links.len(), partition.substructures.len());
        let interfaces = Interfaces::new(structure, &partition, settings.weak, degree);
        let n_subs = partition.substructures.len();
        let ranks = ranks.clamp(1, n_subs.max(1));
        // Rank r holds substructures [r n / P, (r + 1) n / P).
        let first = |r: usize| r * n_subs / ranks;
        let rank_of = |e: usize| (0..ranks).rfind(|&r| first(r) <= e).unwrap_or(0);
        let mut shares: Vec<RankShare> = (0..ranks)
            .map(|r| {
                let substructures = first(r)..first(r + 1);
                let links = partition.substructures[substructures.clone()]
                    .iter()
                    .map(|t| t.links.len())
                    .sum();
                RankShare {
                    substructures,
                    links,
                    neighbours: Vec::new(),
                    values_sent: 0,
                    values_gathered: 0,
                    values_per_answer: 0,
                }
            })
            .collect();
        let mut crossing = 0;
        for iface in &interfaces.list {
            let [a, b] = iface.topology.sides.map(rank_of);
            if a == b {
                continue;
            }
            crossing += 1;
            let rows: usize = iface.free.iter().flatten().filter(|&&f| f).count();
            shares[a].values_sent += VALUES_PER_ROW * rows;
            shares[b].values_sent += VALUES_PER_ROW * rows;
        }
        // A node several substructures hold: each holder sends each other rank holding it its
        // U and r(U)'s pieces there (once per rank, however many of its substructures hold it).
        let mut holders: Vec<Vec<usize>> = vec![Vec::new(); structure.n_nodes()];
        for (e, topo) in partition.substructures.iter().enumerate() {
            topo.nodes.iter().for_each(|&n| holders[n].push(e));
        }
        for (n, subs) in holders.iter().enumerate().filter(|(_, h)| h.len() > 1) {
            let free = structure.held_components(n).iter().filter(|&&h| !h).count();
            let node_ranks: Vec<usize> = subs.iter().map(|&e| rank_of(e)).collect();
            for &from in &node_ranks {
                let mut to: Vec<usize> =
                    node_ranks.iter().copied().filter(|&q| q != from).collect();
                to.dedup();
                for q in to {
                    shares[from].values_sent += VALUES_PER_SHARED_DOF * free;
                    if !shares[from].neighbours.contains(&q) {
                        shares[from].neighbours.push(q);
                    }
                }
            }
        }
        shares.iter_mut().for_each(|s| s.neighbours.sort_unstable());
        let (gathered, whole) =
            gathered_per_substructure(structure, &partition, &interfaces, settings.anderson);
        let total: usize = gathered.iter().sum();
        let total_whole: usize = whole.iter().sum();
        for share in &mut shares {
            let mine = share.substructures.clone();
            share.values_gathered = total - gathered[mine.clone()].iter().sum::<usize>();
            share.values_per_answer = total_whole - whole[mine].iter().sum::<usize>();
        }
        RankLayout {
            subdomains: settings.subdomains,
            ranks: shares,
            interfaces: interfaces.list.len(),
            crossing_interfaces: crossing,
            macro_forces: interfaces.list.iter().map(|i| i.basis.ncols()).sum(),
        }
    }

    /// Values sent between ranks per iteration, all ranks together.
    pub fn values_exchanged(&self) -> usize {
        self.ranks.iter().map(|r| r.values_sent).sum()
    }

    /// The layout as `check` prints it.
    pub fn describe(&self) -> String {
        let kb = |values: usize| (8 * values) as f64 / 1024.0;
        let mut out = format!(
            "ranks: {} (micro-macro, {} substructures of the {} x {} partition in contiguous \
             blocks, row by row)\n",
            self.ranks.len(),
            self.ranks.last().map_or(0, |r| r.substructures.end),
            self.subdomains[0],
            self.subdomains[1],
        );
        for (r, share) in self.ranks.iter().enumerate() {
            let neighbours: Vec<String> = share.neighbours.iter().map(|n| n.to_string()).collect();
            out += &format!(
                "  rank {r}: substructures {}..{} ({}), {} links, neighbours [{}]; per \
                 iteration sends {} values ({:.1} KiB) point to point and receives {} ({:.1} \
                 KiB) in all-gathers; {} values ({:.1} KiB) each time the answer is gathered\n",
                share.substructures.start,
                share.substructures.end,
                share.substructures.len(),
                share.links,
                neighbours.join(", "),
                share.values_sent,
                kb(share.values_sent),
                share.values_gathered,
                kb(share.values_gathered),
                share.values_per_answer,
                kb(share.values_per_answer),
            );
        }
        out += &format!(
            "  per iteration, point to point between neighbouring ranks: {} values ({:.1} KiB) \
             over {} of {} interfaces (U and F per interface row, U and r(U)'s 4 pieces per \
             shared dof); gathered from every rank: the macro right-hand side ({} values, \
             solved on every rank) and per substructure the parts of η, r(U) and Anderson's \
             inner products (at a status step, its line search's parts); the answer is gathered whole \
             at the no-equilibrium checks (iterations 16, 32, 64, ...) and at the end\n",
            self.values_exchanged(),
            kb(self.values_exchanged()),
            self.crossing_interfaces,
            self.interfaces,
            self.macro_forces,
        );
        out
    }
}

/// Per substructure, the values it contributes to an iteration's all-gathers (one macro
/// right-hand side part per macro dof, η's two parts, the slack count, r(U)'s three sums of
/// squares, Anderson's inner products), and to a gather of the answer whole (U per free dof,
/// the tension and the slack flag per link).
fn gathered_per_substructure(
    structure: &Structure,
    partition: &Partition,
    interfaces: &Interfaces,
    anderson: usize,
) -> (Vec<usize>, Vec<usize>) {
    let mut input = vec![0usize; partition.substructures.len()];
    let mut whole = vec![0usize; partition.substructures.len()];
    let mut gathered: Vec<usize> = partition
        .substructures
        .iter()
        .zip(&mut input)
        .zip(&mut whole)
        .map(|((topo, input), whole)| {
            *input = topo.links.len();
            *whole = 2 * topo.links.len() + topo.free_dofs(structure);
            6
        })
        .collect();
    for iface in &interfaces.list {
        let rows: usize = iface.free.iter().flatten().filter(|&&f| f).count();
        for &e in &iface.topology.sides {
            gathered[e] += iface.basis.ncols();
            input[e] += rows;
        }
    }
    // Anderson's two inner products with each of its differences (a full history of
    // `anderson`, and the new one) per chunk of the substructure's input.
    for (g, n) in gathered.iter_mut().zip(&input) {
        *g += 2 * (anderson + 1) * n.div_ceil(crate::linalg::CHUNK).max(1);
    }
    (gathered, whole)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::{GridSpec, LoadPattern};

    /// The paper's grid in 4 × 4 substructures over 1, 2, 4 and 16 ranks.
    #[test]
    fn contiguous_blocks_share_the_links_and_exchange_symmetrically() {
        let s = Structure::grid(&GridSpec::default(), &LoadPattern::default());
        let settings = LatinSettings::default();
        assert_eq!(settings.subdomains, [4, 4]);
        let one = RankLayout::new(&s, &settings, 1);
        assert_eq!(one.ranks.len(), 1);
        assert_eq!(one.ranks[0].substructures, 0..16);
        assert_eq!(one.ranks[0].links, s.links.len());
        assert_eq!((one.crossing_interfaces, one.values_exchanged()), (0, 0));
        assert_eq!(one.ranks[0].values_gathered, 0, "one rank gathers nothing");
        assert!(one.ranks[0].neighbours.is_empty());

        for p in [2, 4, 16] {
            let layout = RankLayout::new(&s, &settings, p);
            assert_eq!(layout.ranks.len(), p);
            assert_eq!(layout.interfaces, one.interfaces);
            assert_eq!(layout.macro_forces, one.macro_forces);
            let links: usize = layout.ranks.iter().map(|r| r.links).sum();
            assert_eq!(links, s.links.len(), "every link on one rank");
            for (r, share) in layout.ranks.iter().enumerate() {
                assert_eq!(share.substructures.len(), 16 / p);
                // Every module of the grid has the same links: a rank's share is its modules'.
                assert_eq!(share.links, s.links.len() / p);
                for &n in &share.neighbours {
                    assert!(
                        layout.ranks[n].neighbours.contains(&r),
                        "neighbours both ways"
                    );
                }
            }
            // Every rank receives what the others' substructures contribute: all ranks
            // together P − 1 times what one rank holding them all would gather (per
            // iteration, and for the answer).
            let two = RankLayout::new(&s, &settings, 2);
            for field in [
                |r: &RankShare| r.values_gathered,
                |r: &RankShare| r.values_per_answer,
            ] {
                let gathered: usize = layout.ranks.iter().map(field).sum();
                let of_two: usize = two.ranks.iter().map(field).sum();
                assert_eq!(gathered, (p - 1) * of_two, "{p} ranks");
            }
            let sent: usize = layout.ranks.iter().map(|r| r.values_sent).sum();
            assert_eq!(sent, layout.values_exchanged());
            // Point to point is the small part: less than a gather of the answer.
            for share in &layout.ranks {
                assert!(share.values_sent > 0 && share.values_sent < share.values_per_answer);
            }
        }
        // One row of substructures per rank: each rank touches only the rows next to it, and
        // an inner rank sends twice what an end rank sends (two boundaries against one).
        let four = RankLayout::new(&s, &settings, 4);
        assert_eq!(four.ranks[0].neighbours, vec![1]);
        assert_eq!(four.ranks[1].neighbours, vec![0, 2]);
        assert_eq!(four.ranks[3].neighbours, vec![2]);
        assert_eq!(four.ranks[1].values_sent, 2 * four.ranks[0].values_sent);
        assert_eq!(four.ranks[2].values_sent, four.ranks[1].values_sent);
        // Two rows per rank on two ranks: one boundary, as long as one of the four-rank ones.
        let two = RankLayout::new(&s, &settings, 2);
        assert_eq!(two.ranks[0].values_sent, four.ranks[0].values_sent);
        // More ranks than substructures: the extra ones would hold nothing, so there are none.
        assert_eq!(RankLayout::new(&s, &settings, 40).ranks.len(), 16);
    }
}
