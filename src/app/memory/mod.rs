//! The memory a command needs, estimated from the case's size before anything large is
//! allocated (issue 13, C1: a 500 × 500 grid passed validation, then died with "memory
//! allocation failed"), and the refusal when it does not fit in what this process may use
//! ([`crate::host::available`]).
//!
//! The estimate is a formula in the structure's size, calibrated against the peak resident
//! memory of `tensolve run` (`/usr/bin/time -v`) on 16 × 16 to 256 × 256 grids, one solver at
//! a time (docs/performance.md, "Memory: the estimate against measurement"). It counts the structure
//! ([`StructureSize::bytes`]) and the sparse factors each solver holds; nothing else grows
//! with the structure.

mod fit;

pub use fit::{ensure_fits, ensure_fits_in};

use super::setup::{checks_by_substructures, AnswerChecks};
use crate::case::Case;
use crate::host::bytes_text;
use crate::linalg::factor_bytes;
use crate::solvers::latin::LatinSettings;
use crate::solvers::newton::LinearSolve;
use crate::solvers::Method;
use crate::structure::StructureSize;

/// What newton substructured (`solver.linear = "krylov"`) holds per dof of the structure at the
/// default Schwarz settings, in place of a factor of K: the overlapping subdomains' factors,
/// their GenEO vectors and the work of finding them, the coarse matrix's factor, and K's
/// pattern, values and analysis. Peak RSS of `tensolve run` less the structure, reference
/// none, `geometric_term = false` (2026-12-07, two threads): 3.3 / 2.8 / 3.1 / 3.3 kB per dof
/// on 64² / 128² / 256² / 512² modules (16 to 1024 subdomains).
const KRYLOV_BYTES_PER_DOF: u64 = 3_600;

/// The whole-structure factors of `methods`, in units of K's: every solver's but
/// micro-macro's, which it counts itself ([`Method::own_bytes`]).
fn whole_structure_units<'m>(methods: impl Iterator<Item = &'m Method>) -> f64 {
    methods
        .filter(|&&m| m != Method::MicroMacro)
        .map(|m| m.factor_units())
        .sum()
}

/// What a command will do with the structure.
#[derive(Debug, Clone, PartialEq)]
pub struct Workload {
    /// The solvers set up together (the run's solvers, LATIN's reference solver when it is not
    /// one of them, and newton as `auto`'s probe).
    pub methods: Vec<Method>,
    /// `output.stability`: one more factorization of the tangent stiffness per row.
    pub stability: bool,
    /// Figure 12: the LATIN solvers set up again on a second grid while the first is held.
    pub compare_modules: bool,
    /// `check`: a rank factorization of `BᵀB` (minimum-degree ordering), freed before the
    /// solvers' set-up.
    pub rank_factorization: bool,
    /// Whether the factor of K with every cable taut is kept after the mechanism check: some
    /// solver solves with it (newton, pcg-lcp, as a solver or as the reference), or a check of
    /// every answer does (`output.stability`, the models with geometric stiffness, and
    /// `output.geometric_term`). Otherwise it is released before the solvers are set up, and
    /// the peak counts the larger of it and theirs, not both.
    pub keeps_taut: bool,
    /// Whether the mechanism check is made substructure by substructure
    /// ([`crate::app::setup::checks_by_substructures`]): K is then never factorized whole, and
    /// the check's substructure factors, one per thread at a time, are small beside the rest.
    pub taut_by_substructures: bool,
    /// micro-macro's settings (partition, Anderson depth, `keep_z`), for its memory when it
    /// is among `methods`.
    pub micro_macro: LatinSettings,
    /// How newton solves its Newton systems: a factor of K (counted in units of K's factor),
    /// or on the substructures (its Schwarz data, counted per dof).
    pub newton_linear: LinearSolve,
}

/// The estimated peak memory of a command on a structure, by part.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryEstimate {
    /// What each part is, and its bytes.
    pub parts: Vec<(String, u64)>,
    /// Threads that run dense kernels (the main thread when a solver is set up, and rayon's
    /// workers for LATIN's parallel stages), for the address space each reserves (see
    /// [`crate::host::Available::dense_buffer`]).
    pub dense_threads: usize,
    /// rayon's worker threads, for their malloc arenas (see [`crate::host::Available::arena`]).
    pub worker_threads: usize,
}

impl MemoryEstimate {
    /// The structure of `size` under `work`: the structure, the taut stiffness's factor, and
    /// every solver's own factors.
    pub fn new(size: StructureSize, work: &Workload) -> MemoryEstimate {
        let factor = factor_bytes(size.dofs(), false);
        let mut parts = vec![("structure".to_string(), size.bytes())];
        let latin = work.methods.iter().any(|m| m.is_latin());
        // The solvers' own memory, as each estimates it: whole-structure factors in units of
        // K's (micro-macro's counted in bytes, from its substructures).
        let krylov = work.newton_linear == LinearSolve::Krylov;
        let factored =
            |m: &&Method| **m != Method::MicroMacro && !(krylov && **m == Method::Newton);
        let solvers = work
            .methods
            .iter()
            .filter(factored)
            .map(|m| m.factor_units_at(size.dofs()))
            .sum::<f64>();
        let substructured = match krylov && work.methods.contains(&Method::Newton) {
            true => KRYLOV_BYTES_PER_DOF * size.dofs() as u64,
            false => 0,
        };
        let micro = work
            .methods
            .iter()
            .map(|m| m.own_bytes(size, &work.micro_macro))
            .sum::<u64>();
        // K with every cable taut (the mechanism check) is factorized unless the check is made
        // by substructures; released, it is gone before the solvers' factors are built.
        let taut = !work.taut_by_substructures;
        let solver_bytes = solvers * factor as f64 + (micro + substructured) as f64;
        let check_alone = !work.keeps_taut && taut && factor as f64 > solver_bytes;
        let mut units = match (work.keeps_taut, taut) {
            (true, true) => 1.0 + solvers,
            _ if check_alone => 1.0,
            _ => solvers,
        };
        let (mut micro_parts, substructured) = match check_alone {
            true => (0, 0),
            false => (micro, substructured),
        };
        if work.stability {
            units += 1.0;
        }
        if work.compare_modules {
            // A second grid: its structure, its taut factor and its LATIN solvers.
            units += 1.0 + whole_structure_units(work.methods.iter().filter(|m| m.is_latin()));
            micro_parts += micro;
            parts.push(("second grid (Figure 12)".into(), size.bytes()));
        }
        let names: Vec<&str> = ["K with every cable taut"]
            .into_iter()
            .filter(|_| taut && (work.keeps_taut || check_alone))
            .chain(
                work.methods
                    .iter()
                    .filter(|m| factored(m) && !check_alone)
                    .map(|m| m.name()),
            )
            .collect();
        if units > 0.0 {
            parts.push((
                format!(
                    "{units} sparse factor(s) of {} ({})",
                    bytes_text(factor),
                    names.join(", ")
                ),
                (units * factor as f64) as u64,
            ));
        }
        if micro_parts > 0 {
            parts.push((
                "micro-macro (substructure factors, Z_E, Anderson's history, macro problem)".into(),
                micro_parts,
            ));
        }
        if substructured > 0 {
            parts.push((
                "newton substructured (subdomain factors, GenEO vectors, coarse matrix)".into(),
                substructured,
            ));
        }
        let units = units + (micro_parts + substructured) as f64 / factor as f64;
        if work.rank_factorization {
            // Freed before the solvers' set-up: counted when larger than what follows it.
            let rank = factor_bytes(size.dofs(), true);
            let later = (units * factor as f64) as u64;
            if rank > later {
                parts.push((
                    "rank factorization, beyond the solvers'".into(),
                    rank - later,
                ));
            }
        }
        let worker_threads = if latin { rayon_threads() } else { 0 };
        MemoryEstimate {
            parts,
            dense_threads: 1 + worker_threads,
            worker_threads,
        }
    }

    /// The sum of the parts, bytes.
    pub fn total(&self) -> u64 {
        self.parts.iter().map(|p| p.1).sum()
    }
}

impl std::fmt::Display for MemoryEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self
            .parts
            .iter()
            .map(|(what, bytes)| format!("{what}: {}", bytes_text(*bytes)))
            .collect();
        write!(
            f,
            "about {} ({})",
            bytes_text(self.total()),
            parts.join("; ")
        )
    }
}

impl Workload {
    /// `tensolve run` of `case` with `methods`: those solvers set up together, LATIN's own
    /// reference solver when it is not one of them at its default settings, and the outputs
    /// that factorize again.
    pub fn run(case: &Case, methods: &[Method]) -> Workload {
        let mut all = methods.to_vec();
        if let Some(reference) = case.solver.reference.method() {
            let shared = methods.contains(&reference) && case.solver.is_default(reference);
            if methods.iter().any(|m| m.reports_error()) && !shared {
                all.push(reference);
            }
        }
        // `auto` measures newton's linear answer at each α against `large` (its probe).
        if case.model_auto && !all.contains(&Method::Newton) {
            all.push(Method::Newton);
        }
        let keeps_taut = AnswerChecks::of(case).any()
            || all
                .iter()
                .any(|&m| case.solver.solves_with_taut_factor(m, case.model_auto));
        Workload {
            keeps_taut,
            taut_by_substructures: checks_by_substructures(case, keeps_taut),
            micro_macro: case.solver.latin,
            newton_linear: case.solver.newton.linear,
            methods: all,
            stability: case.output.stability,
            compare_modules: case.output.plots && !case.output.compare_modules.is_empty(),
            rank_factorization: false,
        }
    }

    /// `tensolve check` of `case`: the rank factorization, then the taut stiffness and the
    /// LATIN solvers' set-up; or, when the run checks for mechanisms substructure by
    /// substructure, that check (which gives the counts too) and the set-ups.
    pub fn check(case: &Case) -> Workload {
        let latin = case
            .solver
            .methods
            .iter()
            .copied()
            .filter(|m| m.is_latin())
            .collect();
        let by_substructures = Workload::run(case, &case.solver.methods).taut_by_substructures;
        Workload {
            methods: latin,
            stability: false,
            compare_modules: false,
            rank_factorization: !by_substructures,
            keeps_taut: !by_substructures,
            taut_by_substructures: by_substructures,
            micro_macro: case.solver.latin,
            newton_linear: case.solver.newton.linear,
        }
    }

    /// `tensolve bench` of `case`: one solver set up at a time, after a reference solved by
    /// `reference` (the case's `solver.reference`).
    pub fn bench(case: &Case, reference: Method) -> Workload {
        let largest = case
            .solver
            .methods
            .iter()
            .copied()
            .chain([reference])
            .max_by(|a, b| a.factor_units().total_cmp(&b.factor_units()))
            .unwrap_or(reference);
        Workload {
            methods: vec![largest],
            stability: false,
            compare_modules: false,
            rank_factorization: false,
            keeps_taut: true,
            taut_by_substructures: false,
            micro_macro: case.solver.latin,
            newton_linear: case.solver.newton.linear,
        }
    }
}

/// The threads rayon's global pool will have: `RAYON_NUM_THREADS`, else one per CPU (rayon's
/// own rule; read without starting the pool).
fn rayon_threads() -> usize {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

#[cfg(test)]
mod tests;
