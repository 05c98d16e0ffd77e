//! The taut cables' colour scale of the deformed-structure figure and the member-force chart:
//! over the actual range of their tensions τ at the figure's α, so that near-uniform tensions
//! (a prestress of 2 kN ± 1 %) still span the whole ramp. Tensions: yellow (smallest) to dark
//! red (largest). When some cable is compressed (a bilateral cable of the linear case), the
//! scale runs from the smallest τ < 0 (dark blue) through 0 (light blue, then yellow) to the
//! largest. Slack cables (τ = 0, drawn dashed) take no part in the range.

use super::palette::{compression_colour, tension_colour};
use crate::solvers::Equilibrium;
use crate::structure::Structure;
use plotters::style::RGBColor;

/// The colour of a taut cable's tension over the range `lo..=hi` of the taut cables' τ.
#[derive(Debug, Clone, Copy)]
pub struct TensionScale {
    pub lo: f64,
    pub hi: f64,
}

impl TensionScale {
    /// The range of the taut cables' tensions of `eq` (0..1 without any).
    pub fn new(s: &Structure, eq: &Equilibrium) -> TensionScale {
        let taut = s
            .links
            .iter()
            .enumerate()
            .filter(|(i, l)| l.kind.is_cable() && !eq.slack[*i])
            .map(|(i, _)| eq.tensions[i]);
        TensionScale::over(taut)
    }

    /// The range of `tensions` (0..1 when empty).
    pub fn over(tensions: impl Iterator<Item = f64>) -> TensionScale {
        let (lo, hi) = tensions
            .filter(|t| t.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
                (lo.min(t), hi.max(t))
            });
        if lo > hi {
            return TensionScale { lo: 0.0, hi: 1.0 };
        }
        TensionScale { lo, hi }
    }

    /// Some cable is compressed.
    pub fn has_compression(&self) -> bool {
        self.lo < 0.0
    }

    /// Yellow to dark red over the tensions' range; with compression, light to dark blue from 0
    /// to the smallest τ, and yellow to dark red from 0 to the largest.
    pub fn colour(&self, tension: f64) -> RGBColor {
        if self.has_compression() {
            return if tension >= 0.0 {
                tension_colour(tension / self.hi.max(f64::MIN_POSITIVE))
            } else {
                compression_colour(tension / self.lo)
            };
        }
        let span = self.hi - self.lo;
        // All tensions equal: the middle of the ramp.
        if span <= 1e-12 * self.hi.abs().max(f64::MIN_POSITIVE) {
            return tension_colour(0.5);
        }
        tension_colour((tension - self.lo) / span)
    }

    /// The colour at `t` ∈ [0, 1] of the colour bar, which spans [lo, hi].
    pub fn at(&self, t: f64) -> RGBColor {
        self.colour(self.lo + t * (self.hi - self.lo))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_uniform_tensions_span_the_whole_ramp() {
        let scale = TensionScale::over([2000.0, 2001.0, 2002.0].into_iter());
        assert_eq!(scale.colour(2000.0), tension_colour(0.0));
        assert_eq!(scale.colour(2002.0), tension_colour(1.0));
        assert_eq!(scale.colour(2001.0), tension_colour(0.5));
        let uniform = TensionScale::over([5.0, 5.0].into_iter());
        assert_eq!(uniform.colour(5.0), tension_colour(0.5));
        // With compression, 0 is where the blues end and the tensions' ramp begins.
        let mixed = TensionScale::over([-10.0, 30.0].into_iter());
        assert_eq!(mixed.colour(-10.0), compression_colour(1.0));
        assert_eq!(mixed.colour(30.0), tension_colour(1.0));
        assert_eq!(mixed.colour(0.0), tension_colour(0.0));
    }
}
