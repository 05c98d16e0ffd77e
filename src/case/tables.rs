//! The `[structure]` tables: `nodes.csv` (`node,x,y,z`) and `members.csv`
//! (`member,a,b,kind,young,section,prestress[,density[,strength[,inertia[,buckling_curve[,breaking_load]]]]][,group]`). Every row is checked and an error
//! names the file, the line, the column, the value and the fix.

use super::numbers::{PHYSICAL_MAX, PHYSICAL_MIN};
use super::CaseError;
use crate::structure::{
    length_and_direction, Buckling, BucklingCurve, CableBreaking, CheckedMember, Geometry,
    LinkKind, Member, MemberChecks,
};
use std::collections::HashMap;
use std::path::Path;

/// A table's row: its line number and its cells.
type Row = (u64, Vec<String>);

/// One table being read: its file name for messages.
struct Table<'a> {
    file: &'a str,
}

impl Table<'_> {
    fn error(&self, line: u64, column: &str, value: &str, fix: impl Into<String>) -> CaseError {
        CaseError::Table {
            file: self.file.to_string(),
            line,
            column: column.to_string(),
            value: value.to_string(),
            fix: fix.into(),
        }
    }

    /// Read `text` as CSV with the header `required` (+ `optional`, in order, then `last`
    /// when the header ends with it): the rows, each with its line number and one string per
    /// column (optional ones empty when absent), and whether the header has `last`.
    fn rows(
        &self,
        text: &str,
        required: &[&str],
        optional: &[&str],
        last: Option<&str>,
    ) -> Result<(Vec<Row>, bool), CaseError> {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(text.as_bytes());
        let mut records = reader.records();
        // The required columns, then the optional ones said as such (a header without them is
        // whole).
        let expected = || {
            let mut text = format!("`{}`", required.join(","));
            // Each optional column in turn: `,density`, then `,strength`, then `,inertia`.
            for (k, column) in optional.iter().enumerate() {
                let lead = if k == 0 {
                    ", optionally followed by"
                } else {
                    ", then"
                };
                text.push_str(&format!("{lead} `,{column}`"));
            }
            if let Some(last) = last {
                text.push_str(&format!(", and optionally last `,{last}`"));
            }
            text
        };
        let header = match records.next() {
            None => {
                return Err(self.error(
                    1,
                    "header",
                    "",
                    format!("the file is empty: start it with the header {}", expected()),
                ))
            }
            Some(Err(e)) => return Err(self.csv_error(e)),
            Some(Ok(h)) => h,
        };
        let line = header.position().map_or(1, |p| p.line());
        let names: Vec<&str> = header.iter().collect();
        let has_last = last.is_some() && names.last().copied() == last;
        let n = names.len() - usize::from(has_last);
        let ok = n >= required.len()
            && n <= required.len() + optional.len()
            && names[..n]
                .iter()
                .zip(required.iter().chain(optional))
                .all(|(a, b)| a == b);
        if !ok {
            return Err(self.error(
                line,
                "header",
                &names.join(","),
                format!("the header must be {}", expected()),
            ));
        }
        let mut rows = Vec::new();
        for record in records {
            let record = record.map_err(|e| self.csv_error(e))?;
            let line = record.position().map_or(0, |p| p.line());
            if record.len() == 1 && record[0].is_empty() {
                continue;
            }
            if record.len() != names.len() {
                return Err(self.error(
                    line,
                    names
                        .get(record.len().min(names.len() - 1))
                        .copied()
                        .unwrap_or("header"),
                    &record.iter().collect::<Vec<_>>().join(","),
                    format!(
                        "the row has {} values: give exactly {} (`{}`)",
                        record.len(),
                        names.len(),
                        names.join(",")
                    ),
                ));
            }
            rows.push((line, record.iter().map(str::to_string).collect()));
        }
        Ok((rows, has_last))
    }

    fn csv_error(&self, e: csv::Error) -> CaseError {
        let line = e.position().map_or(0, |p| p.line());
        self.error(
            line,
            "row",
            "",
            format!("not valid CSV ({e}); write plain UTF-8 comma-separated values"),
        )
    }

    /// A finite number within ±[`PHYSICAL_MAX`], `positive` if asked.
    fn number(
        &self,
        line: u64,
        column: &str,
        text: &str,
        positive: bool,
    ) -> Result<f64, CaseError> {
        let value: f64 = text
            .parse()
            .map_err(|_| self.error(line, column, text, format!("`{column}` must be a number")))?;
        // The same bounds as the case file's physical numbers; the cell is shown as written
        // (a 500-digit number is not `inf`).
        if !value.is_finite() || value.abs() > PHYSICAL_MAX || (positive && value < PHYSICAL_MIN) {
            let what = if positive {
                format!("> 0, at least {PHYSICAL_MIN:e} and ")
            } else {
                "finite and of magnitude ".to_string()
            };
            // Shown as written, cut to 40 characters (a cell may be thousands long).
            let shown = match text.char_indices().nth(40) {
                Some((cut, _)) => {
                    format!("{}… ({} characters)", &text[..cut], text.chars().count())
                }
                None => text.to_string(),
            };
            return Err(self.error(
                line,
                column,
                &shown,
                format!("`{column}` must be {what}≤ {PHYSICAL_MAX:e}"),
            ));
        }
        Ok(value)
    }

    fn id(&self, line: u64, column: &str, text: &str) -> Result<u64, CaseError> {
        text.parse().map_err(|_| {
            self.error(
                line,
                column,
                text,
                format!("`{column}` must be a non-negative integer id"),
            )
        })
    }
}

/// Nodes and members of the `[structure]` tables given as texts; `nodes_name` and
/// `members_name` are the file names used in messages.
pub fn read_geometry(
    nodes_name: &str,
    nodes_text: &str,
    members_name: &str,
    members_text: &str,
    unilateral: bool,
) -> Result<Geometry, CaseError> {
    let (node_ids, nodes, index_of) = read_nodes(nodes_name, nodes_text)?;
    let (members, checks, groups) =
        read_members(members_name, members_text, nodes_name, &nodes, &index_of)?;
    Ok(Geometry {
        node_ids,
        nodes,
        members,
        unilateral,
        grid_roles: None,
        checks,
        groups,
    })
}

/// Node ids, positions, and each id's (index, line), of the nodes table.
type Nodes = (Vec<u64>, Vec<[f64; 3]>, HashMap<u64, (usize, u64)>);

/// The nodes table `nodes_text` (file `nodes_name`): every id unique, every coordinate a
/// bounded number.
fn read_nodes(nodes_name: &str, nodes_text: &str) -> Result<Nodes, CaseError> {
    let table = Table { file: nodes_name };
    let mut node_ids = Vec::new();
    let mut nodes = Vec::new();
    let mut index_of: HashMap<u64, (usize, u64)> = HashMap::new();
    for (line, row) in table
        .rows(nodes_text, &["node", "x", "y", "z"], &[], None)?
        .0
    {
        let id = table.id(line, "node", &row[0])?;
        if let Some(&(_, first)) = index_of.get(&id) {
            return Err(table.error(
                line,
                "node",
                &row[0],
                format!(
                    "node {id} is already defined on line {first}: give every node a unique id"
                ),
            ));
        }
        let mut p = [0.0; 3];
        for k in 0..3 {
            p[k] = table.number(line, ["x", "y", "z"][k], &row[k + 1], false)?;
        }
        index_of.insert(id, (nodes.len(), line));
        node_ids.push(id);
        nodes.push(p);
    }
    if nodes.is_empty() {
        return Err(table.error(1, "node", "", "give at least two nodes, one row each"));
    }
    Ok((node_ids, nodes, index_of))
}

/// Members, their checks' data when given, and their groups when the table has a `group`
/// column.
type Members = (Vec<Member>, Option<MemberChecks>, Option<Vec<String>>);

/// The members table `members_text` (file `members_name`) between the nodes of `nodes` (ids
/// in `index_of`, from the file `nodes_name`): every id unique, both ends defined and apart,
/// a known kind, physical properties; with the member checks' data when a row gives a
/// `strength` or an `inertia`.
fn read_members(
    members_name: &str,
    members_text: &str,
    nodes_name: &str,
    nodes: &[[f64; 3]],
    index_of: &HashMap<u64, (usize, u64)>,
) -> Result<Members, CaseError> {
    let table = Table { file: members_name };
    let mut members = Vec::new();
    let mut checks = Vec::new();
    let mut seen: HashMap<u64, u64> = HashMap::new();
    let columns = ["member", "a", "b", "kind", "young", "section", "prestress"];
    let optional = [
        "density",
        "strength",
        "inertia",
        "buckling_curve",
        "breaking_load",
    ];
    let (rows, grouped) = table.rows(members_text, &columns, &optional, Some("group"))?;
    let mut groups = Vec::new();
    for (line, mut row) in rows {
        if grouped {
            groups.push(table.group(line, row.pop().unwrap_or_default())?);
        }
        let id = table.id(line, "member", &row[0])?;
        if let Some(first) = seen.insert(id, line) {
            return Err(table.error(
                line,
                "member",
                &row[0],
                format!(
                    "member {id} is already defined on line {first}: give every member a unique id"
                ),
            ));
        }
        let end = |column: &str, text: &str| -> Result<usize, CaseError> {
            let node = table.id(line, column, text)?;
            index_of.get(&node).map(|&(i, _)| i).ok_or_else(|| {
                table.error(
                    line,
                    column,
                    text,
                    format!("node {node} is not in `{nodes_name}`: name a node defined there"),
                )
            })
        };
        let a = end("a", &row[1])?;
        let b = end("b", &row[2])?;
        let kind = match row[3].as_str() {
            "bar" => LinkKind::Bar,
            "cable" => LinkKind::Cable,
            other => {
                return Err(table.error(line, "kind", other, "`kind` must be `bar` or `cable`"))
            }
        };
        let young = table.number(line, "young", &row[4], true)?;
        let section = table.number(line, "section", &row[5], true)?;
        let prestress = table.number(line, "prestress", &row[6], false)?;
        let (density, strength, inertia) = table.optional_cells(line, id, kind, &row)?;
        let (length, _) = length_and_direction(nodes[a], nodes[b]);
        let scale = nodes[a]
            .iter()
            .chain(&nodes[b])
            .fold(0.0, |m: f64, x| m.max(x.abs()));
        // Coordinates are finite and ≤ 1e15, so the length is finite.
        if length <= 1e-12 * scale.max(1e-300) {
            return Err(table.error(
                line,
                "b",
                &row[2],
                format!(
                    "member {id} joins nodes {} and {} at the same position (zero length): join two distinct positions",
                    row[1], row[2]
                ),
            ));
        }
        members.push(Member {
            id,
            a,
            b,
            kind,
            young,
            section,
            prestress,
            density,
            module: 0,
        });
        let (buckling, breaking) = table.code_cells(line, id, kind, &row, strength, inertia)?;
        checks.push(CheckedMember {
            strength,
            inertia,
            buckling,
            breaking,
            ..CheckedMember::unchecked(young, section)
        });
    }
    if members.is_empty() {
        return Err(table.error(1, "member", "", "give at least one member, one row each"));
    }
    let checked = checks.iter().any(CheckedMember::is_checked);
    Ok((
        members,
        checked.then_some(MemberChecks::Each(checks)),
        grouped.then_some(groups),
    ))
}

impl Table<'_> {
    /// Member group label `text` (the `group` column): a non-empty name of letters, digits,
    /// `-`, `_` or `.` (a TOML bare key, so that `prestress.targets` can name it).
    fn group(&self, line: u64, text: String) -> Result<String, CaseError> {
        let bare = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.';
        if text.is_empty() || text.len() > 64 || !text.chars().all(bare) {
            return Err(self.error(
                line,
                "group",
                &text,
                "`group` must be a label of 1 to 64 letters, digits, `-`, `_` or `.` (e.g. `bars`, `lower-cables`)",
            ));
        }
        Ok(text)
    }

    /// The optional cells of member `id`'s row (a `kind`): `density` (kg/m³, ≥ 0; empty or
    /// absent: 0), `strength` (Pa, > 0) and `inertia` (m⁴, ≥ 0 on a cable, > 0 on a bar; empty
    /// or absent: not checked).
    fn optional_cells(
        &self,
        line: u64,
        id: u64,
        kind: LinkKind,
        row: &[String],
    ) -> Result<(f64, Option<f64>, Option<f64>), CaseError> {
        let cell = |k: usize| row.get(k).filter(|text| !text.is_empty());
        let density = match cell(7) {
            Some(text) => {
                let d = self.number(line, "density", text, false)?;
                if d < 0.0 {
                    return Err(self.error(line, "density", text, "`density` must be ≥ 0 (kg/m³)"));
                }
                d
            }
            None => 0.0,
        };
        let strength = match cell(8) {
            Some(text) => Some(self.limit(line, id, "strength", text, true, |v| {
                (v.is_nan() || v <= 0.0).then(|| {
                    "must be > 0 (Pa): give the member's design strength, or leave the cell \
                     empty to leave its stress unchecked"
                        .to_string()
                })
            })?),
            None => None,
        };
        let bar = kind == LinkKind::Bar;
        let inertia = match cell(9) {
            Some(text) => Some(self.limit(line, id, "inertia", text, bar, |v| {
                if v.is_nan() || v < 0.0 {
                    Some(
                        "must be ≥ 0 (m⁴): give the section's second moment of area about its \
                          weaker axis, or leave the cell empty to leave its buckling unchecked"
                            .to_string(),
                    )
                } else if bar && v == 0.0 {
                    Some(
                        "must be > 0 on a bar (m⁴): a bar without bending stiffness buckles \
                          under any compression; give the section's second moment of area about \
                          its weaker axis, or leave the cell empty to leave its buckling unchecked"
                            .to_string(),
                    )
                } else {
                    None
                }
            })?),
            None => None,
        };
        Ok((density, strength, inertia))
    }

    /// Member `id`'s cells of EN 1993's checks: `buckling_curve` (a bar with a `strength`,
    /// read as f_y, and an `inertia`) and `breaking_load` (a cable's F_uk, N, > 0); empty or
    /// absent: not checked. The partial factors are put on later (`code_checks`).
    fn code_cells(
        &self,
        line: u64,
        id: u64,
        kind: LinkKind,
        row: &[String],
        strength: Option<f64>,
        inertia: Option<f64>,
    ) -> Result<(Option<Buckling>, Option<CableBreaking>), CaseError> {
        let cell = |k: usize| row.get(k).filter(|text| !text.is_empty());
        let bar = kind == LinkKind::Bar;
        let buckling = match cell(10) {
            None => None,
            Some(text) => {
                let refuse = |fix: String| Err(self.error(line, "buckling_curve", text, fix));
                let Some(curve) = BucklingCurve::from_name(text) else {
                    return refuse(format!(
                        "member {id}: `buckling_curve` must be one of EN 1993-1-1 Table 6.1's                          curves `a0`, `a`, `b`, `c`, `d`, or empty"
                    ));
                };
                if !bar {
                    return refuse(format!(
                        "member {id} is a cable: a buckling curve is a bar's; leave the cell empty"
                    ));
                }
                if strength.is_none() || inertia.is_none() {
                    return refuse(format!(
                        "member {id}: the buckling resistance χ A f_y / γ_M1 needs its                          `strength` (f_y) and `inertia`: give both, or leave the cell empty"
                    ));
                }
                Some(Buckling {
                    curve,
                    gamma_m1: f64::NAN,
                })
            }
        };
        let breaking = match cell(11) {
            None => None,
            Some(text) => {
                let load = self.limit(line, id, "breaking_load", text, true, |v| {
                    if v.is_nan() || v <= 0.0 {
                        Some("must be > 0 (N): give the cable's characteristic breaking load F_uk, or leave the cell empty".to_string())
                    } else if bar {
                        Some("is a cable's (EN 1993-1-11): this member is a bar; leave the cell empty".to_string())
                    } else {
                        None
                    }
                })?;
                Some(CableBreaking {
                    load,
                    gamma_r: f64::NAN,
                })
            }
        };
        Ok((buckling, breaking))
    }

    /// Member `id`'s `column` of `text`: a number that `refuse` finds nothing wrong with (it
    /// says what is, with the fix), else an error naming the member, the column and the value;
    /// then bounded as every physical number (`positive`: at least the smallest one).
    fn limit(
        &self,
        line: u64,
        id: u64,
        column: &str,
        text: &str,
        positive: bool,
        refuse: impl Fn(f64) -> Option<String>,
    ) -> Result<f64, CaseError> {
        if let Some(why) = text.parse::<f64>().ok().and_then(&refuse) {
            return Err(self.error(line, column, text, format!("member {id}: `{column}` {why}")));
        }
        self.number(line, column, text, positive)
    }
}

/// Read the two tables from files (paths as given, already resolved against the case file).
pub fn load_geometry(
    nodes: &Path,
    members: &Path,
    unilateral: bool,
) -> Result<Geometry, CaseError> {
    let read = |path: &Path, what: &'static str| {
        super::read_text(
            path,
            what,
            super::TABLE_MAX_BYTES,
            "a table holds one line per node or member (about four million members at most)",
        )
    };
    read_geometry(
        &nodes.display().to_string(),
        &read(nodes, "nodes table")?,
        &members.display().to_string(),
        &read(members, "members table")?,
        unilateral,
    )
}
