//! How far the answer of a model on the initial geometry (`linear`, `prestress`) lies from the
//! large-displacement one, by Newton steps of the large model's energy (docs/method.md §8) from
//! that answer. [`geometric_term`] is one step and the change it makes: near the large answer
//! Newton converges quadratically, so a step of relative size ε changes the answer by
//! ε (1 + O(ε)): first-order exact where it says the model is close, and "far" where it is not,
//! but it understates a far answer (up to 2× measured at a few %). [`distance_to_large`]
//! iterates the steps until the change settles: the difference itself, to 1 % of its size,
//! which `model.geometry = "auto"` decides by.

use super::uniqueness::CHECKED_UP_TO_DOFS;
use crate::linalg::SparseCholesky;
use crate::model::{CurrentGeometry, Model};
use crate::solvers::{Equilibrium, TautStiffness};

/// A motion below this fraction of the structure's size is round-off, not a deflection.
const ROUND_OFF_MOTION: f64 = 1e-9;

/// [`distance_to_large`] takes at most this many Newton steps.
pub const DISTANCE_STEPS: usize = 8;

/// [`distance_to_large`] stops once a step changes the answer by less than this fraction of
/// the distance so far (quadratic convergence: the steps after it change it by far less).
pub const DISTANCE_SETTLED: f64 = 0.01;

/// [`distance_to_large`] calls an answer far once its Newton steps have moved it by more than
/// this many times the tolerance (after two steps: one may overshoot).
pub const DISTANCE_FAR: f64 = 4.0;

/// The relative change of the answer that the geometry left out makes: with
/// `δ = −H(U)⁻¹ r(U)`, r the large model's unbalance at the answer U and H its tangent there
/// (the exact Hessian of §8's energy; where it is not positive definite, or beyond
/// [`CHECKED_UP_TO_DOFS`] free dofs, K with every cable taut, whose factor is at hand), the
/// larger of `max_node |δ| / max_node |U + δ|` and `max_i |τᵢ(U + δ) − τᵢ| / max_i |τᵢ(U + δ)|`
/// (the members' forces of the large model after the step against the answer's): the change
/// relative to the largest deflection and the largest member force of the large answer.
/// `None` for `large` (nothing is left out), without displacements, and where the step is
/// not finite.
pub fn geometric_term(
    model: &Model,
    eq: &Equilibrium,
    load: &[f64],
    taut: &TautStiffness,
) -> Option<f64> {
    let u = &eq.displacements;
    if !moves(model, eq) {
        return None;
    }
    let stepped = HessianSteps::new(taut).step(model, u, load);
    let stepped_forces = large_forces(&model.structure, &stepped);
    let term = relative_change(model, (u, &eq.tensions), (&stepped, &stepped_forces));
    term.is_finite().then_some(term)
}

/// How far the answer `eq` of a model on the initial geometry is from `large`'s, as
/// [`distance_to_large`] measures it against `tolerance`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LargeDistance {
    /// The Newton steps settled at this relative difference, at most the tolerance.
    Within(f64),
    /// The Newton steps settled at this relative difference, above the tolerance.
    Beyond(f64),
    /// The Newton steps had moved the answer by this much, more than [`DISTANCE_FAR`] times the
    /// tolerance, when they stopped (not settled: the difference is of that order).
    Far(f64),
    /// The steps did not settle in [`DISTANCE_STEPS`] (a status that keeps changing, a
    /// tangent that is not positive definite), or were not finite: no distance is known.
    Unsettled,
}

/// The difference between `eq` and the large-displacement answer near it, relative to the
/// latter's largest deflection and largest member force (as [`geometric_term`] measures a
/// change): Newton steps of the large model from `eq`, to [`DISTANCE_SETTLED`] of the difference, at
/// most [`DISTANCE_STEPS`]. `Within(0)` for an answer that does not move.
pub fn distance_to_large(
    model: &Model,
    eq: &Equilibrium,
    load: &[f64],
    taut: &TautStiffness,
    tolerance: f64,
) -> LargeDistance {
    if !moves(model, eq) {
        return LargeDistance::Within(0.0);
    }
    let s = &model.structure;
    let mut steps = HessianSteps::new(taut);
    let mut u = eq.displacements.clone();
    let mut forces = large_forces(s, &u);
    for step in 1..=DISTANCE_STEPS {
        let stepped = steps.step(model, &u, load);
        let stepped_forces = large_forces(s, &stepped);
        let to = (&stepped[..], &stepped_forces[..]);
        let distance = relative_change(model, (&eq.displacements, &eq.tensions), to);
        // The step's own size, on the same measure (the large model's forces at both ends).
        let last_step = relative_change(model, (&u, &forces), to);
        (u, forces) = (stepped, stepped_forces);
        if !distance.is_finite() || !last_step.is_finite() {
            return LargeDistance::Unsettled;
        }
        let settled = last_step <= DISTANCE_SETTLED * distance;
        match distance <= tolerance {
            true if settled => return LargeDistance::Within(distance),
            false if settled => return LargeDistance::Beyond(distance),
            false if step >= 2 && distance > DISTANCE_FAR * tolerance => {
                return LargeDistance::Far(distance)
            }
            _ => {}
        }
    }
    LargeDistance::Unsettled
}

/// Whether `eq` moves at all (a model on the initial geometry, with displacements).
fn moves(model: &Model, eq: &Equilibrium) -> bool {
    let deflection = super::largest_motion(&model.structure, &eq.displacements);
    !model.updates_geometry() && deflection.is_finite() && deflection > 0.0
}

/// Newton steps of the large model, `U − H(U)⁻¹ r(U)`, r = Σ τ ∇ℓ − F on the current
/// geometry and H its Hessian there (K with every cable taut where H does not factorize or is
/// too large to): one factor and one value array on K's analysis, refactorized at each step.
struct HessianSteps<'t> {
    taut: &'t TautStiffness,
    /// H's factor and values, when the structure is small enough for them.
    hessian: Option<(SparseCholesky, Vec<f64>)>,
}

impl<'t> HessianSteps<'t> {
    fn new(taut: &'t TautStiffness) -> Self {
        let small = taut.pattern.n <= CHECKED_UP_TO_DOFS;
        HessianSteps {
            taut,
            hessian: small.then(|| (taut.factor.share_symbolic(), vec![0.0; taut.pattern.nnz()])),
        }
    }

    /// One step from `u`: `u − H(u)⁻¹ r(u)`.
    fn step(&mut self, model: &Model, u: &[f64], load: &[f64]) -> Vec<f64> {
        let s = &model.structure;
        let geometry = CurrentGeometry::of(s, u);
        let mut step = vec![0.0; u.len()];
        let (trial, _) = geometry.unbalances(s, load, &mut step);
        let pattern = &self.taut.pattern;
        let factored = self.hessian.as_mut().and_then(|(factor, values)| {
            geometry.assemble_tangent(s, &trial, pattern, values);
            factor
                .factorize(pattern, values)
                .is_ok()
                .then_some(&*factor)
        });
        // δ = −H⁻¹ r.
        factored
            .unwrap_or(&self.taut.factor)
            .solve_in_place(&mut step);
        u.iter().zip(&step).map(|(a, d)| a - d).collect()
    }
}

/// The change from displacements U with member forces τ (`from`) to displacements U' with
/// the large model's forces τ' there (`to`), relative to the latter: the larger of
/// `max_node |U' − U| / max_node |U'|` (U' with its prescribed displacements; the change
/// moves free dofs only) and `max_i |τ'ᵢ − τᵢ| / max_i |τ'ᵢ|`. Motions below
/// [`ROUND_OFF_MOTION`] of the structure's size (an unloaded answer's round-off) are no
/// deflection to be relative to.
fn relative_change(model: &Model, from: (&[f64], &[f64]), to: (&[f64], &[f64])) -> f64 {
    let s = &model.structure;
    let ((u, forces), (stepped, after)) = (from, to);
    let change: Vec<f64> = stepped.iter().zip(u).map(|(a, b)| a - b).collect();
    let change_motion = super::largest_node_norm(&s.full_change(&change));
    let floor = ROUND_OFF_MOTION * s.size();
    let displacement_change = change_motion / super::largest_motion(s, stepped).max(floor);
    let largest_force = after.iter().fold(0.0, |m: f64, t| m.max(t.abs()));
    let force_change = after
        .iter()
        .zip(forces)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    displacement_change.max(if largest_force > 0.0 {
        force_change / largest_force
    } else {
        0.0
    })
}

/// The large model's member forces at `u` (a slack cable's 0).
fn large_forces(s: &crate::structure::Structure, u: &[f64]) -> Vec<f64> {
    CurrentGeometry::of(s, u).tensions(s)
}
