//! newton with its Newton systems solved on the substructures (`solver.linear = "krylov"`:
//! PCG with a two-level Schwarz preconditioner whose GenEO coarse space follows the slack
//! cables) gives direct newton's answer: the same slack set, displacements to 1e-8 relative,
//! the same verdicts; and says how many PCG iterations it took.

mod common;

use common::relative_difference;
use std::path::Path;
use tensolve::app::memory::Workload;
use tensolve::app::setup::{prepare, prepare_keeping, set_up, Prepared};
use tensolve::case::{self, Case};
use tensolve::solvers::{Method, Silent, Solution, Status};

/// `path` with the overrides `set`, loaded.
fn case(path: &str, set: &[&str]) -> Case {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    case::load_with(Path::new(path), &set).unwrap()
}

/// newton's answers at every α of `case`, each from the previous (as `run` sweeps).
fn answers(case: &Case) -> Vec<(f64, Solution)> {
    answers_on(case, &prepare(case).unwrap())
}

/// [`answers`] on a set-up made already.
fn answers_on(case: &Case, prepared: &Prepared) -> Vec<(f64, Solution)> {
    let mut newton = set_up(Method::Newton, &case.solver, prepared).unwrap();
    let mut previous = None;
    case.load
        .alphas
        .iter()
        .map(|&alpha| {
            let load = prepared.model.load(alpha);
            let solution = newton
                .solver
                .solve_from(&load, previous.as_ref(), None, &mut Silent);
            previous = Some(solution.equilibrium.clone());
            (alpha, solution)
        })
        .collect()
}

/// Direct and substructured newton on `path` (with `set`) agree: status, slack set exactly,
/// displacements to 1e-8; every substructured row counts its PCG iterations, every direct row
/// none. Returns the substructured rows' PCG iterations.
fn agree(path: &str, set: &[&str]) -> Vec<usize> {
    let direct = answers(&case(path, set));
    let mut krylov_set = set.to_vec();
    krylov_set.push("solver.linear=\"krylov\"");
    let krylov = answers(&case(path, &krylov_set));
    assert_same_answers(path, &direct, &krylov)
}

/// The assertions of [`agree`] on the rows `direct` and `krylov` of `path`.
fn assert_same_answers(
    path: &str,
    direct: &[(f64, Solution)],
    krylov: &[(f64, Solution)],
) -> Vec<usize> {
    assert_eq!(direct.len(), krylov.len());
    direct
        .iter()
        .zip(krylov)
        .map(|((alpha, d), (_, k))| {
            assert_eq!(d.info.status, k.info.status, "{path} at alpha {alpha}");
            assert_eq!(d.info.krylov_iterations, None);
            assert_eq!(
                d.equilibrium.slack, k.equilibrium.slack,
                "{path} at alpha {alpha}: slack sets differ"
            );
            let du =
                relative_difference(&k.equilibrium.displacements, &d.equilibrium.displacements);
            assert!(
                du <= 1e-8,
                "{path} at alpha {alpha}: displacements differ by {du:e}"
            );
            k.info
                .krylov_iterations
                .expect("a substructured row counts its PCG iterations")
        })
        .collect()
}

#[test]
fn the_paper_case_substructured_is_direct_newtons() {
    // 16 × 16 modules on the default 4 × 4 partition, α from 0 to 1: 0 to 11 % slack.
    let iterations = agree("cases/paper.toml", &["model.geometry=\"linear\""]);
    // α = 0 is the prestress alone: newton's first state may already balance it.
    assert!(iterations[1..].iter().all(|&k| k > 0), "{iterations:?}");
}

#[test]
fn a_prestress_model_substructured_is_direct_newtons() {
    // K + K_G(t0): the preconditioner leaves K_G out, PCG still solves to the forcing term.
    agree(
        "cases/paper.toml",
        &["model.geometry=\"prestress\"", "load.alpha=[0.5, 1.0]"],
    );
}

#[test]
fn a_general_structure_substructured_is_direct_newtons() {
    // A [structure] case cut into boxes of its plan, with settlements and point loads.
    agree(
        "cases/skew-grid.toml",
        &["model.geometry=\"linear\"", "solver.subdomains=[3, 2]"],
    );
}

#[test]
fn a_64_grid_substructured_is_direct_newtons_in_few_pcg_iterations() {
    // 64 × 64 modules at α = 0.15 (13.5 % slack) on 16 substructures of 16 × 16 modules.
    let iterations = agree("cases/scale-64.toml", &["model.geometry=\"linear\""]);
    // The go/no-go measured 37 PCG iterations taut and 29 softened to 1e-8 per system; newton
    // takes about seven steps at forcing terms from 0.1 down.
    assert!(iterations[0] <= 400, "{iterations:?}");
}

/// A run of the substructured newton on a grid that asks for no check solving with K's factor
/// never factorises K whole: its mechanism check is made by substructures and no factor is
/// kept (direct newton's run keeps one), and newton's answers from that set-up are direct
/// newton's.
#[test]
fn without_k_factor_the_substructured_newton_is_direct_newtons() {
    let path = "cases/scale-64.toml";
    let set = ["output.geometric_term=false", "load.alpha=[0.05, 0.15]"];
    let direct_case = case(path, &set);
    let krylov_case = case(path, &[set[0], set[1], "solver.linear=\"krylov\""]);
    assert!(Workload::run(&direct_case, &[Method::Newton]).keeps_taut);
    let work = Workload::run(&krylov_case, &[Method::Newton]);
    assert!(!work.keeps_taut && work.taut_by_substructures, "{work:?}");
    let prepared = prepare_keeping(&krylov_case, false).unwrap();
    assert!(prepared.taut.is_none());
    let krylov = answers_on(&krylov_case, &prepared);
    let iterations = assert_same_answers(path, &answers(&direct_case), &krylov);
    assert!(iterations.iter().all(|&i| i > 0), "{iterations:?}");
    // With a check that solves with K's factor (the geometric term), the factor is kept.
    let checked = case(path, &["solver.linear=\"krylov\""]);
    assert!(Workload::run(&checked, &[Method::Newton]).keeps_taut);
}

#[test]
fn no_equilibrium_is_found_substructured_too() {
    let set = ["model.geometry=\"linear\""];
    let direct = answers(&case("cases/simplex-no-equilibrium.toml", &set));
    let krylov = answers(&case(
        "cases/simplex-no-equilibrium.toml",
        &["model.geometry=\"linear\"", "solver.linear=\"krylov\""],
    ));
    for ((alpha, d), (_, k)) in direct.iter().zip(&krylov) {
        assert_eq!(d.info.status, k.info.status, "alpha {alpha}");
    }
    assert!(krylov
        .iter()
        .any(|(_, k)| k.info.status == Status::NoEquilibrium));
}

#[test]
fn krylov_under_large_is_refused_with_the_key_named() {
    let set: Vec<String> = ["model.geometry=\"large\"", "solver.linear=\"krylov\""]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let error = case::load_with(Path::new("cases/paper.toml"), &set)
        .expect_err("refused")
        .to_string();
    assert!(error.contains("solver.linear"), "{error}");
    assert!(error.contains("direct"), "{error}");
}

/// `check` says how newton will solve its Newton systems, on which partition.
#[test]
fn check_says_which_linear_solve_and_why() {
    let check = |set: &[&str]| {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_tensolve"));
        command.arg("check").arg("cases/paper.toml");
        for s in set {
            command.arg("--set").arg(s);
        }
        let output = command.output().unwrap();
        assert!(output.status.success(), "{output:?}");
        String::from_utf8(output.stdout).unwrap()
    };
    let direct = check(&[]);
    assert!(
        direct.contains("newton solve  direct: a sparse factor"),
        "{direct}"
    );
    let krylov = check(&["solver.linear=\"krylov\""]);
    assert!(
        krylov.contains("newton solve  krylov: PCG with a two-level Schwarz preconditioner on the 4 x 4 partition"),
        "{krylov}"
    );
    assert!(krylov.contains("less memory"), "{krylov}");
    // Without newton, nothing to say.
    let latin = check(&["solver.methods=[\"mono-latin\"]"]);
    assert!(!latin.contains("newton solve"), "{latin}");
}

/// Substructured without K's factor, newton builds no Hessian workspace in halves at set-up
/// (its direct step is a fallback: a workspace on K's analysis alone), where direct newton on
/// the same 128 × 128 grid (147 k free dofs, above the split's size) and two threads does.
#[test]
fn without_k_factor_no_hessian_halves_are_built() {
    use tensolve::solvers::newton::Newton;
    use tensolve::solvers::TautStiffness;
    let text = "[grid]\nmodules = [128, 128]\n[supports]\nclamp = \"lower-all-edges\"\n\
                [load]\nalpha = [0.0375]\n[solver]\nmethods = [\"newton\"]\nlinear = \"krylov\"\n";
    let case = case::parse(text).expect("case");
    let model = case.model();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    pool.install(|| {
        let substructured = Newton::substructured(&model, case.solver.newton);
        assert!(!substructured.factors_in_halves());
        drop(substructured);
        let taut = TautStiffness::new(&model).expect("regular");
        let direct = Newton::new(&model, &taut, Default::default()).expect("set-up");
        assert!(direct.factors_in_halves());
    });
}
