//! How far the answer of a model on the initial geometry (`linear`, `prestress`) lies from the
//! large-displacement one, by Newton steps of the large model's energy (docs/method.md §8) from
//! that answer. One step understates a far answer (160× on a column near its Euler load, where
//! the step leaves Newton's quadratic region), so [`distance_to_large`] iterates the steps until
//! the change settles: the difference itself, to 1 % of its size. `model.geometry = "auto"`
//! decides by it, and `summary.csv`'s `geometric_term` reports it. Where the steps settle on an
//! equilibrium whose tangent is not positive definite (a straight column past its Euler load),
//! the distance is no verdict: that equilibrium is a saddle of the energy
//! ([`LargeDistance::Unstable`]), and no model on the initial geometry can say so.

use super::uniqueness::CHECKED_UP_TO_DOFS;
use super::{Equilibrium, TautStiffness};
use crate::linalg::SparseCholesky;
use crate::model::material::{self, SlackRule};
use crate::model::{CurrentGeometry, Model};
use crate::structure::Structure;

/// A motion below this fraction of the structure's size is round-off, not a deflection.
const ROUND_OFF_MOTION: f64 = 1e-9;

/// [`distance_to_large`] takes at most this many Newton steps.
pub const DISTANCE_STEPS: usize = 8;

/// [`distance_to_large`] stops once a step changes the answer by less than this fraction of
/// the distance so far (quadratic convergence: the steps after it change it by far less).
pub const DISTANCE_SETTLED: f64 = 0.01;

/// A step that changes the answer by less than this (relative, as [`distance_to_large`]
/// measures) is round-off: the balance of the answer's forces carries about 1e-9 of them (an
/// unloaded grid's steps wander at 1.5–3e-9 without settling on 1 % of themselves).
pub const DISTANCE_ROUND_OFF: f64 = 1e-7;

/// [`distance_to_large`] calls an answer far once its Newton steps have moved it by more than
/// this many times the tolerance (after two steps: one may overshoot).
pub const DISTANCE_FAR: f64 = 4.0;

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
    /// tangent that is not positive definite along them), or were not finite: no distance is
    /// known.
    Unsettled,
    /// The steps settled at this relative difference (`distance`) on a large-displacement
    /// equilibrium whose tangent (the Hessian of §8's energy) has the negative smallest
    /// eigenvalue `eigenvalue`, N/m: a saddle, which a load path would not stay on.
    Unstable {
        /// The relative difference at which the steps settled.
        distance: f64,
        /// The smallest eigenvalue of large's tangent there, N/m.
        eigenvalue: f64,
    },
}

impl LargeDistance {
    /// The relative difference measured (for [`LargeDistance::Far`], how far the steps had
    /// moved the answer when they stopped: the difference is of that order or more); `None`
    /// where none is known.
    pub fn value(self) -> Option<f64> {
        match self {
            LargeDistance::Within(d) | LargeDistance::Beyond(d) | LargeDistance::Far(d) => Some(d),
            LargeDistance::Unstable { distance, .. } => Some(distance),
            LargeDistance::Unsettled => None,
        }
    }

    /// Whether the model on the initial geometry is off: anything but
    /// [`LargeDistance::Within`].
    pub fn off(self) -> bool {
        !matches!(self, LargeDistance::Within(_))
    }
}

/// The difference between `eq` and the large-displacement answer near it, relative to the
/// latter's largest deflection and largest member force: Newton steps of the large model from
/// `eq`, `U ← U − H(U)⁻¹ r(U)` (r the large model's unbalance, H its exact tangent; K with
/// every cable taut where H is not positive definite or beyond [`CHECKED_UP_TO_DOFS`] free
/// dofs), to [`DISTANCE_SETTLED`] of the difference (or [`DISTANCE_ROUND_OFF`]), at most
/// [`DISTANCE_STEPS`]; the larger of
/// `max_node |U' − U| / max_node |U'|` and `max_i |τ'ᵢ − τᵢ| / max_i |τ'ᵢ|` between the answer
/// (U, τ) and where the steps end (U', the large model's forces τ' there). Where they settle,
/// large's tangent there is checked (up to [`CHECKED_UP_TO_DOFS`] free dofs): not positive
/// definite, with a negative eigenvalue, is [`LargeDistance::Unstable`]. `Within(0)` for an
/// answer that does not move.
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
        let settled = last_step <= (DISTANCE_SETTLED * distance).max(DISTANCE_ROUND_OFF);
        if settled {
            if let Some(eigenvalue) = steps.negative_eigenvalue(s, &u, load) {
                return LargeDistance::Unstable {
                    distance,
                    eigenvalue,
                };
            }
        }
        match distance <= tolerance {
            true if settled => return LargeDistance::Within(distance),
            false if settled => return LargeDistance::Beyond(distance),
            // Far only on a convex energy: with H not positive definite the steps are
            // chords along K, which run away from a saddle (a kinked column past its Euler
            // load: 0.5 % after one step, 5 % after seven, for a 400 % difference).
            false
                if step >= 2
                    && distance > DISTANCE_FAR * tolerance
                    && steps.positive_definite != Some(false) =>
            {
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
    /// Whether the last step's H factorized (Cholesky: positive definite); `None` without H.
    positive_definite: Option<bool>,
}

impl<'t> HessianSteps<'t> {
    fn new(taut: &'t TautStiffness) -> Self {
        let small = taut.pattern.n <= CHECKED_UP_TO_DOFS;
        HessianSteps {
            taut,
            hessian: small.then(|| (taut.factor.share_symbolic(), vec![0.0; taut.pattern.nnz()])),
            positive_definite: None,
        }
    }

    /// The smallest eigenvalue of large's tangent at `u`, where it is negative: only where the
    /// last step's H did not factorize (a Cholesky factor is the proof of positive
    /// definiteness), and not at all without H.
    fn negative_eigenvalue(&mut self, s: &Structure, u: &[f64], load: &[f64]) -> Option<f64> {
        let (_, values) = self.hessian.as_mut()?;
        if self.positive_definite? {
            return None;
        }
        let geometry = CurrentGeometry::of(s, u);
        let mut unbalance = vec![0.0; u.len()];
        let (mut trial, _) = geometry.unbalances(s, load, &mut unbalance);
        // A cable at zero tension with its gap closed (within the slack classification's zero)
        // stiffens one way: taut here, as `min_tangent_eigenvalue` counts it, or a guyed mast
        // whose leeward guy sits at zero reads as a saddle.
        let slack = material::slack_flags(s, &trial, SlackRule::Gap);
        for ((t, slack), link) in trial.iter_mut().zip(slack).zip(&s.links) {
            if link.unilateral && !slack {
                *t = t.max(0.0);
            }
        }
        geometry.assemble_tangent(s, &trial, &self.taut.pattern, values);
        let eigenvalue = super::smallest_assembled_eigenvalue(self.taut, values);
        (eigenvalue < 0.0).then_some(eigenvalue)
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
        let positive_definite = factored.is_some();
        // δ = −H⁻¹ r.
        factored
            .unwrap_or(&self.taut.factor)
            .solve_in_place(&mut step);
        self.positive_definite = self.hessian.is_some().then_some(positive_definite);
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
fn large_forces(s: &Structure, u: &[f64]) -> Vec<f64> {
    CurrentGeometry::of(s, u).tensions(s)
}
