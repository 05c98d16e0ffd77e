//! Natural modes (issue 45 item 1): the simplex's infinitesimal mechanism vibrates only
//! through its prestress: its lowest mode is flagged prestress-governed, and with the members'
//! elastic stiffness alone (no K_G) its frequency drops to zero; the sparse eigenpairs agree
//! with a dense generalized solve.

mod common;

use common::manifest_path;
use nalgebra::{DMatrix, SymmetricEigen};
use tensolve::linalg::lowest_generalized_modes;
use tensolve::model::{GeometricModel, MassKind, Model};
use tensolve::results::modes::natural_modes;
use tensolve::solvers::TautStiffness;

/// The shipped simplex under `model`, its members of steel (7850 kg/m³).
fn steel_simplex(model: GeometricModel) -> Model {
    let mut case = tensolve::case::load(&manifest_path("cases/simplex.toml")).unwrap();
    case.model = model;
    for m in &mut case.geometry.members {
        m.density = 7850.0;
    }
    case.model()
}

#[test]
fn the_simplex_mechanism_is_prestress_governed_and_vanishes_without_k_g() {
    let model = steel_simplex(GeometricModel::Prestress);
    let s = &model.structure;
    let taut = TautStiffness::new(&model).unwrap();
    let (u, carrying) = (vec![0.0; s.n_free], vec![true; s.links.len()]);
    let tensions: Vec<f64> = s.links.iter().map(|l| l.prestress).collect();
    let at_rest = (&u[..], &tensions[..], &carrying[..]);
    let count = 6;
    for mass in [MassKind::Consistent, MassKind::Lumped] {
        let modes =
            natural_modes(&model, at_rest, &taut.pattern, &taut.factor, count, mass).unwrap();
        assert_eq!(modes.len(), count);
        // The mechanism (m = 1): the lowest mode, held by the prestress alone.
        assert!(
            modes[0].prestress_governed(),
            "{mass:?}: {:?}",
            modes[0].elastic_share
        );
        assert!(modes[0].frequency_hz > 0.0);
        for mode in &modes[1..] {
            assert!(
                !mode.prestress_governed(),
                "{mass:?}: {}",
                mode.elastic_share
            );
            assert!(mode.frequency_hz > 3.0 * modes[0].frequency_hz);
        }
        // Against a dense generalized solve of the same K_T and M.
        let p = &taut.pattern;
        let dense = |v: &[f64]| {
            let mut a = DMatrix::zeros(p.n, p.n);
            for (r, c, slot) in p.entries() {
                a[(r, c)] = v[slot];
                a[(c, r)] = v[slot];
            }
            a
        };
        let mut k = vec![0.0; p.nnz()];
        model.assemble_tangent(p, |_| true, &mut k);
        let mut m = vec![0.0; p.nnz()];
        model.assemble_mass(p, mass, &mut m);
        let l = dense(&m).cholesky().unwrap().l().try_inverse().unwrap();
        let mut exact: Vec<f64> = SymmetricEigen::new(&l * dense(&k) * l.transpose())
            .eigenvalues
            .iter()
            .copied()
            .collect();
        exact.sort_by(f64::total_cmp);
        for (mode, lambda) in modes.iter().zip(&exact) {
            let f = lambda.sqrt() / (2.0 * std::f64::consts::PI);
            assert!(
                (mode.frequency_hz - f).abs() <= 1e-9 * f,
                "{mass:?}: {} against {f}",
                mode.frequency_hz
            );
        }
        // Without K_G: the members' elastic stiffness alone leaves the mechanism at zero.
        let mut elastic = vec![0.0; p.nnz()];
        p.assemble(&s.link_dofs, |i| s.links[i].stiffness, &mut elastic);
        let mut factor = taut.factor.share_symbolic();
        let without = lowest_generalized_modes(p, &elastic, &m, &mut factor, count, 1e-10).unwrap();
        assert!(
            without.values[0].abs() <= 1e-10 * without.values[1],
            "{mass:?}: {:?}",
            without.values
        );
        let f1 = |lambda: f64| lambda.sqrt() / (2.0 * std::f64::consts::PI);
        eprintln!(
            "{mass:?}: with K_G {:.6} Hz (elastic share {:.2e}); without {:.3e} Hz, next {:.6} Hz",
            modes[0].frequency_hz,
            modes[0].elastic_share,
            f1(without.values[0].max(0.0)),
            f1(without.values[1])
        );
    }
}
