//! The files of `tensolve design --out DIR`: `nodes.csv` (the form designed), `members.csv`
//! (the prestress column filled, the groups kept), `groups.csv` (per group: kind, members,
//! force, force density and rest length) and `<case>.toml`, the case with its prestress given
//! by those tables, that `run` takes as written. Each is written atomically, after the design
//! succeeded: a refused design writes nothing.

use super::{DesignError, DesignReport};
use crate::case::{self, Case};
use crate::output::write_atomic;
use crate::structure::{MemberChecks, NodeFix};
use std::io::Write;
use std::path::Path;

/// Write the designed case of `case` (file `path`, overrides `set`) into `dir`.
pub fn write_design(
    dir: &Path,
    path: &Path,
    set: &[String],
    case: &Case,
    report: &DesignReport,
) -> Result<(), DesignError> {
    let stem = path
        .file_stem()
        .unwrap_or("case".as_ref())
        .to_string_lossy();
    let table = designed_table(path, set, case)?;
    let write = |name: &str, fill: &dyn Fn(&mut dyn Write) -> std::io::Result<()>| {
        let file = dir.join(name);
        write_atomic(&file, |w| fill(w)).map_err(|e| DesignError::Write {
            path: file,
            reason: e.to_string(),
        })
    };
    write("nodes.csv", &|w| nodes_csv(w, case))?;
    write("members.csv", &|w| members_csv(w, case))?;
    write("groups.csv", &|w| groups_csv(w, report))?;
    let text = toml::to_string(&table).unwrap_or_default();
    write(&format!("{stem}.toml"), &|w| {
        writeln!(
            w,
            "# Written by `tensolve design` from {}: the designed prestress is the members table's.",
            path.display()
        )?;
        w.write_all(text.as_bytes())
    })
}

/// `node,x,y,z`, shortest round-trip numbers (read back bit for bit).
fn nodes_csv(w: &mut dyn Write, case: &Case) -> std::io::Result<()> {
    writeln!(w, "node,x,y,z")?;
    for (id, p) in case.geometry.node_ids.iter().zip(&case.geometry.nodes) {
        writeln!(w, "{id},{},{},{}", p[0], p[1], p[2])?;
    }
    Ok(())
}

/// `member,a,b,kind,young,section,prestress,density,strength,inertia,buckling_curve,breaking_load,group`
/// (empty cells where the case gave none).
fn members_csv(w: &mut dyn Write, case: &Case) -> std::io::Result<()> {
    let g = &case.geometry;
    let groups = g.member_groups();
    writeln!(
        w,
        "member,a,b,kind,young,section,prestress,density,strength,inertia,buckling_curve,breaking_load,group"
    )?;
    let cell = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
    for (j, m) in g.members.iter().enumerate() {
        let checked = match &g.checks {
            Some(MemberChecks::Each(each)) => Some(each[j]),
            _ => None,
        };
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            m.id,
            g.node_ids[m.a],
            g.node_ids[m.b],
            m.kind.name(),
            m.young,
            m.section,
            m.prestress,
            m.density,
            cell(checked.and_then(|c| c.strength)),
            cell(checked.and_then(|c| c.inertia)),
            checked
                .and_then(|c| c.buckling)
                .map_or("", |b| b.curve.name()),
            cell(checked.and_then(|c| c.breaking.map(|b| b.load))),
            groups[j]
        )?;
    }
    Ok(())
}

/// Per group: `group,kind,members,force_min_N,force_max_N,q_min_N_per_m,q_max_N_per_m,rest_length_min_m,rest_length_max_m,given`.
fn groups_csv(w: &mut dyn Write, report: &DesignReport) -> std::io::Result<()> {
    writeln!(
        w,
        "group,kind,members,force_min_N,force_max_N,q_min_N_per_m,q_max_N_per_m,rest_length_min_m,rest_length_max_m,given"
    )?;
    for g in &report.groups {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{}",
            g.name,
            g.kind.name(),
            g.members,
            g.force[0],
            g.force[1],
            g.force_density[0],
            g.force_density[1],
            g.rest_length[0],
            g.rest_length[1],
            g.given.map_or(String::new(), |v| v.to_string())
        )?;
    }
    Ok(())
}

/// The case file's table (overrides applied) with the tables written here, its prestress
/// theirs, its supports and point loads named by node id (a box may hold other nodes once the
/// form is found).
fn designed_table(path: &Path, set: &[String], case: &Case) -> Result<toml::Table, DesignError> {
    let mut table = case::table_with(path, set)?;
    let mut structure = toml::Table::new();
    structure.insert("nodes".into(), "nodes.csv".into());
    structure.insert("members".into(), "members.csv".into());
    table.insert("structure".into(), structure.into());
    if let Some(prestress) = table.get_mut("prestress").and_then(|p| p.as_table_mut()) {
        for key in ["from", "targets", "min_cable", "force_density"] {
            prestress.remove(key);
        }
        if prestress.is_empty() {
            table.remove("prestress");
        }
    }
    let ids = &case.geometry.node_ids;
    let supports = table
        .entry("supports")
        .or_insert_with(|| toml::Table::new().into());
    if let Some(supports) = supports.as_table_mut() {
        supports.insert("fix".into(), fixes_array(&case.fixes, ids));
    }
    if !case.load.points.is_empty() {
        if let Some(load) = table.get_mut("load").and_then(|l| l.as_table_mut()) {
            load.insert("point".into(), points_array(&case.load.points, ids));
        }
    }
    Ok(table)
}

/// `[[supports.fix]]` by node id: one entry per run of nodes held alike.
fn fixes_array(fixes: &[NodeFix], ids: &[u64]) -> toml::Value {
    let mut out: Vec<(Vec<u64>, [bool; 3], [f64; 3])> = Vec::new();
    for f in fixes {
        match out.last_mut() {
            Some(last) if last.1 == f.dofs && last.2 == f.displacement => last.0.push(ids[f.node]),
            _ => out.push((vec![ids[f.node]], f.dofs, f.displacement)),
        }
    }
    let entries = out.into_iter().map(|(nodes, dofs, displacement)| {
        let mut t = toml::Table::new();
        t.insert("nodes".into(), ids_value(&nodes));
        if dofs != [true; 3] {
            let names: Vec<toml::Value> = ["x", "y", "z"]
                .iter()
                .zip(dofs)
                .filter(|(_, held)| *held)
                .map(|(n, _)| (*n).into())
                .collect();
            t.insert("dofs".into(), names.into());
        }
        if displacement != [0.0; 3] {
            t.insert("displacement".into(), floats(&displacement));
        }
        toml::Value::Table(t)
    });
    toml::Value::Array(entries.collect())
}

/// `[[load.point]]` by node id: one entry per run of nodes loaded alike.
fn points_array(points: &[(usize, [f64; 3])], ids: &[u64]) -> toml::Value {
    let mut out: Vec<(Vec<u64>, [f64; 3])> = Vec::new();
    for &(node, force) in points {
        match out.last_mut() {
            Some(last) if last.1 == force && !last.0.contains(&ids[node]) => last.0.push(ids[node]),
            _ => out.push((vec![ids[node]], force)),
        }
    }
    let entries = out.into_iter().map(|(nodes, force)| {
        let mut t = toml::Table::new();
        t.insert("nodes".into(), ids_value(&nodes));
        t.insert("force".into(), floats(&force));
        toml::Value::Table(t)
    });
    toml::Value::Array(entries.collect())
}

fn ids_value(ids: &[u64]) -> toml::Value {
    toml::Value::Array(
        ids.iter()
            .map(|&i| toml::Value::Integer(i as i64))
            .collect(),
    )
}

fn floats(v: &[f64; 3]) -> toml::Value {
    toml::Value::Array(v.iter().map(|&x| toml::Value::Float(x)).collect())
}
