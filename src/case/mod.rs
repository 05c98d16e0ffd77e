//! The case file: what structure to build, which effects to model, which solvers to run and
//! which outputs to write. The file is parsed into raw serde structs ([`raw`]) and converted
//! into a fully typed [`Case`] ([`convert`]) whose numbers are known to be finite and physical;
//! every other module receives that.

mod convert;
mod error;
mod raw;
mod typed;

pub use error::CaseError;
pub use typed::{Case, Load, OutputChoice, ReferenceChoice, SolverChoice};

use std::path::Path;

/// Read, parse and validate a case file; the output directory defaults to
/// `out/<case file stem>`.
pub fn load(path: &Path) -> Result<Case, CaseError> {
    let text = read_bounded(path)?;
    let mut case = parse(&text)?;
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

/// The text of the case file at `path`, refused beyond [`CASE_MAX_BYTES`] (a device such as
/// `/dev/zero` is never read to its end).
fn read_bounded(path: &Path) -> Result<String, CaseError> {
    use std::io::Read;
    let io = |reason: String| CaseError::Io {
        path: path.display().to_string(),
        reason,
    };
    let file = std::fs::File::open(path).map_err(|e| io(e.to_string()))?;
    let mut bytes = Vec::new();
    file.take(CASE_MAX_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| io(e.to_string()))?;
    if bytes.len() as u64 > CASE_MAX_BYTES {
        return Err(io(format!(
            "it is larger than {} MiB; a case file is a few lines of TOML (give long α lists \
             as a range {{ from, to, steps }})",
            CASE_MAX_BYTES >> 20
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        io(format!(
            "it is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// Refuse a solver named twice (in `solver.methods` or on the command line, `key`).
pub fn check_distinct_methods(
    key: &'static str,
    methods: &[crate::solvers::Method],
) -> Result<(), CaseError> {
    convert::check_distinct_methods(key, methods)
}

/// Parse and validate case text (no output directory default is applied here).
pub fn parse(text: &str) -> Result<Case, CaseError> {
    let raw: raw::RawCase = toml::from_str(text).map_err(CaseError::from_toml)?;
    convert::convert(raw)
}
