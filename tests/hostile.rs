//! Issue 13, "nothing lost, nothing wrong": every defect the adversarial review found is kept
//! fixed here, one test per item (named after it). Concurrency, link and kill tests use only
//! temporary directories and are bounded in time.

mod common;

use common::{code, manifest_path, stderr, tensolve, Temp};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};
use tensolve::output::OutputDir;

/// A 4 × 4 grid solved by `methods` at `alphas`, with `extra` TOML appended.
/// (Pinned to the linear model: these are the solvers' own limits, not `auto`'s choice.)
fn small_case(methods: &str, alphas: &str, extra: &str) -> String {
    format!(
        "[model]\ngeometry = \"linear\"\n[grid]\nmodules = [4, 4]\n[load]\nalpha = {alphas}\n\
         [solver]\nmethods = {methods}\n{extra}"
    )
}

/// `tensolve run CASE --out DIR --quiet`.
fn run(case: &Temp, dir: &Path) -> Output {
    tensolve(&["run", case.arg(), "--out", dir.to_str().unwrap(), "--quiet"])
}

/// Every file under `dir`, relative, hidden bookkeeping (`.tensolve*`) left out.
fn files(dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(dir.join(&rel)) else {
            continue;
        };
        for e in entries {
            let e = e.unwrap();
            let path = rel.join(e.file_name());
            if e.file_type().unwrap().is_dir() {
                stack.push(path);
            } else {
                out.insert(path.to_string_lossy().into_owned());
            }
        }
    }
    out.into_iter()
        .filter(|p| !p.starts_with(".tensolve"))
        .collect()
}

/// The summary rows of `dir`, as fields.
fn summary(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("summary.csv")).unwrap_or_default();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Column `name` of `row`.
fn column<'r>(row: &'r [String], name: &str) -> &'r str {
    let index = tensolve::output::SUMMARY_HEADER
        .split(',')
        .position(|c| c == name)
        .unwrap();
    &row[index]
}

/// Every per-solve result file of `dir` belongs to a summary row (nothing published without
/// its row).
fn assert_every_file_has_a_row(dir: &Path) {
    let rows: BTreeSet<String> = summary(dir)
        .iter()
        .map(|r| format!("{}_alpha{}", r[0], r[1]))
        .collect();
    for f in files(dir) {
        if let Some(stem) = f
            .strip_prefix("tensions/")
            .or_else(|| f.strip_prefix("displacements/"))
            .or_else(|| f.strip_prefix("history/"))
            .or_else(|| f.strip_prefix("forces/"))
            .or_else(|| f.strip_prefix("reactions/"))
        {
            let stem = stem.trim_end_matches(".csv");
            assert!(rows.contains(stem), "`{f}` has no summary row: {rows:?}");
        }
    }
}

// ---- Wrong results reported as right ----

#[test]
fn d1_tiny_search_direction_is_refused_by_name() {
    for (l, exit) in [("1e-300", 2), ("1e-9", 2)] {
        let case = Temp::file(
            "d1",
            &small_case("[\"mono-latin\"]", "[1.0]", &format!("l = {l}\n")),
        );
        let dir = Temp::dir("d1-out");
        let out = run(&case, &dir.0);
        assert_eq!(code(&out), exit, "l = {l}: {}", stderr(&out));
        assert!(stderr(&out).contains("solver.l"), "{}", stderr(&out));
        assert!(!dir.0.join("summary.csv").exists());
    }
}

#[test]
fn d5a_newton_is_not_converged_at_zero_under_huge_prestress() {
    let case = Temp::file(
        "d5a",
        &small_case(
            "[\"newton\", \"pcg-lcp\"]",
            "[1.0]",
            "[prestress]\nlower_cable = 1e12\n",
        ),
    );
    let dir = Temp::dir("d5a-out");
    run(&case, &dir.0);
    let rows = summary(&dir.0);
    assert_eq!(rows.len(), 2, "{rows:?}");
    let deflection = |r: &[String]| column(r, "max_deflection").parse::<f64>().unwrap();
    let (newton, pcg) = (deflection(&rows[0]), deflection(&rows[1]));
    assert!(pcg > 1e-4, "pcg-lcp moves: {pcg}");
    assert!(
        (newton - pcg).abs() <= 1e-6 * pcg,
        "newton {newton} against pcg-lcp {pcg}"
    );
    assert_ne!(
        column(&rows[0], "iterations"),
        "0",
        "U = 0 is not an answer"
    );
}

#[test]
fn d5b_pcg_lcp_is_scale_free_at_zero_prestress() {
    for alpha in ["1.0", "1e-30"] {
        let case = Temp::file(
            "d5b",
            &small_case("[\"newton\", \"pcg-lcp\"]", &format!("[{alpha}]"), "").replace(
                "[load]",
                "[prestress]\nlower_cable = 0\n[load]\nnodal = [0, 0, -4e-11]",
            ),
        );
        let dir = Temp::dir("d5b-out");
        let out = run(&case, &dir.0);
        assert_eq!(code(&out), 0, "alpha = {alpha}: {}", stderr(&out));
        let rows = summary(&dir.0);
        let deflection = |r: &[String]| column(r, "max_deflection").parse::<f64>().unwrap();
        let (newton, pcg) = (deflection(&rows[0]), deflection(&rows[1]));
        assert!(newton > 0.0);
        assert_eq!(
            column(&rows[0], "slack_cables"),
            column(&rows[1], "slack_cables"),
            "alpha = {alpha}: slack cables"
        );
        assert!(
            (newton - pcg).abs() <= 1e-6 * newton,
            "alpha = {alpha}: newton {newton} against pcg-lcp {pcg}"
        );
    }
}

#[test]
fn c7_newton_reports_a_stall_at_round_off() {
    let case = Temp::file(
        "c7",
        &small_case("[\"newton\"]", "[1.0]", "tolerance = 1e-15\n"),
    );
    let dir = Temp::dir("c7-out");
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 1, "{}", stderr(&out));
    assert!(stderr(&out).contains("Stalled"), "{}", stderr(&out));
    let rows = summary(&dir.0);
    assert_eq!(column(&rows[0], "converged"), "false");
    let iterations: usize = column(&rows[0], "iterations").parse().unwrap();
    assert!(
        iterations < 100,
        "stopped before max_iterations: {iterations}"
    );
}

// ---- Files torn, stale, mixed or overwritten ----

#[test]
fn d2_d6_a_locked_directory_is_refused() {
    let dir = Temp::dir("d6-out");
    std::fs::create_dir_all(&dir.0).unwrap();
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.0.join(".tensolve.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let case = Temp::file("d6", &small_case("[\"newton\"]", "[1.0]", ""));
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 3, "{}", stderr(&out));
    assert!(stderr(&out).contains("in use"), "{}", stderr(&out));
    assert!(files(&dir.0).is_empty(), "{:?}", files(&dir.0));
    drop(lock);
    assert_eq!(code(&run(&case, &dir.0)), 0);
}

#[test]
fn d2_concurrent_runs_never_mix_or_tear() {
    let dir = Temp::dir("d2-out");
    let cases: Vec<Temp> = (0..4)
        .map(|i| {
            Temp::file(
                "d2",
                &small_case(
                    "[\"newton\", \"mono-latin\"]",
                    "{ from = 0.1, to = 1.0, steps = 6 }",
                    &format!("[prestress]\nlower_cable = {}\n", 500 + 500 * i),
                ),
            )
        })
        .collect();
    let children: Vec<_> = cases
        .iter()
        .map(|c| {
            Command::new(env!("CARGO_BIN_EXE_tensolve"))
                .args(["run", c.arg(), "--out", dir.0.to_str().unwrap(), "--quiet"])
                .spawn()
                .unwrap()
        })
        .collect();
    let codes: Vec<i32> = children
        .into_iter()
        .map(|c| c.wait_with_output().unwrap().status.code().unwrap())
        .collect();
    assert!(codes.iter().all(|&c| c == 0 || c == 3), "{codes:?}");
    assert!(codes.contains(&0), "{codes:?}");
    let rows = summary(&dir.0);
    assert_eq!(rows.len(), 12, "one run's rows: {rows:?}");
    assert_every_file_has_a_row(&dir.0);
    let tensions = files(&dir.0)
        .iter()
        .filter(|f| f.starts_with("tensions/"))
        .count();
    assert_eq!(tensions, 12);
}

#[test]
fn d3_planted_links_are_never_followed() {
    let dir = Temp::dir("d3-out");
    let victim = Temp::dir("d3-victim");
    std::fs::write(&victim.0, "precious\n").unwrap();
    std::fs::create_dir_all(dir.0.join("history")).unwrap();
    std::fs::create_dir_all(dir.0.join("tensions")).unwrap();
    for planted in [
        "history/.mono-latin_alpha1.csv.partial",
        "tensions/mono-latin_alpha1.csv",
        ".summary.csv.tmp-1",
        "summary.csv",
    ] {
        std::os::unix::fs::symlink(&victim.0, dir.0.join(planted)).unwrap();
    }
    let case = Temp::file("d3", &small_case("[\"mono-latin\"]", "[1.0]", ""));
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(&victim.0).unwrap(), "precious\n");
    for published in ["tensions/mono-latin_alpha1.csv", "summary.csv"] {
        let meta = std::fs::symlink_metadata(dir.0.join(published)).unwrap();
        assert!(meta.is_file(), "{published} is a file of its own");
    }
    // A directory replaced by a link is refused, naming it.
    let elsewhere = Temp::dir("d3-elsewhere");
    std::fs::create_dir_all(&elsewhere.0).unwrap();
    std::fs::remove_dir_all(dir.0.join("tensions")).unwrap();
    std::os::unix::fs::symlink(&elsewhere.0, dir.0.join("tensions")).unwrap();
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 1);
    assert!(stderr(&out).contains("tensions"), "{}", stderr(&out));
    assert!(files(&elsewhere.0).is_empty());
}

#[test]
fn d4_a_rerun_leaves_exactly_its_files_and_foreign_ones_alone() {
    let dir = Temp::dir("d4-out");
    let a = Temp::file(
        "d4a",
        &small_case(
            "[\"newton\", \"mono-latin\"]",
            "[0.5, 1.0]",
            "[output]\nvtk = true\nstability = true\nplots = true\n",
        ),
    );
    let b = Temp::file("d4b", &small_case("[\"newton\"]", "[1.0]", ""));
    assert_eq!(code(&run(&a, &dir.0)), 0);
    assert!(files(&dir.0).len() > 14, "{:?}", files(&dir.0));
    std::fs::write(dir.0.join("notes.txt"), "mine").unwrap();
    std::fs::write(dir.0.join("tensions/mine.csv"), "mine").unwrap();
    assert_eq!(code(&run(&b, &dir.0)), 0);
    let expected: BTreeSet<String> = [
        "summary.csv",
        "tensions/newton_alpha1.csv",
        "displacements/newton_alpha1.csv",
        // forces/ and reactions/ (issue 27): per-solve files of the rerun too.
        "forces/newton_alpha1.csv",
        "reactions/newton_alpha1.csv",
        // The reactions' sums per axis (issue 42), a ledger like summary.csv.
        "reaction_totals.csv",
        "notes.txt",
        "tensions/mine.csv",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    assert_eq!(files(&dir.0), expected);
}

#[test]
fn d7_a_killed_sweep_shows_no_file_without_its_row() {
    let dir = Temp::dir("d7-out");
    let case = Temp::file(
        "d7",
        "[grid]\nmodules = [16, 16]\n[load]\nalpha = { from = 0.02, to = 2.0, steps = 100 }\n",
    );
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .args([
            "run",
            case.arg(),
            "--out",
            dir.0.to_str().unwrap(),
            "--quiet",
        ])
        .spawn()
        .unwrap();
    let start = Instant::now();
    while summary(&dir.0).len() < 3 && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL: no handler runs
    child.wait().unwrap();
    assert!(summary(&dir.0).len() >= 3);
    assert_every_file_has_a_row(&dir.0);
    // The rerun clears the killed run's staging directory and files.
    let small = Temp::file("d7b", &small_case("[\"newton\"]", "[1.0]", ""));
    assert_eq!(code(&run(&small, &dir.0)), 0);
    let hidden: Vec<_> = std::fs::read_dir(&dir.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".tensolve-staging"))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
    assert_eq!(summary(&dir.0).len(), 1);
    // summary, tensions, displacements, forces, reactions (issue 27 added the last two),
    // reaction_totals.csv (issue 42: the reactions' sums, out of their table).
    assert_eq!(files(&dir.0).len(), 6, "{:?}", files(&dir.0));
}

#[test]
fn c5_summary_rows_are_appended_not_rewritten() {
    use std::os::unix::fs::MetadataExt;
    let dir = Temp::dir("c5-out");
    let mut out = OutputDir::open(&dir.0).unwrap();
    out.append("summary.csv", "a,b", "1,2").unwrap();
    let inode = std::fs::metadata(dir.0.join("summary.csv")).unwrap().ino();
    for i in 0..100 {
        out.append("summary.csv", "a,b", &format!("{i},{i}"))
            .unwrap();
    }
    // Same file (a rewrite would rename a new one over it), every row once.
    assert_eq!(
        std::fs::metadata(dir.0.join("summary.csv")).unwrap().ino(),
        inode
    );
    let text = std::fs::read_to_string(dir.0.join("summary.csv")).unwrap();
    assert_eq!(text.lines().count(), 102);
    out.finish().unwrap();
}

// ---- Crashes, hangs, runaway resources ----

#[test]
fn c3_reads_are_bounded() {
    let start = Instant::now();
    let out = tensolve(&["check", "/dev/zero"]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("larger than"), "{}", stderr(&out));
    assert!(start.elapsed() < Duration::from_secs(20));
    let long = format!(
        "[grid]\nmodules = [2, 2]\n[load]\nalpha = [{}1]\n",
        "1, ".repeat(2_000_000)
    );
    let case = Temp::file("c3", &long);
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("larger than"), "{}", stderr(&out));
}

#[test]
fn c6_duplicate_solver_names_are_refused() {
    let case = Temp::file("c6", &small_case("[\"newton\", \"newton\"]", "[1.0]", ""));
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("solver.methods"), "{}", stderr(&out));
    let case = Temp::file("c6b", &small_case("[\"newton\"]", "[1.0]", ""));
    let dir = Temp::dir("c6-out");
    let out = tensolve(&[
        "run",
        case.arg(),
        "--out",
        dir.0.to_str().unwrap(),
        "--solver",
        "newton,pcg-lcp,newton",
    ]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("--solver"), "{}", stderr(&out));
}

// ---- Exit codes, refusals, messages ----

#[test]
fn e1_arrays_have_exactly_their_length() {
    for (bad, key) in [
        (
            "[grid]\nmodules = [4, 4, 4]\n[load]\nalpha = [1]\n",
            "modules",
        ),
        (
            "[grid]\nmodules = [4, 4]\n[load]\nnodal = [0, 0, -40, \"junk\"]\nalpha = [1]\n",
            "nodal",
        ),
        (
            "[grid]\nmodules = [4, 4]\n[load]\nnodal = [0, -40]\nalpha = [1]\n",
            "nodal",
        ),
        (
            "[grid]\nmodules = [4, 4]\n[load]\nalpha = [1]\n[solver]\nsubdomains = [1, 1, 1]\n",
            "subdomains",
        ),
    ] {
        let case = Temp::file("e1", bad);
        let out = tensolve(&["check", case.arg()]);
        assert_eq!(code(&out), 2, "{bad}");
        let message = stderr(&out);
        assert!(message.contains(key), "{message}");
        assert!(
            message.contains("expected exactly") || message.contains("invalid type"),
            "{message}"
        );
    }
}

#[test]
fn e2_tiny_load_factors_get_short_file_names() {
    // pcg-lcp: at α = 1e-250 the load is far below the round-off of the prestress's balance, so
    // newton's load-relative stop cannot be met (it said converged only while ‖F‖ underflowed to
    // 0); pcg-lcp's λ = 0 is exact there and its answer K⁻¹F converges.
    let case = Temp::file("e2", &small_case("[\"pcg-lcp\"]", "[1e-250]", ""));
    let dir = Temp::dir("e2-out");
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(dir.0.join("tensions/pcg-lcp_alpha1e-250.csv").exists());
    assert_eq!(summary(&dir.0)[0][1], "1e-250");
    assert_eq!(tensolve::output::alpha_label(0.05), "0.05");
}

/// newton at α = 1e-250 on a 2 × 2 grid, under `linear` and under `auto` (issue 57, E2): the
/// load is below the round-off of the prestress's balance, so the load-relative stop cannot be
/// met; it ended `stalled` at r(U) 3e-17. The answer is the prestressed state to round-off, and
/// the row converges saying so; at α = 1e-3 the same grid converges on the criterion itself.
#[test]
fn e2_a_load_below_the_prestress_round_off_converges_at_round_off() {
    for geometry in ["linear", "auto"] {
        for (alpha, at_roundoff) in [("1e-250", true), ("1e-3", false)] {
            let case = Temp::file(
                "e2-newton",
                &format!(
                    "[model]\ngeometry = \"{geometry}\"\n[grid]\nmodules = [2, 2]\n[load]\n\
                     alpha = [{alpha}]\n[solver]\nmethods = [\"newton\"]\n"
                ),
            );
            let dir = Temp::dir("e2-newton-out");
            let out = tensolve(&["run", case.arg(), "--out", dir.0.to_str().unwrap()]);
            assert_eq!(code(&out), 0, "{geometry} {alpha}: {}", stderr(&out));
            let row = &summary(&dir.0)[0];
            assert_eq!(row[2], "true", "{row:?}");
            let residual: f64 = row[10].parse().unwrap();
            assert!(residual <= 1e-14, "{row:?}");
            assert_eq!(
                stderr(&out).contains("converged at round-off (r(U) is at the round-off"),
                at_roundoff,
                "{geometry} {alpha}: {}",
                stderr(&out)
            );
        }
    }
}

/// Result files honour the umask as `summary.csv` does (issue 57, R5-9: they were 0600 under
/// umask 022): 0644 under 022, 0600 under 077.
#[test]
fn result_files_honour_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    for (umask, mode) in [("022", 0o644), ("077", 0o600)] {
        let case = Temp::file("r9", &small_case("[\"newton\"]", "[1.0]", ""));
        let dir = Temp::dir("r9-out");
        let o = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!(
                "umask {umask} && exec \"$0\" run \"$1\" --out \"$2\" --quiet"
            ))
            .args([
                env!("CARGO_BIN_EXE_tensolve"),
                case.arg(),
                dir.0.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        for file in [
            "summary.csv",
            "tensions/newton_alpha1.csv",
            "displacements/newton_alpha1.csv",
        ] {
            let path = dir.0.join(file);
            if !path.exists() {
                continue;
            }
            let got = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
            assert_eq!(got, mode, "umask {umask}: {file} {got:o}");
        }
        let tensions = dir.0.join("tensions/newton_alpha1.csv");
        assert!(tensions.exists());
    }
}

#[test]
fn e4_tiny_moduli_are_refused_by_name() {
    for key in ["cables", "bars"] {
        let case = Temp::file(
            "e4",
            &format!("[grid]\nmodules = [2, 2]\n[{key}]\nyoung = 1e-150\n[load]\nalpha = [1]\n"),
        );
        let out = tensolve(&["check", case.arg()]);
        assert_eq!(code(&out), 2);
        assert!(
            stderr(&out).contains(&format!("{key}.young")),
            "{}",
            stderr(&out)
        );
        assert!(!stderr(&out).contains("mechanism"));
    }
}

#[test]
fn e5_load_factors_that_round_alike_are_refused() {
    for alphas in [
        "{ from = 1, to = 1.0000000000001, steps = 5 }",
        "[0.5, 1.0, 0.5]",
    ] {
        let case = Temp::file("e5", &small_case("[\"newton\"]", alphas, ""));
        let out = tensolve(&["check", case.arg()]);
        assert_eq!(code(&out), 2, "{alphas}");
        assert!(stderr(&out).contains("distinct"), "{}", stderr(&out));
    }
}

#[test]
fn m1_m4_failure_messages_are_true_and_bounded() {
    let case = Temp::file(
        "m1",
        &small_case(
            "[\"newton\"]",
            "{ from = 0.1, to = 3.0, steps = 30 }",
            "tolerance = 1e-15\n",
        ),
    );
    let dir = Temp::dir("m1-out");
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 1);
    let message = stderr(&out);
    assert!(
        message.contains("30 solve(s) did not converge"),
        "{message}"
    );
    assert!(message.contains("and 20 more"), "{message}");
    assert!(message.contains("its row says converged = false"));
    assert!(message.len() < 3000, "{} bytes", message.len());
    // A huge value is echoed cut short.
    let case = Temp::file(
        "m4",
        &small_case(
            "[\"newton\"]",
            "[1.0]",
            &format!("l = \"{}\"\n", "x".repeat(1 << 20)),
        ),
    );
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).len() < 2000, "{} bytes", stderr(&out).len());
    assert!(stderr(&out).contains("characters)"), "{}", stderr(&out));
}

#[test]
fn m2_set_up_failures_of_l_name_l() {
    let case = Temp::file(
        "m2",
        &small_case(
            "[\"micro-macro\"]",
            "[1.0]",
            "l = 1e15\nsubdomains = [2, 2]\n",
        ),
    );
    let dir = Temp::dir("m2-out");
    let out = run(&case, &dir.0);
    let message = stderr(&out);
    assert_eq!(code(&out), 2, "{message}");
    assert!(message.contains("solver.l"), "{message}");
}

#[test]
fn m5_dates_are_shown_as_written() {
    for alpha in ["1979-05-27", "[1, 1979-05-27]"] {
        let case = Temp::file("m5", &small_case("[\"newton\"]", alpha, ""));
        let out = tensolve(&["check", case.arg()]);
        assert_eq!(code(&out), 2);
        assert!(stderr(&out).contains("1979-05-27"), "{}", stderr(&out));
        assert!(!stderr(&out).contains("toml_private"), "{}", stderr(&out));
    }
}

#[test]
fn m6_output_directory_names_are_kept_or_refused() {
    let case = Temp::file(
        "m6",
        &small_case("[\"newton\"]", "[1.0]", "[output]\ndir = \"\"\n"),
    );
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("output.dir"), "{}", stderr(&out));

    use std::os::unix::ffi::OsStrExt;
    let work = Temp::dir("m6-work");
    std::fs::create_dir_all(&work.0).unwrap();
    let name = std::ffi::OsStr::from_bytes(b"case\xff.toml");
    std::fs::write(work.0.join(name), small_case("[\"newton\"]", "[1.0]", "")).unwrap();
    let status = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .args(["run".as_ref(), name, "--quiet".as_ref()])
        .current_dir(&work.0)
        .status()
        .unwrap();
    assert!(status.success());
    let stem = std::ffi::OsStr::from_bytes(b"case\xff");
    assert!(work.0.join("out").join(stem).join("summary.csv").exists());
}

#[test]
fn c4_a_long_strip_mechanism_is_refused_without_counting_every_mode() {
    let case = Temp::file(
        "c4",
        "[grid]\nmodules = [1000, 1]\n[supports]\nclamp = \"lower-x-edges\"\n[load]\nalpha = [1]\n",
    );
    // A hang guard (the defect took over 300 s), not a speed measurement.
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .args(["check", case.arg()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(120) {
            child.kill().unwrap();
            panic!("the mechanism check of a 1000 x 1 strip did not end in 120 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    assert_eq!(code(&out), 2);
    assert!(
        stderr(&out).contains("at least 64 zero-stiffness mode(s)"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn e3_stiff_cables_set_up_a_regular_macro_problem() {
    // repro e3_macro_stiff: cables 100 times stiffer than the paper's made the pivoting LU's
    // absolute round-trip check call the macro problem singular. The quasi-definite LDLᵀ of
    // the augmented, scaled macro matrix sets it up and the solve converges.
    let case = Temp::file(
        "e3-stiff",
        "[grid]\nmodules = [16, 16]\n[cables]\nyoung = 1e13\n[load]\nalpha = [1.0]\n\
         [solver]\nmethods = [\"micro-macro\"]\nreference = \"none\"\n[output]\n\
         tensions = false\ndisplacements = false\nhistory = false\n",
    );
    let out = Temp::dir("e3-stiff-out");
    let o = run(&case, &out.0);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let rows = summary(&out.0);
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0][2], "true", "{rows:?}");
}

/// `tensolve ARGS` under `ulimit -v KB` (RLIMIT_AS, read back through getrlimit), with `env`;
/// killed, and the test failed, after `limit` (a hang guard, not a speed measurement).
fn under_address_limit(kb: u64, args: &[&str], env: &[(&str, &str)], limit: Duration) -> Output {
    let mut line = format!("ulimit -v {kb}; exec '{}'", env!("CARGO_BIN_EXE_tensolve"));
    for a in args {
        line.push_str(&format!(" '{a}'"));
    }
    let mut child = Command::new("sh")
        .args(["-c", &line])
        .envs(env.iter().copied())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            panic!(
                "`tensolve {}` under ulimit -v {kb} did not end in {limit:?}",
                args.join(" ")
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn c1_a_case_larger_than_the_memory_is_refused_with_its_estimate() {
    // repro c1_big_grid: 500 × 500 modules passed validation, then died with "memory
    // allocation failed" (SIGABRT) under an 8 GB cap. The cap is set here (ulimit -v), so the
    // test does not depend on the machine's memory.
    let case = Temp::file(
        "c1",
        "[grid]\nmodules = [500, 500]\n[load]\nalpha = [1.0]\n",
    );
    let dir = Temp::dir("c1-out");
    let cap = 8_000_000; // kB
    for args in [
        vec![
            "run",
            case.arg(),
            "--out",
            dir.0.to_str().unwrap(),
            "--quiet",
        ],
        vec!["check", case.arg()],
    ] {
        let out = under_address_limit(cap, &args, &[], Duration::from_secs(120));
        let message = stderr(&out);
        assert_eq!(code(&out), 2, "{args:?}: {message}");
        for part in [
            "too large for the memory available",
            "needs about",
            "GB",
            "sparse factor(s)",
            "is available",
            "RLIMIT_AS (ulimit -v)",
            "grid.modules",
            "solver.methods",
        ] {
            assert!(message.contains(part), "{args:?}: `{part}` in {message}");
        }
        assert!(!dir.0.exists(), "nothing written");
    }
    // A grid whose structure alone does not fit is refused before it is generated.
    let huge = Temp::file(
        "c1-huge",
        "[grid]\nmodules = [2000, 2000]\n[load]\nalpha = [1.0]\n",
    );
    let out = under_address_limit(cap, &["check", huge.arg()], &[], Duration::from_secs(60));
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(
        stderr(&out).contains("`loading the case` needs about"),
        "{}",
        stderr(&out)
    );
    // check prints the estimate of a case that fits.
    let small = Temp::file("c1-small", &small_case("[\"newton\"]", "[1.0]", ""));
    let out = tensolve(&["check", small.arg()]);
    assert_eq!(code(&out), 0);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("memory (run)    about"), "{text}");
    assert!(text.contains("  available     "), "{text}");
}

/// cpu0's L3 cache in kB, as `/sys` lists it (`None` when not listed).
fn l3_cache_kb() -> Option<u64> {
    let entries = std::fs::read_dir("/sys/devices/system/cpu/cpu0/cache").ok()?;
    entries.flatten().find_map(|e| {
        let read = |f: &str| std::fs::read_to_string(e.path().join(f)).unwrap_or_default();
        if read("level").trim() != "3" {
            return None;
        }
        read("size").trim().strip_suffix('K')?.parse::<u64>().ok()
    })
}

#[test]
fn c2_the_paper_case_runs_under_a_small_address_space_limit() {
    // Under `ulimit -v` the paper case aborted at 600 MB: every thread that runs a dense
    // kernel reserves twice the L3 cache (faer's gemm). Now a run either fits, or is refused
    // with the estimate; it never aborts. Two rayon workers, as on a 2-CPU machine.
    let env = [("RAYON_NUM_THREADS", "2")];
    let dir = Temp::dir("c2-out");
    let paper_exact = common::manifest_path("cases/paper-exact.toml");
    let paper = common::manifest_path("cases/paper.toml");
    let args = |case: &Path| {
        vec![
            "run".to_string(),
            case.to_str().unwrap().to_string(),
            "--out".into(),
            dir.0.to_str().unwrap().to_string(),
            "--quiet".into(),
        ]
    };
    let run_under = |kb: u64, case: &Path| {
        let a = args(case);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        under_address_limit(kb, &a, &env, Duration::from_secs(120))
    };
    // Every thread that runs a dense kernel reserves twice the L3 cache of address space, and
    // each rayon worker a malloc arena (128 MB): the main thread and two workers, plus 400 MB
    // for the run itself (84 MB measured), and never less than 1 GB. On a machine whose L3 is
    // 32 MB that is 1 GB; one with a 480 MB L3 (seen) needs 3.3 GB.
    let l3_kb = l3_cache_kb().unwrap_or(32 * 1024);
    let roomy = (400_000 + 3 * 2 * l3_kb + 2 * 131_072).max(1_000_000);
    // The two exact solvers run on one thread.
    let out = run_under(roomy, &paper_exact);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    // The four solvers, LATIN's stages on rayon's workers, fit too, and give what an
    // unlimited run gives.
    let out = run_under(roomy, &paper);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let free = Temp::dir("c2-free");
    let out = tensolve(&[
        "run",
        paper.to_str().unwrap(),
        "--out",
        free.0.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let agree = |limited: &Path| {
        let out = tensolve(&[
            "compare",
            limited.to_str().unwrap(),
            free.0.to_str().unwrap(),
        ]);
        assert_eq!(code(&out), 0, "{}", String::from_utf8_lossy(&out.stdout));
    };
    agree(&dir.0);
    // Where the L3 is at most 32 MB (most machines), 400 MB fits one worker and not two:
    // rayon's pool is sized to one, and the results are the same.
    if l3_kb <= 32 * 1024 {
        let out = run_under(400_000, &paper);
        assert_eq!(code(&out), 0, "{}", stderr(&out));
        agree(&dir.0);
    }
    for kb in [50_000, 100_000, 200_000, 300_000, 400_000, 1_000_000] {
        let out = run_under(kb, &paper);
        match code(&out) {
            0 => {}
            2 => assert!(
                stderr(&out).contains("too large for the memory available"),
                "{kb} kB: {}",
                stderr(&out)
            ),
            other => panic!("{kb} kB: exit {other}: {}", stderr(&out)),
        }
    }
}

#[test]
fn e3_one_module_per_substructure_sets_up_a_regular_macro_problem() {
    // repro e3_macro_onemodule: 64 × 64 modules, one per substructure, was refused as "the
    // macro problem is singular". check sets micro-macro up (its macro problem factorized);
    // three iterations of a run set it up again and stop on max_iterations, not on set-up.
    let text = "[model]\ngeometry = \"linear\"\n\
                [grid]\nmodules = [64, 64]\n[supports]\nclamp = \"lower-all-edges\"\n\
                [load]\nalpha = [0.15]\n[solver]\nmethods = [\"micro-macro\"]\n\
                subdomains = [64, 64]\nreference = \"none\"\n";
    let case = Temp::file("e3-one", text);
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        report.contains("substructures 4096 (64 x 64: solver.subdomains)"),
        "{report}"
    );
    let short = Temp::file(
        "e3-one-run",
        &format!("{text}max_iterations = 3\n[output]\ntensions = false\ndisplacements = false\n"),
    );
    let dir = Temp::dir("e3-one-out");
    let out = run(&short, &dir.0);
    let message = stderr(&out);
    assert_eq!(code(&out), 1, "{message}");
    assert!(message.contains("MaxIterations"), "{message}");
    assert!(!message.contains("singular"), "{message}");
}

#[test]
fn m3_write_errors_name_the_file() {
    // A directory planted where a result goes makes its write fail: the message names that
    // file under its final name, not the output directory.
    for planted in ["tensions/newton_alpha1.csv", "summary.csv"] {
        let dir = Temp::dir("m3-out");
        std::fs::create_dir_all(dir.0.join(planted).join("x")).unwrap();
        let case = Temp::file("m3", &small_case("[\"newton\"]", "[0.5, 1.0]", ""));
        let out = run(&case, &dir.0);
        assert_eq!(code(&out), 1, "{}", stderr(&out));
        let file = dir.0.join(planted);
        assert!(
            stderr(&out).starts_with("error: run `")
                && stderr(&out).contains(&format!("`: could not write `{}`:", file.display())),
            "{}",
            stderr(&out)
        );
        // D7: the failed commit (as on a full disk) took back what it had published; the
        // solve before it is whole, with its row.
        if planted.starts_with("tensions") {
            assert_eq!(summary(&dir.0).len(), 1);
            assert!(!dir.0.join("displacements/newton_alpha1.csv").exists());
            assert!(dir.0.join("displacements/newton_alpha0.5.csv").exists());
            assert_every_file_has_a_row(&dir.0);
        }
    }
}

#[test]
fn r3_the_round_off_stop_is_convergence_only_without_load() {
    // Review turn 4, R3: "Δη at round-off of the prestress" stopped a LATIN solve as
    // converged under a load: with stiff cables micro-macro said converged at r(U) = 2.3e-9
    // above its 1e-9, and at α = 1e-8 with η = 2.3e-4 (e = 2 %). It is convergence only
    // with no load (η a ratio of round-off); under a load the floor is 1e-15 of the
    // prestress, and a solve that reaches it unconverged says `stalled`.
    let dir = Temp::dir("r3-stiff");
    let stiff = Temp::file(
        "r3-stiff",
        "[grid]\nmodules = [4, 3]\n[cables]\nyoung = 1e15\n[load]\nalpha = [0.05]\n\
         [solver]\nmethods = [\"micro-macro\"]\ntolerance = 1e-8\nmax_iterations = 100\n\
         subdomains = [2, 2]\ndm = 3.92e6\n",
    );
    let out = run(&stiff, &dir.0);
    let rows = summary(&dir.0);
    assert_eq!(rows.len(), 1);
    let r: f64 = column(&rows[0], "equilibrium_residual").parse().unwrap();
    assert!(
        column(&rows[0], "converged") == "false" || r <= 1e-9,
        "converged with r(U) = {r:e} above its 1e-9"
    );
    assert_eq!(code(&out) == 0, column(&rows[0], "converged") == "true");
    // A tiny load iterates to its tolerance; α = 0 still converges at once.
    let dir = Temp::dir("r3-tiny");
    let tiny = Temp::file(
        "r3-tiny",
        "[grid]\nmodules = [4, 4]\n[load]\nalpha = [0.0, 1e-8]\n[solver]\n\
         methods = [\"micro-macro\", \"mono-latin\"]\nsubdomains = [2, 2]\n",
    );
    let out = run(&tiny, &dir.0);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    for row in summary(&dir.0) {
        assert_eq!(column(&row, "converged"), "true");
        let eta: f64 = column(&row, "residual").parse().unwrap();
        if column(&row, "alpha") != "0" {
            assert!(eta <= 1e-6, "{row:?}: converged at eta = {eta:e}");
        } else {
            assert_eq!(column(&row, "iterations"), "0", "{row:?}");
        }
    }
}

#[test]
fn r7_minus_zero_is_the_load_factor_zero() {
    // Review turn 4, R7: `alpha = [-0.0, 0.0]` gave two rows and the files `newton_alpha-0.csv`
    // and `newton_alpha0.csv`; −0 is 0, named twice.
    let case = Temp::file("r7", &small_case("[\"newton\"]", "[-0.0, 0.0]", ""));
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(stderr(&out).contains("distinct"), "{}", stderr(&out));
    let case = Temp::file("r7-alone", &small_case("[\"newton\"]", "[-0.0, 1.0]", ""));
    let dir = Temp::dir("r7-out");
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let names = files(&dir.0);
    assert!(names.contains("tensions/newton_alpha0.csv"), "{names:?}");
    assert!(!names.iter().any(|n| n.contains("alpha-0")), "{names:?}");
    assert_eq!(column(&summary(&dir.0)[0], "alpha"), "0");
}

#[test]
fn r6_tables_are_read_bounded() {
    // Review turn 4, R6: `nodes = "/dev/zero"` was read to the end of memory (2.1 GB before
    // "cannot read case file `/dev/zero`: out of memory"); tables are now read bounded, like
    // the case file, and the message names the table.
    let members = common::manifest_path("cases/simplex/members.csv");
    let case = Temp::file(
        "r6",
        &format!(
            "[structure]\nnodes = \"/dev/zero\"\nmembers = \"{}\"\n[load]\nalpha = [1.0]\n",
            members.display()
        ),
    );
    let out = under_address_limit(
        1_500_000,
        &["check", case.arg()],
        &[],
        Duration::from_secs(60),
    );
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(
        stderr(&out).contains("cannot read nodes table `/dev/zero`: it is larger than 256 MiB"),
        "{}",
        stderr(&out)
    );
}

// ---- Turn 4: removal through links, kills while a rerun removes, failed reruns ----

#[test]
fn r1_removal_never_follows_a_link() {
    // A planted manifest naming a file through a link to a directory outside, a path that
    // leaves the directory, and the lock: none of them is removed.
    let dir = Temp::dir("r1-out");
    let outside = Temp::dir("r1-outside");
    std::fs::create_dir_all(&dir.0).unwrap();
    std::fs::create_dir_all(&outside.0).unwrap();
    std::fs::write(outside.0.join("x"), "precious\n").unwrap();
    std::os::unix::fs::symlink(&outside.0, dir.0.join("ld")).unwrap();
    let escape = format!("../{}/x", outside.0.file_name().unwrap().to_str().unwrap());
    std::fs::write(
        dir.0.join(".tensolve-manifest"),
        format!(
            "ld/x\n{escape}\n{}\n.tensolve.lock\n",
            outside.0.join("x").display()
        ),
    )
    .unwrap();
    let case = Temp::file("r1", &small_case("[\"newton\"]", "[1.0]", ""));
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert_eq!(
        std::fs::read_to_string(outside.0.join("x")).unwrap(),
        "precious\n"
    );
    // A result directory moved elsewhere and linked back: the rerun removes nothing through
    // the link (and refuses to write through it).
    let elsewhere = Temp::dir("r1-elsewhere");
    std::fs::rename(dir.0.join("forces"), &elsewhere.0).unwrap();
    std::os::unix::fs::symlink(&elsewhere.0, dir.0.join("forces")).unwrap();
    // A published file replaced by a link: the link goes, never its target.
    let victim = Temp::dir("r1-victim");
    std::fs::write(&victim.0, "precious\n").unwrap();
    std::fs::remove_file(dir.0.join("tensions/newton_alpha1.csv")).unwrap();
    std::os::unix::fs::symlink(&victim.0, dir.0.join("tensions/newton_alpha1.csv")).unwrap();
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 1, "{}", stderr(&out));
    assert!(stderr(&out).contains("forces"), "{}", stderr(&out));
    assert_eq!(
        files(&elsewhere.0),
        BTreeSet::from(["newton_alpha1.csv".to_string()])
    );
    assert_eq!(std::fs::read_to_string(&victim.0).unwrap(), "precious\n");
}

#[test]
fn r4_a_kill_while_a_rerun_removes_the_previous_run_shows_no_file_without_its_row() {
    // 1600 result files of a first run; the rerun is killed as soon as it has removed those
    // of the tenth solve (the manifest lists them in the order they were published): every
    // file left has its row.
    let dir = Temp::dir("r4-out");
    let case = Temp::file(
        "r4",
        "[grid]\nmodules = [2, 2]\n[load]\nalpha = { from = 0.01, to = 3.0, steps = 400 }\n\
         [solver]\nmethods = [\"newton\"]\n",
    );
    assert_eq!(code(&run(&case, &dir.0)), 0);
    let rows = summary(&dir.0);
    assert_eq!(rows.len(), 400);
    let first = dir
        .0
        .join(format!("displacements/newton_alpha{}.csv", rows[9][1]));
    assert!(first.exists());
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .args([
            "run",
            case.arg(),
            "--out",
            dir.0.to_str().unwrap(),
            "--quiet",
        ])
        .args(["--set", "load.alpha=[0.5]"])
        .spawn()
        .unwrap();
    let start = Instant::now();
    while first.exists() && start.elapsed() < Duration::from_secs(60) {
        std::hint::spin_loop();
    }
    child.kill().unwrap(); // SIGKILL: no handler runs
    child.wait().unwrap();
    assert!(!first.exists(), "the rerun never started removing");
    assert_every_file_has_a_row(&dir.0);
}

#[test]
fn r5_a_failed_rerun_leaves_nothing_of_the_previous_run() {
    // The rerun cannot write its first file (`ulimit -f 0`, as on a full disk): it exits 1,
    // and the previous run's rows and files are gone, not left looking like its own.
    let dir = Temp::dir("r5-out");
    let case = Temp::file("r5", &small_case("[\"newton\"]", "[0.5, 1.0]", ""));
    assert_eq!(code(&run(&case, &dir.0)), 0);
    assert_eq!(summary(&dir.0).len(), 2);
    std::fs::write(dir.0.join("notes.txt"), "mine").unwrap();
    let line = format!(
        "trap '' XFSZ; ulimit -f 0; exec '{}' run '{}' --out '{}' --quiet --set 'load.alpha=[2.0]'",
        env!("CARGO_BIN_EXE_tensolve"),
        case.arg(),
        dir.0.display()
    );
    let out = Command::new("sh").args(["-c", &line]).output().unwrap();
    assert_eq!(code(&out), 1, "{}", stderr(&out));
    assert!(stderr(&out).contains("could not write"), "{}", stderr(&out));
    assert_eq!(
        files(&dir.0),
        BTreeSet::from(["notes.txt".to_string()]),
        "{}",
        stderr(&out)
    );
}

// ---- Issue 42: the third adversarial review ----

/// T7: the creation of `summary.csv` fails after the first solve's files are published (a full
/// disk exactly there; here a directory planted under its name, which fails the same step):
/// the run ends with exit 1 naming `summary.csv`, and the solve's files are withdrawn, so no
/// result file is left without its row.
#[test]
fn t7_a_summary_that_cannot_be_created_leaves_no_file_without_its_row() {
    let dir = Temp::dir("t7-out");
    std::fs::create_dir_all(dir.0.join("summary.csv/x")).unwrap();
    let case = Temp::file(
        "t7",
        &small_case(
            "[\"newton\", \"mono-latin\"]",
            "[0.5, 1.0]",
            "[output]\nstability = true\n",
        ),
    );
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 1, "{}", stderr(&out));
    let summary = dir.0.join("summary.csv");
    assert!(
        stderr(&out).starts_with("error: run `")
            && stderr(&out).contains(&format!("`: could not write `{}`:", summary.display())),
        "{}",
        stderr(&out)
    );
    // No file but the planted directory: no tensions/, displacements/, forces/, reactions/,
    // history/ file, and no stability.csv or reaction_totals.csv row of a solve without its
    // summary row.
    assert!(dir.0.join("summary.csv/x").is_dir());
    assert_eq!(files(&dir.0), BTreeSet::new(), "{}", stderr(&out));
}

/// T10: a file-size limit (`ulimit -f`) below a result file's size: the write fails and the
/// run says which file, with exit 1, instead of being killed by SIGXFSZ with no word.
#[test]
fn t10_a_file_size_limit_is_a_write_error_naming_the_file() {
    let dir = Temp::dir("t10-out");
    let case = Temp::file("t10", &small_case("[\"newton\"]", "[1.0]", ""));
    // 1 block (512 or 1024 bytes by the shell): the 192 cables' tensions take more.
    let line = format!(
        "ulimit -f 1; exec '{}' run '{}' --out '{}' --quiet",
        env!("CARGO_BIN_EXE_tensolve"),
        case.arg(),
        dir.arg()
    );
    let out = Command::new("sh").args(["-c", &line]).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(1),
        "ended by {:?}: {}",
        out.status,
        stderr(&out)
    );
    let message = stderr(&out);
    assert!(
        message.starts_with("error: run `")
            && message.contains(&format!("`: could not write `{}/", dir.arg()))
            && message.contains("ulimit -f"),
        "{message}"
    );
    assert!(!dir.0.join("summary.csv").exists());
    assert_every_file_has_a_row(&dir.0);
}

/// T11: a bad `--set` among several: the message names that one, not every override given.
#[test]
fn t11_a_bad_override_is_named_alone() {
    let case = Temp::file("t11", &small_case("[\"newton\"]", "[1.0]", ""));
    let out = tensolve(&[
        "check",
        case.arg(),
        "--set",
        "solver.tolerance=1e-8",
        "--set",
        "solver.search_direction=\"Newton\"",
        "--set",
        "load.alpha=[2.0]",
    ]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    let message = stderr(&out);
    assert!(
        message.starts_with("error: check `")
            && message.contains("`: --set solver.search_direction=\"Newton\": unknown variant"),
        "{message}"
    );
    assert!(
        !message.contains("tolerance") && !message.contains("load.alpha"),
        "{message}"
    );
}

/// N-D4 (issue 57): a mistake in the case file itself is the file's, with its line and column,
/// whatever `--set` is given beside it: a misspelt `alpah` was blamed on `--set output.vtk=false`.
#[test]
fn a_files_own_mistake_is_not_blamed_on_an_override() {
    let case = Temp::file(
        "nd4",
        "[grid]\nmodules = [2, 2]\n[load]\nalpah = [1.0]\n[solver]\nmethods = [\"newton\"]\n",
    );
    let alone = tensolve(&["check", case.arg()]);
    let with_set = tensolve(&["check", case.arg(), "--set", "output.vtk=false"]);
    for out in [&alone, &with_set] {
        assert_eq!(code(out), 2, "{}", stderr(out));
        let message = stderr(out);
        assert!(
            message.contains("line 4, column 1") && message.contains("unknown field `alpah`"),
            "{message}"
        );
        assert!(!message.contains("--set"), "{message}");
    }
}

/// N11: `output.homogenised` with no micro-macro solve is refused by name (it wrote nothing
/// and said nothing, exit 0); with micro-macro it is written.
#[test]
fn n11_homogenised_output_without_micro_macro_is_refused() {
    let dir = Temp::dir("n11-out");
    let case = Temp::file(
        "n11",
        &small_case(
            "[\"newton\", \"mono-latin\"]",
            "[1.0]",
            "[output]\nhomogenised = true\n",
        ),
    );
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    let message = stderr(&out);
    assert!(
        message.contains("`output.homogenised` = true")
            && message.contains("newton, mono-latin")
            && message.contains("micro-macro"),
        "{message}"
    );
    assert!(files(&dir.0).is_empty(), "{:?}", files(&dir.0));
    // check refuses what run refuses (this session's adversarial pass: it said nothing).
    let out = tensolve(&["check", case.arg()]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(
        stderr(&out).contains("`output.homogenised` = true"),
        "{}",
        stderr(&out)
    );
    let out = tensolve(&[
        "run",
        case.arg(),
        "--out",
        dir.arg(),
        "--quiet",
        "--solver",
        "micro-macro",
        "--set",
        "solver.subdomains=[2, 2]",
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(files(&dir.0).iter().any(|f| f.starts_with("homogenised/")));
}

/// N13: a link planted under the lock's name is not followed (it created a file at its
/// target): the run is refused, naming it, and the target is not created.
#[test]
fn n13_a_planted_lock_link_is_refused_and_not_followed() {
    let dir = Temp::dir("n13-out");
    let victim = Temp::dir("n13-victim");
    std::fs::create_dir_all(&dir.0).unwrap();
    std::os::unix::fs::symlink(&victim.0, dir.0.join(".tensolve.lock")).unwrap();
    let case = Temp::file("n13", &small_case("[\"newton\"]", "[1.0]", ""));
    let out = run(&case, &dir.0);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(
        stderr(&out).contains(".tensolve.lock` is a link"),
        "{}",
        stderr(&out)
    );
    assert!(
        std::fs::symlink_metadata(&victim.0).is_err(),
        "the target was created"
    );
    assert!(files(&dir.0).is_empty());
}

/// N14: a newline inside a `--set` value, then another key: refused (the rest was dropped
/// silently, exit 0), the message on one line.
#[test]
fn n14_a_newline_inside_an_override_is_refused() {
    let case = Temp::file("n14", &small_case("[\"newton\"]", "[1.0]", ""));
    for set in [
        "solver.tolerance=1e-8\nsolver.methods=[\"pcg-lcp\"]",
        "solver.tolerance=1e-8\n[load]\nalpha=[2.0]",
    ] {
        let out = tensolve(&["check", case.arg(), "--set", set]);
        assert_eq!(code(&out), 2, "{set:?}: {}", stderr(&out));
        let message = stderr(&out);
        assert!(
            message.contains("holds more than one value") && message.lines().count() == 1,
            "{message}"
        );
    }
    // A list written over two lines is one value.
    let out = tensolve(&["check", case.arg(), "--set", "load.alpha=[0.5,\n1.0]"]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
}

/// Adversarial pass M5: an override that mends the file's own mistake at its key leaves the
/// blame to the override that is bad: with `tolerance = "tight"` in the file, `--set
/// solver.tolerance=1e-8` and `--set output.vtk="yes"`, the error named the file's line.
#[test]
fn the_bad_override_is_named_when_another_mends_the_file() {
    let case = Temp::file(
        "m5",
        "[grid]\nmodules = [2, 2]\n[load]\nalpha = [1.0]\n[solver]\nmethods = [\"newton\"]\n\
         tolerance = \"tight\"\n",
    );
    let out = tensolve(&[
        "check",
        case.arg(),
        "--set",
        "solver.tolerance=1e-8",
        "--set",
        "output.vtk=\"yes\"",
    ]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    let message = stderr(&out);
    assert!(message.contains("--set output.vtk=\"yes\""), "{message}");
    assert!(!message.contains("line 7"), "{message}");
    let mended = tensolve(&["check", case.arg(), "--set", "solver.tolerance=1e-8"]);
    assert_eq!(code(&mended), 0, "{}", stderr(&mended));
}

/// N-D7 (issue 57): sections in mm² (523 and 100 for 5.23e-4 and 1e-4 m²) passed `check`
/// silently (the GPa slip is warned about): a member too stocky for a tension structure (its
/// section's diameter a third of its length or more) is now named, for cm² too.
#[test]
fn sections_in_mm2_are_warned_about_by_check() {
    let tables = manifest_path("tests/data/tower3q");
    let members = std::fs::read_to_string(tables.join("members.csv")).unwrap();
    for (scale, warned) in [(1.0, false), (1e4, true), (1e6, true)] {
        let dir = Temp::dir("nd7");
        std::fs::create_dir_all(&dir.0).unwrap();
        std::fs::copy(tables.join("nodes.csv"), dir.0.join("nodes.csv")).unwrap();
        let scaled: String = members
            .lines()
            .enumerate()
            .map(|(i, line)| {
                let mut cells: Vec<String> = line.split(',').map(String::from).collect();
                if i > 0 {
                    cells[5] = (cells[5].parse::<f64>().unwrap() * scale).to_string();
                }
                cells.join(",") + "\n"
            })
            .collect();
        std::fs::write(dir.0.join("members.csv"), scaled).unwrap();
        let case = dir.0.join("case.toml");
        std::fs::write(
            &case,
            "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n[[supports.fix]]\n\
             nodes = [0, 1, 2, 3]\n[prestress]\nfrom = \"design\"\n\
             targets = { bars0 = -5000.0, bars1 = -4000.0, bars2 = -3000.0 }\n[load]\n\
             alpha = [1.0]\n",
        )
        .unwrap();
        let out = tensolve(&["check", case.to_str().unwrap()]);
        assert_eq!(code(&out), 0, "{}", stderr(&out));
        let text = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            text.contains("is too stocky") && text.contains("not mm² or cm²"),
            warned,
            "scale {scale}: {text}"
        );
    }
}
