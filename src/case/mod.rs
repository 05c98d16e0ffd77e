//! The case file: what structure to build, which effects to model, which solvers to run and
//! which outputs to write. The file is parsed into raw serde structs (`raw`) and converted
//! into a fully typed `Case` (`convert`) whose numbers are known to be finite and physical;
//! every other module receives that.
//!
//! Inside, one way only: the checks of a number, the typed case and the raw structs under
//! everything; one file per part of the case file converts it, and `convert` calls them in file
//! order (docs/guide.md's source layout lists them). Every file is read through `read_text`,
//! whose bytes `sources` can record (MPI rank 0) or replay (the others).

mod actions;
mod code_checks;
mod combinations;
mod convert;
mod design;
mod error;
mod force_density;
mod grid;
mod load;
mod loads;
mod modal;
mod nodes;
mod numbers;
mod output;
mod prestress;
mod raw;
mod rebalance;
mod solver;
pub mod sources;
mod stages;
mod tables;
mod typed;

pub use tables::read_geometry;

pub use combinations::PRESTRESS_FACTOR;
pub use design::{Design, GroupForce};
pub use error::CaseError;
pub use solver::default_subdomains;
pub use typed::{
    Case, Combination, Load, LoadCase, OutputChoice, ReferenceChoice, SolverChoice, Stage,
    StageStart,
};

use serde::Deserialize;
use std::path::Path;

/// Read, parse and validate a case file; the output directory defaults to
/// `out/<case file stem>`.
pub fn load(path: &Path) -> Result<Case, CaseError> {
    load_with(path, &[])
}

/// As [`load`], with `key=value` overrides (the command line's `--set`) applied to the file's
/// keys before validation: the key is dotted (`solver.dm`), the value TOML (`2e6`, `[0.5]`,
/// `"newton"`). An override that does not fit is named in the error.
pub fn load_with(path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
    let text = read_bounded(path)?;
    let base = path.parent().unwrap_or(Path::new(""));
    let mut case = if overrides.is_empty() {
        parse_in(&text, base)?
    } else {
        parse_with_in(&text, overrides, base)?
    };
    if case.output.dir.is_none() {
        // The stem as the file system gave it: a name that is not UTF-8 stays that name.
        let stem = path.file_stem().unwrap_or("case".as_ref());
        case.output.dir = Some(Path::new("out").join(stem));
    }
    Ok(case)
}

/// The largest case file read: far above any hand-written case (the paper's is 1 kB) and a
/// list of 100,000 load factors, far below what parsing could exhaust memory with.
pub const CASE_MAX_BYTES: u64 = 4 << 20;

/// The largest node or member table read: 256 MiB is about four million members, beyond
/// what a structure given as a table is (grids are generated, not read).
pub const TABLE_MAX_BYTES: u64 = 256 << 20;

/// The text of the case file at `path`, refused beyond [`CASE_MAX_BYTES`] (a device such as
/// `/dev/zero` is never read to its end).
fn read_bounded(path: &Path) -> Result<String, CaseError> {
    read_text(
        path,
        "case file",
        CASE_MAX_BYTES,
        "a case file is a few lines of TOML (give long α lists as a range { from, to, steps })",
    )
}

/// The text of the file `what` at `path`, refused beyond `limit` bytes (`why` says what such a
/// file holds) or when it is not UTF-8.
pub(crate) fn read_text(
    path: &Path,
    what: &'static str,
    limit: u64,
    why: &str,
) -> Result<String, CaseError> {
    use std::io::Read;
    let read = || -> Result<String, String> {
        let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
        let mut bytes = Vec::new();
        file.take(limit + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| e.to_string())?;
        if bytes.len() as u64 > limit {
            return Err(format!("it is larger than {} MiB; {why}", limit >> 20));
        }
        String::from_utf8(bytes).map_err(|e| {
            format!(
                "it is not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            )
        })
    };
    sources::read_through(path, read).map_err(|reason| CaseError::Io {
        what,
        path: path.display().to_string(),
        reason,
    })
}

/// Refuse a solver named twice (in `solver.methods` or on the command line, `key`).
pub fn check_distinct_methods(
    key: &'static str,
    methods: &[crate::solvers::Method],
) -> Result<(), CaseError> {
    solver::check_distinct_methods(key, methods)
}

/// As [`load_with`], the members table's prestress re-balanced: projected on the self-stress
/// states, least squares (`tensolve design --rebalance`; the report says the largest change).
pub fn load_rebalanced(path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
    let table = table_with(path, overrides)?;
    let mut raw = raw::RawCase::deserialize(toml::Value::Table(table))
        .map_err(|e| CaseError::Syntax(e.to_string().trim_end().to_string()))?;
    raw.rebalance = true;
    convert::convert(raw, path.parent().unwrap_or(Path::new("")))
}

/// The case file at `path` as a TOML table with `key=value` overrides applied, not validated
/// (`tensolve design` writes the designed case from it).
pub fn table_with(path: &Path, overrides: &[String]) -> Result<toml::Table, CaseError> {
    let mut table: toml::Table =
        toml::from_str(&read_bounded(path)?).map_err(CaseError::from_toml)?;
    for set in overrides {
        apply_override(&mut table, set)?;
    }
    Ok(table)
}

/// Parse and validate case text (no output directory default is applied here); `[structure]`
/// tables are read relative to the current directory.
pub fn parse(text: &str) -> Result<Case, CaseError> {
    parse_in(text, Path::new(""))
}

/// Parse and validate case text whose `[structure]` tables are relative to `base`.
pub fn parse_in(text: &str, base: &Path) -> Result<Case, CaseError> {
    let raw: raw::RawCase = toml::from_str(text).map_err(CaseError::from_toml)?;
    convert::convert(raw, base)
}

/// Parse case text, apply `key=value` overrides, and validate (`[structure]` tables relative
/// to the current directory).
pub fn parse_with(text: &str, overrides: &[String]) -> Result<Case, CaseError> {
    parse_with_in(text, overrides, Path::new(""))
}

/// As [`parse_with`], with `[structure]` tables relative to `base`.
pub fn parse_with_in(text: &str, overrides: &[String], base: &Path) -> Result<Case, CaseError> {
    let mut table: toml::Table = toml::from_str(text).map_err(CaseError::from_toml)?;
    for set in overrides {
        apply_override(&mut table, set)?;
    }
    let raw = raw::RawCase::deserialize(toml::Value::Table(table)).map_err(|e| {
        // The overrides it is due to; where none is, the file's own mistake, with its line and
        // column (N-D4: a misspelt key was blamed on an unrelated --set), or every override.
        let blamed = culprits(text, overrides);
        match (blamed.is_empty(), toml::from_str::<raw::RawCase>(text)) {
            (true, Err(own)) => CaseError::from_toml(own),
            (true, Ok(_)) => CaseError::Override {
                set: overrides.join(" "),
                reason: e.to_string().trim_end().to_string(),
            },
            (false, _) => CaseError::Override {
                set: blamed.join(" "),
                reason: e.to_string().trim_end().to_string(),
            },
        }
    })?;
    convert::convert(raw, base).map_err(|e| match e {
        // A value an override set: say so.
        CaseError::Invalid { key, value, fix } => {
            match overrides
                .iter()
                .find(|s| s.split('=').next() == Some(key.as_str()))
            {
                Some(set) => CaseError::Override {
                    set: set.clone(),
                    reason: format!("`{key}` = {value} is not valid: {fix}"),
                },
                None => CaseError::Invalid { key, value, fix },
            }
        }
        other => other,
    })
}

/// The overrides a failed deserialisation is due to: those without which the case file, with
/// the others, reads (an override may also mend the file's own mistake at its key).
fn culprits<'o>(text: &str, overrides: &'o [String]) -> Vec<&'o str> {
    // Whether the case file reads with every override but `left_out`.
    let reads_without = |left_out: usize| -> bool {
        let Ok(mut table) = toml::from_str::<toml::Table>(text) else {
            return false;
        };
        overrides
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != left_out)
            .all(|(_, set)| apply_override(&mut table, set).is_ok())
            && raw::RawCase::deserialize(toml::Value::Table(table)).is_ok()
    };
    (0..overrides.len())
        .filter(|&k| reads_without(k))
        .map(|k| overrides[k].as_str())
        .collect()
}

/// Set one `key=value` (dotted key, TOML value) in the case's table, creating tables on the way.
fn apply_override(table: &mut toml::Table, set: &str) -> Result<(), CaseError> {
    let error = |reason: String| CaseError::Override {
        // A newline shown as `\n`: the message stays one line.
        set: set.replace('\n', "\\n"),
        reason,
    };
    let Some((key, value)) = set.split_once('=') else {
        return Err(error(
            "write it as key=value with a dotted key and a TOML value, e.g. solver.dm=2e6 or \
             load.alpha=[0.5,1.0]"
                .into(),
        ));
    };
    let path: Vec<&str> = key.trim().split('.').map(str::trim).collect();
    if path.iter().any(|p| p.is_empty()) {
        return Err(error(format!(
            "`{key}` is not a dotted key such as solver.dm"
        )));
    }
    let parsed = toml::from_str::<toml::Table>(&format!("v = {value}")).ok();
    // One TOML value and nothing more: what follows a newline (another key, a table header)
    // would be parsed beside `v`.
    if parsed.as_ref().is_some_and(|t| t.len() > 1) {
        return Err(error(format!(
            "`{}` holds more than one value (a newline, then another key or table): give each \
             key its own --set",
            value.replace('\n', "\\n")
        )));
    }
    let value: toml::Value = parsed.and_then(|mut t| t.remove("v")).ok_or_else(|| {
        error(format!(
            "`{}` is not a TOML value; quote strings (solver.methods=[\"newton\"]), write lists \
             in brackets ([0.5, 1.0])",
            value.replace('\n', "\\n")
        ))
    })?;
    let (last, parents) = path.split_last().expect("a key has at least one part");
    let mut node = table;
    for part in parents {
        let entry = node
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        node = entry.as_table_mut().ok_or_else(|| {
            error(format!(
                "`{part}` is a value, not a table, so `{key}` cannot be set"
            ))
        })?;
    }
    node.insert(last.to_string(), value);
    Ok(())
}
