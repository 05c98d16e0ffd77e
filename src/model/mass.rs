//! The mass matrix of the natural modes (issue 45): each member's mass `m = ρ S ℓ` on its two
//! ends, consistent (the linear truss element, `m/6 [2I I; I 2I]` per component) or lumped
//! (`m/2` on each end), on the free dofs.

use super::Model;
use crate::linalg::StiffnessPattern;
use crate::structure::CLAMPED;
use serde::Deserialize;

/// How a member's mass is spread on its ends: the case key `modal.mass`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MassKind {
    /// The linear truss element's consistent mass, `m/6 [2I I; I 2I]`.
    #[default]
    Consistent,
    /// Half the member's mass on each end, `m/2 I` (a diagonal matrix).
    Lumped,
}

impl Model {
    /// `values = M`, the members' mass on the free dofs (lower triangle on `pattern`, the
    /// stiffness's: a member couples only the same component of its two ends). A coupling the
    /// pattern lacks is lumped onto the two diagonals, so no mass is lost.
    pub fn assemble_mass(&self, pattern: &StiffnessPattern, kind: MassKind, values: &mut [f64]) {
        let s = &self.structure;
        values.iter_mut().for_each(|v| *v = 0.0);
        for link in s.links.iter().filter(|l| l.mass > 0.0) {
            let m = link.mass;
            for c in 0..3 {
                let (da, db) = (s.dof_of[3 * link.a + c], s.dof_of[3 * link.b + c]);
                let coupling = match (kind, da, db) {
                    (MassKind::Consistent, CLAMPED, _) | (MassKind::Consistent, _, CLAMPED) => None,
                    (MassKind::Consistent, a, b) => pattern.slot(a.max(b), a.min(b)),
                    (MassKind::Lumped, _, _) => None,
                };
                let diagonal = match (kind, coupling) {
                    (MassKind::Consistent, Some(slot)) => {
                        values[slot] += m / 6.0;
                        m / 3.0
                    }
                    _ => m / 2.0,
                };
                for d in [da, db].into_iter().filter(|&d| d != CLAMPED) {
                    values[pattern.diag_slot[d]] += diagonal;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::MassKind;
    use crate::model::Model;
    use crate::solvers::TautStiffness;
    use crate::structure::{GridSpec, LoadPattern, Structure};

    /// Both kinds carry every member's mass: a rigid translation along each axis has kinetic
    /// mass `uᵀ M u` = the mass on the free dofs, the same lumped or consistent.
    #[test]
    fn both_kinds_carry_the_members_mass() {
        let mut s = Structure::grid(&GridSpec::default(), &LoadPattern::default());
        s.links.iter_mut().for_each(|l| l.mass = 2.0 * l.length);
        let model = Model::linear(s);
        let (pattern, _) = TautStiffness::analyse(&model.structure);
        let mut totals = Vec::new();
        for kind in [MassKind::Consistent, MassKind::Lumped] {
            let mut m = vec![0.0; pattern.nnz()];
            model.assemble_mass(&pattern, kind, &mut m);
            let s = &model.structure;
            let u: Vec<f64> = (0..s.n_free).map(|_| 1.0).collect();
            let mut mu = vec![0.0; s.n_free];
            pattern.sym_matvec(&m, &u, &mut mu);
            totals.push(mu.iter().sum::<f64>());
        }
        assert!(totals[0] > 0.0);
        assert!(
            (totals[0] - totals[1]).abs() <= 1e-12 * totals[0],
            "{totals:?}"
        );
    }
}
