//! A converged answer that is not the only equilibrium says so (issue 42, D1): `summary.csv`'s
//! `unique` and a warning naming the nodes of the free motion. The newcomer's guyed mast
//! (`tests/data/my-mast.toml`): under a pure x load at α = 2 both leeward guys slacken, the
//! bar and the windward guy alone carry force and the top is free in y; newton stops with the
//! top 8.26 mm aside (a leeward guy left at zero tension, its gap closed), the other solvers at
//! 0, all converged.

mod common;

use common::{code, manifest_path, stderr, summary_rows, tensolve, Temp};
use std::path::Path;

const SOLVERS: [&str; 4] = ["newton", "pcg-lcp", "mono-latin", "micro-macro"];

/// (ux, uy, uz) of node `node` in a `displacements/` file.
fn displacement(dir: &Path, solver: &str, alpha: &str, node: &str) -> [f64; 3] {
    let path = dir.join(format!("displacements/{solver}_alpha{alpha}.csv"));
    let mut reader = csv::Reader::from_path(&path).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let at = |name: &str| header.iter().position(|h| h == name).unwrap();
    for r in reader.records() {
        let r = r.unwrap();
        if &r[at("node")] == node {
            return ["ux", "uy", "uz"].map(|c| r[at(c)].parse().unwrap());
        }
    }
    panic!("{}: no node {node}", path.display());
}

fn run_mast(alphas: &str) -> (Temp, std::process::Output) {
    mast("run", &[&format!("load.alpha={alphas}")])
}

/// `tensolve COMMAND` on the mast with `--set` overrides, into a new directory.
fn mast(command: &str, sets: &[&str]) -> (Temp, std::process::Output) {
    let dir = Temp::dir("unique-mast");
    let case = manifest_path("tests/data/my-mast.toml");
    let mut args = vec![command, case.to_str().unwrap(), "--out", dir.arg()];
    for s in sets {
        args.extend(["--set", s]);
    }
    let out = tensolve(&args);
    (dir, out)
}

#[test]
fn the_mast_with_both_leeward_guys_slack_is_not_unique_in_every_solver() {
    let (dir, out) = run_mast("[1.0, 2.0]");
    let err = stderr(&out);
    // Converged rows, however many answers: exit 0.
    assert_eq!(code(&out), 0, "{err}");
    let rows = summary_rows(&dir.0);
    assert_eq!(rows.len(), 8);
    for row in &rows {
        let at = format!("{} at alpha = {}", row["solver"], row["alpha"]);
        assert_eq!(row["status"], "converged", "{at}");
        let want = if row["alpha"] == "2" { "false" } else { "true" };
        assert_eq!(row["unique"], want, "{at}");
    }
    // Not unique in fact: two converged answers, the top 8.26 mm aside in newton's, not in
    // pcg-lcp's (both equilibria of the same energy, along the free motion).
    let newton = displacement(&dir.0, "newton", "2", "1");
    let pcg = displacement(&dir.0, "pcg-lcp", "2", "1");
    assert!((newton[1] - pcg[1]).abs() > 5e-3, "{newton:?} {pcg:?}");
    assert!((newton[0] - pcg[0]).abs() < 1e-9, "{newton:?} {pcg:?}");
    // At α = 1 (every guy taut) the four agree.
    let taut = displacement(&dir.0, "newton", "1", "1");
    for solver in SOLVERS {
        let u = displacement(&dir.0, solver, "1", "1");
        assert!(
            (0..3).all(|k| (u[k] - taut[k]).abs() < 1e-9),
            "{solver}: {u:?}"
        );
    }
    // One warning per row at α = 2, naming the top (node 1) moving in y and no other node.
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("the answer is not unique"))
        .collect();
    assert_eq!(warnings.len(), 4, "{err}");
    for solver in SOLVERS {
        let line = warnings
            .iter()
            .find(|l| l.contains(&format!("warning: {solver} at alpha = 2:")))
            .unwrap_or_else(|| panic!("no warning for {solver}: {err}"));
        let nodes = line
            .split("it moves nodes ")
            .nth(1)
            .and_then(|rest| rest.split(");").next())
            .unwrap_or_else(|| panic!("{line}"));
        // `1 (0.00, 1.00, 0.00)`: node 1 alone, moving along ±y.
        let (id, motion) = nodes.split_once(" (").unwrap_or_else(|| panic!("{line}"));
        assert_eq!(id, "1", "{line}");
        let motion: Vec<f64> = motion
            .trim_end_matches(')')
            .split(", ")
            .map(|x| x.parse().unwrap())
            .collect();
        assert!(
            motion[0].abs() < 0.01
                && (motion[1].abs() - 1.0).abs() < 0.01
                && motion[2].abs() < 0.01,
            "{line}"
        );
        assert!(line.contains("unique = false"), "{line}");
    }
}

/// Slack cables alone do not make an answer non-unique: the paper's grid at α = 1 (hundreds of
/// slack cables, every node held by taut members) is unique, and the mast with its guys taut.
#[test]
fn answers_held_by_their_taut_members_are_unique() {
    let (dir, out) = run_mast("[0.5, 1.0]");
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(!stderr(&out).contains("not unique"), "{}", stderr(&out));
    let rows = summary_rows(&dir.0);
    assert_eq!(rows.len(), 8);
    assert!(rows.iter().all(|r| r["unique"] == "true"), "{rows:?}");

    let dir = Temp::dir("unique-paper");
    let case = manifest_path("cases/paper.toml");
    let out = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        dir.arg(),
        "--solver",
        "newton,pcg-lcp",
        "--set",
        "load.alpha=[1.0]",
        "--set",
        "output.plots=false",
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let rows = summary_rows(&dir.0);
    assert_eq!(rows.len(), 2);
    for row in &rows {
        let slack: usize = row["slack_cables"].parse().unwrap();
        assert!(slack > 100, "{row:?}");
        assert_eq!(row["unique"], "true", "{row:?}");
    }
}

/// The mast's answers at α = 2 are a segment: newton's and pcg-lcp's ends and every point
/// between them are equilibria (r(U) at round-off) of one energy, computed here from the law
/// itself; each is flagged not unique with the top as the free motion's node, whether its
/// leeward guy is at zero tension with its gap closed (newton's end, where the gap rule calls
/// it taut) or slack with its gap open (the rest): the check classifies the cable by the same
/// rule whichever solver left it there.
#[test]
fn every_answer_between_the_solvers_answers_is_an_equilibrium_of_one_energy_and_not_unique() {
    use tensolve::model::material;
    use tensolve::results::equilibrium_residual;
    use tensolve::results::uniqueness::{uniqueness, Uniqueness};
    use tensolve::solvers::newton::{Newton, NewtonSettings};
    use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
    use tensolve::solvers::{AnySolver, Equilibrium, Silent, TautStiffness};

    let case = tensolve::case::load(&manifest_path("tests/data/my-mast.toml")).unwrap();
    let model = case.model();
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let load: Vec<f64> = s.unit_load.iter().map(|f| 2.0 * f).collect();
    let newton = Newton::new(&model, &taut, NewtonSettings::default())
        .unwrap()
        .solve(&load, None, &mut Silent);
    let pcg = PcgLcp::new(&model, &taut, PcgLcpSettings::default()).solve(&load, None, &mut Silent);
    assert!(newton.info.status.converged() && pcg.info.status.converged());
    let (a, b) = (
        &pcg.equilibrium.displacements,
        &newton.equilibrium.displacements,
    );
    // The energy Σ φ(e) − F·U, φ(e) = ∫₀ᵉ τ = (τ(e)² − t0²) / 2k with τ = t0 + k e (clipped
    // at 0 on cables).
    let energy = |u: &[f64]| -> f64 {
        let stored: f64 = s
            .links
            .iter()
            .zip(model.trial_tensions(u))
            .map(|(l, t)| {
                (material::tension(l, t).powi(2) - l.prestress.powi(2)) / (2.0 * l.stiffness)
            })
            .sum();
        stored - load.iter().zip(u).map(|(f, x)| f * x).sum::<f64>()
    };
    let (pattern, analysed) = TautStiffness::analyse(s);
    let e0 = energy(a);
    let mut slack_counts = Vec::new();
    for step in 0..=4 {
        let w = step as f64 / 4.0;
        let u: Vec<f64> = a.iter().zip(b).map(|(x, y)| x + w * (y - x)).collect();
        let tensions: Vec<f64> = s
            .links
            .iter()
            .zip(model.trial_tensions(&u))
            .map(|(l, t)| material::tension(l, t))
            .collect();
        let eq = Equilibrium::classified(&model, u.clone(), tensions);
        assert!(equilibrium_residual(s, &eq, &load) < 1e-12, "at {w}");
        let e = energy(&u);
        assert!(
            (e - e0).abs() <= 1e-12 * e0.abs(),
            "at {w}: {e} against {e0}"
        );
        slack_counts.push(eq.slack_count());
        match uniqueness(&model, &eq, &load, &pattern, &analysed) {
            Uniqueness::NotUnique { nodes } => {
                assert_eq!(nodes.len(), 1, "at {w}: {nodes:?}");
                assert_eq!(nodes[0].0, 1, "at {w}: {nodes:?}");
                assert!(
                    (nodes[0].1[1].abs() - 1.0).abs() < 1e-9,
                    "at {w}: {nodes:?}"
                );
            }
            other => panic!("at {w}: called {other:?}"),
        }
    }
    // Newton's end keeps one guy at zero tension, gap closed: taut by the gap rule.
    assert_eq!(slack_counts, [2, 2, 2, 2, 1]);
    // The energy of the report.
    assert!((e0 - (-402.5004)).abs() < 1e-3, "{e0}");
}

/// The mast's free rotation about the load's axis under the geometric models: its stiffness is
/// round-off there, not an exact zero pivot. Every row says `unique = false` where
/// `min_tangent_eigenvalue` reads 0 — under `prestress` at α = 2 and 4 (K_G of the answer's own
/// tensions), and along a `large` sweep, where a stricter test had flipped `unique` to `true`
/// at 1.5 of 1.1 … 2 (this session's adversarial pass).
#[test]
fn a_zero_tangent_eigenvalue_under_the_geometric_models_is_not_unique() {
    for sets in [
        vec!["model.geometry=\"prestress\"", "load.alpha=[1.0, 2.0, 4.0]"],
        vec![
            "model.geometry=\"large\"",
            "solver.methods=[\"newton\"]",
            "load.point=[{nodes=[1],force=[1000000.0,0.0,0.0]}]",
            "load.alpha=[1.1, 1.15, 1.2, 1.5, 2.0]",
        ],
    ] {
        let (dir, out) = mast("run", &sets);
        assert_eq!(code(&out), 0, "{sets:?}: {}", stderr(&out));
        let rows = summary_rows(&dir.0);
        assert!(rows.len() >= 5, "{sets:?}");
        for row in &rows {
            let at = format!("{sets:?}: {} at alpha = {}", row["solver"], row["alpha"]);
            assert_eq!(row["status"], "converged", "{at}");
            let zero = row["min_tangent_eigenvalue"].parse::<f64>().unwrap() == 0.0;
            let want = if zero { "false" } else { "true" };
            assert_eq!(row["unique"], want, "{at}");
        }
        assert!(rows.iter().any(|r| r["unique"] == "false"), "{sets:?}");
    }
}

/// Under `prestress`, a load that works on the free rotation of the mast (1 N along y besides
/// the wind) meets no resistance from the tangent of the answer's own tensions: the rows said
/// `converged` with the top moving against the load (−5.87 mm); now `unstable`, naming node 1,
/// and no `unique` (this session's adversarial pass).
#[test]
fn a_load_on_a_motion_the_answers_tangent_does_not_resist_is_unstable() {
    let (dir, out) = mast(
        "run",
        &[
            "model.geometry=\"prestress\"",
            "load.alpha=[2.0]",
            "load.point=[{nodes=[1],force=[10000.0,1.0,0.0]}]",
        ],
    );
    let err = stderr(&out);
    assert_eq!(code(&out), 1, "{err}");
    let rows = summary_rows(&dir.0);
    assert_eq!(rows.len(), 4);
    for row in &rows {
        let at = format!("{} at alpha = {}", row["solver"], row["alpha"]);
        assert_eq!(row["converged"], "false", "{at}");
        assert_eq!(row["unique"], "", "{at}");
    }
    let unstable = rows.iter().filter(|r| r["status"] == "unstable").count();
    assert!(unstable >= 3, "{rows:?}");
    assert!(
        err.contains("does not resist (it moves nodes 1 (0.00, 1.00, 0.00))"),
        "{err}"
    );
}

/// `bench` measures e against newton's answer: where that answer is one of several equilibria
/// (the mast at α = 2 and 4) it says so, naming the free motion's node, and not at α = 1
/// (this session's adversarial pass: e of 0.18 and 0.39 with no word).
#[test]
fn bench_says_when_its_reference_is_not_unique() {
    let (_dir, out) = mast("bench", &["load.alpha=[1.0, 2.0, 4.0]"]);
    let err = stderr(&out);
    assert_eq!(code(&out), 0, "{err}");
    for alpha in ["2", "4"] {
        assert!(
            err.contains(&format!(
                "warning: the reference at alpha = {alpha}: the answer is not unique (a motion \
                 free of the load moves nodes 1 (0.00, "
            )),
            "{alpha}: {err}"
        );
    }
    assert!(!err.contains("the reference at alpha = 1:"), "{err}");
}
