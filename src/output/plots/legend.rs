//! What explains a figure beside it: a legend of line samples and a colour bar. Line samples
//! are drawn as rectangles, never as polylines, so that every `<polyline>` of stroke width
//! [`super::SERIES_STROKE_WIDTH`] in a chart is one of its series.

use super::marker::Marker;
use super::tick_label;
use plotters::coord::Shift;
use plotters::prelude::*;

/// One line of a legend.
pub struct LegendEntry {
    pub label: String,
    pub colour: RGBColor,
    /// Drawn as a dashed sample.
    pub dashed: bool,
    /// Drawn on the sample's middle.
    pub marker: Option<Marker>,
}

pub const TEXT_SIZE: u32 = 15;
const ROW: i32 = 22;
const SAMPLE: i32 = 28;

/// A titled column of line samples from the top of `area`. When there are more entries than
/// rows, every k-th one (and the last) is listed, with a note saying so. Returns the height used.
pub fn draw_line_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    top: i32,
    title: &str,
    entries: &[LegendEntry],
) -> Result<i32, DrawingAreaErrorKind<DB::ErrorType>> {
    let text = ("sans-serif", TEXT_SIZE).into_font().color(&BLACK);
    area.draw_text(title, &text, (8, top))?;
    let rows = ((area.dim_in_pixel().1 as i32 - top - 2 * ROW) / ROW).max(2) as usize;
    let step = entries.len().div_ceil(rows).max(1);
    let shown: Vec<&LegendEntry> = entries
        .iter()
        .enumerate()
        .filter(|(i, _)| i % step == 0 || *i + 1 == entries.len())
        .map(|(_, e)| e)
        .collect();
    let mut y = top + ROW + 4;
    let count = shown.len();
    for entry in shown {
        draw_sample(area, (8, y + 7), entry)?;
        area.draw_text(&entry.label, &text, (8 + SAMPLE + 8, y))?;
        y += ROW;
    }
    if step > 1 {
        let note = format!("({count} of {} shown)", entries.len());
        area.draw_text(&note, &("sans-serif", 13).into_font().color(&BLACK), (8, y))?;
        y += ROW;
    }
    Ok(y - top)
}

fn draw_sample<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    entry: &LegendEntry,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let style = entry.colour.filled();
    if entry.dashed {
        for k in 0..4 {
            let x0 = x + 8 * k;
            area.draw(&Rectangle::new([(x0, y - 1), (x0 + 5, y + 2)], style))?;
        }
    } else {
        area.draw(&Rectangle::new([(x, y - 1), (x + SAMPLE, y + 2)], style))?;
    }
    if let Some(marker) = entry.marker {
        marker.draw_at(area, (x + SAMPLE / 2, y), entry.colour)?;
    }
    Ok(())
}

/// A vertical colour bar of `map` over `[lo, hi]` under `caption`, its values on the right.
pub fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    (lo, hi): (f64, f64),
    map: &dyn Fn(f64) -> RGBColor,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    const BAR: u32 = 28;
    const LABELS: u32 = 80;
    const LEFT: u32 = 20;
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5, lo + 0.5)
    };
    let width = area.dim_in_pixel().0;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", TEXT_SIZE))
        .margin_top(8)
        .margin_bottom(24)
        .margin_left(LEFT)
        .margin_right(width.saturating_sub(LEFT + BAR + LABELS))
        .right_y_label_area_size(LABELS)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(6)
        .y_label_formatter(&|v| tick_label(*v))
        .label_style(("sans-serif", 13))
        .draw()?;
    const STEPS: usize = 100;
    let band = (hi - lo) / STEPS as f64;
    chart.draw_series((0..STEPS).map(|k| {
        let y0 = lo + k as f64 * band;
        let colour = map((k as f64 + 0.5) / STEPS as f64);
        Rectangle::new([(0.0, y0), (1.0, y0 + band)], colour.filled())
    }))?;
    Ok(())
}
