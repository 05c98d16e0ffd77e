//! Settings of the LATIN solver, each default written once, at its field.

use crate::decomposition::WeakInterfaces;
use crate::solvers::SetupError;
use crate::structure::Structure;
use serde::Deserialize;

/// The search direction `l` on the links (docs/method.md §4 "Search directions").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SearchDirection {
    /// `l = k` on every link (the paper's choice). The default.
    Stiffness,
    /// The same `l` (N/m) on every link.
    Uniform(f64),
}

/// How the link search direction l evolves along the iterations (docs: docs/method.md §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SearchPolicy {
    /// l stays as set up (`solver.l`): the paper's reference behaviour.
    Stiffness,
    /// l follows the cables' status (the paper's §5.3 proposal): l for taut cables and bars,
    /// ε·l for slack ones, a cable being slack when the linear stage's trial tension
    /// `t0 + k e` is not positive; the operators are rebuilt when that set has changed since
    /// they were built (see [`LatinSettings::update_threshold`]).
    Status,
    /// Status updates as inexact Newton steps (docs/method.md §9): the status is frozen during
    /// an inner LATIN run on the law linearised at it (taut cables elastic both ways, slack
    /// ones without tension), which ends once r(U) under that law is below
    /// [`LatinSettings::forcing`] × the exact r(U) at the step's start; a line search on the
    /// exact energy between the step's start and end, then the status of the blended state
    /// (`t0 + k e > 0`), and new operators (l as for `Status`) only if it changed.
    #[default]
    Newton,
}

/// What a LATIN solve stops on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopOn {
    /// The indicator η ≤ tolerance (the paper's criterion).
    Eta,
    /// The equilibrium residual r(U) of the linear stage ≤ tolerance.
    Residual,
    /// Both η and r(U) ≤ tolerance.
    #[default]
    Both,
}

/// The smallest default tolerance of r(U): micro-macro's accuracy on the paper case is
/// r = 1.65e-10.
const RESIDUAL_FLOOR: f64 = 1e-9;

/// The paper's interface search direction d_m, N/m (§5.2): for its 16 × 16 grid on 4 × 4
/// substructures.
pub const PAPER_DM: f64 = 3.92e6;

/// Settings of one LATIN solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatinSettings {
    /// Substructures along x and y; `[1, 1]` is the monodomain solver. The case's default on a
    /// grid is `crate::case::default_subdomains` (substructures of about 16 × 16 modules, at
    /// least 4 × 4 of them: the paper's `[4, 4]` on its grid); this value, `[4, 4]`, serves
    /// settings built without a case.
    pub subdomains: [usize; 2],
    /// Interface search direction d_m, N/m. Default `None`: `c p k̄ / √H` with c =
    /// [`super::DM_FACTOR`] and p the macro basis's degree (see [`super::auto_dm`]), which
    /// scales with the cables' stiffness; the paper's 3.92e6 is [`PAPER_DM`].
    pub dm: Option<f64>,
    /// Link search direction l. Default `l = k`.
    pub search: SearchDirection,
    /// Interfaces of ≤ 3 nodes. Default all-macro.
    pub weak: WeakInterfaces,
    /// Relaxation μ ∈ (0, 1] of the linear stage, `s ← μ s_new + (1 − μ) s_old` on every
    /// field of s (with Anderson acceleration, the damping β of its step, which is the same
    /// relaxation when no history is kept). Default 0.8; 1 is the paper's plain method.
    pub relaxation: f64,
    /// Anderson acceleration: how many previous iterates the fixed point ŝ ↦ local(linear(ŝ))
    /// extrapolates from (0: none, the plain relaxed iteration). Default 20 (docs/method.md §9: 5 needed
    /// about 30 % more iterations at 1024 substructures).
    pub anderson: usize,
    /// How l evolves. Default status-following.
    pub policy: SearchPolicy,
    /// With inexact Newton status steps: the forcing term ρ, the fraction of the step's
    /// starting r(U) the inner run must bring the linearised residual below. Default 0.2
    /// (docs/method.md §9: 0.3 needed 9–10 rebuilds on 16 substructures of 32 × 32 modules).
    pub forcing: f64,
    /// With status-following l: rebuild the operators once at least this many cables differ
    /// between the current slack set and the one l was built for. Default 1.
    pub update_threshold: usize,
    /// What the solve stops on. Default both η and r(U).
    pub stop_on: StopOn,
    /// Tolerance of η. Default 1e-6.
    pub tolerance: f64,
    /// Tolerance of r(U). Default `None`: `max(tolerance / 100, 1e-9)`. r is a force
    /// residual; the energy error e was measured at up to 40 r on the braced paper grid
    /// (α = 0.05) and 2 r at α = 1, so r two decades below the tolerance keeps e within
    /// 10 × tolerance there. Below 1e-9 lies micro-macro's own accuracy: on the paper case its
    /// iterates settle at r = 1.65e-10 (mono-latin: 3e-14).
    pub residual_tolerance: Option<f64>,
    /// Degree p of the strong interfaces' macro bases: the paper's nine first-order fields, and
    /// for p > 1 the translations times the Legendre polynomials of degree 2 … p along the
    /// interface. Default `None`: `round(H / 4)`, 1 to 16, for substructures of side H modules
    /// (`auto_macro_degree`).
    pub macro_degree: Option<usize>,
    /// Iteration cap. Default 1000.
    pub max_iterations: usize,
    /// Keep every substructure's `Z_E = K_E⁻¹ C_Eᵀ R_E` (E's dofs × its macro dofs). Default
    /// true; false computes `Z_E w` by a second solve with K_E's factor in every linear
    /// stage: a fifth less memory on large grids, and a slower iteration.
    pub keep_z: bool,
    /// Soft interface modes in the macro basis (`super::enrichment`): on each interface, the
    /// motions that a substructure on either side resists less than this fraction θ of d_m,
    /// taken at set-up and at each operator rebuild. Default `None`: the polynomial basis
    /// alone.
    pub soft_modes: Option<f64>,
}

impl Default for LatinSettings {
    fn default() -> Self {
        Self {
            subdomains: [4, 4],
            dm: None,
            search: SearchDirection::Stiffness,
            weak: WeakInterfaces::Macro,
            relaxation: 0.8,
            anderson: 20,
            policy: SearchPolicy::Newton,
            forcing: 0.2,
            update_threshold: 1,
            stop_on: StopOn::Both,
            tolerance: 1e-6,
            residual_tolerance: None,
            macro_degree: None,
            max_iterations: 1000,
            keep_z: true,
            soft_modes: None,
        }
    }
}

/// r_F(U)'s tolerance over r(U)'s ([`LatinSettings::balance_tolerances`]).
pub const LOAD_RESIDUAL_FACTOR: f64 = 100.0;
/// The loosest r_F(U) tolerance, whatever r(U)'s: at U = 0 r_F is 1, so a tolerance of 1 or
/// more would pass it (a `residual_tolerance` of 0.02 did, under `large`).
pub const LOAD_RESIDUAL_LOOSEST: f64 = 1e-2;

/// How far a uniform `solver.l` may be from the links' stiffness: beyond, the stages' round-off
/// (which scales with `1/√l` and `√l`) swamps the indicator (issue 13, D1: `l = 1e-300`
/// "converged" in 0 iterations with an infinite deflection).
const SEARCH_DIRECTION_RANGE: f64 = 1e8;

impl LatinSettings {
    /// Refuse settings the solver cannot be set up with on `structure`: a uniform search
    /// direction `l` outside `[k_min / 1e8, 1e8 k_max]` of the links' stiffness k.
    pub fn validate(&self, structure: &Structure) -> Result<(), SetupError> {
        let SearchDirection::Uniform(l) = self.search else {
            return Ok(());
        };
        let (k_min, k_max) = structure
            .links
            .iter()
            .map(|l| l.stiffness)
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), k| {
                (lo.min(k), hi.max(k))
            });
        let (min, max) = (
            k_min / SEARCH_DIRECTION_RANGE,
            k_max * SEARCH_DIRECTION_RANGE,
        );
        if k_max > 0.0 && !(min..=max).contains(&l) {
            return Err(SetupError::SearchDirectionOutOfRange {
                l,
                k_min,
                k_max,
                min,
                max,
            });
        }
        Ok(())
    }

    /// The tolerance r(U) is held to.
    pub fn residual_tolerance(&self) -> f64 {
        self.residual_tolerance
            .unwrap_or((self.tolerance / 100.0).max(RESIDUAL_FLOOR))
    }

    /// The equilibrium stop every solver shares ([`crate::solvers::Balance`]): r(U) within
    /// [`LatinSettings::residual_tolerance`], and r_F(U), the unbalance relative to the load's
    /// own forces, within `LOAD_RESIDUAL_FACTOR` (100) times it (1e-6 at the defaults, η's
    /// tolerance), and never looser than `LOAD_RESIDUAL_LOOSEST` (1e-2). r_F is the looser because a LATIN iterate's accuracy is set by its stages'
    /// round-off on prestress-sized terms: on the paper case the converged rows have r_F from
    /// 3e-14 to 1.2e-8 (mono-latin) and 1.5e-10 to 9.8e-9 (micro-macro, α 0.01 to 1); held to
    /// r(U)'s 1e-8, micro-macro (which settles at r(U) ≈ 1e-10) could not converge below
    /// α ≈ 0.01.
    pub fn balance_tolerances(&self) -> crate::solvers::BalanceTolerances {
        let residual = self.residual_tolerance();
        crate::solvers::BalanceTolerances {
            residual,
            load_residual: (LOAD_RESIDUAL_FACTOR * residual).min(LOAD_RESIDUAL_LOOSEST),
        }
    }

    /// The degree of the macro bases on `substructures` substructures of a structure of
    /// `links` links: `macro_degree`, or `auto_macro_degree`.
    pub fn macro_degree_on(&self, links: usize, substructures: usize) -> usize {
        self.macro_degree.unwrap_or_else(|| {
            super::auto_macro_degree(super::substructure_side(links, substructures))
        })
    }

    /// The paper's plain method (§3–4): its d_m and first-order macro basis (unless `self`
    /// sets them), no relaxation, no acceleration, l fixed at its set-up value, stopping on η
    /// alone; the rest as `self`.
    pub fn plain(self) -> LatinSettings {
        LatinSettings {
            dm: Some(self.dm.unwrap_or(PAPER_DM)),
            macro_degree: Some(self.macro_degree.unwrap_or(1)),
            relaxation: 1.0,
            anderson: 0,
            policy: SearchPolicy::Stiffness,
            stop_on: StopOn::Eta,
            soft_modes: None,
            ..self
        }
    }

    /// The monodomain solver (`mono-latin`) with the same search directions and stopping
    /// settings: the 1 × 1 partition.
    pub fn monodomain(self) -> LatinSettings {
        LatinSettings {
            subdomains: [1, 1],
            ..self
        }
    }
}
