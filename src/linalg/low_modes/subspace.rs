//! The low eigenpairs of `A v = λ B v` by block subspace iteration, approximately: the cheap
//! sibling of [`super::modes_below`] for a coarse space, which needs the span of the low modes,
//! not their digits (a coarse space of approximate vectors is still exact Galerkin: only the
//! condition number feels the error).
//!
//! `X ← (A − σB)⁻¹ B X`, `sweeps` times from a block of `width` vectors (those of a start
//! block, an earlier answer's, then fixed-seed random ones), B-orthonormalised each time, then
//! Rayleigh–Ritz (the eigenproblem of `Xᵀ A X`) on the last block. An eigenvector's
//! error shrinks by `(λ_i − σ) / (λ_{width+1} − σ)` a sweep: the kernel and the lowest modes
//! come out in two or three sweeps, those near the threshold more roughly. Where more than
//! half the block lies below the threshold the block doubles (at most `max_modes` kept).

use super::basis::{b_norms, combine_by_gram, Basis};
use super::*;

/// The eigenpairs below `threshold` of the subspace iteration's last Ritz step, ascending
/// (see the module's text), at most `max_modes`. `complete` is true when every pair returned
/// meets [`modes_below`]'s residual test and at most half the block lay below the threshold.
///
/// `start` (n rows, possibly none): the block's first columns, at most `width` of them (a warm
/// start from vectors near the wanted ones). `chol` must have been analysed on `pattern`; it
/// is left holding the factor of `A − σB`.
///
/// # Errors
///
/// As [`modes_below`]: [`NotPositiveDefinite`] when `A − σB` does not factorize for any shift
/// tried, or the input holds non-finite values, or a Ritz step fails.
pub fn modes_below_by_subspace(
    pattern: &StiffnessPattern,
    a: &[f64],
    b: &[f64],
    chol: &mut SparseCholesky,
    (threshold, max_modes): (f64, usize),
    (width, sweeps): (usize, usize),
    start: Option<&DMatrix<f64>>,
) -> Result<LowModes, NotPositiveDefinite> {
    let n = pattern.n;
    assert_eq!(a.len(), pattern.nnz(), "A's values on another pattern");
    assert_eq!(b.len(), pattern.nnz(), "B's values on another pattern");
    let refused = NotPositiveDefinite { pivot: 0 };
    if n == 0 && !threshold.is_nan() {
        return Ok(LowModes {
            values: Vec::new(),
            vectors: DMatrix::zeros(0, 0),
            complete: true,
        });
    }
    let rho = pencil_scale(pattern, a, b, threshold)?;
    let floor = FLOOR * rho;
    factorize_shifted(pattern, a, b, chol, threshold, rho)?;
    let chol: &SparseCholesky = chol;
    let mut width = width.clamp(1, n.max(1));
    loop {
        let warm = start.map_or(0, |x| x.ncols().min(width));
        let mut block: Vec<f64> = Vec::with_capacity(n * width);
        if let Some(x) = start {
            assert_eq!(x.nrows(), n, "a start block of another size");
            block.extend(x.columns(0, warm).iter());
        }
        block.extend((warm as u64..width as u64).flat_map(|seed| random_vector(n, seed + 1)));
        let mut b_block = apply(pattern, b, &block, n);
        let mut w = Vec::new();
        let mut bw = Vec::new();
        for _ in 0..sweeps.max(1) {
            // X ← (A − σB)⁻¹ B X, B-orthonormalised. Only the span matters between sweeps
            // (it is the same whatever basis of it the next sweep starts from), so the
            // Rayleigh–Ritz step is made once, after the last: a step per sweep took about
            // half of the iteration's dense work.
            let mut x = b_block;
            let cols = x.len() / n;
            chol.solve_block_in_place(MatMut::from_column_major_slice_mut(&mut x, n, cols));
            let bx = apply(pattern, b, &x, n);
            (w, bw) = b_orthonormal(&x, &bx, n);
            b_block = bw.clone();
        }
        // H = Xᵀ A X and its eigenpairs: the Ritz pairs of the last block.
        let mut basis = Basis::new(n);
        basis.append(pattern, a, w, bw);
        let (theta, u) = symmetric_eigen(basis.h.as_ref()).ok_or(refused)?;
        let below = theta.iter().take_while(|&&t| t < threshold).count();
        let crowded = below >= basis.len();
        if crowded && width < n && width < 2 * max_modes {
            width = (2 * width).min(n);
            continue;
        }
        let count = below.min(max_modes);
        let converged = basis.first_unconverged(&theta, u.as_ref(), 0, count, floor) == count;
        let vectors = product(basis.v(), false, u.as_ref().subcols(0, count));
        return Ok(LowModes {
            values: theta[..count].to_vec(),
            vectors: DMatrix::from_fn(n, count, |i, j| vectors[(i, j)]),
            complete: converged && !crowded && below <= max_modes,
        });
    }
}

/// The columns of `x` made B-orthonormal in one pass (`bx` is B times them): scaled to unit
/// B-norm, then combined by the eigenvectors of their Gram matrix, `X ← X U D^{-1/2}`; a
/// column of zero or non-finite B-norm and a direction of the Gram matrix at
/// `GRAM_DEPENDENT` of its largest or less are dropped. B times the result with it.
fn b_orthonormal(x: &[f64], bx: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let norms = b_norms(x, bx, n);
    let kept: Vec<usize> = (0..norms.len())
        .filter(|&j| norms[j] > 0.0 && norms[j].is_finite())
        .collect();
    let scaled = |v: &[f64]| -> Vec<f64> {
        kept.iter()
            .flat_map(|&j| {
                let norm = norms[j];
                v[j * n..(j + 1) * n].iter().map(move |e| e / norm)
            })
            .collect()
    };
    combine_by_gram(&scaled(x), &scaled(bx), n)
        .map_or((Vec::new(), Vec::new()), |(w, bw, _)| (w, bw))
}
