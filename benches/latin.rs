//! LATIN timings on the paper's case at α = 1 (docs/method.md §5, paper §5.4): set-up and one iteration
//! of `mono-latin` and `micro-macro` (4 × 4 substructures), on all cores and on one thread
//! (the paper's ratios are for one processor), and the whole solve to e < 1e-3 against the
//! Newton reference (set-up included, reference excluded).
//!
//! Run with `cargo bench --bench latin`.
//!
//! `cargo bench --bench latin -- table` prints instead the scaling table of docs/method.md §9
//! (issue "micro-macro earns its place"): grids of n × n modules clamped on all lower edges at
//! ≈ 14 % slack (n = 16 α 2.4, 32 α 0.6, 64 α 0.15, 128 α 0.0375), micro-macro at its
//! defaults on substructures of H × H modules, with the bilateral floor
//! (`cables.unilateral = false`) on the same partition, newton's and mono-latin's time beside
//! it; e against newton. `-- table status` adds the status-following policy of before
//! (`search_direction = "status"`); `-- table quick` stops at 64 × 64.
//!
//! `cargo bench --bench latin -- atscale` prints the table of issue 41 ("micro-macro at scale")
//! on the **default** partition and settings: grids of n × n modules clamped on all lower edges
//! at ≈ 14.6 % slack (n = 128 α 0.0375, 256 α 0.01, 512 α 0.0025; `-- atscale 1024` adds 1024
//! α 0.000625, `-- atscale quick` stops at 256): micro-macro's iterations, rebuilds, η and r(U)
//! at the stop, set-up and solve seconds; the bilateral count (`cables.unilateral = false`) on
//! the same partition; newton's iterations and seconds and e of micro-macro against newton
//! (up to 512 × 512), and newton substructured (`solver.linear = "krylov"`, K never factorised
//! whole): its PCG iterations over all Newton steps, Newton steps and seconds, its slack set
//! checked against direct newton's; and the peak resident memory of each of the three solves
//! (micro-macro, direct newton, krylov newton; the structure included: `VmHWM` reset before
//! each, after freed heap memory is handed back). Run it with `RAYON_NUM_THREADS` set to
//! compare thread counts.
//!
//! `cargo bench --bench latin -- factor [SIDE]` times K's factor on SIDE × SIDE modules (256:
//! 590 k free dofs), in newton's own order, with faer's parallelism `Par::rayon(t)`, t = 1, 2,
//! 4 … threads: the numeric factorization, a solve of one right-hand side and of a block of 16
//! (medians of 3); then two whole factorizations at once on one thread each against one
//! alone, the most that factoring the two halves of the elimination tree side by side could
//! gain; and the factor in the two halves of the nested dissection's top level side by side,
//! as newton's Hessian on two threads (docs/performance.md, "newton at scale, and on two threads").

use criterion::{criterion_group, Criterion};
use std::path::Path;
use std::time::Duration;
use tensolve::solvers::latin::{Latin, LatinSettings, SearchPolicy};
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::{AnySolver, Reference, Silent, Solver, TautStiffness};

fn settings(subdomains: [usize; 2]) -> LatinSettings {
    LatinSettings {
        subdomains,
        ..LatinSettings::default()
    }
}

fn latin(c: &mut Criterion) {
    tensolve::app::allocator::retain_freed_memory();
    let case = tensolve::case::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/paper.toml"
    )))
    .expect("case loads");
    let model = case.model();
    let load: Vec<f64> = model.structure.unit_load.clone();
    let taut = TautStiffness::new(&model).expect("regular");
    let reference = Reference::new(
        &model,
        &Newton::new(&model, &taut, NewtonSettings::default())
            .expect("newton")
            .solve(&load, None, &mut Silent)
            .equilibrium
            .displacements,
    );
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");

    let mut group = c.benchmark_group("paper_alpha1");
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(4));
    for (name, subdomains) in [("mono-latin", [1, 1]), ("micro-macro", [4, 4])] {
        let mut solver = Latin::new(&model, settings(subdomains)).expect("set-up");
        let state = solver.init(&load);
        group.bench_function(format!("{name}/setup"), |b| {
            b.iter(|| Latin::new(&model, settings(subdomains)).expect("set-up"))
        });
        group.bench_function(format!("{name}/setup-1thread"), |b| {
            b.iter(|| one_thread.install(|| Latin::new(&model, settings(subdomains))))
        });
        group.bench_function(format!("{name}/iteration"), |b| {
            b.iter_batched_ref(
                || state.clone(),
                |s| solver.next_iter(s),
                criterion::BatchSize::SmallInput,
            )
        });
        group.bench_function(format!("{name}/iteration-1thread"), |b| {
            b.iter_batched_ref(
                || state.clone(),
                |s| one_thread.install(|| solver.next_iter(s)),
                criterion::BatchSize::SmallInput,
            )
        });
        group.bench_function(format!("{name}/to-e-1e-3"), |b| {
            b.iter(|| {
                let mut solver = Latin::new(&model, settings(subdomains)).expect("set-up");
                let mut state = solver.init(&load);
                while reference.error(&solver.elongations(&state)) >= 1e-3 {
                    solver.next_iter(&mut state);
                }
                state.iteration
            })
        });
    }
    group.finish();
}

/// One row of the scaling table: iterations to e < 1e-3 and e < 1e-6, the total, rebuilds,
/// set-up and solve seconds, e at the stop.
struct Row {
    to_1e3: Option<usize>,
    to_1e6: Option<usize>,
    total: usize,
    rebuilds: usize,
    setup: f64,
    solve: f64,
    final_e: f64,
    converged: bool,
}

/// The case text of an n × n grid at `alpha`, all lower edges clamped.
fn grid_case(n: usize, alpha: f64, extra: &str) -> String {
    format!(
        "[grid]\nmodules = [{n}, {n}]\n[supports]\nclamp = \"lower-all-edges\"\n\
         [load]\nalpha = [{alpha}]\n{extra}\n[solver]\nmethods = [\"micro-macro\"]\n\
         max_iterations = 3000\n"
    )
}

fn latin_row(
    model: &tensolve::model::Model,
    settings: LatinSettings,
    load: &[f64],
    reference: &Reference,
) -> Row {
    let clock = std::time::Instant::now();
    let mut solver = Latin::new(model, settings).expect("set-up");
    let setup = clock.elapsed().as_secs_f64();
    // First the iterates' errors against the reference, then the solve timed alone (the same
    // iterates: the solver is deterministic).
    let mut state = solver.init(load);
    let mut errors = vec![reference.error(&solver.elongations(&state))];
    let converged = loop {
        let progress = solver.progress(&state);
        if let Some(status) = progress.stop {
            break status.converged();
        }
        if state.iteration >= settings.max_iterations {
            break false;
        }
        solver.next_iter(&mut state);
        errors.push(reference.error(&solver.elongations(&state)));
    };
    let clock = std::time::Instant::now();
    let mut state = solver.init(load);
    while solver.progress(&state).stop.is_none() && state.iteration < settings.max_iterations {
        solver.next_iter(&mut state);
    }
    let solve = clock.elapsed().as_secs_f64();
    let first = |tol: f64| errors.iter().position(|&e| e < tol);
    Row {
        to_1e3: first(1e-3),
        to_1e6: first(1e-6),
        total: state.iteration,
        rebuilds: state.rebuilds,
        setup,
        solve,
        final_e: *errors.last().unwrap_or(&f64::NAN),
        converged,
    }
}

fn table(args: &[String]) {
    tensolve::app::allocator::retain_freed_memory();
    let quick = args.iter().any(|a| a == "quick");
    let with_status = args.iter().any(|a| a == "status");
    let grids: &[(usize, f64, &[usize])] = &[
        (16, 2.4, &[4]),
        (32, 0.6, &[4]),
        (64, 0.15, &[4, 8, 16, 32]),
        (128, 0.0375, &[4, 8, 16, 32]),
    ];
    println!(
        "| grid, substructures | policy | to e < 1e-3 | to e < 1e-6 | total | rebuilds | e at stop | set-up s | solve s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let show = |o: Option<usize>| o.map_or("–".to_string(), |k| k.to_string());
    for &(n, alpha, sizes) in grids {
        if quick && n > 64 {
            break;
        }
        for unilateral in [true, false] {
            let extra = if unilateral {
                ""
            } else {
                "[cables]\nunilateral = false"
            };
            let case = tensolve::case::parse(&grid_case(n, alpha, extra)).expect("case");
            let model = case.model();
            let load = model.load(alpha);
            let taut = TautStiffness::new(&model).expect("regular");
            let clock = std::time::Instant::now();
            let newton = Newton::new(&model, &taut, NewtonSettings::default())
                .expect("newton")
                .solve(&load, None, &mut Silent);
            let newton_seconds = clock.elapsed().as_secs_f64();
            let reference = Reference::new(&model, &newton.equilibrium.displacements);
            let label = if unilateral { "" } else { " bilateral" };
            println!(
                "| {n} × {n}{label}: newton | – | – | – | {} | – | – | – | {newton_seconds:.2} (set-up included) |",
                newton.info.iterations
            );
            let mut policies = vec![("inexact Newton", SearchPolicy::Newton)];
            if with_status && unilateral {
                policies.push(("status-following", SearchPolicy::Status));
            }
            for &h in sizes {
                let parts = n / h;
                for &(name, policy) in &policies {
                    let settings = LatinSettings {
                        subdomains: [parts, parts],
                        policy,
                        max_iterations: 3000,
                        ..LatinSettings::default()
                    };
                    let row = latin_row(&model, settings, &load, &reference);
                    let name = if unilateral { name } else { "bilateral" };
                    println!(
                        "| {n} × {n}, {} of {h} × {h} | {name} | {} | {} | {}{} | {} | {:.1e} | {:.2} | {:.2} |",
                        parts * parts,
                        show(row.to_1e3),
                        show(row.to_1e6),
                        row.total,
                        if row.converged { "" } else { " (not converged)" },
                        row.rebuilds,
                        row.final_e,
                        row.setup,
                        row.solve,
                    );
                }
            }
            if n == 64 && unilateral {
                let settings = LatinSettings::default().monodomain();
                let row = latin_row(&model, settings, &load, &reference);
                println!(
                    "| {n} × {n}: mono-latin | inexact Newton | {} | {} | {} | {} | {:.1e} | {:.2} | {:.2} |",
                    show(row.to_1e3),
                    show(row.to_1e6),
                    row.total,
                    row.rebuilds,
                    row.final_e,
                    row.setup,
                    row.solve,
                );
            }
        }
    }
}

/// One row of the at-scale table: micro-macro at the case's defaults on `model`.
struct ScaleRow {
    iterations: usize,
    rebuilds: usize,
    eta: f64,
    residual: f64,
    converged: bool,
    setup: f64,
    solve: f64,
    elongations: Vec<f64>,
}

fn scale_row(model: &tensolve::model::Model, settings: LatinSettings, load: &[f64]) -> ScaleRow {
    let clock = std::time::Instant::now();
    let mut solver = Latin::new(model, settings).expect("set-up");
    let setup = clock.elapsed().as_secs_f64();
    let clock = std::time::Instant::now();
    let mut state = solver.init(load);
    let converged = loop {
        if let Some(status) = solver.progress(&state).stop {
            break status.converged();
        }
        if state.iteration >= settings.max_iterations {
            break false;
        }
        solver.next_iter(&mut state);
    };
    let solve = clock.elapsed().as_secs_f64();
    ScaleRow {
        iterations: state.iteration,
        rebuilds: state.rebuilds,
        eta: state.eta,
        residual: state.residual,
        converged,
        setup,
        solve,
        elongations: solver.elongations(&state),
    }
}

/// Hand freed heap memory back to the kernel and reset the process's peak resident memory to
/// what is resident now (Linux; elsewhere [`peak_gb`] reads nothing).
fn reset_peak() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory of glibc's arenas.
    unsafe {
        libc::malloc_trim(0);
    }
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The peak resident memory since [`reset_peak`] (`VmHWM`), GB; `None` where unreadable.
fn peak_gb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0 / 1e9)
}

/// `f`'s answer and the peak resident memory while it ran, GB as text ("–" where unreadable).
fn with_peak<T>(f: impl FnOnce() -> T) -> (T, String) {
    reset_peak();
    let answer = f();
    let peak = peak_gb().map_or("–".to_string(), |gb| format!("{gb:.2}"));
    (answer, peak)
}

fn atscale(args: &[String]) {
    tensolve::app::allocator::retain_freed_memory();
    let mut grids = vec![(128, 0.0375), (256, 0.01), (512, 0.0025)];
    if args.iter().any(|a| a == "quick") {
        grids.truncate(2);
    }
    if args.iter().any(|a| a == "1024") {
        grids.push((1024, 0.000625));
    }
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| grid | partition (default) | micro-macro iterations (rebuilds) | η, r(U) at stop | bilateral | set-up s | solve s | newton iterations, s | e vs newton | newton krylov: PCG (steps), s | peak GB: micro-macro, newton, krylov |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (n, alpha) in grids {
        let case_text = |extra: &str| {
            format!(
                "[grid]\nmodules = [{n}, {n}]\n[supports]\nclamp = \"lower-all-edges\"\n\
                 [load]\nalpha = [{alpha}]\n{extra}\n[solver]\nmethods = [\"micro-macro\"]\n"
            )
        };
        let case = tensolve::case::parse(&case_text("")).expect("case");
        let settings = case
            .solver
            .latin_settings(tensolve::solvers::Method::MicroMacro)
            .expect("micro-macro settings");
        let model = case.model();
        let load = model.load(alpha);
        let (row, mm_peak) = with_peak(|| scale_row(&model, settings, &load));
        let (newton, error, krylov, peaks) = if n <= 512 {
            let clock = std::time::Instant::now();
            let (answer, newton_peak) = with_peak(|| {
                let taut = TautStiffness::new(&model).expect("regular");
                Newton::new(&model, &taut, NewtonSettings::default())
                    .expect("newton")
                    .solve(&load, None, &mut Silent)
            });
            let seconds = clock.elapsed().as_secs_f64();
            let reference = Reference::new(&model, &answer.equilibrium.displacements);
            // Substructured, on the case's default partition, without K's factor.
            let krylov_case =
                tensolve::case::parse(&format!("{}linear = \"krylov\"\n", case_text("")))
                    .expect("case");
            let clock = std::time::Instant::now();
            let (krylov, krylov_peak) = with_peak(|| {
                Newton::substructured(&model, krylov_case.solver.newton).solve(
                    &load,
                    None,
                    &mut Silent,
                )
            });
            let krylov_seconds = clock.elapsed().as_secs_f64();
            assert_eq!(krylov.equilibrium.slack, answer.equilibrium.slack);
            (
                format!("{}, {seconds:.2}", answer.info.iterations),
                format!("{:.1e}", reference.error(&row.elongations)),
                format!(
                    "{} ({}), {krylov_seconds:.2}",
                    krylov.info.krylov_iterations.unwrap_or(0),
                    krylov.info.iterations
                ),
                format!("{mm_peak}, {newton_peak}, {krylov_peak}"),
            )
        } else {
            let dash = || "–".to_string();
            (dash(), dash(), dash(), format!("{mm_peak}, –, –"))
        };
        drop(model);
        let bilateral_case =
            tensolve::case::parse(&case_text("[cables]\nunilateral = false")).expect("case");
        let bilateral_model = bilateral_case.model();
        let bilateral = scale_row(&bilateral_model, settings, &load);
        let [sx, sy] = settings.subdomains;
        println!(
            "| {n} × {n} | {} of {} × {} ({sx} × {sy}) | {}{} ({}) | {:.1e}, {:.1e} | {}{} | {:.2} | {:.2} | {newton} | {error} | {krylov} | {peaks} |",
            sx * sy,
            n / sx,
            n / sy,
            row.iterations,
            if row.converged { "" } else { " not converged" },
            row.rebuilds,
            row.eta,
            row.residual,
            bilateral.iterations,
            if bilateral.converged { "" } else { " not converged" },
            row.setup,
            row.solve,
        );
    }
}

/// Median of three timings of `f`, seconds.
fn median3(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..3)
        .map(|_| {
            let clock = std::time::Instant::now();
            f();
            clock.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[1]
}

fn factor_table(args: &[String]) {
    let side: usize = args.iter().find_map(|a| a.parse().ok()).unwrap_or(256);
    let case = tensolve::case::parse(&format!(
        "[grid]\nmodules = [{side}, {side}]\n[supports]\nclamp = \"lower-all-edges\"\n\
         [load]\nalpha = [0.01]\n[solver]\nmethods = [\"newton\"]\n"
    ))
    .expect("case");
    let model = case.model();
    let taut = TautStiffness::new(&model).expect("regular");
    let n = model.structure.n_free;
    println!("{side} x {side} modules, {n} free dofs, newton's own ordering");
    println!("| threads | factorize s | solve 1 column s | solve 16 columns s |");
    println!("|---|---|---|---|");
    let most = rayon::current_num_threads();
    let mut threads = 1;
    while threads <= most {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let (factorize, one, block) = pool.install(|| {
            let par = match threads {
                1 => faer::Par::Seq,
                _ => faer::Par::rayon(threads),
            };
            let mut factor = taut.factor.share_symbolic_with(par);
            let pattern = &taut.pattern;
            let factorize = median3(|| factor.factorize(pattern, &taut.values).expect("spd"));
            let rhs: Vec<f64> = (0..n).map(|k| ((k * 7919) % 1013) as f64).collect();
            let one = median3(|| {
                let mut x = rhs.clone();
                factor.solve_in_place(&mut x);
            });
            let block = median3(|| {
                let mut x: Vec<f64> = rhs.iter().cycle().take(16 * n).copied().collect();
                factor
                    .solve_block_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 16));
            });
            (factorize, one, block)
        });
        println!("| {threads} | {factorize:.3} | {one:.4} | {block:.3} |");
        threads = if threads == most {
            most + 1
        } else {
            (2 * threads).min(most)
        };
    }
    // The most a split of the elimination tree in two (its halves factored side by side)
    // could gain: two whole factorizations at once, one thread each, against one alone.
    if most >= 2 {
        let pattern = &taut.pattern;
        let mut first = taut.factor.share_symbolic_with(faer::Par::Seq);
        let mut second = taut.factor.share_symbolic_with(faer::Par::Seq);
        // Five rounds, each timing one alone then two at once (the machine's load drifts).
        let time = |f: &mut dyn FnMut()| {
            let clock = std::time::Instant::now();
            f();
            clock.elapsed().as_secs_f64()
        };
        let (mut alone, mut both) = (Vec::new(), Vec::new());
        for _ in 0..5 {
            alone.push(time(&mut || {
                first.factorize(pattern, &taut.values).expect("spd");
            }));
            both.push(time(&mut || {
                rayon::join(
                    || first.factorize(pattern, &taut.values).expect("spd"),
                    || second.factorize(pattern, &taut.values).expect("spd"),
                );
            }));
        }
        let median = |mut t: Vec<f64>| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        };
        let (alone, both) = (median(alone), median(both));
        println!(
            "two factorizations at once, one thread each: {both:.3} s against {alone:.3} s \
             alone: {:.2}x the throughput of one thread",
            2.0 * alone / both
        );
        // What newton uses on two threads: the halves side by side, then the separator.
        let mut split = taut
            .factor
            .share_symbolic_split(pattern, 1)
            .expect("a top-level split");
        let halves = median3(|| split.factorize(pattern, &taut.values).expect("spd"));
        println!(
            "in two halves side by side (newton's Hessian on two threads): {halves:.3} s, \
             {:.2}x one thread's whole factor",
            alone / halves
        );
    }
}

criterion_group!(benches, latin);

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "table") {
        table(&args);
        return;
    }
    if args.iter().any(|a| a == "factor") {
        factor_table(&args);
        return;
    }
    if args.iter().any(|a| a == "atscale") {
        atscale(&args);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
