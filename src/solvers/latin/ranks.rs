//! How micro-macro's substructures would lie on P ranks (issue 25): contiguous blocks of the
//! partition, row by row, so that most interfaces stay inside a rank; what each rank holds and
//! what crosses between ranks at each iteration. Topology only: nothing is factorized.
//!
//! Today the solve all-gathers the fields of s each linear stage writes and the parts of the
//! macro right-hand side (`exchange.rs`): a rank receives those of every other rank's
//! substructures. Once the exchange is point to point, a rank will send, for every interface it
//! shares with another rank, three values per interface row (a free component of an interface
//! node): its side's U and F (the interface's local stage needs both sides) and its partial
//! sums of r(U) on the shared dofs; the macro right-hand side (one value per macro force)
//! reduced over all ranks.

use super::interfaces::Interfaces;
use super::{LatinSettings, Partition};
use crate::structure::Structure;
use std::ops::Range;

/// Values sent per interface row and iteration: U, F and r(U)'s partial sum.
pub const VALUES_PER_ROW: usize = 3;

/// One rank's share.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RankShare {
    /// Its substructures (row-by-row indices of the partition).
    pub substructures: Range<usize>,
    /// Links of its substructures.
    pub links: usize,
    /// Ranks it shares an interface with, increasing.
    pub neighbours: Vec<usize>,
    /// Values it sends per iteration to its neighbours (as many as it receives) once the
    /// exchange is point to point.
    pub values_sent: usize,
    /// Values it receives per iteration in the solve's all-gathers today, from every other
    /// rank's substructures: the fields of s the linear stage writes (e and t per link, U_E per
    /// dof, U and F per interface row), the macro right-hand side's parts (one per macro dof;
    /// kernel amplitudes left out), η's parts, the slack count, r(U)'s pieces at shared dofs
    /// and sums of squares, and Anderson's inner products with a full history.
    pub values_gathered: usize,
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
        let interfaces = Interfaces::new(structure, &partition, settings.weak);
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
            for (from, to) in [(a, b), (b, a)] {
                shares[from].values_sent += VALUES_PER_ROW * rows;
                if !shares[from].neighbours.contains(&to) {
                    shares[from].neighbours.push(to);
                }
            }
        }
        shares.iter_mut().for_each(|s| s.neighbours.sort_unstable());
        let gathered =
            gathered_per_substructure(structure, &partition, &interfaces, settings.anderson);
        let total: usize = gathered.iter().sum();
        for share in &mut shares {
            share.values_gathered =
                total - gathered[share.substructures.clone()].iter().sum::<usize>();
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
                "  rank {r}: substructures {}..{} ({}), {} links, neighbours [{}], receives {} \
                 values ({:.1} KiB) per iteration (point to point: would send {}, {:.1} KiB)\n",
                share.substructures.start,
                share.substructures.end,
                share.substructures.len(),
                share.links,
                neighbours.join(", "),
                share.values_gathered,
                kb(share.values_gathered),
                share.values_sent,
                kb(share.values_sent),
            );
        }
        out += &format!(
            "  per iteration the solve all-gathers, onto every rank, the other ranks' e and t \
             per link, U per dof, U and F per interface row, macro right-hand side parts and \
             per substructure the parts of η, r(U) and Anderson's inner products; \
             once point to point (not yet): {} values ({:.1} KiB) over {} of {} interfaces \
             (U, F and r(U)'s partial sums, {VALUES_PER_ROW} per interface row), and the macro \
             right-hand side, {} values, reduced over the ranks\n",
            self.values_exchanged(),
            kb(self.values_exchanged()),
            self.crossing_interfaces,
            self.interfaces,
            self.macro_forces,
        );
        out
    }
}

/// Per substructure, the values it contributes to an iteration's all-gathers: e and t per link,
/// U_E per free dof, U and F per interface row and one macro right-hand side part per macro dof.
fn gathered_per_substructure(
    structure: &Structure,
    partition: &Partition,
    interfaces: &Interfaces,
    anderson: usize,
) -> Vec<usize> {
    // Substructures holding each node, for the dofs r(U) sums across substructures.
    let mut holders = vec![0usize; structure.n_nodes()];
    for topo in &partition.substructures {
        topo.nodes.iter().for_each(|&n| holders[n] += 1);
    }
    let mut input = vec![0usize; partition.substructures.len()];
    let mut gathered: Vec<usize> = partition
        .substructures
        .iter()
        .zip(&mut input)
        .map(|(topo, input)| {
            let shared_dofs = topo
                .nodes
                .iter()
                .filter(|&&n| holders[n] > 1)
                .flat_map(|&n| structure.held_components(n))
                .filter(|&held| !held)
                .count();
            *input = topo.links.len();
            // e and t per link, U per dof; η's two parts, the slack count and r(U)'s three
            // sums of squares; r(U)'s three pieces per shared dof.
            2 * topo.links.len() + topo.free_dofs(structure) + 6 + 3 * shared_dofs
        })
        .collect();
    for iface in &interfaces.list {
        let rows: usize = iface.free.iter().flatten().filter(|&&f| f).count();
        for &e in &iface.topology.sides {
            gathered[e] += 2 * rows + iface.basis.ncols();
            input[e] += rows;
        }
    }
    // Anderson's two inner products with each of its differences (a full history of
    // `anderson`, and the new one) per chunk of the substructure's input.
    for (g, n) in gathered.iter_mut().zip(&input) {
        *g += 2 * (anderson + 1) * n.div_ceil(crate::linalg::CHUNK).max(1);
    }
    gathered
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
            // together P − 1 times what one rank holding them all would gather.
            let gathered: usize = layout.ranks.iter().map(|r| r.values_gathered).sum();
            let two: usize = RankLayout::new(&s, &settings, 2)
                .ranks
                .iter()
                .map(|r| r.values_gathered)
                .sum();
            assert_eq!(gathered, (p - 1) * two, "{p} ranks");
            let sent: usize = layout.ranks.iter().map(|r| r.values_sent).sum();
            assert_eq!(sent, layout.values_exchanged());
            assert_eq!(sent % (2 * VALUES_PER_ROW), 0, "as much each way");
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
