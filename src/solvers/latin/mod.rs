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
//! | file | what |
//! |---|---|
//! | `settings` | [`LatinSettings`], search directions |
//! | `substructure` | one substructure's operators (K_E, Z_E, K*_E, L_E) |
//! | `macro_problem` | the homogenised macro problem, factorized once |
//! | `state` | s and ŝ per substructure |
//! | `linear_stage`, `local_stage`, `indicator` | the two stages and η |
//! | `iteration` | the two iteration orders and the `Solver` state machine |
//! | `anderson` | Anderson acceleration of the fixed point ŝ ↦ local(linear(ŝ)) |
//! | `neighbours`, `operators`, `ranks` | a solve shared by MPI ranks: what passes point to point, the set-up of each rank's operators, the layout |
//! | `search` | status-following search directions and operator rebuilds |
//! | `residual`, `dof_ownership` | r(U) of the linear stage's U, substructure by substructure; which substructure owns each dof |

mod anderson;
mod dof_ownership;
mod enrichment;
mod indicator;
mod iteration;
mod linear_stage;
mod link_share;
mod local_stage;
mod macro_problem;
mod neighbours;
mod operators;
mod ranks;
mod residual;
mod search;
mod settings;
mod shapes;
mod state;
mod status_step;
mod substructure;
#[cfg(test)]
mod tests;

#[cfg(test)]
use crate::decomposition::macro_basis::macro_basis;
use crate::decomposition::{block, Exchange, Homogenised, MacroDof, OneProcess, WeakInterfaces};
use crate::decomposition::{Interface, Interfaces, Partition};
pub use link_share::LinkShare;
use link_share::WorldFacts;
pub use ranks::{RankLayout, RankShare, VALUES_PER_ROW, VALUES_PER_SHARED_DOF};
pub use settings::{LatinSettings, SearchDirection, SearchPolicy, StopOn, PAPER_DM};
pub use state::LatinState;
pub(crate) use state::{SideState, SubState};
pub(crate) use substructure::{OperatorStorage, Substructure};

use super::{displacement_residual, SetupError};
use crate::structure::Structure;
use macro_problem::MacroProblem;

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
    /// Kernel columns of all the substructures.
    pub kernel_columns: usize,
    /// Free dofs of the largest substructure.
    pub max_substructure_dofs: usize,
    /// The interface search direction d_m used, N/m.
    pub dm: f64,
    /// The degree of the strong interfaces' macro bases.
    pub macro_degree: usize,
}

/// The LATIN solver, set up for one structure and one partition.
pub struct Latin<'s> {
    structure: &'s Structure,
    settings: LatinSettings,
    /// d_m as used: `settings.dm`, or [`auto_dm`] for this structure and partition.
    dm: f64,
    /// How the substructure operators are kept: as dense inverses (see
    /// `DENSE_BUDGET_BYTES`), and with or without Z_E (`solver.keep_z`).
    storage: OperatorStorage,
    /// Search direction l of every link as set up (`solver.l`).
    base_search: Vec<f64>,
    /// Search direction l of every link now: `base_search`, times ε on the cables of
    /// `search_slack` (status-following l).
    search: Vec<f64>,
    /// The cables whose l is ε·l: the slack set of ŝ when the operators were last built.
    search_slack: Vec<bool>,
    /// A failed rebuild whose undo failed too: the operators match no search direction, and
    /// the solve stops as stalled (it cannot happen: the undo repeats a build that succeeded).
    operators_lost: bool,
    /// The interfaces that carry constraints.
    pub(crate) interfaces: Vec<Interface>,
    /// The substructures, row by row of the partition.
    pub(crate) substructures: Vec<Substructure>,
    macro_problem: MacroProblem,
    /// Per interface: its index in the `sides` of its first and of its second substructure.
    side_slots: Vec<[usize; 2]>,
    dropped_interfaces: usize,
    redundant_nodes: usize,
    /// `(½ Σ t0² / l)^{1/2}`: the prestress in the units of Δη.
    prestress_scale: f64,
    /// Substructures per parallel task: all of them (one task, no threads) when the work of
    /// an iteration is too small to pay for the scheduling.
    chunk: usize,
    /// The processes sharing the solve ([`OneProcess`] unless set up by [`Latin::on_ranks`]).
    exchange: &'s dyn Exchange,
    /// The substructures this process holds (their operators, their halves of the linear
    /// stage): all of them on one process.
    held: std::ops::Range<usize>,
    /// Which substructure owns each free dof, for r(U).
    dof_ownership: dof_ownership::DofOwnership,
    /// On several ranks, what passes point to point after each linear stage; `None` when
    /// every iteration reads the whole state ([`Latin::reads_whole_state`]) and on one
    /// process.
    neighbours: Option<neighbours::NeighbourPlan>,
    /// What it needs of the whole structure.
    world: WorldFacts,
    /// On a rank that keeps only its substructures' links ([`LinkShare`]): per substructure,
    /// its links' indices in the whole structure (`Substructure::links` index the kept ones).
    /// `None` when `structure` is whole.
    world_links: Option<&'s [Vec<usize>]>,
    /// With `solver.soft_modes`: the soft interface modes in the macro bases.
    soft_modes: Option<enrichment::SoftModes>,
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

/// What to change when the macro problem of `settings` is singular with macro bases of
/// `degree`; `takes`: the largest lower degree with which it sets up, if any.
fn singular_macro_advice(settings: &LatinSettings, degree: usize, takes: Option<usize>) -> String {
    let asked = match settings.macro_degree {
        Some(_) => format!("`solver.macro_degree` = {degree}"),
        None => format!("the default macro degree here, {degree}"),
    };
    if let Some(largest) = takes {
        return format!(
            "{asked} is more than this partition's interfaces take (degrees 1 to 16 are valid, \
             but on small substructures a high degree leaves the macro problem singular); the \
             largest degree this partition takes is {largest}: set `solver.macro_degree` to at \
             most {largest}"
        );
    }
    let mut advice =
        vec!["try another `solver.subdomains` (fewer, larger substructures)".to_string()];
    if settings.weak != WeakInterfaces::Macro {
        advice.push("`solver.weak_interfaces = \"macro\"`".to_string());
    }
    let advice = advice.join("; or ");
    match degree > 1 {
        true => format!("{advice} (degree 1 is singular too: {asked} is not the cause)"),
        false => advice,
    }
}

/// Memory all dense substructure inverses together may take (see
/// [`crate::linalg::SpdSolver::new`]).
const DENSE_BUDGET_BYTES: usize = 16 << 20;

impl<'s> Latin<'s> {
    /// Set up: partition, interfaces, substructure operators (in parallel) and the macro
    /// problem; settings the structure cannot take are refused first
    /// ([`LatinSettings::validate`]).
    pub fn new(structure: &'s Structure, settings: LatinSettings) -> Result<Self, SetupError> {
        Self::on_ranks(structure, settings, &OneProcess)
    }

    /// Set up on the processes of `exchange` (every one calls it alike): each builds the
    /// operators of its block of substructures ([`block`]), L_E and Q_E of the others are
    /// gathered, the macro problem is factorised on every rank (see [`Exchange`]). Every rank
    /// holds `structure` whole.
    pub fn on_ranks(
        structure: &'s Structure,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        settings.validate(structure)?;
        let partition = Partition::new(structure, settings.subdomains, settings.weak);
        let world = WorldFacts::of(structure, &settings, partition.substructures.len());
        Self::set_up(structure, &partition, world, None, settings, exchange)
    }

    /// [`Latin::on_ranks`] on a rank that keeps only its substructures' links: `structure`
    /// and `share` as [`LinkShare::new`] made them, with these settings and as many ranks as
    /// `exchange` has.
    pub fn on_share(
        structure: &'s Structure,
        share: &'s LinkShare,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        assert!(
            share.settings == settings && share.ranks == exchange.size(),
            "a share of the links is used with the settings and ranks it was made for"
        );
        Self::set_up(
            structure,
            &share.partition,
            share.world,
            Some(&share.world_links),
            settings,
            exchange,
        )
    }

    /// Set up for `partition` of `structure` (whole, or with the held substructures' links
    /// alone and `world_links` saying where they lie in the whole).
    fn set_up(
        structure: &'s Structure,
        partition: &Partition,
        mut world: WorldFacts,
        world_links: Option<&'s [Vec<usize>]>,
        settings: LatinSettings,
        exchange: &'s dyn Exchange,
    ) -> Result<Self, SetupError> {
        let mut interfaces =
            Interfaces::new(structure, partition, settings.weak, world.macro_degree);
        let base_search: Vec<f64> = structure
            .links
            .iter()
            .map(|l| link_share::base_search(&settings, l.stiffness))
            .collect();
        let mut holders = vec![0u8; structure.n_nodes()];
        for topo in &partition.substructures {
            for &n in &topo.nodes {
                holders[n] += 1;
            }
        }
        // Dense inverses while all of them fit in a cache-sized budget (every iteration reads
        // them whole): 16 × 195² doubles on the paper's case (4.9 MB), not 256 of them (78 MB).
        let dense_bytes: usize = partition
            .substructures
            .iter()
            .map(|t| 8 * t.free_dofs(structure).pow(2))
            .sum();
        let held = block(
            exchange.rank(),
            exchange.size(),
            partition.substructures.len(),
        );
        let storage = OperatorStorage {
            dense: dense_bytes <= DENSE_BUDGET_BYTES,
            keep_z: settings.keep_z,
        };
        let build = |interfaces: &Interfaces, dm: f64| {
            operators::build(
                structure,
                partition,
                &interfaces.list,
                &holders,
                &base_search,
                dm,
                storage,
                (exchange, held.clone()),
            )
        };
        // d_m at the degree p: the default `c p k̄ / √H` is linear in p (`auto_dm`).
        let dm_at = |degree: usize| match settings.dm {
            Some(dm) => dm,
            None => world.dm * degree.max(1) as f64 / world.macro_degree.max(1) as f64,
        };
        let (substructures, macro_problem) = match build(&interfaces, world.dm) {
            Err(SetupError::SingularMacroProblem { .. }) => {
                // The largest degree below the one asked for that sets up, if any: tried
                // downwards, so the degree named is the largest that does (issue 42, T4).
                let takes = (1..world.macro_degree).rev().find_map(|degree| {
                    let lower = Interfaces::new(structure, partition, settings.weak, degree);
                    build(&lower, dm_at(degree))
                        .ok()
                        .map(|built| (degree, lower, built))
                });
                match (settings.macro_degree, takes) {
                    // The default degree is a guess from the substructures' size: where the
                    // partition takes less, the largest it takes is the default (and d_m with
                    // it); `check` prints both.
                    (None, Some((degree, lower, built))) => {
                        world.dm = dm_at(degree);
                        world.macro_degree = degree;
                        interfaces = lower;
                        built
                    }
                    (_, takes) => {
                        return Err(SetupError::SingularMacroProblem {
                            advice: singular_macro_advice(
                                &settings,
                                world.macro_degree,
                                takes.map(|t| t.0),
                            ),
                        })
                    }
                }
            }
            built => built?,
        };
        let dm = world.dm;
        let dof_ownership = dof_ownership::DofOwnership::of(&substructures, structure.n_free);
        let mut latin = Latin {
            structure,
            settings,
            dm,
            storage,
            search: base_search.clone(),
            search_slack: vec![false; structure.links.len()],
            operators_lost: false,
            base_search,
            interfaces: interfaces.list,
            substructures,
            macro_problem,
            side_slots: Vec::new(),
            dropped_interfaces: interfaces.dropped,
            redundant_nodes: interfaces.redundant_nodes,
            prestress_scale: world.prestress_scale,
            chunk: if structure.n_free < PARALLEL_MIN_DOFS {
                usize::MAX
            } else {
                1
            },
            exchange,
            held,
            dof_ownership,
            neighbours: None,
            world,
            world_links,
            soft_modes: None,
        };
        let mut side_slots = vec![[0usize; 2]; latin.interfaces.len()];
        for sub in &latin.substructures {
            for (slot, side) in sub.sides.iter().enumerate() {
                side_slots[side.interface][side.which] = slot;
            }
        }
        latin.side_slots = side_slots;
        if let (Some(theta), false) = (latin.settings.soft_modes, latin.interfaces.is_empty()) {
            latin.soft_modes = Some(enrichment::SoftModes::new(
                theta,
                partition.clone(),
                &latin.interfaces,
                latin.structure.links.len(),
            ));
            let all: Vec<usize> = (0..latin.substructures.len()).collect();
            let search = latin.search.clone();
            latin.enrich(&all, &search)?;
        }
        if exchange.size() > 1 && !latin.reads_whole_state() {
            latin.neighbours = Some(neighbours::NeighbourPlan::new(
                &latin.substructures,
                &latin.interfaces,
                &latin.dof_ownership,
                exchange.rank(),
                exchange.size(),
            ));
        }
        Ok(latin)
    }

    /// Whether every iteration reads the whole state, not only the held substructures' and
    /// what neighbouring ranks send: status-following l (each iteration classifies every
    /// cable) and r(U) with the prestress's geometric stiffness (one pass over the whole
    /// structure).
    fn reads_whole_state(&self) -> bool {
        self.settings.policy == SearchPolicy::Status || self.structure.geometric.is_some()
    }

    /// U of the linear stage on the free dofs, interface nodes averaged over the
    /// substructures holding them.
    fn displacements(&self, subs: &[SubState]) -> Vec<f64> {
        let n = self.structure.n_free;
        let (mut u, mut count) = (vec![0.0; n], vec![0u32; n]);
        for (sub, st) in self.substructures.iter().zip(subs) {
            for (local, &global) in sub.dof_global.iter().enumerate() {
                u[global] += st.u[local];
                count[global] += 1;
            }
        }
        u.iter_mut()
            .zip(&count)
            .for_each(|(ui, &c)| *ui /= c.max(1) as f64);
        u
    }

    /// Every substructure's homogenised flexibility and macro basis, with l as set up (a
    /// solve's status-following l is undone first).
    pub fn homogenised(&mut self) -> Vec<Homogenised> {
        if self.any_search_slack() {
            self.set_search(vec![false; self.structure.links.len()]);
        }
        self.substructures
            .iter()
            .enumerate()
            .map(|(e, sub)| Homogenised {
                substructure: e,
                dofs: sub
                    .sides
                    .iter()
                    .flat_map(|side| {
                        let iface = &self.interfaces[side.interface];
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
        self.substructures
            .iter()
            .map(|e| e.kernel.ncols())
            .collect()
    }

    /// Interface nodes with some components held and others free (they keep only their free
    /// components' rows of continuity).
    pub fn partly_held_interface_nodes(&self) -> usize {
        self.interfaces
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
            .iter()
            .filter(|i| i.topology.is_weak())
            .count();
        PartitionReport {
            substructures: self.substructures.len(),
            interfaces: self.interfaces.len(),
            strong_interfaces: self.interfaces.len() - weak,
            weak_interfaces: weak,
            dropped_interfaces: self.dropped_interfaces,
            redundant_nodes: self.redundant_nodes,
            macro_dofs: self.macro_problem.n_forces,
            macro_system: (self.macro_problem.n, self.macro_problem.factor_entries()),
            kernel_columns: self.substructures.iter().map(|s| s.kernel.ncols()).sum(),
            max_substructure_dofs: self
                .substructures
                .iter()
                .map(|s| s.n_dofs())
                .max()
                .unwrap_or(0),
            dm: self.dm,
            macro_degree: self.world.macro_degree,
        }
    }
}
