//! `groups/{solver}_alpha{α}.csv` (issue 46), written beside `forces/` when the members table
//! has a `group` column: per group, its members and the force of largest magnitude at the
//! answer, with the member carrying it.

use super::write_atomic;
use crate::labels::alpha_label;
use crate::structure::Structure;
use std::collections::HashMap;
use std::path::Path;

/// Write the groups' largest forces of `tensions` (per link of `s`, N).
pub(super) fn write_group_forces(
    dir: &Path,
    solver: &str,
    alpha: f64,
    s: &Structure,
    tensions: &[f64],
) -> std::io::Result<()> {
    // Per group in order of first appearance: (label, members, largest |τ| signed, its link).
    let mut rows: Vec<(&str, usize, f64, usize)> = Vec::new();
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (i, &t) in tensions.iter().enumerate() {
        let Some(label) = s.group_of(i) else {
            return Ok(());
        };
        let k = *index.entry(label).or_insert_with(|| {
            rows.push((label, 0, t, i));
            rows.len() - 1
        });
        let row = &mut rows[k];
        row.1 += 1;
        if t.abs() > row.2.abs() {
            (row.2, row.3) = (t, i);
        }
    }
    // As every per-solve file: `dir/groups/{solver}_alpha{α}.csv`.
    let path = dir
        .join("groups")
        .join(format!("{solver}_alpha{}.csv", alpha_label(alpha)));
    write_atomic(&path, |w| {
        writeln!(w, "group,kind,members,largest_force_N,member")?;
        for (label, members, force, i) in &rows {
            writeln!(
                w,
                "{label},{},{members},{force},{}",
                s.kind_name(*i),
                s.links[*i].id
            )?;
        }
        Ok(())
    })
}
