//! r(U) of the linear stage's U substructure by substructure (docs/method.md §6): each
//! substructure's links give their forces on its own dofs, in parallel and in cache; the
//! pieces are then summed over the substructures holding each dof, in their order (the same
//! sums on any number of threads). Every link belongs to one substructure, so this is
//! `Bᵀτ(U) − F` term by term, grouped by substructure.

use super::{Latin, Substructure};
use crate::linalg::norm;
use crate::structure::law;
use crate::structure::Structure;
use rayon::prelude::*;

/// One substructure's links' forces on its dofs (E's numbering).
struct LinkForces {
    /// `B_Eᵀ τ(U)` under the exact law.
    exact: Vec<f64>,
    /// `Σ |B_E| |τ|`, the scale of r(U).
    size: Vec<f64>,
    /// `B_Eᵀ (τ_frozen − τ)`: what the law linearised at the status changes (mostly zero).
    frozen_change: Vec<f64>,
}

impl Substructure {
    /// E's links' forces at the global displacements `u` (interface nodes averaged): under
    /// the exact law `τ = max(0, t0 + k e)` on unilateral cables, and the change to the law
    /// linearised at `slack` (`τ = t0 + k e` of either sign, 0 on the cables slack in it).
    fn link_forces(&self, structure: &Structure, u: &[f64], slack: &[bool]) -> LinkForces {
        let n = self.dof_global.len();
        let mut out = LinkForces {
            exact: vec![0.0; n],
            size: vec![0.0; n],
            frozen_change: vec![0.0; n],
        };
        for (row, &i) in self.link_dofs.iter().zip(&self.links) {
            let link = &structure.links[i];
            // e = B U on the initial geometry, with U read through E's dof map.
            let e: f64 = row.iter().map(|(d, c)| c * u[self.dof_global[d]]).sum();
            let trial = law::trial_tension(link, e);
            let t = law::tension(link, trial);
            let frozen = if slack[i] { 0.0 } else { trial };
            for (d, c) in row.iter() {
                out.exact[d] += c * t;
                out.size[d] += (c * t).abs();
            }
            if frozen != t {
                row.scatter(frozen - t, &mut out.frozen_change);
            }
        }
        out
    }
}

impl Latin<'_> {
    /// `(r(U), r_frozen(U))` as [`crate::solvers::exact_and_frozen_residuals`] defines them
    /// (the exact law, and the law linearised at `slack`, both relative to
    /// `‖F‖ + ‖|B|ᵀ|τ|‖`), with the links' forces computed substructure by substructure. For
    /// models without the prestress's geometric stiffness (the caller checks).
    pub(super) fn residuals_by_substructure(
        &self,
        u: &[f64],
        load: &[f64],
        slack: &[bool],
    ) -> (f64, f64) {
        let s = self.structure;
        let pieces: Vec<LinkForces> = self
            .substructures
            .par_iter()
            .with_min_len(self.chunk)
            .map(|sub| sub.link_forces(s, u, slack))
            .collect();
        // Summed over the substructures in their order.
        let n = s.n_free;
        let (mut r, mut size, mut change) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for (sub, piece) in self.substructures.iter().zip(&pieces) {
            for (k, &d) in sub.dof_global.iter().enumerate() {
                r[d] += piece.exact[k];
                size[d] += piece.size[k];
                change[d] += piece.frozen_change[k];
            }
        }
        // r = Bᵀτ − F; r_frozen = r + Bᵀ(τ_frozen − τ).
        r.iter_mut().zip(load).for_each(|(ri, fi)| *ri -= fi);
        let frozen: Vec<f64> = r.iter().zip(&change).map(|(a, b)| a + b).collect();
        let scale = norm(load) + norm(&size);
        let relative = |v: &[f64]| {
            let v = norm(v);
            if scale > 0.0 {
                v / scale
            } else {
                v
            }
        };
        (relative(&r), relative(&frozen))
    }
}
