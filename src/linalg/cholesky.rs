//! Sparse Cholesky `A = L Lᵀ` with faer: the symbolic analysis (fill-reducing ordering,
//! supernodes) is done once per pattern; numeric factorizations reuse it and their workspace.
//! Solves take `&self` (a solve's small workspace is allocated per call) so that one factor can
//! be shared.

use super::nested_dissection::SplitTree;
use super::ordering::{node_ordering, NodeOrdering};
use super::split_cholesky::SplitCholesky;
use super::StiffnessPattern;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, simplicial, supernodal, CholeskySymbolicParams, LltRef,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
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
    pub(super) analysis: Arc<Analysis>,
    pub(super) l_values: Vec<f64>,
    factor_scratch: MemBuffer,
    par: Par,
    factorized: bool,
    /// Factored in two halves side by side instead ([`SparseCholesky::share_symbolic_split`]).
    pub(super) split: Option<Box<SplitCholesky>>,
}

/// What one symbolic analysis fixes: the fill-reducing order (faer's symbolic factor holds it
/// and applies it in the solves), the pattern of one triangle of `P A Pᵀ` in that order, where
/// each entry of A goes in it, and faer's symbolic factor. A numeric factorization scatters A's
/// values through `permuted_slot` (one pass) and hands the permuted triangle to faer's numeric
/// kernel: faer's own path re-permutes A at every factorization (15 % of a factorization of
/// the paper case).
pub(super) struct Analysis {
    /// CSC pattern of the triangle of `P A Pᵀ` faer's numeric kernel reads: the upper one for
    /// its simplicial factor, the lower one for its supernodal one. Rows come in no particular
    /// order within a column (both kernels scatter them).
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Slot in that triangle of each slot of A.
    permuted_slot: Vec<u32>,
    pub(super) symbolic: SymbolicCholesky<usize>,
    /// With nested dissection, the dof counts of its top levels' parts (the order itself is
    /// the symbolic factor's permutation).
    pub(super) top_split: Option<SplitTree>,
}

impl Analysis {
    pub(super) fn new(pattern: &StiffnessPattern, ordering: NodeOrdering<'_>) -> Analysis {
        let n = pattern.n;
        let (order, inverse, top_split) = node_ordering(pattern, ordering);
        assert!(
            pattern.nnz() < u32::MAX as usize,
            "pattern too large for 32-bit slots"
        );
        // faer picks simplicial or supernodal from the flop count: on the 195-dof
        // substructures of a 64 × 64 grid simplicial solves were 10–20 % faster per LATIN
        // iteration than forced supernodal ones.
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::AUTO,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&order, &inverse, n)),
            params,
        )
        .expect("symbolic Cholesky of a valid pattern");
        let side = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => Side::Upper,
            SymbolicCholeskyRaw::Supernodal(_) => Side::Lower,
        };
        // Entry (r, c), r ≥ c, of A is entry (max, min) of (inverse[r], inverse[c]) in P A Pᵀ;
        // its column in the chosen triangle is the min (lower) or the max (upper). One
        // counting sort by that column.
        let column_and_row = |slot: usize, c: usize| {
            let (a, b) = (inverse[pattern.row_idx[slot]], inverse[c]);
            let (low, high) = (a.min(b), a.max(b));
            match side {
                Side::Lower => (low, high),
                Side::Upper => (high, low),
            }
        };
        let mut col_ptr = vec![0usize; n + 1];
        for c in 0..n {
            for slot in pattern.col_ptr[c]..pattern.col_ptr[c + 1] {
                col_ptr[column_and_row(slot, c).0 + 1] += 1;
            }
        }
        for k in 0..n {
            col_ptr[k + 1] += col_ptr[k];
        }
        let mut fill = col_ptr[..n].to_vec();
        let mut row_idx = vec![0usize; pattern.nnz()];
        let mut permuted_slot = vec![0u32; pattern.nnz()];
        for c in 0..n {
            let slots = pattern.col_ptr[c]..pattern.col_ptr[c + 1];
            for (slot, target) in slots.clone().zip(&mut permuted_slot[slots]) {
                let (column, row) = column_and_row(slot, c);
                row_idx[fill[column]] = row;
                *target = fill[column] as u32;
                fill[column] += 1;
            }
        }
        Analysis {
            col_ptr,
            row_idx,
            permuted_slot,
            symbolic,
            top_split,
        }
    }

    /// `values` of A scattered into the triangle of `P A Pᵀ` the numeric kernels read.
    pub(super) fn permuted_values(&self, values: &[f64]) -> Vec<f64> {
        assert_eq!(
            values.len(),
            self.permuted_slot.len(),
            "values on another pattern"
        );
        let mut permuted = vec![0.0; self.row_idx.len()];
        for (&v, &slot) in values.iter().zip(&self.permuted_slot) {
            permuted[slot as usize] = v;
        }
        permuted
    }

    pub(super) fn permuted_pattern(&self) -> SymbolicSparseColMatRef<'_, usize> {
        let n = self.col_ptr.len() - 1;
        SymbolicSparseColMatRef::new_unsorted_checked(n, n, &self.col_ptr, None, &self.row_idx)
    }
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &(self.analysis.col_ptr.len() - 1))
            .field("factor_entries", &self.l_values.len())
            .finish()
    }
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
        Self::with_analysis(Arc::new(Analysis::new(pattern, ordering)), par)
    }

    fn with_analysis(analysis: Arc<Analysis>, par: Par) -> SparseCholesky {
        let symbolic = &analysis.symbolic;
        let n = analysis.col_ptr.len() - 1;
        let scratch = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => {
                simplicial::factorize_simplicial_numeric_llt_scratch::<usize, f64>(n)
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                supernodal::factorize_supernodal_numeric_llt_scratch::<usize, f64>(
                    s,
                    par,
                    Default::default(),
                )
            }
        };
        SparseCholesky {
            l_values: vec![0.0; symbolic.len_val()],
            factor_scratch: MemBuffer::new(scratch),
            par,
            factorized: false,
            analysis,
            split: None,
        }
    }

    /// A factorization workspace on the same pattern that factors the subtrees of the
    /// nested dissection's top `levels` levels side by side (`src/linalg/split_cholesky.rs`;
    /// 1: the two halves, 4: 16 subtrees; fewer where the tree has fewer): the same matrix,
    /// another elimination of its separators. `None` when the analysis has no such split (an
    /// AMD order, or a split the pattern's entries cross).
    pub fn share_symbolic_split(
        &self,
        pattern: &StiffnessPattern,
        levels: usize,
    ) -> Option<SparseCholesky> {
        let analysis = &self.analysis;
        let inverse = analysis.symbolic.perm()?.arrays().1;
        let tree = analysis.top_split.as_ref()?;
        let split = SplitCholesky::new(pattern, inverse, tree, levels.max(1), None)?;
        Some(self.holding(split))
    }

    /// The levels of a split that give each of `threads` threads a subtree: ⌈log₂ threads⌉,
    /// at least 1.
    pub fn split_levels_for(threads: usize) -> usize {
        (usize::BITS - (threads.max(2) - 1).leading_zeros()) as usize
    }

    /// The levels of this factor's split (0: factored whole).
    pub fn split_levels(&self) -> usize {
        self.split.as_ref().map_or(0, |s| s.levels())
    }

    /// A factor on this analysis that works through `split` (no whole factor's storage).
    fn holding(&self, split: SplitCholesky) -> SparseCholesky {
        SparseCholesky {
            analysis: Arc::clone(&self.analysis),
            l_values: Vec::new(),
            factor_scratch: MemBuffer::new(faer::dyn_stack::StackReq::EMPTY),
            par: self.par,
            factorized: false,
            split: Some(Box::new(split)),
        }
    }

    /// The factor's order (forward: the dof at each position; inverse), which a split's
    /// solves apply: the analysis of a split is always ordered.
    pub(super) fn split_order(&self) -> (&[usize], &[usize]) {
        self.analysis
            .symbolic
            .perm()
            .expect("a split factor's analysis has an order")
            .arrays()
    }

    /// Whether this factor works in two halves ([`SparseCholesky::share_symbolic_split`]).
    pub fn is_split(&self) -> bool {
        self.split.is_some()
    }

    /// A second factorization workspace on the same symbolic analysis (no new analysis); it
    /// holds no numeric factor until [`SparseCholesky::factorize`].
    pub fn share_symbolic(&self) -> SparseCholesky {
        self.share_symbolic_with(self.par)
    }

    /// [`SparseCholesky::share_symbolic`] with faer's parallelism `par` for its numeric work.
    pub fn share_symbolic_with(&self, par: Par) -> SparseCholesky {
        Self::with_analysis(Arc::clone(&self.analysis), par)
    }

    /// Numeric factorization of `values` on the analysed pattern.
    pub fn factorize(
        &mut self,
        pattern: &StiffnessPattern,
        values: &[f64],
    ) -> Result<(), NotPositiveDefinite> {
        if let Some(split) = &mut self.split {
            return split.factorize(values);
        }
        let analysis = &*self.analysis;
        debug_assert_eq!(pattern.nnz(), values.len());
        // P A Pᵀ, one scatter. Allocated per factorization, not kept: as large as A, and
        // needed only here (a substructure factor held between factorizations is 15 % smaller
        // for it).
        let permuted_values = analysis.permuted_values(values);
        let a = SparseColMatRef::new(analysis.permuted_pattern(), &permuted_values);
        self.factorized = false;
        let stack = MemStack::new(&mut self.factor_scratch);
        let regularization = LltRegularization::default();
        let result = match analysis.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => simplicial::factorize_simplicial_numeric_llt(
                &mut self.l_values,
                a,
                regularization,
                s,
                stack,
            ),
            SymbolicCholeskyRaw::Supernodal(s) => supernodal::factorize_supernodal_numeric_llt(
                &mut self.l_values,
                a,
                regularization,
                s,
                self.par,
                stack,
                Default::default(),
            ),
        };
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

    /// `X ← A⁻¹ X` for a column-major block of right-hand sides: `X ← Pᵀ (L Lᵀ)⁻¹ P X` (faer
    /// applies the permutation its symbolic factor holds).
    pub fn solve_block_in_place(&self, x: MatMut<'_, f64>) {
        if let Some(split) = &self.split {
            return split.solve_block_in_place(self.split_order(), x);
        }
        assert!(self.factorized, "solve before a successful factorization");
        let symbolic = &self.analysis.symbolic;
        let mut scratch =
            MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(x.ncols(), self.par));
        LltRef::new(symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            x,
            self.par,
            MemStack::new(&mut scratch),
        );
    }

    /// `X ← L⁻¹ P X` for a column-major block: the first half of a solve, which leaves X in the
    /// factor's order. With [`SparseCholesky::backward_in_place`], `A⁻¹ = Pᵀ L⁻ᵀ · L⁻¹ P`.
    pub fn forward_block_in_place(&self, mut x: MatMut<'_, f64>) {
        if let Some(split) = &self.split {
            return split.forward_block_in_place(self.split_order().0, x);
        }
        assert!(self.factorized, "solve before a successful factorization");
        let symbolic = &self.analysis.symbolic;
        let (n, k) = (x.nrows(), x.ncols());
        if let Some(perm) = symbolic.perm() {
            // X ← P X, column by column through one buffer.
            let forward = perm.arrays().0;
            let mut column = vec![0.0; n];
            for j in 0..k {
                let mut x_j = x.as_mut().col_mut(j);
                for (slot, &from) in column.iter_mut().zip(forward) {
                    *slot = x_j[from];
                }
                x_j.copy_from(faer::ColRef::from_slice(&column));
            }
        }
        let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(k, self.par));
        let stack = MemStack::new(&mut scratch);
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                faer::sparse::linalg::triangular_solve::solve_lower_triangular_in_place(
                    l,
                    Conj::No,
                    x,
                    self.par,
                );
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                supernodal::SupernodalLltRef::new(s, &self.l_values).l_solve_with_conj(
                    Conj::No,
                    x,
                    self.par,
                    stack,
                );
            }
        }
    }

    /// `x ← Pᵀ L⁻ᵀ x`: the second half of a solve, from the factor's order back to A's.
    pub fn backward_in_place(&self, x: &mut [f64]) {
        if let Some(split) = &self.split {
            return split.backward_in_place(self.split_order().1, x);
        }
        assert!(self.factorized, "solve before a successful factorization");
        let symbolic = &self.analysis.symbolic;
        let n = x.len();
        let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, self.par));
        let stack = MemStack::new(&mut scratch);
        let block = MatMut::from_column_major_slice_mut(x, n, 1);
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                faer::sparse::linalg::triangular_solve::solve_lower_triangular_transpose_in_place(
                    l,
                    Conj::No,
                    block,
                    self.par,
                );
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                supernodal::SupernodalLltRef::new(s, &self.l_values).l_transpose_solve_with_conj(
                    Conj::No,
                    block,
                    self.par,
                    stack,
                );
            }
        }
        if let Some(perm) = symbolic.perm() {
            let inverse = perm.arrays().1;
            let factor_order = x.to_vec();
            for (v, &at) in x.iter_mut().zip(inverse) {
                *v = factor_order[at];
            }
        }
    }
}

impl Clone for SparseCholesky {
    /// Shares the symbolic analysis, copies the numeric factor, allocates fresh workspaces.
    fn clone(&self) -> Self {
        if let Some(split) = &self.split {
            return self.holding((**split).clone());
        }
        let mut copy = self.share_symbolic();
        copy.l_values.copy_from_slice(&self.l_values);
        copy.factorized = self.factorized;
        copy
    }
}

#[cfg(test)]
pub(super) mod tests;
