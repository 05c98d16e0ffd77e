//! `[solver]`: which solvers, and the settings of each, checked; the case's tolerance and
//! iteration cap applied to every solver.

use super::numbers::{number, positive, shown};
use super::raw::RawSolver;
use super::{CaseError, SolverChoice};
use crate::solvers::latin::{LatinSettings, SearchDirection, SearchPolicy, MAX_MACRO_DEGREE};

/// The deepest Anderson history a case may ask for: each level keeps two vectors of the size
/// of the LATIN state, and depths beyond about 10 did not pay on any case measured.
const MAX_ANDERSON_DEPTH: usize = 50;

/// `[solver]` of a grid of `modules` (`None`: a general structure): the solvers' settings, the case's tolerance and
/// iteration cap applied to every one of them.
pub(super) fn solver_choice(
    raw: RawSolver,
    modules: Option<[usize; 2]>,
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
    latin_settings(&raw, modules, &mut choice.latin)?;
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

/// The LATIN keys of `[solver]` on a grid of `modules` (`None`: a general structure), set in
/// `latin`.
fn latin_settings(
    raw: &RawSolver,
    modules: Option<[usize; 2]>,
    latin: &mut LatinSettings,
) -> Result<(), CaseError> {
    // A general structure may be cut into any number of boxes (empty ones are refused at
    // set-up); up to 1000 along each axis.
    let [nx, ny] = modules.unwrap_or([1000, 1000]);
    // The paper's partition, limited to the grid.
    let [dx, dy] = latin.subdomains;
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
