//! The files of a run with load combinations, over its combinations' own directories
//! (`combinations/<name>/`, each a whole run's files): `summary.csv`, their summary rows with a
//! `combination` column first; `envelope/members.csv`, per solver, α and member the largest
//! and smallest axial force and which combination gives each, and the largest utilisation
//! where members are checked; `envelope/nodes.csv`, per solver, α and node the largest
//! displacement. Read back from the combinations' `forces/` and `displacements/` (shortest
//! round-trip numbers: the same bits), written atomically.

use super::{alpha_label, write_atomic};
use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};

/// `envelope/members.csv`'s header.
pub const ENVELOPE_MEMBERS_HEADER: &str = "solver,alpha,member,kind,combinations,max_force_N,max_force_combination,min_force_N,min_force_combination,max_utilisation,max_utilisation_combination";

/// `envelope/nodes.csv`'s header.
pub const ENVELOPE_NODES_HEADER: &str =
    "solver,alpha,node,combinations,max_displacement_m,max_displacement_combination";

/// A combination's name and the directory its run wrote.
pub type Combined = (String, PathBuf);

/// `dir/summary.csv`: every combination's (or stage's) `summary.csv` rows, its name first in
/// the column `column`.
pub fn write_combined_summary(dir: &Path, combined: &[Combined], column: &str) -> io::Result<()> {
    let mut header = None;
    let mut rows = Vec::new();
    for (name, sub) in combined {
        let text = std::fs::read_to_string(sub.join("summary.csv"))?;
        let mut lines = text.lines();
        header = header.or(lines.next().map(str::to_string));
        rows.extend(lines.map(|l| format!("{name},{l}")));
    }
    let header = header.unwrap_or_default();
    write_atomic(&dir.join("summary.csv"), |w| {
        writeln!(w, "{column},{header}")?;
        rows.iter().try_for_each(|r| writeln!(w, "{r}"))
    })
}

/// A CSV file's rows as maps from column to cell.
fn rows(path: &Path) -> io::Result<Vec<BTreeMap<String, String>>> {
    let mut reader = csv::Reader::from_path(path).map_err(io::Error::other)?;
    let header: Vec<String> = reader
        .headers()
        .map_err(io::Error::other)?
        .iter()
        .map(String::from)
        .collect();
    reader
        .records()
        .map(|r| {
            let r = r.map_err(io::Error::other)?;
            Ok(header
                .iter()
                .cloned()
                .zip(r.iter().map(String::from))
                .collect())
        })
        .collect()
}

/// The number in `row[column]`, if the column is there and the cell is not empty.
fn cell(row: &BTreeMap<String, String>, column: &str) -> Option<f64> {
    row.get(column).and_then(|v| v.parse().ok())
}

/// The largest value seen and where.
#[derive(Default)]
struct Extreme {
    value: Option<(f64, usize)>,
}

impl Extreme {
    /// Keep `value` of combination `c` when larger (`sign` −1: when smaller).
    fn see(&mut self, value: f64, c: usize, sign: f64) {
        if self.value.is_none_or(|(v, _)| sign * value > sign * v) {
            self.value = Some((value, c));
        }
    }

    fn cells(&self, names: &[&str]) -> String {
        match self.value {
            Some((v, c)) => format!("{v},{}", names[c]),
            None => ",".to_string(),
        }
    }
}

/// `dir/envelope/members.csv` and `nodes.csv` over `combined`, for each (solver, α) of `keys`
/// whose files the combinations wrote (a combination without them, a solve with no answer,
/// is left out, and the `combinations` column counts those in).
pub fn write_envelopes(
    dir: &Path,
    combined: &[Combined],
    keys: &[(String, f64)],
) -> io::Result<()> {
    let names: Vec<&str> = combined.iter().map(|(n, _)| n.as_str()).collect();
    let mut members = Vec::new();
    let mut nodes = Vec::new();
    for (solver, alpha) in keys {
        let file = |sub: &Path, kind: &str| {
            sub.join(kind)
                .join(format!("{solver}_alpha{}.csv", alpha_label(*alpha)))
        };
        let label = alpha_label(*alpha);
        // Per member: kind, count, largest force, smallest force, largest utilisation.
        let mut member: BTreeMap<u64, (String, usize, Extreme, Extreme, Extreme)> = BTreeMap::new();
        let mut node: BTreeMap<u64, (usize, Extreme)> = BTreeMap::new();
        for (c, (_, sub)) in combined.iter().enumerate() {
            let forces = file(sub, "forces");
            if forces.exists() {
                for r in rows(&forces)? {
                    let id: u64 = r["member"].parse().map_err(io::Error::other)?;
                    let e = member.entry(id).or_insert_with(|| {
                        (
                            r["kind"].clone(),
                            0,
                            Extreme::default(),
                            Extreme::default(),
                            Extreme::default(),
                        )
                    });
                    e.1 += 1;
                    if let Some(f) = cell(&r, "force_N") {
                        e.2.see(f, c, 1.0);
                        e.3.see(f, c, -1.0);
                    }
                    let utilisation = ["utilisation", "buckling_utilisation", "cable_utilisation"]
                        .iter()
                        .filter_map(|k| cell(&r, k))
                        .reduce(f64::max);
                    if let Some(u) = utilisation {
                        e.4.see(u, c, 1.0);
                    }
                }
            }
            let displacements = file(sub, "displacements");
            if displacements.exists() {
                for r in rows(&displacements)? {
                    let id: u64 = r["node"].parse().map_err(io::Error::other)?;
                    let u = ["ux", "uy", "uz"]
                        .iter()
                        .map(|k| cell(&r, k).unwrap_or(0.0).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    let e = node.entry(id).or_default();
                    e.0 += 1;
                    e.1.see(u, c, 1.0);
                }
            }
        }
        for (id, (kind, count, high, low, utilisation)) in &member {
            members.push(format!(
                "{solver},{label},{id},{kind},{count},{},{},{}",
                high.cells(&names),
                low.cells(&names),
                utilisation.cells(&names)
            ));
        }
        for (id, (count, high)) in &node {
            nodes.push(format!(
                "{solver},{label},{id},{count},{}",
                high.cells(&names)
            ));
        }
    }
    let envelope = dir.join("envelope");
    std::fs::create_dir_all(&envelope)?;
    let write = |name: &str, header: &str, lines: &[String]| {
        write_atomic(&envelope.join(name), |w| {
            writeln!(w, "{header}")?;
            lines.iter().try_for_each(|l| writeln!(w, "{l}"))
        })
    };
    write("members.csv", ENVELOPE_MEMBERS_HEADER, &members)?;
    write("nodes.csv", ENVELOPE_NODES_HEADER, &nodes)
}
