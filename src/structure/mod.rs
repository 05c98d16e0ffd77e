//! The discrete structure (docs/method.md §1–2): nodes, links, supports, prestress and load, with the
//! free-dof numbering every solver works in.
//!
//! Invariants: `dof_of[3·node + c]` is the free-dof index of that displacement component or
//! [`CLAMPED`]; free dofs are numbered node by node; `Bᵀ t0 = 0` to round-off.

mod checks;
mod geometry;
mod grid;
mod grouped;
mod nearest_state;
mod share;
mod spec;
mod statics;
mod storage;
mod supports;

pub use checks::{Buckling, BucklingCurve, CableBreaking, CheckedMember, MemberChecks};
pub use geometry::{length_and_direction, transverse_pair, Geometry, Loading, Member, NodeFix};
pub use grid::{module_nodes, GridLayout, GridRole};
pub use grouped::{
    grouped_states, GroupedRefusal, GroupedStates, GROUPED_MAX_ENTRIES, RANK_RELATIVE,
};
pub use nearest_state::{nearest_state, Bounds, Fit, MET_RELATIVE};
pub use spec::{CableSpec, Clamp, GridSpec, LoadPattern, Material, ModuleKind};
pub use statics::{
    equilibrium_counts, mechanism_basis, project_on_self_stress, self_stress_dense,
    self_stress_through, DenseSelfStress, DenseSelfStressRefusal, EquilibriumCounts,
    SelfStressRefusal, DENSE_LIMIT,
};
pub use storage::{StructureSize, BASE_BYTES, BYTES_PER_LINK};

use crate::linalg::SparseRow;

/// A row of the compatibility operator B (docs/method.md §1): `e_i = n·(U_b − U_a)` on the link's free
/// dofs. B is never formed as a matrix.
pub type LinkDofs = SparseRow;

/// Marks a clamped displacement component in [`Structure::dof_of`].
pub const CLAMPED: usize = usize::MAX;

/// What a link is to every solver: a cable (unilateral unless the case says otherwise) or a
/// bar (bilateral). A grid's links also have a role in their module ([`GridRole`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkKind {
    /// A cable (`kind = cable` in a members table; a grid's lower, upper, bracing and
    /// diagonal cables).
    Cable,
    /// A bar (`kind = bar` in a members table; a grid's bars, compressed by the prestress).
    Bar,
}

impl LinkKind {
    /// Every kind but [`LinkKind::Bar`].
    pub fn is_cable(self) -> bool {
        self != LinkKind::Bar
    }

    /// The name output files give a link of a general structure (a grid's links are named by
    /// their [`GridRole`]: [`Structure::kind_name`]).
    pub fn name(self) -> &'static str {
        match self {
            LinkKind::Cable => "cable",
            LinkKind::Bar => "bar",
        }
    }
}

/// A bar or a cable from node `a` to node `b`.
#[derive(Debug, Clone)]
pub struct Link {
    /// The member's id as the user knows it (the link index for grids).
    pub id: u64,
    /// Start node.
    pub a: usize,
    /// End node.
    pub b: usize,
    /// Bar or cable.
    pub kind: LinkKind,
    /// The module the link belongs to (links are never merged across modules).
    pub module: usize,
    /// Unit vector from a to b.
    pub direction: [f64; 3],
    /// Initial length ℓ, m.
    pub length: f64,
    /// Axial stiffness k = E·S/ℓ, N/m.
    pub stiffness: f64,
    /// Prestress t0, N (tension positive), plus `k (e_p − Δℓ0)` where prescribed
    /// displacements impose an elongation `e_p` and the rest length changes by Δℓ0
    /// (docs/method.md §7).
    pub prestress: f64,
    /// Δℓ0, m: the change of the rest length (actuation, temperature; 0 without).
    pub rest_change: f64,
    /// Tension-only: complementarity `0 ≤ τ ⊥ λ ≥ 0` instead of a linear law.
    pub unilateral: bool,
    /// Mass ρ·S·ℓ, kg (0 without a density): the natural modes' mass matrix.
    pub mass: f64,
}

impl Link {
    /// Row i of B on the free dofs numbered by `dof_of` (`3·node + c` → free dof or
    /// [`CLAMPED`]): `e = n·(U_b − U_a)`, clamped components left out.
    pub fn compatibility_row(&self, dof_of: &[usize]) -> LinkDofs {
        self.row_along(self.direction, dof_of)
    }

    /// The row `v·(U_b − U_a)` on the free dofs numbered by `dof_of` (clamped components left
    /// out, zero coefficients kept): with v the member's unit vector, its row of B.
    pub fn row_along(&self, v: [f64; 3], dof_of: &[usize]) -> SparseRow {
        let mut row = SparseRow {
            len: 0,
            dofs: [0; 6],
            coef: [0.0; 6],
        };
        for (node, sign) in [(self.a, -1.0), (self.b, 1.0)] {
            for (k, &vk) in v.iter().enumerate() {
                let d = dof_of[3 * node + k];
                if d != CLAMPED {
                    let i = row.len as usize;
                    row.dofs[i] = d as u32;
                    row.coef[i] = sign * vk;
                    row.len += 1;
                }
            }
        }
        row
    }
}

/// The assembled discrete structure.
#[derive(Debug, Clone)]
pub struct Structure {
    /// Node numbering when the structure is a module grid; `None` for general structures.
    pub layout: Option<GridLayout>,
    /// Per link, its role in its module when the structure is a generated module grid
    /// ([`Geometry::grid_roles`]); `None` for general structures.
    pub grid_roles: Option<Vec<GridRole>>,
    /// Per link, its group label (the members table's `group` column, issue 46); `None`
    /// without one.
    pub groups: Option<Vec<String>>,
    /// Node ids as the user knows them (the CSV's `node`; the index for grids).
    pub node_ids: Vec<u64>,
    /// Initial node positions, m.
    pub nodes: Vec<[f64; 3]>,
    /// Bars and cables; tensions and elongations are indexed like this.
    pub links: Vec<Link>,
    /// Per node: all three components held (at zero or at a prescribed displacement).
    pub clamped: Vec<bool>,
    /// Per global dof `3·node + c`: the prescribed displacement Ud of a held component, m
    /// (zero on free components).
    pub prescribed: Vec<f64>,
    /// Per global dof `3·node + c`: free-dof index, or [`CLAMPED`].
    pub dof_of: Vec<usize>,
    /// Number of free dofs (the unknowns' size).
    pub n_free: usize,
    /// Per link: its free dofs and signs, for applying B and Bᵀ.
    pub link_dofs: Vec<LinkDofs>,
    /// Load at α = 1 on the free dofs, N.
    pub unit_load: Vec<f64>,
    /// Load at α = 1 on held components, N, as `(3·node + c, force)` with the force non-zero:
    /// the point loads and self-weight that fall on a held component. They take no part in
    /// the solve and go straight to the support reactions.
    pub held_load: Vec<(usize, f64)>,
    /// `B_fᵀ (k e_p)` on the free dofs: the nodal forces of the tensions the prescribed
    /// displacements impose (zero without settlements). Solvers that split `τ = t0 + t` and
    /// assume `B_fᵀ t0 = 0` solve under `α F − settlement_force`.
    pub settlement_force: Vec<f64>,
    /// The scale of every prestress, N: the grid's lower cable prestress p, else the largest
    /// `|t0|` of a member.
    pub prestress_scale: f64,
    /// The members' data for the member checks (strength, buckling), when the case gives any
    /// ([`Geometry::checks`]); `None`: no check, and no column of them in the output.
    pub checks: Option<MemberChecks>,
    /// Point masses (`modal.point_mass`): node index and kg on each of its free components,
    /// added to the members' mass in the natural modes (entries on one node add up).
    pub point_masses: Vec<(usize, f64)>,
}

impl Structure {
    /// The grid `spec` under the load pattern `load` (at α = 1): the grid's generated
    /// geometry and clamped nodes, assembled like any other structure.
    pub fn grid(spec: &GridSpec, load: &LoadPattern) -> Structure {
        let (geometry, layout, fixes) = Structure::grid_parts(spec);
        let loading = Loading {
            nodal: load.nodal,
            ..Loading::default()
        };
        let mut s = Structure::new(&geometry, &fixes, &loading);
        s.layout = Some(layout);
        s.prestress_scale = spec.prestress;
        s
    }

    /// The grid of `spec` as a general description: nodes and members, layout, and the nodes
    /// its clamp preset holds.
    pub fn grid_parts(spec: &GridSpec) -> (Geometry, GridLayout, Vec<NodeFix>) {
        let (geometry, layout) = grid::geometry(spec);
        let fixes = supports::clamp_fixes(&layout, spec.clamp);
        (geometry, layout, fixes)
    }

    /// Assemble `geometry` held by `fixes` (later fixes of the same component win) under
    /// `loading` at α = 1.
    ///
    /// Prescribed displacements `Ud` enter as an imposed elongation `e_p = B_p Ud` of every
    /// link (docs/method.md §7): the link's tension is `τ = t0 + k (B_f U_f + e_p)`, so its effective
    /// prestress is `t0 + k e_p`, and [`Structure::settlement_force`] holds `B_fᵀ (k e_p)`.
    /// A change Δℓ0 of a member's rest length (`loading.rest_length_changes`) enters the same
    /// way as `e_p − Δℓ0`: its given prestress becomes `t0 − k Δℓ0`.
    pub fn new(geometry: &Geometry, fixes: &[NodeFix], loading: &Loading) -> Structure {
        let n_nodes = geometry.nodes.len();
        let rest_change = loading.rest_length_change_of(geometry.members.len());
        let mut fixed = vec![false; 3 * n_nodes];
        let mut prescribed = vec![0.0; 3 * n_nodes];
        for fix in fixes {
            for k in 0..3 {
                if fix.dofs[k] {
                    fixed[3 * fix.node + k] = true;
                    prescribed[3 * fix.node + k] = fix.displacement[k];
                }
            }
        }
        let clamped: Vec<bool> = (0..n_nodes)
            .map(|n| (0..3).all(|k| fixed[3 * n + k]))
            .collect();
        let mut dof_of = vec![CLAMPED; 3 * n_nodes];
        let mut n_free = 0;
        for (d, &f) in dof_of.iter_mut().zip(&fixed) {
            if !f {
                *d = n_free;
                n_free += 1;
            }
        }
        let links: Vec<Link> = geometry
            .members
            .iter()
            .zip(&rest_change)
            .map(|(m, &rest_change)| {
                let (length, direction) =
                    length_and_direction(geometry.nodes[m.a], geometry.nodes[m.b]);
                let stiffness = m.young * m.section / length;
                // e_p = n·(Ud_b − Ud_a), the elongation the prescribed displacements impose.
                let imposed: f64 = (0..3)
                    .map(|k| direction[k] * (prescribed[3 * m.b + k] - prescribed[3 * m.a + k]))
                    .sum();
                Link {
                    id: m.id,
                    a: m.a,
                    b: m.b,
                    kind: m.kind,
                    module: m.module,
                    direction,
                    length,
                    stiffness,
                    // t0 + k (e_p − Δℓ0).
                    prestress: m.prestress + stiffness * (imposed - rest_change),
                    rest_change,
                    unilateral: m.kind.is_cable() && geometry.unilateral,
                    mass: m.density * m.section * length,
                }
            })
            .collect();
        let link_dofs: Vec<LinkDofs> = links.iter().map(|l| l.compatibility_row(&dof_of)).collect();
        let mut settlement_force = vec![0.0; n_free];
        for ((l, m), ld) in links.iter().zip(&geometry.members).zip(&link_dofs) {
            let imposed_tension = l.prestress - m.prestress;
            if imposed_tension != 0.0 {
                ld.scatter(imposed_tension, &mut settlement_force);
            }
        }
        let mut unit_load = vec![0.0; n_free];
        // Per global dof: the point loads and self-weight that fall on a held component. The
        // nodal load is the force on every free component only (the paper's "free node").
        let mut on_held = vec![0.0; 3 * n_nodes];
        let mut add = |node: usize, force: [f64; 3], held_too: bool| {
            for k in 0..3 {
                let d = dof_of[3 * node + k];
                if d != CLAMPED {
                    unit_load[d] += force[k];
                } else if held_too {
                    on_held[3 * node + k] += force[k];
                }
            }
        };
        for node in 0..n_nodes {
            add(node, loading.nodal, false);
        }
        for &(node, force) in &loading.points {
            add(node, force, true);
        }
        if let Some(g) = loading.gravity {
            for (m, l) in geometry.members.iter().zip(&links) {
                // ρ S ℓ g / 2 on each end (docs/method.md §7).
                let half = m.density * m.section * l.length / 2.0;
                let w = [half * g[0], half * g[1], half * g[2]];
                add(m.a, w, true);
                add(m.b, w, true);
            }
        }
        let held_load: Vec<(usize, f64)> = on_held
            .into_iter()
            .enumerate()
            .filter(|&(_, f)| f != 0.0)
            .collect();
        let prestress_scale = geometry
            .members
            .iter()
            .fold(0.0, |s: f64, m| s.max(m.prestress.abs()));
        Structure {
            layout: None,
            grid_roles: geometry.grid_roles.clone(),
            groups: geometry.groups.clone(),
            node_ids: geometry.node_ids.clone(),
            nodes: geometry.nodes.clone(),
            links,
            clamped,
            prescribed,
            dof_of,
            n_free,
            link_dofs,
            unit_load,
            held_load,
            settlement_force,
            prestress_scale,
            checks: geometry.checks.clone(),
            point_masses: Vec::new(),
        }
    }

    /// `Bᵀ t0` per node (free components only, prescribed ones zero), with each node's scale
    /// `Σ |t0|` of the links meeting there: the prestress is admissible where the first is
    /// at round-off against the second (docs/method.md §7).
    pub fn free_prestress_imbalance(&self) -> Vec<([f64; 3], f64)> {
        let mut out = vec![([0.0; 3], 0.0); self.n_nodes()];
        for l in &self.links {
            for (node, sign) in [(l.a, -1.0), (l.b, 1.0)] {
                for k in 0..3 {
                    if self.dof_of[3 * node + k] != CLAMPED {
                        out[node].0[k] += sign * l.prestress * l.direction[k];
                    }
                }
                out[node].1 += l.prestress.abs();
            }
        }
        out
    }

    /// Link `i`'s group label, when the members table has a `group` column.
    pub fn group_of(&self, i: usize) -> Option<&str> {
        self.groups.as_ref().map(|g| g[i].as_str())
    }

    /// Link `i`'s role in its module, on a generated module grid.
    pub fn grid_role(&self, i: usize) -> Option<GridRole> {
        self.grid_roles.as_ref().map(|roles| roles[i])
    }

    /// The name output files give link `i` (the `kind` column): its grid role's on a module
    /// grid (`lower`, `upper`, `bracing`, `diagonal`, `bar`), else its kind's (`cable`, `bar`).
    pub fn kind_name(&self, i: usize) -> &'static str {
        match self.grid_role(i) {
            Some(role) => role.name(),
            None => self.links[i].kind.name(),
        }
    }

    /// Number of nodes, clamped ones included.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Which of x, y, z of `node` are held (clamped, or held by `supports.fix`).
    pub fn held_components(&self, node: usize) -> [bool; 3] {
        [0, 1, 2].map(|c| self.dof_of[3 * node + c] == CLAMPED)
    }

    /// The elongation a link's prescribed end displacements impose on the initial geometry,
    /// `e_p = n·(Ud_b − Ud_a)`: [`Link::prestress`] holds `t0 + k e_p`.
    pub fn imposed_elongation(&self, l: &Link) -> f64 {
        (0..3)
            .map(|k| l.direction[k] * (self.prescribed[3 * l.b + k] - self.prescribed[3 * l.a + k]))
            .sum()
    }

    /// The given prestress t0 of a link, without the `k e_p` its prescribed end displacements
    /// impose ([`Link::prestress`] holds `t0 + k (e_p − Δℓ0)`): `t0 − k Δℓ0`, the tension of
    /// the member on the initial geometry once its rest length changed.
    #[inline]
    pub fn given_prestress(&self, l: &Link) -> f64 {
        l.prestress - l.stiffness * self.imposed_elongation(l)
    }

    /// The self-stress t0 of a link as the case gives it, before any change of its rest
    /// length: what the prestress's stability, strain and slack margin are judged on.
    #[inline]
    pub fn self_stress(&self, l: &Link) -> f64 {
        self.given_prestress(l) + l.stiffness * l.rest_change
    }

    /// The nodes' bounding box, m: `[min, max]` per axis (infinite bounds without nodes).
    pub fn bounding_box(&self) -> [[f64; 2]; 3] {
        std::array::from_fn(|k| {
            self.nodes
                .iter()
                .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], x| {
                    [lo.min(x[k]), hi.max(x[k])]
                })
        })
    }

    /// The structure's own size: the diagonal of its nodes' bounding box, m.
    pub fn size(&self) -> f64 {
        self.bounding_box()
            .iter()
            .map(|[lo, hi]| (hi - lo).max(0.0).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// Number of cables (every link but the bars).
    pub fn n_cables(&self) -> usize {
        self.links.iter().filter(|l| l.kind.is_cable()).count()
    }

    /// Number of bars.
    pub fn n_bars(&self) -> usize {
        self.links.len() - self.n_cables()
    }

    /// Length variations `e = B U` of every link, U on the free dofs (docs/method.md §1).
    pub fn elongations(&self, u: &[f64], e: &mut [f64]) {
        for (ei, ld) in e.iter_mut().zip(&self.link_dofs) {
            *ei = ld.elongation(u);
        }
    }

    /// Nodal forces `Bᵀ t` on the free dofs, accumulated into `f` (which is zeroed first).
    pub fn nodal_forces(&self, t: &[f64], f: &mut [f64]) {
        f.iter_mut().for_each(|x| *x = 0.0);
        for (&ti, ld) in t.iter().zip(&self.link_dofs) {
            ld.scatter(ti, f);
        }
    }

    /// `max |Bᵀ t0|` over all dofs, clamped ones included: zero for a self-balanced prestress.
    pub fn prestress_imbalance(&self) -> f64 {
        let mut f = vec![0.0; 3 * self.nodes.len()];
        for l in &self.links {
            for k in 0..3 {
                let fk = l.prestress * l.direction[k];
                f[3 * l.a + k] -= fk;
                f[3 * l.b + k] += fk;
            }
        }
        f.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// Expand free-dof displacements to all `3·nodes` components (held ones at their
    /// prescribed value, zero when clamped).
    pub fn full_displacements(&self, u: &[f64]) -> Vec<f64> {
        self.dof_of
            .iter()
            .zip(&self.prescribed)
            .map(|(&d, &ud)| if d == CLAMPED { ud } else { u[d] })
            .collect()
    }

    /// A change `du` of the free dofs on every node's three components, zero where a component
    /// is held (a settlement is no part of a change).
    pub fn full_change(&self, du: &[f64]) -> Vec<f64> {
        self.dof_of
            .iter()
            .map(|&d| if d == CLAMPED { 0.0 } else { du[d] })
            .collect()
    }
}
