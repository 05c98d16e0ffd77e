//! `tensolve compare RUN GOLDEN`: a run against stored results, for CI regression. Every CSV
//! of the golden directory (summary, tensions, displacements, histories, bench) must exist in
//! the run with the same columns; values are compared column by column, numbers within
//! `|a − b| ≤ atol + rtol · max(|a|, |b|)`, everything else exactly. Timing columns (names
//! ending in `seconds`) are left out. Slack counts and slack sets are exact unless a slack
//! tolerance is given. Links are followed when reading, in both directories (golden trees of
//! links: Bazel runfiles, git-annex). A golden CSV missing from the run, or with other
//! columns there, is a difference (exit 1); only a call that cannot be answered (no such
//! directory, a golden directory with no CSV or an unreadable golden file) is an error (exit 2).

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// Tolerances of a comparison, each default written once.
#[derive(Debug, Clone, Copy)]
pub struct CompareSettings {
    /// Relative tolerance on numbers. Default 1e-6.
    pub rtol: f64,
    /// Absolute tolerance on numbers. Default 1e-12.
    pub atol: f64,
    /// How many cables a slack count (`slack_cables`, `slack_*` counts) or a slack set (the
    /// cables at zero tension in `tensions/`) may differ by. Default 0: exact.
    pub slack_tolerance: u64,
}

impl Default for CompareSettings {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: 1e-12,
            slack_tolerance: 0,
        }
    }
}

/// Why two directories cannot be compared (exit status 2).
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A directory does not exist, cannot be read, or (golden) holds no CSV.
    #[error("{path}: {reason}")]
    Directory {
        /// The directory.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A golden CSV could not be read.
    #[error("{file} in the golden directory: {reason}")]
    Unreadable {
        /// The file.
        file: String,
        /// What went wrong.
        reason: String,
    },
}

/// One column of one file where the runs differ.
#[derive(Debug, Clone, PartialEq)]
pub struct Difference {
    /// The file, relative to both directories.
    pub file: String,
    /// The column (`rows` when the row counts differ).
    pub column: String,
    /// Rows (1-based, after the header) that differ.
    pub rows: usize,
    /// The first differing row.
    pub first_row: usize,
    /// The run's and the golden value there.
    pub first: (String, String),
    /// Largest absolute difference of the numbers that differ (0 for text).
    pub max_abs: f64,
    /// Largest relative difference of the numbers that differ (0 for text).
    pub max_rel: f64,
}

/// The outcome: what was compared and what differs.
#[derive(Debug, Clone, Default)]
pub struct CompareReport {
    /// Files compared.
    pub files: usize,
    /// Values compared.
    pub values: usize,
    /// CSVs of the run that the golden directory does not have (not compared).
    pub extra_in_run: Vec<String>,
    /// Golden files the run does not have, has with other columns, or cannot be read: one
    /// line each, starting with the file.
    pub files_differ: Vec<String>,
    /// What differs.
    pub differences: Vec<Difference>,
}

impl CompareReport {
    /// The runs agree within the tolerances.
    pub fn agree(&self) -> bool {
        self.differences.is_empty() && self.files_differ.is_empty()
    }
}

impl fmt::Display for CompareReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "compared {} values in {} files", self.values, self.files)?;
        for file in &self.extra_in_run {
            writeln!(f, "not in the golden directory (not compared): {file}")?;
        }
        if self.agree() {
            return writeln!(f, "the runs agree");
        }
        for line in &self.files_differ {
            writeln!(f, "{line}")?;
        }
        if self.differences.is_empty() {
            return Ok(());
        }
        writeln!(
            f,
            "{:<40} {:<22} {:>6} {:>10} {:>10}  first difference (run / golden)",
            "file", "column", "rows", "max |d|", "max rel"
        )?;
        for d in &self.differences {
            writeln!(
                f,
                "{:<40} {:<22} {:>6} {:>10.3e} {:>10.3e}  row {}: {} / {}",
                d.file, d.column, d.rows, d.max_abs, d.max_rel, d.first_row, d.first.0, d.first.1
            )?;
        }
        Ok(())
    }
}

/// Compare every CSV of `golden` with the same file of `run`.
pub fn compare(
    run: &Path,
    golden: &Path,
    settings: &CompareSettings,
) -> Result<CompareReport, CompareError> {
    let golden_files = csv_files(golden)?;
    let run_files = csv_files(run)?;
    if golden_files.is_empty() {
        return Err(CompareError::Directory {
            path: golden.to_path_buf(),
            reason: "holds no CSV file: give the directory of a stored run".into(),
        });
    }
    let mut report = CompareReport {
        extra_in_run: run_files
            .iter()
            .filter(|f| !golden_files.contains(f))
            .cloned()
            .collect(),
        ..Default::default()
    };
    for file in &golden_files {
        // The golden file first: an unreadable or empty one is a bad call, not a difference.
        let (golden_header, golden_rows) =
            read(&golden.join(file)).map_err(|reason| CompareError::Unreadable {
                file: file.clone(),
                reason,
            })?;
        if golden_header.is_empty() {
            return Err(CompareError::Unreadable {
                file: file.clone(),
                reason: "is empty (no header): store a run's CSV there".into(),
            });
        }
        if !run_files.contains(file) {
            report.files_differ.push(format!(
                "{file}: in the golden directory but not in the run: rerun the case, or store \
                 a new golden run"
            ));
            continue;
        }
        let (run_header, run_rows) = match read(&run.join(file)) {
            Ok(table) => table,
            Err(reason) => {
                report
                    .files_differ
                    .push(format!("{file}: cannot be read in the run: {reason}"));
                continue;
            }
        };
        if run_header != golden_header {
            let run_header = match run_header.is_empty() {
                true => "(empty file)".to_string(),
                false => run_header.join(","),
            };
            report.files_differ.push(format!(
                "{file}: columns differ (run: {run_header}; golden: {}): the two runs wrote \
                 different outputs",
                golden_header.join(",")
            ));
            continue;
        }
        report.files += 1;
        if run_rows.len() != golden_rows.len() {
            report.differences.push(Difference {
                file: file.clone(),
                column: "rows".into(),
                rows: run_rows.len().abs_diff(golden_rows.len()),
                first_row: run_rows.len().min(golden_rows.len()) + 1,
                first: (run_rows.len().to_string(), golden_rows.len().to_string()),
                max_abs: 0.0,
                max_rel: 0.0,
            });
            continue;
        }
        for (c, name) in golden_header.iter().enumerate() {
            if name.ends_with("seconds") {
                continue;
            }
            let mut column: Option<Difference> = None;
            for (r, (a, b)) in run_rows.iter().zip(&golden_rows).enumerate() {
                report.values += 1;
                let (a, b) = (&a[c], &b[c]);
                let Some((abs, rel)) = differs(name, a, b, settings) else {
                    continue;
                };
                let d = column.get_or_insert_with(|| Difference {
                    file: file.clone(),
                    column: name.clone(),
                    rows: 0,
                    first_row: r + 1,
                    first: (a.clone(), b.clone()),
                    max_abs: 0.0,
                    max_rel: 0.0,
                });
                d.rows += 1;
                d.max_abs = d.max_abs.max(abs);
                d.max_rel = d.max_rel.max(rel);
            }
            report.differences.extend(column);
        }
        // The slack set: cables at exactly zero tension (the solvers write 0 for slack ones).
        if let Some(c) = golden_header.iter().position(|h| h == "tension") {
            let mut set = None::<Difference>;
            for (r, (a, b)) in run_rows.iter().zip(&golden_rows).enumerate() {
                let slack = |v: &str| v.parse::<f64>().is_ok_and(|x| x == 0.0);
                if slack(&a[c]) != slack(&b[c]) {
                    let d = set.get_or_insert_with(|| Difference {
                        file: file.clone(),
                        column: "slack set".into(),
                        rows: 0,
                        first_row: r + 1,
                        first: (a[c].clone(), b[c].clone()),
                        max_abs: 0.0,
                        max_rel: 0.0,
                    });
                    d.rows += 1;
                }
            }
            report
                .differences
                .extend(set.filter(|d| d.rows as u64 > settings.slack_tolerance));
        }
    }
    Ok(report)
}

/// `Some((|a − b|, relative))` when two cells of column `name` differ beyond the tolerances.
fn differs(name: &str, a: &str, b: &str, s: &CompareSettings) -> Option<(f64, f64)> {
    if a == b {
        return None;
    }
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => {
            let abs = (x - y).abs();
            let scale = x.abs().max(y.abs());
            let rel = if scale > 0.0 { abs / scale } else { 0.0 };
            let slack_count =
                name == "slack_cables" || name.starts_with("slack_") && !name.contains("fraction");
            let within = if slack_count {
                abs <= s.slack_tolerance as f64
            } else {
                abs <= s.atol + s.rtol * scale || x.is_nan() && y.is_nan()
            };
            (!within).then_some((abs, rel))
        }
        _ => Some((0.0, 0.0)),
    }
}

/// Every `*.csv` under `dir`, as paths relative to it with `/` separators, sorted. Links are
/// followed (to files and directories, inside the tree or out of it), each directory visited
/// once (a link back to an ancestor is no loop); a CSV link whose target is missing is listed,
/// so that reading it says so.
fn csv_files(dir: &Path) -> Result<Vec<String>, CompareError> {
    use std::os::unix::fs::MetadataExt;
    if !dir.is_dir() {
        return Err(CompareError::Directory {
            path: dir.to_path_buf(),
            reason: "is not a directory: give the output directory of a run".into(),
        });
    }
    let mut found = BTreeMap::new();
    let mut visited = std::collections::BTreeSet::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let meta = std::fs::metadata(&d).map_err(|e| CompareError::Directory {
            path: d.clone(),
            reason: e.to_string(),
        })?;
        if !visited.insert((meta.dev(), meta.ino())) {
            continue;
        }
        let entries = std::fs::read_dir(&d).map_err(|e| CompareError::Directory {
            path: d.clone(),
            reason: e.to_string(),
        })?;
        for entry in entries.flatten() {
            let path = entry.path();
            let csv = path.extension().is_some_and(|e| e == "csv");
            // `metadata` follows a link; a broken one is kept when it names a CSV.
            let (is_dir, is_file) = match std::fs::metadata(&path) {
                Ok(m) => (m.is_dir(), m.is_file()),
                Err(_) => (false, entry.file_type().is_ok_and(|k| k.is_symlink())),
            };
            if is_dir {
                stack.push(path);
            } else if is_file && csv {
                let relative = path.strip_prefix(dir).unwrap_or(&path);
                let name: Vec<String> = relative
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                found.insert(name.join("/"), ());
            }
        }
    }
    Ok(found.into_keys().collect())
}

/// Header and rows of a CSV.
type Table = (Vec<String>, Vec<Vec<String>>);

/// Header and rows of the CSV at `path` (an empty file: no header, no rows), or why it cannot
/// be read.
fn read(path: &Path) -> Result<Table, String> {
    let unreadable = |e: csv::Error| e.to_string();
    let mut reader = csv::Reader::from_path(path).map_err(unreadable)?;
    let header: Vec<String> = reader
        .headers()
        .map_err(unreadable)?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(unreadable)?;
        rows.push(record.iter().map(str::to_string).collect());
    }
    Ok((header, rows))
}
