//! Solver timings on two cases: the paper's 16 x 16 grid at α = 1 and a 64 x 64 grid at
//! α = 0.15. Per case: the shared set-up (structure + taut stiffness factor) alone, then for
//! each solver its set-up + solve (the headline figure) and its solve alone. Then a 41-α
//! sweep of the paper case, cold and warm-started (`paper_sweep41`). The larger grids are in
//! `benches/scale.rs`. `paper_alpha1_floor` times the sparse kernels alone that a cold newton
//! solve of the paper case runs, beside the whole solve: the floor that set-up + solve cannot
//! go below without fewer factorizations or faster ones.
//!
//! Run with `cargo bench --bench solvers`. Solver settings are the defaults, which is what
//! `tensolve run` uses for these cases (neither sets `solver.tolerance` or `max_iterations`).

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, SamplingMode};
use faer::Mat;
use std::path::Path;
use std::time::Duration;
use tensolve::linalg::PROBE_ITERATIONS;
use tensolve::model::{GeometricModel, Model};
use tensolve::solvers::large::LargeNewton;
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use tensolve::solvers::{AnySolver, Equilibrium, LoadPath, Silent, TautStiffness};

/// Sets a solver up on a model and its taut stiffness (both borrowed).
type Build = for<'a> fn(&'a Model, &'a TautStiffness) -> Box<dyn AnySolver + 'a>;

/// `<name>/setup+solve` (TautStiffness::new + the solver's set-up + solve, from the structure
/// already built) and `<name>/solve` (set-up done once, outside the timing). The solve is
/// checked to converge once, before anything is timed.
fn bench_solver(
    group: &mut BenchmarkGroup<WallTime>,
    name: &str,
    model: &Model,
    load: &[f64],
    build: Build,
) {
    let taut = taut_stiffness(model);
    let mut solver = build(model, &taut);
    let info = solver.solve(load, None, &mut Silent).info;
    assert!(
        info.status.converged(),
        "{name}: {:?} after {} iterations (residual {:e})",
        info.status,
        info.iterations,
        info.stopping_value
    );
    group.bench_function(format!("{name}/setup+solve"), |b| {
        b.iter(|| build(model, &taut_stiffness(model)).solve(load, None, &mut Silent))
    });
    group.bench_function(format!("{name}/solve"), |b| {
        b.iter(|| solver.solve(load, None, &mut Silent))
    });
}

/// The model of `cases/paper.toml`.
fn paper_model() -> Model {
    tensolve::case::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/paper.toml"
    )))
    .expect("case loads")
    .model()
}

fn taut_stiffness(model: &Model) -> TautStiffness {
    TautStiffness::new(model).expect("taut stiffness is regular")
}

/// All benchmarks of one case at one α, in the group `id`.
fn bench_case(
    c: &mut Criterion,
    id: &str,
    path: &str,
    alpha: f64,
    configure: impl FnOnce(&mut BenchmarkGroup<WallTime>),
) {
    let mut case = tensolve::case::load(Path::new(path)).expect("case loads");
    case.load.alphas = vec![alpha];
    let model = case.model();
    let load = model.load(alpha);
    let mut group = c.benchmark_group(id);
    configure(&mut group);
    group.bench_function("shared-setup", |b| {
        b.iter(|| {
            let model = case.model();
            let taut = taut_stiffness(&model);
            (model, taut)
        })
    });
    bench_solver(&mut group, "newton", &model, &load, |s, t| {
        Box::new(Newton::new(s, t, NewtonSettings::default()).expect("newton set-up"))
    });
    // The method before factor reuse (a factorization at every step that is not all-taut).
    bench_solver(&mut group, "newton-refactorise", &model, &load, |s, t| {
        let settings = NewtonSettings {
            reuse_factor: false,
            ..NewtonSettings::default()
        };
        Box::new(Newton::new(s, t, settings).expect("newton set-up"))
    });
    bench_solver(&mut group, "pcg-lcp", &model, &load, |s, t| {
        Box::new(PcgLcp::new(s, t, PcgLcpSettings::default()))
    });
    group.finish();
}

fn solvers(c: &mut Criterion) {
    bench_case(
        c,
        "paper_alpha1",
        concat!(env!("CARGO_MANIFEST_DIR"), "/cases/paper.toml"),
        1.0,
        |g| {
            g.warm_up_time(Duration::from_secs(1));
            g.measurement_time(Duration::from_secs(4));
        },
    );
    // 0.2 to 1.2 s per iteration: 10 samples of equal size (flat sampling) keep this group
    // near 100 s and the whole run near 2 min. pcg-lcp/setup+solve then fits only one
    // iteration per sample, and criterion warns that it needs a little over 10 s: harmless.
    bench_case(
        c,
        "scale64_alpha0.15",
        concat!(env!("CARGO_MANIFEST_DIR"), "/cases/scale-64.toml"),
        0.15,
        |g| {
            g.sample_size(10);
            g.sampling_mode(SamplingMode::Flat);
            g.warm_up_time(Duration::from_secs(2));
            g.measurement_time(Duration::from_secs(10));
        },
    );
}

/// The sparse kernels a cold newton solve of the paper case at α = 1 runs, counted from the
/// solve itself (printed once), then timed alone on K (a Hessian's factor and solves cost what
/// K's do: same symbolic factor, same flops): K's pattern, the symbolic analysis, one numeric
/// factorization for K and one per factorized Hessian, one solve per probe iteration, per
/// step solved with a factor and per CG iteration (its preconditioner), and one forward
/// substitution with as many right-hand sides as the correction's columns. Everything else
/// newton does (assemblies, residuals, line searches, CG's products) is left out, so
/// `kernels` is a lower bound of `newton/setup+solve`, timed in the same group.
/// `pattern+analysis` is the part of `kernels` before the first factorization; the rest is
/// faer's numeric work.
fn floor(c: &mut Criterion) {
    let model = paper_model();
    let load = model.structure.unit_load.clone();
    let taut = taut_stiffness(&model);
    let mut newton = Newton::new(&model, &taut, NewtonSettings::default()).expect("set-up");
    let info = newton.solve(&load, None, &mut Silent).info;
    assert!(info.status.converged(), "{info:?}");
    let work = newton.work();
    let factorized_steps = work.steps - work.taut_steps - work.reused_steps;
    let factorizations = 1 + work.factorizations;
    let solves = PROBE_ITERATIONS + work.taut_steps + factorized_steps + work.cg_iterations;
    let columns = work.correction_columns;
    println!(
        "paper_alpha1_floor: {factorizations} factorizations, {solves} solves, a forward \
         substitution with {columns} columns ({work:?})"
    );
    let values = taut.values.clone();
    let n = model.structure.n_free;
    let mut group = c.benchmark_group("paper_alpha1_floor");
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(4));
    group.bench_function("kernels", |b| {
        b.iter(|| {
            let (pattern, mut factor) = TautStiffness::analyse(&model.structure);
            for _ in 0..factorizations {
                factor
                    .factorize(&pattern, &values)
                    .expect("K is positive definite");
            }
            let mut x = load.clone();
            for _ in 0..solves {
                factor.solve_in_place(&mut x);
            }
            let mut w = Mat::<f64>::zeros(n, columns);
            for j in 0..columns {
                w[((97 * j) % n, j)] = 1.0;
            }
            factor.forward_block_in_place(w.as_mut());
            (x, w)
        })
    });
    // The part of `kernels` that is tensolve's own code and faer's symbolic analysis; the rest
    // of `kernels` is faer's numeric work.
    group.bench_function("pattern+analysis", |b| {
        b.iter(|| TautStiffness::analyse(&model.structure))
    });
    group.bench_function("newton/setup+solve", |b| {
        b.iter(|| {
            let taut = taut_stiffness(&model);
            let mut newton = Newton::new(&model, &taut, NewtonSettings::default()).expect("set-up");
            newton.solve(&load, None, &mut Silent).info
        })
    });
    group.finish();
}

/// α = 0, 0.03, …, 1.2: the 41-α sweep of the paper case.
fn sweep_alphas() -> Vec<f64> {
    (0..41).map(|i| 1.2 * i as f64 / 40.0).collect()
}

/// One sweep of `solver` over `alphas`, each α warm-started from the previous answer when
/// `warm`; returns the summed iterations.
fn run_sweep(solver: &mut dyn AnySolver, model: &Model, alphas: &[f64], warm: bool) -> usize {
    let mut previous: Option<Equilibrium> = None;
    let mut iterations = 0;
    for &alpha in alphas {
        let load = model.load(alpha);
        let start = if warm { previous.as_ref() } else { None };
        let solution = solver.solve_from(&load, start, None, &mut Silent);
        assert!(
            solution.info.status.converged(),
            "alpha {alpha}: {:?}",
            solution.info
        );
        iterations += solution.info.iterations;
        previous = Some(solution.equilibrium);
    }
    iterations
}

/// The 41-α sweep of the paper case, solvers set up once (outside the timing): `cold` starts
/// every α from scratch, `warm` from the previous α's answer (what `tensolve run` does);
/// newton `cold-refactorise` also refactorises at every step (no factor reuse: the method
/// before warm starts). Prints the iterations and factorizations per α of each variant once.
fn sweep(c: &mut Criterion) {
    let model = paper_model();
    let taut = taut_stiffness(&model);
    let alphas = sweep_alphas();
    let refactorise = NewtonSettings {
        reuse_factor: false,
        ..NewtonSettings::default()
    };
    let newton_variants = [
        ("newton/cold-refactorise", refactorise, false),
        ("newton/cold", NewtonSettings::default(), false),
        ("newton/warm", NewtonSettings::default(), true),
    ];
    for (name, settings, warm) in newton_variants {
        let mut newton = Newton::new(&model, &taut, settings).expect("newton set-up");
        let iterations = run_sweep(&mut newton, &model, &alphas, warm);
        let work = newton.work();
        println!(
            "paper_sweep41/{name}: {:.2} iterations, {:.2} factorizations, {:.2} CG-reused steps per alpha ({work:?})",
            iterations as f64 / alphas.len() as f64,
            work.factorizations as f64 / alphas.len() as f64,
            work.reused_steps as f64 / alphas.len() as f64,
        );
    }
    for warm in [false, true] {
        let mut pcg = PcgLcp::new(&model, &taut, PcgLcpSettings::default());
        let iterations = run_sweep(&mut pcg, &model, &alphas, warm);
        println!(
            "paper_sweep41/pcg-lcp/{}: {:.2} iterations per alpha",
            if warm { "warm" } else { "cold" },
            iterations as f64 / alphas.len() as f64
        );
    }
    let mut group = c.benchmark_group("paper_sweep41");
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(5));
    group.sample_size(20);
    for (name, settings, warm) in newton_variants {
        group.bench_function(name, |b| {
            b.iter(|| {
                // A fresh solver per sweep: no factor carried over from the previous sample.
                let mut newton = Newton::new(&model, &taut, settings).expect("set-up");
                run_sweep(&mut newton, &model, &alphas, warm)
            })
        });
    }
    for (name, warm) in [("pcg-lcp/cold", false), ("pcg-lcp/warm", true)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut pcg = PcgLcp::new(&model, &taut, PcgLcpSettings::default());
                run_sweep(&mut pcg, &model, &alphas, warm)
            })
        });
    }
    // The geometric models (docs/method.md §8) on the same sweep: `prestress` warm-started like
    // `newton/warm`; `large` along its load path (each α from the previous equilibrium).
    for (name, geometry) in [
        ("newton/prestress-warm", GeometricModel::Prestress),
        ("newton/large", GeometricModel::Large),
    ] {
        let model = Model::new(paper_model().structure, geometry);
        let taut = taut_stiffness(&model);
        let solve = |model: &Model, taut: &TautStiffness| -> (usize, String) {
            if model.updates_geometry() {
                let newton = LargeNewton::new(model, taut, NewtonSettings::default());
                let mut large = LoadPath::new(newton);
                let iterations = run_sweep(&mut large, model, &alphas, true);
                let work = (large.work(), large.solver().step_rule().work());
                (iterations, format!("{work:?}"))
            } else {
                let mut newton =
                    Newton::new(model, taut, NewtonSettings::default()).expect("set-up");
                let iterations = run_sweep(&mut newton, model, &alphas, true);
                (iterations, format!("{:?}", newton.work()))
            }
        };
        let (iterations, work) = solve(&model, &taut);
        println!(
            "paper_sweep41/{name}: {:.2} iterations per alpha ({work})",
            iterations as f64 / alphas.len() as f64
        );
        group.bench_function(name, |b| b.iter(|| solve(&model, &taut)));
    }
    group.finish();
}

/// Criterion under the CLI's allocator policy (src/app/allocator.rs), set once for both
/// groups, so that the benchmarks time what `tensolve` runs.
fn configured() -> Criterion {
    tensolve::app::allocator::retain_freed_memory();
    Criterion::default()
}

criterion_group! {
    name = benches;
    config = configured();
    targets = solvers, sweep, floor
}
criterion_main!(benches);
