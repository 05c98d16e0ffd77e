//! Kernel of a substructure's condensed operator K*_E (docs/method.md §4): the rigid motions ρ of E that
//! vanish on every held component of its nodes (clamped nodes, and the held components of
//! partly held ones) and have no micro trace on any of its interfaces; then
//! `Q_E = orth(R_Eᵀ C_E ρ)`.

use super::macro_basis::orthonormal_columns;
use nalgebra::{DMatrix, DVector, SymmetricEigen, Vector3};

/// Gram eigenvalue below which a rigid motion satisfies the kernel's constraints.
const NULL_THRESHOLD: f64 = 1e-10;

/// One interface of E as the kernel computation sees it: its node positions and macro basis.
pub struct InterfaceTrace<'a> {
    /// Positions of the interface's nodes, in its node order.
    pub positions: Vec<[f64; 3]>,
    /// Per node: its free components (the rows of R, node-major).
    pub free: &'a [[bool; 3]],
    /// Its macro basis R (one row per free component, orthonormal columns).
    pub basis: &'a DMatrix<f64>,
}

/// The frame the six rigid motions of a set of nodes are written in: about the nodes' centre,
/// rotations scaled by their root-mean-square distance to it, so that every field is O(1) per
/// node and Gram thresholds can be absolute.
pub(crate) struct RigidFrame {
    centre: Vector3<f64>,
    length: f64,
}

impl RigidFrame {
    /// The frame of the nodes at `positions`.
    pub(crate) fn new(positions: &[[f64; 3]]) -> RigidFrame {
        let n = positions.len().max(1) as f64;
        let centre = positions
            .iter()
            .fold(Vector3::zeros(), |s, p| s + Vector3::from(*p))
            / n;
        let length = (positions
            .iter()
            .map(|p| (Vector3::from(*p) - centre).norm_squared())
            .sum::<f64>()
            / n)
            .sqrt()
            .max(f64::MIN_POSITIVE);
        RigidFrame { centre, length }
    }

    /// The six rigid motions (3 translations, 3 rotations) evaluated at `p`: a 3 × 6 block.
    pub(crate) fn block(&self, p: &[f64; 3]) -> [[f64; 6]; 3] {
        let d = (Vector3::from(*p) - self.centre) / self.length;
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
}

/// `Σ rᵀ r` over `rows`, added to the 6 × 6 Gram matrix of the rigid motions' amplitudes.
pub(crate) fn add_to_gram(gram: &mut DMatrix<f64>, rows: &[[f64; 6]]) {
    for r in rows {
        for i in 0..6 {
            for j in 0..6 {
                gram[(i, j)] += r[i] * r[j];
            }
        }
    }
}

/// The amplitudes of the rigid motions that satisfy the constraints gathered in `gram`:
/// eigenvectors of eigenvalue at most [`NULL_THRESHOLD`] (the fields are O(1) per node, so a
/// violated constraint gives an eigenvalue of order one or more, a satisfied one round-off).
pub(crate) fn null_amplitudes(gram: DMatrix<f64>) -> Vec<DVector<f64>> {
    let eig = SymmetricEigen::new(gram);
    (0..6)
        .filter(|&i| eig.eigenvalues[i] <= NULL_THRESHOLD)
        .map(|i| eig.eigenvectors.column(i).into_owned())
        .collect()
}

/// `Q_E`: orthonormal columns (rows = E's macro dofs, interfaces in `traces` order).
///
/// `held`: the position of every node of E held on some component, and which components.
pub fn substructure_kernel(
    all_positions: &[[f64; 3]],
    held: &[([f64; 3], [bool; 3])],
    traces: &[InterfaceTrace<'_>],
) -> DMatrix<f64> {
    let frame = RigidFrame::new(all_positions);
    // Constraints on the 6 amplitudes: ρ = 0 on held components; (I − R Rᵀ) ρ|Γ = 0.
    let mut gram = DMatrix::<f64>::zeros(6, 6);
    for (p, components) in held {
        let block = frame.block(p);
        let rows: Vec<[f64; 6]> = (0..3)
            .filter(|&c| components[c])
            .map(|c| block[c])
            .collect();
        add_to_gram(&mut gram, &rows);
    }
    // ρ on the interface's free components, node-major (the rows of its R).
    let trace_of = |t: &InterfaceTrace<'_>| -> DMatrix<f64> {
        let rows: Vec<[f64; 6]> = t
            .positions
            .iter()
            .zip(t.free)
            .flat_map(|(p, free)| {
                let b = frame.block(p);
                (0..3).filter(move |&c| free[c]).map(move |c| b[c])
            })
            .collect();
        DMatrix::from_fn(rows.len(), 6, |i, j| rows[i][j])
    };
    for t in traces {
        let rho = trace_of(t);
        let micro = &rho - t.basis * (t.basis.transpose() * &rho);
        let rows: Vec<[f64; 6]> = (0..micro.nrows())
            .map(|i| std::array::from_fn(|j| micro[(i, j)]))
            .collect();
        add_to_gram(&mut gram, &rows);
    }
    let null = null_amplitudes(gram);
    // R_Eᵀ C_E ρ for each surviving rigid motion.
    let m_e: usize = traces.iter().map(|t| t.basis.ncols()).sum();
    let fields: Vec<Vec<f64>> = null
        .iter()
        .map(|amplitude| {
            let mut out = Vec::with_capacity(m_e);
            for t in traces {
                let rho = trace_of(t) * amplitude;
                out.extend((t.basis.transpose() * rho).iter());
            }
            out
        })
        .collect();
    orthonormal_columns(&fields, m_e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::macro_basis::labelled_macro_basis;
    use crate::decomposition::WeakInterfaces;

    /// A substructure whose nodes are the unit square's corners at z = 0 and z = 1, with one
    /// strong interface (the upper corners, all components free: every rigid motion is macro
    /// there) and the lower corners held as `held` says: the kernel's columns are the rigid
    /// motions the held components leave.
    fn kernel_columns(held: &[[bool; 3]; 4]) -> usize {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let lower: Vec<[f64; 3]> = square.iter().map(|p| [p[0], p[1], 0.0]).collect();
        let upper: Vec<[f64; 3]> = square.iter().map(|p| [p[0], p[1], 1.0]).collect();
        let free = vec![[true; 3]; 4];
        let (basis, _) = labelled_macro_basis(&upper, &free, WeakInterfaces::Macro, 1);
        let all: Vec<[f64; 3]> = lower.iter().chain(&upper).copied().collect();
        let held: Vec<([f64; 3], [bool; 3])> = lower
            .iter()
            .zip(held)
            .filter(|(_, h)| h.iter().any(|&x| x))
            .map(|(p, h)| (*p, *h))
            .collect();
        let traces = [InterfaceTrace {
            positions: upper.clone(),
            free: &free,
            basis: &basis,
        }];
        substructure_kernel(&all, &held, &traces).ncols()
    }

    #[test]
    fn rigid_modes_follow_the_held_components() {
        let none = [false; 3];
        let z = [false, false, true];
        let all = [true; 3];
        // Floating: six rigid motions.
        assert_eq!(kernel_columns(&[none; 4]), 6);
        // Held vertically at the four lower corners: x and y translations, rotation about z.
        assert_eq!(kernel_columns(&[z; 4]), 3);
        // ... and in x at the corner (0, 0, 0) too: the y translation and the rotation about
        // the vertical through that corner.
        assert_eq!(kernel_columns(&[[true, false, true], z, z, z]), 2);
        // That corner clamped, the others held vertically: only that rotation.
        assert_eq!(kernel_columns(&[all, z, z, z]), 1);
        // Two corners clamped: the rotation about the line through them.
        assert_eq!(kernel_columns(&[all, all, none, none]), 1);
        // Three: nothing.
        assert_eq!(kernel_columns(&[all, all, all, none]), 0);
    }
}
