//! The model (docs/method.md §1, §8): a structure and the kinematics its members move by, as
//! one value. [`Model`] holds the [`Structure`] (topology, geometry, supports, loads) and its
//! [`Kinematics`] (`model.geometry`): equilibrium on the initial geometry (`linear`), plus the
//! prestress's geometric stiffness `K_G(t0)` (`prestress`), or on the current geometry
//! (`large`). Every quantity that depends on which (elongations, member states, the tangent,
//! the residual, the energy) is a method of it, so solvers and `results` take a `&Model` and
//! never ask which kinematics it is.
//!
//! | module | what |
//! |---|---|
//! | `material` | the member law: trial tension, tension, slack rules, tangent weight |
//! | `prestress` | `K_G(τ)`, the geometric stiffness of tensions on the initial geometry |
//! | `stability` | prestress stability: `Mᵀ K_G(t0) M` on the mechanisms |
//! | `large` | the current geometry of the `large` model |
//! | `members` | the members at displacements U: trial tensions, elongations, states |
//! | `tangent` | the tangent stiffness: assembly and product |
//! | `mass` | the members' mass matrix, consistent or lumped (the natural modes) |
//! | `residual` | the relative equilibrium residual r(U) |
//! | `unbalance` | `Bᵀτ − F` and its relative sizes |
//! | `energy` | the energy's slope along a direction, and its geometric terms |

mod energy;
mod large;
mod mass;
pub mod material;
mod members;
mod prestress;
mod residual;
mod stability;
mod tangent;
mod unbalance;

pub use large::{internal_slope, CurrentGeometry};
pub use mass::MassKind;
pub use members::MemberStates;
pub use prestress::{geometric_force, geometric_force_on, GeometricStiffness};
pub use stability::{
    indefinite_reason, largest_moving_nodes, prestress_stability, unit_slip_sentence,
    unit_slip_strain, Mode, PrestressStability, PRESTRESS_STRAIN_WARNING,
};
pub use unbalance::{relative_unbalance, unbalances, unbalances_on, Unbalances};

use crate::structure::Structure;
use serde::Deserialize;

/// Which geometric effects the model keeps: the case key `model.geometry`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GeometricModel {
    /// Equilibrium written on the initial geometry (docs/method.md §1, the paper's model).
    #[default]
    Linear,
    /// §1's model plus the geometric stiffness of the prestress, `K + K_G(t0)` (§8): the
    /// linearisation about the prestressed state; stiffens prestress-stable mechanisms.
    Prestress,
    /// The exact-length law `τ = t0 + k (ℓ − L)` on the current geometry, dead loads (§8),
    /// solved by Newton steps along the load path (every solver: [`crate::solvers::large`]).
    Large,
}

impl GeometricModel {
    /// The value of `model.geometry`.
    pub fn name(self) -> &'static str {
        match self {
            GeometricModel::Linear => "linear",
            GeometricModel::Prestress => "prestress",
            GeometricModel::Large => "large",
        }
    }

    /// What the model is, in a few words (`check`).
    pub fn description(self) -> &'static str {
        match self {
            GeometricModel::Linear => "equilibrium on the initial geometry",
            GeometricModel::Prestress => {
                "plus the geometric stiffness of the prestress, K + K_G(t0)"
            }
            GeometricModel::Large => {
                "the exact-length law on the current geometry, Newton steps along the load path"
            }
        }
    }

    /// Whether the model has geometric stiffness (so prestress-stable mechanisms are solvable).
    pub fn has_geometric_stiffness(self) -> bool {
        self != GeometricModel::Linear
    }

    /// Whether the model writes equilibrium on the current geometry (`large`): its answers
    /// are not bounded by the small-displacement domain, and nothing geometric is left out.
    pub fn updates_geometry(self) -> bool {
        self == GeometricModel::Large
    }
}

/// How the members move with the nodes: the geometric model as a value.
#[derive(Debug, Clone)]
pub enum Kinematics {
    /// Equilibrium on the initial geometry: `e = B U`.
    Linear,
    /// Equilibrium on the initial geometry with the prestress's geometric stiffness `K_G(t0)`,
    /// built once.
    Prestress(GeometricStiffness),
    /// Equilibrium on the current geometry: `e = ℓ(U) − L` ([`CurrentGeometry`]).
    Large,
}

/// A structure and its kinematics: what every solver solves.
#[derive(Debug, Clone)]
pub struct Model {
    /// Topology, geometry, supports and loads.
    pub structure: Structure,
    /// How its members move with the nodes.
    pub kinematics: Kinematics,
}

impl Model {
    /// `structure` under geometric model `geometry`: with `prestress`, `K_G(t0)` is built once
    /// here (docs/method.md §8).
    pub fn new(structure: Structure, geometry: GeometricModel) -> Model {
        let kinematics = match geometry {
            GeometricModel::Linear => Kinematics::Linear,
            GeometricModel::Prestress => {
                Kinematics::Prestress(GeometricStiffness::of_prestress(&structure))
            }
            GeometricModel::Large => Kinematics::Large,
        };
        Model {
            structure,
            kinematics,
        }
    }

    /// `structure` on its initial geometry (the paper's model).
    pub fn linear(structure: Structure) -> Model {
        Model::new(structure, GeometricModel::Linear)
    }

    /// `structure` linearised about its prestressed state, `K + K_G(t0)`.
    pub fn prestress(structure: Structure) -> Model {
        Model::new(structure, GeometricModel::Prestress)
    }

    /// The geometric model, as the case names it.
    pub fn geometry(&self) -> GeometricModel {
        match self.kinematics {
            Kinematics::Linear => GeometricModel::Linear,
            Kinematics::Prestress(_) => GeometricModel::Prestress,
            Kinematics::Large => GeometricModel::Large,
        }
    }

    /// Whether the model has geometric stiffness (`prestress`, `large`).
    pub fn has_geometric_stiffness(&self) -> bool {
        self.geometry().has_geometric_stiffness()
    }

    /// Whether the model writes equilibrium on the current geometry (`large`).
    pub fn updates_geometry(&self) -> bool {
        self.geometry().updates_geometry()
    }

    /// `K_G(t0)`, the prestress's geometric stiffness on the initial geometry, when the model
    /// linearises about the prestressed state (`prestress`); `None` otherwise.
    pub fn prestress_stiffness(&self) -> Option<&GeometricStiffness> {
        match &self.kinematics {
            Kinematics::Prestress(g) => Some(g),
            Kinematics::Linear | Kinematics::Large => None,
        }
    }

    /// The load the solvers take at α, on the free dofs: `α F`, less with `prestress` the
    /// geometric force of the prescribed displacements, `K_G,fd(t0) U_d` (docs/method.md §8:
    /// the linearisation `(K + K_G) U = F` on the whole U, settlement included, moves the
    /// held columns to the right-hand side; their axial part `K_fd U_d` is the links'
    /// effective prestress). Prescribed displacements are never scaled by α.
    pub fn load(&self, alpha: f64) -> Vec<f64> {
        let s = &self.structure;
        let mut load: Vec<f64> = s.unit_load.iter().map(|f| alpha * f).collect();
        if let Some(g) = self.prestress_stiffness() {
            g.add_settlement_force(s, -1.0, &mut load);
        }
        load
    }

    /// This model with only `links` of its structure ([`Structure::keeping_links`]), for an
    /// MPI rank's share; `None` with the prestress's geometric stiffness, which is kept for the
    /// whole structure only.
    pub fn keeping_links(&self, links: &[usize]) -> Option<Model> {
        match self.kinematics {
            Kinematics::Prestress(_) => None,
            Kinematics::Linear | Kinematics::Large => Some(Model {
                structure: self.structure.keeping_links(links),
                kinematics: self.kinematics.clone(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Model;
    use crate::structure::{GridSpec, LoadPattern, Structure};

    /// The kept links are the world's, in the order asked, with their rows of B; every nodal
    /// quantity is the world's.
    #[test]
    fn kept_links_are_the_worlds_in_the_order_asked() {
        let s = Structure::grid(&GridSpec::default(), &LoadPattern::default());
        let keep: Vec<usize> = (0..s.links.len()).rev().filter(|i| i % 3 == 1).collect();
        let model = Model::linear(s.clone());
        let kept = model.keeping_links(&keep).expect("no geometric stiffness");
        let kept = &kept.structure;
        assert_eq!(kept.links.len(), keep.len());
        for (j, &i) in keep.iter().enumerate() {
            let (a, b) = (&kept.links[j], &s.links[i]);
            assert_eq!((a.id, a.a, a.b, a.module), (b.id, b.a, b.b, b.module));
            assert_eq!(a.stiffness.to_bits(), b.stiffness.to_bits());
            assert_eq!(a.prestress.to_bits(), b.prestress.to_bits());
            assert_eq!(kept.kind_name(j), s.kind_name(i));
            let u: Vec<f64> = (0..s.n_free).map(|d| (d as f64 * 0.37).sin()).collect();
            assert_eq!(
                kept.link_dofs[j].elongation(&u).to_bits(),
                s.link_dofs[i].elongation(&u).to_bits()
            );
        }
        assert_eq!(kept.n_free, s.n_free);
        assert_eq!(kept.nodes, s.nodes);
        assert_eq!(kept.dof_of, s.dof_of);
        assert_eq!(kept.unit_load, s.unit_load);
        assert!(s.links.len() > 3 * kept.links.len() - 3);
        // The prestress's geometric stiffness belongs to the whole structure: not kept.
        let prestressed = Model::prestress(s);
        assert!(prestressed.keeping_links(&keep).is_none());
    }
}
