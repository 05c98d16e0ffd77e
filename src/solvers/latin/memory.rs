//! What micro-macro holds beside the structure, estimated from the structure's size and its
//! settings before it is set up: the memory estimate asks the solver.

use super::LatinSettings;
use crate::linalg::{factor_bytes, BYTES_PER_FACTOR_ENTRY};
use crate::structure::StructureSize;

/// Entries of a substructure factor per dof: `28 (log2 d_E − 8.3)`, at least `4 log2 d_E`, for
/// `d_E` dofs (AMD on E's node graph). Fitted to the substructure factors of 256 × 256 modules
/// on 2 × 2 to 64 × 64 substructures (148 224 to 180 dofs: 238, 183, 128, 82, 36 and 22 entries
/// per dof, each below the formula).
fn substructure_entries_per_dof(d_e: f64) -> f64 {
    let l = d_e.max(2.0).log2();
    f64::max(28.0 * (l - 8.3), 4.0 * l)
}

/// Macro dofs per substructure with a macro basis of degree p: `6p + 18`, two strong interfaces
/// of `3p + 6` fields and the crosspoints' weak ones (22 on 256 × 256 modules with 256 and
/// 1 024 substructures at p = 1; rounded up).
fn macro_dofs_per_substructure(degree: f64) -> f64 {
    6.0 * degree + 18.0
}

/// Columns of all the Z_E together (each substructure's macro dofs) on an `sx × sy` partition
/// of a grid with a macro basis of degree p: two sides of each strong interface between
/// neighbours along x or y, of `3p + 6` fields, and two of each one-node interface between
/// diagonal neighbours, of 3 (44 per substructure on 256 × 256 modules with 256 substructures
/// at p = 1).
fn z_columns([sx, sy]: [usize; 2], degree: f64) -> f64 {
    let strong = (sx * sy.saturating_sub(1) + sy * sx.saturating_sub(1)) as f64;
    let crosspoints = (2 * sx.saturating_sub(1) * sy.saturating_sub(1)) as f64;
    2.0 * strong * (3.0 * degree + 6.0) + 2.0 * crosspoints * 3.0
}

/// Bytes of micro-macro's own memory beside the structure on a structure of `size` with
/// `settings`: the substructure factors (`substructure_entries_per_dof`, 10 bytes an entry
/// as K's), Z_E unless `keep_z` is false, Anderson's history (two vectors of about 1.25 values
/// per link per depth) and the macro factor (three times a stiffness factor of its dofs: its
/// blocks are denser). Measured against peak RSS of whole runs (2026-11-27, reference none,
/// `geometric_term = false`): 256 × 256 modules on 256 substructures, anderson 10, 1.31 GB
/// (`keep_z = false`, estimate 1.45 GB) and 1.53 GB (1.68 GB); 512 × 512 on 1 024, anderson
/// 10, `keep_z = false`, 5.08 GB (5.8 GB).
pub fn memory_bytes(size: StructureSize, settings: &LatinSettings) -> u64 {
    let d = size.dofs().max(2) as f64;
    let substructures = (settings.subdomains[0] * settings.subdomains[1]).max(1) as f64;
    let d_e = d / substructures;
    let factors = BYTES_PER_FACTOR_ENTRY * substructure_entries_per_dof(d_e) * d;
    let degree = settings.macro_degree_on(size.links, substructures as usize) as f64;
    // Z_E: E's dofs (d / substructures) × its macro dofs, 8 bytes each; twice, since a status
    // rebuild builds the new Z_E beside the old one (kept until the rebuild succeeds).
    let z = match settings.keep_z {
        true => 2.0 * 8.0 * d / substructures * z_columns(settings.subdomains, degree),
        false => 0.0,
    };
    let anderson = 2.0 * 1.25 * 8.0 * settings.anderson as f64 * size.links as f64;
    let macro_size = StructureSize {
        nodes: (macro_dofs_per_substructure(degree) * substructures / 3.0).ceil() as usize,
        links: 0,
    };
    let macro_factor = match substructures > 1.0 {
        true => 3 * factor_bytes(macro_size.dofs(), false),
        false => 0,
    };
    (factors + z + anderson) as u64 + macro_factor
}
