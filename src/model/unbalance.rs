//! The unbalance of nodal forces, `r = Bᵀτ − F`, and its sizes relative to the forces meeting
//! at the nodes: what r(U) is made of, on the initial geometry or on rows of the current one.

use crate::linalg::{norm, SparseRow};
use crate::structure::Structure;

/// `r ← Bᵀτ − F` (the energy's gradient) and its relative size
/// `‖r‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)` on the free dofs: the first of [`unbalances`].
pub fn relative_unbalance(s: &Structure, tensions: &[f64], load: &[f64], r: &mut [f64]) -> f64 {
    unbalances(s, tensions, load, r).relative
}

/// `r ← Bᵀτ − F` and two relative sizes of it, in one pass over the links: r(U),
/// `‖r‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)`, and its size relative to the forces the load brings into play,
/// `‖r‖ / (‖F‖ + ‖|B|ᵀ|τ − t0|‖)` (newton's stopping measure).
///
/// The prestress t0 is left out of the second scale: it is self-balanced, and counted in the
/// scale it let `U = 0` pass as converged at `lower_cable = 1e12` (issue 13, D5a). When load
/// and deformation both vanish exactly (U = 0 under F = 0), the prestress forces are the scale.
pub fn unbalances(s: &Structure, tensions: &[f64], load: &[f64], r: &mut [f64]) -> Unbalances {
    unbalances_on(s, &s.link_dofs, tensions, None, load, r)
}

/// [`unbalances`] with the members' rows given (`B` on the initial geometry, or `∇ℓ` on the
/// current one: docs/method.md §8) and, when the model has one, a geometric force `K_G U` added
/// to `Bᵀτ` (counted in both scales as `|K_G U|`).
pub fn unbalances_on(
    s: &Structure,
    rows: &[SparseRow],
    tensions: &[f64],
    geometric_force: Option<&[f64]>,
    load: &[f64],
    r: &mut [f64],
) -> Unbalances {
    r.iter_mut().for_each(|ri| *ri = 0.0);
    let mut added = vec![0.0; s.n_free];
    let mut all = vec![0.0; s.n_free];
    for ((&t, ld), link) in tensions.iter().zip(rows).zip(&s.links) {
        let change = t - link.prestress;
        for (d, c) in ld.iter() {
            r[d] += c * t;
            added[d] += (c * change).abs();
            all[d] += (c * t).abs();
        }
    }
    if let Some(g) = geometric_force {
        for (d, &gd) in g.iter().enumerate() {
            r[d] += gd;
            added[d] += gd.abs();
            all[d] += gd.abs();
        }
    }
    r.iter_mut().zip(load).for_each(|(ri, fi)| *ri -= fi);
    let (r_norm, load_norm, all_norm) = (norm(r), norm(load), norm(&all));
    let relative_to = |scale: f64| if scale > 0.0 { r_norm / scale } else { r_norm };
    let load_scale = load_norm + norm(&added);
    Unbalances {
        relative: relative_to(load_norm + all_norm),
        scale: load_norm + all_norm,
        load_relative: relative_to(if load_scale > 0.0 {
            load_scale
        } else {
            all_norm
        }),
    }
}

/// The two sizes of an unbalance [`unbalances`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unbalances {
    /// r(U), `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)`.
    pub relative: f64,
    /// Its scale, `‖F‖ + ‖|B|ᵀ|τ|‖` (N; where it is 0, `relative` is `‖Bᵀτ − F‖` itself).
    pub scale: f64,
    /// `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ − t0|‖)`.
    pub load_relative: f64,
}
