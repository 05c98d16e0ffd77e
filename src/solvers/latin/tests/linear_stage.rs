//! The linear stage's invariants: macro continuity, macro force balance, equilibrium per substructure.

use super::kernels::{check_kernels, independent_kernel_dimension};
use super::*;
use crate::model::Model;

/// `Rᵀ v` for an interface field v (3·nodes rows).
fn macro_part(r: &DMatrix<f64>, v: &[f64]) -> Vec<f64> {
    (r.transpose() * nalgebra::DVector::from_column_slice(v))
        .iter()
        .copied()
        .collect()
}

fn diff_norm(a: &[f64], b: &[f64], sign: f64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - sign * y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Returns (worst macro displacement jump, worst macro force imbalance, worst equilibrium
/// residual), each relative.
fn check_linear_stage(
    s: &Structure,
    latin: &Latin<'_>,
    state: &LatinState,
    alpha: f64,
) -> [f64; 3] {
    let f_d = load(s, alpha);
    // Scales: the norm of every U_E, of every side force.
    let u_scale = norm(
        &state
            .subs
            .iter()
            .flat_map(|st| st.u.clone())
            .collect::<Vec<_>>(),
    );
    let f_scale = norm(
        &state
            .subs
            .iter()
            .flat_map(|st| st.sides.iter().flat_map(|sd| sd.f.clone()))
            .collect::<Vec<_>>(),
    );
    assert!(u_scale > 0.0 && f_scale > 0.0);
    let mut worst = [0.0f64; 3];
    for (k, iface) in latin.interfaces.list.iter().enumerate() {
        let [a, b] = iface.topology.sides;
        assert!(a < b);
        let side_of = |e: usize| {
            let sub = &latin.operators.substructures[e];
            let found: Vec<usize> = (0..sub.sides.len())
                .filter(|&j| sub.sides[j].interface == k)
                .collect();
            assert_eq!(
                found.len(),
                1,
                "interface {k} seen {} times by {e}",
                found.len()
            );
            found[0]
        };
        let (ja, jb) = (side_of(a), side_of(b));
        let (sa, sb) = (
            &latin.operators.substructures[a].sides[ja],
            &latin.operators.substructures[b].sides[jb],
        );
        assert_eq!((sa.which, sb.which), (0, 1), "interface {k}");
        assert_eq!((sa.sign(), sb.sign()), (1.0, -1.0), "interface {k}");
        assert_eq!(sa.rows, 3 * iface.topology.nodes.len());
        assert_eq!((sa.rows, sa.cols), (sb.rows, sb.cols));
        assert_eq!(sa.basis, iface.basis);
        assert_eq!(sb.basis, iface.basis);
        let (ua, ub) = (&state.subs[a].sides[ja], &state.subs[b].sides[jb]);
        // The side vectors are C_E U_E, read directly from U_E through gamma_dofs.
        for (e, j, ss) in [(a, ja, ua), (b, jb, ub)] {
            let sub = &latin.operators.substructures[e];
            let side = &sub.sides[j];
            for r in 0..side.rows {
                assert_eq!(
                    ss.u[r],
                    state.subs[e].u[sub.gamma_dofs[side.gamma_offset + r]],
                    "interface {k}, substructure {e}, row {r}: side u is not C_E U_E"
                );
            }
        }
        let du = diff_norm(
            &macro_part(&iface.basis, &ua.u),
            &macro_part(&iface.basis, &ub.u),
            1.0,
        );
        let df = diff_norm(
            &macro_part(&iface.basis, &ua.f),
            &macro_part(&iface.basis, &ub.f),
            -1.0,
        );
        worst[0] = worst[0].max(du / u_scale);
        worst[1] = worst[1].max(df / f_scale);
    }
    // Equilibrium of every substructure: B_Eᵀ(t + t0) − share·F^d − C_Eᵀ F_EΓ = 0.
    for (e, (sub, st)) in latin
        .operators
        .substructures
        .iter()
        .zip(&state.subs)
        .enumerate()
    {
        let n = sub.dof_global.len();
        let mut r = vec![0.0; n];
        let mut magnitude = vec![0.0; n];
        for (j, &i) in sub.links.iter().enumerate() {
            let tau = st.t[j] + s.links[i].prestress;
            sub.link_dofs[j].scatter(tau, &mut r);
            sub.link_dofs[j].scatter(tau.abs(), &mut magnitude);
        }
        for (local, (&global, &share)) in sub.dof_global.iter().zip(&sub.load_share).enumerate() {
            r[local] -= share * f_d[global];
        }
        for (side, ss) in sub.sides.iter().zip(&st.sides) {
            for (row, &f) in ss.f.iter().enumerate() {
                r[sub.gamma_dofs[side.gamma_offset + row]] -= f;
            }
        }
        let scale = norm(&magnitude).max(norm(&f_d));
        let rel = norm(&r) / scale;
        assert!(rel.is_finite(), "substructure {e}");
        worst[2] = worst[2].max(rel);
    }
    worst
}

#[test]
fn linear_stage_invariants() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let alpha = 1.0;
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro)).unwrap();
    let mut state = latin.init(&load(s, alpha));
    for stop in [0, 5, 40] {
        while state.iteration < stop {
            latin.next_iter(&mut state);
        }
        let [du, df, eq] = check_linear_stage(s, &latin, &state, alpha);
        println!(
            "iteration {stop}: macro jump {du:.1e} |U|, macro force imbalance {df:.1e} |F|, \
             equilibrium {eq:.1e}"
        );
        assert!(
            du < 1e-9,
            "iteration {stop}: R^T U_a - R^T U_b = {du:e} |U|"
        );
        assert!(
            df < 1e-9,
            "iteration {stop}: R^T F_a + R^T F_b = {df:e} |F|"
        );
        assert!(eq < 1e-8, "iteration {stop}: equilibrium residual {eq:e}");
    }
    // Every substructure's ŝ enters: the interfaces' micro parts are not trivially zero.
    let micro: f64 = state
        .subs
        .iter()
        .flat_map(|st| st.sides.iter().flat_map(|sd| sd.hat_load.clone()))
        .map(|x| x.abs())
        .sum();
    assert!(micro > 0.0);
}

/// Same invariants on an uneven partition with a supported substructure row.
#[test]
fn linear_stage_invariants_uneven_partition() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let mut latin = Latin::new(&model, settings([3, 5], WeakInterfaces::Macro)).unwrap();
    let mut state = latin.init(&load(s, 0.5));
    for _ in 0..5 {
        latin.next_iter(&mut state);
    }
    let [du, df, eq] = check_linear_stage(s, &latin, &state, 0.5);
    println!("3x5 iteration 5: {du:.1e} {df:.1e} {eq:.1e}");
    assert!(du < 1e-9 && df < 1e-9 && eq < 1e-8, "{du:e} {df:e} {eq:e}");
    // Its kernels, against K*_E and against B_E.
    let (total, _, _) = check_kernels(&latin, "3x5");
    let independent = independent_kernel_dimension(s, [3, 5], WeakInterfaces::Macro);
    let dims: Vec<usize> = independent.iter().map(|d| d.0).collect();
    let cols: Vec<usize> = latin
        .operators
        .substructures
        .iter()
        .map(|s| s.kernel.ncols())
        .collect();
    assert_eq!(cols, dims);
    assert_eq!(total, latin.report().kernel_columns);
}

/// Same invariants with a richer macro basis: 2 × 2 substructures of 8 × 8 modules at degree
/// 3 (and the default, 2), the macro jump measured on every column of R.
#[test]
fn linear_stage_invariants_with_a_higher_degree() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    let first_order = LatinSettings {
        macro_degree: Some(1),
        ..settings([2, 2], WeakInterfaces::Macro)
    };
    let first_order_dofs = Latin::new(&model, first_order).unwrap().report().macro_dofs;
    for degree in [None, Some(3)] {
        let settings = LatinSettings {
            macro_degree: degree,
            ..settings([2, 2], WeakInterfaces::Macro)
        };
        let mut latin = Latin::new(&model, settings).unwrap();
        let report = latin.report();
        assert_eq!(report.macro_degree, degree.unwrap_or(2));
        // Three more fields per degree on each of the four strong interfaces.
        let extra = 4 * 3 * (report.macro_degree - 1);
        assert_eq!(report.macro_dofs, first_order_dofs + extra);
        let mut state = latin.init(&load(s, 1.0));
        for _ in 0..5 {
            latin.next_iter(&mut state);
        }
        let [du, df, eq] = check_linear_stage(s, &latin, &state, 1.0);
        println!(
            "2x2 degree {}: {du:.1e} {df:.1e} {eq:.1e}",
            report.macro_degree
        );
        assert!(du < 1e-9 && df < 1e-9 && eq < 1e-8, "{du:e} {df:e} {eq:e}");
        check_kernels(&latin, "2x2");
    }
}
