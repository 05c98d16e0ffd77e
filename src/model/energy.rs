//! The members' energy along a direction (docs/method.md §1, §8): its slope, the work of the
//! tensions on a change of U, and the terms the prestress's geometric stiffness adds to it.

use super::large;
use super::material::{tension, trial_tension};
use super::{Kinematics, Model};
use crate::linalg::dot;

impl Model {
    /// `K_G(t0) U`, the prestress's geometric force, with `prestress`; `None` otherwise.
    pub fn prestress_force(&self, u: &[f64]) -> Option<Vec<f64>> {
        self.prestress_stiffness().map(|g| g.product(u))
    }

    /// `(dᵀ K_G(t0) U, dᵀ K_G(t0) d)`: what the prestress's geometric stiffness adds to the
    /// energy along the step d from U, `φ(s) = Π(U + s d)` gaining `s dᵀK_G U + ½ s² dᵀK_G d`
    /// (docs/method.md §8); zeros without it.
    pub fn prestress_energy_along(&self, u: &[f64], d: &[f64]) -> (f64, f64) {
        self.prestress_stiffness()
            .map_or((0.0, 0.0), |g| (dot(&g.product(u), d), g.quadratic(d)))
    }

    /// The slope along d of the members' energy at displacements U, the work of the tensions
    /// at U on the change d: `∇Π(U)·d` less the load's `F·d`, without assembling the
    /// gradient. `Σ τ Bᵢ·d` (plus `dᵀ K_G U` with `prestress`) on the initial geometry,
    /// `Σ τ ∇ℓ·d` on the current one ([`large::internal_slope`]).
    pub fn internal_slope(&self, u: &[f64], d: &[f64]) -> f64 {
        let s = &self.structure;
        match &self.kinematics {
            Kinematics::Large => large::internal_slope(s, u, d),
            Kinematics::Linear | Kinematics::Prestress(_) => {
                // Σ τ(U) Bᵢ·d.
                let members: f64 = s
                    .links
                    .iter()
                    .zip(&s.link_dofs)
                    .map(|(l, row)| {
                        tension(l, trial_tension(l, row.elongation(u))) * row.elongation(d)
                    })
                    .sum();
                // + dᵀ K_G(t0) U with the prestress's geometric stiffness.
                members + self.prestress_force(u).map_or(0.0, |f| dot(&f, d))
            }
        }
    }

    /// The tension of link `i` at `tension` whose geometric stiffness the model leaves out
    /// (docs/method.md §8): all of τ on the initial geometry (`linear`), `τ − t0` with
    /// `prestress` (whose `K_G(t0)` is in); `large` leaves nothing out (0).
    pub fn tension_left_out(&self, i: usize, tension: f64) -> f64 {
        let s = &self.structure;
        match self.kinematics {
            Kinematics::Linear => tension,
            Kinematics::Prestress(_) => tension - s.given_prestress(&s.links[i]),
            Kinematics::Large => 0.0,
        }
    }
}
