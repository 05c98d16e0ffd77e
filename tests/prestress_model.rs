//! The `prestress` model (docs/method.md §8) as the linearisation about the prestressed state,
//! and what `check` and the refusals say about it (issue 42: T2, D4, D6, T6, T8, T9, D11).

mod common;

use common::{manifest_path, stderr, tensolve, Temp};
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;
use std::path::Path;

fn read_csv(path: &Path) -> Vec<HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            header
                .iter()
                .cloned()
                .zip(rec.unwrap().iter().map(String::from))
                .collect()
        })
        .collect()
}

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
    let nodes = read_csv(&table("nodes"));
    let members = read_csv(&table("members"));
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
    let rows = read_csv(&out.0.join("summary.csv"));
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
            let got = read_csv(
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
