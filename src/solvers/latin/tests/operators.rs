//! The operators: rebuilds, the macro problem's accuracy, shapes, r(U) by substructure, Z_E, the macro solve's refinement, kernels of thin substructures, the stop on η, the macro operator by rows, U gathered by dof, a rebuild with soft modes condensing each operator once.

use super::super::macro_problem::{Factor, MacroPattern};
use super::*;
use crate::model::Model;
use faer::sparse::Pair;
use std::sync::Arc;

/// Every substructure's operators that a test compares: L_E, and on its own dofs Z_E and K⁺_E.
fn operator_bits(latin: &Latin<'_>) -> Vec<Vec<u64>> {
    latin
        .operators
        .substructures
        .iter()
        .map(|sub| {
            let ops = sub.ops();
            let z = ops.z.as_ref().expect("Z_E kept by default");
            [&sub.flexibility, z, &ops.k_plus]
                .iter()
                .flat_map(|m| m.iter().map(|x| x.to_bits()))
                .collect()
        })
        .collect()
}

/// A status rebuild refactorises in place, and its undo rebuilds from the current directions:
/// both rest on a rebuild giving exactly the operators a set-up with those directions gives.
/// Slack on a third of the cables and back: every operator as set up, bit for bit; and the
/// slack operators differ from the taut ones (the rebuild did rebuild).
#[test]
fn a_rebuild_and_its_undo_give_the_set_up_operators_bit_for_bit() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro)).unwrap();
    let set_up = operator_bits(&latin);
    let slack = slack_every(s, 3);
    assert!(latin.set_search(slack));
    let rebuilt = operator_bits(&latin);
    let differing = set_up.iter().zip(&rebuilt).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing,
        latin.operators.substructures.len(),
        "every substructure has a slack cable"
    );
    assert!(latin.set_search(vec![false; s.links.len()]));
    assert!(
        operator_bits(&latin) == set_up,
        "the undo's operators differ from the set-up's"
    );
}

/// With soft interface modes, a rebuild only refactorizes the substructures that its
/// enrichment condenses anew on the new bases (a condensation on the old bases would be thrown
/// away): after it, every substructure's Z_E and K*_E are those its factor gives on its
/// bases, bit for bit. Slack on a third of the cables (every substructure's modes retaken),
/// then one more cable slack (its substructure's modes kept: condensed at the rebuild itself).
#[test]
fn after_a_rebuild_with_soft_modes_every_operator_is_condensed_on_its_bases() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let settings = LatinSettings {
        soft_modes: Some(0.3),
        ..settings([4, 4], WeakInterfaces::Macro)
    };
    let mut latin = Latin::new(&model, settings).unwrap();
    let condensed_on_its_bases = |latin: &Latin<'_>| {
        latin.operators.substructures.iter().all(|sub| {
            let ops = sub.ops();
            let (z, k_star) = sub.condense_operators(&ops.factor, latin.world.dm);
            let bits = |m: &DMatrix<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            ops.z.as_ref().map(bits) == Some(bits(&z)) && bits(&ops.k_star) == bits(&k_star)
        })
    };
    let macro_dofs = latin.operators.macro_problem.n_forces;
    let mut slack = slack_every(s, 3);
    assert!(latin.set_search(slack.clone()));
    assert!(
        condensed_on_its_bases(&latin),
        "slack on a third of the cables"
    );
    assert_ne!(
        latin.operators.macro_problem.n_forces, macro_dofs,
        "the modes were not retaken"
    );
    let one_more = (0..s.links.len())
        .find(|&i| s.links[i].unilateral && !slack[i])
        .expect("a taut cable");
    slack[one_more] = true;
    let macro_dofs = latin.operators.macro_problem.n_forces;
    assert!(latin.set_search(slack));
    assert!(condensed_on_its_bases(&latin), "one cable more");
    assert_eq!(
        latin.operators.macro_problem.n_forces, macro_dofs,
        "one cable retook a substructure's modes"
    );
}

/// The macro problem's accuracy does not depend on the substructures' status: its
/// equilibration keeps the soft flexibilities of substructures with slack cables from
/// swamping the stiff ones. 64 × 64 modules on 256 substructures, half the cables slack: the
/// error of a solve with a known answer was 4.1e-10 (all taut: 1.9e-10); without the
/// equilibration 2.1e-8 (on 256 × 256 modules it left the macro answer 3e-8 off, and r(U)
/// stalled at 9e-7 for 1000 iterations).
#[test]
fn the_macro_problems_accuracy_does_not_depend_on_the_status() {
    let model = Model::linear(grid_structure(64));
    let s = &model.structure;
    let mut latin = Latin::new(&model, settings([16, 16], WeakInterfaces::Macro)).unwrap();
    let taut = latin.operators.macro_problem.forward_error();
    let slack = slack_every(s, 2);
    assert!(latin.set_search(slack));
    let slack = latin.operators.macro_problem.forward_error();
    println!("macro forward error: taut {taut:.1e}, half the cables slack {slack:.1e}");
    assert!(taut < 1e-9 && slack < 10.0 * taut, "{taut:e} {slack:e}");
}

/// The macro problem on 256 substructures, in 4 subtrees side by side (a bisection of the
/// substructures whose separators hold forces only: leaves of 64 substructures), solves as the
/// whole factor after AMD: with half the cables slack, both refined to the end agree to 1e-9
/// of the answer's largest entry, and the split's forward error is within 10× the whole's.
/// With the default leaves (256 substructures) it is not split.
#[test]
fn the_macro_problem_in_subtrees_solves_as_the_whole_factor() {
    let model = Model::linear(grid_structure(64));
    let s = &model.structure;
    let mut latin = Latin::new(&model, settings([16, 16], WeakInterfaces::Macro)).unwrap();
    assert!(latin.set_search(slack_every(s, 2)));
    let (subs, interfaces) = (&latin.operators.substructures, &latin.interfaces.list);
    let default = &latin.operators.macro_problem;
    assert_eq!(default.split_levels(), 0);
    let split = default.with_leaves(subs, interfaces, Some(64)).unwrap();
    assert_eq!(split.split_levels(), 2);
    let whole = default.with_leaves(subs, interfaces, None).unwrap();
    assert_eq!(whole.split_levels(), 0);
    let rhs: Vec<f64> = (0..split.n)
        .map(|i| ((i * 37) % 11) as f64 - 5.0 + 0.1 * (i % 3) as f64)
        .collect();
    let (x_split, x_whole) = (split.solve_rhs(rhs.clone(), 0.0), whole.solve_rhs(rhs, 0.0));
    let largest = x_whole.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let off = x_split
        .iter()
        .zip(&x_whole)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let (e_split, e_whole) = (split.forward_error(), whole.forward_error());
    println!(
        "split against whole {:.1e}; forward errors {e_split:.1e} {e_whole:.1e}",
        off / largest
    );
    assert!(off <= 1e-9 * largest, "{off:e} of {largest:e}");
    assert!(
        e_split < 1e-9 && e_split <= 10.0 * e_whole.max(1e-14),
        "{e_split:e} {e_whole:e}"
    );
}

/// Substructures of one shape share the pattern of K_E and its analysis: on 64 × 64 modules
/// with 256 substructures, two substructures hold the same pattern object exactly when their
/// patterns are equal, and there are a few shapes (3 when written: a grid clamped on its
/// lower x edges has its substructures along those edges and the rest).
#[test]
fn substructures_of_one_shape_share_their_pattern() {
    let model = Model::linear(grid_structure(64));
    let latin = Latin::new(&model, settings([16, 16], WeakInterfaces::Macro)).unwrap();
    let patterns: Vec<&std::sync::Arc<crate::linalg::StiffnessPattern>> = latin
        .operators
        .substructures
        .iter()
        .map(|sub| &sub.ops().pattern)
        .collect();
    let mut shapes = 0;
    for (i, a) in patterns.iter().enumerate() {
        for b in &patterns[..i] {
            assert_eq!(std::sync::Arc::ptr_eq(a, b), a == b, "substructures {i}");
        }
        shapes += usize::from(patterns[..i].iter().all(|b| b != a));
    }
    println!("{shapes} shapes of {} substructures", patterns.len());
    assert!((1..=9).contains(&shapes), "{shapes}");
}

/// r(U) substructure by substructure is the global r(U) (the links' forces grouped by
/// substructure, so equal to round-off), under the exact law and under the law linearised at
/// a status, on a partition with interfaces and on the paper's plain 1 × 1 one, at a U that
/// leaves about half the cables slack.
#[test]
fn r_u_by_substructure_is_the_global_r_u() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let wavy: Vec<f64> = (0..s.n_free).map(|d| (0.37 * d as f64).sin()).collect();
    // Scaled so that k e is ten times the prestress on average: many cables pulled slack.
    let trial = model.trial_tensions(&wavy);
    let kinds = s.links.iter().zip(&trial);
    let pull: f64 = kinds.map(|(l, t)| (t - l.prestress).abs()).sum::<f64>() / trial.len() as f64;
    let u: Vec<f64> = wavy
        .iter()
        .map(|x| 10.0 * x * s.prestress_scale / pull)
        .collect();
    let slack_now = model
        .trial_tensions(&u)
        .iter()
        .zip(&s.links)
        .filter(|(t, l)| l.unilateral && **t < 0.0)
        .count();
    let cables = s.links.iter().filter(|l| l.unilateral).count();
    assert!(
        slack_now > cables / 10 && slack_now < 9 * cables / 10,
        "{slack_now}/{cables}"
    );
    let law_slack = slack_every(s, 3);
    let f = load(s, 1.0);
    let (sizes, frozen) = model.exact_and_frozen_residuals(&u, &f, &law_slack);
    let (exact, load_relative) = (sizes.relative, sizes.load_relative);
    assert!((exact - frozen).abs() > 1e-3 * exact, "{exact} {frozen}");
    for subdomains in [[4, 4], [3, 5], [1, 1]] {
        let latin = Latin::new(&model, settings(subdomains, WeakInterfaces::Macro)).unwrap();
        let (by_sub, load_by_sub, frozen_by_sub) =
            latin.residuals_by_substructure(&u, &f, &law_slack);
        assert!(
            (by_sub - exact).abs() <= 1e-13 * exact,
            "{subdomains:?}: {by_sub} {exact}"
        );
        assert!(
            (load_by_sub - load_relative).abs() <= 1e-13 * load_relative,
            "{subdomains:?}: {load_by_sub} {load_relative}"
        );
        assert!(
            (frozen_by_sub - frozen).abs() <= 1e-13 * frozen,
            "{subdomains:?}: {frozen_by_sub} {frozen}"
        );
    }
}

/// Without Z_E kept (`solver.keep_z = false`), `Z_E w` by a second solve is the same product
/// to round-off: on the paper's grid at α = 1 (16 substructures, 408 of 3 072 cables slack)
/// both solves take the same iterations and find the same slack set, and their displacements
/// agree within 1e-9 of the largest (measured 1.2e-13 when written).
#[test]
fn a_solve_without_z_e_is_the_solve_with_it() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let f = load(s, 1.0);
    let solve = |keep_z: bool| {
        let mut latin = Latin::new(
            &model,
            LatinSettings {
                keep_z,
                ..settings([4, 4], WeakInterfaces::Macro)
            },
        )
        .unwrap();
        assert_eq!(
            latin
                .operators
                .substructures
                .iter()
                .all(|sub| sub.ops().z.is_some()),
            keep_z
        );
        crate::solvers::drive(&mut latin, &f, None, &mut crate::solvers::Silent)
    };
    let (kept, recomputed) = (solve(true), solve(false));
    assert!(kept.info.status.converged() && recomputed.info.status.converged());
    assert_eq!(kept.info.iterations, recomputed.info.iterations);
    let slack = |x: &crate::solvers::Solution| x.equilibrium.slack.iter().filter(|&&b| b).count();
    assert_eq!(slack(&kept), 408);
    assert_eq!(kept.equilibrium.slack, recomputed.equilibrium.slack);
    let (a, b) = (
        &kept.equilibrium.displacements,
        &recomputed.equilibrium.displacements,
    );
    let largest = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let gap = a
        .iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    println!(
        "keep_z: displacements differ by {:.1e} of the largest",
        gap / largest
    );
    assert!(gap <= 1e-9 * largest, "{gap:e} {largest:e}");
}

/// The macro solve is refined to 1e-9 of its right-hand side while r(U) is above 100 times
/// its tolerance, then to the end for the rest of the solve, even when r(U) rises again (a
/// status step): switching back changed the map under Anderson's history at every crossing.
#[test]
fn the_macro_solve_stays_refined_to_the_end_once_r_u_is_near_its_tolerance() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro)).unwrap();
    let mut state = latin.init(&load(s, 1.0));
    let latin = latin;
    let near = 100.0 * latin.settings.residual_tolerance();
    let mut accuracy = |residual: f64| {
        state.residual = residual;
        latin.macro_accuracy(&mut state)
    };
    assert_eq!(accuracy(1e3 * near), 1e-9);
    assert_eq!(accuracy(2.0 * near), 1e-9);
    assert_eq!(accuracy(0.5 * near), 0.0);
    assert_eq!(accuracy(4.0 * near), 0.0);
}

/// Substructures one module wide (a 2 × 10 grid on [2, 1]): each strip, clamped along one
/// line, has one rigid motion left, the rotation about that line, and K*_E one null
/// eigenvalue. The null eigenvector repeating the rigid motion to 6e-9 was kept as a second
/// kernel column on one strip (issue 42, T5): a regular direction treated as a kernel one.
#[test]
fn a_strip_one_module_wide_has_one_kernel_column_per_null_mode() {
    let spec = GridSpec {
        modules: [2, 10],
        ..GridSpec::default()
    };
    let model = Model::linear(Structure::grid(&spec, &LoadPattern::default()));
    let strips = LatinSettings {
        subdomains: [2, 1],
        ..LatinSettings::default()
    };
    let latin = Latin::new(&model, strips).unwrap();
    let columns: Vec<usize> = latin
        .operators
        .substructures
        .iter()
        .map(|e| e.kernel.ncols())
        .collect();
    assert_eq!(columns, [1, 1]);
}

/// With `stop_on = "eta"`, η met while r(U) is far above the tolerance is a fixed point off
/// the equilibrium: stalled, never converged (issue 42, T5); with r(U) near η, converged.
#[test]
fn an_eta_met_off_the_equilibrium_is_never_converged() {
    let model = Model::linear(grid_structure(4));
    let s = &model.structure;
    let eta_only = LatinSettings {
        stop_on: crate::solvers::latin::StopOn::Eta,
        ..settings([2, 2], WeakInterfaces::Macro)
    };
    let mut latin = Latin::new(&model, eta_only).unwrap();
    let mut state = latin.init(&load(s, 1.0));
    state.eta = 1e-2 * eta_only.tolerance;
    state.residual = 1e4 * eta_only.tolerance;
    assert_eq!(
        latin.progress(&state).stop,
        Some(crate::solvers::Status::Stalled)
    );
    state.residual = eta_only.tolerance;
    assert_eq!(
        latin.progress(&state).stop,
        Some(crate::solvers::Status::Converged)
    );
}

/// U on the free dofs, each interface dof the mean over the substructures holding it, is
/// gathered dof by dof in parallel: bit for bit the serial sum in the substructures' order
/// (`(0 + u_1 + u_2 + …) / count`) that it replaced, on 64 substructures of the paper grid
/// with distinct values per substructure, so that a mean taken in another order or over the
/// wrong holders would differ.
#[test]
fn the_parallel_gather_of_u_is_the_serial_mean_bit_for_bit() {
    let model = Model::linear(paper_structure());
    let latin = Latin::new(&model, settings([8, 8], WeakInterfaces::Macro)).unwrap();
    let subs: Vec<super::super::SubState> = latin
        .operators
        .substructures
        .iter()
        .enumerate()
        .map(|(e, sub)| {
            let mut st = super::super::SubState::zero(sub);
            for (k, u) in st.u.iter_mut().enumerate() {
                *u = ((e * 7919 + k * 104_729) % 1000) as f64 / 997.0 + 0.1 / (1 + e) as f64;
            }
            st
        })
        .collect();
    let n = model.structure.n_free;
    let (mut serial, mut count) = (vec![0.0; n], vec![0u32; n]);
    for (sub, st) in latin.operators.substructures.iter().zip(&subs) {
        for (local, &global) in sub.dof_global.iter().enumerate() {
            serial[global] += st.u[local];
            count[global] += 1;
        }
    }
    serial
        .iter_mut()
        .zip(&count)
        .for_each(|(u, &c)| *u /= c.max(1) as f64);
    let shared = count.iter().filter(|&&c| c > 1).count();
    assert!(shared > 100, "the partition shares {shared} dofs");
    let gathered = latin.displacements(&subs);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert!(bits(&gathered) == bits(&serial));
}

/// `M y` row by row in parallel against the dense symmetric product, on a 40 × 40 banded
/// matrix stored by its lower triangle with a duplicated entry (assembly adds them):
/// every row to 1e-14 of its scale, so a dropped or doubled off-diagonal entry fails.
#[test]
fn the_macro_operator_by_rows_is_the_symmetric_product() {
    let n = 40;
    let mut entries = Vec::new();
    let mut values = Vec::new();
    for c in 0..n {
        for r in c..(c + 4).min(n) {
            entries.push(Pair { row: r, col: c });
            values.push(if r == c {
                10.0 + c as f64
            } else {
                1.0 / (1 + r + c) as f64
            });
        }
    }
    entries.push(Pair { row: 7, col: 5 });
    values.push(0.25);
    let mut dense = vec![vec![0.0; n]; n];
    for (p, v) in entries.iter().zip(&values) {
        dense[p.row][p.col] += v;
        if p.row != p.col {
            dense[p.col][p.row] += v;
        }
    }
    let pattern = Arc::new(MacroPattern::new(n, &entries, n, |_| None).unwrap());
    let factor = Factor::new(pattern, &values, n).unwrap();
    let y: Vec<f64> = (0..n)
        .map(|i| 1.0 + (i % 5) as f64 - 0.3 * i as f64)
        .collect();
    let by_rows = factor.apply(&y);
    for i in 0..n {
        let want: f64 = (0..n).map(|j| dense[i][j] * y[j]).sum();
        let scale: f64 = (0..n).map(|j| (dense[i][j] * y[j]).abs()).sum();
        assert!(
            (by_rows[i] - want).abs() <= 1e-14 * scale,
            "row {i}: {} {want}",
            by_rows[i]
        );
    }
}

/// How soft a slack cable's l (docs/method.md §9): on micro-macro's substructures a slack
/// cable gets ε_soft where both its nodes stay held without it, ε where not; always ε with
/// one substructure (mono-latin) and on one-module substructures. The paper's grid on 16
/// substructures: with every cable slack, a node off the interfaces and unclamped with at most
/// two bars has a stiffness of rank two at most in space, so its cables get ε; a cable between
/// two clamped nodes stays soft.
#[test]
fn a_slack_cable_is_soft_only_where_its_nodes_stay_held() {
    use super::super::slack_direction::SOFT_SLACK_SEARCH_FACTOR as SOFT;
    use super::super::SLACK_SEARCH_FACTOR as EPS;
    use crate::structure::CLAMPED;
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro)).unwrap();
    let interface_dofs: std::collections::HashSet<usize> = latin
        .operators
        .substructures
        .iter()
        .flat_map(|sub| sub.gamma_dofs.iter().map(|&d| sub.dof_global[d]))
        .collect();
    let mut bars = vec![0; s.nodes.len()];
    for l in s.links.iter().filter(|l| !l.unilateral) {
        bars[l.a] += 1;
        bars[l.b] += 1;
    }
    let loose = |n: usize| {
        bars[n] <= 2
            && (0..3).all(|c| {
                let d = s.dof_of[3 * n + c];
                d != CLAMPED && !interface_dofs.contains(&d)
            })
    };
    let count = |factors: &[f64], x: f64| factors.iter().filter(|&&f| f == x).count();
    let third = slack_every(s, 3);
    let factors = latin.slack_factors(&third);
    for (i, (&f, &slack)) in factors.iter().zip(&third).enumerate() {
        assert!(
            if slack {
                f == SOFT || f == EPS
            } else {
                f == 1.0
            },
            "link {i}: {f}"
        );
    }
    println!(
        "a third slack: {} at ε_soft, {} at ε",
        count(&factors, SOFT),
        count(&factors, EPS)
    );
    assert!(count(&factors, SOFT) > count(&factors, EPS));
    let every: Vec<bool> = s.links.iter().map(|l| l.unilateral).collect();
    let factors = latin.slack_factors(&every);
    println!(
        "every cable: {} at ε_soft, {} at ε",
        count(&factors, SOFT),
        count(&factors, EPS)
    );
    for (i, (l, &f)) in s.links.iter().zip(&factors).enumerate() {
        assert_eq!(f == 1.0, !l.unilateral, "link {i}");
        if l.unilateral && (loose(l.a) || loose(l.b)) {
            assert_eq!(f, EPS, "link {i}: a node held by two bars at most");
        }
        if l.unilateral && s.clamped[l.a] && s.clamped[l.b] {
            assert_eq!(f, SOFT, "link {i}: a cable between two clamped nodes");
        }
    }
    for partition in [[1, 1], [16, 16]] {
        let latin = Latin::new(&model, settings(partition, WeakInterfaces::Macro)).unwrap();
        let factors = latin.slack_factors(&third);
        assert_eq!(count(&factors, EPS), third.iter().filter(|&&x| x).count());
    }
}
