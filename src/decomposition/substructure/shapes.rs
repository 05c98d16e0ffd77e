//! Substructures of one shape share the pattern of K_E and its symbolic analysis: a grid's
//! interior substructures are translates of one another (the same local links on the same
//! local dofs), so their patterns are equal and one fill-reducing analysis serves them all.
//! On 256 × 256 modules with 1024 substructures the patterns and analyses, one per
//! substructure, were 550 MB of the 2.34 GB heap; there are a handful of shapes.

use crate::linalg::{NotPositiveDefinite, SparseCholesky, SpdSolver, StiffnessPattern};
use faer::Par;
use std::sync::{Arc, Mutex};

/// The shapes met so far while substructures are built (in parallel): each distinct pattern
/// once, with a factorization workspace on its symbolic analysis when it is factorised sparse.
#[derive(Default)]
pub struct Shapes {
    seen: Mutex<Vec<Shape>>,
}

struct Shape {
    pattern: Arc<StiffnessPattern>,
    /// A workspace on the shape's analysis, shared from ([`SparseCholesky::share_symbolic`]).
    analysed: Option<SparseCholesky>,
}

impl Shapes {
    /// The shared pattern equal to `pattern`, and the factor of `values` on it: on the
    /// shape's symbolic analysis when the factor is sparse (the analysis made by the first
    /// substructure of the shape), else [`SpdSolver::new`]'s dense inverse.
    pub fn factor(
        &self,
        pattern: StiffnessPattern,
        values: &[f64],
        dense: bool,
    ) -> Result<(Arc<StiffnessPattern>, SpdSolver), NotPositiveDefinite> {
        let sparse = SpdSolver::is_sparse(pattern.n, dense);
        let (pattern, factor) = {
            // A poisoned lock only means another build panicked; its shapes are whole.
            let mut seen = self.seen.lock().unwrap_or_else(|p| p.into_inner());
            match seen.iter().find(|s| *s.pattern == pattern) {
                Some(shape) => (
                    Arc::clone(&shape.pattern),
                    shape.analysed.as_ref().map(SparseCholesky::share_symbolic),
                ),
                None => {
                    let pattern = Arc::new(pattern);
                    let analysed = sparse.then(|| SparseCholesky::analyse(&pattern, Par::Seq));
                    let factor = analysed.as_ref().map(SparseCholesky::share_symbolic);
                    seen.push(Shape {
                        pattern: Arc::clone(&pattern),
                        analysed,
                    });
                    (pattern, factor)
                }
            }
        };
        let solver = match factor {
            Some(mut factor) => {
                factor.factorize(&pattern, values)?;
                SpdSolver::Sparse(factor)
            }
            None => SpdSolver::new(&pattern, values, dense)?,
        };
        Ok((pattern, solver))
    }
}
