//! Sparse `A = L D Lᵀ` of a symmetric matrix that need not be positive definite (a tangent
//! stiffness past a limit point, where Cholesky fails), on the symbolic analysis of a
//! [`SparseCholesky`]: the same order and pattern, faer's LDLᵀ kernels without pivoting. A
//! zero pivot is an error; the count of negative pivots is A's number of negative eigenvalues
//! (Sylvester's law of inertia: `L D Lᵀ` is a congruence).
//!
//! With its pivots' signs given ([`SparseLdlt::factorize_signed`]: a quasi-definite matrix such
//! as the macro problem's, + on the forces, − on the kernel amplitudes) a pivot of the wrong
//! sign or too small is held at ± a regularisation, and the factor is also used as
//! `A = L̂ J L̂ᵀ`, `L̂ = L |D|^½`, `J = sign(D)`: the form a half of a split factor takes
//! (`src/linalg/split_cholesky.rs`).

use super::cholesky::{Analysis, SparseCholesky};
use super::{NodeOrdering, StiffnessPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_unit_lower_triangular_in_place, solve_unit_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::{simplicial, supernodal, LdltRef, SymbolicCholeskyRaw};
use faer::sparse::linalg::triangular_solve as sparse_triangular;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Conj, Mat, MatMut, Par};
use std::sync::Arc;

/// The matrix handed to [`SparseLdlt::factorize`] has a zero pivot in the factor's order
/// (it is singular, or nearly so in that order).
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("zero pivot at elimination step {pivot} of an LDLᵀ factorization")]
pub struct ZeroPivot {
    /// Where the zero pivot is, in the factor's fill-reducing order (as faer reports it, or
    /// the position of a zero or non-finite entry of D).
    pub pivot: usize,
}

/// Sparse `L D Lᵀ` factor on the symbolic analysis of a [`SparseCholesky`].
pub struct SparseLdlt {
    pub(super) analysis: Arc<Analysis>,
    pub(super) l_values: Vec<f64>,
    /// The numeric factorization's workspace, made at the first factorization (on the thread
    /// that factors: a split's leaves are made on one thread and factored on many).
    scratch: Option<MemBuffer>,
    /// Negative entries of D in the last successful factorization.
    negative_pivots: usize,
    factorized: bool,
}

impl SparseLdlt {
    /// A factor on the symbolic analysis of `cholesky` (no new analysis, no numeric factor).
    pub fn sharing(cholesky: &SparseCholesky) -> SparseLdlt {
        Self::with_analysis(Arc::clone(&cholesky.analysis))
    }

    /// A factor of `pattern` in `ordering` (its own symbolic analysis, no numeric factor).
    pub fn analyse_ordered(pattern: &StiffnessPattern, ordering: NodeOrdering<'_>) -> SparseLdlt {
        Self::with_analysis(Arc::new(Analysis::new(pattern, ordering)))
    }

    /// A factor on `analysis` with no storage yet: the factor's values and workspace are
    /// allocated by the first factorization.
    fn with_analysis(analysis: Arc<Analysis>) -> SparseLdlt {
        SparseLdlt {
            l_values: Vec::new(),
            scratch: None,
            negative_pivots: 0,
            factorized: false,
            analysis,
        }
    }

    /// The numeric factorization's workspace.
    fn scratch(analysis: &Analysis) -> MemBuffer {
        let symbolic = &analysis.symbolic;
        let scratch = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => {
                simplicial::factorize_simplicial_numeric_ldlt_scratch::<usize, f64>(
                    symbolic.nrows(),
                )
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                supernodal::factorize_supernodal_numeric_ldlt_scratch::<usize, f64>(
                    s,
                    Par::Seq,
                    Default::default(),
                )
            }
        };
        MemBuffer::new(scratch)
    }

    /// Numeric factorization of `values` (on the analysed pattern).
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), ZeroPivot> {
        self.factorize_with(values, LdltRegularization::default())
    }

    /// Numeric factorization of `values` whose pivots have the signs `signs` (per dof of A, +1
    /// or −1): a pivot of the wrong sign or of magnitude at most `regularisation` is replaced by
    /// ±`regularisation`, so that it never fails on a quasi-definite matrix; the factor is then
    /// that of A plus a diagonal of at most 2 `regularisation`, which iterative refinement
    /// against A undoes.
    pub fn factorize_signed(
        &mut self,
        values: &[f64],
        signs: &[i8],
        regularisation: f64,
    ) -> Result<(), ZeroPivot> {
        // faer takes the signs in the factor's order.
        let ordered: Vec<i8> = match self.analysis.symbolic.perm() {
            Some(perm) => perm.arrays().0.iter().map(|&d| signs[d]).collect(),
            None => signs.to_vec(),
        };
        self.factorize_with(
            values,
            LdltRegularization {
                dynamic_regularization_signs: Some(&ordered),
                dynamic_regularization_delta: regularisation,
                dynamic_regularization_epsilon: regularisation,
            },
        )
    }

    fn factorize_with(
        &mut self,
        values: &[f64],
        regularization: LdltRegularization<'_, f64>,
    ) -> Result<(), ZeroPivot> {
        let analysis = &*self.analysis;
        let permuted = analysis.permuted_values(values);
        let a = SparseColMatRef::new(analysis.permuted_pattern(), &permuted);
        self.factorized = false;
        self.l_values.resize(analysis.symbolic.len_val(), 0.0);
        let stack = MemStack::new(self.scratch.get_or_insert_with(|| Self::scratch(analysis)));
        let result = match analysis.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => simplicial::factorize_simplicial_numeric_ldlt(
                &mut self.l_values,
                a,
                regularization,
                s,
                stack,
            ),
            SymbolicCholeskyRaw::Supernodal(s) => supernodal::factorize_supernodal_numeric_ldlt(
                &mut self.l_values,
                a,
                regularization,
                s,
                Par::Seq,
                stack,
                Default::default(),
            ),
        };
        match result {
            Ok(_) => {
                if let Some(pivot) = self.pivots().position(|d| d == 0.0 || !d.is_finite()) {
                    return Err(ZeroPivot { pivot });
                }
                self.negative_pivots = self.pivots().filter(|&d| d < 0.0).count();
                self.factorized = true;
                Ok(())
            }
            Err(faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index }) => {
                Err(ZeroPivot { pivot: index })
            }
        }
    }

    /// The entries of D, in the factor's order: the first stored entry of each column of a
    /// simplicial factor, the diagonal of each supernode's dense block.
    fn pivots(&self) -> Box<dyn Iterator<Item = f64> + '_> {
        match self.analysis.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let col_ptr = s.col_ptr();
                Box::new((0..s.nrows()).map(move |j| self.l_values[col_ptr[j]]))
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let begin = s.supernode_begin();
                let end = s.supernode_end();
                let values_ptr = s.col_ptr_for_val();
                Box::new((0..s.n_supernodes()).flat_map(move |k| {
                    let rows = s.col_ptr_for_row_idx()[k + 1] - s.col_ptr_for_row_idx()[k]
                        + (end[k] - begin[k]);
                    let start = values_ptr[k];
                    (0..end[k] - begin[k]).map(move |j| self.l_values[start + j * rows + j])
                }))
            }
        }
    }

    /// Negative pivots of the last successful factorization: A's negative eigenvalues.
    pub fn negative_pivots(&self) -> usize {
        self.negative_pivots
    }

    /// `x ← A⁻¹ x` with the last successful factorization.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        assert!(self.factorized, "solve before a successful factorization");
        let n = x.len();
        let symbolic = &self.analysis.symbolic;
        let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        LdltRef::new(symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut scratch),
        );
    }
}

/// `L̂ = L |D|^½` and `J = sign(D)` of `A = L̂ J L̂ᵀ`: the halves of a solve with L̂ alone, for a
/// half of a split factor.
impl SparseLdlt {
    /// `X ← |D|^-½ L⁻¹ P X` for a column-major block: `L̂⁻¹ P X`, left in the factor's order.
    pub(super) fn forward_scaled_block_in_place(&self, mut x: MatMut<'_, f64>) {
        assert!(self.factorized, "solve before a successful factorization");
        let symbolic = &self.analysis.symbolic;
        let (n, k) = (x.nrows(), x.ncols());
        if let Some(perm) = symbolic.perm() {
            let forward = perm.arrays().0;
            let permuted = Mat::from_fn(n, k, |i, j| x[(forward[i], j)]);
            x.copy_from(&permuted);
        }
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                sparse_triangular::solve_unit_lower_triangular_in_place(
                    l,
                    Conj::No,
                    x.as_mut(),
                    Par::Seq,
                );
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = supernodal::SupernodalLdltRef::new(s, &self.l_values);
                // One buffer for every supernode's rows below its block.
                let mut buffer = Mat::zeros(rows_below(l), k);
                for node in 0..s.n_supernodes() {
                    let node = l.supernode(node);
                    let size = node.val().ncols();
                    let (top, bottom) = node.val().split_at_row(size);
                    let mut x_top = x.as_mut().subrows_mut(node.start(), size);
                    solve_unit_lower_triangular_in_place(top, x_top.as_mut(), Par::Seq);
                    let mut below = buffer.as_mut().subrows_mut(0, node.pattern().len());
                    matmul(
                        below.as_mut(),
                        Accum::Replace,
                        bottom,
                        x_top.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                    for j in 0..k {
                        for (t, &i) in node.pattern().iter().enumerate() {
                            x[(i, j)] -= below[(t, j)];
                        }
                    }
                }
            }
        }
        let pivots: Vec<f64> = self.pivots().collect();
        for j in 0..k {
            for (i, d) in pivots.iter().enumerate() {
                x[(i, j)] /= d.abs().sqrt();
            }
        }
    }

    /// `x ← Pᵀ L⁻ᵀ |D|^-½ J x` for one column in the factor's order: `L̂⁻ᵀ J x`, back in A's.
    pub(super) fn backward_scaled_in_place(&self, x: &mut [f64]) {
        assert!(self.factorized, "solve before a successful factorization");
        for (v, d) in x.iter_mut().zip(self.pivots()) {
            // J |D|^-½ = sign(d) / √|d|.
            *v *= d.signum() / d.abs().sqrt();
        }
        let symbolic = &self.analysis.symbolic;
        let n = x.len();
        let mut block = MatMut::from_column_major_slice_mut(x, n, 1);
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                sparse_triangular::solve_unit_lower_triangular_transpose_in_place(
                    l,
                    Conj::No,
                    block,
                    Par::Seq,
                );
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = supernodal::SupernodalLdltRef::new(s, &self.l_values);
                let mut buffer = vec![0.0; rows_below(l)];
                for node in (0..s.n_supernodes()).rev() {
                    let node = l.supernode(node);
                    let size = node.val().ncols();
                    let (top, bottom) = node.val().split_at_row(size);
                    let below = &mut buffer[..node.pattern().len()];
                    for (b, &i) in below.iter_mut().zip(node.pattern()) {
                        *b = block[(i, 0)];
                    }
                    let below = faer::MatRef::from_column_major_slice(below, below.len(), 1);
                    let mut x_top = block.as_mut().subrows_mut(node.start(), size);
                    matmul(
                        x_top.as_mut(),
                        Accum::Add,
                        bottom.transpose(),
                        below,
                        -1.0,
                        Par::Seq,
                    );
                    solve_unit_upper_triangular_in_place(top.transpose(), x_top, Par::Seq);
                }
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

/// The most rows any supernode of `l` has below its diagonal block.
fn rows_below(l: supernodal::SupernodalLdltRef<'_, usize, f64>) -> usize {
    (0..l.symbolic().n_supernodes())
        .map(|node| l.supernode(node).pattern().len())
        .max()
        .unwrap_or(0)
}

impl Clone for SparseLdlt {
    /// Shares the symbolic analysis and copies the numeric factor if there is one; the
    /// workspace is made anew by the copy's first factorization.
    fn clone(&self) -> Self {
        let mut copy = Self::with_analysis(Arc::clone(&self.analysis));
        if self.factorized {
            copy.l_values.clone_from(&self.l_values);
            copy.negative_pivots = self.negative_pivots;
            copy.factorized = true;
        }
        copy
    }
}

#[cfg(test)]
mod tests;
