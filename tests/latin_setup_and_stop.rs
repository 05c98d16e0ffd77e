//! The LATIN solvers' set-up refusals and stop (issue 42): a macro degree the partition cannot
//! take named with the largest it can (T4); one-module-wide strips solved to the equilibrium
//! (T5); `solver.forcing` refused where it does nothing (T12); failure messages naming r(U)
//! (M7); no advice of a setting in force (M10).

mod common;

use common::{code, stderr, summary_rows, tensolve, Temp};

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
    "[grid]\nmodules = [16, 16]\n[load]\nalpha = [1.0]\n[model]\ngeometry = \"linear\"\n\
     [solver]\nmethods = [\"micro-macro\"]\n";

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

/// The default macro degree is a guess from the substructures' size: where the partition takes
/// less (a braced 64 × 8 grid on its default 4 × 4 partition: degree 2 by size, 1 taken), the
/// default is the largest it takes, with its d_m, and the run converges to newton's slack set.
#[test]
fn the_default_macro_degree_falls_back_to_what_the_partition_takes() {
    let case = Temp::file(
        "default-degree",
        "[grid]\nmodules = [64, 8]\nmodule = \"braced\"\n[supports]\n\
         clamp = \"lower-all-edges\"\n[load]\nalpha = [0.5]\n[solver]\n\
         methods = [\"micro-macro\", \"newton\"]\n[output]\ngeometric_term = false\n",
    );
    let o = check(&case, &["solver.macro_degree=2"]);
    assert_eq!(
        code(&o),
        2,
        "degree 2 is refused when asked: {}",
        stderr(&o)
    );
    let o = check(&case, &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains("(degree 1 on strong interfaces: default"),
        "{report}"
    );
    let dir = Temp::dir("default-degree-out");
    let o = tensolve(&["run", case.arg(), "--out", dir.arg(), "--quiet"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let rows = summary_rows(&dir.0);
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["converged"] == "true"), "{rows:?}");
    assert_eq!(rows[0]["slack_cables"], rows[1]["slack_cables"]);
}

/// A 2 × `long` grid clamped on its x-edges, split into two strips one module wide, solved by
/// newton and micro-macro.
fn strips(long: usize, stop_on: &str) -> Temp {
    Temp::file(
        "t5",
        &format!(
            "[grid]\nmodules = [2, {long}]\n[supports]\nclamp = \"lower-x-edges\"\n\
             [load]\nalpha = [0.5]\n[solver]\nmethods = [\"newton\", \"micro-macro\"]\n\
             subdomains = [2, 1]\nstop_on = \"{stop_on}\"\nmax_iterations = 300\n"
        ),
    )
}

/// On one-module-wide strips η fell to 1e-11 with r(U) at 1e-2: one strip's kernel held a
/// second, spurious column (a null eigenvector repeating its rigid motion to round-off). With
/// `stop_on = "eta"` the row said `converged`, 44 % off newton's; from 12 modules long the
/// macro problem was refused as singular (T5).
#[test]
fn strips_one_module_wide_solve_to_newtons_answer() {
    for (long, stop_on) in [(10, "eta"), (10, "both"), (12, "both"), (20, "both")] {
        let case = strips(long, stop_on);
        let out = Temp::dir("t5-out");
        let o = tensolve(&["run", case.arg(), "--out", out.arg(), "--quiet"]);
        let at = format!("2 x {long}, stop_on {stop_on}");
        assert_eq!(code(&o), 0, "{at}: {}", stderr(&o));
        let rows = summary_rows(&out.0);
        let deflection = |solver: &str| -> f64 {
            let row = rows.iter().find(|r| r["solver"] == solver).unwrap();
            assert_eq!(row["status"], "converged", "{at}: {solver}");
            row["max_deflection"].parse().unwrap()
        };
        let (newton, latin) = (deflection("newton"), deflection("micro-macro"));
        let off = (latin - newton).abs() / newton;
        assert!(
            off < 1e-4,
            "{at}: micro-macro {latin:e} against newton {newton:e}"
        );
    }
}

/// A LATIN row that ends on its iteration cap names r(U) beside η: either may be the
/// criterion that failed (M7; it named η alone).
#[test]
fn a_latin_failure_names_r_u_beside_eta() {
    let case = Temp::file("m7", PAPER_MICRO_MACRO);
    let out = Temp::dir("m7-out");
    let o = tensolve(&[
        "run",
        case.arg(),
        "--out",
        out.arg(),
        "--quiet",
        "--set",
        "solver.max_iterations=2",
        "--set",
        "solver.reference=\"none\"",
    ]);
    let err = stderr(&o);
    assert_eq!(code(&o), 1, "{err}");
    assert!(err.contains("(MaxIterations), eta = "), "{err}");
    assert!(err.contains(", r(U) = "), "{err}");
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
