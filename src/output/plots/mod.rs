//! SVG figures under `plots/` (the paper's Figures 6–12) and `modes/`, drawn with plotters' SVG backend
//! (text as SVG `<text>`, no fonts needed). The run hands each solve and each LATIN history to
//! a [`FigureData`] and writes the figures once the sweep is done; nothing here solves.
//!
//! | figure | what it draws |
//! |---|---|
//! | `tensions.svg` | sorted cable tensions, one series per α (first solver), α = 0 among them whenever its answer is known — Figure 6; not for a general structure under 100 members, which has `member_forces.svg` |
//! | `member_forces.svg` | a general structure under 100 members: every member's force at the figure's α, one labelled bar each |
//! | `slack_fraction.svg` | slack fraction against α, one series per solver — Figure 7 |
//! | `deformed_alpha{α}.svg` | the deformed structure at the figure's α (`output.figure_alpha`, else the largest), displacements amplified (`output.amplification`, else automatic), oblique view, plan and elevation, τ in colour — Figure 8 |
//! | `error_{solver}.svg`, `eta_{solver}.svg` | e and η per iteration up to `output.max_plot_iterations`, one series per α — Figures 9, 10 |
//! | `error_all.svg` | e per iteration of every LATIN solver at the largest α — Figure 11 |
//! | `error_modules.svg` | e per iteration at the largest α, one series per module kind of `output.compare_modules` and LATIN solver — Figure 12 |
//! | `modes/{solver}_alpha{α}.svg` | the lowest natural modes of one answer, each in the oblique view (`output.modes`) |
//!
//! In the line charts each series is one `<polyline>` of stroke width [`SERIES_STROKE_WIDTH`],
//! and nothing else has that width.

mod amplification;
mod annotate;
mod axes;
mod chart;
mod convergence;
mod deformed;
mod legend;
mod marker;
mod member_forces;
mod modes;
mod palette;
mod series;
mod slack;
mod tension_scale;
mod tensions;
mod views;

pub use chart::LineChart;
pub use modes::write_modes_svg;
pub use series::{Frame, Scale, Series};

use super::{alpha_label, write_atomic};
use crate::solvers::{Equilibrium, IterationRecord, Method};
use crate::structure::Structure;
use std::io;
use std::path::{Path, PathBuf};

/// Stroke width of a line chart's series, and of nothing else in it.
pub const SERIES_STROKE_WIDTH: u32 = 2;

/// The iteration records of one LATIN solve.
#[derive(Debug, Clone)]
pub struct History {
    /// The solver.
    pub solver: Method,
    /// Load factor α of the solve.
    pub alpha: f64,
    /// One record per iteration, in order.
    pub records: Vec<IterationRecord>,
}

/// How the figures are drawn: the case's `output.amplification`, `output.figure_alpha` and
/// `output.max_plot_iterations`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FigureSettings {
    /// Factor the displacements are drawn multiplied by in Figure 8; `None`: automatic.
    pub amplification: Option<f64>,
    /// The α Figure 8 and the member-force chart show; `None`: the largest.
    pub figure_alpha: Option<f64>,
    /// Last iteration the convergence figures show.
    pub max_plot_iterations: usize,
}

/// Slack fraction of one solver at each α, in solve order.
#[derive(Debug, Clone)]
struct SlackSeries {
    solver: Method,
    points: Vec<(f64, f64)>,
}

/// What the figures are drawn from, gathered along the sweep.
#[derive(Debug, Clone)]
pub struct FigureData {
    settings: FigureSettings,
    /// The solver whose results Figures 6 and 8 show.
    first_solver: Method,
    /// Per α: the first solver's cable tensions, sorted increasingly.
    tensions: Vec<(f64, Vec<f64>)>,
    slack: Vec<SlackSeries>,
    histories: Vec<History>,
    /// The first solver's equilibrium at the figure's α.
    deformed: Option<(f64, Equilibrium)>,
}

impl FigureData {
    /// No data yet; `first_solver`'s solves are the ones Figures 6 and 8 show.
    pub fn new(first_solver: Method, settings: FigureSettings) -> Self {
        FigureData {
            settings,
            first_solver,
            tensions: Vec::new(),
            slack: Vec::new(),
            histories: Vec::new(),
            deformed: None,
        }
    }

    /// Keep what the figures need of one solve.
    pub fn add_solve(&mut self, solver: Method, alpha: f64, s: &Structure, eq: &Equilibrium) {
        let fraction = eq.slack_count() as f64 / s.n_cables().max(1) as f64;
        match self.slack.iter_mut().find(|series| series.solver == solver) {
            Some(series) => series.points.push((alpha, fraction)),
            None => self.slack.push(SlackSeries {
                solver,
                points: vec![(alpha, fraction)],
            }),
        }
        if solver != self.first_solver {
            return;
        }
        self.tensions.push((alpha, sorted_cable_tensions(s, eq)));
        let shown = match self.settings.figure_alpha {
            Some(wanted) => alpha == wanted,
            None => self
                .deformed
                .as_ref()
                .is_none_or(|(largest, _)| alpha >= *largest),
        };
        if shown {
            self.deformed = Some((alpha, eq.clone()));
        }
    }

    /// Keep the iteration records of one LATIN solve (Figures 9–11).
    pub fn add_history(&mut self, solver: Method, alpha: f64, records: Vec<IterationRecord>) {
        self.histories.push(History {
            solver,
            alpha,
            records,
        });
    }

    /// Write every figure there is data for under `dir/plots`; returns their paths.
    pub fn write(&self, dir: &Path, s: &Structure) -> io::Result<Vec<PathBuf>> {
        let mut figures: Vec<(String, String)> = Vec::new();
        if !self.tensions.is_empty() && !member_forces::drawn_for(s) {
            let mut sets = self.tensions.clone();
            if !sets.iter().any(|(alpha, _)| *alpha == 0.0) {
                sets.extend(tensions::at_rest(s));
            }
            let chart = tensions::chart(self.first_solver.name(), &sets);
            figures.push(("tensions.svg".into(), chart.to_svg()?));
        }
        if !self.slack.is_empty() {
            let series: Vec<(Method, &[(f64, f64)])> = self
                .slack
                .iter()
                .map(|x| (x.solver, x.points.as_slice()))
                .collect();
            figures.push(("slack_fraction.svg".into(), slack::chart(&series).to_svg()?));
        }
        figures.extend(convergence::figures(&self.histories, &self.settings)?);
        if let Some((alpha, eq)) = &self.deformed {
            let (solver, amplification) = (self.first_solver.name(), self.settings.amplification);
            let svg = deformed::to_svg(solver, *alpha, amplification, s, eq)?;
            figures.push((format!("deformed_alpha{}.svg", alpha_label(*alpha)), svg));
            if member_forces::drawn_for(s) {
                let svg = member_forces::to_svg(solver, *alpha, s, eq)?;
                figures.push(("member_forces.svg".into(), svg));
            }
        }
        let plots = dir.join("plots");
        figures
            .into_iter()
            .map(|(name, svg)| {
                let path = plots.join(name);
                write_atomic(&path, |w| w.write_all(svg.as_bytes()))?;
                Ok(path)
            })
            .collect()
    }
}

/// Write `plots/error_modules.svg` (paper Figure 12) at `path`: e per iteration of every
/// (module kind, LATIN solver) history on the same axes, framed as the other convergence
/// figures. Nothing is written when no history has e.
pub fn write_module_comparison(
    path: &Path,
    histories: &[(&str, History)],
    settings: &FigureSettings,
) -> io::Result<()> {
    match convergence::modules_chart(histories, settings)? {
        Some(svg) => write_atomic(path, |w| w.write_all(svg.as_bytes())),
        None => Ok(()),
    }
}

fn sorted_cable_tensions(s: &Structure, eq: &Equilibrium) -> Vec<f64> {
    let mut tensions: Vec<f64> = s
        .links
        .iter()
        .zip(&eq.tensions)
        .filter(|(l, _)| l.kind.is_cable())
        .map(|(_, &t)| t)
        .collect();
    tensions.sort_by(f64::total_cmp);
    tensions
}

/// A drawing error as an I/O error (the SVG backend writes to a String).
fn plot_error(e: impl std::fmt::Display) -> io::Error {
    io::Error::other(format!("drawing a figure: {e}"))
}

/// α as legends and titles show it: at most 6 decimals, so that α = 0.1 computed by a range
/// (0.09999999999999999) reads 0.1. File names keep [`alpha_label`].
fn alpha_text(alpha: f64) -> String {
    if alpha == 0.0 || alpha.abs() >= 1e-3 {
        trim_zeros(&format!("{alpha:.6}"))
    } else {
        tick_label(alpha)
    }
}

/// Axis label of a linear axis: at most 4 decimals, exponent form outside [1e-3, 1e5).
fn tick_label(v: f64) -> String {
    let a = v.abs();
    if a < 1e-12 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        trim_zeros(&format!("{v:.4}"))
    } else {
        let text = format!("{v:.3e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        format!("{}e{exponent}", trim_zeros(mantissa))
    }
}

/// Axis label of a log axis: powers of ten as 10ⁿ.
fn log_tick_label(v: f64) -> String {
    let exponent = v.log10().round();
    if (v / 10f64.powf(exponent) - 1.0).abs() < 1e-9 {
        format!("10{}", superscript(exponent as i32))
    } else {
        tick_label(v)
    }
}

fn trim_zeros(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text.to_string()
    }
}

fn superscript(n: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let digits = n.unsigned_abs().to_string();
    let sign = if n < 0 { "⁻" } else { "" };
    let body: String = digits
        .bytes()
        .map(|d| DIGITS[(d - b'0') as usize])
        .collect();
    format!("{sign}{body}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(2500.0), "2500");
        assert_eq!(tick_label(0.125), "0.125");
        assert_eq!(tick_label(-0.05), "-0.05");
        assert_eq!(tick_label(2.5e-5), "2.5e-5");
        assert_eq!(log_tick_label(1e-4), "10⁻⁴");
        assert_eq!(log_tick_label(1.0), "10⁰");
        assert_eq!(log_tick_label(100.0), "10²");
        assert_eq!(alpha_text(0.09999999999999999), "0.1");
        assert_eq!(alpha_text(0.05), "0.05");
        assert_eq!(alpha_text(1.0), "1");
        assert_eq!(alpha_text(0.0), "0");
    }
}
