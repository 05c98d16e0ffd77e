//! `summary.csv`'s `geometric_term` (one Newton step of the large model from a `linear` or
//! `prestress` answer) against the difference measured by solving with `large`: first-order
//! exact where it is small, and above the tolerance wherever the measured difference is
//! (issue 44: the estimate must not say "close" of an answer that is not).

mod common;

use common::{csv_rows, difference_of_runs, manifest_path, stderr, tensolve, Temp};
use std::collections::HashMap;
use std::path::Path;

fn number(row: &HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?}", row[key]))
}

/// Solve `case` with `model.geometry = geometry` at `alphas` (newton), writing displacements
/// and forces.
fn solve(case: &Path, geometry: &str, alphas: &str, out: &Temp) {
    let o = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--solver",
        "newton",
        "--set",
        &format!("model.geometry=\"{geometry}\""),
        "--set",
        &format!("load.alpha={alphas}"),
        "--set",
        "output.displacements=true",
        "--set",
        "output.forces=true",
        "--out",
        out.arg(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// Per α of `case`, (the geometric term of `geometry`, the measured difference to `large`).
fn estimates(case: &str, geometry: &str, alphas: &str) -> Vec<(f64, f64)> {
    let case = manifest_path(case);
    let (model, large) = (Temp::dir("geometric-model"), Temp::dir("geometric-large"));
    solve(&case, geometry, alphas, &model);
    solve(&case, "large", alphas, &large);
    csv_rows(&model.0.join("summary.csv"))
        .iter()
        .map(|row| {
            let estimate = number(row, "geometric_term");
            (
                estimate,
                difference_of_runs(&model.0, &large.0, "newton", &row["alpha"]),
            )
        })
        .collect()
}

#[test]
fn the_geometric_term_is_the_measured_difference_where_small_and_flags_it_where_large() {
    let cases = [
        ("cases/simplex.toml", "prestress", "[0.25, 1.0]"),
        ("cases/prism4.toml", "prestress", "[0.25, 1.0]"),
        ("cases/tower.toml", "prestress", "[0.25, 0.5, 1.0]"),
        ("cases/saddle-net.toml", "prestress", "[1.0]"),
        ("cases/paper.toml", "linear", "[0.01, 0.05, 0.25, 1.0]"),
        // A settlement of 5 mm is no part of the step (the estimate read 91 % at α = 0.05
        // for a measured 0.57 % when it was).
        ("cases/skew-grid.toml", "linear", "[0.05, 0.5]"),
    ];
    for (case, geometry, alphas) in cases {
        for (estimate, measured) in estimates(case, geometry, alphas) {
            let what = format!("{case} {geometry}: estimate {estimate}, measured {measured}");
            // First-order exact below 4 %: within 6 % of the measured difference.
            if measured < 0.04 {
                assert!((estimate - measured).abs() <= 0.06 * measured, "{what}");
            }
            // Never "within 1 %" of an answer further than 1 % from `large`.
            assert!(measured <= 0.01 || estimate > 0.01, "{what}");
        }
    }
}

#[test]
fn a_pinned_prestress_on_the_prism_warns_with_the_measured_difference_to_large() {
    let case = manifest_path("cases/prism4.toml");
    let (pinned, large) = (Temp::dir("prism-pinned"), Temp::dir("prism-large"));
    let run = |geometry: &str, tolerance: &str, out: &Temp| {
        tensolve(&[
            "run",
            case.to_str().unwrap(),
            "--set",
            &format!("model.geometry=\"{geometry}\""),
            "--set",
            &format!("model.tolerance={tolerance}"),
            "--out",
            out.arg(),
        ])
    };
    let o = run("prestress", "0.01", &pinned);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(run("large", "0.01", &large).status.code(), Some(0));
    let at_one = |dir: &Temp| {
        csv_rows(&dir.0.join("summary.csv"))
            .into_iter()
            .find(|r| r["alpha"] == "1")
            .unwrap()
    };
    let (p, l) = (at_one(&pinned), at_one(&large));
    let err = stderr(&o);
    // All three rows are off by more than 1 %; the worst is α = 1, measured there.
    let expected = format!(
        "3 row(s) leave out a geometric term (the members' rotation under their tension) that \
         changes the answer by more than model.tolerance = 1 % (measured up to {:.1} %: \
         newton, alpha 1; measured there, `large` gives a largest deflection of {:.4e} m \
         against {:.4e} m",
        100.0 * number(&p, "geometric_term"),
        number(&l, "max_deflection"),
        number(&p, "max_deflection"),
    );
    assert!(err.contains(&expected), "{err}\nexpected: {expected}");
    let tension = format!(
        "a largest cable tension of {:.4e} N against {:.4e} N",
        number(&l, "max_tension"),
        number(&p, "max_tension")
    );
    assert!(err.contains(&tension), "{err}");
    // A tolerance of 50 % flags no row: no warning, and the rows are within it.
    let loose = Temp::dir("prism-loose");
    let o = run("prestress", "0.5", &loose);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("leave out a geometric term"),
        "{}",
        stderr(&o)
    );
    let flags: Vec<String> = csv_rows(&loose.0.join("summary.csv"))
        .iter()
        .map(|r| r["small_displacement_ok"].clone())
        .collect();
    assert_eq!(flags, ["true", "true", "true"]);
}

#[test]
fn a_model_tolerance_outside_zero_to_one_exits_2_naming_the_key() {
    let case = manifest_path("cases/prism4.toml");
    for bad in ["0", "1", "-0.01", "1.5", "nan"] {
        let out = Temp::dir("prism-bad-tolerance");
        let o = tensolve(&[
            "run",
            case.to_str().unwrap(),
            "--set",
            &format!("model.tolerance={bad}"),
            "--out",
            out.arg(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("`model.tolerance`") && err.contains("between 0 and 1"),
            "{err}"
        );
        assert!(!out.0.join("summary.csv").exists());
    }
}

#[test]
fn an_unloaded_answer_whose_motion_is_round_off_is_not_off() {
    // micro-macro's answer at α = 0 on the paper's grid moves nodes by about 4e-17 m: no
    // deflection for a step to be relative to (it read 1010 % when it was).
    let out = Temp::dir("paper-unloaded");
    let case = manifest_path("cases/paper.toml");
    let o = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--set",
        "load.alpha=[0.0]",
        "--out",
        out.arg(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("leave out a geometric term"),
        "{}",
        stderr(&o)
    );
    // Empty where the answer does not move at all (newton, pcg-lcp).
    let rows = csv_rows(&out.0.join("summary.csv"));
    let moved: Vec<_> = rows
        .iter()
        .filter(|r| !r["geometric_term"].is_empty())
        .collect();
    assert!(!moved.is_empty(), "{rows:?}");
    for row in moved {
        assert!(number(row, "geometric_term") < 1e-6, "{row:?}");
    }
}
