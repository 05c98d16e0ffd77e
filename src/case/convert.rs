//! From the raw file to a typed [`Case`]: every number checked (finite; positive where
//! physical; bounded so that nothing can overflow), every default taken from the type it
//! configures. Each error names the key, the value and the fix.

use super::raw::{RawBox, RawCase};
use super::{Case, CaseError, Load, OutputChoice, SolverChoice};
use crate::solvers::latin::SearchDirection;
use crate::structure::{CableSpec, Geometry, GridSpec, LoadPattern, Material, NodeFix};
use std::collections::HashMap;
use std::path::Path;

/// The deepest Anderson history a case may ask for: each level keeps two vectors of the size
/// of the LATIN state, and depths beyond about 10 did not pay on any case measured.
const MAX_ANDERSON_DEPTH: usize = 50;

/// A number as a user would write it: exponent form when very large or very small.
pub(crate) fn number(x: f64) -> String {
    if x != 0.0 && x.is_finite() && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Largest magnitude accepted for any physical number: far beyond any structure, far enough
/// from f64's range (1e308) that stiffnesses, loads and their products cannot overflow.
pub(super) const PHYSICAL_MAX: f64 = 1e15;

/// Smallest magnitude accepted for a positive physical number: products of a few of them
/// (k = EA/L, k², the stiffness's pivots) stay far from f64's underflow (1e-308), so a tiny
/// modulus is refused here by name rather than as a "mechanism" (issue 13, E4).
const PHYSICAL_MIN: f64 = 1e-15;

/// A physical quantity: finite, between [`PHYSICAL_MIN`] and [`PHYSICAL_MAX`].
fn positive(key: &str, value: f64, what: &str) -> Result<(), CaseError> {
    if value.is_finite() && (PHYSICAL_MIN..=PHYSICAL_MAX).contains(&value) {
        Ok(())
    } else {
        Err(CaseError::invalid(
            key,
            number(value),
            format!(
                "give {what} as a number > 0, at least {PHYSICAL_MIN:e} and ≤ {PHYSICAL_MAX:e}"
            ),
        ))
    }
}

/// A finite number of magnitude at most `max`.
pub(super) fn bounded(key: &str, value: f64, max: f64, what: &str) -> Result<(), CaseError> {
    if value.is_finite() && value.abs() <= max {
        Ok(())
    } else {
        Err(CaseError::invalid(
            key,
            number(value),
            format!("give {what} as a finite number of magnitude ≤ {max:e}"),
        ))
    }
}

/// Largest load factor accepted.
const ALPHA_MAX: f64 = 1e6;

/// `[grid]` of a raw case: the grid's description, checked.
fn grid_spec(raw: &RawCase, g: &super::raw::RawGrid) -> Result<GridSpec, CaseError> {
    let paper = GridSpec::default();
    let [nx, ny] = g.modules.0;
    if nx == 0 || ny == 0 {
        return Err(CaseError::invalid(
            "grid.modules",
            format!("[{nx}, {ny}]"),
            "give at least one module along each axis, e.g. [16, 16]",
        ));
    }
    const MAX_MODULES: usize = 4_000_000;
    if nx.saturating_mul(ny) > MAX_MODULES {
        return Err(CaseError::invalid(
            "grid.modules",
            format!("[{nx}, {ny}]"),
            format!("at most {MAX_MODULES} modules in all"),
        ));
    }
    let length = g.length.unwrap_or(paper.length);
    positive("grid.length", length, "the module side L in m")?;
    let height = g.height.unwrap_or(paper.height);
    positive("grid.height", height, "the module height H in m")?;
    let cables = Material {
        young: raw.cables.young.unwrap_or(paper.cables.material.young),
        section: raw.cables.section.unwrap_or(paper.cables.material.section),
    };
    positive(
        "cables.young",
        cables.young,
        "the cables' Young's modulus in Pa",
    )?;
    positive(
        "cables.section",
        cables.section,
        "the cables' cross-section in m²",
    )?;
    let bars = Material {
        young: raw.bars.young.unwrap_or(paper.bars.young),
        section: raw.bars.section.unwrap_or(paper.bars.section),
    };
    positive("bars.young", bars.young, "the bars' Young's modulus in Pa")?;
    positive(
        "bars.section",
        bars.section,
        "the bars' cross-section in m²",
    )?;
    let p = raw.prestress.lower_cable.unwrap_or(paper.prestress);
    if !(p.is_finite() && (0.0..=PHYSICAL_MAX).contains(&p)) {
        return Err(CaseError::invalid(
            "prestress.lower_cable",
            number(p),
            format!("give the lower cables' prestress in N as a number ≥ 0 and ≤ {PHYSICAL_MAX:e}"),
        ));
    }
    Ok(GridSpec {
        modules: [nx, ny],
        length,
        height,
        module: g.module.unwrap_or(paper.module),
        cables: CableSpec {
            material: cables,
            unilateral: raw.cables.unilateral.unwrap_or(paper.cables.unilateral),
        },
        bars,
        prestress: p,
        clamp: raw.supports.clamp.unwrap_or(paper.clamp),
    })
}

/// The nodes (indices) a `nodes = [...]` list or a `box = { min, max }` selects.
fn select(
    key: &str,
    geometry: &Geometry,
    index_of: &HashMap<u64, usize>,
    ids: &Option<Vec<u64>>,
    in_box: &Option<RawBox>,
) -> Result<Vec<usize>, CaseError> {
    match (ids, in_box) {
        (Some(ids), None) => {
            if ids.is_empty() {
                return Err(CaseError::invalid(
                    format!("{key}.nodes"),
                    "[]",
                    "name at least one node id",
                ));
            }
            ids.iter()
                .map(|id| {
                    index_of.get(id).copied().ok_or_else(|| {
                        CaseError::invalid(
                            format!("{key}.nodes"),
                            id,
                            "name a node of the structure (grid: its node index; [structure]: an id of the nodes table)",
                        )
                    })
                })
                .collect()
        }
        (None, Some(b)) => {
            for (k, (&lo, &hi)) in b.min.iter().zip(&b.max).enumerate() {
                bounded(
                    &format!("{key}.box.min[{k}]"),
                    lo,
                    PHYSICAL_MAX,
                    "each coordinate in m",
                )?;
                bounded(
                    &format!("{key}.box.max[{k}]"),
                    hi,
                    PHYSICAL_MAX,
                    "each coordinate in m",
                )?;
            }
            // Boundaries count as inside, to a relative 1e-9 of the structure's size.
            let size = geometry
                .nodes
                .iter()
                .flatten()
                .fold(0.0, |m: f64, x| m.max(x.abs()))
                .max(1.0);
            let tol = 1e-9 * size;
            let nodes: Vec<usize> = (0..geometry.nodes.len())
                .filter(|&n| {
                    let p = geometry.nodes[n];
                    (0..3).all(|k| p[k] >= b.min[k] - tol && p[k] <= b.max[k] + tol)
                })
                .collect();
            if nodes.is_empty() {
                return Err(CaseError::invalid(
                    format!("{key}.box"),
                    format!("{{ min = {:?}, max = {:?} }}", b.min, b.max),
                    "the box holds no node: widen it (positions in m, boundaries included)",
                ));
            }
            Ok(nodes)
        }
        _ => Err(CaseError::invalid(
            key.to_string(),
            "",
            "give exactly one of `nodes = [ids]` and `box = { min = [x, y, z], max = [x, y, z] }`",
        )),
    }
}

/// A force or displacement vector: finite components.
fn vector(key: &str, v: [f64; 3], max: f64, what: &str) -> Result<[f64; 3], CaseError> {
    for (k, &x) in v.iter().enumerate() {
        bounded(&format!("{key}[{k}]"), x, max, what)?;
    }
    Ok(v)
}

/// Relative prestress imbalance above which a prestress is refused: `|Bᵀt0|` at a node
/// against the `Σ|t0|` of the links meeting there.
const IMBALANCE_RELATIVE: f64 = 1e-9;

/// Refuse a prestress not in equilibrium at the free dofs (docs/method.md §7), naming the worst nodes.
fn check_prestress(geometry: &Geometry, fixes: &[NodeFix]) -> Result<(), CaseError> {
    // A unilateral cable carries tension only: a compressed prestress is released at once
    // (every solver would answer with the prestress gone and call it converged).
    if geometry.unilateral {
        let compressed: Vec<&crate::structure::Member> = geometry
            .members
            .iter()
            .filter(|m| m.kind.is_cable() && m.prestress < 0.0)
            .collect();
        if !compressed.is_empty() {
            let ids: Vec<String> = compressed
                .iter()
                .take(10)
                .map(|m| m.id.to_string())
                .collect();
            let most = compressed.iter().fold(0.0f64, |x, m| x.min(m.prestress));
            return Err(CaseError::invalid(
                "prestress",
                format!(
                    "{} unilateral cable(s) in compression, member(s) {}{} (down to {} N)",
                    compressed.len(),
                    ids.join(", "),
                    if compressed.len() > 10 { ", …" } else { "" },
                    number(most)
                ),
                "a cable carries tension only, so its prestress t0 must be ≥ 0 (tension > 0): \
                 check the sign of the members table's prestress column (a self-stress state may \
                 be given with the opposite sign), make those members bars, or set \
                 `cables.unilateral = false`",
            ));
        }
    }
    // Without settlements the effective prestress is t0 itself; with them, the imposed
    // part is carried by the supports on purpose, so check t0 on the same free dofs.
    let s =
        crate::structure::Structure::new(geometry, &NodeFix::unsettled(fixes), &Default::default());
    let mut worst: Vec<(f64, usize, f64)> = s
        .free_prestress_imbalance()
        .iter()
        .enumerate()
        .filter_map(|(n, (f, scale))| {
            let norm = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            (norm > IMBALANCE_RELATIVE * scale.max(f64::MIN_POSITIVE)).then_some((
                norm / scale,
                n,
                norm,
            ))
        })
        .collect();
    if worst.is_empty() {
        return Ok(());
    }
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    let names: Vec<String> = worst
        .iter()
        .take(3)
        .map(|&(_, n, norm)| {
            format!(
                "node {} (|Bᵀt0| = {} N)",
                geometry.node_ids[n],
                number(norm)
            )
        })
        .collect();
    Err(CaseError::invalid(
        "prestress",
        format!("{} unbalanced node(s): {}", worst.len(), names.join(", ")),
        "give member prestresses t0 in equilibrium at every free node (Bᵀt0 = 0 on the free dofs), or hold those nodes",
    ))
}

/// The typed case of a raw one, checked in file order; `[structure]` tables are read
/// relative to `base`.
pub(super) fn convert(raw: RawCase, base: &Path) -> Result<Case, CaseError> {
    let unilateral = raw
        .cables
        .unilateral
        .unwrap_or(GridSpec::default().cables.unilateral);
    let (grid, mut geometry, mut fixes) = match (&raw.grid, &raw.structure) {
        (Some(g), None) => {
            let spec = grid_spec(&raw, g)?;
            // Refuse a grid whose structure alone does not fit before generating it.
            let layout = crate::structure::GridLayout::new(spec.modules[0], spec.modules[1]);
            let size = super::memory::Size {
                nodes: layout.n_nodes(),
                links: spec.module.links_per_module() * spec.modules[0] * spec.modules[1],
            };
            super::memory::ensure_fits(
                &super::memory::MemoryEstimate::structure(size),
                "loading the case",
            )?;
            let (geometry, _, fixes) = crate::structure::Structure::grid_parts(&spec);
            (Some(spec), geometry, fixes)
        }
        (None, Some(st)) => {
            let general_only = |key: &str, given: bool| {
                if given {
                    Err(CaseError::invalid(
                        key.to_string(),
                        "given",
                        "with [structure], members carry their own material and prestress in the members table, and supports are given by [[supports.fix]]: remove this key",
                    ))
                } else {
                    Ok(())
                }
            };
            general_only("cables.young", raw.cables.young.is_some())?;
            general_only("cables.section", raw.cables.section.is_some())?;
            general_only("bars.young", raw.bars.young.is_some())?;
            general_only("bars.section", raw.bars.section.is_some())?;
            general_only("prestress.lower_cable", raw.prestress.lower_cable.is_some())?;
            if raw
                .output
                .compare_modules
                .as_ref()
                .is_some_and(|kinds| !kinds.is_empty())
            {
                return Err(CaseError::invalid(
                    "output.compare_modules".to_string(),
                    "given",
                    "it compares the module kinds of a [grid]; a [structure] has none: remove this key",
                ));
            }
            general_only("supports.clamp", raw.supports.clamp.is_some())?;
            let geometry = super::tables::load_geometry(
                &base.join(&st.nodes),
                &base.join(&st.members),
                unilateral,
            )?;
            (None, geometry, Vec::new())
        }
        (Some(_), Some(_)) => return Err(CaseError::invalid(
            "grid",
            "[grid] and [structure]",
            "give exactly one of [grid] (the module grid) and [structure] (node and member tables)",
        )),
        (None, None) => {
            return Err(CaseError::Syntax(
                "missing field `grid`: give [grid] with `modules = [nx, ny]`, or [structure] \
                 with `nodes` and `members` tables"
                    .into(),
            ))
        }
    };
    let index_of: HashMap<u64, usize> = geometry
        .node_ids
        .iter()
        .enumerate()
        .map(|(i, &id)| (id, i))
        .collect();
    for (i, f) in raw.supports.fix.iter().flatten().enumerate() {
        let key = format!("supports.fix[{i}]");
        let nodes = select(&key, &geometry, &index_of, &f.nodes, &f.in_box)?;
        let mut dofs = [f.dofs.is_none(); 3];
        for d in f.dofs.iter().flatten() {
            dofs[*d as usize] = true;
        }
        if dofs == [false; 3] {
            return Err(CaseError::invalid(
                format!("{key}.dofs"),
                "[]",
                "name the held components, e.g. [\"x\", \"y\", \"z\"] (the default)",
            ));
        }
        let displacement = vector(
            &format!("{key}.displacement"),
            f.displacement.unwrap_or([0.0; 3]),
            PHYSICAL_MAX,
            "each prescribed displacement component in m",
        )?;
        fixes.extend(nodes.into_iter().map(|node| NodeFix {
            node,
            dofs,
            displacement,
        }));
    }
    super::prestress::apply(
        &raw.prestress,
        grid.is_some(),
        &mut geometry,
        &fixes,
        raw.model.geometry.unwrap_or_default(),
    )?;
    check_prestress(&geometry, &fixes)?;

    let default_nodal = if grid.is_some() {
        LoadPattern::default().nodal
    } else {
        [0.0; 3]
    };
    let pattern = LoadPattern {
        nodal: raw.load.nodal.map_or(default_nodal, |n| n.0),
    };
    for (c, &f) in pattern.nodal.iter().enumerate() {
        let key = ["load.nodal[0]", "load.nodal[1]", "load.nodal[2]"][c];
        bounded(key, f, PHYSICAL_MAX, "each nodal force component in N")?;
    }
    let mut points = Vec::new();
    for (i, p) in raw.load.point.iter().flatten().enumerate() {
        let key = format!("load.point[{i}]");
        let nodes = select(&key, &geometry, &index_of, &p.nodes, &p.in_box)?;
        let force = vector(
            &format!("{key}.force"),
            p.force,
            PHYSICAL_MAX,
            "each force component in N",
        )?;
        points.extend(nodes.into_iter().map(|n| (n, force)));
    }
    let gravity = match &raw.load.self_weight {
        None => None,
        Some(w) => Some(vector(
            "load.self_weight.gravity",
            w.gravity.unwrap_or([0.0, 0.0, -9.81]),
            1e6,
            "each gravity component in m/s²",
        )?),
    };
    let load = Load {
        pattern,
        points,
        gravity,
        alphas: alpha_values(&raw.load.alpha)?,
    };

    let modules = grid.as_ref().map(|g| g.modules);
    let solver = solver_choice(raw.solver, modules)?;
    let defaults = OutputChoice::default();
    let o = raw.output;
    if o.dir.as_ref().is_some_and(|d| d.as_os_str().is_empty()) {
        return Err(CaseError::invalid(
            "output.dir",
            "\"\"",
            "give a directory (\".\" for the current one), or remove the key for out/<case file name>",
        ));
    }
    let output = OutputChoice {
        dir: o.dir,
        summary: o.summary.unwrap_or(defaults.summary),
        tensions: o.tensions.unwrap_or(defaults.tensions),
        displacements: o.displacements.unwrap_or(defaults.displacements),
        forces: o.forces.unwrap_or(defaults.forces),
        reactions: o.reactions.unwrap_or(defaults.reactions),
        history: o.history.unwrap_or(defaults.history),
        plots: o.plots.unwrap_or(defaults.plots),
        vtk: o.vtk.unwrap_or(defaults.vtk),
        stability: o.stability.unwrap_or(defaults.stability),
        homogenised: o.homogenised.unwrap_or(defaults.homogenised),
        amplification: o.amplification.unwrap_or(defaults.amplification),
        max_plot_iterations: o
            .max_plot_iterations
            .unwrap_or(defaults.max_plot_iterations),
        compare_modules: o.compare_modules.unwrap_or(defaults.compare_modules),
    };
    positive(
        "output.amplification",
        output.amplification,
        "the factor the displacements are drawn multiplied by (the paper's is 10)",
    )?;
    let kinds = &output.compare_modules;
    if let Some(twice) = kinds
        .iter()
        .enumerate()
        .find(|(i, k)| kinds[..*i].contains(k))
    {
        return Err(CaseError::invalid(
            "output.compare_modules",
            format!("{:?}", kinds.iter().map(|k| k.name()).collect::<Vec<_>>()),
            format!(
                "list each module kind once (`{}` is listed twice), e.g. [\"standard\", \"braced\"]",
                twice.1.name()
            ),
        ));
    }
    if !kinds.is_empty() && !output.plots {
        return Err(CaseError::invalid(
            "output.compare_modules",
            format!("{:?}", kinds.iter().map(|k| k.name()).collect::<Vec<_>>()),
            "it draws Figure 12 under plots/, which is written only with `output.plots = true`: \
             set `plots = true` in [output], or remove `compare_modules`",
        ));
    }
    if output.max_plot_iterations == 0 {
        return Err(CaseError::invalid(
            "output.max_plot_iterations",
            "0",
            "give the last iteration the convergence figures show as an integer ≥ 1 (the paper's is 100)",
        ));
    }
    // `large` follows the load path: its α in increasing order (docs/method.md §8).
    let model = raw.model.geometry.unwrap_or_default();
    let mut load = load;
    if model == crate::structure::GeometricModel::Large {
        load.alphas.sort_by(f64::total_cmp);
    }
    Ok(Case {
        grid,
        geometry,
        fixes,
        load,
        solver,
        output,
        model,
    })
}

/// `[solver]` of a grid of `modules` (`None`: a general structure): the solvers' settings, the case's tolerance and
/// iteration cap applied to every one of them.
fn solver_choice(
    raw: super::raw::RawSolver,
    modules: Option<[usize; 2]>,
) -> Result<SolverChoice, CaseError> {
    // A general structure may be cut into any number of boxes (empty ones are refused at
    // set-up); up to 1000 along each axis.
    let [nx, ny] = modules.unwrap_or([1000, 1000]);
    let mut choice = SolverChoice::default();
    if let Some(methods) = raw.methods {
        if methods.is_empty() {
            return Err(CaseError::invalid(
                "solver.methods",
                "[]",
                "name at least one solver, e.g. [\"newton\"]",
            ));
        }
        check_distinct_methods("solver.methods", &methods)?;
        choice.methods = methods;
    }
    if let Some(tol) = raw.tolerance {
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(CaseError::invalid(
                "solver.tolerance",
                number(tol),
                "give a relative tolerance between 0 and 1 (exclusive), e.g. 1e-8",
            ));
        }
        choice.newton.tolerance = tol;
        choice.pcg_lcp.tolerance = tol;
        choice.latin.tolerance = tol;
    }
    // The paper's partition, limited to the grid.
    let [dx, dy] = choice.latin.subdomains;
    let default = match modules {
        Some(_) => [dx.min(nx), dy.min(ny)],
        None => [1, 1],
    };
    let [sx, sy] = raw.subdomains.map_or(default, |s| s.0);
    if sx == 0 || sy == 0 || sx > nx || sy > ny {
        return Err(CaseError::invalid(
            "solver.subdomains",
            format!("[{sx}, {sy}]"),
            format!("give 1 ≤ sx ≤ {nx} and 1 ≤ sy ≤ {ny} (at most one substructure per module)"),
        ));
    }
    choice.latin.subdomains = [sx, sy];
    if let Some(dm) = raw.dm {
        positive("solver.dm", dm, "the interface search direction d_m in N/m")?;
        choice.latin.dm = Some(dm);
    }
    if let Some(l) = &raw.l {
        choice.latin.search = search_direction(l)?;
    }
    if let Some(weak) = raw.weak_interfaces {
        choice.latin.weak = weak;
    }
    if let Some(mu) = raw.relaxation {
        if !(mu.is_finite() && mu > 0.0 && mu <= 1.0) {
            return Err(CaseError::invalid(
                "solver.relaxation",
                number(mu),
                "give the relaxation μ of the LATIN linear stage in (0, 1], e.g. 0.8 (1: none)",
            ));
        }
        choice.latin.relaxation = mu;
    }
    if let Some(depth) = raw.anderson {
        if depth > MAX_ANDERSON_DEPTH {
            return Err(CaseError::invalid(
                "solver.anderson",
                depth.to_string(),
                "give the Anderson acceleration depth of the LATIN solvers between 0 (none) and 50, e.g. 5",
            ));
        }
        choice.latin.anderson = depth;
    }
    if let Some(policy) = raw.search_direction {
        choice.latin.policy = policy;
    }
    if let Some(rho) = raw.forcing {
        if !(rho.is_finite() && rho > 0.0 && rho < 1.0) {
            return Err(CaseError::invalid(
                "solver.forcing",
                number(rho),
                "give the forcing term ρ of the inexact Newton status steps between 0 and 1 (exclusive), e.g. 0.3",
            ));
        }
        choice.latin.forcing = rho;
    }
    if let Some(stop_on) = raw.stop_on {
        choice.latin.stop_on = stop_on;
    }
    if let Some(tol) = raw.residual_tolerance {
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(CaseError::invalid(
                "solver.residual_tolerance",
                number(tol),
                "give the LATIN equilibrium-residual tolerance between 0 and 1 (exclusive), e.g. 1e-8",
            ));
        }
        choice.latin.residual_tolerance = Some(tol);
    }
    if let Some(reference) = raw.reference {
        choice.reference = reference;
    }
    if let Some(max_iterations) = raw.max_iterations {
        if max_iterations == 0 {
            return Err(CaseError::invalid(
                "solver.max_iterations",
                0,
                "give at least 1 iteration",
            ));
        }
        choice.newton.max_iterations = max_iterations;
        choice.pcg_lcp.max_iterations = max_iterations;
        choice.latin.max_iterations = max_iterations;
    }
    Ok(choice)
}

/// Refuse a solver named twice in `methods` (its files would overwrite each other).
pub(crate) fn check_distinct_methods(
    key: &'static str,
    methods: &[crate::solvers::Method],
) -> Result<(), CaseError> {
    for (i, m) in methods.iter().enumerate() {
        if methods[..i].contains(m) {
            return Err(CaseError::invalid(
                key,
                format!(
                    "{} solvers naming `{}` more than once",
                    methods.len(),
                    m.name()
                ),
                "name each solver once (its files would overwrite each other)",
            ));
        }
    }
    Ok(())
}

/// A TOML value as the user wrote it (a date as a date, not toml's internal form).
fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::Datetime(d) => d.to_string(),
        other => other.to_string(),
    }
}

/// `solver.l`: `"stiffness"` or a number of N/m.
fn search_direction(l: &toml::Value) -> Result<SearchDirection, CaseError> {
    let uniform = |v: f64| {
        positive("solver.l", v, "the link search direction l in N/m")?;
        Ok(SearchDirection::Uniform(v))
    };
    match l {
        toml::Value::String(s) if s == "stiffness" => Ok(SearchDirection::Stiffness),
        toml::Value::Float(v) => uniform(*v),
        toml::Value::Integer(v) => uniform(*v as f64),
        other => Err(CaseError::invalid(
            "solver.l",
            shown(other),
            "give \"stiffness\" (l = k on every link) or a number of N/m",
        )),
    }
}

/// The load factors of `load.alpha`: a non-empty list of finite numbers, or a range
/// `{ from, to, steps }` with `steps ≥ 1` values spaced evenly, both ends included.
fn alpha_values(value: &toml::Value) -> Result<Vec<f64>, CaseError> {
    const KEY: &str = "load.alpha";
    let as_number = |v: &toml::Value| match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let alphas = match value {
        toml::Value::Array(items) => {
            if items.is_empty() {
                return Err(CaseError::invalid(
                    KEY,
                    "[]",
                    "give at least one load factor, e.g. [0.5, 1.0]",
                ));
            }
            items
                .iter()
                .map(|v| {
                    as_number(v).ok_or_else(|| {
                        CaseError::invalid(KEY, shown(v), "every load factor must be a number")
                    })
                })
                .collect::<Result<Vec<_>, _>>()?
        }
        toml::Value::Table(t) => {
            for key in t.keys() {
                if !matches!(key.as_str(), "from" | "to" | "steps") {
                    return Err(CaseError::invalid(
                        KEY,
                        value,
                        format!("unknown key `{key}` in the range: use {{ from, to, steps }}"),
                    ));
                }
            }
            let get = |k: &str| t.get(k).and_then(as_number);
            let (Some(from), Some(to)) = (get("from"), get("to")) else {
                return Err(CaseError::invalid(
                    KEY,
                    value,
                    "a range needs numbers `from` and `to`, e.g. { from = 0.0, to = 1.0, steps = 41 }",
                ));
            };
            let steps = match t.get("steps") {
                Some(toml::Value::Integer(s)) if *s >= 1 && *s <= 1_000_000 => *s as usize,
                _ => {
                    return Err(CaseError::invalid(
                        KEY,
                        value,
                        "a range needs an integer `steps` between 1 and 1000000 (the number of values)",
                    ))
                }
            };
            if steps == 1 {
                vec![from]
            } else {
                // Rounded to 12 significant digits: 0.1 stays 0.1 (not 0.09999999999999999) in
                // file names and tables.
                (0..steps)
                    .map(|i| from + (to - from) * i as f64 / (steps - 1) as f64)
                    .map(|a| format!("{a:.11e}").parse().unwrap_or(a))
                    .collect()
            }
        }
        other => {
            return Err(CaseError::invalid(
                KEY,
                shown(other),
                "give a list such as [0.5, 1.0] or a range such as { from = 0.0, to = 1.0, steps = 41 }",
            ))
        }
    };
    for &a in &alphas {
        bounded(KEY, a, ALPHA_MAX, "every load factor")?;
    }
    // −0 is the load factor 0 (one label, one file name: `alpha0`).
    let alphas: Vec<f64> = alphas.into_iter().map(|a| a + 0.0).collect();
    // Two load factors with one label would write to the same files and repeat a row.
    let mut labels = std::collections::HashMap::new();
    for (i, &a) in alphas.iter().enumerate() {
        if let Some(j) = labels.insert(crate::output::alpha_label(a), i) {
            return Err(CaseError::invalid(
                KEY,
                format!(
                    "a list whose values {j} and {i} are both {}",
                    crate::output::alpha_label(a)
                ),
                "give distinct load factors (a range needs `to` - `from` large enough for its \
                 steps to differ in 12 significant digits)",
            ));
        }
    }
    Ok(alphas)
}
