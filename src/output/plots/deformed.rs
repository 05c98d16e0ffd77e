//! `deformed_alpha{α}.svg` (paper Figure 8): the grid seen from above at one α. Nodes are
//! coloured by their vertical displacement uz, taut cables are drawn in grey to black and
//! thicker as their tension grows, slack cables dashed red; clamped nodes are squares.
//!
//! In a top view a lower edge carries the lower cables of both modules beside it and half of
//! it a bracing cable of each: each link is drawn shrunk toward its module's centre (lower
//! cables by 10 %, bracing cables by 25 %) so that none hides another. Bars are not drawn.

use super::legend::{draw_colour_bar, draw_line_legend, LegendEntry};
use super::palette::{tension_grey, viridis, SLACK};
use super::{alpha_text, plot_error, tick_label};
use crate::solvers::Equilibrium;
use crate::structure::{module_nodes, Link, LinkKind, Structure};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::ops::Range;

/// Pixels per module along the longer side of the grid, and the bounds of that side.
const MODULE_PIXELS: f64 = 60.0;
const GRID_PIXELS: (f64, f64) = (720.0, 1400.0);
const PANEL_WIDTH: u32 = 300;
const MIN_HEIGHT: u32 = 660;
const Y_LABELS: u32 = 70;
const X_LABELS: u32 = 50;
const MARGIN: u32 = 14;
const CAPTION: u32 = 40;

/// The plotted ranges of a grid and their scale.
struct TopView {
    x: Range<f64>,
    y: Range<f64>,
    /// Pixels per metre.
    scale: f64,
}

impl TopView {
    fn new(s: &Structure) -> TopView {
        let span = |k: usize| {
            let (lo, hi) = s
                .nodes
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    (l.min(p[k]), h.max(p[k]))
                });
            let pad = 0.04 * (hi - lo).max(1e-9);
            lo - pad..hi + pad
        };
        let (x, y) = (span(0), span(1));
        let longer = (x.end - x.start).max(y.end - y.start);
        // A general structure is drawn at the scale of a grid as wide as its longest member.
        let modules = match &s.layout {
            Some(layout) => layout.nx.max(layout.ny) as f64,
            None => longer / typical_member(s).max(1e-12),
        };
        let pixels = (MODULE_PIXELS * modules).clamp(GRID_PIXELS.0, GRID_PIXELS.1);
        TopView {
            x,
            y,
            scale: pixels / longer,
        }
    }

    /// The chart's pixel size: the grid at one scale on both axes, plus the axes.
    fn chart_size(&self) -> (u32, u32) {
        let w = ((self.x.end - self.x.start) * self.scale).ceil() as u32;
        let h = ((self.y.end - self.y.start) * self.scale).ceil() as u32;
        (
            w + Y_LABELS + 2 * MARGIN,
            h + X_LABELS + 2 * MARGIN + CAPTION,
        )
    }

    fn node_radius(&self, s: &Structure) -> i32 {
        let module = match &s.layout {
            Some(layout) => s.nodes[layout.corner(1, 0)][0] - s.nodes[layout.corner(0, 0)][0],
            None => typical_member(s),
        };
        (0.08 * module * self.scale).round().clamp(1.0, 5.0) as i32
    }
}

/// What the colours stand for: uz on nodes, τ on taut cables.
struct Colouring {
    uz: Vec<f64>,
    uz_range: (f64, f64),
    max_tension: f64,
}

impl Colouring {
    fn new(s: &Structure, eq: &Equilibrium) -> Colouring {
        let full = s.full_displacements(&eq.displacements);
        let uz: Vec<f64> = full.chunks(3).map(|u| u[2]).collect();
        let lo = uz.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = uz.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let max_tension = s
            .links
            .iter()
            .zip(&eq.tensions)
            .filter(|(l, _)| l.kind.is_cable())
            .fold(0.0, |m: f64, (_, &t)| m.max(t));
        let uz_range = if lo <= hi { (lo, hi) } else { (0.0, 0.0) };
        Colouring {
            uz,
            uz_range,
            max_tension: if max_tension > 0.0 { max_tension } else { 1.0 },
        }
    }

    fn node(&self, node: usize) -> RGBColor {
        let (lo, hi) = self.uz_range;
        let t = if hi > lo {
            (self.uz[node] - lo) / (hi - lo)
        } else {
            0.5
        };
        viridis(t)
    }

    /// Colour and stroke width (1 to 3 px) of a taut cable.
    fn cable(&self, tension: f64) -> (RGBColor, u32) {
        let t = (tension / self.max_tension).clamp(0.0, 1.0);
        (tension_grey(t), 1 + (2.0 * t).round() as u32)
    }
}

pub fn to_svg(solver: &str, alpha: f64, s: &Structure, eq: &Equilibrium) -> io::Result<String> {
    let view = TopView::new(s);
    let colouring = Colouring::new(s, eq);
    let (chart_w, chart_h) = view.chart_size();
    let size = (chart_w + PANEL_WIDTH, chart_h.max(MIN_HEIGHT));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (plot, panel) = root.split_horizontally(chart_w);
        let title = format!(
            "Top view at α = {} ({solver}): uz on nodes, τ on cables",
            alpha_text(alpha)
        );
        draw_grid(&plot, &title, &view, s, eq, &colouring).map_err(plot_error)?;
        draw_panel(&panel, &colouring).map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

/// Where a link is drawn: its ends pulled toward its module's centre.
fn drawn_ends(s: &Structure, link: &Link) -> [(f64, f64); 2] {
    let shrink = match link.kind {
        LinkKind::LowerCable => 0.10,
        LinkKind::BracingCable => 0.25,
        LinkKind::DiagonalCable => 0.15,
        LinkKind::UpperCable => 0.04,
        LinkKind::Bar | LinkKind::Cable => 0.0,
    };
    let Some(layout) = &s.layout else {
        // General structures: members drawn end to end.
        return [link.a, link.b].map(|n| (s.nodes[n][0], s.nodes[n][1]));
    };
    let nx = layout.nx;
    let corners = &module_nodes(layout, link.module % nx, link.module / nx)[..4];
    let centre = |k: usize| corners.iter().map(|&c| s.nodes[c][k]).sum::<f64>() / 4.0;
    let (cx, cy) = (centre(0), centre(1));
    let pull = |node: usize| {
        let p = s.nodes[node];
        (p[0] + shrink * (cx - p[0]), p[1] + shrink * (cy - p[1]))
    };
    [pull(link.a), pull(link.b)]
}

fn draw_grid<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    view: &TopView,
    s: &Structure,
    eq: &Equilibrium,
    colouring: &Colouring,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 21))
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(view.x.clone(), view.y.clone())?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()?;

    let mut taut: Vec<(usize, f64)> = Vec::new();
    let mut slack: Vec<usize> = Vec::new();
    for (i, (link, &tension)) in s.links.iter().zip(&eq.tensions).enumerate() {
        match (link.kind.is_cable(), eq.slack[i]) {
            (false, _) => {}
            (true, true) => slack.push(i),
            (true, false) => taut.push((i, tension)),
        }
    }
    // Most tense on top.
    taut.sort_by(|a, b| a.1.total_cmp(&b.1));
    chart.draw_series(taut.iter().map(|&(i, tension)| {
        let (colour, width) = colouring.cable(tension);
        PathElement::new(drawn_ends(s, &s.links[i]), colour.stroke_width(width))
    }))?;
    for &i in &slack {
        let style = SLACK.stroke_width(2);
        chart.draw_series(DashedLineSeries::new(
            drawn_ends(s, &s.links[i]),
            4,
            3,
            style,
        ))?;
    }

    let radius = view.node_radius(s);
    // Below 3 px an outline would hide the node's colour.
    let outline = RGBColor(60, 60, 60).mix(if radius >= 3 { 1.0 } else { 0.0 });
    let at = |node: usize| (s.nodes[node][0], s.nodes[node][1]);
    let (clamped, free): (Vec<usize>, Vec<usize>) =
        (0..s.n_nodes()).partition(|&node| s.clamped[node]);
    chart.draw_series(free.iter().map(|&node| {
        EmptyElement::at(at(node))
            + Circle::new((0, 0), radius, colouring.node(node).filled())
            + Circle::new((0, 0), radius, outline)
    }))?;
    let r = radius;
    chart.draw_series(clamped.iter().map(|&node| {
        EmptyElement::at(at(node))
            + Rectangle::new([(-r, -r), (r, r)], colouring.node(node).filled())
            + Rectangle::new([(-r, -r), (r, r)], outline)
    }))?;
    Ok(())
}

const NOTES: [&str; 5] = [
    "circles: nodes; squares: clamped nodes",
    "links drawn shrunk toward their",
    "module's centre (lower cables 10 %,",
    "bracing 25 %) so none hides another;",
    "bars not drawn",
];

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    colouring: &Colouring,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (taut, _) = colouring.cable(colouring.max_tension);
    let entries = [
        LegendEntry {
            label: "taut cable".into(),
            colour: taut,
            dashed: false,
            marker: None,
        },
        LegendEntry {
            label: "slack cable (τ = 0)".into(),
            colour: SLACK,
            dashed: true,
            marker: None,
        },
    ];
    let mut y = 60 + draw_line_legend(area, 60, "cables", &entries)? + 6;
    let note = ("sans-serif", 13).into_font().color(&BLACK);
    for line in NOTES {
        area.draw_text(line, &note, (8, y))?;
        y += 17;
    }
    let (_, rest) = area.split_vertically(y + 10);
    let bars = rest.split_evenly((2, 1));
    draw_colour_bar(&bars[0], "nodes: uz (m)", colouring.uz_range, &viridis)?;
    let tension = (0.0, colouring.max_tension);
    draw_colour_bar(&bars[1], "taut cables: τ (N)", tension, &tension_grey)?;
    Ok(())
}

/// The longest member's length, m: the drawing scale of a general structure.
fn typical_member(s: &Structure) -> f64 {
    s.links.iter().fold(0.0, |m: f64, l| m.max(l.length))
}
