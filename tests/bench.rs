//! `tensolve bench`: the files and table it produces on a small case, the assumption its
//! measure of newton and pcg-lcp rests on (a capped solve reproduces the iterate of the full
//! solve), its exit codes, and `tensolve check` on every shipped case file.

mod common;

use common::{manifest_path, stderr, temp_path, tensolve, Temp};
use std::collections::BTreeMap;
use std::path::Path;

use tensolve::app::bench::{Sample, Series, Table, CSV_HEADER};
use tensolve::case;
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use tensolve::solvers::Method;
use tensolve::solvers::{AnySolver, Observer, Recorder, Silent, Solution, Status, TautStiffness};

/// 4 x 4 modules loaded 20 times harder than the paper's nodes, so that 28 of the 192 cables
/// go slack at α = 1 (at the paper's 40 N none does and newton needs one step): newton takes
/// 5 steps, pcg-lcp 19, the LATIN solvers tens.
const SMALL: &str = "\
[grid]
modules = [4, 4]
[load]
nodal = [0.0, 0.0, -800.0]
alpha = [1.0]
[solver]
methods = [\"newton\", \"pcg-lcp\", \"mono-latin\", \"micro-macro\"]
subdomains = [2, 2]
";

const SOLVERS: [&str; 4] = ["newton", "pcg-lcp", "mono-latin", "micro-macro"];

fn is_latin(solver: &str) -> bool {
    matches!(
        Method::from_name(solver).expect("a solver name"),
        Method::MonoLatin | Method::MicroMacro
    )
}

/// bench.csv rows per solver, as (iteration, seconds, error_e), after checking the header.
fn read_bench_csv(path: &Path) -> BTreeMap<String, Vec<(usize, f64, f64)>> {
    let text = std::fs::read_to_string(path).expect("bench.csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    assert_eq!(CSV_HEADER, "solver,alpha,iteration,seconds,error_e");
    let mut rows: BTreeMap<String, Vec<(usize, f64, f64)>> = BTreeMap::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 5, "{line}");
        assert_eq!(f[1], "1", "{line}");
        rows.entry(f[0].to_string()).or_default().push((
            f[2].parse().expect("iteration"),
            f[3].parse().expect("seconds"),
            f[4].parse().expect("error_e"),
        ));
    }
    rows
}

#[test]
fn bench_writes_csv_svg_and_table() {
    let case = Temp::file("bench-small", SMALL);
    let out = Temp(temp_path("bench-small-out"));
    let o = tensolve(&["bench", case.arg(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "--quiet: {}", stderr(&o));

    let rows = read_bench_csv(&out.0.join("bench.csv"));
    assert_eq!(
        rows.keys().collect::<Vec<_>>().len(),
        4,
        "{:?}",
        rows.keys()
    );
    for solver in SOLVERS {
        let series = &rows[solver];
        assert!(series.len() >= 2, "{solver}: {series:?}");
        for pair in series.windows(2) {
            assert!(pair[1].0 > pair[0].0, "{solver}: iterations {pair:?}");
            assert!(pair[1].1 > pair[0].1, "{solver}: seconds {pair:?}");
        }
        assert!(series.iter().all(|r| r.1 > 0.0 && r.2 >= 0.0), "{solver}");
        let (first, last) = (series[0].2, series[series.len() - 1].2);
        // Nonlinear enough that the first iterate is far from the answer…
        assert!(first > 1e-2, "{solver}: first e = {first}");
        // …and every solver ends close to it: the exact solvers to round-off, the LATIN
        // solvers to what η ≤ 1e-6 gives.
        let bound = if is_latin(solver) { 1e-5 } else { 1e-6 };
        assert!(last < bound, "{solver}: last e = {last}");
    }
    // The LATIN solvers start with iteration 0 (the linear stage), the exact ones with 1.
    assert_eq!(rows["mono-latin"][0].0, 0);
    assert_eq!(rows["newton"][0].0, 1);

    let svg = std::fs::read_to_string(out.0.join("bench.svg")).expect("bench.svg");
    let svg = svg.trim();
    assert!(
        svg.starts_with("<svg") || svg.starts_with("<?xml"),
        "{}",
        &svg[..80]
    );
    assert!(svg.ends_with("</svg>"));
    for label in SOLVERS
        .iter()
        .copied()
        .chain(["wall time", "energy error e"])
    {
        assert!(svg.contains(label), "bench.svg lacks `{label}`");
    }

    let stdout = String::from_utf8_lossy(&o.stdout);
    for solver in SOLVERS {
        let row: Vec<&str> = stdout
            .lines()
            .filter(|l| l.split_whitespace().next() == Some(solver))
            .collect();
        assert_eq!(row.len(), 1, "{solver}: {stdout}");
        // Every solver reaches e ≤ 1e-2 (a time, not "—") and the exact ones 1e-8.
        let cells: Vec<&str> = row[0].split_whitespace().collect();
        assert_eq!(cells[1], "1", "{}", row[0]);
        assert!(cells[3] == "ms" || cells[3] == "s", "{}", row[0]);
        if !is_latin(solver) {
            assert!(!row[0].contains('—'), "{}", row[0]);
        }
    }
}

#[test]
fn bench_exit_codes() {
    let missing = tensolve(&["bench", "/nonexistent/case.toml", "--quiet"]);
    assert_eq!(missing.status.code(), Some(2), "{}", stderr(&missing));

    let case = Temp::file("bench-blocked", SMALL);
    let blocker = Temp::file("bench-blocker", "a file, not a directory");
    let under_file = format!("{}/out", blocker.arg());
    let o = tensolve(&["bench", case.arg(), "--out", &under_file, "--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not writable"), "{}", stderr(&o));

    // Solvers stopped by max_iterations: files and table all the same, exit 1.
    let capped = Temp::file(
        "bench-capped",
        &SMALL.replace(
            "subdomains = [2, 2]",
            "subdomains = [2, 2]\nmax_iterations = 3",
        ),
    );
    let out = Temp(temp_path("bench-capped-out"));
    let o = tensolve(&["bench", capped.arg(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("mono-latin at alpha = 1"),
        "{}",
        stderr(&o)
    );
    assert!(out.0.join("bench.csv").is_file());
    assert!(String::from_utf8_lossy(&o.stdout).contains("(not converged)"));
}

/// bench takes its reference from `solver.reference`, as `run` does: against pcg-lcp it
/// measures every iterate's e, and the same e as against newton (both references are exact).
#[test]
fn bench_takes_its_reference_from_solver_reference() {
    let case = Temp::file("bench-reference", SMALL);
    let bench_against = |reference: &str| {
        let out = Temp(temp_path(&format!("bench-reference-{reference}")));
        let set = format!("solver.reference=\"{reference}\"");
        let o = tensolve(&[
            "bench",
            case.arg(),
            "--out",
            out.arg(),
            "--quiet",
            "--set",
            &set,
        ]);
        assert_eq!(o.status.code(), Some(0), "{reference}: {}", stderr(&o));
        read_bench_csv(&out.0.join("bench.csv"))
    };
    let newton = bench_against("newton");
    let pcg_lcp = bench_against("pcg-lcp");
    // The reference is the named solver's answer: at the case's default settings, that solver
    // ends on it exactly.
    let last_e = |rows: &BTreeMap<String, Vec<(usize, f64, f64)>>, solver: &str| {
        rows[solver].last().expect("a row").2
    };
    assert_eq!(last_e(&newton, "newton"), 0.0);
    assert_eq!(last_e(&pcg_lcp, "pcg-lcp"), 0.0);
    assert_eq!(
        newton.keys().collect::<Vec<_>>(),
        pcg_lcp.keys().collect::<Vec<_>>()
    );
    for (solver, rows) in &newton {
        let other = &pcg_lcp[solver];
        assert_eq!(rows.len(), other.len(), "{solver}");
        for (&(k, _, a), &(j, _, b)) in rows.iter().zip(other) {
            assert_eq!(k, j, "{solver}");
            assert!(b.is_finite() && b >= 0.0, "{solver} iteration {k}: e = {b}");
            assert!(
                (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-9,
                "{solver} iteration {k}: e = {a:e} against newton, {b:e} against pcg-lcp"
            );
        }
    }
}

/// bench measures e, so `solver.reference = "none"` is refused before anything is solved or
/// written: exit 2, naming the key, the value and the fix.
#[test]
fn bench_refuses_a_case_without_reference() {
    let case = Temp::file(
        "bench-no-reference",
        &SMALL.replace(
            "subdomains = [2, 2]",
            "subdomains = [2, 2]\nreference = \"none\"",
        ),
    );
    let out = Temp(temp_path("bench-no-reference-out"));
    let o = tensolve(&["bench", case.arg(), "--out", out.arg(), "--quiet"]);
    let message = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{message}");
    for part in [
        "`solver.reference` = \"none\"",
        "\"newton\"",
        "\"pcg-lcp\"",
        "`run`",
    ] {
        assert!(message.contains(part), "`{part}` in {message}");
    }
    assert!(!out.0.exists(), "nothing written: {message}");
}

/// A solve with an iteration cap, watched by an observer.
type CappedSolve<'a> = dyn Fn(usize, &mut dyn Observer) -> Solution + 'a;

/// What bench's measure of newton and pcg-lcp rests on: a solve capped at k iterations ends on
/// iterate k of the full solve, bit for bit.
#[test]
fn capped_solves_reproduce_the_iterates() {
    let case = case::parse(SMALL).unwrap();
    let model = case.model();
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let load: Vec<f64> = s.unit_load.clone();
    let newton = |max_iterations: usize, observer: &mut dyn Observer| {
        let settings = NewtonSettings {
            max_iterations,
            ..NewtonSettings::default()
        };
        Newton::new(&model, &taut, settings)
            .unwrap()
            .solve(&load, None, observer)
    };
    let pcg = |max_iterations: usize, observer: &mut dyn Observer| {
        let settings = PcgLcpSettings {
            max_iterations,
            ..PcgLcpSettings::default()
        };
        PcgLcp::new(&model, &taut, settings).solve(&load, None, observer)
    };
    let solvers: [(&str, &CappedSolve); 2] = [("newton", &newton), ("pcg-lcp", &pcg)];
    for (name, solve) in solvers {
        let mut recorder = Recorder::default();
        let solution = solve(usize::MAX, &mut recorder);
        let full: Vec<f64> = recorder.records.iter().map(|r| r.stopping_value).collect();
        assert_eq!(solution.info.status, Status::Converged, "{name}");
        assert!(full.len() >= 5, "{name}: {} iterations", full.len());
        let n = full.len();
        for (k, &residual) in (1..n).zip(&full) {
            let capped = solve(k, &mut Silent);
            assert_eq!(capped.info.iterations, k, "{name}");
            assert_eq!(
                capped.info.stopping_value.to_bits(),
                residual.to_bits(),
                "{name}: iteration {k}"
            );
        }
        // The last one (whose residual pcg-lcp recomputes on an exact gradient before stopping).
        let capped = solve(n, &mut Silent);
        assert_eq!(
            capped.equilibrium.displacements, solution.equilibrium.displacements,
            "{name}: iteration {n}"
        );
    }
}

fn sample(iteration: usize, seconds: f64, error: f64) -> Sample {
    Sample {
        iteration,
        seconds,
        error,
    }
}

#[test]
fn table_reads_the_first_iterate_below_each_threshold() {
    let series = Series {
        method: Method::MicroMacro,
        alpha: 0.5,
        setup_seconds: 0.001,
        status: Status::MaxIterations,
        samples: vec![
            sample(0, 0.002, 0.5),
            sample(1, 0.003, 5e-3),
            sample(2, 0.004, 2e-2),
            sample(3, 0.005, 1e-5),
        ],
    };
    assert_eq!(series.seconds_to_reach(1e-2), Some(0.003));
    assert_eq!(series.seconds_to_reach(1e-3), Some(0.005));
    assert_eq!(series.seconds_to_reach(1e-4), Some(0.005));
    assert_eq!(series.seconds_to_reach(1e-6), None);
    let table = Table::new(&[series]);
    assert_eq!(
        table.rows[0].seconds_to_reach,
        [Some(0.003), Some(0.005), Some(0.005), None, None]
    );
    let text = table.to_string();
    let row = text.lines().find(|l| l.starts_with("micro-macro")).unwrap();
    let cells: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(
        cells,
        [
            "micro-macro",
            "0.5",
            "3.00",
            "ms",
            "5.00",
            "ms",
            "5.00",
            "ms",
            "—",
            "—",
            "1.0e-5",
            "(not",
            "converged)"
        ]
    );
}

/// Case files added for the figures and the benchmark.
const NEW_CASES: [&str; 5] = [
    "cases/paper-braced.toml",
    "cases/paper-linear.toml",
    "cases/paper-linear-braced.toml",
    "cases/paper-sweep.toml",
    "cases/paper-bench.toml",
];

#[test]
fn check_passes_on_every_new_case() {
    for path in NEW_CASES {
        let file = manifest_path(path);
        let o = tensolve(&["check", file.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{path}: {}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            stdout.contains("positive definite with every cable taut"),
            "{path}: {stdout}"
        );
    }
    let sweep = case::load(&manifest_path("cases/paper-sweep.toml")).unwrap();
    assert_eq!(sweep.load.alphas.len(), 25);
    assert_eq!(sweep.solver.methods, [Method::Newton]);
    let linear = case::load(&manifest_path("cases/paper-linear.toml")).unwrap();
    let linear_braced = case::load(&manifest_path("cases/paper-linear-braced.toml")).unwrap();
    for c in [&linear, &linear_braced] {
        assert!(!c.grid.as_ref().unwrap().cables.unilateral);
        assert_eq!(c.load.alphas, [1.0]);
        assert_eq!(c.solver.methods, [Method::MonoLatin, Method::MicroMacro]);
    }
    assert_ne!(
        linear.grid.as_ref().unwrap().module,
        linear_braced.grid.as_ref().unwrap().module
    );
    let bench = case::load(&manifest_path("cases/paper-bench.toml")).unwrap();
    assert_eq!(bench.solver.methods, Method::ALL);
    assert_eq!(bench.load.alphas, [1.0]);
}

/// `bench` on a `large` case measures e on the exact elongations `ℓ − L`, as newton reports
/// them (its reference was on `B U`, so e stayed near 1): every α ends at e ≤ 1e-8.
#[test]
fn bench_of_a_large_displacement_case_measures_e_on_the_exact_elongations() {
    let out = Temp::dir("bench-large");
    let o = tensolve(&[
        "bench",
        manifest_path("cases/simplex.toml").to_str().unwrap(),
        "--out",
        out.arg(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.0.join("bench.csv")).unwrap();
    let mut last: BTreeMap<String, f64> = BTreeMap::new();
    for line in text.lines().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        last.insert(fields[1].to_string(), fields[4].parse().unwrap());
    }
    assert_eq!(last.len(), 3, "{text}");
    for (alpha, e) in &last {
        assert!(*e <= 1e-8, "alpha {alpha}: final e = {e}");
    }
}

/// Review turn 4, R9: `bench` took no lock (a bench into a directory a running `run` held
/// exited 0) and skipped the beyond-model judgement (E in GPa: every solve "Converged",
/// exit 0, where `run` says beyond_model).
#[test]
fn bench_locks_its_directory_and_judges_answers_as_run_does() {
    let case = Temp::file("bench-r9", SMALL);
    let out = Temp(temp_path("bench-r9-out"));
    std::fs::create_dir_all(&out.0).unwrap();
    let lock = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(out.0.join(".tensolve.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let o = tensolve(&["bench", case.arg(), "--out", out.arg(), "--quiet"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("in use by another tensolve run"),
        "{}",
        stderr(&o)
    );
    assert!(!out.0.join("bench.csv").exists());
    drop(lock);
    let o = tensolve(&[
        "bench",
        case.arg(),
        "--out",
        out.arg(),
        "--quiet",
        "--set",
        "cables.young=100",
        "--set",
        "bars.young=200",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("BeyondModel"), "{}", stderr(&o));
}
