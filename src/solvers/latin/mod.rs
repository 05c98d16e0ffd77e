//! The LATIN solver (SPEC §4, paper §3–4): one implementation for `micro-macro` (an `sx × sy`
//! partition with a homogenised macro problem) and `mono-latin` (a 1 × 1 partition: no
//! interfaces, `K = Bᵀ l B`, the augmented Lagrangian method of the paper's §5.4).
//!
//! The solver alternates a local stage (constitutive laws, per link and per interface, exact;
//! [`local_stage`]) and a linear stage (equilibrium and compatibility per substructure, glued
//! by exact macro continuity; [`linear_stage`]). Iteration 0 is the linear stage from ŝ = 0;
//! iteration k ≥ 1 is a local stage on s_{k−1} followed by a linear stage. After each linear
//! stage it measures the indicator η between s and the ŝ that fed it ([`indicator`]), and
//! stops when η ≤ `tolerance` (or when Δη is at round-off against the prestress).
//!
//! | file | what |
//! |---|---|
//! | `settings` | [`LatinSettings`], search directions, weak interfaces |
//! | `partition` | substructures and interfaces of an `sx × sy` partition |
//! | `interfaces` | interfaces with their macro bases, redundant constraints left out |
//! | `macro_basis`, `kernel` | the macro fields of an interface; the kernel of K*_E |
//! | `substructure` | one substructure's operators (K_E, Z_E, K*_E, L_E) |
//! | `macro_problem` | the homogenised macro problem, factorized once |
//! | `state` | s and ŝ per substructure |
//! | `linear_stage`, `local_stage`, `indicator` | the two stages and η |

mod indicator;
mod interfaces;
mod kernel;
mod linear_stage;
mod local_stage;
mod macro_basis;
mod macro_problem;
pub mod partition;
mod settings;
mod state;
mod substructure;

pub use interfaces::Interface;
pub use local_stage::link_local_stage;
pub use macro_basis::macro_basis;
pub use partition::Partition;
pub use settings::{LatinSettings, SearchDirection, WeakInterfaces};
pub use state::{LatinState, SideState, SubState};
pub use substructure::Substructure;

use super::{Equilibrium, Measure, Progress, SetupError, Solver, Status};
use crate::structure::{Structure, CLAMPED};
use interfaces::Interfaces;
use macro_problem::MacroProblem;
use rayon::prelude::*;

/// What `tensolve check` prints about a partition.
#[derive(Debug, Clone)]
pub struct PartitionReport {
    /// Number of substructures.
    pub substructures: usize,
    /// Interfaces that carry constraints.
    pub interfaces: usize,
    /// Interfaces of more than three nodes (with a macro basis of at most nine fields).
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
    /// Kernel columns of all the substructures.
    pub kernel_columns: usize,
    /// Free dofs of the largest substructure.
    pub max_substructure_dofs: usize,
}

/// The LATIN solver, set up for one structure and one partition.
pub struct Latin<'s> {
    structure: &'s Structure,
    settings: LatinSettings,
    /// Search direction l of every link.
    search: Vec<f64>,
    /// The interfaces that carry constraints.
    pub interfaces: Vec<Interface>,
    /// The substructures, row by row of the partition.
    pub substructures: Vec<Substructure>,
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
}

/// Below this many free dofs in all, an iteration runs on one thread: on the paper's case
/// (2397 dofs, 16 substructures) two threads were slower than one (547 µs against 423 µs).
const PARALLEL_MIN_DOFS: usize = 20_000;

/// Memory all dense substructure inverses together may take (see
/// [`crate::linalg::SpdSolver::new`]).
const DENSE_BUDGET_BYTES: usize = 16 << 20;

impl<'s> Latin<'s> {
    /// Set up: partition, interfaces, substructure operators (in parallel) and the macro
    /// problem.
    pub fn new(structure: &'s Structure, settings: LatinSettings) -> Result<Self, SetupError> {
        let partition = Partition::new(structure, settings.subdomains, settings.weak);
        let interfaces = Interfaces::new(structure, &partition, settings.weak);
        let search: Vec<f64> = structure
            .links
            .iter()
            .map(|l| match settings.search {
                SearchDirection::Stiffness => l.stiffness,
                SearchDirection::Uniform(v) => v,
            })
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
            .map(|t| 8 * (3 * t.nodes.len()).pow(2))
            .sum();
        let dense = dense_bytes <= DENSE_BUDGET_BYTES;
        let built: Vec<Result<Substructure, usize>> = partition
            .substructures
            .par_iter()
            .enumerate()
            .map_init(
                || vec![CLAMPED; 3 * structure.n_nodes()],
                |scratch, (e, topo)| {
                    Substructure::new(
                        e,
                        topo,
                        structure,
                        &interfaces.list,
                        &holders,
                        &search,
                        settings.dm,
                        dense,
                        scratch,
                    )
                    .map_err(|_| e)
                },
            )
            .collect();
        let mut substructures = Vec::with_capacity(built.len());
        for b in built {
            substructures.push(b.map_err(|index| SetupError::SingularSubstructure { index })?);
        }
        let mut side_slots = vec![[0usize; 2]; interfaces.list.len()];
        for sub in &substructures {
            for (slot, side) in sub.sides.iter().enumerate() {
                side_slots[side.interface][side.which] = slot;
            }
        }
        // (½ Σ t0² / l)^{1/2}.
        let prestress_scale = (0.5
            * structure
                .links
                .iter()
                .zip(&search)
                .map(|(l, k)| l.prestress * l.prestress / k)
                .sum::<f64>())
        .sqrt();
        let macro_problem = MacroProblem::new(&substructures, &interfaces.list)
            .map_err(|_| SetupError::SingularMacroProblem)?;
        Ok(Latin {
            structure,
            settings,
            search,
            interfaces: interfaces.list,
            substructures,
            macro_problem,
            side_slots,
            dropped_interfaces: interfaces.dropped,
            redundant_nodes: interfaces.redundant_nodes,
            prestress_scale,
            chunk: if structure.n_free < PARALLEL_MIN_DOFS {
                usize::MAX
            } else {
                1
            },
        })
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
            kernel_columns: self.substructures.iter().map(|s| s.kernel.ncols()).sum(),
            max_substructure_dofs: self
                .substructures
                .iter()
                .map(|s| s.n_dofs())
                .max()
                .unwrap_or(0),
        }
    }
}

impl Solver for Latin<'_> {
    type State = LatinState;
    /// Iteration 0 is the first linear stage.
    const INIT_IS_ITERATE: bool = true;

    fn measure(&self) -> Measure {
        Measure::Indicator
    }

    fn max_iterations(&self) -> usize {
        self.settings.max_iterations
    }

    /// Iteration 0: the linear stage from ŝ = 0.
    fn init(&mut self, load: &[f64]) -> LatinState {
        let mut state = LatinState {
            subs: self.substructures.iter().map(SubState::zero).collect(),
            iteration: 0,
            eta: f64::INFINITY,
            slack_cables: 0,
            at_roundoff: false,
            load: load.to_vec(),
        };
        self.linear_stage(&state.load, &mut state.subs);
        self.measure_state(&mut state);
        state
    }

    /// One iteration: local stage on s, then linear stage.
    fn next_iter(&mut self, state: &mut LatinState) {
        self.local_stage(&mut state.subs);
        self.linear_stage(&state.load, &mut state.subs);
        state.iteration += 1;
        self.measure_state(state);
    }

    fn progress(&self, state: &LatinState) -> Progress {
        let stop = if !state.eta.is_finite() {
            Some(Status::Stalled)
        } else if state.eta <= self.settings.tolerance || state.at_roundoff {
            Some(Status::Converged)
        } else {
            None
        };
        Progress {
            iteration: state.iteration,
            residual: state.eta,
            slack_cables: state.slack_cables,
            stop,
        }
    }

    /// e of the linear stage, link by link (each link belongs to one substructure).
    fn elongations(&self, state: &LatinState) -> Vec<f64> {
        let mut e = vec![0.0; self.structure.links.len()];
        for (sub, st) in self.substructures.iter().zip(&state.subs) {
            for (j, &i) in sub.links.iter().enumerate() {
                e[i] = st.e[j];
            }
        }
        e
    }

    /// U of the linear stage (interface nodes averaged over the substructures holding them),
    /// tensions of the local stage on it (which satisfy the cable law exactly; slack cables
    /// carry exactly 0).
    fn iterate(&self, state: &LatinState) -> Equilibrium {
        let s = self.structure;
        let mut subs = state.subs.clone();
        self.local_stage(&mut subs);
        let mut u = vec![0.0; s.n_free];
        let mut count = vec![0u32; s.n_free];
        let mut tensions = vec![0.0; s.links.len()];
        let mut slack = vec![false; s.links.len()];
        for (sub, st) in self.substructures.iter().zip(&subs) {
            for (local, &global) in sub.dof_global.iter().enumerate() {
                u[global] += st.u[local];
                count[global] += 1;
            }
            for (j, &i) in sub.links.iter().enumerate() {
                slack[i] = st.slack_hat[j];
                tensions[i] = if slack[i] {
                    0.0
                } else {
                    st.t_hat[j] + s.links[i].prestress
                };
            }
        }
        u.iter_mut()
            .zip(&count)
            .for_each(|(ui, &c)| *ui /= c.max(1) as f64);
        Equilibrium {
            displacements: u,
            tensions,
            slack,
        }
    }
}
