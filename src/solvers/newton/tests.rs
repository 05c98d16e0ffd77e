//! The Hessian newton assembles against the product CG uses.

use super::*;
use crate::linalg::norm;
use crate::structure::{GridSpec, LoadPattern};

/// The link-by-link product CG uses is the one of the Hessian a factorization gets, for a
/// taut set with slack cables and a regularisation; and it changes when a link's state
/// does.
#[test]
fn hessian_product_is_the_assembled_hessians() {
    let spec = GridSpec {
        modules: [3, 2],
        ..GridSpec::default()
    };
    let model = Model::linear(Structure::grid(&spec, &LoadPattern::default()));
    let s = &model.structure;
    let taut = TautStiffness::new(&model).expect("regular");
    let taut_links: Vec<bool> = s
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| !l.unilateral || i % 3 != 0)
        .collect();
    assert!(taut_links.iter().any(|t| !t), "some cables slack");
    let mu = 1e-3 * taut.pattern.mean_diagonal(&taut.values);
    let mut assembled = vec![0.0; taut.values.len()];
    assemble_hessian(&model, &taut.pattern, &taut_links, mu, &mut assembled);
    let v: Vec<f64> = (0..s.n_free).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
    let (mut expected, mut product) = (vec![0.0; s.n_free], vec![0.0; s.n_free]);
    taut.pattern.sym_matvec(&assembled, &v, &mut expected);
    model.tangent_product(&taut_links, mu, &v, &mut product);
    let scale = norm(&expected);
    for (p, e) in product.iter().zip(&expected) {
        assert!((p - e).abs() <= 1e-12 * scale, "{p} against {e}");
    }
    let mut one_more_taut = taut_links.clone();
    let flipped = one_more_taut.iter().position(|t| !t).expect("a slack link");
    one_more_taut[flipped] = true;
    let mut changed = vec![0.0; s.n_free];
    model.tangent_product(&one_more_taut, mu, &v, &mut changed);
    assert!(changed
        .iter()
        .zip(&product)
        .any(|(a, b)| (a - b).abs() > 1e-9 * scale));
}

/// On a 128 × 128 grid (263 k links) the krylov solve's Hessian product goes by chunks of
/// links (their spans add up to less than twice the dofs), and it is the link-by-link product
/// to round-off, with slack cables and a regularisation.
#[test]
fn the_chunked_hessian_product_is_the_link_by_link_one() {
    let spec = GridSpec {
        modules: [128, 128],
        ..GridSpec::default()
    };
    let model = Model::linear(Structure::grid(&spec, &LoadPattern::default()));
    let s = &model.structure;
    let mut chunks = crate::linalg::RowChunks::new(&s.link_dofs, s.n_free).expect("chunked");
    let taut_links: Vec<bool> = s
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| !l.unilateral || i % 3 != 0)
        .collect();
    let v: Vec<f64> = (0..s.n_free).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
    let (mut expected, mut product) = (vec![0.0; s.n_free], vec![0.0; s.n_free]);
    model.tangent_product(&taut_links, 2.5e3, &v, &mut expected);
    model.tangent_product_chunked(&mut chunks, &taut_links, 2.5e3, &v, &mut product);
    let scale = norm(&expected);
    for (p, e) in product.iter().zip(&expected) {
        assert!((p - e).abs() <= 1e-13 * scale, "{p} against {e}");
    }
}

/// The substructured solve keeps its GenEO vectors when cables go slack, and finds them
/// anew on the changed subdomains after a step slower than [`krylov::STALE_RATE`] times the
/// step that found them (here made so by a found rate set far below any real one); either way
/// the step solves `H x = b` to its forcing tolerance.
#[test]
fn geneo_vectors_are_kept_until_a_step_is_slow() {
    let spec = GridSpec {
        modules: [16, 16],
        ..GridSpec::default()
    };
    let model = Model::linear(Structure::grid(&spec, &LoadPattern::default()));
    let s = &model.structure;
    let taut = TautStiffness::new(&model).expect("regular");
    let mean = taut.pattern.mean_diagonal(&taut.values);
    let mu = 1e-8 * mean;
    let b: Vec<f64> = (0..s.n_free)
        .map(|d| ((d * 31) % 17) as f64 - 8.0)
        .collect();
    let all_taut = vec![true; s.links.len()];
    // One cable in four slack (two different sets): more than 2 % of every subdomain's links
    // change.
    let softened = |k: usize| -> Vec<bool> {
        (0..s.links.len())
            .map(|i| !s.links[i].unilateral || i % 4 != k)
            .collect()
    };
    let solve = |krylov: &mut krylov::KrylovSolve, taut_links: &[bool], work: &mut NewtonWork| {
        let mut x = b.clone();
        krylov.begin(work);
        assert!(krylov.solve(&model, taut_links, (mu, mean), (1.0, 1e-9), &mut x, work));
        let mut hx = vec![0.0; s.n_free];
        model.tangent_product(taut_links, mu, &x, &mut hx);
        let residual: f64 = hx.iter().zip(&b).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        residual.sqrt() / b.iter().map(|v| v * v).sum::<f64>().sqrt()
    };
    for slow in [false, true] {
        let mut krylov = krylov::KrylovSolve::new(&model, [4, 4]);
        let mut work = NewtonWork::default();
        assert!(solve(&mut krylov, &all_taut, &mut work) <= 0.1 + 1e-12);
        assert_eq!(
            work.geneo_solves, 16,
            "the first update finds every subdomain's"
        );
        if slow {
            krylov.pretend_found_rate(1e-3);
        }
        // The step after the change: vectors kept, whatever the rate (it is judged after).
        assert!(solve(&mut krylov, &softened(0), &mut work) <= 0.1 + 1e-12);
        assert_eq!(work.geneo_solves, 16);
        // Another slack set: found anew only after a slow step.
        assert!(solve(&mut krylov, &softened(1), &mut work) <= 0.1 + 1e-12);
        assert_eq!(work.geneo_solves > 16, slow, "slow step: {slow}");
    }
}
