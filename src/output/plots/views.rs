//! The three views of `deformed_alpha{α}.svg` and how one is drawn: an oblique view (a fixed
//! axonometric projection from the front left and above), a plan (x, y) and an elevation (x, z,
//! seen from the front, along +y). Each projects a node to screen right, screen up (m) and a
//! depth; members are drawn far ones first, so that near ones lie over them (in the plan,
//! bars first, cables over them).
//!
//! Struts are drawn heavier than cables (near black, 4 px, 3 in a grid, against 2); cables are coloured by
//! their tension on the figure's [`TensionScale`]; slack cables are thin dashed grey lines.
//! A grid's plan draws each link shrunk toward its module's centre (lower cables by 10 %,
//! bracing cables by 25 %) so that none hides another; a general structure's views draw every
//! member undeformed in light grey under the deformed structure.

use super::annotate::{draw_labels, draw_loads, draw_supports, px, DrawResult};
use super::tension_scale::TensionScale;
use crate::solvers::Equilibrium;
use crate::structure::{module_nodes, GridRole, Link, Structure};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;

/// Azimuth and elevation of the oblique view, degrees: seen from the front left, above.
const AZIMUTH: f64 = -30.0;
const ELEVATION: f64 = 35.0;

/// Struts: near black and heavier than the cables (whose colours carry the tensions); 3 px in
/// a grid, where at 4 its dense struts hid the cables.
pub const BAR: RGBColor = RGBColor(25, 25, 25);
const BAR_WIDTH: u32 = 4;
const GRID_BAR_WIDTH: u32 = 3;
pub const CABLE_WIDTH: u32 = 2;
/// Slack cables: thin dashed grey.
pub const SLACK: RGBColor = RGBColor(120, 120, 120);
const OUTLINE: RGBColor = RGBColor(150, 150, 150);
/// A general structure's undeformed members, under the deformed ones: light grey, and two
/// pixels wide so that it shows beside them.
pub const UNDEFORMED: RGBColor = RGBColor(170, 170, 170);
const UNDEFORMED_WIDTH: u32 = 2;

/// Maps a view's (screen right, screen up) in m to pixels of the area drawn on.
pub type ToPixel<'a> = &'a dyn Fn((f64, f64)) -> (f64, f64);

/// One of the figure's three views.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    Oblique,
    Plan,
    Elevation,
}

impl View {
    /// Screen right, screen up (m) and depth (larger is farther from the viewer) of `p`.
    pub fn project(self, p: [f64; 3]) -> (f64, f64, f64) {
        match self {
            View::Oblique => {
                let (az, el) = (AZIMUTH.to_radians(), ELEVATION.to_radians());
                let right = p[0] * az.cos() + p[1] * az.sin();
                let back = -p[0] * az.sin() + p[1] * az.cos();
                let up = p[2] * el.cos() + back * el.sin();
                (right, up, back * el.cos() - p[2] * el.sin())
            }
            // Seen from above: the highest node is the nearest.
            View::Plan => (p[0], p[1], -p[2]),
            // Seen from the front, looking along +y.
            View::Elevation => (p[0], p[2], p[1]),
        }
    }

    /// The view's caption.
    pub fn caption(self, general: bool) -> &'static str {
        match (self, general) {
            (View::Oblique, true) => {
                "oblique view (undeformed structure in light grey, under the deformed one)"
            }
            (View::Oblique, false) => "oblique view (undeformed outline in light grey)",
            (View::Plan, true) => "plan, top view (undeformed in light grey)",
            (View::Plan, false) => {
                "plan, top view (links drawn shrunk toward their module's centre)"
            }
            (View::Elevation, true) => "elevation, front view (undeformed in light grey)",
            (View::Elevation, false) => "elevation, front view",
        }
    }

    /// The horizontal and vertical axes' descriptions of the plan and the elevation.
    pub fn axis_descriptions(self) -> (&'static str, &'static str) {
        match self {
            View::Elevation => ("x (m)", "z (m)"),
            View::Plan | View::Oblique => ("x (m)", "y (m)"),
        }
    }
}

/// What every view draws: the structure, its answer at the figure's α drawn amplified, the
/// cables' colour scale, the loads and whether the nodes and members are labelled.
pub struct Scene<'a> {
    pub s: &'a Structure,
    pub eq: &'a Equilibrium,
    /// Every node's position plus its amplified displacement.
    pub deformed: Vec<[f64; 3]>,
    pub scale: TensionScale,
    /// (node, force at α) of every loaded node the figure draws an arrow on.
    pub loads: Vec<(usize, [f64; 3])>,
    /// Node and member labels are drawn.
    pub labelled: bool,
}

impl Scene<'_> {
    pub fn general(&self) -> bool {
        self.s.layout.is_none()
    }

    /// The (right, up) bounds of the view of the deformed structure, and of the undeformed one
    /// where it is drawn (a general structure's views, a grid's oblique outline).
    pub fn bounds(&self, view: View) -> (Range<f64>, Range<f64>) {
        let at_rest = self
            .s
            .nodes
            .iter()
            .filter(|_| self.general() || view == View::Oblique);
        bounds(
            self.deformed
                .iter()
                .chain(at_rest)
                .map(|&p| view.project(p))
                .map(|(r, u, _)| (r, u)),
        )
    }
}

/// The nodes marked as supports: a grid's clamped nodes; every node with a held component of
/// a general structure.
pub fn supports(s: &Structure) -> impl Iterator<Item = usize> + '_ {
    (0..s.n_nodes()).filter(move |&n| {
        if s.layout.is_some() {
            s.clamped[n]
        } else {
            s.held_components(n).iter().any(|&h| h)
        }
    })
}

/// Draw `view` of `scene` on `area`, `to_pixel` mapping its (right, up) to the area's pixels.
pub fn draw_view<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scene: &Scene,
    view: View,
    to_pixel: ToPixel,
) -> DrawResult<DB> {
    let s = scene.s;
    let at = |p: [f64; 3]| {
        let (r, u, _) = view.project(p);
        to_pixel((r, u))
    };
    // A general structure's undeformed members, first: under the deformed ones.
    if scene.general() {
        for link in &s.links {
            let line = vec![px(at(s.nodes[link.a])), px(at(s.nodes[link.b]))];
            area.draw(&PathElement::new(
                line,
                UNDEFORMED.stroke_width(UNDEFORMED_WIDTH),
            ))?;
        }
    }
    for i in drawing_order(scene, view) {
        let [a, b] = match view {
            View::Plan => plan_ends(s, &scene.deformed, i).map(to_pixel),
            _ => [s.links[i].a, s.links[i].b].map(|n| at(scene.deformed[n])),
        };
        draw_link(area, a, b, stroke(&s.links[i], i, scene))?;
    }
    if view == View::Oblique {
        draw_grid_outline(area, s, &at)?;
    }
    let node_at = |n: usize| at(scene.deformed[n]);
    draw_supports(area, supports(s), &node_at)?;
    let project = |v: [f64; 3]| {
        let (r, u, _) = view.project(v);
        (r, u)
    };
    draw_loads(area, &scene.loads, &node_at, &project)?;
    if scene.labelled {
        draw_labels(area, s, &node_at, view == View::Oblique)?;
    }
    Ok(())
}

/// The links in the order drawn: far first (by their ends' depth); in the plan, bars first.
fn drawing_order(scene: &Scene, view: View) -> Vec<usize> {
    let links = &scene.s.links;
    let mut order: Vec<usize> = (0..links.len()).collect();
    if view == View::Plan {
        order.sort_by_key(|&i| links[i].kind.is_cable());
        return order;
    }
    let depth =
        |l: &Link| view.project(scene.deformed[l.a]).2 + view.project(scene.deformed[l.b]).2;
    order.sort_by(|&i, &j| depth(&links[j]).total_cmp(&depth(&links[i])));
    order
}

/// The undeformed outline of a grid's lower corners, over its links.
fn draw_grid_outline<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &Structure,
    at: &dyn Fn([f64; 3]) -> (f64, f64),
) -> DrawResult<DB> {
    let Some(layout) = &s.layout else {
        return Ok(());
    };
    let (nx, ny) = (layout.nx, layout.ny);
    let mut ring: Vec<usize> = (0..=nx).map(|i| layout.corner(i, 0)).collect();
    ring.extend((1..=ny).map(|j| layout.corner(nx, j)));
    ring.extend((0..nx).rev().map(|i| layout.corner(i, ny)));
    ring.extend((0..ny).rev().map(|j| layout.corner(0, j)));
    let outline: Vec<(i32, i32)> = ring.iter().map(|&n| px(at(s.nodes[n]))).collect();
    area.draw(&PathElement::new(outline, OUTLINE.stroke_width(1)))
}

/// Where link `i` is drawn in the plan: its deformed ends, pulled toward its module's deformed
/// centre in a grid, by how much depending on its grid role.
fn plan_ends(s: &Structure, deformed: &[[f64; 3]], i: usize) -> [(f64, f64); 2] {
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

/// How one link is drawn.
#[derive(Clone, Copy)]
enum Stroke {
    Bar(u32),
    Cable(RGBColor),
    Slack,
}

fn stroke(link: &Link, index: usize, scene: &Scene) -> Stroke {
    if !link.kind.is_cable() {
        Stroke::Bar(if scene.general() {
            BAR_WIDTH
        } else {
            GRID_BAR_WIDTH
        })
    } else if scene.eq.slack[index] {
        Stroke::Slack
    } else {
        Stroke::Cable(scene.scale.colour(scene.eq.tensions[index]))
    }
}

/// Draw the segment `a`–`b` (pixels) in `stroke`'s style: one `<polyline>` per link, dashes
/// of a slack cable one each.
fn draw_link<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    a: (f64, f64),
    b: (f64, f64),
    stroke: Stroke,
) -> DrawResult<DB> {
    match stroke {
        Stroke::Bar(width) => area.draw(&PathElement::new(
            vec![px(a), px(b)],
            BAR.stroke_width(width),
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

/// Bounds of points in the plane, padded by 3 %.
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
    // A flat view (a planar grid's elevation) keeps a span of 5 % of the other axis.
    let least = 0.05 * (x.end - x.start).max(y.end - y.start).max(1e-9);
    let pad = |r: Range<f64>| {
        let extra = (least - (r.end - r.start)).max(0.0) / 2.0;
        let p = 0.03 * (r.end - r.start).max(least);
        r.start - extra - p..r.end + extra + p
    };
    (pad(x), pad(y))
}
