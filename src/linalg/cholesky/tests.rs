//! Tests of `src/linalg/cholesky.rs`.

use super::*;
use crate::linalg::SparseRow;
use faer::Mat;

/// Bars between the nodes of a `w × h` grid (neighbours and diagonals), three dofs per
/// node, with stiffnesses that vary from bar to bar, and a soft spring on every dof so that
/// the stiffness is regular.
pub(in crate::linalg) fn grid_stiffness(
    w: usize,
    h: usize,
) -> (StiffnessPattern, Vec<f64>, Vec<[f64; 3]>) {
    let node = |i: usize, j: usize| i + w * j;
    let mut rows = Vec::new();
    let mut add = |a: usize, b: usize, d: [f64; 3]| {
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let n = [d[0] / l, d[1] / l, d[2] / l];
        rows.push(SparseRow::new((0..3).flat_map(|k| {
            [(Some(3 * a + k), -n[k]), (Some(3 * b + k), n[k])]
        })));
    };
    for j in 0..h {
        for i in 0..w {
            let lift = 0.1 * ((i * 7 + j * 3) % 5) as f64;
            if i + 1 < w {
                add(node(i, j), node(i + 1, j), [1.0, 0.0, lift]);
            }
            if j + 1 < h {
                add(node(i, j), node(i, j + 1), [0.0, 1.0, -lift]);
            }
            if i + 1 < w && j + 1 < h {
                add(node(i, j), node(i + 1, j + 1), [1.0, 1.0, 0.5 + lift]);
                add(node(i + 1, j), node(i, j + 1), [-1.0, 1.0, 0.3 - lift]);
            }
        }
    }
    for d in 0..3 * w * h {
        rows.push(SparseRow::new([(Some(d), 0.1)]));
    }
    let pattern = StiffnessPattern::new(3 * w * h, &rows);
    let mut values = vec![0.0; pattern.nnz()];
    pattern.assemble(&rows, |i| 1.0 + (i % 7) as f64, &mut values);
    let xy = (0..w * h)
        .map(|v| [(v % w) as f64, (v / w) as f64, 0.0])
        .collect();
    (pattern, values, xy)
}

pub(in crate::linalg) fn relative_residual(
    p: &StiffnessPattern,
    values: &[f64],
    x: &[f64],
    b: &[f64],
) -> f64 {
    let mut ax = vec![0.0; p.n];
    p.sym_matvec(values, x, &mut ax);
    let r: f64 = ax.iter().zip(b).map(|(a, b)| (a - b) * (a - b)).sum();
    r.sqrt() / b.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// faer gets `P A Pᵀ` already permuted: the solves must be those of A itself, for both of
/// faer's factor kinds (simplicial on the small grid, supernodal on the large one) and
/// both orderings, one right-hand side or a block.
#[test]
fn solves_are_those_of_the_unpermuted_matrix() {
    let mut supernodal = Vec::new();
    for (w, h) in [(3, 2), (40, 40)] {
        let (p, values, xy) = grid_stiffness(w, h);
        for ordering in [NodeOrdering::Amd, NodeOrdering::NestedDissection(&xy)] {
            let mut chol = SparseCholesky::analyse_ordered(&p, Par::Seq, ordering);
            supernodal.push(matches!(
                chol.analysis.symbolic.raw(),
                SymbolicCholeskyRaw::Supernodal(_)
            ));
            chol.factorize(&p, &values).expect("regular stiffness");
            let b: Vec<f64> = (0..p.n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
            let mut x = b.clone();
            chol.solve_in_place(&mut x);
            let r = relative_residual(&p, &values, &x, &b);
            assert!(r < 1e-10, "{w} x {h} {ordering:?}: residual {r:e}");
            // A block of three right-hand sides: column by column the same answers.
            let mut block = Mat::from_fn(p.n, 3, |i, j| b[(i + 5 * j) % p.n]);
            chol.solve_block_in_place(block.as_mut());
            for j in 0..3 {
                let bj: Vec<f64> = (0..p.n).map(|i| b[(i + 5 * j) % p.n]).collect();
                let mut xj = bj.clone();
                chol.solve_in_place(&mut xj);
                for i in 0..p.n {
                    assert!((block[(i, j)] - xj[i]).abs() <= 1e-12 * xj[i].abs().max(1.0));
                }
            }
            // Its two halves, forward then backward, make the same solve.
            let mut halves = b.clone();
            chol.forward_block_in_place(MatMut::from_column_major_slice_mut(&mut halves, p.n, 1));
            chol.backward_in_place(&mut halves);
            for (h, x) in halves.iter().zip(&x) {
                assert!((h - x).abs() <= 1e-12 * x.abs().max(1.0));
            }
            // A second workspace on the same analysis factors another matrix.
            let mut other = chol.share_symbolic();
            let doubled: Vec<f64> = values.iter().map(|v| 2.0 * v).collect();
            other.factorize(&p, &doubled).expect("regular stiffness");
            let mut half = b.clone();
            other.solve_in_place(&mut half);
            for (h, x) in half.iter().zip(&x) {
                assert!((2.0 * h - x).abs() <= 1e-9 * x.abs().max(1.0));
            }
        }
    }
    // Both of faer's factor kinds were exercised.
    assert_eq!(supernodal, [false, false, true, true]);
}

#[test]
fn an_indefinite_matrix_is_refused() {
    let (p, mut values, _) = grid_stiffness(4, 3);
    for &d in &p.diag_slot[..6] {
        values[d] = -1.0;
    }
    let mut chol = SparseCholesky::analyse(&p, Par::Seq);
    assert!(chol.factorize(&p, &values).is_err());
}
