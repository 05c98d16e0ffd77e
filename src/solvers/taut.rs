//! The stiffness with every cable taut, `K = Bᵀ k B` on the free dofs (SPEC §2–3), factorized
//! once per structure and shared by the solvers; building it is where a mechanism is refused.

use super::SetupError;
use crate::linalg::{
    smallest_eigenvalue_bound, zero_mode_count, SparseCholesky, StiffnessPattern,
    ZERO_MODE_RELATIVE,
};
use crate::structure::Structure;
use faer::Par;

/// `K = Bᵀ k B` with every cable taut, its pattern (shared by every stiffness of the structure)
/// and its factor.
#[derive(Debug, Clone)]
pub struct TautStiffness {
    /// The pattern of K, which is also that of every tangent stiffness.
    pub pattern: StiffnessPattern,
    /// Lower triangle of K on `pattern`.
    pub values: Vec<f64>,
    /// Cholesky factor of K.
    pub factor: SparseCholesky,
}

impl TautStiffness {
    /// Assemble and factorize K; refuse a structure whose K is singular, with the number of
    /// its zero-stiffness modes.
    pub fn new(structure: &Structure) -> Result<TautStiffness, SetupError> {
        let pattern = StiffnessPattern::new(structure.n_free, &structure.link_dofs);
        let mut values = vec![0.0; pattern.nnz()];
        pattern.assemble(
            &structure.link_dofs,
            |i| structure.links[i].stiffness,
            &mut values,
        );
        let mut factor = SparseCholesky::analyse(&pattern, Par::Seq);
        let singular = match factor.factorize(&pattern, &values) {
            Err(_) => true,
            Ok(()) => {
                // A positive factorization may still hide a zero mode behind round-off
                // pivots: a few inverse iterations tell.
                smallest_eigenvalue_bound(&pattern, &values, &factor, 3)
                    < ZERO_MODE_RELATIVE * pattern.mean_diagonal(&values)
            }
        };
        if singular {
            let mut probe = factor.share_symbolic();
            let zero_modes = zero_mode_count(&pattern, &values, &mut probe).max(1);
            return Err(SetupError::Mechanism { zero_modes });
        }
        Ok(TautStiffness {
            pattern,
            values,
            factor,
        })
    }
}
