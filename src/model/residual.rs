//! The relative equilibrium residual (docs/method.md §6): the unbalance of the nodal forces
//! against the forces meeting at the nodes. [`Model::residual`] is the one reference-free
//! measure every solver shares: newton stops on it, the LATIN solvers may, and every summary
//! row reports it.

use super::large::CurrentGeometry;
use super::material::tension;
use super::unbalance::{unbalances_on, Unbalances};
use super::{Kinematics, Model};
use crate::linalg::norm;

impl Model {
    /// r(U): the relative equilibrium residual of displacements U under the exact law of the
    /// model (docs/method.md §1, §8): `τ(U) = t0 + k B U` (plus `K_G U` with the prestress's
    /// geometric stiffness), or `t0 + k (ℓ(U) − L)` along the current `∇ℓ` (large
    /// displacements); clipped at 0 for unilateral cables. Zero exactly at the solution.
    pub fn residual(&self, u: &[f64], load: &[f64]) -> f64 {
        self.unbalance_sizes(u, load).relative
    }

    /// r(U) and r_F(U), the same unbalance relative to the forces the load brings into play
    /// ([`Unbalances`]): what the stop every solver shares reads ([`crate::solvers::Balance`]).
    pub fn unbalance_sizes(&self, u: &[f64], load: &[f64]) -> Unbalances {
        let s = &self.structure;
        let mut r = vec![0.0; s.n_free];
        match self.kinematics {
            Kinematics::Large => {
                let current = CurrentGeometry::of(s, u);
                current.unbalances(s, load, &mut r).1
            }
            Kinematics::Linear | Kinematics::Prestress(_) => {
                self.small_unbalances(u, load, &mut r).2
            }
        }
    }

    /// `r ← Bᵀτ(U) (+ K_G U) − F` under the exact law on the initial geometry, with the trial
    /// tensions `t0 + k B U`, the tensions and the sizes of r.
    fn small_unbalances(
        &self,
        u: &[f64],
        load: &[f64],
        r: &mut [f64],
    ) -> (Vec<f64>, Vec<f64>, Unbalances) {
        let s = &self.structure;
        let trial = self.trial_tensions(u);
        let tensions: Vec<f64> = trial
            .iter()
            .zip(&s.links)
            .map(|(&t, l)| tension(l, t))
            .collect();
        let geometric_force = self.prestress_force(u);
        let sizes = unbalances_on(
            s,
            &s.link_dofs,
            &tensions,
            geometric_force.as_deref(),
            load,
            r,
        );
        (trial, tensions, sizes)
    }

    /// `(r(U) and r_F(U), r_frozen(U))`: r(U), and the residual under the law linearised at a slack
    /// status (docs/method.md §9, the inner problem of a status step: `τ = t0 + k e` of either
    /// sign on bars and on the cables taut in `slack`, `τ = 0` on the cables slack in it)
    /// relative to the same scale as r(U), in one pass over the links and a correction on the
    /// cables where the two laws differ. The small-displacement models only.
    pub fn exact_and_frozen_residuals(
        &self,
        u: &[f64],
        load: &[f64],
        slack: &[bool],
    ) -> (Unbalances, f64) {
        let s = &self.structure;
        let mut r = vec![0.0; s.n_free];
        let (trial, tensions, exact) = self.small_unbalances(u, load, &mut r);
        for (i, row) in s.link_dofs.iter().enumerate() {
            let frozen = if slack[i] { 0.0 } else { trial[i] };
            let change = frozen - tensions[i];
            if change != 0.0 {
                for (d, c) in row.iter() {
                    r[d] += c * change;
                }
            }
        }
        let r_norm = norm(&r);
        let frozen = if exact.scale > 0.0 {
            r_norm / exact.scale
        } else {
            r_norm
        };
        (exact, frozen)
    }
}
