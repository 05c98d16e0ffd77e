//! `out += Σ_i w_i rowᵢᵀ (rowᵢ · v)` (a stiffness `Σ w Bᵢᵀ Bᵢ` applied link by link) over fixed
//! chunks of rows side by side: the rows sorted by their first dof and cut into chunks, each
//! chunk scattered into its own buffer over the runs of dofs its rows touch, then each dof
//! adds the chunks' buffers in chunk order. The chunks depend on the rows alone, so the sums
//! are the same on any number of threads. A chunk of rows sorted so touches a few bands of
//! dofs (a grid's links reach the next row of nodes, and from the lower layer's nodes to the
//! upper's, numbered after them); chunks whose runs add up to more than [`MAX_SPAN_RATIO`]
//! times the dofs leave the product unchunked. (The links in their own order, by kind, spanned
//! 5.7 times the dofs of a 128 × 128 grid; sorted, their runs add up to 1.8 times the dofs of
//! a 256 × 256 grid and 1.9 times those of a 512 × 512 one, in at most 227 and 499 runs a
//! chunk, the upper layer's edge cables.)

use super::{SparseRow, CHUNK};
use rayon::prelude::*;
use std::ops::Range;

/// Rows per chunk: 4.2 M links of a 512 × 512 grid give 128 chunks.
const ROWS_PER_CHUNK: usize = 32_768;

/// The chunks' runs may add up to this many times the dofs at most.
const MAX_SPAN_RATIO: usize = 3;

/// Touched dofs at most this far apart are one run.
const RUN_GAP: usize = 96;

/// Fixed chunks of rows and their buffers (module doc).
pub struct RowChunks {
    /// The rows by their first dof (ties by index), each in its chunk's own numbering.
    local_rows: Vec<LocalRow>,
    chunks: Vec<RowChunk>,
    /// Per block of [`CHUNK`] dofs, the (chunk, run) pairs that cover some of its dofs, in
    /// chunk order.
    blocks: Vec<Vec<(u32, u32)>>,
}

/// A row in its chunk's numbering: read in order, with the chunk's own copy of v, so that a
/// product streams through memory (the rows taken by index from the structure's own array,
/// in this order, had made a 256² krylov run 15 % slower).
#[derive(Clone, Copy)]
struct LocalRow {
    /// The row's index (its weight's).
    row: u32,
    /// Its entries' slots in the chunk's buffer.
    slots: [u32; 6],
    len: u8,
    coef: [f64; 6],
}

struct RowChunk {
    /// Its rows: `local_rows[rows]`.
    rows: Range<usize>,
    /// The runs of dofs its rows touch: (first dof, end, where the run starts in the buffer).
    runs: Vec<(usize, usize, usize)>,
    /// v on its runs, then its rows' sums.
    local_v: Vec<f64>,
    buffer: Vec<f64>,
}

impl RowChunk {
    /// The buffer's slot of dof `d` (one the chunk touches).
    #[inline]
    fn slot(&self, d: usize) -> usize {
        let (start, _, at) = self.runs[self.runs.partition_point(|r| r.1 <= d)];
        at + d - start
    }

    /// Its buffer's length.
    fn len(&self) -> usize {
        self.runs
            .last()
            .map_or(0, |&(start, end, at)| at + end - start)
    }
}

impl RowChunks {
    /// Chunks of `rows` (over `n` dofs); `None` when there are fewer than two, or their dofs
    /// are too scattered (module doc).
    pub fn new(rows: &[SparseRow], n: usize) -> Option<RowChunks> {
        if rows.len() < 2 * ROWS_PER_CHUNK || rows.len() > u32::MAX as usize {
            return None;
        }
        let first = |i: usize| rows[i].iter().map(|(d, _)| d).min().unwrap_or(usize::MAX);
        let mut order: Vec<u32> = (0..rows.len() as u32).collect();
        // The keys are distinct: the same order on any number of threads.
        order.par_sort_unstable_by_key(|&i| (first(i as usize), i));
        let chunks: Vec<RowChunk> = (0..rows.len())
            .into_par_iter()
            .step_by(ROWS_PER_CHUNK)
            .map(|start| {
                let range = start..(start + ROWS_PER_CHUNK).min(rows.len());
                let mut dofs: Vec<usize> = order[range.clone()]
                    .iter()
                    .flat_map(|&i| rows[i as usize].iter().map(|(d, _)| d))
                    .collect();
                dofs.sort_unstable();
                dofs.dedup();
                let mut runs: Vec<(usize, usize, usize)> = Vec::new();
                for d in dofs {
                    match runs.last_mut() {
                        Some((_, end, _)) if d < *end + RUN_GAP => *end = d + 1,
                        _ => {
                            let at = runs.last().map_or(0, |&(s, e, at)| at + e - s);
                            runs.push((d, d + 1, at));
                        }
                    }
                }
                RowChunk {
                    rows: range,
                    runs,
                    local_v: Vec::new(),
                    buffer: Vec::new(),
                }
            })
            .collect();
        let spans: usize = chunks.iter().map(RowChunk::len).sum();
        if spans > MAX_SPAN_RATIO * n.max(1) {
            return None;
        }
        let mut blocks = vec![Vec::new(); n.div_ceil(CHUNK)];
        for (c, chunk) in chunks.iter().enumerate() {
            for (r, &(first, end, _)) in chunk.runs.iter().enumerate() {
                for block in &mut blocks[first / CHUNK..end.div_ceil(CHUNK)] {
                    block.push((c as u32, r as u32));
                }
            }
        }
        let local_rows: Vec<LocalRow> = chunks
            .par_iter()
            .flat_map_iter(|chunk| {
                order[chunk.rows.clone()].iter().map(move |&i| {
                    let row = &rows[i as usize];
                    let mut slots = [0u32; 6];
                    for (slot, (d, _)) in slots.iter_mut().zip(row.iter()) {
                        *slot = chunk.slot(d) as u32;
                    }
                    LocalRow {
                        row: i,
                        slots,
                        len: row.len,
                        coef: row.coef,
                    }
                })
            })
            .collect();
        Some(RowChunks {
            local_rows,
            chunks,
            blocks,
        })
    }

    /// `out += Σ_i weight(i) rowᵢᵀ (rowᵢ · v)`, rows of weight 0 skipped.
    pub fn product_add(
        &mut self,
        weight: impl Fn(usize) -> f64 + Sync,
        v: &[f64],
        out: &mut [f64],
    ) {
        // 1. Each chunk into its buffer, side by side.
        let local_rows = &self.local_rows;
        self.chunks.par_iter_mut().for_each(|chunk| {
            let (mut local_v, mut buffer) = (
                std::mem::take(&mut chunk.local_v),
                std::mem::take(&mut chunk.buffer),
            );
            local_v.clear();
            for &(first, end, _) in &chunk.runs {
                local_v.extend_from_slice(&v[first..end]);
            }
            buffer.clear();
            buffer.resize(chunk.len(), 0.0);
            for row in &local_rows[chunk.rows.clone()] {
                let w = weight(row.row as usize);
                if w == 0.0 {
                    continue;
                }
                let entries = row.slots.iter().zip(&row.coef).take(row.len as usize);
                // t = w rowᵢ · v; buffer += rowᵢᵀ t.
                let t = w * entries
                    .clone()
                    .map(|(&slot, &c)| c * local_v[slot as usize])
                    .sum::<f64>();
                for (&slot, &c) in entries {
                    buffer[slot as usize] += c * t;
                }
            }
            (chunk.local_v, chunk.buffer) = (local_v, buffer);
        });
        // 2. Each dof adds the buffers that cover it, in chunk order.
        let (chunks, blocks) = (&self.chunks, &self.blocks);
        out.par_chunks_mut(CHUNK)
            .zip(blocks)
            .enumerate()
            .for_each(|(block, (out, runs))| {
                let start = block * CHUNK;
                let end = start + out.len();
                for &(c, r) in runs {
                    let chunk = &chunks[c as usize];
                    let (first, last, at) = chunk.runs[r as usize];
                    for d in first.max(start)..last.min(end) {
                        out[d - start] += chunk.buffer[at + d - first];
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
        // Rows in an order unrelated to their dofs (as a structure's links come by kind).
        let rows: Vec<SparseRow> = (0..3 * ROWS_PER_CHUNK)
            .map(|i| {
                let a = (i * 7919) % (n - 7);
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
                .install(|| chunks.product_add(weight, &v, &mut out));
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
        // Rows each touching a dof of its own and one far away: each of the 4 chunks' runs
        // span about all the dofs.
        let wide: Vec<SparseRow> = (0..4 * ROWS_PER_CHUNK)
            .map(|i| SparseRow::new([(Some(i % n), 1.0), (Some((i * 131) % n), 1.0)]))
            .collect();
        assert!(RowChunks::new(&wide, n).is_none());
    }
}
