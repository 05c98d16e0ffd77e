//! The geometric stiffness of member tensions on the initial geometry (docs/method.md §8),
//! `K_G(τ) = Σ (τ_i / L_i)(I − n nᵀ)`: with the prestress t0, the `prestress` model's
//! linearisation about the prestressed state; with an answer's tensions, the tangent its
//! stability is judged by.

use crate::linalg::{SparseRow, StiffnessPattern};
use crate::structure::{transverse_pair, Link, Structure, CLAMPED};

/// The geometric stiffness of the prestress on the initial geometry,
/// `K_G(t0) = Σ (t0_i / L_i)(I − n nᵀ)` on each member's relative displacement (docs/method.md
/// §8), kept as two transverse rows per member (`I − n nᵀ = p pᵀ + q qᵀ`), each on the
/// member's own dofs, so that it assembles into the stiffness's pattern.
#[derive(Debug, Clone)]
pub struct GeometricStiffness {
    /// Per link: its two transverse rows.
    rows: Vec<[SparseRow; 2]>,
    /// Per link: `t0 / L`, N/m (negative for a compressed bar).
    weights: Vec<f64>,
}

impl GeometricStiffness {
    /// `K_G(t0)` of `s`, with t0 the given prestress: the linearisation about the
    /// prestressed state, settlement or not (a settlement's `k e_p`, which
    /// [`crate::structure::Link::prestress`] holds, would add `K_G(k e_p) U`, second order in
    /// the displacements, 1.6 % to 5 % of the answer on a 5 mm settlement of review/t2's skew
    /// grid).
    pub fn of_prestress(s: &Structure) -> GeometricStiffness {
        GeometricStiffness::with_tensions(s, |l| s.given_prestress(l))
    }

    /// `K_G(t0)` of `s` with t0 the case's self-stress, before any change of the members'
    /// rest lengths ([`Structure::self_stress`]): what the prestress's stability is judged on.
    pub fn of_self_stress(s: &Structure) -> GeometricStiffness {
        GeometricStiffness::with_tensions(s, |l| s.self_stress(l))
    }

    /// `Σ (t(l) / L)(I − n nᵀ)` over the links `l` of `s`.
    fn with_tensions(s: &Structure, t: impl Fn(&Link) -> f64) -> GeometricStiffness {
        let rows = s
            .links
            .iter()
            .map(|l| {
                let (p, q) = transverse_pair(l.direction);
                [l.row_along(p, &s.dof_of), l.row_along(q, &s.dof_of)]
            })
            .collect();
        let weights = s.links.iter().map(|l| t(l) / l.length).collect();
        GeometricStiffness { rows, weights }
    }

    /// `out += sign · K_G,fd U_d` on the free dofs: the geometric force on the free nodes of
    /// the prescribed displacements U_d, per link `(t0/L)(I − n nᵀ)(Ud_b − Ud_a)` on b's free
    /// components and its opposite on a's (zero without settlements).
    pub fn add_settlement_force(&self, s: &Structure, sign: f64, out: &mut [f64]) {
        for (l, &w) in s.links.iter().zip(&self.weights) {
            let relative: [f64; 3] =
                std::array::from_fn(|k| s.prescribed[3 * l.b + k] - s.prescribed[3 * l.a + k]);
            if w == 0.0 || relative.iter().all(|&d| d == 0.0) {
                continue;
            }
            let along: f64 = (0..3).map(|k| l.direction[k] * relative[k]).sum();
            // (I − n nᵀ) ΔU_d, times t0/L.
            for (node, end_sign) in [(l.a, -1.0), (l.b, 1.0)] {
                for (k, (&r, &n)) in relative.iter().zip(&l.direction).enumerate() {
                    let d = s.dof_of[3 * node + k];
                    if d != CLAMPED {
                        out[d] += sign * end_sign * w * (r - along * n);
                    }
                }
            }
        }
    }

    /// `K_G(τ) = Σ (τ_i / L_i)(I − n nᵀ)` on the initial geometry with per-link tensions τ: a
    /// slack cable (τ = 0) carries no geometric stiffness.
    pub fn of_tensions(s: &Structure, tensions: &[f64]) -> GeometricStiffness {
        let mut g = GeometricStiffness::of_prestress(s);
        g.weights = s
            .links
            .iter()
            .zip(tensions)
            .map(|(l, t)| t / l.length)
            .collect();
        g
    }

    /// `values += K_G` (lower triangle on `pattern`, built from the structure's link rows).
    pub fn add_to(&self, pattern: &StiffnessPattern, values: &mut [f64]) {
        for (i, (rows, &w)) in self.rows.iter().zip(&self.weights).enumerate() {
            if w != 0.0 {
                pattern.add_outer(i, &rows[0], w, values);
                pattern.add_outer(i, &rows[1], w, values);
            }
        }
    }

    /// `out += K_G v`.
    pub fn apply_add(&self, v: &[f64], out: &mut [f64]) {
        for (rows, &w) in self.rows.iter().zip(&self.weights) {
            if w != 0.0 {
                for row in rows {
                    row.scatter(w * row.elongation(v), out);
                }
            }
        }
    }

    /// `K_G v`.
    pub fn product(&self, v: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; v.len()];
        self.apply_add(v, &mut out);
        out
    }

    /// `vᵀ K_G v`.
    pub fn quadratic(&self, v: &[f64]) -> f64 {
        self.rows
            .iter()
            .zip(&self.weights)
            .map(|(rows, &w)| {
                rows.iter()
                    .map(|r| {
                        let x = r.elongation(v);
                        w * x * x
                    })
                    .sum::<f64>()
            })
            .sum()
    }

    /// Per link, `|t0 / L|`: the size of its geometric term.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
}

/// `Σ w_i (I − n nᵀ)(U_b − U_a)` on the free dofs (a geometric stiffness with member weights
/// `w_i`, `τ_i / L_i`, applied to U on the initial geometry: docs/method.md §8).
pub fn geometric_force(s: &Structure, weight: impl Fn(usize) -> f64, u: &[f64]) -> Vec<f64> {
    geometric_force_on(s, weight, u, &s.dof_of, s.n_free)
}

/// [`geometric_force`] on the components numbered by `dof_of` (`3·node + c` → index, or
/// [`CLAMPED`]), `n` of them: with every component numbered, the force on held ones too.
pub fn geometric_force_on(
    s: &Structure,
    weight: impl Fn(usize) -> f64,
    u: &[f64],
    dof_of: &[usize],
    n: usize,
) -> Vec<f64> {
    let mut out = vec![0.0; n];
    for (i, l) in s.links.iter().enumerate() {
        let w = weight(i);
        if w == 0.0 {
            continue;
        }
        let (p, q) = transverse_pair(l.direction);
        for v in [p, q] {
            let row = l.row_along(v, dof_of);
            row.scatter(w * row.elongation(u), &mut out);
        }
    }
    out
}
