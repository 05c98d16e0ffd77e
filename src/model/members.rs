//! The members at displacements U as the model sees them: their trial tensions, elongations,
//! and for reporting their lengths and the unit vectors their forces act along — on the
//! initial geometry (`linear`, `prestress`) or the current one (`large`).

use super::large::CurrentGeometry;
use super::material::trial_tension;
use super::{Kinematics, Model};
use crate::linalg::SparseRow;
use std::borrow::Cow;

/// The members at displacements U as the model sees them, for reporting (`forces/`, the
/// reactions): per link its elongation with the prescribed displacements included, its length,
/// and the unit vector its axial force acts along.
#[derive(Debug, Clone)]
pub struct MemberStates {
    /// Elongations, m: `n·(U_b − U_a)` on the initial geometry (the prescribed displacements'
    /// `e_p` included), `ℓ − L` with `large`.
    pub elongations: Vec<f64>,
    /// Lengths, m: the linearised `L + e` on the initial geometry, the current ℓ with `large`.
    pub lengths: Vec<f64>,
    /// Unit vectors from a to b the axial force acts along: the initial ones, or the current
    /// ones with `large`.
    pub directions: Vec<[f64; 3]>,
}

impl Model {
    /// The trial tension of every link at displacements U (free dofs): `t0 + k B U` on the
    /// initial geometry, `t0 + k (ℓ(U) − L)` on the current one (`large`).
    pub fn trial_tensions(&self, u: &[f64]) -> Vec<f64> {
        let s = &self.structure;
        match self.kinematics {
            Kinematics::Large => CurrentGeometry::of(s, u).trial_tensions(s),
            Kinematics::Linear | Kinematics::Prestress(_) => s
                .links
                .iter()
                .zip(&s.link_dofs)
                .map(|(l, ld)| trial_tension(l, ld.elongation(u)))
                .collect(),
        }
    }

    /// The elongation of every link at displacements U: `B U` on the initial geometry,
    /// `ℓ(U) − L` with `large` (what the energy error e is measured on).
    pub fn elongations(&self, u: &[f64]) -> Vec<f64> {
        let s = &self.structure;
        match self.kinematics {
            Kinematics::Large => CurrentGeometry::of(s, u).elongations,
            Kinematics::Linear | Kinematics::Prestress(_) => {
                s.link_dofs.iter().map(|row| row.elongation(u)).collect()
            }
        }
    }

    /// Per link, the row its elongation changes by along a change of U at U: its row of B on
    /// the initial geometry, `∇ℓ` on the current one (`large`).
    pub fn member_rows(&self, u: &[f64]) -> Cow<'_, [SparseRow]> {
        match self.kinematics {
            Kinematics::Large => Cow::Owned(CurrentGeometry::of(&self.structure, u).rows),
            Kinematics::Linear | Kinematics::Prestress(_) => {
                Cow::Borrowed(&self.structure.link_dofs)
            }
        }
    }

    /// The members' lengths on the current geometry at U with `large`; `None` on the initial
    /// geometry (`linear`, `prestress`: the initial lengths are the ones that count).
    pub fn current_lengths(&self, u: &[f64]) -> Option<Vec<f64>> {
        matches!(self.kinematics, Kinematics::Large).then(|| self.member_states(u).lengths)
    }

    /// [`MemberStates`] at displacements U (free dofs).
    pub fn member_states(&self, u: &[f64]) -> MemberStates {
        let s = &self.structure;
        match self.kinematics {
            Kinematics::Large => {
                let current = CurrentGeometry::of(s, u);
                MemberStates {
                    elongations: current.elongations,
                    lengths: current.lengths,
                    directions: current.directions,
                }
            }
            Kinematics::Linear | Kinematics::Prestress(_) => {
                let elongations: Vec<f64> = s
                    .links
                    .iter()
                    .zip(&s.link_dofs)
                    .map(|(l, ld)| ld.elongation(u) + s.imposed_elongation(l))
                    .collect();
                MemberStates {
                    lengths: s
                        .links
                        .iter()
                        .zip(&elongations)
                        .map(|(l, e)| l.length + e)
                        .collect(),
                    elongations,
                    directions: s.links.iter().map(|l| l.direction).collect(),
                }
            }
        }
    }
}
