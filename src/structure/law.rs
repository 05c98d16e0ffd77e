//! The member law and its tangent, in one place (docs/method.md §1, §8): the trial tension
//! `t0 + k e`, the tension (clipped at 0 for unilateral cables), the slack classification and
//! its two policies, the tangent weight, and the geometric terms the model asks
//! for (`model.geometry`): none (`linear`), the prestress's geometric stiffness `K_G(t0)`
//! (`prestress`), or the exact length on the current geometry (`large`). Every solver and
//! `results` ask here; nothing else writes the law.

use super::{Link, Structure, CLAMPED};
use crate::linalg::{SparseRow, StiffnessPattern};
use serde::Deserialize;

/// Which geometric effects the model keeps: the case key `model.geometry`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GeometricModel {
    /// Equilibrium written on the initial geometry (docs/method.md §1, the paper's model).
    #[default]
    Linear,
    /// §1's model plus the geometric stiffness of the prestress, `K + K_G(t0)` (§8): the
    /// linearisation about the prestressed state; stiffens prestress-stable mechanisms.
    Prestress,
    /// The exact-length law `τ = t0 + k (ℓ − L)` on the current geometry, dead loads (§8),
    /// solved by `newton` along the load path.
    Large,
}

impl GeometricModel {
    /// The value of `model.geometry`.
    pub fn name(self) -> &'static str {
        match self {
            GeometricModel::Linear => "linear",
            GeometricModel::Prestress => "prestress",
            GeometricModel::Large => "large",
        }
    }

    /// Whether the model has geometric stiffness (so prestress-stable mechanisms are solvable).
    pub fn has_geometric_stiffness(self) -> bool {
        self != GeometricModel::Linear
    }
}

/// Relative tolerance of the one slack classification ([`SlackRule::Gap`]): a unilateral cable
/// is slack when its gap is open, `λ = −(e + t0/k) > 0`, by more than this fraction of the
/// cables' force scale, i.e. when its trial tension
/// `t0 + k e < −SLACK_GAP_TOLERANCE · max_cables(|t0|, |t0 + k e|)`. A cable at zero tension
/// with a closed gap (an unprestressed cable at rest) is taut. 1e-6 lies well above the
/// round-off of an exact solution (1e-12 of the scale) and well below the trial tension of any
/// cable that is slack on the paper's grids (> 1e-3 of the scale).
pub const SLACK_GAP_TOLERANCE: f64 = 1e-6;

/// The trial tension `t0 + k e` of a member at elongation e (before a cable's clipping).
#[inline]
pub fn trial_tension(link: &Link, elongation: f64) -> f64 {
    link.prestress + link.stiffness * elongation
}

/// τ: the trial tension, clipped at 0 for a unilateral cable (`τ = max(0, t0 + k e)`).
#[inline]
pub fn tension(link: &Link, trial: f64) -> f64 {
    if link.unilateral {
        trial.max(0.0)
    } else {
        trial
    }
}

/// Whether the member carries its axial stiffness at this trial tension: bars and bilateral
/// cables always, unilateral cables when `t0 + k e ≥ 0`.
#[inline]
pub fn is_taut(link: &Link, trial: f64) -> bool {
    !link.unilateral || trial >= 0.0
}

/// The axial tangent weight: k when taut, 0 when slack.
#[inline]
pub fn tangent_weight(link: &Link, trial: f64) -> f64 {
    if is_taut(link, trial) {
        link.stiffness
    } else {
        0.0
    }
}

/// Which unilateral cables count as slack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlackRule {
    /// The energy's own clipping: the tension is exactly 0 (`t0 + k e ≤ 0`). What newton
    /// follows along its steps.
    Clipped,
    /// The one classification every reported answer shares: the gap is open by more than
    /// [`SLACK_GAP_TOLERANCE`] of the cables' force scale.
    Gap,
}

/// Whether `link` with trial tension `trial` is slack by [`SlackRule::Gap`] against the cables'
/// force `scale`: a unilateral cable whose `t0 + k e` lies below −[`SLACK_GAP_TOLERANCE`] of it.
pub fn gap_slack(link: &Link, trial: f64, scale: f64) -> bool {
    link.unilateral && trial < -SLACK_GAP_TOLERANCE * scale
}

/// Whether `link` carries force at trial tension `trial` by the gap rule's zero against the
/// cables' force `scale`: bars and bilateral cables always; a unilateral cable when
/// `t0 + k e > SLACK_GAP_TOLERANCE · scale`. A cable within that zero either way has its gap
/// closed and no force: [`gap_slack`] does not call it slack, yet it resists only elongation
/// (what the uniqueness check, `crate::results::uniqueness`, treats it as, whichever solver
/// found it).
pub fn carries_force(link: &Link, trial: f64, scale: f64) -> bool {
    !link.unilateral || trial > SLACK_GAP_TOLERANCE * scale
}

/// The cables' force scale of [`SlackRule::Gap`] over `links` with their trial tensions:
/// `max(|t0|, |t0 + k e|)` over the unilateral cables (0 without any). A maximum, so the scale
/// of several groups of links is the largest of theirs.
pub fn gap_scale<'a>(links: impl Iterator<Item = (&'a Link, f64)>) -> f64 {
    links
        .filter(|(l, _)| l.unilateral)
        .fold(0.0f64, |m, (l, t)| m.max(l.prestress.abs()).max(t.abs()))
}

/// Per link: a unilateral cable that is slack by `rule`, from the trial tensions.
pub fn slack_flags(s: &Structure, trial: &[f64], rule: SlackRule) -> Vec<bool> {
    match rule {
        SlackRule::Clipped => s
            .links
            .iter()
            .zip(trial)
            .map(|(l, &t)| l.unilateral && tension(l, t) == 0.0)
            .collect(),
        SlackRule::Gap => {
            let scale = gap_scale(s.links.iter().zip(trial.iter().copied()));
            s.links
                .iter()
                .zip(trial)
                .map(|(l, &t)| gap_slack(l, t, scale))
                .collect()
        }
    }
}

/// The trial tension of every link at displacements U (free dofs) under the structure's model:
/// `t0 + k B U` on the initial geometry (`linear`, `prestress`), `t0 + k (ℓ(U) − L)` on the
/// current one (`large`).
pub fn trial_tensions(s: &Structure, u: &[f64]) -> Vec<f64> {
    match s.model {
        GeometricModel::Large => CurrentGeometry::of(s, u).trial_tensions(s),
        _ => s
            .links
            .iter()
            .zip(&s.link_dofs)
            .map(|(l, ld)| trial_tension(l, ld.elongation(u)))
            .collect(),
    }
}

/// The elongation of every link at displacements U under the structure's model: `B U` on the
/// initial geometry, `ℓ(U) − L` with `large` (what the energy error e is measured on).
pub fn elongations(s: &Structure, u: &[f64]) -> Vec<f64> {
    match s.model {
        GeometricModel::Large => CurrentGeometry::of(s, u).elongations,
        _ => s.link_dofs.iter().map(|row| row.elongation(u)).collect(),
    }
}

/// The members at displacements U as the model sees them, for reporting (`forces/`, the
/// reactions): per link its elongation with the prescribed displacements included, its length,
/// and the unit vector its axial force acts along.
#[derive(Debug, Clone)]
pub struct MemberStates {
    /// Elongations, m: `n·(U_b − U_a)` on the initial geometry (the prescribed displacements'
    /// `e_p` included), `ℓ − L` with `large`.
    pub elongations: Vec<f64>,
    /// Lengths, m: the linearised `L + e` on the initial geometry, the current ℓ with `large`.
    pub lengths: Vec<f64>,
    /// Unit vectors from a to b the axial force acts along: the initial ones, or the current
    /// ones with `large`.
    pub directions: Vec<[f64; 3]>,
}

/// [`MemberStates`] at displacements U (free dofs) under the structure's model.
pub fn member_states(s: &Structure, u: &[f64]) -> MemberStates {
    match s.model {
        GeometricModel::Large => {
            let current = CurrentGeometry::of(s, u);
            MemberStates {
                elongations: current.elongations,
                lengths: current.lengths,
                directions: current.directions,
            }
        }
        _ => {
            let elongations: Vec<f64> = s
                .links
                .iter()
                .zip(&s.link_dofs)
                .map(|(l, ld)| ld.elongation(u) + imposed_elongation(s, l))
                .collect();
            MemberStates {
                lengths: s
                    .links
                    .iter()
                    .zip(&elongations)
                    .map(|(l, e)| l.length + e)
                    .collect(),
                elongations,
                directions: s.links.iter().map(|l| l.direction).collect(),
            }
        }
    }
}

/// The elongation a link's prescribed end displacements impose on the initial geometry,
/// `e_p = n·(Ud_b − Ud_a)`: [`Link::prestress`] holds `t0 + k e_p`.
fn imposed_elongation(s: &Structure, l: &Link) -> f64 {
    (0..3)
        .map(|k| l.direction[k] * (s.prescribed[3 * l.b + k] - s.prescribed[3 * l.a + k]))
        .sum()
}

/// The given prestress t0 of a link, without the `k e_p` its prescribed end displacements
/// impose ([`Link::prestress`] holds `t0 + k e_p`).
#[inline]
pub fn given_prestress(s: &Structure, l: &Link) -> f64 {
    l.prestress - l.stiffness * imposed_elongation(s, l)
}

/// `t0 + k (ℓ − L)` at the elongation `ℓ − L` (docs/method.md §8): the exact length counts the
/// prescribed displacements itself, so the linear `k e_p` is taken out of the prestress.
#[inline]
fn current_trial_tension(s: &Structure, l: &Link, elongation: f64) -> f64 {
    given_prestress(s, l) + l.stiffness * elongation
}

/// Two unit vectors orthogonal to the unit vector n and to each other: `I − n nᵀ = p pᵀ + q qᵀ`.
pub fn transverse_pair(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    // Cross with the axis n is least aligned with.
    let axis = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[axis] = 1.0;
    let p = normalised(cross(n, e));
    (p, cross(n, p))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalised(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

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
    /// prestressed state, settlement or not (a settlement's `k e_p`, which [`Link::prestress`]
    /// holds, would add `K_G(k e_p) U`, second order in the displacements, 1.6 % to 5 % of
    /// the answer on a 5 mm settlement of review/t2's skew grid).
    pub fn of_prestress(s: &Structure) -> GeometricStiffness {
        let rows = s
            .links
            .iter()
            .map(|l| {
                let (p, q) = transverse_pair(l.direction);
                [l.row_along(p, &s.dof_of), l.row_along(q, &s.dof_of)]
            })
            .collect();
        let weights = s
            .links
            .iter()
            .map(|l| given_prestress(s, l) / l.length)
            .collect();
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

/// `values = Σ_taut k Bᵢᵀ Bᵢ + K_G(t0)` (the tangent stiffness of the linear and prestress models
/// on the taut set: docs/method.md §3, §8), lower triangle on `pattern`, built from the
/// structure's link rows.
pub fn assemble_tangent(
    s: &Structure,
    pattern: &StiffnessPattern,
    taut: impl Fn(usize) -> bool,
    values: &mut [f64],
) {
    pattern.assemble(
        &s.link_dofs,
        |i| if taut(i) { s.links[i].stiffness } else { 0.0 },
        values,
    );
    if let Some(g) = &s.geometric {
        g.add_to(pattern, values);
    }
}

/// The `prestress` model's tangent at an answer: `Σ_taut k Bᵢᵀ Bᵢ + K_G(τ)`, the geometric
/// stiffness of the answer's own `tensions` (a slack cable has none), into `values` on
/// `pattern` (docs/method.md §8; issue 42, D6).
pub fn assemble_prestress_tangent(
    s: &Structure,
    pattern: &StiffnessPattern,
    taut: impl Fn(usize) -> bool,
    tensions: &[f64],
    values: &mut [f64],
) {
    pattern.assemble(
        &s.link_dofs,
        |i| if taut(i) { s.links[i].stiffness } else { 0.0 },
        values,
    );
    GeometricStiffness::of_tensions(s, tensions).add_to(pattern, values);
}

/// `out = (Σ_taut k Bᵢᵀ Bᵢ + K_G(t0)) v + μ v`, link by link ([`assemble_tangent`]'s matrix).
pub fn tangent_product(s: &Structure, taut: &[bool], mu: f64, v: &[f64], out: &mut [f64]) {
    out.iter_mut().zip(v).for_each(|(o, vi)| *o = mu * vi);
    for ((link, row), _) in s
        .links
        .iter()
        .zip(&s.link_dofs)
        .zip(taut)
        .filter(|(_, &taut)| taut)
    {
        row.scatter(link.stiffness * row.elongation(v), out);
    }
    if let Some(g) = &s.geometric {
        g.apply_add(v, out);
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

/// `Σ τ ∇ℓ·d` at displacements U (free dofs): the slope along d of the members' energy in
/// the exact-length law (`large`), the work of the tensions at U on the change d — what
/// `∇Π(U)·d` is less the load's `F·d`, without assembling the gradient. d moves free dofs
/// alone (held components do not change).
pub fn internal_slope(s: &Structure, u: &[f64], d: &[f64]) -> f64 {
    let component = |v: &[f64], node: usize, k: usize, held: f64| {
        let dof = s.dof_of[3 * node + k];
        if dof == CLAMPED {
            held
        } else {
            v[dof]
        }
    };
    let mut slope = 0.0;
    for l in &s.links {
        let d0: [f64; 3] = std::array::from_fn(|k| s.nodes[l.b][k] - s.nodes[l.a][k]);
        let du: [f64; 3] = std::array::from_fn(|k| {
            component(u, l.b, k, s.prescribed[3 * l.b + k])
                - component(u, l.a, k, s.prescribed[3 * l.a + k])
        });
        let dd: [f64; 3] =
            std::array::from_fn(|k| component(d, l.b, k, 0.0) - component(d, l.a, k, 0.0));
        let v: [f64; 3] = std::array::from_fn(|k| d0[k] + du[k]);
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        // ℓ − L = (2 d0·Δu + Δu·Δu) / (ℓ + L), as in `CurrentGeometry::of`.
        let squares: f64 = (0..3).map(|k| 2.0 * d0[k] * du[k] + du[k] * du[k]).sum();
        let trial = current_trial_tension(s, l, squares / (len + l.length));
        // τ ∇ℓ·d = τ n·(d_b − d_a).
        slope += tension(l, trial) * (v[0] * dd[0] + v[1] * dd[1] + v[2] * dd[2]) / len;
    }
    slope
}

impl CurrentGeometry {
    /// The geometry at displacements U (free dofs; held components at their prescribed value).
    pub fn of(s: &Structure, u: &[f64]) -> CurrentGeometry {
        // U of a component: the free dof's value, or the held component's prescribed one.
        let displacement = |node: usize, k: usize| {
            let d = s.dof_of[3 * node + k];
            if d == CLAMPED {
                s.prescribed[3 * node + k]
            } else {
                u[d]
            }
        };
        let mut lengths = Vec::with_capacity(s.links.len());
        let mut elongations = Vec::with_capacity(s.links.len());
        let mut directions = Vec::with_capacity(s.links.len());
        let mut rows = Vec::with_capacity(s.links.len());
        for l in &s.links {
            let d0: [f64; 3] = std::array::from_fn(|k| s.nodes[l.b][k] - s.nodes[l.a][k]);
            let du: [f64; 3] = std::array::from_fn(|k| displacement(l.b, k) - displacement(l.a, k));
            let d: [f64; 3] = std::array::from_fn(|k| d0[k] + du[k]);
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            // ℓ² − L² = 2 d0·Δu + Δu·Δu, so ℓ − L = (ℓ² − L²) / (ℓ + L).
            let squares: f64 = (0..3).map(|k| 2.0 * d0[k] * du[k] + du[k] * du[k]).sum();
            let n = [d[0] / len, d[1] / len, d[2] / len];
            lengths.push(len);
            elongations.push(squares / (len + l.length));
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

impl Link {
    /// The row `v·(U_b − U_a)` on the free dofs numbered by `dof_of` (clamped components left
    /// out, zero coefficients kept): with v the member's unit vector, its row of B.
    pub fn row_along(&self, v: [f64; 3], dof_of: &[usize]) -> SparseRow {
        let mut row = SparseRow {
            len: 0,
            dofs: [0; 6],
            coef: [0.0; 6],
        };
        for (node, sign) in [(self.a, -1.0), (self.b, 1.0)] {
            for (k, &vk) in v.iter().enumerate() {
                let d = dof_of[3 * node + k];
                if d != CLAMPED {
                    let i = row.len as usize;
                    row.dofs[i] = d as u32;
                    row.coef[i] = sign * vk;
                    row.len += 1;
                }
            }
        }
        row
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transverse_pair_completes_an_orthonormal_basis() {
        for n in [
            [1.0, 0.0, 0.0],
            [0.0, 0.6, 0.8],
            normalised([1.0, -2.0, 0.5]),
        ] {
            let (p, q) = transverse_pair(n);
            let d = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            for (a, b, want) in [
                (p, p, 1.0),
                (q, q, 1.0),
                (p, q, 0.0),
                (p, n, 0.0),
                (q, n, 0.0),
            ] {
                assert!((d(a, b) - want).abs() < 1e-14, "{a:?}·{b:?}");
            }
        }
    }
}
