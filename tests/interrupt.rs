//! Nothing lost (issue 5): a sweep interrupted by SIGINT leaves every finished solve with
//! complete files and a `summary.csv` that is whole; a rerun into the same directory replaces
//! the files.

mod common;

use common::temp_path;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

const HEADER: &str = tensolve::output::SUMMARY_HEADER;

fn summary_rows(dir: &Path) -> Vec<Vec<String>> {
    let Ok(text) = std::fs::read_to_string(dir.join("summary.csv")) else {
        return vec![];
    };
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(HEADER), "summary.csv header");
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Data lines of a CSV file (its header checked), every line with `columns` fields.
fn data_lines(path: &Path, header: &str, columns: usize) -> usize {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    let mut n = 0;
    for line in lines {
        assert_eq!(
            line.split(',').count(),
            columns,
            "{}: `{line}`",
            path.display()
        );
        n += 1;
    }
    n
}

fn assert_complete(dir: &Path) -> usize {
    let rows = summary_rows(dir);
    for row in &rows {
        assert_eq!(
            row.len(),
            HEADER.split(',').count(),
            "a whole summary row: {row:?}"
        );
        let (solver, alpha) = (&row[0], &row[1]);
        let tensions = dir.join(format!("tensions/{solver}_alpha{alpha}.csv"));
        assert_eq!(
            data_lines(&tensions, "cable,kind,node_a,node_b,tension", 5),
            3072
        );
        let displacements = dir.join(format!("displacements/{solver}_alpha{alpha}.csv"));
        assert_eq!(data_lines(&displacements, "node,x,y,z,ux,uy,uz", 7), 833);
    }
    rows.len()
}

/// `tensolve run CASE --out DIR --quiet`, not started, with SIGINT at its default action as
/// under an interactive shell: a test harness started in the background by a non-interactive
/// shell ignores SIGINT, and an ignored signal stays ignored across `exec`, so the child would
/// run to its end.
fn run_into(case: &Path, dir: &Path) -> Command {
    use std::os::unix::process::CommandExt;
    let mut command = Command::new(env!("CARGO_BIN_EXE_tensolve"));
    command
        .arg("run")
        .arg(case)
        .arg("--out")
        .arg(dir)
        .arg("--quiet");
    // SAFETY: between fork and exec only `signal`, which is async-signal-safe, is called.
    unsafe {
        command.pre_exec(|| {
            if libc::signal(libc::SIGINT, libc::SIG_DFL) == libc::SIG_ERR {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    command
}

#[test]
fn interrupted_sweep_keeps_finished_results_whole() {
    let dir = temp_path("interrupt");
    let case = dir.with_extension("toml");
    std::fs::write(
        &case,
        "[grid]\nmodules = [16, 16]\n[load]\nalpha = { from = 0.02, to = 2.0, steps = 100 }\n\
         [model]\ngeometry = \"linear\"\n",
    )
    .unwrap();
    let mut child = run_into(&case, &dir).spawn().unwrap();
    let start = Instant::now();
    while summary_rows(&dir).len() < 4 && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let exit = child.wait().unwrap();
    assert!(!exit.success(), "the sweep was interrupted, not finished");
    let finished = assert_complete(&dir);
    assert!(
        (4..200).contains(&finished),
        "interrupted mid-sweep: {finished} rows"
    );

    // A rerun into the same directory replaces the files with a complete sweep.
    std::fs::write(
        &case,
        "[grid]\nmodules = [16, 16]\n[load]\nalpha = [0.02, 0.5]\n[model]\ngeometry = \"linear\"\n",
    )
    .unwrap();
    let rerun = run_into(&case, &dir).status().unwrap();
    assert!(rerun.success());
    assert_eq!(assert_complete(&dir), 4);
    let slack: Vec<String> = summary_rows(&dir).iter().map(|r| r[4].clone()).collect();
    assert_eq!(slack, ["0", "0", "36", "36"]);
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_file(&case);
}
