//! The loads of `[load]` or of one `[[load.cases]]` entry: the nodal force, the point loads,
//! gravity for self-weight, and the rest-length changes (`actions`), each checked and named by
//! its key under the entry's prefix.

use super::nodes::select;
use super::numbers::{bounded, vector, PHYSICAL_MAX};
use super::raw::LoadParts;
use super::{CaseError, LoadCase};
use crate::structure::Geometry;
use std::collections::HashMap;

/// `load.self_weight.gravity` when `[load.self_weight]` leaves it out, m/s².
const STANDARD_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// The loads of `parts`, whose keys are under `prefix` (`load`, `load.cases[2]`), checked: the
/// nodal force (`default_nodal` where not given), the point loads, gravity and the
/// rest-length changes.
pub(super) fn case_loads(
    prefix: &str,
    parts: &LoadParts<'_>,
    default_nodal: [f64; 3],
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
) -> Result<LoadCase, CaseError> {
    let nodal = parts.nodal.unwrap_or(default_nodal);
    for (c, &f) in nodal.iter().enumerate() {
        let key = format!("{prefix}.nodal[{c}]");
        bounded(&key, f, PHYSICAL_MAX, "each nodal force component in N")?;
    }
    let mut points = Vec::new();
    for (i, p) in parts.point.iter().flatten().enumerate() {
        let key = format!("{prefix}.point[{i}]");
        let nodes = select(&key, geometry, index_of, &p.nodes, &p.in_box)?;
        let force = vector(
            &format!("{key}.force"),
            p.force,
            PHYSICAL_MAX,
            "each force component in N",
        )?;
        points.extend(nodes.into_iter().map(|n| (n, force)));
    }
    let gravity = match parts.self_weight {
        None => None,
        Some(w) => Some(vector(
            &format!("{prefix}.self_weight.gravity"),
            w.gravity.unwrap_or(STANDARD_GRAVITY),
            1e6,
            "each gravity component in m/s²",
        )?),
    };
    Ok(LoadCase {
        name: String::new(),
        nodal,
        points,
        gravity,
        rest_length_changes: super::actions::rest_length_changes(prefix, parts, geometry)?,
        settlements: Vec::new(),
    })
}
