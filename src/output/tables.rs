//! CSV tables: `summary.csv`, `tensions/{solver}_alpha{α}.csv`,
//! `displacements/{solver}_alpha{α}.csv`, `forces/…`, `reactions/…`, `reaction_totals.csv`.

use super::member_checks::{check_cells, eurocode_cells, CHECK_COLUMNS, EUROCODE_COLUMNS};
use super::write_atomic;
use crate::labels::alpha_label;
use crate::model::{GeometricModel, Model};
use crate::results;
use crate::solvers::{Equilibrium, Measure, Solution, Status};
use crate::structure::Structure;
use std::path::{Path, PathBuf};

/// One row of `summary.csv` (docs/guide.md describes each column).
#[derive(Debug, Clone)]
pub struct SummaryRow {
    /// Solver name.
    pub solver: String,
    /// Load factor.
    pub alpha: f64,
    /// The solver's stopping criterion was met (and the answer is a stable equilibrium).
    pub converged: bool,
    /// How the solve ended ([`Status::code`]).
    pub status: Status,
    /// What `stopping_value` measures (not a column: the solver says it).
    pub measure: Measure,
    /// Iterations done.
    pub iterations: usize,
    /// Unilateral cables that are slack.
    pub slack_cables: usize,
    /// Number of cables.
    pub cables: usize,
    /// Largest cable tension τ, N.
    pub max_tension: f64,
    /// Largest nodal displacement magnitude, m.
    pub max_deflection: f64,
    /// The solver's stopping measure at the end (column `residual`).
    pub stopping_value: f64,
    /// r(U) of the answer's displacements: the measure every solver shares.
    pub equilibrium_residual: f64,
    /// Operator rebuilds during the solve (column `search_updates`).
    pub rebuilds: usize,
    /// Slack cables per family ([`results::SLACK_FAMILIES`]).
    pub slack_by_kind: [usize; results::SLACK_FAMILIES.len()],
    /// The largest relative displacement of a member's ends over its length.
    pub max_member_rotation: f64,
    /// The model updates the geometry (`large`): the small-perturbation check does not apply.
    pub updates_geometry: bool,
    /// The smallest eigenvalue of the tangent stiffness at the answer, N/m, when computed
    /// (models with geometric stiffness, or `output.stability`).
    pub min_tangent_eigenvalue: Option<f64>,
    /// How far the answer is from the large-displacement one, measured by Newton steps of the
    /// large model ([`results::distance_to_large`]; column `geometric_term`); `None` for
    /// `large` and without displacements.
    pub large_distance: Option<results::LargeDistance>,
    /// The case's `model.tolerance`: a geometric term above it says the model is off.
    pub model_tolerance: f64,
    /// Whether a converged answer is the only equilibrium, when checked (column `unique`; the
    /// run warns of the free motion of one that is not).
    pub uniqueness: Option<results::uniqueness::Uniqueness>,
    /// Set-up of the solver for this structure, s.
    pub setup_seconds: f64,
    /// This solve, s.
    pub solve_seconds: f64,
    /// Converged because the stopping measure is at round-off (not a column: the solve line
    /// says so instead of printing the measure, [`crate::solvers::SolveInfo::at_roundoff`]).
    pub at_roundoff: bool,
    /// The α whose equilibrium the solve's load path started from (`large`: the solver's
    /// last equilibrium reached), `None` for a solve with no load path.
    pub path_from: Option<f64>,
    /// The α of the last equilibrium reached on that path: α itself when it converged,
    /// less at a limit point.
    pub path_reached: Option<f64>,
    /// The path did not start at this solver's previous row: the rows since did not reach
    /// their α (a limit point), so this one was solved from the last equilibrium before them.
    pub path_restarted: bool,
    /// The largest member utilisation and its member, when the case checks members and the
    /// row has an answer (columns `max_utilisation`, `max_utilisation_member`).
    pub governing: Option<results::checks::Governing>,
    /// The geometric model the row was solved with (column `model`).
    pub model: GeometricModel,
    /// Why that model (not a column: the solve line says it).
    pub model_reason: String,
    /// The case pins the model (else `auto` chose it): only a pinned model is warned of.
    pub model_pinned: bool,
    /// PCG iterations over all of newton's steps with `solver.linear = "krylov"` (column
    /// `krylov_iterations`, empty for a direct solve).
    pub krylov_iterations: Option<usize>,
    /// The limit load located on the row's load path (column `limit_alpha`; empty where none).
    pub limit_alpha: Option<f64>,
}

impl SummaryRow {
    /// The row of `solution`, by `solver` at `alpha`, whose answer `measures` says,
    /// set up in `setup_seconds`.
    pub fn new(
        solver: &str,
        alpha: f64,
        measures: &results::AnswerMeasures,
        solution: &Solution,
        verdict: (Option<f64>, Option<results::LargeDistance>),
        setup_seconds: f64,
    ) -> SummaryRow {
        let (min_tangent_eigenvalue, large_distance) = verdict;
        let eq = &solution.equilibrium;
        SummaryRow {
            solver: solver.to_string(),
            alpha,
            converged: solution.info.status.converged(),
            status: solution.info.status,
            measure: solution.info.measure,
            min_tangent_eigenvalue,
            iterations: solution.info.iterations,
            slack_cables: eq.slack_count(),
            cables: measures.cables,
            max_tension: measures.max_tension,
            max_deflection: measures.max_deflection,
            stopping_value: solution.info.stopping_value,
            equilibrium_residual: measures.equilibrium_residual,
            rebuilds: solution.info.rebuilds,
            slack_by_kind: measures.slack_by_kind,
            max_member_rotation: measures.max_member_rotation,
            updates_geometry: measures.updates_geometry,
            large_distance,
            model_tolerance: results::DEFAULT_MODEL_TOLERANCE,
            uniqueness: None,
            setup_seconds,
            solve_seconds: solution.info.solve_seconds,
            at_roundoff: solution.info.at_roundoff && solution.info.status.converged(),
            path_from: None,
            path_reached: None,
            path_restarted: false,
            governing: None,
            model: measures.geometry,
            model_reason: String::new(),
            model_pinned: true,
            krylov_iterations: solution.info.krylov_iterations,
            limit_alpha: None,
        }
    }
}

impl SummaryRow {
    /// Whether the small-perturbation model holds for this answer: no member's ends moved
    /// apart by more than [`results::SMALL_DISPLACEMENT_LIMIT`] of its length, and the geometric
    /// term the model leaves out changes the answer by at most
    /// the case's `model.tolerance` ([`SummaryRow::needs_large`]). `None` for the `large`
    /// model, which updates the geometry.
    pub fn small_displacement_ok(&self) -> Option<bool> {
        (!self.updates_geometry).then(|| {
            self.max_member_rotation <= results::SMALL_DISPLACEMENT_LIMIT && !self.needs_large()
        })
    }

    /// Whether the answer is further than the case's `model.tolerance` from the large one, or
    /// no distance could be measured, or large's equilibrium next to it is unstable:
    /// `model.geometry = "large"` is needed.
    pub fn needs_large(&self) -> bool {
        self.large_distance.is_some_and(results::LargeDistance::off)
    }

    /// The `geometric_term` column: the measured relative distance to `large`, where known.
    pub fn geometric_term(&self) -> Option<f64> {
        self.large_distance.and_then(results::LargeDistance::value)
    }

    /// Whether every number of the row is finite (a row with inf or NaN is never written).
    pub fn is_finite(&self) -> bool {
        [
            self.max_tension,
            self.max_deflection,
            self.stopping_value,
            self.equilibrium_residual,
            self.max_member_rotation,
            self.min_tangent_eigenvalue.unwrap_or(0.0),
            self.geometric_term().unwrap_or(0.0),
            self.governing.map_or(0.0, |g| g.utilisation),
        ]
        .iter()
        .all(|x| x.is_finite())
    }
}

/// Header line of `summary.csv`, one column per [`SummaryRow`] field plus `slack_fraction`.
pub const SUMMARY_HEADER: &str = "solver,alpha,converged,iterations,slack_cables,cables,slack_fraction,max_tension,max_deflection,residual,equilibrium_residual,search_updates,slack_lower,slack_upper,slack_bracing,slack_diagonal,slack_cable,max_member_rotation,small_displacement_ok,setup_seconds,solve_seconds,status,min_tangent_eigenvalue,geometric_term,path_from,path_reached,unique,model,krylov_iterations,limit_alpha";

/// The columns `summary.csv` gains when the case checks members (a strength or an inertia).
pub const SUMMARY_CHECK_COLUMNS: &str = ",max_utilisation,max_utilisation_member";

/// The cells of [`SUMMARY_CHECK_COLUMNS`] of `r`, each after a comma: empty without an answer
/// or a checked member.
pub fn summary_check_cells(r: &SummaryRow) -> String {
    match r.governing.filter(|_| !r.status.no_answer()) {
        Some(g) => format!(",{},{}", g.utilisation, g.member),
        None => ",,".to_string(),
    }
}

/// A CSV writer's error as an I/O error of the same kind (a full disk stays `StorageFull`).
fn csv_io(e: csv::Error) -> std::io::Error {
    match e.kind() {
        csv::ErrorKind::Io(io) => std::io::Error::new(io.kind(), e),
        _ => std::io::Error::other(e),
    }
}

/// The line of `summary.csv` of `r` (no newline). A row that is no answer
/// ([`Status::no_answer`]) leaves the answer's columns (tension, deflection, rotation) empty.
pub fn summary_line(r: &SummaryRow) -> String {
    let fraction = if r.cables > 0 {
        r.slack_cables as f64 / r.cables as f64
    } else {
        0.0
    };
    let [lower, upper, bracing, diagonal, cable] = r.slack_by_kind;
    let answer = |x: String| {
        if r.status.no_answer() {
            String::new()
        } else {
            x
        }
    };
    format!(
        "{},{},{},{},{},{},{},{},{},{:e},{:e},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        r.solver,
        alpha_label(r.alpha),
        r.converged,
        r.iterations,
        r.slack_cables,
        r.cables,
        fraction,
        answer(r.max_tension.to_string()),
        answer(r.max_deflection.to_string()),
        r.stopping_value,
        r.equilibrium_residual,
        r.rebuilds,
        lower,
        upper,
        bracing,
        diagonal,
        cable,
        answer(format!("{:e}", r.max_member_rotation)),
        answer(
            r.small_displacement_ok()
                .map(|ok| ok.to_string())
                .unwrap_or_default()
        ),
        r.setup_seconds,
        r.solve_seconds,
        r.status.code(),
        r.min_tangent_eigenvalue
            .map(|v| format!("{v:e}"))
            .unwrap_or_default(),
        answer(
            r.geometric_term()
                .map(|v| format!("{v:e}"))
                .unwrap_or_default()
        ),
        r.path_from.map(alpha_label).unwrap_or_default(),
        r.path_reached.map(alpha_label).unwrap_or_default(),
        r.uniqueness.as_ref().map_or("", |u| u.column()),
        r.model.name(),
        r.krylov_iterations
            .map(|k| k.to_string())
            .unwrap_or_default(),
        r.limit_alpha.map(|v| v.to_string()).unwrap_or_default(),
    )
}

/// Path `dir/{kind}/{solver}_alpha{α}.csv` of a per-solve CSV file.
pub fn result_path(dir: &Path, kind: &str, solver: &str, alpha: f64) -> PathBuf {
    dir.join(kind)
        .join(format!("{solver}_alpha{}.csv", alpha_label(alpha)))
}

/// A CSV file of `header` and `rows`, written atomically.
fn write_rows<H, R, Row>(path: &Path, header: H, rows: R) -> std::io::Result<()>
where
    H: IntoIterator,
    H::Item: AsRef<[u8]>,
    R: Iterator<Item = Row>,
    Row: IntoIterator,
    Row::Item: AsRef<[u8]>,
{
    write_atomic(path, |w| {
        let mut out = csv::Writer::from_writer(w);
        out.write_record(header).map_err(csv_io)?;
        for row in rows {
            out.write_record(row).map_err(csv_io)?;
        }
        out.flush()
    })
}

/// Write `dir/mechanisms.csv`: per refused mechanism mode (numbered from 1) and node (its id),
/// the node's motion in the unit mode.
pub fn write_mechanisms(dir: &Path, modes: &[(u64, usize, [f64; 3])]) -> std::io::Result<()> {
    write_rows(
        &dir.join("mechanisms.csv"),
        ["node", "mode", "ux", "uy", "uz"],
        modes.iter().map(|(node, mode, u)| {
            [
                node.to_string(),
                mode.to_string(),
                format!("{:e}", u[0]),
                format!("{:e}", u[1]),
                format!("{:e}", u[2]),
            ]
        }),
    )
}

/// Write `dir/tensions/{solver}_alpha{α}.csv`: per cable, its kind, end nodes and tension
/// τ (N); returns its path.
pub fn write_tensions(
    dir: &Path,
    solver: &str,
    alpha: f64,
    s: &Structure,
    eq: &Equilibrium,
) -> std::io::Result<PathBuf> {
    let path = result_path(dir, "tensions", solver, alpha);
    let cables = s
        .links
        .iter()
        .zip(&eq.tensions)
        .enumerate()
        .filter(|(_, (l, _))| l.kind.is_cable())
        .enumerate();
    // A grid numbers its cables 0.. among cables; a general structure reports the members
    // and nodes by the ids of its tables.
    let general = s.layout.is_none();
    let rows = cables.map(|(cable, (i, (l, t)))| {
        let mut row = vec![
            if general { l.id } else { cable as u64 }.to_string(),
            s.kind_name(i).to_string(),
            s.node_ids[l.a].to_string(),
            s.node_ids[l.b].to_string(),
            t.to_string(),
        ];
        row.extend(s.group_of(i).map(str::to_string));
        row
    });
    let first = if general { "member" } else { "cable" };
    let mut header = vec![first, "kind", "node_a", "node_b", "tension"];
    header.extend(s.groups.as_ref().map(|_| "group"));
    write_rows(&path, header, rows)?;
    Ok(path)
}

/// `InvalidData` naming `what` when a value of `values` is not finite: nothing is written.
fn finite(what: &str, values: impl IntoIterator<Item = f64>) -> std::io::Result<()> {
    match values.into_iter().find(|v| !v.is_finite()) {
        None => Ok(()),
        Some(v) => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("a {what} is {v} (not finite): no file written"),
        )),
    }
}

/// Write `dir/forces/{solver}_alpha{α}.csv`: per member (bars and cables, by id), its kind,
/// end nodes, total axial force τ (N, tension > 0), elongation and length (m) under the
/// model ([`Model::member_states`]), and the member checks' [`CHECK_COLUMNS`] when the case
/// gives a strength or an inertia; returns its path.
pub fn write_forces(
    dir: &Path,
    solver: &str,
    alpha: f64,
    model: &Model,
    eq: &Equilibrium,
) -> std::io::Result<PathBuf> {
    let path = result_path(dir, "forces", solver, alpha);
    let s = &model.structure;
    let states = model.member_states(&eq.displacements);
    finite("member force", eq.tensions.iter().copied())?;
    finite("member elongation", states.elongations.iter().copied())?;
    finite("member length", states.lengths.iter().copied())?;
    let rows = s.links.iter().enumerate().map(|(i, l)| {
        vec![
            l.id.to_string(),
            s.kind_name(i).to_string(),
            s.node_ids[l.a].to_string(),
            s.node_ids[l.b].to_string(),
            eq.tensions[i].to_string(),
            states.elongations[i].to_string(),
            states.lengths[i].to_string(),
        ]
    });
    let mut header = vec![
        "member",
        "kind",
        "node_a",
        "node_b",
        "force_N",
        "elongation_m",
        "current_length_m",
    ];
    // The member checks' columns only when the case gives a strength or an inertia (and
    // EN 1993's when it gives a buckling curve or a breaking load); the group last, when the
    // members table has one.
    let checks = results::checks::member_checks(model, eq);
    let eurocode = s.checks.as_ref().is_some_and(|c| c.any_eurocode());
    if checks.is_some() {
        header.extend(CHECK_COLUMNS);
    }
    if eurocode {
        header.extend(EUROCODE_COLUMNS);
    }
    header.extend(s.groups.as_ref().map(|_| "group"));
    let rows = rows.enumerate().map(|(i, mut row)| {
        if let Some(checks) = &checks {
            row.extend(check_cells(&checks[i]));
            if eurocode {
                row.extend(eurocode_cells(s, i, &checks[i]));
            }
        }
        row.extend(s.group_of(i).map(str::to_string));
        row
    });
    write_rows(&path, header, rows)?;
    if s.groups.is_some() {
        super::groups::write_group_forces(dir, solver, alpha, s, &eq.tensions)?;
    }
    Ok(path)
}

/// The axes of a held component, in the order of [`results::Reaction::component`].
const AXES: [&str; 3] = ["x", "y", "z"];

/// Write `dir/reactions/{solver}_alpha{α}.csv`: per held component (node id, `x`, `y` or
/// `z`) its reaction (N, [`results::reactions`]), one row each and nothing else (their sums
/// are `reaction_totals.csv`'s row, [`reaction_totals`]); returns its path.
pub fn write_reactions(
    dir: &Path,
    solver: &str,
    alpha: f64,
    model: &Model,
    eq: &Equilibrium,
) -> std::io::Result<PathBuf> {
    let path = result_path(dir, "reactions", solver, alpha);
    let s = &model.structure;
    let states = model.member_states(&eq.displacements);
    let reactions = results::reactions(model, eq, alpha, &states);
    finite("reaction", reactions.iter().map(|r| r.force))?;
    let rows = reactions.iter().map(|r| {
        [
            s.node_ids[r.node].to_string(),
            AXES[r.component].to_string(),
            r.force.to_string(),
        ]
    });
    write_rows(&path, ["node", "component", "reaction_N"], rows)?;
    Ok(path)
}

/// Header line of `reaction_totals.csv`: per solve with an answer, the sum of its reactions
/// along x, y and z (N).
pub const REACTION_TOTALS_HEADER: &str = "solver,alpha,reaction_x_N,reaction_y_N,reaction_z_N";

/// The sums of the reactions per axis at load factor `alpha` (Σ R over the held components of
/// each axis; with the load, `Σ R + Σ F = 0` to the solve's residual). `InvalidData` when one
/// is not finite.
pub fn reaction_totals(model: &Model, eq: &Equilibrium, alpha: f64) -> std::io::Result<[f64; 3]> {
    let states = model.member_states(&eq.displacements);
    let reactions = results::reactions(model, eq, alpha, &states);
    finite("reaction", reactions.iter().map(|r| r.force))?;
    let mut totals = [0.0; 3];
    for r in &reactions {
        totals[r.component] += r.force;
    }
    Ok(totals)
}

/// The line of `reaction_totals.csv` of the solve by `solver` at `alpha` (no newline).
pub fn reaction_totals_line(solver: &str, alpha: f64, totals: [f64; 3]) -> String {
    let [x, y, z] = totals;
    format!("{solver},{},{x},{y},{z}", alpha_label(alpha))
}

/// Write `dir/displacements/{solver}_alpha{α}.csv`: per node, its initial position and
/// displacement (m; the prescribed value on held components), by node id; returns its path.
pub fn write_displacements(
    dir: &Path,
    solver: &str,
    alpha: f64,
    s: &Structure,
    eq: &Equilibrium,
) -> std::io::Result<PathBuf> {
    let path = result_path(dir, "displacements", solver, alpha);
    let full = s.full_displacements(&eq.displacements);
    let rows = s.nodes.iter().enumerate().map(|(node, x)| {
        let u = &full[3 * node..3 * node + 3];
        [
            s.node_ids[node].to_string(),
            x[0].to_string(),
            x[1].to_string(),
            x[2].to_string(),
            u[0].to_string(),
            u[1].to_string(),
            u[2].to_string(),
        ]
    });
    write_rows(&path, ["node", "x", "y", "z", "ux", "uy", "uz"], rows)?;
    Ok(path)
}

/// One row of `stability.csv`.
#[derive(Debug, Clone)]
pub struct StabilityRow {
    /// Solver name.
    pub solver: String,
    /// Load factor.
    pub alpha: f64,
    /// Slack cables of the solution.
    pub slack_cables: usize,
    /// Smallest eigenvalue of the taut members' stiffness, N/m (0: a mechanism).
    pub min_tangent_eigenvalue: f64,
}

/// Header line of `stability.csv`, one column per [`StabilityRow`] field.
pub const STABILITY_HEADER: &str = "solver,alpha,slack_cables,min_tangent_eigenvalue";

/// The line of `stability.csv` of `r` (no newline).
pub fn stability_line(r: &StabilityRow) -> String {
    format!(
        "{},{},{},{}",
        r.solver,
        alpha_label(r.alpha),
        r.slack_cables,
        r.min_tangent_eigenvalue
    )
}
