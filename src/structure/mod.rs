//! The discrete structure (SPEC §1–2): nodes, links, supports, prestress and load, with the
//! free-dof numbering every solver works in.
//!
//! Invariants: `dof_of[3·node + c]` is the free-dof index of that displacement component or
//! [`CLAMPED`]; free dofs are numbered node by node; `Bᵀ t0 = 0` to round-off.

mod compatibility;
mod grid;
mod supports;

pub use compatibility::LinkDofs;
pub use grid::{module_nodes, GridLayout};

use crate::case::Case;

/// Marks a clamped displacement component in [`Structure::dof_of`].
pub const CLAMPED: usize = usize::MAX;

/// What a link is. Cables are unilateral unless the case says otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkKind {
    LowerCable,
    UpperCable,
    BracingCable,
    /// The braced module's unprestressed diagonals.
    DiagonalCable,
    Bar,
}

impl LinkKind {
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
    pub a: usize,
    pub b: usize,
    pub kind: LinkKind,
    /// The module the link belongs to (links are never merged across modules).
    pub module: usize,
    /// Unit vector from a to b.
    pub direction: [f64; 3],
    pub length: f64,
    /// Axial stiffness k = E·S/ℓ, N/m.
    pub stiffness: f64,
    /// Prestress t0, N (tension positive).
    pub prestress: f64,
    /// Tension-only: complementarity `0 ≤ τ ⊥ λ ≥ 0` instead of a linear law.
    pub unilateral: bool,
}

/// The assembled discrete structure.
#[derive(Debug, Clone)]
pub struct Structure {
    pub layout: GridLayout,
    pub nodes: Vec<[f64; 3]>,
    pub links: Vec<Link>,
    /// Per node: clamped (all three components zero).
    pub clamped: Vec<bool>,
    /// Per global dof `3·node + c`: free-dof index, or [`CLAMPED`].
    pub dof_of: Vec<usize>,
    pub n_free: usize,
    /// Per link: its free dofs and signs, for applying B and Bᵀ.
    pub link_dofs: Vec<LinkDofs>,
    /// Load at α = 1 on the free dofs, N.
    pub unit_load: Vec<f64>,
    /// Lower cable prestress p, N (the scale of every prestress).
    pub prestress_scale: f64,
}

impl Structure {
    pub fn from_case(case: &Case) -> Structure {
        let layout = GridLayout::new(case.grid.modules[0], case.grid.modules[1]);
        let (nodes, raw_links) = grid::generate(
            &layout,
            case.grid.length,
            case.grid.height,
            case.grid.module,
        );
        let p = case.prestress.lower_cable;
        let links: Vec<Link> = raw_links
            .into_iter()
            .map(|(a, b, kind, module)| {
                let (xa, xb) = (nodes[a], nodes[b]);
                let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
                let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let direction = [d[0] / length, d[1] / length, d[2] / length];
                let (young, section) = if kind.is_cable() {
                    (case.cables.young, case.cables.section)
                } else {
                    (case.bars.young, case.bars.section)
                };
                // SPEC §2: force densities p/L (lower cables), 2p/L (the others), bars in
                // compression; the diagonals of the braced module carry none.
                let l = case.grid.length;
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
                    stiffness: young * section / length,
                    prestress: density * length,
                    unilateral: kind.is_cable() && case.cables.unilateral,
                }
            })
            .collect();
        let clamped = supports::clamped_nodes(&layout, &nodes, case.supports.clamp);
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
        let link_dofs = links.iter().map(|l| LinkDofs::new(l, &dof_of)).collect();
        let mut unit_load = vec![0.0; n_free];
        for node in 0..nodes.len() {
            for k in 0..3 {
                let d = dof_of[3 * node + k];
                if d != CLAMPED {
                    unit_load[d] = case.load.nodal[k];
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

    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn n_cables(&self) -> usize {
        self.links.iter().filter(|l| l.kind.is_cable()).count()
    }

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
