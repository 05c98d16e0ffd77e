//! The `prestress` model (docs/method.md §8) as the linearisation about the prestressed state,
//! and what `check` and the refusals say about it (issue 42: T2, D4, D6, T6, T8, T9, D11).

mod common;

use common::{csv_rows, manifest_path, stderr, tensolve, Temp};
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;
use std::path::Path;

fn number(row: &HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?} is not a number", row[key]))
}

/// The linearisation about the prestressed state written from docs/method.md §8 alone, dense:
/// `(K + K_G(t0)) U = α F` on the whole U with U_d the prescribed displacements, solved for the
/// free components (every cable taut), from the case file and its tables. Per node id, U.
fn independent_linearisation(case: &Path, alpha: f64) -> HashMap<String, [f64; 3]> {
    let text = std::fs::read_to_string(case).unwrap();
    let c: toml::Value = toml::from_str(&text).unwrap();
    let base = case.parent().unwrap();
    let table = |key: &str| base.join(c["structure"][key].as_str().unwrap());
    let nodes = csv_rows(&table("nodes"));
    let members = csv_rows(&table("members"));
    let index: HashMap<String, usize> = nodes
        .iter()
        .enumerate()
        .map(|(i, r)| (r["node"].clone(), i))
        .collect();
    let x: Vec<[f64; 3]> = nodes
        .iter()
        .map(|r| [number(r, "x"), number(r, "y"), number(r, "z")])
        .collect();
    let n = 3 * nodes.len();
    let as_f = |v: &toml::Value| {
        v.as_float()
            .unwrap_or_else(|| v.as_integer().unwrap() as f64)
    };
    let (mut held, mut ud) = (vec![false; n], vec![0.0; n]);
    for fix in c["supports"]["fix"].as_array().unwrap() {
        let dofs: Vec<usize> = match fix.get("dofs") {
            Some(d) => d
                .as_array()
                .unwrap()
                .iter()
                .map(|s| "xyz".find(s.as_str().unwrap()).unwrap())
                .collect(),
            None => vec![0, 1, 2],
        };
        for node in fix["nodes"].as_array().unwrap() {
            let v = index[&node.as_integer().unwrap().to_string()];
            for &k in &dofs {
                held[3 * v + k] = true;
                if let Some(d) = fix.get("displacement") {
                    ud[3 * v + k] = as_f(&d.as_array().unwrap()[k]);
                }
            }
        }
    }
    let mut f = vec![0.0; n];
    if let Some(nodal) = c["load"].get("nodal") {
        for (i, fi) in f.iter_mut().enumerate() {
            if !held[i] {
                *fi += as_f(&nodal.as_array().unwrap()[i % 3]);
            }
        }
    }
    for point in c["load"]["point"].as_array().unwrap() {
        let force = point["force"].as_array().unwrap();
        for node in point["nodes"].as_array().unwrap() {
            let v = index[&node.as_integer().unwrap().to_string()];
            for k in 0..3 {
                f[3 * v + k] += as_f(&force[k]);
            }
        }
    }
    // Per member [[G, −G], [−G, G]], G = k n nᵀ + (t0/L)(I − n nᵀ).
    let mut t = DMatrix::<f64>::zeros(n, n);
    for m in &members {
        let (a, b) = (index[&m["a"]], index[&m["b"]]);
        let d: Vec<f64> = (0..3).map(|k| x[b][k] - x[a][k]).collect();
        let length = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let u: Vec<f64> = d.iter().map(|v| v / length).collect();
        let k = number(m, "young") * number(m, "section") / length;
        let w = number(m, "prestress") / length;
        for (p, sp) in [(a, -1.0), (b, 1.0)] {
            for (q, sq) in [(a, -1.0), (b, 1.0)] {
                for i in 0..3 {
                    for j in 0..3 {
                        let identity = if i == j { 1.0 } else { 0.0 };
                        t[(3 * p + i, 3 * q + j)] +=
                            sp * sq * (k * u[i] * u[j] + w * (identity - u[i] * u[j]));
                    }
                }
            }
        }
    }
    let free: Vec<usize> = (0..n).filter(|&i| !held[i]).collect();
    let tff = DMatrix::from_fn(free.len(), free.len(), |i, j| t[(free[i], free[j])]);
    let rhs = DVector::from_fn(free.len(), |i, _| {
        alpha * f[free[i]]
            - (0..n)
                .filter(|&j| held[j])
                .map(|j| t[(free[i], j)] * ud[j])
                .sum::<f64>()
    });
    let solution = tff
        .lu()
        .solve(&rhs)
        .expect("K + K_G regular on the free dofs");
    let mut full = ud;
    for (i, &d) in free.iter().enumerate() {
        full[d] = solution[i];
    }
    nodes
        .iter()
        .enumerate()
        .map(|(v, r)| {
            (
                r["node"].clone(),
                [full[3 * v], full[3 * v + 1], full[3 * v + 2]],
            )
        })
        .collect()
}

/// T2: `prestress` with a settlement (cases/skew-grid.toml, 5 mm at node 34) is the
/// linearisation `(K + K_G(t0)) U = F` on the whole U: every solver's answer agrees with the
/// independent dense one to 1e-8 of the largest displacement (before, 19–22 % off: the geometric
/// coupling `K_G,fd(t0) U_d` of the free nodes to the moved support was left out, and K_G was
/// taken at `t0 + k e_p`).
#[test]
fn prestress_with_a_settlement_is_the_linearisation_on_the_whole_displacement() {
    let case = manifest_path("cases/skew-grid.toml");
    let out = Temp::dir("t2-skew-prestress");
    let run = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.arg(),
        "--quiet",
        "--set",
        "model.geometry=\"prestress\"",
        "--set",
        "solver.subdomains=[1,1]",
        "--set",
        "load.alpha=[0.25, 0.5]",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let rows = csv_rows(&out.0.join("summary.csv"));
    assert_eq!(rows.len(), 8);
    for row in &rows {
        assert_eq!(
            row["status"], "converged",
            "{} at {}",
            row["solver"], row["alpha"]
        );
        assert_eq!(
            row["slack_cables"], "0",
            "the independent check has every cable taut"
        );
    }
    for alpha in ["0.25", "0.5"] {
        let want = independent_linearisation(&case, alpha.parse().unwrap());
        let size = want
            .values()
            .flat_map(|u| u.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for solver in ["newton", "pcg-lcp", "mono-latin", "micro-macro"] {
            let got = csv_rows(
                &out.0
                    .join(format!("displacements/{solver}_alpha{alpha}.csv")),
            );
            assert_eq!(got.len(), want.len());
            let worst = got.iter().fold(0.0f64, |m, r| {
                let w = want[&r["node"]];
                ["ux", "uy", "uz"]
                    .iter()
                    .zip(w)
                    .fold(m, |m, (k, wk)| m.max((number(r, k) - wk).abs()))
            });
            assert!(
                worst <= 1e-8 * size,
                "{solver} at alpha = {alpha}: {worst:e} m off the linearisation (largest {size:e} m)"
            );
        }
    }
}

/// A case directory with `nodes.csv`, `members.csv` and `case.toml` (its `[structure]` naming
/// the two tables, then `rest`).
fn case_dir(tag: &str, nodes: &str, members: &str, rest: &str) -> Temp {
    let dir = Temp::dir(tag);
    std::fs::create_dir_all(&dir.0).unwrap();
    std::fs::write(dir.0.join("nodes.csv"), nodes).unwrap();
    std::fs::write(dir.0.join("members.csv"), members).unwrap();
    std::fs::write(
        dir.0.join("case.toml"),
        format!("[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n{rest}"),
    )
    .unwrap();
    dir
}

fn case_file(dir: &Temp) -> String {
    dir.0.join("case.toml").to_str().unwrap().to_string()
}

/// The shipped simplex (cases/simplex.toml's tables and supports), its members' `young`
/// multiplied by `young` and their prestress by `prestress`.
fn scaled_simplex(tag: &str, young: f64, prestress: f64) -> Temp {
    let nodes = std::fs::read_to_string(manifest_path("cases/simplex/nodes.csv")).unwrap();
    let members = csv_rows(&manifest_path("cases/simplex/members.csv"));
    let mut table = String::from("member,a,b,kind,young,section,prestress\n");
    for m in &members {
        table.push_str(&format!(
            "{},{},{},{},{:e},{},{:e}\n",
            m["member"],
            m["a"],
            m["b"],
            m["kind"],
            number(m, "young") * young,
            m["section"],
            number(m, "prestress") * prestress
        ));
    }
    let case = std::fs::read_to_string(manifest_path("cases/simplex.toml")).unwrap();
    // The case's own sections after [structure], whose table paths are replaced.
    let rest: String = case
        .lines()
        .filter(|l| {
            !l.starts_with("nodes = \"") && !l.starts_with("members = \"") && *l != "[structure]"
        })
        .map(|l| format!("{l}\n"))
        .collect();
    case_dir(tag, &nodes, &table, &rest)
}

fn output_text(o: &std::process::Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(o))
}

/// D4: E in GPa (the simplex's E divided by 1e9) under `prestress` and `large` is refused
/// naming the unit slip: the prestress strain t0/(E·S) and the units, not only "the prestress
/// does not stiffen"; `check` warns of it too.
#[test]
fn young_modulus_in_gpa_is_refused_as_a_unit_slip() {
    let dir = scaled_simplex("d4-gpa", 1e-9, 1.0);
    for model in ["prestress", "large"] {
        let out = Temp::dir(&format!("d4-{model}"));
        let run = tensolve(&[
            "run",
            &case_file(&dir),
            "--out",
            out.arg(),
            "--quiet",
            "--set",
            &format!("model.geometry=\"{model}\""),
        ]);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{model}: {err}");
        assert!(
            err.contains("t0/(E·S)") && err.contains("unit slip") && err.contains("not GPa"),
            "{model}: {err}"
        );
    }
    let check = tensolve(&[
        "check",
        &case_file(&dir),
        "--set",
        "model.geometry=\"prestress\"",
    ]);
    let text = output_text(&check);
    assert!(
        text.contains("warning: member") && text.contains("t0/(E·S)"),
        "{text}"
    );
}

/// T6: `check` never says "solvable" of a case it then refuses: the simplex with its
/// prestress scaled by 1e-9 (a stiffening too small for f64 beside E·S) and by 1e6 (a unit
/// slip: bars that buckle under it) is prestress-stable in its mechanism, but `K + K_G(t0)` is not positive
/// definite, and the output says which.
#[test]
fn check_says_solvable_only_of_what_it_does_not_refuse() {
    for (tag, scale, why) in [
        ("t6-tiny", 1e-9, "too little to tell from a zero mode"),
        // Bars at −4.9e9 N: a prestress strain t0/(E·S) of 6.3e2, a unit slip.
        ("t6-huge", 1e6, "t0/(E·S) is 6.3e2"),
    ] {
        let dir = scaled_simplex(tag, 1.0, scale);
        for model in ["linear", "prestress"] {
            let check = tensolve(&[
                "check",
                &case_file(&dir),
                "--set",
                &format!("model.geometry=\"{model}\""),
            ]);
            let text = output_text(&check);
            assert_eq!(check.status.code(), Some(2), "{tag} {model}: {text}");
            assert!(!text.contains("solvable with"), "{tag} {model}: {text}");
            assert!(
                text.contains("K + K_G(t0) is not positive definite") && text.contains(why),
                "{tag} {model}: {text}"
            );
        }
    }
}

/// T9: `check` prints one m: on a 40 × 1 grid held on its lower x edges (78 mechanisms, more
/// than the sparse count's 64) the counts line and the prestress-stability line agree.
#[test]
fn check_prints_one_count_of_mechanisms() {
    let case = Temp::file(
        "t9-strip",
        "[grid]\nmodules = [40, 1]\n[supports]\nclamp = \"lower-x-edges\"\n[load]\nalpha = [1]\n\
         [model]\ngeometry = \"linear\"\n",
    );
    let check = tensolve(&["check", case.arg()]);
    let text = output_text(&check);
    assert!(text.contains(", 78 mechanism(s)"), "{text}");
    assert!(text.contains("has 78 zero-stiffness mode(s)"), "{text}");
    assert!(
        !text.contains("64 mechanism") && !text.contains("64 zero"),
        "{text}"
    );
}

/// T8: the simplex with no equilibrium at tiny and large α is said to have none (status
/// `no_equilibrium`, naming the slack cables), never "beyond the model … a unit slip": newton
/// at every α (before: beyond the model at 1e-12 and 1e-6, its runaway's `B U` all round-off),
/// pcg-lcp at 1 and 1e3 (before: beyond the model at 1e3, its iterate no mechanism while its
/// slack set leaves one). pcg-lcp at tiny α stops on iterates that lengthen the diagonals
/// (issue 42, T3's).
#[test]
fn no_equilibrium_at_any_alpha_is_not_beyond_the_model() {
    for (solver, alphas, rows_expected) in [
        ("newton", "[1e-12, 1e-9, 1e-6, 1.0, 1e3]", 5),
        ("pcg-lcp", "[1.0, 1e3]", 2),
    ] {
        let out = Temp::dir(&format!("t8-noeq-{solver}"));
        let run = tensolve(&[
            "run",
            manifest_path("cases/simplex-no-equilibrium.toml")
                .to_str()
                .unwrap(),
            "--out",
            out.arg(),
            "--quiet",
            "--solver",
            solver,
            "--set",
            &format!("load.alpha={alphas}"),
        ]);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{err}");
        let rows = csv_rows(&out.0.join("summary.csv"));
        assert_eq!(rows.len(), rows_expected, "{err}");
        for row in &rows {
            assert_eq!(
                row["status"], "no_equilibrium",
                "{solver} at {}: {err}",
                row["alpha"]
            );
        }
        assert!(
            !err.contains("beyond the model") && !err.contains("unit slip"),
            "{err}"
        );
        assert!(err.contains("cable(s) 90, 91, 92 slack"), "{err}");
    }
}

/// Three members from clamped nodes 0, 1, 2 to node 3 above them: s = 0, m = 0.
const TRIPOD_NODES: &str = "node,x,y,z\n0,0,0,0\n1,2,0,0\n2,1,1.7,0\n3,1,0.6,1.5\n";

/// The tripod with members 0 and 1 bars and member 2 (from node 2) of `kind`.
fn tripod(tag: &str, kind: &str, rest: &str) -> Temp {
    let members: String = (0..3)
        .map(|i| {
            let kind = if i == 2 { kind } else { "bar" };
            format!("{i},{i},3,{kind},2.1e11,1e-4,0\n")
        })
        .collect();
    case_dir(
        tag,
        TRIPOD_NODES,
        &format!("member,a,b,kind,young,section,prestress\n{members}"),
        // The linear model's refusals and advice (`auto` would move on to `large`).
        &format!("[model]\ngeometry = \"linear\"\n[[supports.fix]]\nnodes = [0, 1, 2]\n{rest}"),
    )
}

/// D11: the failure lines advise what can be done: `prestress.from = "self-stress"` on a
/// structure with no self-stress state (s = 0) does not advise a table prestress (none
/// balances); a no equilibrium there does not advise prestressing its cables; a missing column
/// says `density` is optional; a mechanism that is a rigid rotation is named so.
#[test]
fn advice_names_only_what_the_structure_allows() {
    // prestress.from with s = 0.
    let dir = tripod(
        "d11-from-s0",
        "bar",
        "[prestress]\nfrom = \"self-stress\"\nmember = 0\nforce = 100.0\n[load]\nalpha = [1.0]\n",
    );
    let check = tensolve(&["check", &case_file(&dir)]);
    let err = stderr(&check);
    assert_eq!(check.status.code(), Some(2), "{err}");
    assert!(err.contains("s = 0"), "{err}");
    assert!(
        !err.contains("give each member's prestress in the members table"),
        "{err}"
    );
    // No equilibrium with s = 0: the load pushes node 3 towards node 2, the cable slackens,
    // and node 3 turns about the line of the bars' feet.
    let dir = tripod(
        "d11-noeq-s0",
        "cable",
        "[[load.point]]\nnodes = [3]\nforce = [0.0, 1000.0, 0.0]\n[load]\nalpha = [1.0]\n\
         [solver]\nmethods = [\"newton\", \"pcg-lcp\"]\n",
    );
    let out = Temp::dir("d11-noeq-out");
    let run = tensolve(&["run", &case_file(&dir), "--out", out.arg(), "--quiet"]);
    let err = stderr(&run);
    assert!(err.contains("no equilibrium"), "{err}");
    assert!(!err.contains("prestress those cables"), "{err}");
    assert!(err.contains("no self-stress state"), "{err}");
    // A members table without its prestress column.
    let dir = case_dir(
        "d11-column",
        TRIPOD_NODES,
        "member,a,b,kind,young,section\n0,0,3,bar,2.1e11,1e-4\n",
        "[[supports.fix]]\nnodes = [0, 1, 2]\n[load]\nalpha = [1.0]\n",
    );
    let check = tensolve(&["check", &case_file(&dir)]);
    let err = stderr(&check);
    assert_eq!(check.status.code(), Some(2), "{err}");
    assert!(
        err.contains(
            "`member,a,b,kind,young,section,prestress`, optionally followed by `,density`"
        ),
        "{err}"
    );
    // A rigid tetrahedron of bars held at nodes 0 and 1 only: it turns about the line 0–1.
    let members: String = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
        .iter()
        .enumerate()
        .map(|(i, (a, b))| format!("{i},{a},{b},bar,2.1e11,1e-4,0\n"))
        .collect();
    let dir = case_dir(
        "d11-rotation",
        TRIPOD_NODES,
        &format!("member,a,b,kind,young,section,prestress\n{members}"),
        "[[supports.fix]]\nnodes = [0, 1]\n[load]\nalpha = [1.0]\n",
    );
    let check = tensolve(&["check", &case_file(&dir)]);
    let text = output_text(&check);
    assert_eq!(check.status.code(), Some(2), "{text}");
    assert!(
        text.contains("a rigid-body rotation about the axis through")
            && text.contains("along (1.00, 0.00, 0.00)"),
        "{text}"
    );
}

/// D11: E in GPa on the paper grid under `linear` moves nodes by 2.4e8 m: both rows are
/// refused as beyond the model, naming the unit slip first (the prestress strain), and the
/// geometric-term warning, which counts converged rows only, does not quote them (before:
/// "changes the answer by … up to 13671045077.5 %").
#[test]
fn refused_rows_are_not_quoted_by_the_geometric_term_warning() {
    let out = Temp::dir("d11-gpa-grid");
    let run = tensolve(&[
        "run",
        manifest_path("cases/paper-exact.toml").to_str().unwrap(),
        "--out",
        out.arg(),
        "--set",
        "cables.young=100",
        "--set",
        "bars.young=200",
        "--set",
        "load.alpha=[1.0]",
    ]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("beyond the model"), "{err}");
    let (slip, load) = (
        err.find("unit slip").expect("names the unit slip"),
        err.find("too large for it").unwrap_or(usize::MAX),
    );
    assert!(slip < load, "{err}");
    assert!(!err.contains("leave out a geometric term"), "{err}");
}

/// D6: a guyed mast (10 m bar, three guys at 10 kN) under a wind at its top slackens its two
/// leeward guys at α = 2 and 4; bar and windward guy then leave a neutral mechanism (a turn
/// about the line through the foot and the anchor: `large` reports 0 N/m). With `prestress`
/// the tangent judging the answer has the geometric stiffness of its own tensions, the slack
/// guys' none: 0 N/m, converged, in every solver (before: K_G(t0) with the slack guys' share,
/// −340 N/m, `unstable`).
#[test]
fn slack_cables_carry_no_geometric_stiffness() {
    let nodes = "node,x,y,z\n0,0.0,0.0,0.0\n1,0.0,0.0,10.0\n2,-6.0,0.0,0.0\n\
                 3,3.0,-5.196152422706632,0.0\n4,3.0,5.196152422706632,0.0\n";
    let members = "member,a,b,kind,young,section,prestress\n\
                   0,0,1,bar,2.1e11,2.0e-3,-25724.787771376323\n\
                   1,1,2,cable,1.5e11,1.0e-4,10000.0\n\
                   2,1,3,cable,1.5e11,1.0e-4,10000.0\n\
                   3,1,4,cable,1.5e11,1.0e-4,10000.0\n";
    let dir = case_dir(
        "d6-mast",
        nodes,
        members,
        "[[supports.fix]]\nnodes = [0, 2, 3, 4]\n\
         [[load.point]]\nnodes = [1]\nforce = [10000.0, 0.0, 0.0]\n\
         [load]\nalpha = [1.0, 2.0, 4.0]\n[model]\ngeometry = \"prestress\"\n\
         [solver]\nmethods = [\"newton\", \"pcg-lcp\", \"mono-latin\", \"micro-macro\"]\n",
    );
    let out = Temp::dir("d6-mast-out");
    let run = tensolve(&["run", &case_file(&dir), "--out", out.arg(), "--quiet"]);
    let err = stderr(&run);
    let rows = csv_rows(&out.0.join("summary.csv"));
    assert_eq!(rows.len(), 12, "{err}");
    for row in &rows {
        let (alpha, status) = (&row["alpha"], &row["status"]);
        assert_eq!(status, "converged", "{} at {alpha}: {err}", row["solver"]);
        let eigenvalue = number(row, "min_tangent_eigenvalue");
        if alpha == "1" {
            assert_eq!(row["slack_cables"], "0");
            assert!(eigenvalue > 1e5, "{eigenvalue}");
        } else {
            assert_eq!(row["slack_cables"], "2");
            assert_eq!(eigenvalue, 0.0, "{} at {alpha}", row["solver"]);
        }
    }
}
