//! The equilibrium matrix `A = Bᵀ` (free dofs × members, docs/method.md §7): its rank, the
//! number s of self-stress states and m of mechanisms (the Pellegrino–Calladine counts), and,
//! when s = 1 and m = 0, the self-stress state itself.

use super::Structure;
use crate::linalg::{factorize_counting_zero_modes, SparseCholesky, StiffnessPattern};
use faer::Par;

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

/// The counts, and `A Aᵀ = Bᵀ B` factorized when it is regular (m = 0).
fn counts_and_factor(structure: &Structure) -> (EquilibriumCounts, Option<SparseCholesky>) {
    let n = structure.n_free;
    let members = structure.links.len();
    let (mechanisms, factor) = if n == 0 {
        (0, None)
    } else {
        let pattern = StiffnessPattern::new(n, &structure.link_dofs);
        let mut values = vec![0.0; pattern.nnz()];
        pattern.assemble(&structure.link_dofs, |_| 1.0, &mut values);
        let mut factor = SparseCholesky::analyse(&pattern, Par::Seq);
        let m = factorize_counting_zero_modes(&pattern, &values, &mut factor);
        (m, (m == 0).then_some(factor))
    };
    let rank = n - mechanisms;
    let counts = EquilibriumCounts {
        members,
        free_dofs: n,
        rank,
        self_stress_states: members - rank.min(members),
        mechanisms,
    };
    (counts, factor)
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
