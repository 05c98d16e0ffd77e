//! The case as the program uses it: fully typed, every number validated, every default filled
//! in from the type it configures.

use crate::model::Model;
use crate::solvers::latin::LatinSettings;
use crate::solvers::newton::{LinearSolve, NewtonSettings};
use crate::solvers::pcg_lcp::PcgLcpSettings;
use crate::solvers::{Method, Settings};
use crate::structure::{Geometry, GridLayout, GridSpec, LoadPattern, Loading, NodeFix, Structure};
use serde::Deserialize;
use std::path::PathBuf;

/// A validated case: what structure to build, which solvers to run over which load factors,
/// and which files to write.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// The module grid, its members, prestress and supports, when the case has `[grid]`.
    pub grid: Option<GridSpec>,
    /// Nodes and members: generated from `[grid]`, or read from `[structure]`'s tables.
    pub geometry: Geometry,
    /// Held displacement components: the grid's `supports.clamp`, then `supports.fix`.
    pub fixes: Vec<NodeFix>,
    /// The load pattern and the load factors.
    pub load: Load,
    /// The solvers and their settings.
    pub solver: SolverChoice,
    /// What to write, and where.
    pub output: OutputChoice,
    /// The geometric effects modelled (`model.geometry`): the model pinned, or under `auto`
    /// the one the run starts with (`linear`; a mechanism the prestress stiffens starts
    /// `large`, `crate::app::auto`).
    pub model: crate::model::GeometricModel,
    /// `model.geometry = "auto"` (the default): each row is solved with the cheapest model
    /// within `model_tolerance` of `large`, moving to `large` along the sweep where the
    /// difference grows past it.
    pub model_auto: bool,
    /// How far from the large-displacement answer a model on the initial geometry may be, as
    /// a fraction of the largest deflection and of the largest member force
    /// (`model.tolerance`; default [`crate::results::DEFAULT_MODEL_TOLERANCE`]).
    pub model_tolerance: f64,
    /// How the natural modes spread a member's mass on its ends (`modal.mass`). Default
    /// `consistent`.
    pub modal_mass: crate::model::MassKind,
    /// The designed prestress's report, when `prestress.from` is `"design"` or
    /// `"force-density"` (issue 46).
    pub design: Option<super::Design>,
    /// Point masses of the natural modes (`modal.point_mass`): node index and kg on each of
    /// its components.
    pub point_masses: Vec<(usize, f64)>,
    /// A slack cable is a failed check (`checks.forbid_slack`): listed in `checks.csv` and
    /// warned of. Default false.
    pub forbid_slack: bool,
    /// The construction stages (`[[stages]]`), solved in order, each from the last; empty
    /// without.
    pub stages: Vec<Stage>,
    /// Where a stage's solve starts (set by the stages' run, never read from the file): per
    /// node, the last stage's displacements and the load it was in equilibrium under.
    pub start: Option<StageStart>,
}

/// A construction stage (`[[stages]]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    /// Its name (`name`).
    pub name: String,
    /// The members installed at this stage (indices; `members`, and at the first stage every
    /// member no later stage installs).
    pub members: Vec<usize>,
    /// The nodes held at this stage alone, every component (`props`, indices).
    pub props: Vec<usize>,
    /// Its loads: per load case its factor, and the prestress's factor (`factors`).
    pub loads: Combination,
}

/// Where a construction stage starts: the last stage's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct StageStart {
    /// Per node, its displacement, m.
    pub displacements: Vec<[f64; 3]>,
    /// Per node, the load on it, N.
    pub load: Vec<[f64; 3]>,
}

impl Case {
    /// Refuse a solver other than newton in `methods` (`--solver`) on a run only newton does:
    /// an arc-length path, construction stages.
    pub fn newton_only(&self, methods: &[Method]) -> Result<(), super::CaseError> {
        use crate::solvers::arc_length::PathFollowing;
        let why = match (self.solver.newton.path, self.stages.is_empty()) {
            (PathFollowing::ArcLength, _) => "the arc-length path (`load.path`) is newton's",
            (_, false) => "construction stages are solved by newton",
            _ => return Ok(()),
        };
        match methods.iter().find(|m| **m != Method::Newton) {
            None => Ok(()),
            Some(other) => Err(super::CaseError::invalid(
                "--solver",
                other.name(),
                format!("{why}: give `--solver newton`, or none"),
            )),
        }
    }

    /// The model the case describes: its structure under its geometric model.
    pub fn model(&self) -> Model {
        Model::new(self.structure(), self.model)
    }

    /// Its structure under `geometry`.
    pub fn model_with(&self, geometry: crate::model::GeometricModel) -> Model {
        Model::new(self.structure(), geometry)
    }

    /// The structure the case describes, under its load at α = 1.
    pub fn structure(&self) -> Structure {
        let loading = Loading {
            nodal: self.load.pattern.nodal,
            points: self.load.points.clone(),
            gravity: self.load.gravity,
            rest_length_changes: self.load.rest_length_changes.clone(),
        };
        let mut s = Structure::new(&self.geometry, &self.fixes, &loading);
        s.point_masses = self.point_masses.clone();
        if let Some(grid) = &self.grid {
            s.layout = Some(GridLayout::new(grid.modules[0], grid.modules[1]));
            s.prestress_scale = grid.prestress;
        }
        s
    }

    /// The case with the grid built of `module`s instead (the same nodes, supports and
    /// loads: only the members change), or `None` for a case without `[grid]`. The geometry
    /// is generated again: it, not `grid`, is what [`Case::structure`] builds.
    pub fn with_module(&self, module: crate::structure::ModuleKind) -> Option<Case> {
        let mut grid = self.grid.clone()?;
        grid.module = module;
        let (mut geometry, _, _) = Structure::grid_parts(&grid);
        // The checks of a grid are per member kind: the same on every module kind.
        geometry.checks = self.geometry.checks.clone();
        Some(Case {
            grid: Some(grid),
            geometry,
            ..self.clone()
        })
    }

    /// Whether cables carry tension only.
    pub fn unilateral(&self) -> bool {
        self.geometry.unilateral
    }
}

/// The load: `α · pattern` for every α.
#[derive(Debug, Clone, PartialEq)]
pub struct Load {
    /// The force on every free node at α = 1 (`load.nodal`).
    pub pattern: LoadPattern,
    /// Point loads at α = 1 (`load.point`): node index and force, N.
    pub points: Vec<(usize, [f64; 3])>,
    /// Gravity for self-weight (`load.self_weight.gravity`), m/s².
    pub gravity: Option<[f64; 3]>,
    /// Changes Δℓ0 of members' rest lengths, m, per member index (`load.rest_length_change`
    /// and `load.temperature`, summed; never scaled by α).
    pub rest_length_changes: Vec<(usize, f64)>,
    /// The named load cases of `[[load.cases]]` (empty without: the loads above are the
    /// case's one load).
    pub cases: Vec<LoadCase>,
    /// The combinations of `[[load.combinations]]`, each solved on its own (one per load case,
    /// at factor 1, where none is given); empty without load cases.
    pub combinations: Vec<Combination>,
    /// The load factors α, in solve order; finite, at least one.
    pub alphas: Vec<f64>,
}

/// A named load case (`[[load.cases]]`): its loads at factor 1.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadCase {
    /// Its name (`name`).
    pub name: String,
    /// The force on every free node, N (`nodal`, default none).
    pub nodal: [f64; 3],
    /// Point loads: node index and force, N.
    pub points: Vec<(usize, [f64; 3])>,
    /// Gravity for self-weight, m/s².
    pub gravity: Option<[f64; 3]>,
    /// Changes Δℓ0 of members' rest lengths, m, per member index.
    pub rest_length_changes: Vec<(usize, f64)>,
    /// Support settlements (`settlement`): node index and displacement of its held
    /// components, m.
    pub settlements: Vec<(usize, [f64; 3])>,
}

/// A combination (`[[load.combinations]]`): `Σ factor · case`, solved as one load (never
/// superposed: cables go slack), the prestress scaled by its own factor.
#[derive(Debug, Clone, PartialEq)]
pub struct Combination {
    /// Its name (`name`).
    pub name: String,
    /// Per load case (index into [`Load::cases`]) its factor.
    pub factors: Vec<(usize, f64)>,
    /// The prestress's factor (`factors.prestress`, default 1).
    pub prestress: f64,
}

/// The solution the LATIN error e is measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceChoice {
    /// newton at its own tight defaults.
    #[default]
    Newton,
    /// pcg-lcp at its own tight defaults.
    PcgLcp,
    /// No reference is computed; e is left empty.
    None,
}

impl ReferenceChoice {
    /// The solver of the reference, if any.
    pub fn method(self) -> Option<Method> {
        match self {
            ReferenceChoice::Newton => Some(Method::Newton),
            ReferenceChoice::PcgLcp => Some(Method::PcgLcp),
            ReferenceChoice::None => None,
        }
    }
}

/// `[solver]`: which solvers, with which settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverChoice {
    /// Solvers to run, in order; at least one.
    pub methods: Vec<Method>,
    /// Settings of `newton`.
    pub newton: NewtonSettings,
    /// Settings of `pcg-lcp`.
    pub pcg_lcp: PcgLcpSettings,
    /// Settings of `micro-macro`; `mono-latin` uses them on a 1 × 1 partition.
    pub latin: LatinSettings,
    /// What LATIN's e is measured against.
    pub reference: ReferenceChoice,
    /// Whether `solver.subdomains` was given (else the partition is the default's).
    pub subdomains_given: bool,
}

impl SolverChoice {
    /// Whether `method` solves with the factor of K with every cable taut: pcg-lcp, and newton
    /// but for its substructured solve (`solver.linear = "krylov"`, not under `auto`, whose
    /// probe solves directly); the LATIN solvers never do.
    pub fn solves_with_taut_factor(&self, method: Method, model_auto: bool) -> bool {
        match method {
            Method::Newton => model_auto || self.newton.linear == LinearSolve::Direct,
            Method::PcgLcp => true,
            Method::MonoLatin | Method::MicroMacro => false,
        }
    }
}

impl Default for SolverChoice {
    fn default() -> Self {
        SolverChoice {
            methods: vec![Method::Newton, Method::PcgLcp],
            newton: NewtonSettings::default(),
            pcg_lcp: PcgLcpSettings::default(),
            latin: LatinSettings::default(),
            reference: ReferenceChoice::default(),
            subdomains_given: false,
        }
    }
}

impl SolverChoice {
    /// The settings `method` runs with (`mono-latin`: the LATIN settings on the 1 × 1
    /// partition).
    pub fn settings(&self, method: Method) -> Settings {
        match method {
            Method::Newton => Settings::Newton(self.newton),
            Method::PcgLcp => Settings::PcgLcp(self.pcg_lcp),
            Method::MonoLatin => Settings::MonoLatin(self.latin.monodomain()),
            Method::MicroMacro => Settings::MicroMacro(self.latin),
        }
    }

    /// The LATIN settings of `method`, `None` for the other solvers.
    pub fn latin_settings(&self, method: Method) -> Option<LatinSettings> {
        match self.settings(method) {
            Settings::MonoLatin(latin) | Settings::MicroMacro(latin) => Some(latin),
            Settings::Newton(_) | Settings::PcgLcp(_) => None,
        }
    }

    /// Whether `method` runs at its own default settings (its solution then serves as the
    /// reference of the LATIN error).
    pub fn is_default(&self, method: Method) -> bool {
        let defaults = SolverChoice::default();
        match method {
            Method::Newton => self.newton == defaults.newton,
            Method::PcgLcp => self.pcg_lcp == defaults.pcg_lcp,
            Method::MonoLatin | Method::MicroMacro => false,
        }
    }
}

/// `[output]`: which files to write, and where. Read from the case file as it is (serde's
/// defaults are [`OutputChoice::default`], unknown keys refused), then checked; each key and its
/// default written once.
#[derive(Debug, Clone, PartialEq, Deserialize)]
// What a type error says it expected (`--set output=5`: "expected struct RawOutput"): the
// message as it was before this struct was read directly.
#[serde(default, deny_unknown_fields, expecting = "struct RawOutput")]
pub struct OutputChoice {
    /// Output directory. Default `out/<case file stem>`; `--out` overrides it.
    pub dir: Option<PathBuf>,
    /// `summary.csv`, one row per solver and α. Default true.
    pub summary: bool,
    /// `tensions/{solver}_alpha{α}.csv`. Default true.
    pub tensions: bool,
    /// `displacements/{solver}_alpha{α}.csv`. Default true.
    pub displacements: bool,
    /// `forces/{solver}_alpha{α}.csv`: every member's axial force, elongation and length.
    /// Default true.
    pub forces: bool,
    /// `reactions/{solver}_alpha{α}.csv`: the reaction on every held component, and their
    /// sums. Default true.
    pub reactions: bool,
    /// `history/{solver}_alpha{α}.csv` of the LATIN solvers (e, η per iteration). Default true.
    pub history: bool,
    /// SVG figures under `plots/` (the paper's Figures 6–11). Default false.
    pub plots: bool,
    /// `vtk/{solver}_alpha{α}.vtu`, VTK XML unstructured grids for ParaView. Default false.
    pub vtk: bool,
    /// `stability.csv`: the smallest eigenvalue of the tangent stiffness at every solution
    /// (one more factorization per row). Default false.
    pub stability: bool,
    /// `summary.csv`'s `geometric_term`: the relative change of the answer by the geometric
    /// term a model on the initial geometry leaves out (one solve with the factor of K with
    /// every cable taut per row, and the warning when it is above 1 %). Default true. Without
    /// it, a run whose solvers never solve with that factor (the LATIN solvers, reference
    /// none, no stability) releases it after the mechanism check.
    pub geometric_term: bool,
    /// `homogenised/substructure_{E}.csv`: micro-macro's homogenised flexibility of every
    /// substructure and its macro basis. Default false.
    pub homogenised: bool,
    /// Factor (positive) the displacements are multiplied by in `plots/deformed_alpha{α}.svg`
    /// (Figure 8). Default none: automatic, the largest displacement drawn as a fixed fraction
    /// of the structure's size (`output::plots` says which, and its bounds).
    pub amplification: Option<f64>,
    /// The load factor the deformed-structure figure (and a general structure's member-force
    /// chart) shows: one of `load.alpha`. Default none: the largest.
    pub figure_alpha: Option<f64>,
    /// Last iteration the convergence figures (`plots/error_*.svg`, `plots/eta_*.svg`) show.
    /// Default 100, as in the paper's Figures 9–11; ≥ 1.
    pub max_plot_iterations: usize,
    /// Module kinds drawn on the same axes in `plots/error_modules.svg` (Figure 12): the
    /// case's LATIN solvers at its largest α on the same grid of each kind. Default none
    /// (no figure); drawn only with `plots = true`.
    pub compare_modules: Vec<crate::structure::ModuleKind>,
    /// How many of the lowest natural modes to write at every answer,
    /// `modes/{solver}_alpha{α}.csv` and `…_shapes.csv`; the members need a `density`.
    /// Default 0 (none).
    pub modes: usize,
}

impl Default for OutputChoice {
    fn default() -> Self {
        OutputChoice {
            dir: None,
            summary: true,
            tensions: true,
            displacements: true,
            forces: true,
            reactions: true,
            history: true,
            plots: false,
            vtk: false,
            stability: false,
            geometric_term: true,
            homogenised: false,
            amplification: None,
            figure_alpha: None,
            max_plot_iterations: 100,
            compare_modules: Vec::new(),
            modes: 0,
        }
    }
}
