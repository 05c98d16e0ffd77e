//! The partition report, and the kernels of K*_E checked against a first-principles computation.

use super::*;
use crate::model::Model;

/// Dimension of the null space of K*_E computed from first principles (docs/method.md §4): K*_E u = 0
/// exactly when some U on E's free dofs has `B_E U = 0` and `C_E U = R_E u`, so
/// `ker K*_E = { R_Eᵀ C_E ρ : B_E ρ = 0, (I − R Rᵀ) C_E ρ = 0 on every interface }`.
/// Uses only the structure, the partition and the interfaces' macro bases.
/// Returns (dimension, the gap: smallest non-null / largest eigenvalue of the constraint
/// Gram matrix, and largest null one / largest).
pub(super) fn independent_kernel_dimension(
    s: &Structure,
    subdomains: [usize; 2],
    weak: WeakInterfaces,
) -> Vec<(usize, f64, f64)> {
    let partition = Partition::new(s, subdomains, weak);
    let bases: Vec<DMatrix<f64>> = partition
        .interfaces
        .iter()
        .map(|i| {
            let positions: Vec<[f64; 3]> = i.nodes.iter().map(|&n| s.nodes[n]).collect();
            macro_basis(&positions, weak)
        })
        .collect();
    partition
        .substructures
        .iter()
        .enumerate()
        .map(|(e, topo)| {
            let mut local = vec![usize::MAX; s.n_nodes()];
            for (k, &n) in topo.nodes.iter().enumerate() {
                local[n] = k;
            }
            let n = 3 * topo.nodes.len();
            let mut rows: Vec<Vec<f64>> = Vec::new();
            // B_E: e_i = n·(U_b − U_a), clamped ends dropped.
            for &i in &topo.links {
                let link = &s.links[i];
                let mut row = vec![0.0; n];
                for (node, sign) in [(link.a, -1.0), (link.b, 1.0)] {
                    if !s.clamped[node] {
                        for c in 0..3 {
                            row[3 * local[node] + c] += sign * link.direction[c];
                        }
                    }
                }
                rows.push(row);
            }
            // (I − R Rᵀ) C_E on every interface of E; keep R to map the null space.
            let mut sides = Vec::new();
            for (iface, r) in partition.interfaces.iter().zip(&bases) {
                if !iface.sides.contains(&e) {
                    continue;
                }
                let m = 3 * iface.nodes.len();
                let micro = DMatrix::<f64>::identity(m, m) - r * r.transpose();
                for a in 0..m {
                    let mut row = vec![0.0; n];
                    for b in 0..m {
                        row[3 * local[iface.nodes[b / 3]] + b % 3] += micro[(a, b)];
                    }
                    rows.push(row);
                }
                sides.push((iface.nodes.clone(), r.clone()));
            }
            let a = DMatrix::from_fn(rows.len(), n, |i, j| rows[i][j]);
            let eig = (a.transpose() * &a).symmetric_eigen();
            let top = eig.eigenvalues.max();
            let null: Vec<usize> = (0..n)
                .filter(|&k| eig.eigenvalues[k] <= 1e-11 * top)
                .collect();
            let smallest_kept = (0..n)
                .filter(|k| !null.contains(k))
                .map(|k| eig.eigenvalues[k])
                .fold(f64::INFINITY, f64::min);
            let largest_null = null.iter().map(|&k| eig.eigenvalues[k]).fold(0.0, f64::max);
            // R_Eᵀ C_E ρ for each null vector ρ, then its rank.
            let macro_rows: usize = sides.iter().map(|(_, r)| r.ncols()).sum();
            let mut image = DMatrix::<f64>::zeros(macro_rows.max(1), null.len());
            for (col, &k) in null.iter().enumerate() {
                let rho = eig.eigenvectors.column(k);
                let mut offset = 0;
                for (nodes, r) in &sides {
                    let trace = nalgebra::DVector::from_fn(3 * nodes.len(), |b, _| {
                        rho[3 * local[nodes[b / 3]] + b % 3]
                    });
                    let u = r.transpose() * trace;
                    image.view_mut((offset, col), (r.ncols(), 1)).copy_from(&u);
                    offset += r.ncols();
                }
            }
            let rank = if null.is_empty() {
                0
            } else {
                image
                    .singular_values()
                    .iter()
                    .filter(|&&sv| sv > 1e-8)
                    .count()
            };
            (rank, smallest_kept / top, largest_null / top)
        })
        .collect()
}

/// For every substructure: eigenvalues of K*_E below 1e-6·d_m, kernel.ncols(), and K*_E Q ≈ 0.
pub(super) fn check_kernels(latin: &Latin<'_>, what: &str) -> (usize, f64, f64) {
    let mut total = 0;
    let mut gap = f64::INFINITY;
    let mut worst_null: f64 = 0.0;
    for (e, sub) in latin.operators.substructures.iter().enumerate() {
        let ev = sub.ops().k_star.clone().symmetric_eigenvalues();
        let null = ev.iter().filter(|&&x| x < 1e-6 * DM).count();
        assert_eq!(
            null,
            sub.kernel.ncols(),
            "{what}: substructure {e}: K*_E has {null} eigenvalues below 1e-6 dm, kernel has {} \
             columns (eigenvalues / dm: {:?})",
            sub.kernel.ncols(),
            {
                let mut v: Vec<f64> = ev.iter().map(|x| x / DM).collect();
                v.sort_by(f64::total_cmp);
                v.truncate(8);
                v
            }
        );
        for &x in ev.iter() {
            if x >= 1e-6 * DM {
                gap = gap.min(x / DM);
            } else {
                worst_null = worst_null.max(x.abs() / DM);
            }
        }
        if sub.kernel.ncols() > 0 {
            // The columns span the null space: orthonormal and annihilated by K*_E.
            let q = &sub.kernel;
            let qtq = q.transpose() * q;
            let id = DMatrix::<f64>::identity(q.ncols(), q.ncols());
            assert!(
                (qtq - id).norm() < 1e-10,
                "{what}: substructure {e}: Q not orthonormal"
            );
            let kq = (&sub.ops().k_star * q).norm() / DM;
            assert!(
                kq < 1e-8,
                "{what}: substructure {e}: |K*_E Q| / dm = {kq:e}"
            );
        }
        total += sub.kernel.ncols();
    }
    (total, gap, worst_null)
}

#[test]
fn partition_report_and_kernels_of_paper_case() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let mut kernel_columns = Vec::new();
    for (weak, interfaces, strong, weak_count, dropped, macro_dofs) in [
        (WeakInterfaces::Macro, 42, 24, 18, 0, 270),
        (WeakInterfaces::Micro, 42, 24, 18, 0, 216),
        (WeakInterfaces::Drop, 24, 24, 0, 18, 216),
    ] {
        let latin = Latin::new(&model, settings([4, 4], weak)).unwrap();
        let r = latin.report();
        println!("{weak:?}: {r:?}");
        assert_eq!(r.substructures, 16, "{weak:?}");
        assert_eq!(r.interfaces, interfaces, "{weak:?}");
        assert_eq!(r.strong_interfaces, strong, "{weak:?}");
        assert_eq!(r.weak_interfaces, weak_count, "{weak:?}");
        assert_eq!(r.dropped_interfaces, dropped, "{weak:?}");
        assert_eq!(r.macro_dofs, macro_dofs, "{weak:?}");
        assert_eq!(latin.interfaces.list.len(), interfaces);
        // docs/method.md §2/§4: 195 free dofs for the substructures without supports.
        assert_eq!(r.max_substructure_dofs, 195, "{weak:?}");
        let (total, gap, worst_null) = check_kernels(&latin, &format!("{weak:?}"));
        assert_eq!(total, r.kernel_columns, "{weak:?}");
        // The same dimensions from B_E and the bases alone.
        let independent = independent_kernel_dimension(s, [4, 4], weak);
        for (e, (sub, (dim, kept, null))) in latin
            .operators
            .substructures
            .iter()
            .zip(&independent)
            .enumerate()
        {
            assert_eq!(
                sub.kernel.ncols(),
                *dim,
                "{weak:?}: substructure {e}: kernel has {} columns, ker K*_E from B_E has \
                 dimension {dim} (Gram gap {kept:e} / {null:e})",
                sub.kernel.ncols()
            );
        }
        println!(
            "{weak:?}: kernel columns {total} (per substructure {:?}); K*_E eigenvalues: \
             smallest kept {gap:.3e} dm, largest null {worst_null:.1e} dm",
            latin
                .operators
                .substructures
                .iter()
                .map(|s| s.kernel.ncols())
                .collect::<Vec<_>>()
        );
        kernel_columns.push(total);
    }
    // Macro and drop: 6 rigid motions for each of the 8 substructures away from the clamped
    // edges, 1 (the rotation about the clamped line) for the 8 others. Micro: only the 4
    // unsupported edge substructures keep a rotation that leaves both their crosspoints fixed.
    assert_eq!(
        kernel_columns,
        [56, 4, 56],
        "kernel columns (macro, micro, drop)"
    );
}
