//! Every substructure's own stiffness, factorised, and solved batched: `x_E = K_E⁻¹ b_E` for
//! every E in one call ([`SubstructureSolves`]), the seam where a GPU's batched factor can go.

use super::{holders, LocalDofs, Shapes};
use crate::decomposition::Partition;
use crate::linalg::{SpdSolver, StiffnessPattern};
use crate::structure::{Structure, CLAMPED};
use rayon::prelude::*;
use std::sync::Arc;

/// Solves with every substructure's local operator, all at once.
pub trait SubstructureSolves: Sync {
    /// The number of substructures.
    fn substructures(&self) -> usize;

    /// `rhs[E] ← K_E⁻¹ rhs[E]` for every substructure E (`rhs[E]` on E's local dofs).
    fn solve_each(&self, rhs: &mut [Vec<f64>]);
}

/// Every substructure's `K_E = B_Eᵀ w B_E + diag(s_E)` on its own dofs, factorised (those of one
/// shape on one symbolic analysis), with the dofs it is on.
pub struct SubstructureFactors {
    /// E's own dofs, per substructure.
    pub dofs: Vec<LocalDofs>,
    /// K_E's pattern, shared by the substructures of E's shape.
    pub patterns: Vec<Arc<StiffnessPattern>>,
    /// K_E's values on its pattern.
    pub values: Vec<Vec<f64>>,
    factors: Vec<SpdSolver>,
}

/// Why the substructures' factors could not be made: K_E of substructure `index` is not
/// positive definite (a substructure left floating, or a mechanism of its own).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SingularLocalProblem {
    /// The first such substructure.
    pub index: usize,
}

impl SubstructureFactors {
    /// `K_E = B_Eᵀ w B_E + diag(s_E)` of every substructure of `partition`, in parallel: `weight`
    /// gives each (global) link's w, `shift(E, local dof)` each dof's s_E (0 for a Neumann
    /// problem; a positive shift on the dofs E shares makes a floating substructure's operator
    /// definite). `dense`: as [`SpdSolver::new`]. A K_E that is not positive definite is
    /// refused, never factorised approximately.
    pub fn new(
        structure: &Structure,
        partition: &Partition,
        weight: impl Fn(usize) -> f64 + Sync,
        shift: impl Fn(usize, usize) -> f64 + Sync,
        dense: bool,
    ) -> Result<SubstructureFactors, SingularLocalProblem> {
        let holders = holders(partition, structure.n_nodes());
        let shapes = Shapes::default();
        type Built = (LocalDofs, Arc<StiffnessPattern>, Vec<f64>, SpdSolver);
        let built: Vec<Result<Built, usize>> = partition
            .substructures
            .par_iter()
            .enumerate()
            .map_init(
                || vec![CLAMPED; 3 * structure.n_nodes()],
                |scratch, (e, topo)| {
                    let dofs = LocalDofs::number(topo, structure, &holders, scratch);
                    LocalDofs::clear(topo, scratch);
                    // K_E = B_Eᵀ w B_E + diag(s_E).
                    let pattern = StiffnessPattern::new(dofs.len(), &dofs.link_dofs);
                    let mut values = vec![0.0; pattern.nnz()];
                    pattern.assemble(&dofs.link_dofs, |j| weight(topo.links[j]), &mut values);
                    for d in 0..dofs.len() {
                        values[pattern.diag_slot[d]] += shift(e, d);
                    }
                    let (pattern, factor) =
                        shapes.factor(pattern, &values, dense).map_err(|_| e)?;
                    Ok((dofs, pattern, values, factor))
                },
            )
            .collect();
        let mut factors = SubstructureFactors {
            dofs: Vec::with_capacity(built.len()),
            patterns: Vec::with_capacity(built.len()),
            values: Vec::with_capacity(built.len()),
            factors: Vec::with_capacity(built.len()),
        };
        for b in built {
            let (dofs, pattern, values, factor) =
                b.map_err(|index| SingularLocalProblem { index })?;
            factors.dofs.push(dofs);
            factors.patterns.push(pattern);
            factors.values.push(values);
            factors.factors.push(factor);
        }
        Ok(factors)
    }

    /// `y = K_E x` on E's dofs.
    pub fn apply(&self, e: usize, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        self.patterns[e].sym_matvec(&self.values[e], x, &mut y);
        y
    }
}

impl SubstructureSolves for SubstructureFactors {
    fn substructures(&self) -> usize {
        self.factors.len()
    }

    fn solve_each(&self, rhs: &mut [Vec<f64>]) {
        rhs.par_iter_mut()
            .zip(&self.factors)
            .for_each(|(b, factor)| factor.solve_in_place(b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::WeakInterfaces;
    use crate::structure::{GridSpec, LoadPattern};

    fn grid(n: usize) -> Structure {
        let spec = GridSpec {
            modules: [n, n],
            ..GridSpec::default()
        };
        Structure::grid(&spec, &LoadPattern::default())
    }

    /// The load shares of the substructures holding a dof sum to 1: `Σ_E R_Eᵀ D_E R_E = I`.
    #[test]
    fn load_shares_are_a_partition_of_unity() {
        let s = grid(6);
        let partition = Partition::new(&s, [3, 2], WeakInterfaces::Macro);
        let factors =
            SubstructureFactors::new(&s, &partition, |i| s.links[i].stiffness, |_, _| 1.0, false)
                .unwrap();
        let mut sum = vec![0.0; s.n_free];
        for dofs in &factors.dofs {
            dofs.prolong_add(&dofs.load_share, &mut sum);
        }
        assert!(sum.iter().all(|&v| (v - 1.0).abs() < 1e-15), "{sum:?}");
        // Every free dof is some substructure's, and a shared one several's.
        let shared = factors.dofs.iter().map(LocalDofs::len).sum::<usize>() - s.n_free;
        assert!(shared > 0);
    }

    /// Batched solves: `K_E x_E = b_E` to round-off on every substructure, dense and sparse
    /// factors alike, and R_E then R_Eᵀ gives back a vector on E's dofs.
    #[test]
    fn every_substructure_is_solved_to_round_off() {
        let s = grid(8);
        let partition = Partition::new(&s, [2, 2], WeakInterfaces::Macro);
        for dense in [false, true] {
            let mean_k = s.links.iter().map(|l| l.stiffness).sum::<f64>() / s.links.len() as f64;
            let factors = SubstructureFactors::new(
                &s,
                &partition,
                |i| s.links[i].stiffness,
                |_, _| 1e-3 * mean_k,
                dense,
            )
            .unwrap();
            assert_eq!(factors.substructures(), 4);
            let global: Vec<f64> = (0..s.n_free)
                .map(|d| ((d * 7919) % 97) as f64 - 48.0)
                .collect();
            let rhs: Vec<Vec<f64>> = factors.dofs.iter().map(|d| d.restrict(&global)).collect();
            let mut x = rhs.clone();
            factors.solve_each(&mut x);
            for (e, (x, b)) in x.iter().zip(&rhs).enumerate() {
                let r = factors.apply(e, x);
                let err = r
                    .iter()
                    .zip(b)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    err <= 1e-10 * norm,
                    "E{e} dense={dense}: {err:e} / {norm:e}"
                );
            }
        }
    }

    /// A floating substructure's Neumann operator (no shift) is singular: refused, with that
    /// substructure named, never factorised approximately; shifted, the same one is factorised.
    #[test]
    fn a_singular_local_problem_is_refused() {
        let s = grid(6);
        let partition = Partition::new(&s, [3, 1], WeakInterfaces::Macro);
        // The grid is clamped on its lower x edges: the middle substructure floats.
        let floating = partition
            .substructures
            .iter()
            .position(|t| t.clamped_nodes.is_empty())
            .expect("a substructure off the clamped edges");
        assert_eq!(floating, 1);
        let k = |i: usize| s.links[i].stiffness;
        let neumann_on = |e: usize| move |sub: usize, _| if sub == e { 0.0 } else { 1.0 };
        let refused = SubstructureFactors::new(&s, &partition, k, neumann_on(floating), false);
        assert_eq!(
            refused.err(),
            Some(SingularLocalProblem { index: floating })
        );
        let shifted = SubstructureFactors::new(&s, &partition, k, |_, _| 1.0, false);
        assert!(shifted.is_ok());
    }
}
