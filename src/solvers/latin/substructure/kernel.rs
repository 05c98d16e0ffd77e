//! Steps 6–7 of a substructure's set-up: the kernel Q_E of K*_E (the rigid motions with no
//! micro trace, completed by its numerical null space), `K⁺_E` and `L_E`.

use super::*;

/// `K⁺_E = (K*_E + Q Qᵀ)⁻¹ − Q Qᵀ` and `L_E = K⁺_E − I/d_m`, Q the kernel of K*_E.
pub(super) fn invert(
    k_star: &DMatrix<f64>,
    kernel: &DMatrix<f64>,
    dm: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), SingularSubstructure> {
    let qqt = kernel * kernel.transpose();
    let k_plus = match (k_star + &qqt).cholesky() {
        Some(c) => c.inverse() - &qqt,
        None => return Err(SingularSubstructure),
    };
    let n_macro = k_star.nrows();
    let flexibility = &k_plus - DMatrix::<f64>::identity(n_macro, n_macro) / dm;
    Ok((k_plus, flexibility))
}

/// `orth(R_Eᵀ C_E ρ)` over the rigid motions ρ of E that vanish on every held component of
/// its nodes (clamped or partly held: E's actual constraints) and have no micro trace on its
/// interfaces (docs/method.md §4; [`substructure_kernel`]).
pub(super) fn rigid_kernel(
    sides: &[Side],
    topology: &SubstructureTopology,
    structure: &Structure,
    interfaces: &[Interface],
) -> DMatrix<f64> {
    let traces: Vec<InterfaceTrace<'_>> = sides
        .iter()
        .map(|s| {
            let iface = &interfaces[s.interface];
            InterfaceTrace {
                positions: iface
                    .topology
                    .nodes
                    .iter()
                    .map(|&node| structure.nodes[node])
                    .collect(),
                free: &iface.free,
                basis: &s.basis,
            }
        })
        .collect();
    let all_nodes = || topology.nodes.iter().chain(&topology.clamped_nodes);
    let all_positions: Vec<[f64; 3]> = all_nodes().map(|&node| structure.nodes[node]).collect();
    let held: Vec<([f64; 3], [bool; 3])> = all_nodes()
        .map(|&node| (structure.nodes[node], structure.held_components(node)))
        .filter(|(_, held)| held.iter().any(|&h| h))
        .collect();
    substructure_kernel(&all_positions, &held, &traces)
}

/// Eigenvalues of K*_E below `NULL_RELATIVE · d_m` span its kernel; those above
/// `GAP_RELATIVE · d_m` are regular. On the paper's partitions the two groups sit near 1e-15
/// and above 1e-3 (relative to d_m); an eigenvalue between the bounds has no clear status.
const NULL_RELATIVE: f64 = 1e-8;
const GAP_RELATIVE: f64 = 1e-6;

/// The kernel Q_E of K*_E: the rigid motions with no micro trace (docs/method.md §4, exact) completed by
/// the numerical null space of K*_E, which also holds the internal mechanisms of small
/// substructures (a one-module substructure has three) that rigid motions miss. `None` when
/// an eigenvalue falls between the null and regular bounds.
///
/// Q_E has as many columns as K*_E has null eigenvalues (at least the rigid motions'): a null
/// eigenvector that repeats a rigid motion differs from it by round-off over the spectral gap
/// (6e-9 on a one-module-wide strip), which a dependence test relative to round-off took for a
/// mode of its own; that noise, normalised, made a regular direction a kernel one, whose
/// stiffness the iteration then left out: a fixed point off the equilibrium (issue 42, T5).
/// The completion takes, one by one, the null eigenvector farthest from the columns kept.
pub(super) fn complete_kernel(
    k_star: &DMatrix<f64>,
    rigid: DMatrix<f64>,
    dm: f64,
) -> Option<DMatrix<f64>> {
    let m = k_star.nrows();
    if m == 0 {
        return Some(rigid);
    }
    let eig = k_star.clone().symmetric_eigen();
    let mut null: Vec<DVector<f64>> = Vec::new();
    for (i, &value) in eig.eigenvalues.iter().enumerate() {
        if value.abs() <= NULL_RELATIVE * dm {
            null.push(eig.eigenvectors.column(i).into_owned());
        } else if value.abs() < GAP_RELATIVE * dm {
            return None;
        }
    }
    let columns = null.len().max(rigid.ncols());
    let mut kept: Vec<DVector<f64>> = rigid.column_iter().map(|c| c.into_owned()).collect();
    // v minus its projection on the columns kept (twice, for orthogonality to round-off).
    let remainder = |v: &DVector<f64>, kept: &[DVector<f64>]| {
        let mut r = v.clone();
        for _ in 0..2 {
            for q in kept {
                let along = q.dot(&r);
                r.axpy(-along, q, 1.0);
            }
        }
        r
    };
    while kept.len() < columns {
        let farthest = null
            .iter()
            .map(|v| remainder(v, &kept))
            .max_by(|a, b| a.norm().total_cmp(&b.norm()));
        match farthest {
            Some(r) if r.norm() > DEPENDENT_NULL_VECTOR => kept.push(r.normalize()),
            _ => break,
        }
    }
    Some(match kept.is_empty() {
        true => DMatrix::zeros(m, 0),
        false => DMatrix::from_columns(&kept),
    })
}

/// A null eigenvector (unit) whose part off the kernel columns kept is at most this repeats
/// them.
const DEPENDENT_NULL_VECTOR: f64 = 1e-3;
