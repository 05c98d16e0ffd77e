//! Module and grid generator (docs/method.md §2, paper §5.1). Nodes at the same position are one node;
//! links are never merged (a lower edge shared by two modules carries two cables).

use super::{length_and_direction, Geometry, GridSpec, LinkKind, Member, ModuleKind};

/// What a link of the module grid is in its module (docs/method.md §2): which family of
/// cable, or the bar. It fixes the link's prestress, and output files name a grid's links by
/// it; the solvers only see its [`LinkKind`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GridRole {
    /// Cable along an edge of a module's lower square (between lower corners).
    LowerCable,
    /// Cable between the upper nodes of a module (edge midpoints at height H).
    UpperCable,
    /// Cable from a lower corner up to an upper node.
    BracingCable,
    /// The braced module's unprestressed diagonals.
    DiagonalCable,
    /// Bar from a lower corner to an upper node: compressed by the prestress.
    Bar,
}

impl GridRole {
    /// Bar or cable.
    pub fn kind(self) -> LinkKind {
        match self {
            GridRole::Bar => LinkKind::Bar,
            _ => LinkKind::Cable,
        }
    }

    /// The name used in output files.
    pub fn name(self) -> &'static str {
        match self {
            GridRole::LowerCable => "lower",
            GridRole::UpperCable => "upper",
            GridRole::BracingCable => "bracing",
            GridRole::DiagonalCable => "diagonal",
            GridRole::Bar => "bar",
        }
    }
}

/// Node numbering of an `nx × ny` grid: first the lower corners `(i, j)`, then the upper
/// midpoints of edges along x (`(i + ½, j)`), then those of edges along y (`(i, j + ½)`).
#[derive(Debug, Clone, Copy)]
pub struct GridLayout {
    /// Modules along x.
    pub nx: usize,
    /// Modules along y.
    pub ny: usize,
}

impl GridLayout {
    /// The layout of `nx × ny` modules.
    pub fn new(nx: usize, ny: usize) -> Self {
        Self { nx, ny }
    }

    /// Lower node at corner `(i, j)`, `0 ≤ i ≤ nx`, `0 ≤ j ≤ ny`.
    pub fn corner(&self, i: usize, j: usize) -> usize {
        j * (self.nx + 1) + i
    }

    /// Upper node above the midpoint of the x-edge from `(i, j)` to `(i + 1, j)`.
    pub fn x_mid(&self, i: usize, j: usize) -> usize {
        (self.nx + 1) * (self.ny + 1) + j * self.nx + i
    }

    /// Upper node above the midpoint of the y-edge from `(i, j)` to `(i, j + 1)`.
    pub fn y_mid(&self, i: usize, j: usize) -> usize {
        (self.nx + 1) * (self.ny + 1) + self.nx * (self.ny + 1) + j * (self.nx + 1) + i
    }

    /// Number of nodes: lower corners plus upper x- and y-edge midpoints.
    pub fn n_nodes(&self) -> usize {
        (self.nx + 1) * (self.ny + 1) + self.nx * (self.ny + 1) + (self.nx + 1) * self.ny
    }

    /// Index of module `(i, j)`, row by row along x (`0 ≤ i < nx`, `0 ≤ j < ny`).
    pub fn module_index(&self, i: usize, j: usize) -> usize {
        j * self.nx + i
    }
}

/// The 8 nodes of module `(i, j)`: `[c0, c1, c2, c3, m0, m1, m2, m3]`, counter-clockwise
/// (docs/method.md §2).
pub fn module_nodes(layout: &GridLayout, i: usize, j: usize) -> [usize; 8] {
    [
        layout.corner(i, j),
        layout.corner(i + 1, j),
        layout.corner(i + 1, j + 1),
        layout.corner(i, j + 1),
        layout.x_mid(i, j),
        layout.y_mid(i + 1, j),
        layout.x_mid(i, j + 1),
        layout.y_mid(i, j),
    ]
}

/// A link as generated: `(a, b, role, module)`.
pub(super) type RawLink = (usize, usize, GridRole, usize);

/// Node positions and links of the whole grid.
pub(super) fn generate(
    layout: &GridLayout,
    length: f64,
    height: f64,
    module: ModuleKind,
) -> (Vec<[f64; 3]>, Vec<RawLink>) {
    let (nx, ny) = (layout.nx, layout.ny);
    let mut nodes = vec![[0.0; 3]; layout.n_nodes()];
    for j in 0..=ny {
        for i in 0..=nx {
            nodes[layout.corner(i, j)] = [i as f64 * length, j as f64 * length, 0.0];
        }
    }
    for j in 0..=ny {
        for i in 0..nx {
            nodes[layout.x_mid(i, j)] = [(i as f64 + 0.5) * length, j as f64 * length, height];
        }
    }
    for j in 0..ny {
        for i in 0..=nx {
            nodes[layout.y_mid(i, j)] = [i as f64 * length, (j as f64 + 0.5) * length, height];
        }
    }
    let mut links = Vec::with_capacity(nx * ny * module.links_per_module());
    for j in 0..ny {
        for i in 0..nx {
            let m = layout.module_index(i, j);
            let n = module_nodes(layout, i, j);
            let (c, u) = (&n[..4], &n[4..]);
            for k in 0..4 {
                links.push((c[k], c[(k + 1) % 4], GridRole::LowerCable, m));
            }
            for k in 0..4 {
                links.push((u[k], u[(k + 1) % 4], GridRole::UpperCable, m));
            }
            for k in 0..4 {
                links.push((c[k], u[k], GridRole::BracingCable, m));
            }
            for k in 0..4 {
                links.push((c[k], u[(k + 1) % 4], GridRole::Bar, m));
            }
            if module == ModuleKind::Braced {
                links.push((c[0], c[2], GridRole::DiagonalCable, m));
                links.push((c[1], c[3], GridRole::DiagonalCable, m));
                links.push((u[0], u[2], GridRole::DiagonalCable, m));
                links.push((u[1], u[3], GridRole::DiagonalCable, m));
            }
        }
    }
    (nodes, links)
}

/// The grid of `spec` as a general description: its nodes (ids = indices), its members (ids =
/// indices) with the prestress of docs/method.md §2 and their roles, and its layout.
pub(super) fn geometry(spec: &GridSpec) -> (Geometry, GridLayout) {
    let layout = GridLayout::new(spec.modules[0], spec.modules[1]);
    let (nodes, raw_links) = generate(&layout, spec.length, spec.height, spec.module);
    let p = spec.prestress;
    let roles = raw_links.iter().map(|&(_, _, role, _)| role).collect();
    let members = raw_links
        .into_iter()
        .enumerate()
        .map(|(id, (a, b, role, module))| {
            let (length, _) = length_and_direction(nodes[a], nodes[b]);
            let material = if role.kind().is_cable() {
                spec.cables.material
            } else {
                spec.bars
            };
            // docs/method.md §2: force densities p/L (lower cables), 2p/L (the others), bars in
            // compression; the diagonals of the braced module carry none.
            let l = spec.length;
            let density = match role {
                GridRole::LowerCable => p / l,
                GridRole::UpperCable | GridRole::BracingCable => 2.0 * p / l,
                GridRole::Bar => -2.0 * p / l,
                GridRole::DiagonalCable => 0.0,
            };
            Member {
                id: id as u64,
                a,
                b,
                kind: role.kind(),
                young: material.young,
                section: material.section,
                prestress: density * length,
                density: 0.0,
                module,
            }
        })
        .collect();
    let geometry = Geometry {
        node_ids: (0..nodes.len() as u64).collect(),
        nodes,
        members,
        unilateral: spec.cables.unilateral,
        grid_roles: Some(roles),
        checks: None,
        groups: None,
    };
    (geometry, layout)
}
