//! Sparse linear algebra on top of faer, free of any structural notion: short sparse rows, the
//! pattern of `Σ w_i rowᵢᵀ rowᵢ`, a Cholesky
//! factorization whose symbolic part is computed once, conjugate gradients preconditioned by a
//! factor, and the smallest eigenvalues of a
//! stiffness (mechanism detection).

mod buckets;
mod cholesky;
mod dense;
mod estimate;
mod ldlt;
mod low_modes;
mod low_rank;
mod modal;
mod nested_dissection;
mod ordering;
mod parallel;
mod pattern;
mod pcg;
mod row_chunks;
mod sparse_row;
mod spd_solver;
mod spectrum;
mod split_cholesky;
mod split_quasi_definite;

pub use buckets::buckets;
pub use cholesky::{NotPositiveDefinite, SparseCholesky};
pub use dense::{gemv, gemv_transposed};
pub use estimate::{
    factor_bytes, AMD_FILL_RATIO, BYTES_PER_FACTOR_ENTRY, FACTOR_ENTRIES_PER_DOF_LOG2,
};
pub use ldlt::{SparseLdlt, ZeroPivot};
pub use low_modes::{modes_below, modes_below_by_subspace, LowModes};
pub use low_rank::LowRankUpdate;
pub use modal::{lowest_generalized_modes, GeneralizedModes, NoShiftFactorizes, DENSE_MODES_UP_TO};
pub use nested_dissection::{nested_dissection, SplitTree};
pub use ordering::{amd_order, NodeOrdering};
pub use parallel::{par_dot, par_update, par_zip_map, CHUNK};
pub use pattern::StiffnessPattern;
pub use pcg::{preconditioned_cg, CgOutcome};
pub use row_chunks::RowChunks;
pub use sparse_row::SparseRow;
pub use spd_solver::SpdSolver;
pub use spectrum::{
    factorize_counting_zero_modes, factorize_or_find_singular, factorize_or_find_singular_below,
    smallest_eigenvalue_bound, smallest_eigenvalues, zero_mode_count, zero_modes,
    SmallestEigenvalues, PROBE_ITERATIONS, ZERO_MODES_COUNTED, ZERO_MODE_RELATIVE,
};
pub use split_quasi_definite::SplitQuasiDefinite;

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    let sum: f64 = v.iter().map(|x| x * x).sum();
    if sum.is_normal() || sum.is_nan() || v.iter().all(|&x| x == 0.0) {
        return sum.sqrt();
    }
    // x² underflowed (entries below about 1e-154: a load factor of 1e-165 made ‖F‖ = 0 and its
    // rows "converged" at U = 0) or overflowed (above about 1e154): `m √(Σ (x/m)²)`, m the
    // largest |x|.
    let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if !largest.is_finite() {
        return largest;
    }
    largest * v.iter().map(|x| (x / largest).powi(2)).sum::<f64>().sqrt()
}

/// Dot product `Σ a_k b_k` (over the shorter slice if the lengths differ).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod norm_tests {
    use super::norm;

    #[test]
    fn norm_scales_what_would_underflow_or_overflow() {
        assert_eq!(norm(&[]), 0.0);
        assert_eq!(norm(&[0.0, 0.0]), 0.0);
        assert_eq!(norm(&[3.0, 4.0]), 5.0);
        // x² underflows to 0 below about 1e-162, overflows above about 1e154.
        let tiny = norm(&[3e-170, 4e-170]);
        assert!((tiny / 5e-170 - 1.0).abs() < 1e-15, "{tiny:e}");
        let huge = norm(&[3e200, 4e200]);
        assert!((huge / 5e200 - 1.0).abs() < 1e-15, "{huge:e}");
        assert!(norm(&[1.0, f64::NAN]).is_nan());
        assert_eq!(norm(&[1e-170, f64::INFINITY]), f64::INFINITY);
    }
}
