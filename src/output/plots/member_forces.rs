//! `member_forces.svg`: on a general structure (`[structure]`, not a grid) under
//! [`LABEL_LIMIT`] members, every member's axial force at the figure's α, one horizontal bar
//! per member in the members table's order, labelled `m{id} bar` or `m{id} cable` (`(slack)`
//! when it is): tension to the right, compression to the left, struts near black, cables in
//! their colour of `deformed_alpha{α}.svg` (the same [`TensionScale`]), a black tick on each at
//! its prestress t0, the force at zero load. It takes the place of `tensions.svg`, whose
//! rank-sorted curves lose which member is which.

use super::annotate::LABEL_LIMIT;
use super::tension_scale::TensionScale;
use super::views::BAR;
use super::{alpha_text, plot_error, tick_label};
use crate::solvers::Equilibrium;
use crate::structure::Structure;
use plotters::prelude::*;
use std::io;

/// Height of one member's row, px.
const ROW: u32 = 20;
const WIDTH: u32 = 900;
const TITLE: u32 = 64;
/// Width of the members' labels left of the bars, px.
const LABELS: u32 = 150;
const X_LABELS: u32 = 50;
const MARGIN: u32 = 14;
/// The prestress tick.
pub const PRESTRESS: RGBColor = RGBColor(0, 0, 0);

/// Drawn for a general structure under [`LABEL_LIMIT`] members.
pub fn drawn_for(s: &Structure) -> bool {
    s.layout.is_none() && s.links.len() < LABEL_LIMIT
}

/// The figure as an SVG document: the members' forces of `eq` at `alpha`.
pub fn to_svg(solver: &str, alpha: f64, s: &Structure, eq: &Equilibrium) -> io::Result<String> {
    let n = s.links.len();
    let height = TITLE + n as u32 * ROW + X_LABELS + 2 * MARGIN;
    let prestress = s.links.iter().map(|l| s.self_stress(l));
    let (lo, hi) = eq
        .tensions
        .iter()
        .copied()
        .chain(prestress)
        .filter(|f| f.is_finite())
        .fold((0.0_f64, 0.0_f64), |(lo, hi), f| (lo.min(f), hi.max(f)));
    let pad = 0.05 * (hi - lo).max(1e-9);
    let scale = TensionScale::new(s, eq);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let font = |size: u32| ("sans-serif", size).into_font().color(&BLACK);
        let title = format!("Member forces at α = {} ({solver})", alpha_text(alpha));
        let note = "bar: axial force at α, tension > 0; black tick: prestress t0 (zero load); \
                    cables coloured as in the deformed figure";
        root.draw_text(&title, &font(19), (MARGIN as i32, 10))
            .map_err(plot_error)?;
        root.draw_text(note, &font(13), (MARGIN as i32, 38))
            .map_err(plot_error)?;
        let (_, body) = root.split_vertically(TITLE);
        let mut chart = ChartBuilder::on(&body)
            .margin(MARGIN)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(LABELS)
            .build_cartesian_2d(lo - pad..hi + pad, 0.0..n as f64)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(0)
            .x_desc("axial force (N)")
            .x_label_formatter(&|v| tick_label(*v))
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .draw()
            .map_err(plot_error)?;
        // Member 0 in the top row.
        let row = |i: usize| (n - 1 - i) as f64;
        let zero = PathElement::new(vec![(0.0, 0.0), (0.0, n as f64)], RGBColor(120, 120, 120));
        chart.draw_series([zero]).map_err(plot_error)?;
        for (i, link) in s.links.iter().enumerate() {
            let force = eq.tensions[i];
            let colour = if link.kind.is_cable() {
                scale.colour(force)
            } else {
                BAR
            };
            let y = row(i);
            if !eq.slack[i] {
                let mut bar = Rectangle::new([(0.0, y + 0.2), (force, y + 0.8)], colour.filled());
                bar.set_margin(0, 0, 0, 0);
                chart.draw_series([bar]).map_err(plot_error)?;
            }
            let t0 = s.self_stress(link);
            let tick = PathElement::new(
                vec![(t0, y + 0.05), (t0, y + 0.95)],
                PRESTRESS.stroke_width(2),
            );
            chart.draw_series([tick]).map_err(plot_error)?;
        }
        let plot = chart.plotting_area();
        for (i, link) in s.links.iter().enumerate() {
            let (_, y) = plot.map_coordinate(&(lo, row(i) + 0.5));
            let slack = if eq.slack[i] { " (slack)" } else { "" };
            let label = format!("m{} {}{slack}", link.id, link.kind.name());
            root.draw_text(&label, &font(13), (MARGIN as i32, y - 7))
                .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}
