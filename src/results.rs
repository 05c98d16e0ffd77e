//! Quantities derived from an equilibrium, computed independently of the solver that produced
//! it: equilibrium and complementarity residuals (for checks and tests), deflection, tension.

use crate::linalg::{norm, smallest_eigenvalues, ZERO_MODE_RELATIVE};
use crate::solvers::{relative_unbalance, Equilibrium, Solution, TautStiffness};
use crate::structure::Structure;

/// Every number of a solution is finite (displacements, tensions, stopping measure).
pub fn is_finite(solution: &Solution) -> bool {
    let eq = &solution.equilibrium;
    solution.info.residual.is_finite()
        && eq
            .displacements
            .iter()
            .chain(&eq.tensions)
            .all(|x| x.is_finite())
}

/// Relative equilibrium residual `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)` on the free dofs.
pub fn equilibrium_residual(s: &Structure, eq: &Equilibrium, load: &[f64]) -> f64 {
    let mut r = vec![0.0; s.n_free];
    relative_unbalance(s, &eq.tensions, load, &mut r)
}

/// Relative constitutive residual of every link, from U and τ alone:
/// bars and bilateral cables `τ − t0 − k e`; unilateral cables the violation of
/// `0 ≤ τ ⊥ kλ ≥ 0` with `λ = −e + (τ − t0)/k`, i.e. `min(kλ, τ)`. Normalised by `‖t0‖`
/// (or by `‖τ‖` when there is no prestress).
pub fn constitutive_residual(s: &Structure, eq: &Equilibrium) -> f64 {
    let mut r2 = 0.0;
    let mut scale2 = 0.0;
    for ((l, ld), &tau) in s.links.iter().zip(&s.link_dofs).zip(&eq.tensions) {
        let e = ld.elongation(&eq.displacements);
        let law = tau - l.prestress - l.stiffness * e;
        let violation = if l.unilateral {
            // kλ = k(−e + (τ − t0)/k) = τ − t0 − k e = law
            law.min(tau)
        } else {
            law
        };
        r2 += violation * violation;
        scale2 += l.prestress * l.prestress;
    }
    if scale2 == 0.0 {
        scale2 = eq.tensions.iter().map(|t| t * t).sum();
    }
    if scale2 > 0.0 {
        (r2 / scale2).sqrt()
    } else {
        r2.sqrt()
    }
}

/// Largest nodal displacement magnitude, m.
pub fn max_deflection(s: &Structure, eq: &Equilibrium) -> f64 {
    let full = s.full_displacements(&eq.displacements);
    full.chunks(3)
        // hypot: no overflow to inf for a large but finite displacement.
        .map(|u| u[0].hypot(u[1]).hypot(u[2]))
        .fold(0.0, f64::max)
}

/// Largest cable tension, N (0 without cables).
pub fn max_cable_tension(s: &Structure, eq: &Equilibrium) -> f64 {
    s.links
        .iter()
        .zip(&eq.tensions)
        .filter(|(l, _)| l.kind.is_cable())
        .map(|(_, &t)| t)
        .fold(0.0, f64::max)
}

/// Relative distance `‖a − b‖ / ‖b‖` of two displacement fields.
pub fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let nb = norm(b);
    if nb > 0.0 {
        norm(&d) / nb
    } else {
        norm(&d)
    }
}

/// Smallest eigenvalue (N/m) of the tangent stiffness at an equilibrium: `Bᵀ k B` over the
/// members that carry load there (bars, bilateral cables, taut unilateral cables). How far the
/// structure is from a mechanism (SPEC §2–3); 0 when the taut members form one.
pub fn smallest_tangent_eigenvalue(s: &Structure, eq: &Equilibrium, taut: &TautStiffness) -> f64 {
    let pattern = &taut.pattern;
    let mut values = vec![0.0; pattern.nnz()];
    pattern.assemble(
        &s.link_dofs,
        |i| {
            if eq.slack[i] {
                0.0
            } else {
                s.links[i].stiffness
            }
        },
        &mut values,
    );
    let mut factor = taut.factor.share_symbolic();
    let eig = smallest_eigenvalues(pattern, &values, &mut factor, 4, 60, 1e-10);
    let zero = ZERO_MODE_RELATIVE * pattern.mean_diagonal(&values);
    match eig.values.first() {
        Some(&v) if v > zero => v,
        _ => 0.0,
    }
}
