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
        // 1. The golden file first: an unreadable or empty one is a bad call, not a difference.
        let (header, golden_rows) = read_golden(golden, file)?;
        // 2. The run's: missing, unreadable or with other columns, the whole file differs.
        let run_rows = match read_run(run, file, &run_files, &header) {
            Ok(rows) => rows,
            Err(why) => {
                report.files_differ.push(why);
                continue;
            }
        };
        report.files += 1;
        // 3. Its rows: their count, then column by column, then the slack set.
        let table = Compared {
            file,
            header: &header,
            run: &run_rows,
            golden: &golden_rows,
        };
        if let Some(d) = table.row_count_difference() {
            report.differences.push(d);
            continue;
        }
        for (c, name) in header.iter().enumerate() {
            if !name.ends_with("seconds") {
                report.values += run_rows.len();
                report
                    .differences
                    .extend(table.column_difference(c, settings));
            }
        }
        report.differences.extend(
            table
                .slack_set_difference()
                .filter(|d| d.rows as u64 > settings.slack_tolerance),
        );
    }
    Ok(report)
}

/// Header and rows of `golden`'s CSV `file`; an unreadable or empty one cannot be compared
/// with (exit 2).
fn read_golden(golden: &Path, file: &str) -> Result<Table, CompareError> {
    let (header, rows) = read(&golden.join(file)).map_err(|reason| CompareError::Unreadable {
        file: file.to_string(),
        reason,
    })?;
    if header.is_empty() {
        return Err(CompareError::Unreadable {
            file: file.to_string(),
            reason: "is empty (no header): store a run's CSV there".into(),
        });
    }
    Ok((header, rows))
}

/// The rows of `run`'s CSV `file` (one of `run_files`) with the golden `header`, or why the
/// whole file differs: missing from the run, unreadable there, or with other columns.
fn read_run(
    run: &Path,
    file: &str,
    run_files: &[String],
    header: &[String],
) -> Result<Vec<Vec<String>>, String> {
    if !run_files.iter().any(|f| f == file) {
        return Err(format!(
            "{file}: in the golden directory but not in the run: rerun the case, or store a new \
             golden run"
        ));
    }
    let (run_header, run_rows) = read(&run.join(file))
        .map_err(|reason| format!("{file}: cannot be read in the run: {reason}"))?;
    if run_header != header {
        let run_header = match run_header.is_empty() {
            true => "(empty file)".to_string(),
            false => run_header.join(","),
        };
        return Err(format!(
            "{file}: columns differ (run: {run_header}; golden: {}): the two runs wrote \
             different outputs",
            header.join(",")
        ));
    }
    Ok(run_rows)
}

/// One file of both directories, with the same columns.
struct Compared<'a> {
    file: &'a str,
    header: &'a [String],
    run: &'a [Vec<String>],
    golden: &'a [Vec<String>],
}

impl Compared<'_> {
    /// A difference in `column` first seen at row `r` (0-based) between `first`'s values.
    fn difference(&self, column: &str, r: usize, first: (&str, &str)) -> Difference {
        Difference {
            file: self.file.to_string(),
            column: column.to_string(),
            rows: 0,
            first_row: r + 1,
            first: (first.0.to_string(), first.1.to_string()),
            max_abs: 0.0,
            max_rel: 0.0,
        }
    }

    /// The row counts, when they differ (column `rows`).
    fn row_count_difference(&self) -> Option<Difference> {
        let (run, golden) = (self.run.len(), self.golden.len());
        (run != golden).then(|| Difference {
            rows: run.abs_diff(golden),
            ..self.difference(
                "rows",
                run.min(golden),
                (&run.to_string(), &golden.to_string()),
            )
        })
    }

    /// Column `c`'s rows that differ beyond `settings` ([`differs`]), if any.
    fn column_difference(&self, c: usize, settings: &CompareSettings) -> Option<Difference> {
        let name = &self.header[c];
        let mut column: Option<Difference> = None;
        for (r, (a, b)) in self.run.iter().zip(self.golden).enumerate() {
            let (a, b) = (&a[c], &b[c]);
            let Some((abs, rel)) = differs(name, a, b, settings) else {
                continue;
            };
            let d = column.get_or_insert_with(|| self.difference(name, r, (a, b)));
            d.rows += 1;
            d.max_abs = d.max_abs.max(abs);
            d.max_rel = d.max_rel.max(rel);
        }
        column
    }

    /// The slack set, when the file has a `tension` column: the cables at exactly zero tension
    /// (the solvers write 0 for slack ones), the rows where one run has it and not the other.
    fn slack_set_difference(&self) -> Option<Difference> {
        let c = self.header.iter().position(|h| h == "tension")?;
        let slack = |v: &str| v.parse::<f64>().is_ok_and(|x| x == 0.0);
        let mut set = None::<Difference>;
        for (r, (a, b)) in self.run.iter().zip(self.golden).enumerate() {
            if slack(&a[c]) != slack(&b[c]) {
                set.get_or_insert_with(|| self.difference("slack set", r, (&a[c], &b[c])))
                    .rows += 1;
            }
        }
        set
    }
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
