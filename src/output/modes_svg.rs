//! `modes/{solver}_alpha{α}.svg` (`output.modes` with `output.plots`): the lowest natural modes
//! of one answer drawn for a report, up to [`PANELS`] of them, one oblique view each (seen from
//! the front left, above): the structure where the modes are taken in light grey, the mode
//! shape over it, scaled so that its largest nodal motion is [`AMPLITUDE`] of the structure's
//! size (bars heavier than cables), titled with its frequency and, when so, "prestress-governed".

use super::write_atomic;
use crate::model::Model;
use crate::results::modes::NaturalMode;
use crate::structure::CLAMPED;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

/// Modes drawn at most.
pub const PANELS: usize = 4;
/// The largest nodal motion drawn, as a fraction of the structure's size (its bounding box's
/// diagonal).
pub const AMPLITUDE: f64 = 0.1;
/// A panel's size, px, two panels a row.
const PANEL: (f64, f64) = (400.0, 330.0);
/// Azimuth and elevation of the view, radians (−30°, 35°).
const VIEW: (f64, f64) = (-0.5235987755982988, 0.6108652381980153);

/// Screen coordinates (right, up) of a point in the oblique view.
fn oblique(p: [f64; 3]) -> (f64, f64) {
    let (sa, ca) = VIEW.0.sin_cos();
    let (se, ce) = VIEW.1.sin_cos();
    let depth = -p[0] * sa + p[1] * ca;
    (p[0] * ca + p[1] * sa, p[2] * ce + depth * se)
}

/// Writes the figure of `modes` at the nodes `at` (positions, one per node) into `path`.
pub fn write_modes_svg(
    path: &Path,
    model: &Model,
    at: &[[f64; 3]],
    modes: &[NaturalMode],
) -> io::Result<()> {
    let s = &model.structure;
    let (lo, hi) = at
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            )
        });
    let size = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let shown = modes.len().min(PANELS);
    let rows = shown.div_ceil(2).max(1);
    let (width, height) = (2.0 * PANEL.0, rows as f64 * PANEL.1);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    for (i, mode) in modes.iter().take(shown).enumerate() {
        let motion = |node: usize| -> [f64; 3] {
            std::array::from_fn(|c| match s.dof_of[3 * node + c] {
                CLAMPED => 0.0,
                d => mode.shape[d],
            })
        };
        let largest = (0..at.len())
            .map(|n| motion(n).iter().map(|x| x * x).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        let scale = if largest > 0.0 {
            AMPLITUDE * size / largest
        } else {
            0.0
        };
        let moved: Vec<[f64; 3]> = (0..at.len())
            .map(|n| {
                let m = motion(n);
                std::array::from_fn(|c| at[n][c] + scale * m[c])
            })
            .collect();
        // Fit both drawings in the panel, below its title.
        let projected: Vec<(f64, f64)> = at.iter().chain(&moved).map(|&p| oblique(p)).collect();
        let (x0, x1, y0, y1) = projected.iter().fold(
            (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
            |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
        );
        let (left, top) = ((i % 2) as f64 * PANEL.0, (i / 2) as f64 * PANEL.1);
        let (margin, title) = (20.0, 34.0);
        let fit = ((PANEL.0 - 2.0 * margin) / (x1 - x0).max(1e-12))
            .min((PANEL.1 - title - 2.0 * margin) / (y1 - y0).max(1e-12));
        let screen = |p: [f64; 3]| {
            let (x, y) = oblique(p);
            (
                left + margin + (x - x0) * fit,
                top + title + margin + (y1 - y) * fit,
            )
        };
        let governed = if mode.prestress_governed() {
            ", prestress-governed"
        } else {
            ""
        };
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" font-family="sans-serif" font-size="15" text-anchor="middle">mode {}: {:.4} Hz{governed}</text>"#,
            left + PANEL.0 / 2.0,
            top + 22.0,
            i + 1,
            mode.frequency_hz
        );
        for (points, deformed) in [(at, false), (&moved[..], true)] {
            for l in &s.links {
                let ((ax, ay), (bx, by)) = (screen(points[l.a]), screen(points[l.b]));
                let (colour, stroke) = match (deformed, l.kind.is_cable()) {
                    (false, _) => ("#c8c8c8", 1.0),
                    (true, true) => ("#1f6fb4", 1.5),
                    (true, false) => ("#202020", 3.0),
                };
                let _ = writeln!(
                    svg,
                    r#"<line x1="{ax:.2}" y1="{ay:.2}" x2="{bx:.2}" y2="{by:.2}" stroke="{colour}" stroke-width="{stroke}"/>"#
                );
            }
        }
    }
    let _ = writeln!(
        svg,
        r#"<text x="8" y="{}" font-family="sans-serif" font-size="12" fill="dimgray">grey: the structure where the modes are taken; shapes scaled to {}% of its size; bars heavy, cables blue</text>"#,
        height - 6.0,
        AMPLITUDE * 100.0
    );
    svg.push_str("</svg>\n");
    write_atomic(path, |w| w.write_all(svg.as_bytes()))
}
