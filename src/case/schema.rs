//! Serde schema of a case file. Every section but `[grid]` and `[load]` may be left out; every
//! key but `grid.modules` and `load.alpha` has a default, the paper's value (§5.1, Table 4).
//! Unknown keys are rejected by name (`deny_unknown_fields`).

use serde::Deserialize;
use std::path::PathBuf;

/// A whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub grid: Grid,
    #[serde(default)]
    pub cables: Cables,
    #[serde(default)]
    pub bars: Bars,
    #[serde(default)]
    pub prestress: Prestress,
    #[serde(default)]
    pub supports: Supports,
    pub load: Load,
    #[serde(default)]
    pub solver: SolverKeys,
    #[serde(default)]
    pub output: Output,
}

/// `[grid]`: the module and how many times it is repeated.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// `[nx, ny]` modules along x and y.
    pub modules: [usize; 2],
    /// Module side L, m. Default 1.
    #[serde(default = "default_length")]
    pub length: f64,
    /// Module height H, m. Default 0.5.
    #[serde(default = "default_height")]
    pub height: f64,
    /// Module kind. Default standard.
    #[serde(default)]
    pub module: ModuleKind,
}

fn default_length() -> f64 {
    1.0
}
fn default_height() -> f64 {
    0.5
}

/// The repeated module (SPEC §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModuleKind {
    /// 8 nodes, 12 cables, 4 bars.
    #[default]
    Standard,
    /// The standard module plus 4 diagonal cables without prestress (paper's Figure 5 right).
    Braced,
}

/// `[cables]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cables {
    /// Young's modulus, Pa. Default 1e11.
    #[serde(default = "default_cable_young")]
    pub young: f64,
    /// Cross-section, m². Default 0.5e-4.
    #[serde(default = "default_cable_section")]
    pub section: f64,
    /// `true`: cables carry tension only. `false`: cables behave as bars (linear case).
    #[serde(default = "default_true")]
    pub unilateral: bool,
}

impl Default for Cables {
    fn default() -> Self {
        Self {
            young: default_cable_young(),
            section: default_cable_section(),
            unilateral: true,
        }
    }
}

fn default_cable_young() -> f64 {
    1e11
}
fn default_cable_section() -> f64 {
    0.5e-4
}
fn default_true() -> bool {
    true
}

/// `[bars]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bars {
    /// Young's modulus, Pa. Default 2e11.
    #[serde(default = "default_bar_young")]
    pub young: f64,
    /// Cross-section, m². Default 2.8e-4.
    #[serde(default = "default_bar_section")]
    pub section: f64,
}

impl Default for Bars {
    fn default() -> Self {
        Self {
            young: default_bar_young(),
            section: default_bar_section(),
        }
    }
}

fn default_bar_young() -> f64 {
    2e11
}
fn default_bar_section() -> f64 {
    2.8e-4
}

/// `[prestress]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prestress {
    /// Prestress p of the lower cables, N; the other members follow (SPEC §2). Default 2000.
    #[serde(default = "default_lower_cable")]
    pub lower_cable: f64,
}

impl Default for Prestress {
    fn default() -> Self {
        Self {
            lower_cable: default_lower_cable(),
        }
    }
}

fn default_lower_cable() -> f64 {
    2000.0
}

/// `[supports]`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Supports {
    /// Which lower nodes are clamped. Default lower-x-edges.
    #[serde(default)]
    pub clamp: Clamp,
}

/// Which lower (z = 0) nodes are clamped (all three displacements zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Clamp {
    /// The lower nodes of the edges x = 0 and x = nx·L (the paper's supports).
    #[default]
    LowerXEdges,
    /// The lower nodes of the edges y = 0 and y = ny·L.
    LowerYEdges,
    /// The lower nodes of all four edges.
    LowerAllEdges,
    /// The four lower corners of the grid only.
    LowerCorners,
    /// Nothing is clamped (always a mechanism: refused before solving).
    None,
}

/// `[load]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Load {
    /// Force `[fx, fy, fz]` applied to every free node at α = 1, N. Default `[0, 0, -40]`.
    #[serde(default = "default_nodal")]
    pub nodal: [f64; 3],
    /// Load factors: a list, or `{ from, to, steps }` (steps values, both ends included).
    pub alpha: toml::Value,
    /// The load factors `alpha` stands for, filled in by validation.
    #[serde(skip)]
    pub alphas: Vec<f64>,
}

fn default_nodal() -> [f64; 3] {
    [0.0, 0.0, -40.0]
}

/// A solver the case may ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Exact active-set (semismooth Newton) on the energy.
    Newton,
    /// The paper's reference: cable LCP by projected conjugate gradient.
    PcgLcp,
    /// Monodomain LATIN (augmented Lagrangian): the LATIN solver on a 1 × 1 partition.
    MonoLatin,
    /// Micro-macro LATIN domain decomposition on `solver.subdomains`.
    MicroMacro,
}

impl Method {
    pub const ALL: [Method; 4] = [
        Method::Newton,
        Method::PcgLcp,
        Method::MonoLatin,
        Method::MicroMacro,
    ];

    /// The name used in case files, on the command line and in output file names.
    pub fn name(self) -> &'static str {
        match self {
            Method::Newton => "newton",
            Method::PcgLcp => "pcg-lcp",
            Method::MonoLatin => "mono-latin",
            Method::MicroMacro => "micro-macro",
        }
    }

    /// A LATIN solver (iterates reported with e and η).
    pub fn is_latin(self) -> bool {
        matches!(self, Method::MonoLatin | Method::MicroMacro)
    }

    pub fn from_name(name: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The solution the LATIN error e is measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reference {
    #[default]
    Newton,
    PcgLcp,
    /// No reference is computed; e is left empty.
    None,
}

/// `[solver]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverKeys {
    /// Solvers to run, in order. Default `["newton", "pcg-lcp"]`.
    #[serde(default = "default_methods")]
    pub methods: Vec<Method>,
    /// Stopping tolerance of every solver asked for; absent: each solver's own default
    /// (newton: 1e-10 on the relative equilibrium residual; pcg-lcp: 1e-10 on the relative
    /// complementarity residual; LATIN: 1e-6 on η).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Iteration cap of every solver asked for; absent: each solver's own default
    /// (newton: 100; pcg-lcp: 50 000; LATIN: 1000).
    #[serde(default)]
    pub max_iterations: Option<usize>,
    /// Substructures `[sx, sy]` of micro-macro, `1 ≤ sx ≤ nx`, `1 ≤ sy ≤ ny`. Default
    /// `[min(4, nx), min(4, ny)]` (the paper's 4 × 4 on its grid); validation fills it in.
    #[serde(default)]
    pub subdomains: Option<[usize; 2]>,
    /// Interface search direction d_m, N/m. Default 3.92e6.
    #[serde(default = "default_dm")]
    pub dm: f64,
    /// Link search direction: "stiffness" (l = k per link) or a number in N/m.
    #[serde(default = "default_l")]
    pub l: toml::Value,
    /// The search direction `l` stands for, filled in by validation.
    #[serde(skip)]
    pub search: Option<crate::solvers::latin::SearchDirection>,
    /// Interfaces of ≤ 3 nodes: "macro" (default), "micro" (paper's literal text) or "drop".
    #[serde(default)]
    pub weak_interfaces: crate::solvers::latin::WeakInterfaces,
    /// What LATIN's error e is measured against. Default "newton".
    #[serde(default)]
    pub reference: Reference,
}

impl SolverKeys {
    /// The micro-macro partition (filled in by validation when the case leaves it out).
    pub fn partition(&self) -> [usize; 2] {
        self.subdomains.unwrap_or([4, 4])
    }
}

impl Default for SolverKeys {
    fn default() -> Self {
        Self {
            methods: default_methods(),
            tolerance: None,
            max_iterations: None,
            subdomains: None,
            dm: default_dm(),
            l: default_l(),
            search: None,
            weak_interfaces: Default::default(),
            reference: Default::default(),
        }
    }
}

fn default_dm() -> f64 {
    3.92e6
}
fn default_l() -> toml::Value {
    toml::Value::String("stiffness".into())
}

fn default_methods() -> Vec<Method> {
    vec![Method::Newton, Method::PcgLcp]
}

/// `[output]`: where results go and which files are written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Output directory. Default `out/<case file stem>`; `--out` overrides it.
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// `summary.csv`, one row per solver and α. Default true.
    #[serde(default = "default_true")]
    pub summary: bool,
    /// `tensions/{solver}_alpha{α}.csv`. Default true.
    #[serde(default = "default_true")]
    pub tensions: bool,
    /// `displacements/{solver}_alpha{α}.csv`. Default true.
    #[serde(default = "default_true")]
    pub displacements: bool,
    /// `history/{solver}_alpha{α}.csv` of the LATIN solvers (e, η per iteration). Default true.
    #[serde(default = "default_true")]
    pub history: bool,
    /// SVG figures under `plots/` (the paper's Figures 6–11). Default false.
    #[serde(default)]
    pub plots: bool,
    /// `vtk/{solver}_alpha{α}.vtu`, VTK XML unstructured grids for ParaView. Default false.
    #[serde(default)]
    pub vtk: bool,
    /// `stability.csv`: the smallest eigenvalue of the tangent stiffness at every solution
    /// (one more factorization per row). Default false.
    #[serde(default)]
    pub stability: bool,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            dir: None,
            summary: true,
            tensions: true,
            displacements: true,
            history: true,
            plots: false,
            vtk: false,
            stability: false,
        }
    }
}
