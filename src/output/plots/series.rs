//! What a line chart shows: its curves ([`Series`]), how each axis maps its values ([`Scale`]) and
//! which part of the data it frames ([`Frame`]); drawn by `chart`, fitted to the axes by `axes`,
//! which both read these and not each other's.

use super::alpha_text;
use super::palette::solver_colour;
use crate::solvers::Method;
use plotters::style::RGBColor;

/// How an axis maps its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear, over the span of the values (from 0 on the y axis when they are positive).
    Linear,
    /// Logarithmic over whole decades, labelled 10ⁿ: points with a value ≤ 0 on this axis are
    /// left out.
    Log,
}

/// One curve of a [`LineChart`](super::LineChart).
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

/// Which part of the data a [`LineChart`](super::LineChart) shows (by default, all of it).
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
