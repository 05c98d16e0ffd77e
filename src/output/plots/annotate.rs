//! What the deformed-structure figure marks on each view besides the members: supports (a
//! filled black triangle under each held node), on general structures load arrows (green, their
//! length proportional to the force, the largest [`ARROW`] px; a load along the line of sight a
//! green ring) and, on
//! structures under [`LABEL_LIMIT`] members, node labels `n{id}` in every view and member labels
//! `m{id}` in the oblique one (in all three they hid the tower's members), with the ids of the
//! case's tables.

use crate::structure::{Structure, CLAMPED};
use plotters::coord::Shift;
use plotters::prelude::*;

pub type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// A pixel position, rounded.
pub fn px(p: (f64, f64)) -> (i32, i32) {
    (p.0.round() as i32, p.1.round() as i32)
}

/// Structures with fewer members have their nodes and members labelled.
pub const LABEL_LIMIT: usize = 100;
/// Load arrows are drawn when at most this many nodes are loaded.
pub const MAX_LOAD_ARROWS: usize = 100;
/// Length of the largest load's arrow, px.
const ARROW: f64 = 50.0;
/// Load arrows and rings.
pub const LOAD: RGBColor = RGBColor(0, 140, 70);
const LOAD_WIDTH: u32 = 3;
pub const NODE_LABEL: RGBColor = RGBColor(0, 50, 130);
pub const MEMBER_LABEL: RGBColor = RGBColor(120, 40, 120);

/// The load on every loaded node at `alpha` (`α F`, held components' share included) of a
/// general structure with at most [`MAX_LOAD_ARROWS`] loaded nodes; none otherwise (a grid's
/// load pattern, on every upper node, would hide the grid under its arrows).
pub fn nodal_loads(s: &Structure, alpha: f64) -> Vec<(usize, [f64; 3])> {
    if s.layout.is_some() {
        return Vec::new();
    }
    let mut force = vec![[0.0; 3]; s.n_nodes()];
    for (g, &d) in s.dof_of.iter().enumerate() {
        if d != CLAMPED {
            force[g / 3][g % 3] += alpha * s.unit_load[d];
        }
    }
    for &(g, f) in &s.held_load {
        force[g / 3][g % 3] += alpha * f;
    }
    let loads: Vec<(usize, [f64; 3])> = force
        .into_iter()
        .enumerate()
        .filter(|(_, f)| f.iter().any(|&c| c != 0.0))
        .collect();
    if loads.len() > MAX_LOAD_ARROWS {
        return Vec::new();
    }
    loads
}

/// The largest load's magnitude, N (0 without any).
pub fn largest_load(loads: &[(usize, [f64; 3])]) -> f64 {
    loads.iter().map(|(_, f)| norm(*f)).fold(0.0, f64::max)
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// A filled black triangle under each of `nodes`, its apex on the node.
pub fn draw_supports<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    nodes: impl Iterator<Item = usize>,
    node_at: &dyn Fn(usize) -> (f64, f64),
) -> DrawResult<DB> {
    for node in nodes {
        let (x, y) = px(node_at(node));
        area.draw(&Polygon::new(
            vec![(x, y), (x - 6, y + 10), (x + 6, y + 10)],
            BLACK.filled(),
        ))?;
    }
    Ok(())
}

/// An arrow on each loaded node, its head on the node; `project` gives a force's (right, up)
/// on the view.
pub fn draw_loads<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    loads: &[(usize, [f64; 3])],
    node_at: &dyn Fn(usize) -> (f64, f64),
    project: &dyn Fn([f64; 3]) -> (f64, f64),
) -> DrawResult<DB> {
    let largest = largest_load(loads);
    if largest == 0.0 {
        return Ok(());
    }
    let style = LOAD.stroke_width(LOAD_WIDTH);
    for &(node, force) in loads {
        let (x, y) = node_at(node);
        let (right, up) = project(force);
        // Pixels: screen y points down.
        let (dx, dy) = (ARROW * right / largest, -ARROW * up / largest);
        let length = (dx * dx + dy * dy).sqrt();
        if length < 0.15 * ARROW {
            // Along the line of sight: a ring around the node.
            area.draw(&Circle::new(px((x, y)), 7, style))?;
            continue;
        }
        let (ux, uy) = (dx / length, dy / length);
        // The head stops 3 px short of the node, off the members' ends.
        let tip = (x - 3.0 * ux, y - 3.0 * uy);
        let tail = (tip.0 - dx, tip.1 - dy);
        area.draw(&PathElement::new(vec![px(tail), px(tip)], style))?;
        let barb = |turn: f64| {
            let (c, s) = (turn.cos(), turn.sin());
            let (bx, by) = (-(ux * c - uy * s), -(ux * s + uy * c));
            px((tip.0 + 9.0 * bx, tip.1 + 9.0 * by))
        };
        let head = vec![barb(0.45), px(tip), barb(-0.45)];
        area.draw(&PathElement::new(head, style))?;
    }
    Ok(())
}

/// `n{id}` beside each node, and `m{id}` at each member's middle when `members`.
pub fn draw_labels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &Structure,
    node_at: &dyn Fn(usize) -> (f64, f64),
    members: bool,
) -> DrawResult<DB> {
    let font = ("sans-serif", 11).into_font().color(&MEMBER_LABEL);
    for link in s.links.iter().filter(|_| members) {
        let ((ax, ay), (bx, by)) = (node_at(link.a), node_at(link.b));
        let middle = px((0.5 * (ax + bx) + 3.0, 0.5 * (ay + by) - 12.0));
        area.draw_text(&format!("m{}", link.id), &font, middle)?;
    }
    let nodes = ("sans-serif", 12).into_font().color(&NODE_LABEL);
    for (node, id) in s.node_ids.iter().enumerate() {
        let (x, y) = px(node_at(node));
        area.draw_text(&format!("n{id}"), &nodes, (x + 5, y - 15))?;
    }
    Ok(())
}
