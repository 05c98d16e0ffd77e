//! The energy error e of an iterate against a reference solution (paper §5.3, docs/method.md §4):
//! `e² = Σ_links k (e_i − e_i^ref)² / Σ_links k (e_i^ref)²`, with `e = B U` the link
//! elongations (`ℓ − L` with `model.geometry = "large"`) and k the link stiffness; absolute (no denominator) when the reference strains
//! nothing. This is the one implementation of e: the driver measures it on every iterate of
//! every solver when a solve is given a [`Reference`].
//!
//! The paper weighs by the LATIN search direction l; with the default `l = k` the two agree, and the
//! stiffness makes e a property of the iterate alone, comparable across solvers and settings.

use crate::model::Model;

/// A reference solution, as e needs it.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Link stiffness k, N/m.
    stiffness: Vec<f64>,
    /// `B U_ref`.
    elongations: Vec<f64>,
    /// `Σ k (B U_ref)²`.
    energy: f64,
}

impl Reference {
    /// The reference displacements `displacements` (free dofs) of `model`, its elongations
    /// under that model (`ℓ − L` with `large`, as its solver reports them).
    pub fn new(model: &Model, displacements: &[f64]) -> Reference {
        let elongations = model.elongations(displacements);
        let stiffness: Vec<f64> = model.structure.links.iter().map(|l| l.stiffness).collect();
        let energy = weighted_norm2(&stiffness, elongations.iter().copied());
        Reference {
            stiffness,
            elongations,
            energy,
        }
    }

    /// e of an iterate whose link elongations are `elongations`.
    pub fn error(&self, elongations: &[f64]) -> f64 {
        let difference = elongations
            .iter()
            .zip(&self.elongations)
            .map(|(e, r)| e - r);
        let distance = weighted_norm2(&self.stiffness, difference);
        if self.energy > 0.0 {
            (distance / self.energy).sqrt()
        } else {
            distance.sqrt()
        }
    }
}

/// `Σ k e²`.
fn weighted_norm2(stiffness: &[f64], elongations: impl Iterator<Item = f64>) -> f64 {
    stiffness
        .iter()
        .zip(elongations)
        .map(|(k, e)| k * e * e)
        .sum()
}
