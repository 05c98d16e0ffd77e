//! `tensions.svg` (paper Figure 6): every cable's tension τ sorted increasingly, one series per
//! α, from the first solver of the case.

use super::alpha_text;
use super::chart::{LineChart, Scale, Series};
use super::palette::ordered_colour;

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
