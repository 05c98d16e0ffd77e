//! `model.geometry = "auto"`, the default (issue 44): each row solved with the cheapest model
//! within `model.tolerance` of the large-displacement answer, the summary's `model` column
//! saying which, the solve line why, `check` what it starts with. Every `auto` row is measured
//! here against a run pinned to `large`.

mod common;

use common::{csv_rows, difference_of_runs, manifest_path, stderr, tensolve, Temp};
use std::collections::HashMap;

type Row = HashMap<String, String>;

/// `tensolve run` of `case` (its path under the repository) into `out`, one `--set` per
/// entry of `sets`.
fn run_with(case: &str, sets: &[&str], out: &Temp) -> std::process::Output {
    let case = manifest_path(case);
    let mut args = vec!["run", case.to_str().unwrap(), "--out", out.arg()];
    for set in sets {
        args.extend(["--set", set]);
    }
    tensolve(&args)
}

/// `case` by newton at `alphas`, with `sets`, its displacements and forces written: the rows
/// and the run's stderr.
fn run(case: &str, alphas: &str, sets: &[&str], out: &Temp) -> (Vec<Row>, String) {
    let alpha = format!("load.alpha={alphas}");
    let mut all = vec![
        "solver.methods=[\"newton\"]",
        alpha.as_str(),
        "output.displacements=true",
        "output.forces=true",
        "output.plots=false",
    ];
    all.extend(sets);
    let o = run_with(case, &all, out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    (csv_rows(&out.0.join("summary.csv")), stderr(&o))
}

/// The `model` column per α.
fn models(rows: &[Row]) -> Vec<(String, String)> {
    rows.iter()
        .map(|r| (r["alpha"].clone(), r["model"].clone()))
        .collect()
}

/// `case` under `auto` (with `sets`) and pinned to `large`: every `auto` row within
/// `tolerance` of `large`'s answer; the models of the rows.
fn auto_within_tolerance_of_large(
    case: &str,
    alphas: &str,
    sets: &[&str],
    tolerance: f64,
) -> Vec<(String, String)> {
    let (auto, large) = (Temp::dir("auto"), Temp::dir("auto-large"));
    let tolerance_set = format!("model.tolerance={tolerance}");
    let mut auto_sets = vec!["model.geometry=\"auto\"", tolerance_set.as_str()];
    auto_sets.extend(sets);
    let (rows, _) = run(case, alphas, &auto_sets, &auto);
    let mut large_sets = vec!["model.geometry=\"large\""];
    large_sets.extend(sets);
    run(case, alphas, &large_sets, &large);
    for row in &rows {
        let alpha = &row["alpha"];
        assert_eq!(row["status"], "converged", "{case} α {alpha}");
        if alpha == "0" {
            continue;
        }
        let difference = difference_of_runs(&auto.0, &large.0, "newton", alpha);
        assert!(
            difference <= tolerance,
            "{case} {sets:?} α {alpha}: the {} row is {difference:e} from large",
            row["model"]
        );
    }
    models(&rows)
}

fn pairs(expected: &[(&str, &str)]) -> Vec<(String, String)> {
    expected
        .iter()
        .map(|(a, m)| (a.to_string(), m.to_string()))
        .collect()
}

#[test]
fn the_paper_grid_unpinned_is_linear_at_small_alpha_and_large_from_a_quarter() {
    // Newton's linear answer is 0.10 % from large at α = 0.01, 0.997 % at 0.05, 2.3 % at 0.1.
    let models = auto_within_tolerance_of_large(
        "cases/paper.toml",
        "[0.0, 0.01, 0.05, 0.1, 0.25, 1.0]",
        &[],
        0.01,
    );
    let expected = [
        ("0", "linear"),
        ("0.01", "linear"),
        ("0.05", "linear"),
        ("0.1", "large"),
        ("0.25", "large"),
        ("1", "large"),
    ];
    assert_eq!(models, pairs(&expected));
    // A looser tolerance moves later: linear at 0.1 (2.3 %), large at 0.25 (6.4 %).
    let models =
        auto_within_tolerance_of_large("cases/paper.toml", "[0.05, 0.1, 0.25, 0.5]", &[], 0.05);
    let expected = [
        ("0.05", "linear"),
        ("0.1", "linear"),
        ("0.25", "large"),
        ("0.5", "large"),
    ];
    assert_eq!(models, pairs(&expected));
}

#[test]
fn every_auto_row_is_within_the_tolerance_of_large_on_structures_of_several_kinds() {
    // A braced grid, the paper's grid clamped on all four lower edges, the skew grid (a
    // general structure with a 5 mm settlement), a guyed mast (linear 0.16 % from large at
    // α = 1), a designed tower that its prestress stiffens (linear is 4× off from the smallest
    // load), and the prestress-stable tensegrities.
    let cases: [(&str, &str, &[&str]); 7] = [
        ("cases/paper-braced.toml", "[0.05, 0.1, 0.25, 1.0]", &[]),
        (
            "cases/paper.toml",
            "[0.05, 0.1, 0.25, 0.5, 1.0]",
            &["supports.clamp=\"lower-all-edges\"", "grid.modules=[8, 8]"],
        ),
        ("cases/skew-grid.toml", "[0.05, 0.5, 1.0, 2.0]", &[]),
        ("tests/data/my-mast.toml", "[0.5, 1.0]", &[]),
        ("cases/tower2-design.toml", "[0.25, 1.0]", &[]),
        ("cases/prism4.toml", "[0.25, 1.0]", &[]),
        ("cases/tower.toml", "[0.25, 1.0]", &[]),
    ];
    let mut seen = Vec::new();
    for (case, alphas, sets) in cases {
        for tolerance in [0.01, 0.05] {
            let models = auto_within_tolerance_of_large(case, alphas, sets, tolerance);
            seen.extend(models.into_iter().map(|(_, m)| m));
        }
    }
    // Both models are chosen somewhere: the test measures linear rows too.
    assert!(seen.iter().any(|m| m == "linear") && seen.iter().any(|m| m == "large"));
}

#[test]
fn the_shipped_tensegrities_run_with_no_model_key_and_say_why_large() {
    for case in [
        "cases/prism4.toml",
        "cases/simplex.toml",
        "cases/tower.toml",
        "cases/saddle-net.toml",
        "cases/tower2-design.toml",
    ] {
        let text = std::fs::read_to_string(manifest_path(case)).unwrap();
        let table: toml::Table = text.parse().unwrap();
        assert!(!table.contains_key("model"), "{case} has a [model] table");
        let out = Temp::dir("auto-shipped");
        let o = tensolve(&[
            "run",
            manifest_path(case).to_str().unwrap(),
            "--out",
            out.arg(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{case}: {}", stderr(&o));
        let rows = csv_rows(&out.0.join("summary.csv"));
        assert!(!rows.is_empty());
        for row in &rows {
            assert_eq!(row["model"], "large", "{case} α {}", row["alpha"]);
            assert_eq!(row["status"], "converged", "{case} α {}", row["alpha"]);
        }
        // The solve line says why: a mechanism its prestress stiffens (the four
        // tensegrities), or linear measured off by more than the tolerance (the designed
        // tower, whose K is regular).
        let err = stderr(&o);
        let why = match case {
            "cases/tower2-design.toml" => "large (auto: large's Newton steps move linear's answer",
            _ => "large (auto: a mechanism its prestress stiffens)",
        };
        assert!(err.contains(why), "{case}: {err}");
    }
}

#[test]
fn the_solve_line_and_check_say_which_model_and_why() {
    let out = Temp::dir("auto-lines");
    let newton = "solver.methods=[\"newton\"]";
    let o = run_with(
        "cases/paper.toml",
        &[
            newton,
            "model.geometry=\"auto\"",
            "load.alpha=[0.01, 0.25, 0.5]",
            "output.plots=false",
        ],
        &out,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    for line in [
        "linear (auto: 0.103 % from large, within model.tolerance 1 %)",
        // Past 4 × the tolerance after two Newton steps, they stop: far.
        "large (auto: large's Newton steps move linear's answer by 6.395 % and on, beyond \
         model.tolerance 1 %)",
        "large (auto: large since alpha = 0.25, linear 6.395 % and more from large there)",
    ] {
        assert!(err.contains(line), "{line}\n{err}");
    }
    // `auto` measured its own rows: no warning that a model is off.
    assert!(!err.contains("leave out a geometric term"), "{err}");
    // A pinned model says so.
    let pinned = Temp::dir("auto-pinned");
    let o = run_with(
        "cases/paper.toml",
        &[newton, "load.alpha=[0.01]", "output.plots=false"],
        &pinned,
    );
    assert!(stderr(&o).contains("linear (pinned)"), "{}", stderr(&o));
    // `check` says what `auto` starts with.
    let check = |case: &str| {
        let o = tensolve(&[
            "check",
            manifest_path(case).to_str().unwrap(),
            "--set",
            "model.geometry=\"auto\"",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let grid = check("cases/paper.toml");
    assert!(
        grid.contains(
            "geometry = auto, starts linear (equilibrium on the initial geometry): the structure \
             is stiff with every cable taut"
        ),
        "{grid}"
    );
    assert!(grid.contains("model.tolerance = 1 %"), "{grid}");
    let prism = check("cases/prism4.toml");
    assert!(
        prism.contains("geometry = auto, starts large (")
            && prism.contains("a mechanism its prestress stiffens"),
        "{prism}"
    );
}

#[test]
fn a_bad_model_geometry_exits_2_naming_the_key_and_the_choices() {
    let out = Temp::dir("auto-bad");
    let o = run_with("cases/prism4.toml", &["model.geometry=\"automatic\""], &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("model.geometry") && err.contains("`auto`") && err.contains("`large`"),
        "{err}"
    );
}
