//! The transpose of a list of [`SparseRow`]s as an incidence: per column, the (row, slot) pairs
//! that touch it, rows in increasing order. It turns `f += Σ_i rowᵢᵀ tᵢ` (a scatter, serial)
//! into per-column gathers that threads can share, each column's terms added in the order
//! of the rows: the same sums, bit for bit, as the serial scatter.

use super::SparseRow;

/// Rows at or beyond this count cannot be packed with their slot in a `u32`.
const MAX_ROWS: usize = 1 << 29;

/// Per column, the (row, slot) pairs of the rows that touch it, packed as `8 row + slot`.
#[derive(Debug, Clone)]
pub struct RowIncidence {
    /// Column c's pairs are `entries[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<usize>,
    entries: Vec<u32>,
}

impl RowIncidence {
    /// The incidence of `rows` on `n_cols` columns; `None` beyond 2²⁹ rows.
    pub fn new(rows: &[SparseRow], n_cols: usize) -> Option<RowIncidence> {
        if rows.len() >= MAX_ROWS {
            return None;
        }
        let mut offsets = vec![0usize; n_cols + 1];
        for row in rows {
            for (d, _) in row.iter() {
                offsets[d + 1] += 1;
            }
        }
        for c in 0..n_cols {
            offsets[c + 1] += offsets[c];
        }
        let mut next = offsets.clone();
        let mut entries = vec![0u32; offsets[n_cols]];
        for (i, row) in rows.iter().enumerate() {
            for slot in 0..row.len as usize {
                let d = row.dofs[slot] as usize;
                entries[next[d]] = (8 * i + slot) as u32;
                next[d] += 1;
            }
        }
        Some(RowIncidence { offsets, entries })
    }

    /// The (row, slot) pairs touching column `c`, rows in increasing order.
    #[inline]
    pub fn column(&self, c: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.entries[self.offsets[c]..self.offsets[c + 1]]
            .iter()
            .map(|&e| ((e >> 3) as usize, (e & 7) as usize))
    }

    /// Number of columns.
    pub fn n_cols(&self) -> usize {
        self.offsets.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A gather through the incidence gives the serial scatter's sums bit for bit.
    #[test]
    fn gathers_equal_the_serial_scatter_bit_for_bit() {
        let n = 50;
        let rows: Vec<SparseRow> = (0..400)
            .map(|i| {
                let (a, b) = ((i * 7) % n, (i * 13 + 5) % n);
                let c = 1.0 / (1.0 + i as f64);
                SparseRow::new([(Some(a), c), (None, 2.0), (Some(b), -c * 3.3)])
            })
            .collect();
        let t: Vec<f64> = (0..rows.len()).map(|i| (i as f64).sin() * 1e3).collect();
        let mut scattered = vec![0.0; n];
        for (row, &ti) in rows.iter().zip(&t) {
            row.scatter(ti, &mut scattered);
        }
        let incidence = RowIncidence::new(&rows, n).expect("few rows");
        assert_eq!(incidence.n_cols(), n);
        let gathered: Vec<f64> = (0..n)
            .map(|c| {
                let mut sum = 0.0;
                for (i, slot) in incidence.column(c) {
                    assert_eq!(rows[i].dofs[slot] as usize, c);
                    sum += rows[i].coef[slot] * t[i];
                }
                sum
            })
            .collect();
        for (a, b) in scattered.iter().zip(&gathered) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }
}
