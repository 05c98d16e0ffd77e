//! The solvers a case may ask for, by name.

use crate::structure::GeometricModel;
use serde::Deserialize;

/// A solver the case may ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Exact active-set (semismooth Newton) on the energy.
    Newton,
    /// The paper's reference: cable LCP by projected conjugate gradient.
    PcgLcp,
    /// Monodomain LATIN (augmented Lagrangian): the LATIN solver on a 1 × 1 partition.
    MonoLatin,
    /// Micro-macro LATIN domain decomposition on `solver.subdomains`.
    MicroMacro,
}

impl Method {
    /// Every method, in the order of the README's table.
    pub const ALL: [Method; 4] = [
        Method::Newton,
        Method::PcgLcp,
        Method::MonoLatin,
        Method::MicroMacro,
    ];

    /// The name used in case files, on the command line and in output file names.
    pub fn name(self) -> &'static str {
        match self {
            Method::Newton => "newton",
            Method::PcgLcp => "pcg-lcp",
            Method::MonoLatin => "mono-latin",
            Method::MicroMacro => "micro-macro",
        }
    }

    /// Whether the solver takes geometric model `model` (README "Real tensegrities"):
    /// newton every model, the others `linear` and `prestress` (`large` is newton's alone).
    pub fn supports(self, model: GeometricModel) -> bool {
        self == Method::Newton || model != GeometricModel::Large
    }

    /// The method called `name`.
    pub fn from_name(name: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}
