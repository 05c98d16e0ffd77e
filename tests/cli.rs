//! The `tensolve` binary: exit codes and messages for bad input, the golden summary of the paper
//! case, the per-solve files, `check`, and the output switches.
//!
//! `TENSOLVE_BLESS=1 cargo test --test cli` rewrites `tests/golden/paper_summary.csv` from the
//! current binary (after the physical checks of the new summary pass).

mod common;

use common::{manifest_path, stderr, temp_path, tensolve, Temp};
use std::path::Path;

const VALID: &str = "[grid]\nmodules = [2, 2]\n[load]\nalpha = [1.0]\n";

fn with(extra: &str) -> String {
    format!("{VALID}{extra}\n")
}

fn load_with(load: &str) -> String {
    format!("[grid]\nmodules = [2, 2]\n[load]\n{load}\n")
}

#[test]
fn invalid_cases_exit_2_and_name_the_key() {
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("malformed", "[grid\nmodules = [2, 2]\n".into(), &["line 1"]),
        (
            "unknown-section",
            with("[foo]\nx = 1"),
            &["unknown field `foo`"],
        ),
        (
            "unknown-grid-key",
            "[grid]\nmodules = [2, 2]\ncolour = 1\n[load]\nalpha = [1.0]\n".into(),
            &["unknown field `colour`", "line 3"],
        ),
        (
            "wrong-type",
            "[grid]\nmodules = \"16\"\n[load]\nalpha = [1.0]\n".into(),
            &["modules", "invalid type", "\"16\""],
        ),
        (
            "zero-modules",
            "[grid]\nmodules = [0, 4]\n[load]\nalpha = [1.0]\n".into(),
            &["grid.modules", "[0, 4]"],
        ),
        (
            "negative-young",
            with("[cables]\nyoung = -2.0"),
            &["cables.young", "-2"],
        ),
        (
            "zero-section",
            with("[bars]\nsection = 0.0"),
            &["bars.section", "= 0"],
        ),
        (
            "nan-young",
            with("[cables]\nyoung = nan"),
            &["cables.young", "NaN"],
        ),
        (
            "inf-load",
            load_with("nodal = [0.0, inf, -40.0]\nalpha = [1.0]"),
            &["load.nodal[1]", "inf"],
        ),
        (
            "empty-alpha",
            load_with("alpha = []"),
            &["load.alpha", "[]"],
        ),
        (
            "zero-steps",
            load_with("alpha = { from = 0.0, to = 1.0, steps = 0 }"),
            &["load.alpha", "steps = 0"],
        ),
        (
            "negative-tolerance",
            with("[solver]\ntolerance = -0.5"),
            &["solver.tolerance", "-0.5"],
        ),
        (
            "zero-iterations",
            with("[solver]\nmax_iterations = 0"),
            &["solver.max_iterations", "= 0"],
        ),
        (
            "no-methods",
            with("[solver]\nmethods = []"),
            &["solver.methods", "[]"],
        ),
        (
            "unknown-method",
            with("[solver]\nmethods = [\"gauss\"]"),
            &["gauss", "newton"],
        ),
        (
            "missing-load",
            "[grid]\nmodules = [2, 2]\n".into(),
            &["missing field `load`"],
        ),
        (
            "missing-grid",
            "[load]\nalpha = [1.0]\n".into(),
            &["missing field `grid`"],
        ),
        (
            "mechanism",
            with("[supports]\nclamp = \"none\""),
            &["mechanism", "zero-stiffness mode"],
        ),
        (
            // LATIN alone, nothing solving with K: checked by substructures (a free 2 × 2 grid
            // of the standard module has 7 zero modes, as the whole factor counts).
            "mechanism-checked-by-substructures",
            with(
                "[supports]\nclamp = \"none\"\n[solver]\nmethods = [\"micro-macro\"]\n\
                 reference = \"none\"\n[output]\ngeometric_term = false",
            ),
            &[
                "mechanism",
                "has 7 zero-stiffness mode(s)",
                "supports.clamp",
            ],
        ),
        (
            "overflowing-young",
            with("[cables]\nyoung = 1e300"),
            &["cables.young", "1e300", "≤ 1e15"],
        ),
        (
            "huge-alpha",
            load_with("alpha = [1e300]"),
            &["load.alpha", "1e300", "≤ 1e6"],
        ),
        (
            "partition-larger-than-grid",
            with("[solver]\nsubdomains = [3, 1]"),
            &["solver.subdomains", "[3, 1]", "sx ≤ 2"],
        ),
        (
            "zero-dm",
            with("[solver]\ndm = 0.0"),
            &["solver.dm", "= 0", "> 0"],
        ),
        (
            "negative-dm",
            with("[solver]\ndm = -3.92e6"),
            &["solver.dm", "-3.92e6"],
        ),
        (
            "bad-search-direction",
            with("[solver]\nl = \"stiff\""),
            &["solver.l", "stiffness"],
        ),
        (
            "unknown-weak-interfaces",
            with("[solver]\nweak_interfaces = \"glue\""),
            &["glue", "macro"],
        ),
        (
            "relaxation-zero",
            with("[solver]\nrelaxation = 0.0"),
            &["solver.relaxation", "(0, 1]"],
        ),
        (
            "relaxation-above-one",
            with("[solver]\nrelaxation = 1.5"),
            &["solver.relaxation", "1.5"],
        ),
        (
            "unknown-search-direction",
            with("[solver]\nsearch_direction = \"gradient\""),
            &["gradient", "status", "newton"],
        ),
        (
            "forcing-out-of-range",
            with("[solver]\nforcing = 1.5"),
            &["solver.forcing", "1.5", "between 0 and 1"],
        ),
        (
            "keep-z-not-a-boolean",
            with("[solver]\nkeep_z = \"no\""),
            &["keep_z", "bool"],
        ),
        (
            "macro-degree-zero",
            with("[solver]\nmacro_degree = 0"),
            &["solver.macro_degree", "between 1", "16"],
        ),
        (
            "macro-degree-too-high",
            with("[solver]\nmacro_degree = 40"),
            &["solver.macro_degree", "40", "16"],
        ),
        (
            "macro-degree-not-an-integer",
            with("[solver]\nmacro_degree = 2.5"),
            &["macro_degree = 2.5", "expected usize"],
        ),
        (
            "unknown-stop-on",
            with("[solver]\nstop_on = \"never\""),
            &["never", "residual"],
        ),
        (
            "residual-tolerance-one",
            with("[solver]\nresidual_tolerance = 1.0"),
            &["solver.residual_tolerance", "between 0 and 1"],
        ),
    ];
    let out = Temp::dir("invalid-out");
    let mut failures = Vec::new();
    for (name, text, fragments) in &cases {
        let file = Temp::file(name, text);
        let o = tensolve(&["run", file.arg(), "--out", out.arg(), "--quiet"]);
        let err = stderr(&o);
        if o.status.code() != Some(2) {
            failures.push(format!("{name}: exit {:?}, stderr: {err}", o.status.code()));
        }
        for f in fragments.iter() {
            if !err.contains(f) {
                failures.push(format!("{name}: stderr lacks `{f}`: {err}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn unwritable_output_directory_exits_2() {
    // A path below a regular file can never be a directory.
    let blocker = Temp::file("blocker", "not a directory");
    let case = Temp::file("unwritable", VALID);
    let out = format!("{}/out", blocker.arg());
    let o = tensolve(&["run", case.arg(), "--out", &out, "--quiet"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&out) && err.contains("--out"), "{err}");
}

#[test]
fn missing_case_file_exits_2() {
    let missing = temp_path("does-not-exist.toml");
    let path = missing.to_str().unwrap();
    for command in ["run", "check"] {
        let o = tensolve(&[command, path]);
        assert_eq!(o.status.code(), Some(2), "{command}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("cannot read case file") && err.contains(path),
            "{command}: {err}"
        );
    }
}

#[test]
fn unknown_solver_option_exits_2() {
    let file = Temp::file("valid", VALID);
    let out = Temp::dir("bogus-out");
    let o = tensolve(&["run", file.arg(), "--solver", "bogus", "--out", out.arg()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("bogus"), "{}", stderr(&o));
    assert!(!out.0.join("summary.csv").exists());
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| rec.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

fn run_paper(out: &Temp) {
    let case = manifest_path("cases/paper-exact.toml");
    let o = tensolve(&["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

fn number(s: &str) -> f64 {
    s.parse().unwrap_or_else(|_| panic!("not a number: {s}"))
}

/// What the paper case must give whatever the golden file says (docs/method.md §2).
fn assert_plausible_summary(header: &[String], rows: &[Vec<String>]) {
    let expected_slack = [(0.05, 0), (0.25, 2), (0.5, 36), (0.75, 272), (1.0, 408)];
    assert_eq!(rows.len(), 10);
    for (i, row) in rows.iter().enumerate() {
        let (alpha, slack) = expected_slack[i / 2];
        assert_eq!(
            row[column(header, "solver")],
            ["newton", "pcg-lcp"][i % 2],
            "row {i}"
        );
        assert_eq!(number(&row[column(header, "alpha")]), alpha, "row {i}");
        assert_eq!(row[column(header, "converged")], "true", "row {i}");
        assert_eq!(
            row[column(header, "slack_cables")],
            slack.to_string(),
            "row {i}"
        );
        assert_eq!(row[column(header, "cables")], "3072", "row {i}");
        assert!(number(&row[column(header, "residual")]) <= 1e-10, "row {i}");
    }
}

fn relative_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs())
}

#[test]
fn paper_summary_matches_golden() {
    let out = Temp::dir("paper-golden");
    run_paper(&out);
    let (header, rows) = read_csv(&out.0.join("summary.csv"));
    assert_plausible_summary(&header, &rows);
    let golden_path = manifest_path("tests/golden/paper_summary.csv");
    if std::env::var_os("TENSOLVE_BLESS").is_some() {
        std::fs::copy(out.0.join("summary.csv"), &golden_path).unwrap();
    }
    let (golden_header, golden) = read_csv(&golden_path);
    assert_eq!(header, golden_header);
    assert_eq!(rows.len(), golden.len());
    let exact = [
        "solver",
        "alpha",
        "converged",
        "slack_cables",
        "cables",
        "slack_fraction",
        "iterations",
    ];
    for (i, (row, want)) in rows.iter().zip(&golden).enumerate() {
        for name in exact {
            let c = column(&header, name);
            assert_eq!(row[c], want[c], "row {i}, {name}");
        }
        for name in ["max_tension", "max_deflection"] {
            let c = column(&header, name);
            let (got, expected) = (number(&row[c]), number(&want[c]));
            assert!(
                relative_close(got, expected, 1e-9),
                "row {i}, {name}: {got} vs {expected}"
            );
        }
        let c = column(&header, "residual");
        assert!(
            number(&want[c]) <= 1e-10 && number(&row[c]) <= 1e-10,
            "row {i}, residual"
        );
    }
}

/// Every field that reads as a number must be finite (Rust parses `NaN`, `inf`, `-inf`).
fn assert_all_finite(path: &Path) {
    let (_, rows) = read_csv(path);
    for (i, row) in rows.iter().enumerate() {
        for field in row {
            if let Ok(x) = field.parse::<f64>() {
                assert!(x.is_finite(), "{}: row {i} has {field}", path.display());
            }
        }
    }
}

#[test]
fn per_solve_files_exist_and_parse() {
    let out = Temp::dir("paper-files");
    run_paper(&out);

    let (header, rows) = read_csv(&out.0.join("tensions/newton_alpha1.csv"));
    assert_eq!(header, ["cable", "kind", "node_a", "node_b", "tension"]);
    assert_eq!(rows.len(), 3072);
    let tension = column(&header, "tension");
    assert_eq!(
        rows.iter().filter(|r| number(&r[tension]) == 0.0).count(),
        408
    );
    assert!(
        rows.iter().all(|r| number(&r[tension]) >= 0.0),
        "negative cable tension"
    );

    let (header, rows) = read_csv(&out.0.join("displacements/pcg-lcp_alpha0.05.csv"));
    assert_eq!(header, ["node", "x", "y", "z", "ux", "uy", "uz"]);
    assert_eq!(rows.len(), 833);

    let mut files = 0;
    for sub in ["tensions", "displacements"] {
        for solver in ["newton", "pcg-lcp"] {
            for alpha in ["0.05", "0.25", "0.5", "0.75", "1"] {
                assert_all_finite(&out.0.join(format!("{sub}/{solver}_alpha{alpha}.csv")));
                files += 1;
            }
        }
    }
    assert_all_finite(&out.0.join("summary.csv"));
    assert_eq!(files, 20);
}

#[test]
fn check_prints_the_model() {
    let case = manifest_path("cases/paper-exact.toml");
    let o = tensolve(&["check", case.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for (label, value) in [
        ("nodes", "833"),
        ("dofs", "2499"),
        ("free dofs", "2397"),
        ("cables", "3072"),
        ("bars", "1024"),
    ] {
        let found = text.lines().any(|line| {
            line.trim_start().starts_with(label) && line.split_whitespace().any(|w| w == value)
        });
        assert!(found, "no line `{label} ... {value}` in:\n{text}");
    }
}

/// The default partition (issue 41): substructures of about 16 × 16 modules, at least 4 × 4
/// of them, printed by `check` with where it comes from; a given `solver.subdomains` is named.
#[test]
fn check_prints_the_default_partition_and_why() {
    let partition = |modules: [usize; 2], extra: &str| {
        let file = Temp::file(
            "default-partition",
            &format!(
                "[grid]\nmodules = [{}, {}]\n[supports]\nclamp = \"lower-all-edges\"\n\
                 [load]\nalpha = [0.01]\n[solver]\nmethods = [\"micro-macro\"]\n{extra}\
                 [output]\ngeometric_term = false\n",
                modules[0], modules[1]
            ),
        );
        let o = tensolve(&["check", file.arg()]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        text.lines()
            .find(|l| l.trim_start().starts_with("substructures"))
            .unwrap_or_else(|| panic!("no substructures line in:\n{text}"))
            .to_string()
    };
    // 16 x 16: the paper's 4 x 4; 40 x 24: at least 4 a side; 96 x 200: round(n / 16).
    for (modules, count, shape) in [
        ([16, 16], 16, "4 x 4"),
        ([40, 24], 16, "4 x 4"),
        ([96, 200], 78, "6 x 13"),
        ([3, 20], 12, "3 x 4"),
    ] {
        let line = partition(modules, "");
        assert!(
            line.contains(&format!("substructures {count} ({shape}: default")),
            "{modules:?}: {line}"
        );
    }
    let line = partition([96, 200], "subdomains = [2, 3]\n");
    assert!(
        line.contains("substructures 6 (2 x 3: solver.subdomains)"),
        "{line}"
    );
}

#[test]
fn output_switches_limit_the_files() {
    let file = Temp::file(
        "switches",
        // pcg-lcp (a default solver) writes a history since main's c85db27: switched off too.
        // forces/ and reactions/ (issue 27) are per-solve files too: switched off likewise.
        &format!(
            "{VALID}[output]\ntensions = false\ndisplacements = false\nhistory = false\n\
             forces = false\nreactions = false\n"
        ),
    );
    let out = Temp::dir("switches-out");
    let o = tensolve(&["run", file.arg(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(&out.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        // The run's lock and manifest (issue 13) are bookkeeping, not results.
        .filter(|n| !n.starts_with(".tensolve"))
        .collect();
    names.sort();
    assert_eq!(names, ["summary.csv"]);
    let (_, rows) = read_csv(&out.0.join("summary.csv"));
    assert_eq!(rows.len(), 2, "one row per solver");
}

#[test]
fn stability_csv_reports_the_smallest_tangent_eigenvalue() {
    let case = Temp::file(
        "stability",
        "[grid]\nmodules = [16, 16]\n[load]\nalpha = [1.0]\n[solver]\nmethods = [\"newton\"]\n\
         [output]\nstability = true\ntensions = false\ndisplacements = false\n\
         [model]\ngeometry = \"linear\"\n",
    );
    let out = Temp::dir("stability-out");
    let o = tensolve(&["run", case.arg(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text =
        std::fs::read_to_string(std::path::Path::new(out.arg()).join("stability.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("solver,alpha,slack_cables,min_tangent_eigenvalue")
    );
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&row[..3], ["newton", "1", "408"]);
    let lambda: f64 = row[3].parse().unwrap();
    assert!(
        (lambda - 164.0).abs() < 2.0,
        "docs/method.md: ≈ 164 N/m, got {lambda}"
    );
}

/// `scripts/peers/peers.py` on a `[structure]` case says it compares grids and names the peer
/// that takes general structures (it died on `KeyError: 'grid'`). Needs numpy, which CI installs
/// with openseespy. A peer check: ignored by a plain `cargo test`, failed where numpy is missing.
#[test]
#[ignore = "peer check: needs python3 with numpy (python3 -m pip install numpy); run with -- --include-ignored"]
fn peers_script_refuses_a_structure_case_plainly() {
    common::require_python(&["numpy"]);
    let o = std::process::Command::new("python3")
        .arg(manifest_path("scripts/peers/peers.py"))
        .args([
            manifest_path("cases/skew-grid.toml").to_str().unwrap(),
            "1.0",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("has no [grid]") && err.contains("corot.py"),
        "{err}"
    );
    assert!(!err.contains("Traceback"), "{err}");
}

/// `check` prints the bounding box and the ranges of member lengths and E·S, and warns about
/// a stiffness ratio beyond 1e8 (E of some members in the wrong unit) and a member beyond
/// 1e4 m (coordinates in mm).
#[test]
fn check_shows_magnitudes_and_warns_about_unit_slips() {
    let skew = manifest_path("cases/skew-grid.toml");
    let o = tensolve(&["check", skew.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for line in [
        "bounding box    x 0.0000e0 .. 7.6000e0, y 0.0000e0 .. 4.0000e0, z 0.0000e0 .. 1.1000e0 m",
        "member lengths  5.8523e-1 .. 1.4318e0 m",
        "member E·S      5.0000e6 .. 5.6000e7 N",
    ] {
        assert!(text.contains(line), "{text}");
    }
    assert!(!text.contains("warning"), "{text}");
    let paper = manifest_path("cases/paper-exact.toml");
    let slipped = tensolve(&[
        "check",
        paper.to_str().unwrap(),
        "--set",
        "cables.young=1e3",
        "--set",
        "grid.length=2e4",
    ]);
    let text = String::from_utf8_lossy(&slipped.stdout);
    assert!(
        text.contains("warning: the members' stiffness E·S/ℓ spans a ratio of")
            && text.contains("warning: a member is 2.236e4 m long"),
        "{text}"
    );
}

/// E given in GPa (a unit slip): the linear model's answer moves nodes by 2.4e8 m, far beyond
/// the structure's own size; the rows say converged = false, status = beyond_model, exit 1.
#[test]
fn an_answer_beyond_the_structures_size_is_not_converged() {
    let out = Temp::dir("gpa");
    let o = tensolve(&[
        "run",
        manifest_path("cases/paper-exact.toml").to_str().unwrap(),
        "--out",
        out.arg(),
        "--set",
        "cables.young=100",
        "--set",
        "bars.young=200",
        "--set",
        "load.alpha=[1.0]",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("beyond the model"), "{}", stderr(&o));
    let (header, rows) = read_csv(&out.0.join("summary.csv"));
    for row in &rows {
        assert_eq!(row[column(&header, "converged")], "false");
        assert_eq!(row[column(&header, "status")], "beyond_model");
    }
}

/// A LATIN row at α = 0 stops on Δη at round-off of the prestress (η is then round-off over
/// round-off): its solve line says so, and does not print `converged … eta 5.2e-1` as if η had
/// met the tolerance.
#[test]
fn a_latin_row_without_load_says_it_stopped_at_round_off() {
    let out = Temp::dir("alpha0");
    let case = manifest_path("cases/paper.toml");
    let o = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.arg(),
        "--set",
        "load.alpha=[0]",
        "--set",
        "output.plots=false",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stderr(&o);
    for solver in ["mono-latin", "micro-macro"] {
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{solver} alpha = 0 ")))
            .unwrap_or_else(|| panic!("no line of {solver} at alpha = 0 in:\n{text}"));
        assert!(
            line.contains("converged (no load: Δη at round-off of the prestress) in 0 it"),
            "{line}"
        );
        assert!(!line.contains("eta"), "{line}");
        assert!(line.contains("r(U)"), "{line}");
    }
    // The exact solvers' lines are unchanged.
    let newton = text
        .lines()
        .find(|l| l.trim_start().starts_with("newton alpha = 0 "))
        .unwrap();
    assert!(newton.contains(" converged in "), "{newton}");
}
