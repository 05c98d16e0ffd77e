//! No equilibrium (docs/method.md §8): when slack cables leave a mechanism that the load works on,
//! the energy is unbounded below and a solver's displacements run away along it. The runaway
//! direction is its own certificate, checked here; the driver asks on a doubling schedule so
//! that no solver spins to its cap, and the sweep asks of every answer.

use super::Equilibrium;
use crate::linalg::{dot, norm};
use crate::structure::{largest_moving_nodes, GeometricModel, Structure};

/// Why an answer is no equilibrium (docs/method.md §8): a direction d that bars and bilateral
/// cables do not stretch, that no unilateral cable lengthens, and on which the load works —
/// the energy decreases without bound along it.
#[derive(Debug, Clone)]
pub struct NoEquilibrium {
    /// The ids of the cables that shorten along d (they go slack), in link order.
    pub slack_cables: Vec<u64>,
    /// The ids of the nodes d moves most, with their motion (d of unit norm).
    pub mode_nodes: Vec<(u64, [f64; 3])>,
}

/// A member's length change along a unit direction at most this (m per m) is none.
const MECHANISM_TOLERANCE: f64 = 1e-6;

/// The no-equilibrium certificate of an answer whose displacements U have run away: with
/// `d = U / ‖U‖`, `B_bars d = 0`, `B_cables d ≤ 0`, `F·d > 0` (to [`MECHANISM_TOLERANCE`]),
/// and, with the prestress's geometric stiffness, `dᵀ K_G d ≤ 0`. `None` when U is not such a
/// direction (a finite answer, however large, is judged elsewhere) or the model is `large`.
pub fn no_equilibrium(s: &Structure, eq: &Equilibrium, load: &[f64]) -> Option<NoEquilibrium> {
    if s.model == GeometricModel::Large {
        return None;
    }
    let size = norm(&eq.displacements);
    if size.is_nan() || size <= 0.0 || !size.is_finite() {
        return None;
    }
    let d: Vec<f64> = eq.displacements.iter().map(|x| x / size).collect();
    let mut slack_cables = Vec::new();
    for (l, row) in s.links.iter().zip(&s.link_dofs) {
        let e = row.elongation(&d);
        if l.unilateral {
            if e > MECHANISM_TOLERANCE {
                return None;
            }
            if e < -MECHANISM_TOLERANCE {
                slack_cables.push(l.id);
            }
        } else if e.abs() > MECHANISM_TOLERANCE {
            return None;
        }
    }
    let work = dot(load, &d);
    let stiffened = s
        .geometric
        .as_ref()
        .is_some_and(|g| g.quadratic(&d) > MECHANISM_TOLERANCE * norm(load));
    if work.is_nan() || work <= MECHANISM_TOLERANCE * norm(load) || stiffened {
        return None;
    }
    Some(NoEquilibrium {
        slack_cables,
        mode_nodes: largest_moving_nodes(s, &d, 3),
    })
}
