//! The nodes a `nodes = [ids]` list or a `box = { min, max }` selects (supports and point
//! loads).

use super::numbers::{bounded, PHYSICAL_MAX};
use super::raw::RawBox;
use super::CaseError;
use crate::structure::Geometry;
use std::collections::HashMap;

/// The index of every node id of `geometry`.
pub(super) fn index_of(geometry: &Geometry) -> HashMap<u64, usize> {
    geometry
        .node_ids
        .iter()
        .enumerate()
        .map(|(i, &id)| (id, i))
        .collect()
}

/// The nodes (indices) a `nodes = [...]` list or a `box = { min, max }` selects.
pub(super) fn select(
    key: &str,
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
    ids: &Option<Vec<u64>>,
    in_box: &Option<RawBox>,
) -> Result<Vec<usize>, CaseError> {
    match (ids, in_box) {
        (Some(ids), None) => {
            if ids.is_empty() {
                return Err(CaseError::invalid(
                    format!("{key}.nodes"),
                    "[]",
                    "name at least one node id",
                ));
            }
            ids.iter()
                .map(|id| {
                    index_of.get(id).copied().ok_or_else(|| {
                        CaseError::invalid(
                            format!("{key}.nodes"),
                            id,
                            "name a node of the structure (grid: its node index; [structure]: an id of the nodes table)",
                        )
                    })
                })
                .collect()
        }
        (None, Some(b)) => {
            for (k, (&lo, &hi)) in b.min.iter().zip(&b.max).enumerate() {
                bounded(
                    &format!("{key}.box.min[{k}]"),
                    lo,
                    PHYSICAL_MAX,
                    "each coordinate in m",
                )?;
                bounded(
                    &format!("{key}.box.max[{k}]"),
                    hi,
                    PHYSICAL_MAX,
                    "each coordinate in m",
                )?;
            }
            // Boundaries count as inside, to a relative 1e-9 of the structure's size.
            let size = geometry
                .nodes
                .iter()
                .flatten()
                .fold(0.0, |m: f64, x| m.max(x.abs()))
                .max(1.0);
            let tol = 1e-9 * size;
            let nodes: Vec<usize> = (0..geometry.nodes.len())
                .filter(|&n| {
                    let p = geometry.nodes[n];
                    (0..3).all(|k| p[k] >= b.min[k] - tol && p[k] <= b.max[k] + tol)
                })
                .collect();
            if nodes.is_empty() {
                return Err(CaseError::invalid(
                    format!("{key}.box"),
                    format!("{{ min = {:?}, max = {:?} }}", b.min, b.max),
                    "the box holds no node: widen it (positions in m, boundaries included)",
                ));
            }
            Ok(nodes)
        }
        _ => Err(CaseError::invalid(
            key.to_string(),
            "",
            "give exactly one of `nodes = [ids]` and `box = { min = [x, y, z], max = [x, y, z] }`",
        )),
    }
}
