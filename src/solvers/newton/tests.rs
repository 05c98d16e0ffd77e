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
