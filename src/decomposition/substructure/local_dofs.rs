//! A substructure E's own dofs: the free components of its nodes, their global free dofs, the
//! share of a nodal load E carries and B_E on them; `R_E` (restriction to E's dofs) and `R_Eᵀ`
//! (prolongation, summed over the substructures that share a dof).

use crate::decomposition::Partition;
use crate::decomposition::SubstructureTopology;
use crate::structure::{LinkDofs, Structure, CLAMPED};

/// E's own dofs and B_E on them.
#[derive(Debug, Clone)]
pub struct LocalDofs {
    /// Local dof → global free dof.
    pub dof_global: Vec<usize>,
    /// Per local dof: the share of a nodal load E carries (1 / substructures holding the node).
    pub load_share: Vec<f64>,
    /// Per link of E (in `topology.links` order): its row of B_E on E's local dofs
    /// (`e = n·(U_b − U_a)`).
    pub link_dofs: Vec<LinkDofs>,
}

impl LocalDofs {
    /// E's local dofs: the free components of its nodes, in node order (a node held on some
    /// components only keeps the others; held components stay out of E, like clamped nodes),
    /// and B_E on them. `holders`: per node, the substructures holding it ([`holders`]).
    /// `local_dof` maps `3·node + c` to E's local dof on exit, for the caller's own rows on
    /// E's dofs; [`LocalDofs::clear`] makes it all [`CLAMPED`] again, as it is on entry.
    pub fn number(
        topology: &SubstructureTopology,
        structure: &Structure,
        holders: &[u8],
        local_dof: &mut [usize],
    ) -> LocalDofs {
        let mut dof_global = Vec::with_capacity(3 * topology.nodes.len());
        let mut load_share = Vec::with_capacity(3 * topology.nodes.len());
        for &node in &topology.nodes {
            for c in 0..3 {
                let global = structure.dof_of[3 * node + c];
                if global != CLAMPED {
                    local_dof[3 * node + c] = dof_global.len();
                    dof_global.push(global);
                    load_share.push(1.0 / holders[node] as f64);
                }
            }
        }
        // B_E: per link, `e = n·(U_b − U_a)` on E's local dofs.
        let link_dofs = topology
            .links
            .iter()
            .map(|&i| structure.links[i].compatibility_row(local_dof))
            .collect();
        LocalDofs {
            dof_global,
            load_share,
            link_dofs,
        }
    }

    /// Undo [`LocalDofs::number`]'s map: `local_dof` all [`CLAMPED`] again.
    pub fn clear(topology: &SubstructureTopology, local_dof: &mut [usize]) {
        for &node in &topology.nodes {
            for c in 0..3 {
                local_dof[3 * node + c] = CLAMPED;
            }
        }
    }

    /// E's number of dofs.
    pub fn len(&self) -> usize {
        self.dof_global.len()
    }

    /// Whether E has no free dof.
    pub fn is_empty(&self) -> bool {
        self.dof_global.is_empty()
    }

    /// `R_E u`: `global`'s values at E's dofs.
    pub fn restrict(&self, global: &[f64]) -> Vec<f64> {
        self.dof_global.iter().map(|&d| global[d]).collect()
    }

    /// `global += R_Eᵀ local`: E's values added at their global dofs.
    pub fn prolong_add(&self, local: &[f64], global: &mut [f64]) {
        for (&d, &v) in self.dof_global.iter().zip(local) {
            global[d] += v;
        }
    }
}

/// Per node of `structure` (`nodes` of them), how many of `partition`'s substructures hold it.
pub fn holders(partition: &Partition, nodes: usize) -> Vec<u8> {
    let mut holders = vec![0u8; nodes];
    for topo in &partition.substructures {
        for &n in &topo.nodes {
            holders[n] += 1;
        }
    }
    holders
}
