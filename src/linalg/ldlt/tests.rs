use super::*;
use crate::linalg::StiffnessPattern;

/// A symmetric indefinite tridiagonal matrix (diagonal `d`, off-diagonal 1) on a path
/// pattern: solved to round-off, its negative eigenvalues counted.
#[test]
fn an_indefinite_matrix_is_solved_and_its_inertia_counted() {
    let n = 40;
    let entries: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| std::iter::once((i, i)).chain((i + 1 < n).then_some((i + 1, i))))
        .collect();
    let pattern = StiffnessPattern::from_lower_entries(n, &entries);
    // d_i = −2.5 for the first ten, 3 after: eigenvalues of the tridiagonal matrix.
    let diagonal = |i: usize| if i < 10 { -2.5 } else { 3.0 };
    let mut values = vec![0.0; pattern.nnz()];
    for (row, c, slot) in pattern.entries() {
        values[slot] = if row == c { diagonal(c) } else { 1.0 };
    }
    let cholesky = SparseCholesky::analyse(&pattern, Par::Seq);
    let mut ldlt = SparseLdlt::sharing(&cholesky);
    ldlt.factorize(&values).unwrap();
    // A x for a known x, then solved back.
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
    let mut b = vec![0.0; n];
    for i in 0..n {
        b[i] = diagonal(i) * x[i];
        if i > 0 {
            b[i] += x[i - 1];
        }
        if i + 1 < n {
            b[i] += x[i + 1];
        }
    }
    ldlt.solve_in_place(&mut b);
    let error = b
        .iter()
        .zip(&x)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(error < 1e-12, "{error}");
    // The dense eigenvalues of the same matrix, counted below zero.
    let dense = nalgebra::DMatrix::from_fn(n, n, |i, j| match i.abs_diff(j) {
        0 => diagonal(i),
        1 => 1.0,
        _ => 0.0,
    });
    let negative = dense
        .symmetric_eigenvalues()
        .iter()
        .filter(|&&v| v < 0.0)
        .count();
    assert_eq!(negative, 10);
    assert_eq!(ldlt.negative_pivots(), negative);
}

/// The 3-D 7-point Laplacian on 14³ points shifted by σ (large enough for faer's
/// supernodal factor): its negative eigenvalues, `Σ_d (2 − 2 cos(k_d π / 15)) < σ`,
/// counted in closed form.
#[test]
fn a_supernodal_factor_counts_the_negative_eigenvalues_of_a_shifted_laplacian() {
    let m = 14;
    let n = m * m * m;
    let index = |i: usize, j: usize, k: usize| (i * m + j) * m + k;
    let mut entries = Vec::new();
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                let p = index(i, j, k);
                entries.push((p, p));
                for q in [
                    (i + 1 < m).then(|| index(i + 1, j, k)),
                    (j + 1 < m).then(|| index(i, j + 1, k)),
                    (k + 1 < m).then(|| index(i, j, k + 1)),
                ]
                .into_iter()
                .flatten()
                {
                    entries.push((q, p));
                }
            }
        }
    }
    let pattern = StiffnessPattern::from_lower_entries(n, &entries);
    let shift = 0.9;
    let mut values = vec![0.0; pattern.nnz()];
    for (row, c, slot) in pattern.entries() {
        values[slot] = if row == c { 6.0 - shift } else { -1.0 };
    }
    let cholesky = SparseCholesky::analyse(&pattern, Par::Seq);
    let mut ldlt = SparseLdlt::sharing(&cholesky);
    assert!(matches!(
        ldlt.analysis.symbolic.raw(),
        SymbolicCholeskyRaw::Supernodal(_)
    ));
    ldlt.factorize(&values).unwrap();
    let one = |k: usize| 2.0 - 2.0 * (k as f64 * std::f64::consts::PI / (m + 1) as f64).cos();
    let mut negative = 0;
    for a in 1..=m {
        for b in 1..=m {
            for c in 1..=m {
                negative += usize::from(one(a) + one(b) + one(c) < shift);
            }
        }
    }
    assert!(negative > 5, "{negative}");
    assert_eq!(ldlt.negative_pivots(), negative);
    // A x for a known x, solved back.
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
    let mut b = vec![0.0; n];
    pattern.sym_matvec(&values, &x, &mut b);
    ldlt.solve_in_place(&mut b);
    let error = b
        .iter()
        .zip(&x)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(error < 1e-9, "{error}");
}
