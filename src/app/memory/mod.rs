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
use crate::solvers::latin::LatinSettings;
use crate::solvers::newton::SPLIT_MIN_DOFS;
use crate::solvers::Method;
use crate::structure::StructureSize;

/// Entries of a sparse Cholesky factor per dof and per `log2(dofs)` under nested dissection:
/// 124 M entries on 256 × 256 modules (592 899 dofs, log2 = 19.2) is 10.9.
pub const FACTOR_ENTRIES_PER_DOF_LOG2: f64 = 11.0;

/// Bytes per factor entry: the value (8) and the supernodal structure's indices and workspace
/// (peak RSS of `newton` minus that of `pcg-lcp`, one factor apart, is 9.5 bytes per entry on
/// 64 × 64 to 256 × 256 grids; rounded up).
pub const BYTES_PER_FACTOR_ENTRY: f64 = 10.0;

/// What factoring newton's Hessian in two halves adds, in units of K's factor.
pub const NEWTON_SPLIT_UNITS: f64 = 0.6;

/// Fill of the minimum-degree ordering against nested dissection (194 M against 124 M
/// entries on 256 × 256 modules), for `check`'s rank factorization. The solvers' factors use
/// minimum degree only below 512 free nodes (it was 10 000 when the formula was calibrated,
/// and it still bounded what was measured there, up to 56 × 56 modules), so they are all
/// counted as nested dissection.
pub const AMD_FILL_RATIO: f64 = 1.6;

/// Bytes of one sparse Cholesky factor of the stiffness of a structure of `size`:
/// `11 · d · log2(d)` entries of 10 bytes for `d` dofs (nested dissection), [`AMD_FILL_RATIO`]
/// times that with `amd`.
pub fn factor_bytes(size: StructureSize, amd: bool) -> u64 {
    let d = size.dofs().max(2) as f64;
    let entries = FACTOR_ENTRIES_PER_DOF_LOG2 * d * d.log2();
    let fill = if amd { AMD_FILL_RATIO } else { 1.0 };
    (fill * entries * BYTES_PER_FACTOR_ENTRY) as u64
}

/// Entries of a substructure factor per dof: `28 (log2 d_E − 8.3)`, at least `4 log2 d_E`, for
/// `d_E` dofs (AMD on E's node graph). Fitted to the substructure factors of 256 × 256 modules
/// on 2 × 2 to 64 × 64 substructures (148 224 to 180 dofs: 238, 183, 128, 82, 36 and 22 entries
/// per dof, each below the formula).
fn substructure_entries_per_dof(d_e: f64) -> f64 {
    let l = d_e.max(2.0).log2();
    f64::max(28.0 * (l - 8.3), 4.0 * l)
}

/// Macro dofs per substructure with a macro basis of degree p: `6p + 18`, two strong interfaces
/// of `3p + 6` fields and the crosspoints' weak ones (22 on 256 × 256 modules with 256 and
/// 1 024 substructures at p = 1; rounded up).
fn macro_dofs_per_substructure(degree: f64) -> f64 {
    6.0 * degree + 18.0
}

/// Columns of all the Z_E together (each substructure's macro dofs) on an `sx × sy` partition
/// of a grid with a macro basis of degree p: two sides of each strong interface between
/// neighbours along x or y, of `3p + 6` fields, and two of each one-node interface between
/// diagonal neighbours, of 3 (44 per substructure on 256 × 256 modules with 256 substructures
/// at p = 1).
fn z_columns([sx, sy]: [usize; 2], degree: f64) -> f64 {
    let strong = (sx * sy.saturating_sub(1) + sy * sx.saturating_sub(1)) as f64;
    let crosspoints = (2 * sx.saturating_sub(1) * sy.saturating_sub(1)) as f64;
    2.0 * strong * (3.0 * degree + 6.0) + 2.0 * crosspoints * 3.0
}

/// Bytes of micro-macro's own memory beside the structure on a structure of `size` with
/// `settings`: the substructure factors (`substructure_entries_per_dof`, 10 bytes an entry
/// as K's), Z_E unless `keep_z` is false, Anderson's history (two vectors of about 1.25 values
/// per link per depth) and the macro factor (three times a stiffness factor of its dofs: its
/// blocks are denser). Measured against peak RSS of whole runs (2026-11-27, reference none,
/// `geometric_term = false`): 256 × 256 modules on 256 substructures, anderson 10, 1.31 GB
/// (`keep_z = false`, estimate 1.45 GB) and 1.53 GB (1.68 GB); 512 × 512 on 1 024, anderson
/// 10, `keep_z = false`, 5.08 GB (5.8 GB).
pub fn micro_macro_bytes(size: StructureSize, settings: &LatinSettings) -> u64 {
    let d = size.dofs().max(2) as f64;
    let substructures = (settings.subdomains[0] * settings.subdomains[1]).max(1) as f64;
    let d_e = d / substructures;
    let factors = BYTES_PER_FACTOR_ENTRY * substructure_entries_per_dof(d_e) * d;
    let degree = settings.macro_degree_on(size.links, substructures as usize) as f64;
    // Z_E: E's dofs (d / substructures) × its macro dofs, 8 bytes each; twice, since a status
    // rebuild builds the new Z_E beside the old one (kept until the rebuild succeeds).
    let z = match settings.keep_z {
        true => 2.0 * 8.0 * d / substructures * z_columns(settings.subdomains, degree),
        false => 0.0,
    };
    let anderson = 2.0 * 1.25 * 8.0 * settings.anderson as f64 * size.links as f64;
    let macro_size = StructureSize {
        nodes: (macro_dofs_per_substructure(degree) * substructures / 3.0).ceil() as usize,
        links: 0,
    };
    let macro_factor = match substructures > 1.0 {
        true => 3 * factor_bytes(macro_size, false),
        false => 0,
    };
    (factors + z + anderson) as u64 + macro_factor
}

/// The whole-structure factors of `methods`, in units of K's: every solver's but
/// micro-macro's, which [`micro_macro_bytes`] counts.
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
        let factor = factor_bytes(size, false);
        let mut parts = vec![("structure".to_string(), size.bytes())];
        let latin = work.methods.iter().any(|m| m.is_latin());
        // The solvers' own memory: whole-structure factors in units of K's, and micro-macro's
        // substructure operators in bytes.
        let mut solvers = whole_structure_units(work.methods.iter());
        // newton's Hessian in two halves (from `SPLIT_MIN_DOFS` free dofs, on two threads or
        // more; counted on any number): the halves' patterns, slots and values beside their
        // factors, and the separator's dense blocks. 256 × 256 peaked at 3.56 GB on two
        // threads against 2.89 on one: 0.54 of a factor.
        if work.methods.contains(&Method::Newton) && size.dofs() >= SPLIT_MIN_DOFS {
            solvers += NEWTON_SPLIT_UNITS;
        }
        let micro = match work.methods.contains(&Method::MicroMacro) {
            true => micro_macro_bytes(size, &work.micro_macro),
            false => 0,
        };
        // K with every cable taut (the mechanism check) is factorized unless the check is made
        // by substructures; released, it is gone before the solvers' factors are built.
        let taut = !work.taut_by_substructures;
        let solver_bytes = solvers * factor as f64 + micro as f64;
        let check_alone = !work.keeps_taut && taut && factor as f64 > solver_bytes;
        let mut units = match (work.keeps_taut, taut) {
            (true, true) => 1.0 + solvers,
            _ if check_alone => 1.0,
            _ => solvers,
        };
        let mut micro_parts = match check_alone {
            true => 0,
            false => micro,
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
                    .filter(|&&m| m != Method::MicroMacro && !check_alone)
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
        let units = units + micro_parts as f64 / factor as f64;
        if work.rank_factorization {
            // Freed before the solvers' set-up: counted when larger than what follows it.
            let rank = factor_bytes(size, true);
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
        let keeps_taut = AnswerChecks::of(case).any() || all.iter().any(|m| !m.is_latin());
        Workload {
            keeps_taut,
            taut_by_substructures: checks_by_substructures(case, keeps_taut),
            micro_macro: case.solver.latin,
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
