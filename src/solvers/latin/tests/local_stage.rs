//! The local stage's law on both search directions.

use super::*;
use crate::model::Model;

#[test]
fn local_stage_law() {
    let model = Model::linear(paper_structure());
    let s = &model.structure;
    // The plain method: with relaxation, s is not on the search direction through ŝ.
    let mut latin = Latin::new(&model, settings([4, 4], WeakInterfaces::Macro).plain()).unwrap();
    let mut state = latin.init(&load(s, 1.0));
    let (mut slack, mut taut, mut bars) = (0, 0, 0);
    let mut worst_product: f64 = 0.0;
    for _ in 0..5 {
        // s_{k−1}: the local stage of next_iter starts from it.
        let previous = state.subs.clone();
        latin.next_iter(&mut state);
        for ((sub, st), prev) in latin
            .operators
            .substructures
            .iter()
            .zip(&state.subs)
            .zip(&previous)
        {
            for (j, &i) in sub.links.iter().enumerate() {
                let link = &s.links[i];
                let (k, t0) = (link.stiffness, link.prestress);
                let (e_hat, t_hat) = (st.e_hat[j], st.t_hat[j]);
                // ŝ_k on the search direction E+ through s_{k−1}: (t̂ − t) + l (ê − e) = 0;
                // s_k on E− through ŝ_k: (t − t̂) − l (e − ê) = 0. Here l = k.
                let l = k;
                let (e_prev, t_prev) = (prev.e[j], prev.t[j]);
                let (e1, t1) = (st.e[j], st.t[j]);
                let checks = [
                    (
                        "E+",
                        (t_hat - t_prev) + l * (e_hat - e_prev),
                        t_prev.abs() + l * e_prev.abs(),
                    ),
                    (
                        "E-",
                        (t1 - t_hat) - l * (e1 - e_hat),
                        t1.abs() + l * e1.abs(),
                    ),
                ];
                for (what, gap, scale) in checks {
                    let scale = scale + t_hat.abs() + l * e_hat.abs();
                    assert!(
                        gap.abs() <= 1e-12 * scale.max(1e-300),
                        "link {i}: {what} violated by {gap:e} (scale {scale:e})"
                    );
                }
                if !link.unilateral {
                    bars += 1;
                    assert!(!st.slack_hat[j], "link {i}: bilateral link flagged slack");
                    let d = t_hat - k * e_hat;
                    assert!(
                        d.abs() <= 1e-12 * t_hat.abs().max(k * e_hat.abs()).max(1e-300),
                        "link {i}: t̂ − k ê = {d:e}"
                    );
                    continue;
                }
                let tau = t_hat + t0;
                let lambda = -e_hat + t_hat / k;
                // Scale of λ̂: the terms it is made of.
                let lambda_scale = e_hat.abs() + t_hat.abs() / k + t0 / k;
                assert!(tau >= 0.0, "link {i}: τ̂ = {tau:e}");
                assert!(
                    lambda >= -1e-9 * lambda_scale,
                    "link {i}: λ̂ = {lambda:e} (scale {lambda_scale:e})"
                );
                assert_eq!(
                    st.slack_hat[j],
                    tau == 0.0,
                    "link {i}: slack flag vs τ̂ = {tau:e}"
                );
                if st.slack_hat[j] {
                    slack += 1;
                } else {
                    taut += 1;
                    let rel = lambda.abs() / lambda_scale;
                    worst_product = worst_product.max(rel);
                    assert!(
                        rel <= 1e-9,
                        "link {i}: taut, τ̂ = {tau:e}, λ̂ = {lambda:e} ({rel:e} of its scale)"
                    );
                }
            }
        }
        // The slack count of the state is that of ŝ.
        let count: usize = state
            .subs
            .iter()
            .map(|st| st.slack_hat.iter().filter(|&&x| x).count())
            .sum();
        assert_eq!(count, state.slack_cables);
    }
    println!(
        "local stage, 5 iterations: {slack} slack and {taut} taut cable states, {bars} bar \
         states; worst |λ̂| of a taut cable {worst_product:.1e} of its scale"
    );
    assert!(slack > 0 && taut > 0 && bars > 0);
    // The equilibrium handed out: the local stage's tensions on the last s, its slack set the
    // shared classification of U (a slack cable carries exactly 0; a cable at τ = 0 whose gap
    // is closed is taut at rest).
    let eq = latin.iterate(&state);
    let shared = crate::solvers::Equilibrium::classified(
        &model,
        eq.displacements.clone(),
        eq.tensions.clone(),
    );
    assert_eq!(eq.slack, shared.slack);
    for (i, link) in s.links.iter().enumerate() {
        assert!(!eq.slack[i] || eq.tensions[i] == 0.0, "link {i}");
        assert!(!link.unilateral || eq.tensions[i] >= 0.0, "link {i}");
    }
}
