//! The case file as written: serde structs mirroring its sections, every key optional but
//! `load.alpha` and one of `[grid]` / `[structure]`, unknown keys rejected by name (`deny_unknown_fields`).
//! Nothing here has a default value: [`super::convert`] takes each default from the type it
//! configures. `[output]` is read straight into [`OutputChoice`], whose defaults are its own.

use crate::decomposition::WeakInterfaces;
use crate::solvers::latin::{SearchPolicy, StopOn};
use crate::solvers::newton::LinearSolve;
use crate::solvers::Method;
use crate::structure::{Clamp, ModuleKind};
use serde::Deserialize;
use std::path::PathBuf;

use super::{OutputChoice, ReferenceChoice};

/// A list of exactly `N` values: TOML arrays of any other length are refused (serde's own
/// arrays accept and drop extra elements).
#[derive(Debug, Clone, Copy)]
pub(super) struct Exact<T, const N: usize>(pub [T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let items = Vec::<T>::deserialize(d)?;
        let found = items.len();
        <[T; N]>::try_from(items).map(Exact).map_err(|_| {
            serde::de::Error::invalid_length(found, &format!("exactly {N} values").as_str())
        })
    }
}

/// A whole case file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCase {
    pub grid: Option<RawGrid>,
    pub structure: Option<RawStructure>,
    #[serde(default)]
    pub cables: RawCables,
    #[serde(default)]
    pub bars: RawBars,
    #[serde(default)]
    pub prestress: RawPrestress,
    #[serde(default)]
    pub supports: RawSupports,
    pub load: RawLoad,
    #[serde(default)]
    pub solver: RawSolver,
    #[serde(default)]
    pub output: OutputChoice,
    #[serde(default)]
    pub model: RawModel,
    #[serde(default)]
    pub modal: RawModal,
    #[serde(default)]
    pub checks: RawChecks,
    pub stages: Option<Vec<RawStage>>,
    /// `tensolve design --rebalance`: never read from the file.
    #[serde(skip)]
    pub rebalance: bool,
}

/// `[modal]`: the natural modes' settings (`output.modes` asks for them).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawModal {
    pub mass: Option<crate::model::MassKind>,
    pub point_mass: Option<Vec<RawPointMass>>,
}

/// `[[modal.point_mass]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPointMass {
    pub nodes: Option<Vec<u64>>,
    #[serde(rename = "box")]
    pub in_box: Option<RawBox>,
    pub mass: f64,
}

/// `[model]`: the effects modelled.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawModel {
    pub geometry: Option<GeometryKey>,
    pub tolerance: Option<f64>,
}

/// `model.geometry`: a model the case pins, or `auto` (the default).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum GeometryKey {
    /// The model chosen per row (docs/method.md §8, "auto").
    Auto,
    Linear,
    Prestress,
    Large,
}

/// `[grid]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGrid {
    pub modules: Exact<usize, 2>,
    pub length: Option<f64>,
    pub height: Option<f64>,
    pub module: Option<ModuleKind>,
}

/// `[structure]`: the node and member tables, paths relative to the case file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStructure {
    pub nodes: PathBuf,
    pub members: PathBuf,
}

/// Which nodes: by id, or by a box of positions.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

/// A displacement component.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawDof {
    X,
    Y,
    Z,
}

/// `[[supports.fix]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFix {
    pub nodes: Option<Vec<u64>>,
    #[serde(rename = "box")]
    pub in_box: Option<RawBox>,
    pub dofs: Option<Vec<RawDof>>,
    pub displacement: Option<[f64; 3]>,
}

/// `[[load.point]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPoint {
    pub nodes: Option<Vec<u64>>,
    #[serde(rename = "box")]
    pub in_box: Option<RawBox>,
    pub force: [f64; 3],
}

/// `[[load.cases.settlement]]`: a load case's support settlement.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSettlement {
    pub nodes: Option<Vec<u64>>,
    #[serde(rename = "box")]
    pub in_box: Option<RawBox>,
    pub displacement: [f64; 3],
}

/// `[load.self_weight]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSelfWeight {
    pub gravity: Option<[f64; 3]>,
}

/// `[cables]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCables {
    pub young: Option<f64>,
    pub section: Option<f64>,
    pub unilateral: Option<bool>,
    pub strength: Option<f64>,
    pub breaking_load: Option<f64>,
    pub density: Option<f64>,
}

/// `[bars]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBars {
    pub young: Option<f64>,
    pub section: Option<f64>,
    pub strength: Option<f64>,
    pub inertia: Option<f64>,
    pub buckling_curve: Option<String>,
    pub density: Option<f64>,
}

/// `[checks]`: the partial factors of EN 1993's member checks, and whether a cable may go
/// slack.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawChecks {
    pub gamma_m1: Option<f64>,
    pub gamma_r: Option<f64>,
    pub forbid_slack: Option<bool>,
}

/// `[prestress]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPrestress {
    pub lower_cable: Option<f64>,
    pub from: Option<RawPrestressSource>,
    pub member: Option<u64>,
    pub force: Option<f64>,
    pub targets: Option<std::collections::BTreeMap<String, f64>>,
    pub min_cable: Option<f64>,
    pub force_density: Option<std::collections::BTreeMap<String, f64>>,
}

/// `prestress.from`: where a general structure's prestress comes from instead of the members
/// table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub(super) enum RawPrestressSource {
    /// The structure's single self-stress state, scaled.
    SelfStress,
    /// The grouped self-stress state nearest to `targets` (issue 46).
    Design,
    /// Schek's force density method: the free nodes placed by `force_density` (issue 46).
    ForceDensity,
}

/// `[supports]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSupports {
    pub clamp: Option<Clamp>,
    pub fix: Option<Vec<RawFix>>,
}

/// `[load]`. `alpha` is a list or a `{ from, to, steps }` table, read by hand so that each
/// mistake gets its own message.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLoad {
    pub nodal: Option<Exact<f64, 3>>,
    pub point: Option<Vec<RawPoint>>,
    pub self_weight: Option<RawSelfWeight>,
    pub rest_length_change: Option<Vec<RawRestLengthChange>>,
    pub temperature: Option<Vec<RawTemperature>>,
    pub cases: Option<Vec<RawLoadCase>>,
    pub combinations: Option<Vec<RawCombination>>,
    pub path: Option<crate::solvers::arc_length::PathFollowing>,
    pub alpha: toml::Value,
}

/// `[[load.cases]]`: a named load case, with `[load]`'s loads.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLoadCase {
    pub name: String,
    pub settlement: Option<Vec<RawSettlement>>,
    pub nodal: Option<Exact<f64, 3>>,
    pub point: Option<Vec<RawPoint>>,
    pub self_weight: Option<RawSelfWeight>,
    pub rest_length_change: Option<Vec<RawRestLengthChange>>,
    pub temperature: Option<Vec<RawTemperature>>,
}

/// `[[stages]]`: a construction stage.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStage {
    pub name: String,
    pub members: Option<Vec<u64>>,
    pub props: Option<Vec<u64>>,
    pub factors: Option<std::collections::BTreeMap<String, f64>>,
}

/// `[[load.combinations]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCombination {
    pub name: String,
    pub factors: std::collections::BTreeMap<String, f64>,
}

/// `[[load.rest_length_change]]`: actuation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRestLengthChange {
    pub members: Option<Vec<u64>>,
    pub group: Option<String>,
    pub kind: Option<String>,
    pub change: f64,
}

/// `[[load.temperature]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTemperature {
    pub members: Option<Vec<u64>>,
    pub group: Option<String>,
    pub kind: Option<String>,
    pub change: f64,
    pub expansion: f64,
}

/// `[solver]`. `l` is `"stiffness"` or a number, read by hand.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSolver {
    pub methods: Option<Vec<Method>>,
    pub tolerance: Option<f64>,
    pub max_iterations: Option<usize>,
    pub subdomains: Option<Exact<usize, 2>>,
    pub dm: Option<f64>,
    pub l: Option<toml::Value>,
    pub weak_interfaces: Option<WeakInterfaces>,
    pub relaxation: Option<f64>,
    pub anderson: Option<usize>,
    pub search_direction: Option<SearchPolicy>,
    pub forcing: Option<f64>,
    pub stop_on: Option<StopOn>,
    pub residual_tolerance: Option<f64>,
    pub keep_z: Option<bool>,
    pub soft_modes: Option<f64>,
    pub macro_degree: Option<usize>,
    pub reference: Option<ReferenceChoice>,
    pub linear: Option<LinearSolve>,
}

/// The loads of `[load]` or of one `[[load.cases]]` entry, as written.
pub(super) struct LoadParts<'a> {
    pub nodal: Option<[f64; 3]>,
    pub point: &'a Option<Vec<RawPoint>>,
    pub self_weight: &'a Option<RawSelfWeight>,
    pub rest_length_change: &'a Option<Vec<RawRestLengthChange>>,
    pub temperature: &'a Option<Vec<RawTemperature>>,
}

impl RawLoad {
    /// `[load]`'s own loads.
    pub(super) fn parts(&self) -> LoadParts<'_> {
        LoadParts {
            nodal: self.nodal.as_ref().map(|n| n.0),
            point: &self.point,
            self_weight: &self.self_weight,
            rest_length_change: &self.rest_length_change,
            temperature: &self.temperature,
        }
    }
}

impl RawLoadCase {
    /// The case's loads.
    pub(super) fn parts(&self) -> LoadParts<'_> {
        LoadParts {
            nodal: self.nodal.as_ref().map(|n| n.0),
            point: &self.point,
            self_weight: &self.self_weight,
            rest_length_change: &self.rest_length_change,
            temperature: &self.temperature,
        }
    }
}

impl LoadParts<'_> {
    /// Whether any load is written.
    pub(super) fn any(&self) -> bool {
        self.nodal.is_some()
            || self.point.is_some()
            || self.self_weight.is_some()
            || self.rest_length_change.is_some()
            || self.temperature.is_some()
    }
}
