//! Whether an equilibrium found by an increment lies on the load path from the last one
//! (docs/method.md §8): the energy at the increment's load convex along the segment between
//! them. One reached across a region where it is not lies on another branch.

use super::{LoadPath, PathSolver, PathState};
use crate::linalg::{dot, norm};
use crate::model::Model;

/// Points (besides the last equilibrium) at which the slope of the energy along an
/// increment's segment is sampled for `LoadPath::on_the_path`.
const SEGMENT_SAMPLES: usize = 4;

impl<S: PathSolver> LoadPath<S> {
    /// Whether the equilibrium of `state` at the increment's load lies on the path from the
    /// last one, `state.u_done`: the energy Π at that load is convex along the segment
    /// between them, its slope `ψ(s) = ∇Π(U_done + s d)·d` (`d = U − U_done`) never
    /// decreasing, sampled at [`SEGMENT_SAMPLES`] points. An equilibrium reached across a
    /// region where Π is concave along d (a snap-through past a limit point: a von Mises arch
    /// passing flat) is not on the path. Near an equilibrium of the path Π is convex (its
    /// tangent is positive definite), so a short enough increment along the path passes.
    pub(super) fn on_the_path(&self, state: &PathState<S::State>) -> bool {
        let point = self.solver.point(&state.step);
        let d: Vec<f64> = point
            .displacements
            .iter()
            .zip(&state.u_done)
            .map(|(u, v)| u - v)
            .collect();
        let size = norm(&d);
        if size == 0.0 || !size.is_finite() {
            return size == 0.0;
        }
        let load_work = dot(&state.load, &d);
        let model: &Model = self.solver.model();
        // ψ(s) = Σ τ ∇ℓ·d − F·d at U_done + s d.
        let slope_at = |fraction: f64| {
            let u: Vec<f64> = state
                .u_done
                .iter()
                .zip(&d)
                .map(|(v, d)| v + fraction * d)
                .collect();
            model.internal_slope(&u, &d) - load_work
        };
        let mut previous = slope_at(0.0);
        // Round-off of ψ: each end is an equilibrium to the tolerance only (|∇Π| up to
        // tolerance × scale there), and ψ(0) is −ΔF·d up to that.
        let noise =
            10.0 * (self.solver.tolerance() + 1e-12) * point.scale * size + 1e-6 * previous.abs();
        for k in 1..=SEGMENT_SAMPLES {
            let slope = match k {
                SEGMENT_SAMPLES => dot(point.gradient, &d),
                _ => slope_at(k as f64 / SEGMENT_SAMPLES as f64),
            };
            if !slope.is_finite() || slope < previous - noise {
                return false;
            }
            previous = slope;
        }
        true
    }
}

/// `‖a − b‖`.
pub(super) fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}
