//! Prestress stability (docs/method.md §8; Pellegrino & Calladine, Connelly's second-order
//! stability): with M a basis of the mechanisms (`B M = 0` on the free dofs), the structure is
//! prestress-stable when `Mᵀ K_G(t0) M` is positive definite. Dense, for structures of at most
//! [`DENSE_LIMIT`] free dofs (real tensegrities are small; a grid's mechanisms are refused
//! without it).

use crate::structure::{mechanism_basis, Structure, CLAMPED, DENSE_LIMIT};
use nalgebra::{DMatrix, SymmetricEigen};

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
    /// When it is a rigid-body rotation of the whole structure (too few supports, or supports
    /// on one line): a point of its axis and the axis's unit vector, m.
    pub rotation: Option<([f64; 3], [f64; 3])>,
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
            match (self.translation, self.rotation) {
                (true, _) => ", a rigid translation: too few supports".to_string(),
                (false, Some((p, a))) => format!(
                    ", a rigid-body rotation about the axis through ({:.2}, {:.2}, {:.2}) along \
                     ({:.2}, {:.2}, {:.2}): too few supports (or all on that line)",
                    p[0], p[1], p[2], a[0], a[1], a[2]
                ),
                (false, None) => String::new(),
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

/// The test for `s`, whatever its model (`K_G(t0)` of its self-stress, before any change of
/// the rest lengths), or `None` above
/// [`DENSE_LIMIT`] free dofs.
pub fn prestress_stability(s: &Structure) -> Option<PrestressStability> {
    let n = s.n_free;
    if n == 0 || n > DENSE_LIMIT {
        return None;
    }
    // BᵀB with unit member stiffness: its null space is the mechanisms'.
    let basis = mechanism_basis(s);
    let m = basis.len();
    let geometric = super::GeometricStiffness::of_self_stress(s);
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
                rotation: rigid_rotation(s, &displacement),
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

/// Whether the mode is a rigid-body motion `u = a + ω × x` of every node (held components
/// at rest) that turns (`|ω| ℓ` above 1e-8 of its largest motion, ℓ the structure's size), to
/// 1e-8 of that motion: a point of its axis `ω × a / |ω|²` and the unit vector of ω.
fn rigid_rotation(s: &Structure, mode: &[f64]) -> Option<([f64; 3], [f64; 3])> {
    let n = s.nodes.len();
    let full: Vec<f64> = s
        .dof_of
        .iter()
        .map(|&d| if d == CLAMPED { 0.0 } else { mode[d] })
        .collect();
    let size = full.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if size == 0.0 || n < 2 {
        return None;
    }
    // Least squares of u_v = a + ω × x_v: columns a (3) and ω (3); ω × x = −[x]× ω.
    let centre: [f64; 3] =
        std::array::from_fn(|k| s.nodes.iter().map(|x| x[k]).sum::<f64>() / n as f64);
    let a = DMatrix::<f64>::from_fn(3 * n, 6, |r, c| {
        let (v, k) = (r / 3, r % 3);
        let x: [f64; 3] = std::array::from_fn(|i| s.nodes[v][i] - centre[i]);
        match c {
            0..=2 => (c == k) as u8 as f64,
            // (ω × x)_k = ω_{k+1} x_{k+2} − ω_{k+2} x_{k+1}.
            _ => {
                let w = c - 3;
                if w == (k + 1) % 3 {
                    x[(k + 2) % 3]
                } else if w == (k + 2) % 3 {
                    -x[(k + 1) % 3]
                } else {
                    0.0
                }
            }
        }
    });
    let b = nalgebra::DVector::from_column_slice(&full);
    let fit = a.clone().svd(true, true).solve(&b, 1e-12).ok()?;
    let misfit = (&a * &fit - &b).amax();
    let omega = [fit[3], fit[4], fit[5]];
    let turn = omega.iter().map(|w| w * w).sum::<f64>().sqrt();
    if misfit > 1e-8 * size || turn * s.size() <= 1e-8 * size {
        return None;
    }
    // The axis's direction with its largest component positive (one way of naming it).
    let largest = (0..3)
        .max_by(|&i, &j| omega[i].abs().total_cmp(&omega[j].abs()))
        .unwrap_or(0);
    let sense = if omega[largest] < 0.0 { -1.0 } else { 1.0 };
    let t = [fit[0], fit[1], fit[2]];
    // u = t + ω × (x − c): the axis passes through c + ω × t / |ω|².
    let cross = [
        omega[1] * t[2] - omega[2] * t[1],
        omega[2] * t[0] - omega[0] * t[2],
        omega[0] * t[1] - omega[1] * t[0],
    ];
    Some((
        std::array::from_fn(|k| centre[k] + cross[k] / (turn * turn)),
        std::array::from_fn(|k| sense * omega[k] / turn),
    ))
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

/// A prestress strain `|t0| / (E·S)` beyond this is no material's (steel yields near 2e-3,
/// the strongest fibres break near 5e-2): the members table has a unit slip.
pub const PRESTRESS_STRAIN_WARNING: f64 = 0.1;

/// The member (its id) with the largest prestress strain `|t0| / (E·S)` (t0 the given
/// prestress, `E·S = k L`), and that strain, when it lies beyond [`PRESTRESS_STRAIN_WARNING`].
pub fn unit_slip_strain(s: &Structure) -> Option<(u64, f64)> {
    s.links
        .iter()
        .map(|l| {
            let strain = s.self_stress(l).abs() / (l.stiffness * l.length);
            (l.id, if strain.is_nan() { 0.0 } else { strain })
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .filter(|&(_, strain)| strain > PRESTRESS_STRAIN_WARNING)
}

/// The unit-slip sentence of a prestress strain `strain` of member `id`.
pub fn unit_slip_sentence(id: u64, strain: f64) -> String {
    format!(
        "member {id}'s prestress strain t0/(E·S) is {strain:.1e}, which no material takes (a \
         real one lies below 1e-2): a unit slip? E in Pa (not GPa or MPa), section in m² (not \
         mm² or cm²), prestress in N"
    )
}

/// The compressed bar whose geometric term `−t0/L` is largest against its axial stiffness k
/// (its id and `−t0 / (L k)`), when that ratio reaches 1e-2: a prestress of that size buckles
/// the bars it compresses.
fn buckling_bar(s: &Structure) -> Option<(u64, f64)> {
    s.links
        .iter()
        .filter(|l| !l.kind.is_cable())
        .map(|l| {
            let t0 = s.self_stress(l);
            (l.id, -t0 / (l.length * l.stiffness))
        })
        .filter(|&(_, r)| r >= 1e-2)
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Why `K + K_G(t0)` is not positive definite, as far as the structure tells (docs/method.md
/// §8), with the fix: a unit slip in the members table, the prestress's stiffening of the
/// mechanisms too small to tell from a zero mode in f64 (`stability` stable), a compression
/// that buckles the bars, or else a mechanism the prestress does not stiffen.
pub fn indefinite_reason(s: &Structure, stability: Option<&PrestressStability>) -> String {
    if let Some((id, strain)) = unit_slip_strain(s) {
        return unit_slip_sentence(id, strain);
    }
    // The mean diagonal of K, the scale of the factorization's zero-mode test.
    let mut diagonal = vec![0.0; s.n_free];
    for (l, row) in s.links.iter().zip(&s.link_dofs) {
        for (d, c) in row.iter() {
            diagonal[d] += l.stiffness * c * c;
        }
    }
    let mean = diagonal.iter().sum::<f64>() / s.n_free.max(1) as f64;
    let zero = crate::linalg::ZERO_MODE_RELATIVE * mean;
    match stability
        .filter(|st| st.stable())
        .and_then(|st| st.smallest())
    {
        Some(smallest) if smallest <= zero => format!(
            "the prestress stiffens every mechanism, but by {smallest:.3e} N/m at least, below \
             {:.0e} of the members' mean axial stiffness ({mean:.3e} N/m): too little to tell \
             from a zero mode in f64; raise the prestress (is it in N?) or add members or \
             supports",
            crate::linalg::ZERO_MODE_RELATIVE
        ),
        _ => match buckling_bar(s) {
            Some((id, ratio)) => format!(
                "the prestress compresses bar {id} so much that its geometric term −t0/L is \
                 {ratio:.1e} of its axial stiffness E·S/L: a prestress this large buckles the \
                 structure; lower the prestress (is it in N?)"
            ),
            None => "a mechanism the prestress does not stiffen, or a compressed bar that \
                     buckles under its own prestress; add members or supports, or change the \
                     prestress"
                .to_string(),
        },
    }
}
