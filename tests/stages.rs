//! Construction stages (`[[stages]]`, issue 60 item 2): each stage installs members, holds
//! props and applies loads, solved under `large` from where the last stage left the
//! structure. The shipped tower built in stages (its top ring last, its top held by props
//! until the ring closes the self-stress, then loaded in two steps) ends where one `large`
//! solve of the same load does; a prop released while it carries a reaction is refused, as
//! is every key that does not fit.

mod common;

use common::{code, csv_rows, manifest_path, stderr, tensolve, Temp};
use std::path::Path;

/// The tower's case with `stages` (load case G: the tower's own point load on its top).
fn tower_stages(stages: &str) -> String {
    format!(
        "[structure]\nnodes = \"{0}/nodes.csv\"\nmembers = \"{0}/members.csv\"\n\
         [[supports.fix]]\nnodes = [0, 1, 2]\n\
         [[load.cases]]\nname = \"G\"\n[[load.cases.point]]\nnodes = [15, 16, 17]\n\
         force = [500.0, 866.0, 0.0]\n\
         [load]\nalpha = [1.0]\n[model]\ngeometry = \"large\"\n\
         [solver]\nmethods = [\"newton\"]\n{stages}",
        manifest_path("cases/tower").display()
    )
}

/// The tower's modules with props on its top, its top ring installed, then G at 0.5 and 1.
const BUILT_IN_STAGES: &str = "[[stages]]\nname = \"modules\"\nprops = [15, 16, 17]\n\
     [[stages]]\nname = \"ring\"\nmembers = [18, 19, 20]\nprops = [15, 16, 17]\n\
     [[stages]]\nname = \"half\"\nfactors = { G = 0.5 }\n\
     [[stages]]\nname = \"service\"\nfactors = { G = 1.0 }\n";

/// Run the case text `text` into `out`.
fn run(dir: &Temp, text: &str, out: &Path, sets: &[&str]) -> std::process::Output {
    std::fs::create_dir_all(&dir.0).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    tensolve(&args)
}

/// Every displacement component of a run's file, in file order.
fn displacements(path: &Path) -> Vec<f64> {
    csv_rows(path)
        .iter()
        .flat_map(|r| ["ux", "uy", "uz"].map(|k| r[k].parse::<f64>().unwrap()))
        .collect()
}

/// The largest difference of `a` and `b` against b's largest entry.
fn relative(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / scale
}

/// Built in stages, the tower sits unmoved while propped (its prestress balanced by the
/// props, then by the closed ring), and its two loaded stages equal one `large` solve of
/// G × 0.5 and G × 1 from the prestressed state to 1e-9: the second started from the first's
/// answer under its load. The summary lists the stages in order.
#[test]
fn the_tower_built_in_stages_ends_where_one_solve_does() {
    let dir = Temp::dir("stages-tower");
    let out = dir.0.join("out");
    let o = run(&dir, &tower_stages(BUILT_IN_STAGES), &out, &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let summary = csv_rows(&out.join("summary.csv"));
    let names: Vec<&str> = summary.iter().map(|r| r["stage"].as_str()).collect();
    assert_eq!(names, ["modules", "ring", "half", "service"]);
    assert!(summary.iter().all(|r| r["status"] == "converged"));
    let stage = |name: &str| out.join(format!("stages/{name}/displacements/newton_alpha1.csv"));
    for name in ["modules", "ring"] {
        let u = displacements(&stage(name));
        assert!(u.iter().all(|x| x.abs() < 1e-12), "{name}: {u:?}");
    }
    // One solve: the shipped tower under `large` at α = 0.5 and 1.
    let one = dir.0.join("one");
    let o = tensolve(&[
        "run",
        manifest_path("cases/tower.toml").to_str().unwrap(),
        "--out",
        one.to_str().unwrap(),
        "--quiet",
        "--set",
        "model.geometry=\"large\"",
        "--set",
        "load.alpha=[0.5, 1.0]",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    for (name, alpha) in [("half", "0.5"), ("service", "1")] {
        let staged = displacements(&stage(name));
        let once = displacements(&one.join(format!("displacements/newton_alpha{alpha}.csv")));
        let off = relative(&staged, &once);
        assert!(off < 1e-9, "{name}: {off:e}");
    }
}

/// `check` lists the stages in order, and no combination.
#[test]
fn check_lists_the_stages() {
    let dir = Temp::dir("stages-check");
    std::fs::create_dir_all(&dir.0).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(&case, tower_stages(BUILT_IN_STAGES)).unwrap();
    let o = tensolve(&["check", case.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        text.contains("stages          modules, ring, half, service: solved in order"),
        "{text}"
    );
    assert!(!text.contains("combinations"), "{text}");
}

/// A stage that lets a prop go while it carries a reaction is refused, naming the stage's
/// props, the node, its reaction and the stage it carried it at: the top's props before the
/// ring closes the self-stress, and a prop that took a load.
#[test]
fn a_prop_released_under_load_is_refused() {
    let early = BUILT_IN_STAGES.replace(
        "members = [18, 19, 20]\nprops = [15, 16, 17]",
        "members = [18, 19, 20]",
    );
    let loaded = BUILT_IN_STAGES.replace(
        "members = [18, 19, 20]\nprops = [15, 16, 17]",
        "members = [18, 19, 20]\nprops = [15, 16, 17]\nfactors = { G = 1.0 }",
    );
    for (tag, stages, key, at) in [
        ("early", early, "stages[1].props", "at stage `modules`"),
        ("loaded", loaded, "stages[2].props", "at stage `ring`"),
    ] {
        let dir = Temp::dir(&format!("stages-{tag}"));
        let out = dir.0.join("out");
        let o = run(&dir, &tower_stages(&stages), &out, &[]);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{tag}: {err}");
        assert!(
            err.contains(key) && err.contains("node 15") && err.contains(at),
            "{tag}: {err}"
        );
    }
}

/// What a staged case is refused with (exit 2, naming the key and the fix).
#[test]
fn stage_keys_that_do_not_fit_are_refused() {
    let dir = Temp::dir("stages-refused");
    let text = tower_stages(BUILT_IN_STAGES);
    let cases: [(&[&str], &str, &str); 9] = [
        (
            &["load.path=\"arc-length\""],
            "load.path",
            "remove `load.path`",
        ),
        (
            &["model.geometry=\"prestress\""],
            "stages",
            "model.geometry = \"large\"",
        ),
        (
            &["solver.methods=[\"newton\", \"pcg-lcp\"]"],
            "stages",
            "names pcg-lcp",
        ),
        (&["load.alpha=[0.5, 1.0]"], "load.alpha", "α = 1"),
        (
            &["load.combinations=[{name = \"C\", factors = {G = 1.0}}]"],
            "load.combinations",
            "remove [[load.combinations]]",
        ),
        (
            &["stages=[{name = \"a\", members = [99]}]"],
            "stages[0].members",
            "no member has this id",
        ),
        (
            &["stages=[{name = \"a\", members = [18]}, {name = \"b\", members = [18]}]"],
            "stages[1].members",
            "installs this member already",
        ),
        (
            &["stages=[{name = \"a\", props = [99]}]"],
            "stages[0].props",
            "no node has this id",
        ),
        (
            &["stages=[{name = \"a\", factors = {Q = 1.0}}]"],
            "stages[0].factors.Q",
            "no load case is named",
        ),
    ];
    for (k, (sets, key, fix)) in cases.iter().enumerate() {
        let out = dir.0.join(format!("out{k}"));
        let o = run(&dir, &text, &out, sets);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{sets:?}: {err}");
        assert!(err.contains(key) && err.contains(fix), "{sets:?}: {err}");
    }
}

/// A prop first given at a later stage holds its node where the last stage left it (not
/// where it started): node 15 propped after G × 0.5 stays where G × 0.5 put it under G × 1.
/// A `--solver` other than newton is refused on a staged case.
#[test]
fn a_late_prop_holds_its_node_where_it_is() {
    let stages = "[[stages]]\nname = \"built\"\n\
         [[stages]]\nname = \"half\"\nfactors = { G = 0.5 }\n\
         [[stages]]\nname = \"propped\"\nprops = [15]\nfactors = { G = 1.0 }\n";
    let dir = Temp::dir("stages-late-prop");
    let out = dir.0.join("out");
    let o = run(&dir, &tower_stages(stages), &out, &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let node = |name: &str| {
        let rows = csv_rows(&out.join(format!("stages/{name}/displacements/newton_alpha1.csv")));
        let row = rows.iter().find(|r| r["node"] == "15").unwrap().clone();
        ["ux", "uy", "uz"].map(|k| row[k].parse::<f64>().unwrap())
    };
    let (half, propped) = (node("half"), node("propped"));
    assert!(half.iter().any(|x| x.abs() > 1e-4), "{half:?}");
    assert_eq!(half, propped);
    let o = tensolve(&[
        "run",
        dir.0.join("case.toml").to_str().unwrap(),
        "--out",
        dir.0.join("other").to_str().unwrap(),
        "--quiet",
        "--solver",
        "pcg-lcp",
    ]);
    let err = stderr(&o);
    assert_eq!(code(&o), 2, "{err}");
    assert!(
        err.contains("--solver") && err.contains("solved by newton"),
        "{err}"
    );
}
