//! Settings of the LATIN solver, each default written once, at its field.

use serde::Deserialize;

/// The search direction `l` on the links (SPEC §4 "Search directions").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SearchDirection {
    /// `l = k` on every link (the paper's choice). The default.
    Stiffness,
    /// The same `l` (N/m) on every link.
    Uniform(f64),
}

/// What to do with interfaces of three nodes or fewer (SPEC §4 "Weak interfaces").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WeakInterfaces {
    /// All-macro (R = identity): exact continuity through the macro problem. The default.
    #[default]
    Macro,
    /// All-micro (no macro part): the paper's literal statement; stalls on the paper's case.
    Micro,
    /// One-node interfaces whose node lies in another interface are dropped; other weak
    /// interfaces are all-macro.
    Drop,
}

/// Settings of one LATIN solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatinSettings {
    /// Substructures along x and y; `[1, 1]` is the monodomain solver. Default `[4, 4]` (the
    /// paper's), limited to the grid by the case.
    pub subdomains: [usize; 2],
    /// Interface search direction d_m, N/m. Default 3.92e6 (paper §5.2).
    pub dm: f64,
    /// Link search direction l. Default `l = k`.
    pub search: SearchDirection,
    /// Interfaces of ≤ 3 nodes. Default all-macro.
    pub weak: WeakInterfaces,
    /// Indicator η to reach. Default 1e-6.
    pub tolerance: f64,
    /// Iteration cap. Default 1000.
    pub max_iterations: usize,
}

impl Default for LatinSettings {
    fn default() -> Self {
        Self {
            subdomains: [4, 4],
            dm: 3.92e6,
            search: SearchDirection::Stiffness,
            weak: WeakInterfaces::Macro,
            tolerance: 1e-6,
            max_iterations: 1000,
        }
    }
}

impl LatinSettings {
    /// The monodomain solver (`mono-latin`) with the same search directions and stopping
    /// settings: the 1 × 1 partition.
    pub fn monodomain(self) -> LatinSettings {
        LatinSettings {
            subdomains: [1, 1],
            ..self
        }
    }
}
