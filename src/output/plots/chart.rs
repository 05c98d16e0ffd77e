//! The line chart every curve figure is: series of (x, y) points on a linear x axis and a
//! linear or logarithmic y axis, axis labels with units, a legend beside the plot.

use super::legend::{draw_line_legend, LegendEntry};
use super::marker::Marker;
use super::{log_tick_label, plot_error, tick_label, SERIES_STROKE_WIDTH};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::ops::Range;

const SIZE: (u32, u32) = (960, 600);
const LEGEND_WIDTH: u32 = 190;
/// A series is drawn with at most this many points (the plot is ~700 px wide).
const MAX_POINTS: usize = 1400;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    Linear,
    /// Logarithmic: points with y ≤ 0 are left out.
    Log,
}

pub struct Series {
    pub label: String,
    pub colour: RGBColor,
    pub points: Vec<(f64, f64)>,
}

pub struct LineChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub y_scale: Scale,
    /// Heading of the legend (what the series differ by).
    pub legend_title: String,
    /// Mark every point, with a different marker per series (sparse data, series that may
    /// coincide).
    pub markers: bool,
    pub series: Vec<Series>,
}

impl LineChart {
    /// The chart as an SVG document. Non-finite points (and y ≤ 0 on a log axis) are left out.
    pub fn to_svg(&self) -> io::Result<String> {
        let series: Vec<Series> = self.series.iter().map(|s| self.drawable(s)).collect();
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
            root.fill(&WHITE).map_err(plot_error)?;
            let (plot, legend) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
            let x = x_range(&series, self.markers);
            let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
            match self.y_scale {
                Scale::Linear => self.draw(&plot, &series, x, linear_range(ys), tick_label),
                Scale::Log => {
                    self.draw(&plot, &series, x, log_range(ys).log_scale(), log_tick_label)
                }
            }
            .map_err(plot_error)?;
            let entries: Vec<LegendEntry> = series
                .iter()
                .enumerate()
                .map(|(i, s)| LegendEntry {
                    label: s.label.clone(),
                    colour: s.colour,
                    dashed: false,
                    marker: self.markers.then(|| Marker::nth(i)),
                })
                .collect();
            draw_line_legend(&legend, 60, &self.legend_title, &entries).map_err(plot_error)?;
            root.present().map_err(plot_error)?;
        }
        Ok(svg)
    }

    fn drawable(&self, s: &Series) -> Series {
        let keep = |&(x, y): &(f64, f64)| {
            x.is_finite() && y.is_finite() && (self.y_scale == Scale::Linear || y > 0.0)
        };
        let points: Vec<(f64, f64)> = s.points.iter().copied().filter(keep).collect();
        Series {
            label: s.label.clone(),
            colour: s.colour,
            points: thin(&points, MAX_POINTS),
        }
    }

    fn draw<DB, Y>(
        &self,
        area: &DrawingArea<DB, Shift>,
        series: &[Series],
        x: Range<f64>,
        y: Y,
        y_tick: fn(f64) -> String,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
    where
        DB: DrawingBackend,
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", 21))
            .margin(14)
            .x_label_area_size(55)
            .y_label_area_size(85)
            .build_cartesian_2d(x, y)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_labels(10)
            .y_labels(10)
            .x_label_formatter(&|v| tick_label(*v))
            .y_label_formatter(&|v| y_tick(*v))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()?;
        for (i, s) in series.iter().enumerate() {
            let style = s.colour.stroke_width(SERIES_STROKE_WIDTH);
            chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
            if self.markers {
                Marker::nth(i).draw_on_chart(&mut chart, &s.points, s.colour)?;
            }
        }
        Ok(())
    }
}

/// The span of the x values (0..1 without any), 2 % wider on each side with markers so that
/// the end markers are whole.
fn x_range(series: &[Series], markers: bool) -> Range<f64> {
    let (lo, hi) = min_max(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let pad = if markers { 0.02 } else { 0.0 };
    match (lo, hi) {
        (Some(lo), Some(hi)) if hi > lo => lo - pad * (hi - lo)..hi + pad * (hi - lo),
        (Some(lo), _) => lo - 0.5..lo + 0.5,
        _ => 0.0..1.0,
    }
}

/// From 0 (or below the smallest value when negative) to 5 % above the largest value.
fn linear_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = min_max(values);
    let (lo, hi) = (lo.unwrap_or(0.0), hi.unwrap_or(1.0));
    let span = hi - lo.min(0.0);
    let pad = if span > 0.0 {
        0.05 * span
    } else {
        hi.abs().max(1.0)
    };
    let lo = if lo >= 0.0 { 0.0 } else { lo - pad };
    lo..hi + pad
}

/// Whole decades around the positive values, widened by a hair so that round-off in the
/// logarithms never drops the end decades' labels.
fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = min_max(values.filter(|&y| y > 0.0));
    let lo = lo.map_or(-1.0, |v| v.log10().floor());
    let hi = hi.map_or(0.0, |v| v.log10().ceil()).max(lo + 1.0);
    10f64.powf(lo) * (1.0 - 1e-9)..10f64.powf(hi) * (1.0 + 1e-9)
}

fn min_max(values: impl Iterator<Item = f64>) -> (Option<f64>, Option<f64>) {
    values.fold((None, None), |(lo, hi), v| {
        (
            Some(lo.map_or(v, |l: f64| l.min(v))),
            Some(hi.map_or(v, |h: f64| h.max(v))),
        )
    })
}

/// At most about `max` points: consecutive points in buckets, each bucket keeping its lowest
/// and highest point in order (a curve keeps its shape at the plot's resolution).
pub fn thin(points: &[(f64, f64)], max: usize) -> Vec<(f64, f64)> {
    if points.len() <= max {
        return points.to_vec();
    }
    let bucket = points.len().div_ceil(max / 2);
    let mut kept = Vec::with_capacity(max + 2);
    for chunk in points.chunks(bucket) {
        let by_y = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
        let low = chunk
            .iter()
            .enumerate()
            .min_by(|a, b| by_y(&a.1, &b.1))
            .unwrap();
        let high = chunk
            .iter()
            .enumerate()
            .max_by(|a, b| by_y(&a.1, &b.1))
            .unwrap();
        let (first, second) = if low.0 <= high.0 {
            (low, high)
        } else {
            (high, low)
        };
        kept.push(*first.1);
        if second.0 != first.0 {
            kept.push(*second.1);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_keeps_ends_and_extremes() {
        let points: Vec<(f64, f64)> = (0..10_000).map(|i| (i as f64, (i as f64).sqrt())).collect();
        let kept = thin(&points, 100);
        assert!(kept.len() <= 102);
        assert_eq!(kept.first(), points.first());
        assert_eq!(kept.last(), points.last());
        assert!(kept.windows(2).all(|w| w[0].0 < w[1].0));
    }

    #[test]
    fn ranges() {
        let r = log_range([2e-5, 0.3, 0.0].into_iter());
        assert!((r.start / 1e-5 - 1.0).abs() < 1e-8 && r.start < 1e-5);
        assert!((r.end - 1.0).abs() < 1e-8 && r.end > 1.0);
        let r = linear_range([0.0, 100.0].into_iter());
        assert_eq!(r.start, 0.0);
        assert!(r.end > 100.0);
    }
}
