//! The solvers a case may ask for, and what the rest of the program knows of each: its name,
//! its colour in the figures, the factors it holds, whether it reports the energy error e.
//! Every fact about a solver that is not its algorithm is here,
//! matched exhaustively, so a new solver cannot be forgotten by one of them.

use super::latin::LatinSettings;
use super::newton::NewtonSettings;
use super::pcg_lcp::PcgLcpSettings;
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

    /// Whether the solver is a LATIN solver, set up on a partition into substructures
    /// (`solver.subdomains`; mono-latin's is 1 × 1) with the `[solver]` LATIN settings.
    pub fn is_latin(self) -> bool {
        match self {
            Method::Newton | Method::PcgLcp => false,
            Method::MonoLatin | Method::MicroMacro => true,
        }
    }

    /// Whether the solver reports the energy error e of every iterate against a reference
    /// solve (`solver.reference`): the LATIN solvers, whose stopping measure η is not e. Those
    /// write `history/` and appear in the convergence figures (Figures 9–12).
    pub fn reports_error(self) -> bool {
        self.is_latin()
    }

    /// Sparse factors the solver holds beyond the taut stiffness every run factorizes, in
    /// units of the structure's stiffness factor (the memory estimate): newton its Hessian's;
    /// pcg-lcp none (it solves with K's); mono-latin its whole-structure operators (measured
    /// 3.0–3.4 units on 64 × 64 to 256 × 256, rounded up to 4). micro-macro's memory is
    /// counted from its substructures ([`Method::own_bytes`]); its 2 units
    /// (1.1–1.6 measured with 4 × 4 substructures on 64 × 64 to 256 × 256) only rank it among
    /// the solvers `bench` sets up one at a time.
    pub fn factor_units(self) -> f64 {
        match self {
            Method::Newton => 1.0,
            Method::PcgLcp => 0.0,
            Method::MonoLatin => 4.0,
            Method::MicroMacro => 2.0,
        }
    }

    /// The whole-structure factors the solver holds on a structure of `dofs` dofs, in units of
    /// its stiffness factor: [`Method::factor_units`], and for newton from
    /// [`super::newton::SPLIT_MIN_DOFS`] dofs its Hessian in two halves beside their factors
    /// (the halves' patterns, slots and values and the separator's dense blocks: 256 × 256
    /// peaked at 3.56 GB on two threads against 2.89 on one, 0.54 of a factor; counted on any
    /// number of threads).
    pub fn factor_units_at(self, dofs: usize) -> f64 {
        let split = match self == Method::Newton && dofs >= super::newton::SPLIT_MIN_DOFS {
            true => NEWTON_SPLIT_UNITS,
            false => 0.0,
        };
        self.factor_units() + split
    }

    /// The bytes the solver holds beside its whole-structure factors on a structure of `size`
    /// with LATIN settings `latin`: micro-macro its substructures' operators, Anderson's history
    /// and its macro problem ([`super::latin::memory_bytes`]); the others none.
    pub fn own_bytes(
        self,
        size: crate::structure::StructureSize,
        latin: &super::latin::LatinSettings,
    ) -> u64 {
        match self {
            Method::MicroMacro => super::latin::memory_bytes(size, latin),
            _ => 0,
        }
    }

    /// The solver's colour in every figure, sRGB.
    pub fn colour(self) -> [u8; 3] {
        match self {
            Method::Newton => [31, 119, 180],
            Method::PcgLcp => [255, 127, 14],
            Method::MonoLatin => [44, 160, 44],
            Method::MicroMacro => [148, 103, 189],
        }
    }

    /// The method called `name`.
    pub fn from_name(name: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The settings of one solver, paired with its method by type: a solver cannot be given
/// another's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Settings {
    /// `newton`'s (the large-rotation newton takes the same).
    Newton(NewtonSettings),
    /// `pcg-lcp`'s.
    PcgLcp(PcgLcpSettings),
    /// `mono-latin`'s: LATIN settings on the 1 × 1 partition.
    MonoLatin(LatinSettings),
    /// `micro-macro`'s.
    MicroMacro(LatinSettings),
}

impl Settings {
    /// The method these settings are for.
    pub fn method(&self) -> Method {
        match self {
            Settings::Newton(_) => Method::Newton,
            Settings::PcgLcp(_) => Method::PcgLcp,
            Settings::MonoLatin(_) => Method::MonoLatin,
            Settings::MicroMacro(_) => Method::MicroMacro,
        }
    }
}

/// What factoring newton's Hessian in two halves adds, in units of K's factor
/// ([`Method::factor_units_at`]).
pub const NEWTON_SPLIT_UNITS: f64 = 0.6;
