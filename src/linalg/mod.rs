//! Sparse linear algebra on top of faer, free of any structural notion: short sparse rows, the
//! pattern of `Σ w_i rowᵢᵀ rowᵢ`, a Cholesky
//! factorization whose symbolic part is computed once, conjugate gradients preconditioned by a
//! factor, and the smallest eigenvalues of a
//! stiffness (mechanism detection).

mod cholesky;
mod dense;
mod low_rank;
mod nested_dissection;
mod ordering;
mod parallel;
mod pattern;
mod pcg;
mod sparse_row;
mod spd_solver;
mod spectrum;

pub use cholesky::{NotPositiveDefinite, SparseCholesky};
pub use dense::{gemv, gemv_transposed};
pub use low_rank::LowRankUpdate;
pub use nested_dissection::nested_dissection;
pub use ordering::NodeOrdering;
pub use parallel::{par_dot, par_update, par_zip_map, CHUNK};
pub use pattern::StiffnessPattern;
pub use pcg::{preconditioned_cg, CgOutcome};
pub use sparse_row::SparseRow;
pub use spd_solver::SpdSolver;
pub use spectrum::{
    factorize_counting_zero_modes, factorize_or_find_singular, smallest_eigenvalue_bound,
    smallest_eigenvalues, zero_mode_count, zero_modes, SmallestEigenvalues, PROBE_ITERATIONS,
    ZERO_MODES_COUNTED, ZERO_MODE_RELATIVE,
};

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Dot product `Σ a_k b_k` (over the shorter slice if the lengths differ).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
