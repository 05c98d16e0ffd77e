//! `bench.svg`: e against wall time, log–log, one line per solver (and α), drawn as the run's
//! figures are: an [`output::plots::LineChart`](crate::output::plots::LineChart).

use super::Series;
use crate::output::plots::{LineChart, Scale, Series as Curve};

/// A series with more iterates than this is drawn as a line only: its markers would merge.
/// The chart marks every series or none, so it marks them when every series is this short.
const MAX_MARKED_POINTS: usize = 100;

/// Smallest e drawn: e = 0 (an iterate equal to the reference) sits on the lower edge.
const PLOT_FLOOR: f64 = 1e-16;

/// `bench.svg` as an SVG document: e against wall time (set-up included), log–log, one line
/// per solver and, when the bench has several α, per α ("solver (α = a)", grouped by solver),
/// in the solvers' colours of the run's figures, every iterate marked when no series has more
/// than 100. e is drawn no lower than 10⁻¹⁶: e = 0 (an iterate equal to the reference) sits
/// on the lower edge, and its series' label says ", e = 0 on the lower edge".
pub fn render_svg(series: &[Series], title: &str) -> Result<String, String> {
    chart(series, title).to_svg().map_err(|e| e.to_string())
}

/// The chart [`render_svg`] draws.
fn chart(series: &[Series], title: &str) -> LineChart {
    let several_alphas = series.iter().any(|s| s.alpha != series[0].alpha);
    // Grouped by solver (in the bench's order), α increasing within a solver: the legend
    // lists a solver's lines together, and with markers those of one solver (one colour)
    // differ by their marker (markers go round by series index).
    let first_of = |s: &Series| series.iter().position(|t| t.method == s.method);
    let mut order: Vec<&Series> = series.iter().collect();
    order.sort_by(|a, b| {
        first_of(a)
            .cmp(&first_of(b))
            .then(a.alpha.total_cmp(&b.alpha))
    });
    let curves: Vec<Curve> = order
        .into_iter()
        .map(|s| {
            let points = s
                .samples
                .iter()
                .filter(|p| p.error.is_finite())
                .map(|p| (p.seconds, p.error.max(PLOT_FLOOR)))
                .collect();
            let alpha = several_alphas.then_some(s.alpha);
            let mut curve = Curve::of_solver(s.method, alpha, points);
            if s.samples.iter().any(|p| p.error <= 0.0) {
                curve.label += ", e = 0 on the lower edge";
            }
            curve
        })
        .collect();
    LineChart {
        title: title.to_string(),
        x_label: "wall time, set-up included (s)".into(),
        y_label: "energy error e (–)".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        legend_title: "solver".into(),
        markers: series.iter().all(|s| s.samples.len() <= MAX_MARKED_POINTS),
        series: curves,
    }
}
