//! The interfaces of a partition as the solver uses them: each with its macro basis and its
//! place among the macro unknowns, redundant exact constraints at crosspoints left out.

use super::macro_basis::{labelled_macro_basis, orthonormal_columns_kept};
use super::partition::WeakInterfaces;
use super::partition::{InterfaceTopology, Partition};
use crate::structure::Structure;
use nalgebra::DMatrix;

/// An interface with its macro basis and where its macro forces sit in the macro problem.
#[derive(Debug, Clone)]
pub struct Interface {
    /// Its two substructures and shared nodes.
    pub topology: InterfaceTopology,
    /// Per node of `topology.nodes`: which of its components are free (a node held on some
    /// components only keeps the others). R and every interface vector have one row per free
    /// component, node-major, x y z.
    pub free: Vec<[bool; 3]>,
    /// R: orthonormal columns, one row per free component of the interface's nodes.
    pub basis: DMatrix<f64>,
    /// First column of its macro forces among the macro problem's unknowns.
    pub macro_offset: usize,
    /// What each column of R is (see `super::macro_basis::labelled_macro_basis`).
    pub fields: Vec<String>,
    /// Centroid G of its nodes, m.
    pub centroid: [f64; 3],
}

impl Interface {
    /// Its macro basis made of `fields` (one row per free component of its nodes), dependent
    /// ones dropped, each labelled as `labels` says.
    pub(crate) fn set_fields(&mut self, fields: &[Vec<f64>], labels: &[String]) {
        let (basis, kept) = orthonormal_columns_kept(fields, self.basis.nrows());
        self.fields = kept.iter().map(|&k| labels[k].clone()).collect();
        self.basis = basis;
    }
}

/// The macro offsets of `interfaces` numbered in their order, after their bases changed.
pub(crate) fn number_macro_dofs(interfaces: &mut [Interface]) {
    let mut offset = 0;
    for iface in interfaces {
        iface.macro_offset = offset;
        offset += iface.basis.ncols();
    }
}

/// Exact (all-macro) continuity constraints node by node, kept independent.
///
/// A node held by several substructures (a crosspoint) lies in one interface per pair of them.
/// All-macro weak interfaces impose exact continuity of the node on each pair; around a
/// crosspoint of four one-module substructures that is six constraints of which three are
/// independent, and the macro problem would be singular. A union–find per node keeps a node in
/// an interface only when the interface joins two substructures not yet tied at that node;
/// otherwise its continuity already holds exactly through the others and the node leaves that
/// interface.
#[derive(Default)]
struct ExactContinuity {
    /// Per node: (substructure, component) of the substructures tied at it so far.
    components: std::collections::HashMap<usize, Vec<(usize, usize)>>,
}

impl ExactContinuity {
    fn keep_independent(&mut self, topology: &mut InterfaceTopology) {
        let [a, b] = topology.sides;
        let components = &mut self.components;
        topology.nodes.retain(|&node| {
            let comps = components.entry(node).or_default();
            let mut find = |e: usize| -> usize {
                match comps.iter().find(|(sub, _)| *sub == e) {
                    Some(&(_, c)) => c,
                    None => {
                        comps.push((e, e));
                        e
                    }
                }
            };
            let (ca, cb) = (find(a), find(b));
            if ca == cb {
                return false;
            }
            for entry in comps.iter_mut() {
                if entry.1 == cb {
                    entry.1 = ca;
                }
            }
            true
        });
    }
}

/// The interfaces of `partition` that carry constraints, with their macro bases, and how many
/// were dropped and how many nodes left out as redundant.
pub(crate) struct Interfaces {
    /// The interfaces kept, macro offsets in this order.
    pub list: Vec<Interface>,
    /// Interfaces left out (`drop`, or all their nodes redundant).
    pub dropped: usize,
    /// Nodes left out of all-macro weak interfaces as redundant.
    pub redundant_nodes: usize,
}

impl Interfaces {
    /// The interfaces of `partition`, redundant exact constraints left out, with their bases.
    /// `degree` is the macro basis's ([`super::macro_basis::labelled_macro_basis`]).
    pub(crate) fn new(
        structure: &Structure,
        partition: &Partition,
        weak: WeakInterfaces,
        degree: usize,
    ) -> Self {
        let mut offset = 0;
        let mut exact = ExactContinuity::default();
        let mut redundant_nodes = 0;
        let mut dropped = partition.dropped_interfaces;
        let list: Vec<Interface> = partition
            .interfaces
            .iter()
            .filter_map(|topology| {
                let mut topology = topology.clone();
                if topology.is_weak() && weak != WeakInterfaces::Micro {
                    let before = topology.nodes.len();
                    exact.keep_independent(&mut topology);
                    redundant_nodes += before - topology.nodes.len();
                    if topology.nodes.is_empty() {
                        dropped += 1;
                        return None;
                    }
                }
                Some(topology)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .map(|topology| {
                let positions: Vec<[f64; 3]> =
                    topology.nodes.iter().map(|&n| structure.nodes[n]).collect();
                let free: Vec<[bool; 3]> = topology
                    .nodes
                    .iter()
                    .map(|&n| structure.held_components(n).map(|held| !held))
                    .collect();
                let (basis, fields) = labelled_macro_basis(&positions, &free, weak, degree);
                let count = positions.len().max(1) as f64;
                let centroid =
                    [0, 1, 2].map(|c| positions.iter().map(|p| p[c]).sum::<f64>() / count);
                let iface = Interface {
                    topology,
                    free,
                    macro_offset: offset,
                    basis,
                    fields,
                    centroid,
                };
                offset += iface.basis.ncols();
                iface
            })
            .collect();
        Interfaces {
            list,
            dropped,
            redundant_nodes,
        }
    }
}
