//! What one MPI rank keeps of a structure for a solve it shares (issue 25): every node, support
//! and load, so that the free-dof numbering and every nodal vector are the world's, but only the
//! links of its own substructures, renumbered in the order it holds them.

use super::Structure;

impl Structure {
    /// This structure with only `links` (world link indices), renumbered `0 … links.len()` in
    /// that order: their compatibility rows, grid roles and everything per link follow them;
    /// the nodes, supports, free dofs and loads are kept whole.
    pub fn keeping_links(&self, links: &[usize]) -> Structure {
        Structure {
            layout: self.layout,
            grid_roles: self
                .grid_roles
                .as_ref()
                .map(|roles| links.iter().map(|&i| roles[i]).collect()),
            groups: self
                .groups
                .as_ref()
                .map(|g| links.iter().map(|&i| g[i].clone()).collect()),
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
            checks: self.checks.as_ref().map(|c| c.keeping(links)),
            point_masses: self.point_masses.clone(),
        }
    }
}
