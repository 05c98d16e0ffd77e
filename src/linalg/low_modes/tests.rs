//! Tests of `modes_below` against dense solves and closed forms.

use super::{modes_below, modes_below_by_subspace, modes_below_with_basis, LowModes};
use crate::linalg::{SparseCholesky, SparseRow, StiffnessPattern};
use faer::Par;
use nalgebra::{DMatrix, SymmetricEigen};

/// The rows of a free 2D lattice of `nx × ny` nodes, two dofs a node (x at `2k`, y at
/// `2k + 1`, node `k = i + nx j`): a bar along each row and column between neighbours, and
/// with `diagonals` one bar across each cell (triangulated: rigid, a kernel of the 3 rigid
/// motions). Without them every row's x and every column's y move freely: a kernel of
/// `nx + ny`.
fn lattice(nx: usize, ny: usize, diagonals: bool) -> Vec<SparseRow> {
    let node = |i: usize, j: usize| i + nx * j;
    let mut rows = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (2 * node(i, j), 2 * node(i, j) + 1);
            if i + 1 < nx {
                let x1 = 2 * node(i + 1, j);
                rows.push(SparseRow::new([(Some(x), -1.0), (Some(x1), 1.0)]));
            }
            if j + 1 < ny {
                let y1 = 2 * node(i, j + 1) + 1;
                rows.push(SparseRow::new([(Some(y), -1.0), (Some(y1), 1.0)]));
            }
            if diagonals && i + 1 < nx && j + 1 < ny {
                let far = 2 * node(i + 1, j + 1);
                let c = std::f64::consts::FRAC_1_SQRT_2;
                rows.push(SparseRow::new([
                    (Some(x), -c),
                    (Some(y), -c),
                    (Some(far), c),
                    (Some(far + 1), c),
                ]));
            }
        }
    }
    rows
}

/// Stiffness values `Σ w_i rowᵢᵀ rowᵢ`, the weights varying irregularly in 1 to 1.5.
fn stiffness(pattern: &StiffnessPattern, rows: &[SparseRow]) -> Vec<f64> {
    let mut a = vec![0.0; pattern.nnz()];
    pattern.assemble(
        rows,
        |i| 1.0 + 0.5 * ((i * 7919) % 13) as f64 / 13.0,
        &mut a,
    );
    a
}

/// Values on the pattern from `entry(row, column)`.
fn on_pattern(pattern: &StiffnessPattern, entry: impl Fn(usize, usize) -> f64) -> Vec<f64> {
    let mut values = vec![0.0; pattern.nnz()];
    for (r, c, s) in pattern.entries() {
        values[s] = entry(r, c);
    }
    values
}

/// A mass-like B on the pattern: diagonal 1 to 1.3, off-diagonal entries 0 to 0.02
/// (diagonally dominant for up to 35 neighbours: positive definite), irregular.
fn mass(pattern: &StiffnessPattern) -> Vec<f64> {
    on_pattern(pattern, |r, c| {
        if r == c {
            1.0 + 0.3 * ((r * 31) % 17) as f64 / 17.0
        } else {
            0.02 * (((r + c) * 13) % 7) as f64 / 7.0
        }
    })
}

fn dense(pattern: &StiffnessPattern, values: &[f64]) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(pattern.n, pattern.n);
    for (r, c, s) in pattern.entries() {
        m[(r, c)] = values[s];
        m[(c, r)] = values[s];
    }
    m
}

/// Every eigenvalue of `A v = λ B v`, ascending: `B = L Lᵀ`, those of `L⁻¹ A L⁻ᵀ`.
fn dense_eigenvalues(pattern: &StiffnessPattern, a: &[f64], b: &[f64]) -> Vec<f64> {
    let l = dense(pattern, b).cholesky().unwrap().l();
    let half = l.solve_lower_triangular(&dense(pattern, a)).unwrap();
    let c = l.solve_lower_triangular(&half.transpose()).unwrap();
    let c = (&c + c.transpose()) * 0.5;
    let mut values: Vec<f64> = SymmetricEigen::new(c).eigenvalues.iter().copied().collect();
    values.sort_by(f64::total_cmp);
    values
}

/// ρ: the mean diagonal of A over B's.
fn rho(pattern: &StiffnessPattern, a: &[f64], b: &[f64]) -> f64 {
    pattern.mean_diagonal(a) / pattern.mean_diagonal(b)
}

/// A threshold halfway between `exact[k − 1]` and `exact[k]`, for the first `k ≥ at_least`
/// where they lie 1e-3 apart (relative): `k` eigenvalues below it, none near it.
fn threshold_above(exact: &[f64], at_least: usize) -> (f64, usize) {
    let k = (at_least..exact.len())
        .find(|&k| exact[k] - exact[k - 1] > 1e-3 * exact[k])
        .unwrap();
    (0.5 * (exact[k - 1] + exact[k]), k)
}

/// `found` matches `exact` (as many) to 1e-8 relative, 1e-10 ρ absolute.
fn assert_values_match(found: &[f64], exact: &[f64], rho: f64) {
    assert_eq!(found.len(), exact.len());
    for (i, (f, e)) in found.iter().zip(exact).enumerate() {
        assert!(
            (f - e).abs() <= 1e-8 * e.abs() + 1e-10 * rho,
            "{i}: {f:e} against {e:e}"
        );
    }
}

/// The vectors are B-orthonormal to 1e-10, and each pair's residual
/// `‖A x − λ B x‖ ≤ 1e-6 (|λ| + 1e-3 ρ) ‖B x‖`.
fn assert_pairs_hold(pattern: &StiffnessPattern, a: &[f64], b: &[f64], modes: &LowModes) {
    let (n, count) = (pattern.n, modes.values.len());
    assert_eq!(modes.vectors.shape(), (n, count));
    let floor = 1e-3 * rho(pattern, a, b);
    let (mut ax, mut bx) = (DMatrix::zeros(n, count), DMatrix::zeros(n, count));
    for j in 0..count {
        let x: Vec<f64> = modes.vectors.column(j).iter().copied().collect();
        let (mut ay, mut by) = (vec![0.0; n], vec![0.0; n]);
        pattern.sym_matvec(a, &x, &mut ay);
        pattern.sym_matvec(b, &x, &mut by);
        ax.column_mut(j).copy_from_slice(&ay);
        bx.column_mut(j).copy_from_slice(&by);
        let lambda = modes.values[j];
        let residual = (ax.column(j) - bx.column(j) * lambda).norm();
        assert!(
            residual <= 1e-6 * (lambda.abs() + floor) * bx.column(j).norm(),
            "{j}: residual {residual:e} at {lambda:e}"
        );
    }
    let gram = modes.vectors.transpose() * &bx;
    let off = (gram - DMatrix::<f64>::identity(count, count)).amax();
    assert!(off <= 1e-10, "VᵀBV − I up to {off:e}");
    assert!(modes.values.windows(2).all(|w| w[0] <= w[1]));
}

/// On a triangulated 12 × 10 lattice (240 dofs, the 3 rigid motions its kernel, A
/// singular) with a mass-like B: as many eigenvalues below a threshold past the 40th as a
/// dense solve has, each to 1e-8, B-orthonormal vectors, small residuals, complete.
#[test]
fn every_mode_below_the_threshold_matches_a_dense_solve() {
    let rows = lattice(12, 10, true);
    let pattern = StiffnessPattern::new(240, &rows);
    let (a, b) = (stiffness(&pattern, &rows), mass(&pattern));
    let rho = rho(&pattern, &a, &b);
    let exact = dense_eigenvalues(&pattern, &a, &b);
    assert_eq!(exact.iter().filter(|&&l| l.abs() < 1e-9 * rho).count(), 3);
    let (threshold, count) = threshold_above(&exact, 40);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    let modes = modes_below(&pattern, &a, &b, &mut chol, threshold, 1000).unwrap();
    assert!(modes.complete);
    assert_values_match(&modes.values, &exact[..count], rho);
    assert_pairs_hold(&pattern, &a, &b, &modes);
}

/// Free chains of `lengths` dofs side by side, the rows of their springs.
fn chains(lengths: &[usize]) -> Vec<SparseRow> {
    let mut rows = Vec::new();
    let mut first = 0;
    for &length in lengths {
        for at in first..first + length - 1 {
            rows.push(SparseRow::new([(Some(at), -1.0), (Some(at + 1), 1.0)]));
        }
        first += length;
    }
    rows
}

/// 20 free chains of 15 to 25 dofs (404 in all), their springs and masses differing: the
/// pattern, A and B.
fn twenty_free_chains() -> (StiffnessPattern, Vec<f64>, Vec<f64>) {
    let lengths: Vec<usize> = (0..20).map(|p| 15 + (p * 7) % 11).collect();
    let rows = chains(&lengths);
    let pattern = StiffnessPattern::new(lengths.iter().sum(), &rows);
    let (a, b) = (stiffness(&pattern, &rows), mass(&pattern));
    (pattern, a, b)
}

/// 20 free chains of 15 to 25 dofs (404 in all), their springs and masses differing: a
/// kernel of 20 (each chain's translation), more than a block holds, the other eigenvalues
/// apart. All 20 zero eigenvalues come out, with a basis short of the whole space (not
/// exact by exhaustion), below a threshold just above the kernel and one past the 50th
/// eigenvalue, and every value matches a dense solve.
#[test]
fn a_kernel_of_twenty_comes_out_whole() {
    let (pattern, a, b) = twenty_free_chains();
    let n = pattern.n;
    let rho = rho(&pattern, &a, &b);
    let exact = dense_eigenvalues(&pattern, &a, &b);
    assert_eq!(exact.iter().filter(|&&l| l.abs() < 1e-9 * rho).count(), 20);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    // The kernel alone (it converges before round-off could bring out the copies the
    // first start block misses), then the kernel and 30 more.
    for at_least in [20, 50] {
        let (threshold, count) = threshold_above(&exact, at_least);
        let (modes, basis) =
            modes_below_with_basis(&pattern, &a, &b, &mut chol, threshold, 1000).unwrap();
        assert!(modes.complete);
        assert!(basis < n, "a basis of {basis} for {n} dofs");
        let zeros = modes.values.iter().filter(|&&l| l.abs() < 1e-9 * rho);
        assert_eq!(zeros.count(), 20);
        assert_values_match(&modes.values, &exact[..count], rho);
        assert_pairs_hold(&pattern, &a, &b, &modes);
    }
}

/// A diagonal pencil of 200 dofs: eigenvalue 0 on 20 of them, 1 on one, and apart from
/// 10 to 19 on the others. One Krylov sequence from 16 start vectors spans 16 of the
/// kernel, and the pair at 1 (the first above the threshold) converges before round-off
/// could bring out the other 4 kernel vectors: the run of 16 equal Ritz values takes a
/// fresh start block, which finds them.
#[test]
fn a_kernel_beyond_the_first_start_block_is_found() {
    let n = 200;
    let pattern = StiffnessPattern::from_lower_entries(n, &[]);
    let b = on_pattern(&pattern, |r, _| 1.0 + 0.5 * (r % 3) as f64);
    let lambda = |r: usize| match r {
        _ if r % 10 == 3 => 0.0,
        100 => 1.0,
        _ => 10.0 + 0.05 * r as f64,
    };
    let a = on_pattern(&pattern, |r, _| lambda(r) * (1.0 + 0.5 * (r % 3) as f64));
    let rho = rho(&pattern, &a, &b);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    let (modes, basis) = modes_below_with_basis(&pattern, &a, &b, &mut chol, 0.5, 1000).unwrap();
    assert!(modes.complete);
    assert!(basis < n, "a basis of {basis} for {n} dofs");
    assert_values_match(&modes.values, &[0.0; 20], rho);
    assert_pairs_hold(&pattern, &a, &b, &modes);
}

/// 20 identical free chains of 25 dofs (500): every eigenvalue 20 times, the kernel
/// too. The 60 below a threshold between the third and fourth distinct values all come
/// out, with a basis short of the whole space.
#[test]
fn twenty_identical_pieces_give_every_eigenvalue_twenty_times() {
    let length = 25;
    let rows = chains(&[length; 20]);
    let n = 20 * length;
    let pattern = StiffnessPattern::new(n, &rows);
    let mut a = vec![0.0; pattern.nnz()];
    pattern.assemble(
        &rows,
        |i| 1.0 + 0.3 * ((i % (length - 1)) % 3) as f64,
        &mut a,
    );
    let b = on_pattern(&pattern, |r, c| {
        if r == c {
            1.0 + 0.2 * ((r % length) % 4) as f64
        } else {
            0.1
        }
    });
    let rho = rho(&pattern, &a, &b);
    let exact = dense_eigenvalues(&pattern, &a, &b);
    let (threshold, count) = threshold_above(&exact, 41);
    assert_eq!(count, 60);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    let (modes, basis) =
        modes_below_with_basis(&pattern, &a, &b, &mut chol, threshold, 1000).unwrap();
    assert!(modes.complete);
    assert!(basis < n, "a basis of {basis} for {n} dofs");
    assert_values_match(&modes.values, &exact[..count], rho);
    assert_pairs_hold(&pattern, &a, &b, &modes);
}

/// With more pairs below the threshold than `max_modes`, the `max_modes` lowest, and
/// `complete` false; with exactly as many as allowed, complete.
#[test]
fn max_modes_caps_and_says_incomplete() {
    let rows = lattice(12, 10, true);
    let pattern = StiffnessPattern::new(240, &rows);
    let (a, b) = (stiffness(&pattern, &rows), mass(&pattern));
    let rho = rho(&pattern, &a, &b);
    let exact = dense_eigenvalues(&pattern, &a, &b);
    let (threshold, count) = threshold_above(&exact, 40);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    let (_, ten) = threshold_above(&exact, 10);
    let capped = modes_below(&pattern, &a, &b, &mut chol, threshold, ten).unwrap();
    assert!(!capped.complete);
    assert_values_match(&capped.values, &exact[..ten], rho);
    assert_pairs_hold(&pattern, &a, &b, &capped);
    let none = modes_below(&pattern, &a, &b, &mut chol, threshold, 0).unwrap();
    assert!(!none.complete && none.values.is_empty());
    assert_eq!(none.vectors.shape(), (240, 0));
    let all = modes_below(&pattern, &a, &b, &mut chol, threshold, count).unwrap();
    assert!(all.complete);
    assert_values_match(&all.values, &exact[..count], rho);
}

/// A free 60 × 50 grid Laplacian L (3 000 dofs, unit springs) under a diagonal B = D,
/// `A = D^{1/2} L D^{1/2}`: the pencil's eigenvalues are L's,
/// `4 sin²(iπ/120) + 4 sin²(jπ/100)`. The ones below a threshold past the 120th match them to
/// 1e-8, with a basis of at most 500 vectors.
#[test]
fn a_3000_dof_grid_matches_its_hand_formula() {
    let (nx, ny) = (60, 50);
    let n = nx * ny;
    let mut rows = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let k = i + nx * j;
            if i + 1 < nx {
                rows.push(SparseRow::new([(Some(k), -1.0), (Some(k + 1), 1.0)]));
            }
            if j + 1 < ny {
                rows.push(SparseRow::new([(Some(k), -1.0), (Some(k + nx), 1.0)]));
            }
        }
    }
    let pattern = StiffnessPattern::new(n, &rows);
    let d: Vec<f64> = (0..n)
        .map(|k| 1.0 + 0.5 * ((k * 37) % 11) as f64 / 11.0)
        .collect();
    let mut a = vec![0.0; pattern.nnz()];
    pattern.assemble(&rows, |_| 1.0, &mut a);
    for (r, c, s) in pattern.entries() {
        a[s] *= (d[r] * d[c]).sqrt();
    }
    let b = on_pattern(&pattern, |r, c| if r == c { d[r] } else { 0.0 });
    let rho = rho(&pattern, &a, &b);
    let chain = |m: usize, i: usize| {
        4.0 * (i as f64 * std::f64::consts::PI / (2 * m) as f64)
            .sin()
            .powi(2)
    };
    let mut exact: Vec<f64> = (0..nx)
        .flat_map(|i| (0..ny).map(move |j| (i, j)))
        .map(|(i, j)| chain(nx, i) + chain(ny, j))
        .collect();
    exact.sort_by(f64::total_cmp);
    let (threshold, count) = threshold_above(&exact, 120);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    let (modes, basis) =
        modes_below_with_basis(&pattern, &a, &b, &mut chol, threshold, 1000).unwrap();
    assert!(modes.complete);
    assert!(basis <= 500, "a basis of {basis}");
    assert_values_match(&modes.values, &exact[..count], rho);
    assert_pairs_hold(&pattern, &a, &b, &modes);
}

/// A stiffness that no shift makes positive definite, and a NaN, are errors.
#[test]
fn what_does_not_factorize_is_an_error() {
    let rows: Vec<SparseRow> = (0..9)
        .map(|i| SparseRow::new([(Some(i), -1.0), (Some(i + 1), 1.0)]))
        .collect();
    let pattern = StiffnessPattern::new(10, &rows);
    let b = on_pattern(&pattern, |r, c| if r == c { 1.0 } else { 0.0 });
    let negative = on_pattern(&pattern, |r, c| if r == c { -1e6 } else { 0.0 });
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    assert!(modes_below(&pattern, &negative, &b, &mut chol, 0.25, 10).is_err());
    let mut a = stiffness(&pattern, &rows);
    let fine = modes_below(&pattern, &a, &b, &mut chol, 0.25, 10).unwrap();
    assert!(fine.complete && !fine.values.is_empty());
    a[3] = f64::NAN;
    assert!(modes_below(&pattern, &a, &b, &mut chol, 0.25, 10).is_err());
    a[3] = 0.0;
    assert!(modes_below(&pattern, &a, &b, &mut chol, f64::NAN, 10).is_err());
}

/// The subspace iteration on the 20 free chains (a kernel of 20, 404 dofs), a block of 24
/// and a threshold past the 30th eigenvalue: the block doubles (all 24 lay below), the whole
/// kernel comes out, every value is an upper bound of its eigenvalue (Courant–Fischer), no
/// more come out than lie below, and the vectors are B-orthonormal. Warm-started from the
/// exact pairs, one sweep gives them back to 1e-8.
#[test]
fn the_subspace_iteration_holds_the_kernel_and_bounds_the_rest() {
    let (pattern, a, b) = twenty_free_chains();
    let n = pattern.n;
    let rho = rho(&pattern, &a, &b);
    let exact = dense_eigenvalues(&pattern, &a, &b);
    let (threshold, count) = threshold_above(&exact, 30);
    let mut chol = SparseCholesky::analyse(&pattern, Par::Seq);
    let pencil = (threshold, 1000);
    let modes = modes_below_by_subspace(&pattern, &a, &b, &mut chol, pencil, (24, 4), None);
    let modes = modes.unwrap();
    assert!(modes.values.len() > 24 && modes.values.len() <= count);
    let zeros = modes.values.iter().filter(|&&l| l.abs() < 1e-9 * rho);
    assert_eq!(zeros.count(), 20);
    for (k, (found, below)) in modes.values.iter().zip(&exact).enumerate() {
        assert!(
            *found >= below - 1e-10 * rho,
            "{k}: {found:e} below {below:e}"
        );
    }
    let (n_modes, v) = (modes.values.len(), &modes.vectors);
    let mut bv = DMatrix::zeros(n, n_modes);
    for j in 0..n_modes {
        let x: Vec<f64> = v.column(j).iter().copied().collect();
        let mut y = vec![0.0; n];
        pattern.sym_matvec(&b, &x, &mut y);
        bv.column_mut(j).copy_from_slice(&y);
    }
    let off = (v.transpose() * bv - DMatrix::<f64>::identity(n_modes, n_modes)).amax();
    assert!(off <= 1e-10, "VᵀBV − I up to {off:e}");
    let exact_modes = modes_below(&pattern, &a, &b, &mut chol, threshold, 1000).unwrap();
    let start = Some(&exact_modes.vectors);
    let warm = modes_below_by_subspace(&pattern, &a, &b, &mut chol, pencil, (64, 1), start);
    let warm = warm.unwrap();
    assert!(warm.complete);
    assert_values_match(&warm.values, &exact[..count], rho);
    assert_pairs_hold(&pattern, &a, &b, &warm);
}
