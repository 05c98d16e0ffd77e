//! Prestress stability (docs/method.md §8; Pellegrino & Calladine, Connelly's second-order
//! stability): with M a basis of the mechanisms (`B M = 0` on the free dofs), the structure is
//! prestress-stable when `Mᵀ K_G(t0) M` is positive definite. Dense, for structures of at most
//! [`DENSE_LIMIT`] free dofs (real tensegrities are small; a grid's mechanisms are refused
//! without it).

use super::Structure;
use nalgebra::{DMatrix, SymmetricEigen};

/// The most free dofs the dense test takes (an eigen-decomposition of `BᵀB`, n × n).
pub const DENSE_LIMIT: usize = 1500;

/// Eigenvalues of `BᵀB` (unit member stiffness) below this fraction of the largest span the
/// mechanisms.
const NULL_RELATIVE: f64 = 1e-10;

/// Eigenvalues of `Mᵀ K_G M` at or below this fraction of the largest `|t0 / L|` of a member
/// are not a stiffening (round-off of the projection is ≈ 1e-14 of it).
const STIFFENED_RELATIVE: f64 = 1e-9;

/// A mechanism mode and how the prestress stiffens it.
#[derive(Debug, Clone)]
pub struct Mode {
    /// Its eigenvalue in `Mᵀ K_G M`, N/m (per unit of the mode's norm squared).
    pub stiffness: f64,
    /// The mode on the free dofs, unit norm.
    pub displacement: Vec<f64>,
    /// Whether it moves every node alike (a rigid translation: too few supports).
    pub translation: bool,
}

impl Mode {
    /// `mode 1 (prestress stiffness -2.1e3 N/m) moves nodes 4 (0.57, 0.10, 0.00), 5 (…), 6 (…)`:
    /// the three nodes it moves most, by id, with their motion (the mode of unit norm).
    pub fn describe(&self, s: &Structure, number: usize) -> String {
        let nodes: Vec<String> = largest_moving_nodes(s, &self.displacement, 3)
            .into_iter()
            .map(|(id, u)| format!("{id} ({:.2}, {:.2}, {:.2})", u[0], u[1], u[2]))
            .collect();
        format!(
            "mode {number} (prestress stiffness {:.3e} N/m{}) moves nodes {}",
            self.stiffness,
            if self.translation {
                ", a rigid translation: too few supports"
            } else {
                ""
            },
            nodes.join(", ")
        )
    }
}

/// The prestress-stability test of a structure.
#[derive(Debug, Clone)]
pub struct PrestressStability {
    /// Mechanisms m (rigid-body motions included).
    pub mechanisms: usize,
    /// Every mechanism mode, by increasing stiffness (the eigenvectors of `Mᵀ K_G M`).
    pub modes: Vec<Mode>,
    /// The stiffness at or below which a mode counts as not stiffened, N/m.
    pub threshold: f64,
}

impl PrestressStability {
    /// Whether the prestress stiffens every mechanism.
    pub fn stable(&self) -> bool {
        self.modes.iter().all(|m| m.stiffness > self.threshold)
    }

    /// The modes the prestress does not stiffen.
    pub fn unstiffened(&self) -> impl Iterator<Item = &Mode> {
        self.modes.iter().filter(|m| m.stiffness <= self.threshold)
    }

    /// The smallest stiffness of a mode (N/m), `None` without mechanisms.
    pub fn smallest(&self) -> Option<f64> {
        self.modes.first().map(|m| m.stiffness)
    }
}

/// The test for `s` (whose [`Structure::geometric`] need not be set: `K_G(t0)` is taken from
/// its links), or `None` above [`DENSE_LIMIT`] free dofs.
pub fn prestress_stability(s: &Structure) -> Option<PrestressStability> {
    let n = s.n_free;
    if n == 0 || n > DENSE_LIMIT {
        return None;
    }
    // BᵀB with unit member stiffness: its null space is the mechanisms'.
    let mut btb = DMatrix::<f64>::zeros(n, n);
    for row in &s.link_dofs {
        for (p, cp) in row.iter() {
            for (q, cq) in row.iter() {
                btb[(p, q)] += cp * cq;
            }
        }
    }
    let eig = SymmetricEigen::new(btb);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let null: Vec<usize> = (0..n)
        .filter(|&i| eig.eigenvalues[i] <= NULL_RELATIVE * largest)
        .collect();
    let m = null.len();
    let geometric = super::GeometricStiffness::of_prestress(s);
    let threshold = STIFFENED_RELATIVE
        * geometric
            .weights()
            .iter()
            .fold(0.0f64, |w, x| w.max(x.abs()));
    if m == 0 {
        return Some(PrestressStability {
            mechanisms: 0,
            modes: Vec::new(),
            threshold,
        });
    }
    let basis: Vec<Vec<f64>> = null
        .iter()
        .map(|&i| eig.eigenvectors.column(i).iter().copied().collect())
        .collect();
    let kg_basis: Vec<Vec<f64>> = basis.iter().map(|v| geometric.product(v)).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    // Mᵀ K_G M, symmetrised.
    let reduced = DMatrix::from_fn(m, m, |i, j| {
        0.5 * (dot(&basis[i], &kg_basis[j]) + dot(&basis[j], &kg_basis[i]))
    });
    let small = SymmetricEigen::new(reduced);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&i, &j| small.eigenvalues[i].total_cmp(&small.eigenvalues[j]));
    let modes = order
        .into_iter()
        .map(|c| {
            let mut displacement = vec![0.0; n];
            for (k, v) in basis.iter().enumerate() {
                let w = small.eigenvectors[(k, c)];
                displacement
                    .iter_mut()
                    .zip(v)
                    .for_each(|(d, x)| *d += w * x);
            }
            Mode {
                stiffness: small.eigenvalues[c],
                translation: is_translation(s, &displacement),
                displacement,
            }
        })
        .collect();
    Some(PrestressStability {
        mechanisms: m,
        modes,
        threshold,
    })
}

/// Whether the mode moves every free node by the same vector (to 1e-8 of its largest motion).
fn is_translation(s: &Structure, mode: &[f64]) -> bool {
    let full = s.full_displacements(mode);
    let moving: Vec<&[f64]> = full
        .chunks(3)
        .filter(|c| c.iter().any(|x| *x != 0.0))
        .collect();
    let Some(first) = moving.first() else {
        return false;
    };
    let size = mode.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    moving.len() == s.nodes.len()
        && moving
            .iter()
            .all(|c| (0..3).all(|k| (c[k] - first[k]).abs() <= 1e-8 * size))
}

/// The ids of the `count` nodes a mode moves most, with their motion (largest first).
pub fn largest_moving_nodes(s: &Structure, mode: &[f64], count: usize) -> Vec<(u64, [f64; 3])> {
    let full = s.full_displacements(mode);
    let mut nodes: Vec<(usize, f64)> = full
        .chunks(3)
        .enumerate()
        .map(|(v, c)| (v, c[0].hypot(c[1]).hypot(c[2])))
        .filter(|&(_, size)| size > 0.0)
        .collect();
    nodes.sort_by(|a, b| b.1.total_cmp(&a.1));
    nodes
        .into_iter()
        .take(count)
        .map(|(v, _)| {
            (
                s.node_ids[v],
                [full[3 * v], full[3 * v + 1], full[3 * v + 2]],
            )
        })
        .collect()
}
