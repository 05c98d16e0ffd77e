//! The LATIN solver (docs/method.md §4, paper §3–4), on the partitions of [`crate::decomposition`]: one implementation for `micro-macro` (an `sx × sy`
//! partition with a homogenised macro problem) and `mono-latin` (a 1 × 1 partition: no
//! interfaces, `K = Bᵀ l B`, the augmented Lagrangian method of the paper's §5.4).
//!
//! The solver alternates a local stage (constitutive laws, per link and per interface, exact;
//! `local_stage`) and a linear stage (equilibrium and compatibility per substructure, glued
//! by exact macro continuity; `linear_stage`). Iteration 0 is the linear stage from ŝ = 0;
//! iteration k ≥ 1 is a local stage on s_{k−1} followed by a linear stage. After each linear
//! stage it measures the indicator η between s and the ŝ that fed it (`indicator`), and
//! stops when η ≤ `tolerance` (or, with no load, when Δη is at round-off against the prestress;
//! under a load that is a stall).
//!
//! Its files, one role each, are listed in docs/guide.md's source layout (kept true by
//! `tests/docs.rs`).

mod anderson;
mod distribution;
mod dof_ownership;
mod enrichment;
mod indicator;
mod iteration;
mod linear_stage;
mod link_share;
mod local_stage;
mod macro_problem;
mod memory;
mod neighbours;
mod operators;
mod ranks;
mod residual;
mod search;
mod set_up;
mod settings;
mod slack_direction;
mod state;
mod status_step;
mod substructure;
#[cfg(test)]
mod tests;

#[cfg(test)]
use crate::decomposition::macro_basis::macro_basis;
use crate::decomposition::{block, Exchange, Homogenised, MacroDof};
use crate::decomposition::{Interface, Partition};
pub use link_share::LinkShare;
use link_share::WorldFacts;
pub use memory::memory_bytes;
pub use ranks::{RankLayout, RankShare, VALUES_PER_ROW, VALUES_PER_SHARED_DOF};
pub use settings::{LatinSettings, SearchDirection, SearchPolicy, StopOn, PAPER_DM};
pub use state::{LatinState, StatusSteps};
pub(crate) use state::{SideState, SubState};
pub(crate) use substructure::{OperatorStorage, Substructure};

use crate::linalg::CHUNK;
use crate::model::Model;
use crate::structure::Structure;
use distribution::Distribution;
use macro_problem::MacroProblem;
use rayon::prelude::*;

/// What `tensolve check` prints about a partition.
#[derive(Debug, Clone)]
pub struct PartitionReport {
    /// Number of substructures.
    pub substructures: usize,
    /// Interfaces that carry constraints.
    pub interfaces: usize,
    /// Interfaces of more than three nodes (with a macro basis of at most nine fields, and
    /// three more per degree above 1).
    pub strong_interfaces: usize,
    /// Interfaces of at most three nodes.
    pub weak_interfaces: usize,
    /// Interfaces left out (`drop`, or all their nodes redundant).
    pub dropped_interfaces: usize,
    /// Nodes left out of all-macro weak interfaces because their continuity already holds
    /// exactly through other interfaces.
    pub redundant_nodes: usize,
    /// Macro force unknowns.
    pub macro_dofs: usize,
    /// Unknowns of the macro system (forces and kernel amplitudes) and entries of its
    /// `L D Lᵀ` factor, which every process holds.
    pub macro_system: (usize, usize),
    /// Subtrees of substructures its factor is factored and solved in side by side (1: whole).
    pub macro_subtrees: usize,
    /// Kernel columns of all the substructures.
    pub kernel_columns: usize,
    /// Free dofs of the largest substructure.
    pub max_substructure_dofs: usize,
    /// The interface search direction d_m used, N/m.
    pub dm: f64,
    /// The degree of the strong interfaces' macro bases.
    pub macro_degree: usize,
}

/// The LATIN solver, set up for one structure and one partition: the model and settings, what
/// it needs of the whole structure, and one value per role — the interfaces, the set-up
/// operators (rebuilt by an explicit step when the search directions change), the search
/// directions, and the distribution across ranks. The state of a solve is [`LatinState`].
pub struct Latin<'s> {
    model: &'s Model,
    structure: &'s Structure,
    settings: LatinSettings,
    /// What it needs of the whole structure: d_m, the macro degree, the prestress scale.
    world: WorldFacts,
    /// The interfaces that carry constraints, and what the partition left out.
    interfaces: InterfaceSet,
    /// The substructures' operators and the macro problem they make.
    operators: Operators,
    /// The links' search directions l.
    search: SearchDirections,
    /// The processes sharing the solve and what each holds.
    ranks: Distribution<'s>,
}

/// The interfaces that carry constraints, and what the partition left out.
pub(crate) struct InterfaceSet {
    /// The interfaces.
    pub(crate) list: Vec<Interface>,
    /// Per interface: its index in the `sides` of its first and of its second substructure.
    side_slots: Vec<[usize; 2]>,
    /// Interfaces left out (`drop`, or all their nodes redundant).
    dropped: usize,
    /// Nodes left out of all-macro weak interfaces (their continuity holds through others).
    redundant_nodes: usize,
}

/// The set-up operators: built once, rebuilt by [`Latin::rebuild`] (search.rs) for new search
/// directions, never changed inside an iteration's stages.
pub(crate) struct Operators {
    /// The substructures, row by row of the partition.
    pub(crate) substructures: Vec<Substructure>,
    macro_problem: MacroProblem,
    /// How the substructure operators are kept: as dense inverses (see
    /// `DENSE_BUDGET_BYTES`), and with or without Z_E (`solver.keep_z`).
    storage: OperatorStorage,
    /// With `solver.soft_modes`: the soft interface modes in the macro bases.
    soft_modes: Option<enrichment::SoftModes>,
    /// A failed rebuild whose undo failed too: the operators match no search direction, and
    /// the solve stops as stalled (it cannot happen: the undo repeats a build that succeeded).
    lost: bool,
}

/// The links' search directions l.
struct SearchDirections {
    /// Every link's l as set up (`solver.l`).
    base: Vec<f64>,
    /// Every link's l now: `base`, times ε on the cables of `slack` (status-following l).
    now: Vec<f64>,
    /// The cables whose l is ε·l: the slack set of ŝ when the operators were last built.
    slack: Vec<bool>,
}

/// The factor c of the default `d_m = c k̄ / √H` ([`auto_dm`]).
pub const DM_FACTOR: f64 = 0.25;

/// Below this many free dofs in all, an iteration runs on one thread: on the paper's case
/// (2397 dofs, 16 substructures) two threads were slower than one (547 µs against 423 µs).
const PARALLEL_MIN_DOFS: usize = 20_000;

/// ε of status-following l: a slack cable's search direction is ε·l. It must stay > 0 (a link
/// with l = 0 has no local stage); why 1e-2: docs/method.md, "Tuning log".
const SLACK_SEARCH_FACTOR: f64 = 1e-2;

/// Half-width of the band around zero tension inside which a cable keeps its search
/// direction, relative to the RMS trial tension of the cables.
const STATUS_BAND: f64 = 1e-3;

/// A cable's search direction follows its status only once the status has differed from the
/// one l was built for in this many consecutive linear stages (why 2: docs/method.md, "Tuning
/// log").
const STATUS_PERSISTENCE: u8 = 2;

/// Modules of a substructure's side per degree of its interfaces' macro basis: the default
/// degree is `p = round(H / MODULES_PER_MACRO_DEGREE)`, 1 to 16 (`auto_macro_degree`), so
/// that the micro part of an interface, what the macro problem leaves to the search direction
/// d_m, varies over about this many modules whatever the substructures' size. Why 4:
/// docs/method.md, "Tuning log".
pub const MODULES_PER_MACRO_DEGREE: f64 = 4.0;

/// H, the side of a substructure counted in modules of the paper's grid: `H = √(m / 16)` with
/// m the mean number of links per substructure (a module has 16), at least 1.
pub(crate) fn substructure_side(links: usize, substructures: usize) -> f64 {
    (links as f64 / substructures.max(1) as f64 / 16.0)
        .sqrt()
        .max(1.0)
}

/// The default degree of the macro basis on substructures of side H modules
/// ([`substructure_side`]): `round(H / 4)` between 1 (the paper's nine first-order fields, up
/// to 5 × 5 modules) and [`MAX_MACRO_DEGREE`].
pub(crate) fn auto_macro_degree(h: f64) -> usize {
    ((h / MODULES_PER_MACRO_DEGREE).round() as usize).clamp(1, MAX_MACRO_DEGREE)
}

/// The largest degree of the macro basis (`solver.macro_degree`, and the default's cap): three
/// fields per degree, and beyond the number of an interface's nodes along it the fields are
/// dependent and dropped.
pub const MAX_MACRO_DEGREE: usize = 16;

/// The default d_m, N/m: `d_m = DM_FACTOR p k̄ / √H` for a macro basis of degree p. k̄ is the
/// stiffness of a median cable and a median bar in series, `k̄ = (1/k_c + 1/k_b)⁻¹` (the softer
/// of the two governs how a load passes through a module). H is the side of a substructure in
/// modules (`substructure_side`). With p = 1 this is the optimised-Schwarz scaling
/// `d_m ∝ 1/√(hH)` at fixed module size h; a richer macro basis leaves the search direction
/// only the interface's shorter waves, which a stiffer d_m suits (measured: docs/method.md,
/// "Tuning log"). The paper's 3.92e6 ([`PAPER_DM`]) suits only the smallest substructures.
pub fn auto_dm(structure: &Structure, substructures: usize, degree: usize) -> f64 {
    let median = |cables: bool| {
        let mut k: Vec<f64> = structure
            .links
            .iter()
            .filter(|l| l.unilateral == cables)
            .map(|l| l.stiffness)
            .collect();
        k.sort_by(f64::total_cmp);
        k.get(k.len() / 2).copied()
    };
    // 1/k̄ = 1/k_c + 1/k_b, from whichever kinds the structure has.
    let compliance: f64 = [median(true), median(false)]
        .iter()
        .flatten()
        .map(|k| 1.0 / k)
        .sum();
    if !(compliance.is_finite() && compliance > 0.0) {
        return PAPER_DM;
    }
    let h = substructure_side(structure.links.len(), substructures);
    DM_FACTOR * degree.max(1) as f64 / compliance / h.sqrt()
}

impl<'s> Latin<'s> {
    /// Whether every iteration reads the whole state, not only the held substructures' and
    /// what neighbouring ranks send: status-following l (each iteration classifies every
    /// cable) and r(U) with the prestress's geometric stiffness (one pass over the whole
    /// structure).
    fn reads_whole_state(&self) -> bool {
        self.settings.policy == SearchPolicy::Status || self.model.prestress_stiffness().is_some()
    }

    /// U of the linear stage on the free dofs, interface nodes averaged over the
    /// substructures holding them.
    fn displacements(&self, subs: &[SubState]) -> Vec<f64> {
        let own = self.ranks.dof_ownership();
        (0..self.structure.n_free)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|d| own.mean(d, |e, local| subs[e].u[local]))
            .collect()
    }

    /// Every substructure's homogenised flexibility and macro basis, with l as set up (a
    /// solve's status-following l is undone first).
    pub fn homogenised(&mut self) -> Vec<Homogenised> {
        if self.any_search_slack() {
            self.set_search(vec![false; self.structure.links.len()]);
        }
        self.operators
            .substructures
            .iter()
            .enumerate()
            .map(|(e, sub)| Homogenised {
                substructure: e,
                dofs: sub
                    .sides
                    .iter()
                    .flat_map(|side| {
                        let iface = &self.interfaces.list[side.interface];
                        let neighbour = iface.topology.sides[1 - side.which];
                        iface.fields.iter().map(move |field| MacroDof {
                            interface: side.interface,
                            neighbour,
                            field: field.clone(),
                            centroid: iface.centroid,
                        })
                    })
                    .collect(),
                flexibility: sub.flexibility.clone(),
            })
            .collect()
    }

    /// The number of kernel columns (rigid and zero-energy modes of K*_E) of every
    /// substructure, row by row of the partition.
    pub fn kernel_columns(&self) -> Vec<usize> {
        self.operators
            .substructures
            .iter()
            .map(|e| e.kernel.ncols())
            .collect()
    }

    /// Interface nodes with some components held and others free (they keep only their free
    /// components' rows of continuity).
    pub fn partly_held_interface_nodes(&self) -> usize {
        self.interfaces
            .list
            .iter()
            .flat_map(|i| &i.free)
            .filter(|f| f.iter().any(|&x| x) && !f.iter().all(|&x| x))
            .count()
    }

    /// The settings it was set up with.
    pub fn settings(&self) -> &LatinSettings {
        &self.settings
    }

    /// What `tensolve check` prints about the partition.
    pub fn report(&self) -> PartitionReport {
        let weak = self
            .interfaces
            .list
            .iter()
            .filter(|i| i.topology.is_weak())
            .count();
        PartitionReport {
            substructures: self.operators.substructures.len(),
            interfaces: self.interfaces.list.len(),
            strong_interfaces: self.interfaces.list.len() - weak,
            weak_interfaces: weak,
            dropped_interfaces: self.interfaces.dropped,
            redundant_nodes: self.interfaces.redundant_nodes,
            macro_dofs: self.operators.macro_problem.n_forces,
            macro_system: (
                self.operators.macro_problem.n,
                self.operators.macro_problem.factor_entries(),
            ),
            macro_subtrees: 1 << self.operators.macro_problem.split_levels(),
            kernel_columns: self
                .operators
                .substructures
                .iter()
                .map(|s| s.kernel.ncols())
                .sum(),
            max_substructure_dofs: self
                .operators
                .substructures
                .iter()
                .map(|s| s.n_dofs())
                .max()
                .unwrap_or(0),
            dm: self.world.dm,
            macro_degree: self.world.macro_degree,
        }
    }
}
