//! The macro matrix's factor (docs/method.md §4): equilibrated, `S M S`, factored `L D Lᵀ` with
//! its pivots' signs held (+ forces, − kernel amplitudes), then refined against M. Whole (AMD,
//! faer's supernodal `L D Lᵀ`, whose solves run on one thread), or split into subtrees of
//! substructures factored and solved side by side ([`super::tree`]).

use super::tree::MacroTree;
use super::SingularMacroProblem;
use crate::linalg::{buckets, SplitQuasiDefinite, StiffnessPattern};
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

/// Rows of the macro matrix per parallel task in `M y` (a row has tens of entries).
const APPLY_ROWS_PER_TASK: usize = 512;

/// The pattern of the macro matrix, fixed by the partition and the kernels (the search
/// directions change only values): its lower triangle, the order that maps the assembly's
/// entries onto it, and the symbolic analysis of its factor.
pub(in crate::solvers::latin) struct MacroPattern {
    lower: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    /// Number of assembled entries the order maps (the same partition always gives the same).
    pub(super) argsort_len: usize,
    analysis: Analysis,
    /// The strict lower triangle by rows: row i's entries `(column, position in the values)`
    /// at `by_row[row_start[i]..row_start[i + 1]]`, so that `M y` is computed row by row in
    /// parallel.
    row_start: Vec<usize>,
    by_row: Vec<(usize, usize)>,
}

/// How the macro matrix is factored.
enum Analysis {
    /// Whole: faer's symbolic `L D Lᵀ` after AMD.
    Whole(Box<SymbolicCholesky<usize>>),
    /// In subtrees side by side: the split with no numeric factor yet (each [`Factor`] takes a
    /// copy), and the lower triangle's slots as the split's pattern numbers them.
    Split(Box<SplitQuasiDefinite>, Vec<usize>),
}

/// A factor of `S M S`, as its pattern's [`Analysis`] says.
enum Numeric {
    Whole(Vec<f64>),
    Split(Box<SplitQuasiDefinite>),
}

/// The scaled augmented matrix `D [Ã, N; Nᵀ, 0] D` (lower triangle, D = √d_m on forces,
/// 1/√d_m on kernel amplitudes: every block O(1)) and its `L D Lᵀ` factor.
pub(in crate::solvers::latin) struct Factor {
    pub(super) pattern: Arc<MacroPattern>,
    lower: SparseColMat<usize, f64>,
    numeric: Numeric,
    /// The symmetric equilibration S of the factorised matrix `S M S` (see [`equilibration`]).
    scaling: Vec<f64>,
}

impl MacroPattern {
    /// The pattern of `entries` (n × n, lower triangle), its assembly order and its symbolic
    /// analysis: split along the order `tree` gives for the pattern when it gives one and the split holds (its separators
    /// hold forces only), else `L D Lᵀ` after AMD. `n_forces`: the first unknowns, forces (+
    /// pivots); the rest are kernel amplitudes (−).
    pub(in crate::solvers::latin) fn new(
        n: usize,
        entries: &[Pair<usize, usize>],
        n_forces: usize,
        tree: impl FnOnce(SymbolicSparseColMatRef<'_, usize>) -> Option<MacroTree>,
    ) -> Result<Self, SingularMacroProblem> {
        let (lower, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, entries)
            .map_err(|_| SingularMacroProblem)?;
        let split = tree(lower.as_ref()).and_then(|tree| {
            let signs: Vec<i8> = (0..n).map(|i| if i < n_forces { 1 } else { -1 }).collect();
            let pairs: Vec<(usize, usize)> = (0..n)
                .flat_map(|c| {
                    lower.row_idx()[lower.col_range(c)]
                        .iter()
                        .map(move |&r| (r, c))
                })
                .collect();
            let pattern = StiffnessPattern::from_lower_entries(n, &pairs);
            let slots: Vec<usize> = pairs
                .iter()
                .map(|&(r, c)| pattern.slot(r, c).expect("the pattern holds its entries"))
                .collect();
            let split = SplitQuasiDefinite::new(
                &pattern,
                tree.order,
                &tree.split,
                tree.levels,
                &signs,
                REGULARISATION,
            )?;
            Some(Analysis::Split(Box::new(split), slots))
        });
        let analysis = match split {
            Some(split) => split,
            None => Analysis::Whole(Box::new(
                factorize_symbolic_cholesky(
                    lower.as_ref(),
                    Side::Lower,
                    SymmetricOrdering::Amd,
                    Default::default(),
                )
                .map_err(|_| SingularMacroProblem)?,
            )),
        };
        let (row_start, by_row) = strict_lower_by_row(lower.as_ref());
        Ok(MacroPattern {
            argsort_len: entries.len(),
            lower,
            argsort,
            analysis,
            row_start,
            by_row,
        })
    }

    /// The levels of subtrees its factor is split into (0: whole).
    pub(super) fn split_levels(&self) -> usize {
        match &self.analysis {
            Analysis::Whole(_) => 0,
            Analysis::Split(split, _) => split.levels(),
        }
    }
}

impl Factor {
    /// The regularised `L D Lᵀ` factor of the matrix of `values` (in `pattern`'s assembly
    /// order); the first `n_forces` unknowns are forces (+), the rest kernel amplitudes (−).
    pub(in crate::solvers::latin) fn new(
        pattern: Arc<MacroPattern>,
        values: &[f64],
        n_forces: usize,
    ) -> Result<Self, SingularMacroProblem> {
        let lower = SparseColMat::new_from_argsort(pattern.lower.clone(), &pattern.argsort, values)
            .map_err(|_| SingularMacroProblem)?;
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
        let symbolic = match &pattern.analysis {
            Analysis::Whole(symbolic) => symbolic,
            Analysis::Split(split, slots) => {
                let mut values = vec![0.0; slots.len()];
                for (&slot, &v) in slots.iter().zip(scaled.val()) {
                    values[slot] = v;
                }
                let mut split = split.clone();
                split.factorize(&values).map_err(|_| SingularMacroProblem)?;
                return Ok(Factor {
                    pattern: Arc::clone(&pattern),
                    lower,
                    numeric: Numeric::Split(split),
                    scaling,
                });
            }
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
            numeric: Numeric::Whole(factor_values),
            scaling,
        })
    }

    /// Entries of its factor (with a split's dense separator blocks).
    pub(super) fn entries(&self) -> usize {
        match &self.numeric {
            Numeric::Whole(values) => values.len(),
            Numeric::Split(split) => split.entries(),
        }
    }

    /// A regularised factor of a singular matrix solves nothing: solve M y = M y0 for a known
    /// y0 of size `n` and compare.
    pub(super) fn check_regular(&self, n: usize) -> Result<(), SingularMacroProblem> {
        let error = self.forward_error(n);
        if error.is_nan() || error > 1e-6 {
            return Err(SingularMacroProblem);
        }
        Ok(())
    }

    /// The largest error of a solve (refined to the end) of `M y = M y0` for a known y0 of
    /// size `n`, entries in [1, 2).
    pub(super) fn forward_error(&self, n: usize) -> f64 {
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
    pub(in crate::solvers::latin) fn apply(&self, y: &[f64]) -> Vec<f64> {
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
    pub(super) fn solve(&self, b: &mut [f64], refined: f64) {
        let n = b.len();
        let mut scratch = MemBuffer::new(match &self.pattern.analysis {
            Analysis::Whole(symbolic) => symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
            Analysis::Split(..) => faer::dyn_stack::StackReq::EMPTY,
        });
        // M⁻¹ = S (S M S)⁻¹ S.
        let mut solve = |x: &mut [f64]| {
            x.iter_mut().zip(&self.scaling).for_each(|(x, s)| *x *= s);
            match (&self.numeric, &self.pattern.analysis) {
                (Numeric::Split(split), _) => split.solve_in_place(x),
                (Numeric::Whole(values), Analysis::Whole(symbolic)) => {
                    LdltRef::new(symbolic, values).solve_in_place_with_conj(
                        Conj::No,
                        MatMut::from_column_major_slice_mut(x, n, 1),
                        Par::Seq,
                        MemStack::new(&mut scratch),
                    )
                }
                (Numeric::Whole(_), Analysis::Split(..)) => {
                    unreachable!("a whole factor of a split")
                }
            }
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
