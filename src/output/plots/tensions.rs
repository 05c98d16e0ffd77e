//! `tensions.svg` (paper Figure 6): every cable's tension τ sorted increasingly, one series per
//! α, from the first solver of the case. α = 0 is shown whenever its answer is known: when the
//! case does not solve it, its curve is the prestress τ₀ itself, the exact solution at zero load
//! (u = 0) of a prestress balanced at the free nodes (supports may take part of it) with no
//! settlement.

use super::alpha_text;
use super::chart::LineChart;
use super::palette::ordered_colour;
use super::series::{Scale, Series};
use crate::structure::Structure;

/// The cable tensions at α = 0 when u = 0 is the answer there: the prestress balances at the
/// free dofs (`max |Bᵀτ₀|` over them below 1e-9 of its scale; the supports take the rest) and
/// no support is settled (a settlement is applied at every α). τ₀, sorted; None otherwise.
pub fn at_rest(s: &Structure) -> Option<(f64, Vec<f64>)> {
    let free_imbalance = s
        .free_prestress_imbalance()
        .iter()
        .flat_map(|(force, _)| force.iter())
        .fold(0.0_f64, |m, f| m.max(f.abs()));
    let settled = s.prescribed.iter().any(|&u| u != 0.0);
    if settled || free_imbalance > 1e-9 * s.prestress_scale.abs().max(f64::MIN_POSITIVE) {
        return None;
    }
    let mut tensions: Vec<f64> = s
        .links
        .iter()
        .filter(|l| l.kind.is_cable())
        .map(|l| l.prestress)
        .collect();
    tensions.sort_by(f64::total_cmp);
    Some((0.0, tensions))
}

/// `sets`: per α, the sorted cable tensions (N).
pub fn chart(solver: &str, sets: &[(f64, Vec<f64>)]) -> LineChart {
    let mut sets: Vec<&(f64, Vec<f64>)> = sets.iter().collect();
    sets.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = sets.len();
    let series = sets
        .iter()
        .enumerate()
        .map(|(i, (alpha, tensions))| Series {
            label: format!("α = {}", alpha_text(*alpha)),
            colour: ordered_colour(i, n),
            points: tensions
                .iter()
                .enumerate()
                .map(|(rank, &t)| (rank as f64, t))
                .collect(),
        })
        .collect();
    LineChart {
        title: format!("Cable tensions sorted increasingly ({solver})"),
        x_label: "cable rank (–)".into(),
        y_label: "cable tension τ (N)".into(),
        x_scale: Scale::Linear,
        y_scale: Scale::Linear,
        legend_title: "load factor".into(),
        markers: false,
        series,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// D7 (issue 42): α = 0's curve is drawn when the supports take part of the prestress. On
    /// the saddle net (`cases/saddle-net.toml`) the cables to the held boundary load the
    /// supports, so `Bᵀτ₀` is not zero over all dofs, but it is at the free ones: u = 0 with
    /// τ = τ₀ is the answer at zero load, and its curve is τ₀ sorted, one point per cable. (The
    /// net itself, a general structure under 100 members, draws `member_forces.svg` instead.)
    #[test]
    fn d7_alpha_zero_is_known_when_supports_take_part_of_the_prestress() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/saddle-net.toml");
        let s = crate::case::load(&path)
            .expect("the shipped case")
            .structure();
        assert!(s.prestress_imbalance() > 1e-3 * s.prestress_scale);
        let (alpha, tensions) = at_rest(&s).expect("u = 0 is the answer at zero load");
        assert_eq!(alpha, 0.0);
        assert_eq!(tensions.len(), s.n_cables());
        assert!(tensions.windows(2).all(|w| w[0] <= w[1]));
        let mut t0: Vec<f64> = s
            .links
            .iter()
            .filter(|l| l.kind.is_cable())
            .map(|l| l.prestress)
            .collect();
        t0.sort_by(f64::total_cmp);
        assert_eq!(tensions, t0);
    }
}
