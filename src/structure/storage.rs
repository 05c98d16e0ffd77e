//! The memory a structure takes, from its size alone: counted before the structure is
//! generated or read, so that a case too large for the machine is refused before it is built
//! (issue 13, C1: a 500 × 500 grid passed validation, then died with "memory allocation
//! failed"). A command's estimate (`app::memory`) adds the solvers' factors to it.

use super::{Geometry, GridLayout, GridSpec};

/// Bytes per link for the structure and everything sized by it: the case's geometry, the
/// structure's links and compatibility rows, the stiffness pattern and values, a solver's
/// vectors (fitted: peak RSS of `pcg-lcp` minus one factor, 1.1–1.2 kB per dof on 64 × 64 to
/// 256 × 256 grids, which have 16/9 links per dof; rounded up).
pub const BYTES_PER_LINK: u64 = 700;

/// The process before any structure: binary, runtime, small buffers.
pub const BASE_BYTES: u64 = 32 << 20;

/// The size of a structure, as memory estimates need it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StructureSize {
    /// Nodes.
    pub nodes: usize,
    /// Links (bars and cables).
    pub links: usize,
}

impl StructureSize {
    /// The size of the structure `geometry` describes.
    pub fn of(geometry: &Geometry) -> StructureSize {
        StructureSize {
            nodes: geometry.nodes.len(),
            links: geometry.members.len(),
        }
    }

    /// The size of the grid `spec` describes, without generating it.
    pub fn of_grid(spec: &GridSpec) -> StructureSize {
        let [nx, ny] = spec.modules;
        StructureSize {
            nodes: GridLayout::new(nx, ny).n_nodes(),
            links: spec.module.links_per_module() * nx * ny,
        }
    }

    /// Dofs, held ones included (an upper bound of the free dofs).
    pub fn dofs(&self) -> usize {
        3 * self.nodes
    }

    /// Bytes of the structure and what is sized by it: [`BASE_BYTES`] + [`BYTES_PER_LINK`] ·
    /// links.
    pub fn bytes(&self) -> u64 {
        BASE_BYTES + BYTES_PER_LINK * self.links as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::{ModuleKind, Structure};

    /// The size of a grid counted without generating it is that of the grid generated.
    #[test]
    fn a_grid_is_counted_as_generated() {
        for module in [ModuleKind::Standard, ModuleKind::Braced] {
            let spec = GridSpec {
                modules: [3, 2],
                module,
                ..GridSpec::default()
            };
            let (geometry, _, _) = Structure::grid_parts(&spec);
            assert_eq!(StructureSize::of_grid(&spec), StructureSize::of(&geometry));
        }
    }
}
