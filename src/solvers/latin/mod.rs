//! The LATIN solver (SPEC §4, paper §3–4): one implementation for `micro-macro` (an `sx × sy`
//! partition with a homogenised macro problem) and `mono-latin` (a 1 × 1 partition: no
//! interfaces, `K = Bᵀ l B`, the augmented Lagrangian method of the paper's §5.4).
//!
//! The solver alternates a local stage (constitutive laws, per link and per interface, exact)
//! and a linear stage (equilibrium and compatibility per substructure, glued by exact macro
//! continuity). Iteration 0 is the linear stage from ŝ = 0; iteration k ≥ 1 is a local stage
//! on s_{k−1} followed by a linear stage. After each linear stage it reports the error e
//! against a reference (when given) and the indicator η between s and the ŝ that fed it.
//! It stops when η ≤ `tolerance`.

mod kernel;
mod local_stage;
mod macro_basis;
mod macro_problem;
pub mod partition;
mod substructure;

pub use macro_basis::macro_basis;
pub use partition::{Partition, WeakInterfaces};
pub use substructure::Substructure;

use super::{Equilibrium, IterationRecord, Observer, SetupError, Solution, SolveInfo, Status};
use crate::linalg::gemv;
use crate::structure::{Structure, CLAMPED};
use local_stage::{interface_local_stage, link_local_stage};
use macro_problem::MacroProblem;
use nalgebra::DMatrix;
use partition::InterfaceTopology;
use rayon::prelude::*;
use std::time::Instant;

/// The search direction `l` on the links (SPEC §4 "Search directions").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SearchDirection {
    /// `l = k` on every link (the paper's choice). The default.
    Stiffness,
    /// The same `l` (N/m) on every link.
    Uniform(f64),
}

/// Settings with their defaults.
#[derive(Debug, Clone, Copy)]
pub struct LatinSettings {
    /// Substructures along x and y. `[1, 1]` is the monodomain solver.
    pub subdomains: [usize; 2],
    /// Interface search direction d_m, N/m. Default 3.92e6 (paper §5.2).
    pub dm: f64,
    pub search: SearchDirection,
    pub weak: WeakInterfaces,
    /// Indicator η to reach. Default 1e-6.
    pub tolerance: f64,
    /// Default 1000.
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

/// An interface with its macro basis and where its macro forces sit in the macro problem.
#[derive(Debug, Clone)]
pub struct Interface {
    pub topology: InterfaceTopology,
    /// R: orthonormal columns, 3·nodes rows.
    pub basis: DMatrix<f64>,
    pub macro_offset: usize,
}

/// Exact (all-macro) continuity constraints node by node, kept independent.
///
/// A node held by several substructures (a crosspoint) lies in one interface per pair of them.
/// All-macro weak interfaces impose exact continuity of the node on each pair; around a
/// crosspoint of four one-module substructures that is six constraints of which three are
/// independent, and the macro problem would be singular. A union–find per node keeps a node in
/// an interface only when the interface joins two substructures not yet tied at that node;
/// otherwise its continuity already holds exactly through the others and the node leaves that
/// interface.
#[derive(Default)]
struct ExactContinuity {
    /// Per node: (substructure, component) of the substructures tied at it so far.
    components: std::collections::HashMap<usize, Vec<(usize, usize)>>,
}

impl ExactContinuity {
    fn keep_independent(&mut self, topology: &mut InterfaceTopology) {
        let [a, b] = topology.sides;
        let components = &mut self.components;
        topology.nodes.retain(|&node| {
            let comps = components.entry(node).or_default();
            let mut find = |e: usize| -> usize {
                match comps.iter().find(|(sub, _)| *sub == e) {
                    Some(&(_, c)) => c,
                    None => {
                        comps.push((e, e));
                        e
                    }
                }
            };
            let (ca, cb) = (find(a), find(b));
            if ca == cb {
                return false;
            }
            for entry in comps.iter_mut() {
                if entry.1 == cb {
                    entry.1 = ca;
                }
            }
            true
        });
    }
}

/// What `tensolve check` prints about a partition.
#[derive(Debug, Clone)]
pub struct PartitionReport {
    pub substructures: usize,
    pub interfaces: usize,
    pub strong_interfaces: usize,
    pub weak_interfaces: usize,
    pub dropped_interfaces: usize,
    /// Nodes left out of all-macro weak interfaces because their continuity already holds
    /// exactly through other interfaces.
    pub redundant_nodes: usize,
    pub macro_dofs: usize,
    pub kernel_columns: usize,
    /// Free dofs of the largest substructure.
    pub max_substructure_dofs: usize,
}

/// One side of an interface as E holds it: s (U, F) and ŝ (Û, F̂), full nodal vectors in the
/// interface's node order, and the load the micro search direction puts on E,
/// `F̂^m + d_m Û^m`. F is the force of the interface on E.
#[derive(Debug, Clone)]
pub struct SideState {
    pub u: Vec<f64>,
    pub f: Vec<f64>,
    pub u_hat: Vec<f64>,
    pub f_hat: Vec<f64>,
    pub hat_load: Vec<f64>,
}

/// Everything that changes along the iterations for one substructure. Per-link arrays follow
/// `Substructure::links`; `sides` follows `Substructure::sides`; `u` is U_E on E's dofs.
#[derive(Debug, Clone)]
pub struct SubState {
    pub e: Vec<f64>,
    pub t: Vec<f64>,
    pub e_hat: Vec<f64>,
    pub t_hat: Vec<f64>,
    pub slack_hat: Vec<bool>,
    pub sides: Vec<SideState>,
    pub u: Vec<f64>,
}

/// The iterate of the LATIN state machine: after [`Latin::init`] or [`Latin::next_iter`] it
/// holds s (the last linear stage) and the ŝ that fed it.
#[derive(Debug, Clone)]
pub struct LatinState {
    pub subs: Vec<SubState>,
    pub iteration: usize,
    /// η between s and ŝ.
    pub eta: f64,
    /// e against the reference, when one was given.
    pub error: Option<f64>,
    /// Slack cables of ŝ.
    pub slack_cables: usize,
    /// Δη is at round-off level against the prestress: nothing is left to iterate on.
    pub at_roundoff: bool,
    load: Vec<f64>,
    reference: Option<(Vec<f64>, f64)>,
}

pub struct Latin<'s> {
    structure: &'s Structure,
    settings: LatinSettings,
    /// Search direction l of every link.
    search: Vec<f64>,
    pub interfaces: Vec<Interface>,
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

/// Δη below this fraction of the prestress scale is round-off (a load-induced Δη on the
/// paper's case is 1e-4 of it at η = 1e-4).
const ROUNDOFF: f64 = 1e-12;

/// Memory all dense substructure inverses together may take (see [`SpdSolver::new`]).
const DENSE_BUDGET_BYTES: usize = 16 << 20;

impl<'s> Latin<'s> {
    pub fn new(structure: &'s Structure, settings: LatinSettings) -> Result<Self, SetupError> {
        let partition = Partition::new(structure, settings.subdomains, settings.weak);
        let mut offset = 0;
        let mut exact = ExactContinuity::default();
        let mut redundant_nodes = 0;
        let mut dropped_interfaces = partition.dropped_interfaces;
        let interfaces: Vec<Interface> = partition
            .interfaces
            .iter()
            .filter_map(|topology| {
                let mut topology = topology.clone();
                if topology.is_weak() && settings.weak != WeakInterfaces::Micro {
                    let before = topology.nodes.len();
                    exact.keep_independent(&mut topology);
                    redundant_nodes += before - topology.nodes.len();
                    if topology.nodes.is_empty() {
                        dropped_interfaces += 1;
                        return None;
                    }
                }
                Some(topology)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .map(|topology| {
                let positions: Vec<[f64; 3]> =
                    topology.nodes.iter().map(|&n| structure.nodes[n]).collect();
                let basis = macro_basis(&positions, settings.weak);
                let iface = Interface {
                    topology,
                    macro_offset: offset,
                    basis,
                };
                offset += iface.basis.ncols();
                iface
            })
            .collect();
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
                        &interfaces,
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
        let mut side_slots = vec![[0usize; 2]; interfaces.len()];
        for sub in &substructures {
            for (slot, side) in sub.sides.iter().enumerate() {
                side_slots[side.interface][side.which] = slot;
            }
        }
        let prestress_scale = (0.5
            * structure
                .links
                .iter()
                .zip(&search)
                .map(|(l, k)| l.prestress * l.prestress / k)
                .sum::<f64>())
        .sqrt();
        let macro_problem = MacroProblem::new(&substructures, &interfaces)
            .map_err(|_| SetupError::SingularMacroProblem)?;
        Ok(Latin {
            structure,
            settings,
            search,
            interfaces,
            substructures,
            macro_problem,
            side_slots,
            dropped_interfaces,
            redundant_nodes,
            prestress_scale,
            chunk: if structure.n_free < PARALLEL_MIN_DOFS {
                usize::MAX
            } else {
                1
            },
        })
    }

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

    fn initial_state(&self) -> Vec<SubState> {
        self.substructures
            .iter()
            .map(|sub| {
                let m = sub.links.len();
                SubState {
                    e: vec![0.0; m],
                    t: vec![0.0; m],
                    e_hat: vec![0.0; m],
                    t_hat: vec![0.0; m],
                    slack_hat: vec![false; m],
                    sides: sub
                        .sides
                        .iter()
                        .map(|side| SideState {
                            u: vec![0.0; side.rows],
                            f: vec![0.0; side.rows],
                            u_hat: vec![0.0; side.rows],
                            f_hat: vec![0.0; side.rows],
                            hat_load: vec![0.0; side.rows],
                        })
                        .collect(),
                    u: vec![0.0; sub.n_dofs()],
                }
            })
            .collect()
    }

    /// Linear stage (SPEC §4): given ŝ in `state`, find s.
    fn linear_stage(&self, load: &[f64], state: &mut [SubState]) {
        let s = self.structure;
        let dm = self.settings.dm;
        let search = &self.search;
        // Per substructure: F̂d_E, y_E = K_E⁻¹ F̂d_E, g_E = d_m R_Eᵀ C_E y_E.
        let condensed: Vec<(Vec<f64>, Vec<f64>)> = self
            .substructures
            .par_iter()
            .zip(state.par_iter())
            .with_min_len(self.chunk)
            .map(|(sub, st)| {
                let mut f: Vec<f64> = sub
                    .dof_global
                    .iter()
                    .zip(&sub.load_share)
                    .map(|(&d, &share)| load[d] * share)
                    .collect();
                for (j, &i) in sub.links.iter().enumerate() {
                    let w = st.t_hat[j] - search[i] * st.e_hat[j] + s.links[i].prestress;
                    sub.link_dofs[j].scatter(-w, &mut f);
                }
                for (side, ss) in sub.sides.iter().zip(&st.sides) {
                    for (r, &v) in ss.hat_load.iter().enumerate() {
                        f[sub.gamma_dofs[side.gamma_offset + r]] += v;
                    }
                }
                sub.factor.solve_in_place(&mut f);
                let mut g = sub.project(&f);
                g.iter_mut().for_each(|x| *x *= dm);
                (f, g)
            })
            .collect();
        let (y, g): (Vec<Vec<f64>>, Vec<Vec<f64>>) = condensed.into_iter().unzip();
        let solution = self
            .macro_problem
            .solve(&self.substructures, &self.interfaces, &g);
        let interfaces = &self.interfaces;
        let kernel_offset = &self.macro_problem.kernel_offset;
        self.substructures
            .par_iter()
            .zip(state.par_iter_mut())
            .zip(y.into_par_iter().zip(g.into_par_iter()))
            .with_min_len(self.chunk)
            .enumerate()
            .for_each(|(e, ((sub, st), (y, g)))| {
                // f_E = c_E f_Γ, a_E; u_E = L_E f_E + K⁺_E g_E + Q_E a_E.
                let mut f_e = vec![0.0; sub.n_macro];
                for side in &sub.sides {
                    let off = interfaces[side.interface].macro_offset;
                    for i in 0..side.cols {
                        f_e[side.macro_offset + i] = side.sign() * solution[off + i];
                    }
                }
                let a_e = &solution[kernel_offset[e]..kernel_offset[e] + sub.kernel.ncols()];
                let mut u_e = vec![0.0; sub.n_macro];
                gemv(&mut u_e, &sub.flexibility, &f_e, false);
                gemv(&mut u_e, &sub.k_plus, &g, true);
                gemv(&mut u_e, &sub.kernel, a_e, true);
                // U_E = y_E + d_m Z_E (u_E + f_E/d_m).
                let star: Vec<f64> = u_e.iter().zip(&f_e).map(|(u, f)| dm * u + f).collect();
                st.u.copy_from_slice(&y);
                gemv(&mut st.u, &sub.z, &star, true);
                // e_E = B_E U_E, t_E = t̂_E + l(e_E − ê_E).
                for (j, &i) in sub.links.iter().enumerate() {
                    st.e[j] = sub.link_dofs[j].elongation(&st.u);
                    st.t[j] = st.t_hat[j] + search[i] * (st.e[j] - st.e_hat[j]);
                }
                // Interfaces: U = C_E U_E, U^M = R u, F^M = R f, F^m = F̂^m + d_m Û^m − d_m(U − U^M).
                for (side, ss) in sub.sides.iter().zip(st.sides.iter_mut()) {
                    let block = side.macro_offset..side.macro_offset + side.cols;
                    let mut u_macro = vec![0.0; side.rows];
                    let mut f_macro = vec![0.0; side.rows];
                    gemv(&mut u_macro, &side.basis, &u_e[block.clone()], false);
                    gemv(&mut f_macro, &side.basis, &f_e[block], false);
                    for r in 0..side.rows {
                        let u = st.u[sub.gamma_dofs[side.gamma_offset + r]];
                        ss.u[r] = u;
                        ss.f[r] = f_macro[r] + ss.hat_load[r] - dm * (u - u_macro[r]);
                    }
                }
            });
    }

    /// Local stage (SPEC §4): given s in `state`, find ŝ.
    fn local_stage(&self, state: &mut [SubState]) {
        let s = self.structure;
        let search = &self.search;
        self.substructures
            .par_iter()
            .zip(state.par_iter_mut())
            .with_min_len(self.chunk)
            .for_each(|(sub, st)| {
                for (j, &i) in sub.links.iter().enumerate() {
                    let (e_hat, t_hat, slack) =
                        link_local_stage(&s.links[i], search[i], st.e[j], st.t[j]);
                    st.e_hat[j] = e_hat;
                    st.t_hat[j] = t_hat;
                    st.slack_hat[j] = slack;
                }
            });
        for (iface, &[ia, ib]) in self.interfaces.iter().zip(&self.side_slots) {
            // Interfaces list their substructures in increasing order: a < b.
            let [a, b] = iface.topology.sides;
            let (lo, hi) = state.split_at_mut(b);
            interface_local_stage(
                &iface.basis,
                self.settings.dm,
                &mut lo[a].sides[ia],
                &mut hi[0].sides[ib],
            );
        }
    }

    /// `(Δη, η̃)`: η = Δη/η̃ between s and the ŝ that fed it (SPEC §4 "Indicator", §5.3).
    fn indicator(&self, state: &[SubState]) -> (f64, f64) {
        let dm = self.settings.dm;
        let mut delta = 0.0;
        let mut size = 0.0;
        for (sub, st) in self.substructures.iter().zip(state) {
            for (j, &i) in sub.links.iter().enumerate() {
                let l = self.search[i];
                let d = (st.t[j] - st.t_hat[j]) + l * (st.e[j] - st.e_hat[j]);
                delta += d * d / l;
                let e_mid = 0.5 * (st.e[j] + st.e_hat[j]);
                let t_mid = 0.5 * (st.t[j] + st.t_hat[j]);
                size += l * e_mid * e_mid + t_mid * t_mid / l;
            }
            for ss in &st.sides {
                for r in 0..ss.u.len() {
                    let df = (ss.f[r] - ss.f_hat[r]) - dm * (ss.u[r] - ss.u_hat[r]);
                    delta += df * df / dm;
                    let u_mid = 0.5 * (ss.u[r] + ss.u_hat[r]);
                    let f_mid = 0.5 * (ss.f[r] + ss.f_hat[r]);
                    size += dm * u_mid * u_mid + f_mid * f_mid / dm;
                }
            }
        }
        ((0.5 * delta).sqrt(), (0.5 * size).sqrt())
    }

    /// Energy error e against the reference elongations (SPEC §4 "Error").
    fn error(&self, state: &[SubState], reference: &[f64], reference_energy: f64) -> f64 {
        let mut num = 0.0;
        for (sub, st) in self.substructures.iter().zip(state) {
            for (j, &i) in sub.links.iter().enumerate() {
                let d = st.e[j] - reference[i];
                num += d * self.search[i] * d;
            }
        }
        if reference_energy > 0.0 {
            (num / reference_energy).sqrt()
        } else {
            num.sqrt()
        }
    }

    /// Iteration 0: the linear stage from ŝ = 0. With `reference` displacements (free dofs)
    /// the error e is measured after every linear stage.
    pub fn init(&self, load: &[f64], reference: Option<&[f64]>) -> LatinState {
        let s = self.structure;
        let reference = reference.map(|u_ref| {
            let mut e = vec![0.0; s.links.len()];
            s.elongations(u_ref, &mut e);
            let energy = e
                .iter()
                .zip(&self.search)
                .map(|(ei, li)| ei * li * ei)
                .sum();
            (e, energy)
        });
        let mut state = LatinState {
            subs: self.initial_state(),
            iteration: 0,
            eta: f64::INFINITY,
            error: None,
            slack_cables: 0,
            at_roundoff: false,
            load: load.to_vec(),
            reference,
        };
        self.linear_stage(&state.load, &mut state.subs);
        self.measure(&mut state);
        state
    }

    /// One iteration: local stage on s, then linear stage.
    pub fn next_iter(&self, state: &mut LatinState) {
        self.local_stage(&mut state.subs);
        self.linear_stage(&state.load, &mut state.subs);
        state.iteration += 1;
        self.measure(state);
    }

    fn measure(&self, state: &mut LatinState) {
        let (distance, size) = self.indicator(&state.subs);
        state.eta = if size > 0.0 { distance / size } else { 0.0 };
        // η is scale-free: when s and ŝ are both round-off (no load: the exact answer is
        // zero), it is a ratio of noise. Δη at round-off against the prestress is convergence.
        state.at_roundoff = distance <= ROUNDOFF * self.prestress_scale;
        state.error = state
            .reference
            .as_ref()
            .map(|(e, energy)| self.error(&state.subs, e, *energy));
        state.slack_cables = state
            .subs
            .iter()
            .map(|st| st.slack_hat.iter().filter(|&&x| x).count())
            .sum();
    }

    /// The answer of a state: U of its linear stage, tensions of the local stage on it (which
    /// satisfy the cable law exactly; slack cables carry exactly 0).
    pub fn equilibrium(&self, state: &LatinState) -> Equilibrium {
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

    /// Iterate from [`Latin::init`] until η ≤ tolerance or `max_iterations`.
    pub fn solve(
        &self,
        load: &[f64],
        reference: Option<&[f64]>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let clock = Instant::now();
        let mut state = self.init(load, reference);
        let status = loop {
            observer.iteration(&IterationRecord {
                iteration: state.iteration,
                residual: state.eta,
                error: state.error,
                slack_cables: state.slack_cables,
                elapsed_seconds: clock.elapsed().as_secs_f64(),
            });
            if !state.eta.is_finite() {
                break Status::Stalled;
            }
            if state.eta <= self.settings.tolerance || state.at_roundoff {
                break Status::Converged;
            }
            if state.iteration >= self.settings.max_iterations {
                break Status::MaxIterations;
            }
            self.next_iter(&mut state);
        };
        Solution {
            equilibrium: self.equilibrium(&state),
            info: SolveInfo {
                status,
                iterations: state.iteration,
                residual: state.eta,
                solve_seconds: clock.elapsed().as_secs_f64(),
            },
        }
    }
}
