//! The mass matrix of the natural modes (issue 45): each member's mass `m = ρ S ℓ` on its two
//! ends, consistent (the linear truss element, `m/6 [2I I; I 2I]` per component) or lumped
//! (`m/2` on each end), on the free dofs, plus the point masses on their nodes' free components.

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
                let (diagonal, coupling) = match kind {
                    // m/6 [2 1; 1 2] per component, restricted to the free dofs: a held end
                    // takes its rows and columns away, the free end keeps its m/3.
                    MassKind::Consistent => (m / 3.0, m / 6.0),
                    MassKind::Lumped => (m / 2.0, 0.0),
                };
                for d in [da, db].into_iter().filter(|&d| d != CLAMPED) {
                    values[pattern.diag_slot[d]] += diagonal;
                }
                if coupling == 0.0 || da == CLAMPED || db == CLAMPED {
                    continue;
                }
                match pattern.slot(da.max(db), da.min(db)) {
                    Some(slot) => values[slot] += coupling,
                    None => {
                        values[pattern.diag_slot[da]] += coupling;
                        values[pattern.diag_slot[db]] += coupling;
                    }
                }
            }
        }
        // A point mass on each free component of its node.
        for &(node, mass) in &s.point_masses {
            for d in (0..3)
                .map(|c| s.dof_of[3 * node + c])
                .filter(|&d| d != CLAMPED)
            {
                values[pattern.diag_slot[d]] += mass;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::MassKind;
    use crate::model::Model;
    use crate::solvers::TautStiffness;
    use crate::structure::{GridSpec, LoadPattern, Structure, CLAMPED};

    /// Each kind is the members' own matrix restricted to the free dofs: consistent
    /// `m/6 [2I I; I 2I]`, a held end's rows and columns dropped (its free end keeps `m/3`),
    /// lumped `m/2 I`, plus the point masses on their nodes' diagonals, assembled here densely
    /// on all `3n` dofs and compared entry by entry;
    /// the grid's supports leave members with one end held, and the free block holds no entry
    /// outside the pattern (its sum is the pattern's).
    #[test]
    fn each_kind_is_the_member_matrix_on_the_free_dofs() {
        let mut s = Structure::grid(&GridSpec::default(), &LoadPattern::default());
        s.links.iter_mut().for_each(|l| l.mass = 2.0 * l.length);
        // Point masses: two entries on a free node (they add up), one on a held node (none).
        let held = |s: &Structure, node: usize| s.dof_of[3 * node] == CLAMPED;
        let free_node = (0..s.n_nodes()).find(|&n| !held(&s, n)).unwrap();
        let held_node = (0..s.n_nodes()).find(|&n| held(&s, n)).unwrap();
        s.point_masses = vec![(free_node, 3.0), (held_node, 5.0), (free_node, 1.5)];
        let model = Model::linear(s);
        let (pattern, _) = TautStiffness::analyse(&model.structure);
        let s = &model.structure;
        let held = |node: usize| held(s, node);
        assert!(s.links.iter().any(|l| held(l.a) != held(l.b)));
        let n = s.dof_of.len();
        let mut global_of = vec![0; s.n_free];
        for (g, &d) in s.dof_of.iter().enumerate().filter(|(_, &d)| d != CLAMPED) {
            global_of[d] = g;
        }
        for (kind, diagonal, coupling) in [
            (MassKind::Consistent, 1.0 / 3.0, 1.0 / 6.0),
            (MassKind::Lumped, 0.5, 0.0),
        ] {
            let mut full = vec![0.0; n * n];
            for l in &s.links {
                for c in 0..3 {
                    let (a, b) = (3 * l.a + c, 3 * l.b + c);
                    full[a * n + a] += diagonal * l.mass;
                    full[b * n + b] += diagonal * l.mass;
                    full[a * n + b] += coupling * l.mass;
                    full[b * n + a] += coupling * l.mass;
                }
            }
            for &(node, mass) in &s.point_masses {
                for g in 3 * node..3 * node + 3 {
                    full[g * n + g] += mass;
                }
            }
            let mut m = vec![0.0; pattern.nnz()];
            model.assemble_mass(&pattern, kind, &mut m);
            let mut on_pattern = 0.0;
            for (r, c, slot) in pattern.entries() {
                let expected = full[global_of[r] * n + global_of[c]];
                assert!(
                    (m[slot] - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                    "{kind:?} ({r}, {c}): {} against {expected}",
                    m[slot]
                );
                on_pattern += if r == c { expected } else { 2.0 * expected };
            }
            let free_block: f64 = global_of
                .iter()
                .flat_map(|&r| global_of.iter().map(move |&c| (r, c)))
                .map(|(r, c)| full[r * n + c])
                .sum();
            assert!((free_block - on_pattern).abs() <= 1e-12 * free_block);
        }
    }
}
