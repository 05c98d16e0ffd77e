//! Load cases and combinations (issue 60 item 1): each combination is solved as one load, so
//! its answer is that of a plain run of the same loads written as one pattern (the same bits
//! of input: to 1e-12, here to the bit); the envelope is the largest and smallest over the
//! combinations' own files; the prestress's factor scales t0; actions in a case are scaled by
//! its factor; and bad input is refused naming the key.

mod common;

use common::{code, csv_rows, stderr, tensolve, Temp};
use std::collections::HashMap;
use std::path::Path;

type Rows = Vec<HashMap<String, String>>;

/// The paper's grid, 16 × 16 modules, linear (pinned), two α, newton and pcg-lcp.
const GRID: &str = "[grid]\nmodules = [16, 16]\n[model]\ngeometry = \"linear\"\n\
                    [solver]\nmethods = [\"newton\", \"pcg-lcp\"]\n[load]\nalpha = [0.5, 1.0]\n";

/// Write `text` as `case.toml` in a fresh directory and run it into `out`; exit 0 asserted.
fn run(tag: &str, text: &str) -> (Temp, Temp) {
    let dir = Temp::dir(tag);
    std::fs::create_dir_all(&dir.0).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let out = Temp::dir(&format!("{tag}-out"));
    let o = tensolve(&["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"]);
    assert_eq!(code(&o), 0, "{tag}: {}", stderr(&o));
    (dir, out)
}

fn file(dir: &Path, kind: &str, solver: &str, alpha: &str) -> Rows {
    csv_rows(&dir.join(kind).join(format!("{solver}_alpha{alpha}.csv")))
}

/// The combination G × fg + Q × fq of a grid (G: nodal, Q: a point load on half the upper
/// nodes) equals the plain case of nodal `fg · g` and point `fq · q`, written with the same
/// f64 values: forces and displacements identical, for both solvers and both α.
#[test]
fn a_combination_is_the_plain_run_of_its_loads() {
    let (g, q) = (-20.0f64, -30.0f64);
    let (fg, fq) = (1.35f64, 1.5f64);
    let point_box = "box = { min = [0.0, 0.0, -1.0], max = [8.0, 16.0, 1.0] }";
    let combined = format!(
        "{GRID}[[load.cases]]\nname = \"G\"\nnodal = [0.0, 0.0, {g:?}]\n\
         [[load.cases]]\nname = \"Q\"\n[[load.cases.point]]\n{point_box}\nforce = [0.0, 0.0, {q:?}]\n\
         [[load.combinations]]\nname = \"ULS\"\nfactors = {{ G = {fg:?}, Q = {fq:?} }}\n\
         [[load.combinations]]\nname = \"SLS\"\nfactors = {{ G = 1.0, Q = 1.0 }}\n"
    );
    let (_d, out) = run("comb-grid", &combined);
    for (name, a, b) in [("ULS", fg, fq), ("SLS", 1.0, 1.0)] {
        let plain = format!(
            "{GRID}nodal = [0.0, 0.0, {:?}]\n[[load.point]]\n{point_box}\nforce = [0.0, 0.0, {:?}]\n",
            a * g,
            b * q
        );
        let (_p, plain_out) = run(&format!("comb-plain-{name}"), &plain);
        let sub = out.0.join("combinations").join(name);
        for solver in ["newton", "pcg-lcp"] {
            for alpha in ["0.5", "1"] {
                for kind in ["forces", "displacements"] {
                    assert_eq!(
                        file(&sub, kind, solver, alpha),
                        file(&plain_out.0, kind, solver, alpha),
                        "{name} {solver} α {alpha}: {kind}"
                    );
                }
            }
        }
    }
    // The summary: every combination's rows, `combination` first.
    let summary = csv_rows(&out.0.join("summary.csv"));
    let names: Vec<&str> = summary.iter().map(|r| r["combination"].as_str()).collect();
    assert_eq!(
        names,
        ["ULS", "ULS", "ULS", "ULS", "SLS", "SLS", "SLS", "SLS"]
    );
}

/// The envelope is the largest and smallest force over the combinations' own `forces/`, and
/// the largest displacement over their `displacements/`, each with its combination.
#[test]
fn the_envelope_is_the_extreme_over_the_combinations() {
    let text = format!(
        "{GRID}[[load.cases]]\nname = \"down\"\nnodal = [0.0, 0.0, -40.0]\n\
         [[load.cases]]\nname = \"up\"\nnodal = [0.0, 0.0, 25.0]\n\
         [[load.cases]]\nname = \"side\"\nnodal = [30.0, 0.0, 0.0]\n"
    );
    let (_d, out) = run("comb-envelope", &text);
    let names = ["down", "up", "side"];
    for solver in ["newton", "pcg-lcp"] {
        for alpha in ["0.5", "1"] {
            let subs: Vec<Rows> = names
                .iter()
                .map(|n| file(&out.0.join("combinations").join(n), "forces", solver, alpha))
                .collect();
            let envelope: Vec<_> = csv_rows(&out.0.join("envelope/members.csv"))
                .into_iter()
                .filter(|r| r["solver"] == solver && r["alpha"] == alpha)
                .collect();
            assert_eq!(envelope.len(), subs[0].len());
            for (i, row) in envelope.iter().enumerate() {
                assert_eq!(row["member"], subs[0][i]["member"]);
                assert_eq!(row["combinations"], "3");
                let forces: Vec<f64> = subs
                    .iter()
                    .map(|s| s[i]["force_N"].parse().unwrap())
                    .collect();
                let max = forces.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let min = forces.iter().copied().fold(f64::INFINITY, f64::min);
                assert_eq!(row["max_force_N"].parse::<f64>().unwrap(), max);
                assert_eq!(row["min_force_N"].parse::<f64>().unwrap(), min);
                let at = |v: f64| names[forces.iter().position(|&f| f == v).unwrap()];
                assert_eq!(row["max_force_combination"], at(max));
                assert_eq!(row["min_force_combination"], at(min));
            }
        }
    }
    // Somewhere the governing combinations differ (the loads pull different ways).
    let rows = csv_rows(&out.0.join("envelope/members.csv"));
    let governing: std::collections::BTreeSet<&str> = rows
        .iter()
        .map(|r| r["max_force_combination"].as_str())
        .collect();
    assert!(governing.len() >= 2, "{governing:?}");
    let nodes = csv_rows(&out.0.join("envelope/nodes.csv"));
    assert!(!nodes.is_empty());
    for r in nodes
        .iter()
        .filter(|r| r["solver"] == "newton" && r["alpha"] == "1")
    {
        let u: Vec<f64> = names
            .iter()
            .map(|n| {
                let d = file(
                    &out.0.join("combinations").join(n),
                    "displacements",
                    "newton",
                    "1",
                );
                let row = d.iter().find(|x| x["node"] == r["node"]).unwrap();
                ["ux", "uy", "uz"]
                    .iter()
                    .map(|k| row[*k].parse::<f64>().unwrap().powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let max = u.iter().copied().fold(0.0, f64::max);
        assert_eq!(r["max_displacement_m"].parse::<f64>().unwrap(), max);
    }
}

/// `factors.prestress = 0.9` is the grid with `prestress.lower_cable` 0.9 × 2000 N; a case's
/// rest-length change under factor 2 is the plain run with the change doubled.
#[test]
fn the_prestress_factor_and_actions_scale_with_their_factors() {
    let text = format!(
        "{GRID}[[load.cases]]\nname = \"G\"\nnodal = [0.0, 0.0, -40.0]\n\
         [[load.cases]]\nname = \"A\"\n[[load.cases.rest_length_change]]\nmembers = [5, 9]\nchange = -0.0002\n\
         [[load.combinations]]\nname = \"P\"\nfactors = {{ G = 1.0, prestress = 0.9 }}\n\
         [[load.combinations]]\nname = \"GA\"\nfactors = {{ G = 1.0, A = 2.0 }}\n"
    );
    let (_d, out) = run("comb-factors", &text);
    let scaled = format!("{GRID}[prestress]\nlower_cable = {:?}\n", 0.9 * 2000.0);
    let (_p, plain) = run("comb-factors-prestress", &scaled);
    let doubled = format!(
        "{GRID}[[load.rest_length_change]]\nmembers = [5, 9]\nchange = {:?}\n",
        2.0 * -0.0002
    );
    let (_a, plain_a) = run("comb-factors-actions", &doubled);
    for solver in ["newton", "pcg-lcp"] {
        for (name, reference) in [("P", &plain), ("GA", &plain_a)] {
            let sub = out.0.join("combinations").join(name);
            let ours = file(&sub, "forces", solver, "1");
            let theirs = file(&reference.0, "forces", solver, "1");
            let largest = theirs
                .iter()
                .map(|r| r["force_N"].parse::<f64>().unwrap().abs())
                .fold(0.0, f64::max);
            for (x, y) in ours.iter().zip(&theirs) {
                let (a, b): (f64, f64) =
                    (x["force_N"].parse().unwrap(), y["force_N"].parse().unwrap());
                assert!(
                    (a - b).abs() <= 1e-12 * largest,
                    "{name} {solver}: {a} against {b}"
                );
            }
        }
    }
}

/// Bad input: exit 2, the key, the value and the fix.
#[test]
fn bad_combinations_are_refused_with_their_key() {
    let case_g = "[[load.cases]]\nname = \"G\"\nnodal = [0.0, 0.0, -40.0]\n";
    let cases: [(String, &[&str]); 8] = [
        (
            format!("{case_g}[[load.combinations]]\nname = \"U\"\nfactors = {{ G = 1.35, W = 1.5 }}\n"),
            &["load.combinations[0].factors.W", "no load case is named `W`", "G"],
        ),
        (
            format!("{case_g}[[load.combinations]]\nname = \"U\"\nfactors = {{ G = inf }}\n"),
            &["load.combinations[0].factors.G", "finite factor"],
        ),
        (
            format!("{case_g}[[load.cases]]\nname = \"G\"\n"),
            &["load.cases[1].name", "\"G\"", "another entry has this name"],
        ),
        (
            format!("nodal = [0.0, 0.0, -1.0]\n{case_g}"),
            &["`load`", "move `load.nodal`"],
        ),
        (
            "[[load.combinations]]\nname = \"U\"\nfactors = { G = 1.0 }\n".to_string(),
            &["load.combinations[0]", "[[load.cases]]"],
        ),
        (
            "[[load.cases]]\nname = \"prestress\"\n".to_string(),
            &["load.cases[0].name", "names the prestress's factor"],
        ),
        (
            format!("{case_g}[[load.combinations]]\nname = \"U\"\nfactors = {{ G = 1.0, prestress = -1.0 }}\n"),
            &["load.combinations[0].factors.prestress", "≥ 0"],
        ),
        (
            format!("{case_g}[[load.combinations]]\nname = \"a/b\"\nfactors = {{ G = 1.0 }}\n"),
            &["load.combinations[0].name", "\"a/b\"", "letters, digits"],
        ),
    ];
    for (k, (load, expected)) in cases.iter().enumerate() {
        let dir = Temp::dir(&format!("comb-bad-{k}"));
        std::fs::create_dir_all(&dir.0).unwrap();
        let case = dir.0.join("case.toml");
        std::fs::write(&case, format!("{GRID}{load}")).unwrap();
        let o = tensolve(&["check", case.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "case {k}: {err}");
        for piece in *expected {
            assert!(err.contains(piece), "case {k}: `{piece}` not in {err}");
        }
    }
}

/// The shipped worked example (`cases/tower-combinations.toml`, `large`): its ULS combination
/// (1.35 G + 1.5 W + T) is the plain run of those loads, and its `prestress-loss` combination
/// the plain run with every member's prestress at 0.8 of the table's.
#[test]
fn the_shipped_tower_combinations_are_their_plain_runs() {
    let dir = Temp::dir("comb-tower");
    std::fs::create_dir_all(dir.0.join("tower")).unwrap();
    let members =
        std::fs::read_to_string(common::manifest_path("cases/tower/members.csv")).unwrap();
    std::fs::copy(
        common::manifest_path("cases/tower/nodes.csv"),
        dir.0.join("tower/nodes.csv"),
    )
    .unwrap();
    std::fs::write(dir.0.join("tower/members.csv"), &members).unwrap();
    // The same table with every prestress × 0.8 (the f64 product, written round-trip).
    let mut lines = members.lines();
    let mut scaled = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        let t0: f64 = cells[6].parse().unwrap();
        cells[6] = format!("{:?}", t0 * 0.8);
        scaled.push_str(&format!("{}\n", cells.join(",")));
    }
    std::fs::write(dir.0.join("tower/scaled.csv"), &scaled).unwrap();
    let shipped =
        std::fs::read_to_string(common::manifest_path("cases/tower-combinations.toml")).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(&case, &shipped).unwrap();
    let out = Temp::dir("comb-tower-out");
    let o = tensolve(&["run", case.to_str().unwrap(), "--out", out.arg(), "--quiet"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let head = shipped.split("[[load.cases]]").next().unwrap();
    let g = [0.0, 0.0, -100.0f64];
    let w = [500.0, 866.0, 0.0f64];
    let point = |f: [f64; 3], k: f64| {
        format!(
            "[[load.point]]\nnodes = [15, 16, 17]\nforce = [{:?}, {:?}, {:?}]\n",
            k * f[0],
            k * f[1],
            k * f[2]
        )
    };
    let uls = format!(
        "{head}{}{}[[load.temperature]]\nkind = \"cable\"\nchange = -10.0\nexpansion = 1.2e-5\n",
        point(g, 1.35),
        point(w, 1.5)
    );
    let loss = format!("{head}{}{}", point(g, 1.0), point(w, 1.0))
        .replace("tower/members.csv", "tower/scaled.csv");
    for (name, text) in [("ULS", uls), ("prestress-loss", loss)] {
        let plain = dir.0.join(format!("{name}.toml"));
        std::fs::write(&plain, text).unwrap();
        let plain_out = Temp::dir(&format!("comb-tower-{name}"));
        let o = tensolve(&[
            "run",
            plain.to_str().unwrap(),
            "--out",
            plain_out.arg(),
            "--quiet",
        ]);
        assert_eq!(code(&o), 0, "{name}: {}", stderr(&o));
        for alpha in ["0.5", "1"] {
            let ours = file(
                &out.0.join("combinations").join(name),
                "forces",
                "newton",
                alpha,
            );
            let theirs = file(&plain_out.0, "forces", "newton", alpha);
            for (x, y) in ours.iter().zip(&theirs) {
                let (a, b): (f64, f64) =
                    (x["force_N"].parse().unwrap(), y["force_N"].parse().unwrap());
                assert!(
                    (a - b).abs() <= 1e-12 * 4e3,
                    "{name} α {alpha}: {a} against {b}"
                );
            }
        }
    }
}

/// `check` names the load cases and the combinations, and says how they are solved.
#[test]
fn check_names_the_cases_and_combinations() {
    let o = tensolve(&[
        "check",
        common::manifest_path("cases/tower-combinations.toml")
            .to_str()
            .unwrap(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("load cases      G, W, T"), "{text}");
    assert!(
        text.contains("combinations    ULS, SLS, prestress-loss: each solved on its own"),
        "{text}"
    );
}

/// `checks.forbid_slack`: every slack cable of a combination's answer is a row of its
/// `checks.csv` (as many as its summary's `slack_cables`, members whose force is 0), and
/// a combination with none writes no file.
#[test]
fn forbidden_slack_is_listed_per_combination() {
    let text = "[grid]\nmodules = [8, 8]\n[model]\ngeometry = \"linear\"\n\
                [solver]\nmethods = [\"newton\"]\n[load]\nalpha = [1.0]\n\
                [checks]\nforbid_slack = true\n\
                [[load.cases]]\nname = \"G\"\nnodal = [0.0, 0.0, -40.0]\n\
                [[load.combinations]]\nname = \"heavy\"\nfactors = { G = 2.5 }\n\
                [[load.combinations]]\nname = \"light\"\nfactors = { G = 0.1 }\n";
    let (_d, out) = run("comb-slack", text);
    let heavy = out.0.join("combinations/heavy");
    let listed = csv_rows(&heavy.join("checks.csv"));
    let slack = csv_rows(&heavy.join("summary.csv"))[0]["slack_cables"]
        .parse::<usize>()
        .unwrap();
    assert!(slack > 0);
    assert_eq!(listed.len(), slack);
    let forces = file(&heavy, "forces", "newton", "1");
    for row in &listed {
        assert_eq!(row["clause"], "slack (checks.forbid_slack)");
        let t = forces
            .iter()
            .find(|t| t["member"] == row["member"])
            .unwrap();
        assert_eq!(t["force_N"].parse::<f64>().unwrap(), 0.0, "{row:?}");
    }
    assert!(!out.0.join("combinations/light/checks.csv").exists());
}

/// A load case's support settlement (`[[load.cases.settlement]]`) under its factor equals the
/// plain run whose `[[supports.fix]]` prescribes that displacement (the shipped skew grid,
/// `linear`, its node 34 sinking 1.5 × 2 mm): forces to 1e-12 of the largest, which the
/// settlement changes. A settlement of a component no support holds is refused.
#[test]
fn a_settlement_case_is_the_plain_run_with_that_support_moved() {
    let tables = common::manifest_path("cases/skew-grid");
    let head = format!(
        "[structure]\nnodes = \"{0}/nodes.csv\"\nmembers = \"{0}/members.csv\"\n\
         [model]\ngeometry = \"linear\"\n[solver]\nmethods = [\"newton\"]\n\
         [load]\nalpha = [1.0]\n\
         [[supports.fix]]\nnodes = [0, 7, 14, 21, 28]\n\
         [[supports.fix]]\nnodes = [6, 13, 20, 27]\ndofs = [\"z\"]\n",
        tables.display()
    );
    let point = "nodes = [40, 58]\nforce = [0.0, 500.0, -2000.0]\n";
    let combined = format!(
        "{head}[[supports.fix]]\nnodes = [34]\ndofs = [\"z\"]\n\
         [[load.cases]]\nname = \"W\"\n[[load.cases.point]]\n{point}\
         [[load.cases]]\nname = \"S\"\n[[load.cases.settlement]]\nnodes = [34]\n\
         displacement = [0.0, 0.0, -0.002]\n\
         [[load.combinations]]\nname = \"WS\"\nfactors = {{ W = 1.0, S = 1.5 }}\n"
    );
    let (_d, out) = run("comb-settle", &combined);
    let plain = |settlement: f64| {
        format!(
            "{head}[[supports.fix]]\nnodes = [34]\ndofs = [\"z\"]\n\
             displacement = [0.0, 0.0, {settlement:?}]\n[[load.point]]\n{point}"
        )
    };
    let (_p, plain_out) = run("comb-settle-plain", &plain(1.5 * -0.002));
    let (_n, unsettled_out) = run("comb-settle-none", &plain(0.0));
    let ours = file(&out.0.join("combinations/WS"), "forces", "newton", "1");
    let theirs = file(&plain_out.0, "forces", "newton", "1");
    let unsettled = file(&unsettled_out.0, "forces", "newton", "1");
    let force = |r: &HashMap<String, String>| r["force_N"].parse::<f64>().unwrap();
    let largest = theirs.iter().map(|r| force(r).abs()).fold(0.0, f64::max);
    let moved = (theirs.iter().zip(&unsettled))
        .map(|(a, b)| (force(a) - force(b)).abs())
        .fold(0.0, f64::max);
    assert!(
        moved > 1e-3 * largest,
        "the settlement moves nothing: {moved}"
    );
    for (x, y) in ours.iter().zip(&theirs) {
        assert!(
            (force(x) - force(y)).abs() <= 1e-12 * largest,
            "{x:?} against {y:?}"
        );
    }
    // A settlement of node 34's x component, which no support holds.
    let dir = Temp::dir("comb-settle-free");
    std::fs::create_dir_all(&dir.0).unwrap();
    let case = dir.0.join("case.toml");
    let bad = combined.replace("[0.0, 0.0, -0.002]", "[0.001, 0.0, -0.002]");
    std::fs::write(&case, bad).unwrap();
    let o = tensolve(&["check", case.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(code(&o), 2, "{err}");
    assert!(
        err.contains("load.cases[1].settlement[0].displacement")
            && err.contains("node 34's x component is not held"),
        "{err}"
    );
}

/// A designed tower (`cases/tower2-design.toml`: its prestress designed for bar targets,
/// `prestress.from = "design"`) under `large`: a combination 1.35 G + 1.5 W (W the shipped
/// point load, G its top nodes' weight) equals the plain run of the same loads written as one
/// pattern, forces and displacements to 1e-12, every α.
#[test]
fn a_combination_on_a_designed_tower_is_its_plain_run() {
    let tables = common::manifest_path("cases/tower2-design");
    let head = format!(
        "[structure]\nnodes = \"{0}/nodes.csv\"\nmembers = \"{0}/members.csv\"\n\
         [[supports.fix]]\nnodes = [0, 1, 2]\n\
         [prestress]\nfrom = \"design\"\ntargets = {{ bars0 = -3000.0, bars1 = -2000.0 }}\n\
         [model]\ngeometry = \"large\"\n[solver]\nmethods = [\"newton\"]\n\
         [load]\nalpha = [0.5, 1.0]\n",
        tables.display()
    );
    let (g, w) = ([0.0, 0.0, -100.0], [200.0, 0.0, -500.0]);
    let combined = format!(
        "{head}[[load.cases]]\nname = \"G\"\n[[load.cases.point]]\nnodes = [9, 10, 11]\n\
         force = {g:?}\n[[load.cases]]\nname = \"W\"\n[[load.cases.point]]\n\
         nodes = [9, 10, 11]\nforce = {w:?}\n\
         [[load.combinations]]\nname = \"ULS\"\nfactors = {{ G = 1.35, W = 1.5 }}\n"
    );
    let (_d, out) = run("comb-designed", &combined);
    let sum: Vec<f64> = (0..3).map(|k| 1.35 * g[k] + 1.5 * w[k]).collect();
    let plain = format!(
        "{head}[[load.point]]\nnodes = [9, 10, 11]\nforce = [{:?}, {:?}, {:?}]\n",
        sum[0], sum[1], sum[2]
    );
    let (_p, plain_out) = run("comb-designed-plain", &plain);
    let sub = out.0.join("combinations/ULS");
    for alpha in ["0.5", "1"] {
        for (kind, column) in [("forces", "force_N"), ("displacements", "uz")] {
            let ours = file(&sub, kind, "newton", alpha);
            let theirs = file(&plain_out.0, kind, "newton", alpha);
            let value = |r: &HashMap<String, String>| r[column].parse::<f64>().unwrap();
            let largest = theirs.iter().map(|r| value(r).abs()).fold(0.0, f64::max);
            assert!(largest > 0.0, "{kind} α {alpha}");
            for (x, y) in ours.iter().zip(&theirs) {
                assert!(
                    (value(x) - value(y)).abs() <= 1e-12 * largest,
                    "{kind} α {alpha}: {x:?} against {y:?}"
                );
            }
        }
    }
}
