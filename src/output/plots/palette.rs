//! Colours of the figures: a fixed colour per solver (the same in every figure), the
//! Okabe–Ito qualitative palette for series of α (viridis beyond seven), yellow to dark red for
//! cable tensions, blues for compressions.

use crate::solvers::Method;
use plotters::style::RGBColor;

/// The colour of a solver, the same in every figure ([`Method::colour`]).
pub fn solver_colour(method: Method) -> RGBColor {
    let [r, g, b] = method.colour();
    RGBColor(r, g, b)
}

/// The Okabe–Ito palette (Okabe & Ito, *Color Universal Design*, 2008) without its yellow,
/// which does not show on white, ordered so that neighbours differ in hue and lightness: told
/// apart also by the colour-blind, and on thin lines.
const QUALITATIVE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(230, 159, 0),   // orange
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(0, 0, 0),       // black
];

/// Series `i` of `n` ones in order (α increasing): up to seven, the colours of
/// [`QUALITATIVE`], whose neighbours are told apart (viridis gave α = 0.05 and 0.25 of the
/// paper's sweep two nearly equal dark blues); beyond, `n` samples of viridis from dark purple
/// to green (its light yellow end does not show on white), the legend telling them apart.
pub fn ordered_colour(i: usize, n: usize) -> RGBColor {
    if n <= QUALITATIVE.len() {
        return QUALITATIVE[i.min(QUALITATIVE.len() - 1)];
    }
    let t = if n > 1 {
        i as f64 / (n - 1) as f64
    } else {
        0.0
    };
    viridis(0.85 * t)
}

/// Viridis at `t` ∈ [0, 1] (clamped), linear between nine samples of the map.
pub fn viridis(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (72, 40, 120),
        (62, 73, 137),
        (49, 104, 142),
        (38, 130, 142),
        (31, 158, 137),
        (53, 183, 121),
        (110, 206, 88),
        (253, 231, 37),
    ];
    interpolate(&STOPS, t)
}

/// Cable tension ramp at `t` ∈ [0, 1] of the largest tension: yellow to dark red.
pub fn tension_colour(t: f64) -> RGBColor {
    interpolate(
        &[(254, 204, 92), (253, 141, 60), (227, 26, 28), (128, 0, 38)],
        t,
    )
}

/// Cable compression ramp at `t` ∈ [0, 1] of the largest compression: light to dark blue.
pub fn compression_colour(t: f64) -> RGBColor {
    interpolate(&[(158, 202, 225), (33, 113, 181), (8, 48, 107)], t)
}

fn interpolate(stops: &[(u8, u8, u8)], t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (stops[i], stops[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CIE L*a*b* (D65) of an sRGB colour.
    fn lab(c: RGBColor) -> [f64; 3] {
        let linear = |v: u8| {
            let v = v as f64 / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (linear(c.0), linear(c.1), linear(c.2));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let f = |t: f64| {
            let d: f64 = 6.0 / 29.0;
            if t > d.powi(3) {
                t.cbrt()
            } else {
                t / (3.0 * d * d) + 4.0 / 29.0
            }
        };
        let (fx, fy, fz) = (f(x), f(y), f(z));
        [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
    }

    /// CIE76 colour difference ΔE*ab.
    fn delta_e(a: RGBColor, b: RGBColor) -> f64 {
        let (a, b) = (lab(a), lab(b));
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    /// The paper's sweep (α = 0, 0.05, 0.25, 0.5, 0.75, 1; five curves where α = 0 is left
    /// out): every two neighbouring series differ by ΔE76 ≥ 50, and any two by ≥ 25. ΔE76 ≈ 2.3
    /// is a just-noticeable difference between large patches; on 2-px curves colours look far
    /// closer than on patches, and viridis' neighbours here (ΔE76 20–36) read as one hue.
    #[test]
    fn neighbouring_alpha_series_are_told_apart() {
        for n in [5, 6] {
            let colours: Vec<RGBColor> = (0..n).map(|i| ordered_colour(i, n)).collect();
            for i in 1..n {
                let d = delta_e(colours[i - 1], colours[i]);
                assert!(d >= 50.0, "{n} series: {} and {i}: ΔE76 = {d:.1}", i - 1);
                for j in 0..i {
                    let d = delta_e(colours[j], colours[i]);
                    assert!(d >= 25.0, "{n} series: {j} and {i}: ΔE76 = {d:.1}");
                }
            }
        }
        // Beyond seven series, viridis samples, distinct and in order of lightness.
        let many: Vec<RGBColor> = (0..10).map(|i| ordered_colour(i, 10)).collect();
        assert!(many.windows(2).all(|w| lab(w[1])[0] > lab(w[0])[0]));
    }
}
