//! `tensolve check`: what a case describes, and whether every solver can be set up for it, as
//! a report struct (tests read it directly; the command line prints its `Display`).

use super::memory::{MemoryEstimate, Workload};
use super::setup::zero_modes_by_substructures;
use crate::case::Case;
use crate::host::Available;
use crate::model::{prestress_stability, GeometricModel, Model, PrestressStability};
use crate::output::alpha_label;
use crate::solvers::latin::{Latin, LatinSettings, PartitionReport};
use crate::solvers::{Method, SetupError, TautStiffness};
use crate::structure::{ModuleKind, Structure, StructureSize};
use std::fmt;
use std::path::PathBuf;

/// The model a case describes.
#[derive(Debug, Clone)]
pub struct ModelReport {
    /// The case file.
    pub case: PathBuf,
    /// `[nx, ny]` modules, when the case is a grid.
    pub modules: Option<[usize; 2]>,
    /// The module, when the case is a grid.
    pub module: Option<ModuleKind>,
    /// Nodes.
    pub nodes: usize,
    /// Free dofs.
    pub free_dofs: usize,
    /// Clamped nodes (all three components held).
    pub clamped_nodes: usize,
    /// Nodes held on one or two components only.
    pub partly_held_nodes: usize,
    /// Held components with a non-zero prescribed displacement (settlements).
    pub prescribed_components: usize,
    /// Held components that carry a load (`load.point`, self-weight): it goes straight to the
    /// reactions.
    pub held_load_components: usize,
    /// Cables.
    pub cables: usize,
    /// Whether the cables carry tension only.
    pub unilateral: bool,
    /// Bars.
    pub bars: usize,
    /// `max |Bᵀt0|` over all dofs, N, of the given prestress t0 (without settlements).
    pub prestress_imbalance: f64,
    /// `max |Bᵀt0|` over the free dofs, N (zero up to round-off for an admissible prestress).
    pub free_prestress_imbalance: f64,
    /// The equilibrium matrix `A = Bᵀ` (free dofs × members): rank r, s = members − r
    /// self-stress states, m = free dofs − r mechanisms (docs/method.md §7).
    pub counts: EquilibriumCounts,
    /// The lower cable prestress p, N.
    pub prestress: f64,
    /// The geometric effects modelled (`model.geometry`).
    pub geometry: GeometricModel,
    /// The nodes' bounding box, m: `[min, max]` per axis.
    pub bounding_box: [[f64; 2]; 3],
    /// The range of the members' lengths, m.
    pub lengths: [f64; 2],
    /// The range of the members' E·S, N.
    pub axial_rigidity: [f64; 2],
    /// The range of the members' stiffness k = E·S/ℓ, N/m.
    pub member_stiffness: [f64; 2],
    /// The prestress-stability test (docs/method.md §8), when there are mechanisms and at most
    /// [`crate::structure::DENSE_LIMIT`] free dofs.
    pub stability: Option<PrestressStability>,
    /// The modes the prestress does not stiffen, described (nodes they move most).
    pub unstiffened_modes: Vec<String>,
    /// When the prestress stiffens every mechanism: whether `K + K_G(t0)` is positive definite
    /// too (the models with geometric stiffness solve only then), and if not, why.
    pub geometric_regular: Option<Result<(), String>>,
    /// Whether m is a lower bound: the sparse count stops at
    /// [`crate::linalg::ZERO_MODES_COUNTED`] and no dense test counted them all.
    pub mechanisms_at_least: bool,
    /// The member with a prestress strain `|t0|/(E·S)` no material takes, and that strain.
    pub prestress_strain: Option<(u64, f64)>,
    /// The load factors.
    pub alphas: Vec<f64>,
    /// The solvers.
    pub methods: Vec<Method>,
}

pub use crate::structure::{equilibrium_counts, EquilibriumCounts};

impl ModelReport {
    /// Largest over smallest member stiffness `k = E·S/ℓ` (1 without members).
    pub fn stiffness_ratio(&self) -> f64 {
        let [k_min, k_max] = self.member_stiffness;
        if k_min > 0.0 {
            k_max / k_min
        } else {
            1.0
        }
    }
}

/// The partition of one LATIN solver.
#[derive(Debug, Clone)]
pub struct LatinReport {
    /// `mono-latin` or `micro-macro`.
    pub method: Method,
    /// Its settings.
    pub settings: LatinSettings,
    /// Its partition.
    pub partition: PartitionReport,
    /// Where its partition comes from: `solver.subdomains`, or the default's rule.
    pub partition_origin: &'static str,
}

/// What `tensolve check` found.
#[derive(Debug)]
pub struct CheckReport {
    /// The model.
    pub model: ModelReport,
    /// The stiffness with every cable taut is positive definite (no mechanism).
    pub stiffness_regular: bool,
    /// The partition of every LATIN solver set up before `error`.
    pub latin: Vec<LatinReport>,
    /// Why a solver cannot be set up: a mechanism, or a LATIN partition that cannot be.
    pub error: Option<SetupError>,
    /// The memory `tensolve run` of the case is estimated to need.
    pub memory: MemoryEstimate,
    /// The memory available, and which limit says so (`None` when none can be read).
    pub available: Option<Available>,
}

/// Why `method`'s partition of `case` is what it is, for `check`.
fn partition_origin(case: &Case, method: Method) -> &'static str {
    match (method, case.solver.subdomains_given, case.grid.is_some()) {
        (Method::MonoLatin, ..) => "one substructure, the monodomain solver",
        (_, true, _) => "solver.subdomains",
        (_, false, true) => {
            "default: per axis max(round(modules / 16), 4) and at most the modules, substructures of \
             about 16 x 16 modules"
        }
        (_, false, false) => {
            "default for a general structure: boxes of the plan of about 833 nodes each (one \
             below 1666 nodes)"
        }
    }
}

/// Check `case` (read from `path`), with `available` the memory this process could use before
/// it built anything.
pub fn check(case: &Case, path: PathBuf, available: Option<Available>) -> CheckReport {
    let case_model = case.model();
    let s = &case_model.structure;
    // The mechanism check as the run makes it: substructure by substructure when the run
    // never factorizes K whole, which then also gives the counts (m = dim ker K).
    let run = Workload::run(case, &case.solver.methods);
    let zero_modes = zero_modes_by_substructures(case, s, run.keeps_taut);
    // The given prestress t0, without the tensions prescribed displacements impose.
    let unsettled = crate::structure::NodeFix::unsettled(&case.fixes);
    let given = Structure::new(&case.geometry, &unsettled, &Default::default());
    let free_prestress_imbalance = given
        .free_prestress_imbalance()
        .iter()
        .flat_map(|(f, _)| *f)
        .fold(0.0, |m: f64, x| m.max(x.abs()));
    let model = ModelReport {
        case: path,
        modules: case.grid.as_ref().map(|g| g.modules),
        module: case.grid.as_ref().map(|g| g.module),
        nodes: s.n_nodes(),
        free_dofs: s.n_free,
        clamped_nodes: s.clamped.iter().filter(|&&c| c).count(),
        partly_held_nodes: (0..s.n_nodes())
            .filter(|&v| {
                let held = s.held_components(v).iter().filter(|&&h| h).count();
                (1..3).contains(&held)
            })
            .count(),
        prescribed_components: s.prescribed.iter().filter(|&&d| d != 0.0).count(),
        held_load_components: s.held_load.len(),
        cables: s.n_cables(),
        unilateral: case.unilateral(),
        bars: s.n_bars(),
        prestress_imbalance: given.prestress_imbalance(),
        free_prestress_imbalance,
        counts: match zero_modes {
            Some(m) => EquilibriumCounts::new(s, m),
            None => equilibrium_counts(s),
        },
        prestress: s.prestress_scale,
        geometry: case.model,
        bounding_box: s.bounding_box(),
        lengths: range(s.links.iter().map(|l| l.length)),
        axial_rigidity: range(s.links.iter().map(|l| l.stiffness * l.length)),
        member_stiffness: range(s.links.iter().map(|l| l.stiffness)),
        stability: None,
        unstiffened_modes: Vec::new(),
        geometric_regular: None,
        mechanisms_at_least: false,
        prestress_strain: crate::model::unit_slip_strain(s),
        alphas: case.load.alphas.clone(),
        methods: case.solver.methods.clone(),
    };
    let mut model = model;
    if model.counts.mechanisms > 0 {
        model.stability = prestress_stability(s);
        if let Some(st) = &model.stability {
            model.unstiffened_modes = st
                .unstiffened()
                .take(5)
                .enumerate()
                .map(|(k, mode)| mode.describe(s, k + 1))
                .collect();
            // The dense test's m is exact; the sparse count stops at ZERO_MODES_COUNTED.
            if st.mechanisms != model.counts.mechanisms {
                model.counts = EquilibriumCounts::new(s, st.mechanisms);
            }
            // Mᵀ K_G M positive definite does not make K + K_G(t0) so (a prestress too small
            // to resolve, or one that buckles the bars): the models with geometric stiffness
            // solve only when it is.
            if st.stable() {
                model.geometric_regular = Some(
                    TautStiffness::new(&Model::prestress(s.clone()))
                        .map(drop)
                        .map_err(|_| crate::model::indefinite_reason(s, Some(st))),
                );
            }
        }
    }
    model.mechanisms_at_least =
        model.stability.is_none() && model.counts.mechanisms >= crate::linalg::ZERO_MODES_COUNTED;
    let mut report = CheckReport {
        model,
        stiffness_regular: false,
        latin: Vec::new(),
        error: None,
        memory: MemoryEstimate::new(StructureSize::of(&case.geometry), &run),
        available,
    };
    let mut regular = match zero_modes {
        Some(0) => Ok(()),
        Some(modes) => Err(TautStiffness::refusal(&case_model, modes)),
        None => TautStiffness::new(&case_model).map(drop),
    };
    // The refusal's count of K's zero modes (m: k > 0 on every member) is the sparse one,
    // capped; the dense test's is exact, and the output says one m.
    if let (Err(SetupError::Mechanism { zero_modes, .. }), Some(st)) =
        (&mut regular, &report.model.stability)
    {
        *zero_modes = st.mechanisms;
    }
    if let Err(e) = regular {
        report.error = Some(e);
        return report;
    }
    report.stiffness_regular = true;
    if let Some(&method) = case.solver.methods.iter().find(|m| !m.supports(case.model)) {
        report.error = Some(SetupError::ModelNotSupported {
            solver: method.name(),
            model: case.model.name(),
        });
        return report;
    }
    for &method in &case.solver.methods {
        let Some(settings) = case.solver.latin_settings(method) else {
            continue;
        };
        match Latin::new(&case_model, settings) {
            Ok(latin) => report.latin.push(LatinReport {
                method,
                settings,
                partition_origin: partition_origin(case, method),
                partition: latin.report(),
            }),
            Err(e) => {
                report.error = Some(e);
                break;
            }
        }
    }
    report
}

/// `[min, max]` of `values` (`[0, 0]` when empty).
fn range(values: impl Iterator<Item = f64>) -> [f64; 2] {
    let [lo, hi] = values.fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], x| {
        [lo.min(x), hi.max(x)]
    });
    if lo <= hi {
        [lo, hi]
    } else {
        [0.0, 0.0]
    }
}

/// A member stiffness ratio (largest k / smallest k) beyond this is warned about: a unit slip
/// (E in GPa on some members) or a member f64 cannot resolve beside the others.
pub const STIFFNESS_RATIO_WARNING: f64 = 1e8;
/// A member longer than this (m) is warned about: coordinates in mm instead of m.
pub const LENGTH_WARNING: f64 = 1e4;

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_structure(f)?;
        self.write_model(f)?;
        self.write_run(f)?;
        if !self.stiffness_regular {
            return Ok(());
        }
        self.write_set_up(f)
    }
}

impl CheckReport {
    /// The structure: its size, supports, members and their magnitudes (with the unit-slip
    /// warnings).
    fn write_structure(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        writeln!(f, "case            {}", m.case.display())?;
        match (m.modules, m.module) {
            (Some([nx, ny]), Some(module)) => {
                writeln!(f, "grid            {nx} x {ny} modules ({module:?})")?
            }
            _ => writeln!(f, "structure       general (node and member tables)")?,
        }
        writeln!(f, "nodes           {}", m.nodes)?;
        writeln!(f, "dofs            {}", 3 * m.nodes)?;
        writeln!(f, "free dofs       {}", m.free_dofs)?;
        writeln!(
            f,
            "held nodes      {} (all three components), {} on some components; {} \
             prescribed non-zero displacement(s)",
            m.clamped_nodes, m.partly_held_nodes, m.prescribed_components
        )?;
        if m.held_load_components > 0 {
            writeln!(
                f,
                "held loads      {} load component(s) (load.point, self-weight) sit on held \
                 components: they take no part in the solve and go straight to the reactions \
                 (reactions/)",
                m.held_load_components
            )?;
        }
        writeln!(
            f,
            "cables          {} ({})",
            m.cables,
            if m.unilateral {
                "unilateral"
            } else {
                "bilateral"
            }
        )?;
        writeln!(f, "bars            {}", m.bars)?;
        let [x, y, z] = m.bounding_box;
        writeln!(
            f,
            "bounding box    x {:.4e} .. {:.4e}, y {:.4e} .. {:.4e}, z {:.4e} .. {:.4e} m",
            x[0], x[1], y[0], y[1], z[0], z[1]
        )?;
        writeln!(
            f,
            "member lengths  {:.4e} .. {:.4e} m",
            m.lengths[0], m.lengths[1]
        )?;
        writeln!(
            f,
            "member E·S      {:.4e} .. {:.4e} N",
            m.axial_rigidity[0], m.axial_rigidity[1]
        )?;
        let ratio = m.stiffness_ratio();
        if ratio > STIFFNESS_RATIO_WARNING {
            writeln!(
                f,
                "  warning: the members' stiffness E·S/ℓ spans a ratio of {ratio:.1e} (beyond \
                 {STIFFNESS_RATIO_WARNING:.0e}): is E given in Pa on every member (not GPa), S in m²?"
            )?;
        }
        if let Some((id, strain)) = m.prestress_strain {
            writeln!(
                f,
                "  warning: {}",
                crate::model::unit_slip_sentence(id, strain)
            )?;
        }
        if m.lengths[1] > LENGTH_WARNING {
            writeln!(
                f,
                "  warning: a member is {:.3e} m long (beyond {LENGTH_WARNING:.0e} m): are the \
                 coordinates in m (not mm)?",
                m.lengths[1]
            )?;
        }
        Ok(())
    }

    /// The model, the prestress's balance, and the equilibrium matrix's counts (with the
    /// mechanisms' prestress stability).
    fn write_model(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        writeln!(
            f,
            "model           geometry = {} ({})",
            m.geometry.name(),
            m.geometry.description()
        )?;
        writeln!(
            f,
            "max |B^T t0|    {:.3e} N ({:.1e} of the prestress scale)",
            m.prestress_imbalance,
            if m.prestress > 0.0 {
                m.prestress_imbalance / m.prestress
            } else {
                0.0
            }
        )?;
        writeln!(f, "  at free dofs  {:.3e} N", m.free_prestress_imbalance)?;
        let c = &m.counts;
        if m.mechanisms_at_least {
            writeln!(
                f,
                "equilibrium     A = B^T is {} x {}, rank at most {}: at least {} self-stress \
                 state(s), at least {} mechanism(s) (rigid motions included; counted up to {}, \
                 every one above {} free dofs)",
                c.free_dofs,
                c.members,
                c.rank,
                c.self_stress_states,
                c.mechanisms,
                crate::linalg::ZERO_MODES_COUNTED,
                crate::structure::DENSE_LIMIT
            )?;
        } else {
            writeln!(
                f,
                "equilibrium     A = B^T is {} x {}, rank {}: {} self-stress state(s), {} mechanism(s) (rigid motions included)",
                c.free_dofs, c.members, c.rank, c.self_stress_states, c.mechanisms
            )?;
        }
        if c.mechanisms > 0 {
            match &m.stability {
                Some(st) if st.stable() && matches!(m.geometric_regular, Some(Err(_))) => writeln!(
                    f,
                    "                prestress-stable in its {} mechanism(s) (smallest \
                         eigenvalue of M^T K_G M {:.3e} N/m), but K + K_G(t0) is not positive \
                         definite, so no model solves it: {}",
                    st.mechanisms,
                    st.smallest().unwrap_or(0.0),
                    match &m.geometric_regular {
                        Some(Err(reason)) => reason.as_str(),
                        _ => "",
                    }
                )?,
                Some(st) if st.stable() => writeln!(
                    f,
                    "                prestress-stable: the prestress stiffens all {} mechanism(s) \
                     (smallest eigenvalue of M^T K_G M {:.3e} N/m): solvable with \
                     model.geometry = prestress or large{}",
                    st.mechanisms,
                    st.smallest().unwrap_or(0.0),
                    if m.geometry.has_geometric_stiffness() {
                        ""
                    } else {
                        " (refused with the linear model, which has no geometric stiffness)"
                    }
                )?,
                Some(st) => {
                    writeln!(
                        f,
                        "                not prestress-stable: {} of {} mechanism(s) not stiffened \
                         by the prestress (refused by every model); hold more components \
                         (`supports.fix`), add members or change the prestress:",
                        st.unstiffened().count(),
                        st.mechanisms
                    )?;
                    for mode in &m.unstiffened_modes {
                        writeln!(f, "                  {mode}")?;
                    }
                }
                None => writeln!(
                    f,
                    "                a mechanism: refused with model.geometry = linear; prestress \
                     stability is tested here up to {} free dofs (with geometric stiffness, run \
                     factorizes K + K_G(t0) and refuses it when not positive definite)",
                    crate::structure::DENSE_LIMIT
                )?,
            }
        }
        Ok(())
    }

    /// What a run would do: the load factors, the solvers, the memory it needs.
    fn write_run(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        let alphas: Vec<String> = m.alphas.iter().map(|&a| alpha_label(a)).collect();
        writeln!(f, "load factors    {}", alphas.join(", "))?;
        let methods: Vec<&str> = m.methods.iter().map(|m| m.name()).collect();
        writeln!(f, "solvers         {}", methods.join(", "))?;
        writeln!(f, "memory (run)    {}", self.memory)?;
        match &self.available {
            Some(a) => writeln!(f, "  available     {a}")?,
            None => writeln!(f, "  available     unknown (no limit readable)")?,
        }
        Ok(())
    }

    /// The taut stiffness, and each LATIN solver's partition as set up.
    fn write_set_up(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        writeln!(
            f,
            "stiffness       positive definite with every cable taut{}",
            if m.geometry.has_geometric_stiffness() {
                " (K + K_G(t0), the prestress's geometric stiffness included)"
            } else {
                ""
            }
        )?;
        for LatinReport {
            method,
            settings,
            partition: r,
            partition_origin,
        } in &self.latin
        {
            let [sx, sy] = settings.subdomains;
            writeln!(f, "{}:", method.name())?;
            writeln!(
                f,
                "  substructures {} ({sx} x {sy}: {partition_origin}), largest {} free dofs",
                r.substructures, r.max_substructure_dofs
            )?;
            writeln!(
                f,
                "  interfaces    {} ({} strong, {} weak, {} dropped; weak = {:?})",
                r.interfaces,
                r.strong_interfaces,
                r.weak_interfaces,
                r.dropped_interfaces,
                settings.weak
            )?;
            let degree_origin = match settings.macro_degree {
                Some(_) => "solver.macro_degree",
                None => "default round(H/4), 1 to 16, at most what the partition takes",
            };
            match r.strong_interfaces {
                0 => writeln!(f, "  macro dofs    {}", r.macro_dofs)?,
                _ => writeln!(
                    f,
                    "  macro dofs    {} (degree {} on strong interfaces: {degree_origin})",
                    r.macro_dofs, r.macro_degree
                )?,
            }
            writeln!(f, "  kernel cols   {}", r.kernel_columns)?;
            let (unknowns, entries) = r.macro_system;
            if unknowns > 0 {
                writeln!(
                    f,
                    "  macro system  {unknowns} unknowns, its LDLt factor {entries} entries \
                     ({:.1} MB; factorised and solved on every MPI rank)",
                    8.0 * entries as f64 / 1e6
                )?;
            }
            let origin = if settings.dm.is_some() {
                "solver.dm".to_string()
            } else {
                format!("default {} p k/sqrt(H)", crate::solvers::latin::DM_FACTOR)
            };
            writeln!(f, "  d_m           {:.4e} N/m ({origin})", r.dm)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case;

    /// A grid case of `modules` under `clamp` solved by `methods` alone, with nothing that
    /// needs K's factor when the methods are LATIN's.
    fn grid_case(module: &str, clamp: &str, methods: &str) -> Case {
        case::parse(&format!(
            "[grid]\nmodules = [20, 5]\nmodule = \"{module}\"\n[supports]\nclamp = \"{clamp}\"\n\
             [load]\nalpha = [1.0]\n[solver]\nmethods = [{methods}]\nreference = \"none\"\n\
             subdomains = [2, 1]\n[output]\ngeometric_term = false\n"
        ))
        .expect("the case parses")
    }

    /// `check` of a case whose run checks for mechanisms substructure by substructure makes
    /// the same check, and takes the counts from it: the same counts, verdict and refusal as
    /// the rank factorization and K's whole factor give, with and without mechanisms (20 × 5
    /// modules: two check blocks along x).
    #[test]
    fn check_by_substructures_counts_as_the_whole_factor() {
        for module in ["standard", "braced"] {
            for clamp in ["lower-x-edges", "lower-all-edges", "lower-corners", "none"] {
                let by_parts = grid_case(module, clamp, "\"micro-macro\"");
                let whole = grid_case(module, clamp, "\"newton\"");
                let structure = by_parts.structure();
                let modes = zero_modes_by_substructures(&by_parts, &structure, false);
                let Some(modes) = modes else {
                    panic!("{module} {clamp}: not checked by substructures");
                };
                assert_eq!(
                    EquilibriumCounts::new(&structure, modes),
                    equilibrium_counts(&structure),
                    "{module} {clamp}"
                );
                assert!(!Workload::check(&by_parts).rank_factorization);
                assert!(Workload::check(&whole).rank_factorization);
                let (a, b) = (
                    check(&by_parts, "a.toml".into(), None),
                    check(&whole, "b.toml".into(), None),
                );
                assert_eq!(a.model.counts, b.model.counts, "{module} {clamp}");
                assert_eq!(a.model.counts, equilibrium_counts(&structure));
                assert_eq!(a.stiffness_regular, b.stiffness_regular, "{module} {clamp}");
                assert_eq!(
                    a.error.as_ref().map(ToString::to_string),
                    b.error.as_ref().map(ToString::to_string),
                    "{module} {clamp}"
                );
            }
        }
    }
}
