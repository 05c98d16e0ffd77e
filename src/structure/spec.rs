//! What a structure is built from: a plain description of the module grid, its members, its
//! prestress, its supports and its load pattern. The paper's values (§5.1, Table 4) are the
//! defaults, written once here; the case file converts into these types.

use serde::Deserialize;

/// The repeated module (docs/method.md §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModuleKind {
    /// 8 nodes, 12 cables, 4 bars.
    #[default]
    Standard,
    /// The standard module plus 4 diagonal cables without prestress (paper's Figure 5 right).
    Braced,
}

impl ModuleKind {
    /// The name a case file gives it.
    pub fn name(self) -> &'static str {
        match self {
            ModuleKind::Standard => "standard",
            ModuleKind::Braced => "braced",
        }
    }

    /// Links per module: 12 cables and 4 bars, plus 4 diagonal cables when braced.
    pub fn links_per_module(self) -> usize {
        match self {
            ModuleKind::Standard => 16,
            ModuleKind::Braced => 20,
        }
    }
}

/// Which lower (z = 0) nodes are clamped (all three displacements zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Clamp {
    /// The lower nodes of the edges x = 0 and x = nx·L (the paper's supports).
    #[default]
    LowerXEdges,
    /// The lower nodes of the edges y = 0 and y = ny·L.
    LowerYEdges,
    /// The lower nodes of all four edges.
    LowerAllEdges,
    /// The four lower corners of the grid only.
    LowerCorners,
    /// Nothing is clamped (always a mechanism: refused before solving).
    None,
}

impl Clamp {
    /// The name a case file gives it (`supports.clamp`).
    pub fn name(self) -> &'static str {
        match self {
            Clamp::LowerXEdges => "lower-x-edges",
            Clamp::LowerYEdges => "lower-y-edges",
            Clamp::LowerAllEdges => "lower-all-edges",
            Clamp::LowerCorners => "lower-corners",
            Clamp::None => "none",
        }
    }
}

/// Axial material of a family of members.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus, Pa.
    pub young: f64,
    /// Cross-section, m².
    pub section: f64,
}

/// The cables: their material and whether they carry tension only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableSpec {
    /// Young's modulus and cross-section.
    pub material: Material,
    /// `true`: tension only (complementarity); `false`: they behave as bars (linear case).
    pub unilateral: bool,
}

/// An `nx × ny` grid of tensegrity modules, its members, prestress and supports.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSpec {
    /// `[nx, ny]` modules along x and y, each ≥ 1.
    pub modules: [usize; 2],
    /// Module side L, m.
    pub length: f64,
    /// Module height H, m.
    pub height: f64,
    /// The repeated module.
    pub module: ModuleKind,
    /// The cables.
    pub cables: CableSpec,
    /// The bars.
    pub bars: Material,
    /// Prestress p of the lower cables, N; the other members follow (docs/method.md §2).
    pub prestress: f64,
    /// Which lower nodes are clamped.
    pub clamp: Clamp,
}

impl Default for GridSpec {
    /// The paper's case (§5.1, Table 4): 16 × 16 standard modules of 1 m × 0.5 m, steel cables
    /// of 0.5 cm² and bars of 2.8 cm², p = 2000 N, clamped along the lower x-edges.
    fn default() -> Self {
        GridSpec {
            modules: [16, 16],
            length: 1.0,
            height: 0.5,
            module: ModuleKind::Standard,
            cables: CableSpec {
                material: Material {
                    young: 1e11,
                    section: 0.5e-4,
                },
                unilateral: true,
            },
            bars: Material {
                young: 2e11,
                section: 2.8e-4,
            },
            prestress: 2000.0,
            clamp: Clamp::LowerXEdges,
        }
    }
}

/// The load at α = 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadPattern {
    /// Force `[fx, fy, fz]` on every free node, N.
    pub nodal: [f64; 3],
}

impl Default for LoadPattern {
    /// The paper's load: 40 N downwards on every free node.
    fn default() -> Self {
        LoadPattern {
            nodal: [0.0, 0.0, -40.0],
        }
    }
}
