//! No equilibrium (docs/method.md §8): when slack cables leave a mechanism that the load works on,
//! the energy is unbounded below and a solver's displacements run away along it. The runaway
//! direction is its own certificate, checked here; the driver asks on a doubling schedule so
//! that no solver spins to its cap, and the sweep asks of every answer.

use super::Equilibrium;
use crate::linalg::{dot, norm};
use crate::model::{largest_moving_nodes, Model};
use crate::structure::{Link, LinkDofs, DENSE_LIMIT};

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

/// ... and the members' stretch energy along U, `Σ k e(U)²` (cables where they lengthen), is
/// at most this fraction of the load's work `F·U`: along a runaway the work grows without
/// bound while the stretch stays bounded; at an equilibrium the two are of one size
/// (Clapeyron). The length test alone is not scale-free: on a 256 × 256 grid a converged
/// smooth deflection (r(U) = 1e-12) has every member's length change below 1e-6 of ‖U‖.
const RUNAWAY_ENERGY_RATIO: f64 = 1e-3;

/// A length change along a unit direction at most this (m per m) is the round-off of `B d`,
/// not a stretch: once a runaway ‖U‖ passes 1e16 times its finite part, `B U` is round-off
/// alone, and its `‖U‖ Σ k e(d)²` (1e-3 N·m at ‖U‖ = 1e22 on the simplex) outweighed the work of
/// a small load (issue 42, T8: no equilibrium at α = 1e-6 read as beyond the model).
const ROUNDOFF_ELONGATION: f64 = 1e-12;

/// The no-equilibrium certificate of an answer whose displacements U have run away: with
/// `d = U / ‖U‖`, `B_bars d = 0`, `B_cables d ≤ 0`, `F·d > 0` (to `MECHANISM_TOLERANCE`),
/// the stretch energy negligible against the load's work (`RUNAWAY_ENERGY_RATIO`),
/// and, with the prestress's geometric stiffness, `dᵀ K_G d ≤ 0`. `None` when U is not such a
/// direction (a finite answer, however large, is judged elsewhere) or the model is `large`.
pub fn no_equilibrium(model: &Model, eq: &Equilibrium, load: &[f64]) -> Option<NoEquilibrium> {
    no_equilibrium_along(model, &eq.displacements, load)
}

/// [`no_equilibrium`] of a displacement (or a change of displacements) `u`.
pub fn no_equilibrium_along(model: &Model, u: &[f64], load: &[f64]) -> Option<NoEquilibrium> {
    let d = unit_direction(model, u)?;
    let s = &model.structure;
    let links = s.links.iter().zip(&s.link_dofs).enumerate();
    let part = LinksAlong::of(links.map(|(i, (l, row))| (i, l, row)), &d.direction)?;
    d.certificate(
        model,
        part.stretch,
        part.slack.into_iter().map(|(_, id)| id).collect(),
        load,
    )
}

/// The certificate of an answer's slack set, when its displacements are none (docs/method.md
/// §8: "confirm with the LP on the final slack set"): `d = P F`, the load projected on the
/// mechanisms of the links the answer keeps (bars, taut cables: the null space of their `BᵀB`,
/// dense), tested like any direction. A solver stopped early on a runaway (pcg-lcp's
/// proportioning steps) leaves a U that is no mechanism, though its slack set leaves one.
/// `None` above [`DENSE_LIMIT`] free dofs, without slack cables, under
/// `large`, or when the load does not work on those mechanisms.
pub fn no_equilibrium_of_slack_set(
    model: &Model,
    slack: &[bool],
    load: &[f64],
) -> Option<NoEquilibrium> {
    let s = &model.structure;
    let n = s.n_free;
    if n == 0 || n > DENSE_LIMIT || model.updates_geometry() || !slack.iter().any(|&x| x) {
        return None;
    }
    let mut btb = nalgebra::DMatrix::<f64>::zeros(n, n);
    for (row, _) in s.link_dofs.iter().zip(slack).filter(|(_, &x)| !x) {
        for (p, cp) in row.iter() {
            for (q, cq) in row.iter() {
                btb[(p, q)] += cp * cq;
            }
        }
    }
    let eig = nalgebra::SymmetricEigen::new(btb);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // d = Σ (v·F) v over the null vectors v (eigenvalues of BᵀB below 1e-10 of the largest).
    let mut d = vec![0.0; n];
    for (i, _) in eig
        .eigenvalues
        .iter()
        .enumerate()
        .filter(|(_, &v)| v <= 1e-10 * largest)
    {
        let v = eig.eigenvectors.column(i);
        let along: f64 = v.iter().zip(load).map(|(a, b)| a * b).sum();
        d.iter_mut()
            .zip(v.iter())
            .for_each(|(x, vk)| *x += along * vk);
    }
    if norm(&d) <= MECHANISM_TOLERANCE * norm(load) {
        return None;
    }
    no_equilibrium_along(model, &d, load)
}

/// [`no_equilibrium_of_slack_set`] of an answer whose displacements are no certificate: its
/// own slack set, else the unilateral cables that its U shortens (a solver stopped on a
/// runaway may still hold them taut: pcg-lcp stalled at α = 1e-9 on the simplex with no
/// equilibrium, its diagonals at 1.2e9 N).
pub fn no_equilibrium_of_answer(
    model: &Model,
    eq: &Equilibrium,
    load: &[f64],
) -> Option<NoEquilibrium> {
    let s = &model.structure;
    no_equilibrium_of_slack_set(model, &eq.slack, load).or_else(|| {
        let shortened: Vec<bool> = s
            .links
            .iter()
            .zip(&s.link_dofs)
            .map(|(l, row)| l.unilateral && row.elongation(&eq.displacements) < 0.0)
            .collect();
        (shortened != eq.slack)
            .then(|| no_equilibrium_of_slack_set(model, &shortened, load))
            .flatten()
    })
}

/// `d = U / ‖U‖` and ‖U‖, the direction a certificate is tested along: `None` under the
/// `large` model or for a U of no finite, non-zero size.
pub struct UnitDirection {
    /// `U / ‖U‖`.
    pub direction: Vec<f64>,
    /// ‖U‖.
    pub size: f64,
}

/// The direction of `u`, when a certificate can be tested along it (see [`UnitDirection`]).
pub fn unit_direction(model: &Model, u: &[f64]) -> Option<UnitDirection> {
    if model.updates_geometry() {
        return None;
    }
    let size = norm(u);
    if size.is_nan() || size <= 0.0 || !size.is_finite() {
        return None;
    }
    Some(UnitDirection {
        direction: u.iter().map(|x| x / size).collect(),
        size,
    })
}

/// Some links' part of a certificate along a unit direction d: their stretch energy
/// `Σ k e(d)²` (cables where they lengthen) and the cables that shorten. `None` when one of
/// them rules d out (a bar or bilateral cable stretched, a unilateral cable lengthened).
#[derive(Debug, Clone, Default)]
pub struct LinksAlong {
    /// `Σ k e(d)²` over these links, in their order.
    pub stretch: f64,
    /// The unilateral cables that shorten along d: `(index, id)` with the index the caller's.
    pub slack: Vec<(usize, u64)>,
}

impl LinksAlong {
    /// The part of `links` (`(index, link, its row of B)`) along `d`.
    pub fn of<'a>(
        links: impl Iterator<Item = (usize, &'a Link, &'a LinkDofs)>,
        d: &[f64],
    ) -> Option<LinksAlong> {
        let mut part = LinksAlong::default();
        for (i, l, row) in links {
            let e = row.elongation(d);
            if l.unilateral {
                if e > MECHANISM_TOLERANCE {
                    return None;
                }
                if e < -MECHANISM_TOLERANCE {
                    part.slack.push((i, l.id));
                }
                if e > ROUNDOFF_ELONGATION {
                    part.stretch += l.stiffness * e * e;
                }
            } else if e.abs() > MECHANISM_TOLERANCE {
                return None;
            } else if e.abs() > ROUNDOFF_ELONGATION {
                part.stretch += l.stiffness * e * e;
            }
        }
        Some(part)
    }
}

impl UnitDirection {
    /// The certificate along d once every link has passed ([`LinksAlong`]): the links'
    /// `stretch` in all and the ids of the cables that shorten (`slack_cables`), in link order.
    /// `model` gives the nodes (and K_G(t0) where it has it).
    pub fn certificate(
        &self,
        model: &Model,
        stretch: f64,
        slack_cables: Vec<u64>,
        load: &[f64],
    ) -> Option<NoEquilibrium> {
        let (d, size) = (&self.direction, self.size);
        let work = dot(load, d);
        // Σ k e(U)² = ‖U‖² Σ k e(d)² against F·U = ‖U‖ F·d.
        if size * stretch > RUNAWAY_ENERGY_RATIO * work {
            return None;
        }
        // A direction that shortens no cable (and stretches no member) would be a mechanism
        // of K with every cable taut, which set-up refused: it is round-off, not a runaway
        // (seen on 1024 × 1024 modules: a status step's change of 1e-6 of the answer, every
        // member's length change along it below the tolerance, passed the energy test by its
        // small size).
        if slack_cables.is_empty() {
            return None;
        }
        let stiffened = model
            .prestress_stiffness()
            .is_some_and(|g| g.quadratic(d) > MECHANISM_TOLERANCE * norm(load));
        if work.is_nan() || work <= MECHANISM_TOLERANCE * norm(load) || stiffened {
            return None;
        }
        Some(NoEquilibrium {
            slack_cables,
            mode_nodes: largest_moving_nodes(&model.structure, d, 3),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::{Clamp, GridSpec, LoadPattern, Structure};

    /// A direction that shortens no cable is never a certificate, however the load works on
    /// it: a free grid's rigid translation (every length change exactly 0) under a load along
    /// it is a mechanism of K itself, which set-up refuses (before the guard it passed every
    /// test: no member stretched, no cable lengthened, the load working on it).
    #[test]
    fn a_direction_that_shortens_no_cable_is_no_certificate() {
        let spec = GridSpec {
            modules: [3, 2],
            clamp: Clamp::None,
            ..GridSpec::default()
        };
        let s = Structure::grid(&spec, &LoadPattern::default());
        let load: Vec<f64> = s.unit_load.clone();
        let down: Vec<f64> = (0..s.n_free)
            .map(|d| if d % 3 == 2 { -1e-9 } else { 0.0 })
            .collect();
        assert!(dot(&load, &down) > 0.0);
        assert!(no_equilibrium_along(&Model::linear(s), &down, &load).is_none());
    }
}
