//! pcg-lcp's stop (issue 42): no equilibrium said as such, never as non-finite values (D2); a
//! stop relative to the load's tensions, not the prestress (T3); a history never a header
//! alone (M11).

mod common;

use common::{code, manifest_path, stderr, summary_rows, tensolve, Temp};

/// `tensolve run case --out dir` with the overrides.
fn run(case: &str, out: &Temp, sets: &[&str]) -> std::process::Output {
    let mut args = vec!["run", case, "--out", out.arg(), "--quiet"];
    for s in sets {
        args.extend(["--set", s]);
    }
    tensolve(&args)
}

/// A sign bracket (a strut pinned to a wall, its tip hung from two stays) under uplift: the
/// stays go slack and the strut swings up without bound. pcg-lcp's proportioning step meets
/// `βᵀW̃β = 0` there; it wrote non-finite values and no row (issue 42, D2).
#[test]
fn pcg_lcp_says_no_equilibrium_where_the_stays_go_slack() {
    let dir = Temp::dir("bracket");
    std::fs::create_dir_all(&dir.0).unwrap();
    std::fs::write(
        dir.0.join("nodes.csv"),
        "node,x,y,z\n0,0.0,0.0,0.0\n1,2.0,0.0,0.0\n2,0.0,0.8,1.0\n3,0.0,-0.8,1.0\n",
    )
    .unwrap();
    std::fs::write(
        dir.0.join("members.csv"),
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,2.1e11,4.0e-4,0.0\n\
         1,1,2,cable,1.2e11,7.85e-5,0.0\n2,1,3,cable,1.2e11,7.85e-5,0.0\n",
    )
    .unwrap();
    let case = dir.0.join("bracket.toml");
    std::fs::write(
        &case,
        "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
         [[supports.fix]]\nnodes = [0, 2, 3]\n\
         [[load.point]]\nnodes = [1]\nforce = [0.0, 0.0, 1000.0]\n\
         [load]\nalpha = [0.5, 1.0]\n[model]\ngeometry = \"linear\"\n\
         [solver]\nmethods = [\"pcg-lcp\"]\n",
    )
    .unwrap();
    let out = Temp::dir("bracket-out");
    let o = run(case.to_str().unwrap(), &out, &[]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    assert!(!stderr(&o).contains("non-finite"), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no equilibrium: with cable(s) 1, 2 slack"),
        "{}",
        stderr(&o)
    );
    let rows = summary_rows(&out.0);
    assert_eq!(rows.len(), 2);
    for row in &rows {
        assert_eq!(row["status"], "no_equilibrium");
        assert_eq!(row["converged"], "false");
    }
}

/// `simplex-no-equilibrium` has no equilibrium at any α > 0; at α = 1e-10 pcg-lcp said
/// `converged` in 0 iterations (its stop relative to the prestress), exit 0 (issue 42, T3).
#[test]
fn pcg_lcp_finds_no_equilibrium_at_a_tiny_load() {
    let out = Temp::dir("noeq-tiny");
    let case = manifest_path("cases/simplex-no-equilibrium.toml");
    let o = run(
        case.to_str().unwrap(),
        &out,
        &["load.alpha=[1e-10]", "solver.methods=[\"pcg-lcp\"]"],
    );
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let rows = summary_rows(&out.0);
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["status"], "no_equilibrium");
}

/// Below α ≈ 1e-162 the load's entries square to 0: ‖F‖ and pcg-lcp's complementarity
/// residual underflowed, and both exact solvers said `converged` at U = 0 where no equilibrium
/// exists (this session's adversarial pass). `norm` scales what would underflow.
#[test]
fn no_equilibrium_is_found_at_a_load_whose_squares_underflow() {
    let case = manifest_path("cases/simplex-no-equilibrium.toml");
    for alpha in ["1e-165", "1e-300"] {
        let out = Temp::dir("noeq-underflow");
        let o = run(
            case.to_str().unwrap(),
            &out,
            &[
                &format!("load.alpha=[{alpha}]"),
                "solver.methods=[\"newton\", \"pcg-lcp\"]",
            ],
        );
        assert_eq!(code(&o), 1, "{alpha}: {}", stderr(&o));
        let rows = summary_rows(&out.0);
        assert_eq!(rows.len(), 2);
        for row in &rows {
            assert_eq!(row["status"], "no_equilibrium", "{alpha}: {row:?}");
        }
    }
}

/// Below α ≈ 1e-4 no prestressed cable of the braced paper grid goes slack and the answer is
/// homogeneous in α; pcg-lcp's answer at α = 1e-10 was 46 % off that line (issue 42, T3).
#[test]
fn pcg_lcp_is_homogeneous_at_small_load_against_the_prestress() {
    let out = Temp::dir("braced-tiny");
    let case = manifest_path("cases/paper-braced.toml");
    let o = run(
        case.to_str().unwrap(),
        &out,
        &[
            "load.alpha=[1e-5, 1e-10]",
            "solver.methods=[\"pcg-lcp\"]",
            "solver.reference=\"none\"",
        ],
    );
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let rows = summary_rows(&out.0);
    let per_alpha: Vec<f64> = rows
        .iter()
        .map(|r| {
            assert_eq!(r["status"], "converged");
            r["max_deflection"].parse::<f64>().unwrap() / r["alpha"].parse::<f64>().unwrap()
        })
        .collect();
    let off = (per_alpha[1] - per_alpha[0]).abs() / per_alpha[0];
    assert!(
        off < 1e-6,
        "deflection per unit alpha {per_alpha:?}: {off:e} off"
    );
}

/// At α = 0 pcg-lcp's start (λ = 0) is the answer: it stops at iteration 0, and its history
/// said nothing but its header (issue 42, M11).
#[test]
fn a_pcg_lcp_history_that_stops_at_its_start_has_that_row() {
    let out = Temp::dir("history-start");
    let case = manifest_path("cases/paper.toml");
    let o = run(
        case.to_str().unwrap(),
        &out,
        &[
            "load.alpha=[0.0]",
            "solver.methods=[\"pcg-lcp\"]",
            "solver.reference=\"none\"",
        ],
    );
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let history = std::fs::read_dir(out.0.join("history"))
        .unwrap()
        .map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap())
        .collect::<Vec<_>>();
    assert_eq!(history.len(), 1);
    let lines: Vec<&str> = history[0].lines().collect();
    assert_eq!(lines.len(), 2, "{}", history[0]);
    assert!(lines[1].starts_with("0,"), "{}", history[0]);
}
