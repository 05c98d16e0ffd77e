//! How far an answer moves the nodes.

use crate::structure::Structure;

/// Largest nodal magnitude of the free-dof motion `u`, every component (held ones at their
/// prescribed value), m.
pub fn largest_motion(s: &Structure, u: &[f64]) -> f64 {
    largest_node_norm(&s.full_displacements(u))
}

/// Largest node-wise magnitude of `full`, three components per node.
pub fn largest_node_norm(full: &[f64]) -> f64 {
    full.chunks(3)
        // hypot: no overflow to inf for a large but finite displacement.
        .map(|u| u[0].hypot(u[1]).hypot(u[2]))
        .fold(0.0, f64::max)
}
