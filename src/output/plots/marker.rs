//! Point markers that tell apart series drawn on top of each other (solvers that agree): a
//! large hollow circle first, then a hollow square, a filled triangle and a small dot, each
//! smaller than the one before so that all stay visible where the curves coincide.

use plotters::coord::CoordTranslate;
use plotters::coord::Shift;
use plotters::prelude::*;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Square,
    Triangle,
    Dot,
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

impl Marker {
    /// The marker of series `i`.
    pub fn nth(i: usize) -> Marker {
        [
            Marker::Circle,
            Marker::Square,
            Marker::Triangle,
            Marker::Dot,
        ][i % 4]
    }

    /// The marker on every point of a chart.
    pub fn draw_on_chart<DB, CT>(
        self,
        chart: &mut ChartContext<'_, DB, CT>,
        points: &[(f64, f64)],
        colour: RGBColor,
    ) -> DrawResult<DB>
    where
        DB: DrawingBackend,
        CT: CoordTranslate<From = (f64, f64)>,
    {
        let at = points.iter().map(|&p| EmptyElement::at(p));
        let hollow = colour.stroke_width(2);
        match self {
            Marker::Circle => chart.draw_series(at.map(|e| e + Circle::new((0, 0), 7, hollow))),
            Marker::Square => chart.draw_series(at.map(|e| e + Rectangle::new(SQUARE, hollow))),
            Marker::Triangle => {
                chart.draw_series(at.map(|e| e + TriangleMarker::new((0, 0), 5, colour.filled())))
            }
            Marker::Dot => {
                chart.draw_series(at.map(|e| e + Circle::new((0, 0), 2, colour.filled())))
            }
        }
        .map(|_| ())
    }

    /// The marker at one pixel of an area (a legend).
    pub fn draw_at<DB: DrawingBackend>(
        self,
        area: &DrawingArea<DB, Shift>,
        at: (i32, i32),
        colour: RGBColor,
    ) -> DrawResult<DB> {
        let e = EmptyElement::at(at);
        let hollow = colour.stroke_width(2);
        match self {
            Marker::Circle => area.draw(&(e + Circle::new((0, 0), 7, hollow))),
            Marker::Square => area.draw(&(e + Rectangle::new(SQUARE, hollow))),
            Marker::Triangle => area.draw(&(e + TriangleMarker::new((0, 0), 5, colour.filled()))),
            Marker::Dot => area.draw(&(e + Circle::new((0, 0), 2, colour.filled()))),
        }
    }
}

const SQUARE: [(i32, i32); 2] = [(-4, -4), (4, 4)];
