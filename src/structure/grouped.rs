//! The grouped self-stress states (docs/method.md §7, "Designing a prestress"): the
//! prestresses uniform on each member group that are in equilibrium at the free dofs, the null
//! space of `A·G` (A = Bᵀ the equilibrium matrix, free dofs × members; G the member → group
//! incidence, members × groups). With few groups `A·G` is tall and thin: its columns are
//! summed sparsely, row by row of B, and its SVD is a small dense one.

use super::Structure;
use faer::Mat;

/// A singular value of the equilibrium-normalised `A·G` at or below this fraction of the
/// largest counts as zero (the rank decision; the SVD's round-off is about 1e-16 times the
/// largest, a 1 mm rounding of metre coordinates about 1e-3).
pub const RANK_RELATIVE: f64 = 1e-9;

/// The most entries the dense `A·G` takes (free dofs × groups, 8 bytes each: 400 MB).
pub const GROUPED_MAX_ENTRIES: usize = 50_000_000;

/// The grouped self-stress states of a structure.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupedStates {
    /// An orthonormal basis of the states: s₂ vectors of one force per group, N (unscaled).
    pub basis: Vec<Vec<f64>>,
    /// The singular values of `A·G` with unit columns, decreasing (min(free dofs, groups)).
    pub singular: Vec<f64>,
    /// The rank decision: the smallest singular value kept and the largest counted as zero,
    /// each relative to the largest (`None` where there is none).
    pub gap: (Option<f64>, Option<f64>),
}

impl GroupedStates {
    /// s₂: the number of grouped self-stress states.
    pub fn count(&self) -> usize {
        self.basis.len()
    }
}

/// Why the grouped states cannot be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GroupedRefusal {
    /// `A·G` would hold more than [`GROUPED_MAX_ENTRIES`]: (free dofs, groups).
    TooLarge(usize, usize),
    /// The SVD did not converge.
    NoConvergence,
}

/// The null space of `A·G` for `structure` with member `j` in group `group_of[j]` (`groups`
/// groups). The columns are scaled to unit norm first (a group of many members has a long
/// column; scaling changes no null vector's support), and the basis scaled back.
pub fn grouped_states(
    structure: &Structure,
    group_of: &[usize],
    groups: usize,
) -> Result<GroupedStates, GroupedRefusal> {
    let n = structure.n_free;
    if n.saturating_mul(groups) > GROUPED_MAX_ENTRIES {
        return Err(GroupedRefusal::TooLarge(n, groups));
    }
    // (A·G)[d, k] = Σ_{j in group k} A[d, j]: each member's row of B added to its group's column.
    let mut ag = Mat::<f64>::zeros(n, groups);
    for (j, row) in structure.link_dofs.iter().enumerate() {
        for (d, c) in row.iter() {
            ag[(d, group_of[j])] += c;
        }
    }
    let norms: Vec<f64> = (0..groups)
        .map(|k| (0..n).map(|d| ag[(d, k)] * ag[(d, k)]).sum::<f64>().sqrt())
        .collect();
    // A group loading no free dof (its members between held nodes) is a state of its own.
    let zero_columns: Vec<usize> = (0..groups).filter(|&k| norms[k] == 0.0).collect();
    let live: Vec<usize> = (0..groups).filter(|&k| norms[k] > 0.0).collect();
    let scaled = Mat::<f64>::from_fn(n, live.len(), |d, c| ag[(d, live[c])] / norms[live[c]]);
    let (singular, null) = null_space(&scaled)?;
    let largest = singular.first().copied().unwrap_or(0.0);
    let rank = singular
        .iter()
        .filter(|&&x| x > RANK_RELATIVE * largest)
        .count();
    let relative = |x: f64| if largest > 0.0 { x / largest } else { 0.0 };
    let gap = (
        rank.checked_sub(1).map(|i| relative(singular[i])),
        singular.get(rank).map(|&x| relative(x)),
    );
    // The null space: V's columns from `rank` on, scaled back (x = D⁻¹ y), then orthonormal.
    let mut basis: Vec<Vec<f64>> = (rank..live.len())
        .map(|c| {
            let mut x = vec![0.0; groups];
            for (r, &k) in live.iter().enumerate() {
                x[k] = null[(r, c)] / norms[k];
            }
            x
        })
        .collect();
    basis.extend(zero_columns.iter().map(|&k| {
        let mut x = vec![0.0; groups];
        x[k] = 1.0;
        x
    }));
    orthonormalise(&mut basis);
    Ok(GroupedStates {
        basis,
        singular,
        gap,
    })
}

/// The singular values (decreasing) and the right singular vectors V (every column) of `m`.
fn null_space(m: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>), GroupedRefusal> {
    let (rows, cols) = (m.nrows(), m.ncols());
    if cols == 0 {
        return Ok((Vec::new(), Mat::zeros(0, 0)));
    }
    if rows == 0 {
        return Ok((Vec::new(), Mat::identity(cols, cols)));
    }
    // Tall: the thin SVD has every column of V; wide: the full one.
    let svd = if rows >= cols { m.thin_svd() } else { m.svd() }
        .map_err(|_| GroupedRefusal::NoConvergence)?;
    let s = svd.S().column_vector();
    let singular: Vec<f64> = (0..rows.min(cols)).map(|i| s[i]).collect();
    Ok((singular, svd.V().to_owned()))
}

/// Gram–Schmidt (twice) on `basis`, in place: the scaled-back null vectors are no longer
/// orthonormal.
fn orthonormalise(basis: &mut [Vec<f64>]) {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    for i in 0..basis.len() {
        for _ in 0..2 {
            for k in 0..i {
                let p = dot(&basis[i], &basis[k]);
                let (done, rest) = basis.split_at_mut(i);
                rest[0]
                    .iter_mut()
                    .zip(&done[k])
                    .for_each(|(x, y)| *x -= p * y);
            }
        }
        let norm = dot(&basis[i], &basis[i]).sqrt();
        basis[i].iter_mut().for_each(|x| *x /= norm);
    }
}
