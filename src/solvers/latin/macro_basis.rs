//! Macro basis R of an interface (SPEC §4, paper §4.1.2): nine first-order nodal fields about
//! the centroid G in the interface's principal frame (n3 the normal, least spread), made
//! orthonormal by modified Gram–Schmidt (twice), dependent fields dropped. Weak interfaces get
//! the identity (all-macro) or nothing (all-micro).

use super::partition::WeakInterfaces;
use nalgebra::{DMatrix, Matrix3, SymmetricEigen, Vector3};

/// Orthonormal columns spanning `fields` (each of length `rows`), dependent ones dropped.
pub fn orthonormal_columns(fields: &[Vec<f64>], rows: usize) -> DMatrix<f64> {
    let mut kept: Vec<Vec<f64>> = Vec::new();
    for f in fields {
        let mut v = f.clone();
        let before = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if before == 0.0 {
            continue;
        }
        for _ in 0..2 {
            for q in &kept {
                let r: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(q).for_each(|(vi, qi)| *vi -= r * qi);
            }
        }
        let after = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if after > 1e-10 * before {
            v.iter_mut().for_each(|x| *x /= after);
            kept.push(v);
        }
    }
    DMatrix::from_fn(rows, kept.len(), |i, j| kept[j][i])
}

/// The macro basis (3·nodes rows, node-major, x y z) of an interface through `positions`.
pub fn macro_basis(positions: &[[f64; 3]], weak: WeakInterfaces) -> DMatrix<f64> {
    let n = positions.len();
    let rows = 3 * n;
    if n <= super::partition::WEAK_MAX_NODES {
        return match weak {
            WeakInterfaces::Macro | WeakInterfaces::Drop => DMatrix::identity(rows, rows),
            WeakInterfaces::Micro => DMatrix::zeros(rows, 0),
        };
    }
    let x: Vec<Vector3<f64>> = positions.iter().map(|p| Vector3::from(*p)).collect();
    let g = x.iter().fold(Vector3::zeros(), |s, p| s + p) / n as f64;
    let spread = x
        .iter()
        .fold(Matrix3::zeros(), |s, p| s + (p - g) * (p - g).transpose());
    let eig = SymmetricEigen::new(spread);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axis = |k: usize| -> Vector3<f64> { eig.eigenvectors.column(order[k]).into_owned() };
    let (n1, n2, n3) = (axis(0), axis(1), axis(2));
    let field = |f: &dyn Fn(&Vector3<f64>) -> Vector3<f64>| -> Vec<f64> {
        x.iter()
            .flat_map(|p| {
                let v = f(&(p - g));
                [v[0], v[1], v[2]]
            })
            .collect()
    };
    let fields = vec![
        // Translations along n1, n2, n3.
        field(&|_| n1),
        field(&|_| n2),
        field(&|_| n3),
        // Rotations about (G, n_i).
        field(&|d| n1.cross(d)),
        field(&|d| n2.cross(d)),
        field(&|d| n3.cross(d)),
        // Extensions along n1 and n2.
        field(&|d| n1 * n1.dot(d)),
        field(&|d| n2 * n2.dot(d)),
        // In-plane distortion (n1 n2ᵀ + n2 n1ᵀ)(X − G).
        field(&|d| n1 * n2.dot(d) + n2 * n1.dot(d)),
    ];
    orthonormal_columns(&fields, rows)
}
