//! The lower-triangular CSC pattern of `Σ_i w_i rowᵢᵀ rowᵢ` (plus every diagonal entry) for a
//! list of [`SparseRow`]s, with the value slot of each row's entries precomputed so that a
//! numeric assembly with new weights is one pass over the rows. The pattern never changes with
//! the weights: a zero weight leaves its slots in place, so one symbolic factorization serves
//! every set of weights (for a stiffness, every set of taut members).

use super::SparseRow;

/// Lower-triangular CSC sparsity pattern of `Σ_i w_i rowᵢᵀ rowᵢ`, with every diagonal entry,
/// and the value slots each row adds into.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessPattern {
    /// Order of the matrix (number of dofs).
    pub n: usize,
    /// Column `c`'s entries are slots `col_ptr[c]..col_ptr[c + 1]` (length `n + 1`).
    pub col_ptr: Vec<usize>,
    /// Row index of each slot, increasing within a column, all `≥` the column.
    pub row_idx: Vec<usize>,
    /// Slot of each diagonal entry.
    pub diag_slot: Vec<usize>,
    /// Per row `i`, `slots[offsets[i]..offsets[i+1]]`: the slots of its pairs `(p, q)` with
    /// `dof_p ≥ dof_q`, in the order of [`StiffnessPattern::assemble`]'s double loop.
    slots: Vec<u32>,
    offsets: Vec<usize>,
}

impl StiffnessPattern {
    /// The pattern of `n` dofs for `sparse_rows`, whatever their weights (zero ones included).
    pub fn new(n: usize, sparse_rows: &[SparseRow]) -> StiffnessPattern {
        // Every pair (p, q), p ≥ q, of every row, numbered g in the order of `assemble`'s
        // double loop: g is its position in `slots`.
        let mut offsets = Vec::with_capacity(sparse_rows.len() + 1);
        offsets.push(0);
        let mut count = vec![0u32; n];
        for ld in sparse_rows {
            let mut pairs = 0;
            for (p, _) in ld.iter() {
                for (q, _) in ld.iter() {
                    if p >= q {
                        count[q] += 1;
                        pairs += 1;
                    }
                }
            }
            offsets.push(offsets.last().copied().unwrap_or(0) + pairs);
        }
        let total = offsets.last().copied().unwrap_or(0);
        assert!(
            total < u32::MAX as usize && n < u32::MAX as usize,
            "pattern too large for 32-bit slots"
        );
        // Bucket the pairs by column q (counting sort): (row p, pair number g).
        let mut start = vec![0usize; n + 1];
        for c in 0..n {
            start[c + 1] = start[c] + count[c] as usize;
        }
        let mut bucket = vec![(0u32, 0u32); total];
        let mut fill = start[..n].to_vec();
        let mut g = 0u32;
        for ld in sparse_rows {
            for (p, _) in ld.iter() {
                for (q, _) in ld.iter() {
                    if p >= q {
                        bucket[fill[q]] = (p as u32, g);
                        fill[q] += 1;
                        g += 1;
                    }
                }
            }
        }
        drop(fill);
        // Column by column: its distinct rows (the diagonal first), sorted; then each pair's
        // slot by a dense row → slot map valid for this column (no search per pair).
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx: Vec<usize> = Vec::with_capacity(total / 2 + n);
        let mut diag_slot = Vec::with_capacity(n);
        let mut slots = vec![0u32; total];
        let mut seen_in = vec![u32::MAX; n];
        let mut slot_of = vec![0u32; n];
        for c in 0..n {
            let first = row_idx.len();
            row_idx.push(c);
            seen_in[c] = c as u32;
            for &(p, _) in &bucket[start[c]..start[c + 1]] {
                if seen_in[p as usize] != c as u32 {
                    seen_in[p as usize] = c as u32;
                    row_idx.push(p as usize);
                }
            }
            row_idx[first..].sort_unstable();
            for (k, &r) in row_idx[first..].iter().enumerate() {
                slot_of[r] = (first + k) as u32;
            }
            diag_slot.push(first);
            for &(p, g) in &bucket[start[c]..start[c + 1]] {
                slots[g as usize] = slot_of[p as usize];
            }
            col_ptr.push(row_idx.len());
        }
        StiffnessPattern {
            n,
            col_ptr,
            row_idx,
            diag_slot,
            slots,
            offsets,
        }
    }

    /// The pattern of the lower-triangle entries `(row, column)` (`row ≥ column`, repeats
    /// allowed) and every diagonal entry, for a matrix assembled entry by entry rather than
    /// from rows: it has no row slots, so [`StiffnessPattern::assemble`], `add_outer` and
    /// `add_block` are not for it; values go in through [`StiffnessPattern::slot`].
    pub fn from_lower_entries(n: usize, entries: &[(usize, usize)]) -> StiffnessPattern {
        let mut columns: Vec<Vec<usize>> = (0..n).map(|c| vec![c]).collect();
        for &(r, c) in entries {
            assert!(
                r >= c && r < n,
                "entry ({r}, {c}) outside the lower triangle of {n}"
            );
            columns[c].push(r);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        let mut diag_slot = Vec::with_capacity(n);
        for mut rows in columns {
            rows.sort_unstable();
            rows.dedup();
            // The diagonal is the smallest row of its column: the column's first slot.
            diag_slot.push(row_idx.len());
            row_idx.extend(rows);
            col_ptr.push(row_idx.len());
        }
        StiffnessPattern {
            n,
            col_ptr,
            row_idx,
            diag_slot,
            slots: Vec::new(),
            offsets: vec![0],
        }
    }

    /// The slot of entry `(row, column)`, `row ≥ column`, if the pattern holds it.
    pub fn slot(&self, row: usize, column: usize) -> Option<usize> {
        let start = self.col_ptr[column];
        self.row_idx[start..self.col_ptr[column + 1]]
            .binary_search(&row)
            .ok()
            .map(|k| start + k)
    }

    /// Number of stored entries (lower triangle with the diagonal).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// `values = Σ_i weight_i Bᵢᵀ Bᵢ` (lower triangle). `rows` must be the slice the pattern
    /// was built from.
    pub fn assemble(&self, rows: &[SparseRow], weight: impl Fn(usize) -> f64, values: &mut [f64]) {
        values.iter_mut().for_each(|v| *v = 0.0);
        for (i, ld) in rows.iter().enumerate() {
            let w = weight(i);
            if w == 0.0 {
                continue;
            }
            let mut s = self.offsets[i];
            for (p, cp) in ld.iter() {
                for (q, cq) in ld.iter() {
                    if p >= q {
                        values[self.slots[s] as usize] += w * cp * cq;
                        s += 1;
                    }
                }
            }
        }
    }

    /// `values += w rowᵀ row` for a row on the same dofs, in the same order, as row `i` of the
    /// rows the pattern was built from (a member's transverse or current-direction row: docs/method.md
    /// §8): it lands in row i's slots.
    pub fn add_outer(&self, i: usize, row: &SparseRow, w: f64, values: &mut [f64]) {
        let mut s = self.offsets[i];
        for (p, cp) in row.iter() {
            for (q, cq) in row.iter() {
                if p >= q {
                    values[self.slots[s] as usize] += w * cp * cq;
                    s += 1;
                }
            }
        }
    }

    /// `values += Σ_{p ≥ q} sign_p sign_q G[comp_p][comp_q]` over the entries `(dof, sign, comp)`
    /// of row `i` of the rows the pattern was built from (the same dofs in the same order): a
    /// two-node member's block `[[G, −G], [−G, G]]` in one pass (docs/method.md §8).
    pub fn add_block(
        &self,
        i: usize,
        entries: &[(usize, f64, usize)],
        g: &[[f64; 3]; 3],
        values: &mut [f64],
    ) {
        let mut s = self.offsets[i];
        for &(p, sp, cp) in entries {
            for &(q, sq, cq) in entries {
                if p >= q {
                    values[self.slots[s] as usize] += sp * sq * g[cp][cq];
                    s += 1;
                }
            }
        }
    }

    /// Every stored entry as `(row, column, slot)`, column by column.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        (0..self.n).flat_map(move |c| {
            (self.col_ptr[c]..self.col_ptr[c + 1]).map(move |s| (self.row_idx[s], c, s))
        })
    }

    /// `y = A x` for a symmetric A stored as this lower triangle.
    pub fn sym_matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..self.n {
            let (start, end) = (self.col_ptr[c], self.col_ptr[c + 1]);
            // The diagonal is the first entry of its column; the others are below it.
            let mut below = 0.0;
            for (&r, &v) in self.row_idx[start..end].iter().zip(&values[start..end]) {
                y[r] += v * x[c];
                if r != c {
                    below += v * x[r];
                }
            }
            y[c] += below;
        }
    }

    /// `Y = M X` for a column-major block X of `x.len() / n` columns ([`Self::sym_matvec`] on
    /// each, in one pass over the pattern: the block is interleaved by rows first, so that
    /// each stored entry is read once for all columns).
    pub fn sym_matmat(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let n = self.n;
        assert_eq!(x.len(), y.len(), "X and Y of different sizes");
        if n == 0 || x.is_empty() {
            return;
        }
        let cols = x.len() / n;
        // Row-interleaved copies: entry (i, k) at i * cols + k.
        let mut xr = vec![0.0; x.len()];
        for (k, column) in x.chunks(n).enumerate() {
            for (i, v) in column.iter().enumerate() {
                xr[i * cols + k] = *v;
            }
        }
        let mut yr = vec![0.0; x.len()];
        let mut below = vec![0.0; cols];
        for c in 0..n {
            let (start, end) = (self.col_ptr[c], self.col_ptr[c + 1]);
            below.iter_mut().for_each(|b| *b = 0.0);
            let xc: Vec<f64> = xr[c * cols..(c + 1) * cols].to_vec();
            for (&r, &v) in self.row_idx[start..end].iter().zip(&values[start..end]) {
                let yr_r = &mut yr[r * cols..(r + 1) * cols];
                yr_r.iter_mut().zip(&xc).for_each(|(t, s)| *t += v * s);
                if r != c {
                    let xr_r = &xr[r * cols..(r + 1) * cols];
                    below.iter_mut().zip(xr_r).for_each(|(b, s)| *b += v * s);
                }
            }
            // M's upper triangle: row c gains the entries below the diagonal of column c.
            yr[c * cols..(c + 1) * cols]
                .iter_mut()
                .zip(&below)
                .for_each(|(t, b)| *t += b);
        }
        for (k, column) in y.chunks_mut(n).enumerate() {
            for (i, v) in column.iter_mut().enumerate() {
                *v = yr[i * cols + k];
            }
        }
    }

    /// Mean of the diagonal: the scale regularisations and thresholds are relative to.
    pub fn mean_diagonal(&self, values: &[f64]) -> f64 {
        if self.n == 0 {
            return 0.0;
        }
        self.diag_slot.iter().map(|&s| values[s]).sum::<f64>() / self.n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    const N: usize = 9;

    /// Rows of 2 to 6 pairs over 9 dofs, indices unsorted, a clamped (`None`) component, and
    /// pairs shared between rows ((3, 0), (7, 6), (8, 2), (5, 4), …).
    fn row_pairs() -> Vec<Vec<(Option<usize>, f64)>> {
        vec![
            vec![(Some(0), 1.0), (Some(3), -2.0)],
            vec![
                (Some(0), 0.5),
                (Some(1), -1.5),
                (Some(2), 2.0),
                (Some(6), -0.7),
                (Some(7), 0.3),
                (Some(8), 1.1),
            ],
            vec![
                (Some(3), 0.8),
                (None, 4.0),
                (Some(4), -0.6),
                (Some(5), 1.2),
                (Some(0), -0.4),
            ],
            vec![(Some(7), -1.0), (Some(6), 1.0), (Some(3), 0.25)],
            vec![(Some(5), 2.5), (Some(4), -0.9), (Some(8), 0.4)],
            vec![(Some(8), -1.0), (Some(2), 1.0)],
        ]
    }

    /// `Σ_i w_i rowᵢᵀ rowᵢ`, dense and full, straight from the pairs.
    fn dense(pairs: &[Vec<(Option<usize>, f64)>], weights: &[f64]) -> Vec<Vec<f64>> {
        let mut k = vec![vec![0.0; N]; N];
        for (row, &w) in pairs.iter().zip(weights) {
            let used: Vec<(usize, f64)> = row.iter().filter_map(|&(d, c)| Some((d?, c))).collect();
            for &(a, ca) in &used {
                for &(b, cb) in &used {
                    k[a][b] += w * ca * cb;
                }
            }
        }
        k
    }

    /// Slot of `(r, c)`, `r ≥ c`, if the pattern stores it.
    fn slot(p: &StiffnessPattern, r: usize, c: usize) -> Option<usize> {
        (p.col_ptr[c]..p.col_ptr[c + 1]).find(|&s| p.row_idx[s] == r)
    }

    fn check_values(p: &StiffnessPattern, values: &[f64], k: &[Vec<f64>]) {
        let scale = k.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for (r, c, s) in p.entries() {
            let expected = k[r][c];
            assert!(
                (values[s] - expected).abs() <= 1e-12 * expected.abs().max(scale),
                "entry ({r}, {c}) at slot {s}: {} assembled, {expected} dense",
                values[s]
            );
        }
        // Every nonzero of the dense lower triangle is stored.
        for (r, row) in k.iter().enumerate() {
            for (c, &value) in row.iter().enumerate().take(r + 1) {
                if value != 0.0 {
                    assert!(slot(p, r, c).is_some(), "nonzero ({r}, {c}) not in pattern");
                }
            }
        }
        // `y = A x` against the dense product.
        let x: Vec<f64> = (0..N)
            .map(|i| 1.0 + 0.37 * i as f64 - 0.05 * (i * i) as f64)
            .collect();
        let mut y = vec![f64::NAN; N];
        p.sym_matvec(values, &x, &mut y);
        for i in 0..N {
            let expected: f64 = (0..N).map(|j| k[i][j] * x[j]).sum();
            assert!(
                (y[i] - expected).abs() <= 1e-12 * scale * x.iter().map(|v| v.abs()).sum::<f64>(),
                "(A x)[{i}]: {} sym_matvec, {expected} dense",
                y[i]
            );
        }
        // `Y = A X` on a block of three columns (x, 2x − 1, and a third) equals `sym_matvec`
        // on each column, to the bit.
        let block: Vec<f64> = (0..3 * N)
            .map(|g| x[g % N] * (1 + g / N) as f64 - (g / N) as f64)
            .collect();
        let mut y_block = vec![f64::NAN; 3 * N];
        p.sym_matmat(values, &block, &mut y_block);
        for (xc, yc) in block.chunks(N).zip(y_block.chunks(N)) {
            let mut single = vec![f64::NAN; N];
            p.sym_matvec(values, xc, &mut single);
            assert_eq!(single, yc, "sym_matmat against sym_matvec");
        }
        let trace: f64 = (0..N).map(|i| k[i][i]).sum();
        assert!((p.mean_diagonal(values) - trace / N as f64).abs() <= 1e-12 * scale);
    }

    #[test]
    fn assembly_matches_dense_sum_of_row_products() {
        let pairs = row_pairs();
        let rows: Vec<SparseRow> = pairs.iter().map(|r| SparseRow::new(r.clone())).collect();
        let p = StiffnessPattern::new(N, &rows);

        // CSC shape: lower triangle, rows increasing within a column, diagonal first.
        assert_eq!(p.n, N);
        assert_eq!(p.col_ptr.len(), N + 1);
        assert_eq!(p.col_ptr[0], 0);
        assert_eq!(p.col_ptr[N], p.nnz());
        assert_eq!(p.row_idx.len(), p.nnz());
        assert_eq!(p.diag_slot.len(), N);
        for c in 0..N {
            let column = &p.row_idx[p.col_ptr[c]..p.col_ptr[c + 1]];
            assert!(
                column.windows(2).all(|w| w[0] < w[1]),
                "column {c}: {column:?}"
            );
            assert!(column.iter().all(|&r| r >= c), "column {c}: {column:?}");
            let d = p.diag_slot[c];
            assert!((p.col_ptr[c]..p.col_ptr[c + 1]).contains(&d));
            assert_eq!(p.row_idx[d], c, "diagonal slot of dof {c}");
        }

        // The pattern is exactly the structural lower triangle of the rows plus the diagonal,
        // whatever the weights.
        let mut structural: BTreeSet<(usize, usize)> = (0..N).map(|d| (d, d)).collect();
        for row in &pairs {
            for &(a, _) in row {
                for &(b, _) in row {
                    if let (Some(a), Some(b)) = (a, b) {
                        structural.insert((a.max(b), a.min(b)));
                    }
                }
            }
        }
        let stored: BTreeSet<(usize, usize)> = (0..N)
            .flat_map(|c| (p.col_ptr[c]..p.col_ptr[c + 1]).map(move |s| (s, c)))
            .map(|(s, c)| (p.row_idx[s], c))
            .collect();
        assert_eq!(stored, structural);
        assert_eq!(p.nnz(), structural.len());

        // Positive and zero weights; the zero-weight row's own pairs (8, 4), (8, 5) keep their
        // slots, holding zero.
        let weights = [1.7, 0.9, 2.3, 4.0, 0.0, 3.0];
        let mut values = vec![f64::NAN; p.nnz()];
        p.assemble(&rows, |i| weights[i], &mut values);
        check_values(&p, &values, &dense(&pairs, &weights));
        assert_eq!(values[slot(&p, 8, 4).expect("slot of (8, 4)")], 0.0);
        assert_eq!(values[slot(&p, 8, 5).expect("slot of (8, 5)")], 0.0);

        // New weights on the same pattern and buffer.
        let weights = [0.0, 2.5, 0.4, 1.0, 6.0, 0.0];
        p.assemble(&rows, |i| weights[i], &mut values);
        check_values(&p, &values, &dense(&pairs, &weights));
    }
}
