//! Substructuring (SPEC §4): a partition `sx × sy` assigns each module, with all its links, to
//! one substructure (modules split as evenly as possible, so splits may be uneven). Each pair of
//! substructures sharing non-clamped nodes has one interface, its nodes in increasing global
//! order (the order both sides use).

use super::WeakInterfaces;
use crate::structure::Structure;
use std::collections::BTreeMap;

/// Interfaces with at most this many nodes are weak (a 10-field basis cannot be defined).
pub const WEAK_MAX_NODES: usize = 3;

/// One substructure of a partition: its links (all those of its modules) and the nodes they touch.
#[derive(Debug, Clone)]
pub struct SubstructureTopology {
    /// Global link indices.
    pub links: Vec<usize>,
    /// Non-clamped nodes touched by its links, increasing.
    pub nodes: Vec<usize>,
    /// Clamped nodes touched by its links, increasing.
    pub clamped_nodes: Vec<usize>,
}

/// An interface Γ_EE': the pair of substructures (E, E') and the non-clamped nodes they share.
#[derive(Debug, Clone)]
pub struct InterfaceTopology {
    /// The two substructures, `sides[0] < sides[1]`; macro forces count positive on sides[0].
    pub sides: [usize; 2],
    /// Shared non-clamped nodes, increasing.
    pub nodes: Vec<usize>,
}

impl InterfaceTopology {
    /// Weak interface: at most [`WEAK_MAX_NODES`] nodes, too few for the nine-field macro basis.
    pub fn is_weak(&self) -> bool {
        self.nodes.len() <= WEAK_MAX_NODES
    }
}

/// An `sx × sy` partition of the grid's modules into substructures, with their interfaces.
#[derive(Debug, Clone)]
pub struct Partition {
    /// `[sx, sy]`: substructures along x and along y.
    pub shape: [usize; 2],
    /// Per substructure, row by row (index `iy · sx + ix`): its links and nodes.
    pub substructures: Vec<SubstructureTopology>,
    /// One per pair of substructures sharing non-clamped nodes, by increasing pair `(E, E')`.
    pub interfaces: Vec<InterfaceTopology>,
    /// One-node interfaces removed by [`WeakInterfaces::Drop`].
    pub dropped_interfaces: usize,
}

/// Part of each of `n` consecutive items among `parts` parts, as even as possible.
fn split(n: usize, parts: usize) -> Vec<usize> {
    (0..n).map(|i| i * parts / n).collect()
}

impl Partition {
    /// Requires `1 ≤ sx ≤ nx`, `1 ≤ sy ≤ ny` (checked by case validation).
    pub fn new(structure: &Structure, shape: [usize; 2], weak: WeakInterfaces) -> Partition {
        let (nx, ny) = (structure.layout.nx, structure.layout.ny);
        let (px, py) = (split(nx, shape[0]), split(ny, shape[1]));
        let sub_of_module = |m: usize| py[m / nx] * shape[0] + px[m % nx];
        let n_subs = shape[0] * shape[1];
        let mut links = vec![Vec::new(); n_subs];
        let mut subs_of_node: Vec<Vec<usize>> = vec![Vec::new(); structure.n_nodes()];
        for (i, link) in structure.links.iter().enumerate() {
            let e = sub_of_module(link.module);
            links[e].push(i);
            for node in [link.a, link.b] {
                if !subs_of_node[node].contains(&e) {
                    subs_of_node[node].push(e);
                }
            }
        }
        let mut nodes = vec![Vec::new(); n_subs];
        let mut clamped_nodes = vec![Vec::new(); n_subs];
        let mut shared: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
        for (node, subs) in subs_of_node.iter_mut().enumerate() {
            subs.sort_unstable();
            let clamped = structure.clamped[node];
            for &e in subs.iter() {
                if clamped {
                    clamped_nodes[e].push(node);
                } else {
                    nodes[e].push(node);
                }
            }
            if !clamped {
                for (i, &a) in subs.iter().enumerate() {
                    for &b in &subs[i + 1..] {
                        shared.entry((a, b)).or_default().push(node);
                    }
                }
            }
        }
        let mut interfaces: Vec<InterfaceTopology> = shared
            .into_iter()
            .map(|((a, b), nodes)| InterfaceTopology {
                sides: [a, b],
                nodes,
            })
            .collect();
        let mut dropped_interfaces = 0;
        if weak == WeakInterfaces::Drop {
            let mut appearances = vec![0usize; structure.n_nodes()];
            for i in &interfaces {
                for &n in &i.nodes {
                    appearances[n] += 1;
                }
            }
            let before = interfaces.len();
            interfaces.retain(|i| !(i.nodes.len() == 1 && appearances[i.nodes[0]] > 1));
            dropped_interfaces = before - interfaces.len();
        }
        let substructures = links
            .into_iter()
            .zip(nodes)
            .zip(clamped_nodes)
            .map(|((links, nodes), clamped_nodes)| SubstructureTopology {
                links,
                nodes,
                clamped_nodes,
            })
            .collect();
        Partition {
            shape,
            substructures,
            interfaces,
            dropped_interfaces,
        }
    }
}
