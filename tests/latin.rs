//! The LATIN solvers (docs/method.md §4) on the paper case, from outside: convergence rates
//! against the newton solution, the stall with all-micro weak interfaces, convergence to the
//! exact solution at tight tolerance, the linear case, uneven partitions, and the CLI. The
//! invariants of the solver's internals (the partition and the kernels of K*_E, the linear
//! stage's continuity and equilibrium, the local stage's law) are tested beside them, in
//! `src/solvers/latin/tests.rs`.
//!
//! Figures measured when these tests were written are quoted next to each bound; run with
//! `--nocapture` to see the current ones.

mod common;

use common::{load, paper_model, paper_text_with, temp_path};
use std::process::Command;
use tensolve::decomposition::WeakInterfaces;
use tensolve::model::Model;
use tensolve::results::relative_difference;
use tensolve::solvers::latin::{Latin, LatinSettings, SearchPolicy};
use tensolve::solvers::newton::Newton;
use tensolve::solvers::{AnySolver, Reference, Silent, Solution, Solver, TautStiffness};

/// Interface search direction of the paper, N/m (set explicitly by `settings`).
const DM: f64 = tensolve::solvers::latin::PAPER_DM;

/// The exact solution (newton from U = 0, default settings) at `alpha`.
fn newton(s: &Model, alpha: f64) -> Solution {
    let taut = TautStiffness::new(s).expect("taut stiffness is regular");
    let sol = Newton::new(s, &taut, Default::default())
        .expect("newton set-up")
        .solve(&load(&s.structure, alpha), None, &mut Silent);
    assert!(sol.info.status.converged(), "newton: {:?}", sol.info);
    sol
}

fn settings(subdomains: [usize; 2], weak: WeakInterfaces) -> LatinSettings {
    LatinSettings {
        subdomains,
        weak,
        dm: Some(DM),
        ..LatinSettings::default()
    }
}

/// e after every linear stage from iteration 0 to `iterations` (init, then next_iter).
fn error_history(
    s: &Model,
    latin: &mut Latin<'_>,
    alpha: f64,
    reference: &Solution,
    iterations: usize,
) -> Vec<f64> {
    let reference = Reference::new(s, &reference.equilibrium.displacements);
    let mut state = latin.init(&load(&s.structure, alpha));
    let mut history = vec![reference.error(&latin.elongations(&state))];
    while state.iteration < iterations {
        latin.next_iter(&mut state);
        history.push(reference.error(&latin.elongations(&state)));
    }
    history
}

/// First iteration whose e is below `threshold`.
fn first_below(history: &[f64], threshold: f64) -> Option<usize> {
    history.iter().position(|&e| e < threshold)
}

// ---------------------------------------------------------------------------------------------
// 1. Convergence rates of the paper's plain method (docs/method.md §4 "Measured on the paper case"):
//    `LatinSettings::plain()`, the behaviour the paper describes, stays reachable.

#[test]
fn micro_macro_rate_on_paper_case() {
    let model = paper_model(&[]);
    let reference = newton(&model, 1.0);
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro).plain()).unwrap();
    let h = error_history(&model, &mut latin, 1.0, &reference, 80);
    let (at_2, at_3) = (first_below(&h, 1e-2), first_below(&h, 1e-3));
    println!(
        "micro-macro 4x4, alpha 1: e < 1e-2 at {at_2:?}, e < 1e-3 at {at_3:?}, e(80) = {:.3e}",
        h[80]
    );
    // Measured: 30 and 63 (the prototype of docs/method.md §6: 31, 64).
    assert!(at_2.is_some_and(|k| k <= 40), "e < 1e-2 first at {at_2:?}");
    assert!(at_3.is_some_and(|k| k <= 80), "e < 1e-3 first at {at_3:?}");
}

#[test]
fn mono_latin_rate_on_paper_case() {
    let model = paper_model(&[]);
    let reference = newton(&model, 1.0);
    let mut latin = Latin::new(&model, settings([1, 1], WeakInterfaces::Macro).plain()).unwrap();
    assert_eq!(latin.report().interfaces, 0);
    assert_eq!(latin.report().substructures, 1);
    let h = error_history(&model, &mut latin, 1.0, &reference, 15);
    let at_2 = first_below(&h, 1e-2);
    println!(
        "mono-latin, alpha 1: e < 1e-2 at {at_2:?}, e(15) = {:.3e}",
        h[15]
    );
    // Measured: 10 (the prototype of docs/method.md §6: 11).
    assert!(at_2.is_some_and(|k| k <= 15), "e < 1e-2 first at {at_2:?}");
}

#[test]
fn micro_macro_rate_at_small_load() {
    let model = paper_model(&[]);
    let reference = newton(&model, 0.05);
    assert_eq!(reference.equilibrium.slack_count(), 0);
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro).plain()).unwrap();
    let h = error_history(&model, &mut latin, 0.05, &reference, 40);
    let at_4 = first_below(&h, 1e-4);
    println!(
        "micro-macro 4x4, alpha 0.05: e < 1e-2 at {:?}, 1e-3 at {:?}, 1e-4 at {at_4:?}",
        first_below(&h, 1e-2),
        first_below(&h, 1e-3)
    );
    // Measured: 27 (the prototype of docs/method.md §6: 28).
    assert!(at_4.is_some_and(|k| k <= 40), "e < 1e-4 first at {at_4:?}");
}

// ---------------------------------------------------------------------------------------------
// 3. All-micro weak interfaces stall (docs/method.md §4 "Weak interfaces").

#[test]
fn micro_weak_interfaces_stall() {
    let model = paper_model(&[]);
    let reference = newton(&model, 1.0);
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Micro).plain()).unwrap();
    let h = error_history(&model, &mut latin, 1.0, &reference, 100);
    println!("weak = micro, alpha 1: e(100) = {:.3e}", h[100]);
    // Measured: 0.806 (docs/method.md: ≈ 0.8).
    assert!(h[100] > 0.1, "e after 100 iterations = {:e}", h[100]);
}

// ---------------------------------------------------------------------------------------------
// 4. Tight tolerance: both LATIN solvers end on the exact solution.

fn assert_ends_on_newton(subdomains: [usize; 2], alpha: f64, tolerance: f64, budget: usize) {
    let model = paper_model(&[]);
    let s = &model.structure;
    let reference = newton(&model, alpha);
    let mut latin = Latin::new(
        &model,
        LatinSettings {
            tolerance,
            max_iterations: budget,
            ..settings(subdomains, WeakInterfaces::Macro)
        },
    )
    .unwrap();
    let mut recorder = tensolve::solvers::Recorder::default();
    let sol = latin.solve(
        &load(s, alpha),
        Some(&Reference::new(
            &model,
            &reference.equilibrium.displacements,
        )),
        &mut recorder,
    );
    let trace: Vec<(usize, f64, Option<f64>)> = recorder
        .records
        .iter()
        .map(|r| (r.iteration, r.stopping_value, r.error))
        .collect();
    let d = relative_difference(
        &sol.equilibrium.displacements,
        &reference.equilibrium.displacements,
    );
    let last = trace.last().copied().unwrap();
    println!(
        "{subdomains:?} alpha {alpha} tol {tolerance:e}: {:?} after {} iterations, eta {:.3e}, \
         e {:.3e}, slack {} (newton {}), |dU|/|U| {d:.3e}, {:.2} s",
        sol.info.status,
        sol.info.iterations,
        sol.info.stopping_value,
        last.2.unwrap(),
        sol.equilibrium.slack_count(),
        reference.equilibrium.slack_count(),
        sol.info.solve_seconds
    );
    assert!(
        sol.info.status.converged(),
        "{subdomains:?} alpha {alpha}: {:?}; eta/e at 0, 1/4, 1/2, 3/4 and the end: {:?}",
        sol.info,
        [
            0,
            trace.len() / 4,
            trace.len() / 2,
            3 * trace.len() / 4,
            trace.len() - 1
        ]
        .map(|k| trace[k])
    );
    assert_eq!(
        sol.equilibrium.slack_count(),
        reference.equilibrium.slack_count(),
        "{subdomains:?} alpha {alpha}: slack count"
    );
    assert!(
        sol.equilibrium.slack == reference.equilibrium.slack,
        "{subdomains:?} alpha {alpha}: slack sets differ"
    );
    assert!(d < 1e-6, "{subdomains:?} alpha {alpha}: |dU|/|U| = {d:e}");
}

#[test]
fn micro_macro_ends_on_newton_at_tight_tolerance() {
    // Measured: 2023 iterations at alpha 1 (η ≤ 1e-9, e ≈ 1.7e-9), |dU|/|U| ≈ 2e-11, ~1 s.
    assert_ends_on_newton([4, 4], 1.0, 1e-9, 5000);
}

#[test]
fn mono_latin_ends_on_newton_at_tight_tolerance() {
    // Measured: 1463 iterations at alpha 1 (e ≈ 4e-11), |dU|/|U| ≈ 1.3e-11, ~0.4 s.
    assert_ends_on_newton([1, 1], 1.0, 1e-9, 5000);
}

// ---------------------------------------------------------------------------------------------
// 5. Linear case: monodomain LATIN is exact after one iteration.

#[test]
fn mono_latin_solves_linear_case_in_one_iteration() {
    let model = paper_model(&[("cables", "unilateral", false.into())]);
    let s = &model.structure;
    let reference = newton(&model, 1.0);
    // The relaxed iteration measures η between s and the ŝ that fed it, so it knows after
    // iteration 1; the accelerated one (the default) measures η between s and local(s), so it
    // knows after the first linear stage (iteration 0). Inexact Newton status steps (the
    // default policy) always iterate in the accelerated order.
    let fixed = SearchPolicy::Stiffness;
    let default = LatinSettings::default();
    for (anderson, policy, iterations) in [
        (0, fixed, 1),
        (default.anderson, fixed, 0),
        (0, default.policy, 0),
        (default.anderson, default.policy, 0),
    ] {
        let mut latin = Latin::new(
            &model,
            LatinSettings {
                anderson,
                policy,
                ..settings([1, 1], WeakInterfaces::Macro)
            },
        )
        .unwrap();
        let sol = latin.solve(&load(s, 1.0), None, &mut Silent);
        let d = relative_difference(
            &sol.equilibrium.displacements,
            &reference.equilibrium.displacements,
        );
        println!(
            "linear case, mono-latin (anderson {anderson}): {:?}, |dU|/|U| = {d:e}",
            sol.info
        );
        assert!(sol.info.status.converged(), "{:?}", sol.info);
        assert_eq!(sol.info.iterations, iterations, "{:?}", sol.info);
        assert!(d < 1e-9, "|dU|/|U| = {d:e}");
        assert_eq!(sol.equilibrium.slack_count(), 0);
        let dt = relative_difference(&sol.equilibrium.tensions, &reference.equilibrium.tensions);
        assert!(dt < 1e-9, "tensions differ by {dt:e} (relative)");
    }
}

// ---------------------------------------------------------------------------------------------
// 8. Uneven partitions.

#[test]
fn uneven_partition_3x5_ends_on_newton() {
    // Uneven: 16 modules into 3 along x and 5 along y. Measured: 1629 iterations at alpha 1
    // (η ≤ 1e-8, e ≈ 1.5e-8), |dU|/|U| ≈ 1.1e-9.
    assert_ends_on_newton([3, 5], 1.0, 1e-8, 5000);
}

#[test]
fn one_module_per_substructure_ends_on_newton() {
    let model = paper_model(&[]);
    // The kernels' dimensions on this partition are checked from B_E in the solver's own
    // tests (src/solvers/latin/tests.rs).
    if let Err(err) = Latin::new(&model, settings([16, 16], WeakInterfaces::Macro)) {
        panic!("[16, 16] set-up: {err:?}");
    }
    assert_ends_on_newton([16, 16], 0.5, 1e-8, 20000);
}

// ---------------------------------------------------------------------------------------------
// 9. CLI.

struct TempPath(std::path::PathBuf);

impl Drop for TempPath {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
        let _ = std::fs::remove_file(&self.0);
    }
}

fn micro_macro_case(tag: &str, extra: &[(&str, &str, toml::Value)]) -> TempPath {
    let mut overrides: Vec<(&str, &str, toml::Value)> = vec![
        (
            "solver",
            "methods",
            toml::Value::Array(vec!["micro-macro".into()]),
        ),
        ("load", "alpha", toml::Value::Array(vec![1.0.into()])),
    ];
    overrides.extend(extra.iter().cloned());
    let path = TempPath(temp_path(&format!("{tag}.toml")));
    std::fs::write(&path.0, paper_text_with(&overrides)).unwrap();
    path
}

#[test]
fn cli_check_prints_the_partition() {
    let case = micro_macro_case("latin-check", &[]);
    let out = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .arg("check")
        .arg(&case.0)
        .output()
        .expect("run tensolve");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = stdout.lines().map(str::trim).collect();
    assert!(
        lines.contains(&"interfaces    42 (24 strong, 18 weak, 0 dropped; weak = Macro)"),
        "{stdout}"
    );
    // The paper's 24 × 9 + 18 × 3: substructures of 4 × 4 modules keep the first-order basis.
    assert!(
        lines.contains(
            &"macro dofs    270 (degree 1 on strong interfaces: default round(H/4), 1 to 16, at most what the partition takes)"
        ),
        "{stdout}"
    );
    assert!(lines.contains(&"micro-macro:"), "{stdout}");
    // The macro system: the 270 forces and the substructures' kernel columns, its factor sized.
    let number = |key: &str| -> usize {
        let line = lines.iter().find(|l| l.starts_with(key)).expect(key);
        line[key.len()..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let system = lines
        .iter()
        .find(|l| l.starts_with("macro system"))
        .unwrap();
    assert_eq!(
        number("macro system"),
        270 + number("kernel cols"),
        "{stdout}"
    );
    assert!(
        system.contains("whole; factorised and solved on every MPI rank"),
        "{stdout}"
    );
    let entries: usize = system
        .split("factor ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(entries >= number("macro system"), "{stdout}");
}

/// From 1024 substructures on, `check` says the macro factor is split into two subtrees of
/// substructures (128 × 128 modules on 32 × 32 substructures); the paper's partition above is
/// whole.
#[test]
fn cli_check_says_the_macro_factor_is_split_from_1024_substructures() {
    let out = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .arg("check")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/scale-128.toml"))
        .args(["--set", "solver.methods=[\"micro-macro\"]"])
        .args(["--set", "solver.subdomains=[32, 32]"])
        .output()
        .expect("run tensolve");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let system = stdout
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("macro system"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        system.contains("in 2 subtrees of substructures side by side;"),
        "{system}"
    );
}

#[test]
fn cli_run_writes_micro_macro_history() {
    let case = micro_macro_case("latin-run", &[("solver", "tolerance", 1e-3.into())]);
    let dir = TempPath(temp_path("latin-run-out"));
    let out = Command::new(env!("CARGO_BIN_EXE_tensolve"))
        .arg("run")
        .arg(&case.0)
        .arg("--out")
        .arg(&dir.0)
        .arg("--quiet")
        .output()
        .expect("run tensolve");
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    let history_dir = dir.0.join("history");
    let text = std::fs::read_to_string(history_dir.join("micro-macro_alpha1.csv"))
        .expect("history/micro-macro_alpha1.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("iteration,error_e,indicator_eta,equilibrium_residual,slack_fraction,search_updates,elapsed_seconds")
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert!(rows.len() >= 2, "{text}");
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 7, "row {k}: {row:?}");
        assert_eq!(
            row[0].parse::<usize>().unwrap(),
            k,
            "iterations numbered from 0"
        );
    }
    let e: Vec<f64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    let eta: Vec<f64> = rows.iter().map(|r| r[2].parse().unwrap()).collect();
    println!(
        "history: {} rows, e {:.3e} -> {:.3e}, eta {:.3e} -> {:.3e}",
        rows.len(),
        e[0],
        e[e.len() - 1],
        eta[0],
        eta[eta.len() - 1]
    );
    assert!(e[e.len() - 1] < e[0], "e did not decrease: {e:?}");
    assert!(eta[eta.len() - 1] <= 1e-3);
    let leftovers: Vec<String> = std::fs::read_dir(&history_dir)
        .unwrap()
        .map(|d| d.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let summary = std::fs::read_to_string(dir.0.join("summary.csv")).expect("summary.csv");
    let mut reader = csv::Reader::from_reader(summary.as_bytes());
    let headers = reader.headers().unwrap().clone();
    let col = |name: &str| headers.iter().position(|h| h == name).expect(name);
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
    let mm: Vec<&csv::StringRecord> = rows
        .iter()
        .filter(|r| &r[col("solver")] == "micro-macro")
        .collect();
    assert_eq!(mm.len(), 1, "{summary}");
    assert_eq!(&mm[0][col("converged")], "true", "{summary}");
    assert_eq!(
        mm[0][col("iterations")].parse::<usize>().unwrap(),
        rows_len_minus_one(&text),
        "{summary}"
    );
}

/// Iterations of a history file: its last iteration number.
fn rows_len_minus_one(history: &str) -> usize {
    history.lines().count() - 2
}

/// `cases/paper-plain.toml`, the paper's method as published (relaxation 1, no acceleration,
/// l = k fixed, d_m = 3.92e6, stop on η), run by the binary: its history at α = 1 reaches
/// e < 1e-2 first at iteration 30 and e < 1e-3 first at 63, the paper's rates.
#[test]
fn paper_plain_case_reproduces_the_papers_rates() {
    let out = temp_path("paper-plain");
    let case = common::manifest_path("cases/paper-plain.toml");
    let run = common::tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "load.alpha=[1.0]",
        "--set",
        "output.plots=false",
    ]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let history = std::fs::read_to_string(out.join("history/micro-macro_alpha1.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (iteration, error) = (at("iteration"), at("error_e"));
    let rows: Vec<(usize, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[iteration].parse().unwrap(), f[error].parse().unwrap())
        })
        .collect();
    let first_below = |threshold: f64| rows.iter().find(|(_, e)| *e < threshold).map(|r| r.0);
    assert_eq!(first_below(1e-2), Some(30), "e < 1e-2");
    assert_eq!(first_below(1e-3), Some(63), "e < 1e-3");
}
