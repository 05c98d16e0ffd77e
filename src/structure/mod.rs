//! The discrete structure (SPEC §1–2): nodes, links, supports, prestress and load, with the
//! free-dof numbering every solver works in.
//!
//! Invariants: `dof_of[3·node + c]` is the free-dof index of that displacement component or
//! [`CLAMPED`]; free dofs are numbered node by node; `Bᵀ t0 = 0` to round-off.

mod grid;
mod spec;
mod supports;

pub use grid::{module_nodes, GridLayout};
pub use spec::{CableSpec, Clamp, GridSpec, LoadPattern, Material, ModuleKind};

use crate::linalg::SparseRow;

/// A row of the compatibility operator B (SPEC §1): `e_i = n·(U_b − U_a)` on the link's free
/// dofs. B is never formed as a matrix.
pub type LinkDofs = SparseRow;

/// Marks a clamped displacement component in [`Structure::dof_of`].
pub const CLAMPED: usize = usize::MAX;

/// What a link is. Cables are unilateral unless the case says otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkKind {
    /// Cable along an edge of a module's lower square (between lower corners).
    LowerCable,
    /// Cable between the upper nodes of a module (edge midpoints at height H).
    UpperCable,
    /// Cable from a lower corner up to an upper node.
    BracingCable,
    /// The braced module's unprestressed diagonals.
    DiagonalCable,
    /// Bar from a lower corner to an upper node: bilateral, compressed by the prestress.
    Bar,
}

impl LinkKind {
    /// Every kind but [`LinkKind::Bar`].
    pub fn is_cable(self) -> bool {
        self != LinkKind::Bar
    }

    /// The name used in output files.
    pub fn name(self) -> &'static str {
        match self {
            LinkKind::LowerCable => "lower",
            LinkKind::UpperCable => "upper",
            LinkKind::BracingCable => "bracing",
            LinkKind::DiagonalCable => "diagonal",
            LinkKind::Bar => "bar",
        }
    }
}

/// A bar or a cable from node `a` to node `b`.
#[derive(Debug, Clone)]
pub struct Link {
    /// Start node.
    pub a: usize,
    /// End node.
    pub b: usize,
    /// Bar or which family of cable.
    pub kind: LinkKind,
    /// The module the link belongs to (links are never merged across modules).
    pub module: usize,
    /// Unit vector from a to b.
    pub direction: [f64; 3],
    /// Initial length ℓ, m.
    pub length: f64,
    /// Axial stiffness k = E·S/ℓ, N/m.
    pub stiffness: f64,
    /// Prestress t0, N (tension positive).
    pub prestress: f64,
    /// Tension-only: complementarity `0 ≤ τ ⊥ λ ≥ 0` instead of a linear law.
    pub unilateral: bool,
}

impl Link {
    /// Row i of B on the free dofs numbered by `dof_of` (`3·node + c` → free dof or
    /// [`CLAMPED`]): `e = n·(U_b − U_a)`, clamped components left out.
    pub fn compatibility_row(&self, dof_of: &[usize]) -> LinkDofs {
        let free = |d: usize| (d != CLAMPED).then_some(d);
        let ends = [(self.a, -1.0), (self.b, 1.0)];
        SparseRow::new(ends.into_iter().flat_map(|(node, sign)| {
            (0..3).map(move |k| (free(dof_of[3 * node + k]), sign * self.direction[k]))
        }))
    }
}

/// The assembled discrete structure.
#[derive(Debug, Clone)]
pub struct Structure {
    /// Node numbering of the grid.
    pub layout: GridLayout,
    /// Initial node positions, m.
    pub nodes: Vec<[f64; 3]>,
    /// Bars and cables; tensions and elongations are indexed like this.
    pub links: Vec<Link>,
    /// Per node: clamped (all three components zero).
    pub clamped: Vec<bool>,
    /// Per global dof `3·node + c`: free-dof index, or [`CLAMPED`].
    pub dof_of: Vec<usize>,
    /// Number of free dofs (the unknowns' size).
    pub n_free: usize,
    /// Per link: its free dofs and signs, for applying B and Bᵀ.
    pub link_dofs: Vec<LinkDofs>,
    /// Load at α = 1 on the free dofs, N.
    pub unit_load: Vec<f64>,
    /// Lower cable prestress p, N (the scale of every prestress).
    pub prestress_scale: f64,
}

impl Structure {
    /// The grid `spec` under the load pattern `load` (at α = 1).
    pub fn grid(spec: &GridSpec, load: &LoadPattern) -> Structure {
        let layout = GridLayout::new(spec.modules[0], spec.modules[1]);
        let (nodes, raw_links) = grid::generate(&layout, spec.length, spec.height, spec.module);
        let p = spec.prestress;
        let links: Vec<Link> = raw_links
            .into_iter()
            .map(|(a, b, kind, module)| {
                let (xa, xb) = (nodes[a], nodes[b]);
                let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
                let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let direction = [d[0] / length, d[1] / length, d[2] / length];
                let material = if kind.is_cable() {
                    spec.cables.material
                } else {
                    spec.bars
                };
                // SPEC §2: force densities p/L (lower cables), 2p/L (the others), bars in
                // compression; the diagonals of the braced module carry none.
                let l = spec.length;
                let density = match kind {
                    LinkKind::LowerCable => p / l,
                    LinkKind::UpperCable | LinkKind::BracingCable => 2.0 * p / l,
                    LinkKind::Bar => -2.0 * p / l,
                    LinkKind::DiagonalCable => 0.0,
                };
                Link {
                    a,
                    b,
                    kind,
                    module,
                    direction,
                    length,
                    stiffness: material.young * material.section / length,
                    prestress: density * length,
                    unilateral: kind.is_cable() && spec.cables.unilateral,
                }
            })
            .collect();
        let clamped = supports::clamped_nodes(&layout, &nodes, spec.clamp);
        let mut dof_of = vec![CLAMPED; 3 * nodes.len()];
        let mut n_free = 0;
        for (node, &c) in clamped.iter().enumerate() {
            if !c {
                for k in 0..3 {
                    dof_of[3 * node + k] = n_free;
                    n_free += 1;
                }
            }
        }
        let link_dofs = links.iter().map(|l| l.compatibility_row(&dof_of)).collect();
        let mut unit_load = vec![0.0; n_free];
        for node in 0..nodes.len() {
            for k in 0..3 {
                let d = dof_of[3 * node + k];
                if d != CLAMPED {
                    unit_load[d] = load.nodal[k];
                }
            }
        }
        Structure {
            layout,
            nodes,
            links,
            clamped,
            dof_of,
            n_free,
            link_dofs,
            unit_load,
            prestress_scale: p,
        }
    }

    /// Number of nodes, clamped ones included.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of cables (every link but the bars).
    pub fn n_cables(&self) -> usize {
        self.links.iter().filter(|l| l.kind.is_cable()).count()
    }

    /// Number of bars.
    pub fn n_bars(&self) -> usize {
        self.links.len() - self.n_cables()
    }

    /// Length variations `e = B U` of every link, U on the free dofs (SPEC §1).
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

    /// Expand free-dof displacements to all `3·nodes` components (clamped ones zero).
    pub fn full_displacements(&self, u: &[f64]) -> Vec<f64> {
        self.dof_of
            .iter()
            .map(|&d| if d == CLAMPED { 0.0 } else { u[d] })
            .collect()
    }
}
