//! The lower-triangular CSC pattern of `Σ_links w_i Bᵢᵀ Bᵢ` (plus every diagonal entry), with
//! the value slot of each link's entries precomputed so that a numeric assembly with new link
//! weights is one pass over the links. The pattern never changes when a cable goes slack: its
//! weight becomes zero, so one symbolic factorization serves every active set.

use crate::structure::LinkDofs;

#[derive(Debug, Clone)]
pub struct StiffnessPattern {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    /// Slot of each diagonal entry.
    pub diag_slot: Vec<usize>,
    /// Per link `i`, `slots[offsets[i]..offsets[i+1]]`: the slots of its pairs `(p, q)` with
    /// `dof_p ≥ dof_q`, in the order of [`StiffnessPattern::assemble`]'s double loop.
    slots: Vec<u32>,
    offsets: Vec<usize>,
}

impl StiffnessPattern {
    pub fn new(n: usize, links: &[LinkDofs]) -> StiffnessPattern {
        // Bucket the rows of each column (counting sort), then sort and dedup each short column.
        let mut count = vec![1usize; n]; // the diagonal
        for ld in links {
            for (p, _) in ld.iter() {
                for (q, _) in ld.iter() {
                    if p > q {
                        count[q] += 1;
                    }
                }
            }
        }
        let mut start = vec![0usize; n + 1];
        for c in 0..n {
            start[c + 1] = start[c] + count[c];
        }
        let mut rows = vec![0usize; start[n]];
        let mut fill = start[..n].to_vec();
        for (c, f) in fill.iter_mut().enumerate() {
            rows[*f] = c;
            *f += 1;
        }
        for ld in links {
            for (p, _) in ld.iter() {
                for (q, _) in ld.iter() {
                    if p > q {
                        rows[fill[q]] = p;
                        fill[q] += 1;
                    }
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(rows.len());
        for c in 0..n {
            let column = &mut rows[start[c]..start[c + 1]];
            column.sort_unstable();
            let first = row_idx.len();
            for &r in column.iter() {
                if row_idx.len() == first || *row_idx.last().expect("non-empty") != r {
                    row_idx.push(r);
                }
            }
            col_ptr.push(row_idx.len());
        }
        let find = |r: usize, c: usize| -> usize {
            let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            col_ptr[c] + rows.binary_search(&r).expect("entry in pattern")
        };
        let diag_slot = (0..n).map(|d| find(d, d)).collect();
        let mut slots = Vec::with_capacity(links.len() * 21);
        let mut offsets = Vec::with_capacity(links.len() + 1);
        offsets.push(0);
        for ld in links {
            for (p, _) in ld.iter() {
                for (q, _) in ld.iter() {
                    if p >= q {
                        slots.push(find(p, q) as u32);
                    }
                }
            }
            offsets.push(slots.len());
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

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// `values = Σ_i weight_i Bᵢᵀ Bᵢ` (lower triangle). `links` must be the slice the pattern
    /// was built from.
    pub fn assemble(&self, links: &[LinkDofs], weight: impl Fn(usize) -> f64, values: &mut [f64]) {
        values.iter_mut().for_each(|v| *v = 0.0);
        for (i, ld) in links.iter().enumerate() {
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

    /// `y = A x` for a symmetric A stored as this lower triangle.
    pub fn sym_matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..self.n {
            for s in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = self.row_idx[s];
                y[r] += values[s] * x[c];
                if r != c {
                    y[c] += values[s] * x[r];
                }
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
