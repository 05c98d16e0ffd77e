//! The tangent stiffness of the model (docs/method.md §3, §8): on the initial geometry
//! `Σ_taut k Bᵢᵀ Bᵢ`, plus with geometric stiffness the prestress's `K_G(t0)`; at an answer,
//! the tangent its stability and uniqueness are judged by.

use super::large::CurrentGeometry;
use super::prestress::GeometricStiffness;
use super::{Kinematics, Model};
use crate::linalg::{par_zip_map, RowChunks, StiffnessPattern};
use std::borrow::Cow;

impl Model {
    /// `K_G(t0)` when the model has geometric stiffness: the prestress model's own, or with
    /// `large` that of its tangent at the prestressed state (U = 0), built here.
    fn initial_geometric_stiffness(&self) -> Option<Cow<'_, GeometricStiffness>> {
        match &self.kinematics {
            Kinematics::Linear => None,
            Kinematics::Prestress(g) => Some(Cow::Borrowed(g)),
            Kinematics::Large => Some(Cow::Owned(GeometricStiffness::of_prestress(
                &self.structure,
            ))),
        }
    }

    /// `values = Σ_taut k Bᵢᵀ Bᵢ + K_G(t0)` (the tangent stiffness on the initial geometry on
    /// the taut set, `K_G(t0)` with geometric stiffness: docs/method.md §3, §8), lower
    /// triangle on `pattern`, built from the structure's link rows.
    pub fn assemble_tangent(
        &self,
        pattern: &StiffnessPattern,
        taut: impl Fn(usize) -> bool,
        values: &mut [f64],
    ) {
        let s = &self.structure;
        pattern.assemble(
            &s.link_dofs,
            |i| if taut(i) { s.links[i].stiffness } else { 0.0 },
            values,
        );
        if let Some(g) = self.initial_geometric_stiffness() {
            g.add_to(pattern, values);
        }
    }

    /// `out = (Σ_taut k Bᵢᵀ Bᵢ + K_G(t0)) v + μ v`, link by link ([`Model::assemble_tangent`]'s
    /// matrix).
    pub fn tangent_product(&self, taut: &[bool], mu: f64, v: &[f64], out: &mut [f64]) {
        let s = &self.structure;
        out.iter_mut().zip(v).for_each(|(o, vi)| *o = mu * vi);
        for ((link, row), _) in s
            .links
            .iter()
            .zip(&s.link_dofs)
            .zip(taut)
            .filter(|(_, &taut)| taut)
        {
            row.scatter(link.stiffness * row.elongation(v), out);
        }
        if let Some(g) = self.initial_geometric_stiffness() {
            g.apply_add(v, out);
        }
    }

    /// [`Model::tangent_product`] with the links' part over `chunks` of the structure's link
    /// rows side by side (`src/linalg/row_chunks.rs`: the same bits on any number of threads,
    /// round-off apart from the link-by-link product).
    pub fn tangent_product_chunked(
        &self,
        chunks: &mut RowChunks,
        taut: &[bool],
        mu: f64,
        v: &[f64],
        out: &mut [f64],
    ) {
        let s = &self.structure;
        par_zip_map(out, v, v, |vi, _| mu * vi);
        let weight = |i: usize| if taut[i] { s.links[i].stiffness } else { 0.0 };
        chunks.product_add(weight, v, out);
        if let Some(g) = self.initial_geometric_stiffness() {
            g.apply_add(v, out);
        }
    }

    /// The tangent at an answer (displacements `u`, tensions `tensions`) over the members
    /// `carrying` force, into `values` on `pattern`: `Σ_carrying k Bᵢᵀ Bᵢ` on the initial
    /// geometry, plus with `prestress` the geometric stiffness of the answer's own tensions
    /// `K_G(τ)` (a slack cable has none: docs/method.md §8; issue 42, D6), or with `large` the
    /// Hessian of the exact-length energy on the current geometry (a member not carrying force
    /// given neither stiffness nor force).
    pub fn assemble_answer_tangent(
        &self,
        u: &[f64],
        tensions: &[f64],
        carrying: impl Fn(usize) -> bool,
        pattern: &StiffnessPattern,
        values: &mut [f64],
    ) {
        let s = &self.structure;
        match self.kinematics {
            Kinematics::Large => {
                let current = CurrentGeometry::of(s, u);
                // A negative trial tension gives a cable neither stiffness nor force.
                let trial: Vec<f64> = current
                    .trial_tensions(s)
                    .into_iter()
                    .enumerate()
                    .map(|(i, t)| if carrying(i) { t } else { -1.0 })
                    .collect();
                current.assemble_tangent(s, &trial, pattern, values);
            }
            Kinematics::Prestress(_) => {
                pattern.assemble(
                    &s.link_dofs,
                    |i| {
                        if carrying(i) {
                            s.links[i].stiffness
                        } else {
                            0.0
                        }
                    },
                    values,
                );
                GeometricStiffness::of_tensions(s, tensions).add_to(pattern, values);
            }
            Kinematics::Linear => self.assemble_tangent(pattern, carrying, values),
        }
    }

    /// The tangent a natural mode is taken on, at an answer (`u`, `tensions`) over the members
    /// `carrying` force: with `large` the exact energy's Hessian there
    /// ([`Model::assemble_answer_tangent`]), on the initial geometry the model's own
    /// ([`Model::assemble_tangent`]: `K`, plus `K_G(t0)` with `prestress`).
    pub fn assemble_modal_tangent(
        &self,
        u: &[f64],
        tensions: &[f64],
        carrying: impl Fn(usize) -> bool,
        pattern: &StiffnessPattern,
        values: &mut [f64],
    ) {
        match self.kinematics {
            Kinematics::Large => {
                self.assemble_answer_tangent(u, tensions, carrying, pattern, values)
            }
            Kinematics::Linear | Kinematics::Prestress(_) => {
                self.assemble_tangent(pattern, carrying, values)
            }
        }
    }
}
