//! `tensolve compare`: the README's CI recipe on the stored run `tests/golden/small/` (its case
//! is `tests/golden/small.toml`), and every exit status: 0 when the runs agree, 1 when a value,
//! a slack count, a slack set, a file or its columns differ (named in the report), 2 on a bad
//! call (no such directory, a golden directory with no CSV, a bad flag).
//!
//! `TENSOLVE_BLESS=1 cargo test --test compare` rewrites the stored run from the current binary.

mod common;

use common::{manifest_path, stderr, tensolve, Temp};
use std::path::Path;

/// Run the stored case into `out`, as the CI recipe does.
fn run_small(out: &Temp) {
    let case = manifest_path("tests/golden/small.toml");
    let o = tensolve(&["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

fn compare(run: &Path, golden: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let mut args = vec!["compare", run.to_str().unwrap(), golden.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = tensolve(&args);
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
    (o.status.code(), text)
}

/// Copy a directory tree.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        // tensolve's own bookkeeping (lock, manifest) is not part of a stored run.
        if entry.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// Rewrite one cell (row `row` after the header, column `column`) of a CSV.
fn edit_cell(path: &Path, row: usize, column: &str, value: &str) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let c = lines[0].split(',').position(|h| h == column).unwrap();
    let mut cells: Vec<String> = lines[row].split(',').map(str::to_string).collect();
    let old = std::mem::replace(&mut cells[c], value.to_string());
    lines[row] = cells.join(",");
    std::fs::write(path, lines.join("\n") + "\n").unwrap();
    old
}

#[test]
fn a_fresh_run_agrees_with_the_stored_one() {
    let golden = manifest_path("tests/golden/small");
    let out = Temp::dir("compare-fresh");
    run_small(&out);
    if std::env::var_os("TENSOLVE_BLESS").is_some() {
        let _ = std::fs::remove_dir_all(&golden);
        copy_dir(&out.0, &golden);
    }
    let (code, text) = compare(&out.0, &golden, &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("the runs agree"), "{text}");
    // Summary, 8 tensions, 8 displacements, 8 forces, 8 reactions, 4 LATIN and 2 pcg-lcp
    // histories.
    assert!(text.contains("in 39 files"), "{text}");
}

#[test]
fn a_perturbed_tension_differs_and_is_named() {
    let golden = manifest_path("tests/golden/small");
    let run = Temp::dir("compare-tension");
    copy_dir(&golden, &run.0);
    let file = run.0.join("tensions/newton_alpha12.csv");
    let old: f64 = edit_cell(&file, 5, "tension", "0").parse().unwrap();
    assert!(old != 0.0, "row 5 must be a taut cable");
    // Put a different, non-zero value back: a tension differs, the slack set does not.
    edit_cell(&file, 5, "tension", &format!("{}", old * (1.0 + 1e-4)));
    let (code, text) = compare(&run.0, &golden, &[]);
    assert_eq!(code, Some(1), "{text}");
    let line = text
        .lines()
        .find(|l| l.starts_with("tensions/newton_alpha12.csv"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        line.contains("tension") && !line.contains("slack set"),
        "{line}"
    );
    // Within a looser relative tolerance the runs agree.
    let (code, text) = compare(&run.0, &golden, &["--rtol", "1e-3"]);
    assert_eq!(code, Some(0), "{text}");
}

#[test]
fn a_changed_slack_set_differs_unless_tolerated() {
    let golden = manifest_path("tests/golden/small");
    let run = Temp::dir("compare-slack");
    copy_dir(&golden, &run.0);
    // A taut cable made slack (tension 0).
    edit_cell(
        &run.0.join("tensions/pcg-lcp_alpha12.csv"),
        5,
        "tension",
        "0",
    );
    let (code, text) = compare(&run.0, &golden, &["--rtol", "1"]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("tensions/pcg-lcp_alpha12.csv") && l.contains("slack set")),
        "{text}"
    );
    let (code, text) = compare(&run.0, &golden, &["--rtol", "1", "--slack-tolerance", "1"]);
    assert_eq!(code, Some(0), "{text}");
    // A slack count in the summary is exact too.
    let summary = run.0.join("summary.csv");
    let count: u64 = edit_cell(&summary, 2, "slack_cables", "0").parse().unwrap();
    edit_cell(&summary, 2, "slack_cables", &(count + 1).to_string());
    let (code, text) = compare(&run.0, &golden, &["--rtol", "1", "--slack-tolerance", "1"]);
    assert_eq!(code, Some(0), "{text}");
    let (code, text) = compare(&run.0, &golden, &["--rtol", "1"]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("summary.csv") && l.contains("slack_cables")),
        "{text}"
    );
}

#[test]
fn a_run_missing_a_file_or_with_other_columns_differs() {
    let golden = manifest_path("tests/golden/small");
    // A golden file missing from the run: named, and the other files still compared.
    let run = Temp::dir("compare-missing");
    copy_dir(&golden, &run.0);
    std::fs::remove_file(run.0.join("history/micro-macro_alpha6.csv")).unwrap();
    let (code, text) = compare(&run.0, &golden, &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("history/micro-macro_alpha6.csv"), "{text}");
    assert!(text.contains("in 38 files"), "{text}");
    // Renamed and swapped columns.
    let summary = run.0.join("summary.csv");
    let original = std::fs::read_to_string(golden.join("summary.csv")).unwrap();
    let renamed = original.replacen("slack_cables", "slack_count", 1);
    let swapped = original.replacen("solver,alpha", "alpha,solver", 1);
    for text in [renamed, swapped] {
        std::fs::write(&summary, text).unwrap();
        let (code, text) = compare(&run.0, &golden, &[]);
        assert_eq!(code, Some(1), "{text}");
        assert!(text.contains("columns differ"), "{text}");
    }
    // An empty summary.csv in the run.
    std::fs::write(&summary, "").unwrap();
    let (code, text) = compare(&run.0, &golden, &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("summary.csv"), "{text}");
}

#[test]
fn bad_input_exits_2() {
    let golden = manifest_path("tests/golden/small");
    // No such directory; a golden directory with no CSV; a bad tolerance.
    let (code, _) = compare(Path::new("/nonexistent/tensolve-run"), &golden, &[]);
    assert_eq!(code, Some(2));
    let (code, _) = compare(&golden, Path::new("/nonexistent/tensolve-golden"), &[]);
    assert_eq!(code, Some(2));
    let empty = Temp::dir("compare-empty-golden");
    std::fs::create_dir_all(&empty.0).unwrap();
    let (code, text) = compare(&golden, &empty.0, &[]);
    assert_eq!(code, Some(2), "{text}");
    let (code, text) = compare(&golden, &golden, &["--rtol=-1"]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("--rtol"), "{text}");
}

/// Golden trees of links (Bazel runfiles, git-annex): a linked file or directory is read
/// through its link and compared, never skipped.
#[test]
fn linked_golden_files_and_directories_are_compared() {
    let golden = manifest_path("tests/golden/small");
    let run = Temp::dir("compare-linked-run");
    copy_dir(&golden, &run.0);
    let file = "tensions/newton_alpha6.csv";
    edit_cell(&run.0.join(file), 5, "tension", "9999");
    // A golden file that is a link.
    let linked = Temp::dir("compare-linked-file");
    copy_dir(&golden, &linked.0);
    std::fs::remove_file(linked.0.join(file)).unwrap();
    std::os::unix::fs::symlink(golden.join(file), linked.0.join(file)).unwrap();
    let (code, text) = compare(&run.0, &linked.0, &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.lines().any(|l| l.starts_with(file)), "{text}");
    assert!(!text.contains("not in the golden directory"), "{text}");
    // A golden directory that is a link.
    let linked = Temp::dir("compare-linked-dir");
    copy_dir(&golden, &linked.0);
    std::fs::remove_dir_all(linked.0.join("tensions")).unwrap();
    std::os::unix::fs::symlink(golden.join("tensions"), linked.0.join("tensions")).unwrap();
    let (code, text) = compare(&run.0, &linked.0, &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.lines().any(|l| l.starts_with(file)), "{text}");
    // Links in the run are read too: a run linking to the golden files agrees, every file.
    let (code, text) = compare(&linked.0, &golden, &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("in 39 files"), "{text}");
}

/// `tensolve compare … | head`: a reader that closed its end is a normal end of the report
/// (exit 0 when the runs agree, no panic), not a crash on the broken pipe.
#[test]
fn a_closed_pipe_ends_the_report_quietly() {
    let golden = manifest_path("tests/golden/small");
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .args([
            "compare",
            golden.to_str().unwrap(),
            golden.to_str().unwrap(),
        ])
        .stdout(writer)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
}
