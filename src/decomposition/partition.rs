//! Substructuring (docs/method.md §4): a partition `sx × sy` assigns each module, with all its links, to
//! one substructure (modules split as evenly as possible, so splits may be uneven); on a
//! general structure (docs/method.md §7) each link goes to the box of its midpoint among `sx × sy` equal
//! boxes of the plan (x, y) bounding box of the nodes. Each pair of
//! substructures sharing non-clamped nodes has one interface, its nodes in increasing global
//! order (the order both sides use).

use crate::structure::Structure;
use serde::Deserialize;
use std::collections::BTreeMap;

/// What to do with interfaces of three nodes or fewer (docs/method.md §4 "Weak interfaces").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WeakInterfaces {
    /// All-macro (R = identity): exact continuity through the macro problem. The default.
    #[default]
    Macro,
    /// All-micro (no macro part): the paper's literal statement; stalls on the paper's case.
    Micro,
    /// One-node interfaces whose node lies in another interface are dropped; other weak
    /// interfaces are all-macro.
    Drop,
}

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
    /// The two substructures, `sides[0] < sides[1]`; macro forces count positive on `sides[0]`.
    pub sides: [usize; 2],
    /// Shared non-clamped nodes, increasing.
    pub nodes: Vec<usize>,
}

impl SubstructureTopology {
    /// Its free dofs: the free components of its nodes (the size of K_E).
    pub fn free_dofs(&self, structure: &Structure) -> usize {
        self.nodes
            .iter()
            .flat_map(|&n| structure.held_components(n))
            .filter(|&held| !held)
            .count()
    }
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

/// The substructure (row by row, `iy · sx + ix`) of every link: by module on a grid, by
/// midpoint in the plan bounding box otherwise (a midpoint on a box boundary goes to the box
/// above it, the last box keeping the upper edge).
fn substructure_of_link(structure: &Structure, shape: [usize; 2]) -> Vec<usize> {
    if let Some(layout) = &structure.layout {
        let (nx, ny) = (layout.nx, layout.ny);
        let (px, py) = (split(nx, shape[0]), split(ny, shape[1]));
        return structure
            .links
            .iter()
            .map(|l| py[l.module / nx] * shape[0] + px[l.module % nx])
            .collect();
    }
    let span = |k: usize| {
        structure
            .nodes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            })
    };
    let boxes = [span(0), span(1)];
    let index = |k: usize, x: f64| {
        let (lo, hi) = boxes[k];
        let width = hi - lo;
        if width <= 0.0 {
            return 0;
        }
        (((x - lo) / width * shape[k] as f64).floor() as usize).min(shape[k] - 1)
    };
    structure
        .links
        .iter()
        .map(|l| {
            let (a, b) = (structure.nodes[l.a], structure.nodes[l.b]);
            let mid = |k: usize| 0.5 * (a[k] + b[k]);
            index(1, mid(1)) * shape[0] + index(0, mid(0))
        })
        .collect()
}

impl Partition {
    /// On a grid, requires `1 ≤ sx ≤ nx`, `1 ≤ sy ≤ ny` (checked by case validation).
    pub fn new(structure: &Structure, shape: [usize; 2], weak: WeakInterfaces) -> Partition {
        let sub_of_link = substructure_of_link(structure, shape);
        let n_subs = shape[0] * shape[1];
        let mut links = vec![Vec::new(); n_subs];
        let mut subs_of_node: Vec<Vec<usize>> = vec![Vec::new(); structure.n_nodes()];
        for (i, link) in structure.links.iter().enumerate() {
            let e = sub_of_link[i];
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
            substructures,
            interfaces,
            dropped_interfaces,
        }
    }
}
