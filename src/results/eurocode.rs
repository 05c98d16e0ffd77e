//! EN 1993's member resistances: a strut's flexural buckling resistance (EN 1993-1-1 §6.3.1)
//! and a cable's design resistance (EN 1993-1-11 §6.3). Pure formulas; the member checks
//! (`results::checks`) apply them to an answer.

use crate::structure::BucklingCurve;

/// A strut's flexural buckling by EN 1993-1-1 §6.3.1.2 (cross-section classes 1 to 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlexuralBuckling {
    /// The non-dimensional slenderness `λ̄ = √(A f_y / N_cr)` (6.49).
    pub slenderness: f64,
    /// `Φ = 0.5 [1 + α (λ̄ − 0.2) + λ̄²]`.
    pub phi: f64,
    /// The reduction factor `χ = 1 / (Φ + √(Φ² − λ̄²))`, at most 1 (6.49).
    pub chi: f64,
    /// The design buckling resistance `N_b,Rd = χ A f_y / γ_M1`, N (6.47).
    pub resistance: f64,
}

/// The flexural buckling of a strut of section `area` (m²) and yield strength `f_y` (Pa),
/// elastic critical force `n_cr` (N, `π² E I / L_cr²`), on buckling curve `curve`, with the
/// partial factor `gamma_m1`.
pub fn flexural_buckling(
    area: f64,
    f_y: f64,
    n_cr: f64,
    curve: BucklingCurve,
    gamma_m1: f64,
) -> FlexuralBuckling {
    // λ̄ = √(A f_y / N_cr).
    let slenderness = (area * f_y / n_cr).sqrt();
    // Φ = 0.5 [1 + α (λ̄ − 0.2) + λ̄²].
    let phi = 0.5 * (1.0 + curve.imperfection() * (slenderness - 0.2) + slenderness.powi(2));
    // χ = 1 / (Φ + √(Φ² − λ̄²)) ≤ 1 (λ̄ ≤ 0.2: χ = 1, buckling ignored, §6.3.1.2 (4)).
    let chi = (1.0 / (phi + (phi * phi - slenderness * slenderness).sqrt())).min(1.0);
    FlexuralBuckling {
        slenderness,
        phi,
        chi,
        // N_b,Rd = χ A f_y / γ_M1.
        resistance: chi * area * f_y / gamma_m1,
    }
}

/// A cable's design resistance `F_Rd = F_uk / (1.5 γ_R)` (EN 1993-1-11 (6.3)), N.
pub fn cable_resistance(breaking_load: f64, gamma_r: f64) -> f64 {
    breaking_load / (1.5 * gamma_r)
}
