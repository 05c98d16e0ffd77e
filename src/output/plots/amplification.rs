//! How much `deformed_alpha{α}.svg` magnifies the displacements: `output.amplification` when
//! the case gives it; otherwise automatically, the largest nodal displacement drawn as
//! [`FRACTION`] of the structure's size (the diagonal of its nodes' bounding box,
//! [`Structure::size`]), rounded to two significant digits and kept within
//! [`MIN_AUTOMATIC`]..=[`MAX_AUTOMATIC`]: never below 1, so that a displacement already larger
//! than the fraction is drawn true to scale rather than shrunk, and never above 1000, so that a
//! displacement below 1e-4 of the size (round-off, a nearly rigid structure) is not blown up
//! into a shape it does not have. The figure's subtitle says which of these it is.

use super::tick_label;
use crate::solvers::Equilibrium;
use crate::structure::Structure;

/// The automatic amplification draws the largest displacement as this fraction of the
/// structure's size.
pub const FRACTION: f64 = 0.10;
/// Smallest automatic amplification: displacements are never drawn smaller than they are.
pub const MIN_AUTOMATIC: f64 = 1.0;
/// Largest automatic amplification.
pub const MAX_AUTOMATIC: f64 = 1000.0;

/// Where an amplification comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// `output.amplification`.
    Given,
    /// [`FRACTION`] of the size over the largest displacement, within the bounds.
    Fraction,
    /// Capped at [`MAX_AUTOMATIC`]: the displacements are smaller than the fraction would need.
    Capped,
    /// Held at [`MIN_AUTOMATIC`]: the displacements are larger than the fraction already.
    TrueScale,
    /// Nothing moves.
    NoDisplacement,
}

/// The factor the displacements are drawn multiplied by, and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Amplification {
    pub factor: f64,
    pub source: Source,
    /// The largest nodal displacement |u|, m.
    pub largest: f64,
    /// The structure's size, m.
    pub size: f64,
}

impl Amplification {
    /// `given` (`output.amplification`), or the automatic one of `eq` on `s`.
    pub fn of(given: Option<f64>, s: &Structure, eq: &Equilibrium) -> Amplification {
        let full = s.full_displacements(&eq.displacements);
        let largest = full
            .chunks(3)
            .map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt())
            .fold(0.0_f64, f64::max);
        let size = s.size();
        let (factor, source) = match given {
            Some(factor) => (factor, Source::Given),
            None => automatic(largest, size),
        };
        Amplification {
            factor,
            source,
            largest,
            size,
        }
    }

    /// The figure's subtitle: where the factor comes from, the largest displacement and the size.
    pub fn explanation(&self) -> String {
        let (largest, size) = (length_text(self.largest), length_text(self.size));
        let percent = tick_label(100.0 * FRACTION);
        match self.source {
            Source::Given => format!(
                "amplification from output.amplification; largest displacement {largest}, \
                 structure size {size}"
            ),
            Source::Fraction => format!(
                "automatic amplification: the largest displacement, {largest}, drawn as \
                 {percent} % of the structure's size ({size})"
            ),
            Source::Capped => format!(
                "automatic amplification, capped at × {}: the largest displacement, {largest}, \
                 is tiny beside the structure's size ({size})",
                tick_label(MAX_AUTOMATIC)
            ),
            Source::TrueScale => format!(
                "true scale: the largest displacement, {largest}, is over {percent} % of the \
                 structure's size ({size})"
            ),
            Source::NoDisplacement => "no node moves".to_string(),
        }
    }
}

/// `FRACTION · size / largest` (two significant digits) within the bounds.
fn automatic(largest: f64, size: f64) -> (f64, Source) {
    if !(largest > 0.0 && largest.is_finite() && size > 0.0) {
        return (1.0, Source::NoDisplacement);
    }
    let exact = FRACTION * size / largest;
    if exact > MAX_AUTOMATIC {
        (MAX_AUTOMATIC, Source::Capped)
    } else if exact < MIN_AUTOMATIC {
        (MIN_AUTOMATIC, Source::TrueScale)
    } else {
        (two_significant_digits(exact), Source::Fraction)
    }
}

/// `x` > 0 rounded to two significant digits: 7.68 → 7.7, 123.4 → 120.
fn two_significant_digits(x: f64) -> f64 {
    let unit = 10f64.powf(x.log10().floor() - 1.0);
    let digits = (x / unit).round();
    // 10^k computed as a quotient reads exactly (4.8, not 4.800000000000001).
    if unit < 1.0 {
        digits / (1.0 / unit).round()
    } else {
        digits * unit
    }
}

/// A length with three significant digits, in mm below 1 m: `41.7 mm`, `2.06 m`.
pub fn length_text(metres: f64) -> String {
    let (value, unit) = if metres.abs() < 1.0 {
        (1000.0 * metres, "mm")
    } else {
        (metres, "m")
    };
    if value == 0.0 {
        return format!("0 {unit}");
    }
    let decimals = (2 - value.abs().log10().floor() as i32).max(0) as usize;
    format!("{value:.decimals$} {unit}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn automatic_amplification_is_the_fraction_within_bounds() {
        // 10 % of 3.2 m over 41.7 mm: 7.67…, drawn × 7.7.
        assert_eq!(automatic(0.0417, 3.2), (7.7, Source::Fraction));
        assert_eq!(automatic(0.00253, 3.3).0, 130.0);
        assert_eq!(automatic(1e-9, 3.0), (MAX_AUTOMATIC, Source::Capped));
        assert_eq!(automatic(2.0, 3.0), (MIN_AUTOMATIC, Source::TrueScale));
        assert_eq!(automatic(0.0, 3.0), (1.0, Source::NoDisplacement));
        assert_eq!(two_significant_digits(4.84), 4.8);
        assert_eq!(two_significant_digits(1.0), 1.0);
        assert_eq!(two_significant_digits(999.0), 1000.0);
    }

    #[test]
    fn lengths_read_with_three_digits() {
        assert_eq!(length_text(0.04169), "41.7 mm");
        assert_eq!(length_text(0.0001234), "0.123 mm");
        assert_eq!(length_text(3.2016), "3.20 m");
        assert_eq!(length_text(12.5), "12.5 m");
    }
}
