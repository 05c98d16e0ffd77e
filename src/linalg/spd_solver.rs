//! Solves with a symmetric positive definite matrix stored as a lower-triangular pattern:
//! a dense inverse when the matrix is small (a solve is then one matrix–vector product, far
//! cheaper than a sparse triangular solve at this size), a sparse Cholesky factor otherwise.

use super::{NotPositiveDefinite, SparseCholesky, StiffnessPattern};
use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, Par, Side};
use nalgebra::DMatrix;

/// A solver for `A x = b` with A symmetric positive definite, dense or sparse by size.
pub enum SpdSolver {
    /// `A⁻¹`, dense.
    Dense(DMatrix<f64>),
    /// Sparse Cholesky factor of A.
    Sparse(SparseCholesky),
}

impl SpdSolver {
    /// Matrices of at most this order may be inverted densely (8 MB at most).
    pub const DENSE_MAX: usize = 1000;

    /// Whether [`SpdSolver::new`] factorises a matrix of order `n` sparse: unless `dense` is
    /// asked and honoured (up to [`SpdSolver::DENSE_MAX`]).
    pub fn is_sparse(n: usize, dense: bool) -> bool {
        !dense || n > Self::DENSE_MAX
    }

    /// `dense`: invert densely (only honoured up to [`SpdSolver::DENSE_MAX`]). A dense inverse
    /// is read whole at every solve, so it pays while the inverses of all the matrices solved
    /// together stay in cache; the caller knows how many there are.
    pub fn new(
        pattern: &StiffnessPattern,
        values: &[f64],
        dense: bool,
    ) -> Result<Self, NotPositiveDefinite> {
        let n = pattern.n;
        if Self::is_sparse(n, dense) {
            let mut factor = SparseCholesky::analyse(pattern, Par::Seq);
            factor.factorize(pattern, values)?;
            return Ok(SpdSolver::Sparse(factor));
        }
        let mut a = Mat::<f64>::zeros(n, n);
        for (r, c, s) in pattern.entries() {
            a[(r, c)] = values[s];
            a[(c, r)] = values[s];
        }
        let llt = a
            .llt(Side::Lower)
            .map_err(|_| NotPositiveDefinite { pivot: 0 })?;
        let inverse = llt.inverse();
        Ok(SpdSolver::Dense(DMatrix::from_fn(n, n, |i, j| {
            inverse[(i, j)]
        })))
    }

    /// `x ← A⁻¹ x`.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        match self {
            SpdSolver::Dense(inverse) => {
                let rhs = x.to_vec();
                super::gemv(x, inverse, &rhs, false);
            }
            SpdSolver::Sparse(factor) => factor.solve_in_place(x),
        }
    }

    /// `Z ← A⁻¹ Z`, column by column of a column-major block.
    pub fn solve_columns(&self, z: &mut DMatrix<f64>) {
        match self {
            SpdSolver::Dense(inverse) => {
                let (n, m) = z.shape();
                let rhs = z.clone();
                if m > 0 {
                    faer::linalg::matmul::matmul(
                        faer::MatMut::from_column_major_slice_mut(z.as_mut_slice(), n, m),
                        faer::Accum::Replace,
                        faer::MatRef::from_column_major_slice(inverse.as_slice(), n, n),
                        faer::MatRef::from_column_major_slice(rhs.as_slice(), n, m),
                        1.0,
                        Par::Seq,
                    );
                }
            }
            SpdSolver::Sparse(factor) => {
                let (n, m) = z.shape();
                if m > 0 {
                    factor.solve_block_in_place(faer::MatMut::from_column_major_slice_mut(
                        z.as_mut_slice(),
                        n,
                        m,
                    ));
                }
            }
        }
    }
}
