//! The lowest eigenpairs of the generalized problem `K φ = λ M φ` (natural modes, issue 45):
//! block Lanczos on the shift-inverted operator `(K − σM)⁻¹ M` with full M-orthogonalisation
//! and a Rayleigh–Ritz step on K (dense, on the Krylov basis only), over the sparse Cholesky
//! factor of `K − σM`. K may be singular (σ < 0) and M singular where members carry no mass.

use super::{dot, SparseCholesky, StiffnessPattern};
use nalgebra::{DMatrix, SymmetricEigen};

/// The lowest eigenpairs found, ascending.
#[derive(Debug, Clone)]
pub struct GeneralizedModes {
    /// Eigenvalues λ = ω² (the Rayleigh quotients of the Ritz vectors), ascending.
    pub values: Vec<f64>,
    /// The eigenvectors, M-orthonormal, one per value.
    pub vectors: Vec<Vec<f64>>,
    /// Every pair's residual `‖K φ − λ M φ‖` fell below the tolerance (or the basis spans
    /// the whole space).
    pub converged: bool,
}

/// Why no modes: `K − σM` would not factorize for any shift tried (K indefinite beyond the
/// largest shift, or M zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoShiftFactorizes;

/// Deterministic pseudo-random vector (xorshift), entries in [−0.5, 0.5).
fn random_vector(n: usize, seed: u64) -> Vec<f64> {
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

/// The Krylov basis, M-orthonormal, with M and K applied to each vector.
struct Basis {
    v: Vec<Vec<f64>>,
    mv: Vec<Vec<f64>>,
    kv: Vec<Vec<f64>>,
}

impl Basis {
    /// Adds the columns of `block` M-orthogonalised against the basis and each other (twice);
    /// returns how many were kept (a column whose M-norm falls below 1e-10 of its own is
    /// dependent, or massless, and dropped).
    fn extend(&mut self, pattern: &StiffnessPattern, k: &[f64], m: &[f64], block: Vec<Vec<f64>>) {
        let n = pattern.n;
        let mut mx = vec![0.0; n];
        for mut x in block {
            pattern.sym_matvec(m, &x, &mut mx);
            let before = dot(&x, &mx).max(0.0).sqrt();
            for _ in 0..2 {
                for (q, mq) in self.v.iter().zip(&self.mv) {
                    let r = dot(mq, &x);
                    x.iter_mut().zip(q).for_each(|(xi, qi)| *xi -= r * qi);
                }
            }
            pattern.sym_matvec(m, &x, &mut mx);
            let norm = dot(&x, &mx).max(0.0).sqrt();
            // A NaN norm is dropped too.
            let kept = norm > 1e-10 * before && before > 0.0;
            if !kept {
                continue;
            }
            x.iter_mut().for_each(|xi| *xi /= norm);
            mx.iter_mut().for_each(|xi| *xi /= norm);
            let mut kx = vec![0.0; n];
            pattern.sym_matvec(k, &x, &mut kx);
            self.v.push(x);
            self.mv.push(mx.clone());
            self.kv.push(kx);
        }
    }

    /// Rayleigh–Ritz on K: the `count` lowest Ritz values and vectors.
    fn ritz(&self, count: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
        let size = self.v.len();
        let h = DMatrix::from_fn(size, size, |i, j| {
            0.5 * (dot(&self.v[i], &self.kv[j]) + dot(&self.v[j], &self.kv[i]))
        });
        let eig = SymmetricEigen::new(h);
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let n = self.v.first().map_or(0, Vec::len);
        let vectors = order
            .iter()
            .take(count)
            .map(|&c| {
                let mut x = vec![0.0; n];
                for (r, q) in self.v.iter().enumerate() {
                    let y = eig.eigenvectors[(r, c)];
                    x.iter_mut().zip(q).for_each(|(xi, qi)| *xi += y * qi);
                }
                x
            })
            .collect();
        let values = order
            .iter()
            .take(count)
            .map(|&c| eig.eigenvalues[c])
            .collect();
        (values, vectors)
    }
}

/// The `count` lowest eigenpairs of `K φ = λ M φ`, K and M symmetric lower triangles on
/// `pattern` (K positive semidefinite, M positive semidefinite and positive on K's kernel).
/// `chol` must have been analysed on `pattern`; it is left holding `K − σM`. Converged when
/// every pair's residual `‖K φ − λ M φ‖ ≤ tolerance · (|λ| + |σ|) ‖M φ‖`.
pub fn lowest_generalized_modes(
    pattern: &StiffnessPattern,
    k: &[f64],
    m: &[f64],
    chol: &mut SparseCholesky,
    count: usize,
    tolerance: f64,
) -> Result<GeneralizedModes, NoShiftFactorizes> {
    let n = pattern.n;
    let count = count.min(n);
    let ratio = pattern.mean_diagonal(k).abs() / pattern.mean_diagonal(m).max(f64::MIN_POSITIVE);
    let sigma = factorize_shifted(pattern, k, m, chol, ratio)?;
    let block_size = (count + 4).max(2 * count).min(n);
    let mut basis = Basis {
        v: Vec::new(),
        mv: Vec::new(),
        kv: Vec::new(),
    };
    let apply = |x: &[f64]| {
        let mut y = vec![0.0; n];
        pattern.sym_matvec(m, x, &mut y);
        chol.solve_in_place(&mut y);
        y
    };
    let mut block: Vec<Vec<f64>> = (0..block_size)
        .map(|j| apply(&random_vector(n, j as u64 + 1)))
        .collect();
    let (mut kx, mut mx) = (vec![0.0; n], vec![0.0; n]);
    loop {
        let start = basis.v.len();
        basis.extend(pattern, k, m, block);
        let exhausted = basis.v.len() == start || basis.v.len() >= n;
        let (values, vectors) = basis.ritz(count);
        let converged = exhausted
            || values.iter().zip(&vectors).all(|(&lambda, x)| {
                pattern.sym_matvec(k, x, &mut kx);
                pattern.sym_matvec(m, x, &mut mx);
                let r: f64 = kx
                    .iter()
                    .zip(&mx)
                    .map(|(a, b)| (a - lambda * b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                r <= tolerance * (lambda.abs() + sigma.abs()) * dot(&mx, &mx).sqrt()
            });
        if converged || basis.v.len() >= 60 * block_size.max(4) {
            return Ok(GeneralizedModes {
                values,
                vectors,
                converged,
            });
        }
        block = basis.v[start..].iter().map(|x| apply(x)).collect();
    }
}

/// Factorizes `K − σM` with σ = −1e-4 · ratio (ratio the mean diagonal of K over M's), the
/// shift grown a hundredfold while it does not factorize; returns σ.
fn factorize_shifted(
    pattern: &StiffnessPattern,
    k: &[f64],
    m: &[f64],
    chol: &mut SparseCholesky,
    ratio: f64,
) -> Result<f64, NoShiftFactorizes> {
    let mut sigma = -1e-4 * ratio;
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
}
