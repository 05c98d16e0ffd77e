//! `[solver]`: which solvers, and the settings of each, checked; the case's tolerance and
//! iteration cap applied to every solver.

use super::numbers::{number, positive, shown};
use super::raw::RawSolver;
use super::{CaseError, SolverChoice};
use crate::solvers::latin::{LatinSettings, SearchDirection, SearchPolicy, MAX_MACRO_DEGREE};
use crate::solvers::newton::LinearSolve;

/// The deepest Anderson history a case may ask for: each level keeps two vectors of the size
/// of the LATIN state, and depths beyond about 10 did not pay on any case measured.
const MAX_ANDERSON_DEPTH: usize = 50;

/// `[solver]` of a grid of `modules` (`None`: a general structure of `nodes`): the solvers'
/// settings, the case's tolerance and iteration cap applied to every one of them.
pub(super) fn solver_choice(
    raw: RawSolver,
    modules: Option<[usize; 2]>,
    nodes: &[[f64; 3]],
) -> Result<SolverChoice, CaseError> {
    let mut choice = SolverChoice::default();
    if let Some(methods) = &raw.methods {
        if methods.is_empty() {
            return Err(CaseError::invalid(
                "solver.methods",
                "[]",
                "name at least one solver, e.g. [\"newton\"]",
            ));
        }
        check_distinct_methods("solver.methods", methods)?;
        choice.methods = methods.clone();
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
    latin_settings(&raw, modules, nodes, &mut choice.latin)?;
    // newton's substructured solve works on the case's partition.
    choice.newton.subdomains = choice.latin.subdomains;
    if let Some(linear) = raw.linear {
        choice.newton.linear = linear;
    }
    choice.subdomains_given = raw.subdomains.is_some();
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

/// `solver.linear = "krylov"` solves newton's systems on the initial geometry (`linear`,
/// `prestress`, and `auto`'s rows until it moves to `large`, whose rows are then solved
/// directly); a case pinned to `large` is refused.
pub(super) fn linear_fits_model(
    choice: &SolverChoice,
    model: crate::model::GeometricModel,
) -> Result<(), CaseError> {
    if choice.newton.linear == LinearSolve::Krylov && model.updates_geometry() {
        return Err(CaseError::invalid(
            "solver.linear",
            "\"krylov\"",
            "newton's substructured solve works on the initial geometry for now: with \
             `model.geometry = \"large\"` use `solver.linear = \"direct\"` (the default), or \
             `model.geometry = \"auto\"`, whose rows on the initial geometry it solves",
        ));
    }
    Ok(())
}

/// The LATIN keys of `[solver]` on a grid of `modules` (`None`: a general structure of
/// `nodes`), set in `latin`.
fn latin_settings(
    raw: &RawSolver,
    modules: Option<[usize; 2]>,
    nodes: &[[f64; 3]],
    latin: &mut LatinSettings,
) -> Result<(), CaseError> {
    // A general structure may be cut into any number of boxes (empty ones are refused at
    // set-up); up to 1000 along each axis.
    let [nx, ny] = modules.unwrap_or([1000, 1000]);
    let default = match modules {
        Some(grid) => default_subdomains(grid),
        None => default_boxes(nodes),
    };
    let [sx, sy] = raw.subdomains.map_or(default, |s| s.0);
    if sx == 0 || sy == 0 || sx > nx || sy > ny {
        return Err(CaseError::invalid(
            "solver.subdomains",
            format!("[{sx}, {sy}]"),
            format!("give 1 ≤ sx ≤ {nx} and 1 ≤ sy ≤ {ny} (at most one substructure per module)"),
        ));
    }
    latin.subdomains = [sx, sy];
    if let Some(dm) = raw.dm {
        positive("solver.dm", dm, "the interface search direction d_m in N/m")?;
        latin.dm = Some(dm);
    }
    if let Some(l) = &raw.l {
        latin.search = search_direction(l)?;
    }
    if let Some(weak) = raw.weak_interfaces {
        latin.weak = weak;
    }
    if let Some(mu) = raw.relaxation {
        if !(mu.is_finite() && mu > 0.0 && mu <= 1.0) {
            return Err(CaseError::invalid(
                "solver.relaxation",
                number(mu),
                "give the relaxation μ of the LATIN linear stage in (0, 1], e.g. 0.8 (1: none)",
            ));
        }
        latin.relaxation = mu;
    }
    if let Some(depth) = raw.anderson {
        if depth > MAX_ANDERSON_DEPTH {
            return Err(CaseError::invalid(
                "solver.anderson",
                depth.to_string(),
                "give the Anderson acceleration depth of the LATIN solvers between 0 (none) and 50, e.g. 5",
            ));
        }
        latin.anderson = depth;
    }
    if let Some(policy) = raw.search_direction {
        latin.policy = policy;
    }
    if let Some(rho) = raw.forcing {
        if !(rho.is_finite() && rho > 0.0 && rho < 1.0) {
            return Err(CaseError::invalid(
                "solver.forcing",
                number(rho),
                "give the forcing term ρ of the inexact Newton status steps between 0 and 1 (exclusive), e.g. 0.3",
            ));
        }
        // The forcing term of the inexact Newton status steps: with the other search
        // directions there are none, and a value given would do nothing (issue 42, T12).
        if latin.policy != SearchPolicy::Newton {
            return Err(CaseError::invalid(
                "solver.forcing",
                number(rho),
                format!(
                    "`solver.forcing` is the forcing term of `solver.search_direction = \"newton\"` \
                     and does nothing with `search_direction = \"{}\"`: remove it, or set \
                     `solver.search_direction = \"newton\"`",
                    match latin.policy {
                        SearchPolicy::Stiffness => "stiffness",
                        SearchPolicy::Status => "status",
                        SearchPolicy::Newton => "newton",
                    }
                ),
            ));
        }
        latin.forcing = rho;
    }
    if let Some(stop_on) = raw.stop_on {
        latin.stop_on = stop_on;
    }
    if let Some(keep) = raw.keep_z {
        latin.keep_z = keep;
    }
    macro_basis_settings(raw, latin)?;
    if let Some(tol) = raw.residual_tolerance {
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(CaseError::invalid(
                "solver.residual_tolerance",
                number(tol),
                "give the LATIN equilibrium-residual tolerance between 0 and 1 (exclusive), e.g. 1e-8",
            ));
        }
        latin.residual_tolerance = Some(tol);
    }
    Ok(())
}

/// The keys of `[solver]` that shape micro-macro's macro basis, set in `latin`: its degree
/// and the soft interface modes.
fn macro_basis_settings(raw: &RawSolver, latin: &mut LatinSettings) -> Result<(), CaseError> {
    if let Some(degree) = raw.macro_degree {
        if !(1..=MAX_MACRO_DEGREE).contains(&degree) {
            return Err(CaseError::invalid(
                "solver.macro_degree",
                degree.to_string(),
                format!("give the degree of the interfaces' macro basis between 1 (the paper's nine fields) and {MAX_MACRO_DEGREE}, e.g. 2"),
            ));
        }
        latin.macro_degree = Some(degree);
    }
    if let Some(theta) = raw.soft_modes {
        if !(theta.is_finite() && (0.0..1.0).contains(&theta)) {
            return Err(CaseError::invalid(
                "solver.soft_modes",
                number(theta),
                "give the fraction of d_m below which an interface motion is soft, between 0 (none: the polynomial macro basis alone) and 1 (exclusive), e.g. 0.3",
            ));
        }
        latin.soft_modes = (theta > 0.0).then_some(theta);
    }
    Ok(())
}

/// Modules along a side of the substructure the default partition aims at: at 16 × 16
/// micro-macro's iterations stay near twice the bilateral floor while each substructure's
/// factor stays small (docs/performance.md, "Iterations against the bilateral floor").
pub const DEFAULT_SUBSTRUCTURE_SIDE: usize = 16;

/// Substructures along each axis the default partition never goes below (where the grid has
/// as many modules): 4 × 4 = 16 substructures, one for each of 16 threads, and the paper's
/// partition of its 16 × 16 grid.
pub const DEFAULT_MIN_SUBDOMAINS: usize = 4;

/// The default partition of a grid of `modules`: per axis `max(round(n / 16), 4)`, at most one
/// substructure per module. It depends on the grid alone (not on the machine's threads), so that
/// a case gives the same iterates everywhere.
pub fn default_subdomains(modules: [usize; 2]) -> [usize; 2] {
    modules.map(|n| {
        let by_size = (n + DEFAULT_SUBSTRUCTURE_SIDE / 2) / DEFAULT_SUBSTRUCTURE_SIDE;
        by_size.max(DEFAULT_MIN_SUBDOMAINS).min(n)
    })
}

/// Nodes of a general structure per substructure the default partition aims at: those of
/// 16 × 16 modules of the grid (833 on the paper's).
pub const DEFAULT_SUBSTRUCTURE_NODES: usize = 833;

/// The default partition of a general structure of `nodes` into boxes of its plan: about
/// [`DEFAULT_SUBSTRUCTURE_NODES`] nodes a box, laid out as the plan's sides' ratio; one box
/// (the monodomain) below twice that.
pub fn default_boxes(nodes: &[[f64; 3]]) -> [usize; 2] {
    let count = (nodes.len() + DEFAULT_SUBSTRUCTURE_NODES / 2) / DEFAULT_SUBSTRUCTURE_NODES;
    if count < 2 {
        return [1, 1];
    }
    let side = |k: usize| {
        let (low, high) = nodes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[k]), h.max(p[k]))
            });
        (high - low).max(0.0)
    };
    let (wx, wy) = (side(0), side(1));
    // sx / sy = wx / wy and sx · sy = count; a side of no width gets one box.
    let sx = match (wx > 0.0, wy > 0.0) {
        (true, true) => ((count as f64 * wx / wy).sqrt().round() as usize).clamp(1, count),
        (true, false) => count,
        _ => 1,
    };
    let sy = (count as f64 / sx as f64).round().max(1.0) as usize;
    [sx, sy.min(1000)]
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_partition_of_a_grid_aims_at_16_modules_a_side() {
        for (modules, expected) in [
            ([16, 16], [4, 4]),
            ([71, 71], [4, 4]),
            ([72, 64], [5, 4]),
            ([128, 128], [8, 8]),
            ([512, 256], [32, 16]),
            ([3, 1024], [3, 64]),
        ] {
            assert_eq!(default_subdomains(modules), expected, "{modules:?}");
        }
    }

    #[test]
    fn default_boxes_of_a_structure_follow_its_node_count_and_plan() {
        let plan = |count: usize, wx: f64, wy: f64| -> Vec<[f64; 3]> {
            let side = (count as f64).sqrt().ceil() as usize;
            (0..count)
                .map(|k| {
                    let (i, j) = (k % side, k / side);
                    [
                        wx * i as f64 / side as f64,
                        wy * j as f64 / side as f64,
                        0.0,
                    ]
                })
                .collect()
        };
        assert_eq!(default_boxes(&plan(12, 1.0, 1.0)), [1, 1]);
        assert_eq!(default_boxes(&plan(1200, 1.0, 1.0)), [1, 1]);
        // The softened 128 x 128 grid's 49 665 nodes: 60 boxes of a square plan.
        assert_eq!(default_boxes(&plan(49_665, 128.0, 128.0)), [8, 8]);
        // 5 boxes of a plan twice as long as wide.
        assert_eq!(default_boxes(&plan(4_000, 2.0, 1.0)), [3, 2]);
        // A mast: a plan of no width along y.
        assert_eq!(default_boxes(&plan(4_000, 2.0, 0.0)), [5, 1]);
    }
}
