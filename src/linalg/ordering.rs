//! Fill-reducing orderings of a node-major pattern: the node graph (dofs taken three by three),
//! ordered by approximate minimum degree or by nested dissection from the nodes' coordinates,
//! expanded back to the dofs. [`super::SparseCholesky`] analyses a pattern in this order.

use super::nested_dissection::{nested_dissection_split, SplitTree};
use super::StiffnessPattern;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::SymbolicSparseColMatRef;

/// Fill-reducing ordering of the node graph (dofs taken three by three, as every pattern here
/// numbers a node's three components consecutively), expanded to the dofs. Any permutation
/// is correct, so a pattern that is not node-major only loses fill quality.
#[derive(Debug, Clone, Copy)]
pub enum NodeOrdering<'a> {
    /// Approximate minimum degree on the node graph: nine times fewer entries than AMD on the
    /// dofs, with the same fill on these grids.
    Amd,
    /// Nested dissection from each node's coordinates (one per node of the pattern,
    /// i.e. per three dofs), [`nested_dissection`](super::nested_dissection); falls back to
    /// AMD if the count differs.
    NestedDissection(&'a [[f64; 3]]),
    /// Nested dissection of a pattern of dense blocks of any size (a coarse matrix: one block
    /// per subdomain), block `k` the dofs `offsets[k]..offsets[k + 1]` at `centres[k]`;
    /// falls back to AMD if the counts differ.
    Blocks {
        /// Block k's dofs are `offsets[k]..offsets[k + 1]` (one more entry than blocks).
        offsets: &'a [usize],
        /// Block k's position.
        centres: &'a [[f64; 3]],
    },
    /// The pattern's own order (a pattern already ordered, such as a half of a split factor).
    Given,
}

/// The node graph of a node-major pattern, as CSR (offsets, neighbours), symmetric.
fn node_graph(p: &StiffnessPattern) -> (Vec<usize>, Vec<usize>) {
    let nodes = p.n / 3;
    // A link couples all three components of its two nodes, so the first component of each
    // node carries the whole node graph: its column lists the later neighbours (r > c).
    let later = |c: usize| {
        p.row_idx[p.col_ptr[c]..p.col_ptr[c + 1]]
            .iter()
            .filter(move |&&r| r % 3 == 0 && r / 3 != c / 3)
            .map(|&r| r / 3)
    };
    let mut offsets = vec![0usize; nodes + 1];
    for v in 0..nodes {
        for w in later(3 * v) {
            offsets[v + 1] += 1;
            offsets[w + 1] += 1;
        }
    }
    for v in 0..nodes {
        offsets[v + 1] += offsets[v];
    }
    // Filling node by node puts each list in increasing order: earlier neighbours first (they
    // are filled while visiting them, in order), then the later ones (rows are sorted).
    let mut neighbours = vec![0usize; offsets[nodes]];
    let mut fill = offsets[..nodes].to_vec();
    for v in 0..nodes {
        for w in later(3 * v) {
            neighbours[fill[w]] = v;
            fill[w] += 1;
        }
        for w in later(3 * v) {
            neighbours[fill[v]] = w;
            fill[v] += 1;
        }
    }
    (offsets, neighbours)
}

/// The dof permutation (forward, inverse) of `ordering` on `p`'s node graph, and with nested
/// dissection its top levels' splits in dofs (each part's separator after its two halves).
pub(super) fn node_ordering(
    p: &StiffnessPattern,
    ordering: NodeOrdering<'_>,
) -> (Vec<usize>, Vec<usize>, Option<SplitTree>) {
    let n = p.n;
    let identity = || ((0..n).collect(), (0..n).collect(), None);
    if let NodeOrdering::Blocks { offsets, centres } = ordering {
        if offsets.len() == centres.len() + 1 && offsets.last() == Some(&n) {
            return block_ordering(p, offsets, centres);
        }
    }
    if !n.is_multiple_of(3) || n == 0 || matches!(ordering, NodeOrdering::Given) {
        return identity();
    }
    let nodes = n / 3;
    let (offsets, neighbours) = node_graph(p);
    let mut top = None;
    let perm = match ordering {
        NodeOrdering::NestedDissection(xy) if xy.len() == nodes => {
            let (order, tree) = nested_dissection_split(&offsets, &neighbours, xy);
            top = tree.map(|t| t.measured(0, &|_, k| 3 * k));
            order
        }
        _ => match amd_order(&offsets, &neighbours) {
            Some(perm) => perm,
            None => return identity(),
        },
    };
    let mut perm_inv = vec![0usize; nodes];
    for (k, &v) in perm.iter().enumerate() {
        perm_inv[v] = k;
    }
    let expand = |p: &[usize]| -> Vec<usize> {
        p.iter()
            .flat_map(|&k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect()
    };
    (expand(&perm), expand(&perm_inv), top)
}

/// faer's approximate minimum degree order of the graph `(offsets, neighbours)` (CSR, both
/// triangles, no diagonal, each list increasing): `order[k]` is the vertex eliminated k-th;
/// `None` if faer refuses the graph.
pub fn amd_order(offsets: &[usize], neighbours: &[usize]) -> Option<Vec<usize>> {
    let n = offsets.len() - 1;
    let graph = SymbolicSparseColMatRef::new_checked(n, n, offsets, None, neighbours);
    let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
    let mut scratch = MemBuffer::new(amd::order_scratch::<usize>(n, neighbours.len()));
    amd::order(
        &mut perm,
        &mut perm_inv,
        graph,
        Default::default(),
        MemStack::new(&mut scratch),
    )
    .ok()?;
    Some(perm)
}

/// [`NodeOrdering::Blocks`]: nested dissection of the block graph (two blocks adjacent where an
/// entry couples them), expanded to the dofs block by block.
fn block_ordering(
    p: &StiffnessPattern,
    offsets: &[usize],
    centres: &[[f64; 3]],
) -> (Vec<usize>, Vec<usize>, Option<SplitTree>) {
    let blocks = centres.len();
    let mut block_of = vec![0usize; p.n];
    for k in 0..blocks {
        block_of[offsets[k]..offsets[k + 1]].fill(k);
    }
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); blocks];
    for c in 0..p.n {
        for &r in &p.row_idx[p.col_ptr[c]..p.col_ptr[c + 1]] {
            let (a, b) = (block_of[r], block_of[c]);
            if a != b {
                adjacent[a].push(b);
                adjacent[b].push(a);
            }
        }
    }
    let mut graph_offsets = vec![0usize];
    let mut neighbours = Vec::new();
    for list in &mut adjacent {
        list.sort_unstable();
        list.dedup();
        neighbours.extend_from_slice(list);
        graph_offsets.push(neighbours.len());
    }
    let (block_order, tree) = nested_dissection_split(&graph_offsets, &neighbours, centres);
    // Dofs of the blocks at positions at..at + k of the block order.
    let mut before = vec![0usize; blocks + 1];
    for (i, &k) in block_order.iter().enumerate() {
        before[i + 1] = before[i] + offsets[k + 1] - offsets[k];
    }
    let tree = tree.map(|t| t.measured(0, &|at, k| before[at + k] - before[at]));
    let order: Vec<usize> = block_order
        .iter()
        .flat_map(|&k| offsets[k]..offsets[k + 1])
        .collect();
    let mut inverse = vec![0usize; p.n];
    for (k, &d) in order.iter().enumerate() {
        inverse[d] = k;
    }
    (order, inverse, tree)
}
