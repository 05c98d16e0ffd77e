//! newton at scale: `cases/scale-128.toml` (147 k free dofs, α = 0.04) and
//! `cases/scale-256.toml` (590 k free dofs, α = 0.01), set-up included (structure, taut
//! stiffness with its mechanism check, newton's set-up, the solve), each checked to converge
//! once before it is timed.
//!
//! Run with `cargo bench --bench scale` (about 10 minutes: ten samples of one solve each;
//! `-- scale128` for the smaller one alone). Peak memory is not measured here: use
//! `/usr/bin/time -v target/release/tensolve run cases/scale-256.toml`.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use std::path::Path;
use std::time::Duration;
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::{AnySolver, Silent, TautStiffness};

fn bench_case(c: &mut Criterion, id: &str, file: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(file);
    let case = tensolve::case::load(&path).expect("case loads");
    let alpha = case.load.alphas[0];
    let setup_and_solve = || {
        let model = case.model();
        let taut = TautStiffness::new(&model).expect("taut stiffness is regular");
        let load = model.load(alpha);
        let mut newton =
            Newton::new(&model, &taut, NewtonSettings::default()).expect("newton set-up");
        newton.solve(&load, None, &mut Silent).info
    };
    let info = setup_and_solve();
    assert!(
        info.status.converged() && info.stopping_value <= 1e-10,
        "{id}: {info:?}"
    );
    let mut group = c.benchmark_group(id);
    group.sample_size(10);
    group.sampling_mode(SamplingMode::Flat);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(10));
    group.bench_function("newton/setup+solve", |b| b.iter(setup_and_solve));
    group.finish();
}

fn scale(c: &mut Criterion) {
    tensolve::app::allocator::retain_freed_memory();
    bench_case(c, "scale128_alpha0.04", "scale-128.toml");
    bench_case(c, "scale256_alpha0.01", "scale-256.toml");
}

criterion_group!(benches, scale);
criterion_main!(benches);
