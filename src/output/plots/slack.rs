//! `slack_fraction.svg` (paper Figure 7): the fraction of slack cables against α, one series
//! per solver.

use super::chart::LineChart;
use super::palette::solver_colour;
use super::series::{Scale, Series};
use crate::solvers::Method;

/// `per_solver`: (solver, [(α, slack fraction)]).
pub fn chart(per_solver: &[(Method, &[(f64, f64)])]) -> LineChart {
    let series = per_solver
        .iter()
        .map(|(solver, points)| {
            let mut points = points.to_vec();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: solver.name().to_string(),
                colour: solver_colour(*solver),
                points,
            }
        })
        .collect();
    LineChart {
        title: "Fraction of slack cables against the load factor".into(),
        x_label: "load factor α (–)".into(),
        y_label: "slack cables / cables (–)".into(),
        x_scale: Scale::Linear,
        y_scale: Scale::Linear,
        legend_title: "solver".into(),
        markers: true,
        series,
    }
}
