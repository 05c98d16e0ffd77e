//! Sparse Cholesky `A = L Lᵀ` with faer: the symbolic analysis (fill-reducing ordering,
//! supernodes) is done once per pattern; numeric factorizations reuse it and their workspace.
//! Solves take `&self` (a solve's small workspace is allocated per call) so that one factor can
//! be shared.

use super::{nested_dissection, StiffnessPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use std::sync::Arc;

/// The matrix handed to [`SparseCholesky::factorize`] is not numerically positive definite.
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("matrix is not positive definite (non-positive pivot at elimination step {pivot})")]
pub struct NotPositiveDefinite {
    /// Elimination step of the failing pivot as faer reports it, in the factor's fill-reducing
    /// order (the dense path of [`SpdSolver`](crate::linalg::SpdSolver) always reports 0).
    pub pivot: usize,
}

/// Sparse Cholesky factor `A = L Lᵀ` of a matrix on a [`StiffnessPattern`]: one symbolic
/// analysis, reused by every numeric [`SparseCholesky::factorize`].
pub struct SparseCholesky {
    symbolic: Arc<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
    factor_scratch: MemBuffer,
    par: Par,
    factorized: bool,
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.symbolic.nrows())
            .field("factor_entries", &self.l_values.len())
            .finish()
    }
}

/// Fill-reducing ordering of the node graph (dofs taken three by three, as every pattern here
/// numbers a node's three components consecutively), expanded to the dofs. Any permutation
/// is correct, so a pattern that is not node-major only loses fill quality.
#[derive(Debug, Clone, Copy)]
pub enum NodeOrdering<'a> {
    /// Approximate minimum degree on the node graph: nine times fewer entries than AMD on the
    /// dofs, with the same fill on these grids.
    Amd,
    /// Nested dissection from each node's plane coordinates (one per node of the pattern,
    /// i.e. per three dofs), [`nested_dissection`]; falls back to AMD if the count differs.
    NestedDissection(&'a [[f64; 2]]),
}

/// The node graph of a node-major pattern, as CSR (offsets, neighbours), symmetric.
fn node_graph(p: &StiffnessPattern) -> (Vec<usize>, Vec<usize>) {
    let nodes = p.n / 3;
    // A link couples all three components of its two nodes, so the first component of each
    // node carries the whole node graph.
    let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); nodes];
    for c in (0..p.n).step_by(3) {
        for &r in &p.row_idx[p.col_ptr[c]..p.col_ptr[c + 1]] {
            if r % 3 == 0 && r != c {
                adjacency[r / 3].push(c / 3);
                adjacency[c / 3].push(r / 3);
            }
        }
    }
    let mut offsets = Vec::with_capacity(nodes + 1);
    let mut neighbours = Vec::new();
    offsets.push(0);
    for list in &mut adjacency {
        list.sort_unstable();
        list.dedup();
        neighbours.extend_from_slice(list);
        offsets.push(neighbours.len());
    }
    (offsets, neighbours)
}

/// The dof permutation (forward, inverse) of `ordering` on `p`'s node graph.
fn node_ordering(p: &StiffnessPattern, ordering: NodeOrdering<'_>) -> (Vec<usize>, Vec<usize>) {
    let n = p.n;
    let identity = || ((0..n).collect(), (0..n).collect());
    if !n.is_multiple_of(3) || n == 0 {
        return identity();
    }
    let nodes = n / 3;
    let (offsets, neighbours) = node_graph(p);
    let perm = match ordering {
        NodeOrdering::NestedDissection(xy) if xy.len() == nodes => {
            nested_dissection(&offsets, &neighbours, xy)
        }
        _ => {
            let graph =
                SymbolicSparseColMatRef::new_checked(nodes, nodes, &offsets, None, &neighbours);
            let (mut perm, mut perm_inv) = (vec![0usize; nodes], vec![0usize; nodes]);
            let mut scratch = MemBuffer::new(amd::order_scratch::<usize>(nodes, neighbours.len()));
            let ordered = amd::order(
                &mut perm,
                &mut perm_inv,
                graph,
                Default::default(),
                MemStack::new(&mut scratch),
            );
            if ordered.is_err() {
                return identity();
            }
            perm
        }
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
    (expand(&perm), expand(&perm_inv))
}

fn symbolic_ref(p: &StiffnessPattern) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(p.n, p.n, &p.col_ptr, None, &p.row_idx)
}

impl SparseCholesky {
    /// Symbolic analysis of `pattern` (lower triangle). `par`: faer's parallelism inside one
    /// factorization (use `Par::Seq` when factorizations already run in parallel).
    pub fn analyse(pattern: &StiffnessPattern, par: Par) -> SparseCholesky {
        Self::analyse_ordered(pattern, par, NodeOrdering::Amd)
    }

    /// [`SparseCholesky::analyse`] with the fill-reducing `ordering` of the caller's choice.
    pub fn analyse_ordered(
        pattern: &StiffnessPattern,
        par: Par,
        ordering: NodeOrdering<'_>,
    ) -> SparseCholesky {
        // faer picks simplicial or supernodal from the flop count: on the 195-dof
        // substructures of a 64 × 64 grid simplicial solves were 10–20 % faster per LATIN
        // iteration than forced supernodal ones.
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::AUTO,
            ..Default::default()
        };
        let (forward, inverse) = node_ordering(pattern, ordering);
        let ordering =
            SymmetricOrdering::Custom(PermRef::new_checked(&forward, &inverse, pattern.n));
        let symbolic =
            factorize_symbolic_cholesky(symbolic_ref(pattern), Side::Lower, ordering, params)
                .expect("symbolic Cholesky of a valid pattern");
        let factor_scratch =
            MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        let l_values = vec![0.0; symbolic.len_val()];
        SparseCholesky {
            symbolic: Arc::new(symbolic),
            l_values,
            factor_scratch,
            par,
            factorized: false,
        }
    }

    /// A second factorization workspace on the same symbolic analysis (no new analysis); it
    /// holds no numeric factor until [`SparseCholesky::factorize`].
    pub fn share_symbolic(&self) -> SparseCholesky {
        SparseCholesky {
            symbolic: Arc::clone(&self.symbolic),
            l_values: vec![0.0; self.l_values.len()],
            factor_scratch: MemBuffer::new(
                self.symbolic
                    .factorize_numeric_llt_scratch::<f64>(self.par, Default::default()),
            ),
            par: self.par,
            factorized: false,
        }
    }

    /// Numeric factorization of `values` on the analysed pattern.
    pub fn factorize(
        &mut self,
        pattern: &StiffnessPattern,
        values: &[f64],
    ) -> Result<(), NotPositiveDefinite> {
        let a = SparseColMatRef::new(symbolic_ref(pattern), values);
        self.factorized = false;
        let result = self.symbolic.factorize_numeric_llt(
            &mut self.l_values,
            a,
            Side::Lower,
            LltRegularization::default(),
            self.par,
            MemStack::new(&mut self.factor_scratch),
            Default::default(),
        );
        match result {
            Ok(_) => {
                self.factorized = true;
                Ok(())
            }
            Err(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) => {
                Err(NotPositiveDefinite { pivot: index })
            }
        }
    }

    /// `x ← A⁻¹ x` with the last successful factorization.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let n = x.len();
        self.solve_block_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
    }

    /// `X ← A⁻¹ X` for a column-major block of right-hand sides.
    pub fn solve_block_in_place(&self, x: MatMut<'_, f64>) {
        assert!(self.factorized, "solve before a successful factorization");
        let mut scratch = MemBuffer::new(
            self.symbolic
                .solve_in_place_scratch::<f64>(x.ncols(), self.par),
        );
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            x,
            self.par,
            MemStack::new(&mut scratch),
        );
    }
}

impl Clone for SparseCholesky {
    /// Shares the symbolic analysis, copies the numeric factor, allocates fresh workspaces.
    fn clone(&self) -> Self {
        let mut copy = self.share_symbolic();
        copy.l_values.copy_from_slice(&self.l_values);
        copy.factorized = self.factorized;
        copy
    }
}
