//! A quasi-definite matrix (the macro problem's `[Ã N; Nᵀ 0]`: + pivots on Ã's unknowns, −
//! on the others) factored in 2^k subtrees side by side: the split factor of
//! `src/linalg/split_cholesky.rs` with `L̂ J L̂ᵀ` leaves, on an order and a tree the caller
//! gives, whose separators hold + unknowns only.
//!
//! Every separator then holds + pivots only (forces, never kernel amplitudes): each leaf half is
//! factored `M_h = L̂ J L̂ᵀ` (`SparseLdlt::factorize_signed`, J = ±1 by the given signs) and its
//! Schur complement on S, `K_SS − K_Sh K_hh⁻¹ K_hS`, has the inertia of M_h less that of K_hh
//! (Sylvester): |S| positive pivots, so `T_h = L̂_SS` and the separator's S̃ is positive
//! definite as in the Cholesky split. A solve applies J in the leaves' backward halves
//! (`x_h = L̂_hh⁻ᵀ (J_h y_h − …)`).

use super::nested_dissection::SplitTree;
use super::split_cholesky::SplitCholesky;
use super::{NotPositiveDefinite, StiffnessPattern};
use faer::MatMut;

/// A quasi-definite matrix factored in subtrees side by side (module doc).
#[derive(Clone)]
pub struct SplitQuasiDefinite {
    split: SplitCholesky,
    /// `order[k]`: the unknown at position k; `inverse[i]`: the position of unknown i.
    order: Vec<usize>,
    inverse: Vec<usize>,
}

impl SplitQuasiDefinite {
    /// The split of `pattern` (its lower triangle) in `order`, whose first positions are
    /// `tree`'s halves and then its separator, recursively down to `levels` levels; `signs[i]`:
    /// the sign of unknown i's pivot (+1 or −1), a pivot of the wrong sign or of magnitude at
    /// most `regularisation` held at ±`regularisation`. `None` when `order` is not such a
    /// split (an entry couples two halves, or a separator holds a − unknown).
    pub fn new(
        pattern: &StiffnessPattern,
        order: Vec<usize>,
        tree: &SplitTree,
        levels: usize,
        signs: &[i8],
        regularisation: f64,
    ) -> Option<SplitQuasiDefinite> {
        let mut inverse = vec![0; order.len()];
        for (k, &i) in order.iter().enumerate() {
            inverse[i] = k;
        }
        let by_position: Vec<i8> = order.iter().map(|&i| signs[i]).collect();
        let split = SplitCholesky::new(
            pattern,
            &inverse,
            tree,
            levels.max(1),
            Some((&by_position, regularisation)),
        )?;
        Some(SplitQuasiDefinite {
            split,
            order,
            inverse,
        })
    }

    /// The levels of subtrees factored side by side.
    pub fn levels(&self) -> usize {
        self.split.levels()
    }

    /// Entries it stores: its leaves' factors and its dense separator blocks.
    pub fn entries(&self) -> usize {
        self.split.entries()
    }

    /// Numeric factorization of `values` (on `pattern`'s slots). An error when a separator's
    /// Schur complement is not positive definite (the matrix is singular, or not
    /// quasi-definite on these signs).
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), NotPositiveDefinite> {
        self.split.factorize(values)
    }

    /// `x ← A⁻¹ x` with the last successful factorization (its regularised pivots included).
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let n = x.len();
        self.split.solve_block_in_place(
            (&self.order, &self.inverse),
            MatMut::from_column_major_slice_mut(x, n, 1),
        );
    }
}
