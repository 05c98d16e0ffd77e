//! The line chart every curve figure is: series of (x, y) points on a linear or logarithmic x
//! axis and a linear or logarithmic y axis, axis labels with units, a legend beside the plot.

use super::legend::{draw_line_legend, LegendEntry, TEXT_SIZE};
use super::marker::Marker;
use super::palette::solver_colour;
use crate::solvers::Method;
use super::{alpha_text, log_tick_label, plot_error, tick_label, SERIES_STROKE_WIDTH};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;
use std::ops::Range;

/// Width of the plot (axes, labels and title), px.
const PLOT_WIDTH: u32 = 770;
/// Height of the whole figure, px.
const HEIGHT: u32 = 600;
/// Width of the legend column beside the plot when every label fits in it, px.
const LEGEND_WIDTH: u32 = 190;
/// Where a legend label starts in the legend column: the line sample's left margin (8), the
/// sample (28) and the gap after it (8), as `draw_line_legend` lays them out.
const LEGEND_LABEL_LEFT: u32 = 44;
/// Room kept right of the widest legend label, px.
const LEGEND_RIGHT_MARGIN: u32 = 12;
/// A series is drawn with at most this many points (the plot is ~700 px wide).
const MAX_POINTS: usize = 1400;

/// How an axis maps its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear, over the span of the values (from 0 on the y axis when they are positive).
    Linear,
    /// Logarithmic over whole decades, labelled 10ⁿ: points with a value ≤ 0 on this axis are
    /// left out.
    Log,
}

/// One curve of a [`LineChart`].
#[derive(Debug, Clone)]
pub struct Series {
    /// What the legend calls it.
    pub label: String,
    /// Its line (and markers, and legend sample).
    pub colour: RGBColor,
    /// Its points in drawing order; non-finite ones are left out.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// One solver's curve in the solver's colour (the same in every figure), labelled with
    /// the solver's name, followed by ` (α = a)` when `alpha` is given (figures with several
    /// load factors).
    pub fn of_solver(solver: Method, alpha: Option<f64>, points: Vec<(f64, f64)>) -> Series {
        let name = solver.name();
        let label = match alpha {
            Some(alpha) => format!("{name} (α = {})", alpha_text(alpha)),
            None => name.to_string(),
        };
        Series {
            label,
            colour: solver_colour(solver),
            points,
        }
    }
}

/// A line chart: its series as lines over a linear or log x axis and a linear or log y axis,
/// with a legend in a column right of the plot (widened when a label would not fit).
#[derive(Debug, Clone)]
pub struct LineChart {
    /// Caption above the plot.
    pub title: String,
    /// Description of the x axis, with its unit.
    pub x_label: String,
    /// Description of the y axis, with its unit.
    pub y_label: String,
    /// Scale of the x axis.
    pub x_scale: Scale,
    /// Scale of the y axis.
    pub y_scale: Scale,
    /// Heading of the legend (what the series differ by).
    pub legend_title: String,
    /// Mark every point, with a different marker per series (sparse data, series that may
    /// coincide).
    pub markers: bool,
    /// The curves, drawn in this order and listed so in the legend.
    pub series: Vec<Series>,
}

/// Which part of the data a [`LineChart`] shows (by default, all of it).
#[derive(Debug, Clone, Copy, Default)]
pub struct Frame {
    /// Points with a larger x are left out (the convergence figures stop at
    /// `output.max_plot_iterations`).
    pub x_max: Option<f64>,
    /// The y axis spans only the points with at least this x (the convergence figures leave
    /// iteration 0 out, whose start value may lie decades above the rest); a series starting
    /// beyond that span is drawn from where its first segment crosses the axis' edge.
    pub y_from_x: Option<f64>,
}

impl LineChart {
    /// The chart as an SVG document. Non-finite points, and points with a value ≤ 0 on a log
    /// axis, are left out.
    pub fn to_svg(&self) -> io::Result<String> {
        self.to_svg_framed(&Frame::default())
    }

    /// The chart as an SVG document showing the part of the data `frame` says. Non-finite
    /// points, and points with a value ≤ 0 on a log axis, are left out. A series of a single
    /// point is drawn as a dot (markers or not), and its value does not set the y axis when
    /// another series has two points or more: a solve that stopped at its first iteration
    /// must not stretch the axis of the others.
    pub fn to_svg_framed(&self, frame: &Frame) -> io::Result<String> {
        let series: Vec<Series> = self
            .series
            .iter()
            .map(|s| self.drawable(s, frame))
            .collect();
        let legend_width = legend_width(&self.legend_title, &self.series);
        let mut svg = String::new();
        {
            let size = (PLOT_WIDTH + legend_width, HEIGHT);
            let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
            root.fill(&WHITE).map_err(plot_error)?;
            let (plot, legend) = root.split_horizontally(PLOT_WIDTH);
            let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
            let ys = y_span_values(&series, frame);
            let ys = ys.into_iter();
            let (x, x_factor) = match self.x_scale {
                Scale::Linear => (x_range(&series, self.markers), 1.0),
                Scale::Log => log_axis(log_x_range(xs, self.markers)),
            };
            let (y, y_factor) = match self.y_scale {
                Scale::Linear => (linear_range(ys), 1.0),
                Scale::Log => log_axis(log_range(ys)),
            };
            let y_edges = match self.y_scale {
                Scale::Linear => y.clone(),
                Scale::Log => y.start / y_factor..y.end / y_factor,
            };
            let notes = single_point_notes(&series, &y_edges);
            let series: Vec<Series> = series
                .into_iter()
                .map(|s| clip_start(s, &y_edges, self.y_scale))
                .collect();
            let series = scaled(series, x_factor, y_factor);
            let tick = |scale: Scale, factor: f64| {
                move |v: f64| match scale {
                    Scale::Linear => tick_label(v),
                    Scale::Log => log_tick_label(v / factor),
                }
            };
            let (x_tick, y_tick) = (tick(self.x_scale, x_factor), tick(self.y_scale, y_factor));
            match (self.x_scale, self.y_scale) {
                (Scale::Linear, Scale::Linear) => self.draw(&plot, &series, x, &x_tick, y, &y_tick),
                (Scale::Linear, Scale::Log) => {
                    self.draw(&plot, &series, x, &x_tick, y.log_scale(), &y_tick)
                }
                (Scale::Log, Scale::Linear) => {
                    self.draw(&plot, &series, x.log_scale(), &x_tick, y, &y_tick)
                }
                (Scale::Log, Scale::Log) => {
                    let (x, y) = (x.log_scale(), y.log_scale());
                    self.draw(&plot, &series, x, &x_tick, y, &y_tick)
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
            let used =
                draw_line_legend(&legend, 60, &self.legend_title, &entries).map_err(plot_error)?;
            let note_font = ("sans-serif", 13).into_font().color(&BLACK);
            for (k, line) in notes.iter().enumerate() {
                let at = (8, 60 + used + 6 + 17 * k as i32);
                legend.draw_text(line, &note_font, at).map_err(plot_error)?;
            }
            root.present().map_err(plot_error)?;
        }
        Ok(svg)
    }

    fn drawable(&self, s: &Series, frame: &Frame) -> Series {
        let on_axis = |v: f64, scale: Scale| v.is_finite() && (scale == Scale::Linear || v > 0.0);
        let in_frame = |x: f64| frame.x_max.is_none_or(|max| x <= max);
        let keep = |&(x, y): &(f64, f64)| {
            on_axis(x, self.x_scale) && on_axis(y, self.y_scale) && in_frame(x)
        };
        let points: Vec<(f64, f64)> = s.points.iter().copied().filter(keep).collect();
        Series {
            label: s.label.clone(),
            colour: s.colour,
            points: thin(&points, MAX_POINTS),
        }
    }

    fn draw<DB, X, Y>(
        &self,
        area: &DrawingArea<DB, Shift>,
        series: &[Series],
        x: X,
        x_tick: &dyn Fn(f64) -> String,
        y: Y,
        y_tick: &dyn Fn(f64) -> String,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
    where
        DB: DrawingBackend,
        X: AsRangedCoord<Value = f64>,
        X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
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
            .x_label_formatter(&|v| x_tick(*v))
            .y_label_formatter(&|v| y_tick(*v))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()?;
        for (i, s) in series.iter().enumerate() {
            let style = s.colour.stroke_width(SERIES_STROKE_WIDTH);
            chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
            if let [only] = s.points.as_slice() {
                if !self.markers {
                    chart.draw_series([Circle::new(*only, 4, s.colour.filled())])?;
                }
            }
            if self.markers {
                Marker::nth(i).draw_on_chart(&mut chart, &s.points, s.colour)?;
            }
        }
        Ok(())
    }
}

/// Width of the legend column: [`LEGEND_WIDTH`], or more when its title or a label (by an
/// estimate of its width in the legend's font) would run past it.
fn legend_width(title: &str, series: &[Series]) -> u32 {
    let widest = series
        .iter()
        .map(|s| LEGEND_LABEL_LEFT + text_width(&s.label, TEXT_SIZE))
        .chain([8 + text_width(title, TEXT_SIZE)])
        .max()
        .unwrap_or(0);
    LEGEND_WIDTH.max(widest + LEGEND_RIGHT_MARGIN)
}

/// Estimated width in px of `text` in a sans-serif font of `size` px (DejaVu Sans' advances,
/// which are on the wide side of the common sans-serif fonts).
fn text_width(text: &str, size: u32) -> u32 {
    let em: f64 = text
        .chars()
        .map(|c| match c {
            'i' | 'j' | 'l' | '\'' | '|' => 0.28,
            ' ' | '.' | ',' | ':' | ';' | '!' | 'f' | 't' | 'I' => 0.34,
            'r' | '-' | '(' | ')' | '[' | ']' => 0.40,
            'm' => 0.98,
            'w' | '=' | '+' | '<' | '>' | '≤' => 0.84,
            'M' | 'W' => 1.0,
            c if c.is_ascii_uppercase() => 0.72,
            _ => 0.63,
        })
        .sum();
    (em * size as f64).ceil() as u32
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

/// Whole decades around the positive x values ([`log_range`]); with markers, widened by 2 %
/// of the span (in decades) at an end where a point lies on the edge, so that its marker is
/// whole.
fn log_x_range(values: impl Iterator<Item = f64>, markers: bool) -> Range<f64> {
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
fn log_axis(range: Range<f64>) -> (Range<f64>, f64) {
    if range.start >= LOG_AXIS_SMALLEST {
        return (range, 1.0);
    }
    let factor = 10f64.powi(-(range.start.log10().floor() as i32));
    (range.start * factor..range.end * factor, factor)
}

/// Two lines under the legend for every series of a single point (drawn as a dot, on the
/// axis' edge when its value is beyond it): what it is, and its value.
fn single_point_notes(series: &[Series], edges: &Range<f64>) -> Vec<String> {
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
fn y_span_values(series: &[Series], frame: &Frame) -> Vec<f64> {
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
fn clip_start(mut s: Series, edges: &Range<f64>, scale: Scale) -> Series {
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
fn scaled(series: Vec<Series>, x_factor: f64, y_factor: f64) -> Vec<Series> {
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

    /// The `points` attribute of every series polyline (stroke width
    /// [`SERIES_STROKE_WIDTH`]), as pixel pairs.
    fn series_polylines(svg: &str) -> Vec<Vec<(i32, i32)>> {
        let width = format!("stroke-width=\"{SERIES_STROKE_WIDTH}\"");
        svg.split("<polyline")
            .skip(1)
            .map(|tail| &tail[..tail.find("/>").expect("a closed polyline")])
            .filter(|element| element.contains(&width))
            .map(|element| {
                let start = element.find("points=\"").expect("points") + "points=\"".len();
                let list = &element[start..];
                let list = &list[..list.find('"').expect("closing quote")];
                list.split_whitespace()
                    .map(|pair| {
                        let (x, y) = pair.split_once(',').expect("x,y");
                        (x.parse().expect("x"), y.parse().expect("y"))
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn log_log_chart_leaves_out_points_off_the_axes() {
        let chart = LineChart {
            title: "log–log".into(),
            x_label: "time (s)".into(),
            y_label: "error (–)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            legend_title: "solver".into(),
            markers: true,
            series: vec![
                Series {
                    label: "a".into(),
                    colour: RGBColor(31, 119, 180),
                    points: vec![(0.0, 0.5), (1e-2, 1e-1), (1e-1, 1e-3), (2.0, 1e-5)],
                },
                Series {
                    label: "b".into(),
                    colour: RGBColor(255, 127, 14),
                    points: vec![(-1.0, 1.0), (2e-2, 1e-2), (3e-1, 0.0), (0.5, 1e-4)],
                },
            ],
        };
        let svg = chart.to_svg().expect("an SVG");
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        let lines = series_polylines(&svg);
        assert_eq!(lines.len(), chart.series.len());
        // x ≤ 0 (and y ≤ 0) left out: 3 of a's 4 points, 2 of b's 4.
        assert_eq!(lines[0].len(), 3);
        assert_eq!(lines[1].len(), 2);
        // Increasing x, decreasing y, all inside the plot.
        for line in &lines {
            assert!(line.windows(2).all(|w| w[0].0 < w[1].0 && w[0].1 < w[1].1));
            assert!(line.iter().all(|&(x, _)| 85 < x && x < PLOT_WIDTH as i32));
        }
        // Decade ticks on both axes: 10⁻² to 10¹ in x, 10⁻⁵ to 10⁻¹ in y (the points left
        // out, with y up to 1, do not widen the y range to 10⁰).
        let texts = texts(&svg);
        let count = |tick: &str| texts.iter().filter(|&&t| t == tick).count();
        let y_only = ["10⁻⁵", "10⁻⁴", "10⁻³"];
        let both = ["10⁻²", "10⁻¹"];
        for (ticks, axes) in [(&y_only[..], 1), (&both[..], 2)] {
            for &tick in ticks {
                assert_eq!(count(tick), axes, "{tick}: {texts:?}");
            }
        }
        assert_eq!(count("10⁰"), 1, "{texts:?}");
        assert_eq!(count("10¹"), 1, "{texts:?}");
    }

    #[test]
    fn log_axis_labels_decades_below_machine_epsilon() {
        let chart = LineChart {
            title: String::new(),
            x_label: "time (s)".into(),
            y_label: "error (–)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            legend_title: "solver".into(),
            markers: false,
            series: vec![Series::of_solver(
                Method::Newton,
                Some(0.05),
                vec![(1e-3, 1.0), (2e-3, 1e-9), (3e-3, 1e-16)],
            )],
        };
        let svg = chart.to_svg().expect("an SVG");
        let texts = texts(&svg);
        for tick in ["10⁻¹⁶", "10⁻⁸", "10⁰", "10⁻³", "newton (α = 0.05)"] {
            assert!(texts.contains(&tick), "{tick}: {texts:?}");
        }
        assert_eq!(series_polylines(&svg)[0].len(), 3);
    }

    /// The content of every `<text>` element, trimmed.
    fn texts(svg: &str) -> Vec<&str> {
        svg.split("<text")
            .skip(1)
            .filter_map(|tail| {
                let body = &tail[tail.find('>')? + 1..];
                Some(body[..body.find("</text>")?].trim())
            })
            .collect()
    }

    #[test]
    fn frame_cuts_x_and_keeps_iteration_0_and_single_points_off_the_y_range() {
        let decay: Vec<(f64, f64)> = (0..200)
            .map(|i| (i as f64, if i == 0 { 1e3 } else { 0.5f64.powi(i / 10) }))
            .collect();
        let chart = LineChart {
            title: String::new(),
            x_label: "iteration (–)".into(),
            y_label: "error (–)".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
            legend_title: "load factor".into(),
            markers: false,
            series: vec![
                Series::of_solver(Method::MicroMacro, Some(1.0), decay),
                Series::of_solver(Method::MonoLatin, Some(1.0), vec![(0.0, 1e-14)]),
            ],
        };
        let frame = Frame {
            x_max: Some(100.0),
            y_from_x: Some(1.0),
        };
        let svg = chart.to_svg_framed(&frame).expect("an SVG");
        let texts = texts(&svg);
        // y from the values after iteration 0 (1 down to 0.5⁹ ≈ 2e-3): 10⁻³ to 10⁰, neither
        // the start (1e3) nor the single point (1e-14) stretching it.
        for tick in ["10⁻³", "10⁰", "100"] {
            assert!(texts.contains(&tick), "{tick}: {texts:?}");
        }
        for tick in ["10³", "10⁻¹⁴", "120"] {
            assert!(!texts.contains(&tick), "{tick}: {texts:?}");
        }
        assert!(texts.contains(&"(0, 1.0e-14), below the axis"), "{texts:?}");
        let lines = series_polylines(&svg);
        // Iterations 0 to 100, the first drawn where its segment crosses the top edge.
        assert_eq!(lines[0].len(), 101);
        assert!(lines[0][0].1 <= lines[0][1].1 && lines[0][0].0 > 85);
        // The single point, on the lower edge.
        assert_eq!(lines[1].len(), 1);
    }

    #[test]
    fn legend_widens_for_long_labels_only() {
        let series = |label: &str| Series {
            label: label.into(),
            colour: RGBColor(0, 0, 0),
            points: vec![],
        };
        assert_eq!(
            legend_width("solver", &[series("micro-macro")]),
            LEGEND_WIDTH
        );
        assert_eq!(
            legend_width("load factor", &[series("α = 0.05")]),
            LEGEND_WIDTH
        );
        let long = "newton, e = 0 on the lower edge";
        assert!(legend_width("solver", &[series(long)]) > LEGEND_WIDTH + 80);
    }
}
