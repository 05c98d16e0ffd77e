//! r(U) of the linear stage's U substructure by substructure (docs/method.md §6): each
//! substructure's links give their forces on its own dofs, in parallel, in cache and on the
//! rank that holds it; a dof held by several substructures sums their pieces in their order
//! (gathered from every rank), and each norm adds per substructure the dofs it owns, then the
//! substructures in their order (the same sums on any number of threads and of ranks). Every
//! link belongs to one substructure, so this is `Bᵀτ(U) − F` term by term, grouped by
//! substructure.

use super::dof_ownership::NOT_SHARED;
use super::neighbours::PIECES_PER_DOF;
use super::{Latin, Substructure};
use crate::linalg::norm;
use crate::model::material;
use crate::structure::Structure;
use rayon::prelude::*;

/// One substructure's links' forces on its dofs (E's numbering).
struct LinkForces {
    /// `B_Eᵀ τ(U)` under the exact law.
    exact: Vec<f64>,
    /// `Σ |B_E| |τ|`, the scale of r(U).
    size: Vec<f64>,
    /// `Σ |B_E| |τ − t0|`, the scale of r_F(U) (the forces the load brings into play).
    added: Vec<f64>,
    /// `B_Eᵀ (τ_frozen − τ)`: what the law linearised at the status changes (mostly zero).
    frozen_change: Vec<f64>,
}

impl Substructure {
    /// E's links' forces at the global displacements `u` (interface nodes averaged): under
    /// the exact law `τ = max(0, t0 + k e)` on unilateral cables, and the change to the law
    /// linearised at `slack` (`τ = t0 + k e` of either sign, 0 on the cables slack in it).
    fn link_forces(&self, structure: &Structure, u: &[f64], slack: &[bool]) -> LinkForces {
        let n = self.dof_global.len();
        let mut out = LinkForces {
            exact: vec![0.0; n],
            size: vec![0.0; n],
            added: vec![0.0; n],
            frozen_change: vec![0.0; n],
        };
        for (row, &i) in self.link_dofs.iter().zip(&self.links) {
            let link = &structure.links[i];
            // e = B U on the initial geometry, with U read through E's dof map.
            let e: f64 = row.iter().map(|(d, c)| c * u[self.dof_global[d]]).sum();
            let trial = material::trial_tension(link, e);
            let t = material::tension(link, trial);
            let frozen = if slack[i] { 0.0 } else { trial };
            for (d, c) in row.iter() {
                out.exact[d] += c * t;
                out.size[d] += (c * t).abs();
                out.added[d] += (c * (t - link.prestress)).abs();
            }
            if frozen != t {
                row.scatter(frozen - t, &mut out.frozen_change);
            }
        }
        out
    }
}

impl Latin<'_> {
    /// `(r(U), r_F(U), r_frozen(U))` as [`crate::model::Model::exact_and_frozen_residuals`]
    /// defines them (the exact law relative to `‖F‖ + ‖|B|ᵀ|τ|‖` and to the load's forces
    /// `‖F‖ + ‖|B|ᵀ|τ − t0|‖`, the law linearised at `slack`), with the links' forces computed substructure by substructure, each
    /// on the rank that holds it. A dof's forces are summed over the substructures holding it
    /// in their order (the values at shared dofs gathered from every rank), and each norm
    /// over the substructures in their order, each adding the dofs it owns: the same numbers
    /// on any number of threads and of ranks. For models without the prestress's geometric
    /// stiffness (the caller checks).
    pub(super) fn residuals_by_substructure(
        &self,
        u: &[f64],
        load: &[f64],
        slack: &[bool],
    ) -> (f64, f64, f64) {
        let s = self.structure;
        let own = self.ranks.dof_ownership();
        let held = self.ranks.held();
        let pieces: Vec<LinkForces> = self.operators.substructures[held.clone()]
            .par_iter()
            .with_min_len(self.ranks.chunk())
            .map(|sub| sub.link_forces(s, u, slack))
            .collect();
        // The pieces at shared dofs, from the ranks holding them, summed in the
        // substructures' order.
        let at_shared = self.pieces_at_shared_dofs(&pieces);
        // Per held substructure, the squares of the dofs it owns: r = Bᵀτ − F,
        // r_frozen = r + Bᵀ(τ_frozen − τ), |B|ᵀ|τ| and |B|ᵀ|τ − t0|.
        let squares: Vec<f64> = self.operators.substructures[held.clone()]
            .par_iter()
            .zip(&pieces)
            .enumerate()
            .with_min_len(self.ranks.chunk())
            .flat_map_iter(|(i, (sub, piece))| {
                let e = (held.start + i) as u32;
                let mut sums = [0.0; 4];
                for (k, &d) in sub.dof_global.iter().enumerate() {
                    if own.owner[d] != e {
                        continue;
                    }
                    let [force, scale, frozen_change, added] = match own.shared_slot[d] {
                        NOT_SHARED => [
                            piece.exact[k],
                            piece.size[k],
                            piece.frozen_change[k],
                            piece.added[k],
                        ],
                        slot => at_shared[slot as usize],
                    };
                    let exact = force - load[d];
                    let frozen = exact + frozen_change;
                    sums[0] += exact * exact;
                    sums[1] += frozen * frozen;
                    sums[2] += scale * scale;
                    sums[3] += added * added;
                }
                sums
            })
            .collect();
        let total = self
            .ranks
            .gather(&squares)
            .chunks(4)
            .fold([0.0; 4], |t, p| {
                [t[0] + p[0], t[1] + p[1], t[2] + p[2], t[3] + p[3]]
            });
        let load_norm = norm(load);
        let relative = |square: f64, scale: f64| {
            let v = square.sqrt();
            if scale > 0.0 {
                v / scale
            } else {
                v
            }
        };
        let scale = load_norm + total[2].sqrt();
        // r_F's scale; where load and deformation both vanish, the prestress's (as
        // `crate::model::unbalances` takes it).
        let load_scale = match load_norm + total[3].sqrt() {
            0.0 => total[2].sqrt(),
            added => added,
        };
        (
            relative(total[0], scale),
            relative(total[0], load_scale),
            relative(total[1], scale),
        )
    }

    /// Per shared dof (by its slot), `Bᵀτ`, `|B|ᵀ|τ|` and `Bᵀ(τ_frozen − τ)` summed over the
    /// substructures holding it in their order, from the `pieces` of the held ones and those
    /// the other ranks give: all of them on one process; point to point from the neighbouring
    /// ranks (the dofs the held substructures share), or gathered from every rank when the
    /// solve shares its whole state at each iteration. The same sums either way.
    fn pieces_at_shared_dofs(&self, pieces: &[LinkForces]) -> Vec<[f64; PIECES_PER_DOF]> {
        let own = self.ranks.dof_ownership();
        let held = self.ranks.held();
        let mine: Vec<Vec<f64>> = pieces
            .iter()
            .zip(&own.shared_local[held.clone()])
            .map(|(piece, shared)| {
                shared
                    .iter()
                    .flat_map(|&k| {
                        let k = k as usize;
                        [
                            piece.exact[k],
                            piece.size[k],
                            piece.frozen_change[k],
                            piece.added[k],
                        ]
                    })
                    .collect()
            })
            .collect();
        let mut at_shared = vec![[0.0; PIECES_PER_DOF]; own.n_shared];
        let mut add = |e: usize, position: usize, v: &[f64]| {
            let k = own.shared_local[e][position] as usize;
            let sums = &mut at_shared[own.slot(self.operators.substructures[e].dof_global[k])];
            sums.iter_mut().zip(v).for_each(|(s, v)| *s += v);
        };
        match (self.ranks.neighbours(), self.ranks.size()) {
            (_, 1) => {
                for (e, values) in held.clone().zip(&mine) {
                    for (position, v) in values.chunks_exact(PIECES_PER_DOF).enumerate() {
                        add(e, position, v);
                    }
                }
            }
            (Some(plan), _) => {
                // (substructure, position in its shared dofs, pieces), put in the
                // substructures' order.
                let mut all = plan.share_pieces(self.ranks.exchange(), |e| &mine[e - held.start]);
                for (e, values) in held.clone().zip(&mine) {
                    for (position, v) in values.chunks_exact(PIECES_PER_DOF).enumerate() {
                        all.push((e, position as u32, [v[0], v[1], v[2], v[3]]));
                    }
                }
                all.sort_by_key(|c| c.0);
                for (e, position, v) in all {
                    add(e, position as usize, &v);
                }
            }
            (None, _) => {
                let all = self.ranks.gather(&mine.concat());
                let mut values = all.chunks_exact(PIECES_PER_DOF);
                for (e, shared) in own.shared_local.iter().enumerate() {
                    for (position, v) in (0..shared.len()).zip(&mut values) {
                        add(e, position, v);
                    }
                }
            }
        }
        at_shared
    }
}
