//! What one MPI rank keeps of a structure for a solve it shares (issue 25): every node, support
//! and load, so that the free-dof numbering and every nodal vector are the world's, but only the
//! links of its own substructures, renumbered in the order it holds them.

use super::Structure;

impl Structure {
    /// This structure with only `links` (world link indices), renumbered `0 … links.len()` in
    /// that order: their compatibility rows, grid roles and everything per link follow them;
    /// the nodes, supports, free dofs and loads are kept whole. `None` with the prestress's
    /// geometric stiffness, which is kept for the whole structure only.
    pub fn keeping_links(&self, links: &[usize]) -> Option<Structure> {
        if self.geometric.is_some() {
            return None;
        }
        Some(Structure {
            layout: self.layout,
            grid_roles: self
                .grid_roles
                .as_ref()
                .map(|roles| links.iter().map(|&i| roles[i]).collect()),
            node_ids: self.node_ids.clone(),
            nodes: self.nodes.clone(),
            links: links.iter().map(|&i| self.links[i].clone()).collect(),
            clamped: self.clamped.clone(),
            prescribed: self.prescribed.clone(),
            dof_of: self.dof_of.clone(),
            n_free: self.n_free,
            link_dofs: links.iter().map(|&i| self.link_dofs[i]).collect(),
            unit_load: self.unit_load.clone(),
            held_load: self.held_load.clone(),
            settlement_force: self.settlement_force.clone(),
            prestress_scale: self.prestress_scale,
            model: self.model,
            geometric: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::structure::{GeometricModel, GridSpec, LoadPattern, Structure};

    /// The kept links are the world's, in the order asked, with their rows of B; every nodal
    /// quantity is the world's.
    #[test]
    fn kept_links_are_the_worlds_in_the_order_asked() {
        let s = Structure::grid(&GridSpec::default(), &LoadPattern::default());
        let keep: Vec<usize> = (0..s.links.len()).rev().filter(|i| i % 3 == 1).collect();
        let kept = s.keeping_links(&keep).expect("no geometric stiffness");
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
        let prestressed = s.clone().with_model(GeometricModel::Prestress);
        assert!(prestressed.keeping_links(&keep).is_none());
    }
}
