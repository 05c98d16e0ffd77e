//! `load.path = "arc-length"` (issue 60, item 4): newton on the `large` model follows the
//! equilibrium path through limit points. The von Mises arch's limit load and snapped branch
//! against the closed form; the simplex under 1 MN per top node past its limit point, its
//! answers before the limit equal to load control's, after it on the snapped branch; the
//! `limit_alpha` column under both paths; the refusals; and OpenSees' `ArcLength` as the peer.

mod common;

use common::{code, csv_rows, manifest_path, stderr, tensolve, Temp};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

type Row = HashMap<String, String>;

fn number(row: &Row, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?} is not a number in {row:?}", row[key]))
}

/// A case directory with `case.toml` beside its tables.
fn case_dir(tag: &str, nodes: &str, members: &str, body: &str) -> (Temp, PathBuf) {
    let dir = Temp::dir(tag);
    std::fs::create_dir_all(&dir.0).unwrap();
    std::fs::write(dir.0.join("nodes.csv"), nodes).unwrap();
    std::fs::write(dir.0.join("members.csv"), members).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(&case, body).unwrap();
    (dir, case)
}

/// Run `case` into `out` with `sets`; the process and the summary rows.
fn run(case: &Path, out: &Path, sets: &[&str]) -> (std::process::Output, Vec<Row>) {
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
    let o = tensolve(&args);
    let rows = match out.join("summary.csv").exists() {
        true => csv_rows(&out.join("summary.csv")),
        false => Vec::new(),
    };
    (o, rows)
}

/// The von Mises arch of tests/load_path.rs: two bars (EA = 5.6e7 N) from (±1, 0, 0) to the
/// apex (0, 0, 0.1), 10 kN down on the apex per unit α, on an arc-length path.
fn arch(tag: &str) -> (Temp, PathBuf) {
    case_dir(
        tag,
        "node,x,y,z\n0,-1.0,0.0,0.0\n1,0.0,0.0,0.1\n2,1.0,0.0,0.0\n",
        "member,a,b,kind,young,section,prestress\n\
         0,0,1,bar,200000000000.0,0.00028,0.0\n1,1,2,bar,200000000000.0,0.00028,0.0\n",
        "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n\
         [[supports.fix]]\nnodes = [0, 2]\n[[supports.fix]]\nnodes = [1]\ndofs = [\"y\"]\n\
         [[load.point]]\nnodes = [1]\nforce = [0.0, 0.0, -10000.0]\n\
         [load]\nalpha = [1.0, 2.0, 3.0, 4.0, 5.0]\npath = \"arc-length\"\n\
         [model]\ngeometry = \"large\"\n[solver]\nmethods = [\"newton\"]\n",
    )
}

/// The arch's load factor at apex height w, by the exact-length law: `α = −2 N w / (ℓ 10⁴)`,
/// `N = EA (ℓ − L) / L`, `ℓ = √(1 + w²)` (an independent computation).
fn arch_alpha(w: f64) -> f64 {
    let (ea, length) = (2e11 * 2.8e-4, 1.01f64.sqrt());
    let l = (1.0 + w * w).sqrt();
    -2.0 * ea * (l - length) / length * w / l / 1e4
}

/// The arch's limit load: the maximum of α over w in (0, 0.1), by golden-section search.
fn arch_limit() -> f64 {
    let (mut a, mut b) = (0.0, 0.1);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if arch_alpha(c) > arch_alpha(d) {
            b = d;
        } else {
            a = c;
        }
    }
    arch_alpha(0.5 * (a + b))
}

/// The apex height w in [low, high] where the arch carries α, by bisection: α falls from
/// `arch_alpha(low)` above it to `arch_alpha(high)` below it along the branch.
fn arch_height(alpha: f64, (mut low, mut high): (f64, f64)) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        if arch_alpha(mid) > alpha {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.5 * (low + high)
}

/// The apex height on the snapped-through branch (w < −0.1, the bars in tension) at α: α
/// rises as the apex goes down below the inverted rest shape.
fn arch_snapped_height(alpha: f64) -> f64 {
    arch_height(alpha, (-2.0, -0.1))
}

/// The apex height on the rising branch (w between the limit's and 0.1) at α: α falls from
/// the limit load to 0 as w rises to 0.1.
fn arch_rising_height(alpha: f64) -> f64 {
    arch_height(alpha, (0.1 / 3f64.sqrt(), 0.1))
}

/// The apex's vertical displacement in a run's displacements file.
fn apex_uz(out: &Path, alpha: &str) -> f64 {
    let rows = csv_rows(&out.join(format!("displacements/newton_alpha{alpha}.csv")));
    number(&rows[1], "uz")
}

/// Displacements of every node of a run at α, in file order.
fn displacements(out: &Path, alpha: &str) -> Vec<f64> {
    csv_rows(&out.join(format!("displacements/newton_alpha{alpha}.csv")))
        .iter()
        .flat_map(|r| ["ux", "uy", "uz"].map(|k| number(r, k)))
        .collect()
}

/// The arch's limit load to 1e-8 (the issue asks 1e-4) and its snapped branch at α = 3, 4, 5
/// (0.2303 m at α = 5) to 1e-8 of the closed form; before the limit the same answers as load
/// control's, every row converged and stable, `limit_alpha` empty until the limit is passed.
#[test]
fn arch_limit_load_and_snapped_branch_match_the_closed_form() {
    let (dir, case) = arch("arc-arch");
    let out = dir.0.join("out");
    let (o, rows) = run(&case, &out, &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let limit = arch_limit();
    assert!((limit - 2.13409).abs() < 1e-5, "{limit}");
    for row in &rows {
        let alpha = number(row, "alpha");
        assert_eq!(row["status"], "converged", "{row:?}");
        assert!(number(row, "min_tangent_eigenvalue") > 0.0, "{row:?}");
        if alpha < limit {
            assert!(row["limit_alpha"].is_empty(), "{row:?}");
        } else {
            let located = number(row, "limit_alpha");
            assert!(
                (located - limit).abs() <= 1e-8 * limit,
                "{located} vs {limit}"
            );
            let w = arch_snapped_height(alpha);
            let uz = apex_uz(&out, &row["alpha"]);
            assert!(
                (uz - (w - 0.1)).abs() <= 1e-8 * uz.abs(),
                "α {alpha}: {uz} vs {}",
                w - 0.1
            );
        }
    }
    let uz5 = apex_uz(&out, "5");
    assert!((uz5 + 0.2303).abs() < 1e-4, "{uz5}");
    // Before the limit, the rising branch of the closed form, and load control's answers.
    let control = dir.0.join("control");
    let (o, control_rows) = run(&case, &control, &["load.path=\"load-control\""]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    for (label, alpha) in [("1", 1.0), ("2", 2.0)] {
        let w = arch_rising_height(alpha);
        let (a, b) = (apex_uz(&out, label), apex_uz(&control, label));
        assert!(
            (a - (w - 0.1)).abs() <= 1e-8 * a.abs(),
            "α {alpha}: {a} vs {}",
            w - 0.1
        );
        assert!((a - b).abs() <= 1e-8 * b.abs(), "α {alpha}: {a} vs {b}");
    }
    // Load control stops at the limit: its rows beyond say where, in `limit_alpha` too.
    for row in control_rows.iter().filter(|r| number(r, "alpha") > limit) {
        assert_eq!(row["status"], "limit_point", "{row:?}");
        assert_eq!(row["limit_alpha"], row["path_reached"], "{row:?}");
        let located = number(row, "limit_alpha");
        assert!(
            located <= limit && located >= limit * (1.0 - 1e-4),
            "{located}"
        );
    }
}

/// The simplex under 1 MN down on each top node (tests/load_path.rs: load control stops at its
/// limit point, OpenSees at 0.6845): the arc-length path passes it at 0.68440, every row
/// converges, those before the limit equal load control's to 1e-8, those after it lie on the
/// snapped branch (the top 3.3 m down, three cables slack).
#[test]
fn simplex_passes_its_limit_point_onto_the_snapped_branch() {
    let dir = Temp::dir("arc-simplex");
    std::fs::create_dir_all(&dir.0).unwrap();
    let case = dir.0.join("case.toml");
    std::fs::write(&case, simplex_case()).unwrap();
    let out = dir.0.join("out");
    let (o, rows) = run(&case, &out, &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let control = dir.0.join("control");
    let (o, control_rows) = run(&case, &control, &["load.path=\"load-control\""]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    for (row, control_row) in rows.iter().zip(&control_rows) {
        assert_eq!(row["status"], "converged", "{row:?}");
        let alpha = number(row, "alpha");
        if alpha < 0.6844 {
            assert!(row["limit_alpha"].is_empty(), "{row:?}");
            assert_eq!(control_row["status"], "converged");
            let (a, b) = (
                displacements(&out, &row["alpha"]),
                displacements(&control, &row["alpha"]),
            );
            let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let worst = a
                .iter()
                .zip(&b)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(worst <= 1e-8 * scale, "α {alpha}: {worst} of {scale}");
        } else {
            let located = number(row, "limit_alpha");
            assert!((0.68440..0.68441).contains(&located), "{row:?}");
            assert_eq!(control_row["status"], "limit_point");
            assert!(number(row, "max_deflection") > 3.3, "{row:?}");
            assert_eq!(row["slack_cables"], "3", "{row:?}");
        }
    }
}

fn simplex_case() -> String {
    format!(
        "[structure]\nnodes = \"{0}/nodes.csv\"\nmembers = \"{0}/members.csv\"\n\
         [[supports.fix]]\nnodes = [0, 1, 2]\n[[load.point]]\nnodes = [3, 4, 5]\n\
         force = [300.0, 0.0, -1000.0]\n[load]\nnodal = [0.0, 0.0, -1e6]\n\
         alpha = [0.25, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]\npath = \"arc-length\"\n\
         [model]\ngeometry = \"large\"\n[solver]\nmethods = [\"newton\"]\n",
        manifest_path("cases/simplex").display()
    )
}

/// Peer: OpenSees `ArcLength` (scripts/peers/corot.py, through corot_compare.py) on the arch
/// and the simplex: every α's displacements and tensions to 1e-8, the same slack cables, and
/// the limit load to 1e-6 (its parabola through three arc steps of 0.5 mm / 5 mm).
#[test]
#[ignore = "peer check: needs python3 with openseespy and numpy (python3 -m pip install openseespy numpy); run with -- --include-ignored"]
fn arc_length_agrees_with_opensees_arc_length() {
    common::require_python(&["openseespy.opensees", "numpy"]);
    let (dir, arch_case) = arch("arc-peer-arch");
    let simplex = dir.0.join("simplex.toml");
    std::fs::write(&simplex, simplex_case()).unwrap();
    for (case, step) in [(arch_case, "0.0005"), (simplex, "0.005")] {
        let out = dir.0.join(format!("out-{step}"));
        let (o, _) = run(&case, &out, &[]);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        let compare = std::process::Command::new("python3")
            .arg(manifest_path("scripts/peers/corot_compare.py"))
            .arg(&case)
            .arg(&out)
            .args(["--rtol", "1e-8", "--limit-rtol", "1e-6", "--arc-step", step])
            .output()
            .unwrap();
        let printed = String::from_utf8_lossy(&compare.stdout);
        assert!(compare.status.success(), "{printed}{}", stderr(&compare));
        assert!(printed.contains("limit: the peer"), "{printed}");
    }
}

/// What the arc length is refused with, each naming the key and the fix (exit 2).
#[test]
fn arc_length_refusals_name_the_key() {
    let (dir, case) = arch("arc-refuse");
    let cases: [(&[&str], &str, &str); 6] = [
        (
            &["model.geometry=\"prestress\""],
            "load.path",
            "model.geometry = \"large\"",
        ),
        (
            &["solver.methods=[\"newton\", \"pcg-lcp\"]"],
            "load.path",
            "names pcg-lcp",
        ),
        (&["load.alpha=[-1.0, 1.0]"], "load.alpha", "α ≥ 0"),
        (&["load.point=[]"], "load.path", "has none"),
        (
            &["load.point=[{nodes = [1], force = [0.0, 0.0, 0.0]}]"],
            "load.path",
            "has none",
        ),
        (&["load.path=\"riks\""], "load-control", "arc-length"),
    ];
    for (k, (sets, key, fix)) in cases.iter().enumerate() {
        let out = dir.0.join(format!("out{k}"));
        let (o, _) = run(&case, &out, sets);
        let err = stderr(&o);
        assert_eq!(code(&o), 2, "{sets:?}: {err}");
        assert!(err.contains(key) && err.contains(fix), "{sets:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let o = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        dir.0.join("solver").to_str().unwrap(),
        "--solver",
        "pcg-lcp",
    ]);
    let err = stderr(&o);
    assert_eq!(code(&o), 2, "{err}");
    assert!(
        err.contains("--solver") && err.contains("newton's"),
        "{err}"
    );
}

/// A first α far below the next (1e-6, then 1 and 5) does not leave the steps tiny: every row
/// converges, α = 5 on the snapped branch of the closed form; and a row just below the limit
/// (2.134088) has no `limit_alpha`, the path not having passed it.
#[test]
fn a_tiny_first_alpha_and_a_row_just_below_the_limit() {
    let (dir, case) = arch("arc-tiny");
    let out = dir.0.join("out");
    let (o, rows) = run(&case, &out, &["load.alpha=[1e-6, 2.134088, 5.0]"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(rows.iter().all(|r| r["status"] == "converged"), "{rows:?}");
    assert!(rows[1]["limit_alpha"].is_empty(), "{:?}", rows[1]);
    let located = number(&rows[2], "limit_alpha");
    assert!(
        (located - arch_limit()).abs() <= 1e-8 * located,
        "{located}"
    );
    let (uz, w) = (apex_uz(&out, "5"), arch_snapped_height(5.0));
    assert!(
        (uz - (w - 0.1)).abs() <= 1e-8 * uz.abs(),
        "{uz} vs {}",
        w - 0.1
    );
}
