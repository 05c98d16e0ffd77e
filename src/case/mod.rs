//! The case file: what structure to build, which effects to model, which solvers to run and
//! which outputs to write. The file is parsed into raw serde structs ([`raw`]) and converted
//! into a fully typed [`Case`] ([`convert`]) whose numbers are known to be finite and physical;
//! every other module receives that.

mod convert;
mod error;
mod raw;
mod tables;
mod typed;

pub use tables::read_geometry;

pub use error::CaseError;
pub use typed::{Case, Load, OutputChoice, ReferenceChoice, SolverChoice};

use std::path::Path;

/// Read, parse and validate a case file; the output directory defaults to
/// `out/<case file stem>`.
pub fn load(path: &Path) -> Result<Case, CaseError> {
    let text = std::fs::read_to_string(path).map_err(|e| CaseError::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let mut case = parse_in(&text, base)?;
    if case.output.dir.is_none() {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "case".into());
        case.output.dir = Some(Path::new("out").join(stem));
    }
    Ok(case)
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
