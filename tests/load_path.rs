//! `model.geometry = "large"` along its load path (issue 42: T1, D5, D10, T13): a row is
//! `converged` only on the path from the prestressed state, a load beyond a limit point of
//! that path says `limit_point` whatever the α before it, and a limit point is said with
//! where the path stopped (`path_from`, `path_reached`), the cables a loss of equilibrium
//! slackens, and a stopping value measured at the row's α.

mod common;

use common::{code, csv_rows, manifest_path, stderr, tensolve, Temp};
use std::collections::HashMap;
use tensolve::solvers::LIMIT_TOLERANCE;

type Row = HashMap<String, String>;

fn number(row: &Row, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?} is not a number in {row:?}", row[key]))
}

/// A case directory: `case.toml` (its `[load]` alphas from `alphas`) beside its tables.
struct CaseDir {
    dir: Temp,
}

impl CaseDir {
    fn new(tag: &str, nodes: &str, members: &str, body: &str) -> CaseDir {
        let dir = Temp::dir(tag);
        std::fs::create_dir_all(&dir.0).unwrap();
        std::fs::write(dir.0.join("nodes.csv"), nodes).unwrap();
        std::fs::write(dir.0.join("members.csv"), members).unwrap();
        let text = format!(
            "[structure]\nnodes = \"nodes.csv\"\nmembers = \"members.csv\"\n{body}\n\
             [model]\ngeometry = \"large\"\n[solver]\nmethods = [\"newton\"]\n"
        );
        std::fs::write(dir.0.join("case.toml"), text).unwrap();
        CaseDir { dir }
    }

    /// Run the case at `alphas`: the process and its summary rows.
    fn run(&self, alphas: &[f64]) -> (std::process::Output, Vec<Row>) {
        let out = self.dir.0.join(format!("out-{}", alphas.len()));
        let _ = std::fs::remove_dir_all(&out);
        let list = alphas
            .iter()
            .map(|a| format!("{a:?}"))
            .collect::<Vec<_>>()
            .join(", ");
        let run = tensolve(&[
            "run",
            self.dir.0.join("case.toml").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--set",
            &format!("load.alpha=[{list}]"),
        ]);
        let rows = csv_rows(&out.join("summary.csv"));
        (run, rows)
    }
}

/// The von Mises arch of review T1: two bars (EA = 5.6e7 N) from (±1, 0, 0) to the apex
/// (0, 0, 0.1), the apex held in y, 10 kN down on it per unit α.
fn von_mises_arch() -> CaseDir {
    CaseDir::new(
        "von-mises",
        "node,x,y,z\n0,-1.0,0.0,0.0\n1,0.0,0.0,0.1\n2,1.0,0.0,0.0\n",
        "member,a,b,kind,young,section,prestress\n\
         0,0,1,bar,200000000000.0,0.00028,0.0\n1,1,2,bar,200000000000.0,0.00028,0.0\n",
        "[[supports.fix]]\nnodes = [0, 2]\n[[supports.fix]]\nnodes = [1]\ndofs = [\"y\"]\n\
         [[load.point]]\nnodes = [1]\nforce = [0.0, 0.0, -10000.0]\n[load]\nalpha = [1.0]\n",
    )
}

/// The arch's apex load (N, down) in equilibrium at apex height w under the exact-length law:
/// `P = −2 N w / ℓ`, `N = EA (ℓ − L) / L`, `ℓ = √(1 + w²)`: an independent computation.
fn arch_load(w: f64) -> f64 {
    let (ea, length) = (2e11 * 2.8e-4, 1.01f64.sqrt());
    let l = (1.0 + w * w).sqrt();
    -2.0 * ea * (l - length) / length * w / l
}

/// The arch's limit point: the largest α = P / 10 kN over the rising branch, w in (0, 0.1),
/// and the apex height there.
fn arch_limit() -> (f64, f64) {
    (1..100_000)
        .map(|i| 0.1 * i as f64 / 100_000.0)
        .map(|w| (arch_load(w) / 1e4, w))
        .fold(
            (f64::MIN, 0.0),
            |best, x| if x.0 > best.0 { x } else { best },
        )
}

/// The apex deflection at α on the rising branch (w between the limit and 0.1), by bisection.
fn arch_deflection(alpha: f64) -> f64 {
    let (_, w_limit) = arch_limit();
    let (mut low, mut high) = (w_limit, 0.1);
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        // P falls from the limit load to 0 as w rises to 0.1.
        if arch_load(mid) / 1e4 > alpha {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.1 - 0.5 * (low + high)
}

/// T1, D5: α = 1 … 8 on the arch. Before the fix α = 3 stopped at the iteration cap, α = 4
/// converged on the snapped-through branch and 5 … 8 said `limit_point` (a nearly singular
/// factor kept as a chord for every halved retry), and α = 5 alone converged. Now every α
/// beyond the limit point (α = 2.13409, computed here independently) says `limit_point`
/// with the path stopped just below it, whatever the list; those below converge on the path.
#[test]
fn arch_beyond_its_limit_point_says_limit_point_whatever_the_alpha_list() {
    let arch = von_mises_arch();
    let (limit, _) = arch_limit();
    assert!((limit - 2.13409).abs() < 1e-4, "{limit}");
    let (run, rows) = arch.run(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]);
    assert_eq!(code(&run), 1, "{}", stderr(&run));
    assert_eq!(rows.len(), 8);
    for row in &rows {
        let alpha = number(row, "alpha");
        if alpha < limit {
            assert_eq!(row["status"], "converged", "{row:?}");
            let want = arch_deflection(alpha);
            let got = number(row, "max_deflection");
            assert!(
                (got - want).abs() <= 1e-6 * want,
                "{alpha}: {got} vs {want}"
            );
            assert_eq!(number(row, "path_reached"), alpha, "{row:?}");
        } else {
            assert_eq!(row["status"], "limit_point", "{row:?}");
            assert_eq!(row["converged"], "false", "{row:?}");
            // D5: every later row starts from the last equilibrium on the path, α = 2, and
            // stops at the limit point, located to LIMIT_TOLERANCE of its load (L1).
            assert_eq!(number(row, "path_from"), 2.0, "{row:?}");
            let reached = number(row, "path_reached");
            assert!(
                reached <= limit && reached >= limit * (1.0 - LIMIT_TOLERANCE),
                "{alpha}: reached {reached}, limit {limit}"
            );
        }
    }
    // L1: the limit is located once, by the first row past it: every later row reports the
    // same (it varied 2.1289 to 2.1338 per row, each locating it anew), and the failure is
    // said once for all of them.
    let beyond: Vec<&str> = rows[2..]
        .iter()
        .map(|r| r["path_reached"].as_str())
        .collect();
    assert!(beyond.iter().all(|r| *r == beyond[0]), "{beyond:?}");
    assert_eq!(
        stderr(&run).matches("limit point:").count(),
        1,
        "{}",
        stderr(&run)
    );
    assert!(
        stderr(&run).contains("newton at alpha = 3, 4, 5, 6, 7, 8: limit point:"),
        "{}",
        stderr(&run)
    );
    // The same loads alone: the same verdicts, from the prestressed state.
    for alpha in [2.1, 2.2, 5.0, 8.0] {
        let (run, rows) = arch.run(&[alpha]);
        let row = &rows[0];
        match alpha < limit {
            true => {
                assert_eq!(code(&run), 0, "{}", stderr(&run));
                assert_eq!(row["status"], "converged", "{row:?}");
                let want = arch_deflection(alpha);
                let got = number(row, "max_deflection");
                assert!(
                    (got - want).abs() <= 1e-6 * want,
                    "{alpha}: {got} vs {want}"
                );
            }
            false => {
                assert_eq!(code(&run), 1, "{}", stderr(&run));
                assert_eq!(row["status"], "limit_point", "{row:?}");
                assert_eq!(number(row, "path_from"), 0.0, "{row:?}");
                let reached = number(row, "path_reached");
                assert!(
                    reached <= limit && reached >= limit * (1.0 - LIMIT_TOLERANCE),
                    "{alpha}: reached {reached}"
                );
            }
        }
    }
}

/// T1, D5: the solve line and the failure message of a row beyond the limit point say where
/// the path started and stopped, and that beyond it the equilibria lie on another branch.
#[test]
fn a_limit_point_row_says_where_the_path_stopped() {
    let arch = von_mises_arch();
    let (run, rows) = arch.run(&[2.0, 4.0, 5.0]);
    assert_eq!(code(&run), 1);
    assert_eq!(rows[1]["status"], "limit_point");
    assert_eq!(rows[2]["status"], "limit_point");
    let printed = format!("{}{}", String::from_utf8_lossy(&run.stdout), stderr(&run));
    assert!(
        printed.contains("alpha = 4      NOT converged (limit point)")
            && printed.contains("path from alpha = 2 stopped at alpha = 2.13"),
        "{printed}"
    );
    assert!(
        stderr(&run).contains(
            "newton at alpha = 4, 5: limit point: the load path from alpha = 2 (the last \
             equilibrium reached) was followed to alpha = 2.13"
        ) && stderr(&run).contains("lie on another branch"),
        "{}",
        stderr(&run)
    );
    // The bracket it was located in, both ends within LIMIT_TOLERANCE of the exact limit.
    let (limit, _) = arch_limit();
    let text = stderr(&run);
    let bracket = text
        .split("the limit lies between alpha = ")
        .nth(1)
        .and_then(|rest| rest.split(" (").next())
        .expect("the bracket is said");
    let ends: Vec<f64> = bracket.split(" and ").map(|x| x.parse().unwrap()).collect();
    assert!(
        ends[0] <= limit && limit <= ends[1],
        "{ends:?} around {limit}"
    );
    assert!(
        ends[1] - ends[0] <= 2.0 * LIMIT_TOLERANCE * ends[0],
        "{ends:?}"
    );
}

/// The newcomer's 3-stage tower (tests/data/tower3q) under loads 1000 times too large: its
/// path needs increments far below a thousandth of α = 0.25 at first, and reaches a limit at
/// α ≈ 0.319.
fn tower_too_loaded() -> CaseDir {
    let table = |name: &str| {
        std::fs::read_to_string(manifest_path(&format!("tests/data/tower3q/{name}.csv"))).unwrap()
    };
    CaseDir::new(
        "tower-too-loaded",
        &table("nodes"),
        &table("members"),
        "[[supports.fix]]\nnodes = [0, 1, 2, 3]\n[[load.point]]\nnodes = [12, 13, 14, 15]\n\
         force = [1500000.0, 0.0, -1000000.0]\n[prestress]\nfrom = \"design\"\n\
         targets = { bars0 = -5000.0, bars1 = -4000.0, bars2 = -3000.0 }\n[load]\nalpha = [0.25]\n",
    )
}

/// N-D1: the smallest increment is a load, not a fraction of the path. α = 0.25 asked alone
/// said "limit point at α = 0" (its increments stopped at 1/1024 of 0.25), while a sweep of
/// small steps converged there; now both converge to the same answer, and the limit beyond
/// (≈ 0.319) is located to LIMIT_TOLERANCE from either start.
#[test]
fn the_verdict_at_an_alpha_does_not_depend_on_the_alphas_before_it() {
    let tower = tower_too_loaded();
    let (alone, rows) = tower.run(&[0.25]);
    assert_eq!(code(&alone), 0, "{}", stderr(&alone));
    let direct = number(&rows[0], "max_deflection");
    let steps: Vec<f64> = (1..=10).map(|i| 0.025 * i as f64).collect();
    let (swept, rows) = tower.run(&steps);
    assert_eq!(code(&swept), 0, "{}", stderr(&swept));
    let last = rows.last().unwrap();
    assert_eq!(last["status"], "converged", "{last:?}");
    let through = number(last, "max_deflection");
    assert!(
        (direct - through).abs() <= 1e-8 * direct,
        "{direct} vs {through}"
    );
    assert!(direct > 5.0, "a large displacement: {direct}");
    // The limit beyond, from the prestressed state and from α = 0.31.
    let limit_of = |alphas: &[f64]| {
        let (run, rows) = tower.run(alphas);
        assert_eq!(code(&run), 1, "{}", stderr(&run));
        let row = rows.last().unwrap();
        assert_eq!(row["status"], "limit_point", "{row:?}");
        number(row, "path_reached")
    };
    let (from_rest, from_near) = (limit_of(&[0.4]), limit_of(&[0.31, 0.4]));
    assert!((0.3185..0.3195).contains(&from_rest), "{from_rest}");
    assert!(
        (from_rest - from_near).abs() <= LIMIT_TOLERANCE * from_rest,
        "{from_rest} vs {from_near}"
    );
}

/// T13: a `limit_point` row's stopping value is r(U) of its answer (the last equilibrium on
/// the path) measured at its own α, the `equilibrium_residual` beside it, far above the
/// tolerance; before the fix it was measured at the last equilibrium's load (1.3e-11, or 0
/// from the prestressed state).
#[test]
fn a_limit_point_rows_stopping_value_is_measured_at_its_alpha() {
    let arch = von_mises_arch();
    for alphas in [vec![1.0, 2.0, 3.0], vec![2.2]] {
        let (_, rows) = arch.run(&alphas);
        let row = rows.last().unwrap();
        assert_eq!(row["status"], "limit_point", "{row:?}");
        let (stop, residual) = (number(row, "residual"), number(row, "equilibrium_residual"));
        assert!(stop > 1e-4, "{row:?}");
        assert!((stop - residual).abs() <= 1e-9 * residual, "{row:?}");
    }
}

/// T1b: the simplex under 1 MN down on each top node passes a real limit point (OpenSees
/// corotTruss stops at α = 0.6845); before the fix α = 0.7 … 1 said `converged` on the
/// snapped-through branch (3.34 m), exit 0.
#[test]
fn simplex_snap_through_is_a_limit_point() {
    let dir = Temp::dir("simplex-snap");
    std::fs::create_dir_all(&dir.0).unwrap();
    let tables = manifest_path("cases/simplex");
    let text = format!(
        "[structure]\nnodes = \"{0}/nodes.csv\"\nmembers = \"{0}/members.csv\"\n\
         [[supports.fix]]\nnodes = [0, 1, 2]\n[[load.point]]\nnodes = [3, 4, 5]\n\
         force = [300.0, 0.0, -1000.0]\n[load]\nnodal = [0.0, 0.0, -1e6]\n\
         alpha = [0.25, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]\n[model]\ngeometry = \"large\"\n\
         [solver]\nmethods = [\"newton\"]\n",
        tables.display()
    );
    let case = dir.0.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let out = dir.0.join("out");
    let run = tensolve(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code(&run), 1, "{}", stderr(&run));
    let rows = csv_rows(&out.join("summary.csv"));
    let statuses: Vec<&str> = rows.iter().map(|r| r["status"].as_str()).collect();
    assert_eq!(
        statuses,
        [
            "converged",
            "converged",
            "converged",
            "limit_point",
            "limit_point",
            "limit_point",
            "limit_point"
        ]
    );
    for row in &rows[3..] {
        let reached = number(row, "path_reached");
        assert!((0.68..=0.6846).contains(&reached), "{row:?}");
        assert!(row["max_deflection"].is_empty(), "{row:?}");
    }
}

/// D10: the bracket's stays go slack under uplift and the strut swings: with `large` the path
/// loses its equilibrium at once. Before the fix: "not converged after 100 iterations
/// (MaxIterations)"; now `limit_point` at α = 0, naming the stays.
#[test]
fn bracket_loss_of_equilibrium_is_a_limit_point_naming_the_cables() {
    let bracket = CaseDir::new(
        "bracket",
        "node,x,y,z\n0,0.0,0.0,0.0\n1,2.0,0.0,0.0\n2,0.0,0.8,1.0\n3,0.0,-0.8,1.0\n",
        "member,a,b,kind,young,section,prestress\n0,0,1,bar,2.1e11,4.0e-4,0.0\n\
         1,1,2,cable,1.2e11,7.85e-5,0.0\n2,1,3,cable,1.2e11,7.85e-5,0.0\n",
        "[[supports.fix]]\nnodes = [0, 2, 3]\n[[load.point]]\nnodes = [1]\n\
         force = [0.0, 0.0, 1000.0]\n[load]\nalpha = [0.5]\n",
    );
    let (run, rows) = bracket.run(&[0.5, 1.0]);
    assert_eq!(code(&run), 1);
    for row in &rows {
        assert_eq!(row["status"], "limit_point", "{row:?}");
        assert_eq!(number(row, "path_reached"), 0.0, "{row:?}");
    }
    let message = stderr(&run);
    assert!(
        message.contains("a loss of equilibrium where cable(s) 1, 2 go slack")
            && !message.contains("MaxIterations"),
        "{message}"
    );
}

/// The path check's slope `Σ τ ∇ℓ·d` (`Model::internal_slope`, no gradient assembled) is
/// `∇Π(U)·d + F·d` with the assembled gradient, on the tower displaced far enough that
/// cables are slack, along a direction that moves every free dof.
#[test]
fn internal_slope_is_the_gradient_along_d() {
    use tensolve::model::{CurrentGeometry, GeometricModel};
    use tensolve::solvers::large::LargeNewton;
    use tensolve::solvers::newton::NewtonSettings;
    use tensolve::solvers::{drive, LoadPath, Silent, TautStiffness};
    let mut case = tensolve::case::load(&manifest_path("cases/tower.toml")).unwrap();
    case.model = GeometricModel::Large;
    let model = case.model();
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let load: Vec<f64> = s.unit_load.clone();
    let answer = drive(
        &mut LoadPath::new(LargeNewton::new(&model, &taut, NewtonSettings::default())),
        &load,
        None,
        &mut Silent,
    );
    let u: Vec<f64> = answer
        .equilibrium
        .displacements
        .iter()
        .map(|x| 3.0 * x)
        .collect();
    let d: Vec<f64> = (0..s.n_free).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
    let mut gradient = vec![0.0; s.n_free];
    CurrentGeometry::of(s, &u).unbalances(s, &load, &mut gradient);
    let assembled: f64 = gradient.iter().zip(&d).map(|(g, d)| g * d).sum::<f64>()
        + load.iter().zip(&d).map(|(f, d)| f * d).sum::<f64>();
    let lean = model.internal_slope(&u, &d);
    assert!(
        (lean - assembled).abs() <= 1e-10 * lean.abs().max(1.0),
        "{lean} against {assembled}"
    );
}

/// Under `large` `solver.max_iterations` caps each increment: a cap too low for the arch's
/// increments to converge ends at `limit_point` (the increments are halved), and the message
/// says the cap, not the structure, may be the cause.
#[test]
fn a_low_cap_under_large_is_named_in_the_limit_point_message() {
    let arch = von_mises_arch();
    let out = arch.dir.0.join("out-cap");
    let run = tensolve(&[
        "run",
        arch.dir.0.join("case.toml").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "solver.max_iterations=1",
        "--set",
        "load.alpha=[2.0]",
    ]);
    assert_eq!(code(&run), 1, "{}", stderr(&run));
    let rows = csv_rows(&out.join("summary.csv"));
    assert_eq!(rows[0]["status"], "limit_point", "{:?}", rows[0]);
    assert!(
        stderr(&run).contains("each given 1 Newton step(s) by solver.max_iterations"),
        "{}",
        stderr(&run)
    );
}

/// Adversarial pass H2: under `large` a loose `solver.tolerance` is held to the path's own
/// (r(U) ≤ 1e-8, r_F ≤ 1e-6): at 1e-2 newton said converged at α = 3 on the arch's inverted
/// branch, and at 1e-3 located its limit 2 % off. Now both newton and pcg-lcp stop at the
/// limit, located to LIMIT_TOLERANCE.
#[test]
fn a_loose_tolerance_never_passes_a_snap_through() {
    let arch = von_mises_arch();
    let (limit, _) = arch_limit();
    for tolerance in ["1e-2", "1e-3"] {
        let out = arch.dir.0.join(format!("out-loose-{tolerance}"));
        let run = tensolve(&[
            "run",
            arch.dir.0.join("case.toml").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--solver",
            "newton,pcg-lcp",
            "--set",
            &format!("solver.tolerance={tolerance}"),
            "--set",
            "load.alpha=[3.0]",
        ]);
        assert_eq!(code(&run), 1, "{}", stderr(&run));
        for row in csv_rows(&out.join("summary.csv")) {
            assert_eq!(row["status"], "limit_point", "{tolerance}: {row:?}");
            let reached = number(&row, "path_reached");
            assert!(
                reached <= limit && reached >= limit * (1.0 - LIMIT_TOLERANCE),
                "{tolerance}: {row:?}"
            );
        }
    }
}

/// Adversarial pass M2: a LATIN solver's load path that gives out near a limit point is its
/// own stall, not the structure's limit: mono-latin and micro-macro said "limit point at
/// 2.1194" at α = 2.125 on the arch, where newton and pcg-lcp converge (the limit is 2.13409).
#[test]
fn latin_near_the_arch_limit_claims_no_limit_point() {
    let arch = von_mises_arch();
    let out = arch.dir.0.join("out-latin-near");
    let run = tensolve(&[
        "run",
        arch.dir.0.join("case.toml").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--solver",
        "newton,pcg-lcp,mono-latin,micro-macro",
        "--set",
        "load.alpha=[2.125]",
    ]);
    for row in csv_rows(&out.join("summary.csv")) {
        match row["solver"].as_str() {
            "newton" | "pcg-lcp" => assert_eq!(row["status"], "converged", "{row:?}"),
            _ => assert_ne!(row["status"], "limit_point", "{row:?}"),
        }
    }
    assert!(!stderr(&run).contains("limit point"), "{}", stderr(&run));
}
