//! `[modal]`'s point masses (`[[modal.point_mass]]`): masses on nodes, besides the members',
//! for the natural modes.

use super::nodes::select;
use super::numbers::positive;
use super::raw::RawModal;
use super::CaseError;
use crate::structure::Geometry;
use std::collections::HashMap;

/// The point masses of `[[modal.point_mass]]` on `geometry`: each entry's `mass` (kg, > 0) on
/// every node its `nodes` or `box` selects, as (node index, kg); entries on one node add up.
pub(super) fn point_masses(
    raw: &RawModal,
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
) -> Result<Vec<(usize, f64)>, CaseError> {
    let mut masses = Vec::new();
    for (i, p) in raw.point_mass.iter().flatten().enumerate() {
        let key = format!("modal.point_mass[{i}]");
        positive(
            &format!("{key}.mass"),
            p.mass,
            "the mass on each node in kg",
        )?;
        let nodes = select(&key, geometry, index_of, &p.nodes, &p.in_box)?;
        masses.extend(nodes.into_iter().map(|n| (n, p.mass)));
    }
    Ok(masses)
}
