//! The coarse problem of the two-level Schwarz preconditioner: `E = Zᵀ H Z` with
//! `Z = [R_jᵀ Z_j]_j` (the subdomains' GenEO vectors), assembled block by block from
//! `Y_j = H R_jᵀ Z_j` (H applied link by link, so on Ω_j and one layer of dofs around it), and
//! factorised by faer's sparse Cholesky on its own analysis (docs/method.md, "Newton–Krylov on
//! the substructures"). Where only link weights changed since (the coarse vectors and μ the
//! same), E is updated by the changed links alone, `E += Σ Δw_i (Zᵀ b_i)(Zᵀ b_i)ᵀ`, and
//! refactorised on the same analysis.

use super::local::LocalProblem;
use super::overlap::Overlap;
use crate::linalg::{NodeOrdering, NotPositiveDefinite, SparseCholesky, StiffnessPattern};
use crate::structure::Structure;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// A shift, relative to E's mean diagonal, added when E does not factorise (coarse vectors of
/// neighbouring subdomains dependent to round-off); multiplied by 100 at each retry.
const FIRST_SHIFT: f64 = 1e-12;

/// The factorised coarse matrix E.
pub(super) struct Coarse {
    /// First coarse unknown of each subdomain (one more entry than subdomains).
    pub offsets: Vec<usize>,
    factor: Option<SparseCholesky>,
    /// E itself, and the link weights it holds (`None`: no coarse space).
    matrix: Option<Assembled>,
}

/// E's lower triangle on its pattern, and the link weights it holds.
struct Assembled {
    pattern: StiffnessPattern,
    values: Vec<f64>,
    weights: Vec<f64>,
}

/// E is factored on the subtrees of its nested dissection side by side from this many
/// unknowns (and two threads); below it, whole. On two threads (2026-12-07, krylov newton,
/// whole runs): 128 × 128's E (64 subdomains, 2 600–3 100 unknowns, 200 entries a column)
/// solved in 2.3 ms split against 1.8 ms whole, its separator's dense blocks outweighing the
/// halves; 256 × 256's (256 subdomains, about 12 000) in 10.5 ms against 12.0 ms.
const SPLIT_MIN_UNKNOWNS: usize = 6_000;

/// E's factor: ordered by nested dissection of the subdomains (each subdomain's coarse
/// unknowns one block, at the mean position of its dofs' nodes) and, from
/// [`SPLIT_MIN_UNKNOWNS`] on more than one thread, factored and solved in the subtrees of that
/// dissection side by side (one per thread, `src/linalg/split_cholesky.rs`), the separators'
/// dense blocks last: no coarse solve on one core alone.
fn coarse_factor(
    structure: &Structure,
    overlap: &Overlap,
    offsets: &[usize],
    pattern: &StiffnessPattern,
) -> SparseCholesky {
    let whole = coarse_analysis(structure, overlap, offsets, pattern);
    let threads = rayon::current_num_threads();
    let split = (threads >= 2 && pattern.n >= SPLIT_MIN_UNKNOWNS)
        .then(|| whole.share_symbolic_split(pattern, SparseCholesky::split_levels_for(threads)))
        .flatten();
    split.unwrap_or(whole)
}

/// E's analysis, whole, in the nested dissection of the subdomains (see [`coarse_factor`]).
fn coarse_analysis(
    structure: &Structure,
    overlap: &Overlap,
    offsets: &[usize],
    pattern: &StiffnessPattern,
) -> SparseCholesky {
    let mut node_of_free = vec![0usize; structure.n_free];
    for (dof, &free) in structure.dof_of.iter().enumerate() {
        if free < structure.n_free {
            node_of_free[free] = dof / 3;
        }
    }
    let centres: Vec<[f64; 3]> = overlap
        .dofs
        .iter()
        .map(|dofs| {
            let mut centre = [0.0; 3];
            for &d in dofs {
                let x = structure.nodes[node_of_free[d]];
                (0..3).for_each(|k| centre[k] += x[k]);
            }
            centre.map(|c| c / dofs.len().max(1) as f64)
        })
        .collect();
    let ordering = NodeOrdering::Blocks {
        offsets,
        centres: &centres,
    };
    SparseCholesky::analyse_ordered(pattern, Par::rayon(0), ordering)
}

impl Coarse {
    /// No coarse space.
    pub(super) fn none(subdomains: usize) -> Coarse {
        Coarse {
            offsets: vec![0; subdomains + 1],
            factor: None,
            matrix: None,
        }
    }

    /// The coarse unknowns.
    pub(super) fn len(&self) -> usize {
        self.offsets.last().copied().unwrap_or(0)
    }

    /// `E = Zᵀ H Z` for `H = Σ w_i b_i b_iᵀ + μ I`, factorised.
    pub(super) fn new(
        structure: &Structure,
        overlap: &Overlap,
        locals: &[LocalProblem],
        (weights, mu): (&[f64], f64),
    ) -> Result<Coarse, NotPositiveDefinite> {
        let mut offsets = vec![0usize; locals.len() + 1];
        for (j, local) in locals.iter().enumerate() {
            offsets[j + 1] = offsets[j] + local.coarse.ncols();
        }
        let n = offsets[locals.len()];
        if n == 0 {
            return Ok(Coarse::none(locals.len()));
        }
        // Per subdomain j, the blocks E_ij = Z_iᵀ (Y_j on Ω_i) of the subdomains i ≥ j that
        // Y_j reaches.
        let blocks: Vec<Vec<(usize, DMatrix<f64>)>> = (0..locals.len())
            .into_par_iter()
            .map(|j| column_blocks(structure, overlap, locals, j, (weights, mu)))
            .collect();
        // Lower-triangle entries of E in coarse numbering.
        let mut entries = Vec::new();
        let mut values = Vec::new();
        for (j, column) in blocks.iter().enumerate() {
            for (i, block) in column {
                for b in 0..block.ncols() {
                    for a in 0..block.nrows() {
                        let (row, col) = (offsets[*i] + a, offsets[j] + b);
                        if row >= col {
                            entries.push((row, col));
                            values.push(block[(a, b)]);
                        }
                    }
                }
            }
        }
        let pattern = StiffnessPattern::from_lower_entries(n, &entries);
        let mut e = vec![0.0; pattern.nnz()];
        for (&(r, c), v) in entries.iter().zip(&values) {
            let slot = pattern.slot(r, c).expect("an entry of the pattern");
            e[slot] += v;
        }
        drop(entries);
        let mut factor = coarse_factor(structure, overlap, &offsets, &pattern);
        let mean = pattern.mean_diagonal(&e).abs();
        let mut shift = 0.0;
        let mut next = FIRST_SHIFT * mean;
        let assembled = |pattern, values| Assembled {
            pattern,
            values,
            weights: weights.to_vec(),
        };
        for _ in 0..4 {
            if factor.factorize(&pattern, &e).is_ok() {
                return Ok(Coarse {
                    offsets,
                    factor: Some(factor),
                    matrix: Some(assembled(pattern, e)),
                });
            }
            for &s in &pattern.diag_slot {
                e[s] += next - shift;
            }
            shift = next;
            next *= 100.0;
        }
        factor.factorize(&pattern, &e)?;
        Ok(Coarse {
            offsets,
            factor: Some(factor),
            matrix: Some(assembled(pattern, e)),
        })
    }

    /// E for new link weights, where the subdomains' coarse vectors are those E was made with:
    /// `E += Σ_i Δw_i g_i g_iᵀ` over the links whose weight changed, `g_i = Zᵀ b_i` (nonzero
    /// on the subdomains holding a dof of link i), accumulated block by block, then
    /// refactorised on the same analysis. E keeps the μ it was made with, as a kept subdomain
    /// factor does (a preconditioner need not be exact; a raised μ finds new vectors, so a new
    /// E). `false` where it cannot be (no E, or E no longer factorises): the caller makes E
    /// anew.
    pub(super) fn update_weights(
        &mut self,
        structure: &Structure,
        overlap: &Overlap,
        locals: &[LocalProblem],
        weights: &[f64],
    ) -> bool {
        let (Some(matrix), Some(factor)) = (self.matrix.as_mut(), self.factor.as_mut()) else {
            return false;
        };
        // ΔE_ab = Σ Δw g_a g_bᵀ per pair of subdomains a ≥ b (a's coarse rows, b's columns).
        let mut blocks: BTreeMap<(usize, usize), DMatrix<f64>> = BTreeMap::new();
        for (i, (&new, &old)) in weights.iter().zip(&matrix.weights).enumerate() {
            if new == old {
                continue;
            }
            // g_i by subdomain: Z_jᵀ R_j b_i.
            let mut g: Vec<(usize, DVector<f64>)> = Vec::new();
            for (d, c) in structure.link_dofs[i].iter() {
                for j in overlap.holders_of(d) {
                    let z = &locals[j].coarse;
                    let Ok(k) = overlap.dofs[j].binary_search(&d) else {
                        continue;
                    };
                    let at = match g.iter().position(|(h, _)| *h == j) {
                        Some(at) => at,
                        None => {
                            g.push((j, DVector::zeros(z.ncols())));
                            g.len() - 1
                        }
                    };
                    g[at].1.axpy(c, &z.row(k).transpose(), 1.0);
                }
            }
            for (a, ga) in &g {
                for (b, gb) in &g {
                    if a >= b && !ga.is_empty() && !gb.is_empty() {
                        let block = blocks
                            .entry((*a, *b))
                            .or_insert_with(|| DMatrix::zeros(ga.len(), gb.len()));
                        block.ger(new - old, ga, gb, 1.0);
                    }
                }
            }
        }
        // Into E's slots: a column's rows of one subdomain lie side by side in the pattern.
        let pattern = &matrix.pattern;
        for ((a, b), block) in &blocks {
            let (row0, col0) = (self.offsets[*a], self.offsets[*b]);
            for q in 0..block.ncols() {
                let col = col0 + q;
                let first = if a == b { q } else { 0 };
                let Some(slot) = pattern.slot(row0 + first, col) else {
                    return false;
                };
                for p in first..block.nrows() {
                    let at = slot + p - first;
                    // E's blocks are whole: a gap would mean another pattern (made anew then).
                    if at >= pattern.col_ptr[col + 1] || pattern.row_idx[at] != row0 + p {
                        return false;
                    }
                    matrix.values[at] += block[(p, q)];
                }
            }
        }
        matrix.weights.copy_from_slice(weights);
        factor.factorize(pattern, &matrix.values).is_ok()
    }

    /// `c ← E⁻¹ c` by E factored in the subtrees of `levels` levels of its dissection side by
    /// side, whatever E's size, and those levels (0: no split), for the tests.
    #[cfg(test)]
    pub(super) fn solve_split(
        &self,
        structure: &Structure,
        overlap: &Overlap,
        levels: usize,
        c: &mut [f64],
    ) -> usize {
        let matrix = self.matrix.as_ref().expect("a coarse space");
        let whole = coarse_analysis(structure, overlap, &self.offsets, &matrix.pattern);
        let mut split = whole
            .share_symbolic_split(&matrix.pattern, levels)
            .expect("a split");
        split
            .factorize(&matrix.pattern, &matrix.values)
            .expect("E is positive definite");
        split.solve_in_place(c);
        split.split_levels()
    }

    /// E's lower triangle, entry by entry (row, column, value), for the tests.
    #[cfg(test)]
    pub(super) fn entries(&self) -> Vec<(usize, usize, f64)> {
        self.matrix.as_ref().map_or_else(Vec::new, |m| {
            m.pattern
                .entries()
                .map(|(r, c, s)| (r, c, m.values[s]))
                .collect()
        })
    }

    /// `c ← E⁻¹ c`.
    pub(super) fn solve(&self, c: &mut [f64]) {
        if let Some(factor) = &self.factor {
            factor.solve_in_place(c);
        }
    }
}

/// The blocks `E_ij = Z_iᵀ H Z_j`, i ≥ j, of coarse column block j.
fn column_blocks(
    structure: &Structure,
    overlap: &Overlap,
    locals: &[LocalProblem],
    j: usize,
    (weights, mu): (&[f64], f64),
) -> Vec<(usize, DMatrix<f64>)> {
    let z = &locals[j].coarse;
    let m = z.ncols();
    if m == 0 {
        return Vec::new();
    }
    let dofs = &overlap.dofs[j];
    // The dofs Y_j = H R_jᵀ Z_j reaches: Ω_j's and those of its links.
    let mut reach: Vec<usize> = dofs.clone();
    for &(i, _) in &overlap.links[j] {
        reach.extend(structure.link_dofs[i].iter().map(|(d, _)| d));
    }
    reach.sort_unstable();
    reach.dedup();
    let at = |d: usize| reach.binary_search(&d).expect("a reached dof");
    // Z_j and Y_j by rows (row k at k·m..(k + 1)·m): a link touches a few rows whole.
    let z_transposed = z.transpose();
    let z_rows = z_transposed.as_slice();
    // Y_j = Σ_links w b (bᵀ R_jᵀ Z_j) + μ R_jᵀ Z_j.
    let mut y = vec![0.0; reach.len() * m];
    let mut t = vec![0.0; m];
    for &(i, _) in &overlap.links[j] {
        let w = weights[i];
        if w == 0.0 {
            continue;
        }
        let row = &structure.link_dofs[i];
        t.iter_mut().for_each(|v| *v = 0.0);
        for (d, c) in row.iter() {
            if let Ok(k) = dofs.binary_search(&d) {
                let zk = &z_rows[k * m..(k + 1) * m];
                t.iter_mut().zip(zk).for_each(|(tv, zv)| *tv += c * zv);
            }
        }
        for (d, c) in row.iter() {
            let r = at(d);
            let yr = &mut y[r * m..(r + 1) * m];
            yr.iter_mut().zip(&t).for_each(|(yv, tv)| *yv += w * c * tv);
        }
    }
    for (k, &d) in dofs.iter().enumerate() {
        let r = at(d);
        let (yr, zk) = (&mut y[r * m..(r + 1) * m], &z_rows[k * m..(k + 1) * m]);
        yr.iter_mut().zip(zk).for_each(|(yv, zv)| *yv += mu * zv);
    }
    // Y_j's rows as a faer view (row-major: the transpose of a column-major m × reach).
    let y_view = MatRef::from_column_major_slice(&y, m, reach.len()).transpose();
    // The subdomains i ≥ j that hold a reached dof.
    let mut near: Vec<usize> = reach
        .iter()
        .flat_map(|&d| overlap.holders_of(d))
        .filter(|&i| i >= j)
        .collect();
    near.sort_unstable();
    near.dedup();
    near.into_iter()
        .filter(|&i| locals[i].coarse.ncols() > 0)
        .map(|i| {
            // E_ij = Z_i[Ω_i ∩ reach]ᵀ Y_j[Ω_i ∩ reach].
            let common: Vec<(usize, usize)> = overlap.dofs[i]
                .iter()
                .enumerate()
                .filter_map(|(k, &d)| reach.binary_search(&d).ok().map(|r| (k, r)))
                .collect();
            let zi = &locals[i].coarse;
            let zi_rows = Mat::from_fn(common.len(), zi.ncols(), |a, b| zi[(common[a].0, b)]);
            let y_rows = Mat::from_fn(common.len(), m, |a, b| y_view[(common[a].1, b)]);
            let mut block = Mat::<f64>::zeros(zi.ncols(), m);
            matmul(
                block.as_mut(),
                Accum::Replace,
                zi_rows.transpose(),
                y_rows.as_ref(),
                1.0,
                Par::Seq,
            );
            (i, DMatrix::from_fn(block.nrows(), m, |a, b| block[(a, b)]))
        })
        .collect()
}
