//! `tensolve check`: what a case describes, and whether every solver can be set up for it, as
//! a report struct (tests read it directly; the command line prints its `Display`).

mod text;

use super::auto::{linear_start, mechanism_start, RowModel};
use super::memory::{MemoryEstimate, Workload};
use super::setup::zero_modes_by_substructures;
use crate::case::Case;
use crate::host::Available;
use crate::model::{prestress_stability, GeometricModel, Model, PrestressStability};
use crate::solvers::latin::{Latin, LatinSettings, PartitionReport};
use crate::solvers::{Method, SetupError, TautStiffness};
use crate::structure::{ModuleKind, Structure, StructureSize};
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
    /// The geometric effects modelled (`model.geometry`): under `auto`, the model it starts
    /// with.
    pub geometry: GeometricModel,
    /// Under `model.geometry = "auto"`: the model it starts with, and why.
    pub auto: Option<RowModel>,
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
    /// The member too stocky for a tension structure ([`crate::structure::Geometry::thickest_member`]).
    pub thick_member: Option<(u64, f64, f64, f64)>,
    /// A form found by force densities that is flat: its spread off its plane.
    pub flat_form: Option<f64>,
    /// The load factors.
    pub alphas: Vec<f64>,
    /// The load cases' and the combinations' names (empty without `[[load.cases]]`).
    pub combinations: (Vec<String>, Vec<String>),
    /// The construction stages' names, in order (empty without `[[stages]]`).
    pub stages: Vec<String>,
    /// The solvers.
    pub methods: Vec<Method>,
    /// How newton solves its Newton systems, and on which partition, when newton is asked.
    pub newton_linear: Option<(crate::solvers::newton::LinearSolve, [usize; 2])>,
}

pub use crate::structure::{equilibrium_counts, EquilibriumCounts};

/// Under `auto`, on a mechanism (`regular` the linear model's refusal): the `large` model it
/// starts with when its prestress stiffens it (K + K_G(t0) factorizes), which `regular` and
/// the report then say; `None` otherwise (a mechanism the prestress does not stiffen keeps
/// linear's refusal).
fn auto_large_start(
    case: &Case,
    regular: &mut Result<(), SetupError>,
    report: &mut CheckReport,
) -> Option<Model> {
    if !case.model_auto || !matches!(regular, Err(SetupError::Mechanism { .. })) {
        return None;
    }
    let large = crate::app::auto::large_model(case);
    TautStiffness::new(&large).ok()?;
    *regular = Ok(());
    report.model.geometry = large.geometry();
    report.model.auto = Some(mechanism_start());
    Some(large)
}

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

/// How newton of `case` solves its Newton systems, and on which partition, when it is asked.
fn newton_linear(case: &Case) -> Option<(crate::solvers::newton::LinearSolve, [usize; 2])> {
    let newton = &case.solver.newton;
    case.solver
        .methods
        .contains(&Method::Newton)
        .then_some((newton.linear, newton.subdomains))
}

/// The names of `case`'s load cases and combinations.
fn load_names(case: &Case) -> (Vec<String>, Vec<String>) {
    let load = &case.load;
    let cases = load.cases.iter().map(|c| c.name.clone()).collect();
    (
        cases,
        load.combinations.iter().map(|c| c.name.clone()).collect(),
    )
}

/// Check `case` (read from `path`), with `available` the memory this process could use before
/// it built anything.
pub fn check(case: &Case, path: PathBuf, available: Option<Available>) -> CheckReport {
    let case_model = case.model();
    let s = &case_model.structure;
    // The mechanism check as the run makes it (by substructures where it never factorizes K).
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
        auto: case.model_auto.then(|| linear_start(case.model_tolerance)),
        bounding_box: s.bounding_box(),
        lengths: range(s.links.iter().map(|l| l.length)),
        axial_rigidity: range(s.links.iter().map(|l| l.stiffness * l.length)),
        member_stiffness: range(s.links.iter().map(|l| l.stiffness)),
        stability: None,
        unstiffened_modes: Vec::new(),
        geometric_regular: None,
        mechanisms_at_least: false,
        prestress_strain: crate::model::unit_slip_strain(s),
        thick_member: case.geometry.thickest_member(),
        flat_form: case.design.as_ref().and_then(|d| d.flat),
        alphas: case.load.alphas.clone(),
        combinations: load_names(case),
        stages: case.stages.iter().map(|s| s.name.clone()).collect(),
        methods: case.solver.methods.clone(),
        newton_linear: newton_linear(case),
    };
    let mut model = model;
    if model.counts.mechanisms > 0 {
        model.add_stability(s);
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
    // Under `auto`, a mechanism its prestress stiffens starts `large`.
    let large_model = auto_large_start(case, &mut regular, &mut report);
    let case_model = large_model.as_ref().unwrap_or(&case_model);
    // The refusal's K zero modes (m: k > 0 on every member): the dense test's count, exact.
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
    // With `large` a LATIN solver solves the problems linearised at each step: the first
    // one, at the prestressed state, is what its set-up is checked on.
    let at_rest;
    let latin_model = match case_model.updates_geometry() {
        true => {
            at_rest = crate::solvers::large::latin_problem_at_rest(case_model);
            &at_rest
        }
        false => case_model,
    };
    for &method in &case.solver.methods {
        let Some(settings) = case.solver.latin_settings(method) else {
            continue;
        };
        match Latin::new(latin_model, settings) {
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

impl ModelReport {
    /// The prestress-stability test of the mechanisms of `s` (docs/method.md §8), the modes it
    /// leaves unstiffened, and whether `K + K_G(t0)` is positive definite where it stiffens
    /// them all.
    fn add_stability(&mut self, s: &Structure) {
        self.stability = prestress_stability(s);
        let Some(st) = &self.stability else {
            return;
        };
        self.unstiffened_modes = st
            .unstiffened()
            .take(5)
            .enumerate()
            .map(|(k, mode)| mode.describe(s, k + 1))
            .collect();
        // The dense test's m is exact; the sparse count stops at ZERO_MODES_COUNTED.
        if st.mechanisms != self.counts.mechanisms {
            self.counts = EquilibriumCounts::new(s, st.mechanisms);
        }
        // Mᵀ K_G M positive definite does not make K + K_G(t0) so (a prestress too small to
        // resolve, or one that buckles the bars): the models with geometric stiffness solve
        // only when it is.
        if st.stable() {
            self.geometric_regular = Some(
                TautStiffness::new(&Model::prestress(s.clone()))
                    .map(drop)
                    .map_err(|_| crate::model::indefinite_reason(s, Some(st))),
            );
        }
    }
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
             subdomains = [2, 1]\n[output]\ngeometric_term = false\n\
             [model]\ngeometry = \"linear\"\n"
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
