//! The `large` model's kinematics (docs/method.md §8): the members on the current geometry
//! `X + U`, their exact lengths ℓ, and the law `τ = t0 + k (ℓ − L)` along the current unit
//! vectors, whose energy's Hessian is the tangent.

use super::material::{tangent_weight, tension};
use super::unbalance::{unbalances_on, Unbalances};
use crate::linalg::{SparseRow, StiffnessPattern};
use crate::structure::{Link, Structure, CLAMPED};

/// The members on the current geometry `X + U` (docs/method.md §8): per link its current length
/// ℓ and the row `∇ℓ` on the free dofs (the current unit vector n on b's dofs, −n on a's).
#[derive(Debug, Clone)]
pub struct CurrentGeometry {
    /// Current lengths ℓ, m.
    pub lengths: Vec<f64>,
    /// `ℓ − L`, m, computed as `(2 d0·Δu + Δu·Δu) / (ℓ + L)` (d0 the initial member vector, Δu
    /// its ends' relative displacement): no cancellation at small displacements, where
    /// `ℓ − L` by subtraction loses `1e-16 ℓ · k` of tension, above newton's tolerance.
    pub elongations: Vec<f64>,
    /// Current unit vectors n, from a to b.
    pub directions: Vec<[f64; 3]>,
    /// `∇ℓ` on the free dofs, on the same dofs and in the same order as the link's row of B.
    pub rows: Vec<SparseRow>,
}

/// `t0 + k (ℓ − L)` at the elongation `ℓ − L` (docs/method.md §8): the exact length counts the
/// prescribed displacements itself, so the linear `k e_p` is taken out of the prestress.
#[inline]
fn current_trial_tension(s: &Structure, l: &Link, elongation: f64) -> f64 {
    s.given_prestress(l) + l.stiffness * elongation
}

/// `Σ τ ∇ℓ·d` at displacements U (free dofs): the slope along d of the members' energy in
/// the exact-length law (`large`), the work of the tensions at U on the change d — what
/// `∇Π(U)·d` is less the load's `F·d`, without assembling the gradient. d moves free dofs
/// alone (held components do not change).
pub fn internal_slope(s: &Structure, u: &[f64], d: &[f64]) -> f64 {
    let mut slope = 0.0;
    for l in &s.links {
        let (v, len, elongation) = member_vector(s, l, u);
        let trial = current_trial_tension(s, l, elongation);
        let dd: [f64; 3] =
            std::array::from_fn(|k| component(s, d, l.b, k, 0.0) - component(s, d, l.a, k, 0.0));
        // τ ∇ℓ·d = τ n·(d_b − d_a).
        slope += tension(l, trial) * (v[0] * dd[0] + v[1] * dd[1] + v[2] * dd[2]) / len;
    }
    slope
}

/// Component k of node's value in `v` (free dofs), or `held` where the component is held.
#[inline]
fn component(s: &Structure, v: &[f64], node: usize, k: usize, held: f64) -> f64 {
    match s.dof_of[3 * node + k] {
        CLAMPED => held,
        dof => v[dof],
    }
}

/// A member at displacements U (held components at their prescribed value): its current
/// vector `X_b + U_b − X_a − U_a`, its length ℓ, and its elongation ℓ − L.
#[inline]
fn member_vector(s: &Structure, l: &Link, u: &[f64]) -> ([f64; 3], f64, f64) {
    let at = |node: usize, k: usize| component(s, u, node, k, s.prescribed[3 * node + k]);
    let d0: [f64; 3] = std::array::from_fn(|k| s.nodes[l.b][k] - s.nodes[l.a][k]);
    let du: [f64; 3] = std::array::from_fn(|k| at(l.b, k) - at(l.a, k));
    let v: [f64; 3] = std::array::from_fn(|k| d0[k] + du[k]);
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    // ℓ² − L² = 2 d0·Δu + Δu·Δu, so ℓ − L = (ℓ² − L²) / (ℓ + L).
    let squares: f64 = (0..3).map(|k| 2.0 * d0[k] * du[k] + du[k] * du[k]).sum();
    (v, len, squares / (len + l.length))
}

impl CurrentGeometry {
    /// The geometry at displacements U (free dofs; held components at their prescribed value).
    pub fn of(s: &Structure, u: &[f64]) -> CurrentGeometry {
        let mut lengths = Vec::with_capacity(s.links.len());
        let mut elongations = Vec::with_capacity(s.links.len());
        let mut directions = Vec::with_capacity(s.links.len());
        let mut rows = Vec::with_capacity(s.links.len());
        for l in &s.links {
            let (d, len, elongation) = member_vector(s, l, u);
            let n = [d[0] / len, d[1] / len, d[2] / len];
            lengths.push(len);
            elongations.push(elongation);
            directions.push(n);
            rows.push(l.row_along(n, &s.dof_of));
        }
        CurrentGeometry {
            lengths,
            elongations,
            directions,
            rows,
        }
    }

    /// The trial tensions `t0 + k (ℓ − L)` of every member (before a cable's clipping).
    pub fn trial_tensions(&self, s: &Structure) -> Vec<f64> {
        s.links
            .iter()
            .zip(&self.elongations)
            .map(|(l, &e)| current_trial_tension(s, l, e))
            .collect()
    }

    /// `r ← Σ τ ∇ℓ − F` on this geometry (docs/method.md §8: the large model's energy
    /// gradient) and its sizes ([`unbalances_on`]); returns the trial tensions
    /// `t0 + k (ℓ − L)` too.
    pub fn unbalances(&self, s: &Structure, load: &[f64], r: &mut [f64]) -> (Vec<f64>, Unbalances) {
        let trial = self.trial_tensions(s);
        let tensions: Vec<f64> = trial
            .iter()
            .zip(&s.links)
            .map(|(&t, l)| tension(l, t))
            .collect();
        let sizes = unbalances_on(s, &self.rows, &tensions, None, load, r);
        (trial, sizes)
    }

    /// `values = Σ [[G, −G], [−G, G]]`, `G = k_t n nᵀ + (τ/ℓ)(I − n nᵀ)` per member (the
    /// Hessian of §8's energy), lower triangle on `pattern`; `trial` the current trial tensions.
    pub fn assemble_tangent(
        &self,
        s: &Structure,
        trial: &[f64],
        pattern: &StiffnessPattern,
        values: &mut [f64],
    ) {
        values.iter_mut().for_each(|v| *v = 0.0);
        let mut entries = Vec::with_capacity(6);
        for (i, l) in s.links.iter().enumerate() {
            let t = trial[i];
            let (axial, transverse) = (tangent_weight(l, t), tension(l, t) / self.lengths[i]);
            let n = self.directions[i];
            // G = k_t n nᵀ + (τ/ℓ)(I − n nᵀ).
            let g: [[f64; 3]; 3] = std::array::from_fn(|a| {
                std::array::from_fn(|b| {
                    let identity = if a == b { 1.0 } else { 0.0 };
                    axial * n[a] * n[b] + transverse * (identity - n[a] * n[b])
                })
            });
            entries.clear();
            for (node, sign) in [(l.a, -1.0), (l.b, 1.0)] {
                for k in 0..3 {
                    let d = s.dof_of[3 * node + k];
                    if d != CLAMPED {
                        entries.push((d, sign, k));
                    }
                }
            }
            pattern.add_block(i, &entries, &g, values);
        }
    }
}
