//! The macro problem (docs/method.md §4), assembled and factorised once per set of substructure
//! operators: `[Σ c_Eᵀ L_E c_E, N; Nᵀ, 0] [f_Γ; a] = −[Σ c_Eᵀ K⁺_E g_E; (Q_Eᵀ g_E)_E]`,
//! `N = [c_Eᵀ Q_E]_E`. Unknowns: the macro forces of every interface, then the kernel amplitudes
//! of every substructure.
//!
//! `L_E = K⁺_E − I/d_m` is −1/d_m on the kernel of K*_E, so the force block is indefinite and
//! the matrix needs a pivoting LU (COLAMD), which cost 0.45 s per factorisation on a 64 × 64
//! grid (6902 unknowns). The second equation `Nᵀ f_Γ = b_a` makes the force block definite
//! without changing the solution: adding `γ N (Nᵀ f_Γ − b_a) = 0` to the first gives
//! `Ã = Σ c_Eᵀ (L_E + γ Q_E Q_Eᵀ) c_E`, which is 1/d_m on each kernel and `K⁺_E − I/d_m > 0`
//! on its range for γ = 2/d_m. The matrix `[Ã, N; Nᵀ, 0]` is then factorised as a symmetric
//! quasi-definite one, `L D Lᵀ` after AMD, with the kernel pivots held negative by a tiny
//! regularisation that a few steps of iterative refinement against the exact matrix undo.
//! It is factorised equilibrated, `S M S` with `S_ii = 1/√M_ii` on the forces: substructures
//! whose slack cables make them soft have flexibilities far above the others', and unscaled
//! their spread cost the macro answer two decades of accuracy on 256 substructures (noise
//! that the LATIN iterates then carry: r(U) stalled at 9e-7 on 256 × 256 modules).

use super::substructure::Substructure;
use super::Interface;
use crate::linalg::{buckets, gemv, gemv_transposed};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LdltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{
    Argsort, Pair, SparseColMat, SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef,
};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
use std::sync::Arc;

/// γ d_m of the augmentation `Ã = A + γ N Nᵀ`: the force block is then 1/d_m on every kernel.
const AUGMENTATION: f64 = 2.0;

/// A kernel pivot is held at −`REGULARISATION` (the matrix is scaled to O(1) entries) when
/// elimination reaches it before the forces it is coupled to.
const REGULARISATION: f64 = 1e-9;

/// Iterative refinement stops after this many steps, or once the residual stops falling,
/// or, in the iterations, once the residual is below a fraction of the right-hand side
/// (largest entries) that the caller chooses: the first solve leaves 1e-8 to 1e-6 of it (the
/// regularised kernel pivots), each step gains about three decades more. Refining to the end
/// took 4 to 5 solves per macro solve on a 32 × 32 grid of 64 substructures, 3 at 1024
/// substructures, where 1e-9 takes 2 and leaves the iteration counts unchanged. A less
/// accurate macro answer can slow the LATIN, never make a row converged (r(U) is measured on
/// U). The set-up's regularity check refines to the end.
const MAX_REFINEMENT: usize = 6;

/// The macro problem `[Σ c_Eᵀ L_E c_E, N; Nᵀ, 0] [f_Γ; a] = −[Σ c_Eᵀ K⁺_E g_E; (Q_Eᵀ g_E)_E]`,
/// factorised once.
pub struct MacroProblem {
    /// Number of macro force unknowns (Σ over interfaces of their macro dofs).
    pub n_forces: usize,
    /// First kernel amplitude of each substructure, after the forces.
    pub kernel_offset: Vec<usize>,
    /// Size of the macro system: `n_forces` + Σ kernel columns.
    pub n: usize,
    /// `d_m`, for the augmentation and the scaling.
    dm: f64,
    factor: Option<Factor>,
}

/// Rows of the macro matrix per parallel task in `M y` (a row has tens of entries).
const APPLY_ROWS_PER_TASK: usize = 512;

/// The pattern of the macro matrix, fixed by the partition and the kernels (the search
/// directions change only values): its lower triangle, the order that maps the assembly's
/// entries onto it, and the symbolic `L D Lᵀ` analysis (AMD).
pub(super) struct MacroPattern {
    lower: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    /// Number of assembled entries the order maps (the same partition always gives the same).
    argsort_len: usize,
    symbolic: SymbolicCholesky<usize>,
    /// The strict lower triangle by rows: row i's entries `(column, position in the values)`
    /// at `by_row[row_start[i]..row_start[i + 1]]`, so that `M y` is computed row by row in
    /// parallel.
    row_start: Vec<usize>,
    by_row: Vec<(usize, usize)>,
}

/// The scaled augmented matrix `D [Ã, N; Nᵀ, 0] D` (lower triangle, D = √d_m on forces,
/// 1/√d_m on kernel amplitudes: every block O(1)) and its `L D Lᵀ` factor.
pub(super) struct Factor {
    pattern: Arc<MacroPattern>,
    lower: SparseColMat<usize, f64>,
    values: Vec<f64>,
    /// The symmetric equilibration S of the factorised matrix `S M S` (see [`equilibration`]).
    scaling: Vec<f64>,
}

/// The macro matrix is singular (an interface or kernel mode is left undetermined).
#[derive(Debug, Clone, Copy)]
pub struct SingularMacroProblem;

impl MacroProblem {
    /// Entries of its `L D Lᵀ` factor (every rank holds one: it is solved on every rank).
    pub fn factor_entries(&self) -> usize {
        self.factor.as_ref().map_or(0, |f| f.values.len())
    }

    /// Assemble and factorise the macro matrix; `Err` if it is singular.
    pub fn new(
        subs: &[Substructure],
        interfaces: &[Interface],
        dm: f64,
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(subs, interfaces, dm, None)
    }

    /// The macro problem of new substructure operators on the same partition, reusing this
    /// one's symbolic analysis when the pattern is the same (the search directions changed,
    /// the kernels did not).
    pub fn refactor(
        &self,
        subs: &[Substructure],
        interfaces: &[Interface],
    ) -> Result<MacroProblem, SingularMacroProblem> {
        Self::assemble(subs, interfaces, self.dm, self.factor.as_ref())
    }

    /// Assemble the macro matrix in an order fixed by the partition, reuse `previous`'s
    /// symbolic analysis when the pattern is the same, factorise, and check the factor.
    fn assemble(
        subs: &[Substructure],
        interfaces: &[Interface],
        dm: f64,
        previous: Option<&Factor>,
    ) -> Result<MacroProblem, SingularMacroProblem> {
        let n_forces: usize = interfaces.iter().map(|i| i.basis.ncols()).sum();
        let mut kernel_offset = Vec::with_capacity(subs.len());
        let mut n = n_forces;
        for sub in subs {
            kernel_offset.push(n);
            n += sub.kernel.ncols();
        }
        let problem = |factor| MacroProblem {
            n_forces,
            kernel_offset: kernel_offset.clone(),
            n,
            dm,
            factor,
        };
        if n == 0 {
            return Ok(problem(None));
        }
        let (entries, values) = Self::entries(subs, interfaces, dm, &kernel_offset, n);
        let pattern = match previous {
            Some(old) if old.pattern.argsort_len == values.len() => Arc::clone(&old.pattern),
            _ => Arc::new(MacroPattern::new(n, &entries)?),
        };
        drop(entries);
        let factor = Factor::new(pattern, &values, n_forces)?;
        drop(values);
        // Checked at set-up only: a re-set-up changes l > 0 alone, which keeps every
        // K*_E + Q_E Q_Eᵀ definite (its Cholesky succeeded) and so Ã definite.
        if previous.is_none() {
            factor.check_regular(n)?;
        }
        Ok(problem(Some(factor)))
    }

    /// Lower triangle of D [Ã, N; Nᵀ, 0] D, entry by entry in an order fixed by the partition
    /// (zeros included, so the pattern never changes); duplicates are summed on assembly.
    fn entries(
        subs: &[Substructure],
        interfaces: &[Interface],
        dm: f64,
        kernel_offset: &[usize],
        n: usize,
    ) -> (Vec<Pair<usize, usize>>, Vec<f64>) {
        let gamma = AUGMENTATION / dm;
        let mut entries: Vec<Pair<usize, usize>> = Vec::new();
        let mut values: Vec<f64> = Vec::new();
        let mut add = |r: usize, c: usize, v: f64| {
            if r >= c {
                entries.push(Pair::new(r, c));
                values.push(v);
            }
        };
        for (e, sub) in subs.iter().enumerate() {
            // L_E + γ Q_E Q_Eᵀ, scaled by d_m.
            let q = &sub.kernel;
            let block = (&sub.flexibility + q * q.transpose() * gamma) * dm;
            for s1 in &sub.sides {
                let row0 = interfaces[s1.interface].macro_offset;
                for s2 in &sub.sides {
                    let col0 = interfaces[s2.interface].macro_offset;
                    let sign = s1.sign() * s2.sign();
                    for i in 0..s1.cols {
                        for j in 0..s2.cols {
                            let v = block[(s1.macro_offset + i, s2.macro_offset + j)];
                            add(row0 + i, col0 + j, sign * v);
                        }
                    }
                }
                for i in 0..s1.cols {
                    for k in 0..q.ncols() {
                        let v = s1.sign() * q[(s1.macro_offset + i, k)];
                        add(kernel_offset[e] + k, row0 + i, v);
                    }
                }
            }
        }
        // Every pivot is in the pattern.
        for i in 0..n {
            add(i, i, 0.0);
        }
        (entries, values)
    }

    /// A zero right-hand side `[b_f; b_a]`.
    pub fn zero_rhs(&self) -> Vec<f64> {
        vec![0.0; self.n]
    }

    /// Substructure E's part of the right-hand side in E's own macro dofs, computed where E
    /// is held: `K⁺_E g_E + γ Q_E Q_Eᵀ g_E` on its macro dofs, then `Q_Eᵀ g_E`.
    pub fn rhs_piece(&self, sub: &Substructure, g: &[f64]) -> Vec<f64> {
        let gamma = AUGMENTATION / self.dm;
        let mut kg = vec![0.0; sub.n_macro];
        gemv(&mut kg, &sub.ops().k_plus, g, false);
        let mut qg = vec![0.0; sub.kernel.ncols()];
        gemv_transposed(&mut qg, &sub.kernel, g, false);
        let mut nb = vec![0.0; sub.n_macro];
        gemv(&mut nb, &sub.kernel, &qg, false);
        let mut piece: Vec<f64> = kg.iter().zip(&nb).map(|(k, n)| k + gamma * n).collect();
        piece.extend_from_slice(&qg);
        piece
    }

    /// Substructure E's `piece` ([`Self::rhs_piece`]) added to `rhs` (a sum over the
    /// substructures, in their order on every rank): `b_f −= c_Eᵀ (K⁺_E g_E + γ Q_E Q_Eᵀ g_E)`,
    /// `b_a,E = −Q_Eᵀ g_E`.
    pub fn add_rhs(
        &self,
        e: usize,
        sub: &Substructure,
        interfaces: &[Interface],
        piece: &[f64],
        rhs: &mut [f64],
    ) {
        let (forces, kernel) = piece.split_at(sub.n_macro);
        for side in &sub.sides {
            let row0 = interfaces[side.interface].macro_offset;
            for i in 0..side.cols {
                rhs[row0 + i] -= side.sign() * forces[side.macro_offset + i];
            }
        }
        let kernel_rows = self.kernel_offset[e]..self.kernel_offset[e] + sub.kernel.ncols();
        rhs[kernel_rows]
            .iter_mut()
            .zip(kernel)
            .for_each(|(r, q)| *r -= q);
    }

    /// The error the set-up's regularity check measures (invariant tests: the equilibration).
    #[cfg(test)]
    pub(super) fn forward_error(&self) -> f64 {
        self.factor
            .as_ref()
            .map_or(0.0, |f| f.forward_error(self.n))
    }

    /// `[f_Γ; a]` from the assembled right-hand side, refined until the residual is below
    /// `accuracy` times the right-hand side's largest entry (scaled).
    pub fn solve_rhs(&self, mut rhs: Vec<f64>, accuracy: f64) -> Vec<f64> {
        if let Some(factor) = &self.factor {
            // x = D y with (D M̃ D) y = D b.
            let scale = |i: usize| {
                if i < self.n_forces {
                    self.dm.sqrt()
                } else {
                    1.0 / self.dm.sqrt()
                }
            };
            rhs.iter_mut().enumerate().for_each(|(i, b)| *b *= scale(i));
            factor.solve(&mut rhs, accuracy);
            rhs.iter_mut().enumerate().for_each(|(i, y)| *y *= scale(i));
        }
        rhs
    }

    /// Substructure E's share of the answer: its macro forces `f_E = c_E f_Γ` (signed per
    /// side) and its kernel amplitudes `a_E`.
    pub fn answer<'a>(
        &self,
        e: usize,
        sub: &Substructure,
        interfaces: &[Interface],
        solution: &'a [f64],
    ) -> (Vec<f64>, &'a [f64]) {
        let mut f_e = vec![0.0; sub.n_macro];
        for side in &sub.sides {
            let off = interfaces[side.interface].macro_offset;
            for i in 0..side.cols {
                f_e[side.macro_offset + i] = side.sign() * solution[off + i];
            }
        }
        let a_e = &solution[self.kernel_offset[e]..self.kernel_offset[e] + sub.kernel.ncols()];
        (f_e, a_e)
    }
}

impl MacroPattern {
    /// The pattern of `entries` (n × n, lower triangle), its assembly order and its symbolic
    /// `L D Lᵀ` analysis (AMD).
    pub(super) fn new(
        n: usize,
        entries: &[Pair<usize, usize>],
    ) -> Result<Self, SingularMacroProblem> {
        let (lower, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, entries)
            .map_err(|_| SingularMacroProblem)?;
        let symbolic = factorize_symbolic_cholesky(
            lower.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|_| SingularMacroProblem)?;
        let (row_start, by_row) = strict_lower_by_row(lower.as_ref());
        Ok(MacroPattern {
            argsort_len: entries.len(),
            lower,
            argsort,
            symbolic,
            row_start,
            by_row,
        })
    }
}

impl Factor {
    /// The regularised `L D Lᵀ` factor of the matrix of `values` (in `pattern`'s assembly
    /// order); the first `n_forces` unknowns are forces (+), the rest kernel amplitudes (−).
    pub(super) fn new(
        pattern: Arc<MacroPattern>,
        values: &[f64],
        n_forces: usize,
    ) -> Result<Self, SingularMacroProblem> {
        let lower = SparseColMat::new_from_argsort(pattern.lower.clone(), &pattern.argsort, values)
            .map_err(|_| SingularMacroProblem)?;
        let symbolic = &pattern.symbolic;
        let n = lower.nrows();
        let scaling = equilibration(lower.as_ref(), n_forces);
        let scaled = {
            let mut scaled = lower.clone();
            let m = lower.as_ref();
            let vals = scaled.val_mut();
            for c in 0..n {
                for k in m.col_range(c) {
                    vals[k] *= scaling[m.symbolic().row_idx()[k]] * scaling[c];
                }
            }
            scaled
        };
        // + for the forces, − for the kernel amplitudes.
        let signs: Vec<i8> = (0..n).map(|i| if i < n_forces { 1 } else { -1 }).collect();
        let mut factor_values = vec![0.0; symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_ldlt(
                &mut factor_values,
                scaled.as_ref(),
                Side::Lower,
                LdltRegularization {
                    dynamic_regularization_signs: Some(&signs),
                    dynamic_regularization_delta: REGULARISATION,
                    dynamic_regularization_epsilon: REGULARISATION,
                },
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|_| SingularMacroProblem)?;
        Ok(Factor {
            pattern: Arc::clone(&pattern),
            lower,
            values: factor_values,
            scaling,
        })
    }

    /// A regularised factor of a singular matrix solves nothing: solve M y = M y0 for a known
    /// y0 of size `n` and compare.
    fn check_regular(&self, n: usize) -> Result<(), SingularMacroProblem> {
        let error = self.forward_error(n);
        if error.is_nan() || error > 1e-6 {
            return Err(SingularMacroProblem);
        }
        Ok(())
    }

    /// The largest error of a solve (refined to the end) of `M y = M y0` for a known y0 of
    /// size `n`, entries in [1, 2).
    fn forward_error(&self, n: usize) -> f64 {
        let y0: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 / 7.0).collect();
        let mut y = self.apply(&y0);
        self.solve(&mut y, 0.0);
        y.iter()
            .zip(&y0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }
}

impl Factor {
    /// `M y`, M symmetric stored by its lower triangle: row i is lower column i (rows ≥ i)
    /// and lower row i (columns < i), each row summed alone, rows in parallel.
    pub(super) fn apply(&self, y: &[f64]) -> Vec<f64> {
        let m = self.lower.as_ref();
        let (rows, vals) = (m.symbolic().row_idx(), m.val());
        let pattern = &self.pattern;
        (0..y.len())
            .into_par_iter()
            .with_min_len(APPLY_ROWS_PER_TASK)
            .map(|i| {
                let column = m.col_range(i);
                let below: f64 = rows[column.clone()]
                    .iter()
                    .zip(&vals[column])
                    .map(|(&r, v)| v * y[r])
                    .sum();
                let left = &pattern.by_row[pattern.row_start[i]..pattern.row_start[i + 1]];
                below + left.iter().map(|&(c, at)| vals[at] * y[c]).sum::<f64>()
            })
            .collect()
    }

    /// `y ← M⁻¹ y`: the regularised factor, then iterative refinement against M.
    /// `refined`: refinement stops once the residual is below this fraction of `b` (0: only
    /// when it stops falling).
    fn solve(&self, b: &mut [f64], refined: f64) {
        let n = b.len();
        let symbolic = &self.pattern.symbolic;
        let ldlt = LdltRef::new(symbolic, &self.values);
        let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        // M⁻¹ = S (S M S)⁻¹ S.
        let mut solve = |x: &mut [f64]| {
            x.iter_mut().zip(&self.scaling).for_each(|(x, s)| *x *= s);
            ldlt.solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(x, n, 1),
                Par::Seq,
                MemStack::new(&mut scratch),
            );
            x.iter_mut().zip(&self.scaling).for_each(|(x, s)| *x *= s);
        };
        let rhs = b.to_vec();
        solve(b);
        let mut last = f64::INFINITY;
        let enough = refined * rhs.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for _ in 0..MAX_REFINEMENT {
            // r = b − M y; y += M̃⁻¹ r.
            let my = self.apply(b);
            let mut r: Vec<f64> = rhs.iter().zip(&my).map(|(b, m)| b - m).collect();
            let norm = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if norm.is_nan() || norm >= 0.5 * last || norm <= enough {
                break;
            }
            last = norm;
            solve(&mut r);
            b.iter_mut().zip(&r).for_each(|(y, d)| *y += d);
        }
    }
}

/// The strict lower triangle of `lower` (a symbolic CSC lower triangle) by rows: per row, the
/// start of its entries, and per entry its column and position in the values.
fn strict_lower_by_row(
    lower: SymbolicSparseColMatRef<'_, usize>,
) -> (Vec<usize>, Vec<(usize, usize)>) {
    buckets(lower.nrows(), |emit| {
        for c in 0..lower.ncols() {
            for at in lower.col_range(c) {
                let r = lower.row_idx()[at];
                if r != c {
                    emit(r, (c, at));
                }
            }
        }
    })
}

/// A symmetric equilibration S of the macro matrix M (lower triangle `m`, whose first
/// `n_forces` unknowns are forces): `1/√M_ii` on a force row, and on a kernel row (zero
/// diagonal) the inverse of its largest entry once the forces are scaled, so that every row of
/// `S M S` has entries of order one.
fn equilibration(m: SparseColMatRef<'_, usize, f64>, n_forces: usize) -> Vec<f64> {
    let column = |c: usize| {
        let range = m.col_range(c);
        m.symbolic().row_idx()[range.clone()]
            .iter()
            .copied()
            .zip(m.val()[range].iter().copied())
    };
    let mut scaling = vec![1.0; m.nrows()];
    for (c, s) in scaling.iter_mut().enumerate().take(n_forces) {
        if let Some((_, v)) = column(c).find(|&(r, v)| r == c && v > 0.0) {
            *s = 1.0 / v.sqrt();
        }
    }
    // A kernel row r ≥ n_forces meets the force columns in the lower triangle.
    let mut largest = vec![0.0f64; m.nrows()];
    for (c, &s) in scaling.iter().enumerate().take(n_forces) {
        for (r, v) in column(c).filter(|&(r, _)| r >= n_forces) {
            largest[r] = largest[r].max((v * s).abs());
        }
    }
    for (s, &l) in scaling.iter_mut().zip(&largest).skip(n_forces) {
        if l > 0.0 {
            *s = 1.0 / l;
        }
    }
    scaling
}
