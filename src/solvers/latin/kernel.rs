//! Kernel of a substructure's condensed operator K*_E (docs/method.md §4): the rigid motions ρ of E that
//! vanish on its clamped nodes and have no micro trace on any of its interfaces; then
//! `Q_E = orth(R_Eᵀ C_E ρ)`.

use super::macro_basis::orthonormal_columns;
use nalgebra::{DMatrix, SymmetricEigen, Vector3};

/// Gram eigenvalue below which a rigid motion satisfies the kernel's constraints.
const NULL_THRESHOLD: f64 = 1e-10;

/// One interface of E as the kernel computation sees it: its node positions and macro basis.
pub struct InterfaceTrace<'a> {
    /// Positions of the interface's nodes, in its node order.
    pub positions: Vec<[f64; 3]>,
    /// Its macro basis R (3·nodes rows, orthonormal columns).
    pub basis: &'a DMatrix<f64>,
}

/// The six rigid motions (3 translations, 3 rotations about `centre`, scaled by `length`)
/// evaluated at `p`: a 3 × 6 block.
fn rigid_block(p: &[f64; 3], centre: &Vector3<f64>, length: f64) -> [[f64; 6]; 3] {
    let d = (Vector3::from(*p) - centre) / length;
    let mut block = [[0.0; 6]; 3];
    for k in 0..3 {
        block[k][k] = 1.0;
        let mut axis = Vector3::zeros();
        axis[k] = 1.0;
        let r = axis.cross(&d);
        for c in 0..3 {
            block[c][3 + k] = r[c];
        }
    }
    block
}

/// `Q_E`: orthonormal columns (rows = E's macro dofs, interfaces in `traces` order).
pub fn substructure_kernel(
    all_positions: &[[f64; 3]],
    clamped_positions: &[[f64; 3]],
    traces: &[InterfaceTrace<'_>],
) -> DMatrix<f64> {
    let n = all_positions.len().max(1) as f64;
    let centre = all_positions
        .iter()
        .fold(Vector3::zeros(), |s, p| s + Vector3::from(*p))
        / n;
    let length = (all_positions
        .iter()
        .map(|p| (Vector3::from(*p) - centre).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt()
        .max(f64::MIN_POSITIVE);
    // Constraints on the 6 amplitudes: ρ = 0 at clamped nodes; (I − R Rᵀ) ρ|Γ = 0.
    let mut gram = DMatrix::<f64>::zeros(6, 6);
    let mut add_rows = |rows: &[[f64; 6]]| {
        for r in rows {
            for i in 0..6 {
                for j in 0..6 {
                    gram[(i, j)] += r[i] * r[j];
                }
            }
        }
    };
    for p in clamped_positions {
        add_rows(&rigid_block(p, &centre, length));
    }
    let trace_of = |t: &InterfaceTrace<'_>| -> DMatrix<f64> {
        let rows = 3 * t.positions.len();
        let mut m = DMatrix::zeros(rows, 6);
        for (k, p) in t.positions.iter().enumerate() {
            let b = rigid_block(p, &centre, length);
            for c in 0..3 {
                for j in 0..6 {
                    m[(3 * k + c, j)] = b[c][j];
                }
            }
        }
        m
    };
    for t in traces {
        let rho = trace_of(t);
        let micro = &rho - t.basis * (t.basis.transpose() * &rho);
        let rows: Vec<[f64; 6]> = (0..micro.nrows())
            .map(|i| std::array::from_fn(|j| micro[(i, j)]))
            .collect();
        add_rows(&rows);
    }
    // The six fields are O(1) per node (rotations scaled by the substructure's size), so a
    // motion that violates a constraint has a Gram eigenvalue of order one or more, and one
    // that satisfies them only round-off: the threshold is absolute.
    let eig = SymmetricEigen::new(gram);
    let null: Vec<usize> = (0..6)
        .filter(|&i| eig.eigenvalues[i] <= NULL_THRESHOLD)
        .collect();
    // R_Eᵀ C_E ρ for each surviving rigid motion.
    let m_e: usize = traces.iter().map(|t| t.basis.ncols()).sum();
    let fields: Vec<Vec<f64>> = null
        .iter()
        .map(|&i| {
            let amplitude = eig.eigenvectors.column(i).into_owned();
            let mut out = Vec::with_capacity(m_e);
            for t in traces {
                let rho = trace_of(t) * &amplitude;
                out.extend((t.basis.transpose() * rho).iter());
            }
            out
        })
        .collect();
    orthonormal_columns(&fields, m_e)
}
