//! The line chart every curve figure is: series of (x, y) points on a linear or logarithmic x
//! axis and a linear or logarithmic y axis, axis labels with units, a legend beside the plot.

use super::axes::{
    clip_start, linear_range, log_axis, log_range, log_x_range, scaled, single_point_notes, thin,
    x_range, y_span_values,
};
use super::legend::{draw_line_legend, LegendEntry, TEXT_SIZE};
use super::marker::Marker;
use super::series::{Frame, Scale, Series};
use super::{log_tick_label, plot_error, tick_label, SERIES_STROKE_WIDTH};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::Method;

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
