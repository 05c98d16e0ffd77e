//! Tests of `src/linalg/split_cholesky.rs`.

use super::super::cholesky::tests::{grid_stiffness, relative_residual};
use super::super::SparseCholesky;
use super::*;

/// The two halves and the separator solve as the whole factor does, on both of faer's
/// factor kinds for the halves (simplicial on the small grid, supernodal on the larger),
/// on one thread or two alike, and refuse a matrix that is not positive definite.
#[test]
fn two_halves_solve_as_the_whole_factor() {
    for (w, h) in [(6, 5), (40, 40)] {
        let (p, values, xy) = grid_stiffness(w, h);
        let mut whole =
            SparseCholesky::analyse_ordered(&p, Par::Seq, NodeOrdering::NestedDissection(&xy));
        whole.factorize(&p, &values).expect("regular stiffness");
        let mut split = whole
            .share_symbolic_split(&p, 1)
            .expect("a top-level split");
        assert_eq!(split.split_levels(), 1);
        assert!(split.is_split() && !whole.is_split());
        split.factorize(&p, &values).expect("regular stiffness");
        let halves = &split.split.as_ref().expect("split").halves;
        let supernodal = halves.iter().map(|h| match &h.factor {
            HalfFactor::Whole(f) => {
                matches!(
                    f.analysis.symbolic.raw(),
                    SymbolicCholeskyRaw::Supernodal(_)
                )
            }
            HalfFactor::Split { .. } => panic!("one level: the halves are whole"),
        });
        assert!(supernodal.into_iter().all(|s| s == (w > 10)));
        let b: Vec<f64> = (0..p.n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let (mut x_whole, mut x) = (b.clone(), b.clone());
        whole.solve_in_place(&mut x_whole);
        split.solve_in_place(&mut x);
        let largest = x_whole.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in x.iter().zip(&x_whole) {
            assert!(
                (a - b).abs() <= 1e-10 * largest,
                "{w} x {h}: {a} against {b}"
            );
        }
        assert!(relative_residual(&p, &values, &x, &b) < 1e-10);
        // Forward then backward is the solve; a block is its columns.
        let mut halves = b.clone();
        split.forward_block_in_place(MatMut::from_column_major_slice_mut(&mut halves, p.n, 1));
        split.backward_in_place(&mut halves);
        assert_eq!(halves, x);
        let mut block = Mat::from_fn(p.n, 2, |i, j| b[(i + 3 * j) % p.n]);
        split.solve_block_in_place(block.as_mut());
        let mut second: Vec<f64> = (0..p.n).map(|i| b[(i + 3) % p.n]).collect();
        split.solve_in_place(&mut second);
        for i in 0..p.n {
            assert!((block[(i, 0)] - x[i]).abs() <= 1e-12 * largest);
            assert!((block[(i, 1)] - second[i]).abs() <= 1e-12 * largest);
        }
        // On one thread, the same numbers.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        let mut alone = b.clone();
        one.install(|| {
            let mut again = split.clone();
            again.factorize(&p, &values).expect("regular stiffness");
            again.solve_in_place(&mut alone);
        });
        assert_eq!(alone, x);
        // Not positive definite: refused.
        let negated: Vec<f64> = values.iter().map(|v| -v).collect();
        assert!(split.factorize(&p, &negated).is_err());
    }
}

/// The solve of `factor` on `b` against the whole factor's `expected`, to 1e-10 of its
/// largest entry.
fn assert_solves_as(factor: &SparseCholesky, b: &[f64], expected: &[f64], what: &str) {
    let mut x = b.to_vec();
    factor.solve_in_place(&mut x);
    let largest = expected.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, e) in x.iter().zip(expected) {
        assert!((a - e).abs() <= 1e-10 * largest, "{what}: {a} against {e}");
    }
}

/// Split down 2, 3 and 4 levels of the tree (4, 8, 16 subtrees side by side, each level's
/// separator dense), the factor solves as the whole one does, on one thread or many alike,
/// and still refuses a matrix that is not positive definite.
#[test]
fn subtrees_side_by_side_solve_as_the_whole_factor() {
    let (p, values, xy) = grid_stiffness(40, 40);
    let mut whole =
        SparseCholesky::analyse_ordered(&p, Par::Seq, NodeOrdering::NestedDissection(&xy));
    whole.factorize(&p, &values).expect("regular stiffness");
    let b: Vec<f64> = (0..p.n).map(|i| ((i * 29) % 13) as f64 - 6.0).collect();
    let mut expected = b.clone();
    whole.solve_in_place(&mut expected);
    for levels in [2, 3, 4] {
        let mut split = whole.share_symbolic_split(&p, levels).expect("a split");
        assert_eq!(split.split_levels(), levels);
        split.factorize(&p, &values).expect("regular stiffness");
        assert_solves_as(&split, &b, &expected, &format!("{levels} levels"));
        let mut block = Mat::from_fn(p.n, 3, |i, _| b[i]);
        split.solve_block_in_place(block.as_mut());
        let mut x = b.clone();
        split.solve_in_place(&mut x);
        let largest = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for j in 0..3 {
            assert!((0..p.n).all(|i| (block[(i, j)] - x[i]).abs() <= 1e-12 * largest));
        }
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        let mut alone = b.clone();
        one.install(|| split.solve_in_place(&mut alone));
        assert_eq!(alone, x);
        let negated: Vec<f64> = values.iter().map(|v| -v).collect();
        assert!(split.factorize(&p, &negated).is_err());
    }
    assert_eq!(SparseCholesky::split_levels_for(1), 1);
    assert_eq!(SparseCholesky::split_levels_for(2), 1);
    assert_eq!(SparseCholesky::split_levels_for(3), 2);
    assert_eq!(SparseCholesky::split_levels_for(16), 4);
}

/// A matrix of dense blocks of uneven sizes (a coarse matrix: one block per subdomain of a
/// 7 × 6 partition, 1 to 5 unknowns each, coupled to the 8 neighbours): ordered by nested
/// dissection of the block graph, its split solves as the whole factor, and the split's
/// halves hold whole blocks (no block is cut by a part's boundary).
#[test]
fn a_pattern_of_blocks_splits_by_its_block_graph() {
    let (w, h) = (7usize, 6usize);
    let size = |k: usize| 1 + (k * 7) % 5;
    let mut offsets = vec![0usize];
    let mut centres = Vec::new();
    for k in 0..w * h {
        offsets.push(offsets[k] + size(k));
        centres.push([(k % w) as f64, (k / w) as f64, 0.0]);
    }
    let n = offsets[w * h];
    let adjacent = |a: usize, b: usize| {
        let (ax, ay, bx, by) = (a % w, a / w, b % w, b / w);
        ax.abs_diff(bx) <= 1 && ay.abs_diff(by) <= 1
    };
    let mut entries = Vec::new();
    let mut value = Vec::new();
    for a in 0..w * h {
        for b in 0..=a {
            if !adjacent(a, b) {
                continue;
            }
            for r in offsets[a]..offsets[a + 1] {
                for c in offsets[b]..offsets[b + 1] {
                    if r >= c {
                        entries.push((r, c));
                        // Diagonally dominant: 40 on the diagonal, small couplings.
                        value.push(if r == c {
                            40.0
                        } else {
                            -0.3 - 0.01 * ((r + c) % 7) as f64
                        });
                    }
                }
            }
        }
    }
    let p = StiffnessPattern::from_lower_entries(n, &entries);
    let mut values = vec![0.0; p.nnz()];
    for (&(r, c), v) in entries.iter().zip(&value) {
        values[p.slot(r, c).expect("entry")] += v;
    }
    let blocks = NodeOrdering::Blocks {
        offsets: &offsets,
        centres: &centres,
    };
    let mut whole = SparseCholesky::analyse_ordered(&p, Par::Seq, blocks);
    whole.factorize(&p, &values).expect("diagonally dominant");
    let b: Vec<f64> = (0..n).map(|i| ((i * 17) % 9) as f64 - 4.0).collect();
    let mut expected = b.clone();
    whole.solve_in_place(&mut expected);
    assert!(relative_residual(&p, &values, &expected, &b) < 1e-12);
    // Each part of the top split is a union of whole blocks, in the factor's order.
    let (order, _) = whole.split_order();
    let tree = whole.analysis.top_split.as_ref().expect("a split");
    let block_of = |d: usize| offsets.partition_point(|&o| o <= d) - 1;
    for boundary in [tree.parts[0], tree.parts[0] + tree.parts[1]] {
        assert_ne!(block_of(order[boundary - 1]), block_of(order[boundary]));
    }
    for levels in [1, 2] {
        let mut split = whole.share_symbolic_split(&p, levels).expect("a split");
        assert_eq!(split.split_levels(), levels);
        split.factorize(&p, &values).expect("diagonally dominant");
        assert_solves_as(&split, &b, &expected, &format!("blocks, {levels} levels"));
    }
}
