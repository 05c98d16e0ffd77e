//! The equilibrium matrix `A = Bᵀ` (free dofs × members, docs/method.md §7): its rank, the
//! number s of self-stress states and m of mechanisms (the Pellegrino–Calladine counts), and,
//! when s = 1 and m = 0, the self-stress state itself.

use super::Structure;
use crate::linalg::{
    factorize_counting_zero_modes, SparseCholesky, StiffnessPattern, ZERO_MODES_COUNTED,
};
use faer::Par;

/// The most free dofs a dense test takes (an eigen-decomposition of `BᵀB` or `B Bᵀ`, n × n:
/// the self-stress states here, prestress stability in `crate::model`).
pub const DENSE_LIMIT: usize = 1500;

/// The Pellegrino–Calladine counts of the equilibrium matrix `A = Bᵀ` (docs/method.md §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EquilibriumCounts {
    /// Members (columns of A).
    pub members: usize,
    /// Free dofs (rows of A).
    pub free_dofs: usize,
    /// rank r of A.
    pub rank: usize,
    /// s = members − r: independent self-stress states.
    pub self_stress_states: usize,
    /// m = free dofs − r: mechanisms, rigid-body motions included.
    pub mechanisms: usize,
}

/// The counts of `structure`, from the zero modes of `A Aᵀ = Bᵀ B` (unit member stiffness):
/// one sparse Cholesky factorization, and when it reveals a singular matrix, block inverse
/// iterations for the eigenvalues below `ZERO_MODE_RELATIVE` × mean diagonal — no dense
/// matrix, so it scales like a solve (64 × 64 grids included).
pub fn equilibrium_counts(structure: &Structure) -> EquilibriumCounts {
    counts_and_factor(structure).0
}

/// The counts, and `A Aᵀ = Bᵀ B` factorized when it is regular (m = 0). The sparse count
/// stops at [`ZERO_MODES_COUNTED`] (a lower bound): there, up to [`DENSE_LIMIT`] free dofs the
/// mechanisms are counted densely; above it m is at least `free dofs − members` (r ≤ members).
/// A flat net form-found from coplanar anchors has 88 mechanisms: it was reported with 64 and
/// a rank of 167 for 144 members (issue 57, N-D6).
fn counts_and_factor(structure: &Structure) -> (EquilibriumCounts, Option<SparseCholesky>) {
    let n = structure.n_free;
    let (mechanisms, factor) = if n == 0 {
        (0, None)
    } else {
        let pattern = StiffnessPattern::new(n, &structure.link_dofs);
        let mut values = vec![0.0; pattern.nnz()];
        pattern.assemble(&structure.link_dofs, |_| 1.0, &mut values);
        let mut factor = SparseCholesky::analyse(&pattern, Par::Seq);
        let m = match factorize_counting_zero_modes(&pattern, &values, &mut factor) {
            m if m < ZERO_MODES_COUNTED => m,
            _ if n <= DENSE_LIMIT => mechanism_basis(structure).len(),
            m => m.max(n.saturating_sub(structure.links.len())),
        };
        (m, (m == 0).then_some(factor))
    };
    (EquilibriumCounts::new(structure, mechanisms), factor)
}

/// Eigenvalues of `BᵀB` (unit member stiffness) at or below this fraction of the largest span
/// the mechanisms.
const NULL_RELATIVE: f64 = 1e-10;

/// An orthonormal basis of the mechanisms, `B M = 0` on the free dofs (dense: for at most
/// [`DENSE_LIMIT`] free dofs): the eigenvectors of `BᵀB` (unit member stiffness) whose
/// eigenvalues are at most `NULL_RELATIVE` (1e-10) of the largest.
pub fn mechanism_basis(structure: &Structure) -> Vec<Vec<f64>> {
    let n = structure.n_free;
    let mut btb = nalgebra::DMatrix::<f64>::zeros(n, n);
    for row in &structure.link_dofs {
        for (p, cp) in row.iter() {
            for (q, cq) in row.iter() {
                btb[(p, q)] += cp * cq;
            }
        }
    }
    let eig = nalgebra::SymmetricEigen::new(btb);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    (0..n)
        .filter(|&i| eig.eigenvalues[i] <= NULL_RELATIVE * largest)
        .map(|i| eig.eigenvectors.column(i).iter().copied().collect())
        .collect()
}

impl EquilibriumCounts {
    /// The counts of `structure` from its number of mechanisms m, the dimension of ker A
    /// (of `B` and of `Bᵀ k B` alike, every member's stiffness k being positive):
    /// r = free dofs − m, s = members − r.
    pub fn new(structure: &Structure, mechanisms: usize) -> EquilibriumCounts {
        let (members, free_dofs) = (structure.links.len(), structure.n_free);
        let rank = free_dofs - mechanisms.min(free_dofs);
        EquilibriumCounts {
            members,
            free_dofs,
            rank,
            self_stress_states: members - rank.min(members),
            mechanisms,
        }
    }
}

/// Why the self-stress state cannot scale a prestress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SelfStressRefusal {
    /// s ≠ 1, or m > 0 (the projection below needs `Bᵀ B` regular).
    Counts(EquilibriumCounts),
    /// The state's component on the member is zero: `v_j²` (v the unit state) is this small.
    ZeroComponent(f64),
}

/// A unit self-stress component below this (`v_j²` with `‖v‖ = 1`) is zero: the projection's
/// round-off is about 1e-16 times the condition number of `Bᵀ B`.
const ZERO_COMPONENT: f64 = 1e-10;

/// Entries of the scaled state below this fraction of its largest are round-off, set to 0.
const ROUNDOFF_RELATIVE: f64 = 1e-12;

/// The self-stress state of a structure with s = 1 and m = 0, scaled so that member `j`
/// carries 1: the projection of the unit vector `e_j` onto the null space of A,
/// `t = e_j − B (Bᵀ B)⁻¹ Bᵀ e_j` (then `t_j = v_j²`), divided by `t_j`. Entries at
/// round-off (below 1e-12 of the largest) are set to exactly 0.
pub fn self_stress_through(structure: &Structure, j: usize) -> Result<Vec<f64>, SelfStressRefusal> {
    let (counts, factor) = counts_and_factor(structure);
    if counts.self_stress_states != 1 || counts.mechanisms != 0 {
        return Err(SelfStressRefusal::Counts(counts));
    }
    let mut y = vec![0.0; structure.n_free];
    structure.link_dofs[j].scatter(1.0, &mut y);
    if let Some(factor) = &factor {
        factor.solve_in_place(&mut y);
    }
    // t = e_j − B y.
    let mut t: Vec<f64> = structure
        .link_dofs
        .iter()
        .map(|ld| -ld.elongation(&y))
        .collect();
    t[j] += 1.0;
    let tj = t[j];
    // NaN (a breakdown) counts as zero too.
    if tj.is_nan() || tj <= ZERO_COMPONENT {
        return Err(SelfStressRefusal::ZeroComponent(tj.max(0.0)));
    }
    t.iter_mut().for_each(|x| *x /= tj);
    let largest = t.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
    for x in &mut t {
        if x.abs() <= ROUNDOFF_RELATIVE * largest {
            *x = 0.0;
        }
    }
    t[j] = 1.0;
    Ok(t)
}

/// The non-trivial self-stress state of a structure with mechanisms or trivial states, dense
/// (docs/method.md §7–8): a member between two held nodes has no free dof, so it is a trivial
/// self-stress state of its own (any tension there is carried by the supports); those are
/// counted apart. With exactly one non-trivial state, it is returned scaled so that member `j`
/// carries 1 (zero on the trivial members), with the number of trivial states.
#[derive(Debug, Clone, PartialEq)]
pub struct DenseSelfStress {
    /// The state, scaled so that member `j` carries 1; zero on trivial members.
    pub state: Vec<f64>,
    /// Members between two held nodes (trivial states), by index.
    pub trivial: Vec<usize>,
}

/// Why [`self_stress_dense`] cannot give the state.
#[derive(Debug, Clone, PartialEq)]
pub enum DenseSelfStressRefusal {
    /// Not exactly one non-trivial state: `(non-trivial s, trivial member indices)`.
    Count(usize, Vec<usize>),
    /// The structure is larger than the dense computation takes (free dofs or members).
    TooLarge,
    /// The state's component on member `j` is zero (or `j` is trivial).
    ZeroComponent,
}

/// The most members the dense self-stress takes (an eigen-decomposition of `A Aᵀ`, members²).
pub const DENSE_MEMBERS: usize = 3000;

/// See [`DenseSelfStress`]: the null space of `A = Bᵀ` over the non-trivial members, from the
/// eigen-decomposition of `B Bᵀ` (members × members, unit stiffness).
pub fn self_stress_dense(
    structure: &Structure,
    j: usize,
) -> Result<DenseSelfStress, DenseSelfStressRefusal> {
    let trivial: Vec<usize> = (0..structure.links.len())
        .filter(|&i| structure.link_dofs[i].len == 0)
        .collect();
    let kept: Vec<usize> = (0..structure.links.len())
        .filter(|&i| structure.link_dofs[i].len > 0)
        .collect();
    let m = kept.len();
    if m > DENSE_MEMBERS || structure.n_free > DENSE_LIMIT {
        return Err(DenseSelfStressRefusal::TooLarge);
    }
    // B Bᵀ over the kept members: its null space is the self-stress states.
    let mut dense = vec![vec![0.0; structure.n_free]; m];
    for (r, &i) in kept.iter().enumerate() {
        for (d, c) in structure.link_dofs[i].iter() {
            dense[r][d] += c;
        }
    }
    let bbt = nalgebra::DMatrix::from_fn(m, m, |a, b| {
        dense[a]
            .iter()
            .zip(&dense[b])
            .map(|(x, y)| x * y)
            .sum::<f64>()
    });
    let eig = nalgebra::SymmetricEigen::new(bbt);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |x, v| x.max(v.abs()));
    let null: Vec<usize> = (0..m)
        .filter(|&c| eig.eigenvalues[c] <= 1e-10 * largest)
        .collect();
    if null.len() != 1 {
        return Err(DenseSelfStressRefusal::Count(null.len(), trivial));
    }
    let Some(row) = kept.iter().position(|&i| i == j) else {
        return Err(DenseSelfStressRefusal::ZeroComponent);
    };
    let v = eig.eigenvectors.column(null[0]);
    if v[row].abs() <= ZERO_COMPONENT.sqrt() {
        return Err(DenseSelfStressRefusal::ZeroComponent);
    }
    let mut state = vec![0.0; structure.links.len()];
    for (r, &i) in kept.iter().enumerate() {
        state[i] = v[r] / v[row];
    }
    let largest = state.iter().fold(0.0f64, |x, t| x.max(t.abs()));
    for x in &mut state {
        if x.abs() <= ROUNDOFF_RELATIVE * largest {
            *x = 0.0;
        }
    }
    state[j] = 1.0;
    Ok(DenseSelfStress { state, trivial })
}

/// The members' forces `t0` projected on the self-stress states, least squares (issue 46,
/// re-balancing): `t = t0 − B y` with `(BᵀB) y = Bᵀ t0` at the free dofs — the nearest
/// balanced prestress. One sparse factorization when m = 0; with mechanisms, `BᵀB`'s
/// pseudo-inverse (dense, up to [`DENSE_LIMIT`] free dofs), else `None`.
pub fn project_on_self_stress(structure: &Structure, t0: &[f64]) -> Option<Vec<f64>> {
    let n = structure.n_free;
    let mut y = vec![0.0; n];
    for (row, &t) in structure.link_dofs.iter().zip(t0) {
        row.scatter(t, &mut y);
    }
    let (counts, factor) = counts_and_factor(structure);
    match factor {
        Some(factor) => factor.solve_in_place(&mut y),
        None if counts.mechanisms == 0 => {}
        None if n <= DENSE_LIMIT => y = pseudo_inverse_solve(structure, &y),
        None => return None,
    }
    Some(
        structure
            .link_dofs
            .iter()
            .zip(t0)
            .map(|(row, &t)| t - row.elongation(&y))
            .collect(),
    )
}

/// `(BᵀB)⁺ f` through the eigen-decomposition of `BᵀB` (eigenvalues below 1e-10 of the
/// largest, the mechanisms', left out: f = Bᵀt0 has no component on them).
fn pseudo_inverse_solve(structure: &Structure, f: &[f64]) -> Vec<f64> {
    let n = structure.n_free;
    let mut btb = nalgebra::DMatrix::<f64>::zeros(n, n);
    for row in &structure.link_dofs {
        for (p, cp) in row.iter() {
            for (q, cq) in row.iter() {
                btb[(p, q)] += cp * cq;
            }
        }
    }
    let eig = nalgebra::SymmetricEigen::new(btb);
    let largest = eig.eigenvalues.amax();
    let f = nalgebra::DVector::from_column_slice(f);
    let mut y = nalgebra::DVector::zeros(n);
    for (c, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda > 1e-10 * largest {
            let v = eig.eigenvectors.column(c);
            y += v * (v.dot(&f) / lambda);
        }
    }
    y.iter().copied().collect()
}
