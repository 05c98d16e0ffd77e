//! `deformed_alpha{α}.svg` (paper Figure 8): the deformed structure at the figure's α (the
//! largest, or `output.figure_alpha`), displacements multiplied by an [`Amplification`]
//! (`output.amplification`, or automatic: the largest displacement drawn as 10 % of the
//! structure's size), which the title states and its subtitle explains. One SVG of three
//! views ([`View`]): the oblique view beside the legend and colour bar, the plan and the
//! elevation side by side under it, both with axes in m on one scale.
//!
//! Every link is drawn: struts heavier than cables, taut cables coloured by their tension τ
//! over the range of this α's tensions ([`TensionScale`]), slack cables thin dashed grey.
//! Supports are black triangles, loads green arrows; structures under
//! [`LABEL_LIMIT`](super::annotate::LABEL_LIMIT) members have their nodes and members labelled
//! (`n{id}`, `m{id}`, the ids of the case's tables).

use super::amplification::Amplification;
use super::annotate::{largest_load, nodal_loads, LABEL_LIMIT, LOAD};
use super::legend::{draw_colour_bar, draw_line_legend, LegendEntry, TEXT_SIZE};
use super::tension_scale::TensionScale;
use super::views::{draw_view, Scene, View, BAR, SLACK, UNDEFORMED};
use super::{alpha_text, plot_error, tick_label};
use crate::solvers::Equilibrium;
use crate::structure::Structure;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::ops::Range;

/// Width of the whole figure, px.
const WIDTH: u32 = 1100;
/// Width of the column of legend and colour bar right of the oblique view, px.
const PANEL_WIDTH: u32 = 210;
/// Height of the figure's title and subtitle, px.
const TITLE: u32 = 56;
/// Largest height of the oblique view's drawing, px.
const MAX_OBLIQUE_HEIGHT: f64 = 520.0;
/// Largest height of the plan's and the elevation's drawings, px.
const MAX_VIEW_HEIGHT: f64 = 420.0;
/// Least height of the oblique view's row: the legend and the colour bar beside it.
const PANEL_HEIGHT: u32 = 540;
const Y_LABELS: u32 = 60;
const X_LABELS: u32 = 44;
const MARGIN: u32 = 12;
/// Caption height of a view, px.
const CAPTION: u32 = 26;

/// The drawn position of every node: its position plus the amplified displacement.
fn deformed_nodes(s: &Structure, eq: &Equilibrium, amplification: f64) -> Vec<[f64; 3]> {
    let full = s.full_displacements(&eq.displacements);
    s.nodes
        .iter()
        .zip(full.chunks(3))
        .map(|(p, u)| std::array::from_fn(|k| p[k] + amplification * u[k]))
        .collect()
}

/// A view's bounds (m) and pixels per metre.
struct Placed {
    x: Range<f64>,
    y: Range<f64>,
    scale: f64,
}

impl Placed {
    fn width(&self) -> f64 {
        (self.x.end - self.x.start) * self.scale
    }

    fn height(&self) -> f64 {
        (self.y.end - self.y.start) * self.scale
    }
}

/// Where the views go: the oblique one on its own scale, the plan and the elevation on one.
struct Layout {
    oblique: Placed,
    plan: Placed,
    elevation: Placed,
}

impl Layout {
    fn of(scene: &Scene) -> Layout {
        let (x, y) = scene.bounds(View::Oblique);
        let inner = (WIDTH - PANEL_WIDTH - 2 * MARGIN) as f64;
        let scale = (inner / (x.end - x.start)).min(MAX_OBLIQUE_HEIGHT / (y.end - y.start));
        let oblique = Placed { x, y, scale };
        let (plan_x, plan_y) = scene.bounds(View::Plan);
        let (front_x, front_z) = scene.bounds(View::Elevation);
        let plot_width = (WIDTH / 2 - Y_LABELS - 2 * MARGIN) as f64;
        let span = |r: &Range<f64>| r.end - r.start;
        let scale = (plot_width / span(&plan_x))
            .min(plot_width / span(&front_x))
            .min(MAX_VIEW_HEIGHT / span(&plan_y))
            .min(MAX_VIEW_HEIGHT / span(&front_z));
        Layout {
            oblique,
            plan: Placed {
                x: plan_x,
                y: plan_y,
                scale,
            },
            elevation: Placed {
                x: front_x,
                y: front_z,
                scale,
            },
        }
    }

    fn oblique_row(&self) -> u32 {
        (self.oblique.height().ceil() as u32 + CAPTION + 2 * MARGIN).max(PANEL_HEIGHT)
    }

    /// The size of the plan's or the elevation's area, axes included.
    fn axes_view(placed: &Placed) -> (u32, u32) {
        (
            placed.width().ceil() as u32 + Y_LABELS + 2 * MARGIN,
            placed.height().ceil() as u32 + X_LABELS + 2 * MARGIN + CAPTION,
        )
    }

    fn lower_row(&self) -> u32 {
        Layout::axes_view(&self.plan)
            .1
            .max(Layout::axes_view(&self.elevation).1)
    }
}

/// The figure as an SVG document: the deformed structure of `eq` at `alpha`, displacements
/// multiplied by `amplification` when given, else by the automatic one.
pub fn to_svg(
    solver: &str,
    alpha: f64,
    amplification: Option<f64>,
    s: &Structure,
    eq: &Equilibrium,
) -> io::Result<String> {
    let amplification = Amplification::of(amplification, s, eq);
    let scene = Scene {
        s,
        eq,
        deformed: deformed_nodes(s, eq, amplification.factor),
        scale: TensionScale::new(s, eq),
        loads: nodal_loads(s, alpha),
        labelled: s.links.len() < LABEL_LIMIT,
    };
    let layout = Layout::of(&scene);
    let height = TITLE + layout.oblique_row() + layout.lower_row();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (title_row, body) = root.split_vertically(TITLE);
        let title = format!(
            "Deformed structure at α = {} ({solver}), displacements × {}",
            alpha_text(alpha),
            tick_label(amplification.factor)
        );
        draw_title(&title_row, &title, &amplification.explanation()).map_err(plot_error)?;
        let (upper, lower) = body.split_vertically(layout.oblique_row());
        let (oblique, panel) = upper.split_horizontally(WIDTH - PANEL_WIDTH);
        draw_oblique(&oblique, &scene, &layout.oblique).map_err(plot_error)?;
        draw_panel(&panel, &scene, alpha).map_err(plot_error)?;
        let (left, right) = lower.split_horizontally(WIDTH / 2);
        for (area, view, placed) in [
            (left, View::Plan, &layout.plan),
            (right, View::Elevation, &layout.elevation),
        ] {
            // Exactly the view's size: a chart fills its area, and both axes keep one scale.
            let (width, height) = Layout::axes_view(placed);
            let (area, _) = area.split_horizontally(width);
            let (area, _) = area.split_vertically(height);
            draw_axes_view(&area, &scene, view, placed).map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

fn draw_title<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: &str,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = |size: u32| ("sans-serif", size).into_font().color(&BLACK);
    area.draw_text(title, &font(19), (MARGIN as i32, 8))?;
    area.draw_text(subtitle, &font(14), (MARGIN as i32, 33))
}

fn draw_oblique<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scene: &Scene,
    placed: &Placed,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let caption = ("sans-serif", TEXT_SIZE).into_font().color(&BLACK);
    area.draw_text(
        View::Oblique.caption(scene.general()),
        &caption,
        (MARGIN as i32, 4),
    )?;
    let to_pixel = |(right, up): (f64, f64)| {
        (
            MARGIN as f64 + (right - placed.x.start) * placed.scale,
            (CAPTION + MARGIN) as f64 + (placed.y.end - up) * placed.scale,
        )
    };
    draw_view(area, scene, View::Oblique, &to_pixel)
}

/// The plan or the elevation, with axes in m.
fn draw_axes_view<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scene: &Scene,
    view: View,
    placed: &Placed,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let mut chart = ChartBuilder::on(area)
        .caption(view.caption(scene.general()), ("sans-serif", TEXT_SIZE))
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(placed.x.clone(), placed.y.clone())?;
    let (x_desc, y_desc) = view.axis_descriptions();
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(6)
        .y_labels(6)
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
    draw_view(&plot.strip_coord_spec(), scene, view, &to_pixel)
}

/// A force with three significant digits: `300 N`, `1.04 kN`.
fn force_text(newtons: f64) -> String {
    if newtons.abs() >= 1e3 {
        format!("{} kN", tick_label((newtons / 1e3 * 100.0).round() / 100.0))
    } else {
        format!("{} N", tick_label(newtons.round()))
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scene: &Scene,
    alpha: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let entry = |label: String, colour: RGBColor, dashed: bool| LegendEntry {
        label,
        colour,
        dashed,
        marker: None,
    };
    let general = scene.general();
    let scale = &scene.scale;
    let mut entries = vec![
        entry("strut (bar)".into(), BAR, false),
        entry("cable (τ in colour)".into(), scale.colour(scale.hi), false),
        entry(
            format!("slack cable ({})", scene.eq.slack_count()),
            SLACK,
            true,
        ),
    ];
    if general {
        entries.push(entry("undeformed".into(), UNDEFORMED, false));
    }
    if !scene.loads.is_empty() {
        let largest = force_text(largest_load(&scene.loads));
        entries.push(entry(format!("load (max {largest})"), LOAD, false));
    }
    let title = if general { "members" } else { "links" };
    let mut y = 30 + draw_line_legend(area, 30, title, &entries)?;
    let note = ("sans-serif", 13).into_font().color(&BLACK);
    let mut notes = vec![if general {
        "▲ support (held node)"
    } else {
        "▲ clamped node"
    }];
    if scene.labelled {
        notes.push("n3: node 3, m3: member 3");
    }
    if scale.has_compression() {
        notes.push("blue: compressed cable");
    }
    for text in notes {
        area.draw_text(text, &note, (8, y))?;
        y += 18;
    }
    y += 6;
    let (_, rest) = area.split_vertically(y);
    let (bar, rest) = rest.split_vertically(330.min(rest.dim_in_pixel().1));
    draw_colour_bar(&bar, "cable τ (N)", (scale.lo, scale.hi), &|t| scale.at(t))?;
    let range = format!("taut cables' range at α = {}", alpha_text(alpha));
    rest.draw_text(&range, &note, (8, 0))?;
    Ok(())
}
