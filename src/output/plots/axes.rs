//! The axes of a line chart: the range each axis spans (linear, or whole decades on a log
//! axis), the scale a log axis is drawn in below f64's epsilon, and the series fitted to them
//! (a start beyond the y axis clipped to its edge, long series thinned).

use super::series::{Frame, Scale, Series};
use super::tick_label;
use std::ops::Range;

/// The span of the x values (0..1 without any), 2 % wider on each side with markers so that
/// the end markers are whole.
pub(super) fn x_range(series: &[Series], markers: bool) -> Range<f64> {
    let (lo, hi) = min_max(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let pad = if markers { 0.02 } else { 0.0 };
    match (lo, hi) {
        (Some(lo), Some(hi)) if hi > lo => lo - pad * (hi - lo)..hi + pad * (hi - lo),
        (Some(lo), _) => lo - 0.5..lo + 0.5,
        _ => 0.0..1.0,
    }
}

/// Whole decades around the positive x values ([`log_range`]); with markers, widened by 2 %
/// of the span (in decades) at an end where a point lies on the edge, so that its marker is
/// whole.
pub(super) fn log_x_range(values: impl Iterator<Item = f64>, markers: bool) -> Range<f64> {
    let values: Vec<f64> = values.filter(|&x| x > 0.0).collect();
    let range = log_range(values.iter().copied());
    if !markers {
        return range;
    }
    let (lo, hi) = (range.start.log10(), range.end.log10());
    let pad = 0.02 * (hi - lo);
    let near = |edge: f64| values.iter().any(|x| (x.log10() - edge).abs() < pad);
    let lo = if near(lo) { lo - pad } else { lo };
    let hi = if near(hi) { hi + pad } else { hi };
    10f64.powf(lo)..10f64.powf(hi)
}

/// Below this, a log axis is drawn in scaled units (see [`log_axis`]).
const LOG_AXIS_SMALLEST: f64 = 1e-12;

/// A log axis over `range` and the factor its values are drawn multiplied by: 1, or when the
/// range reaches below [`LOG_AXIS_SMALLEST`] the power of ten that brings its lower end into
/// [1, 10). Plotters takes log-axis values below `f64::EPSILON` for the axis' zero and draws
/// no tick or grid line there (e = 0 drawn at 10⁻¹⁶ would sit on an unlabelled edge); the
/// tick labels divide the factor out again.
pub(super) fn log_axis(range: Range<f64>) -> (Range<f64>, f64) {
    if range.start >= LOG_AXIS_SMALLEST {
        return (range, 1.0);
    }
    let factor = 10f64.powi(-(range.start.log10().floor() as i32));
    (range.start * factor..range.end * factor, factor)
}

/// Two lines under the legend for every series of a single point (drawn as a dot, on the
/// axis' edge when its value is beyond it): what it is, and its value.
pub(super) fn single_point_notes(series: &[Series], edges: &Range<f64>) -> Vec<String> {
    let mut notes = Vec::new();
    for s in series {
        if let [(x, y)] = s.points.as_slice() {
            let side = if *y < edges.start {
                ", below the axis"
            } else if *y > edges.end {
                ", above the axis"
            } else {
                ""
            };
            notes.push(format!("{}: a single point,", s.label));
            notes.push(format!("({}, {y:.1e}){side}", tick_label(*x)));
        }
    }
    notes
}

/// The y values the y axis spans: those of the series of two points or more (of all series
/// when none has two), at x ≥ `frame.y_from_x` when some are.
pub(super) fn y_span_values(series: &[Series], frame: &Frame) -> Vec<f64> {
    let lines: Vec<&Series> = series.iter().filter(|s| s.points.len() >= 2).collect();
    let lines = if lines.is_empty() {
        series.iter().collect()
    } else {
        lines
    };
    let from = frame.y_from_x.unwrap_or(f64::NEG_INFINITY);
    let after: Vec<f64> = lines
        .iter()
        .flat_map(|s| s.points.iter().filter(|p| p.0 >= from).map(|p| p.1))
        .collect();
    if after.is_empty() {
        lines
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .collect()
    } else {
        after
    }
}

/// `s` with its leading points beyond the y axis' `edges` replaced by the point where the
/// line to the next point crosses the edge (interpolated in the axis' scale), so that a start
/// above the axis is drawn from the edge. A one-point series beyond the edges is drawn on the
/// nearer edge (the note under the legend gives its value).
pub(super) fn clip_start(mut s: Series, edges: &Range<f64>, scale: Scale) -> Series {
    if let [(x, y)] = s.points.as_slice() {
        let (x, y) = (*x, *y);
        if y < edges.start {
            s.points = vec![(x, edges.start)];
        } else if y > edges.end {
            s.points = vec![(x, edges.end)];
        }
        return s;
    }
    let map = |y: f64| match scale {
        Scale::Linear => y,
        Scale::Log => y.log10(),
    };
    let unmap = |v: f64| match scale {
        Scale::Linear => v,
        Scale::Log => 10f64.powf(v),
    };
    let (lo, hi) = (map(edges.start), map(edges.end));
    let inside = |y: f64| (lo..=hi).contains(&map(y));
    let first_inside = s.points.iter().position(|p| inside(p.1));
    match first_inside {
        None => s.points.clear(),
        Some(0) => {}
        Some(k) => {
            let (x0, y0) = s.points[k - 1];
            let (x1, y1) = s.points[k];
            let (v0, v1) = (map(y0), map(y1));
            let edge = if v0 > hi { hi } else { lo };
            let f = (edge - v0) / (v1 - v0);
            let crossing = (x0 + f * (x1 - x0), unmap(edge));
            s.points.splice(..k, [crossing]);
        }
    }
    s
}

/// `series` with every x multiplied by `x_factor` and every y by `y_factor` (as is when both
/// are 1).
pub(super) fn scaled(series: Vec<Series>, x_factor: f64, y_factor: f64) -> Vec<Series> {
    if x_factor == 1.0 && y_factor == 1.0 {
        return series;
    }
    series
        .into_iter()
        .map(|s| Series {
            points: s
                .points
                .iter()
                .map(|&(x, y)| (x * x_factor, y * y_factor))
                .collect(),
            ..s
        })
        .collect()
}

/// From 0 (or below the smallest value when negative) to 5 % above the largest value.
pub(super) fn linear_range(values: impl Iterator<Item = f64>) -> Range<f64> {
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
pub(super) fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
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
