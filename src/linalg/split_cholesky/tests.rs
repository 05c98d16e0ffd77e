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
            _ => panic!("one level: the halves are whole Cholesky factors"),
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

/// A quasi-definite matrix `[A N; Nᵀ 0]`: A a 5-point stencil on a `(2a + 1) × (2b + 1)` grid
/// of + unknowns, N two − unknowns per 3 × 3 patch (a constant and a linear weight on its
/// nine nodes), split two levels deep by hand: the middle column, then each side's middle
/// row; each leaf's patches inside it, its kernels after its nodes. Returns the pattern and
/// values in the split's order (position k is unknown k) and the tree.
fn quasi_definite_grid(a: usize, b: usize) -> (StiffnessPattern, Vec<f64>, Vec<i8>, SplitTree) {
    let (w, h) = (2 * a + 1, 2 * b + 1);
    // The leaves (x range, y range), in the order of the split, and the separators after them.
    let leaf = |x: (usize, usize), y: (usize, usize)| (x, y);
    let leaves = [
        leaf((0, a), (0, b)),
        leaf((0, a), (b + 1, h)),
        leaf((a + 1, w), (0, b)),
        leaf((a + 1, w), (b + 1, h)),
    ];
    let mut position = vec![usize::MAX; w * h];
    let mut next = 0;
    let mut kernels: Vec<(usize, Vec<(usize, f64)>)> = Vec::new();
    let mut sizes = Vec::new();
    let mut place_row = |x: (usize, usize), y: usize, next: &mut usize| {
        for i in x.0..x.1 {
            position[i + w * y] = *next;
            *next += 1;
        }
    };
    for (k, &(x, y)) in leaves.iter().enumerate() {
        let start = next;
        for j in y.0..y.1 {
            place_row(x, j, &mut next);
        }
        // Patches of 3 × 3 inside the leaf: two kernel unknowns each.
        for py in (y.0..y.1 - 2).step_by(3) {
            for px in (x.0..x.1 - 2).step_by(3) {
                for weight in 0..2 {
                    let nodes = (0..9)
                        .map(|t| {
                            let (dx, dy) = (t % 3, t / 3);
                            let v = if weight == 0 {
                                1.0
                            } else {
                                dx as f64 - 1.0 + 0.5 * (dy as f64 - 1.0)
                            };
                            ((px + dx) + w * (py + dy), v)
                        })
                        .collect();
                    kernels.push((next, nodes));
                    next += 1;
                }
            }
        }
        sizes.push(next - start);
        // The side's separator row after its second leaf.
        if k % 2 == 1 {
            let start = next;
            place_row(x, b, &mut next);
            sizes.push(next - start);
        }
    }
    for j in 0..h {
        place_row((a, a + 1), j, &mut next);
    }
    let n = next;
    let mut entries = Vec::new();
    let mut value = Vec::new();
    let mut add = |r: usize, c: usize, v: f64| {
        entries.push((r.max(c), r.min(c)));
        value.push(v);
    };
    for j in 0..h {
        for i in 0..w {
            let p = position[i + w * j];
            add(p, p, 4.5 + 0.1 * ((i + 3 * j) % 4) as f64);
            if i + 1 < w {
                add(p, position[i + 1 + w * j], -1.0);
            }
            if j + 1 < h {
                add(p, position[i + w * (j + 1)], -1.0);
            }
        }
    }
    let mut signs = vec![1i8; n];
    for (k, nodes) in &kernels {
        signs[*k] = -1;
        add(*k, *k, 0.0);
        for &(node, v) in nodes {
            add(*k, position[node], v);
        }
    }
    let p = StiffnessPattern::from_lower_entries(n, &entries);
    let mut values = vec![0.0; p.nnz()];
    for (&(r, c), v) in entries.iter().zip(&value) {
        values[p.slot(r, c).expect("entry")] += v;
    }
    let side = |first: usize, second: usize, separator: usize| -> usize {
        sizes[first] + sizes[second] + sizes[separator]
    };
    let tree = SplitTree {
        parts: [side(0, 1, 2), side(3, 4, 5)],
        children: [
            Some(Box::new(SplitTree {
                parts: [sizes[0], sizes[1]],
                children: [None, None],
            })),
            Some(Box::new(SplitTree {
                parts: [sizes[3], sizes[4]],
                children: [None, None],
            })),
        ],
    };
    (p, values, signs, tree)
}

/// A quasi-definite matrix split one and two levels deep with `L̂ J L̂ᵀ` leaves (simplicial
/// leaves on the small grid, supernodal on the larger) solves to round-off (its residual, an
/// independent check), on one thread as on two; a separator holding a − unknown is refused.
#[test]
fn a_quasi_definite_matrix_splits_with_signed_leaves() {
    for (a, b, supernodal) in [(4, 4, false), (30, 30, true)] {
        let (p, values, signs, tree) = quasi_definite_grid(a, b);
        let n = p.n;
        let identity: Vec<usize> = (0..n).collect();
        let b_rhs: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        for levels in [1, 2] {
            let mut split = SplitCholesky::new(&p, &identity, &tree, levels, Some((&signs, 1e-12)))
                .expect("separators of + unknowns");
            assert_eq!(split.levels(), levels);
            split.factorize(&values).expect("quasi-definite");
            let leaves = |split: &SplitCholesky| -> Vec<bool> {
                fn walk(split: &SplitCholesky, out: &mut Vec<bool>) {
                    for half in &split.halves {
                        match &half.factor {
                            HalfFactor::Signed { ldlt, .. } => out.push(matches!(
                                ldlt.analysis.symbolic.raw(),
                                SymbolicCholeskyRaw::Supernodal(_)
                            )),
                            HalfFactor::Split { split, .. } => walk(split, out),
                            HalfFactor::Whole(_) => panic!("a Cholesky leaf in a signed split"),
                        }
                    }
                }
                let mut out = Vec::new();
                walk(split, &mut out);
                out
            };
            let kinds = leaves(&split);
            assert_eq!(kinds.len(), 1 << levels);
            assert!(kinds.iter().all(|&k| k == supernodal), "{kinds:?}");
            let mut x = b_rhs.clone();
            split.solve_block_in_place(
                (&identity, &identity),
                MatMut::from_column_major_slice_mut(&mut x, n, 1),
            );
            let residual = relative_residual(&p, &values, &x, &b_rhs);
            assert!(residual < 1e-12, "{a} x {b}, {levels} levels: {residual:e}");
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .expect("pool");
            let mut alone = b_rhs.clone();
            one.install(|| {
                let mut again = split.clone();
                again.factorize(&values).expect("quasi-definite");
                again.solve_block_in_place(
                    (&identity, &identity),
                    MatMut::from_column_major_slice_mut(&mut alone, n, 1),
                );
            });
            assert_eq!(alone, x);
        }
        // The last unknown (in the top separator) taken as a − pivot: no split.
        let mut wrong = signs.clone();
        wrong[n - 1] = -1;
        assert!(SplitCholesky::new(&p, &identity, &tree, 2, Some((&wrong, 1e-12))).is_none());
    }
}
