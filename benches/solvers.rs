//! Solver timings on two cases: the paper's 16 x 16 grid at α = 1 and a 64 x 64 grid at
//! α = 0.15. Per case: the shared set-up (structure + taut stiffness factor) alone, then for
//! each solver its set-up + solve (the headline figure) and its solve alone.
//!
//! Run with `cargo bench --bench solvers`. Solver settings are the defaults, which is what
//! `tensolve run` uses for these cases (neither sets `solver.tolerance` or `max_iterations`).

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, SamplingMode};
use std::path::Path;
use std::time::Duration;
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use tensolve::solvers::{AnySolver, Silent, TautStiffness};
use tensolve::structure::Structure;

/// Sets a solver up on a structure and its taut stiffness (both borrowed).
type Build = for<'a> fn(&'a Structure, &'a TautStiffness) -> Box<dyn AnySolver + 'a>;

/// `<name>/setup+solve` (TautStiffness::new + the solver's set-up + solve, from the structure
/// already built) and `<name>/solve` (set-up done once, outside the timing). The solve is
/// checked to converge once, before anything is timed.
fn bench_solver(
    group: &mut BenchmarkGroup<WallTime>,
    name: &str,
    structure: &Structure,
    load: &[f64],
    build: Build,
) {
    let taut = taut_stiffness(structure);
    let mut solver = build(structure, &taut);
    let info = solver.solve(load, None, &mut Silent).info;
    assert!(
        info.status.converged(),
        "{name}: {:?} after {} iterations (residual {:e})",
        info.status,
        info.iterations,
        info.residual
    );
    group.bench_function(format!("{name}/setup+solve"), |b| {
        b.iter(|| build(structure, &taut_stiffness(structure)).solve(load, None, &mut Silent))
    });
    group.bench_function(format!("{name}/solve"), |b| {
        b.iter(|| solver.solve(load, None, &mut Silent))
    });
}

fn taut_stiffness(structure: &Structure) -> TautStiffness {
    TautStiffness::new(structure).expect("taut stiffness is regular")
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
    let structure = case.structure();
    let load: Vec<f64> = structure.unit_load.iter().map(|f| alpha * f).collect();
    let mut group = c.benchmark_group(id);
    configure(&mut group);
    group.bench_function("shared-setup", |b| {
        b.iter(|| {
            let structure = case.structure();
            let taut = taut_stiffness(&structure);
            (structure, taut)
        })
    });
    bench_solver(&mut group, "newton", &structure, &load, |s, t| {
        Box::new(Newton::new(s, t, NewtonSettings::default()).expect("newton set-up"))
    });
    bench_solver(&mut group, "pcg-lcp", &structure, &load, |s, t| {
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

criterion_group!(benches, solvers);
criterion_main!(benches);
