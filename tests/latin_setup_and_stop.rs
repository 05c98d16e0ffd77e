//! The LATIN solvers' set-up refusals and stop (issue 42): a macro degree the partition cannot
//! take named with the largest it can (T4); one-module-wide strips never `converged` off the
//! equilibrium, and their refusal explained (T5); `solver.forcing` refused where it does
//! nothing (T12); failure messages naming r(U) (M7); no advice of a setting in force (M10).

mod common;

use common::{code, stderr, tensolve, Temp};
use std::collections::HashMap;
use std::path::Path;

/// The summary's rows as column → value.
fn summary_rows(dir: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("summary.csv")).expect("summary.csv");
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

/// `tensolve check case --set …` (sets up every solver of the case).
fn check(case: &Temp, sets: &[&str]) -> std::process::Output {
    let mut args = vec!["check", case.arg()];
    for s in sets {
        args.extend(["--set", s]);
    }
    tensolve(&args)
}

/// The paper's 16 × 16 grid with micro-macro alone.
const PAPER_MICRO_MACRO: &str =
    "[grid]\nmodules = [16, 16]\n[load]\nalpha = [1.0]\n[solver]\nmethods = [\"micro-macro\"]\n";

/// A valid `solver.macro_degree` (1 to 16) the partition cannot take was refused as "the macro
/// problem is singular", advising `weak_interfaces = "macro"`, the default (T4, M10).
#[test]
fn a_macro_degree_the_partition_cannot_take_is_refused_with_the_largest_it_can() {
    let case = Temp::file("t4", PAPER_MICRO_MACRO);
    for (subdomains, degree, largest) in [("[8, 8]", 2, 1), ("[4, 4]", 6, 5)] {
        let o = check(
            &case,
            &[
                &format!("solver.subdomains={subdomains}"),
                &format!("solver.macro_degree={degree}"),
            ],
        );
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{err}");
        assert!(err.contains("`solver.macro_degree` = "), "{err}");
        assert!(
            err.contains(&format!(
                "the largest degree this partition takes is {largest}"
            )),
            "{err}"
        );
        assert!(!err.contains("weak_interfaces"), "{err}");
        // The degree named sets up.
        let o = check(
            &case,
            &[
                &format!("solver.subdomains={subdomains}"),
                &format!("solver.macro_degree={largest}"),
            ],
        );
        assert_eq!(code(&o), 0, "{}", stderr(&o));
    }
}

/// A 2 × `long` grid clamped on its x-edges, split into two strips one module wide.
fn strips(long: usize, stop_on: &str) -> Temp {
    Temp::file(
        "t5",
        &format!(
            "[grid]\nmodules = [2, {long}]\n[supports]\nclamp = \"lower-x-edges\"\n\
             [load]\nalpha = [0.5]\n[solver]\nmethods = [\"micro-macro\"]\n\
             subdomains = [2, 1]\nstop_on = \"{stop_on}\"\nmax_iterations = 300\n"
        ),
    )
}

/// On one-module-wide strips η falls to 1e-11 with r(U) at 1e-2: with `stop_on = "eta"` the
/// row said `converged`, 44 % off (T5); now it stalls, and the message names r(U) (M7).
#[test]
fn strips_one_module_wide_are_never_converged_off_the_equilibrium() {
    for stop_on in ["eta", "both"] {
        let case = strips(10, stop_on);
        let out = Temp::dir("t5-out");
        let o = tensolve(&["run", case.arg(), "--out", out.arg(), "--quiet"]);
        let err = stderr(&o);
        assert_eq!(code(&o), 1, "{stop_on}: {err}");
        let rows = summary_rows(&out.0);
        assert_eq!(rows[0]["converged"], "false", "{stop_on}");
        let r: f64 = rows[0]["equilibrium_residual"].parse().unwrap();
        assert!(r > 1e-4, "{stop_on}: r(U) = {r:e}");
        assert!(err.contains("r(U) = "), "{stop_on}: {err}");
        assert!(err.contains("not the equilibrium"), "{stop_on}: {err}");
    }
    // η met: it stops there, stalled, rather than run to its cap.
    let out = Temp::dir("t5-eta");
    let o = tensolve(&[
        "run",
        strips(10, "eta").arg(),
        "--out",
        out.arg(),
        "--quiet",
    ]);
    assert_eq!(code(&o), 1);
    assert_eq!(summary_rows(&out.0)[0]["status"], "stalled");
}

/// From 12 modules long the strips' macro problem is singular: the refusal says why, and
/// advises no setting already in force (T5, M10).
#[test]
fn a_singular_partition_of_strips_says_they_are_one_module_wide() {
    let o = check(&strips(12, "both"), &[]);
    let err = stderr(&o);
    assert_eq!(code(&o), 2, "{err}");
    assert!(err.contains("one module wide"), "{err}");
    assert!(!err.contains("weak_interfaces = \"macro\""), "{err}");
}

/// `solver.forcing` is the forcing term of the inexact Newton status steps; with another
/// search direction it was accepted and did nothing (T12).
#[test]
fn forcing_is_refused_with_the_search_directions_that_have_none() {
    let case = Temp::file("t12", PAPER_MICRO_MACRO);
    for policy in ["stiffness", "status"] {
        let o = check(
            &case,
            &[
                &format!("solver.search_direction=\"{policy}\""),
                "solver.forcing=0.3",
            ],
        );
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{policy}: {err}");
        assert!(err.contains("solver.forcing"), "{err}");
        assert!(err.contains(policy), "{err}");
    }
    let o = check(
        &case,
        &["solver.search_direction=\"newton\"", "solver.forcing=0.3"],
    );
    assert_eq!(code(&o), 0, "{}", stderr(&o));
}
