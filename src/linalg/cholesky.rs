//! Sparse Cholesky `A = L Lᵀ` with faer: the symbolic analysis (fill-reducing ordering,
//! supernodes) is done once per pattern; numeric factorizations reuse it and their workspace.
//! Solves take `&self` (a solve's small workspace is allocated per call) so that one factor can
//! be shared.

use super::StiffnessPattern;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use std::sync::Arc;

/// The matrix handed to [`SparseCholesky::factorize`] is not numerically positive definite.
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("matrix is not positive definite (non-positive pivot at elimination step {pivot})")]
pub struct NotPositiveDefinite {
    pub pivot: usize,
}

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

fn symbolic_ref(p: &StiffnessPattern) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(p.n, p.n, &p.col_ptr, None, &p.row_idx)
}

impl SparseCholesky {
    /// Symbolic analysis of `pattern` (lower triangle). `par`: faer's parallelism inside one
    /// factorization (use `Par::Seq` when factorizations already run in parallel).
    pub fn analyse(pattern: &StiffnessPattern, par: Par) -> SparseCholesky {
        // Supernodal always: its dense-block triangular solves are several times faster than
        // the simplicial ones faer would pick for small matrices (measured on the 195-dof
        // substructures of the paper's case), and solves dominate the LATIN iterations.
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            symbolic_ref(pattern),
            Side::Lower,
            Default::default(),
            params,
        )
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

    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Entries of the factor L (a measure of fill and memory).
    pub fn factor_entries(&self) -> usize {
        self.l_values.len()
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
