//! How a solve ended and what it cost: [`Status`], the measure a solver stops on ([`Measure`])
//! and the [`SolveInfo`] the driver returns with every solution.

use std::fmt;

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The stopping criterion was met: the stopping measure is at or below the tolerance.
    Converged,
    /// `max_iterations` was reached before the stopping criterion.
    MaxIterations,
    /// No further progress is possible in floating point (descent lost, a non-finite measure)
    /// before the stopping criterion.
    Stalled,
    /// No equilibrium exists: slack cables leave a mechanism that the load works on, so the
    /// energy is unbounded below (docs/method.md §8). The displacements are not an answer.
    NoEquilibrium,
    /// The load path could not be followed to the load (`large`: the increment fell below its
    /// minimum): a limit point, or a loss of equilibrium, on the way. Not an answer.
    LimitPoint,
    /// The stopping criterion holds, but the tangent stiffness there has a negative eigenvalue:
    /// an unstable equilibrium (a saddle of the energy), not the answer a load would reach.
    Unstable,
    /// The answer of a model on the initial geometry moves a node by more than the structure's
    /// own size, whether the stopping criterion held or not: beyond what that model describes
    /// (a unit slip, such as E in GPa, or a load far too large for it). Not an answer.
    BeyondModel,
}

impl Status {
    /// Whether the stopping criterion was met.
    pub fn converged(self) -> bool {
        self == Status::Converged
    }

    /// The `status` column's word: `converged`, `max_iterations`, `stalled`,
    /// `no_equilibrium`, `limit_point`, `unstable`, `beyond_model`.
    pub fn code(self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::MaxIterations => "max_iterations",
            Status::Stalled => "stalled",
            Status::NoEquilibrium => "no_equilibrium",
            Status::LimitPoint => "limit_point",
            Status::Unstable => "unstable",
            Status::BeyondModel => "beyond_model",
        }
    }

    /// Whether the final iterate is no answer: no equilibrium, the load never reached, beyond
    /// the model, or the stopping criterion unmet (stalled, at the cap). No displacement or
    /// tension file is written for it, and its row leaves the answer's columns empty: a row
    /// that did not converge writes nothing that looks like an answer (issue 57, D10: stalled
    /// rows wrote U = 0 files). An unstable equilibrium is one, and is written.
    pub fn no_answer(self) -> bool {
        !matches!(self, Status::Converged | Status::Unstable)
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Status::Converged => "converged",
            Status::MaxIterations => "stopped at max_iterations",
            Status::Stalled => "stalled",
            Status::NoEquilibrium => "no equilibrium",
            Status::LimitPoint => "limit point",
            Status::Unstable => "unstable equilibrium",
            Status::BeyondModel => "beyond the model",
        })
    }
}

/// What a solver's stopping measure (its `stopping_value`) measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Relative equilibrium residual `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ|‖)` on the free dofs
    /// (`newton`, which stops when `‖Bᵀτ − F‖ / (‖F‖ + ‖|B|ᵀ|τ − t0|‖)`, the stricter, meets
    /// the tolerance too).
    EquilibriumResidual,
    /// Relative complementarity residual `‖min(kλ, τ)‖ / ‖k_c B_c K⁻¹ F‖` of the cable LCP
    /// (`pcg-lcp`; relative to `‖t0_c‖` at zero load).
    ComplementarityResidual,
    /// The LATIN indicator η between the two half-steps (paper §5.3).
    Indicator,
}

impl Measure {
    /// A short name for messages: `residual` or `eta`.
    pub fn short_name(self) -> &'static str {
        match self {
            Measure::EquilibriumResidual | Measure::ComplementarityResidual => "residual",
            Measure::Indicator => "eta",
        }
    }
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Measure::EquilibriumResidual => "relative equilibrium residual",
            Measure::ComplementarityResidual => "relative complementarity residual",
            Measure::Indicator => "LATIN indicator eta",
        })
    }
}

/// What a solver did for one load.
#[derive(Debug, Clone)]
pub struct SolveInfo {
    /// How the solve ended.
    pub status: Status,
    /// Iterations done (newton steps, MPRGP steps, LATIN iterations after iteration 0).
    pub iterations: usize,
    /// What `stopping_value` measures.
    pub measure: Measure,
    /// The stopping measure at the end, as described by `measure`.
    pub stopping_value: f64,
    /// Operator rebuilds during the solve (status-following LATIN; 0 for the others).
    pub rebuilds: usize,
    /// PCG iterations over every Newton step of the solve (newton with `solver.linear =
    /// "krylov"`; `None` otherwise).
    pub krylov_iterations: Option<usize>,
    /// Wall time of the iterations (the solver's own work, observers excluded), s.
    pub solve_seconds: f64,
    /// Converged because the stopping measure is at round-off, not because the criterion
    /// holds ([`super::Progress::at_roundoff`]): the measure's value says nothing.
    pub at_roundoff: bool,
    /// With [`Status::NoEquilibrium`] found by the driver: the runaway direction's certificate.
    pub no_equilibrium: Option<super::NoEquilibrium>,
    /// How far a solver that follows a load path (`large`) followed it; `None` for the others.
    pub load_path: Option<LoadPathEnd>,
}

/// How far a solve followed its load path, from the solver's last equilibrium to its load.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadPathEnd {
    /// The fraction of the path at whose load the last equilibrium on it was reached: 1 when
    /// the solve converged at its load, less at a limit point.
    pub reached: f64,
    /// Increments whose equilibrium was rejected because it lies on another branch: the
    /// energy is not convex along the way from the last equilibrium to it (the path crossed a
    /// limit point and snapped through).
    pub branch_jumps: usize,
    /// At a limit point: the ids of the cables taut at the last equilibrium that went slack
    /// in the last increment tried (a loss of equilibrium where they go slack).
    pub slackened: Vec<u64>,
    /// The Newton steps each increment was given before it was halved.
    pub increment_steps: usize,
    /// At a limit point: the fraction of the path past `reached` within which the limit lies
    /// (the smallest increment that found no equilibrium).
    pub limit_bracket: Option<f64>,
    /// The load of the highest limit point the path located (arc length: a local maximum of α
    /// along it, passed; load control fills it from where the path stopped), α.
    pub limit_alpha: Option<f64>,
}
