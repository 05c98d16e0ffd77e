//! Quantities derived from an equilibrium, computed independently of the solver that produced
//! it: equilibrium and complementarity residuals (for checks and tests), deflection, tension.

pub mod checks;
pub mod eurocode;

// The analyses of an answer, where their users have found them.
pub use crate::analysis::{
    distance_to_large, largest_motion, largest_node_norm, modes, smallest_assembled_eigenvalue,
    smallest_tangent_eigenvalue, uniqueness, LargeDistance, DISTANCE_FAR, DISTANCE_ROUND_OFF,
    DISTANCE_SETTLED, DISTANCE_STEPS, EIGENVALUE_FULL_DOFS, TANGENT_ZERO_RELATIVE,
};

use crate::linalg::norm;
use crate::model::material::{tension, trial_tension};
use crate::model::{geometric_force_on, relative_unbalance, GeometricModel, MemberStates, Model};
use crate::solvers::{Equilibrium, Solution};
use crate::structure::{GridRole, Structure};

/// Every number of a solution is finite (displacements, tensions, stopping measure).
pub fn is_finite(solution: &Solution) -> bool {
    let eq = &solution.equilibrium;
    solution.info.stopping_value.is_finite()
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
    largest_motion(s, &eq.displacements)
}

/// Whether `eq` is beyond the model: a model on the initial geometry (`linear`, `prestress`)
/// whose answer moves a node by more than the structure's own size (the diagonal of its
/// bounding box) has left its domain (a unit slip such as E in GPa, or a load far beyond it).
pub fn beyond_model(model: &Model, eq: &Equilibrium) -> bool {
    let s = &model.structure;
    !model.updates_geometry() && max_deflection(s, eq) > s.size()
}

/// The small-perturbation model (docs/method.md §1: geometry not updated) is trusted while no
/// member's ends move apart, relative to each other, by more than this fraction of its length
/// (about its rotation, in radians).
pub const SMALL_DISPLACEMENT_LIMIT: f64 = 0.1;

/// The largest relative displacement of a member's ends over its length, `max |U_b − U_a| / ℓ`
/// (about the largest member rotation). A whole grid may sag by more than a module height while
/// every member turns by little; this measures what the linearised geometry neglects.
pub fn max_member_rotation(s: &Structure, eq: &Equilibrium) -> f64 {
    let full = s.full_displacements(&eq.displacements);
    s.links
        .iter()
        .map(|l| member_rotation(l, &full))
        .fold(0.0, f64::max)
}

/// `|U_b − U_a| / ℓ` of link `l`, U on every component (`full`).
fn member_rotation(l: &crate::structure::Link, full: &[f64]) -> f64 {
    let (a, b) = (&full[3 * l.a..3 * l.a + 3], &full[3 * l.b..3 * l.b + 3]);
    (b[0] - a[0]).hypot(b[1] - a[1]).hypot(b[2] - a[2]) / l.length
}

/// What a summary row says of an answer beside the solver's own figures.
#[derive(Debug, Clone, PartialEq)]
pub struct AnswerMeasures {
    /// Cables of the structure.
    pub cables: usize,
    /// The largest cable tension, N.
    pub max_tension: f64,
    /// The largest nodal displacement, m.
    pub max_deflection: f64,
    /// r(U), the relative equilibrium residual of the answer's U under the exact law.
    pub equilibrium_residual: f64,
    /// Slack cables per family of [`SLACK_FAMILIES`].
    pub slack_by_kind: [usize; SLACK_FAMILIES.len()],
    /// [`max_member_rotation`].
    pub max_member_rotation: f64,
    /// Whether the model updates the geometry (`large`).
    pub updates_geometry: bool,
    /// The model the answer is of.
    pub geometry: GeometricModel,
}

impl AnswerMeasures {
    /// The measures of `eq` under `load` on the whole model `model`.
    pub fn of(model: &Model, eq: &Equilibrium, load: &[f64]) -> AnswerMeasures {
        let s = &model.structure;
        AnswerMeasures {
            cables: s.n_cables(),
            max_tension: max_cable_tension(s, eq),
            max_deflection: max_deflection(s, eq),
            equilibrium_residual: model.residual(&eq.displacements, load),
            slack_by_kind: slack_by_kind(s, eq),
            max_member_rotation: max_member_rotation(s, eq),
            updates_geometry: model.updates_geometry(),
            geometry: model.geometry(),
        }
    }

    /// The measures of `eq` (whole: U on every dof, tensions and slack flags on every link)
    /// when each process of `exchange` keeps a share of the links: `s` this process's (its
    /// links alone, `world[j]` the whole structure's index of its link j; nodes whole) and
    /// `cables` the whole structure's. Maxima and counts over each share are reduced; r(U)'s
    /// nodal forces `Bᵀτ` and `|B|ᵀ|τ|` are added over the processes in rank order, so r(U)
    /// may differ from [`AnswerMeasures::of`]'s in its last bits. Every process calls it alike.
    /// The small-displacement models only.
    pub fn over_shares(
        model: &Model,
        world: &[usize],
        cables: usize,
        eq: &Equilibrium,
        load: &[f64],
        exchange: &dyn crate::decomposition::Exchange,
    ) -> AnswerMeasures {
        let s = &model.structure;
        let full = s.full_displacements(&eq.displacements);
        // Per share: the largest cable tension and member rotation, the slack counts.
        let mut mine = vec![0.0; 2 + SLACK_FAMILIES.len()];
        let (mut forces, mut magnitudes) = (vec![0.0; s.n_free], vec![0.0; s.n_free]);
        for (j, (l, row)) in s.links.iter().zip(&s.link_dofs).enumerate() {
            let i = world[j];
            if l.kind.is_cable() {
                mine[0] = f64::max(mine[0], eq.tensions[i]);
            }
            mine[1] = f64::max(mine[1], member_rotation(l, &full));
            if eq.slack[i] {
                if let Some(k) = slack_family(s, j) {
                    mine[2 + k] += 1.0;
                }
            }
            // τ(U) under the exact law, as `Model::residual` takes it.
            let t = tension(l, trial_tension(l, row.elongation(&eq.displacements)));
            for (d, c) in row.iter() {
                forces[d] += c * t;
                magnitudes[d] += (c * t).abs();
            }
        }
        let parts = exchange.all_gather(&mine);
        let mut out = [0.0; 2 + SLACK_FAMILIES.len()];
        for part in parts.chunks_exact(mine.len()) {
            out[0] = f64::max(out[0], part[0]);
            out[1] = f64::max(out[1], part[1]);
            for k in 2..out.len() {
                out[k] += part[k];
            }
        }
        forces.extend_from_slice(&magnitudes);
        drop(magnitudes);
        let shares = exchange.all_gather(&forces);
        let n = s.n_free;
        let (mut r, mut all) = (vec![0.0; n], vec![0.0; n]);
        for share in shares.chunks_exact(2 * n) {
            r.iter_mut().zip(&share[..n]).for_each(|(x, y)| *x += y);
            all.iter_mut().zip(&share[n..]).for_each(|(x, y)| *x += y);
        }
        r.iter_mut().zip(load).for_each(|(ri, fi)| *ri -= fi);
        let scale = norm(load) + norm(&all);
        let r_norm = norm(&r);
        AnswerMeasures {
            cables,
            max_tension: out[0],
            max_deflection: max_deflection(s, eq),
            equilibrium_residual: if scale > 0.0 { r_norm / scale } else { r_norm },
            slack_by_kind: std::array::from_fn(|k| out[2 + k] as usize),
            max_member_rotation: out[1],
            updates_geometry: model.updates_geometry(),
            geometry: model.geometry(),
        }
    }
}

/// Per component `3·node + c` of every node, held ones included, the nodal forces of the
/// members: each member's axial force τ (the answer's tensions) along `states.directions` (the
/// initial unit vectors, or the current ones with `large`), `+τ n` at b and `−τ n` at a, i.e.
/// `Bᵀτ` on every component; with `prestress`, plus the prestress's geometric force
/// `K_G(t0) U` as the solver has it (on the free displacements). At a free component it
/// balances the load to the solve's residual; at a held one it is what the support takes.
pub fn member_nodal_forces(model: &Model, eq: &Equilibrium, states: &MemberStates) -> Vec<f64> {
    let s = &model.structure;
    let every: Vec<usize> = (0..3 * s.n_nodes()).collect();
    let mut f = vec![0.0; every.len()];
    for ((l, &t), &n) in s.links.iter().zip(&eq.tensions).zip(&states.directions) {
        l.row_along(n, &every).scatter(t, &mut f);
    }
    if let Some(g) = model.prestress_stiffness() {
        // U on every component, the prescribed U_d included (K_G couples the free nodes to
        // a moved support).
        let u = s.full_displacements(&eq.displacements);
        let weights = g.weights();
        let geometric = geometric_force_on(s, |i| weights[i], &u, &every, every.len());
        f.iter_mut().zip(&geometric).for_each(|(fi, gi)| *fi += gi);
    }
    f
}

/// The reaction of a support on one held component, N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reaction {
    /// The node (index).
    pub node: usize,
    /// 0, 1, 2 for x, y, z.
    pub component: usize,
    /// The force the support puts on the node, N: `R = Bᵀτ − F` there (the members' pull
    /// on the node and the load at that component balanced), with F the load on the held
    /// component at α (`load.point`, self-weight: [`Structure::held_load`]).
    pub force: f64,
}

/// The reaction on every held component at load factor `alpha`, node by node, x, y, z: with
/// the load, they balance the structure as a whole to the solve's residual (`Σ R + Σ F = 0`).
pub fn reactions(
    model: &Model,
    eq: &Equilibrium,
    alpha: f64,
    states: &MemberStates,
) -> Vec<Reaction> {
    let s = &model.structure;
    let mut f = member_nodal_forces(model, eq, states);
    for &(global, load) in &s.held_load {
        f[global] -= alpha * load;
    }
    s.dof_of
        .iter()
        .enumerate()
        .filter(|(_, &d)| d == crate::structure::CLAMPED)
        .map(|(global, _)| Reaction {
            node: global / 3,
            component: global % 3,
            force: f[global],
        })
        .collect()
}

/// `model.tolerance`'s default: a geometric term above 1 % of the answer is worth modelling
/// (`model.geometry = "large"` is recommended).
pub const DEFAULT_MODEL_TOLERANCE: f64 = 0.01;

/// Slack cables per family, in the order of [`SLACK_FAMILIES`].
pub fn slack_by_kind(s: &Structure, eq: &Equilibrium) -> [usize; SLACK_FAMILIES.len()] {
    let mut counts = [0; SLACK_FAMILIES.len()];
    for (i, &slack) in eq.slack.iter().enumerate() {
        if slack {
            if let Some(k) = slack_family(s, i) {
                counts[k] += 1;
            }
        }
    }
    counts
}

/// The cable families `summary.csv` breaks the slack count down by (`slack_{name}` columns):
/// a grid's cables by their [`GridRole`], then a general structure's cables.
pub const SLACK_FAMILIES: [&str; 5] = ["lower", "upper", "bracing", "diagonal", "cable"];

/// The index in [`SLACK_FAMILIES`] of link `i`'s family; `None` for a bar.
fn slack_family(s: &Structure, i: usize) -> Option<usize> {
    match s.grid_role(i) {
        Some(GridRole::LowerCable) => Some(0),
        Some(GridRole::UpperCable) => Some(1),
        Some(GridRole::BracingCable) => Some(2),
        Some(GridRole::DiagonalCable) => Some(3),
        Some(GridRole::Bar) => None,
        None => s.links[i].kind.is_cable().then_some(4),
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::OneProcess;
    use crate::solvers::newton::Newton;
    use crate::solvers::{AnySolver, Silent, TautStiffness};
    use crate::structure::{GridSpec, LoadPattern};

    /// Over one share holding every link the measures are [`AnswerMeasures::of`]'s bit for bit;
    /// over a share that keeps them in another order (`world` its map) the same but for r(U)'s
    /// round-off: the slack families, the largest tension and rotation follow each link.
    #[test]
    fn measures_over_shares_are_the_whole_structures() {
        let model = Model::linear(Structure::grid(
            &GridSpec::default(),
            &LoadPattern::default(),
        ));
        let s = &model.structure;
        let taut = TautStiffness::new(&model).unwrap();
        let mut newton = Newton::new(&model, &taut, Default::default()).unwrap();
        let load: Vec<f64> = s.unit_load.iter().map(|f| 1.0 * f).collect();
        let eq = newton.solve(&load, None, &mut Silent).equilibrium;
        let whole = AnswerMeasures::of(&model, &eq, &load);
        assert_eq!(whole.slack_by_kind.iter().sum::<usize>(), 408);
        let identity: Vec<usize> = (0..s.links.len()).collect();
        let all = model.keeping_links(&identity).unwrap();
        let one =
            AnswerMeasures::over_shares(&all, &identity, s.n_cables(), &eq, &load, &OneProcess);
        assert_eq!(one, whole);
        let reversed: Vec<usize> = identity.iter().rev().copied().collect();
        let kept = model.keeping_links(&reversed).unwrap();
        let other =
            AnswerMeasures::over_shares(&kept, &reversed, s.n_cables(), &eq, &load, &OneProcess);
        let close = (other.equilibrium_residual - whole.equilibrium_residual).abs()
            <= 1e-6 * whole.equilibrium_residual;
        assert!(
            close,
            "{} against {}",
            other.equilibrium_residual, whole.equilibrium_residual
        );
        assert_eq!(
            AnswerMeasures {
                equilibrium_residual: whole.equilibrium_residual,
                ..other
            },
            whole
        );
    }
}
