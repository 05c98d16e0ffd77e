//! The member checks' columns of `forces/` ([`results::checks::MemberCheck`]), EN 1993's
//! among them where the case asks for a buckling curve or a breaking load, and `checks.csv`:
//! every member above a utilisation of 1, one row per member and solve.

use super::sinks::{append, Sink, SolveEnd, SolveKey, WriteError};
use super::OutputDir;
use crate::results::checks::{member_checks, MemberCheck};
use crate::structure::Structure;
use std::cell::RefCell;

/// The member checks' columns of `forces/`.
pub const CHECK_COLUMNS: [&str; 5] = [
    "stress_Pa",
    "utilisation",
    "euler_load_N",
    "buckling_utilisation",
    "slack_margin",
];

/// EN 1993's columns of `forces/`, after [`CHECK_COLUMNS`], when a member has a buckling curve
/// or a breaking load.
pub const EUROCODE_COLUMNS: [&str; 8] = [
    "buckling_curve",
    "slenderness",
    "chi",
    "buckling_resistance_N",
    "cable_resistance_N",
    "cable_utilisation",
    "governing_utilisation",
    "clause",
];

/// `checks.csv`'s header.
pub const CHECKS_HEADER: &str = "solver,alpha,member,kind,utilisation,clause";

/// A number's cell: empty where the member is not so checked, or where it is not finite (it
/// cannot be: sections, inertias and strengths are > 0).
fn cell(v: Option<f64>) -> String {
    v.filter(|v| v.is_finite())
        .map(|v| v.to_string())
        .unwrap_or_default()
}

/// The cells of `c` under [`CHECK_COLUMNS`].
pub(super) fn check_cells(c: &MemberCheck) -> [String; 5] {
    [
        cell(Some(c.stress)),
        cell(c.utilisation),
        cell(c.euler_load),
        cell(c.buckling_utilisation),
        cell(c.slack_margin),
    ]
}

/// The cells of link `i` of `s` (checks `c`) under [`EUROCODE_COLUMNS`].
pub(super) fn eurocode_cells(s: &Structure, i: usize, c: &MemberCheck) -> [String; 8] {
    let data = s.checks.as_ref().map(|m| m.of(i, s.links[i].kind));
    let curve = data
        .and_then(|d| d.buckling)
        .filter(|_| c.flexural.is_some())
        .map_or(String::new(), |b| b.curve.name().to_string());
    let governing = c.governing();
    [
        curve,
        cell(c.flexural.map(|f| f.slenderness)),
        cell(c.flexural.map(|f| f.chi)),
        cell(c.flexural.map(|f| f.resistance)),
        cell(c.cable_resistance),
        cell(c.cable_utilisation),
        cell(governing.map(|(u, _)| u)),
        governing.map_or(String::new(), |(_, clause)| clause.name().to_string()),
    ]
}

/// `checks.csv`: after every solve with an answer, a row per member whose largest utilisation
/// is above 1, and, where slack is forbidden, per slack cable (none: no row; none in the whole
/// run: no file).
pub struct ChecksSink<'s> {
    out: &'s RefCell<OutputDir>,
    /// Slack cables are listed (`checks.forbid_slack`).
    forbid_slack: bool,
}

/// The clause of a slack cable's row of `checks.csv`.
pub const SLACK_CLAUSE: &str = "slack (checks.forbid_slack)";

impl<'s> ChecksSink<'s> {
    /// `checks.csv` in `out`, with the slack cables when `forbid_slack`.
    pub fn new(out: &'s RefCell<OutputDir>, forbid_slack: bool) -> Self {
        ChecksSink { out, forbid_slack }
    }
}

impl Sink for ChecksSink<'_> {
    fn end(&mut self, key: &SolveKey, end: SolveEnd) -> Result<(), WriteError> {
        let SolveEnd::Solved {
            solution, model, ..
        } = end
        else {
            return Ok(());
        };
        let eq = &solution.equilibrium;
        let s = &model.structure;
        let row = |i: usize, utilisation: String, clause: &str| {
            let (solver, alpha, id) = (key.method.name(), key.alpha, s.links[i].id);
            format!(
                "{solver},{alpha},{id},{},{utilisation},{clause}",
                s.kind_name(i)
            )
        };
        let checks = member_checks(model, eq).unwrap_or_default();
        let mut rows: Vec<String> = checks
            .iter()
            .enumerate()
            .filter_map(|(i, c)| {
                let (u, clause) = c.governing().filter(|(u, _)| *u > 1.0)?;
                Some(row(i, u.to_string(), clause.name()))
            })
            .collect();
        if self.forbid_slack {
            // A slack cable's row: its utilisation empty, its tension 0.
            let slack = (0..s.links.len()).filter(|&i| s.links[i].unilateral && eq.slack[i]);
            rows.extend(slack.map(|i| row(i, String::new(), SLACK_CLAUSE)));
        }
        if rows.is_empty() {
            return Ok(());
        }
        append(self.out, "checks.csv", CHECKS_HEADER, &rows.join("\n"))
    }
}
