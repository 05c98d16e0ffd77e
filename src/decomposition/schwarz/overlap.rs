//! Overlapping subdomains from a partition by links (docs/method.md, "Newton–Krylov on the
//! substructures"): `Ω_j⁰` the free dofs of substructure j's nodes, `Ω_j` those of `Ω_j⁰`'s
//! nodes and of every node within `layers` links of them; the partition of unity
//! `D_j = 1 / (subdomains holding the dof)`, so that `Σ_j R_jᵀ D_j R_j = I`; and per
//! subdomain the links with a free dof in it, those with every free dof in it marked inner (the
//! links of its Neumann matrix).

use crate::decomposition::Partition;
use crate::linalg::CHUNK;
use crate::structure::{Structure, CLAMPED};
use rayon::prelude::*;

/// The overlapping subdomains of a partition.
pub struct Overlap {
    /// Per subdomain: its free dofs (global), increasing.
    pub dofs: Vec<Vec<usize>>,
    /// Per subdomain: `D_j` on its dofs, 1 / (subdomains holding the dof).
    pub unity: Vec<Vec<f64>>,
    /// Per subdomain: every link with a free dof in it, and whether all its free dofs are.
    pub links: Vec<Vec<(usize, bool)>>,
    /// Per global free dof, the subdomains holding it (`holders[holder_ptr[d]..holder_ptr[d + 1]]`).
    holder_ptr: Vec<usize>,
    holders: Vec<u32>,
    /// Beside each holder, the dof's position in that subdomain's `dofs`.
    holder_slot: Vec<u32>,
}

impl Overlap {
    /// The subdomains of `partition`'s substructures on `structure`, each grown by `layers`
    /// layers of nodes through the links.
    pub fn new(structure: &Structure, partition: &Partition, layers: usize) -> Overlap {
        let (n_nodes, n_free) = (structure.n_nodes(), structure.n_free);
        // Links at each node (CSR).
        let mut ptr = vec![0usize; n_nodes + 1];
        for l in &structure.links {
            ptr[l.a + 1] += 1;
            ptr[l.b + 1] += 1;
        }
        for v in 0..n_nodes {
            ptr[v + 1] += ptr[v];
        }
        let mut fill = ptr.clone();
        let mut at_node = vec![0usize; ptr[n_nodes]];
        for (i, l) in structure.links.iter().enumerate() {
            for v in [l.a, l.b] {
                at_node[fill[v]] = i;
                fill[v] += 1;
            }
        }
        let node_links = |v: usize| &at_node[ptr[v]..ptr[v + 1]];
        type Built = (Vec<usize>, Vec<(usize, bool)>);
        let built: Vec<Built> = partition
            .substructures
            .par_iter()
            .enumerate()
            .map_init(
                // Per task: node, dof and link stamps (subdomain index + 1; never cleared).
                || {
                    (
                        vec![0u32; n_nodes],
                        vec![0u32; n_free],
                        vec![0u32; structure.links.len()],
                    )
                },
                |(node_mark, dof_mark, link_mark), (j, topo)| {
                    let stamp = j as u32 + 1;
                    // Ω_j's nodes: the substructure's, then `layers` rings through the links.
                    let mut nodes: Vec<usize> = topo.nodes.clone();
                    nodes.iter().for_each(|&v| node_mark[v] = stamp);
                    let mut ring = nodes.clone();
                    for _ in 0..layers {
                        let mut next = Vec::new();
                        for &v in &ring {
                            for &i in node_links(v) {
                                let l = &structure.links[i];
                                let w = if l.a == v { l.b } else { l.a };
                                if node_mark[w] != stamp {
                                    node_mark[w] = stamp;
                                    next.push(w);
                                }
                            }
                        }
                        nodes.extend_from_slice(&next);
                        ring = next;
                    }
                    // Its free dofs, increasing.
                    let mut dofs: Vec<usize> = nodes
                        .iter()
                        .flat_map(|&v| (0..3).map(move |c| structure.dof_of[3 * v + c]))
                        .filter(|&d| d != CLAMPED)
                        .collect();
                    dofs.sort_unstable();
                    dofs.iter().for_each(|&d| dof_mark[d] = stamp);
                    // The links with a free dof in it; inner when every free dof is.
                    let mut links = Vec::new();
                    for &v in &nodes {
                        for &i in node_links(v) {
                            if link_mark[i] == stamp {
                                continue;
                            }
                            link_mark[i] = stamp;
                            let row = &structure.link_dofs[i];
                            let inside = |(d, _): (usize, f64)| dof_mark[d] == stamp;
                            if row.iter().any(inside) {
                                links.push((i, row.iter().all(inside)));
                            }
                        }
                    }
                    links.sort_unstable();
                    (dofs, links)
                },
            )
            .collect();
        let (dofs, links): (Vec<_>, Vec<_>) = built.into_iter().unzip();
        // The subdomains holding each dof, and D_j.
        let mut holder_ptr = vec![0usize; n_free + 1];
        for d in dofs.iter().flatten() {
            holder_ptr[d + 1] += 1;
        }
        for d in 0..n_free {
            holder_ptr[d + 1] += holder_ptr[d];
        }
        let mut fill = holder_ptr.clone();
        let mut holders = vec![0u32; holder_ptr[n_free]];
        let mut holder_slot = vec![0u32; holder_ptr[n_free]];
        for (j, ds) in dofs.iter().enumerate() {
            for (k, &d) in ds.iter().enumerate() {
                holders[fill[d]] = j as u32;
                holder_slot[fill[d]] = k as u32;
                fill[d] += 1;
            }
        }
        let unity = dofs
            .iter()
            .map(|ds| {
                ds.iter()
                    .map(|&d| 1.0 / (holder_ptr[d + 1] - holder_ptr[d]) as f64)
                    .collect()
            })
            .collect();
        Overlap {
            dofs,
            unity,
            links,
            holder_ptr,
            holders,
            holder_slot,
        }
    }

    /// `out = Σ_j R_jᵀ parts[j]` (`parts[j]` on Ω_j's dofs): per dof the sum over the
    /// subdomains holding it in increasing j, the order a scatter subdomain by subdomain adds
    /// them in, so the same sums bit for bit; dofs in parallel.
    pub fn sum_into(&self, parts: &[Vec<f64>], out: &mut [f64]) {
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(k, chunk)| {
                for (i, o) in chunk.iter_mut().enumerate() {
                    let d = k * CHUNK + i;
                    let held = self.holder_ptr[d]..self.holder_ptr[d + 1];
                    *o = self.holders[held.clone()]
                        .iter()
                        .zip(&self.holder_slot[held])
                        .fold(0.0, |sum, (&j, &at)| sum + parts[j as usize][at as usize]);
                }
            });
    }

    /// The number of subdomains.
    pub fn len(&self) -> usize {
        self.dofs.len()
    }

    /// Whether there is no subdomain.
    pub fn is_empty(&self) -> bool {
        self.dofs.is_empty()
    }

    /// The subdomains holding global free dof `d`, increasing.
    pub fn holders_of(&self, d: usize) -> impl Iterator<Item = usize> + '_ {
        self.holders[self.holder_ptr[d]..self.holder_ptr[d + 1]]
            .iter()
            .map(|&j| j as usize)
    }
}
