//! What `large` costs in each solver (issue 44), measured in one run as medians:
//! - `sweep41`: the paper case's 41-α sweep (α = 0, 0.03, …, 1.2), each solver set up once,
//!   under `linear` (warm starts, as `tensolve run`) and under `large` (along the load path),
//!   and their ratio;
//! - `grid128`: micro-macro against newton under `large` on `cases/scale-128.toml` at a small
//!   α (one solve from the prestressed state), with the solvers' default settings.
//!
//! - `steps`: where `large`'s time goes in pcg-lcp, mono-latin and micro-macro on that sweep
//!   (one run): the linearised solves' set-up seconds and inner iterations per Newton step.
//!
//! - `auto`: what `model.geometry = "auto"` costs: `tensolve run` of the paper case (newton,
//!   then mono-latin) over 41 α from 0 to 0.05 (every row `linear`: the cost of measuring each
//!   α against `large`) against the case pinned `linear`, and over 41 α from 0 to 1.2 (`large`
//!   from α = 0.09) against the case pinned `large`.
//!
//! Run with `cargo bench --bench large` (`-- sweep41`, `-- grid128`, `-- steps` or `-- auto` for one part). Each
//! figure is the median of [`REPEATS`] runs (the machine is shared and noisy).

use std::path::Path;
use std::time::Instant;
use tensolve::app::setup::{prepare, set_up, SetUpSolver};
use tensolve::case::Case;
use tensolve::decomposition::OneProcess;
use tensolve::model::GeometricModel;
use tensolve::solvers::large::{Large, LinearisedStep};
use tensolve::solvers::{AnySolver, Equilibrium, LoadPath, Method, Settings, Silent};

const REPEATS: usize = 3;

fn case(name: &str, geometry: GeometricModel) -> Case {
    let path = format!("{}/cases/{name}", env!("CARGO_MANIFEST_DIR"));
    let mut case = tensolve::case::load(Path::new(&path)).expect("case loads");
    case.model = geometry;
    case.model_auto = false;
    case
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// One sweep of `solver` over `alphas` (each α from the previous answer; `large` from its
/// own last equilibrium): seconds and the summed iterations. Every solve must converge.
fn sweep(solver: &mut SetUpSolver<'_>, case: &Case, alphas: &[f64]) -> (f64, usize) {
    let model = case.model();
    let clock = Instant::now();
    let (mut previous, mut iterations): (Option<Equilibrium>, usize) = (None, 0);
    for &alpha in alphas {
        let load = model.load(alpha);
        let solution = solver
            .solver
            .solve_from(&load, previous.as_ref(), None, &mut Silent);
        assert!(
            solution.info.status.converged(),
            "{} {:?} at α {alpha}: {:?}",
            solver.method.name(),
            case.model,
            solution.info
        );
        iterations += solution.info.iterations;
        previous = Some(solution.equilibrium);
    }
    (clock.elapsed().as_secs_f64(), iterations)
}

/// The 41-α sweep per solver, `linear` against `large`.
fn sweep41() {
    let alphas: Vec<f64> = (0..41).map(|i| 1.2 * i as f64 / 40.0).collect();
    println!("sweep41: the paper case, 41 α from 0 to 1.2, median of {REPEATS} sweeps");
    println!("solver       linear s  (its/α)   large s  (steps/α)   large / linear");
    for method in Method::ALL {
        let mut row = Vec::new();
        for geometry in [GeometricModel::Linear, GeometricModel::Large] {
            let case = case("paper.toml", geometry);
            let prepared = prepare(&case).expect("prepared");
            let mut seconds = Vec::new();
            let mut iterations = 0;
            for _ in 0..REPEATS {
                // Set up afresh each time: `large` keeps its path's last equilibrium.
                let mut solver = set_up(method, &case.solver, &prepared).expect("set up");
                let (s, its) = sweep(&mut solver, &case, &alphas);
                seconds.push(s);
                iterations = its;
            }
            row.push((median(seconds), iterations as f64 / alphas.len() as f64));
        }
        println!(
            "{:12} {:8.3}  ({:5.1})  {:8.3}  ({:5.1})    {:6.1}",
            method.name(),
            row[0].0,
            row[0].1,
            row[1].0,
            row[1].1,
            row[1].0 / row[0].0
        );
    }
}

/// micro-macro against newton under `large` on the 128 × 128 grid.
fn grid128() {
    let alpha = 0.01;
    println!("grid128: cases/scale-128.toml under large at α = {alpha}, median of {REPEATS}");
    let case = {
        let mut case = case("scale-128.toml", GeometricModel::Large);
        case.load.alphas = vec![alpha];
        case
    };
    let prepared = prepare(&case).expect("prepared");
    let mut times = Vec::new();
    for method in [Method::Newton, Method::MicroMacro] {
        let mut seconds = Vec::new();
        let mut steps = 0;
        for _ in 0..REPEATS {
            let clock = Instant::now();
            let mut solver = set_up(method, &case.solver, &prepared).expect("set up");
            let (_, its) = sweep(&mut solver, &case, &[alpha]);
            seconds.push(clock.elapsed().as_secs_f64());
            steps = its;
        }
        let s = median(seconds);
        println!(
            "{:12} {s:8.2} s set-up + solve, {steps} Newton steps",
            method.name()
        );
        times.push(s);
    }
    println!("micro-macro / newton: {:.1}", times[1] / times[0]);
}

/// Where the time of `large` goes in the solvers that find their directions on the linearised
/// problems: the 41-α sweep once, the direction rule's own counters.
fn steps() {
    let alphas: Vec<f64> = (0..41).map(|i| 1.2 * i as f64 / 40.0).collect();
    let case = case("paper.toml", GeometricModel::Large);
    let model = case.model();
    println!("steps: the paper case under large, 41 α, one sweep");
    println!("solver       seconds  Newton steps  set-up s  inner its/step  unconverged");
    for method in [Method::PcgLcp, Method::MonoLatin, Method::MicroMacro] {
        let step = match case.solver.settings(method) {
            Settings::PcgLcp(settings) => LinearisedStep::pcg_lcp(settings),
            Settings::MonoLatin(settings) | Settings::MicroMacro(settings) => {
                LinearisedStep::latin(&model, settings, &OneProcess).unwrap()
            }
            Settings::Newton(_) => unreachable!("newton finds its own directions"),
        };
        let mut path = LoadPath::new(Large::linearised(&model, step));
        let clock = Instant::now();
        let mut previous: Option<Equilibrium> = None;
        for &alpha in &alphas {
            let solution =
                path.solve_from(&model.load(alpha), previous.as_ref(), None, &mut Silent);
            assert!(
                solution.info.status.converged(),
                "{alpha}: {:?}",
                solution.info
            );
            previous = Some(solution.equilibrium);
        }
        let seconds = clock.elapsed().as_secs_f64();
        let work = path.solver().step_rule().work();
        println!(
            "{:12} {seconds:7.3}  {:12}  {:8.3}  {:14.1}  {:11}",
            method.name(),
            work.steps,
            work.setup_seconds,
            work.inner_iterations as f64 / work.steps.max(1) as f64,
            work.inner_unconverged
        );
    }
}

fn main() {
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let wanted = |name: &str| filter.is_empty() || filter.iter().any(|f| name.contains(f));
    if wanted("sweep41") {
        sweep41();
    }
    if wanted("grid128") {
        grid128();
    }
    if wanted("steps") {
        steps();
    }
    if wanted("auto") {
        auto();
    }
}

/// `tensolve run` of the paper case by `method` over `alphas` under `geometry` (`None`:
/// `auto`), no file but the summary: seconds, and the rows' models.
fn run_paper(
    method: Method,
    alphas: &[f64],
    geometry: Option<GeometricModel>,
) -> (f64, Vec<GeometricModel>) {
    let mut case = case("paper.toml", geometry.unwrap_or(GeometricModel::Linear));
    case.model_auto = geometry.is_none();
    case.load.alphas = alphas.to_vec();
    case.solver.reference = tensolve::case::ReferenceChoice::None;
    case.output.plots = false;
    case.output.history = false;
    case.output.tensions = false;
    case.output.displacements = false;
    let out = std::env::temp_dir().join(format!("tensolve-bench-auto-{}", std::process::id()));
    let options = tensolve::app::sweep::RunOptions {
        out_dir: Some(out.clone()),
        methods: Some(vec![method]),
    };
    let clock = Instant::now();
    let rows = tensolve::app::sweep::run(&case, &options, &mut |_| {}).expect("the run converges");
    let seconds = clock.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&out);
    (seconds, rows.iter().map(|r| r.model).collect())
}

/// What `auto` costs beside the model it picks.
fn auto() {
    let small: Vec<f64> = (0..41).map(|i| 0.05 * i as f64 / 40.0).collect();
    let whole: Vec<f64> = (0..41).map(|i| 1.2 * i as f64 / 40.0).collect();
    println!("auto: tensolve run of the paper case, 41 α, median of {REPEATS} runs");
    println!("solver       α range    auto s    pinned s  (model)   auto / pinned  rows linear");
    for method in [Method::Newton, Method::MonoLatin] {
        for (range, alphas, pinned) in [
            ("0 .. 0.05", &small, GeometricModel::Linear),
            ("0 .. 1.2", &whole, GeometricModel::Large),
        ] {
            let mut auto_seconds = Vec::new();
            let mut pinned_seconds = Vec::new();
            let mut linear_rows = 0;
            for _ in 0..REPEATS {
                let (s, models) = run_paper(method, alphas, None);
                auto_seconds.push(s);
                linear_rows = models
                    .iter()
                    .filter(|&&m| m == GeometricModel::Linear)
                    .count();
                pinned_seconds.push(run_paper(method, alphas, Some(pinned)).0);
            }
            let (a, p) = (median(auto_seconds), median(pinned_seconds));
            println!(
                "{:12} {range:9} {a:8.3}  {p:8.3}  ({:6})   {:6.2}         {linear_rows} / 41",
                method.name(),
                pinned.name(),
                a / p
            );
        }
    }
}
