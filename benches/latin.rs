//! LATIN timings on the paper's case at α = 1 (docs/method.md §5, paper §5.4): set-up and one iteration
//! of `mono-latin` and `micro-macro` (4 × 4 substructures), on all cores and on one thread
//! (the paper's ratios are for one processor), and the whole solve to e < 1e-3 against the
//! Newton reference (set-up included, reference excluded).
//!
//! Run with `cargo bench --bench latin`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;
use std::time::Duration;
use tensolve::solvers::latin::{Latin, LatinSettings};
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
    let structure = case.structure();
    let load: Vec<f64> = structure.unit_load.clone();
    let taut = TautStiffness::new(&structure).expect("regular");
    let reference = Reference::new(
        &structure,
        &Newton::new(&structure, &taut, NewtonSettings::default())
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
        let mut solver = Latin::new(&structure, settings(subdomains)).expect("set-up");
        let state = solver.init(&load);
        group.bench_function(format!("{name}/setup"), |b| {
            b.iter(|| Latin::new(&structure, settings(subdomains)).expect("set-up"))
        });
        group.bench_function(format!("{name}/setup-1thread"), |b| {
            b.iter(|| one_thread.install(|| Latin::new(&structure, settings(subdomains))))
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
                let mut solver = Latin::new(&structure, settings(subdomains)).expect("set-up");
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

criterion_group!(benches, latin);
criterion_main!(benches);
