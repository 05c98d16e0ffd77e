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
