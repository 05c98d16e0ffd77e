//! A sparse Cholesky factor in two halves factored side by side: the top level of a nested
//! dissection splits the dofs into two parts A, B and a separator S (in the factor's order
//! A, B, S; no entry couples A with B). Each half `M_h = K[h ∪ S, h ∪ S]`, a principal
//! submatrix (so positive definite), is factored by faer on its own thread:
//! `L(M_h) = [L_hh 0; L_Sh T_h]` with `T_h T_hᵀ = K_SS − K_Sh K_hh⁻¹ K_hS`. Then
//! `S̃ = T_A T_Aᵀ + T_B T_Bᵀ − K_SS` is K's Schur complement on S, factored densely
//! (`S̃ = L̃ L̃ᵀ`), and `K = L Lᵀ` with `L = [L_AA 0 0; 0 L_BB 0; L_SA L_SB L̃]`.
//!
//! faer 0.24's supernodal factorization works through the supernodes in one loop (its
//! parallelism is inside each front's dense kernels), which gains 1.1× from a second thread
//! on a 256 × 256 grid's K; two whole factorizations run side by side at 1.7–1.9× the
//! throughput of one (`cargo bench --bench latin -- factor`). This split is what takes the
//! second thread to the elimination tree's two halves. Not faer's own code: a block
//! elimination (substructuring) around two of its factors and a dense one.
//!
//! Recursively, a half `M_h` in its order (h's own two parts, its separator S_h, then S) is
//! split the same way at the next level of the dissection tree: its halves side by side, then
//! `S_h ∪ S` dense, whose trailing |S| × |S| block is T_h. k levels give 2^k subtrees on as
//! many threads (the Schwarz coarse matrix; newton's Hessian keeps one level).
//! A quasi-definite K splits with signed `L̂ J L̂ᵀ` leaves (`src/linalg/split_quasi_definite.rs`).

use super::nested_dissection::SplitTree;
use super::{NodeOrdering, NotPositiveDefinite, SparseCholesky, SparseLdlt, StiffnessPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::matmul::triangular::{matmul as triangular_matmul, BlockStructure};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::{supernodal, SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::SparseColMatRef;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use std::sync::Arc;

/// A slot of K that is not in a half.
const NONE: u32 = u32::MAX;

/// No split beyond a separator of this many dofs: its three dense |S| × |S| matrices (T_A,
/// T_B, L̃) would outgrow the halves (a 1024 × 1024 grid's top separator has about 9 000).
const MAX_SEPARATOR: usize = 6_000;

/// One half `M_h = K[h ∪ S, h ∪ S]`, in the factor's order (h's dofs, then S's).
#[derive(Clone)]
struct Half {
    /// The half's first position in the factor's order, and its number of dofs (S aside).
    offset: usize,
    len: usize,
    /// Shared by the copies of a split (a copy holds its own numbers only).
    pattern: Arc<StiffnessPattern>,
    factor: HalfFactor,
    /// Per slot of K, its slot in the half's values ([`NONE`]: not in the half).
    slot: Arc<Vec<u32>>,
    /// `T_h`, the trailing |S| × |S| block of L(M_h) (lower), and `T_h T_hᵀ` (its lower
    /// triangle), from the last factorization.
    trailing: Mat<f64>,
    gram: Mat<f64>,
    /// M_h's values, kept between factorizations.
    values: Vec<f64>,
}

/// A half's factor: faer's, or the half split again at the next level of the tree (its own
/// two halves and the separator of both levels, `S_h ∪ S`, dense), in the half's own order.
#[derive(Clone)]
enum HalfFactor {
    Whole(SparseCholesky),
    /// A leaf of a quasi-definite split: `M_h = L̂ J L̂ᵀ` with its pivots' signs (the half's
    /// own dofs' signs, then + on S) and their regularisation.
    Signed {
        ldlt: SparseLdlt,
        signs: Vec<i8>,
        regularisation: f64,
    },
    Split {
        split: Box<SplitCholesky>,
        /// The identity order of the half, which the split's solves take.
        identity: Vec<usize>,
    },
}

/// K in two halves and a separator (module doc).
#[derive(Clone)]
pub(super) struct SplitCholesky {
    halves: [Half; 2],
    /// The separator's first position and its size.
    separator: (usize, usize),
    /// K's entries in S × S: (slot of K, row, column), local to S, row ≥ column.
    separator_entries: Vec<(u32, u32, u32)>,
    /// L̃ (lower), `L̃ L̃ᵀ = S̃`, from the last factorization.
    schur: Mat<f64>,
    factorized: bool,
}

impl SplitCholesky {
    /// The split of `pattern` in the order whose inverse is `inverse` (`inverse[d]`: the
    /// position of dof d) and whose first `tree.parts[0]` positions are A, the next
    /// `tree.parts[1]` B, each half split again by its subtree down to `levels` levels. `None`
    /// when the order's top level is not such a split (an entry couples A with B, or a part
    /// is empty); a half whose own split fails is factored whole.
    ///
    /// `signs`: for a quasi-definite K, each position's pivot sign and their regularisation
    /// (module doc); `None` also when a separator holds a − pivot.
    pub(super) fn new(
        pattern: &StiffnessPattern,
        inverse: &[usize],
        tree: &SplitTree,
        levels: usize,
        signs: Option<(&[i8], f64)>,
    ) -> Option<SplitCholesky> {
        let n = pattern.n;
        let [a, b] = tree.parts;
        let s0 = a + b;
        if a == 0 || b == 0 || s0 >= n || n - s0 > MAX_SEPARATOR {
            return None;
        }
        if signs.is_some_and(|(signs, _)| signs[s0..].iter().any(|&s| s < 0)) {
            return None;
        }
        let part = |p: usize| -> usize {
            match p {
                _ if p < a => 0,
                _ if p < s0 => 1,
                _ => 2,
            }
        };
        let offsets = [0, a];
        let lens = [a, b];
        // Position p of half h (or of S) → its index in M_h.
        let local = |h: usize, p: usize| -> usize {
            if p >= s0 {
                lens[h] + (p - s0)
            } else {
                p - offsets[h]
            }
        };
        let mut entries: [Vec<(usize, usize)>; 2] = [Vec::new(), Vec::new()];
        let mut separator_entries = Vec::new();
        let mut owner = vec![[false; 2]; pattern.nnz()];
        for c in 0..n {
            for slot in pattern.col_ptr[c]..pattern.col_ptr[c + 1] {
                let (pr, pc) = (inverse[pattern.row_idx[slot]], inverse[c]);
                let (hr, hc) = (part(pr), part(pc));
                // Which halves hold the entry: both for S × S, else the one it touches.
                let halves: [Option<usize>; 2] = match (hr, hc) {
                    (2, 2) => [Some(0), Some(1)],
                    (h, 2) | (2, h) => [Some(h), None],
                    (h, k) if h == k => [Some(h), None],
                    _ => return None,
                };
                if (hr, hc) == (2, 2) {
                    let (r, c) = (pr.max(pc) - s0, pr.min(pc) - s0);
                    separator_entries.push((slot as u32, r as u32, c as u32));
                }
                for h in halves.into_iter().flatten() {
                    let (lr, lc) = (local(h, pr), local(h, pc));
                    entries[h].push((lr.max(lc), lr.min(lc)));
                    owner[slot][h] = true;
                }
            }
        }
        let m = n - s0;
        let make = |h: usize| -> Half {
            let size = lens[h] + m;
            let half_pattern = StiffnessPattern::from_lower_entries(size, &entries[h]);
            let mut slot = vec![NONE; pattern.nnz()];
            for c in 0..n {
                for k in pattern.col_ptr[c]..pattern.col_ptr[c + 1] {
                    if owner[k][h] {
                        let (lr, lc) =
                            (local(h, inverse[pattern.row_idx[k]]), local(h, inverse[c]));
                        let at = half_pattern
                            .slot(lr.max(lc), lr.min(lc))
                            .expect("the half's pattern holds its entries");
                        slot[k] = at as u32;
                    }
                }
            }
            let identity: Vec<usize> = (0..size).collect();
            let below = tree.children[h].as_deref().filter(|_| levels > 1);
            let half_signs = signs.map(|(signs, r)| (half_signs(signs, offsets[h], lens[h], m), r));
            let split = below.and_then(|t| {
                let signs = half_signs.as_ref().map(|(s, r)| (s.as_slice(), *r));
                SplitCholesky::new(&half_pattern, &identity, t, levels - 1, signs)
            });
            let factor = match (split, half_signs) {
                (Some(split), _) => HalfFactor::Split {
                    split: Box::new(split),
                    identity,
                },
                (None, Some((signs, regularisation))) => HalfFactor::Signed {
                    ldlt: SparseLdlt::analyse_ordered(&half_pattern, NodeOrdering::Given),
                    signs,
                    regularisation,
                },
                (None, None) => HalfFactor::Whole(SparseCholesky::analyse_ordered(
                    &half_pattern,
                    Par::Seq,
                    NodeOrdering::Given,
                )),
            };
            Half {
                offset: offsets[h],
                len: lens[h],
                pattern: Arc::new(half_pattern),
                factor,
                slot: Arc::new(slot),
                trailing: Mat::zeros(0, 0),
                gram: Mat::zeros(0, 0),
                values: Vec::new(),
            }
        };
        let (first, second) = rayon::join(|| make(0), || make(1));
        let halves = [first, second];
        Some(SplitCholesky {
            halves,
            separator: (s0, m),
            separator_entries,
            schur: Mat::zeros(0, 0),
            factorized: false,
        })
    }

    /// The levels of the tree this split factors side by side (1: two halves).
    pub(super) fn levels(&self) -> usize {
        1 + self
            .halves
            .iter()
            .map(|h| match &h.factor {
                HalfFactor::Whole(_) | HalfFactor::Signed { .. } => 0,
                HalfFactor::Split { split, .. } => split.levels(),
            })
            .max()
            .unwrap_or(0)
    }

    /// Values it stores: its halves' factors, their trailing blocks and Gram matrices, and the
    /// separator's dense factor.
    pub(super) fn entries(&self) -> usize {
        let (_, m) = self.separator;
        let half = |h: &Half| {
            2 * m * m
                + match &h.factor {
                    HalfFactor::Whole(f) => f.l_values.len(),
                    HalfFactor::Signed { ldlt, .. } => ldlt.l_values.len(),
                    HalfFactor::Split { split, .. } => split.entries(),
                }
        };
        m * m + self.halves.iter().map(half).sum::<usize>()
    }

    /// `K = L Lᵀ` for K's `values` (on the pattern it was split from): the two halves side
    /// by side, then the Schur complement on the separator.
    pub(super) fn factorize(&mut self, values: &[f64]) -> Result<(), NotPositiveDefinite> {
        self.factorized = false;
        let (s0, m) = self.separator;
        let [first, second] = &mut self.halves;
        // 1. M_A and M_B factored on two threads; each keeps T_h and T_h T_hᵀ.
        let (a, b) = rayon::join(
            || first.factorize(values, m),
            || second.factorize(values, m),
        );
        a?;
        b?;
        // 2. S̃ = T_A T_Aᵀ + T_B T_Bᵀ − K_SS (lower triangle), into L̃'s storage.
        let schur = &mut self.schur;
        if schur.nrows() != m {
            *schur = Mat::zeros(m, m);
        }
        let (ga, gb) = (&self.halves[0].gram, &self.halves[1].gram);
        for j in 0..m {
            for i in j..m {
                schur[(i, j)] = ga[(i, j)] + gb[(i, j)];
            }
        }
        for &(slot, r, c) in &self.separator_entries {
            schur[(r as usize, c as usize)] -= values[slot as usize];
        }
        // 3. S̃ = L̃ L̃ᵀ, in place.
        let par = Par::rayon(0);
        let mut scratch =
            MemBuffer::new(cholesky_in_place_scratch::<f64>(m, par, Default::default()));
        cholesky_in_place(
            schur.as_mut(),
            Default::default(),
            par,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .map_err(|_| NotPositiveDefinite { pivot: s0 })?;
        self.factorized = true;
        Ok(())
    }

    /// `X ← L⁻¹ P X`, left in the factor's order (`order[k]`: the dof at position k): the
    /// halves' forward solves side by side, then L̃'s.
    pub(super) fn forward_block_in_place(&self, order: &[usize], mut x: MatMut<'_, f64>) {
        assert!(self.factorized, "solve before a successful factorization");
        let (s0, m) = self.separator;
        let k = x.ncols();
        let permuted = Mat::from_fn(x.nrows(), k, |i, j| x[(order[i], j)]);
        let [first, second] = &self.halves;
        // Y_h = L_hh⁻¹ B_h and C_h = L_Sh Y_h = −T_h Z_h, Z_h the separator part of
        // L(M_h)⁻¹ [B_h; 0].
        let ((ya, ca), (yb, cb)) = rayon::join(
            || first.forward(permuted.as_ref(), m),
            || second.forward(permuted.as_ref(), m),
        );
        let mut ys = Mat::from_fn(m, k, |i, j| permuted[(s0 + i, j)] - ca[(i, j)] - cb[(i, j)]);
        solve_lower_triangular_in_place(self.schur.as_ref(), ys.as_mut(), Par::Seq);
        x.as_mut()
            .subrows_mut(first.offset, first.len)
            .copy_from(&ya);
        x.as_mut()
            .subrows_mut(second.offset, second.len)
            .copy_from(&yb);
        x.as_mut().subrows_mut(s0, m).copy_from(&ys);
    }

    /// `x ← Pᵀ L⁻ᵀ x` for one column in the factor's order (`inverse[d]`: the position of dof
    /// d): L̃'s backward solve, then the halves' side by side.
    pub(super) fn backward_in_place(&self, inverse: &[usize], x: &mut [f64]) {
        assert!(self.factorized, "solve before a successful factorization");
        let (s0, m) = self.separator;
        let mut xs = x[s0..].to_vec();
        solve_upper_triangular_in_place(
            self.schur.as_ref().transpose(),
            MatMut::from_column_major_slice_mut(&mut xs, m, 1),
            Par::Seq,
        );
        let [first, second] = &self.halves;
        // x_h = L_hh⁻ᵀ (y_h − L_Shᵀ x_S): L(M_h)⁻ᵀ [y_h; T_hᵀ x_S].
        let (xa, xb) = rayon::join(|| first.backward(x, &xs), || second.backward(x, &xs));
        let mut permuted = vec![0.0; x.len()];
        permuted[first.offset..first.offset + first.len].copy_from_slice(&xa);
        permuted[second.offset..second.offset + second.len].copy_from_slice(&xb);
        permuted[s0..].copy_from_slice(&xs);
        for (v, &at) in x.iter_mut().zip(inverse) {
            *v = permuted[at];
        }
    }

    /// `X ← K⁻¹ X`: the block forward, then each column backward.
    pub(super) fn solve_block_in_place(
        &self,
        (order, inverse): (&[usize], &[usize]),
        mut x: MatMut<'_, f64>,
    ) {
        self.forward_block_in_place(order, x.as_mut());
        for j in 0..x.ncols() {
            let mut column: Vec<f64> = x.as_ref().col(j).iter().copied().collect();
            self.backward_in_place(inverse, &mut column);
            x.as_mut()
                .col_mut(j)
                .copy_from(faer::ColRef::from_slice(&column));
        }
    }
}

impl Half {
    /// M_h's values from K's, factored; T_h and `T_h T_hᵀ` kept.
    fn factorize(&mut self, values: &[f64], m: usize) -> Result<(), NotPositiveDefinite> {
        self.values.resize(self.pattern.nnz(), 0.0);
        for (&slot, &v) in self.slot.iter().zip(values) {
            if slot != NONE {
                self.values[slot as usize] = v;
            }
        }
        let factored = match &mut self.factor {
            HalfFactor::Whole(factor) => factor.factorize(&self.pattern, &self.values),
            HalfFactor::Signed {
                ldlt,
                signs,
                regularisation,
            } => ldlt
                .factorize_signed(&self.values, signs, *regularisation)
                .map_err(|e| NotPositiveDefinite { pivot: e.pivot }),
            HalfFactor::Split { split, .. } => split.factorize(&self.values),
        };
        factored.map_err(|e| NotPositiveDefinite {
            pivot: self.offset + e.pivot,
        })?;
        match &self.factor {
            HalfFactor::Whole(factor) => trailing_block(
                &factor.analysis.symbolic,
                &factor.l_values,
                self.len,
                &mut self.trailing,
            ),
            // L D Lᵀ's trailing block holds D_SS on its diagonal: T_h = L_SS D_SS^½, D_SS > 0
            // (module doc).
            HalfFactor::Signed { ldlt, .. } => {
                trailing_block(
                    &ldlt.analysis.symbolic,
                    &ldlt.l_values,
                    self.len,
                    &mut self.trailing,
                );
                for j in 0..m {
                    let d = self.trailing[(j, j)];
                    if d.is_nan() || d <= 0.0 {
                        return Err(NotPositiveDefinite {
                            pivot: self.offset + self.len + j,
                        });
                    }
                    let root = d.sqrt();
                    self.trailing[(j, j)] = root;
                    for i in j + 1..m {
                        self.trailing[(i, j)] *= root;
                    }
                }
            }
            // The half's trailing block lies in its split's dense separator block, after the
            // half's own separator S_h.
            HalfFactor::Split { split, .. } => {
                let from = self.len - split.separator.0;
                self.trailing = split.schur.as_ref().submatrix(from, from, m, m).to_owned();
            }
        }
        debug_assert_eq!(self.trailing.nrows(), m);
        if self.gram.nrows() != m {
            self.gram = Mat::zeros(m, m);
        }
        // T_h T_hᵀ: lower triangular times upper triangular, its lower half.
        triangular_matmul(
            self.gram.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            self.trailing.as_ref(),
            BlockStructure::TriangularLower,
            self.trailing.as_ref().transpose(),
            BlockStructure::TriangularUpper,
            1.0,
            Par::Seq,
        );
        Ok(())
    }

    /// `(Y_h, C_h)` of the forward solve (see [`SplitCholesky::forward_block_in_place`]),
    /// from K's right-hand sides in the factor's order.
    fn forward(&self, permuted: MatRef<'_, f64>, m: usize) -> (Mat<f64>, Mat<f64>) {
        let k = permuted.ncols();
        let mut z = Mat::zeros(self.len + m, k);
        z.as_mut()
            .subrows_mut(0, self.len)
            .copy_from(permuted.subrows(self.offset, self.len));
        match &self.factor {
            HalfFactor::Whole(factor) => factor.forward_block_in_place(z.as_mut()),
            HalfFactor::Signed { ldlt, .. } => ldlt.forward_scaled_block_in_place(z.as_mut()),
            HalfFactor::Split { split, identity } => {
                split.forward_block_in_place(identity, z.as_mut())
            }
        }
        let mut c = Mat::zeros(m, k);
        // C_h = −T_h Z_S.
        triangular_matmul(
            c.as_mut(),
            BlockStructure::Rectangular,
            Accum::Replace,
            self.trailing.as_ref(),
            BlockStructure::TriangularLower,
            z.as_ref().subrows(self.len, m),
            BlockStructure::Rectangular,
            -1.0,
            Par::Seq,
        );
        (z.as_ref().subrows(0, self.len).to_owned(), c)
    }

    /// `x_h` of the backward solve, from `y` (the factor's order) and x_S.
    fn backward(&self, y: &[f64], xs: &[f64]) -> Vec<f64> {
        let m = xs.len();
        let mut v = vec![0.0; self.len + m];
        v[..self.len].copy_from_slice(&y[self.offset..self.offset + self.len]);
        // T_hᵀ x_S.
        triangular_matmul(
            MatMut::from_column_major_slice_mut(&mut v[self.len..], m, 1),
            BlockStructure::Rectangular,
            Accum::Replace,
            self.trailing.as_ref().transpose(),
            BlockStructure::TriangularUpper,
            MatRef::from_column_major_slice(xs, m, 1),
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        match &self.factor {
            HalfFactor::Whole(factor) => factor.backward_in_place(&mut v),
            HalfFactor::Signed { ldlt, .. } => ldlt.backward_scaled_in_place(&mut v),
            HalfFactor::Split { split, identity } => split.backward_in_place(identity, &mut v),
        }
        v.truncate(self.len);
        v
    }
}

/// The signs of a half's positions: its own (`len` from `offset`), then + on the separator's
/// `m`.
fn half_signs(signs: &[i8], offset: usize, len: usize, m: usize) -> Vec<i8> {
    let own = &signs[offset..offset + len];
    own.iter()
        .copied()
        .chain(std::iter::repeat_n(1, m))
        .collect()
}

/// `block ← L[from.., from..]` of the factor `l_values` on `analysis` (lower, in the factor's
/// order, an L D Lᵀ factor's D on the diagonal; `block` reshaped if it is not that size).
fn trailing_block(
    symbolic: &SymbolicCholesky<usize>,
    l_values: &[f64],
    from: usize,
    block: &mut Mat<f64>,
) {
    let n = symbolic.nrows();
    if (block.nrows(), block.ncols()) == (n - from, n - from) {
        block.fill(0.0);
    } else {
        *block = Mat::zeros(n - from, n - from);
    }
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let l = SparseColMatRef::new(s.factor(), l_values);
            for j in from..n {
                for (i, v) in l.row_idx_of_col(j).zip(l.val_of_col(j)) {
                    block[(i - from, j - from)] = *v;
                }
            }
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let l = supernodal::SupernodalLltRef::new(s, l_values);
            for k in 0..s.n_supernodes() {
                let node = l.supernode(k);
                let (start, values) = (node.start(), node.val());
                let columns = values.ncols();
                for jj in (0..columns).filter(|&jj| start + jj >= from) {
                    let j = start + jj - from;
                    for ii in jj..columns {
                        block[(start + ii - from, j)] = values[(ii, jj)];
                    }
                    for (t, &row) in node.pattern().iter().enumerate() {
                        block[(row - from, j)] = values[(columns + t, jj)];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
