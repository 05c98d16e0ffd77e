//! `deformed_alpha{α}.svg` (paper Figure 8): the deformed structure at one α, displacements
//! multiplied by `output.amplification` (×10 by default, as the paper's), in one SVG of two
//! panels: an oblique view (a fixed axonometric projection, seen from the front left and
//! above) and a top view with x and y axes in m.
//!
//! Every link is drawn. Cables are coloured by their tension τ on one scale, shown by the
//! colour bar: yellow to dark red in tension, light to dark blue in compression (a bilateral
//! cable of the linear case may carry it). Slack cables are thin dashed grey lines; bars are
//! thin, near black and uncoloured.
//!
//! A grid: the oblique view draws the undeformed outline of its lower corners in grey; clamped
//! nodes are small black squares. In the top view a lower edge carries the lower cables of
//! both modules beside it and half of it a bracing cable of each: each link is drawn shrunk
//! toward its module's centre (lower cables by 10 %, bracing cables by 25 %) so that none
//! hides another.
//!
//! A general structure (`[structure]`, no modules): both views draw every member undeformed
//! in light grey under the deformed structure, members end to end; supports (nodes with a held
//! component) are small black squares.

use super::legend::{draw_colour_bar, draw_line_legend, LegendEntry, TEXT_SIZE};
use super::palette::{compression_colour, tension_colour};
use super::{alpha_text, plot_error, tick_label};
use crate::solvers::Equilibrium;
use crate::structure::{module_nodes, GridRole, Link, Structure};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::ops::Range;

/// Width of the whole figure, px: the README shows it at this size.
const WIDTH: u32 = 800;
/// Width of the column of legend and colour bar right of the views, px.
const PANEL_WIDTH: u32 = 180;
/// Height of the figure's title row, px.
const TITLE: u32 = 34;
/// Largest height of either view's drawing, px (tall grids are drawn smaller).
const MAX_VIEW_HEIGHT: f64 = 560.0;
const Y_LABELS: u32 = 60;
const X_LABELS: u32 = 44;
const MARGIN: u32 = 12;
/// Caption height of a view, px.
const CAPTION: u32 = 26;
/// Azimuth and elevation of the oblique view, degrees: seen from the front left, above.
const AZIMUTH: f64 = -30.0;
const ELEVATION: f64 = 35.0;

/// Bars: thin and near black, uncoloured (the cables' colours carry the tensions).
pub const BAR: RGBColor = RGBColor(25, 25, 25);
const BAR_WIDTH: u32 = 1;
const CABLE_WIDTH: u32 = 2;
/// Slack cables: thin dashed grey.
pub const SLACK: RGBColor = RGBColor(120, 120, 120);
const OUTLINE: RGBColor = RGBColor(150, 150, 150);
/// A general structure's undeformed members, under the deformed ones: light grey, and two
/// pixels wide so that it shows beside them.
pub const UNDEFORMED: RGBColor = RGBColor(170, 170, 170);
const UNDEFORMED_WIDTH: u32 = 2;

/// The nodes marked as supports: a grid's clamped nodes; every node with a held component of
/// a general structure.
fn supports(s: &Structure) -> impl Iterator<Item = usize> + '_ {
    (0..s.n_nodes()).filter(move |&n| {
        if s.layout.is_some() {
            s.clamped[n]
        } else {
            s.held_components(n).iter().any(|&h| h)
        }
    })
}

/// Draw the segment `a`–`b` (pixels) of an undeformed member.
fn draw_undeformed<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    a: (f64, f64),
    b: (f64, f64),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let px = |p: (f64, f64)| (p.0.round() as i32, p.1.round() as i32);
    area.draw(&PathElement::new(
        vec![px(a), px(b)],
        UNDEFORMED.stroke_width(UNDEFORMED_WIDTH),
    ))
}

/// The drawn position of every node: its position plus the amplified displacement.
fn deformed_nodes(s: &Structure, eq: &Equilibrium, amplification: f64) -> Vec<[f64; 3]> {
    let full = s.full_displacements(&eq.displacements);
    s.nodes
        .iter()
        .zip(full.chunks(3))
        .map(|(p, u)| {
            [
                p[0] + amplification * u[0],
                p[1] + amplification * u[1],
                p[2] + amplification * u[2],
            ]
        })
        .collect()
}

/// The cables' colour scale: from min(0, smallest τ) to the largest τ.
struct TensionScale {
    lo: f64,
    hi: f64,
}

impl TensionScale {
    fn new(s: &Structure, eq: &Equilibrium) -> TensionScale {
        let cables = s
            .links
            .iter()
            .zip(&eq.tensions)
            .filter(|(l, _)| l.kind.is_cable())
            .map(|(_, &t)| t);
        let (lo, hi) = cables.fold((0.0_f64, 0.0_f64), |(lo, hi), t| (lo.min(t), hi.max(t)));
        let hi = if hi > 0.0 { hi } else { 1.0 };
        TensionScale { lo, hi }
    }

    /// Yellow to dark red over [0, hi]; light to dark blue over [lo, 0).
    fn colour(&self, tension: f64) -> RGBColor {
        if tension >= 0.0 {
            tension_colour(tension / self.hi)
        } else {
            compression_colour(tension / self.lo)
        }
    }

    /// The colour at `t` ∈ [0, 1] of the colour bar, which spans [lo, hi].
    fn at(&self, t: f64) -> RGBColor {
        self.colour(self.lo + t * (self.hi - self.lo))
    }
}

/// How one link is drawn.
#[derive(Clone, Copy)]
enum Stroke {
    Bar,
    Cable(RGBColor),
    Slack,
}

fn stroke(link: &Link, index: usize, eq: &Equilibrium, scale: &TensionScale) -> Stroke {
    if !link.kind.is_cable() {
        Stroke::Bar
    } else if eq.slack[index] {
        Stroke::Slack
    } else {
        Stroke::Cable(scale.colour(eq.tensions[index]))
    }
}

/// Draw the segment `a`–`b` (pixels) in `stroke`'s style: one `<polyline>` per link, dashes
/// of a slack cable one each.
fn draw_link<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    a: (f64, f64),
    b: (f64, f64),
    stroke: Stroke,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let px = |p: (f64, f64)| (p.0.round() as i32, p.1.round() as i32);
    match stroke {
        Stroke::Bar => area.draw(&PathElement::new(
            vec![px(a), px(b)],
            BAR.stroke_width(BAR_WIDTH),
        )),
        Stroke::Cable(colour) => area.draw(&PathElement::new(
            vec![px(a), px(b)],
            colour.stroke_width(CABLE_WIDTH),
        )),
        Stroke::Slack => {
            let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
            let (dash, gap) = (4.0, 3.0);
            let mut from = 0.0;
            while from < length {
                let to = (from + dash).min(length);
                let at = |d: f64| {
                    let f = if length > 0.0 { d / length } else { 0.0 };
                    (a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1))
                };
                area.draw(&PathElement::new(
                    vec![px(at(from)), px(at(to))],
                    SLACK.stroke_width(1),
                ))?;
                from += dash + gap;
            }
            Ok(())
        }
    }
}

/// The oblique projection of a point: screen right and screen up (m), and its depth (larger
/// is farther from the viewer).
fn oblique(p: [f64; 3]) -> (f64, f64, f64) {
    let (az, el) = (AZIMUTH.to_radians(), ELEVATION.to_radians());
    let right = p[0] * az.cos() + p[1] * az.sin();
    let back = -p[0] * az.sin() + p[1] * az.cos();
    let up = p[2] * el.cos() + back * el.sin();
    (right, up, back * el.cos() - p[2] * el.sin())
}

/// Bounds of points in the plane.
fn bounds(points: impl Iterator<Item = (f64, f64)>) -> (Range<f64>, Range<f64>) {
    let (mut x, mut y) = (
        f64::INFINITY..f64::NEG_INFINITY,
        f64::INFINITY..f64::NEG_INFINITY,
    );
    for (px, py) in points {
        x = x.start.min(px)..x.end.max(px);
        y = y.start.min(py)..y.end.max(py);
    }
    if !(x.start.is_finite() && x.end.is_finite() && y.start.is_finite() && y.end.is_finite()) {
        return (0.0..1.0, 0.0..1.0);
    }
    let pad = |r: Range<f64>| {
        let p = 0.03 * (r.end - r.start).max(1e-9);
        r.start - p..r.end + p
    };
    (pad(x), pad(y))
}

/// The figure as an SVG document: the deformed structure of `eq` at `alpha`, displacements
/// multiplied by `amplification`.
pub fn to_svg(
    solver: &str,
    alpha: f64,
    amplification: f64,
    s: &Structure,
    eq: &Equilibrium,
) -> io::Result<String> {
    let deformed = deformed_nodes(s, eq, amplification);
    let scale = TensionScale::new(s, eq);
    let view_width = (WIDTH - PANEL_WIDTH) as f64;

    // The oblique view: pixels per metre from the width, at most MAX_VIEW_HEIGHT tall.
    let projected: Vec<(f64, f64, f64)> = deformed.iter().map(|&p| oblique(p)).collect();
    let at_rest: Vec<(f64, f64, f64)> = s.nodes.iter().map(|&p| oblique(p)).collect();
    let (ox, oy) = bounds(projected.iter().chain(&at_rest).map(|&(r, u, _)| (r, u)));
    let inner = view_width - 2.0 * MARGIN as f64;
    let oblique_scale = (inner / (ox.end - ox.start)).min(MAX_VIEW_HEIGHT / (oy.end - oy.start));
    let oblique_height = ((oy.end - oy.start) * oblique_scale).ceil() as u32 + CAPTION + MARGIN;

    // The top view: one scale on both axes (a general structure's undeformed members too).
    let at_rest_plan = s.nodes.iter().filter(|_| s.layout.is_none());
    let (tx, ty) = bounds(deformed.iter().chain(at_rest_plan).map(|p| (p[0], p[1])));
    let plot_width = view_width - (Y_LABELS + 2 * MARGIN) as f64;
    let top_scale = (plot_width / (tx.end - tx.start)).min(MAX_VIEW_HEIGHT / (ty.end - ty.start));
    let top_plot_width = ((tx.end - tx.start) * top_scale).ceil() as u32;
    let top_height =
        ((ty.end - ty.start) * top_scale).ceil() as u32 + X_LABELS + 2 * MARGIN + CAPTION;

    let height = (TITLE + oblique_height + top_height).max(560);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let title = format!(
            "Deformed structure at α = {} ({solver}), displacements × {}",
            alpha_text(alpha),
            tick_label(amplification)
        );
        let (title_row, body) = root.split_vertically(TITLE);
        title_row
            .draw_text(
                &title,
                &("sans-serif", 19).into_font().color(&BLACK),
                (MARGIN as i32, 8),
            )
            .map_err(plot_error)?;
        let (views, panel) = body.split_horizontally(WIDTH - PANEL_WIDTH);
        let (upper, lower) = views.split_vertically(oblique_height);
        let drawing = ObliqueDrawing {
            projected: &projected,
            at_rest: &at_rest,
            x0: ox.start,
            y1: oy.end,
            scale: oblique_scale,
        };
        draw_oblique(&upper, &drawing, s, eq, &scale).map_err(plot_error)?;
        let lower_width = top_plot_width + Y_LABELS + 2 * MARGIN;
        let (lower, _) = lower.split_horizontally(lower_width);
        draw_top(&lower, (tx, ty), &deformed, s, eq, &scale).map_err(plot_error)?;
        draw_panel(&panel, &scale, eq, s.layout.is_none()).map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

/// The oblique view's projected nodes and their mapping to pixels.
struct ObliqueDrawing<'a> {
    projected: &'a [(f64, f64, f64)],
    at_rest: &'a [(f64, f64, f64)],
    /// Left edge and top edge (screen up, m) of the drawing.
    x0: f64,
    y1: f64,
    /// Pixels per metre.
    scale: f64,
}

impl ObliqueDrawing<'_> {
    fn pixel(&self, (right, up, _): (f64, f64, f64)) -> (f64, f64) {
        (
            MARGIN as f64 + (right - self.x0) * self.scale,
            CAPTION as f64 + (self.y1 - up) * self.scale,
        )
    }
}

fn draw_oblique<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    drawing: &ObliqueDrawing,
    s: &Structure,
    eq: &Equilibrium,
    scale: &TensionScale,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let caption = ("sans-serif", TEXT_SIZE).into_font().color(&BLACK);
    let general = s.layout.is_none();
    area.draw_text(
        if general {
            "oblique view (undeformed structure in light grey, under the deformed one)"
        } else {
            "oblique view (undeformed outline in light grey)"
        },
        &caption,
        (MARGIN as i32, 4),
    )?;
    // A general structure's undeformed members, first: under the deformed ones.
    if general {
        for link in &s.links {
            let a = drawing.pixel(drawing.at_rest[link.a]);
            let b = drawing.pixel(drawing.at_rest[link.b]);
            draw_undeformed(area, a, b)?;
        }
    }
    // Far links first, so that near ones are drawn over them.
    let depth = |l: &Link| drawing.projected[l.a].2 + drawing.projected[l.b].2;
    let mut order: Vec<usize> = (0..s.links.len()).collect();
    order.sort_by(|&i, &j| depth(&s.links[j]).total_cmp(&depth(&s.links[i])));
    for i in order {
        let link = &s.links[i];
        let a = drawing.pixel(drawing.projected[link.a]);
        let b = drawing.pixel(drawing.projected[link.b]);
        draw_link(area, a, b, stroke(link, i, eq, scale))?;
    }
    // The undeformed outline of a grid: the lower corners around it, over the links.
    if let Some(layout) = &s.layout {
        let (nx, ny) = (layout.nx, layout.ny);
        let mut ring: Vec<usize> = (0..=nx).map(|i| layout.corner(i, 0)).collect();
        ring.extend((1..=ny).map(|j| layout.corner(nx, j)));
        ring.extend((0..nx).rev().map(|i| layout.corner(i, ny)));
        ring.extend((0..ny).rev().map(|j| layout.corner(0, j)));
        let outline: Vec<(i32, i32)> = ring
            .iter()
            .map(|&n| {
                let (x, y) = drawing.pixel(drawing.at_rest[n]);
                (x.round() as i32, y.round() as i32)
            })
            .collect();
        area.draw(&PathElement::new(outline, OUTLINE.stroke_width(1)))?;
    }
    for node in supports(s) {
        let (x, y) = drawing.pixel(drawing.projected[node]);
        let (x, y) = (x.round() as i32, y.round() as i32);
        area.draw(&Rectangle::new(
            [(x - 2, y - 2), (x + 2, y + 2)],
            BLACK.filled(),
        ))?;
    }
    Ok(())
}

/// Where link `i` is drawn in the top view: its deformed ends pulled toward its module's
/// deformed centre, by how much depending on its grid role.
fn top_ends(s: &Structure, deformed: &[[f64; 3]], i: usize) -> [(f64, f64); 2] {
    let link = &s.links[i];
    let shrink = match s.grid_role(i) {
        Some(GridRole::LowerCable) => 0.10,
        Some(GridRole::BracingCable) => 0.25,
        Some(GridRole::DiagonalCable) => 0.15,
        Some(GridRole::UpperCable) => 0.04,
        Some(GridRole::Bar) | None => 0.0,
    };
    let Some(layout) = &s.layout else {
        // General structures: members drawn end to end.
        return [link.a, link.b].map(|n| (deformed[n][0], deformed[n][1]));
    };
    let nx = layout.nx;
    let corners = &module_nodes(layout, link.module % nx, link.module / nx)[..4];
    let centre = |k: usize| corners.iter().map(|&c| deformed[c][k]).sum::<f64>() / 4.0;
    let (cx, cy) = (centre(0), centre(1));
    let pull = |node: usize| {
        let p = deformed[node];
        (p[0] + shrink * (cx - p[0]), p[1] + shrink * (cy - p[1]))
    };
    [pull(link.a), pull(link.b)]
}

fn draw_top<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (Range<f64>, Range<f64>),
    deformed: &[[f64; 3]],
    s: &Structure,
    eq: &Equilibrium,
    scale: &TensionScale,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let general = s.layout.is_none();
    let mut chart = ChartBuilder::on(area)
        .caption(
            if general {
                "top view (undeformed structure in light grey, under the deformed one)"
            } else {
                "top view (links drawn shrunk toward their module's centre)"
            },
            ("sans-serif", TEXT_SIZE),
        )
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .draw()?;
    let plot = chart.plotting_area();
    let to_pixel = |p: (f64, f64)| {
        let (px, py) = plot.map_coordinate(&p);
        let (ox, oy) = plot.get_base_pixel();
        ((px - ox) as f64, (py - oy) as f64)
    };
    // A general structure's undeformed members, first: under the deformed ones.
    if general {
        let plan = |n: usize| (s.nodes[n][0], s.nodes[n][1]);
        for link in &s.links {
            draw_undeformed(
                &plot.strip_coord_spec(),
                to_pixel(plan(link.a)),
                to_pixel(plan(link.b)),
            )?;
        }
    }
    // Bars first: in the top view the cables lie over them.
    let mut order: Vec<usize> = (0..s.links.len()).collect();
    order.sort_by_key(|&i| s.links[i].kind.is_cable());
    for i in order {
        let link = &s.links[i];
        let [a, b] = top_ends(s, deformed, i);
        draw_link(
            &plot.strip_coord_spec(),
            to_pixel(a),
            to_pixel(b),
            stroke(link, i, eq, scale),
        )?;
    }
    chart.draw_series(
        supports(s)
            .map(|n| (deformed[n][0], deformed[n][1]))
            .map(|p| EmptyElement::at(p) + Rectangle::new([(-2, -2), (2, 2)], BLACK.filled())),
    )?;
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scale: &TensionScale,
    eq: &Equilibrium,
    general: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let slack = eq.slack_count();
    let mut entries = vec![
        LegendEntry {
            label: "bar".into(),
            colour: BAR,
            dashed: false,
            marker: None,
        },
        LegendEntry {
            label: "cable (τ in colour)".into(),
            colour: scale.colour(scale.hi),
            dashed: false,
            marker: None,
        },
        LegendEntry {
            label: format!("slack cable ({slack})"),
            colour: SLACK,
            dashed: true,
            marker: None,
        },
    ];
    if general {
        entries.push(LegendEntry {
            label: "undeformed".into(),
            colour: UNDEFORMED,
            dashed: false,
            marker: None,
        });
    }
    let title = if general { "members" } else { "links" };
    let mut y = 30 + draw_line_legend(area, 30, title, &entries)?;
    let note = ("sans-serif", 13).into_font().color(&BLACK);
    let marker = if general {
        "■ support (held node)"
    } else {
        "■ clamped node"
    };
    area.draw_text(marker, &note, (8, y))?;
    y += 18;
    if scale.lo < 0.0 {
        area.draw_text("blue: compressed cable", &note, (8, y))?;
        y += 18;
    }
    y += 6;
    let (_, rest) = area.split_vertically(y);
    let (bar, _) = rest.split_vertically(380.min(rest.dim_in_pixel().1));
    draw_colour_bar(&bar, "cable τ (N)", (scale.lo, scale.hi), &|t| scale.at(t))?;
    Ok(())
}
