//! Every eigenpair below a threshold of the symmetric pencil `A v = λ B v`, A positive
//! semidefinite (a subdomain's Neumann stiffness: singular, with a kernel of rigid motions and
//! mechanisms) and B positive definite, for GenEO coarse spaces.
//!
//! Block Lanczos on the shift-inverted operator `(A − σB)⁻¹ B`, σ < 0 (so that `A − σB` is
//! positive definite even where A is singular), from a fixed-seed start block of [`BLOCK`]
//! vectors: every new block is B-orthogonalised twice against the whole basis (classical
//! Gram–Schmidt by blocks, then an eigen-decomposition of the block's own Gram matrix, which
//! drops the dependent directions). Rayleigh–Ritz on A over the B-orthonormal basis V (the
//! dense eigenproblem of `Vᵀ A V`) gives the eigenvalues λ directly, each Ritz value an upper
//! bound of its eigenvalue. The basis grows until every Ritz pair below the threshold and the
//! first one at or above it have converged. A Krylov sequence of blocks of p vectors holds at
//! most p copies of an eigenvalue: one of larger multiplicity (a kernel of 20) shows as a run
//! of p equal converged Ritz values, and the blocks then widen by [`BLOCK`] fresh random
//! vectors (filtered by the operator), which bring out the other copies.

use super::modal::random_vector;
use super::{NotPositiveDefinite, SparseCholesky, StiffnessPattern};
use basis::Basis;
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::DMatrix;

/// Vectors per Lanczos block at the start: an eigenvalue of up to this multiplicity comes out
/// of one start block; a larger one once the blocks widen.
const BLOCK: usize = 16;

/// Relative residual a Ritz pair must reach: `‖A x − λ B x‖ ≤ TOLERANCE (|λ| + FLOOR ρ) ‖B x‖`.
const TOLERANCE: f64 = 1e-6;

/// The residual test's absolute floor, a fraction of ρ (the mean diagonal of A over B's): a
/// zero mode's residual is round-off on A, not zero.
const FLOOR: f64 = 1e-3;

/// A column whose B-norm after the projection falls below this fraction of its norm before
/// lies in the basis already (to round-off), and is dropped.
const DEPENDENT: f64 = 1e-10;

/// An eigenvalue of a block's unit-diagonal Gram matrix below this fraction of the largest is
/// a dependent direction within the block, dropped.
const GRAM_DEPENDENT: f64 = 1e-13;

/// Shifts tried, each ten times further below 0 than the one before.
const SHIFT_TRIES: usize = 4;

/// Converged Ritz values this close, relative to `|λ| + FLOOR ρ`, are one multiple eigenvalue.
const CLUSTER: f64 = 1e-5;

/// The eigenpairs below a threshold found by [`modes_below`], ascending.
#[derive(Debug, Clone)]
pub struct LowModes {
    /// Eigenvalues λ < threshold, ascending.
    pub values: Vec<f64>,
    /// The eigenvectors, B-orthonormal, column j for `values[j]` (n × values.len()).
    pub vectors: DMatrix<f64>,
    /// Every eigenvalue below the threshold was found (the first Ritz value at or above it
    /// converged too), and each pair's residual met the tolerance.
    pub complete: bool,
}

/// Every eigenpair `A v = λ B v` with `λ < threshold`, ascending, A (positive semidefinite,
/// possibly singular) and B (positive definite) symmetric, stored as lower triangles on
/// `pattern`. At most `max_modes` pairs: where more lie below the threshold, the `max_modes`
/// lowest, with `complete` false.
///
/// `chol` must have been analysed on `pattern` ([`SparseCholesky::analyse`]); it is left
/// holding the factor of `A − σB`, σ < 0 the shift used (−0.1 times the threshold, or
/// further down where that does not factorize).
///
/// A pair counts as converged when `‖A x − λ B x‖ ≤ 1e-6 (|λ| + 1e-3 ρ) ‖B x‖`, ρ the mean
/// diagonal of A over B's. `complete` is true when every pair returned and the first Ritz
/// pair at or above the threshold converged (or the basis spans the whole space), and no more
/// than `max_modes` lie below the threshold.
///
/// # Errors
///
/// [`NotPositiveDefinite`] when `A − σB` does not factorize for any shift tried (A not
/// positive semidefinite, or B not positive definite), and, with `pivot` 0, when A or B holds
/// a NaN or an infinite value, when the threshold is NaN (an infinite one is accepted: every
/// pair, up to `max_modes`), when B's mean diagonal is not positive, or when the projected
/// eigenproblem fails (non-finite Ritz values).
///
/// # Panics
///
/// If `a` or `b` is not of `pattern.nnz()` values.
pub fn modes_below(
    pattern: &StiffnessPattern,
    a: &[f64],
    b: &[f64],
    chol: &mut SparseCholesky,
    threshold: f64,
    max_modes: usize,
) -> Result<LowModes, NotPositiveDefinite> {
    modes_below_with_basis(pattern, a, b, chol, threshold, max_modes).map(|(modes, _)| modes)
}

/// [`modes_below`], with the number of basis vectors it took.
fn modes_below_with_basis(
    pattern: &StiffnessPattern,
    a: &[f64],
    b: &[f64],
    chol: &mut SparseCholesky,
    threshold: f64,
    max_modes: usize,
) -> Result<(LowModes, usize), NotPositiveDefinite> {
    let n = pattern.n;
    assert_eq!(a.len(), pattern.nnz(), "A's values on another pattern");
    assert_eq!(b.len(), pattern.nnz(), "B's values on another pattern");
    let refused = NotPositiveDefinite { pivot: 0 };
    if n == 0 && !threshold.is_nan() {
        let modes = LowModes {
            values: Vec::new(),
            vectors: DMatrix::zeros(0, 0),
            complete: true,
        };
        return Ok((modes, 0));
    }
    let rho = pencil_scale(pattern, a, b, threshold)?;
    let floor = FLOOR * rho;
    factorize_shifted(pattern, a, b, chol, threshold, rho)?;
    let chol: &SparseCholesky = chol;
    // (A − σB)⁻¹ Y and (A − σB)⁻¹ B X, a block at a time.
    let solve = |mut y: Vec<f64>| {
        let cols = y.len() / n;
        chol.solve_block_in_place(MatMut::from_column_major_slice_mut(&mut y, n, cols));
        y
    };
    let op = |x: &[f64]| solve(apply(pattern, b, x, n));
    let cap = basis_cap(n, max_modes);
    let mut basis = Basis::new(n);
    let mut seed = 0u64;
    // A fresh start block of `cols` vectors: random, filtered twice by the operator (B-orthogonal
    // to the basis in between), so that the eigenvalues near σ dominate it.
    let fresh = |basis: &Basis, cols: usize, seed: &mut u64| {
        let start: Vec<f64> = (0..cols)
            .flat_map(|_| {
                *seed += 1;
                random_vector(n, *seed)
            })
            .collect();
        let mut once = op(&start);
        basis.project_out(&mut once);
        op(&once)
    };
    // Vectors per block: BLOCK, and BLOCK more for each widening. An eigenvalue of
    // multiplicity up to the width comes out.
    let mut width = BLOCK.min(n);
    let mut block = fresh(&basis, width, &mut seed);
    // The leading Ritz pairs whose residuals held at the last check.
    let mut settled = 0;
    loop {
        let old = basis.len();
        let (w, bw) = basis.orthonormalize(pattern, b, block);
        basis.append(pattern, a, w, bw);
        // A block that lost columns (the Krylov space became invariant, to round-off) is
        // topped up with fresh vectors, so that the width stays.
        let target = width.min(n - old);
        if basis.len() - old < target {
            let extra = fresh(&basis, target - (basis.len() - old), &mut seed);
            let (w, bw) = basis.orthonormalize(pattern, b, extra);
            basis.append(pattern, a, w, bw);
        }
        let len = basis.len();
        let grew = len > old;
        let (theta, u) = symmetric_eigen(basis.h.as_ref()).ok_or(refused)?;
        let below = theta.iter().take_while(|&&t| t < threshold).count();
        let capped = below > max_modes;
        let exact = len >= n;
        // The pairs that must converge: those returned, and the first at or above the
        // threshold (where none is capped away).
        let wanted = if capped { max_modes } else { below + 1 };
        let mut converged = exact;
        if !exact && wanted <= len {
            let residual = |from: usize, to: usize| {
                basis.first_unconverged(&theta, u.as_ref(), from, to, floor)
            };
            settled = residual(settled.min(wanted), wanted);
            if settled >= wanted {
                // The pairs below the frontier were converged at earlier checks: confirm them
                // on the current Ritz vectors.
                settled = residual(0, wanted);
                converged = settled >= wanted;
            }
        }
        let stuck = !grew || len >= cap;
        if converged && !exact && !stuck && longest_run(&theta[..wanted], floor) >= width {
            // A run of `width` (or more) equal values: an eigenvalue that may have more
            // copies than a Krylov sequence of this width holds. The sequence goes on with
            // BLOCK fresh vectors more in each block: the next block is the operator on the
            // last one, and the fresh ones (a sequence started apart would share no block with
            // this one, and the two would converge only slowly in each other's presence).
            let mut wider = solve(basis.bv_from(old));
            wider.extend(fresh(&basis, BLOCK.min(n - len), &mut seed));
            width += BLOCK;
            block = wider;
            continue;
        }
        if converged || stuck {
            let count = below.min(max_modes);
            let complete = converged && !capped;
            let vectors = product(basis.v(), false, u.as_ref().subcols(0, count));
            let modes = LowModes {
                values: theta[..count].to_vec(),
                vectors: DMatrix::from_fn(n, count, |i, j| vectors[(i, j)]),
                complete,
            };
            return Ok((modes, len));
        }
        // The operator on the columns just added: B times them is at hand.
        block = solve(basis.bv_from(old));
    }
}

/// ρ, the pencil's scale (A's mean diagonal over B's), once the input is checked: refused
/// where a value is not finite, the threshold is NaN, or B's mean diagonal is not positive.
fn pencil_scale(
    pattern: &StiffnessPattern,
    a: &[f64],
    b: &[f64],
    threshold: f64,
) -> Result<f64, NotPositiveDefinite> {
    let refused = NotPositiveDefinite { pivot: 0 };
    if threshold.is_nan() || a.iter().chain(b).any(|x| !x.is_finite()) {
        return Err(refused);
    }
    let mean_b = pattern.mean_diagonal(b);
    // Finite: A and B are.
    if mean_b <= 0.0 {
        return Err(refused);
    }
    let rho = pattern.mean_diagonal(a).abs() / mean_b;
    if !rho.is_finite() {
        return Err(refused);
    }
    Ok(rho)
}

/// The most basis vectors before the iteration stops unconverged: the Ritz step's cost grows
/// with their cube. Four vectors a pair allowed and ten blocks: 120 pairs of a 3 000-dof grid
/// Laplacian took 448 (3.7 a pair), 17 took 144.
fn basis_cap(n: usize, max_modes: usize) -> usize {
    n.min(
        max_modes
            .min(n)
            .saturating_mul(4)
            .saturating_add(10 * BLOCK),
    )
}

/// Factorizes `A − σB` with σ = −0.1 times the threshold (at least 1e-6 ρ; ρ where the
/// threshold is not positive or infinite), moved ten times further down while it does not
/// factorize, [`SHIFT_TRIES`] tries; the last error otherwise.
fn factorize_shifted(
    pattern: &StiffnessPattern,
    a: &[f64],
    b: &[f64],
    chol: &mut SparseCholesky,
    threshold: f64,
    rho: f64,
) -> Result<f64, NotPositiveDefinite> {
    let reference = if rho > 0.0 { rho } else { 1.0 };
    let scale = if threshold.is_finite() && threshold > 0.0 {
        threshold.max(1e-6 * reference)
    } else {
        reference
    };
    let mut sigma = -0.1 * scale;
    let mut shifted = vec![0.0; a.len()];
    let mut last = NotPositiveDefinite { pivot: 0 };
    for _ in 0..SHIFT_TRIES {
        shifted
            .iter_mut()
            .zip(a.iter().zip(b))
            .for_each(|(s, (x, y))| *s = x - sigma * y);
        match chol.factorize(pattern, &shifted) {
            Ok(()) => return Ok(sigma),
            Err(error) => last = error,
        }
        sigma *= 10.0;
    }
    Err(last)
}

/// A column-major block of vectors of length `n` as a faer view.
fn view(values: &[f64], n: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(values, n, values.len() / n)
}

/// `op(a) b` (`op` the transpose when `transposed`), a new matrix.
fn product(a: MatRef<'_, f64>, transposed: bool, b: MatRef<'_, f64>) -> Mat<f64> {
    let a = if transposed { a.transpose() } else { a };
    let mut y = Mat::<f64>::zeros(a.nrows(), b.ncols());
    matmul(y.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    y
}

/// `M X` for the symmetric M of `values` on `pattern` and a column-major block X.
fn apply(pattern: &StiffnessPattern, values: &[f64], x: &[f64], n: usize) -> Vec<f64> {
    debug_assert_eq!(pattern.n, n);
    let mut y = vec![0.0; x.len()];
    pattern.sym_matmat(values, x, &mut y);
    y
}

/// The eigenvalues (ascending) and eigenvectors of the symmetric `h` (its lower triangle
/// read), sequentially (the same bits whatever the thread count); `None` if `h` or the result
/// holds a non-finite value or the iteration fails.
fn symmetric_eigen(h: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    let m = h.nrows();
    if (0..m).any(|j| (j..m).any(|i| !h[(i, j)].is_finite())) {
        return None;
    }
    let mut s = Diag::<f64>::zeros(m);
    let mut u = Mat::<f64>::zeros(m, m);
    let par = Par::Seq;
    let mut scratch = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
        m,
        ComputeEigenvectors::Yes,
        par,
        Default::default(),
    ));
    self_adjoint_evd(
        h,
        s.as_mut(),
        Some(u.as_mut()),
        par,
        MemStack::new(&mut scratch),
        Default::default(),
    )
    .ok()?;
    let values: Vec<f64> = s.column_vector().iter().copied().collect();
    if values.iter().any(|x| !x.is_finite()) {
        return None;
    }
    Some((values, u))
}

/// Length of the longest run of consecutive values (ascending) that differ by at most
/// `CLUSTER (|λ| + floor)`: the multiplicity of the most repeated eigenvalue among them.
fn longest_run(values: &[f64], floor: f64) -> usize {
    let mut longest = usize::from(!values.is_empty());
    let mut run = 1;
    for pair in values.windows(2) {
        if pair[1] - pair[0] <= CLUSTER * (pair[0].abs() + floor) {
            run += 1;
            longest = longest.max(run);
        } else {
            run = 1;
        }
    }
    longest
}

mod basis;
mod subspace;
pub use subspace::modes_below_by_subspace;
#[cfg(test)]
mod tests;
