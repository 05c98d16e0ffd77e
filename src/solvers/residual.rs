//! The relative equilibrium residual of a set of tensions (SPEC §6): the unbalance of the
//! nodal forces against the forces meeting at the nodes. newton stops on it; results checks
//! every solver's answer with it.

use crate::linalg::norm;
use crate::structure::Structure;

/// `r ← Bᵀτ − F` (the energy's gradient) and its relative size
/// `‖r‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)` on the free dofs.
pub fn relative_unbalance(s: &Structure, tensions: &[f64], load: &[f64], r: &mut [f64]) -> f64 {
    s.nodal_forces(tensions, r);
    let mut magnitude = vec![0.0; s.n_free];
    for (t, ld) in tensions.iter().zip(&s.link_dofs) {
        for (d, c) in ld.iter() {
            magnitude[d] += (c * t).abs();
        }
    }
    r.iter_mut().zip(load).for_each(|(ri, fi)| *ri -= fi);
    let scale = norm(load) + norm(&magnitude);
    if scale > 0.0 {
        norm(r) / scale
    } else {
        norm(r)
    }
}
