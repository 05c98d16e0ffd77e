//! The `large` model's kinematics (docs/method.md §8): the members on the current geometry
//! `X + U`, their exact lengths ℓ, and the law `τ = t0 + k (ℓ − L)` along the current unit
//! vectors, whose energy's Hessian is the tangent.

use super::material::{tangent_weight, tension};
use super::prestress::GeometricStiffness;
use super::unbalance::{unbalances_on, Unbalances};
use super::{Kinematics, Model};
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

    /// The member forces τ on this geometry: the trial tensions, a slack cable's clipped to 0.
    pub fn tensions(&self, s: &Structure) -> Vec<f64> {
        s.links
            .iter()
            .zip(self.trial_tensions(s))
            .map(|(l, t)| tension(l, t))
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

    /// The `large` model linearised at U, as a model on the initial-geometry kinematics
    /// (docs/method.md §8, the sequential LCP): the structure on the current geometry `X + U`
    /// (rows of B along the current unit vectors, lengths ℓ), the trial tensions
    /// `t0 + k (ℓ − L)` as its prestress (a slack cable's negative, so that it stays slack
    /// until it is stretched back), `K_G(τ) = Σ (τ/ℓ)(I − n nᵀ)` as its geometric stiffness,
    /// the prescribed displacements already applied. Its energy in ΔU is Π's second-order
    /// model at U on each taut set: its gradient at ΔU = 0 is `∇Π(U)` and its Hessian on the
    /// taut set of U is Π's. `trial`: the trial tensions at U. Without
    /// `geometric_stiffness`, `K_G(τ)` is left out (the material tangent on the current
    /// geometry alone: a modified Newton step).
    pub fn linearised(
        &self,
        s: &Structure,
        u: &[f64],
        trial: &[f64],
        geometric_stiffness: bool,
    ) -> Model {
        let mut moved = s.clone();
        for (v, x) in moved.nodes.iter_mut().enumerate() {
            for (k, xk) in x.iter_mut().enumerate() {
                *xk += component(s, u, v, k, s.prescribed[3 * v + k]);
            }
        }
        moved.prescribed.iter_mut().for_each(|d| *d = 0.0);
        for (i, l) in moved.links.iter_mut().enumerate() {
            l.direction = self.directions[i];
            l.length = self.lengths[i];
            l.prestress = trial[i];
        }
        moved.link_dofs = self.rows.clone();
        // The solvers that split τ = t0 + t take `B_fᵀ t0` to the load (`settlement_force`):
        // here t0 is the trial tension at U, not a balanced prestress.
        moved.settlement_force.iter_mut().for_each(|f| *f = 0.0);
        for (row, &t) in self.rows.iter().zip(trial) {
            row.scatter(t, &mut moved.settlement_force);
        }
        let tensions: Vec<f64> = s
            .links
            .iter()
            .zip(trial)
            .map(|(l, &t)| tension(l, t))
            .collect();
        let kinematics = match geometric_stiffness {
            true => Kinematics::Prestress(GeometricStiffness::of_tensions(&moved, &tensions)),
            false => Kinematics::Linear,
        };
        Model {
            structure: moved,
            kinematics,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::CurrentGeometry;
    use crate::linalg::{norm, StiffnessPattern};
    use crate::model::material::is_taut;
    use crate::structure::{GridSpec, LoadPattern, Structure};

    /// The linearised model at U is Π's second-order model there: its energy's slope at
    /// ΔU = 0 along any d is `∇Π(U)·d + F·d` (the members' part), and its tangent on the
    /// taut set of U is the large model's Hessian, `K_G(τ)` on the current geometry included;
    /// without geometric stiffness, the material part alone.
    #[test]
    fn the_linearised_model_is_the_second_order_model_at_u() {
        let s = Structure::grid(
            &GridSpec {
                modules: [3, 2],
                ..GridSpec::default()
            },
            &LoadPattern::default(),
        );
        // Displacements large enough to turn members and slacken some cables.
        let u: Vec<f64> = (0..s.n_free)
            .map(|i| 0.02 * ((i as f64 * 0.73).sin() + 0.3 * (i as f64 * 1.9).cos()))
            .collect();
        let current = CurrentGeometry::of(&s, &u);
        let trial = current.trial_tensions(&s);
        let taut: Vec<bool> = s
            .links
            .iter()
            .zip(&trial)
            .map(|(l, &t)| is_taut(l, t))
            .collect();
        assert!(taut.iter().any(|t| !t) && taut.iter().filter(|t| **t).count() > 10);
        let linearised = current.linearised(&s, &u, &trial, true);
        let d: Vec<f64> = (0..s.n_free).map(|i| (i as f64 * 0.37).cos()).collect();
        let zero = vec![0.0; s.n_free];
        let (slope, expected) = (
            linearised.internal_slope(&zero, &d),
            super::internal_slope(&s, &u, &d),
        );
        assert!(
            (slope - expected).abs() <= 1e-12 * expected.abs(),
            "{slope} {expected}"
        );
        let pattern = StiffnessPattern::new(s.n_free, &s.link_dofs);
        let mut hessian = vec![0.0; pattern.nnz()];
        current.assemble_tangent(&s, &trial, &pattern, &mut hessian);
        let (mut want, mut got) = (vec![0.0; s.n_free], vec![0.0; s.n_free]);
        pattern.sym_matvec(&hessian, &d, &mut want);
        linearised.tangent_product(&taut, 0.0, &d, &mut got);
        let scale = norm(&want);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-10 * scale, "{g} against {w}");
        }
        // Without K_G(τ): the material tangent on the current geometry, which differs.
        let material = current.linearised(&s, &u, &trial, false);
        material.tangent_product(&taut, 0.0, &d, &mut got);
        let difference: f64 = got.iter().zip(&want).map(|(g, w)| (g - w).abs()).sum();
        assert!(difference > 1e-6 * scale);
    }
}
