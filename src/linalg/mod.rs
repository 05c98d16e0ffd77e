//! Sparse linear algebra on top of faer: the stiffness pattern of a set of links, a Cholesky
//! factorization whose symbolic part is computed once, and the smallest eigenvalues of a
//! stiffness (mechanism detection).

mod cholesky;
mod dense;
mod pattern;
mod spd_solver;
mod spectrum;

pub use cholesky::{NotPositiveDefinite, SparseCholesky};
pub use dense::{gemv, gemv_transposed};
pub use pattern::StiffnessPattern;
pub use spd_solver::SpdSolver;
pub use spectrum::{
    smallest_eigenvalue_bound, smallest_eigenvalues, zero_mode_count, SmallestEigenvalues,
    ZERO_MODE_RELATIVE,
};

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
