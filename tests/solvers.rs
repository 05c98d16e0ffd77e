//! The two reference solvers on the paper case (docs/method.md §2–3): slack counts, agreement, residuals,
//! the linear case and the refusal of mechanisms.

mod common;

use common::{max_law_violation, paper_model, solve_both};
use tensolve::case;
use tensolve::results::{constitutive_residual, equilibrium_residual, relative_difference};
use tensolve::solvers::{SetupError, Solution, TautStiffness};
use tensolve::structure::Structure;

fn slack_counts(alpha: f64) -> (usize, usize) {
    let model = paper_model(&[]);
    let (newton, pcg) = solve_both(&model, alpha);
    (
        newton.equilibrium.slack_count(),
        pcg.equilibrium.slack_count(),
    )
}

#[test]
fn slack_cables_at_alpha_1() {
    assert_eq!(slack_counts(1.0), (408, 408));
}

#[test]
fn slack_cables_at_alpha_half() {
    assert_eq!(slack_counts(0.5), (36, 36));
}

fn assert_agree(s: &Structure, newton: &Solution, pcg: &Solution, what: &str) {
    let d = relative_difference(
        &newton.equilibrium.displacements,
        &pcg.equilibrium.displacements,
    );
    assert!(d < 1e-8, "{what}: displacements differ by {d:e} (relative)");
    assert_eq!(
        newton.equilibrium.slack, pcg.equilibrium.slack,
        "{what}: slack sets differ"
    );
    assert_eq!(newton.equilibrium.slack.len(), s.links.len());
}

#[test]
fn solvers_agree_on_paper_case() {
    let model = paper_model(&[]);
    let s = &model.structure;
    for alpha in [0.5, 1.0] {
        let (newton, pcg) = solve_both(&model, alpha);
        assert_agree(s, &newton, &pcg, &format!("alpha {alpha}"));
    }
}

/// Equilibrium and the cable law, checked from U and τ alone.
fn assert_physical(s: &Structure, sol: &Solution, alpha: f64, what: &str) {
    let f = common::load(s, alpha);
    let eq = equilibrium_residual(s, &sol.equilibrium, &f);
    assert!(eq < 1e-9, "{what}: equilibrium residual {eq:e}");
    // Slack flags and zero tensions go together, and only unilateral cables are slack.
    for (i, (l, &slack)) in s.links.iter().zip(&sol.equilibrium.slack).enumerate() {
        assert!(
            !slack || l.unilateral,
            "{what}: link {i} ({:?}) slack",
            l.kind
        );
        assert_eq!(
            slack,
            l.unilateral && sol.equilibrium.tensions[i] == 0.0,
            "{what}: link {i}"
        );
    }
    let own = max_law_violation(s, sol);
    assert!(
        own < 1e-8,
        "{what}: cable law violated by {own:e} p (independent check)"
    );
}

#[test]
fn solutions_satisfy_equilibrium_and_cable_law() {
    let model = paper_model(&[]);
    let s = &model.structure;
    for alpha in [0.05, 0.5, 1.0] {
        let (newton, pcg) = solve_both(&model, alpha);
        assert_physical(s, &newton, alpha, &format!("newton alpha {alpha}"));
        assert_physical(s, &pcg, alpha, &format!("pcg-lcp alpha {alpha}"));
    }
}

/// `results::constitutive_residual` itself, on solutions with and without slack cables.
#[test]
fn constitutive_residual_is_small_on_solutions() {
    let model = paper_model(&[]);
    let s = &model.structure;
    for alpha in [0.05, 0.5, 1.0] {
        let (newton, pcg) = solve_both(&model, alpha);
        for (name, sol) in [("newton", &newton), ("pcg-lcp", &pcg)] {
            let r = constitutive_residual(s, &sol.equilibrium);
            assert!(
                r < 1e-8,
                "{name} alpha {alpha}: constitutive_residual = {r:e}"
            );
        }
    }
}

/// The residual must see a violation: a taut cable whose tension is off by 1 % of p.
#[test]
fn constitutive_residual_detects_a_wrong_tension() {
    let model = paper_model(&[]);
    let s = &model.structure;
    let (mut newton, _) = solve_both(&model, 0.05);
    newton.equilibrium.tensions[0] += 0.01 * common::P;
    assert!(constitutive_residual(s, &newton.equilibrium) > 1e-6);
    assert!(max_law_violation(s, &newton) > 1e-3);
}

#[test]
fn linear_case_has_no_slack_cable() {
    let model = paper_model(&[("cables", "unilateral", false.into())]);
    let s = &model.structure;
    assert!(s.links.iter().all(|l| !l.unilateral));
    // At α = 3 the unilateral model slackens 846 cables (docs/method.md §2): here they take compression.
    for alpha in [1.0, 3.0] {
        let (newton, pcg) = solve_both(&model, alpha);
        assert_eq!(newton.equilibrium.slack_count(), 0);
        assert_eq!(pcg.equilibrium.slack_count(), 0);
        assert_agree(s, &newton, &pcg, &format!("linear alpha {alpha}"));
        assert_physical(s, &newton, alpha, "linear newton");
        assert_physical(s, &pcg, alpha, "linear pcg-lcp");
    }
    let (newton, _) = solve_both(&model, 3.0);
    let compressed = s
        .links
        .iter()
        .zip(&newton.equilibrium.tensions)
        .filter(|(l, &t)| l.kind.is_cable() && t < 0.0)
        .count();
    assert!(
        compressed > 0,
        "no cable in compression at alpha 3: bilateral law not used?"
    );
}

fn case_text(modules: [usize; 2], module: &str, clamp: &str) -> String {
    format!(
        "[grid]\nmodules = [{}, {}]\nmodule = \"{module}\"\n\
         [supports]\nclamp = \"{clamp}\"\n[load]\nalpha = [1.0]\n",
        modules[0], modules[1]
    )
}

/// The zero-stiffness modes `TautStiffness::new` reports; panics if it accepts the structure.
fn zero_modes(modules: [usize; 2], module: &str, clamp: &str) -> usize {
    let text = case_text(modules, module, clamp);
    let model = (case::parse(&text).expect("valid case")).model();
    match TautStiffness::new(&model) {
        Err(SetupError::Mechanism { zero_modes, .. }) => zero_modes,
        Err(other) => panic!("not refused as a mechanism: {other}"),
        Ok(_) => panic!("a mechanism was accepted:\n{text}"),
    }
}

/// Nullity of K = Bᵀ k B by a dense eigen-decomposition (small grids only), with a clear gap.
fn dense_zero_modes(modules: [usize; 2], module: &str, clamp: &str) -> usize {
    let model = (case::parse(&case_text(modules, module, clamp)).unwrap()).model();
    let s = &model.structure;
    let n = s.n_free;
    let k = common::dense_stiffness(s);
    let mut ev: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    let max = ev[n - 1];
    let zeros = ev.iter().filter(|&&e| e < 1e-12 * max).count();
    assert!(
        zeros == n || ev[zeros] > 1e-6 * max,
        "no clear gap: {:?}",
        &ev[..zeros + 1]
    );
    zeros
}

#[test]
fn mechanism_count_matches_dense_eigenvalues() {
    for (modules, module, clamp) in [
        ([1, 1], "standard", "lower-corners"),
        ([1, 1], "standard", "none"),
        ([3, 3], "standard", "none"),
        ([4, 4], "standard", "none"),
        ([4, 4], "braced", "none"),
        ([2, 3], "standard", "lower-corners"),
    ] {
        let dense = dense_zero_modes(modules, module, clamp);
        let what = format!("{modules:?} {module} clamp = {clamp}");
        if dense == 0 {
            let text = case_text(modules, module, clamp);
            let model = (case::parse(&text).unwrap()).model();
            assert!(
                TautStiffness::new(&model).is_ok(),
                "{what}: regular K refused"
            );
        } else {
            assert_eq!(zero_modes(modules, module, clamp), dense, "{what}");
        }
    }
}

#[test]
fn unsupported_grid_is_a_mechanism() {
    let standard = zero_modes([16, 16], "standard", "none");
    let braced = zero_modes([16, 16], "braced", "none");
    println!("16 x 16, clamp = none: standard {standard}, braced {braced} zero modes");
    // A free body has at least its 6 rigid-body motions; the braced grid has no other.
    assert!(standard >= 6, "{standard} zero modes");
    assert_eq!(braced, 6);
    // The standard grid adds one internal mechanism (dense eigenvalues: 7 on every grid from
    // 2 x 2 to 8 x 8).
    assert_eq!(standard, 7);
}

#[test]
fn single_module_on_its_corners_has_one_mode() {
    // 12 free dofs, 12 links acting on them, one self-stress: one mechanism (docs/method.md §2).
    assert_eq!(zero_modes([1, 1], "standard", "lower-corners"), 1);
}

#[test]
fn supported_paper_grid_is_not_a_mechanism() {
    let model = paper_model(&[]);
    assert!(TautStiffness::new(&model).is_ok());
}

/// A run that never solves with K's factor releases it (`Prepared::release_taut`); a solver
/// that needs it, set up afterwards, is refused with a set-up error naming it (never a
/// panic), while the LATIN solvers, which never use it, set up as before.
#[test]
fn a_released_taut_factor_refuses_the_solvers_that_need_it() {
    use tensolve::app::setup::{prepare, set_up};
    use tensolve::solvers::Method;
    let case = common::paper_with(&[]);
    let mut prepared = prepare(&case).unwrap();
    prepared.release_taut();
    for method in [Method::Newton, Method::PcgLcp] {
        match set_up(method, &case.solver, &prepared) {
            Err(e @ SetupError::TautReleased { .. }) => {
                assert!(e.to_string().starts_with(method.name()), "{e}")
            }
            Err(e) => panic!("{method:?}: {e}"),
            Ok(_) => panic!("{method:?} set up without K's factor"),
        }
    }
    for method in [Method::MonoLatin, Method::MicroMacro] {
        assert!(
            set_up(method, &case.solver, &prepared).is_ok(),
            "{method:?}"
        );
    }
}

/// newton's Hessian factored in two halves side by side (two threads, a 128 × 128 grid of
/// 147 k free dofs: above the split's size) ends where the whole factor on one thread does:
/// the same iterations, the same slack set (25 816 cables of 196 608 at α = 0.0375), U to the
/// solvers' tolerance.
#[test]
fn newton_in_two_halves_ends_where_the_whole_factor_does() {
    use tensolve::solvers::newton::{Newton, NewtonSettings};
    use tensolve::solvers::{AnySolver, Silent};
    let text = "[grid]\nmodules = [128, 128]\n[supports]\nclamp = \"lower-all-edges\"\n\
                [load]\nalpha = [0.0375]\n[solver]\nmethods = [\"newton\"]\n";
    let model = case::parse(text).expect("case").model();
    let taut = TautStiffness::new(&model).expect("regular");
    let f: Vec<f64> = model
        .structure
        .unit_load
        .iter()
        .map(|x| 0.0375 * x)
        .collect();
    let solve_on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut newton = Newton::new(&model, &taut, NewtonSettings::default()).expect("set-up");
            let halves = newton.factors_in_halves();
            (halves, newton.solve(&f, None, &mut Silent))
        })
    };
    let (whole_halves, whole) = solve_on(1);
    let (split_halves, split) = solve_on(2);
    assert!(!whole_halves && split_halves);
    assert!(whole.info.status.converged() && split.info.status.converged());
    assert_eq!(whole.info.iterations, split.info.iterations);
    let slack = |s: &Solution| -> Vec<bool> {
        s.equilibrium
            .tensions
            .iter()
            .zip(&model.structure.links)
            .map(|(&t, l)| l.unilateral && t == 0.0)
            .collect()
    };
    assert_eq!(slack(&whole), slack(&split));
    assert_eq!(slack(&whole).iter().filter(|&&x| x).count(), 25_816);
    let d = relative_difference(
        &split.equilibrium.displacements,
        &whole.equilibrium.displacements,
    );
    assert!(d < 1e-9, "U differs by {d:e}");
}
