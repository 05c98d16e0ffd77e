//! Colours of the figures: a fixed colour per solver (the same in every figure), viridis for
//! ordered series (α), yellow to dark red for cable tensions, blues for compressions.

use plotters::style::RGBColor;

/// The colour of a solver, the same in every figure.
pub fn solver_colour(name: &str) -> RGBColor {
    match name {
        "newton" => RGBColor(31, 119, 180),
        "pcg-lcp" => RGBColor(255, 127, 14),
        "mono-latin" => RGBColor(44, 160, 44),
        "micro-macro" => RGBColor(148, 103, 189),
        _ => RGBColor(127, 127, 127),
    }
}

/// Series `i` of `n` ordered ones (α increasing): dark purple to green, leaving out viridis'
/// light yellow end, which does not show on white.
pub fn ordered_colour(i: usize, n: usize) -> RGBColor {
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
