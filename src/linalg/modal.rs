//! The lowest eigenpairs of the generalized problem `K φ = λ M φ` (natural modes, issue 45):
//! block Lanczos on the shift-inverted operator `(K − σM)⁻¹ M` with full M-orthogonalisation
//! and a Rayleigh–Ritz step on K (dense, on the Krylov basis only), over the sparse Cholesky
//! factor of `K − σM`, restarted from its best Ritz vectors every [`RESTART_BLOCKS`] blocks. K may be singular (σ < 0) and M singular where members carry no mass.

use super::{SparseCholesky, StiffnessPattern};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::{DMatrix, SymmetricEigen};

/// Blocks the Krylov basis grows to before it restarts from its best Ritz vectors.
const RESTART_BLOCKS: usize = 12;

/// Free dofs up to which a Krylov solve that returns fewer pairs than asked, or unconverged
/// ones, is redone densely (a dense shift-invert solve, then inverse iteration per mode): a
/// mass that dwarfs the others (a 1e8 kg point mass on a 3-node simplex) leaves the Krylov
/// vectors M-dependent to round-off, and the basis stops short of the modes asked for.
pub const DENSE_MODES_UP_TO: usize = 600;

/// The lowest eigenpairs found, ascending.
#[derive(Debug, Clone)]
pub struct GeneralizedModes {
    /// Eigenvalues λ = ω² (the Rayleigh quotients of the Ritz vectors), ascending.
    pub values: Vec<f64>,
    /// The eigenvectors, M-orthonormal, one per value.
    pub vectors: Vec<Vec<f64>>,
    /// As many pairs as asked for (up to the dofs) were found, and every pair's residual
    /// `‖K φ − λ M φ‖` fell below the tolerance.
    pub converged: bool,
}

/// Why no modes: `K − σM` would not factorize for any shift tried (K indefinite beyond the
/// largest shift, or M zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoShiftFactorizes;

/// Deterministic pseudo-random vector (xorshift), entries in [−0.5, 0.5): the start vectors of
/// the Krylov solvers here.
pub(super) fn random_vector(n: usize, seed: u64) -> Vec<f64> {
    let mut state = 0x9E37_79B9_7F4A_7C15u64 ^ seed.wrapping_mul(0x2545_F491_4F6C_DD1D);
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

/// `Σ a_k b_k` in eight interleaved partial sums (vectorised, in a fixed order).
fn dot8(a: &[f64], b: &[f64]) -> f64 {
    let mut partial = [0.0; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            partial[k] += x[k] * y[k];
        }
    }
    partial.iter().sum::<f64>() + tail
}

/// A column-major `n × cols` block of vectors as a faer view.
fn view(values: &[f64], n: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(values, n, values.len() / n.max(1))
}

/// `Y = op(A) B` (`op` the transpose when `transposed`), a new column-major matrix.
fn product(a: MatRef<'_, f64>, transposed: bool, b: MatRef<'_, f64>) -> Mat<f64> {
    let a = if transposed { a.transpose() } else { a };
    let mut y = Mat::<f64>::zeros(a.nrows(), b.ncols());
    matmul(y.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    y
}

/// One block of the basis: its vectors and M times them, column-major `n × cols`.
struct Block {
    v: Vec<f64>,
    mv: Vec<f64>,
}

/// The Krylov basis, M-orthonormal, by blocks, and the projection `H = Vᵀ K V` grown a column
/// at a time (`h[j][i] = v_i · K v_j`, i ≤ j).
struct Basis {
    n: usize,
    blocks: Vec<Block>,
    h: Vec<Vec<f64>>,
}

impl Basis {
    fn new(n: usize) -> Basis {
        Basis {
            n,
            blocks: Vec::new(),
            h: Vec::new(),
        }
    }

    /// Vectors in the basis.
    fn len(&self) -> usize {
        self.h.len()
    }

    /// Adds the columns of `x` (column-major `n × b`) M-orthogonalised against the basis
    /// (twice, by blocks: `X −= V (MV)ᵀ X`) and each other (twice, one by one); returns how
    /// many were kept (a column whose M-norm falls below 1e-10 of its own is dependent, or
    /// massless, and dropped).
    fn extend(
        &mut self,
        pattern: &StiffnessPattern,
        k: &[f64],
        m: &[f64],
        mut x: Vec<f64>,
    ) -> usize {
        let n = self.n;
        let mut mx = vec![0.0; n];
        let before: Vec<f64> = x
            .chunks(n)
            .map(|c| {
                pattern.sym_matvec(m, c, &mut mx);
                dot8(c, &mx).max(0.0).sqrt()
            })
            .collect();
        for _ in 0..2 {
            for block in &self.blocks {
                let c = product(view(&block.mv, n), true, view(&x, n));
                let cols = x.len() / n;
                let mut xm = MatMut::from_column_major_slice_mut(&mut x, n, cols);
                matmul(
                    xm.as_mut(),
                    Accum::Add,
                    view(&block.v, n),
                    c.as_ref(),
                    -1.0,
                    Par::Seq,
                );
            }
        }
        let (mut v, mut mv) = (Vec::new(), Vec::new());
        for (column, &size) in x.chunks(n).zip(&before) {
            let mut column = column.to_vec();
            for _ in 0..2 {
                for (q, mq) in v.chunks(n).zip(mv.chunks(n)) {
                    let r = dot8(mq, &column);
                    column.iter_mut().zip(q).for_each(|(xi, qi)| *xi -= r * qi);
                }
            }
            pattern.sym_matvec(m, &column, &mut mx);
            let norm = dot8(&column, &mx).max(0.0).sqrt();
            // A NaN norm is dropped too.
            if !(norm > 1e-10 * size && size > 0.0) {
                continue;
            }
            v.extend(column.iter().map(|xi| xi / norm));
            mv.extend(mx.iter().map(|xi| xi / norm));
        }
        let kept = v.len() / n;
        if kept == 0 {
            return 0;
        }
        let mut kv = vec![0.0; v.len()];
        for (q, kq) in v.chunks(n).zip(kv.chunks_mut(n)) {
            pattern.sym_matvec(k, q, kq);
        }
        self.blocks.push(Block { v, mv });
        // H's new columns: every basis vector (the new block's too) against K times the new.
        let parts: Vec<Mat<f64>> = self
            .blocks
            .iter()
            .map(|b| product(view(&b.v, n), true, view(&kv, n)))
            .collect();
        let first = self.len();
        for j in 0..kept {
            let column: Vec<f64> = parts
                .iter()
                .flat_map(|p| (0..p.nrows()).map(move |i| p[(i, j)]))
                .take(first + j + 1)
                .collect();
            self.h.push(column);
        }
        kept
    }

    /// Rayleigh–Ritz on K: the `count` lowest Ritz values and vectors (column-major `n ×
    /// count`).
    fn ritz(&self, count: usize) -> (Vec<f64>, Vec<f64>) {
        let (n, size) = (self.n, self.len());
        let h = DMatrix::from_fn(size, size, |i, j| self.h[i.max(j)][i.min(j)]);
        let eig = SymmetricEigen::new(h);
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        order.truncate(count);
        let mut vectors = Mat::<f64>::zeros(n, order.len());
        let mut row = 0;
        for block in &self.blocks {
            let cols = block.v.len() / n;
            let y = Mat::<f64>::from_fn(cols, order.len(), |i, c| {
                eig.eigenvectors[(row + i, order[c])]
            });
            matmul(
                vectors.as_mut(),
                Accum::Add,
                view(&block.v, n),
                y.as_ref(),
                1.0,
                Par::Seq,
            );
            row += cols;
        }
        let values = order.iter().map(|&c| eig.eigenvalues[c]).collect();
        let columns =
            (0..order.len()).flat_map(|c| vectors.col(c).iter().copied().collect::<Vec<_>>());
        (values, columns.collect())
    }
}

/// The `count` lowest eigenpairs of `K φ = λ M φ`, K and M symmetric lower triangles on
/// `pattern` (K positive semidefinite, M positive semidefinite and positive on K's kernel).
/// `chol` must have been analysed on `pattern`; it is left holding `K − σM`. Converged when
/// `count` pairs (at most the dofs with mass) were found and every pair's residual
/// `‖K φ − λ M φ‖ ≤ tolerance · (|λ| + 1e-4 ρ) ‖M φ‖`, ρ the mean diagonal of K over M's.
/// Up to [`DENSE_MODES_UP_TO`] dofs, a Krylov solve short of that is redone densely.
pub fn lowest_generalized_modes(
    pattern: &StiffnessPattern,
    k: &[f64],
    m: &[f64],
    chol: &mut SparseCholesky,
    count: usize,
    tolerance: f64,
) -> Result<GeneralizedModes, NoShiftFactorizes> {
    let ratio = pattern.mean_diagonal(k).abs() / pattern.mean_diagonal(m).max(f64::MIN_POSITIVE);
    let sigma = factorize_shifted(pattern, k, m, chol, ratio)?;
    let krylov = krylov_modes(pattern, (k, m), chol, count, tolerance, ratio);
    if krylov.converged || pattern.n > DENSE_MODES_UP_TO {
        return Ok(krylov);
    }
    let dense = dense_generalized_modes(pattern, (k, m), sigma, count);
    let converged = dense.values.len() == count.min(massive_dofs(pattern, m))
        && residuals_hold(pattern, (k, m), &dense, 1e-4 * ratio, tolerance);
    Ok(GeneralizedModes { converged, ..dense })
}

/// Block Lanczos on `(K − σM)⁻¹ M` (`chol` holding `K − σM`), [`lowest_generalized_modes`]'s
/// first try.
fn krylov_modes(
    pattern: &StiffnessPattern,
    (k, m): (&[f64], &[f64]),
    chol: &mut SparseCholesky,
    count: usize,
    tolerance: f64,
    ratio: f64,
) -> GeneralizedModes {
    let n = pattern.n;
    let count = count.min(n);
    // The residuals' absolute floor: 1e-4 of the mean diagonal's eigenvalue scale (a zero
    // mode's residual is round-off on K, not zero).
    let floor = 1e-4 * ratio;
    let block_size = (count + 4).max(2 * count).min(n);
    let mut basis = Basis::new(n);
    // (K − σM)⁻¹ M X, a block at a time.
    let apply = |x: &[f64]| {
        let mut y = vec![0.0; x.len()];
        for (xc, yc) in x.chunks(n).zip(y.chunks_mut(n)) {
            pattern.sym_matvec(m, xc, yc);
        }
        let cols = y.len() / n;
        chol.solve_block_in_place(MatMut::from_column_major_slice_mut(&mut y, n, cols));
        y
    };
    let start: Vec<f64> = (0..block_size)
        .flat_map(|j| random_vector(n, j as u64 + 1))
        .collect();
    let mut block = apply(&start);
    // Vectors the basis has taken, over every restart: the work is bounded by this.
    let mut taken = 0;
    loop {
        let kept = basis.extend(pattern, k, m, block);
        taken += kept;
        let exhausted = kept == 0 || basis.len() >= n;
        let (values, vectors) = basis.ritz(count);
        let modes = GeneralizedModes {
            values,
            vectors: vectors.chunks(n).map(<[f64]>::to_vec).collect(),
            converged: false,
        };
        // A basis that spans the whole space holds every pair; one that stopped short of
        // `count` (M-dependent to round-off) holds fewer than asked: not converged.
        let converged = modes.values.len() == count
            && (basis.len() >= n || residuals_hold(pattern, (k, m), &modes, floor, tolerance));
        if converged || exhausted || taken >= 60 * block_size.max(4) {
            return GeneralizedModes { converged, ..modes };
        }
        block = if basis.len() >= RESTART_BLOCKS * block_size {
            // Restart from the best block_size Ritz vectors: the basis's cost (its products
            // grow with its size squared) stays bounded on large structures.
            let (_, best) = basis.ritz(block_size);
            basis = Basis::new(n);
            basis.extend(pattern, k, m, best);
            apply(&basis.blocks[0].v)
        } else {
            apply(basis.blocks.last().map_or(&[][..], |b| &b.v[..]))
        };
    }
}

/// Whether every pair of `modes` has `‖K φ − λ M φ‖ ≤ tolerance · (|λ| + floor) ‖M φ‖`.
fn residuals_hold(
    pattern: &StiffnessPattern,
    (k, m): (&[f64], &[f64]),
    modes: &GeneralizedModes,
    floor: f64,
    tolerance: f64,
) -> bool {
    let n = pattern.n;
    let (mut kx, mut mx) = (vec![0.0; n], vec![0.0; n]);
    modes.values.iter().zip(&modes.vectors).all(|(&lambda, x)| {
        pattern.sym_matvec(k, x, &mut kx);
        pattern.sym_matvec(m, x, &mut mx);
        let r: f64 = kx
            .iter()
            .zip(&mx)
            .map(|(a, b)| (a - lambda * b).powi(2))
            .sum::<f64>()
            .sqrt();
        r <= tolerance * (lambda.abs() + floor) * dot8(&mx, &mx).sqrt()
    })
}

/// The dofs with mass: the diagonal entries of M above 0 (a massless dof has no mode).
fn massive_dofs(pattern: &StiffnessPattern, m: &[f64]) -> usize {
    pattern
        .entries()
        .filter(|&(r, c, slot)| r == c && m[slot] > 0.0)
        .count()
}

/// The `count` lowest pairs of `K φ = λ M φ` densely: `K − σM = L Lᵀ` (σ from
/// [`factorize_shifted`], so positive definite), the eigenpairs `(μ, y)` of the symmetric
/// `L⁻¹ M L⁻ᵀ`, then `φ = L⁻ᵀ y / √μ` (M-normalised: `φᵀ M φ = 1`), each refined by two steps
/// of inverse iteration at its own shift, `φ ← (K − λM)⁻¹ M φ` (one shift resolves the pairs
/// to `‖K − σM‖` only: 1e-7 of the stiff end with a mass 1e8 times the others), λ the
/// Rayleigh quotient `φᵀ K φ / φᵀ M φ`. A μ at round-off of the largest (a massless
/// direction, λ infinite) is no mode.
fn dense_generalized_modes(
    pattern: &StiffnessPattern,
    (k, m): (&[f64], &[f64]),
    sigma: f64,
    count: usize,
) -> GeneralizedModes {
    let n = pattern.n;
    let empty = GeneralizedModes {
        values: Vec::new(),
        vectors: Vec::new(),
        converged: false,
    };
    let (mut shifted, mut mass) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    for (r, c, slot) in pattern.entries() {
        let (a, b) = (k[slot] - sigma * m[slot], m[slot]);
        (shifted[(r, c)], shifted[(c, r)]) = (a, a);
        (mass[(r, c)], mass[(c, r)]) = (b, b);
    }
    let Some(cholesky) = nalgebra::Cholesky::new(shifted.clone()) else {
        return empty;
    };
    let l = cholesky.l();
    // C = L⁻¹ M L⁻ᵀ: two triangular solves.
    let Some(half) = l.solve_lower_triangular(&mass) else {
        return empty;
    };
    let Some(c) = l.solve_lower_triangular(&half.transpose()) else {
        return empty;
    };
    let c = (&c + c.transpose()) * 0.5;
    let eig = SymmetricEigen::new(c);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    // Descending μ is ascending λ.
    let mut order: Vec<usize> = (0..n)
        .filter(|&i| eig.eigenvalues[i] > 1e-14 * largest)
        .collect();
    order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    order.truncate(count);
    let lt = l.transpose();
    // K itself, from K − σM.
    let stiffness = &shifted + &mass * sigma;
    let (mut values, mut vectors) = (Vec::new(), Vec::new());
    for i in order {
        let Some(mut phi) = lt.solve_upper_triangular(&eig.eigenvectors.column(i).into_owned())
        else {
            return empty;
        };
        let mut lambda = sigma + 1.0 / eig.eigenvalues[i];
        for step in 0..=2 {
            // M-normalised, and λ its Rayleigh quotient φᵀ K φ.
            let norm = phi.dot(&(&mass * &phi)).sqrt();
            phi /= norm;
            lambda = phi.dot(&(&stiffness * &phi));
            if step == 2 {
                break;
            }
            // φ ← (K − λM)⁻¹ M φ.
            let Some(next) = (&stiffness - &mass * lambda).lu().solve(&(&mass * &phi)) else {
                break;
            };
            if !next.iter().all(|x| x.is_finite()) {
                break;
            }
            phi = next;
        }
        values.push(lambda);
        vectors.push(phi.iter().copied().collect());
    }
    GeneralizedModes {
        values,
        vectors,
        converged: false,
    }
}

/// Factorizes `K − σM` with σ = −1e-8 · ratio (ratio the mean diagonal of K over M's), the
/// shift grown a hundredfold while it does not factorize; returns σ. A small shift keeps the
/// lowest modes apart in `(K − σM)⁻¹ M` (eigenvalues `1/(λ − σ)`): on a large structure they
/// lie far below the mean diagonal's scale.
fn factorize_shifted(
    pattern: &StiffnessPattern,
    k: &[f64],
    m: &[f64],
    chol: &mut SparseCholesky,
    ratio: f64,
) -> Result<f64, NoShiftFactorizes> {
    let mut sigma = -1e-8 * ratio;
    let mut shifted = vec![0.0; k.len()];
    while sigma.abs() <= 1e4 * ratio && ratio > 0.0 {
        shifted
            .iter_mut()
            .zip(k.iter().zip(m))
            .for_each(|(s, (a, b))| *s = a - sigma * b);
        if chol.factorize(pattern, &shifted).is_ok() {
            return Ok(sigma);
        }
        sigma *= 100.0;
    }
    Err(NoShiftFactorizes)
}

#[cfg(test)]
mod tests {
    use super::lowest_generalized_modes;
    use crate::linalg::{SparseCholesky, SparseRow, StiffnessPattern};
    use faer::Par;
    use nalgebra::{DMatrix, SymmetricEigen};

    /// The lowest eigenvalues of `K φ = λ M φ` against a dense solve (`L⁻¹ K L⁻ᵀ`, M = L Lᵀ), on
    /// a chain of springs with a free end (K regular) and with none held (one zero mode, K
    /// singular), consistent masses: including the repeated ones of two equal chains.
    #[test]
    fn lowest_modes_match_a_dense_solve() {
        for held in [true, false] {
            let chain = 40;
            let n = 2 * chain;
            // Two equal chains side by side: every eigenvalue twice.
            let mut rows = Vec::new();
            for c in 0..2 {
                let at = |i: usize| c * chain + i;
                if held {
                    rows.push(SparseRow::new([(Some(at(0)), 1.0)]));
                }
                for i in 0..chain - 1 {
                    rows.push(SparseRow::new([
                        (Some(at(i)), -1.0),
                        (Some(at(i + 1)), 1.0),
                    ]));
                }
            }
            let pattern = StiffnessPattern::new(n, &rows);
            let mut k = vec![0.0; pattern.nnz()];
            pattern.assemble(&rows, |i| 1.0 + (i % 3) as f64, &mut k);
            let mut m = vec![0.0; pattern.nnz()];
            pattern.assemble(&rows, |_| 0.0, &mut m);
            for (r, c, s) in pattern.entries() {
                m[s] = if r == c { 2.0 } else { 0.5 };
            }
            let dense = |v: &[f64]| {
                let mut a = DMatrix::zeros(n, n);
                for (r, c, s) in pattern.entries() {
                    a[(r, c)] = v[s];
                    a[(c, r)] = v[s];
                }
                a
            };
            let l = dense(&m).cholesky().unwrap().l();
            let li = l.clone().try_inverse().unwrap();
            let c = &li * dense(&k) * li.transpose();
            let mut exact: Vec<f64> = SymmetricEigen::new(c).eigenvalues.iter().copied().collect();
            exact.sort_by(f64::total_cmp);
            let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
            let modes = lowest_generalized_modes(&pattern, &k, &m, &mut chol, 6, 1e-10).unwrap();
            assert!(modes.converged);
            for (i, (a, b)) in modes.values.iter().zip(&exact).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-9 * exact[5],
                    "{held} {i}: {a} against {b}"
                );
            }
            assert_eq!(modes.values.len(), 6);
        }
    }

    /// A long fixed–free chain (3000 unit springs, unit masses, consistent): its lowest
    /// eigenvalues lie 1e-7 below the mean diagonal's scale, and match the hand formula
    /// `λ_j = 6 (1 − cos θ_j) / (2 + cos θ_j)`, `θ_j = (2j − 1) π / 2N` (the symmetric modes of
    /// the fixed–fixed chain of 2N), to 1e-8: the shift stays near them.
    #[test]
    fn a_long_chain_matches_its_hand_formula() {
        let n = 3000;
        let mut rows = vec![SparseRow::new([(Some(0), 1.0)])];
        for i in 0..n - 1 {
            rows.push(SparseRow::new([(Some(i), -1.0), (Some(i + 1), 1.0)]));
        }
        let pattern = StiffnessPattern::new(n, &rows);
        let mut k = vec![0.0; pattern.nnz()];
        pattern.assemble(&rows, |_| 1.0, &mut k);
        // m/6 [2 1; 1 2] per spring; the held end's rows and columns dropped.
        let mut m = vec![0.0; pattern.nnz()];
        for (r, c, s) in pattern.entries() {
            m[s] = match (r == c, r) {
                (true, r) if r == n - 1 => 1.0 / 3.0,
                (true, _) => 2.0 / 3.0,
                (false, _) => 1.0 / 6.0,
            };
        }
        let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
        let modes = lowest_generalized_modes(&pattern, &k, &m, &mut chol, 6, 1e-10).unwrap();
        assert!(modes.converged);
        for (j, lambda) in modes.values.iter().enumerate() {
            let theta = (2 * j + 1) as f64 * std::f64::consts::PI / (2 * n) as f64;
            let exact = 6.0 * (1.0 - theta.cos()) / (2.0 + theta.cos());
            assert!(
                (lambda - exact).abs() <= 1e-8 * exact,
                "{j}: {lambda:e} against {exact:e}"
            );
        }
    }
}
