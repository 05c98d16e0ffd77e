//! Steps 2–4 of a substructure's set-up (docs/method.md §4 "Linear stage"), beside its local
//! dofs and B_E from the substructure room ([`crate::decomposition::substructure`]): its share
//! of K_G, its interfaces' rows and columns, and the values of K_E.

use super::*;

/// E's share of `K_G(t0) = Σ (t0/L)(I − n nᵀ)` (docs/method.md §8), with `I − n nᵀ = p pᵀ +
/// q qᵀ`, when the model has the prestress's geometric stiffness: per link of E (its index j
/// in E) its two transverse rows p, q on E's dofs and `t0 / L`, links without prestress left
/// out. Empty without it.
pub(super) fn geometric_rows(
    topology: &SubstructureTopology,
    model: &Model,
    local_dof: &[usize],
) -> Vec<(usize, LinkDofs, f64)> {
    if model.prestress_stiffness().is_none() {
        return Vec::new();
    }
    let structure = &model.structure;
    topology
        .links
        .iter()
        .enumerate()
        .flat_map(|(j, &i)| {
            let l = &structure.links[i];
            let (p, q) = transverse_pair(l.direction);
            let w = structure.given_prestress(l) / l.length;
            [
                (j, l.row_along(p, local_dof), w),
                (j, l.row_along(q, local_dof), w),
            ]
        })
        .filter(|&(_, _, w)| w != 0.0)
        .collect()
}

/// E's view of the interfaces it touches (substructure `index`), by increasing interface
/// index: its [`Side`]s, the local dof of each row of U_EΓ (C_E as an index map: an
/// interface node's free components) and the number of macro dofs (columns of R_E).
pub(super) fn interface_sides(
    index: usize,
    interfaces: &[Interface],
    local_dof: &[usize],
) -> (Vec<Side>, Vec<usize>, usize) {
    let mut sides = Vec::new();
    let mut gamma_dofs = Vec::new();
    let mut n_macro = 0;
    for (k, iface) in interfaces.iter().enumerate() {
        let Some(which) = iface.topology.sides.iter().position(|&e| e == index) else {
            continue;
        };
        let rows = iface.basis.nrows();
        let cols = iface.basis.ncols();
        sides.push(Side {
            interface: k,
            which,
            gamma_offset: gamma_dofs.len(),
            macro_offset: n_macro,
            rows,
            cols,
            basis: iface.basis.clone(),
        });
        for (&node, free) in iface.topology.nodes.iter().zip(&iface.free) {
            for c in (0..3).filter(|&c| free[c]) {
                gamma_dofs.push(local_dof[3 * node + c]);
            }
        }
        n_macro += cols;
    }
    (sides, gamma_dofs, n_macro)
}

/// The values of `K_E = B_Eᵀ l B_E + K_G,E + d_m C_Eᵀ C_E` on `pattern` (`links`: E's global
/// link indices, for their search direction in `search`; `geometric`: E's share of `K_G(t0)`,
/// empty without geometric stiffness).
pub(super) fn stiffness(
    pattern: &StiffnessPattern,
    link_dofs: &[LinkDofs],
    geometric: &[(usize, LinkDofs, f64)],
    gamma_dofs: &[usize],
    links: &[usize],
    search: &[f64],
    dm: f64,
) -> Vec<f64> {
    let mut values = vec![0.0; pattern.nnz()];
    pattern.assemble(link_dofs, |j| search[links[j]], &mut values);
    for (j, row, w) in geometric {
        pattern.add_outer(*j, row, *w, &mut values);
    }
    for &d in gamma_dofs {
        values[pattern.diag_slot[d]] += dm;
    }
    values
}
