//! `modes/{solver}_alpha{α}.svg` (`output.modes` with `output.plots`): the lowest natural modes
//! of one answer drawn for a report, up to [`PANELS`] of them, each in the oblique view of the
//! deformed-structure figure ([`View::Oblique`]): the structure where the modes are taken in
//! light grey, the mode shape over it, scaled so that its largest nodal motion is [`AMPLITUDE`]
//! of the structure's size (bars heavier than cables), titled with its frequency and, when so,
//! "prestress-governed".

use super::annotate::{px, DrawResult};
use super::plot_error;
use super::views::{View, BAR, UNDEFORMED};
use crate::model::Model;
use crate::output::write_atomic;
use crate::results::modes::NaturalMode;
use crate::structure::{Structure, CLAMPED};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::path::Path;

/// Modes drawn at most.
pub const PANELS: usize = 4;
/// The largest nodal motion drawn, as a fraction of the structure's size (its bounding box's
/// diagonal).
pub const AMPLITUDE: f64 = 0.1;
/// A panel's size, px, two panels a row.
const PANEL: (u32, u32) = (400, 330);
/// The caption's row under the panels, px.
const CAPTION: u32 = 22;
/// Cables of the mode shape: blue, beside the near black bars.
const CABLE: RGBColor = RGBColor(31, 111, 180);

/// Writes the figure of `modes` at the nodes `at` (positions, one per node) into `path`.
pub fn write_modes_svg(
    path: &Path,
    model: &Model,
    at: &[[f64; 3]],
    modes: &[NaturalMode],
) -> io::Result<()> {
    let shown = modes.len().min(PANELS);
    let rows = shown.div_ceil(2).max(1) as u32;
    let (width, height) = (2 * PANEL.0, rows * PANEL.1 + CAPTION);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (body, caption) = root.split_vertically(rows * PANEL.1);
        let panels = body.split_evenly((rows as usize, 2));
        for (i, (mode, panel)) in modes.iter().zip(&panels).take(shown).enumerate() {
            draw_mode(panel, &model.structure, at, mode, i + 1).map_err(plot_error)?;
        }
        let text = format!(
            "grey: the structure where the modes are taken; shapes scaled to {}% of its size; \
             bars heavy, cables blue",
            AMPLITUDE * 100.0
        );
        let font = ("sans-serif", 15)
            .into_font()
            .color(&RGBColor(105, 105, 105));
        caption
            .draw_text(&text, &font, (8, 4))
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_atomic(path, |w| w.write_all(svg.as_bytes()))
}

/// Mode `number` on `area`: its title, the structure at `at` in grey, the shape over it.
fn draw_mode<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &Structure,
    at: &[[f64; 3]],
    mode: &NaturalMode,
    number: usize,
) -> DrawResult<DB> {
    let moved = mode_shape(s, at, mode);
    // Fit both drawings in the panel, below its title: (right, up) of the oblique view.
    let project = |p: [f64; 3]| {
        let (right, up, _) = View::Oblique.project(p);
        (right, up)
    };
    let (x0, x1, y0, y1) = at.iter().chain(&moved).map(|&p| project(p)).fold(
        (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
        |(a, b, c, d), (x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
    );
    let (margin, title) = (20.0, 34.0);
    let (w, h) = (PANEL.0 as f64, PANEL.1 as f64);
    let fit = ((w - 2.0 * margin) / (x1 - x0).max(1e-12))
        .min((h - title - 2.0 * margin) / (y1 - y0).max(1e-12));
    // Centred in the room left by the fit.
    let left = margin + 0.5 * (w - 2.0 * margin - (x1 - x0) * fit);
    let top = title + margin + 0.5 * (h - title - 2.0 * margin - (y1 - y0) * fit);
    let screen = |p: [f64; 3]| {
        let (x, y) = project(p);
        px((left + (x - x0) * fit, top + (y1 - y) * fit))
    };
    let governed = match mode.prestress_governed() {
        true => ", prestress-governed",
        false => "",
    };
    let font = ("sans-serif", 18).into_font().color(&BLACK);
    let style = font.pos(plotters::style::text_anchor::Pos::new(
        plotters::style::text_anchor::HPos::Center,
        plotters::style::text_anchor::VPos::Top,
    ));
    area.draw_text(
        &format!("mode {number}: {:.4} Hz{governed}", mode.frequency_hz),
        &style,
        ((w / 2.0) as i32, 8),
    )?;
    for (points, deformed) in [(at, false), (&moved[..], true)] {
        for l in &s.links {
            let style = match (deformed, l.kind.is_cable()) {
                (false, _) => UNDEFORMED.stroke_width(1),
                (true, true) => CABLE.stroke_width(2),
                (true, false) => BAR.stroke_width(3),
            };
            let line = vec![screen(points[l.a]), screen(points[l.b])];
            area.draw(&PathElement::new(line, style))?;
        }
    }
    Ok(())
}

/// The nodes at `at` moved along `mode`, scaled so that the largest motion is [`AMPLITUDE`] of
/// the structure's size (the diagonal of the box of `at`).
fn mode_shape(s: &Structure, at: &[[f64; 3]], mode: &NaturalMode) -> Vec<[f64; 3]> {
    let (lo, hi) = at
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            )
        });
    let size = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let motion = |node: usize| -> [f64; 3] {
        std::array::from_fn(|c| match s.dof_of[3 * node + c] {
            CLAMPED => 0.0,
            d => mode.shape[d],
        })
    };
    let largest = (0..at.len())
        .map(|n| motion(n).iter().map(|x| x * x).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    let scale = match largest > 0.0 {
        true => AMPLITUDE * size / largest,
        false => 0.0,
    };
    (0..at.len())
        .map(|n| {
            let m = motion(n);
            std::array::from_fn(|c| at[n][c] + scale * m[c])
        })
        .collect()
}
