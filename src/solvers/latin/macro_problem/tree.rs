//! The macro problem's unknowns in the order of a bisection of the substructures, so that its
//! factor splits into subtrees factored and solved side by side
//! (`src/linalg/split_quasi_definite.rs`): the substructures are halved at the median of their
//! centres along their longest extent, `levels` times; the forces of the interfaces between
//! two halves are their separator, last; a leaf holds its substructures' kernel amplitudes and
//! the forces of the interfaces inside it, ordered by AMD. A kernel amplitude is never in a
//! separator, so every separator's Schur complement is positive definite (the macro matrix
//! has one + pivot per force and one − pivot per kernel amplitude; a leaf takes the −).

use super::super::substructure::Substructure;
use super::super::Interface;
use crate::linalg::{amd_order, SplitTree};
use faer::sparse::SymbolicSparseColMatRef;

/// No split into leaves of fewer substructures than this: a leaf's factor must outweigh its
/// dense blocks, which hold every separator above it (m² each: `src/linalg/split_cholesky.rs`).
/// 128 × 128 modules on 1024 substructures (29 446 unknowns, half the cables slack; the whole
/// factor after AMD 7.0 M entries, 57 ms a refined solve on two threads, 64 ms on one): in two
/// leaves 8.5 M entries, 35 ms and 58 ms; in four 13.6 M, 39 ms and 71 ms.
pub(in crate::solvers::latin) const LEAF_SUBSTRUCTURES: usize = 512;

/// At most 2² = 4 subtrees: deeper, each leaf's dense blocks grow with every separator above
/// it, where the leaf's own factor shrinks.
const MAX_LEVELS: usize = 2;

/// An order of the macro unknowns and the split it makes.
pub(in crate::solvers::latin) struct MacroTree {
    /// `order[k]`: the unknown at position k.
    pub order: Vec<usize>,
    /// The sizes of the halves at each level (each half's own separator at its end).
    pub split: SplitTree,
    /// The levels of the split.
    pub levels: usize,
}

/// The bisection order of the macro unknowns (module doc): `n` unknowns, the interfaces'
/// forces at their `macro_offset`, substructure e's kernel amplitudes from `kernel_offset[e]`,
/// the pattern's lower triangle `lower`, leaves of at least `leaf_substructures` substructures.
/// `None` when there are too few substructures to split.
/// The levels depend on the partition alone, not on the machine's threads, so that every run
/// of a case factors the same way.
pub(in crate::solvers::latin) fn macro_tree(
    subs: &[Substructure],
    interfaces: &[Interface],
    kernel_offset: &[usize],
    lower: SymbolicSparseColMatRef<'_, usize>,
    leaf_substructures: usize,
) -> Option<MacroTree> {
    let levels = (subs.len() / leaf_substructures)
        .checked_ilog2()
        .map_or(0, |l| (l as usize).min(MAX_LEVELS));
    if levels == 0 {
        return None;
    }
    let centres: Vec<[f64; 3]> = subs
        .iter()
        .map(|sub| {
            let count = sub.sides.len().max(1) as f64;
            let mut centre = [0.0; 3];
            for side in &sub.sides {
                let g = interfaces[side.interface].centroid;
                (0..3).for_each(|k| centre[k] += g[k] / count);
            }
            centre
        })
        .collect();
    let mut bisection = Bisection {
        subs,
        interfaces,
        kernel_offset,
        centres,
        region: vec![0; subs.len()],
        next_region: 1,
        graph: symmetric_graph(lower),
        local: vec![usize::MAX; lower.nrows()],
        levels,
    };
    let mut order = Vec::with_capacity(lower.nrows());
    let split = bisection.order((0..subs.len()).collect(), 0, 0, &mut order)?;
    debug_assert_eq!(order.len(), lower.nrows());
    Some(MacroTree {
        order,
        split,
        levels,
    })
}

struct Bisection<'a> {
    subs: &'a [Substructure],
    interfaces: &'a [Interface],
    kernel_offset: &'a [usize],
    centres: Vec<[f64; 3]>,
    /// The part each substructure is in now.
    region: Vec<usize>,
    next_region: usize,
    /// The macro matrix's graph (CSR, both triangles, no diagonal).
    graph: (Vec<usize>, Vec<usize>),
    /// Per unknown, its index in the leaf being ordered (`usize::MAX`: not in it).
    local: Vec<usize>,
    levels: usize,
}

impl Bisection<'_> {
    /// Appends the unknowns of part `region` (substructures `set`) to `order`: its halves', then
    /// its separator's; returns its split (`None`: a leaf).
    fn order(
        &mut self,
        set: Vec<usize>,
        region: usize,
        level: usize,
        order: &mut Vec<usize>,
    ) -> Option<SplitTree> {
        let halves = (level < self.levels).then(|| self.halve(&set)).flatten();
        let Some([left, right]) = halves else {
            self.leaf(&set, region, order);
            return None;
        };
        let (a, b) = (self.next_region, self.next_region + 1);
        self.next_region += 2;
        left.iter().for_each(|&e| self.region[e] = a);
        right.iter().for_each(|&e| self.region[e] = b);
        // The separator: the interfaces between the two halves.
        let mut separator: Vec<usize> = left
            .iter()
            .flat_map(|&e| self.subs[e].sides.iter().map(|side| side.interface))
            .filter(|&i| {
                let [s, t] = self.interfaces[i].topology.sides;
                (self.region[s] == a && self.region[t] == b)
                    || (self.region[s] == b && self.region[t] == a)
            })
            .collect();
        separator.sort_unstable();
        separator.dedup();
        let start = order.len();
        let first = self.order(left, a, level + 1, order);
        let middle = order.len();
        let second = self.order(right, b, level + 1, order);
        let end = order.len();
        for &i in &separator {
            let iface = &self.interfaces[i];
            order.extend(iface.macro_offset..iface.macro_offset + iface.basis.ncols());
        }
        Some(SplitTree {
            parts: [middle - start, end - middle],
            children: [first.map(Box::new), second.map(Box::new)],
        })
    }

    /// `set` halved at the median of its centres along their longest extent; `None` when a
    /// half would be empty.
    fn halve(&self, set: &[usize]) -> Option<[Vec<usize>; 2]> {
        let extent = |axis: usize| {
            let (lo, hi) = set
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &e| {
                    (lo.min(self.centres[e][axis]), hi.max(self.centres[e][axis]))
                });
            hi - lo
        };
        let extents = [extent(0), extent(1), extent(2)];
        let axis = (0..3)
            .max_by(|&a, &b| extents[a].total_cmp(&extents[b]).then(b.cmp(&a)))
            .expect("three axes");
        let mut along: Vec<f64> = set.iter().map(|&e| self.centres[e][axis]).collect();
        let middle = along.len() / 2;
        let (_, &mut median, _) = along.select_nth_unstable_by(middle, f64::total_cmp);
        let (left, right): (Vec<usize>, Vec<usize>) =
            set.iter().partition(|&&e| self.centres[e][axis] < median);
        (!left.is_empty() && !right.is_empty()).then_some([left, right])
    }

    /// Appends a leaf's unknowns (the forces of the interfaces inside it, its substructures'
    /// kernel amplitudes) to `order`, ordered by AMD on the leaf's graph.
    fn leaf(&mut self, set: &[usize], region: usize, order: &mut Vec<usize>) {
        let mut unknowns: Vec<usize> = Vec::new();
        let mut inside: Vec<usize> = set
            .iter()
            .flat_map(|&e| self.subs[e].sides.iter().map(|side| side.interface))
            .filter(|&i| {
                let [s, t] = self.interfaces[i].topology.sides;
                self.region[s] == region && self.region[t] == region
            })
            .collect();
        inside.sort_unstable();
        inside.dedup();
        for &i in &inside {
            let iface = &self.interfaces[i];
            unknowns.extend(iface.macro_offset..iface.macro_offset + iface.basis.ncols());
        }
        for &e in set {
            let first = self.kernel_offset[e];
            unknowns.extend(first..first + self.subs[e].kernel.ncols());
        }
        unknowns.sort_unstable();
        for (k, &u) in unknowns.iter().enumerate() {
            self.local[u] = k;
        }
        // The leaf's graph, in its own numbering.
        let (offsets, neighbours) = &self.graph;
        let mut leaf_offsets = vec![0usize];
        let mut leaf_neighbours = Vec::new();
        for &u in &unknowns {
            leaf_neighbours.extend(
                neighbours[offsets[u]..offsets[u + 1]]
                    .iter()
                    .map(|&v| self.local[v])
                    .filter(|&v| v != usize::MAX),
            );
            leaf_offsets.push(leaf_neighbours.len());
        }
        match amd_order(&leaf_offsets, &leaf_neighbours) {
            Some(perm) => order.extend(perm.iter().map(|&k| unknowns[k])),
            None => order.extend_from_slice(&unknowns),
        }
        unknowns.iter().for_each(|&u| self.local[u] = usize::MAX);
    }
}

/// Both triangles of `lower` but its diagonal, as CSR (offsets, neighbours; rows sorted).
fn symmetric_graph(lower: SymbolicSparseColMatRef<'_, usize>) -> (Vec<usize>, Vec<usize>) {
    let n = lower.nrows();
    let mut offsets = vec![0usize; n + 1];
    for c in 0..n {
        for &r in lower.row_idx()[lower.col_range(c)]
            .iter()
            .filter(|&&r| r != c)
        {
            offsets[r + 1] += 1;
            offsets[c + 1] += 1;
        }
    }
    for k in 0..n {
        offsets[k + 1] += offsets[k];
    }
    let mut fill = offsets[..n].to_vec();
    let mut neighbours = vec![0usize; offsets[n]];
    for c in 0..n {
        for &r in lower.row_idx()[lower.col_range(c)]
            .iter()
            .filter(|&&r| r != c)
        {
            neighbours[fill[r]] = c;
            fill[r] += 1;
            neighbours[fill[c]] = r;
            fill[c] += 1;
        }
    }
    (offsets, neighbours)
}
