//! Warm starts along a sweep and factor reuse inside newton: they shorten the way, never move
//! the end. Every α of a 41-α sweep of the paper case ends on the same slack set, to the same
//! tolerance, as a cold start with a fresh solver that refactorises at every step.

mod common;

use common::{load, paper_model, relative_difference};
use tensolve::solvers::newton::{Newton, NewtonSettings};
use tensolve::solvers::pcg_lcp::{PcgLcp, PcgLcpSettings};
use tensolve::solvers::{AnySolver, Equilibrium, Silent, Solution, TautStiffness};
use tensolve::structure::Structure;

/// α = 0, 0.03, …, 1.2.
fn alphas() -> Vec<f64> {
    (0..41).map(|i| 1.2 * i as f64 / 40.0).collect()
}

/// One solver along the sweep, each α warm-started from the previous answer.
fn warm_sweep(solver: &mut dyn AnySolver, s: &Structure) -> Vec<Solution> {
    let mut previous: Option<Equilibrium> = None;
    alphas()
        .into_iter()
        .map(|alpha| {
            let solution = solver.solve_from(&load(s, alpha), previous.as_ref(), None, &mut Silent);
            previous = Some(solution.equilibrium.clone());
            solution
        })
        .collect()
}

// Both answers meet r(U) ≤ 1e-10; with the stiffness's conditioning that leaves U agreeing to
// about 1e-9 (measured up to 1.1e-9 on this sweep).
#[test]
fn warm_started_sweeps_end_where_cold_starts_end() {
    let model = paper_model(&[]);
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let plain = NewtonSettings {
        reuse_factor: false,
        ..NewtonSettings::default()
    };
    // Cold: a fresh newton for every α, U = 0, a factorization at every step.
    let mut cold_factorizations = 0;
    let mut cold_iterations = 0;
    let cold: Vec<Solution> = alphas()
        .into_iter()
        .map(|alpha| {
            let mut newton = Newton::new(&model, &taut, plain).unwrap();
            let solution = newton.solve(&load(s, alpha), None, &mut Silent);
            cold_factorizations += newton.work().factorizations;
            cold_iterations += solution.info.iterations;
            solution
        })
        .collect();
    let mut warm_newton = Newton::new(&model, &taut, NewtonSettings::default()).unwrap();
    let warm = warm_sweep(&mut warm_newton, s);
    let mut warm_pcg = PcgLcp::new(&model, &taut, PcgLcpSettings::default());
    let warm_lcp = warm_sweep(&mut warm_pcg, s);
    let mut warm_iterations = 0;
    for (i, alpha) in alphas().into_iter().enumerate() {
        for (name, solution) in [
            ("cold newton", &cold[i]),
            ("warm newton", &warm[i]),
            ("warm pcg-lcp", &warm_lcp[i]),
        ] {
            assert!(
                solution.info.status.converged() && solution.info.stopping_value <= 1e-10,
                "{name} at alpha {alpha}: {:?}",
                solution.info
            );
        }
        assert_eq!(
            warm[i].equilibrium.slack, cold[i].equilibrium.slack,
            "warm newton's slack set at alpha {alpha}"
        );
        assert_eq!(
            warm_lcp[i].equilibrium.slack, cold[i].equilibrium.slack,
            "warm pcg-lcp's slack set at alpha {alpha}"
        );
        let d = relative_difference(
            &warm[i].equilibrium.displacements,
            &cold[i].equilibrium.displacements,
        );
        assert!(
            d <= 1e-7,
            "warm newton's U at alpha {alpha}: {d:e} from cold"
        );
        warm_iterations += warm[i].info.iterations;
    }
    // No load, nothing slack.
    assert_eq!(warm[0].equilibrium.slack_count(), 0);
    // Fewer steps and far fewer factorizations than the cold sweep.
    let work = warm_newton.work();
    assert!(
        warm_iterations < cold_iterations,
        "{warm_iterations} warm iterations, {cold_iterations} cold"
    );
    assert!(
        2 * work.factorizations < cold_factorizations,
        "{work:?}; cold: {cold_factorizations} factorizations"
    );
    assert!(work.reused_steps > 0, "{work:?}");
}

#[test]
fn factor_reuse_changes_the_work_not_the_answer() {
    let model = paper_model(&[]);
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let alpha = 1.0;
    let mut reusing = Newton::new(&model, &taut, NewtonSettings::default()).unwrap();
    let mut plain = Newton::new(
        &model,
        &taut,
        NewtonSettings {
            reuse_factor: false,
            ..NewtonSettings::default()
        },
    )
    .unwrap();
    // Two solves each: the second starts with the factor the first left behind.
    for _ in 0..2 {
        let a = reusing.solve(&load(s, alpha), None, &mut Silent);
        let b = plain.solve(&load(s, alpha), None, &mut Silent);
        assert!(a.info.status.converged() && b.info.status.converged());
        assert_eq!(a.equilibrium.slack_count(), 408);
        assert_eq!(a.equilibrium.slack, b.equilibrium.slack);
        let d = relative_difference(&a.equilibrium.displacements, &b.equilibrium.displacements);
        assert!(d <= 1e-7, "U differs by {d:e}");
    }
    let (with, without) = (reusing.work(), plain.work());
    assert_eq!(without.reused_steps, 0);
    assert_eq!(without.cg_iterations, 0);
    assert_eq!(without.correction_columns, 0);
    assert!(with.reused_steps > 0, "{with:?}");
    assert!(
        with.factorizations < without.factorizations,
        "{with:?} against {without:?}"
    );
    // Every step that was neither all-taut nor reused factorized at least once.
    assert!(with.factorizations >= with.steps - with.taut_steps - with.reused_steps);
}

/// A cold solve of the paper case at α = 1 moves its taut set by 492, then about a hundred,
/// then 18 and 2 cables. The last two changes are absorbed by the factor of the second
/// Hessian corrected for the changed cables (Woodbury, src/linalg/low_rank.rs), each in at most
/// three CG iterations: two factorizations after K's, not three (CG preconditioned with the
/// bare factor needed a third, for the 18 cables).
#[test]
fn small_changes_of_the_taut_set_are_absorbed_without_refactorising() {
    let model = paper_model(&[]);
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let mut newton = Newton::new(&model, &taut, NewtonSettings::default()).unwrap();
    let solution = newton.solve(&load(s, 1.0), None, &mut Silent);
    assert!(solution.info.status.converged());
    assert!(
        solution.info.stopping_value <= 1e-10,
        "{:e}",
        solution.info.stopping_value
    );
    assert_eq!(solution.equilibrium.slack_count(), 408);
    let work = newton.work();
    assert_eq!(work.steps, 5, "{work:?}");
    assert_eq!(work.taut_steps, 1, "{work:?}");
    assert_eq!(work.factorizations, 2, "{work:?}");
    assert_eq!(work.reused_steps, 2, "{work:?}");
    assert!(work.cg_iterations <= 6, "{work:?}");
    // 18 columns for the first correction, 2 more for the second: the 18 are kept, not
    // recomputed (38 if they were).
    assert_eq!(work.correction_columns, 20, "{work:?}");
}
