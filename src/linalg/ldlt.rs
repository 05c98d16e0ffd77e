//! Sparse `A = L D Lᵀ` of a symmetric matrix that need not be positive definite (a tangent
//! stiffness past a limit point, where Cholesky fails), on the symbolic analysis of a
//! [`SparseCholesky`]: the same order and pattern, faer's LDLᵀ kernels without pivoting. A
//! zero pivot is an error; the count of negative pivots is A's number of negative eigenvalues
//! (Sylvester's law of inertia: `L D Lᵀ` is a congruence).

use super::cholesky::{Analysis, SparseCholesky};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{simplicial, supernodal, LdltRef, SymbolicCholeskyRaw};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par};
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
    analysis: Arc<Analysis>,
    l_values: Vec<f64>,
    scratch: MemBuffer,
    /// Negative entries of D in the last successful factorization.
    negative_pivots: usize,
    factorized: bool,
}

impl SparseLdlt {
    /// A factor on the symbolic analysis of `cholesky` (no new analysis, no numeric factor).
    pub fn sharing(cholesky: &SparseCholesky) -> SparseLdlt {
        let analysis = Arc::clone(&cholesky.analysis);
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
        SparseLdlt {
            l_values: vec![0.0; symbolic.len_val()],
            scratch: MemBuffer::new(scratch),
            negative_pivots: 0,
            factorized: false,
            analysis,
        }
    }

    /// Numeric factorization of `values` (on the analysed pattern).
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), ZeroPivot> {
        let analysis = &*self.analysis;
        let permuted = analysis.permuted_values(values);
        let a = SparseColMatRef::new(analysis.permuted_pattern(), &permuted);
        self.factorized = false;
        let stack = MemStack::new(&mut self.scratch);
        let regularization = LdltRegularization::default();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::StiffnessPattern;

    /// A symmetric indefinite tridiagonal matrix (diagonal `d`, off-diagonal 1) on a path
    /// pattern: solved to round-off, its negative eigenvalues counted.
    #[test]
    fn an_indefinite_matrix_is_solved_and_its_inertia_counted() {
        let n = 40;
        let entries: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| std::iter::once((i, i)).chain((i + 1 < n).then_some((i + 1, i))))
            .collect();
        let pattern = StiffnessPattern::from_lower_entries(n, &entries);
        // d_i = −2.5 for the first ten, 3 after: eigenvalues of the tridiagonal matrix.
        let diagonal = |i: usize| if i < 10 { -2.5 } else { 3.0 };
        let mut values = vec![0.0; pattern.nnz()];
        for (row, c, slot) in pattern.entries() {
            values[slot] = if row == c { diagonal(c) } else { 1.0 };
        }
        let cholesky = SparseCholesky::analyse(&pattern, Par::Seq);
        let mut ldlt = SparseLdlt::sharing(&cholesky);
        ldlt.factorize(&values).unwrap();
        // A x for a known x, then solved back.
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
        let mut b = vec![0.0; n];
        for i in 0..n {
            b[i] = diagonal(i) * x[i];
            if i > 0 {
                b[i] += x[i - 1];
            }
            if i + 1 < n {
                b[i] += x[i + 1];
            }
        }
        ldlt.solve_in_place(&mut b);
        let error = b
            .iter()
            .zip(&x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error < 1e-12, "{error}");
        // The dense eigenvalues of the same matrix, counted below zero.
        let dense = nalgebra::DMatrix::from_fn(n, n, |i, j| match i.abs_diff(j) {
            0 => diagonal(i),
            1 => 1.0,
            _ => 0.0,
        });
        let negative = dense
            .symmetric_eigenvalues()
            .iter()
            .filter(|&&v| v < 0.0)
            .count();
        assert_eq!(negative, 10);
        assert_eq!(ldlt.negative_pivots(), negative);
    }

    /// The 3-D 7-point Laplacian on 14³ points shifted by σ (large enough for faer's
    /// supernodal factor): its negative eigenvalues, `Σ_d (2 − 2 cos(k_d π / 15)) < σ`,
    /// counted in closed form.
    #[test]
    fn a_supernodal_factor_counts_the_negative_eigenvalues_of_a_shifted_laplacian() {
        let m = 14;
        let n = m * m * m;
        let index = |i: usize, j: usize, k: usize| (i * m + j) * m + k;
        let mut entries = Vec::new();
        for i in 0..m {
            for j in 0..m {
                for k in 0..m {
                    let p = index(i, j, k);
                    entries.push((p, p));
                    for q in [
                        (i + 1 < m).then(|| index(i + 1, j, k)),
                        (j + 1 < m).then(|| index(i, j + 1, k)),
                        (k + 1 < m).then(|| index(i, j, k + 1)),
                    ]
                    .into_iter()
                    .flatten()
                    {
                        entries.push((q, p));
                    }
                }
            }
        }
        let pattern = StiffnessPattern::from_lower_entries(n, &entries);
        let shift = 0.9;
        let mut values = vec![0.0; pattern.nnz()];
        for (row, c, slot) in pattern.entries() {
            values[slot] = if row == c { 6.0 - shift } else { -1.0 };
        }
        let cholesky = SparseCholesky::analyse(&pattern, Par::Seq);
        let mut ldlt = SparseLdlt::sharing(&cholesky);
        assert!(matches!(
            ldlt.analysis.symbolic.raw(),
            SymbolicCholeskyRaw::Supernodal(_)
        ));
        ldlt.factorize(&values).unwrap();
        let one = |k: usize| 2.0 - 2.0 * (k as f64 * std::f64::consts::PI / (m + 1) as f64).cos();
        let mut negative = 0;
        for a in 1..=m {
            for b in 1..=m {
                for c in 1..=m {
                    negative += usize::from(one(a) + one(b) + one(c) < shift);
                }
            }
        }
        assert!(negative > 5, "{negative}");
        assert_eq!(ldlt.negative_pivots(), negative);
        // A x for a known x, solved back.
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
        let mut b = vec![0.0; n];
        pattern.sym_matvec(&values, &x, &mut b);
        ldlt.solve_in_place(&mut b);
        let error = b
            .iter()
            .zip(&x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error < 1e-9, "{error}");
    }
}
