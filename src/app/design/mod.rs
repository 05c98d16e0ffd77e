//! `tensolve design` (issue 46): a case whose `prestress.from` is `"design"` or
//! `"force-density"`, designed and reported — the counts, the rank decision, each group's
//! force, force density and rest length, the prestress-stability verdict — and, with `--out`,
//! written as a case that `run` takes as written (`files`).

mod files;

use crate::case::{self, Case, CaseError, Design};
use crate::linalg::ZERO_MODES_COUNTED;
use crate::model::{prestress_stability, PrestressStability};
use crate::structure::{Geometry, LinkKind, DENSE_LIMIT, RANK_RELATIVE};
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

pub use files::write_design;

/// Why `design` stops.
#[derive(Debug, Error)]
pub enum DesignError {
    /// The case, or its design, refused.
    #[error("{0}")]
    Case(#[from] CaseError),
    /// The design is no structure `run` takes: a rest length at or below 0, no prestress
    /// stability, or a set-up `run` refuses. Nothing is written.
    #[error("the design is refused, and nothing is written: {0}")]
    Impossible(String),
    /// A file of `--out` could not be written.
    #[error("cannot write `{path}`: {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        reason: String,
    },
}

impl DesignError {
    /// 2 for bad input, 1 for a file not written.
    pub fn exit_code(&self) -> i32 {
        match self {
            DesignError::Case(_) | DesignError::Impossible(_) => 2,
            DesignError::Write { .. } => 1,
        }
    }
}

/// One group's numbers in the form designed.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupRow {
    /// The group's label.
    pub name: String,
    /// Cable or bar.
    pub kind: LinkKind,
    /// Its members.
    pub members: usize,
    /// Force over its members, N: `[min, max]` (one value under `design`; `t = qℓ` varies
    /// along a group under `force-density`).
    pub force: [f64; 2],
    /// Force density `t/ℓ` over its members, N/m: `[min, max]`.
    pub force_density: [f64; 2],
    /// Rest length `ℓ·ES/(ES + t)` over its members, m: `[min, max]`.
    pub rest_length: [f64; 2],
    /// The target (N) or force density (N/m) the case gave, if any.
    pub given: Option<f64>,
}

/// What `design` found.
#[derive(Debug, Clone)]
pub struct DesignReport {
    /// The case file.
    pub case: PathBuf,
    /// The design's counts, rank decision and group forces.
    pub design: Design,
    /// Per group, in order of first appearance.
    pub groups: Vec<GroupRow>,
    /// The prestress-stability test of the designed prestress (`None` above
    /// [`DENSE_LIMIT`] free dofs).
    pub stability: Option<PrestressStability>,
    /// Free dofs (the stability test's size).
    pub free_dofs: usize,
}

/// Load the case at `path` (with `--set` overrides), design its prestress (or, with
/// `rebalance`, project the members table's on the self-stress states), and report; with `out`,
/// write the designed case there.
pub fn design(
    path: &Path,
    set: &[String],
    out: Option<&Path>,
    rebalance: bool,
) -> Result<DesignReport, DesignError> {
    let case = if rebalance {
        case::load_rebalanced(path, set)?
    } else {
        case::load_with(path, set)?
    };
    let Some(design) = case.design.clone() else {
        return Err(CaseError::Invalid {
            key: "prestress.from".into(),
            value: "not \"design\" or \"force-density\"".into(),
            fix: "`tensolve design` designs a prestress: set `[prestress] from = \"design\"` with `targets`, or `from = \"force-density\"` with `force_density`, or re-balance the members table's with `--rebalance`".into(),
        }
        .into());
    };
    let report = report(path, &case, design);
    refuse_impossible(&case, &report)?;
    if let Some(dir) = out {
        write_design(dir, path, set, &case, &report)?;
    }
    Ok(report)
}

/// Refuse a design that `run` would not take as written (issue 57, R5-3): a member whose force
/// is at or beyond −E·S (its rest length `ℓ·ES/(ES + t)` is not positive), a prestress that does
/// not stiffen the mechanisms, or any refusal of `run`'s own set-up on the designed case.
fn refuse_impossible(case: &Case, report: &DesignReport) -> Result<(), DesignError> {
    let (key, what) = match report.design.fit {
        crate::structure::Fit::ForceDensity => ("prestress.force_density", "force density"),
        crate::structure::Fit::Rebalanced => ("the members table's prestress", "prestress"),
        _ => ("prestress.targets", "target"),
    };
    let geometry = &case.geometry;
    for m in &geometry.members {
        let es = m.young * m.section;
        // ℓ₀ = ℓ·ES/(ES + t) > 0 ⇔ t > −ES (a NaN fails too).
        let positive_rest_length = es + m.prestress > 0.0;
        if !positive_rest_length {
            let (length, _) =
                crate::structure::length_and_direction(geometry.nodes[m.a], geometry.nodes[m.b]);
            return Err(DesignError::Impossible(format!(
                "member {} ({}) would carry {:.6e} N, at or beyond −E·S = {:.6e} N: its rest \
                 length ℓ·ES/(ES + t) would be {:.6e} m, no member; `{key}` asks for more \
                 compression than its section takes: lower that group's {what}, or give it a \
                 larger E·S",
                m.id,
                m.kind.name(),
                m.prestress,
                -es,
                length * es / (es + m.prestress),
            )));
        }
    }
    if let Some(stability) = report.stability.as_ref().filter(|s| !s.stable()) {
        return Err(DesignError::Impossible(format!(
            "the designed prestress is not prestress-stable (the smallest eigenvalue of Mᵀ K_G M \
             on the {} mechanism(s) is {:.6e} N/m, threshold {:.3e}): `run` would refuse it as \
             a mechanism; change `{key}` (signs: cables in tension, bars in compression), or \
             add members or supports",
            stability.mechanisms,
            stability.smallest().unwrap_or(0.0),
            stability.threshold
        )));
    }
    // What `run` does first, on the case as it would be written.
    let mut designed = case.clone();
    crate::app::auto::prepare_start(&mut designed, false)
        .map(|_| ())
        .map_err(|refused| {
            DesignError::Impossible(format!("`run` refuses the designed case: {refused}"))
        })
}

/// The report of `case`, designed.
fn report(path: &Path, case: &Case, design: Design) -> DesignReport {
    let structure = case.structure();
    let stability = prestress_stability(&structure);
    DesignReport {
        case: path.to_path_buf(),
        groups: design
            .groups
            .iter()
            .map(|g| group_row(&case.geometry, g))
            .collect(),
        design,
        stability,
        free_dofs: structure.n_free,
    }
}

/// A group's row: its force densities and rest lengths over its members.
fn group_row(geometry: &Geometry, g: &case::GroupForce) -> GroupRow {
    let mut q = [f64::INFINITY, f64::NEG_INFINITY];
    let mut rest = q;
    let mut force = q;
    for &j in &g.members {
        let m = &geometry.members[j];
        let (length, _) =
            crate::structure::length_and_direction(geometry.nodes[m.a], geometry.nodes[m.b]);
        let es = m.young * m.section;
        // q = t/ℓ; the rest length ℓ₀ = ℓ·ES/(ES + t), from t = ES (ℓ − ℓ₀)/ℓ₀.
        let (qj, rj) = (m.prestress / length, length * es / (es + m.prestress));
        q = [q[0].min(qj), q[1].max(qj)];
        rest = [rest[0].min(rj), rest[1].max(rj)];
        force = [force[0].min(m.prestress), force[1].max(m.prestress)];
    }
    GroupRow {
        name: g.name.clone(),
        kind: g.kind,
        members: g.members.len(),
        force,
        force_density: q,
        rest_length: rest,
        given: g.given,
    }
}

impl DesignReport {
    /// The stability verdict in words.
    pub fn verdict(&self) -> String {
        match &self.stability {
            None if self.design.counts.mechanisms == 0 => {
                "no mechanism (m = 0): stable without the prestress".to_string()
            }
            None => format!(
                "not tested (above {DENSE_LIMIT} free dofs: the dense test of `check`)"
            ),
            Some(s) if s.mechanisms == 0 => {
                "no mechanism (m = 0): stable without the prestress".to_string()
            }
            Some(s) => format!(
                "{} — the smallest eigenvalue of Mᵀ K_G M on the {} mechanism(s) is {:.6e} N/m (threshold {:.3e})",
                if s.stable() { "prestress-stable" } else { "NOT prestress-stable" },
                s.mechanisms,
                s.smallest().unwrap_or(0.0),
                s.threshold
            ),
        }
    }
}

/// A target or force density as the case gave it, short: `-2000`, `0.5`, `-1e-300` (its
/// digits, not 300 zeros; issue 57, R5-10).
fn given_label(v: f64) -> String {
    match v != 0.0 && !(1e-4..1e15).contains(&v.abs()) {
        true => format!("{v:e}"),
        false => format!("{v}"),
    }
}

/// The warning of a flat form found by force densities (issue 57, N-D11).
pub fn flat_form_sentence(spread: f64) -> String {
    format!(
        "the form found is flat: every node lies in one plane (off it by {spread:.1e} of the \
         form's size), the plane of the anchors, since force densities place each free node at \
         a weighted mean of its neighbours; out of that plane it is stiff by its prestress \
         alone. For a curved form (a saddle, a dome) put the anchors out of one plane"
    )
}

/// `[min, max]` as one value when they agree to 1e-12, else `min..max`.
fn range_label(range: [f64; 2], show: impl Fn(f64) -> String) -> String {
    match (range[1] - range[0]).abs() <= 1e-12 * range[0].abs().max(range[1].abs()) {
        true => show(range[0]),
        false => format!("{}..{}", show(range[0]), show(range[1])),
    }
}

impl fmt::Display for DesignReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = &self.design;
        let c = &d.counts;
        writeln!(f, "design of {}", self.case.display())?;
        // Above the dense test's size, m from the sparse count that stops at its cap is a
        // lower bound (and r an upper one, s a lower one), as `check` says it.
        let bound = c.free_dofs > DENSE_LIMIT && c.mechanisms >= ZERO_MODES_COUNTED;
        let (at_most, at_least) = match bound {
            true => ("at most ", "at least "),
            false => ("", ""),
        };
        writeln!(
            f,
            "  members {}, free dofs {}: rank r = {at_most}{}, s = {at_least}{} self-stress state(s), m = {at_least}{} mechanism(s)",
            c.members, c.free_dofs, c.rank, c.self_stress_states, c.mechanisms
        )?;
        let shown = |x: Option<f64>| x.map_or("none".to_string(), |v| format!("{v:.3e}"));
        writeln!(
            f,
            "  groups {}, grouped self-stress states s₂ = {} (rank decision at σ/σ₁ ≤ {RANK_RELATIVE:e}: smallest kept {}, largest dropped {})",
            d.groups.len(),
            d.grouped_states,
            shown(d.gap.0),
            shown(d.gap.1)
        )?;
        writeln!(f, "  prestress: {}", d.fit.name())?;
        if let Some((change, id)) = d.rebalanced {
            writeln!(
                f,
                "  re-balanced: largest change {change:.6e} N, on member {id}"
            )?;
        }
        if d.fit == crate::structure::Fit::ForceDensity {
            let mixed = self.groups.iter().any(|g| g.given.is_some_and(|q| q < 0.0));
            writeln!(
                f,
                "  rank condition: the force-density Laplacian at the free nodes is regular{}",
                if mixed {
                    " (force densities of mixed signs)"
                } else {
                    " (every force density positive)"
                }
            )?;
        } else if d.fit != crate::structure::Fit::Rebalanced {
            writeln!(f, "  min_cable = {} N", d.min_cable)?;
        }
        writeln!(f, "  stability: {}", self.verdict())?;
        if let Some(spread) = d.flat {
            writeln!(f, "  warning: {}", flat_form_sentence(spread))?;
        }
        // Each figure over the group's members: one value where they all carry it, else
        // `min..max` (under force densities t = qℓ and the rest length vary along a group).
        writeln!(
            f,
            "  {:<16} {:<6} {:>7} {:>27} {:>27} {:>25} {:>12}",
            "group",
            "kind",
            "members",
            "force_N (min..max)",
            "q_N_per_m (min..max)",
            "rest_length_m (min..max)",
            "given"
        )?;
        for g in &self.groups {
            writeln!(
                f,
                "  {:<16} {:<6} {:>7} {:>27} {:>27} {:>25} {:>12}",
                g.name,
                g.kind.name(),
                g.members,
                range_label(g.force, |x| format!("{x:.6e}")),
                range_label(g.force_density, |x| format!("{x:.6e}")),
                range_label(g.rest_length, |x| format!("{x:.9}")),
                g.given.map_or(String::new(), given_label)
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    /// A group's figure is one value where its members agree, else labelled as a range
    /// (issue 57, N-D6: one unlabelled force and rest length was printed per group).
    #[test]
    fn a_range_is_one_value_or_min_to_max() {
        let show = |x: f64| format!("{x}");
        assert_eq!(super::range_label([2.0, 2.0], show), "2");
        assert_eq!(super::range_label([1.5, 2.0], show), "1.5..2");
    }

    /// A target of −1e-300 printed its 300 zeros (issue 57, R5-10); ordinary ones stay plain.
    #[test]
    fn a_given_value_is_printed_short() {
        assert_eq!(super::given_label(-1e-300), "-1e-300");
        assert_eq!(super::given_label(-2000.0), "-2000");
        assert_eq!(super::given_label(0.5), "0.5");
        assert_eq!(super::given_label(2.5e20), "2.5e20");
        assert_eq!(super::given_label(0.0), "0");
    }
}
