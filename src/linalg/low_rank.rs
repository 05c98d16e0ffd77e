//! Solves with `A + U S Uᵀ` from a Cholesky factor of A, for a change U S Uᵀ of low rank made of
//! sparse rows (a link's compatibility row uᵢ with weight sᵢ: ± its stiffness when it became
//! taut or slack). Sherman–Morrison–Woodbury in the factor's coordinates: with
//! `A = Pᵀ L Lᵀ P` and `W = L⁻¹ P U`,
//! `(A + U S Uᵀ)⁻¹ = Pᵀ L⁻ᵀ (I − W C⁻¹ Wᵀ) L⁻¹ P`, `C = S⁻¹ + Wᵀ W` (r × r, symmetric,
//! indefinite when a weight is negative).
//!
//! A solve then costs one solve with the factor and two products with the n × r block W;
//! building W costs one forward substitution with r right-hand sides, and a column is kept
//! from one [`LowRankUpdate::update`] to the next while its row and weight stay the same.

use super::{SparseCholesky, SparseRow};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::{DMatrix, DVector};

/// The change `U S Uᵀ` to a factored matrix, ready to solve with.
#[derive(Debug, Clone)]
pub struct LowRankUpdate {
    /// The caller's key and the weight sᵢ of each column of U.
    columns: Vec<(usize, f64)>,
    /// `W = L⁻¹ P U`, n × r, in the factor's order.
    w: Mat<f64>,
    /// LU factors of the capacitance `C = S⁻¹ + Wᵀ W`, or `None` when there is no change or C
    /// is singular.
    capacitance: Option<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>>,
}

impl LowRankUpdate {
    /// No change (rank 0) on a matrix of order n.
    pub fn none(n: usize) -> LowRankUpdate {
        LowRankUpdate {
            columns: Vec::new(),
            w: Mat::zeros(n, 0),
            capacitance: None,
        }
    }

    /// The rank r of the change.
    pub fn rank(&self) -> usize {
        self.columns.len()
    }

    /// Make the change `Σ sᵢ uᵢ uᵢᵀ` over `wanted` = (key, uᵢ, sᵢ), on the matrix `factor` holds.
    /// Columns whose key and weight were already there are kept (the caller keeps a key's row
    /// the same and `factor` unchanged between calls, or starts from [`LowRankUpdate::none`]);
    /// the others cost one block forward substitution. Returns the number of new columns.
    pub fn update(
        &mut self,
        factor: &SparseCholesky,
        wanted: &[(usize, &SparseRow, f64)],
    ) -> usize {
        let n = self.w.nrows();
        // Each wanted column's place in the old W, if it is there with the same weight.
        let old: Vec<Option<usize>> = wanted
            .iter()
            .map(|&(key, _, weight)| {
                self.columns
                    .iter()
                    .position(|&(k, s)| k == key && s == weight)
            })
            .collect();
        // Kept columns first, then the new ones; one n × r block at a time beyond the old W.
        let kept: Vec<(usize, usize)> = old
            .iter()
            .enumerate()
            .filter_map(|(i, o)| o.map(|o| (i, o)))
            .collect();
        let new: Vec<usize> = (0..wanted.len()).filter(|&i| old[i].is_none()).collect();
        let mut w = Mat::<f64>::zeros(n, wanted.len());
        for (j, &(_, old)) in kept.iter().enumerate() {
            w.col_mut(j).copy_from(self.w.col(old));
        }
        // W's new columns: L⁻¹ P uᵢ.
        for (j, &i) in new.iter().enumerate() {
            for (d, c) in wanted[i].1.iter() {
                w[(d, kept.len() + j)] += c;
            }
        }
        if !new.is_empty() {
            factor.forward_block_in_place(w.as_mut().subcols_mut(kept.len(), new.len()));
        }
        self.w = w;
        self.columns = kept
            .iter()
            .map(|&(i, _)| i)
            .chain(new.iter().copied())
            .map(|i| (wanted[i].0, wanted[i].2))
            .collect();
        self.capacitance = self.capacitance_lu();
        new.len()
    }

    /// `C = S⁻¹ + Wᵀ W`, LU-factored (partial pivoting: C is indefinite when a link left the
    /// matrix); `None` if a weight is zero or C is singular.
    fn capacitance_lu(&self) -> Option<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>> {
        let r = self.rank();
        if r == 0
            || self
                .columns
                .iter()
                .any(|&(_, s)| s == 0.0 || !s.is_finite())
        {
            return None;
        }
        let mut gram = Mat::<f64>::zeros(r, r);
        matmul(
            gram.as_mut(),
            Accum::Replace,
            self.w.transpose(),
            self.w.as_ref(),
            1.0,
            Par::Seq,
        );
        let c = DMatrix::from_fn(r, r, |i, j| {
            gram[(i, j)] + if i == j { 1.0 / self.columns[i].1 } else { 0.0 }
        });
        let lu = c.lu();
        lu.is_invertible().then_some(lu)
    }

    /// No change, or a regular capacitance C: [`LowRankUpdate::solve_in_place`] solves with
    /// the changed matrix.
    pub fn is_solvable(&self) -> bool {
        self.rank() == 0 || self.capacitance.is_some()
    }

    /// `x ← (A + U S Uᵀ)⁻¹ x` (with no change, `x ← A⁻¹ x`). Only meaningful when
    /// [`LowRankUpdate::is_solvable`]; otherwise the correction is skipped.
    pub fn solve_in_place(&self, factor: &SparseCholesky, x: &mut [f64]) {
        let n = x.len();
        factor.forward_block_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
        if let Some(lu) = &self.capacitance {
            // y ← y − W C⁻¹ Wᵀ y, the two products with W by faer's matrix products.
            let r = self.rank();
            let mut wt_y = DVector::zeros(r);
            matmul(
                MatMut::from_column_major_slice_mut(wt_y.as_mut_slice(), r, 1),
                Accum::Replace,
                self.w.transpose(),
                MatRef::from_column_major_slice(x, n, 1),
                1.0,
                Par::Seq,
            );
            let t = lu.solve(&wt_y);
            if let Some(t) = t.filter(|t| t.iter().all(|v| v.is_finite())) {
                matmul(
                    MatMut::from_column_major_slice_mut(x, n, 1),
                    Accum::Add,
                    self.w.as_ref(),
                    MatRef::from_column_major_slice(t.as_slice(), r, 1),
                    -1.0,
                    Par::Seq,
                );
            }
        }
        factor.backward_in_place(x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::StiffnessPattern;

    /// A chain of springs (three dofs per node) with a soft spring on every dof, and the rows
    /// of all its links.
    fn chain(nodes: usize) -> (StiffnessPattern, Vec<SparseRow>) {
        let mut rows = Vec::new();
        for v in 0..nodes - 1 {
            for k in 0..3 {
                rows.push(SparseRow::new([
                    (Some(3 * v + k), -1.0),
                    (Some(3 * (v + 1) + k), 1.0),
                    (Some(3 * v + (k + 1) % 3), 0.3),
                ]));
            }
            if v + 2 < nodes {
                rows.push(SparseRow::new([
                    (Some(3 * v), -0.5),
                    (Some(3 * (v + 2) + 1), 0.7),
                ]));
            }
        }
        for d in 0..3 * nodes {
            rows.push(SparseRow::new([(Some(d), 0.05)]));
        }
        (StiffnessPattern::new(3 * nodes, &rows), rows)
    }

    /// Links taken out of the factored matrix and others put back: the solve is the one of the
    /// changed matrix factored afresh, and kept columns give the same answer as new ones.
    #[test]
    fn solves_with_the_changed_matrix() {
        let (p, rows) = chain(60);
        let stiffness = |i: usize| 1.0 + (i % 5) as f64;
        let base_in = |i: usize| i % 7 != 3;
        let mut base = vec![0.0; p.nnz()];
        p.assemble(
            &rows,
            |i| if base_in(i) { stiffness(i) } else { 0.0 },
            &mut base,
        );
        let mut factor = SparseCholesky::analyse(&p, Par::Seq);
        factor.factorize(&p, &base).expect("regular");
        // Out: 10, 20, 40 (were in); in: 3, 10 + 7 · 5 = 45 (were out).
        let flip = [10usize, 20, 40, 3, 45];
        let changed_in = |i: usize| base_in(i) != flip.contains(&i);
        let mut target = vec![0.0; p.nnz()];
        p.assemble(
            &rows,
            |i| if changed_in(i) { stiffness(i) } else { 0.0 },
            &mut target,
        );
        let mut exact = factor.share_symbolic();
        exact.factorize(&p, &target).expect("regular");
        let b: Vec<f64> = (0..p.n).map(|i| ((i * 13) % 7) as f64 - 3.0).collect();
        let mut expected = b.clone();
        exact.solve_in_place(&mut expected);

        let weight = |i: usize| {
            if base_in(i) {
                -stiffness(i)
            } else {
                stiffness(i)
            }
        };
        let wanted: Vec<(usize, &SparseRow, f64)> =
            flip.iter().map(|&i| (i, &rows[i], weight(i))).collect();
        let mut update = LowRankUpdate::none(p.n);
        assert_eq!(update.update(&factor, &wanted[..3]), 3);
        assert_eq!(update.update(&factor, &wanted), 2, "three columns kept");
        let mut x = b.clone();
        assert!(update.is_solvable());
        update.solve_in_place(&factor, &mut x);
        for (x, e) in x.iter().zip(&expected) {
            assert!((x - e).abs() <= 1e-10 * e.abs().max(1.0), "{x} against {e}");
        }
        // Without the change: a plain solve with the factor, different from the changed one.
        let mut plain = b.clone();
        let none = LowRankUpdate::none(p.n);
        assert!(none.is_solvable());
        none.solve_in_place(&factor, &mut plain);
        let mut by_factor = b.clone();
        factor.solve_in_place(&mut by_factor);
        assert_eq!(plain, by_factor);
        assert!(plain
            .iter()
            .zip(&expected)
            .any(|(a, e)| (a - e).abs() > 1e-6));
    }
}
