//! `out += Σ_i w_i rowᵢᵀ (rowᵢ · v)` (a stiffness `Σ w Bᵢᵀ Bᵢ` applied link by link) over fixed
//! chunks of rows side by side: each chunk scatters into its own buffer over the span of dofs
//! its rows touch, then each dof adds the chunks' buffers in chunk order. The chunks depend on
//! the rows alone, so the sums are the same on any number of threads. Rows numbered along the
//! structure (a grid's, module by module) touch a narrow band of dofs per chunk; where the
//! spans would add up to more than [`MAX_SPAN_RATIO`] times the dofs there is no chunking.

use super::{SparseRow, CHUNK};
use rayon::prelude::*;
use std::ops::Range;

/// Rows per chunk: 4.2 M links of a 512 × 512 grid give 128 chunks.
const ROWS_PER_CHUNK: usize = 32_768;

/// The chunks' spans may add up to this many times the dofs at most.
const MAX_SPAN_RATIO: usize = 2;

/// Fixed chunks of rows and their buffers (module doc).
pub struct RowChunks {
    chunks: Vec<RowChunk>,
}

struct RowChunk {
    rows: Range<usize>,
    /// The dofs its rows touch lie in `span`; its buffer is indexed from `span.start`.
    span: Range<usize>,
    buffer: Vec<f64>,
}

impl RowChunks {
    /// Chunks of `rows` (over `n` dofs); `None` when there are fewer than two or their spans
    /// are too wide.
    pub fn new(rows: &[SparseRow], n: usize) -> Option<RowChunks> {
        if rows.len() < 2 * ROWS_PER_CHUNK {
            return None;
        }
        let chunks: Vec<RowChunk> = (0..rows.len())
            .step_by(ROWS_PER_CHUNK)
            .map(|start| {
                let range = start..(start + ROWS_PER_CHUNK).min(rows.len());
                let (lo, hi) = rows[range.clone()]
                    .iter()
                    .flat_map(|row| row.iter().map(|(d, _)| d))
                    .fold((usize::MAX, 0), |(lo, hi), d| (lo.min(d), hi.max(d + 1)));
                RowChunk {
                    rows: range,
                    span: lo.min(hi)..hi,
                    buffer: Vec::new(),
                }
            })
            .collect();
        let spans: usize = chunks.iter().map(|c| c.span.len()).sum();
        (spans <= MAX_SPAN_RATIO * n.max(1)).then_some(RowChunks { chunks })
    }

    /// `out += Σ_i weight(i) rowᵢᵀ (rowᵢ · v)`, rows of weight 0 skipped.
    pub fn product_add(
        &mut self,
        rows: &[SparseRow],
        weight: impl Fn(usize) -> f64 + Sync,
        v: &[f64],
        out: &mut [f64],
    ) {
        // 1. Each chunk into its buffer, side by side.
        self.chunks.par_iter_mut().for_each(|chunk| {
            let lo = chunk.span.start;
            chunk.buffer.clear();
            chunk.buffer.resize(chunk.span.len(), 0.0);
            for i in chunk.rows.clone() {
                let w = weight(i);
                if w == 0.0 {
                    continue;
                }
                // t = w rowᵢ · v; buffer += rowᵢᵀ t.
                let row = &rows[i];
                let t = w * row.elongation(v);
                for (d, c) in row.iter() {
                    chunk.buffer[d - lo] += c * t;
                }
            }
        });
        // 2. Each dof adds the buffers that cover it, in chunk order.
        let chunks = &self.chunks;
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(block, out)| {
                let start = block * CHUNK;
                let end = start + out.len();
                for chunk in chunks {
                    let (from, to) = (chunk.span.start.max(start), chunk.span.end.min(end));
                    for d in from..to {
                        out[d - start] += chunk.buffer[d - chunk.span.start];
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows along a chain of `n` dofs (each couples a few dofs near its position): the
    /// chunked product is the row-by-row one to round-off, the same bits on one thread and
    /// two, and rows touching far-apart dofs are not chunked.
    #[test]
    fn the_chunked_product_is_the_row_by_row_one() {
        let n = 40_000;
        let rows: Vec<SparseRow> = (0..3 * ROWS_PER_CHUNK)
            .map(|i| {
                let a = (i / 3) % (n - 7);
                SparseRow::new([
                    (Some(a), 1.0 + (i % 5) as f64 * 0.1),
                    (Some(a + 3), -0.7),
                    (Some(a + 7), 0.25 * (i % 3) as f64),
                ])
            })
            .collect();
        let weight = |i: usize| {
            if i.is_multiple_of(11) {
                0.0
            } else {
                1.0 + (i % 4) as f64
            }
        };
        let v: Vec<f64> = (0..n)
            .map(|k| ((k * 37) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let mut serial = vec![0.5; n];
        for (i, row) in rows.iter().enumerate() {
            row.scatter(weight(i) * row.elongation(&v), &mut serial);
        }
        let on = |threads: usize| {
            let mut chunks = RowChunks::new(&rows, n).expect("chunked");
            assert_eq!(chunks.chunks.len(), 3);
            let mut out = vec![0.5; n];
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| chunks.product_add(&rows, weight, &v, &mut out));
            out
        };
        let (one, two) = (on(1), on(2));
        assert!(one
            .iter()
            .zip(&two)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let scale = serial.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (a, b) in two.iter().zip(&serial) {
            assert!((a - b).abs() <= 1e-13 * scale, "{a} {b}");
        }
        // A row per chunk touching dof 0 and the last: every span the whole vector.
        let mut wide = rows.clone();
        for chunk in 0..3 {
            wide[chunk * ROWS_PER_CHUNK] = SparseRow::new([(Some(0), 1.0), (Some(n - 1), 1.0)]);
        }
        assert!(RowChunks::new(&wide, n).is_none());
    }
}
