//! The LATIN convergence figures: `error_{solver}.svg` and `eta_{solver}.svg` (paper Figures 9
//! and 10: e and η per iteration, one series per α) and `error_all.svg` (Figure 11: e of every
//! LATIN solver at the largest α). A figure without any point (e with `reference = "none"`)
//! is not drawn.
//!
//! The x axis stops at `output.max_plot_iterations` (100 by default, as the paper's), and the
//! y axis spans the values from iteration 1 on: the start (iteration 0) of a solve may lie
//! decades above the rest and is drawn from the axis' edge. A solve of a single iteration
//! (the direct mono-latin of a linear case, α = 0) is a dot, on the axis' edge when beyond it,
//! whose value a note under the legend gives; it does not stretch the axis.

use super::chart::LineChart;
use super::palette::{ordered_colour, solver_colour};
use super::series::{Frame, Scale, Series};
use super::{alpha_text, FigureSettings, History};
use crate::solvers::{IterationRecord, Method};
use std::io;

#[derive(Debug, Clone, Copy)]
pub(super) enum Measure {
    /// Energy error e against the reference.
    Error,
    /// LATIN indicator η.
    Eta,
}

impl Measure {
    fn value(self, r: &IterationRecord) -> Option<f64> {
        match self {
            Measure::Error => r.error,
            Measure::Eta => Some(r.stopping_value),
        }
    }

    fn file_stem(self) -> &'static str {
        match self {
            Measure::Error => "error",
            Measure::Eta => "eta",
        }
    }

    fn axis_label(self) -> &'static str {
        match self {
            Measure::Error => "energy error e (–)",
            Measure::Eta => "error indicator η (–)",
        }
    }

    fn what(self) -> &'static str {
        match self {
            Measure::Error => "Energy error e",
            Measure::Eta => "Error indicator η",
        }
    }
}

/// (file name, SVG) of every convergence figure the histories give.
pub fn figures(
    histories: &[History],
    settings: &FigureSettings,
) -> io::Result<Vec<(String, String)>> {
    let frame = Frame {
        x_max: Some(settings.max_plot_iterations as f64),
        y_from_x: Some(1.0),
    };
    let mut solvers: Vec<Method> = Vec::new();
    for h in histories {
        if !solvers.contains(&h.solver) {
            solvers.push(h.solver);
        }
    }
    let mut figures = Vec::new();
    for &solver in &solvers {
        let mut own: Vec<&History> = histories.iter().filter(|h| h.solver == solver).collect();
        own.sort_by(|a, b| a.alpha.total_cmp(&b.alpha));
        for measure in [Measure::Error, Measure::Eta] {
            if let Some(chart) = per_alpha_chart(solver, measure, &own) {
                let name = format!("{}_{}.svg", measure.file_stem(), solver.name());
                figures.push((name, chart.to_svg_framed(&frame)?));
            }
        }
    }
    let at_largest: Vec<&History> = solvers
        .iter()
        .filter_map(|&solver| {
            histories
                .iter()
                .filter(|h| h.solver == solver)
                .max_by(|a, b| a.alpha.total_cmp(&b.alpha))
        })
        .collect();
    if let Some(chart) = solvers_chart(&at_largest) {
        figures.push(("error_all.svg".into(), chart.to_svg_framed(&frame)?));
    }
    Ok(figures)
}

fn points(h: &History, measure: Measure) -> Vec<(f64, f64)> {
    h.records
        .iter()
        .filter_map(|r| measure.value(r).map(|v| (r.iteration as f64, v)))
        .collect()
}

/// One series per α of one solver; None when no record has the measure.
fn per_alpha_chart(solver: Method, measure: Measure, histories: &[&History]) -> Option<LineChart> {
    let n = histories.len();
    let series: Vec<Series> = histories
        .iter()
        .enumerate()
        .map(|(i, h)| Series {
            label: format!("α = {}", alpha_text(h.alpha)),
            colour: ordered_colour(i, n),
            points: points(h, measure),
        })
        .collect();
    convergence_chart(
        format!("{} per iteration ({})", measure.what(), solver.name()),
        measure,
        "load factor",
        series,
    )
}

/// Figure 12: e of every (module kind, solver) history on one chart, as an SVG; None when no
/// record has e.
pub fn modules_chart(
    histories: &[(&str, History)],
    settings: &FigureSettings,
) -> io::Result<Option<String>> {
    let frame = Frame {
        x_max: Some(settings.max_plot_iterations as f64),
        y_from_x: Some(1.0),
    };
    let mut modules: Vec<&str> = Vec::new();
    let mut solvers: Vec<Method> = Vec::new();
    for (module, h) in histories {
        if !modules.contains(module) {
            modules.push(module);
        }
        if !solvers.contains(&h.solver) {
            solvers.push(h.solver);
        }
    }
    // Solvers whose curves are lines take the full hues; one-point ones (a direct solve) the
    // lighter shades.
    let is_line = |solver: Method| {
        histories
            .iter()
            .any(|(_, h)| h.solver == solver && h.records.len() > 1)
    };
    solvers.sort_by_key(|&solver| !is_line(solver));
    let index = |list: &[&str], name: &str| list.iter().position(|x| *x == name).unwrap_or(0);
    let solver_index = |solver: Method| solvers.iter().position(|&x| x == solver).unwrap_or(0);
    let series: Vec<Series> = histories
        .iter()
        .map(|(module, h)| Series {
            label: format!("{module}, {}", h.solver.name()),
            colour: module_colour(index(&modules, module), solver_index(h.solver)),
            points: points(h, Measure::Error),
        })
        .collect();
    let alphas: Vec<String> = histories.iter().map(|(_, h)| alpha_text(h.alpha)).collect();
    let title = match alphas.first() {
        Some(alpha) => format!("Energy error e per iteration by module kind at α = {alpha}"),
        None => "Energy error e per iteration by module kind".to_string(),
    };
    match convergence_chart(title, Measure::Error, "module, solver", series) {
        Some(chart) => Ok(Some(chart.to_svg_framed(&frame)?)),
        None => Ok(None),
    }
}

/// Figure 12's colour of module kind `module` and solver `solver` (indices in order of
/// appearance): one hue per module kind (blue, red, green), lighter for each further solver.
fn module_colour(module: usize, solver: usize) -> plotters::style::RGBColor {
    use plotters::style::RGBColor;
    const HUES: [(f64, f64, f64); 3] = [
        (31.0, 119.0, 180.0),
        (214.0, 39.0, 40.0),
        (44.0, 160.0, 44.0),
    ];
    let (r, g, b) = HUES[module % HUES.len()];
    let light = 1.0 - 0.55f64.powi(solver as i32);
    let mix = |c: f64| (c + light * (235.0 - c)).round() as u8;
    RGBColor(mix(r), mix(g), mix(b))
}

/// e of every solver's history; None when no record has e.
fn solvers_chart(histories: &[&History]) -> Option<LineChart> {
    let alphas: Vec<String> = histories.iter().map(|h| alpha_text(h.alpha)).collect();
    let mut distinct = alphas.clone();
    distinct.dedup();
    let series: Vec<Series> = histories
        .iter()
        .map(|h| Series {
            label: if distinct.len() == 1 {
                h.solver.name().to_string()
            } else {
                format!("{} (α = {})", h.solver.name(), alpha_text(h.alpha))
            },
            colour: solver_colour(h.solver),
            points: points(h, Measure::Error),
        })
        .collect();
    let title = match distinct.as_slice() {
        [alpha] => format!("Energy error e per iteration at α = {alpha}"),
        _ => "Energy error e per iteration at the largest α".to_string(),
    };
    convergence_chart(title, Measure::Error, "solver", series)
}

pub(super) fn convergence_chart(
    title: String,
    measure: Measure,
    legend_title: &str,
    series: Vec<Series>,
) -> Option<LineChart> {
    if series.iter().all(|s| s.points.is_empty()) {
        return None;
    }
    Some(LineChart {
        title,
        x_label: "iteration (–)".into(),
        y_label: measure.axis_label().into(),
        x_scale: Scale::Linear,
        y_scale: Scale::Log,
        legend_title: legend_title.into(),
        markers: false,
        series,
    })
}
