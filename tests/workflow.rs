//! The researcher's workflow: `--set` overrides on `run` and `check`, validated like the file,
//! and `scripts/sweep.sh`, the documented load-sweep example, on a small grid.

mod common;

use common::{manifest_path, stderr, tensolve, Temp};
use std::process::Command;

#[test]
fn set_overrides_case_keys() {
    let case = manifest_path("cases/paper-exact.toml");
    let out = Temp::dir("set-run");
    let o = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.arg(),
        "--quiet",
        "--set",
        "load.alpha=[0.5]",
        "--set",
        "solver.methods=[\"newton\"]",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).unwrap();
    let rows: Vec<&str> = summary.lines().skip(1).collect();
    // One solver at one α: the paper's 36 slack cables at α = 0.5.
    assert_eq!(rows.len(), 1, "{summary}");
    assert!(rows[0].starts_with("newton,0.5,true,"), "{summary}");
    assert!(rows[0].contains(",36,3072,"), "{summary}");
    // A key the file does not have, in a table it does not have.
    let o = tensolve(&[
        "check",
        case.to_str().unwrap(),
        "--set",
        "grid.modules=[2, 2]",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.lines()
            .any(|l| l.starts_with("nodes") && l.contains(" 21")),
        "{text}"
    );
}

#[test]
fn bad_overrides_exit_2_and_are_named() {
    let case = manifest_path("cases/paper-exact.toml");
    for (set, expected) in [
        ("solver.dm=-1", "`solver.dm` = -1 is not valid"),
        ("solver.dm=abc", "not a TOML value"),
        ("solver.bogus=1", "unknown field `bogus`"),
        ("no-equals-sign", "key=value"),
        ("grid.modules.x=1", "not a table"),
    ] {
        let o = tensolve(&["run", case.to_str().unwrap(), "--quiet", "--set", set]);
        let message = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {message}");
        assert!(
            message.contains(&format!("--set {set}")),
            "{set}: {message}"
        );
        assert!(message.contains(expected), "{set}: {message}");
    }
}

#[test]
fn sweep_script_collects_slack_fraction_against_prestress() {
    let case = Temp::file(
        "sweep-case",
        "[grid]\nmodules = [4, 4]\n[load]\nalpha = [6.0, 12.0]\n[solver]\nmethods = [\"newton\"]\n",
    );
    let out = Temp::dir("sweep-out");
    let csv = out.0.join("prestress.csv");
    let o = Command::new("bash")
        .arg(manifest_path("scripts/sweep.sh"))
        .args([case.arg(), csv.to_str().unwrap(), "1000", "2000"])
        .env("TENSOLVE", env!("CARGO_BIN_EXE_tensolve"))
        .output()
        .expect("run bash");
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("prestress,solver,alpha,slack_fraction,converged")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "{text}");
    let fraction = |p: &str, alpha: &str| -> f64 {
        let row = rows
            .iter()
            .find(|r| r[0] == p && r[2] == alpha)
            .unwrap_or_else(|| panic!("no row {p} {alpha}: {text}"));
        assert_eq!(row[4], "true");
        row[3].parse().unwrap()
    };
    // The problem is homogeneous in (prestress, load): doubling both keeps the slack set.
    assert!(fraction("1000", "12") > 0.0, "{text}");
    assert_eq!(fraction("1000", "6"), fraction("2000", "12"), "{text}");
    // More prestress, fewer slack cables at the same load.
    assert!(fraction("2000", "12") < fraction("1000", "12"), "{text}");
}

#[test]
fn one_slack_classification_for_every_solver() {
    // The braced grid at α = 0: the unprestressed diagonals carry τ = 0 with a closed gap
    // (taut at rest), so every solver reports 0 slack cables; at α = 0.05 they all agree.
    let case = manifest_path("cases/paper-braced.toml");
    let out = Temp::dir("slack-classification");
    let o = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.arg(),
        "--quiet",
        "--set",
        "load.alpha=[0.0, 0.05]",
        "--set",
        "solver.methods=[\"newton\", \"pcg-lcp\", \"mono-latin\", \"micro-macro\"]",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).unwrap();
    let mut lines = summary.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 8, "{summary}");
    for alpha in ["0", "0.05"] {
        let counts: Vec<&str> = rows
            .iter()
            .filter(|r| r[col("alpha")] == alpha)
            .map(|r| r[col("slack_cables")])
            .collect();
        // Broken down by kind, the four solvers agree too, and the kinds add up.
        for kind in ["lower", "upper", "bracing", "diagonal", "cable"] {
            let by_kind: Vec<&str> = rows
                .iter()
                .filter(|r| r[col("alpha")] == alpha)
                .map(|r| r[col(&format!("slack_{kind}"))])
                .collect();
            assert!(
                by_kind.iter().all(|c| *c == by_kind[0]),
                "alpha {alpha} {kind}: {by_kind:?}"
            );
        }
        for r in rows.iter().filter(|r| r[col("alpha")] == alpha) {
            let sum: usize = ["lower", "upper", "bracing", "diagonal", "cable"]
                .iter()
                .map(|k| r[col(&format!("slack_{k}"))].parse::<usize>().unwrap())
                .sum();
            assert_eq!(sum.to_string(), r[col("slack_cables")], "{summary}");
        }
        assert_eq!(counts.len(), 4, "{summary}");
        assert!(
            counts.iter().all(|c| *c == counts[0]),
            "alpha {alpha}: {counts:?}"
        );
        if alpha == "0" {
            assert_eq!(counts[0], "0", "{summary}");
        } else {
            assert_ne!(counts[0], "0", "{summary}");
        }
    }
}

#[test]
fn large_displacements_are_flagged() {
    // A 24 x 10 grid clamped on its short edges sags 3.47 m at α = 1: members turn by about
    // 49 % of their length, beyond the small-perturbation model (a per-row warning). Already at
    // α = 0.05 the geometric term the linear model leaves out changes its answer by ≈ 10 %
    // (the large-displacement answer is 65.8 mm against 56.7 mm): both rows are flagged, and one
    // warning recommends `model.geometry = "large"`. The paper's case is within 1 % at
    // α = 0.05 only (0.995 %; large 6.84 mm against 6.77 mm), beyond from α = 0.25 (6.0 %).
    let flagged = Temp::file(
        "large-displacement",
        "[grid]\nmodules = [24, 10]\n[supports]\nclamp = \"lower-x-edges\"\n[load]\n\
         alpha = [0.05, 1.0]\n[solver]\nmethods = [\"newton\"]\n[model]\ngeometry = \"linear\"\n",
    );
    let out = Temp::dir("large-displacement-out");
    let o = tensolve(&["run", flagged.arg(), "--out", out.arg()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let warning = stderr(&o);
    assert!(
        warning.contains("warning: newton at alpha = 1") && !warning.contains("alpha = 0.05:"),
        "{warning}"
    );
    assert!(
        warning.contains("warning: 2 row(s) leave out a geometric term")
            && warning.contains("model.geometry = \"large\""),
        "{warning}"
    );
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).unwrap();
    let header: Vec<&str> = summary.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ok, term) = (column("small_displacement_ok"), column("geometric_term"));
    let rows: Vec<Vec<&str>> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let flags: Vec<&str> = rows.iter().map(|r| r[ok]).collect();
    assert_eq!(flags, ["false", "false"], "{summary}");
    let terms: Vec<f64> = rows.iter().map(|r| r[term].parse().unwrap()).collect();
    assert!(terms[0] > 0.05 && terms[1] > 0.5, "{terms:?}");
    let golden = std::fs::read_to_string(manifest_path("tests/golden/paper_summary.csv")).unwrap();
    let header: Vec<&str> = golden.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for line in golden.lines().skip(1) {
        let row: Vec<&str> = line.split(',').collect();
        let within = row[column("alpha")] == "0.05";
        assert_eq!(
            row[column("small_displacement_ok")],
            within.to_string(),
            "{line}"
        );
        let term: f64 = row[column("geometric_term")].parse().unwrap();
        assert_eq!(term <= 0.01, within, "{line}");
    }
}

/// `summary.csv` of `dir` as rows of named columns.
fn summary_rows(dir: &std::path::Path) -> Vec<std::collections::HashMap<String, String>> {
    let summary = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    let mut lines = summary.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect()
        })
        .collect()
}

#[test]
fn the_geometric_term_is_computed_only_when_asked() {
    // The 24 x 10 grid of `large_displacements_are_flagged` at α = 0.05, where the term is
    // ≈ 10 % (flagged) while the members turn by less than 10 % of their length. Without
    // `output.geometric_term` the column is empty, the warning is not given, and
    // small_displacement_ok says what the rotation alone says; micro-macro alone (reference
    // none), whose run then releases K's factor after the mechanism check, solves alike.
    let text = |methods: &str, term: bool| {
        format!(
            "[model]\ngeometry = \"linear\"\n\
             [grid]\nmodules = [24, 10]\n[supports]\nclamp = \"lower-x-edges\"\n[load]\n\
             alpha = [0.05]\n[solver]\nmethods = {methods}\nreference = \"none\"\n\
             [output]\ngeometric_term = {term}\n"
        )
    };
    let mut rows = Vec::new();
    for (methods, term) in [
        ("[\"newton\", \"micro-macro\"]", true),
        ("[\"newton\", \"micro-macro\"]", false),
        ("[\"micro-macro\"]", false),
    ] {
        let case = Temp::file("geometric-term", &text(methods, term));
        let out = Temp::dir("geometric-term-out");
        let o = tensolve(&["run", case.arg(), "--out", out.arg()]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{err}");
        assert_eq!(err.contains("leave out a geometric term"), term, "{err}");
        rows.push(summary_rows(&out.0));
    }
    let (with, without, alone) = (&rows[0], &rows[1], &rows[2]);
    for row in with {
        let term: f64 = row["geometric_term"].parse().unwrap();
        assert!(term > 0.05, "{row:?}");
        assert_eq!(row["small_displacement_ok"], "false", "{row:?}");
    }
    for row in without.iter().chain(alone) {
        assert_eq!(row["geometric_term"], "", "{row:?}");
        assert_eq!(row["small_displacement_ok"], "true", "{row:?}");
    }
    // The same solves: micro-macro's row alone is its row beside newton.
    let same = [
        "iterations",
        "slack_cables",
        "max_deflection",
        "equilibrium_residual",
    ];
    for key in same {
        assert_eq!(with[1][key], alone[0][key], "{key}");
        assert_eq!(without[1][key], alone[0][key], "{key}");
    }
}

#[test]
fn the_readme_command_reproduces_the_papers_section_5() {
    // `cargo run --release -- run cases/paper.toml`, the case file as it is.
    let case = manifest_path("cases/paper.toml");
    let out = Temp::dir("paper-main");
    let o = tensolve(&["run", case.to_str().unwrap(), "--out", out.arg()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).unwrap();
    let mut lines = summary.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let solvers = ["pcg-lcp", "mono-latin", "micro-macro", "newton"];
    let alphas = ["0", "0.05", "0.25", "0.5", "0.75", "1"];
    assert_eq!(rows.len(), solvers.len() * alphas.len(), "{summary}");
    for r in &rows {
        assert_eq!(r[col("converged")], "true", "{summary}");
        // The paper's §5: 36 slack cables at α = 0.5 and 408 at α = 1, whatever the solver.
        let expected = match r[col("alpha")] {
            "0.5" => Some("36"),
            "1" => Some("408"),
            _ => None,
        };
        if let Some(expected) = expected {
            assert_eq!(r[col("slack_cables")], expected, "{summary}");
        }
    }
    // The histories of the paper's three iterative solvers (newton, the exact reference,
    // writes none), each naming its stopping measure.
    for solver in solvers {
        for alpha in alphas {
            let path = out.0.join(format!("history/{solver}_alpha{alpha}.csv"));
            if solver == "newton" {
                assert!(!path.exists(), "{}", path.display());
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let measure = if solver == "pcg-lcp" {
                "complementarity_residual"
            } else {
                "indicator_eta"
            };
            assert!(
                text.lines().next().unwrap().contains(measure),
                "{}",
                path.display()
            );
        }
    }
    // Figures 6 to 11.
    for figure in [
        "slack_fraction",
        "tensions",
        "deformed_alpha1",
        "error_mono-latin",
        "error_micro-macro",
        "eta_mono-latin",
        "eta_micro-macro",
        "error_all",
    ] {
        let path = out.0.join(format!("plots/{figure}.svg"));
        assert!(path.is_file(), "{}", path.display());
    }
    // Progress without a terminal: one line per solve, the LATIN ones with their final e.
    let row_lines: Vec<&str> = err.lines().filter(|l| l.contains(" alpha = ")).collect();
    assert_eq!(row_lines.len(), rows.len(), "{err}");
    for line in row_lines
        .iter()
        .filter(|l| l.contains("latin") || l.contains("macro"))
    {
        assert!(line.contains(", e = "), "{line}");
    }
}

/// The words of a documented shell command: split at spaces, single quotes grouping.
fn shell_words(command: &str) -> Vec<String> {
    let mut words = Vec::new();
    let (mut word, mut quoted, mut started) = (String::new(), false, false);
    for c in command.chars() {
        match c {
            '\'' => (quoted, started) = (!quoted, true),
            ' ' if !quoted => {
                if started {
                    words.push(std::mem::take(&mut word));
                }
                started = false;
            }
            _ => {
                word.push(c);
                started = true;
            }
        }
    }
    if started {
        words.push(word);
    }
    words
}

/// D9 (issue 42): the guide's command for the paper grid with `large` runs as written (it
/// failed: the case lists pcg-lcp, which does not take `large`), and gives the figures the
/// guide quotes beside it (289.0 mm and 500 slack cables at α = 1, 86.1 mm and 88 at 0.5).
#[test]
fn d9_the_guides_large_paper_grid_command_runs_and_gives_its_figures() {
    let guide = std::fs::read_to_string(manifest_path("docs/guide.md")).unwrap();
    let lead = "**The paper's grid with `large`**";
    let after = &guide[guide.find(lead).expect("the guide's paragraph") + lead.len()..];
    let command = after
        .split('`')
        .nth(1)
        .expect("the command in backquotes")
        .replace('\n', " ");
    let words = shell_words(&command);
    assert_eq!(words[..2], ["tensolve", "run"], "{command}");
    let case = manifest_path(&words[2]);
    let out = Temp::dir("guide-large");
    let mut args: Vec<&str> = vec!["run", case.to_str().unwrap()];
    args.extend(words[3..].iter().map(String::as_str));
    args.extend(["--out", out.arg(), "--quiet"]);
    let o = tensolve(&args);
    assert_eq!(o.status.code(), Some(0), "{command}: {}", stderr(&o));
    let summary = std::fs::read_to_string(out.0.join("summary.csv")).unwrap();
    let header: Vec<&str> = summary.lines().next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let rows: Vec<Vec<&str>> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 5, "{summary}");
    for (alpha, deflection_mm, slack) in [("0.5", 86.1, Some("88")), ("1", 289.0, Some("500"))]
        .into_iter()
        .chain([("0.05", 6.84, None), ("0.25", 36.7, None)])
    {
        let row = rows
            .iter()
            .find(|r| r[at("alpha")] == alpha)
            .unwrap_or_else(|| panic!("α = {alpha}: {summary}"));
        assert_eq!(row[at("status")], "converged", "α = {alpha}");
        let mm = 1e3 * row[at("max_deflection")].parse::<f64>().unwrap();
        // The guide's figures, to the digits it gives.
        let digits = if deflection_mm < 10.0 { 0.005 } else { 0.05 };
        assert!(
            (mm - deflection_mm).abs() <= digits,
            "α = {alpha}: {mm} mm, the guide says {deflection_mm}"
        );
        if let Some(slack) = slack {
            assert_eq!(row[at("slack_cables")], slack, "α = {alpha}");
        }
    }
}
